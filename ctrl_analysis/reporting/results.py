"""Result records of a study: quantities beside the paper's values, computed verdicts, findings.

:class:`StudyResult` is what a study's ``run`` returns; :meth:`StudyResult.to_dict` is the
results.json contract (schema :data:`RESULTS_SCHEMA`). A verdict is computed from the value, the
paper's value and the relative tolerance, never typed in.
"""

from __future__ import annotations

import math
import platform
from dataclasses import dataclass, field

from .._validate import (
    check_in,
    check_nonnegative,
    check_str,
)
from .quantity import Quantity, _to_jsonable
from .study import Claim, Plausible
from .verdicts import (
    CENTRAL,
    CLAIM_VERDICTS,
    DEFAULT_TOLERANCE,
    KINDS,
    VERDICT_POLICY,
    VERDICTS,
    ClaimResult,
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
#: ``tolerance`` or ``derived`` with ``derived_from``), ``kind`` and plausible ranges of reconstructions; 4 judges
#: over the plausible box: a claim's ``support``, ``drivers``, ``nearest_flip`` and ``by_algorithm``, a cell's
#: ``box`` and the ``reachable`` verdict, ``beyond`` claims, and deterministic tolerances from the printed digits.
RESULTS_SCHEMA = 4


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
    #: how the plausible box was explored (:func:`ctrl_analysis.reporting.sensitivity.apply`), written to results.json
    sensitivity: dict = field(default_factory=dict)

    def __post_init__(self):
        if not isinstance(self.info, StudyInfo):
            raise TypeError(f"info must be a StudyInfo, got {self.info!r}")

    def quantity(self, id: str, label: str, value, paper=None, **kw) -> Quantity:
        """Add a quantity and return it (an id may be recorded once).

        Keywords are the fields of :class:`Quantity`:

        - ``unit`` (str, "" = dimensionless) and ``tolerance`` (relative; default half a unit of the last
          digit the paper value is recorded with) are written to results.json and REPORT.md.
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

    def claim(self, claim: Claim, holds, evidence=(), note: str = "", *, measure=None,
              noise_floor=None) -> ClaimResult:
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
        measure, noise_floor : float, optional
            The effect the claim is judged on (e.g. the change of the overshoot) and the smallest effect the
            runs can resolve (e.g. twice its standard error): when ``|measure| < noise_floor`` the claim is
            ``untestable`` (holds None) with that reason, never ``fails``.

        Returns
        -------
        ClaimResult
        """
        if any(c.claim.id == getattr(claim, "id", None) for c in self.claims):
            raise ValueError(f"claim {claim.id!r} is already judged in study {self.info.name!r}")
        if (measure is None) != (noise_floor is None):
            raise ValueError("give measure and noise_floor together (the effect and the smallest effect resolved)")
        if measure is not None:
            m, f = float(measure), float(check_nonnegative("noise_floor", noise_floor, scalar=True))
            if not math.isfinite(m) or abs(m) < f:
                holds = None
                note = (note + " " if note else "") + (
                    f"Untestable: the measure ({m:.3g}) is below its own noise floor ({f:.3g}).")
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

    def merge(self, part: StudyResult) -> None:
        """Append what ``part`` recorded, as if it had been recorded here after everything already here.

        A study computes independent parts side by side (each into its own result, in other processes)
        and merges them in the order it would have run them, so results.json is the same as one process
        recording all of them in that order.

        Parameters
        ----------
        part : StudyResult
            Of the same study, recorded from empty.

        Raises
        ------
        TypeError
            If ``part`` is not a StudyResult.
        ValueError
            If it is another study's, or records a quantity, claim or setting, seed or caption key
            already recorded here.
        """
        if not isinstance(part, StudyResult):
            raise TypeError(f"part must be a StudyResult, got {part!r:.80}")
        if part.info != self.info:
            raise ValueError(f"part must be of study {self.info.name!r}, got {part.info.name!r}")
        for kind, mine, theirs in (("quantity", [q.id for q in self.quantities], [q.id for q in part.quantities]),
                                   ("claim", [c.claim.id for c in self.claims], [c.claim.id for c in part.claims])):
            clash = set(mine) & set(theirs)
            if clash:
                raise ValueError(f"part records {kind} ids already recorded here: {sorted(clash)}")
        for kind in ("settings", "seeds", "captions", "sensitivity"):
            clash = set(getattr(self, kind)) & set(getattr(part, kind))
            if clash:
                raise ValueError(f"part records {kind} keys already recorded here: {sorted(clash)}")
        for kind in ("reconstructions", "quantities", "findings", "missing", "claims"):
            getattr(self, kind).extend(getattr(part, kind))
        self.figures.extend(f for f in part.figures if f not in self.figures)
        for kind in ("settings", "seeds", "captions", "sensitivity"):
            getattr(self, kind).update(getattr(part, kind))

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
