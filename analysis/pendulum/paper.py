"""The paper's printed values and every reconstruction of the `pendulum` study, in two frozen objects.

:data:`VERIFY` holds §2–§4 (the model, Q, R, the printed P and K) and the settings of the gain
verification; :data:`LOOP` holds §3.2 and §5 (the fuzzy controller's factors, the step) and the
closed-loop reconstructions (sampling period, rule table, simulated noise, horizons).
Quick settings are ``dataclasses.replace`` of these (see :func:`quick`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from ctrl_analysis.study import printed, reconstructed

__all__ = ["LOOP", "VERIFY", "ClosedLoop", "Verify", "physical_a21", "quick"]

#: §4: printed "steady-state error covariance" (6×6, as extracted; entry (6,2) reads −12.5, (2,6) −125).
P_PRINTED = (
    (266.3, 44.7, -470.1, 141.8, -20.1, -84.5),
    (44.7, 371.4, -763.6, 67.7, 4.0, -125.0),
    (-470.1, -763.6, 2648.1, -416.3, 40.9, 442.0),
    (141.8, 67.7, -416.3, 107.7, -14.7, -74.4),
    (-20.1, 4.0, 40.9, -14.7, 2.7, 7.7),
    (-84.5, -12.5, 442.0, -74.4, 7.7, 75.2),
)


def physical_a21(b2: float, g: float) -> tuple[float, float]:
    """Pendulum length and a21 consistent with the input gain.

    For ``φ'' = 3g/(4l) φ + 3/(4l) u`` (u = cart acceleration), ``B2 = 3/(4l)`` so
    ``l = 3/(4 B2)`` and ``a21 = 3g/(4l) = g·B2``.

    Parameters
    ----------
    b2 : float, > 0
        Input gain (1/m).
    g : float, > 0
        Gravity (m/s²).

    Returns
    -------
    (l, a21) : (m, 1/s²)

    Raises
    ------
    ValueError
        If ``b2`` or ``g`` is not positive.
    """
    if not (b2 > 0 and g > 0):
        raise ValueError(f"b2 and g must be > 0, got b2={b2!r}, g={g!r}")
    length = 3.0 / (4.0 * b2)
    return length, 3.0 * g / (4.0 * length)


@dataclass(frozen=True)
class Verify:
    """§2–§4: the model, the noise intensities, the printed P and K; settings of the verification."""

    B2: float = printed(2.6683, "§3.1 and §4: B = [0, 2.6683]ᵀ (1/m, input = cart acceleration)")
    a21_printed: float = printed(2.6149, "§4 filter equation (§3.1 extracts as '2.614 9')")
    Q: float = printed(100.0, "§3.1 and §5: Q(t) = 100")
    R: float = printed(50.0, "§3.1 and §5: R(t) = 50")
    K_printed: tuple = printed((0.950, 0.863), "§4: K = P(t)Cᵀ(t)R⁻¹(t) = [0.950, 0.863]ᵀ = [α, β]ᵀ")
    P_printed: tuple = printed(P_PRINTED, "§4: the 6×6 'steady-state P' as extracted")
    step: float = printed(0.1, "§5: step input of 0.1 rad")
    step_deg_printed: float = printed(5.7325, "§5: '0.1 弧度 (相当于 5.7325°)'")
    g: float = reconstructed(9.8, "gravity used to derive a21 = 3g/(4l) = g·B2; 9.8 reproduces the printed digits")
    T_alpha_beta: float = reconstructed(
        0.01, "sampling period for the discrete α-β gains (not printed; 10 ms is typical of laboratory pendulum "
              "rigs); noise sampled exactly (Van Loan) with Rd = R/T")
    T_grid: tuple = reconstructed((0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1),
                                  "sampling periods tried when looking for an interpretation that reproduces K (s)")
    T_sweep: tuple = reconstructed((1e-3, 0.5, 200), "range and resolution of the continuous sweep of T (s), evidence only")
    gain_tol: float = reconstructed(0.02, "relative tolerance for the printed gains (3 printed digits; allows "
                                          "rounding of a21 and T)")
    riccati_t_end: float = 2.5
    riccati_n_t: int = 301
    riccati_P0: tuple = (
        ("P(0) = 0", ((0.0, 0.0), (0.0, 0.0))),
        ("P(0) = diag(1e3, 1e3)", ((1e3, 0.0), (0.0, 1e3))),
        ("P(0) = diag(2e3, 3e4)", ((2e3, 0.0), (0.0, 3e4))),
        ("P(0) = diag(1e2, 1e5)", ((1e2, 0.0), (0.0, 1e5))),
    )
    riccati_rtol: float = 1e-8
    bode_omega: tuple = (1e-1, 1e3, 400)
    root_check_q: float = reconstructed(
        2.0, "Q/R at which the sympy ARE root is checked to be the stabilising one, at this study's two a21 "
             "readings (sample points moved out of the library's symbolic/riccati.py)")

    @property
    def a21(self) -> float:
        """The physical a21 = g·B2 (the default reading; see the reconstruction ``a21``)."""
        return physical_a21(self.B2, self.g)[1]

    @property
    def length(self) -> float:
        return physical_a21(self.B2, self.g)[0]


@dataclass(frozen=True)
class ClosedLoop:
    """§3.2 and §5: the fuzzy controller, the step, and the closed-loop reconstructions."""

    b2: float = printed(2.6683, "§3.1: B2 (1/m)")
    K_printed: tuple = printed((0.950, 0.863), "§4: the suboptimal filter's K = [α, β]ᵀ")
    step: float = printed(0.1, "§5: step of 0.1 rad in the angle reference")
    Ke: float = printed(70.0, "§3.2: Ke = 6/0.0857 = 70 (0.0857 rad the largest angle error)")
    Kec: float = printed(5.0, "§3.2: Kec = 6/1.2 = 5 (1.2 rad/s the largest error rate)")
    Ku: float = printed(18.0, "§3.2: Ku = 126/7 = 18 (126 m/s² the largest acceleration)")
    input_range: float = printed(6.0, "§3.2: inputs quantised onto [−6, 6] (the 6 in 6/0.0857 and 6/1.2)")
    output_range: float = printed(7.0, "§3.2: output universe [−7, 7] (the 7 in 126/7)")
    n_terms: int = reconstructed(7, "membership functions not printed: seven evenly spaced triangular terms "
                                    "NB NM NS ZO PS PM PB on each universe")
    rule_sign: int = reconstructed(1, "rule table not printed: U = sat(E + EC, ±3) with e = r − φ, ec = ė; the "
                                      "sign that makes a positive error accelerate φ upward (B2 > 0), checked in "
                                      "closed loop (finding rule-sign)")
    n_lookup: int = reconstructed(121, "query-table grid per input universe (0.1 quantisation steps), bilinear "
                                       "interpolation; direct inference is the reference")
    T: float = reconstructed(0.005, "sampling period of the controller and the filter, not printed; 5 ms is the "
                                    "usual period of teaching pendulum rigs; 10 ms makes the fuzzy loop oscillate, "
                                    "2 ms removes a small limit cycle but costs 2.5× the steps (finding "
                                    "sampling-period)")
    period_check: tuple = reconstructed((0.002, 0.005, 0.01), "sampling periods compared noise-free (s)")
    substeps: int = reconstructed(4, "RK4 steps per sample for the pendulum (inputs held)")
    t_end: float = reconstructed(3.0, "simulated horizon (s); the paper's Fig. 3-4 axes are not legible")
    sigma_v: float = reconstructed(0.005, "measurement noise std per sample (rad): 0.29°, a coarse encoder or a "
                                          "potentiometer; the paper's R = 50 is not an angle noise (finding "
                                          "noise-plausibility)")
    qr_ratio: float = reconstructed(2.0, "Q/R of the simulated noise kept at the paper's 100/50, so the filter "
                                         "gains derived from Q/R are the optimal ones for the simulated noise")
    P0_kf: tuple = reconstructed((0.01, 1.0), "initial covariance diag of the time-varying KF (rad², rad²/s²)")
    settle_band: float = reconstructed(0.05, "settling band ±5 % of the step (the 2 % band lies inside the noise)")
    settle_hold: float = reconstructed(0.5, "a run counts as settled only if it stays in the band for the last 0.5 s "
                                           "of the record (otherwise its settling time is not defined)")
    t_ss: float = reconstructed(1.5, "start of the steady-state window (s) for angle_rms and accel_rms; the overshoot is the peak before it")
    bound: float = reconstructed(1e3, "a run whose state leaves |x| ≤ 1000 is flagged as diverged")
    runs: int = reconstructed(100, "Monte Carlo runs (default; --runs overrides, --quick uses 10)")
    recover_angles: tuple = reconstructed((0.02, 1.56, 78), "initial angles swept for the largest recoverable angle "
                                                             "(start, stop, count; rad), noise-free, r = 0")
    recover_tol: float = reconstructed(0.005, "recovered: |φ(t_end)| below this (rad) and |φ| < π/2 throughout")

    @property
    def sigma_w(self) -> float:
        """Process noise std per sample (rad/s²): intensities scaled together, ``σ_w² T / (σ_v² T) = Q/R``."""
        return math.sqrt(self.qr_ratio) * self.sigma_v


VERIFY = Verify()
LOOP = ClosedLoop()


def quick(verify: Verify = VERIFY, loop: ClosedLoop = LOOP) -> tuple[Verify, ClosedLoop]:
    """The ``--quick`` settings: coarser grids, shorter horizon, fewer angles."""
    return (dataclasses.replace(verify, T_sweep=(verify.T_sweep[0], verify.T_sweep[1], 40), riccati_n_t=101,
                                bode_omega=(verify.bode_omega[0], verify.bode_omega[1], 100)),
            dataclasses.replace(loop, t_end=2.0, t_ss=1.0, runs=10, recover_angles=(0.02, 1.56, 23)))
