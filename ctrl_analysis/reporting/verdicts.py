"""The verdict policy: how a reproduced number is judged beside the paper's, and how a claim is judged.

* a number the paper got from one noisy simulation agrees when it lies within the central 95 % of the
  reproduced Monte Carlo runs (:func:`central_interval`, the *percentile* policy);
* a deterministic number agrees within a relative tolerance (:func:`relative_error`), justified by the
  digits printed (:func:`digits_tolerance`), the *tolerance* policy;
* a derived quantity takes the verdict of the one it derives from (the *derived* policy);
* a claim (:class:`ClaimResult`) holds, fails, is untestable, or depends on a reconstruction.

:data:`VERDICT_POLICY` states it in words for the report.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._validate import check_array, check_bool, check_int, check_nonnegative, check_str
from .study import Claim

__all__ = ["VERDICTS", "CLAIM_VERDICTS", "KINDS", "DEFAULT_TOLERANCE", "CENTRAL", "VERDICT_POLICY", "ClaimResult",
           "central_interval", "compute_verdict", "digits_tolerance", "relative_error"]

VERDICTS = ("agrees", "differs", "new", "diverged")
#: Verdicts of a paper's claim: ``depends`` when it flips inside the plausible range of a reconstruction.
CLAIM_VERDICTS = ("holds", "fails", "untestable", "depends")
#: ``reproduction``: a cell the paper printed from its own computation; ``check``: an algebraic identity or
#: a check of the paper's own arithmetic (an erratum), listed apart and never counted as a reproduction.
KINDS = ("reproduction", "check")
DEFAULT_TOLERANCE = 0.1
#: Central share of the Monte Carlo runs within which a paper value from one noisy simulation agrees.
CENTRAL = 0.95
#: The verdict policy, printed in the report.
VERDICT_POLICY = (
    "A number the paper got from one noisy simulation *agrees* when it lies within the central 95 % of the "
    "reproduced Monte Carlo runs (its percentile among the runs is shown); a deterministic number agrees "
    "within a relative tolerance justified by the digits printed; a derived quantity (an SNR computed from an "
    "RMSE) takes the verdict of the quantity it derives from. A quantity with diverged runs shows their count, "
    "and is *diverged* when at least half its runs diverged. A claim of the paper *holds* or *fails* on the "
    "quantities it names; it *depends* when its verdict flips for some value inside the plausible range of a "
    "reconstruction (a value the paper does not print), and is *untestable* when nothing computed can decide "
    "it. Algebraic identities and the paper's own arithmetic slips are listed as checks and errata, apart from "
    "the reproduced cells.")



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


def digits_tolerance(paper: float, decimals: int) -> float:
    """Relative tolerance justified by the digits printed: half a unit of the last printed decimal.

    Parameters
    ----------
    paper : float
        The printed value (non-zero).
    decimals : int
        Decimals printed (``0.950`` → 3).

    Returns
    -------
    float
        ``0.5 · 10^-decimals / |paper|``.

    Examples
    --------
    >>> round(digits_tolerance(0.950, 3), 6)
    0.000526
    """
    decimals = check_int("decimals", decimals, minimum=0, maximum=15)
    paper = float(paper)
    if not math.isfinite(paper) or paper == 0:
        raise ValueError(f"paper must be a finite non-zero number, got {paper!r}")
    return 0.5 * 10.0 ** (-decimals) / abs(paper)


def central_interval(samples, share: float = CENTRAL) -> tuple[float, float]:
    """The central ``share`` of the runs' values: the (1 − share)/2 and (1 + share)/2 quantiles.

    Parameters
    ----------
    samples : array_like
        One finite value per healthy run.
    share : float
        Central share, in (0, 1).

    Returns
    -------
    (float, float)

    Examples
    --------
    >>> [round(x, 6) for x in central_interval(range(101))]
    [2.5, 97.5]
    """
    v = np.asarray(check_array("samples", samples), dtype=float).ravel()
    if v.size == 0 or not np.all(np.isfinite(v)):
        raise ValueError(f"samples must be a non-empty array of finite values, got {v.size} values")
    if not 0.0 < share < 1.0:
        raise ValueError(f"share must be in (0, 1), got {share!r}")
    lo, hi = np.quantile(v, [(1 - share) / 2, (1 + share) / 2])
    return float(lo), float(hi)


def compute_verdict(value, paper, tolerance: float | None, *, diverged: bool = False, interval=None) -> str:
    """The verdict of a reproduced value beside the paper's.

    With ``interval`` (the central 95 % of the Monte Carlo runs, :func:`central_interval`) a scalar paper
    value agrees when it lies inside it; otherwise the relative ``tolerance`` decides.

    Parameters
    ----------
    value : float, array_like or None
        Reproduced value.
    paper : float, array_like or None
        Printed value (``None``: the paper does not print it).
    tolerance : float or None
        Relative tolerance (default :data:`DEFAULT_TOLERANCE`).
    diverged : bool
        At least half the runs diverged.
    interval : (float, float), optional
        Central interval of the runs (percentile policy).

    Returns
    -------
    str
        ``diverged``; ``new`` without a paper value; else ``agrees`` or ``differs``.

    Examples
    --------
    >>> compute_verdict(1.0, 1.2, 0.1), compute_verdict(1.0, 1.2, 0.1, interval=(0.8, 1.3))
    ('differs', 'agrees')
    """
    if check_bool("diverged", diverged):
        return "diverged"
    if paper is None:
        return "new"
    tol = DEFAULT_TOLERANCE if tolerance is None else _check_tolerance(tolerance)
    if value is None:
        return "differs"
    if interval is not None:
        lo, hi = (float(x) for x in interval)
        p = float(np.asarray(paper, dtype=float).ravel()[0]) if np.size(paper) == 1 else math.nan
        if not math.isfinite(p):
            raise ValueError(f"the percentile policy needs a scalar paper value, got {paper!r}")
        return "agrees" if lo <= p <= hi else "differs"
    return "agrees" if relative_error(value, paper) <= tol else "differs"


@dataclass
class ClaimResult:
    """A paper's claim judged on computed quantities; its verdict is computed, never typed.

    ``holds`` is the study's judgement at the chosen reconstructions (True, False, or None when nothing
    computed can decide it). A sensitivity sweep (:mod:`ctrl_analysis.reporting.sensitivity`) fills ``depends_on``
    with the reconstructions whose plausible range flips the judgement, and ``robust_to`` with those it
    tried without a flip.

    Parameters
    ----------
    claim : ctrl_analysis.reporting.study.Claim
    holds : bool or None
    evidence : tuple of str
        Ids of the quantities that decide it.
    note : str
        How it was judged (generated from the numbers).
    """

    claim: Claim
    holds: bool | None
    evidence: tuple = ()
    note: str = ""
    depends_on: list = field(default_factory=list)
    robust_to: list = field(default_factory=list)

    def __post_init__(self):
        if not isinstance(self.claim, Claim):
            raise TypeError(f"claim must be a Claim, got {self.claim!r}")
        if self.holds is not None:
            self.holds = check_bool("holds", self.holds)
        self.evidence = tuple(check_str("evidence", e) for e in self.evidence)
        check_str("note", self.note, empty=True)

    @property
    def base_verdict(self) -> str:
        """``holds``, ``fails`` or ``untestable`` at the chosen reconstructions.

        Returns
        -------
        str
        """
        return "untestable" if self.holds is None else ("holds" if self.holds else "fails")

    @property
    def verdict(self) -> str:
        """:attr:`base_verdict`, or ``depends`` when a plausible reconstruction flips it.

        Returns
        -------
        str
        """
        if self.holds is not None and self.depends_on:
            return "depends"
        return self.base_verdict

    def to_dict(self) -> dict:
        """The claim as results.json writes it.

        Returns
        -------
        dict
        """
        return dict({"id": self.claim.id, "section": self.claim.section, "statement": self.claim.statement,
                             "verdict": self.verdict, "base_verdict": self.base_verdict,
                             "evidence": list(self.evidence), "depends_on": self.depends_on,
                             "robust_to": self.robust_to, "note": self.note})


