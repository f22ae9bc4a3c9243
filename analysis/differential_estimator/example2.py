"""Example 2 (eq. 20, Fig. 5): linear analysis of the printed loop, the stable preset, simulations, robustness.

The loop is :func:`.loops.example2_loop`; it is linearised with :func:`control.linearize` on its
``control.interconnect`` (:func:`.loops.example2_linear`) and simulated with both presets (Σ's
``a`` printed, and the stable preset) on one batch, Monte Carlo runs and a (b1, b2, b3) grid.
"""

from __future__ import annotations

from dataclasses import replace

import control as ct
import numpy as np

from ctrl_analysis.estimators.differential import DifferentialEstimator
from ctrl_analysis.metrics import mean_abs_error, rmse
from ctrl_analysis.noise import draw_noise, uniform_noise
from ctrl_analysis.reporting.report import StudyResult
from ctrl_analysis.runs.parallel import chunk_slices

from . import loops
from .example1 import quantity_ms
from .paper import Example2, setpoint

__all__ = ["PRESETS", "RUNS_PER_PART", "softened_square_wave", "tracking", "stable_estimator_a",
           "controller_scale_threshold", "literal_eigenvalues", "linear_analysis", "simulate", "quantities",
           "nonminimum_phase", "oscillation"]


def stable_estimator_a(p: Example2, a_max: float = 200.0) -> tuple[float, float]:
    """Least integer ``a >= p.a`` whose linearised loop has all eigenvalues at Re <= -p.stable_margin; the boundary."""
    def f(a):
        return loops.max_real_eig(loops.example2_linear(p, a))

    a = float(np.ceil(p.a))
    while f(a) > -p.stable_margin:
        a += 1.0
        if a > a_max:
            raise ValueError(f"no a <= {a_max} gives a decay margin of {p.stable_margin}")
    lo, hi = p.a, a
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if f(mid) > 0 else (lo, mid)
    return a, hi


def controller_scale_threshold(p: Example2, scales=None) -> dict:
    """Max Re of the linearised loop, every controller pole scaled by ``c`` (``k_i -> c^i k_i``; Σ as printed)."""
    scales = np.linspace(0.02, 1.0, 50) if scales is None else np.asarray(scales)
    pw = np.arange(len(p.K), 0, -1)
    vals = np.array([loops.max_real_eig(loops.example2_linear(replace(p, K=tuple(np.array(p.K) * c**pw))))
                     for c in scales])
    best = int(np.argmin(vals))
    stable = scales[vals < 0]
    return {"best_scale": float(scales[best]), "best_max_real": float(vals[best]),
            "largest_stable_scale": float(stable.max()) if stable.size else None}


def literal_eigenvalues(result: StudyResult, p: Example2) -> np.ndarray:
    """Eigenvalues of the printed loop linearised at 0 (largest Re first); quantity ``ex2.literal.max_real_eig``."""
    eig = np.linalg.eigvals(loops.example2_linear(p))
    eig = eig[np.lexsort((eig.imag, -eig.real))]
    result.quantity("ex2.literal.max_real_eig", f"Example 2 as printed (Σ a = {p.a:g}, K = [2184, 506, 39]): max Re of "
                    "the linearised loop's eigenvalues", float(eig.real.max()), unit="1/s",
                    note=f"control.linearize of the loop's control.interconnect at the origin (w = 0, no noise), "
                         f"b1 = {p.b1:g}, b2 = {p.b2:g}, {p.reading} reading")
    return eig


def linear_analysis(result: StudyResult, p: Example2) -> dict:
    """Eigenvalues of the printed loop and of the stable preset; findings ``ex2-literal-*``, ``ex2-stable-preset``."""
    eig = literal_eigenvalues(result, p)
    max_re = float(eig.real.max())
    re_corr = loops.max_real_eig(loops.example2_linear(p, reading="corrected"))
    re_eps4 = loops.max_real_eig(loops.example2_linear(p, extra_gain=1.0))
    a_new, a_star = stable_estimator_a(p)
    cs = controller_scale_threshold(p)
    eig_new = np.linalg.eigvals(loops.example2_linear(p, a_new))
    result.quantity("ex2.fast_estimator.max_real_eig", f"Example 2, preset fast_estimator (Σ a = {a_new:g}): max Re "
                    "of the linearised loop's eigenvalues", float(eig_new.real.max()), unit="1/s")
    est_lit, est_new = DifferentialEstimator(p.n0, p.a), DifferentialEstimator(p.n0, a_new)
    slow = est_lit.poles[np.argmax(est_lit.poles.real)]
    result.settings["ex2.linear"] = {"literal_eigenvalues": eig, "literal_max_real_corrected_reading": re_corr,
                                     "literal_max_real_eps4_reading": re_eps4, "stable_a": a_new, "a_boundary": a_star,
                                     "stable_eigenvalues": np.sort_complex(eig_new), "controller_scaling": cs}
    result.finding(
        "ex2-literal-unstable" if max_re > 0 else "ex2-literal-stable",
        (f"The printed Example 2 loop is unstable: linearised about the origin its largest eigenvalue real part, "
         f"{max_re:+.2f} 1/s, is positive. " if max_re > 0 else
         f"The printed Example 2 loop is stable: its largest eigenvalue real part, {max_re:+.2f} 1/s, is negative. ")
        + f"Linearised about the origin (w = 0, no noise), plant (20) with b = ({p.b1:g}, {p.b2:g}, {p.b3:g}) + Σ "
        f"(n0 = 5, a = 5) + controller (18) has eigenvalues " + ", ".join(f"{z.real:.2f}{z.imag:+.2f}j" for z in eig)
        + f": max Re = {max_re:+.2f} 1/s, so the printed configuration is " + ("UNSTABLE. " if max_re > 0 else
                                                                              "stable. ")
        + f"Cause: the breakaway design leaves three of Σ's poles slow (slowest {slow.real:.2f}{slow.imag:+.2f}j; only "
          f"the double pole sits at -n0 a = -25), slower than the controller poles -12, -13, -14, so the estimates lag "
          f"the states the controller differentiates. Other readings do not rescue it: eq. (11)'s corrected estimates "
          f"give max Re = {re_corr:+.2f}, and letting the printed trailing 1 multiply ε4 = θ4 - z4 gives "
          f"{re_eps4:+.2f}. b3 drops out of the linearisation (x3|x3| has zero slope at 0).")
    result.finding(
        "ex2-stable-preset",
        f"Raising Σ's a from {p.a:g} to {a_new:g} (K kept) gives Example 2 a decay margin of {p.stable_margin:g} 1/s; "
        f"slowing the controller instead never reaches it. "
        f"Stable preset 'fast_estimator', found from the eigenvalues: keep K, raise Σ's a. The linearised loop becomes "
        f"stable at a = {a_star:.2f} and has every eigenvalue at Re <= -{p.stable_margin:g} 1/s from a = {a_new:g} "
        f"(max Re = {eig_new.real.max():+.2f}; Σ's slowest pole moves from {slow.real:.2f} to "
        f"{est_new.poles.real.max():.2f}). The alternative — slowing the controller, every pole × c — is stable only "
        f"for c <= {cs['largest_stable_scale']:.3g} and never reaches the margin (best max Re = "
        f"{cs['best_max_real']:+.2f} at c = {cs['best_scale']:.2f}). Raising a is the smallest change that yields a "
        f"usable loop; a = {a_new:g} lies outside the range a ∈ [2, 20] the paper recommends.")
    return {"eig": eig, "a_new": a_new, "pair": eig[np.argmax(eig.real)]}


def softened_square_wave(omega: float, r, h: float) -> np.ndarray:
    """``θ = (v, v', v'')`` of ``r`` held over each step through ``ω³/(s+ω)³``, at every sample, in closed form.

    The same numbers as :func:`ctrl_analysis.estimators.tracking.softened_setpoint` with a third-order
    :class:`~ctrl_analysis.estimators.lowpass.LowPassFilter` (its exact zero-order-hold propagation; tested to
    1e-12), without a Python loop over the samples: ``r`` held over each step is piecewise constant, so the
    state at ``t_k`` is the sum over the jumps of ``r`` (a jump ``Δ`` at sample ``j`` acts from ``t_j``) of
    ``Δ`` times the filter's state step response at ``t_k - t_j``: ``v = 1 - e^(-ωτ)(1 + ωτ + (ωτ)²/2)``,
    ``v' = ω³τ² e^(-ωτ)/2``, ``v'' = ω³ e^(-ωτ)(τ - ωτ²/2)``. A square wave has a few jumps, so this costs a few
    vector operations where the propagation costs one matrix product per sample.

    Parameters
    ----------
    omega : float
        The softener's bandwidth (rad/s).
    r : array_like, shape (N,)
        The raw reference at ``t_k = k h``.
    h : float
        The step (s).

    Returns
    -------
    numpy.ndarray, shape (N, 3)
    """
    r = np.asarray(r, dtype=float)
    jumps = np.diff(r, prepend=0.0)
    theta = np.zeros((r.size, 3))
    t = h * np.arange(r.size)
    for j in np.flatnonzero(jumps):
        tau = t[j:] - t[j]
        wt = omega * tau
        e = np.exp(-wt)
        theta[j:, 0] += jumps[j] * (1.0 - e * (1.0 + wt + 0.5 * wt * wt))
        theta[j:, 1] += jumps[j] * (0.5 * omega ** 3 * tau * tau * e)
        theta[j:, 2] += jumps[j] * (omega ** 3 * e * (tau - 0.5 * omega * tau * tau))
    return theta


def oscillation(e: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Half peak-to-peak amplitude and frequency (Hz, from mean-crossings) of each column of ``e``."""
    amp = 0.5 * (np.nanmax(e, axis=0) - np.nanmin(e, axis=0))
    dev = e - np.nanmean(e, axis=0)
    crossings = np.sum(np.signbit(dev[1:]) != np.signbit(dev[:-1]), axis=0)
    return amp, crossings / 2.0 / (h * (e.shape[0] - 1))


#: Example 2's presets: Σ's ``a`` as printed, and the study's stable preset (``a_new``).
PRESETS = ("literal", "fast_estimator")


#: Most Monte Carlo runs simulated in one batch: up to this many (the default 100) the batch keeps ``x1`` and
#: ``u`` of every run; above it each preset's rows are simulated in parts of at most this many and reduced to
#: their per-run values as each part ends (:func:`tracking`), so memory is bounded by the part, not ``--runs``.
RUNS_PER_PART = 128


def tracking(p: Example2, x1, u, v) -> dict:
    """Per run: mean |v − x1|, the half peak-to-peak amplitude and frequency of x1 − v over the last quarter, its
    mean there (the offset) and the RMS of u; ``x1``, ``u`` of shape ``(N + 1, B)``, ``v`` ``(N,)``."""
    n = x1.shape[0] - 1
    e = x1[:-1] - v[:, None]
    tail = slice(n - n // 4, n)
    amp, freq = oscillation(e[tail], p.h)
    return {"err": mean_abs_error(x1[:-1], v[:, None]), "amp": amp, "freq": freq,
            "offset": np.mean(e[tail], axis=0), "rms_u": rmse(u[:-1], 0.0)}


def simulate(p: Example2, seeds, a_new: float, runs: int, *, traces: bool = True, presets=PRESETS) -> dict:
    """The presets (Σ a = p.a and a_new), ``runs`` Monte Carlo rows + the (b1, b2, b3) grid each, one batch.

    The batch keeps ``x1`` and ``u`` of every run and :func:`tracking` reduces them (``per_run``); above
    :data:`RUNS_PER_PART` runs each preset's rows are simulated in parts, each reduced as it ends, and the
    signals are not kept (``sig`` None). With ``traces`` the states, estimates and control drawn in Fig. 5 are
    kept for one run per preset (the first Monte Carlo run that did not diverge), re-run alone (a run does
    not depend on its batch, so it is the same run). The box evaluations skip the traces and the stable
    preset (``presets=("literal",)``): no claim reads them, only notes.
    """
    presets = tuple(presets)
    if not presets or set(presets) - set(PRESETS):
        raise ValueError(f"presets must be a non-empty subset of {PRESETS}, got {presets}")
    a_of = {"literal": p.a, "fast_estimator": a_new}
    m = len(presets)
    G = np.meshgrid(p.sweep_b1, p.sweep_b2, p.sweep_b3, indexing="ij")
    per = runs + G[0].size
    b = tuple(np.tile(np.r_[np.full(runs, nom), g.ravel()], m) for nom, g in zip((p.b1, p.b2, p.b3), G, strict=True))
    n = int(round(p.T / p.h))
    r = setpoint(p, n)
    theta = softened_square_wave(p.omega, r, p.h)
    sampler = uniform_noise([-p.xi_bound, -p.eta_bound], [p.xi_bound, p.eta_bound])
    whole = runs <= RUNS_PER_PART
    # [ξ, η] as (2, N, m per): the presets share each row's noise (row r: seed r % per)
    noise = np.tile(draw_noise(seeds, n, sampler).transpose(2, 0, 1), m) if whole else None
    thetas = {f"theta[{i}]": theta[:, i] for i in range(3)}
    a_rows = np.repeat([a_of[x] for x in presets], per)

    def batch(rows, keep):  # rows: a slice or index array of the batch
        k = len(range(m * per)[rows]) if isinstance(rows, slice) else len(rows)
        params = loops.example2_params(p, a_rows[rows], tuple(v[rows] for v in b))
        nz = noise[:, :, rows] if noise is not None else draw_noise(
            [seeds[i % per] for i in np.asarray(rows)], n, sampler).transpose(2, 0, 1)
        inputs = thetas | {"xi": nz[0], "eta": nz[1]}
        return loops.simulate_signals(loops.example2_loop(p), n, keep, inputs=inputs, runs=k, bound=p.bound,
                                      params=params)

    if whole:
        sig, div, step = batch(slice(None), ["x[0]", "u"])
        per_run = tracking(p, sig["x[0]"], sig["u"], theta[:, 0])
    else:
        sig, parts = None, []
        for j in range(m):
            for sl in chunk_slices(per, chunk_size=RUNS_PER_PART):
                part, div_p, step_p = batch(np.arange(j * per + sl.start, j * per + sl.stop), ["x[0]", "u"])
                parts.append((tracking(p, part["x[0]"], part["u"], theta[:, 0]), div_p, step_p))
        per_run = {k: np.concatenate([t[k] for t, _, _ in parts]) for k in parts[0][0]}
        div, step = (np.concatenate([x[i] for x in parts]) for i in (1, 2))
    ok = ~div
    pick = [int(np.flatnonzero(ok[j * per:j * per + runs])[0]) + j * per if ok[j * per:j * per + runs].any()
            else j * per for j in range(m)]
    traces = batch(np.array(pick), ["x[0]", "x[1]", "xhat[0]", "xhat[1]", "u"])[0] if traces else None
    return {"sig": sig, "per_run": per_run, "ok": ok, "diverged": div, "step": step, "r": r, "theta": theta,
            "per": per,
            "runs": runs, "grid": G, "t": p.h * np.arange(n + 1), "a": tuple(a_of[x] for x in presets),
            "presets": presets, "seeds": list(seeds), "pick": pick, "traces": traces}


def quantities(result: StudyResult, p: Example2, d: dict, lin: dict | None) -> dict:
    """Quantities ``ex2.<preset>.*``, ``ex2.sweep.*`` (findings unless ``lin`` is None); returns the stability maps."""
    ok, per, runs, pr = d["ok"], d["per"], d["runs"], d["per_run"]
    err, amp, freq = pr["err"], pr["amp"], pr["freq"]
    stable = ok & (amp < p.ripple_tol)
    # outcome per run: 0 settles, 1 oscillates (bounded, ripple above the tolerance), 2 diverges
    outcome = np.where(~ok, 2, np.where(stable, 0, 1))
    maps = {}
    for j, name in enumerate(d["presets"]):
        mc, grid = slice(j * per, j * per + runs), slice(j * per + runs, (j + 1) * per)
        label = f"preset {name} (Σ a = {d['a'][j]:g})"
        quantity_ms(result, f"ex2.{name}.mean_abs_tracking_error", f"Example 2, {label}, mean |v - x1| over {p.T:g} s",
                    err[mc], ok[mc], note="includes the transients after the setpoint steps")
        quantity_ms(result, f"ex2.{name}.tail_amplitude", f"Example 2, {label}, half peak-to-peak of x1 - v over the "
                    f"last {p.T / 4:g} s", amp[mc], ok[mc], note="a limit cycle shows here; noise alone gives ~1e-3")
        result.quantity(f"ex2.{name}.share_settled", f"Example 2, {label}: share of the runs whose half peak-to-peak "
                        f"of x1 - v over the last {p.T / 4:g} s is below {p.ripple_tol:g} (diverged runs count as not "
                        "settled)", float(np.mean(stable[mc])), runs=runs, unit="",
                        note="the paper shows one run (Fig. 5): the claim is judged run by run")
        quantity_ms(result, f"ex2.{name}.rms_control", f"Example 2, {label}, RMS of u", pr["rms_u"][mc], ok[mc])
        result.quantity(f"ex2.{name}.diverged_fraction", f"Example 2, {label}: fraction of runs flagged as diverged "
                        f"(|state| > {p.bound:g})", float(np.mean(d["diverged"][mc])), runs=runs, unit="")
        sid = "ex2.sweep.fraction_stable" if name == "fast_estimator" else f"ex2.sweep.{name}.fraction_stable"
        result.quantity(sid, f"Example 2, {label}: fraction of the {per - runs}-point (b1, b2, b3) grid that settles "
                        f"(no divergence; half peak-to-peak of x1 - v < {p.ripple_tol:g} over the last {p.T / 4:g} s)",
                        float(np.mean(stable[grid])), runs=per - runs, unit="",
                        note=f"b1 ∈ {list(p.sweep_b1)}, b2 ∈ {list(p.sweep_b2)}, b3 ∈ {list(p.sweep_b3)}; one seed "
                             "per point")
        for k, what in ((1, "oscillates"), (2, "diverges")):
            result.quantity(f"{sid.removesuffix('fraction_stable')}fraction_{what}", f"Example 2, {label}: fraction of "
                            f"the {per - runs}-point (b1, b2, b3) grid that {what}", float(np.mean(outcome[grid] == k)),
                            runs=per - runs, unit="", note="the three outcomes add up to 1")
        # the linearised map is drawn and read by the findings only (not by a claim): skipped without ``lin``
        lin_map = None if lin is None else np.array(
            [[loops.max_real_eig(loops.example2_linear(p, d["a"][j], b1, b2)) for b2 in p.sweep_b2]
             for b1 in p.sweep_b1])
        maps[name] = {"stable": stable[grid].reshape(d["grid"][0].shape), "lin": lin_map,
                      "outcome": outcome[grid].reshape(d["grid"][0].shape),
                      "amp": amp[grid].reshape(d["grid"][0].shape), "offset": pr["offset"][grid]}
    for k in ("diverged", "step"):
        result.settings[f"ex2.sim.{k}"] = d[k]
    if lin is not None and set(maps) == set(PRESETS):
        _findings(result, p, d, lin, maps, err, amp, freq)
    return {"maps": maps, "amp": amp, "freq": freq}


def _findings(result, p, d, lin, maps, err, amp, freq) -> None:
    ok, runs, per = d["ok"], d["runs"], d["per"]
    ok_l = ok[:runs]
    pair = lin["pair"]
    amp_lit = maps["literal"]["amp"]
    result.finding(
        "ex2-literal-simulation",
        "Simulated as printed, x1 settles into a limit cycle around v (half peak-to-peak "
        f"{np.mean(amp[:runs][ok_l]):.3g} at {np.mean(freq[:runs][ok_l]):.2f} Hz) instead of tracking it. Simulated as "
        f"printed, {int((~ok_l).sum())} of {runs} runs diverge (bound {p.bound:g}): the linear instability is caught "
        "by the nonlinear damping -b3 x3|x3| and x1 settles into a limit cycle around v with half peak-to-peak "
        f"amplitude {np.mean(amp[:runs][ok_l]):.3g} at {np.mean(freq[:runs][ok_l]):.2f} Hz (the linearised unstable "
        f"pair {pair.real:+.1f} ± {abs(pair.imag):.1f}j rad/s, i.e. {abs(pair.imag) / (2 * np.pi):.2f} Hz), mean |v - "
        f"x1| = {np.mean(err[:runs][ok_l]):.3g} and RMS u = {np.mean(d['per_run']['rms_u'][:runs][ok_l]):.3g}. "
        "Over the grid the limit-cycle amplitude is set by the damping b3: "
        "" + ", ".join(f"{amp_lit[:, :, k].min():.3g}-{amp_lit[:, :, k].max():.3g} at b3 = {b3:g}"
                                         for k, b3 in enumerate(p.sweep_b3))
        + ". At large b3 a plot of the printed loop can look like tracking; the eigenvalues say it is not stable.")
    fast, lit = maps["fast_estimator"], maps["literal"]
    b1s = np.asarray(p.sweep_b1)
    result.finding(
        "ex2-robustness",
        "The robustness claim holds for the stable preset, not for the printed loop: "
        f"{np.mean(fast['stable']) * 100:.0f} % against {np.mean(lit['stable']) * 100:.0f} % of the {per - runs} (b1, "
        "b2, b3) grid points settle. The paper claims 'strong robustness to parameter changes': with the "
        f"fast_estimator preset {np.mean(fast['stable']) * 100:.0f} % of the {per - runs} grid points settle (b1 > 0: "
        f"{np.mean(fast['stable'][b1s > 0]) * 100:.0f} %); the linearisation at the origin is stable on "
        f"{np.mean(fast['lin'] < 0) * 100:.0f} % of the (b1, b2) grid (max Re from {fast['lin'].min():.2f} to "
        f"{fast['lin'].max():.2f}). As printed (a = 5) the linearisation is stable at "
        f"{np.mean(lit['lin'] < 0) * 100:.0f} % of the grid points and {np.mean(lit['stable']) * 100:.0f} % of the "
        "points settle. The claim holds for the stable preset over the mapped range (|b1|, |b2| <= "
        f"{max(np.abs(b1s).max(), np.abs(np.asarray(p.sweep_b2)).max()):g}, b3 ∈ [{min(p.sweep_b3):g}, "
        f"{max(p.sweep_b3):g}]), not for the printed configuration. Robust stability is not robust accuracy: (18) has "
        f"no integral action, so the static term b1 x1 leaves an offset ≈ b1 v / k_3 (k_3 = {p.K[0]:g}); the preset's "
        f"largest tail offset is {np.abs(fast['offset']).max():.3g}.")


def _plant_abcd(b1: float, b2: float):
    """State-space matrices of plant (20) linearised at the origin (b3 drops out), input u, output x1."""
    A = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [b1, -b2, 0.0]])
    return A, np.array([[0.0], [0.0], [1.0]]), np.array([[1.0, 0.0, 0.0]]), np.zeros((1, 1))


def nonminimum_phase(result: StudyResult, p: Example2) -> None:
    """The paper's "non-minimum phase for b1 > 0": poles and zeros of the linearised plant 1/(s³ + b2 s - b1)."""
    rows = {}
    for b1 in p.sweep_b1:
        poles = np.roots([1.0, 0.0, p.b2, -b1])
        rows[b1] = float(poles.real.max())
    result.quantity("ex2.plant.max_real_pole", f"Example 2: max Re of the poles of the linearised plant "
                    f"1/(s^3 + b2 s - b1), b2 = {p.b2:g}, per b1 ∈ {list(p.sweep_b1)}", list(rows.values()), unit="1/s",
                    note="no finite zeros for any b1")
    zeros = [np.asarray(ct.ss(*_plant_abcd(p.b1 if b1 is None else b1, p.b2)).zeros())
             for b1 in (None, *p.sweep_b1)]
    result.quantity("ex2.plant.rhp_zeros", f"Example 2: zeros of the linearised plant u → x1 in the closed right "
                    f"half-plane, b2 = {p.b2:g}, b1 = {p.b1:g} and b1 ∈ {list(p.sweep_b1)} (count, all b1)",
                    int(sum(np.sum(z.real >= 0) for z in zeros)), unit="",
                    note=f"control.StateSpace.zeros() (invariant zeros): {sum(z.size for z in zeros)} finite zeros in "
                    f"all; the plant "
                         "is minimum phase for every b1 (an unstable pole is not a right-half-plane zero)")
    result.finding(
        "ex2-nonminimum-phase",
        f"For b1 > 0 the plant of Example 2 is unstable but not non-minimum phase: linearised, u -> x1 = "
        f"1/(s^3 + b2 s - b1) has no zeros at all. "
        f"The paper calls the plant 'unstable, i.e. non-minimum phase' for b1 > 0. Linearised at the origin, u -> x1 "
        f"is 1/(s^3 + b2 s - b1): it has no zeros at all, so it is minimum phase in the usual sense for every b1; an "
        f"unstable pole is not a right-half-plane zero. The characteristic polynomial has no s^2 term (x3 enters "
        f"only through b3 x3|x3|, whose slope at 0 is 0), so it is never Hurwitz: with b2 = {p.b2:g}, max Re of the "
        f"poles is " + ", ".join(f"{v:+.3g} at b1 = {k:g}" for k, v in rows.items())
        + ". b1 > 0 gives a real unstable pole (the product of the roots is b1); b1 <= 0 still leaves poles on or "
          "right of the imaginary axis. The plant is open-loop unstable or marginal for every b1, not only b1 > 0.")
