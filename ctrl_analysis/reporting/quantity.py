"""One reproduced number beside the paper's, with its computed verdict (:class:`Quantity`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._validate import (
    check_array,
    check_bool,
    check_finite,
    check_int,
    check_nonnegative,
    check_str,
)
from .verdicts import (
    DEFAULT_TOLERANCE,
    KINDS,
    VERDICTS,
    _check_tolerance,
    central_interval,
    compute_verdict,
    printed_tolerance,
)

__all__ = ["Quantity"]


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


@dataclass
class Quantity:
    """One reproduced number (or vector) beside the paper's.

    ``verdict`` is computed, never set by hand, by the verdict policy (:data:`VERDICT_POLICY`):

    - ``samples`` (one value per healthy Monte Carlo run) with a scalar ``paper``: the *percentile*
      policy, the paper's value agrees when it lies within the central 95 % of the runs
      (:func:`central_interval`); its percentile among the runs is recorded;
    - ``derived_from`` (the id of another quantity): the *derived* policy, the verdict of that quantity
      (an SNR computed from an RMSE); resolved by :meth:`StudyResult.to_dict`;
    - otherwise the *tolerance* policy, a relative ``tolerance``; by default half a unit of the last digit the
      paper value was recorded with (:func:`~ctrl_analysis.reporting.verdicts.printed_tolerance`).

    A value outside its band at the chosen reconstructions is ``reachable`` when the box exploration
    (:func:`ctrl_analysis.reporting.sensitivity.apply`) found a plausible point whose band holds the
    paper's value (``box["verdict"]``).

    A quantity is ``diverged`` when ``diverged=True`` (every run diverged, ``value`` None) or when at
    least half of its ``runs`` diverged (``runs_diverged``); the value of the healthy runs is kept.
    ``unit`` is always written ("" = dimensionless). ``cell`` names the paper cell the quantity scores
    (e.g. ``"Table 2 / x1 ESO"``); quantities sharing a cell are counted once, by the one with
    ``primary=True`` (default: the first recorded). ``kind="check"`` marks an algebraic identity or a
    check of the paper's own arithmetic: listed under checks and errata, never counted as a reproduction.

    Parameters
    ----------
    id, label : str
        Stable id (e.g. ``ex1.mfac.rmse``) and a label for readers.
    value, paper, std : float, array_like or None
        Reproduced value, printed value (only what the paper prints) and the Monte Carlo std.
    runs, runs_diverged : int, optional
        Runs asked for and how many of them diverged.
    tolerance : float, optional
        Relative tolerance of the tolerance policy (default: from the paper value's printed digits).
    note, unit : str
        Free note; unit ("" = dimensionless).
    cell : str, optional
        The paper cell the quantity scores.
    primary, diverged : bool
        The cell's primary reading; every run diverged.
    samples : array_like, optional
        One value per healthy run (percentile policy); not written whole to results.json.
    derived_from : str, optional
        Id of the quantity whose verdict this one takes.
    kind : {"reproduction", "check"}
        A reproduced cell, or a check / erratum.
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
    samples: object = None
    derived_from: str | None = None
    kind: str = "reproduction"
    #: set by the box exploration (:func:`ctrl_analysis.reporting.sensitivity.apply`): the cell's verdict over the
    #: plausible box (``agrees`` / ``reachable`` / ``differs``), where it is reached and its range there
    box: dict | None = None

    def __post_init__(self):
        for name in ("id", "label"):
            if not isinstance(getattr(self, name), str) or (name == "id" and not self.id):
                raise TypeError(f"{name} must be a non-empty string, got {getattr(self, name)!r}")
        if not isinstance(self.unit, str):
            raise TypeError(f"unit must be a string ('' for dimensionless), got {self.unit!r}")
        if self.cell is not None and (not isinstance(self.cell, str) or not self.cell.strip()):
            raise ValueError(f"cell must be a non-empty string naming the paper cell, got {self.cell!r}")
        if self.kind not in KINDS:
            raise ValueError(f"kind must be one of {KINDS}, got {self.kind!r}")
        if self.tolerance is not None:
            self.tolerance = _check_tolerance(self.tolerance)
        if self.value is not None:  # NaN allowed: the mean of runs that all diverged
            check_array("value", self.value)
        if self.paper is not None:
            check_finite("paper", self.paper)
        self.primary = check_bool("primary", self.primary)
        self.diverged = check_bool("diverged", self.diverged)
        if self.runs is not None:
            self.runs = check_int("runs", self.runs, minimum=0)
        if self.runs_diverged is not None and self.runs is None:
            raise ValueError(f"quantity {self.id!r}: runs_diverged={self.runs_diverged!r} needs runs (the total it "
                             "counts from)")
        if self.runs == 0 and self.value is not None:
            raise ValueError(f"quantity {self.id!r}: runs is 0 (no run contributed), so value must be None, "
                             f"got {self.value!r}")
        if self.std is not None and self.value is not None:
            check_nonnegative("std", self.std)
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
        if self.derived_from is not None:
            check_str("derived_from", self.derived_from)
            if self.samples is not None:
                raise ValueError(f"quantity {self.id!r}: give samples or derived_from, not both")
        self._interval = self._percentile = None
        if self.samples is not None:
            v = np.asarray(check_array("samples", self.samples), dtype=float).ravel()
            v = v[np.isfinite(v)]
            self.samples = v
            if self.paper is not None and v.size:
                if np.size(self.paper) != 1:
                    raise ValueError(f"quantity {self.id!r}: the percentile policy (samples) needs a scalar paper "
                                     f"value, got {self.paper!r}")
                p = float(np.asarray(self.paper, dtype=float).ravel()[0])
                self._interval = central_interval(v)
                self._percentile = float(100.0 * (np.mean(v < p) + 0.5 * np.mean(v == p)))

    @property
    def policy(self) -> str:
        """``percentile``, ``derived`` or ``tolerance`` (which rule decides the verdict).

        Returns
        -------
        str
        """
        if self.derived_from is not None:
            return "derived"
        return "percentile" if self._interval is not None else "tolerance"

    @property
    def percentile(self) -> float | None:
        """Percentage of the healthy runs below the paper's value (percentile policy), else None.

        Returns
        -------
        float or None
        """
        return self._percentile

    @property
    def is_diverged(self) -> bool:
        """Every run, or at least half of the runs, diverged.

        Returns
        -------
        bool
        """
        return self.diverged or bool(self.runs and self.runs_diverged and 2 * self.runs_diverged >= self.runs)

    @property
    def verdict(self) -> str:
        """The computed verdict (:func:`compute_verdict`); for a derived quantity, see :meth:`StudyResult.to_dict`.

        Returns
        -------
        str
        """
        verdict = compute_verdict(self.value, self.paper, self.effective_tolerance, diverged=self.is_diverged,
                                  interval=self._interval)
        if verdict == "differs" and (self.box or {}).get("verdict") == "reachable":
            return "reachable"
        return verdict

    @property
    def effective_tolerance(self) -> float | None:
        """The tolerance policy's relative band: ``tolerance``, else from the printed digits; None without paper.

        Returns
        -------
        float or None
        """
        if self.paper is None:
            return None
        if self.tolerance is not None:
            return self.tolerance
        try:
            return printed_tolerance(self.paper)
        except (TypeError, ValueError):
            return DEFAULT_TOLERANCE

    def to_dict(self, derived_verdict: str | None = None) -> dict:
        """The quantity as results.json writes it (numpy converted, non-finite numbers as null).

        Parameters
        ----------
        derived_verdict : str, optional
            The verdict of the quantity named by ``derived_from`` (derived policy).

        Returns
        -------
        dict
        """
        verdict = self.verdict
        if self.derived_from is not None and verdict not in ("new", "diverged"):
            if derived_verdict not in VERDICTS:
                raise ValueError(f"quantity {self.id!r} derives from {self.derived_from!r}, whose verdict is unknown")
            verdict = derived_verdict
        d = {
            "id": self.id,
            "label": self.label,
            "paper": self.paper,
            "value": self.value,
            # one run has no spread: record none rather than a misleading 0
            "std": self.std if (self.runs is None or self.runs > 1) and not self.diverged else None,
            "runs": self.runs,
            "unit": self.unit,
            "tolerance": self.effective_tolerance,
            "verdict": verdict,
            "policy": self.policy if self.paper is not None else None,
            "kind": self.kind,
            "note": self.note,
        }
        if self._interval is not None:
            d["interval"] = list(self._interval)
            d["percentile"] = round(self._percentile, 2)
        if self.derived_from is not None:
            d["derived_from"] = self.derived_from
        if self.cell is not None:
            d["cell"] = self.cell
            d["primary"] = bool(self.primary)
        if self.runs_diverged is not None:
            d["runs_diverged"] = self.runs_diverged
        if self.box is not None:
            d["box"] = self.box
        if self.value is not None and not np.all(np.isfinite(np.asarray(self.value, dtype=float))):
            d["note"] = (self.note + " " if self.note else "") + "value is not finite (diverged run?)"
        return _to_jsonable(d)
