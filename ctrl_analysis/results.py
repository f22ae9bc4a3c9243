"""Result records of a study: quantities beside the paper's values, computed verdicts, findings.

:class:`StudyResult` is what a study's ``run`` returns; :meth:`StudyResult.to_dict` is the
results.json contract (schema :data:`RESULTS_SCHEMA`). A verdict is computed from the value, the
paper's value and the relative tolerance, never typed in.
"""

from __future__ import annotations

import math
import platform
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ._validate import check_array, check_bool, check_int, check_nonnegative, check_str

__all__ = ["VERDICTS", "RESULTS_SCHEMA", "DEFAULT_TOLERANCE", "Quantity", "StudyInfo", "StudyResult",
           "compute_verdict", "relative_error", "versions"]

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
    """Largest element-wise relative error ``|value - paper| / |paper|`` (absolute where ``paper == 0``).

    Parameters
    ----------
    value, paper : float or array_like
        Reproduced and printed values (vectors of the same length).

    Returns
    -------
    float
        The error; ``inf`` for a length mismatch or a non-finite value.
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
    """The verdict of a reproduced value beside the paper's.

    Parameters
    ----------
    value : float, array_like or None
        Reproduced value.
    paper : float, array_like or None
        Printed value (``None``: the paper does not print it).
    tolerance : float or None
        Relative tolerance (default :data:`DEFAULT_TOLERANCE`).
    diverged : bool
        Every run diverged.

    Returns
    -------
    str
        ``diverged``; ``new`` without a paper value; else ``agrees`` within the tolerance, or ``differs``.
    """
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

    Parameters
    ----------
    id, label : str
        Stable id (e.g. ``ex1.mfac.rmse``) and a label for readers.
    value, paper, std : float, array_like or None
        Reproduced value, printed value (only what the paper prints) and the Monte Carlo std.
    runs, runs_diverged : int, optional
        Runs in the value and how many of them diverged.
    tolerance : float, optional
        Relative tolerance of the verdict.
    note, unit : str
        Free note; unit ("" = dimensionless).
    cell : str, optional
        The paper cell the quantity scores.
    primary, diverged : bool
        The cell's primary reading; every run diverged.
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
        """The computed verdict (:func:`compute_verdict`), one of :data:`VERDICTS`.

        Returns
        -------
        str
        """
        return compute_verdict(self.value, self.paper, self.tolerance, diverged=self.diverged)

    def to_dict(self) -> dict:
        """The quantity as results.json writes it (numpy converted, non-finite numbers as null).

        Returns
        -------
        dict
        """
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
    """What a study is: its CLI name, seed file, paper and what it reproduces.

    Parameters
    ----------
    name : str
        CLI name (non-empty).
    seed_file, paper, reproduces : str
        The paper's text file in ``shared/seeds``, its citation, and what the study reproduces.
    """

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
    """Everything one study reproduced; serialised to results.json.

    Parameters
    ----------
    info : StudyInfo
    settings, seeds, captions : dict, optional
        Every parameter used, the per-run seeds, and a caption per figure.
    reconstructions, quantities, findings, figures, missing : list, optional
        Filled through :meth:`reconstruction`, :meth:`quantity`, :meth:`finding` and the context's
        ``save_figure``; ``missing`` lists what the study does not reproduce.
    runtime_s : float
        Wall time of the study (set by the CLI).
    """

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
          number of healthy runs that contributed) with ``value=None``. A quantity some of whose runs
          diverged keeps its value (averaged over the healthy runs) and can record ``runs_diverged``.

        Parameters
        ----------
        id, label : str
            Stable id and label.
        value, paper : object
            Reproduced and printed values.
        **kw
            The other fields of :class:`Quantity`.

        Returns
        -------
        Quantity
        """
        if any(q.id == id for q in self.quantities):
            raise ValueError(f"quantity id {id!r} is already recorded in study {self.info.name!r}")
        q = Quantity(id=id, label=label, value=value, paper=paper, **kw)
        self.quantities.append(q)
        return q

    def reconstruction(self, name: str, value, why: str) -> None:
        """Record a value the paper does not print (or prints wrongly) and the reason for the choice.

        Parameters
        ----------
        name : str
        value : object
        why : str
        """
        self.reconstructions.append({"name": check_str("name", name), "value": value, "why": check_str("why", why)})

    def finding(self, id: str, text: str, evidence=None) -> None:
        """Record an erratum, an inconsistency, an irreproducible claim or an instability.

        Parameters
        ----------
        id, text : str
            Stable id and the finding, generated from computed numbers.
        evidence : object, optional
            The numbers behind it (kept whole in results.json, summarised in REPORT.md).
        """
        item = {"id": check_str("id", id), "text": check_str("text", text)}
        if evidence is not None:
            item["evidence"] = evidence
        self.findings.append(item)

    def get(self, id: str) -> Quantity:
        """The recorded quantity ``id``.

        Parameters
        ----------
        id : str

        Returns
        -------
        Quantity

        Raises
        ------
        KeyError
            If no quantity has that id.
        """
        for q in self.quantities:
            if q.id == id:
                return q
        raise KeyError(id)

    def to_dict(self) -> dict:
        """The results.json contract (schema :data:`RESULTS_SCHEMA`).

        Returns
        -------
        dict

        Raises
        ------
        ValueError
            If a paper cell has two primary quantities.
        """
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
