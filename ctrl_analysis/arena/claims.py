"""Paper claims of one estimator against another, judged at each family's best tuning.

A study that claims "estimator A is more accurate than estimator B" judged it at the paper's one
tuning. The arena can say whether the claim survives when each family is tuned to its own best on
the same records: a :class:`ClaimCheck` names the study's claim (``"<study>/<claim id>"``), the
families on each side, the signal classes it is judged on, and how the arena reads it. The checks
are registered from outside the library (the studies know their claim ids; the library does not),
with :func:`register_claim_check`.

**Verdict** (per claim, from the arena's numbers): the accuracy measure is the RMS error of ``f̂'``
after the transient, each family tuned for it (the papers compare mean errors); a claimed winner
*holds* when it is more accurate than every claimed loser in every case (signal class × noise
class × noise bound) of the claim's classes, *fails* when it is less accurate in every case,
*mixed* otherwise, and *untestable* when the claim cannot be put to the arena's estimators (the
check says why) or its classes were not run. A winner or a loser may be a fixed configuration
``(family, parameters)`` rather than a tuned family: the raw backward difference, or a paper's
printed gains (an estimator run at given parameters only, :data:`~.interface.GIVEN`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import check_finite, check_in, check_str
from .interface import FAMILIES, GIVEN, family

__all__ = ["MEASURES", "VERDICT_TEXT", "ClaimCheck", "fixed_configurations", "judge_claims", "register_claim_check",
           "registered_claim_checks", "tuned_for_signal"]

#: What a claim may be judged on: the RMS error of the derivative estimate f̂' (x2) and of the signal estimate f̂
#: (x1), each family tuned for that measure (:data:`~.tuning.COSTS`).
MEASURES = {"rms": "RMS error of f̂'", "rms_f": "RMS error of f̂"}
#: A ratio within this of 1 is counted as a near tie in a verdict's text (the verdict itself is strict).
TIE = 0.01
#: How each verdict reads in a report.
VERDICT_TEXT = {"holds": "holds at best tuning", "fails": "does not hold at best tuning",
                "mixed": "holds in some cases only, at best tuning", "untestable": "not testable in the arena"}


@dataclass(frozen=True)
class ClaimCheck:
    """One paper claim of estimator against estimator, in the arena's terms.

    Attributes
    ----------
    claim : str
        ``"<study>/<claim id>"`` of the study's judged claim.
    winners, losers : tuple
        Family names claimed better / worse; either may also be ``(family, parameters)``, a fixed
        configuration (of a tuned family or of :data:`~.interface.GIVEN`). Both empty: the claim cannot
        be put to the arena (``how`` says why).
    signals : tuple of str
        Signal classes it is judged on (empty: every class of the run).
    statement : str
        The claim, in the arena's words.
    how : str
        How the arena reads it, or why it cannot.
    measures : tuple of str
        What it is judged on, keys of :data:`MEASURES` (default the derivative's RMS error; a paper that claims
        the signal and its derivative: ``("rms_f", "rms")``). It holds only where it holds on each.
    errors : callable, optional
        For estimators that need more than the record (a plant's input, a model): ``errors(cases, setup)``
        returns ``{label: {measure: error per case}}`` on the arena's cases (the same records, noise and
        scoring window), each estimator at its own best for each measure; ``winners`` and ``losers`` are then
        its labels, not family names.
    """

    claim: str
    winners: tuple
    losers: tuple
    signals: tuple
    statement: str
    how: str
    measures: tuple = ("rms",)
    errors: object = None

    def __post_init__(self):
        check_str("claim", self.claim)
        if self.claim.count("/") != 1 or not all(self.claim.split("/")):
            raise ValueError(f"claim must be '<study>/<claim id>', got {self.claim!r}")
        for name in ("winners", "losers", "signals"):
            if not isinstance(getattr(self, name), tuple):
                raise TypeError(f"{name} must be a tuple, got {getattr(self, name)!r:.80}")
        if bool(self.winners) != bool(self.losers):
            raise ValueError(f"winners and losers must both be given or both be empty, got {self.winners!r} and "
                             f"{self.losers!r}")
        names = [f.name for f in FAMILIES]
        given = names + [f.name for f in GIVEN]
        if self.errors is not None:
            if not callable(self.errors):
                raise TypeError(f"errors must be a callable errors(cases, setup) or None, got {self.errors!r:.80}")
            if not self.winners or not all(isinstance(x, str) and x for x in self.winners + self.losers):
                raise TypeError("with errors, winners and losers must be non-empty tuples of the labels it returns, "
                                f"got {self.winners!r:.60} and {self.losers!r:.60}")
        for side in (() if self.errors is not None else ("winners", "losers")):
            for x in getattr(self, side):
                if isinstance(x, str):  # a tuned family
                    check_in(side, x, names)
                    continue
                if not (isinstance(x, tuple) and len(x) == 2 and isinstance(x[1], tuple)):
                    raise TypeError(f"{side} must hold family names or (family, parameter tuple) pairs, got "
                                    f"{x!r:.80}")
                fam = family(check_in(side, x[0], given), given=True)
                row = np.asarray(check_finite(f"{side} parameters", x[1]), dtype=float)
                if row.shape != (len(fam.params),):
                    raise ValueError(f"{side} parameters of {fam.name} must have {len(fam.params)} entries, got "
                                     f"{x[1]!r}")
        for sig in self.signals:
            check_str("signals", sig)
        if not isinstance(self.measures, tuple) or not self.measures:
            raise TypeError(f"measures must be a non-empty tuple of names from {list(MEASURES)}, got "
                            f"{self.measures!r:.80}")
        for m in self.measures:
            check_in("measures", m, list(MEASURES))
        check_str("statement", self.statement)
        check_str("how", self.how)


_CHECKS: dict = {}


def register_claim_check(check: ClaimCheck) -> ClaimCheck:
    """Register a claim check (the same claim again replaces it).

    Parameters
    ----------
    check : ClaimCheck

    Returns
    -------
    ClaimCheck
    """
    if not isinstance(check, ClaimCheck):
        raise TypeError(f"check must be a ClaimCheck, got {check!r:.80}")
    _CHECKS[check.claim] = check
    return check


def registered_claim_checks() -> list:
    """The registered checks, in registration order.

    Returns
    -------
    list of ClaimCheck
    """
    return list(_CHECKS.values())


def fixed_configurations(checks=None) -> list:
    """The fixed configurations the claim checks compare with: ``(family, parameter tuple)``, each once.

    Evaluate them beforehand (:func:`~ctrl_analysis.arena.tuning.evaluate`, e.g. beside the tuning) and
    hand :func:`judge_claims` their errors as ``fixed``; otherwise it evaluates them itself.

    Parameters
    ----------
    checks : list of ClaimCheck, optional
        Default: the registered ones.

    Returns
    -------
    list of (str, tuple of float)
    """
    return list(dict.fromkeys((x[0], tuple(float(v) for v in x[1])) for chk in _checks(checks)
                              for x in chk.winners + chk.losers if not isinstance(x, str)))


def _checks(checks) -> list:
    """``checks`` checked (a list of ClaimCheck), or the registered ones for None."""
    if checks is not None and (not isinstance(checks, (list, tuple)) or
                               not all(isinstance(c, ClaimCheck) for c in checks)):
        raise TypeError(f"checks must be a list of ClaimCheck or None, got {checks!r:.80}")
    return registered_claim_checks() if checks is None else list(checks)


def _side_errors(lo, cases, table, setup, fixed, measure="rms") -> tuple:
    """``(label, error per case)`` of a winner or loser on ``measure`` (:data:`MEASURES`): a tuned family's best for
    it, or a fixed configuration (from ``fixed`` where it has every case, else evaluated here)."""
    if isinstance(lo, str):
        return lo, np.array([table[lo][c.key][measure] for c in cases])
    from .tuning import METRICS, evaluate

    name, params = lo[0], np.asarray(lo[1], dtype=float)
    label = f"{name} fixed at " + ", ".join(f"{p.name} = {v:g}" for p,
                                            v in zip(family(name, given=True).params, params, strict=True))
    known = fixed.get((name, tuple(float(v) for v in params)), {})
    # a value is the derivative's RMS error, or a dict by measure
    known = {k: (v.get(measure) if isinstance(v, dict) else v if measure == "rms" else None) for k, v in known.items()}
    if all(known.get(c.key) is not None for c in cases):
        return label, np.array([known[c.key] for c in cases], dtype=float)
    m = evaluate((name, setup, tuple(cases), [(i, params) for i in range(len(cases))], "auto"))
    return label, m[:, METRICS.index(measure)]


def tuned_for_signal(checks=None) -> set:
    """The tuned families a claim check judges on the signal estimate f̂ (measure ``"rms_f"``).

    The arena tunes them for that measure too.

    Parameters
    ----------
    checks : list of ClaimCheck, optional
        Default: the registered ones.

    Returns
    -------
    set of str
    """
    return {x for chk in _checks(checks) if "rms_f" in chk.measures for x in chk.winners + chk.losers
            if isinstance(x, str) and chk.errors is None}


def _side(x, measure, own, cases, table, setup, fixed) -> tuple:
    """``(label, error per case)`` from a check's own errors where it has them, else :func:`_side_errors`."""
    return (x, own[x][measure]) if own is not None else _side_errors(x, cases, table, setup, fixed, measure)


def _own_errors(chk, cases, setup) -> dict:
    """A check's own ``errors(cases, setup)``, checked: every label of its sides, every measure, one finite error
    > 0 per case."""
    out = chk.errors(tuple(cases), setup)
    for x in chk.winners + chk.losers:
        for m in chk.measures:
            v = np.asarray(out.get(x, {}).get(m, ()), dtype=float) if isinstance(out, dict) else None
            if v is None or v.shape != (len(cases),) or not np.all(np.isfinite(v) & (v > 0)):
                raise ValueError(f"claim check {chk.claim}: errors must return {{label: {{measure: one finite error "
                                 f"> 0 per case}}}}; {x!r}, {m!r} is {v!r:.80}")
            out[x][m] = v
    return out


def _verdict(wins: np.ndarray) -> str:
    return "holds" if wins.all() else "fails" if not wins.any() else "mixed"


def judge_claims(result, cases, table, setup, checks=None, fixed=None) -> list:
    """Record one finding per claim check (``claim`` and ``claim_verdict`` set) and return the verdicts.

    Parameters
    ----------
    result : StudyResult
        The arena's record.
    cases : list of Case
    table : dict
        ``table[family][case key]`` with ``"rms"`` (the RMS-tuned error of f̂') and, for a check judged on it,
        ``"rms_f"`` (of f̂, tuned for it), from the arena's run.
    setup : Setup
    checks : list of ClaimCheck, optional
        Default: the registered ones.
    fixed : dict, optional
        Errors of the fixed configurations (:func:`fixed_configurations`) evaluated beforehand:
        ``{(family, parameter tuple): {case key: RMS error of f̂', or {measure: error}}}``; the others are
        evaluated here.

    Returns
    -------
    list of (str, str)
        ``(claim, verdict)`` per check.
    """
    from ..reporting.results import StudyResult
    from .tuning import Case, Setup

    if not isinstance(result, StudyResult):
        raise TypeError(f"result must be a StudyResult, got {result!r:.80}")
    if not isinstance(cases, (list, tuple)) or not all(isinstance(c, Case) for c in cases):
        raise TypeError(f"cases must be a list of Case, got {cases!r:.80}")
    if not isinstance(table, dict):
        raise TypeError(f"table must be a dict table[family][case key], got {table!r:.80}")
    if not isinstance(setup, Setup):
        raise TypeError(f"setup must be a Setup, got {setup!r:.80}")
    checks = _checks(checks)
    if fixed is not None and (not isinstance(fixed, dict) or not all(isinstance(v, dict) for v in fixed.values())):
        raise TypeError(f"fixed must be a dict {{(family, params): {{case key: error}}}} or None, got {fixed!r:.80}")
    fixed = fixed or {}
    out = []
    for chk in checks:
        run = [c for c in cases if not chk.signals or c.signal in chk.signals]
        study, cid = chk.claim.split("/")
        fid = f"claim-{study}-{cid}"
        missing = ([] if chk.errors is not None else
                   [f for f in chk.winners + chk.losers if isinstance(f, str) and f not in table])
        if not chk.winners or not run or missing:
            why = (chk.how if not chk.winners else f"its signal classes ({', '.join(chk.signals)}) were not run"
                   if not run else f"the families {', '.join(missing)} were not run")
            verdict, evidence = "untestable", None
            text = f"{study} claim '{cid}' — {chk.statement}: {VERDICT_TEXT[verdict]}: {why}."
        else:
            parts, evidence, wins_all = [], {}, []
            own = _own_errors(chk, run, setup) if chk.errors is not None else None
            for measure in chk.measures:
                for win in chk.winners:
                    w, ew = _side(win, measure, own, run, table, setup, fixed)
                    for lo in chk.losers:
                        label, el = _side(lo, measure, own, run, table, setup, fixed)
                        ratio = el / ew
                        wins_all.append(ratio > 1.0)
                        key = f"{label} / {w}" if measure == "rms" else f"{measure}: {label} / {w}"
                        evidence[key] = {c.key: float(r) for c, r in zip(run, ratio, strict=True)}
                        ties = int(np.sum(np.abs(ratio - 1.0) < TIE))
                        parts.append(f"{MEASURES[measure]}, {label} / {w}: {np.min(ratio):.2f}..{np.max(ratio):.2f} "
                                     f"(median {np.median(ratio):.2f}; {w} better in {int(np.sum(ratio > 1))} of "
                                     f"{len(run)}" + (f", {ties} within {TIE:.0%} of a tie" if ties else "") + ")")
            verdict = _verdict(np.concatenate(wins_all))
            signals = ", ".join(sorted({c.signal for c in run}))
            said, tuned = VERDICT_TEXT[verdict], "Each family tuned to its best on each measure"
            if chk.errors is not None:
                tuned = "Each estimator at its own best on each measure (the check's own evaluation)"
            if any(not isinstance(x, str) for x in chk.winners + chk.losers):
                # a fixed configuration is run as given: the verdict is not "at best tuning" for it
                said = (said.replace(", at best tuning", "").replace(" at best tuning", "")
                        + " (tuned families at their best, fixed configurations as given)")
                tuned = "Each tuned family at its best on each measure, each fixed configuration as given,"
            text = (f"{study} claim '{cid}' — {chk.statement}: {said}. {tuned} on {len(run)} "
                    f"case{'s' if len(run) != 1 else ''} ({signals}): " + "; ".join(parts) + f". Reading: {chk.how}.")
        result.finding(fid, text, evidence, claim=chk.claim, claim_verdict=verdict)
        out.append((chk.claim, verdict))
    return out
