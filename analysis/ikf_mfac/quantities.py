"""Monte Carlo runs, Table 1, its consistency, the ranking, the sweeps beyond the paper; findings from the numbers."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ctrl_analysis.estimators.kalman import random_walk_gain
from ctrl_analysis.metrics import mean_std, rmse, snr_db

from .claims import table1_cell
from .loops import SchemeRuns, noise_draws, run_scheme
from .paper import SCHEMES, TABLE1, Example
from .plants import reference

__all__ = [
    "TABLE_CHUNK",
    "TableRuns",
    "chunked_metrics",
    "chunks_of",
    "d_mfac_rearm_variant",
    "metrics_of",
    "ranking",
    "ratio_rows",
    "run_with_sweeps",
    "sweep_table",
    "table1_consistency",
    "td_step_scan",
]

#: Table 1's Monte Carlo runs (and every per-run scan over its seeds) are simulated this many at a
#: time and reduced to per-run values chunk by chunk: peak memory is bounded by a chunk's traces
#: (about 50 kB a run per scheme), not by ``--runs``. The default 200 runs are one chunk.
TABLE_CHUNK = 2000


def metrics_of(runs) -> tuple[np.ndarray, np.ndarray]:
    """Per-run RMSE and SNR (dB) over k = 1..N on the true output (NaN for diverged runs)."""
    ref = runs.y_ref[:, None]
    with np.errstate(all="ignore"):
        e, s = rmse(ref, runs.y), snr_db(ref, runs.y)
    return np.where(runs.diverged, np.nan, e), np.where(runs.diverged, np.nan, s)


def table1_consistency(n1: int, n2: int) -> list[dict]:
    """Every printed SNR against the SNR its printed RMSE implies, ``10 lg(mean y*²) − 20 lg RMSE``.

    SNR = 10 lg(Σ y*² / Σ e²) and RMSE² = Σ e² / N give SNR = 10 lg(mean y*²) − 20 lg RMSE; for
    |y*| = 1 (Example 1) mean y*² = 1 and SNR = −20 lg RMSE exactly.
    """
    rows = []
    for key, kind, n in (("ex1", "step", n1), ("ex2", "sine", n2)):
        p_ref = float(np.mean(reference(kind, n) ** 2))
        for s in SCHEMES:
            rm, sn = TABLE1[key]["rmse"][s], TABLE1[key]["snr"][s]
            implied = 10 * np.log10(p_ref) - 20 * np.log10(rm)
            # printed to 4 decimals: RMSE ± 5e-5 moves the implied SNR by 20/ln10 · 5e-5/RMSE, SNR ± 5e-5
            rounding = 20.0 / np.log(10.0) * 5e-5 / rm + 5e-5
            rows.append({"cell": table1_cell(key, s, "snr"), "rmse": rm, "snr_printed": sn,
                         "snr_implied": float(implied), "diff_db": float(sn - implied), "rounding_db": float(rounding),
                         "rmse_implied": float(np.sqrt(p_ref) * 10 ** (-sn / 20)), "mean_ref_sq": p_ref,
                         # the signal power mean y*² this cell's own RMSE and SNR imply (same y* for every scheme)
                         "ref_power_implied": float(10 ** ((sn + 20 * np.log10(rm)) / 10))})
    return rows


def d_mfac_rearm_variant(ex: Example, seeds) -> tuple:
    """D-MFAC with the other k_m rule (``rearm`` flipped): per-run (RMSE, SNR), NaN where a run diverged."""
    return chunked_metrics(dataclasses.replace(ex, rearm=not ex.rearm), "d_mfac", seeds)


def chunks_of(seeds, size: int | None = None) -> list:
    """``seeds`` cut into consecutive pieces of ``size`` (default :data:`TABLE_CHUNK`) runs, the last one longer.

    A remainder of a single run joins the piece before it: numpy sums a one-column ``(N, 1)`` array
    pairwise but a wider one row by row, so a chunk of one run would move the last digit of its SNR
    away from the value the same run has in a wider batch.
    """
    size = TABLE_CHUNK if size is None else size
    seeds = list(seeds)
    pieces = [seeds[lo:lo + size] for lo in range(0, len(seeds), size)] or [seeds]
    if len(pieces) > 1 and len(pieces[-1]) == 1:
        pieces[-2:] = [pieces[-2] + pieces[-1]]
    return pieces


def chunked_metrics(ex: Example, scheme: str, seeds, engine: str = "auto") -> tuple:
    """Per-run (RMSE, SNR) of ``scheme`` on ``seeds``, simulated :data:`TABLE_CHUNK` runs at a time.

    Runs are independent, so the values equal one batch of every run; memory is bounded by a chunk's
    traces, not by the run count.
    """
    parts = [metrics_of(run_scheme(ex, scheme, noise_draws(ex, sd), engine=engine)) for sd in chunks_of(seeds)]
    return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])


def ranking(per_run: dict) -> tuple[list, dict]:
    """Schemes ordered by mean RMSE, and the fraction of runs with RMSE(a) < RMSE(b) for each pair."""
    means = {s: np.nanmean(per_run[s][0]) for s in SCHEMES}
    order = sorted(SCHEMES, key=lambda s: means[s])
    frac = {}
    for i, a in enumerate(SCHEMES):
        for b in SCHEMES[i + 1:]:
            ea, eb = per_run[a][0], per_run[b][0]
            both = np.isfinite(ea) & np.isfinite(eb)
            frac[f"{a}<{b}"] = float(np.mean(ea[both] < eb[both])) if both.any() else float("nan")
    return order, frac


def td_step_scan(ex: Example, seeds, counts, feedthrough_options=(False, True), engine: str = "auto",
                 known: dict | None = None) -> dict:
    """TD-MFAC over TD step counts per sample: {(feedthrough, count): per-run RMSE (NaN where a run diverged)}.

    ``known`` holds rows already run on the same seeds (e.g. Table 1's TD-MFAC at the count used), taken as they are.
    """
    known = known or {}
    return {(ft, n): known[(ft, n)] if (ft, n) in known else
            chunked_metrics(dataclasses.replace(ex, td_substeps=n, td_feedthrough=ft, td_reading="substeps"),
                            "td_mfac", seeds, engine=engine)[0]
            for ft in feedthrough_options for n in counts}


def _segments(ex: Example, scheme: str, seeds, sweep_seeds, sweeps: dict) -> list:
    """Grid points run side by side: (sweep name, value, seeds, parameter overrides, noise std)."""
    segs = [("table", None, list(seeds), {}, ex.noise_std)]
    segs += [("noise", lv, sweep_seeds, {}, lv) for lv in sweeps["noise"]]
    segs += [(name, val, sweep_seeds, {name: val}, ex.noise_std) for name in ("rho", "lam") for val in sweeps[name]]
    if scheme == "ikf_mfac":
        segs += [("q", q, sweep_seeds, {"Q": q * ex.R}, ex.noise_std) for q in sweeps["q"]]
    return segs


@dataclass(frozen=True)
class TableRuns:
    """Table 1's runs of one scheme, reduced as they are simulated: what the study reads of every run.

    Attributes
    ----------
    rmse, snr : numpy.ndarray, shape (runs,)
        Per-run RMSE and SNR (dB) over k = 1..N on the true output (NaN where a run diverged).
    diverged : numpy.ndarray of bool, shape (runs,)
    diverged_step : numpy.ndarray of int, shape (runs,)
    first : SchemeRuns
        The first run's traces (Fig. 3-6 draw it), a batch of one.
    """

    rmse: np.ndarray
    snr: np.ndarray
    diverged: np.ndarray
    diverged_step: np.ndarray
    first: SchemeRuns


def run_with_sweeps(ex: Example, scheme: str, seeds, sweep_seeds, sweeps: dict):
    """Table 1's runs of ``scheme`` and every sweep point, side by side on the batch axis, reduced chunk by chunk.

    Each sweep point is a block of ``sweep_seeds`` runs with one parameter changed (noise std,
    ``rho``, ``lam``, or ``Q`` at the example's ``R`` for IKF-MFAC); they run beside Table 1's first
    :data:`TABLE_CHUNK` runs, and the rest of Table 1's runs follow that many at a time. A batch equals
    its runs alone, so every run is the same as run by itself; each chunk is reduced to per-run
    values before the next one runs (memory bounded by a chunk, whatever ``--runs``).

    Returns
    -------
    table : TableRuns
        Table 1's runs.
    points : dict
        ``{(name, value): (mean RMSE, std, runs, diverged runs)}`` for every sweep point.
    per_run : dict
        ``{(name, value): RMSE per run}`` (NaN: diverged) for every sweep point.
    """
    first, *rest = chunks_of(seeds)
    segs = _segments(ex, scheme, first, sweep_seeds, sweeps)
    v = np.concatenate([noise_draws(ex, sd, std) for _, _, sd, _, std in segs], axis=1)
    params = {}
    for name in ("rho", "lam", "Q"):
        params[name] = np.concatenate([np.full(len(sd), ov.get(name, getattr(ex, name))) for _, _, sd, ov, _ in segs])
    runs = run_scheme(dataclasses.replace(ex, **params), scheme, v)
    e, snr = metrics_of(runs)
    n0 = len(first)
    parts = [(e[:n0], snr[:n0], runs.diverged[:n0], runs.diverged_step[:n0])]
    one = dataclasses.replace(runs, y=runs.y[:, :1].copy(), y_m=runs.y_m[:, :1].copy(), u=runs.u[:, :1].copy(),
                              y_f=runs.y_f[:, :1].copy(), diverged=runs.diverged[:1].copy(),
                              diverged_step=runs.diverged_step[:1].copy())
    points, per_run, start = {}, {}, n0
    for name, val, sd, _, _ in segs[1:]:
        row = e[start:start + len(sd)]
        points[(name, val)] = mean_std(row, np.isfinite(row)) + (int(np.sum(~np.isfinite(row))),)
        per_run[(name, val)] = row
        start += len(sd)
    del runs, v
    for sd in rest:
        r = run_scheme(ex, scheme, noise_draws(ex, sd))
        parts.append(metrics_of(r) + (r.diverged, r.diverged_step))
    table = TableRuns(*(np.concatenate([p[i] for p in parts]) for i in range(4)), first=one)
    return table, points, per_run


def sweep_table(points: dict, sweeps: dict) -> dict:
    """``{scheme: {name: [row per value]}}`` from the points of :func:`run_with_sweeps` (per scheme)."""
    return {s: {name: [points[s][(name, val)] for val in sweeps[name]] for name in ("noise", "rho", "lam")}
            for s in SCHEMES}


def ratio_rows(points_ikf: dict, sweeps: dict, ex: Example) -> dict:
    """IKF-MFAC mean RMSE against q = Q/R, with K∞(q)."""
    q = list(sweeps["q"])
    return {"q": q, "rmse": [points_ikf[("q", v)] for v in q], "k_inf": [random_walk_gain(v * ex.R, ex.R) for v in q]}
