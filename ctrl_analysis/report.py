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

__all__ = [
    "Quantity",
    "StudyInfo",
    "StudyContext",
    "StudyResult",
    "compute_verdict",
    "relative_error",
    "versions",
    "write_results_json",
    "write_report_md",
    "new_figure",
]

VERDICTS = ("agrees", "differs", "new")
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
    v = np.atleast_1d(np.asarray(value, dtype=float))
    p = np.atleast_1d(np.asarray(paper, dtype=float))
    if v.shape != p.shape or not np.all(np.isfinite(v)):
        return math.inf
    scale = np.where(p == 0, 1.0, np.abs(p))
    return float(np.max(np.abs(v - p) / scale))


def compute_verdict(value, paper, tolerance: float | None) -> str:
    """``new`` without a paper value; else ``agrees`` when the relative error is within tolerance."""
    if paper is None:
        return "new"
    tol = DEFAULT_TOLERANCE if tolerance is None else tolerance
    if value is None:
        return "differs"
    return "agrees" if relative_error(value, paper) <= tol else "differs"


@dataclass
class Quantity:
    """One reproduced number (or vector) beside the paper's.

    ``verdict`` is computed from ``value``, ``paper`` and ``tolerance`` (relative); it is never set by hand.
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

    @property
    def verdict(self) -> str:
        return compute_verdict(self.value, self.paper, self.tolerance)

    def to_dict(self) -> dict:
        d = {
            "id": self.id,
            "label": self.label,
            "paper": self.paper,
            "value": self.value,
            "std": self.std,
            "runs": self.runs,
            "tolerance": (DEFAULT_TOLERANCE if self.tolerance is None else self.tolerance)
            if self.paper is not None
            else None,
            "verdict": self.verdict,
            "note": self.note,
        }
        if self.unit:
            d["unit"] = self.unit
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


@dataclass
class StudyResult:
    """Everything one study reproduced; serialised to results.json."""

    info: StudyInfo
    settings: dict = field(default_factory=dict)
    reconstructions: list = field(default_factory=list)
    quantities: list = field(default_factory=list)
    findings: list = field(default_factory=list)
    figures: list = field(default_factory=list)
    missing: list = field(default_factory=list)
    seeds: dict = field(default_factory=dict)
    runtime_s: float = 0.0

    def quantity(self, id: str, label: str, value, paper=None, **kw) -> Quantity:
        """Add (or replace) a quantity and return it."""
        if any(q.id == id for q in self.quantities):
            raise ValueError(f"quantity id {id!r} is already recorded in study {self.info.name!r}")
        q = Quantity(id=id, label=label, value=value, paper=paper, **kw)
        self.quantities.append(q)
        return q

    def reconstruction(self, name: str, value, why: str) -> None:
        """Record a value the paper does not print (or prints wrongly) and the reason for the choice."""
        self.reconstructions.append({"name": name, "value": value, "why": why})

    def finding(self, id: str, text: str, evidence=None) -> None:
        """Record an erratum, an inconsistency, an irreproducible claim or an instability."""
        item = {"id": id, "text": text}
        if evidence is not None:
            item["evidence"] = evidence
        self.findings.append(item)

    def get(self, id: str) -> Quantity:
        for q in self.quantities:
            if q.id == id:
                return q
        raise KeyError(id)

    def to_dict(self) -> dict:
        return _to_jsonable(
            {
                "study": self.info.name,
                "seed_file": self.info.seed_file,
                "paper": self.info.paper,
                "settings": self.settings,
                "reconstructions": self.reconstructions,
                "quantities": [q.to_dict() for q in self.quantities],
                "findings": self.findings,
                "figures": self.figures,
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

    def runs_or(self, default: int, quick_default: int | None = None) -> int:
        """The requested number of Monte Carlo runs, or the study's default (smaller with --quick)."""
        if self.runs is not None:
            return self.runs
        if self.quick:
            return quick_default if quick_default is not None else max(1, min(default, 3))
        return default

    def save_figure(self, result: StudyResult, fig, filename: str, dpi: int = 120) -> Path:
        """Save ``fig`` as ``out_dir/filename``, close it and list it in ``result.figures``."""
        import matplotlib.pyplot as plt

        self.out_dir.mkdir(parents=True, exist_ok=True)
        path = self.out_dir / filename
        fig.savefig(path, dpi=dpi, bbox_inches="tight")
        plt.close(fig)
        if filename not in result.figures:
            result.figures.append(filename)
        return path


def versions() -> dict:
    """Versions of Python and the numeric stack, recorded in every results.json."""
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
    """Write ``out_dir/results.json`` (the contract in DESIGN.md)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "results.json"
    path.write_text(json.dumps(result.to_dict(), indent=2, ensure_ascii=False) + "\n", encoding="utf-8")
    return path


def _fmt(value, std=None) -> str:
    if value is None:
        return "—"
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_fmt(v) for v in np.ravel(np.asarray(value, dtype=object))) + "]"
    if isinstance(value, bool):
        return str(int(value))
    if isinstance(value, (int, np.integer)):
        return str(value)
    try:
        v = float(value)
    except (TypeError, ValueError):
        return str(value)
    text = f"{v:.4g}"
    if std is not None:
        text += f" ± {_fmt(std)}"
    return text


def _cell(text) -> str:
    """Text safe inside a Markdown table cell (pipes escaped, one line)."""
    return str(text or "").replace("|", "\\|").replace("\n", " ")


def summary_table(results: dict) -> str:
    """A Markdown table of the quantities of one results.json dict."""
    rows = ["| id | quantity | paper | reproduced | verdict | note |", "|---|---|---|---|---|---|"]
    for q in results["quantities"]:
        note = _cell(q.get("note"))
        rows.append(
            f"| `{q['id']}` | {_cell(q['label'])} | {_fmt(q['paper'])} | {_fmt(q['value'], q.get('std'))}"
            f"{' (' + str(q['runs']) + ' runs)' if q.get('runs') else ''} | {q['verdict']} | {note} |"
        )
    return "\n".join(rows)


def write_report_md(results: list[dict], out_dir: Path) -> Path:
    """Write ``out_dir/REPORT.md`` from the results.json dicts of several studies."""
    lines = [
        "# ctrl-analysis: reproduction report",
        "",
        "Generated by `ctrl-analysis reproduce all`. Every reproduced value below was computed by the code;",
        "verdicts are computed from the relative tolerance shown in each study's results.json.",
        "",
    ]
    for r in results:
        counts = {v: sum(q["verdict"] == v for q in r["quantities"]) for v in VERDICTS}
        lines += [
            f"## {r['study']}",
            "",
            f"*{r['paper']}* — seed `{r['seed_file']}`. "
            f"{counts['agrees']} agree, {counts['differs']} differ, {counts['new']} new; "
            f"runtime {r['runtime_s']:.1f} s.",
            "",
        ]
        if r.get("missing"):
            lines += ["**Not built yet:** " + "; ".join(r["missing"]), ""]
        if r["quantities"]:
            lines += [summary_table(r), ""]
        if r["reconstructions"]:
            lines += ["### Reconstructions", ""]
            lines += [f"- **{c['name']}** = `{_fmt(c['value'])}` — {c['why']}" for c in r["reconstructions"]]
            lines.append("")
        if r["findings"]:
            lines += ["### Findings", ""]
            lines += [f"- **{f['id']}**: {f['text']}" for f in r["findings"]]
            lines.append("")
        if r["figures"]:
            lines += ["### Figures", ""]
            lines += [f"![{name}]({r['study']}/{name})" for name in r["figures"]]
            lines.append("")
    path = out_dir / "REPORT.md"
    out_dir.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def new_figure(nrows: int = 1, ncols: int = 1, *, title: str | None = None, size=(7.0, 4.5), **kw):
    """A figure in the toolkit's style (object API, grid on, readable size). Returns (fig, axes)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(nrows, ncols, figsize=size, squeeze=True, constrained_layout=True, **kw)
    for ax in np.atleast_1d(axes).ravel():
        ax.grid(True, alpha=0.3)
    if title:
        fig.suptitle(title)
    return fig, axes


class Stopwatch:
    """Wall-clock timer for ``runtime_s``."""

    def __init__(self):
        self.t0 = time.perf_counter()

    def elapsed(self) -> float:
        return time.perf_counter() - self.t0
