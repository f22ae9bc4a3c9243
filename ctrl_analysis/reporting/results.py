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

from .._validate import (
    check_array,
    check_bool,
    check_in,
    check_int,
    check_nonnegative,
    check_str,
)
from .study import Claim, Plausible
from .verdicts import (
    CENTRAL,
    CLAIM_VERDICTS,
    DEFAULT_TOLERANCE,
    KINDS,
    VERDICT_POLICY,
    VERDICTS,
    ClaimResult,
    _check_tolerance,
    central_interval,
    compute_verdict,
    digits_tolerance,
    relative_error,
)

__all__ = ["VERDICTS", "CLAIM_VERDICTS", "KINDS", "RESULTS_SCHEMA", "DEFAULT_TOLERANCE", "CENTRAL",
           "VERDICT_POLICY", "ClaimResult", "Quantity", "StudyInfo", "StudyResult", "compute_verdict",
           "central_interval", "digits_tolerance", "relative_error", "versions"]

#: Version of the results.json layout: 2 adds ``unit`` and ``tolerance`` on every quantity, the
#: ``diverged`` verdict, paper ``cell`` / ``primary`` and ``settings["cli"]``; 3 adds ``claims``,
#: ``sensitivity``, the verdict ``policy`` of each quantity (``percentile`` with ``interval``,
#: ``tolerance`` or ``derived`` with ``derived_from``), ``kind`` and plausible ranges of reconstructions.
RESULTS_SCHEMA = 3


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
    - otherwise the *tolerance* policy, a relative ``tolerance`` (default :data:`DEFAULT_TOLERANCE`).

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
        Relative tolerance of the tolerance policy.
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
    #: set by a sensitivity sweep (:mod:`ctrl_analysis.reporting.sensitivity`): the cell's values and verdicts across
    #: each reconstruction's plausible range
    sensitivity: dict | None = None

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
        return compute_verdict(self.value, self.paper, self.tolerance, diverged=self.is_diverged,
                               interval=self._interval)

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
            "tolerance": (DEFAULT_TOLERANCE if self.tolerance is None else self.tolerance)
            if self.paper is not None
            else None,
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
        if self.sensitivity is not None:
            d["sensitivity"] = self.sensitivity
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
    #: the paper's claims, judged (:meth:`claim`)
    claims: list = field(default_factory=list)
    #: what a sensitivity sweep tried (:func:`ctrl_analysis.reporting.sensitivity.sweep`), written to results.json
    sensitivity: dict = field(default_factory=dict)

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

    def check(self, id: str, label: str, value, paper=None, **kw) -> Quantity:
        """Add a check: an algebraic identity, or a check of the paper's own arithmetic (an erratum).

        Checks are listed under "checks and errata" and never counted as reproduced cells. Keywords as
        :meth:`quantity`.

        Parameters
        ----------
        id, label : str
        value, paper : object
        **kw
            The other fields of :class:`Quantity`.

        Returns
        -------
        Quantity
        """
        return self.quantity(id, label, value, paper, kind="check", **kw)

    def claim(self, claim: Claim, holds, evidence=(), note: str = "") -> ClaimResult:
        """Judge one of the paper's claims on computed quantities (a claim may be judged once).

        Parameters
        ----------
        claim : ctrl_analysis.reporting.study.Claim
            As declared in the study's ``paper.py``.
        holds : bool or None
            The judgement at the chosen reconstructions; None when nothing computed decides it.
        evidence : sequence of str
            Ids of the quantities that decide it (each must be recorded by the time results.json is written).
        note : str
            How it was judged, generated from the numbers.

        Returns
        -------
        ClaimResult
        """
        if any(c.claim.id == getattr(claim, "id", None) for c in self.claims):
            raise ValueError(f"claim {claim.id!r} is already judged in study {self.info.name!r}")
        c = ClaimResult(claim, None if holds is None else bool(holds), tuple(evidence), note)
        self.claims.append(c)
        return c

    def get_claim(self, id: str) -> ClaimResult:
        """The judged claim ``id``.

        Parameters
        ----------
        id : str

        Returns
        -------
        ClaimResult

        Raises
        ------
        KeyError
            If no claim has that id.
        """
        for c in self.claims:
            if c.claim.id == id:
                return c
        raise KeyError(id)

    def reconstruction(self, name: str, value, why: str, plausible: Plausible | None = None) -> None:
        """Record a value the paper does not print (or prints wrongly), the reason, and its plausible range.

        Parameters
        ----------
        name : str
        value : object
        why : str
        plausible : ctrl_analysis.reporting.study.Plausible, optional
            What else a reader could have chosen (:func:`ctrl_analysis.reporting.study.span`, ``choices``, ``fixed``).
        """
        item = {"name": check_str("name", name), "value": value, "why": check_str("why", why)}
        if plausible is not None:
            if not isinstance(plausible, Plausible):
                raise TypeError(f"plausible must be a Plausible, got {plausible!r}")
            item["plausible"] = plausible.to_dict()
        self.reconstructions.append(item)

    def finding(self, id: str, text: str, evidence=None, *, kind: str = "finding", claim: str | None = None,
                claim_verdict: str | None = None) -> None:
        """Record an inconsistency, an irreproducible claim, an instability, or (``kind="erratum"``) an erratum.

        Errata (the paper's own slips: a typo, an arithmetic error) are listed with the checks.

        Parameters
        ----------
        id, text : str
            Stable id and the finding, generated from computed numbers.
        evidence : object, optional
            The numbers behind it (kept whole in results.json, summarised in REPORT.md).
        kind : {"finding", "erratum"}
        claim, claim_verdict : str, optional
            A finding about another study's claim (the estimator arena's): ``"<study>/<claim id>"`` and
            what the finding says of it (``"holds"``, ``"fails"``, ``"mixed"``, ``"untestable"``); REPORT.md
            shows it beside that claim. Given together.
        """
        if kind not in ("finding", "erratum"):
            raise ValueError(f"kind must be 'finding' or 'erratum', got {kind!r}")
        item = {"id": check_str("id", id), "text": check_str("text", text)}
        if evidence is not None:
            item["evidence"] = evidence
        if kind != "finding":
            item["kind"] = kind
        if (claim is None) != (claim_verdict is None):
            raise ValueError(f"claim and claim_verdict must be given together, got {claim!r} and {claim_verdict!r}")
        if claim is not None:
            item["claim"] = check_str("claim", claim)
            item["claim_verdict"] = check_in("claim_verdict", claim_verdict, ("holds", "fails", "mixed", "untestable"))
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
        ids = {q.id for q in self.quantities}
        for c in self.claims:
            unknown = [e for e in c.evidence if e not in ids]
            if unknown:
                raise ValueError(f"claim {c.claim.id!r} cites quantities that are not recorded: {unknown}")
        return _to_jsonable(
            {
                "schema": RESULTS_SCHEMA,
                "study": self.info.name,
                "seed_file": self.info.seed_file,
                "paper": self.info.paper,
                "settings": self.settings,
                "reconstructions": self.reconstructions,
                "claims": [c.to_dict() for c in self.claims],
                "quantities": self._quantity_dicts(),
                "findings": self.findings,
                "figures": self.figures,
                "captions": {name: self.captions[name] for name in self.figures if name in self.captions},
                "missing": self.missing,
                "seeds": self.seeds,
                "sensitivity": self.sensitivity,
                "runtime_s": round(self.runtime_s, 3),
                "versions": versions(),
            }
        )


    def _quantity_dicts(self) -> list:
        """Every quantity as a dict, derived verdicts resolved (a chain of derivations is followed)."""
        by_id = {q.id: q for q in self.quantities}

        def source_verdict(q, seen=()):
            """The verdict ``q`` takes from the quantity it derives from (a chain of derivations followed)."""
            src = by_id.get(q.derived_from)
            if src is None or src.id in seen:
                raise ValueError(f"quantity {q.id!r} derives from {q.derived_from!r}, which is not recorded "
                                 "(or the derivations form a circle)")
            return src.to_dict(None if src.derived_from is None else source_verdict(src, seen + (q.id,)))["verdict"]

        return [q.to_dict(None if q.derived_from is None else source_verdict(q)) for q in self.quantities]


def versions() -> dict:
    """Versions of Python and the numeric stack, recorded in every results.json.

    Returns
    -------
    dict of str -> str
    """
    return {"python": platform.python_version(),
            **{name: _version(name) for name in ("control", "numpy", "scipy", "sympy", "matplotlib")}}


def _version(name: str) -> str:
    """``name.__version__`` when the package is imported, else its installed version (without importing it).

    A study that never imported python-control, sympy or matplotlib (a small or stand-in study) does not
    pay about 1.3 s of CPU to import them for their version strings (results.json is written in every worker
    process); the installed distribution's version is what that process would import.
    """
    import sys
    from importlib.metadata import PackageNotFoundError, version

    module = sys.modules.get(name)
    if module is not None and isinstance(getattr(module, "__version__", None), str):
        return module.__version__
    try:
        return version(name)
    except PackageNotFoundError:  # importable but not installed as a distribution (e.g. on PYTHONPATH)
        return __import__(name).__version__
