"""What a study is handed (StudyContext), results.json writing and its schema check, and the figure style.

The result records themselves (:class:`Quantity`, :class:`StudyResult`, computed verdicts) are in
:mod:`ctrl_analysis.reporting.results` and re-exported here; REPORT.md is written by
:mod:`ctrl_analysis.reporting.markdown`
(import it from there: this module does not import it, so the two form no import circle).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._validate import check_callable, check_int, check_path, check_positive, check_str
from ..noise import MAX_RUNS
from .atomic import staged_directory, write_text_atomic  # noqa: F401 (public API)
from .results import (  # noqa: F401 (public API)
    CLAIM_VERDICTS,
    DEFAULT_TOLERANCE,
    KINDS,
    RESULTS_SCHEMA,
    VERDICTS,
    Quantity,
    StudyInfo,
    StudyResult,
    compute_verdict,
    relative_error,
    versions,
)
from .verdicts import claim_verdict

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
    "read_runtime",
    "validate_results",
    "versions",
    "write_text_atomic",
    "staged_directory",
    "write_results_json",
    "new_figure",
]

def _silent(message: str) -> None:
    """The default progress sink of :class:`StudyContext`: discard the message.

    Parameters
    ----------
    message : str

    Returns
    -------
    None
    """


@dataclass
class StudyContext:
    """What the CLI hands a study: where to write, how many runs, which seed, quick or full.

    Parameters
    ----------
    out_dir : Path
        Where the study writes its figures (a staging directory during a CLI run).
    runs : int, optional
        Monte Carlo runs asked for (``--runs``); ``None``: the study's default.
    seed : int
        Base seed (``--seed``).
    quick : bool
        Fewer runs and shorter horizons, figures at low resolution (``--quick``).
    progress : callable
        ``progress(message)``, where the study reports what it is doing.
    jobs : int
        Processes the study may use (``--jobs``).
    scheduler : str, optional
        A Dask scheduler address (``--scheduler``).
    """

    out_dir: Path
    runs: int | None = None
    seed: int = 0
    quick: bool = False
    progress: Callable[[str], None] = _silent
    jobs: int = 1
    scheduler: str | None = None
    _pending: list = field(default_factory=list, init=False, repr=False, compare=False)

    def __post_init__(self):
        self.out_dir = check_path("out_dir", self.out_dir)
        if self.runs is not None:
            self.runs = check_int("runs", self.runs, minimum=1, maximum=MAX_RUNS)
        self.seed = check_int("seed", self.seed, minimum=0)
        self.jobs = check_int("jobs", self.jobs, minimum=1)
        check_callable("progress", self.progress, "progress(message)")

    def runs_or(self, default: int, quick_default: int | None = None) -> int:
        """The requested number of Monte Carlo runs, or the study's default (smaller with --quick).

        Parameters
        ----------
        default : int
            The study's default number of runs.
        quick_default : int, optional
            The default with ``--quick`` (else ``min(default, 3)``).

        Returns
        -------
        int
        """
        default = check_int("default", default, minimum=1, maximum=MAX_RUNS)
        if quick_default is not None:
            quick_default = check_int("quick_default", quick_default, minimum=1, maximum=MAX_RUNS)
        if self.runs is not None:
            return self.runs
        if self.quick:
            return quick_default if quick_default is not None else max(1, min(default, 3))
        return default

    def save_figure(self, result: StudyResult, fig, filename: str, dpi: int = 120, caption: str | None = None) -> Path:
        """Save ``fig`` as ``out_dir/filename``, close it and list it in ``result.figures``.

        ``caption`` (what is plotted, which paper figure it redraws, what to compare) goes to
        ``result.captions[filename]`` and is printed under the figure in REPORT.md. In quick mode (a
        smoke test) the figure is rendered at no more than 50 dpi, without the tight bounding box and
        without a layout engine (constrained layout is most of the rendering cost).

        In a study driver of a run with a shared pool (``reproduce all`` on more cores than studies,
        :mod:`ctrl_analysis.runs.taskpool`) the figure is pickled and rendered by a worker of the pool
        while the study goes on (the PNG is the same bytes: the worker runs the same matplotlib on
        the same figure); :meth:`wait_figures` waits for them. A figure that does not pickle (one
        holding a lambda) is rendered here.

        Parameters
        ----------
        result : StudyResult
        fig : matplotlib.figure.Figure
        filename : str
            A plain file name (no directory).
        dpi : int
            Resolution.
        caption : str, optional

        Returns
        -------
        Path
            The file written.
        """
        import matplotlib.pyplot as plt

        path, dpi, bbox = self._prepare(result, fig, filename, dpi, caption)
        if not self._render_elsewhere(fig, path, dpi, bbox):
            fig.savefig(path, dpi=dpi, bbox_inches=bbox)
        plt.close(fig)
        self._listed(result, filename)
        return path

    def save_figures(self, result: StudyResult, figures) -> list[Path]:
        """Save several figures as :meth:`save_figure` does each, rendered side by side over ``jobs`` processes.

        The same PNG bytes as saving them one by one (each is pickled and rendered by the same
        matplotlib); in a run's shared pool each goes to the pool as :meth:`save_figure` sends it. A
        figure that does not pickle is rendered here.

        Parameters
        ----------
        result : StudyResult
        figures : sequence of tuple
            ``(fig, filename, caption)`` or ``(fig, filename, caption, dpi)`` (default 120).

        Returns
        -------
        list of Path
            The files written, in the order of ``figures``.
        """
        import matplotlib.pyplot as plt

        from ..runs.parallel import map_chunks
        from ..runs.taskpool import pool_available

        if isinstance(figures, (str, bytes)) or not hasattr(figures, "__iter__"):
            raise TypeError(f"figures must be a sequence of (fig, filename, caption[, dpi]), got {figures!r:.80}")
        figures = list(figures)
        if not all(isinstance(f, tuple) and len(f) in (3, 4) for f in figures):
            raise TypeError("figures must be a sequence of (fig, filename, caption[, dpi]) tuples")
        if pool_available() or self.jobs == 1 or len(figures) < 2:
            return [self.save_figure(result, f[0], f[1], dpi=f[3] if len(f) == 4 else 120, caption=f[2])
                    for f in figures]
        tasks, paths = [], []
        for f in figures:
            fig, filename = f[0], f[1]
            path, dpi, bbox = self._prepare(result, fig, filename, f[3] if len(f) == 4 else 120, f[2])
            blob = _pickled(fig)
            if blob is None:  # a figure holding a lambda: rendered here
                fig.savefig(path, dpi=dpi, bbox_inches=bbox)
            else:
                tasks.append((blob, str(path), dpi, bbox))
            plt.close(fig)
            paths.append(path)
        map_chunks(_render_figure, tasks, jobs=max(1, min(self.jobs, len(tasks))), scheduler=False, desc="figures",
                   unit="figure")
        for f in figures:
            self._listed(result, f[1])
        return paths

    def _prepare(self, result, fig, filename, dpi, caption) -> tuple:
        """Check a figure's arguments, record its caption and apply quick mode: ``(path, dpi, bbox_inches)``."""
        if not isinstance(result, StudyResult) or not hasattr(fig, "savefig"):
            raise TypeError(f"result must be a StudyResult and fig a matplotlib Figure, got {result!r}, {fig!r}")
        if Path(check_str("filename", filename)).name != filename or filename in (".", ".."):
            raise ValueError(f"filename must be a plain file name inside out_dir (no directory), got {filename!r}")
        dpi = check_int("dpi", dpi, minimum=1)
        if self.quick:
            dpi = min(dpi, 50)
            fig.set_layout_engine("none")
        if caption is not None:
            if not isinstance(caption, str) or not caption.strip():
                raise ValueError(f"caption must be a non-empty string, got {caption!r}")
            result.captions[filename] = caption
        self.out_dir.mkdir(parents=True, exist_ok=True)
        return self.out_dir / filename, dpi, None if self.quick else "tight"

    @staticmethod
    def _listed(result, filename) -> None:
        if filename not in result.figures:
            result.figures.append(filename)

    def _render_elsewhere(self, fig, path: Path, dpi: int, bbox) -> bool:
        """Send ``fig`` to the run's shared pool to be saved as ``path``; False when it must be saved here."""
        import threading

        from ..runs.progress import _CONTEXT
        from ..runs.taskpool import lane_fields, map_on_pool, pool_available, trace_event

        if not pool_available():
            return False
        blob = _pickled(fig)
        if blob is None:  # e.g. a FuncFormatter holding a lambda: rendered here instead
            return False
        failed: list = []
        label, lane = _CONTEXT["label"], lane_fields()  # sent from a chain of drive(): the trace says which

        def render():
            import time

            submitted, cpu = time.time(), time.process_time()
            try:
                value = map_on_pool(_render_figure, [(blob, str(path), dpi, bbox)], lambda i, v: None,
                                    priority=lane.get("priority", 0))[0]
            except BaseException as exc:  # noqa: BLE001 - raised by wait_figures in the study's thread
                failed.append(exc)
                return
            # the driver does not wait for it: its CPU clock does not advance over the render (scaling.py)
            trace_event({"kind": "map", "async": True, "study": label, "where": "pool", "submitted": submitted,
                         "returned": time.time(), "cpu_submitted": cpu, "cpu_returned": cpu, "calls": [value[1:]],
                         **lane})

        thread = threading.Thread(target=render, daemon=True, name=f"ctrl-analysis-render {path.name}")
        thread.start()
        self._pending.append((thread, failed, path.name))
        return True

    def wait_figures(self) -> None:
        """Wait for the figures :meth:`save_figure` sent to the run's pool.

        Raises
        ------
        RuntimeError
            Naming the first figure that could not be rendered (after every render has ended).
        """
        pending, self._pending = self._pending, []
        for thread, _, _ in pending:
            thread.join()
        for _, failed, name in pending:
            if failed:
                raise RuntimeError(f"figure {name} could not be rendered: {type(failed[0]).__name__}: "
                                   f"{failed[0]}") from failed[0]


def _pickled(fig) -> bytes | None:
    """``fig`` pickled (to be rendered in another process), or ``None`` when it does not pickle."""
    import pickle

    try:
        return pickle.dumps(fig)
    except Exception:  # noqa: BLE001 - any figure that does not pickle is rendered where it was drawn
        return None


def _render_figure(task) -> str:
    """Save a pickled matplotlib figure as a PNG (a pool worker's half of :meth:`StudyContext.save_figure`).

    Parameters
    ----------
    task : tuple
        ``(pickled figure, path, dpi, bbox_inches)``.

    Returns
    -------
    str
        The path written.
    """
    import pickle

    import matplotlib

    blob, path, dpi, bbox = task
    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    fig = pickle.loads(blob)
    try:
        fig.savefig(path, dpi=dpi, bbox_inches=bbox)
    finally:
        plt.close(fig)
    return path


def write_results_json(result: StudyResult, out_dir: Path) -> Path:
    """Write ``out_dir/results.json`` atomically (the contract in DESIGN.md); validated first.

    Parameters
    ----------
    result : StudyResult
    out_dir : str or Path

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    ValueError
        If the record breaks the schema (:func:`validate_results`).
    """
    if not isinstance(result, StudyResult):
        raise TypeError(f"result must be a StudyResult, got {type(result).__name__}")
    out_dir = check_path("out_dir", out_dir)
    data = result.to_dict()
    validate_results(data)
    # what differs from run to run (the wall time) goes beside results.json, not into it: a results.json
    # (tracked in the repository's figures/) is reproduced byte for byte by the command that wrote it
    write_text_atomic(out_dir / TIMING, json.dumps({"runtime_s": round(result.runtime_s, 3)}) + "\n")
    return write_text_atomic(out_dir / "results.json",
                             json.dumps(data, indent=2, ensure_ascii=False) + "\n")


def read_runtime(study_dir) -> float | None:
    """The wall time of the study written into ``study_dir`` (its ``timing.json``), or None when unknown.

    Parameters
    ----------
    study_dir : str or Path

    Returns
    -------
    float or None
    """
    study_dir = check_path("study_dir", study_dir)
    try:
        value = float(json.loads((study_dir / TIMING).read_text(encoding="utf-8"))["runtime_s"])
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return value if math.isfinite(value) and value >= 0 else None


#: The file beside results.json holding what varies between identical runs (the wall time); not tracked.
TIMING = "timing.json"


_QUANTITY_KEYS = ("id", "label", "paper", "value", "std", "runs", "unit", "tolerance", "verdict", "note")
_CLAIM_KEYS = ("id", "section", "statement", "verdict", "base_verdict", "evidence", "depends_on")
_RESULTS_KEYS = ("study", "seed_file", "settings", "reconstructions", "quantities", "findings", "figures",
                 "versions")


def validate_results(data: dict) -> dict:
    """Check a results.json dict against the schema; return it unchanged or raise ``ValueError``.

    Rules: the top-level keys of DESIGN.md are present; every quantity has ``id``, ``label``,
    ``paper``, ``value``, ``std``, ``runs``, ``unit`` (a string, "" = dimensionless), ``tolerance``
    (a number >= 0 whenever ``paper`` is given), ``verdict`` in :data:`VERDICTS` and equal to the
    verdict recomputed from the record, ``paper`` None for ``new``, ``value`` None for ``diverged``;
    ids are unique and a paper cell has at most one primary quantity; ``captions``, when present, map
    figures of the study to non-empty strings; ``claims``, when present, have a verdict in
    :data:`CLAIM_VERDICTS` that follows from their base verdict and ``support`` (the policy's thresholds), and cite
    recorded
    quantities. Verdicts are recomputed under the stated policy (``percentile`` from ``interval``,
    ``derived`` from the quantity named by ``derived_from``, else ``tolerance``).

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
        raise ValueError(f"data (results of study {data.get('study')!r}) lack keys {missing}")
    study = data["study"]
    if not isinstance(data["quantities"], list):
        raise ValueError(f"{study}: quantities must be a list")
    seen, primaries = set(), {}
    by_id = {q.get("id"): q for q in data["quantities"] if isinstance(q, dict)}
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
        if q.get("kind", "reproduction") not in KINDS:
            raise ValueError(f"{where}: kind must be one of {list(KINDS)}, got {q.get('kind')!r}")
        verdict = q["verdict"]
        if verdict not in VERDICTS:
            raise ValueError(f"{where}: verdict must be one of {list(VERDICTS)}, got {verdict!r}")
        tol = q["tolerance"]
        if q["paper"] is not None and (isinstance(tol, bool) or not isinstance(tol, (int, float))
                                       or not math.isfinite(tol) or tol < 0):
            raise ValueError(f"{where}: tolerance must be a number >= 0 when paper is given, got {tol!r}")
        if verdict == "new" and q["paper"] is not None:
            raise ValueError(f"{where}: verdict 'new' needs paper None, got {q['paper']!r}")
        runs, bad = q.get("runs"), q.get("runs_diverged")
        if runs and bad == runs and q["value"] is not None:
            raise ValueError(f"{where}: every run diverged, so verdict 'diverged' needs value None, got {q['value']!r}")
        diverged = bool(runs and bad and 2 * bad >= runs) or (verdict == "diverged" and q["value"] is None)
        if q.get("policy") == "derived" and verdict not in ("new", "diverged"):
            src = by_id.get(q.get("derived_from"))
            recomputed = src["verdict"] if isinstance(src, dict) else None
        else:
            recomputed = compute_verdict(q["value"], q["paper"], tol, diverged=diverged,
                                         interval=q.get("interval") if q.get("policy") == "percentile" else None)
            if recomputed == "differs" and (q.get("box") or {}).get("verdict") == "reachable":
                recomputed = "reachable"
        if recomputed != verdict:
            raise ValueError(f"{where}: verdict {verdict!r} does not follow from value, paper and the "
                             f"{q.get('policy') or 'tolerance'} policy ({recomputed!r})")
        if q.get("cell") is not None:
            if not isinstance(q["cell"], str):
                raise ValueError(f"{where}: cell must be a string, got {q['cell']!r}")
            if q.get("primary"):
                if q["cell"] in primaries:
                    raise ValueError(f"{where}: cell {q['cell']!r} already has primary {primaries[q['cell']]!r}")
                primaries[q["cell"]] = q["id"]
    _validate_claims(study, data.get("claims", []), seen)
    captions = data.get("captions", {})
    if not isinstance(captions, dict) or not all(isinstance(v, str) and v.strip() for v in captions.values()):
        raise ValueError(f"{study}: captions must map figure names to non-empty strings, got {captions!r}")
    stray = [name for name in captions if name not in data["figures"]]
    if stray:
        raise ValueError(f"{study}: captions {stray} name no figure of the study")
    return data


def _validate_claims(study: str, claims, ids: set) -> None:
    """The ``claims`` list: keys, verdicts that follow from base verdict and support, cited ids recorded."""
    if not isinstance(claims, list):
        raise ValueError(f"{study}: claims must be a list")
    seen = set()
    for c in claims:
        if not isinstance(c, dict) or any(k not in c for k in _CLAIM_KEYS):
            raise ValueError(f"{study}: a claim lacks keys {[k for k in _CLAIM_KEYS if k not in (c or {})]}")
        where = f"{study}: claim {c['id']!r}"
        if c["id"] in seen:
            raise ValueError(f"{where} is judged twice")
        seen.add(c["id"])
        if c["verdict"] not in CLAIM_VERDICTS or c["base_verdict"] not in ("holds", "fails", "untestable"):
            raise ValueError(f"{where}: verdict must be one of {list(CLAIM_VERDICTS)}, got {c['verdict']!r}")
        support = c.get("support")
        if support is not None and not (isinstance(support, dict) and "holds" in support):
            raise ValueError(f"{where}: support must be a dict with 'holds', got {support!r}")
        expected = claim_verdict((support or {}).get("holds"), c["base_verdict"])
        if c["verdict"] != expected:
            raise ValueError(f"{where}: verdict {c['verdict']!r} does not follow from base verdict "
                             f"{c['base_verdict']!r} and support {(support or {}).get('holds')!r} ({expected!r})")
        unknown = [e for e in c["evidence"] if e not in ids]
        if unknown:
            raise ValueError(f"{where} cites quantities that are not recorded: {unknown}")


def count_verdicts(results: dict) -> dict:
    """Headline counts of one results.json dict: ``{verdict: n}`` over paper cells, each scored once.

    Quantities sharing a ``cell`` count once, with the verdict of the one marked ``primary`` (default:
    the first in that cell); quantities without a cell count individually; checks (``kind="check"``)
    are not counted.

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
        if q.get("kind", "reproduction") == "check":
            continue
        cell = q.get("cell")
        if cell is None:
            counts[q["verdict"]] += 1
        elif cell not in by_cell or (q.get("primary") and not by_cell[cell].get("primary")):
            by_cell[cell] = q
    for q in by_cell.values():
        counts[q["verdict"]] += 1
    return counts


#: Most axes :func:`new_figure` draws (a grid of thousands takes minutes to lay out).
MAX_AXES = 100


def new_figure(nrows: int = 1, ncols: int = 1, *, title: str | None = None, size=(7.0, 4.5), **kw):
    """A figure in the toolkit's style (object API, grid on, readable size, constrained layout).

    Parameters
    ----------
    nrows, ncols : int
        Subplot grid.
    title : str, optional
        Figure title (what is plotted, never a conclusion).
    size : (float, float)
        Width and height in inches.
    **kw
        Passed to :func:`matplotlib.pyplot.subplots` (e.g. ``sharex``).

    Returns
    -------
    fig : matplotlib.figure.Figure
    axes : matplotlib.axes.Axes or numpy.ndarray of them
    """
    import matplotlib

    nrows = check_int("nrows", nrows, minimum=1, maximum=MAX_AXES)
    ncols = check_int("ncols", ncols, minimum=1, maximum=MAX_AXES)
    if nrows * ncols > MAX_AXES:
        raise ValueError(f"nrows * ncols must be <= {MAX_AXES} axes (MAX_AXES), got nrows={nrows}, ncols={ncols}")
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
