"""The verdict policy: how a reproduced number is judged beside the paper's, and how a claim is judged.

* a printed number has a *band* at each point of the study's plausible box: the central 95 % of the
  reproduced Monte Carlo runs when the paper got it from a noisy simulation (:func:`central_interval`, the
  *percentile* policy), or half a unit of its last printed digit when it is deterministic
  (:func:`printed_tolerance`, the *tolerance* policy); it ``agrees`` when the paper's value lies in the band at
  the chosen reconstructions, is ``reachable`` when it does so somewhere in the plausible box (found by the
  box exploration, :mod:`ctrl_analysis.reporting.sensitivity`, which records the point), and ``differs`` only
  when no plausible point reaches it;
* a derived quantity takes the verdict of the one it derives from (the *derived* policy);
* a claim (:class:`ClaimResult`) is judged over the whole box: its ``support`` is the share of the box where it
  holds; it *holds* at or above :data:`SUPPORT_HIGH`, *fails* at or below :data:`SUPPORT_LOW`, *depends* in
  between, and is *untestable* when its measure is below its own noise floor or the method cannot run.

:data:`VERDICT_POLICY` states it in words for the report.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._validate import (
    check_array,
    check_bool,
    check_finite,
    check_int,
    check_nonnegative,
    check_real,
    check_str,
)
from .study import Claim

__all__ = ["VERDICTS", "CLAIM_VERDICTS", "KINDS", "DEFAULT_TOLERANCE", "CENTRAL", "SUPPORT_LOW", "SUPPORT_HIGH",
           "VERDICT_POLICY", "ClaimResult", "central_interval", "claim_verdict", "compute_verdict",
           "digits_tolerance", "printed_tolerance", "relative_error"]

VERDICTS = ("agrees", "reachable", "differs", "new", "diverged")
#: Verdicts of a paper's claim: ``depends`` when its support over the plausible box lies between the thresholds.
CLAIM_VERDICTS = ("holds", "fails", "untestable", "depends")
#: ``reproduction``: a cell the paper printed from its own computation; ``check``: an algebraic identity or
#: a check of the paper's own arithmetic (an erratum), listed apart and never counted as a reproduction.
KINDS = ("reproduction", "check")
#: Relative tolerance of a deterministic number whose printed digits are not known (an array without them).
DEFAULT_TOLERANCE = 0.1
#: Central share of the Monte Carlo runs within which a paper value from one noisy simulation agrees.
CENTRAL = 0.95
#: A claim *fails* when it holds on at most this share of the plausible box, and *holds* from
#: :data:`SUPPORT_HIGH` on; in between it *depends*.
SUPPORT_LOW = 0.05
SUPPORT_HIGH = 0.95
#: The verdict policy, printed in the report.
VERDICT_POLICY = (
    "Every value the paper does not print (a reconstruction) has a plausible range; together they span the "
    "study's *plausible box*. A printed number has a band at each point of the box: the central 95 % of the "
    "reproduced Monte Carlo runs when the paper got it from one noisy simulation, or half a unit of its last "
    "printed digit when it is deterministic — one rule for both, no blanket allowance. It *agrees* when the "
    "paper's value lies in the band at the chosen reconstructions, is *reachable* when it does so at some "
    "plausible point (the point is recorded; the box is searched by a Latin hypercube sample, bisection between "
    "samples on either side of the paper's value and a local search), and *differs* only when no plausible "
    "point reaches it; a derived quantity (an SNR computed from an RMSE) takes the verdict of the quantity it "
    "derives from; a quantity is *diverged* when at least half its runs diverged (the count is always shown). "
    "A claim of the paper is judged on the measure the paper used, at a Latin hypercube sample of the whole box "
    "(all reconstructions varied jointly, at least 64 points): its *support* is the share of the box where it "
    "holds (± its binomial standard error); it *holds* when the support is at least "
    f"{100 * SUPPORT_HIGH:.0f} %, *fails* when it is at most {100 * SUPPORT_LOW:.0f} %, and *depends* in between, "
    "with the reconstructions that drive it (first-order Sobol' indices) and the nearest point of the box where "
    "it flips (located by bisection). It is *untestable* when its measure is below its own noise floor or the "
    "paper's method cannot run as printed (the reason is given). Where the study runs the paper's printed "
    "algorithm and a correction, each claim is judged under both and the scorecard says when it holds only with "
    "one of them. Algebraic identities and the paper's own arithmetic slips are listed as checks and errata, "
    "apart from the reproduced cells; the project's own tests are listed beyond the paper.")


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
    p = np.atleast_1d(check_finite("paper", paper))
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
    paper = float(check_finite("paper", paper, scalar=True))
    if paper == 0:
        raise ValueError(f"paper must be a finite non-zero number, got {paper!r}")
    return 0.5 * 10.0 ** (-decimals) / abs(paper)


def printed_tolerance(paper) -> float:
    """Relative tolerance of a printed number from the digits it was recorded with (half a unit of the last one).

    The study records each printed number as the paper prints it (``1.3179e-4``, ``0.95``), so the shortest
    representation of the float carries the printed significant digits; a trailing zero the paper printed
    (``0.950``) is lost, which makes the band wider, never narrower. For a vector, the tightest element's
    tolerance; an exact zero gives :data:`DEFAULT_TOLERANCE` (an absolute band, :func:`relative_error`).

    Parameters
    ----------
    paper : float or array_like
        The printed value(s).

    Returns
    -------
    float

    Examples
    --------
    >>> round(printed_tolerance(1.3179e-4), 8), round(printed_tolerance(12.0), 6)
    (3.794e-05, 0.041667)
    """
    values = np.atleast_1d(check_array("paper", paper)).astype(float).ravel()
    if values.size == 0:
        raise ValueError("paper must hold at least one printed value, got an empty array")
    tols = []
    for v in values:
        if v == 0 or not math.isfinite(v):
            tols.append(DEFAULT_TOLERANCE)
            continue
        mantissa, _, exp = repr(abs(float(v))).partition("e")  # shortest repr: the digits as recorded
        exp = int(exp or 0)
        decimals = len(mantissa.partition(".")[2].rstrip("0")) if "." in mantissa else 0
        tols.append(0.5 * 10.0 ** (exp - decimals) / abs(v))
    return float(min(tols))


def claim_verdict(support: float | None, base: str) -> str:
    """A claim's verdict from its support over the plausible box (or its base verdict without a box).

    Parameters
    ----------
    support : float or None
        Share of the box's testable samples where the claim holds; None when the box was not explored.
    base : {"holds", "fails", "untestable"}
        The verdict at the chosen reconstructions.

    Returns
    -------
    str

    Examples
    --------
    >>> claim_verdict(0.97, "holds"), claim_verdict(0.5, "holds"), claim_verdict(None, "fails")
    ('holds', 'depends', 'fails')
    """
    if base not in ("holds", "fails", "untestable"):
        raise ValueError(f"base must be holds, fails or untestable, got {base!r}")
    if support is not None:
        support = check_real("support", support)
        if not 0.0 <= support <= 1.0:
            raise ValueError(f"support must be a share in [0, 1] (or None), got {support!r}")
    if base == "untestable" or support is None:
        return base
    if support >= SUPPORT_HIGH:
        return "holds"
    if support <= SUPPORT_LOW:
        return "fails"
    return "depends"


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
    share = check_real("share", share)
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
    computed can decide it; ``note`` then says why, e.g. the measure is below its own noise floor). The box
    exploration (:func:`ctrl_analysis.reporting.sensitivity.apply`) fills ``box``: the claim's support over the
    plausible box, the reconstructions that drive it, the nearest point where it flips and, where the study
    has an algorithm axis, the support under the paper's printed and the corrected algorithm.

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
    #: set by the box exploration: ``support``, ``drivers``, ``nearest_flip``, ``boundary``, ``by_algorithm``, ...
    box: dict | None = None

    def __post_init__(self):
        if not isinstance(self.claim, Claim):
            raise TypeError(f"claim must be a Claim, got {self.claim!r}")
        if self.holds is not None:
            self.holds = check_bool("holds", self.holds)
        if not isinstance(self.evidence, (tuple, list)):
            raise TypeError(f"evidence must be a tuple of quantity ids, got {self.evidence!r:.80}")
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
    def support(self) -> float | None:
        """Share of the plausible box where the claim holds (None before the box is explored).

        Returns
        -------
        float or None
        """
        s = (self.box or {}).get("support") or {}
        return s.get("holds")

    @property
    def verdict(self) -> str:
        """From :attr:`support` by the policy's thresholds (:func:`claim_verdict`); :attr:`base_verdict` without a box.

        Returns
        -------
        str
        """
        return claim_verdict(self.support, self.base_verdict)

    @property
    def depends_on(self) -> list:
        """The reconstructions whose values differ at the nearest flip, with the value there (empty if none).

        Returns
        -------
        list of dict
        """
        return list((self.box or {}).get("depends_on") or [])

    def to_dict(self) -> dict:
        """The claim as results.json writes it.

        Returns
        -------
        dict
        """
        d = {"id": self.claim.id, "section": self.claim.section, "statement": self.claim.statement,
             "verdict": self.verdict, "base_verdict": self.base_verdict, "evidence": list(self.evidence),
             "depends_on": self.depends_on, "note": self.note, "beyond": self.claim.beyond}
        if self.box is not None:
            d.update({k: v for k, v in self.box.items() if k != "depends_on"})
        return d
