"""Linear part of the study: eq. (5)/(9)/(12) checks, Fig. 2's low-pass claim, the design table, controller (18).

Each function records its quantities and findings into a :class:`~ctrl_analysis.reporting.report.StudyResult`
and returns the data the figures need; finding texts are generated from the computed numbers.
"""

from __future__ import annotations

import math

import control as ct
import numpy as np
import sympy as sp
from scipy.optimize import brentq

from ctrl_analysis.controllers.differential_feedback import hurwitz_roots
from ctrl_analysis.estimators.differential import DifferentialEstimator
from ctrl_analysis.metrics import resonance_peak
from ctrl_analysis.reporting.report import StudyResult
from ctrl_analysis.symbolic import differential as sym

from .paper import Linear, applied_gains, printed_eq5_coefficients, printed_eq9_gain

__all__ = ["min_stable_gain", "peak", "design_row", "eq9_checks", "eq5_checks", "lowpass_checks",
           "controller_poles", "fmt_poles"]


def min_stable_gain(n0: int, a: float) -> float:
    """Smallest K > 0 above which Σ(n0, a, K) is Hurwitz (0 if it is Hurwitz for every K > 0).

    Bisection on the largest real part of the roots of ``s^n0 + K (s + a)^(n0-1)``.
    """

    def max_real(k):
        return DifferentialEstimator(n0, a, k, allow_unstable=True).poles.real.max()

    k_design = sym.breakaway_gain(n0, a)
    lo = 1e-9 * k_design
    if max_real(lo) < 0:
        return 0.0
    return float(brentq(max_real, lo, k_design, xtol=1e-12 * k_design, rtol=1e-12))


def peak(est: DifferentialEstimator) -> tuple[float, float]:
    """Resonance peak (dB) and its frequency of Φ: :func:`ctrl_analysis.metrics.resonance_peak` on a fine grid."""
    return resonance_peak(est.tf, est.a * np.logspace(-1, 1.5, 40001))


def design_row(n0: int, a: float) -> dict:
    """One row of the design table: K, a_i, poles, bandwidth, peak, roll-off, stability range."""
    est = DifferentialEstimator(n0, a)
    phi = est.tf
    bw = float(ct.bandwidth(phi))
    peak_db, w_peak = peak(est)
    k_min = min_stable_gain(n0, a)
    return {"n0": n0, "a": a, "K": est.K, "a_coeffs": est.a_coeffs.tolist(), "poles": est.poles.tolist(),
            "bandwidth_3db_rad_s": bw, "bandwidth_over_a": bw / a, "resonance_peak_db": peak_db,
            "resonance_freq_rad_s": w_peak, "gain_db_at_10x_bandwidth": float(20 * np.log10(abs(phi(10j * bw)))),
            "K_min_stable": k_min, "K_over_K_min": est.K / k_min if k_min > 0 else math.inf}


def fmt_poles(p) -> str:
    """Poles as text, a complex pair once as ``re±imj``."""
    parts = []
    for z in p:
        if abs(z.imag) < 1e-6 * max(1.0, abs(z)):
            parts.append(f"{z.real:.4g}")
        elif z.imag > 0:
            parts.append(f"{z.real:.4g}±{z.imag:.4g}j")
    return "[" + ", ".join(parts) + "]"


def eq9_checks(result: StudyResult, L: Linear) -> dict:
    """Derive the breakaway point and gain, compare with the printed eq. (9); quantities ``eq9.*``."""
    d = sym.derive_breakaway()
    n = sp.Symbol("n", integer=True, positive=True)
    ratio = sp.simplify(sp.powsimp(d.gain / printed_eq9_gain(sym.N0, sym.A, n), force=True))
    n0, a = L.fig1_n0, L.fig1_a
    est = DifferentialEstimator(n0, a)
    s_b, k_b = sym.breakaway_point(n0, a), sym.breakaway_gain(n0, a)
    k_printed = {m: float(printed_eq9_gain(n0, a, m)) for m in (2, 3, 4, n0)}
    cl_poles = ct.feedback(est.open_loop_tf, 1).poles()
    near = np.sort(np.abs(cl_poles - s_b))[:2]
    printed_formula = -sym.N0 * sym.A
    same = sp.simplify(d.breakaway - printed_formula) == 0
    result.check(
        "eq9.breakaway_point", "Breakaway point of the root locus of G, n0 = 5, a = 2 (derived with sympy)",
        s_b, unit="1/s",
        note=f"The paper prints the formula s = {L.breakaway} (text above eq. (8)), no number; sympy gives dK/ds = 0 "
             f"<=> {sp.sstr(d.dK_ds_reduced)} = 0 besides s = 0, i.e. s = {sp.sstr(d.breakaway)}, "
             f"{'the printed formula' if same else 'NOT the printed formula'}; for n0 = {n0}, a = {a:g} the printed "
             f"formula gives {float(printed_formula.subs({sym.N0: n0, sym.A: a})):g}. An algebraic identity: a "
             "check, not a reproduced cell.")
    result.check(
        "eq9.double_pole_gap", f"Distance between the two closed-loop poles of Σ nearest to the breakaway point at the "
        f"derived gain, n0 = {n0}, a = {a:g} (python-control)", float(near.max()), unit="1/s",
        note=f"feedback(G, 1) at K = {k_b:.6g}: a double real pole at {s_b:g} shows as a gap of ~0 (numerical "
             f"root splitting of a double root is ~sqrt(machine epsilon)); largest pole real part "
             f"{float(cl_poles.real.max()):+.4g}.")
    result.check("eq9.design_max_real_pole", f"Largest real part of Σ's poles at the derived gain, n0 = {n0}, "
                 f"a = {a:g}", float(cl_poles.real.max()), unit="1/s", note="negative: Σ is stable at the design gain")
    result.quantity(
        "eq9.gain_K", "Gain K at the breakaway point, n0 = 5, a = 2 (derived)", k_b, unit="1/s",
        note=f"derived K = n0^n0 a/(n0-1)^(n0-1) = {k_b:.6g}. The paper prints no number, only the formula "
             f"K = n0^n a/(n0-1)^(n0-1) with the plant order n unfixed: for n = 2, 3, 4, 5 it gives "
             + ", ".join(f"{v:.6g}" for v in k_printed.values()) + "; equal to the derived gain only for n = n0 "
             "(finding eq9-exponent).")
    p_pr = {m: DifferentialEstimator(n0, a, k, allow_unstable=True).poles for m, k in k_printed.items()}
    result.finding(
        "eq9-exponent",
        "Eq. (9)'s exponent n must read n0: only K = n0^n0 a/(n0-1)^(n0-1) puts a double pole at the breakaway point "
        "s = -n0 a (sympy, for general n0 and a). Eq. (9) is printed K = n0^n a/(n0-1)^(n0-1). Solving dK/ds = 0 on "
        "K(s) = -s^n0/(s+a)^(n0-1) with sympy for general n0, a gives dK/ds · (s + a)^n0/s^(n0-1) = "
        f"{sp.sstr(d.dK_ds_reduced)}, so besides s = 0 (K = 0) the only critical point, the breakaway (strictly a "
        f"break-in: K has a minimum there, d2K/ds2 = {sp.sstr(d.second_derivative)} > 0) is s = {sp.sstr(d.breakaway)} "
        f"as the paper says, and K(-n0 a) = {sp.sstr(d.gain)}, i.e. n0^n0 a/(n0-1)^(n0-1): the exponent of n0 must be "
        f"n0, not n (derived/printed = {sp.sstr(ratio)}). The power of a (a^1) is right: a_n0 = K a^(n0-1) has units "
        f"s^-n0, so K must have units 1/s like a. For n0 = 5, a = 2: derived K = {k_b:.6g} (closed-loop poles "
        f"{fmt_poles(p_pr[n0])}, double pole at -10 confirmed by python-control); printed with n = 4: K = "
        f"{k_printed[4]:.6g}, poles {fmt_poles(p_pr[4])} (stable but no double pole, a lightly damped pair); n = 3: K "
        f"= {k_printed[3]:.4g}, max Re = {p_pr[3].real.max():.3f}; n = 2: K = {k_printed[2]:.4g}, max Re = "
        f"{p_pr[2].real.max():.3f} (unstable). Only n = n0 reproduces the stated double pole, so n is a typo (or lost "
        "subscript) for n0.",
        evidence={"derived_gain": sp.sstr(d.gain), "derived_over_printed": sp.sstr(ratio), "K_derived": k_b,
                  "K_printed_by_n": k_printed,
                  "max_real_pole_by_n": {m: float(p.real.max()) for m, p in p_pr.items()}}, kind="erratum")
    return {"K_printed_by_n": k_printed}


def eq5_checks(result: StudyResult, L: Linear) -> None:
    """Compare the printed sign pattern of eq. (5) with the expansion of K ∏(s - z_i) (finding ``eq5-sign``)."""
    rows = {}
    for n0 in L.table_n0:
        zs = sp.symbols(f"z1:{n0}")
        derived = sym.coefficients_from_zeros(zs)
        a1, a2, an0 = printed_eq5_coefficients(zs, sym.KGAIN)
        rows[n0] = {"a1_ok": sp.expand(derived[0] - a1) == 0,
                    "a2_ok": sp.expand(derived[1] - a2) == 0 if n0 >= 3 else None,
                    "an0_ratio": sp.sstr(sp.cancel(derived[-1] / an0))}
    est = DifferentialEstimator(L.fig1_n0, L.fig1_a)
    flipped = est.a_coeffs.copy()
    flipped[-1] *= -1  # (5) as printed, with z_i = -a: a_n0 = (-1)^n0 K (-a)^(n0-1) = -K a^(n0-1)
    p_flip = np.roots(np.concatenate(([1.0], flipped)))
    a2_ok = all(r["a2_ok"] in (True, None) for r in rows.values())
    ratios = sorted({r["an0_ratio"] for r in rows.values()})
    result.finding(
        "eq5-sign",
        f"Eq. (5) has the wrong sign on its last coefficient, and with the printed sign Σ is unstable for every K "
        f"(largest pole real part {p_flip.real.max():+.3g} for n0 = 5, a = 2). "
        f"Eq. (5) prints a_1 = K, a_2 = -K Σz_i, a_n0 = (-1)^n0 K ∏z_i. Expanding K ∏(s - z_i) with sympy "
        f"for n0 = {L.table_n0[0]}..{L.table_n0[-1]} and symbolic zeros: a_1 and a_2 are right "
        f"({'all match' if a2_ok else 'MISMATCH'}), but derived/printed a_n0 = {', '.join(ratios)} for every n0: "
        f"the last term is a_n0 = (-1)^(n0-1) K ∏z_i (in general a_i = (-1)^(i-1) K e_(i-1)(z)). With the "
        f"printed sign and z_i = -a, a_n0 = -K a^(n0-1) < 0, so the characteristic polynomial has a negative "
        f"coefficient and Σ is unstable for every K: for n0 = 5, a = 2 at the design gain the largest pole real "
        f"part is {p_flip.real.max():+.4f} (derived signs: {est.poles.real.max():+.4f}). Eq. (6) also says "
        f"z_i = -a for i = 1..n0, but (4) has only n0 - 1 zeros. The toolkit uses the derived signs, "
        f"a_i = K C(n0-1, i-1) a^(i-1).",
        evidence={"per_n0": rows, "max_real_pole_printed_sign": float(p_flip.real.max())}, kind="erratum")


def lowpass_checks(result: StudyResult, L: Linear) -> list:
    """Fig. 2 bandwidth and peak (``fig2.*``), the design table, findings ``lowpass-claim``, ``eq12-limit``."""
    est2 = DifferentialEstimator(L.fig2_n0, L.fig2_a)
    row2 = design_row(L.fig2_n0, L.fig2_a)
    dc, hf = float(ct.dcgain(est2.tf)), float(abs(est2.tf(1e6j)))
    result.quantity("fig2.bandwidth_3db", "Fig. 2: -3 dB bandwidth of Φ, n0 = 5, a = 5",
                    row2["bandwidth_3db_rad_s"], unit="rad/s", note="control.bandwidth")
    result.quantity("fig2.resonance_peak_db", "Fig. 2: resonance peak of |Φ|, n0 = 5, a = 5",
                    row2["resonance_peak_db"], unit="dB",
                    note=f"at {row2['resonance_freq_rad_s']:.4g} rad/s (ctrl_analysis.metrics.resonance_peak)")
    result.quantity("fig2.dc_gain", "Fig. 2: DC gain of Φ, n0 = 5, a = 5", dc, unit="", note="control.dcgain")
    result.quantity("fig2.gain_db_at_10x_bandwidth", "Fig. 2: |Φ| a decade above the −3 dB bandwidth, n0 = 5, a = 5",
                    row2["gain_db_at_10x_bandwidth"], unit="dB",
                    note="a first-order low-pass has −20 dB there")
    table = [design_row(n0, a) for n0 in L.table_n0 for a in L.table_a]
    result.settings["design_table"] = table
    by_n0 = {n0: [r for r in table if r["n0"] == n0] for n0 in L.table_n0}
    spread = max(np.ptp([r["bandwidth_over_a"] for r in rows]) / np.mean([r["bandwidth_over_a"] for r in rows])
                 for rows in by_n0.values())
    peak_spread = max(np.ptp([r["resonance_peak_db"] for r in rows]) for rows in by_n0.values())
    summary = "; ".join(
        f"n0 = {n0}: ω_b = {rows[0]['bandwidth_over_a']:.3g}·a, peak {rows[0]['resonance_peak_db']:.2f} dB, "
        + (f"K/K_min = {rows[0]['K_over_K_min']:.3g}" if rows[0]["K_min_stable"] > 0 else "stable for all K > 0")
        for n0, rows in by_n0.items())
    result.finding(
        "lowpass-claim",
        f"Σ is a first-order low-pass with a {row2['resonance_peak_db']:.2g} dB resonance bump, not a sharp filter: "
        f"beyond its bandwidth Φ(s) rolls off at only -20 dB/decade (n0 = 5, a = 5). "
        f"The paper calls Σ a good low-pass filter (Fig. 2). Measured on Φ(s) for n0 = 5, a = 5 (K = "
        f"{est2.K:.4g}): DC gain {dc:.6g}, -3 dB bandwidth {row2['bandwidth_3db_rad_s']:.4g} rad/s, resonance "
        f"peak +{row2['resonance_peak_db']:.3g} dB at {row2['resonance_freq_rad_s']:.4g} rad/s, "
        f"{row2['gain_db_at_10x_bandwidth']:.3g} dB at 10 ω_b. Φ has relative degree 1, so beyond the bandwidth "
        f"it rolls off at only -20 dB/decade (|Φ| → K/ω): a first-order low-pass with a "
        f"{row2['resonance_peak_db']:.2g} dB bump, not a sharp filter; noise attenuation comes from a wide "
        f"bandwidth (about {row2['bandwidth_over_a']:.3g}·a). Φ depends on a only through s/a (a_i ∝ a^i): "
        f"ω_b/a varies by at most {spread:.1e} (relative) and the peak by {peak_spread:.1e} dB across a = "
        f"{', '.join(f'{v:g}' for v in L.table_a)}. Per n0 (design gain): {summary}. The peak grows with n0; Σ "
        f"is unstable for K < K_min (branches leave the n0-fold pole at 0 into the right half-plane for "
        f"n0 >= 3). Full table: settings.design_table.",
        evidence={"dc_gain": dc, "gain_at_1e6_rad_s": hf, **{k: row2[k] for k in (
            "bandwidth_3db_rad_s", "resonance_peak_db", "resonance_freq_rad_s", "gain_db_at_10x_bandwidth")}})
    result.finding(
        "eq12-limit",
        f"Eq. (12) takes the limit at the wrong end: tracking needs Φ(0) = 1 (s → 0), while Φ(s) → 0 as s → ∞. "
        f"Eq. (12) prints lim_(s→∞) Φ(s) = 1; the limit that gives tracking is s → 0: Φ(0) = {dc:.6g} "
        f"(control.dcgain), while |Φ(j·10^6)| = {hf:.3g} → 0 (Φ is strictly proper).", kind="erratum")
    return table


def controller_poles(result: StudyResult, L: Linear) -> None:
    """Roots of the printed controller polynomial (quantity ``ex2.controller_poles``)."""
    K = applied_gains(L.ex2_K)
    roots = hurwitz_roots(K)
    result.settings["ex2_controller"] = {"K_printed": list(L.ex2_K), "K_applied": list(K),
                                         "polynomial": [1.0, *K[::-1]]}
    result.check(
        "ex2.controller_poles", "Example 2: roots of s^3 + 39 s^2 + 506 s + 2184 (controller (18))",
        roots.real, paper=list(L.ex2_poles), tolerance=1e-6, unit="1/s", cell="§4 Example 2: roots -12, -13, -14",
        note="A check of the paper's arithmetic (not a reproduced cell); the printed roots are integers, 1e-6 covers "
             f"numpy.roots' rounding; max |Im| = {np.abs(roots.imag).max():.1e}. Read as polynomial coefficients, the "
             "printed K = [2184, 506, 39, 1] runs from s^0 to s^3 (the trailing 1 is the coefficient of s^3); the "
             "study applies K = [2184, 506, 39] (reconstruction ex2.K).")
