"""Results records, computed verdicts, results.json and REPORT.md, and the shared figure style."""

from __future__ import annotations

import json
import math
import platform
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from .atomic import staged_directory, write_text_atomic  # noqa: F401 (public API)
from ._validate import (check_array, check_bool, check_callable, check_int, check_nonnegative, check_path,
                        check_positive, check_str)

__all__ = [
    "Quantity",
    "StudyInfo",
    "StudyContext",
    "StudyResult",
    "VERDICTS",
    "RESULTS_SCHEMA",
    "compute_verdict",
    "count_verdicts",
    "relative_error",
    "validate_results",
    "versions",
    "write_text_atomic",
    "staged_directory",
    "write_results_json",
    "new_figure",
]

VERDICTS = ("agrees", "differs", "new", "diverged")
#: Version of the results.json layout: 2 adds ``unit`` and ``tolerance`` on every quantity, the
#: ``diverged`` verdict, paper ``cell`` / ``primary`` and ``settings["cli"]``.
RESULTS_SCHEMA = 2
DEFAULT_TOLERANCE = 0.1


def _to_jsonable(value):
    """numpy → plain Python; non-finite floats → None (JSON has no NaN)."""
    if isinstance(value, dict):
        return {str(k): _to_jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return _to_jsonable(value.tolist())
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        value = float(value)
        return value if math.isfinite(value) else None
    if isinstance(value, complex):
        return [_to_jsonable(value.real), _to_jsonable(value.imag)]
    if isinstance(value, Path):
        return str(value)
    return value


def relative_error(value, paper) -> float:
    """Largest element-wise relative error |value - paper| / |paper| (absolute where paper == 0).

    Vectors must have the same length; a length mismatch or a non-finite value gives ``inf``.
    """
    v = np.atleast_1d(check_array("value", value))
    p = np.atleast_1d(check_array("paper", paper))
    if v.shape != p.shape or not np.all(np.isfinite(v)):
        return math.inf
    scale = np.where(p == 0, 1.0, np.abs(p))
    return float(np.max(np.abs(v - p) / scale))


def _check_tolerance(tolerance) -> float:
    return float(check_nonnegative("tolerance", tolerance, scalar=True))


def compute_verdict(value, paper, tolerance: float | None, *, diverged: bool = False) -> str:
    """``diverged`` when every run diverged; ``new`` without a paper value; else ``agrees`` when the
    relative error is within tolerance, ``differs`` otherwise."""
    if check_bool("diverged", diverged):
        return "diverged"
    if paper is None:
        return "new"
    tol = DEFAULT_TOLERANCE if tolerance is None else _check_tolerance(tolerance)
    if value is None:
        return "differs"
    return "agrees" if relative_error(value, paper) <= tol else "differs"


@dataclass
class Quantity:
    """One reproduced number (or vector) beside the paper's.

    ``verdict`` is computed from ``value``, ``paper``, ``tolerance`` (relative) and ``diverged``; it is
    never set by hand. ``unit`` is always written ("" = dimensionless); ``tolerance`` is written
    whenever ``paper`` is (default :data:`DEFAULT_TOLERANCE`). ``cell`` names the paper cell the
    quantity scores (e.g. ``"Table 2 / x1 ESO"``); quantities sharing a cell are counted once, by the
    one with ``primary=True`` (default: the first recorded). ``diverged=True`` (or ``runs_diverged``
    equal to ``runs``, or ``runs=0`` healthy runs with ``value=None``) means every run diverged: no
    value, verdict ``diverged``.
    """

    id: str
    label: str
    value: object
    paper: object = None
    std: object = None
    runs: int | None = None
    tolerance: float | None = None
    note: str = ""
    unit: str = ""
    cell: str | None = None
    primary: bool = False
    diverged: bool = False
    runs_diverged: int | None = None

    def __post_init__(self):
        for name in ("id", "label"):
            if not isinstance(getattr(self, name), str) or (name == "id" and not self.id):
                raise TypeError(f"{name} must be a non-empty string, got {getattr(self, name)!r}")
        if not isinstance(self.unit, str):
            raise TypeError(f"unit must be a string ('' for dimensionless), got {self.unit!r}")
        if self.cell is not None and (not isinstance(self.cell, str) or not self.cell.strip()):
            raise ValueError(f"cell must be a non-empty string naming the paper cell, got {self.cell!r}")
        if self.tolerance is not None:
            self.tolerance = _check_tolerance(self.tolerance)
        self.primary = check_bool("primary", self.primary)
        self.diverged = check_bool("diverged", self.diverged)
        if self.runs is not None:
            self.runs = check_int("runs", self.runs, minimum=0)
        if self.runs_diverged is not None:
            self.runs_diverged = check_int("runs_diverged", self.runs_diverged, minimum=0,
                                           maximum=self.runs)
            if self.runs and self.runs_diverged == self.runs:
                self.diverged = True
        if self.runs == 0 and self.value is None:  # no run contributed a value: every run diverged
            self.diverged = True
        if self.diverged and self.value is not None:
            raise ValueError(f"quantity {self.id!r}: a diverged quantity has no value (value must be None), "
                             f"got {self.value!r}")

    @property
    def verdict(self) -> str:
        return compute_verdict(self.value, self.paper, self.tolerance, diverged=self.diverged)

    def to_dict(self) -> dict:
        d = {
            "id": self.id,
            "label": self.label,
            "paper": self.paper,
            "value": self.value,
            # one run has no spread: record none rather than a misleading 0
            "std": self.std if (self.runs is None or self.runs > 1) and not self.diverged else None,
            "runs": self.runs,
            "unit": self.unit,
            "tolerance": (DEFAULT_TOLERANCE if self.tolerance is None else self.tolerance)
            if self.paper is not None
            else None,
            "verdict": self.verdict,
            "note": self.note,
        }
        if self.cell is not None:
            d["cell"] = self.cell
            d["primary"] = bool(self.primary)
        if self.runs_diverged is not None:
            d["runs_diverged"] = self.runs_diverged
        if self.value is not None and not np.all(np.isfinite(np.asarray(self.value, dtype=float))):
            d["note"] = (self.note + " " if self.note else "") + "value is not finite (diverged run?)"
        return _to_jsonable(d)


@dataclass(frozen=True)
class StudyInfo:
    """What a study is: its CLI name, seed file, paper and what it reproduces."""

    name: str
    seed_file: str
    paper: str
    reproduces: str

    def __post_init__(self):
        check_str("name", self.name)
        for name in ("seed_file", "paper", "reproduces"):
            check_str(name, getattr(self, name), empty=True)


@dataclass
class StudyResult:
    """Everything one study reproduced; serialised to results.json."""

    info: StudyInfo
    settings: dict = field(default_factory=dict)
    reconstructions: list = field(default_factory=list)
    quantities: list = field(default_factory=list)
    findings: list = field(default_factory=list)
    figures: list = field(default_factory=list)
    #: figure file name -> caption (what is plotted and which paper figure it redraws), shown in REPORT.md
    captions: dict = field(default_factory=dict)
    missing: list = field(default_factory=list)
    seeds: dict = field(default_factory=dict)
    runtime_s: float = 0.0

    def __post_init__(self):
        if not isinstance(self.info, StudyInfo):
            raise TypeError(f"info must be a StudyInfo, got {self.info!r}")

    def quantity(self, id: str, label: str, value, paper=None, **kw) -> Quantity:
        """Add a quantity and return it (an id may be recorded once).

        Keywords are the fields of :class:`Quantity`:

        - ``unit`` (str, "" = dimensionless) and ``tolerance`` (relative; default
          :data:`DEFAULT_TOLERANCE` when ``paper`` is given) are written to results.json and REPORT.md.
        - ``std`` and ``runs`` for Monte Carlo values (no std is written for a single run).
        - ``cell="Table 2 / x1 ESO"`` names the paper cell the quantity scores; quantities sharing a
          cell are counted once in the headline counts, by the one with ``primary=True`` (default: the
          first recorded in that cell). Quantities without a cell count individually.
        - ``diverged=True`` when every run diverged: pass ``value=None``; the verdict is
          ``diverged``. Equivalently give ``runs`` and ``runs_diverged`` equal, or ``runs=0`` (the
          number of healthy runs that contributed) with ``value=None``. A quantity some of whose runs diverged keeps its value (averaged
          over the healthy runs) and can record ``runs_diverged`` for the note.
        """
        if any(q.id == id for q in self.quantities):
            raise ValueError(f"quantity id {id!r} is already recorded in study {self.info.name!r}")
        q = Quantity(id=id, label=label, value=value, paper=paper, **kw)
        self.quantities.append(q)
        return q

    def reconstruction(self, name: str, value, why: str) -> None:
        """Record a value the paper does not print (or prints wrongly) and the reason for the choice."""
        self.reconstructions.append({"name": check_str("name", name), "value": value, "why": check_str("why", why)})

    def finding(self, id: str, text: str, evidence=None) -> None:
        """Record an erratum, an inconsistency, an irreproducible claim or an instability."""
        item = {"id": check_str("id", id), "text": check_str("text", text)}
        if evidence is not None:
            item["evidence"] = evidence
        self.findings.append(item)

    def get(self, id: str) -> Quantity:
        for q in self.quantities:
            if q.id == id:
                return q
        raise KeyError(id)

    def to_dict(self) -> dict:
        cells: dict = {}
        for q in self.quantities:
            if q.cell is not None and q.primary:
                if q.cell in cells:
                    raise ValueError(f"cell {q.cell!r} has two primary quantities: {cells[q.cell]!r} and {q.id!r}")
                cells[q.cell] = q.id
        return _to_jsonable(
            {
                "schema": RESULTS_SCHEMA,
                "study": self.info.name,
                "seed_file": self.info.seed_file,
                "paper": self.info.paper,
                "settings": self.settings,
                "reconstructions": self.reconstructions,
                "quantities": [q.to_dict() for q in self.quantities],
                "findings": self.findings,
                "figures": self.figures,
                "captions": {name: self.captions[name] for name in self.figures if name in self.captions},
                "missing": self.missing,
                "seeds": self.seeds,
                "runtime_s": round(self.runtime_s, 3),
                "versions": versions(),
            }
        )


@dataclass
class StudyContext:
    """What the CLI hands a study: where to write, how many runs, which seed, quick or full."""

    out_dir: Path
    runs: int | None = None
    seed: int = 0
    quick: bool = False
    progress: Callable[[str], None] = lambda msg: None
    jobs: int = 1
    scheduler: str | None = None

    def __post_init__(self):
        self.out_dir = Path(self.out_dir)
        if self.runs is not None:
            self.runs = check_int("runs", self.runs, minimum=1)
        self.seed = check_int("seed", self.seed, minimum=0)
        check_callable("progress", self.progress, "progress(message)")

    def runs_or(self, default: int, quick_default: int | None = None) -> int:
        """The requested number of Monte Carlo runs, or the study's default (smaller with --quick)."""
        default = check_int("default", default, minimum=1)
        if quick_default is not None:
            quick_default = check_int("quick_default", quick_default, minimum=1)
        if self.runs is not None:
            return self.runs
        if self.quick:
            return quick_default if quick_default is not None else max(1, min(default, 3))
        return default

    def save_figure(self, result: StudyResult, fig, filename: str, dpi: int = 120, caption: str | None = None) -> Path:
        """Save ``fig`` as ``out_dir/filename``, close it and list it in ``result.figures``.

        ``caption`` (what is plotted, which paper figure it redraws, what to compare) goes to
        ``result.captions[filename]`` and is printed under the figure in REPORT.md. In quick mode (a
        smoke test) the figure is rendered at no more than 50 dpi: rendering is most of its cost.
        """
        import matplotlib.pyplot as plt

        if not isinstance(result, StudyResult) or not hasattr(fig, "savefig"):
            raise TypeError(f"result must be a StudyResult and fig a matplotlib Figure, got {result!r}, {fig!r}")
        if Path(check_str("filename", filename)).name != filename or filename in (".", ".."):
            raise ValueError(f"filename must be a plain file name inside out_dir (no directory), got {filename!r}")
        dpi = check_int("dpi", dpi, minimum=1)
        if self.quick:
            dpi = min(dpi, 50)
        if caption is not None:
            if not isinstance(caption, str) or not caption.strip():
                raise ValueError(f"caption must be a non-empty string, got {caption!r}")
            result.captions[filename] = caption
        self.out_dir.mkdir(parents=True, exist_ok=True)
        path = self.out_dir / filename
        fig.savefig(path, dpi=dpi, bbox_inches=None if self.quick else "tight")
        plt.close(fig)
        if filename not in result.figures:
            result.figures.append(filename)
        return path


def versions() -> dict:
    """Versions of Python and the numeric stack, recorded in every results.json.

    Returns
    -------
    dict of str -> str
    """
    import control
    import matplotlib
    import scipy
    import sympy

    return {
        "python": platform.python_version(),
        "control": control.__version__,
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "sympy": sympy.__version__,
        "matplotlib": matplotlib.__version__,
    }


def write_results_json(result: StudyResult, out_dir: Path) -> Path:
    """Write ``out_dir/results.json`` atomically (the contract in DESIGN.md); validated first."""
    if not isinstance(result, StudyResult):
        raise TypeError(f"result must be a StudyResult, got {type(result).__name__}")
    out_dir = check_path("out_dir", out_dir)
    data = result.to_dict()
    validate_results(data)
    return write_text_atomic(out_dir / "results.json",
                             json.dumps(data, indent=2, ensure_ascii=False) + "\n")


_QUANTITY_KEYS = ("id", "label", "paper", "value", "std", "runs", "unit", "tolerance", "verdict", "note")
_RESULTS_KEYS = ("study", "seed_file", "settings", "reconstructions", "quantities", "findings", "figures",
                 "runtime_s", "versions")


def validate_results(data: dict) -> dict:
    """Check a results.json dict against the schema; return it unchanged or raise ``ValueError``.

    Rules: the top-level keys of DESIGN.md are present; every quantity has ``id``, ``label``,
    ``paper``, ``value``, ``std``, ``runs``, ``unit`` (a string, "" = dimensionless), ``tolerance``
    (a number >= 0 whenever ``paper`` is given), ``verdict`` in :data:`VERDICTS` and equal to the
    verdict recomputed from the record, ``paper`` None for ``new``, ``value`` None for ``diverged``;
    ids are unique and a paper cell has at most one primary quantity; ``captions``, when present, map
    figures of the study to non-empty strings.

    Parameters
    ----------
    data : dict
        A results.json dict.

    Returns
    -------
    dict
        ``data``, unchanged.

    Raises
    ------
    ValueError
        Naming the study, the quantity and the broken rule.
    """
    if not isinstance(data, dict):
        raise ValueError(f"data must be a results dict, got {type(data).__name__}")
    missing = [k for k in _RESULTS_KEYS if k not in data]
    if missing:
        raise ValueError(f"results of study {data.get('study')!r} lack keys {missing}")
    study = data["study"]
    if not isinstance(data["quantities"], list):
        raise ValueError(f"{study}: quantities must be a list")
    seen, primaries = set(), {}
    for i, q in enumerate(data["quantities"]):
        where = f"{study}: quantity {q.get('id', i)!r}" if isinstance(q, dict) else f"{study}: quantity #{i}"
        if not isinstance(q, dict):
            raise ValueError(f"{where} must be a dict")
        lack = [k for k in _QUANTITY_KEYS if k not in q]
        if lack:
            raise ValueError(f"{where} lacks keys {lack}")
        if q["id"] in seen:
            raise ValueError(f"{where} is recorded twice")
        seen.add(q["id"])
        if not isinstance(q["unit"], str):
            raise ValueError(f"{where}: unit must be a string ('' = dimensionless), got {q['unit']!r}")
        verdict = q["verdict"]
        if verdict not in VERDICTS:
            raise ValueError(f"{where}: verdict must be one of {list(VERDICTS)}, got {verdict!r}")
        tol = q["tolerance"]
        if q["paper"] is not None and (isinstance(tol, bool) or not isinstance(tol, (int, float))
                                       or not math.isfinite(tol) or tol < 0):
            raise ValueError(f"{where}: tolerance must be a number >= 0 when paper is given, got {tol!r}")
        if verdict == "new" and q["paper"] is not None:
            raise ValueError(f"{where}: verdict 'new' needs paper None, got {q['paper']!r}")
        if verdict == "diverged" and q["value"] is not None:
            raise ValueError(f"{where}: verdict 'diverged' needs value None, got {q['value']!r}")
        recomputed = compute_verdict(q["value"], q["paper"], tol, diverged=verdict == "diverged")
        if recomputed != verdict:
            raise ValueError(f"{where}: verdict {verdict!r} does not follow from value, paper and tolerance "
                             f"({recomputed!r})")
        if q.get("cell") is not None:
            if not isinstance(q["cell"], str):
                raise ValueError(f"{where}: cell must be a string, got {q['cell']!r}")
            if q.get("primary"):
                if q["cell"] in primaries:
                    raise ValueError(f"{where}: cell {q['cell']!r} already has primary {primaries[q['cell']]!r}")
                primaries[q["cell"]] = q["id"]
    captions = data.get("captions", {})
    if not isinstance(captions, dict) or not all(isinstance(v, str) and v.strip() for v in captions.values()):
        raise ValueError(f"{study}: captions must map figure names to non-empty strings, got {captions!r}")
    stray = [name for name in captions if name not in data["figures"]]
    if stray:
        raise ValueError(f"{study}: captions {stray} name no figure of the study")
    return data


def count_verdicts(results: dict) -> dict:
    """Headline counts of one results.json dict: ``{verdict: n}`` over paper cells, each scored once.

    Quantities sharing a ``cell`` count once, with the verdict of the one marked ``primary`` (default:
    the first in that cell); quantities without a cell count individually.

    Parameters
    ----------
    results : dict
        A results.json dict.

    Returns
    -------
    dict
        ``{verdict: count}`` for every verdict of :data:`VERDICTS`.

    Raises
    ------
    ValueError
        If ``results`` has no ``quantities`` list.
    """
    if not isinstance(results, dict) or not isinstance(results.get("quantities"), list):
        raise ValueError(f"results must be a results.json dict with a 'quantities' list, got {type(results).__name__}")
    counts = dict.fromkeys(VERDICTS, 0)
    by_cell: dict = {}
    for q in results["quantities"]:
        cell = q.get("cell")
        if cell is None:
            counts[q["verdict"]] += 1
        elif cell not in by_cell or (q.get("primary") and not by_cell[cell].get("primary")):
            by_cell[cell] = q
    for q in by_cell.values():
        counts[q["verdict"]] += 1
    return counts


def new_figure(nrows: int = 1, ncols: int = 1, *, title: str | None = None, size=(7.0, 4.5), **kw):
    """A figure in the toolkit's style (object API, grid on, readable size). Returns (fig, axes)."""
    import matplotlib

    nrows = check_int("nrows", nrows, minimum=1)
    ncols = check_int("ncols", ncols, minimum=1)
    size = np.atleast_1d(check_positive("size", size))
    if size.shape != (2,):
        raise ValueError(f"size must be (width, height) in inches, got {size.tolist()}")
    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(nrows, ncols, figsize=tuple(size), squeeze=True, constrained_layout=True, **kw)
    for ax in np.atleast_1d(axes).ravel():
        ax.grid(True, alpha=0.25)
    if title:
        fig.suptitle(title)
    return fig, axes


class Stopwatch:
    """Wall-clock timer for ``runtime_s``."""

    def __init__(self):
        self.t0 = time.perf_counter()

    def elapsed(self) -> float:
        return time.perf_counter() - self.t0


def __getattr__(name):
    """REPORT.md writing lives in :mod:`.report_md`; its functions are re-exported here lazily (so either
    module can be imported first)."""
    if name in ("summary_table", "write_report_md"):
        from . import report_md

        return getattr(report_md, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
