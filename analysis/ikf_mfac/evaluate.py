"""The study as a function of its parameters, for the plausible box: Table 1's cells and every claim.

:func:`evaluate_many` evaluates many points of the box at once: every point's runs of one scheme (and one TD step
count) go side by side on the batch axis of one simulation (:func:`~.loops.run_batch`), on the same recorded
seeds at every point (common random numbers). The cells and claims are recorded with the main run's functions
(:mod:`.claims`). What each point needs is simulated once per process: a scheme's runs depend only on the
parameters that scheme reads (MFAC in Example 1 on φ̂'s reset value only), so they are cached under those.

The noise-level claim is simulated only as far as it is undecided: the paper's own level is Table 1's runs; the
other levels first without TD-MFAC (the costly scheme), and TD-MFAC only where IKF-MFAC is still the lowest in
more than half the runs minus the noise floor at every level. Leaving a scheme out can only raise IKF-MFAC's
share, so a claim that fails without it fails with it: the verdict is the one of the full evaluation.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ctrl_analysis.noise import draw_noise, gaussian_noise
from ctrl_analysis.reporting.report import StudyInfo, StudyResult

from .claims import (
    fig2_measures,
    judge_claims,
    noise_parts,
    record_fig2,
    record_table1,
    share_floor,
)
from .loops import effective, run_batch, run_scheme, structure
from .paper import SCHEMES, Example, Fig2Sweep
from .quantities import metrics_of

__all__ = ["MonteCarlo", "evaluate", "evaluate_many", "fig2_data"]

#: Parameters only one scheme reads; every other field of an example is read by all four.
_OWN = {"td_mfac": {"td_r", "td_h", "td_h0", "td_substeps", "td_feedthrough", "td_reading"},
        "d_mfac": {"e_m", "rearm"}, "ikf_mfac": {"Q", "R", "P0"}}
_ALL_OWN = set().union(*_OWN.values())
_CACHE: dict = {}
_UNIT: dict = {}
#: At most this many cached simulations per process (a box exploration needs a few thousand).
_CACHE_SIZE = 20000


@dataclass(frozen=True)
class MonteCarlo:
    """The runs of one evaluation: the seeds of Table 1's cells and of every noise level, of Fig. 2; the noise grids.

    Table 1's cells and the noise levels share their seeds, so the paper's own noise level is Table 1's runs.
    """

    runs: tuple
    fig2: tuple
    levels_ex1: tuple
    levels_ex2: tuple


def _key(ex: Example, scheme: str, *rest) -> tuple:
    """What ``scheme``'s runs depend on: the fields it reads (of the TD it actually runs), and ``rest``."""
    ex = effective(ex)
    read = tuple((f.name, getattr(ex, f.name)) for f in dataclasses.fields(ex)
                 if f.name not in _ALL_OWN or f.name in _OWN.get(scheme, ()))
    return (type(ex).__name__, scheme, read) + tuple(rest)


def _unit(n: int, seeds: tuple) -> np.ndarray:
    """Standard normal draws of ``seeds``, shape ``(n, B)``: ``0.0 + std * z`` equals :func:`~.loops.noise_draws`."""
    k = (n, seeds)
    if k not in _UNIT:
        _UNIT[k] = draw_noise(list(seeds), n, gaussian_noise(1.0))[:, :, 0]
    return _UNIT[k]


def _simulate(requests: list) -> list:
    """The outcome of every request ``(ex, scheme, noise std, seeds, fig2)``, simulated once per process.

    ``fig2`` None: ``(RMSE per run, SNR per run)``; ``(rise_level, steady)``: Fig. 2's measures per run
    ``(diverged, fluct, rise)``. The missing requests of one loop structure run as one batch.
    """
    keys = [_key(ex, s, std, seeds, what) for ex, s, std, seeds, what in requests]
    missing = {}
    for k, r in zip(keys, requests, strict=True):
        if k not in _CACHE:
            missing.setdefault(k, r)
    if len(_CACHE) + len(missing) > _CACHE_SIZE:
        _CACHE.clear()
    groups: dict = {}
    for k, (ex, s, _, _, _) in missing.items():
        groups.setdefault(structure(ex, s), []).append(k)
    for gkeys in groups.values():
        reqs = [missing[k] for k in gkeys]
        scheme = reqs[0][1]
        vs = [0.0 + std * _unit(ex.n, seeds) for ex, _, std, seeds, _ in reqs]
        runs = run_batch([r[0] for r in reqs], scheme, vs)
        e, snr = metrics_of(runs)
        start = 0
        for k, (_ex, _, _, seeds, what) in zip(gkeys, reqs, strict=True):
            sl = slice(start, start + len(seeds))
            start += len(seeds)
            if what is None:
                _CACHE[k] = (e[sl], snr[sl])
            else:
                fl, rise = fig2_measures(runs.y[:, sl], runs.y_ref, runs.diverged[sl], *what)
                _CACHE[k] = (runs.diverged[sl].copy(), fl, rise)
    return [_CACHE[k] for k in keys]


def fig2_data(ex1: Example, fig2: Fig2Sweep, seeds, keep_first: bool = False):
    """Fig. 2's measures per R: ``[(diverged per run, rejection per run, rise per run)]`` (and the first run's y per R).

    IKF-MFAC in Example 1 with R from ``fig2.R`` at Example 1's Q, every R on the same ``seeds``.
    """
    grid = np.asarray(fig2.R, dtype=float)
    n = len(seeds)
    v = np.tile(noise_draws_of(ex1, seeds), (1, grid.size))
    r = run_scheme(dataclasses.replace(ex1, R=np.repeat(grid, n)), "ikf_mfac", v)
    out = []
    for i in range(grid.size):
        sl = slice(i * n, (i + 1) * n)
        fl, rise = fig2_measures(r.y[:, sl], r.y_ref, r.diverged[sl], fig2.rise_level, fig2.steady)
        out.append((r.diverged[sl].copy(), fl, rise))
    first = {float(R): r.y[:, i * n] for i, R in enumerate(grid)}
    return (out, first) if keep_first else out


def noise_draws_of(ex: Example, seeds, noise_std: float | None = None) -> np.ndarray:
    """:func:`~.loops.noise_draws` from the cached standard normal draws (the same numbers)."""
    std = ex.noise_std if noise_std is None else noise_std
    return 0.0 + std * _unit(ex.n, tuple(seeds))


def _levels(mc: MonteCarlo) -> dict:
    return {"ex1": tuple(mc.levels_ex1), "ex2": tuple(mc.levels_ex2)}


def _fails(levels: dict, rows: dict, runs: int) -> bool:
    """The noise claim fails whatever the schemes not run yet show (some part's share below 1/2 − its floor)."""
    parts = noise_parts(levels, rows)
    return min(float(np.mean(ok)) for _, ok in parts) - 0.5 <= -share_floor(runs)


def evaluate_many(variants: list) -> list:
    """Table 1's cells and every claim at each parameter set (``{"ex1", "ex2", "fig2", "mc"}``), all at once.

    Parameters
    ----------
    variants : list of dict
        ``ex1`` (:class:`~.paper.Example`), ``ex2`` (:class:`~.paper.Example2`), ``fig2``
        (:class:`~.paper.Fig2Sweep`) and ``mc`` (:class:`MonteCarlo`, the same for all).

    Returns
    -------
    list of StudyResult
    """
    if not variants:
        return []
    mc = variants[0]["mc"]
    if any(v["mc"] != mc for v in variants):
        raise ValueError("evaluate_many evaluates parameter sets with one MonteCarlo, got several")
    levels = _levels(mc)
    runs = tuple(mc.runs)
    # Table 1's runs of every scheme in both examples, and Fig. 2's, for every point
    reqs = []
    for v in variants:
        reqs += [(v[k], s, v[k].noise_std, runs, None) for k in ("ex1", "ex2") for s in SCHEMES]
        f = v["fig2"]
        reqs += [(dataclasses.replace(v["ex1"], R=float(R)), "ikf_mfac", v["ex1"].noise_std, tuple(mc.fig2),
                  (f.rise_level, tuple(f.steady))) for R in f.R]
    outs = _simulate(reqs)
    tables, figs, pos = [], [], 0
    for v in variants:
        tables.append({k: {s: outs[pos + 4 * i + j] for j, s in enumerate(SCHEMES)} for i,
                       k in enumerate(("ex1", "ex2"))})
        pos += 8
        figs.append(outs[pos:pos + len(v["fig2"].R)])
        pos += len(v["fig2"].R)
    # the noise levels, as far as the claim is undecided: without TD-MFAC first, then with it
    rows = [{k: {s: [tables[i][k][s][0] if lv == variants[i][k].noise_std else None for lv in levels[k]]
                 for s in SCHEMES} for k in levels} for i in range(len(variants))]
    skipped = ["" for _ in variants]
    others = ("mfac", "d_mfac", "ikf_mfac")
    why = ("Only Table 1's noise levels were simulated: the claim already fails there.",
           "Example 2's other noise levels were not simulated: the claim already fails in Example 1.",
           "TD-MFAC was not simulated at the other noise levels: the claim already fails without it.",
           "TD-MFAC was not simulated at Example 2's other noise levels: the claim already fails without it.")
    for stage, (key, schemes) in enumerate((("ex1", others), ("ex2", others), ("ex1", ("td_mfac",)),
                                            ("ex2", ("td_mfac",)))):
        todo = [i for i in range(len(variants)) if not _fails(levels, rows[i], len(runs))]
        for i in range(len(variants)):
            if i not in todo and not skipped[i]:
                skipped[i] = why[stage]
        need = [(i, key, j, s) for i in todo for j in range(len(levels[key])) for s in schemes
                if rows[i][key][s][j] is None]
        got = _simulate([(variants[i][k], s, levels[k][j], runs, None) for i, k, j, s in need])
        for (i, k, j, s), (e, _) in zip(need, got, strict=True):
            rows[i][k][s][j] = e
    results = []
    for i, v in enumerate(variants):
        result = StudyResult(StudyInfo("ikf-mfac", "", "", ""))
        for k in ("ex1", "ex2"):
            record_table1(result, k, tables[i][k])
        record_fig2(result, v["fig2"].R, len(mc.fig2), figs[i], v["ex1"].Q)
        judge_claims(result, {k: {s: tables[i][k][s][0] for s in SCHEMES} for k in levels},
                     {"levels": levels, "rows": rows[i]}, figs[i], skipped[i])
        results.append(result)
    return results


def evaluate(params: dict) -> StudyResult:
    """Table 1's cells and every claim at ``params`` (:func:`evaluate_many` of one point).

    Parameters
    ----------
    params : dict
        ``ex1``, ``ex2``, ``fig2`` and ``mc`` (:class:`MonteCarlo`).

    Returns
    -------
    StudyResult
    """
    return evaluate_many([params])[0]
