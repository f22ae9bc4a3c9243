"""CONTRIBUTING.md stays true to the tree: every path and module it names exists, and its block template runs."""

from __future__ import annotations

import doctest
import importlib
import re
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TEXT = (ROOT / "CONTRIBUTING.md").read_text(encoding="utf-8")
PROSE = re.sub(r"```.*?```", "", TEXT, flags=re.DOTALL)  # the text without its code blocks (templates name new files)


def _layout_paths() -> list[str]:
    """The paths of the layout map (the fenced block after "How the project is laid out"), rebuilt from its indents."""
    block = re.search(r"## How the project is laid out\n.*?\n```\n(.*?)```", TEXT, re.DOTALL)
    assert block, "CONTRIBUTING.md has no layout map under '## How the project is laid out'"
    paths, parents = [], []  # parents: (indent, folder) of the enclosing entries
    for line in block.group(1).splitlines():
        m = re.match(r"( *)(\S.*?)(?: {2,}|$)", line)  # the names: up to the first run of 2+ spaces
        if not m or len(m.group(1)) >= 20:  # a blank line, or the continuation of a description
            continue
        indent, names = len(m.group(1)), [n.strip() for n in m.group(2).split(",")]
        while parents and parents[-1][0] >= indent:
            parents.pop()
        paths += ["/".join([f for _, f in parents] + [n.rstrip("/")]) for n in names]
        if names[-1].endswith("/"):
            parents.append((indent, names[-1].rstrip("/")))
    return paths


def _named_paths() -> set[str]:
    """Every repository path the text names in backticks (``a/b.py``, ``a/b/``), placeholders (``<study>``) left out."""
    names = set()
    for token in re.findall(r"`([^`\s]+)`", PROSE):
        token = token.split("::")[0].rstrip(".,:;")
        if "<" in token or "*" in token or "/" not in token or token.startswith(("-", "/", "http")):
            continue
        if re.match(r"^(ctrl_analysis|analysis|tests|docs|benchmarks|figures)/", token):
            names.add(token.rstrip("/"))
    return names


def _named_modules() -> set[str]:
    """Every dotted name under ``ctrl_analysis.`` the text names in backticks."""
    return set(re.findall(r"`(ctrl_analysis(?:\.\w+)+)", PROSE))


def test_the_layout_map_names_only_paths_that_exist():
    paths = _layout_paths()
    assert len(paths) >= 10, paths  # the map was parsed, not skipped
    missing = [p for p in paths if not (ROOT / p).exists()]
    assert not missing, f"CONTRIBUTING.md's layout map names paths that do not exist: {missing}"


def test_the_layout_map_lists_every_module_of_the_library_and_the_engine():
    listed = set(_layout_paths())
    actual = set()
    for folder in ("ctrl_analysis", "ctrl_analysis/engine"):
        actual |= {f"{folder}/{p.name}" for p in (ROOT / folder).iterdir()
                   if (p.suffix == ".py" and p.name != "__init__.py") or (p.is_dir() and (p / "__init__.py").exists())}
    assert actual <= listed, f"modules missing from CONTRIBUTING.md's layout map: {sorted(actual - listed)}"


def test_every_path_the_text_names_exists():
    named = _named_paths()
    assert "ctrl_analysis/engine/blocks.py" in named and "tests/lib/test_fuzz_api.py" in named
    missing = sorted(p for p in named if not (ROOT / p).exists())
    assert not missing, f"CONTRIBUTING.md names paths that do not exist: {missing}"


@pytest.mark.parametrize("name", sorted(_named_modules()))
def test_every_module_the_text_names_imports(name):
    parts = name.split(".")
    for i in range(len(parts), 0, -1):  # the longest importable prefix, then attributes
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ModuleNotFoundError:
            continue
        for attr in parts[i:]:
            assert hasattr(obj, attr), f"CONTRIBUTING.md names {name}, but {obj.__name__} has no {attr!r}"
            obj = getattr(obj, attr)
        return
    pytest.fail(f"CONTRIBUTING.md names {name}, which does not import")


def _templates() -> tuple[str, str]:
    """The block template and the test template of "Add a block" (the first two python blocks of the section)."""
    section = TEXT[TEXT.index("## Add a block"):TEXT.index("## Add a study")]
    blocks = [textwrap.dedent(b) for b in re.findall(r"```python\n(.*?)\n *```", section, re.DOTALL)]
    assert len(blocks) == 2, f"'Add a block' should hold two python templates, found {len(blocks)}"
    return blocks[0], blocks[1]


@pytest.mark.filterwarnings("error:compiled engine unavailable")
def test_the_block_template_runs_its_doctest_and_passes_the_test_template():
    module, tests = _templates()
    ns = {"__name__": "contributing_template"}
    # the template is a module of ctrl_analysis' subpackages: its relative imports, made absolute
    exec(compile(module.replace("from ..", "from ctrl_analysis."), "CONTRIBUTING.md (block template)", "exec"), ns)  # noqa: S102
    block = ns["RateLimiter"]
    runner = doctest.DocTestRunner()
    for test in doctest.DocTestFinder().find(block, "RateLimiter", globs=dict(ns)):
        runner.run(test)
    assert runner.failures == 0 and runner.tries > 0
    own_import = re.compile(r"^from ctrl_analysis\.\w+\.rate_limit import RateLimiter$", re.MULTILINE)
    assert own_import.search(tests), "the test template imports the block from its module"
    exec(compile(own_import.sub("", tests), "CONTRIBUTING.md (test template)", "exec"), ns)  # noqa: S102
    ran = 0
    for name, fn in list(ns.items()):
        if not (name.startswith("test_") and callable(fn)):
            continue
        marks = [m for m in getattr(fn, "pytestmark", []) if m.name == "parametrize"]
        if not marks:
            fn()
            ran += 1
            continue
        names, values = marks[0].args
        names = [n.strip() for n in (names.split(",") if isinstance(names, str) else names)]
        for row in values:
            fn(**dict(zip(names, row if len(names) > 1 else (row,), strict=True)))
            ran += 1
    assert ran >= 6
