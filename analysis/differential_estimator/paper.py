"""What Qi, Chen, Xue & Yuan (2004) print, and every value the study reconstructs, in frozen objects.

:data:`LINEAR` holds the linear part (eq. 5-9, Fig. 1-2, controller (18)), :data:`EX1` Example 1
(eq. 19, Fig. 3-4) and :data:`EX2` Example 2 (eq. 20, Fig. 5). Each field is declared with
:func:`~ctrl_analysis.reporting.study.printed` (where the paper prints it) or
:func:`~ctrl_analysis.reporting.study.reconstructed` (why this value); quick settings are
``dataclasses.replace(EX1, T=2.0)``, never module globals.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ctrl_analysis.reporting.study import (
    Claim,
    choices,
    fixed,
    printed,
    reconstructed,
    span,
)

__all__ = ["Linear", "Example1", "Example2", "Readings", "LINEAR", "EX1", "EX2", "READINGS", "CLAIMS", "han_eso_gains",
           "applied_gains", "printed_eq9_gain", "printed_eq5_coefficients", "HAN_2008", "setpoint"]

#: The source of the ESO exponents and of the step-size gain rule (the paper prints neither).
HAN_2008 = ("Han Jingqing, Active Disturbance Rejection Control Technique (自抗扰控制技术), National "
            "Defense Industry Press, Beijing, 2008, ESO chapter")


@dataclass(frozen=True)
class Linear:
    """The linear part: Fig. 1 and Fig. 2 settings, eq. (8)-(9), controller (18) of Example 2."""

    fig1_n0: int = printed(5, "Fig. 1: root locus for n0 = 5")
    fig1_a: float = printed(2.0, "Fig. 1: a = 2")
    fig2_n0: int = printed(5, "Fig. 2: Bode plot for n0 = 5")
    fig2_a: float = printed(5.0, "Fig. 2: a = 5")
    breakaway: str = printed("-n0 a", "text above eq. (8): the breakaway point is s = -n0 a (a formula, no number)")
    eq9_n: int = reconstructed(
        4, "eq. (9) is printed K = n0^n a/(n0-1)^(n0-1) with n the plant order, which Fig. 1 does not fix; "
           "n = n0 - 1 = 4 (the largest order an n0 = 5 estimator serves) is drawn in Fig. 1; only the figure "
           "uses it, the quantity eq9.gain_K carries no paper value",
        plausible=fixed("only Fig. 1's extra marker (the printed gain's poles) uses it; no quantity, cell or claim "
                        "reads it, and every n < n0 misses the double pole (finding eq9-exponent)"))
    ex2_K: tuple = printed((2184.0, 506.0, 39.0, 1.0), "§4 Example 2: K = [2184, 506, 39, 1]")
    ex2_poles: tuple = printed((-12.0, -13.0, -14.0), "§4 Example 2: roots of s^3 + 39 s^2 + 506 s + 2184")
    table_n0: tuple = (2, 3, 4, 5, 6, 7, 8)  # design table (beyond the paper)
    table_a: tuple = (2.0, 5.0, 7.0)  # a of Fig. 1, Fig. 2 / Example 2, Example 1


def han_eso_gains(h: float) -> tuple[float, float, float]:
    """Han's step rule for the 3rd-order nonlinear ESO: ``β01 = 1/h``, ``β02 = 1/(1.6 h^1.5)``, ``β03 = 1/(8.6 h^2.2)``.

    Parameters
    ----------
    h : float
        The step the gains are designed for (s).

    Returns
    -------
    tuple of float

    References
    ----------
    Han (2008), ESO chapter (:data:`HAN_2008`): the rule with ``fal`` exponents 0.5, 0.25 and
    ``δ = h``, as quoted throughout the ADRC literature (not checked against the book here).
    The paper's ESO reference, Han 1995 ([8]), prints no gains.
    """
    return 1.0 / h, 1.0 / (1.6 * h**1.5), 1.0 / (8.6 * h**2.2)


@dataclass(frozen=True)
class Example1:
    """Example 1, eq. (19): plant + Σ (n0 = 5, a = 7) against Han's nonlinear ESO."""

    b1: float = printed(3.0, "§4 Example 1, eq. (19)")
    b2: float = printed(1.0, "§4 Example 1, eq. (19)")
    w_freq: float = printed(0.3, "§4 Example 1: w = sign(cos(0.3 t)), rad/s")
    xi_bound: float = printed(0.1, "§4 Example 1: ξ ~ U[-0.1, 0.1]")
    eta_bound: float = printed(0.001, "§4 Example 1: η ~ U[-0.001, 0.001]")
    n0: int = printed(5, "§4 Example 1: Σ with n0 = 5")
    a: float = printed(7.0, "§4 Example 1: Σ with a = 7")
    sigma_err: tuple = printed((1.3179e-4, 5.4e-3), "§4 Example 1, Fig. 3: mean errors of Σ")
    eso_err: tuple = printed((5.769e-4, 8.23e-2), "§4 Example 1, Fig. 4: mean errors of the ESO of [7]")
    h: float = reconstructed(
        1e-3, "the paper prints no step; 1 ms fixed step, noise drawn once per step and held (white noise of a sampled "
              "simulation), as the spec suggests first",
        plausible=span(5e-4, 2e-3, "fixed steps of 0.5-2 ms are what a simulation of this plant (fastest estimator "
                                   "pole ~ -35 1/s) would use; the step is also the noise's hold time, so it sets the "
                                   "noise's spectral density", scale="log", points=3))
    T: float = reconstructed(
        20.0, "the paper prints no horizon; 20 s (spec); mean errors include the start-up transient from zero "
              "initial states",
        plausible=span(10.0, 40.0, "Fig. 3-4's time axes are lost in extraction; 10-40 s covers half to two periods "
                                   "of w = sign(cos 0.3 t) (period 21 s)", scale="log", points=3))
    method: str = reconstructed(
        "rk4", "classical RK4 on plant + Σ + ESO together",
        plausible=choices(("euler",), "forward Euler is how Han's ESO is usually simulated (and Simulink's ode1)"))
    eso_alpha: tuple = reconstructed(
        (1.0, 0.5, 0.25), f"the paper prints no ESO parameter at all; the fal exponents 0.5, 0.25 of the second "
                          f"and third channel and the linear first channel (α = 1) are Han's textbook defaults "
                          f"({HAN_2008})",
        plausible=choices(((1.0, 0.75, 0.5), (1.0, 1.0, 1.0)),
                          "milder fal exponents, and the linear ESO (all α = 1), are the other forms in the ADRC "
                          "literature of the time"))
    eso_tuning_ratio: float = reconstructed(
        1.0, f"the paper prints no β0i; Han's step-size rule β01 = 1/h', β02 = 1/(1.6 h'^1.5), β03 = 1/(8.6 h'^2.2) "
             f"({HAN_2008}) for the simulation step, h' = h (ratio h'/h = 1); not tuned toward the paper's numbers",
        plausible=span(1.0, 3.0, "the rule for a design step h' from the simulation step up to 3 steps (a slower, "
                                 "less noise-sensitive ESO, as in Han's practice of a filter step h0 > h); below 1 "
                                 "the gains would be designed for a shorter step than the one simulated, against the "
                                 "rule's intent (at 1/4 and 1/8 of it the ESO diverges: claim eso-diverges). A ratio, "
                                 "so that the design step follows the simulation step h, which the box varies too",
                       scale="log", points=3))
    eso_delta: float | None = reconstructed(
        None, "δ of fal is unprinted; δ = h' (None) goes with Han's step-size rule",
        plausible=choices((5e-3, 1e-2), "δ = 5 ms and δ = 10 ms (5 and 10 steps of 1 ms) are the other common choices "
                                        "in Han's examples"))
    reading: str = reconstructed(
        "state", "remark (1): with measurement noise the states z_i of Σ are taken as the estimates, x̂_i = z_i",
        plausible=fixed("not an unprinted value: remark (1) prescribes this reading whenever there is measurement "
                        "noise, as in both examples; eq. (11)'s corrected estimate x̂_i = z_i + a_(i-1)(y - z1) is the "
                        "noise-free theorem's. Nor is it the paper's formula against a correction (both are printed), "
                        "so it is not an algorithm axis either. What eq. (11)'s reading would change is computed "
                        "beside the main run (quantity ex1.sigma.corrected.mean_abs_err_x2, finding ex1-reading, "
                        "and the note of claim sigma-beats-eso)"))
    t_sens: float = 5.0  # s, window of the half-step sensitivity
    bound: float = 1e8  # |state| beyond this: diverged


@dataclass(frozen=True)
class Example2:
    """Example 2, eq. (20): third-order plant + Σ + high-order differential feedback (18)."""

    b1: float = reconstructed(
        1.0, "b1, b2, b3 are 'arbitrary' (b3 > 0); b1 = 1 (open-loop unstable plant, the case the paper singles out)",
        plausible=span(-10.0, 10.0, "'any real numbers in a fairly large range'; ±10 is an order of magnitude "
                                    "either side of 1 (the grid of the robustness map goes to ±100)", points=5))
    b2: float = reconstructed(2.0, "'arbitrary'; spec reconstruction",
                              plausible=span(-10.0, 10.0, "'any real numbers in a fairly large range'", points=5))
    b3: float = reconstructed(1.0, "'arbitrary', b3 > 0; spec reconstruction",
                              plausible=span(0.1, 10.0, "'arbitrary' with b3 > 0: two decades around 1", scale="log",
                                             points=3))
    w_amp: float = printed(0.2, "§4 Example 2: w = 0.2 sign(cos(0.5 t))")
    w_freq: float = printed(0.5, "§4 Example 2: w = 0.2 sign(cos(0.5 t)), rad/s")
    r_freq: float = printed(0.15, "§4 Example 2: r = sign(cos(0.15 t)), rad/s")
    xi_bound: float = printed(0.1, "§4 Example 2: noise as in Example 1")
    eta_bound: float = printed(0.001, "§4 Example 2: noise as in Example 1")
    K: tuple = reconstructed(
        (2184.0, 506.0, 39.0),
        "the printed K = [2184, 506, 39, 1] is read as the ascending coefficients of the monic s^3 + 39 s^2 + "
        "506 s + 2184: the trailing 1 is the coefficient of s^3 and enters no gain, u = 2184 ε1 + 506 ε2 + 39 ε3 "
        "— the only reading under which the printed roots -12, -13, -14 are the closed-loop poles on x''' = u "
        "(with u += ε4 the s^3 coefficient would be 2)",
        plausible=fixed("the printed polynomial s^3 + 39 s^2 + 506 s + 2184 fixes the three gains; the other reading "
                        "(the trailing 1 multiplying ε4) is analysed in the linearisation and is unstable as well "
                        "(finding ex2-literal-unstable)"))
    n0: int = printed(5, "§4 Example 2: Σ with n0 = 5")
    a: float = printed(5.0, "§4 Example 2: Σ with a = 5")
    reading: str = reconstructed(
        "state", "remark (1): with noise the states z_i are the estimates fed back, x̂_i = z_i, i = 1..3",
        plausible=fixed("remark (1) prescribes this reading with measurement noise (Example 2 has it); eq. (11)'s "
                        "corrected estimates are the noise-free theorem's. Its effect on the linearised loop is "
                        "computed beside (finding ex2-literal-unstable: unstable under both readings)"))
    omega: float = reconstructed(
        2.0, "the paper 'softens' r = sign(cos 0.15 t) without saying how; r through ω³/(s+ω)³ "
             "(LowPassFilter, exact zero-order hold), whose phase-variable states are θ = (v, v', v'') exactly",
        plausible=span(0.5, 5.0, "a third-order softener from a slow ramp (time constant 2 s, well inside the 21 s "
                                 "half-period of r) to an almost raw step", scale="log", points=3))
    h: float = reconstructed(1e-3, "unprinted; 1 ms RK4 step and noise held per step as in Example 1; the control "
                                   "u = K ε is evaluated at every integration stage (θ and the noise held)",
                             plausible=span(5e-4, 2e-3, "as Example 1's step", scale="log", points=3))
    T: float = reconstructed(
        30.0, "unprinted; 30 s covers the rise at 0 s and the switch of r at 10.5 s",
        plausible=choices((25.0, 50.0), "horizons whose last quarter (where settling is judged) holds no switch of r "
                                        "(switches at 10.5, 31.4, 52.4 s)"))
    bound: float = 1e6  # |state| beyond this: diverged
    stable_margin: float = reconstructed(
        1.0, "decay margin (1/s) required of the study's stable preset fast_estimator (beyond the paper)",
        plausible=fixed("designs the study's own preset; no verdict reads it (the preset's numbers appear only in "
                        "the notes of ex2-tracks and ex2-robust)"))
    ripple_tol: float = reconstructed(
        0.01, "the paper says x1 'tracks' v without a bar; settled = half peak-to-peak of x1 - v over the last "
              "quarter below 0.01 (1 % of the unit setpoint)",
        plausible=span(0.003, 0.03, "a settling bar from 0.3 % to 3 % of the unit setpoint", scale="log", points=3))
    sweep_b1: tuple = (-100.0, -10.0, 0.0, 1.0, 10.0, 100.0)
    sweep_b2: tuple = (-100.0, -10.0, 0.0, 2.0, 10.0, 100.0)
    sweep_b3: tuple = (0.1, 1.0, 10.0)


@dataclass(frozen=True)
class Readings:
    """How the study reads the paper's words when it judges the claims (no simulation depends on them)."""

    fair_margin: float = reconstructed(
        1.05, "'more accurate' at equal bandwidth (claim sigma-beats-eso-fair) is read as every ESO's mean error at "
              "least 5 % above Σ's on every state; a smaller gap is a tie (the step and horizon reconstructions alone "
              "move Σ's errors by more than 5 %)",
        plausible=span(1.0, 1.2, "from any strict advantage to a 20 % one", points=3))


LINEAR = Linear()
EX1 = Example1()
EX2 = Example2()
READINGS = Readings()

#: The paper's claims, each judged in :mod:`.claims` on computed quantities (``sigma-beats-eso-fair`` is the
#: project's own test, beyond the paper: the paper never compares at equal bandwidth).
CLAIMS = (
    Claim("breakaway-design", "§2, eq. (6)-(9), Fig. 1",
          "Placing two closed-loop poles at the breakaway point s = -n0 a gives Σ a real repeated pole there and a "
          "stable estimator"),
    Claim("lowpass", "§2, remark (1), Fig. 2",
          "Σ is a good low-pass filter: it tracks the low-frequency signal without static error and strongly "
          "attenuates high-frequency noise"),
    Claim("larger-n0", "§2, remark (2)", "The larger n0, the higher the estimation accuracy"),
    Claim("sigma-beats-eso", "§4 Example 1, Fig. 3-4",
          "Σ estimates x1 and x2 more accurately than the observer of [7] (Han's ESO), at the paper's tuning "
          "(unprinted; Han's step-size rule)"),
    Claim("sigma-beats-eso-fair", "§4 Example 1 (the comparison made tuning-fair; the project's own test)",
          "Σ estimates x1 and x2 more accurately than an ESO of the same -3 dB bandwidth (linear, and Han's fal form)",
          beyond=True),
    Claim("eso-diverges", "§4 Example 1, last sentence",
          "The observer of [7] diverges when its parameters are badly chosen"),
    Claim("ex2-tracks", "§4 Example 2, Fig. 5",
          "Controller (18) with K = [2184, 506, 39, 1] and Σ (n0 = 5, a = 5) stabilises plant (20) and x1 tracks "
          "the softened square wave v"),
    Claim("ex2-robust", "§4 Example 2",
          "The loop keeps Fig. 5's behaviour for b1, b2, b3 chosen arbitrarily over a wide range, also for b1 > 0"),
    Claim("nonminimum-phase", "§4 Example 2", "For b1 > 0 the plant is unstable, i.e. non-minimum phase"),
)


def applied_gains(printed_K) -> tuple:
    """The gains ``[k_3, k_2, k_1]`` the study applies, from the printed ``[k_3, k_2, k_1, 1]``.

    Raises
    ------
    ValueError
        If the printed vector does not end with the leading coefficient 1.
    """
    if printed_K[-1] != 1.0:
        raise ValueError(f"printed_K must end with the leading coefficient 1, got {printed_K[-1]}")
    return tuple(printed_K[:-1])


def printed_eq9_gain(n0, a, n):
    """Eq. (9) as printed: ``K = n0^n a / (n0 - 1)^(n0-1)`` (numbers or sympy symbols)."""
    return n0**n * a / (n0 - 1) ** (n0 - 1)


def printed_eq5_coefficients(zeros, K):
    """The coefficients eq. (5) prints: ``(a_1, a_2, a_n0) = (K, -K Σ z_i, (-1)^n0 K ∏ z_i)`` (the rest elided)."""
    import sympy as sp

    zeros = list(zeros)
    n0 = len(zeros) + 1
    return K, -K * sum(zeros), (-1) ** n0 * K * sp.prod(zeros)


def setpoint(p: Example2, n_steps: int) -> np.ndarray:
    """``r_k = sign(cos(0.15 t_k))`` at ``t_k = k h`` (Example 2's raw square wave)."""
    return np.sign(np.cos(p.r_freq * p.h * np.arange(n_steps)))
