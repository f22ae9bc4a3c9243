"""The project's layering and shape rules, checked on the source tree.

* ``ctrl_analysis`` (the library) never imports ``analysis`` (the studies), except the CLI's registry;
* no paper's printed constant appears as a literal in ``ctrl_analysis``: every value a study declares
  with :func:`ctrl_analysis.reporting.study.printed` (and a few distinctive printed numbers of the papers
  listed below) is searched for among the library's numeric literals;
* no function in ``analysis/`` is longer than 80 lines; no module of ``ctrl_analysis``, ``analysis`` or
  ``benchmarks`` is longer than 600 lines.
"""

import ast
import dataclasses
import importlib
import pkgutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
LIB = ROOT / "ctrl_analysis"
STUDIES = ROOT / "analysis"

#: Distinctive numbers the five papers print (besides the studies' ``printed`` fields), e.g. the
#: pendulum's B and printed gain, Table 1 cells of ikf-mfac, the TD parameters, the ckf control RMS.
PAPER_NUMBERS = {2.6683, 2.6149, 0.950, 0.863, 1.3179e-4, 5.769e-4, 8.23e-2, 5.4e-3, 0.1248, 0.1043, 0.0983,
                 0.0905, 0.6856, 0.58, 0.8853, 0.4281, 1800.0, 0.0018, 1450.0, 0.0035, 1.27, 2.285714, 5.7325,
                 0.28, 2.28, 0.0857}
#: Numbers too generic to tie a literal to a paper (small integers, simple fractions, method constants
#: such as the golden-section ratios 0.382 / 0.618, which belong to the method, not to one paper, and the
#: verdict policy's central 95 % share of the Monte Carlo runs; the pendulum's printed gain is still caught by 0.863).
GENERIC = {0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 10.0, 0.5, 0.25, 0.1, 0.01, 0.001, 50.0, 100.0, 1000.0,
           0.382, 0.618, 0.95}


def _significant_digits(v: float) -> int:
    digits = f"{abs(v):.12e}".split("e")[0].replace(".", "").rstrip("0")
    return len(digits)


def _py_files(folder: Path):
    return sorted(p for p in folder.rglob("*.py") if "__pycache__" not in p.parts)


def _printed_values() -> set:
    """Every numeric value declared with ``printed(...)`` in a study's frozen parameter objects."""
    values = set()
    for mod in pkgutil.walk_packages([str(STUDIES)], prefix="analysis."):
        module = importlib.import_module(mod.name)
        for obj in vars(module).values():
            if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
                for f in dataclasses.fields(obj):
                    if "printed" in f.metadata:
                        v = getattr(obj, f.name)
                        for x in (v if isinstance(v, tuple) else (v,)):
                            if isinstance(x, (int, float)) and not isinstance(x, bool):
                                values.add(float(x))
    return values


def test_library_never_imports_the_studies():
    offenders = []
    for path in _py_files(LIB):
        if path.name == "cli.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            offenders += [f"{path.relative_to(ROOT)}:{node.lineno} imports {n}" for n in names
                          if n == "analysis" or n.startswith("analysis.")]
    assert not offenders, "\n".join(offenders)


def test_no_printed_paper_constant_in_the_library():
    # one-significant-digit numbers (0.3, 20, 500) and small integers are too common to tie to a paper
    paper = {v for v in (_printed_values() | PAPER_NUMBERS)
             if v not in GENERIC and not (v.is_integer() and abs(v) < 100) and _significant_digits(v) > 1}
    assert len(paper) > len(PAPER_NUMBERS) // 2  # the collection found something to look for
    offenders = []
    for path in _py_files(LIB):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) \
                    and not isinstance(node.value, bool) and float(node.value) in paper:
                offenders.append(f"{path.relative_to(ROOT)}:{node.lineno} literal {node.value!r}")
    assert not offenders, "paper constants in the library (move them to analysis/):\n" + "\n".join(offenders)


def test_study_functions_read_in_a_screen():
    long = []
    for path in _py_files(STUDIES):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                if n > 80:
                    long.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.name} is {n} lines")
    assert not long, "\n".join(long)


@pytest.mark.parametrize("path", _py_files(LIB) + _py_files(STUDIES) + _py_files(ROOT / "benchmarks"),
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_modules_hold_one_topic(path):
    n = len(path.read_text(encoding="utf-8").splitlines())
    assert n <= 600, f"{path.relative_to(ROOT)} has {n} lines (> 600): split it by topic"


def _import_graph(lazy: bool) -> dict:
    """``{module: {ctrl_analysis modules it imports}}`` from the source (``lazy``: imports inside functions too)."""
    import ast

    pkg = ROOT / "ctrl_analysis"
    graph = {}
    for path in pkg.rglob("*.py"):
        rel = path.relative_to(ROOT).with_suffix("")
        name = ".".join(rel.parts[:-1] if rel.name == "__init__" else rel.parts)
        is_pkg = rel.name == "__init__"
        tree = ast.parse(path.read_text(encoding="utf-8"))
        nodes = ast.walk(tree) if lazy else tree.body
        deps = set()
        for node in nodes:
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = name.split(".") if is_pkg else name.split(".")[:-1]
                    base = base[:len(base) - node.level + 1]
                    mod = ".".join(base + ([node.module] if node.module else []))
                else:
                    mod = node.module or ""
                targets = [mod] + [f"{mod}.{a.name}" for a in node.names]
            elif isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            else:
                continue
            deps |= {t for t in targets if t.startswith("ctrl_analysis")}
        graph[name] = deps
    return {m: {d for d in deps if d in graph and d != m} for m, deps in graph.items()}


def _cycles(graph: dict) -> list:
    import sys

    sys.setrecursionlimit(10000)
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def strong(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in graph:
        if v not in index:
            strong(v)
    return out


def test_no_import_cycles():
    """No two library modules import each other, directly or round a circle (a package's
    ``__init__`` re-exporting its modules is not a circle with them); imports inside functions count too."""
    graph = _import_graph(lazy=True)
    for m in graph:  # a package imports its own modules to re-export them; they may import siblings through it
        graph[m] = {d for d in graph[m] if not (m.startswith(d + ".") and d in graph)}
    assert _cycles(graph) == []


def test_cycle_detector_finds_a_known_circle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []
