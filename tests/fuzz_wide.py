"""A generated fuzz: every public callable, one argument at a time replaced by generic bad values of its kind.

Where tests/lib/test_fuzz_api.py holds a hand-written table of bad values, this file generates them. For each
valid starting call of that table (``build_cases``: every public constructor and function, methods through
small wrappers) plus the engine's paths (:func:`extra_cases`), each argument is replaced in turn by the generic
bad values of its kind (:func:`bad_values`): for a real number NaN, +-inf, a negative, zero, +-1e300, 1e-300,
a bool, a list, a complex, a string and ``None``; for an integer also 2.5, 10**12 and 10**100; for an array
empty, too short, too long, extra dimensions, a NaN, an inf, a 1e300 or a string entry; for a string "",
"nonsense" and bytes; and so on. The kind is read from the valid value (or, where that is ``None``, from the
signature's annotation and :data:`KIND_HINTS`).

Every call runs in a worker process under a watchdog: a per-call time limit (SIGALRM in the worker, and a
hard limit in the parent that kills the worker) and a memory cap (``resource.setrlimit(RLIMIT_AS)``), so that
a hang, an exhausted memory or a crash (the worker dies) is counted, not suffered; the parent then starts a
new worker on the next input. Each input is classified:

``clear``    ValueError or TypeError whose message names the argument;
``obscure``  another exception, or one that does not name the argument;
``silent``   accepted, although :data:`VALID` does not list it as a valid input (silent nonsense);
``valid``    accepted, and listed in :data:`VALID` with the reason it is a valid input (not a bad input);
``hang``     no answer within the time limit, or ``MemoryError`` under the memory cap;
``crash``    the worker process died.

Run it by hand for the full counts (about 8 000 inputs, minutes)::

    python tests/fuzz_wide.py                 # every input, counts per class and every finding
    python tests/fuzz_wide.py --sample 400    # a seeded sample, as tests/lib/test_fuzz_wide.py runs it
    python tests/fuzz_wide.py --valid         # also list every accepted valid input with its reason

The suite runs a seeded sample of a few hundred inputs (tests/lib/test_fuzz_wide.py).
"""

from __future__ import annotations

import argparse
import collections
import copy
import inspect
import json
import math
import os
import random
import select
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from ctrl_analysis.engine import Execution

HERE = Path(__file__).resolve().parent
for _p in (HERE, HERE / "lib"):
    if str(_p) not in sys.path:
        sys.path.insert(0, str(_p))

NAN, INF = math.nan, math.inf
SOFT_S = 10  # per-call limit in the worker (SIGALRM): a Python-level hang
HARD_S = 40  # per-call limit in the parent (kill): a hang in compiled code, where SIGALRM cannot reach
MEMORY_CAP = 6 * 2**30  # bytes of address space for a worker (RLIMIT_AS)

CLASSES = ("clear", "obscure", "silent", "valid", "hang", "crash")


# -- the kinds of arguments and their generic bad values -------------------------------------------------------
#: The kind of an argument whose valid starting value is ``None`` (or absent), by name where the signature's
#: annotation does not tell.
KIND_HINTS = {
    "x0": "array", "F": "array", "b": "array", "P0": "array", "initial": "array", "theta0": "array",
    "lower": "array", "upper": "array", "omega": "array", "axis": "int", "n_output_terms": "int",
    "seeds": "array", "stream": "object", "scheduler": "str", "names": "names", "chunk_runs": "int",
    "max_bytes": "real", "keep": "names", "progress": "callable", "params": "dict", "outputs": "names",
    "h0": "real", "max_trace": "real", "batch": "int", "chunk_size": "int", "position": "int",
    "output_filter": "object", "known": "callable", "controller": "callable", "observe": "callable", "u": "callable",
    "output": "callable", "cell": "str", "runs_diverged": "int", "this_run": "dict", "failed": "dict",
    "tolerance": "real", "runs": "int", "unit": "str", "note": "str", "jobs": "int", "refine": "int",
    "cell_steps": "int", "search_rounds": "int", "points": "int", "share": "real", "scale": "str",
    "require": "str", "method": "str", "bound": "real", "warn": "bool", "allow_unstable": "bool",
    "diverged": "bool",
}


def kind_of(value, name: str = "", annotation=None) -> str:
    """The kind of an argument from its valid value (``real``, ``int``, ``bool``, ``str``, ``names``, ``array``,
    ``callable``, ``dict``, ``path``, ``object``)."""
    import numpy as np

    if value is None:
        text = "" if annotation in (None, inspect.Parameter.empty) else str(annotation)
        for word, kind in (("Callable", "callable"), ("bool", "bool"), ("float", "real"), ("int", "int"),
                           ("str", "str"), ("dict", "dict"), ("Block", "object")):
            if word in text:
                return kind
        return KIND_HINTS.get(name, "object")
    if isinstance(value, (bool, np.bool_)):
        return "bool"
    if isinstance(value, (int, np.integer)):
        return "int"
    if isinstance(value, (float, np.floating)):
        return "real"
    if isinstance(value, str):
        return "str"
    if isinstance(value, os.PathLike):
        return "path"
    if isinstance(value, dict):
        return "dict"
    if isinstance(value, (list, tuple)) and value and all(isinstance(v, str) for v in value):
        return "names"
    if isinstance(value, np.ndarray) and value.dtype.kind in "biuf":
        return "array"
    if isinstance(value, (list, tuple)) and value:
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            return "object"
        return "array" if arr.size else "object"
    if callable(value) and not inspect.isclass(value) and (inspect.isfunction(value) or inspect.ismethod(value)):
        return "callable"
    return "object"


def bad_values(kind: str, valid):
    """``[(tag, value)]``: the generic bad values of an argument of ``kind`` whose valid value is ``valid``."""
    import numpy as np

    if kind == "real":
        v = abs(float(valid)) if valid is not None and math.isfinite(float(valid)) and float(valid) else 1.0
        return [("none", None), ("str", "abc"), ("complex", 1 + 2j), ("list", [v, v]), ("bool", True),
                ("nan", NAN), ("inf", INF), ("-inf", -INF), ("negative", -v), ("zero", 0.0), ("huge", 1e300),
                ("-huge", -1e300), ("tiny", 1e-300)]
    if kind == "int":
        return [("none", None), ("str", "3"), ("float", 2.5), ("nan", NAN), ("inf", INF), ("bool", True),
                ("list", [3]), ("negative", -1), ("zero", 0), ("huge", 10**12), ("-huge", -10**12),
                ("giant", 10**100)]
    if kind == "bool":
        return [("none", None), ("str", "yes"), ("int", 2), ("float", 0.5), ("list", [True])]
    if kind == "str":
        return [("none", None), ("int", 3), ("float", 1.5), ("empty", ""), ("unknown", "nonsense"),
                ("bytes", b"x"), ("list", [valid or "x"])]
    if kind == "names":
        names = tuple(valid) if valid else ("x",)
        return [("none", None), ("int", 3), ("empty", ()), ("entry-int", (3,) + names[1:]),
                ("entry-empty", ("",) + names[1:]), ("unknown", ("nonsense",) * len(names)),
                ("longer", names + ("extra",))]
    if kind == "array":
        a = np.array([1.0, 2.0]) if valid is None else np.array(valid, dtype=float)
        if a.ndim == 0:
            a = a.reshape(1)
        out = [("none", None), ("str", "abc"), ("empty", []), ("extra-dims", a.reshape(a.shape + (1, 1))),
               ("nan-entry", _entry(a, NAN)), ("inf-entry", _entry(a, INF)), ("huge-entry", _entry(a, 1e300)),
               ("str-entry", _entry(a.astype(object), "x")), ("complex", a + 1j), ("negative", -np.abs(a) - 1.0),
               ("longer", np.concatenate([a, a[:1]]))]
        if a.shape[0] > 1:
            out.append(("shorter", a[:-1]))
        return out
    if kind == "callable":
        return [("none", None), ("int", 3), ("str", "f")]
    if kind == "dict":
        out = [("none", None), ("int", 3), ("str", "x"), ("list", [1])]
        if valid:
            out.append(("unknown", {"nonsense": 1.0}))
        return out
    if kind == "path":
        return [("none", None), ("int", 3), ("empty", "")]
    return [("none", None), ("int", 3), ("str", "x"), ("object", object())]


def _entry(a, value):
    out = a.copy()
    out.flat[0] = value
    return out


# -- the cases --------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Input:
    label: str  # the callable's label (test_fuzz_api's table, or an engine path)
    arg: str
    tag: str  # the class of the bad value (see bad_values)
    shown: str  # the value, shortened


def _signature(fn):
    try:
        return inspect.signature(fn)
    except (TypeError, ValueError):
        return None


def extra_cases(tmp):
    """Starting points beyond the table: the engine's paths (numpy, compiled, auto; the per-run parameters)."""
    import numpy as np
    import test_fuzz_api as table

    def simulate(engine):
        def call(n_steps=3, inputs=None, runs=2, bound=1e8, t0=0.0, params=None, x0=None, chunk_runs=None):
            loop = table._loop(dt=0.1)
            return loop.simulate(n_steps, inputs={"u": 1.0} if inputs is None else inputs, runs=runs,
                                 execution=Execution(bound=bound, chunk_runs=chunk_runs, engine=engine),
                                 t0=t0, params=params, x0=x0)

        return call

    ikf = table.ikf.ImprovedKalmanFilter(Q=0.1, R=1.0)

    def per_run(engine):
        def call(Q=None, R=None, y_m=None):
            loop = table.loop_mod.Loop([table.loop_mod.place(ikf, "f")], dt=1.0)
            params = {"f": {"Q": np.linspace(0.1, 0.5, 3) if Q is None else Q, "R": 1.0 if R is None else R}}
            inputs = {"y_m": np.ones((4, 3)) if y_m is None else y_m, "dy_model": 0.0}
            return loop.simulate(4, inputs=inputs, params=params, execution=Execution(engine=engine))

        return call

    def layout(fields):  # Layout(*fields) for a sequence, Layout(fields) for one bad field
        fields = fields if isinstance(fields, (list, tuple)) else (fields,)
        return table.engine_kernels.Layout(*fields)

    valid = dict(n_steps=3, inputs={"u": 1.0}, runs=2, bound=1e8, t0=0.0)
    cases = [("Layout(*fields)", layout, {"fields": ("a", ("b", 2))}, {})]
    cases += [(f"Loop.simulate[{e}]", simulate(e), dict(valid), {}) for e in ("compiled", "auto")]
    cases += [(f"Loop.simulate[{e}, per-run params]", per_run(e),
               dict(Q=np.linspace(0.1, 0.5, 3), R=1.0, y_m=np.ones((4, 3))), {})
              for e in ("numpy", "compiled")]
    return cases


def starting_points(tmp):
    """``[(label, fn, valid kwargs, {arg: kind}, wrapped)]`` for the table's cases and :func:`extra_cases`."""
    import test_fuzz_api as table

    points = []
    for label, fn, valid, bad in list(table.build_cases(tmp)) + extra_cases(tmp):
        if label == "Layout":  # Layout(*fields): the table's wrapper unpacks one argument; see extra_cases
            continue
        sig = _signature(fn)
        params = sig.parameters if sig is not None else {}
        kinds = {}
        harness = getattr(fn, "harness", ())  # a wrapper's own selector arguments: not the library's
        for arg in list(valid) + [a for a in bad if a not in valid]:
            if arg in harness:
                continue
            p = params.get(arg)
            value = valid.get(arg, p.default if p is not None and p.default is not inspect.Parameter.empty else None)
            kinds[arg] = kind_of(value, arg, p.annotation if p is not None else None)
        points.append((label, fn, valid, kinds, {a: params[a].default for a in kinds if a in params}))
    return points


def generate(tmp):
    """``[(Input, thunk)]``, in a fixed order (the parent and every worker build the same list)."""
    out = []
    for label, fn, valid, kinds, defaults in starting_points(tmp):
        for arg, kind in kinds.items():
            for tag, value in bad_values(kind, valid.get(arg)):
                if value is None and (valid.get(arg, 0) is None or defaults.get(arg, 0) is None):
                    continue  # None is the default there: a valid input, not a bad one
                shown = repr(value)
                shown = shown if len(shown) <= 60 else shown[:57] + "..."
                out.append((Input(label, arg, tag, shown), (fn, valid, arg, value)))
    return out


#: Tags of finite numbers of extreme magnitude: accepted, they are valid inputs when the answer is finite.
MAGNITUDE = frozenset({"huge", "-huge", "tiny", "huge-entry"})
#: Tags of finite values: an accepted one whose answer is NaN or inf (where the valid call's is finite) is nonsense.
FINITE_TAGS = MAGNITUDE | {"negative", "zero", "longer", "shorter", "extra-dims", "empty", "float", "list", "bool",
                           "int", "giant", "unknown"}


def nonfinite(obj, depth: int = 0) -> bool:
    """Whether ``obj`` (a number, an array, or a record of them, two levels deep) holds a NaN or an inf."""
    import numpy as np

    if depth > 2 or isinstance(obj, (bool, np.bool_, str, bytes)) or obj is None:
        return False
    if np.any(getattr(obj, "diverged", False)):  # a simulation's NaN marks its runs flagged as diverged
        return False
    if isinstance(obj, (int, float, complex, np.number)):
        try:
            return not bool(np.isfinite(obj))
        except (OverflowError, TypeError):
            return False
    if isinstance(obj, np.ndarray):
        return obj.dtype.kind in "fc" and obj.size > 0 and not bool(np.isfinite(obj).all())
    if isinstance(obj, (list, tuple)):
        return any(nonfinite(v, depth + 1) for v in obj[:50])
    if isinstance(obj, dict):
        return any(nonfinite(v, depth + 1) for v in list(obj.values())[:50])
    if hasattr(obj, "__dict__") and not inspect.ismodule(obj) and not callable(obj):
        return any(nonfinite(v, depth + 1) for v in list(vars(obj).values())[:50])
    if hasattr(obj, "__dataclass_fields__"):
        return any(nonfinite(getattr(obj, f, None), depth + 1) for f in obj.__dataclass_fields__)
    return False


# -- which accepted inputs are valid ----------------------------------------------------------------------------
def valid_reason(inp: Input) -> str | None:
    """Why ``inp`` is a valid input, from tests/fuzz_wide_valid.py (``None``: it is a bad input)."""
    from fuzz_wide_valid import valid_table

    return valid_table().get((inp.label, inp.arg), {}).get(inp.tag)


# -- the worker ---------------------------------------------------------------------------------------------------
def _names_argument(message: str, arg: str) -> bool:
    import re

    return re.search(rf"(?<![A-Za-z0-9_]){re.escape(arg)}(?![A-Za-z0-9_])", message) is not None


class _Alarm(BaseException):
    """Raised by SIGALRM: a BaseException, so that no ``except Exception`` in the library swallows it."""


def _copied(valid):
    kwargs = {}
    for k, v in valid.items():
        try:
            kwargs[k] = copy.deepcopy(v)
        except Exception:  # noqa: BLE001 - an object that cannot be copied is passed as it is
            kwargs[k] = v
    return kwargs


_BASELINE: dict[str, bool] = {}


def classify(inp: Input, thunk, soft_s: float) -> tuple[str, str]:
    """Run one input under the soft time limit; ``(class, detail)``."""
    fn, valid, arg, value = thunk
    if inp.label not in _BASELINE:  # whether the valid call's answer is finite
        try:
            _BASELINE[inp.label] = nonfinite(fn(**_copied(valid)))
        except Exception:  # noqa: BLE001 - a broken starting point shows in every input's class
            _BASELINE[inp.label] = True
        _close_figures()
    kwargs = _copied(valid)
    kwargs[arg] = value

    def fire(signum, frame):
        raise _Alarm()

    old = signal.signal(signal.SIGALRM, fire)
    signal.setitimer(signal.ITIMER_REAL, soft_s)
    try:
        answer = fn(**kwargs)
    except _Alarm:
        return "hang", f"no answer within {soft_s} s"
    except MemoryError as exc:
        if type(exc) is MemoryError and str(exc):  # the library's own up-front refusal, saying what to change
            return "clear", f"MemoryError: {exc}"
        return "hang", f"MemoryError under the {MEMORY_CAP / 2**30:.0f} GiB cap: {exc}"
    except (ValueError, TypeError) as exc:
        if _names_argument(str(exc), arg):
            return "clear", f"{type(exc).__name__}: {exc}"
        return "obscure", f"{type(exc).__name__} does not name {arg!r}: {exc}"
    except Exception as exc:  # noqa: BLE001 - anything else is a finding
        return "obscure", f"{type(exc).__name__}: {exc}"
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
        _close_figures()
    reason = valid_reason(inp)
    if reason:
        return "valid", reason
    if inp.tag in FINITE_TAGS and not _BASELINE[inp.label] and nonfinite(answer):
        return "silent", "accepted, and the answer holds NaN or inf"
    if inp.tag in MAGNITUDE:
        return "valid", "a finite number of extreme magnitude, in the argument's domain; the answer is finite"
    return "silent", "accepted"


def _close_figures():
    if "matplotlib.pyplot" in sys.modules:
        sys.modules["matplotlib.pyplot"].close("all")


def worker(indices: list[int], soft_s: float) -> None:
    """Run ``indices`` of :func:`generate`'s list; one JSON line per input on the original stdout."""
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_CAP, MEMORY_CAP))
    out = os.fdopen(os.dup(1), "w", buffering=1)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.dup2(devnull, 2)
    import warnings

    warnings.simplefilter("ignore")
    tmp = Path(tempfile.mkdtemp(prefix="fuzz_wide_"))
    os.chdir(tmp)
    cases = generate(tmp)
    for i in indices:
        inp, thunk = cases[i]
        out.write(json.dumps({"start": i}) + "\n")
        cls, detail = classify(inp, thunk, soft_s)
        out.write(json.dumps({"done": i, "class": cls, "detail": detail[:300]}) + "\n")
    out.write(json.dumps({"end": True}) + "\n")


# -- the parent ---------------------------------------------------------------------------------------------------
def _spawn(indices, soft_s):
    env = dict(os.environ, MPLBACKEND="Agg", OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1",
               NUMBA_NUM_THREADS="1", PYTHONWARNINGS="ignore")
    return subprocess.Popen([sys.executable, str(Path(__file__).resolve()), "--worker", "--soft", str(soft_s)],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=env,
                            start_new_session=True, text=True, bufsize=1)


def _kill(proc):
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.wait()


def run(indices: list[int], soft_s: float = SOFT_S, hard_s: float = HARD_S, start_s: float = 120.0):
    """``{index: (class, detail)}`` for ``indices``; a worker that dies or stops answering is replaced."""
    results, todo = {}, list(indices)
    while todo:
        proc = _spawn(todo, soft_s)
        proc.stdin.write(json.dumps(todo) + "\n")
        proc.stdin.close()
        current, wait = None, start_s
        while True:
            ready, _, _ = select.select([proc.stdout], [], [], wait)
            line = proc.stdout.readline() if ready else None
            if line is None or line == "":  # silence past the limit, or the worker is gone
                if line is None:
                    _kill(proc)
                    cls, detail = "hang", f"killed after {wait:.0f} s without an answer"
                else:
                    rc = proc.wait()
                    cls, detail = "crash", f"the worker died (exit {rc})"
                if current is None:  # the worker failed before its first input
                    raise RuntimeError(f"the fuzz worker failed to start: {detail}")
                results[current] = (cls, detail)
                todo = todo[todo.index(current) + 1:]
                break
            msg = json.loads(line)
            if "start" in msg:
                current, wait = msg["start"], hard_s
            elif "done" in msg:
                results[msg["done"]] = (msg["class"], msg["detail"])
                current = None
                wait = hard_s
            elif "end" in msg:
                proc.wait()
                todo = []
                break
    return results


def sample(n_total: int, size: int | None, seed: int = 28) -> list[int]:
    if size is None or size >= n_total:
        return list(range(n_total))
    return sorted(random.Random(seed).sample(range(n_total), size))


def summary(cases, results):
    """Counts per class, the callables covered, and the findings (every input not clear and not valid)."""
    counts = collections.Counter(cls for cls, _ in results.values())
    findings = [(cases[i], cls, detail) for i, (cls, detail) in sorted(results.items())
                if cls not in ("clear", "valid")]
    return counts, findings


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--soft", type=float, default=SOFT_S, help="per-call limit in the worker, seconds")
    parser.add_argument("--hard", type=float, default=HARD_S, help="per-call limit before the worker is killed")
    parser.add_argument("--sample", type=int, default=None, help="a seeded sample of this many inputs")
    parser.add_argument("--only", default=None, help="only the starting points whose label matches this regex")
    parser.add_argument("--valid", action="store_true", help="also list the accepted valid inputs with reasons")
    parser.add_argument("--json", type=Path, default=None, help="write every input's class here")
    args = parser.parse_args(argv)
    if args.worker:
        worker(json.loads(sys.stdin.readline()), args.soft)
        return 0
    with tempfile.TemporaryDirectory() as d:
        cases = [inp for inp, _ in generate(Path(d))]
    chosen = sample(len(cases), args.sample)
    if args.only:
        import re

        chosen = [i for i in chosen if re.search(args.only, cases[i].label)]
    t = time.perf_counter()
    results = run(chosen, args.soft, args.hard)
    counts, findings = summary(cases, results)
    for inp, cls, detail in findings:
        print(f"{cls:8s} {inp.label}({inp.arg}={inp.shown}) [{inp.tag}]: {detail}")
    if args.valid:
        for i, (cls, detail) in sorted(results.items()):
            if cls == "valid":
                inp = cases[i]
                print(f"valid    {inp.label}({inp.arg}={inp.shown}) [{inp.tag}]: {detail}")
    if args.json:
        args.json.write_text(json.dumps([dict(vars(cases[i]), cls=c, detail=d) for i, (c, d) in
                                         sorted(results.items())], indent=0))
    n = sum(counts.values())
    bad = n - counts["valid"]
    labels = {cases[i].label for i in results}
    print(f"\n{n} inputs over {len(labels)} starting points in {time.perf_counter() - t:.0f} s: "
          + ", ".join(f"{counts[c]} {c}" for c in CLASSES))
    if bad:
        print(f"bad inputs (all but the valid ones): {bad}, of which {counts['clear']} clear "
              f"({100 * counts['clear'] / bad:.1f} %)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
