"""Gong & Wu 2010: every printed value and every reconstruction of the `ckf` study, in one frozen object."""

from __future__ import annotations

from dataclasses import dataclass

from ctrl_analysis.controllers.golden_section import GOLDEN_L1, GOLDEN_L2
from ctrl_analysis.study import printed, reconstructed

__all__ = ["PAPER", "CKFStudy"]



@dataclass(frozen=True)
class CKFStudy:
    """Simulation settings of §3 (printed) and every value the extracted text lost (reconstructed)."""

    Ts: float = printed(0.01, "§3: sampling time 0.01 s")
    t_end: float = printed(100.0, "§3: simulation time 100 s")
    reference: float = printed(10.0, "§3: track the output from 0 to 10")
    noise_std: float = printed(1.0, "§3: measurement noise e ~ N(0, 1)")
    t_filter: float = printed(2.0, "§3: the filtered signal is not used during the first 2 s")
    t_steady: float = printed(20.0, "§3, Table 1: steady stage 20 s - 100 s")
    u_rms_nofilter: float = printed(1.27, "§3: without a filter the control's RMS reaches 1.27")
    plant: str = reconstructed(
        "interlaced",
        "plant (12) lost in extraction; the spec's reconstruction G(s) = 2.285714 (s+2)(s+3)(s+5)(s+7) / "
        "((s+1)(s+2.5)(s+4)(s+6)(s+8)): 5th order, relative degree 1, unit DC gain, real poles and zeros interlaced")
    R: float = printed(1.0, "§3: e ~ N(0, 1), so the measurement variance R = 1 (§2: R from the sensor statistics)")
    Q: tuple = reconstructed(
        ((1e-5, 0.0), (0.0, 1e-5)),
        "§2: the process noise (identification error) 'is hard to know; set a small value first'; 1e-5 I: "
        "between the characteristic model's own one-step residual on the true plant (variance ~1e-7) and the "
        "per-sample change of x in the transient (~1e-2); the sweep of Q (Fig. 11) shows how the ranking depends on it")
    P0_ckf: float = reconstructed(1.0, "initial CKF covariance not printed; the measurement variance")
    forgetting: float = reconstructed(
        0.999, "λ of eq. (9) not printed; memory ~1000 samples (10 s): long enough to average N(0,1) noise, "
        "short against the 100 s run")
    P0_rls: float = reconstructed(1e-3, "initial RLS covariance not printed; small, because the regressors are "
                                  "~10 (the output) and a unit P0 lets the first samples throw θ far from θ0")
    max_trace: float = reconstructed(
        3e-3, "the paper prints no anti-windup; with forgetting and the weak excitation of the steady stage the "
        "RLS covariance grows like λ^-k and the estimates burst after ~50 s; trace R is kept <= trace P0 (3e-3)")
    theta0: tuple = reconstructed(
        (1.9, -0.9, 0.02),
        "θ0 not printed; (f1, f2) inside Wu's ranges near a slow double pole, g0 ≈ (high-frequency gain) · Ts")
    lower: tuple = reconstructed(
        (1.4331, -1.0, 1e-3),
        "projection box: f1 >= 1.4331 and f2 >= -1 are Wu's characteristic-model ranges for small Ts (refs [7],[8]; "
        "quoted by the spec); g0 >= 1e-3 keeps 1/ĝ0 finite (the paper prints no bound)")
    upper: tuple = reconstructed(
        (2.0, -0.5134, 1.0), "projection box: f1 <= 2, f2 <= -0.5134 (Wu's ranges); g0 <= 1 (loose)")
    project: bool = reconstructed(True, "the paper does not say; Wu's identification uses these ranges; "
                                  "the effect of switching it off is reported")
    id_signal: str = reconstructed(
        "lpf", "which signals form z and h in (9) is not printed; options: 'raw' measurement, 'lpf' output "
        "(in every case), 'feedback' (what the controller sees); 'lpf' is the only one under which all three "
        "loops track in every run (ident.*.tracking_fraction); its f̂1, f̂2 bias against the noise-free fit is "
        "not the smallest (ident.* quantities, finding identification-signal)")
    l1: float = reconstructed(GOLDEN_L1, "golden-section coefficient of refs [6]-[8]; eq. (16) lost in extraction")
    l2: float = reconstructed(GOLDEN_L2, "golden-section coefficient of refs [6]-[8]; eq. (16) lost in extraction")
    k_I: float = reconstructed(0.005, "logic-integral gain of eq. (18) not printed; small, so the integral "
                               "removes the offset in a few seconds without amplifying the noise")
    c2: float = reconstructed(0.995, "logic-integral leak c2 of eq. (18) not printed; 0 < c2 <= c1 = 1")
    mu: float = reconstructed(
        1.0, "regularisation 1/(ĝ0 + μ) of eq. (16)-(17) not printed; without it the golden-section gain "
        "0.38 f1/ĝ0 ~ 30 turns N(0,1) noise into a control of RMS ~ 40, against the printed 1.27")
    lpf_omega: float = reconstructed(
        2.0, "LPF cut-off not printed; 2 rad/s lags visibly in the transient (time constant 0.5 s) "
        "yet cuts the noise by ~ sqrt(ω Ts / 2) = 0.1 in the steady state")
    lpf_order: int = reconstructed(1, "LPF order not printed; first order, the simplest digital LPF")
    runs: int = reconstructed(100, "Monte Carlo runs; the paper shows one run")
    option_runs: int = reconstructed(20, "runs of the comparison of identification options and of the "
                                     "projection switch (every option runs all three cases)")
    option_t_end: float = reconstructed(60.0, "horizon of the option and projection comparisons (steady stage "
                                        "20-60 s), to keep `reproduce ckf` under 30 s")
    kf_Q: float = reconstructed(0.01, "process noise of the full-order KF that knows the plant, as an input "
                                "disturbance: Q = q b bᵀ (b the discrete input vector), q = 0.01 (std 0.1, 1 % of "
                                "the steady control); the plant is deterministic, a small Q keeps the gain from vanishing")
    kf_P0: float = reconstructed(1.0, "initial covariance of the full-order KF")


PAPER = CKFStudy()

