"""Linear part of the `differential-estimator` study: eq. (3)-(9), Fig. 1-2, a design table.

Qi, Chen, Xue & Yuan (2004). Everything here is linear: the root locus of the open loop G(s)
(Fig. 1), the Bode plot of the closed loop Φ(s) (Fig. 2), the breakaway point and gain of
eq. (9) derived with sympy and checked against the printed formula, the sign pattern of eq. (5),
the claim that Σ is a good low-pass filter (bandwidth, resonance peak, roll-off), and the
controller polynomial of Example 2.
"""

from __future__ import annotations

import math

import control as ct
import numpy as np
import sympy as sp
from scipy.optimize import brentq, minimize_scalar

from ctrl_analysis.estimators.differential import DifferentialEstimator
from ctrl_analysis.report import StudyContext, StudyResult, new_figure
from ctrl_analysis.symbolic import differential as sym

__all__ = [
    "FIG1_N0",
    "FIG1_A",
    "FIG2_N0",
    "FIG2_A",
    "TABLE_N0",
    "TABLE_A",
    "EQ9_PRINTED_N",
    "PAPER_BREAKAWAY",
    "EX2_K",
    "PAPER_EX2_POLES",
    "printed_eq9_gain",
    "printed_eq5_coefficients",
    "min_stable_gain",
    "resonance_peak",
    "design_row",
    "plot_root_locus",
    "plot_bode",
    "plot_normalised_magnitude",
    "run_linear",
]

# ---------------------------------------------------------------- the paper's numbers
FIG1_N0, FIG1_A = 5, 2.0  # Fig. 1: root locus, n0 = 5, a = 2
FIG2_N0, FIG2_A = 5, 5.0  # Fig. 2: Bode plot, n0 = 5, a = 5
TABLE_N0 = tuple(range(2, 9))  # design table (beyond the paper)
TABLE_A = (2.0, 5.0, 7.0)  # a of Fig. 1, Fig. 2 / Example 2, Example 1
#: Eq. (9) is printed with the exponent ``n`` (the order of the plant (1)), which Fig. 1 does not
#: fix; the paper requires n0 >= n + 1, so n = n0 - 1 = 4 is the largest order an n0 = 5 estimator
#: serves. Reconstruction; the values for n = 2, 3 are reported too.
EQ9_PRINTED_N = 4
PAPER_BREAKAWAY = -10.0  # text above eq. (8): s = -n0 a, with n0 = 5, a = 2
#: Example 2, controller (18): K = [k_n, ..., k_1] as printed, with a trailing 1 (the leading
#: coefficient of s^n), and the paper's roots of s^3 + 39 s^2 + 506 s + 2184.
EX2_K = (2184.0, 506.0, 39.0, 1.0)
PAPER_EX2_POLES = (-12.0, -13.0, -14.0)

BODE_OMEGA = np.logspace(-1, 4, 2000)  # rad/s, Fig. 2


# ---------------------------------------------------------------- formulas as printed
def printed_eq9_gain(n0, a, n):
    """Eq. (9) as printed: ``K = n0^n a / (n0 - 1)^(n0-1)`` (works on numbers and sympy symbols)."""
    return n0**n * a / (n0 - 1) ** (n0 - 1)


def printed_eq5_coefficients(zeros, K):
    """The three coefficients eq. (5) prints: ``a_1 = K``, ``a_2 = -K Σ z_i``, ``a_n0 = (-1)^n0 K ∏ z_i``.

    Returns ``(a_1, a_2, a_n0)``; the terms in between are elided ("...") in the paper.
    """
    zeros = list(zeros)
    n0 = len(zeros) + 1
    return K, -K * sum(zeros), (-1) ** n0 * K * sp.prod(zeros)


# ---------------------------------------------------------------- measurements
def min_stable_gain(n0: int, a: float) -> float:
    """Smallest K > 0 above which Σ(n0, a, K) is Hurwitz (0 if it is Hurwitz for every K > 0).

    Bisection on the largest real part of the roots of ``s^n0 + K (s + a)^(n0-1)``; the caller
    checks on a grid that there is a single crossing.
    """

    def max_real(k):
        return DifferentialEstimator(n0, a, k, allow_unstable=True).poles.real.max()

    k_design = sym.breakaway_gain(n0, a)
    lo = 1e-9 * k_design
    if max_real(lo) < 0:
        return 0.0
    return float(brentq(max_real, lo, k_design, xtol=1e-12 * k_design, rtol=1e-12))


def resonance_peak(sys) -> tuple[float, float]:
    """``(peak in dB, frequency in rad/s)`` of a stable SISO system's gain (grid, then refined)."""
    omega = np.logspace(-3, 4, 4000) * max(1.0, float(np.max(np.abs(sys.poles()))))
    mag = np.abs(sys(1j * omega))
    k = int(np.argmax(mag))
    lo, hi = omega[max(k - 1, 0)], omega[min(k + 1, omega.size - 1)]
    res = minimize_scalar(lambda w: -abs(sys(1j * w)), bounds=(lo, hi), method="bounded",
                          options={"xatol": 1e-10 * hi})
    return float(20 * np.log10(-res.fun)), float(res.x)


def design_row(n0: int, a: float) -> dict:
    """One row of the design table: K, a_i, poles, bandwidth, peak, roll-off, stability range."""
    est = DifferentialEstimator(n0, a)
    phi = est.tf
    bw = float(ct.bandwidth(phi))
    peak_db, w_peak = resonance_peak(phi)
    k_min = min_stable_gain(n0, a)
    return {
        "n0": n0,
        "a": a,
        "K": est.K,
        "a_coeffs": est.a_coeffs.tolist(),
        "poles": est.poles.tolist(),
        "bandwidth_3db_rad_s": bw,
        "bandwidth_over_a": bw / a,
        "resonance_peak_db": peak_db,
        "resonance_freq_rad_s": w_peak,
        "gain_db_at_10x_bandwidth": float(20 * np.log10(abs(phi(10j * bw)))),
        "K_min_stable": k_min,
        "K_over_K_min": est.K / k_min if k_min > 0 else math.inf,
    }


# ---------------------------------------------------------------- figures
def plot_root_locus(est: DifferentialEstimator, *, printed_K: float | None = None, printed_n=None,
                    title: str = ""):
    """Root locus of G(s) = K (s+a)^(n0-1)/s^n0 over K > 0, design poles "x", breakaway annotated.

    Left panel: overview with the breakaway point; right panel: zoom on the origin, where the
    branches leave the n0-fold pole (some into the right half-plane) and the slow design poles sit.
    """
    n0, a, k_design = est.n0, est.a, est.K
    g_unit = est.open_loop_tf / k_design  # (s + a)^(n0-1) / s^n0
    gains = np.unique(np.concatenate([
        [0.0],
        np.logspace(-16, 4, 1000) * k_design,
        np.linspace(0.95, 1.05, 101) * k_design,
        [k_design],
    ]))
    loci = ct.root_locus_map(g_unit, gains).loci
    s_b = est.breakaway_point
    design = est.poles

    fig, axes = new_figure(1, 2, title=title, size=(12.0, 5.2), width_ratios=[1.6, 1.0])
    k_min = min_stable_gain(n0, a)
    p_min = DifferentialEstimator(n0, a, k_min, allow_unstable=True).poles if k_min > 0 else np.array([])
    crossing = p_min[np.abs(p_min.real) < 1e-6 * max(1.0, a)]
    views = [((2.5 * s_b, -0.3 * s_b), (1.2 * s_b, -1.2 * s_b)), ((-1.9 * a, 0.8 * a), (-1.5 * a, 1.5 * a))]
    for panel, (ax, (xlim, ylim)) in enumerate(zip(axes, views)):
        for j in range(loci.shape[1]):
            ax.plot(loci[:, j].real, loci[:, j].imag, color="C0", lw=1.3,
                    label="root locus, K from 0 to ∞" if j == 0 else None)
        ax.plot([0], [0], "s", mfc="none", mec="k", ms=9, label=f"open-loop poles (×{n0} at 0)")
        ax.plot([-a], [0], "o", mfc="none", mec="k", ms=9, label=f"open-loop zeros (×{n0 - 1} at −a = {-a:g})")
        ax.plot(design.real, design.imag, "x", color="C3", ms=11, mew=2.2,
                label=f"closed-loop poles at K = {k_design:.4g} (design)")
        if printed_K is not None:
            p_pr = DifferentialEstimator(n0, a, printed_K, allow_unstable=True).poles
            ax.plot(p_pr.real, p_pr.imag, "+", color="C1", ms=11, mew=2.0,
                    label=f"closed-loop poles at printed eq. (9), n = {printed_n}: K = {printed_K:.4g}")
        if crossing.size:
            ax.plot(crossing.real, crossing.imag, "D", color="C4", ms=6,
                    label=f"imaginary-axis crossing, K = {k_min:.4g} (Σ stable only for K > {k_min:.4g})")
        ax.axhline(0, color="0.5", lw=0.6)
        ax.axvline(0, color="0.5", lw=0.6)
        ax.set_xlim(*xlim)
        ax.set_ylim(*ylim)
        ax.set_xlabel("Re s  [1/s]")
        ax.set_ylabel("Im s  [1/s]")
    ax0, ax1 = axes
    ax0.annotate(
        f"breakaway (break-in) point s = −n0·a = {s_b:g}\n(double pole at K = n0^n0·a/(n0−1)^(n0−1) = {k_design:.4g})",
        xy=(s_b, 0), xytext=(1.65 * s_b, 0.8 * abs(s_b)),
        arrowprops=dict(arrowstyle="->", color="C3"), ha="center", fontsize=9, color="C3",
    )
    ax0.set_title("overview")
    ax1.set_title("zoom near the origin")
    ax0.legend(loc="lower left", fontsize=8, framealpha=0.9)
    return fig


def plot_bode(est: DifferentialEstimator, omega=BODE_OMEGA, *, title: str = ""):
    """Bode magnitude (dB) and phase (deg) of Φ(s), −3 dB line, bandwidth, peak, hf asymptote."""
    phi = est.tf
    resp = ct.frequency_response(phi, omega)
    mag_db = 20 * np.log10(np.abs(resp.magnitude))
    phase_deg = np.degrees(np.unwrap(resp.phase))
    bw = float(ct.bandwidth(phi))
    peak_db, w_peak = resonance_peak(phi)

    fig, (axm, axp) = new_figure(2, 1, title=title, size=(8.0, 6.5), sharex=True)
    axm.semilogx(omega, mag_db, color="C0", lw=2.2, label="|Φ(jω)|", zorder=3)
    axm.semilogx(omega, 20 * np.log10(est.a_coeffs[0] / omega), "--", color="0.3", lw=0.9, zorder=4,
                 label=f"high-frequency asymptote a₁/ω (−20 dB/dec), a₁ = K = {est.K:.4g}")
    axm.axhline(-3, color="C3", ls=":", lw=1.2, label="−3 dB")
    axm.axvline(bw, color="C3", ls=":", lw=1.2)
    axm.plot([bw], [-3], "o", color="C3", label=f"bandwidth ω_b = {bw:.4g} rad/s")
    axm.plot([w_peak], [peak_db], "^", color="C2", label=f"resonance peak {peak_db:.3g} dB at {w_peak:.4g} rad/s")
    axm.set_ylim(max(mag_db.min(), -60) - 5, peak_db + 5)
    axm.set_ylabel("magnitude [dB]")
    axm.legend(loc="lower left", fontsize=8)
    axp.semilogx(omega, phase_deg, color="C0", lw=1.8)
    axp.axvline(bw, color="C3", ls=":", lw=1.2)
    axp.set_ylabel("phase [deg]")
    axp.set_xlabel("frequency ω [rad/s]")
    axp.set_yticks(np.arange(-180, 91, 45))
    axp.set_ylim(min(-100, phase_deg.min() - 10), max(10, phase_deg.max() + 10))
    return fig


def plot_normalised_magnitude(n0_values, *, title: str = ""):
    """|Φ(jω)| against ω/a for several n0 (Φ depends on a only through ω/a)."""
    fig, ax = new_figure(title=title, size=(8.0, 4.8))
    w_over_a = np.logspace(-2, 3, 1500)
    for k, n0 in enumerate(n0_values):
        phi = DifferentialEstimator(n0, 1.0).tf
        ax.semilogx(w_over_a, 20 * np.log10(np.abs(phi(1j * w_over_a))), color=f"C{k}", label=f"n0 = {n0}")
    ax.axhline(-3, color="k", ls=":", lw=1, label="−3 dB")
    ax.set_xlabel("normalised frequency ω / a  [–]")
    ax.set_ylabel("|Φ(jω)|  [dB]")
    ax.set_ylim(-40, 6)
    ax.legend(fontsize=8, ncol=2)
    return fig


# ---------------------------------------------------------------- the study's linear part
def _eq9_checks(result: StudyResult) -> dict:
    """Derive breakaway point and gain, compare with the printed eq. (9), record the quantities."""
    d = sym.derive_breakaway()
    n = sp.Symbol("n", integer=True, positive=True)
    ratio = sp.simplify(sp.powsimp(d.gain / printed_eq9_gain(sym.N0, sym.A, n), force=True))
    n0, a = FIG1_N0, FIG1_A
    est = DifferentialEstimator(n0, a)
    s_b = sym.breakaway_point(n0, a)
    k_b = sym.breakaway_gain(n0, a)
    k_printed = {m: float(printed_eq9_gain(n0, a, m)) for m in (2, 3, 4, n0)}

    # python-control cross-check: the closed loop of G at the design gain has a double pole at s_b
    cl_poles = ct.feedback(est.open_loop_tf, 1).poles()
    near = np.sort(np.abs(cl_poles - s_b))[:2]
    result.quantity(
        "eq9.breakaway_point", "Breakaway point of the root locus of G, n0 = 5, a = 2 (derived: -n0 a)",
        s_b, paper=PAPER_BREAKAWAY, tolerance=1e-6, unit="1/s",
        note=f"sympy: dK/ds = 0 <=> {sp.sstr(d.dK_ds_reduced)} = 0 (besides s = 0); python-control: the two "
             f"closed-loop poles of feedback(G, 1) nearest to {s_b:g} lie within {near.max():.1e} of it.",
    )
    result.quantity(
        "eq9.gain_K", "Gain K at the breakaway point, n0 = 5, a = 2 (paper: eq. (9) as printed)",
        k_b, paper=k_printed[EQ9_PRINTED_N], tolerance=1e-6, unit="1/s",
        note=f"derived K = n0^n0 a/(n0-1)^(n0-1) = {k_b:.6g}; printed n0^n a/(n0-1)^(n0-1) with n = "
             f"{EQ9_PRINTED_N} (reconstruction) = {k_printed[EQ9_PRINTED_N]:.6g}; equal only if n = n0.",
    )
    result.reconstruction(
        "eq9_printed_n", EQ9_PRINTED_N,
        "Eq. (9) is printed as K = n0^n a/(n0-1)^(n0-1) with n the plant order of (1), which Fig. 1 "
        "(n0 = 5, a = 2) does not fix; n = n0 - 1 = 4 is the largest order allowed by n0 >= n + 1. "
        f"Printed values for n = 2, 3, 4, 5: {', '.join(f'{v:.6g}' for v in k_printed.values())}.",
    )

    p_pr = {m: DifferentialEstimator(n0, a, k, allow_unstable=True).poles for m, k in k_printed.items()}
    result.finding(
        "eq9-exponent",
        f"Eq. (9) is printed K = n0^n a/(n0-1)^(n0-1). Solving dK/ds = 0 on K(s) = -s^n0/(s+a)^(n0-1) "
        f"with sympy for general n0, a gives dK/ds · (s + a)^n0/s^(n0-1) = {sp.sstr(d.dK_ds_reduced)}, so "
        f"besides s = 0 (K = 0) the only critical point, the breakaway "
        f"(strictly a break-in: K has a minimum there, d2K/ds2 = {sp.sstr(d.second_derivative)} > 0) is "
        f"s = {sp.sstr(d.breakaway)} as the paper says, and K(-n0 a) = {sp.sstr(d.gain)}, i.e. "
        f"n0^n0 a/(n0-1)^(n0-1): the exponent of n0 must be n0, not n (derived/printed = "
        f"{sp.sstr(ratio)}). The power of a (a^1) is right: a_n0 = K a^(n0-1) has units s^-n0, so K "
        f"must have units 1/s like a. For n0 = 5, a = 2: derived K = {k_b:.6g} (closed-loop poles "
        f"{_fmt_poles(p_pr[n0])}, double pole at -10 confirmed by python-control); printed with "
        f"n = 4: K = {k_printed[4]:.6g}, poles {_fmt_poles(p_pr[4])} (stable but no double pole, "
        f"a lightly damped pair); n = 3: K = {k_printed[3]:.4g}, max Re = {p_pr[3].real.max():.3f}; "
        f"n = 2: K = {k_printed[2]:.4g}, max Re = {p_pr[2].real.max():.3f} (unstable). Only n = n0 "
        f"reproduces the stated double pole, so n is a typo (or lost subscript) for n0.",
        evidence={"derived_gain": sp.sstr(d.gain), "derived_over_printed": sp.sstr(ratio),
                  "K_derived": k_b, "K_printed_by_n": k_printed,
                  "max_real_pole_by_n": {m: float(p.real.max()) for m, p in p_pr.items()}},
    )
    return {"K_printed_by_n": k_printed}


def _eq5_checks(result: StudyResult) -> None:
    """Compare the printed sign pattern of eq. (5) with the expansion of K ∏(s - z_i)."""
    rows = {}
    for n0 in TABLE_N0:
        zs = sp.symbols(f"z1:{n0}")
        derived = sym.coefficients_from_zeros(zs)
        a1, a2, an0 = printed_eq5_coefficients(zs, sym.KGAIN)
        rows[n0] = {
            "a1_ok": sp.expand(derived[0] - a1) == 0,
            "a2_ok": sp.expand(derived[1] - a2) == 0 if n0 >= 3 else None,
            "an0_ratio": sp.sstr(sp.cancel(derived[-1] / an0)),
        }
    n0, a = FIG1_N0, FIG1_A
    est = DifferentialEstimator(n0, a)
    flipped = est.a_coeffs.copy()
    flipped[-1] *= -1  # (5) as printed, with z_i = -a: a_n0 = (-1)^n0 K (-a)^(n0-1) = -K a^(n0-1)
    p_flip = np.roots(np.concatenate(([1.0], flipped)))
    a2_ok = all(r["a2_ok"] in (True, None) for r in rows.values())
    ratios = sorted({r["an0_ratio"] for r in rows.values()})
    result.finding(
        "eq5-sign",
        f"Eq. (5) prints a_1 = K, a_2 = -K Σz_i, a_n0 = (-1)^n0 K ∏z_i. Expanding K ∏(s - z_i) with sympy "
        f"for n0 = {TABLE_N0[0]}..{TABLE_N0[-1]} and symbolic zeros: a_1 and a_2 are right "
        f"({'all match' if a2_ok else 'MISMATCH'}), but derived/printed a_n0 = {', '.join(ratios)} for "
        f"every n0: the last term is a_n0 = (-1)^(n0-1) K ∏z_i (in general a_i = (-1)^(i-1) K e_(i-1)(z)). "
        f"With the printed sign and z_i = -a, a_n0 = -K a^(n0-1) < 0, so the characteristic polynomial "
        f"has a negative coefficient and Σ is unstable for every K: for n0 = 5, a = 2 at the design gain "
        f"the largest pole real part is {p_flip.real.max():+.4f} (derived signs: "
        f"{est.poles.real.max():+.4f}). Eq. (6) also says z_i = -a for i = 1..n0, but (4) has only "
        f"n0 - 1 zeros. The toolkit uses the derived signs, a_i = K C(n0-1, i-1) a^(i-1).",
        evidence={"per_n0": rows, "max_real_pole_printed_sign": float(p_flip.real.max())},
    )


def _fmt_poles(p) -> str:
    parts = []
    for z in p:
        if abs(z.imag) < 1e-6 * max(1.0, abs(z)):
            parts.append(f"{z.real:.4g}")
        elif z.imag > 0:
            parts.append(f"{z.real:.4g}±{z.imag:.4g}j")
    return "[" + ", ".join(parts) + "]"


def run_linear(ctx: StudyContext, result: StudyResult) -> None:
    """Fig. 1, Fig. 2, the design table, eq. (5)/(9)/(12) checks and the Example 2 controller poles."""
    ctx.progress("linear part: eq. (9) and (5) checks")
    result.settings["fig1"] = {"n0": FIG1_N0, "a": FIG1_A}
    result.settings["fig2"] = {"n0": FIG2_N0, "a": FIG2_A, "omega_rad_s": [BODE_OMEGA[0], BODE_OMEGA[-1]]}
    eq9 = _eq9_checks(result)
    _eq5_checks(result)

    # ------------------------------------------------------------ Fig. 1
    ctx.progress("Fig. 1 root locus")
    est1 = DifferentialEstimator(FIG1_N0, FIG1_A)
    result.settings["fig1"].update({"K": est1.K, "a_coeffs": est1.a_coeffs.tolist(), "poles": est1.poles.tolist()})
    fig = plot_root_locus(
        est1, printed_K=eq9["K_printed_by_n"][EQ9_PRINTED_N], printed_n=EQ9_PRINTED_N,
        title=f"Fig. 1  Root locus of G(s) = K(s+{FIG1_A:g})^{FIG1_N0 - 1}/s^{FIG1_N0} "
              f"(n0 = {FIG1_N0}, a = {FIG1_A:g}); × = closed-loop poles at the design gain",
    )
    ctx.save_figure(result, fig, "fig1_root_locus.png")

    # ------------------------------------------------------------ Fig. 2 and the low-pass claim
    ctx.progress("Fig. 2 Bode plot and design table")
    est2 = DifferentialEstimator(FIG2_N0, FIG2_A)
    fig = plot_bode(est2, title=f"Fig. 2  Bode plot of Φ(s), y → z₁ (n0 = {FIG2_N0}, a = {FIG2_A:g}, "
                                f"K = {est2.K:.4g})")
    ctx.save_figure(result, fig, "fig2_bode.png")
    row2 = design_row(FIG2_N0, FIG2_A)
    dc = float(ct.dcgain(est2.tf))
    hf = float(abs(est2.tf(1e6j)))
    result.quantity("fig2.bandwidth_3db", "Fig. 2: -3 dB bandwidth of Φ, n0 = 5, a = 5",
                    row2["bandwidth_3db_rad_s"], unit="rad/s", note="control.bandwidth")
    result.quantity("fig2.resonance_peak_db", "Fig. 2: resonance peak of |Φ|, n0 = 5, a = 5",
                    row2["resonance_peak_db"], unit="dB",
                    note=f"at {row2['resonance_freq_rad_s']:.4g} rad/s")

    table = [design_row(n0, a) for n0 in TABLE_N0 for a in TABLE_A]
    result.settings["design_table"] = table
    fig = plot_normalised_magnitude(TABLE_N0, title="Beyond the paper: |Φ(jω)| of Σ at the design gain, "
                                                     "against ω/a, n0 = 2..8")
    ctx.save_figure(result, fig, "extra_phi_magnitude_vs_n0.png")

    by_n0 = {n0: [r for r in table if r["n0"] == n0] for n0 in TABLE_N0}
    spread = max(np.ptp([r["bandwidth_over_a"] for r in rows]) / np.mean([r["bandwidth_over_a"] for r in rows])
                 for rows in by_n0.values())
    peak_spread = max(np.ptp([r["resonance_peak_db"] for r in rows]) for rows in by_n0.values())
    summary = "; ".join(
        f"n0 = {n0}: ω_b = {rows[0]['bandwidth_over_a']:.3g}·a, peak {rows[0]['resonance_peak_db']:.2f} dB, "
        + (f"K/K_min = {rows[0]['K_over_K_min']:.3g}" if rows[0]["K_min_stable"] > 0 else "stable for all K > 0")
        for n0, rows in by_n0.items()
    )
    result.finding(
        "lowpass-claim",
        f"The paper calls Σ a good low-pass filter (Fig. 2). Measured on Φ(s) for n0 = 5, a = 5 (K = "
        f"{est2.K:.4g}): DC gain {dc:.6g}, -3 dB bandwidth {row2['bandwidth_3db_rad_s']:.4g} rad/s, "
        f"resonance peak +{row2['resonance_peak_db']:.3g} dB at {row2['resonance_freq_rad_s']:.4g} rad/s, "
        f"{row2['gain_db_at_10x_bandwidth']:.3g} dB at 10 ω_b. Φ has relative degree 1, so beyond the "
        f"bandwidth it rolls off at only -20 dB/decade (|Φ| → K/ω): a first-order low-pass with a "
        f"{row2['resonance_peak_db']:.2g} dB bump, not a sharp filter; noise attenuation comes from a wide "
        f"bandwidth (about {row2['bandwidth_over_a']:.3g}·a). Φ depends on a only through s/a (a_i ∝ a^i): "
        f"ω_b/a varies by at most {spread:.1e} (relative) and the peak by {peak_spread:.1e} dB across "
        f"a = {', '.join(f'{v:g}' for v in TABLE_A)}. Per n0 (design gain): {summary}. The peak grows "
        f"with n0; Σ is unstable for K < K_min (branches leave the n0-fold pole at 0 into the right "
        f"half-plane for n0 >= 3). Full table: settings.design_table.",
        evidence={"dc_gain": dc, "gain_at_1e6_rad_s": hf, **{k: row2[k] for k in
                  ("bandwidth_3db_rad_s", "resonance_peak_db", "resonance_freq_rad_s", "gain_db_at_10x_bandwidth")}},
    )
    result.finding(
        "eq12-limit",
        f"Eq. (12) prints lim_(s→∞) Φ(s) = 1; the limit that gives tracking is s → 0: Φ(0) = "
        f"{dc:.6g} (control.dcgain), while |Φ(j·10^6)| = {hf:.3g} → 0 (Φ is strictly proper).",
    )

    # ------------------------------------------------------------ Example 2 controller polynomial
    coeffs = np.array(EX2_K[::-1])  # K = [k_n, ..., k_1, 1] -> s^3 + k_1 s^2 + k_2 s + k_3
    roots = np.roots(coeffs)
    roots = roots[np.argsort(-roots.real)]
    result.settings["ex2_controller"] = {"K_printed": list(EX2_K), "polynomial": coeffs.tolist()}
    result.quantity(
        "ex2.controller_poles", "Example 2: roots of s^3 + 39 s^2 + 506 s + 2184 (controller (18))",
        roots.real, paper=list(PAPER_EX2_POLES), tolerance=1e-6, unit="1/s",
        note=f"numpy.roots; max |Im| = {np.abs(roots.imag).max():.1e}. Read as polynomial coefficients, "
             f"the printed K = [2184, 506, 39, 1] runs from s^0 to s^3 (the trailing 1 is the coefficient of "
             f"s^3); how that 1 enters u in (18) is decided with the Example 2 simulation.",
    )
