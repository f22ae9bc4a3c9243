"""The study as a function of its parameters, for the sensitivity sweep: Table 1's cells and every claim.

:func:`evaluate` runs the four schemes on the recorded seeds (common random numbers: the same noise in
every evaluation) with the variant parameters and records the cells and claims with the main run's
functions (:mod:`.claims`). Simulations a parameter cannot influence (the IKF's Q for MFAC, the TD's
step count for D-MFAC) are taken from a per-process cache keyed by the parameters each scheme reads,
so they are the baseline's numbers exactly.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ctrl_analysis.metrics import mean_std
from ctrl_analysis.reporting.report import StudyInfo, StudyResult

from .claims import (
    fig2_measures,
    judge_claims,
    record_fig2,
    record_noise_margin,
    record_table1,
)
from .loops import noise_draws, run_scheme
from .paper import SCHEMES, Example, Fig2Sweep
from .quantities import metrics_of

__all__ = ["MonteCarlo", "evaluate", "fig2_data", "noise_rows", "scheme_metrics"]

#: Parameters only one scheme reads; every other field of an example is read by all four.
_OWN = {"td_mfac": {"td_r", "td_h", "td_h0", "td_substeps", "td_feedthrough"}, "d_mfac": {"e_m", "rearm"},
        "ikf_mfac": {"Q", "R", "P0"}}
_ALL_OWN = set().union(*_OWN.values())
_CACHE: dict = {}


@dataclass(frozen=True)
class MonteCarlo:
    """The runs of one evaluation: seeds of Table 1's cells, of each noise level, of Fig. 2; the noise grids."""

    table: tuple
    noise: tuple
    fig2: tuple
    levels_ex1: tuple
    levels_ex2: tuple


def _key(ex: Example, scheme: str, *rest) -> tuple:
    read = tuple((f.name, getattr(ex, f.name)) for f in dataclasses.fields(ex)
                 if f.name not in _ALL_OWN or f.name in _OWN.get(scheme, ()))
    return (type(ex).__name__, scheme, read) + tuple(rest)


def _cached(key, fn):
    if key not in _CACHE:
        if len(_CACHE) > 200:
            _CACHE.clear()
        _CACHE[key] = fn()
    return _CACHE[key]


def scheme_metrics(ex: Example, scheme: str, seeds) -> tuple:
    """Per-run (RMSE, SNR) of ``scheme`` on ``seeds`` (NaN where a run diverged), cached per parameters read."""
    def run():
        return metrics_of(run_scheme(ex, scheme, noise_draws(ex, seeds)))
    return _cached(_key(ex, scheme, "table", tuple(seeds)), run)


def noise_rows(ex: Example, scheme: str, seeds, levels) -> list:
    """``[(mean RMSE, std, healthy runs, diverged runs)]`` per noise std in ``levels`` (one batch for all)."""
    def run():
        v = np.concatenate([noise_draws(ex, seeds, lv) for lv in levels], axis=1)
        e, _ = metrics_of(run_scheme(ex, scheme, v))
        n = len(seeds)
        return [mean_std(e[i * n:(i + 1) * n], np.isfinite(e[i * n:(i + 1) * n]))
                + (int(np.sum(~np.isfinite(e[i * n:(i + 1) * n]))),) for i in range(len(levels))]
    return _cached(_key(ex, scheme, "noise", tuple(seeds), tuple(levels)), run)


def fig2_data(ex1: Example, fig2: Fig2Sweep, seeds, keep_first: bool = False):
    """Fig. 2's measures per R: ``[(diverged runs, rejection samples, rise samples)]`` (and the first run's y per R).

    IKF-MFAC in Example 1 with R from ``fig2.R`` at Example 1's Q, every R on the same ``seeds``.
    """
    def run():
        grid = np.asarray(fig2.R, dtype=float)
        n = len(seeds)
        v = np.tile(noise_draws(ex1, seeds), (1, grid.size))
        r = run_scheme(dataclasses.replace(ex1, R=np.repeat(grid, n)), "ikf_mfac", v)
        out = []
        for i in range(grid.size):
            sl = slice(i * n, (i + 1) * n)
            fl, rise = fig2_measures(r.y[:, sl], r.y_ref, r.diverged[sl], fig2.rise_level, fig2.steady)
            out.append((int(r.diverged[sl].sum()), fl, rise))
        first = {float(R): r.y[:, i * n] for i, R in enumerate(grid)}
        return out, first
    out, first = _cached(_key(ex1, "ikf_mfac", "fig2", fig2, tuple(seeds)), run)
    return (out, first) if keep_first else out


def evaluate(params: dict) -> StudyResult:
    """Table 1's cells and every claim at ``params`` (``{"ex1", "ex2", "fig2", "mc"}``), for the sensitivity sweep.

    Parameters
    ----------
    params : dict
        ``ex1`` (:class:`~.paper.Example`), ``ex2`` (:class:`~.paper.Example2`), ``fig2``
        (:class:`~.paper.Fig2Sweep`) and ``mc`` (:class:`MonteCarlo`).

    Returns
    -------
    StudyResult
    """
    mc = params["mc"]
    result = StudyResult(StudyInfo("ikf-mfac", "", "", ""))
    for key, levels in (("ex1", mc.levels_ex1), ("ex2", mc.levels_ex2)):
        ex = params[key]
        record_table1(result, key, {s: scheme_metrics(ex, s, mc.table) for s in SCHEMES})
        record_noise_margin(result, key, levels, {s: noise_rows(ex, s, mc.noise, levels) for s in SCHEMES})
    fig2 = params["fig2"]
    record_fig2(result, fig2.R, len(mc.fig2), fig2_data(params["ex1"], fig2, mc.fig2), params["ex1"].Q)
    judge_claims(result)
    return result
