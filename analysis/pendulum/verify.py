"""The verify part of the study (§2, §4): the steady-state gain, the Riccati ODE, the printed P and K.

Every interpretation of "the steady-state gain of the stated problem" that was tried (continuous
ARE, the printed ARE literally, discrete steady states over T × noise model × filter/predictor form
× β convention, both a21 readings, Q and R as given or swapped), the printed 6×6 P checked as a
covariance, and the stability of the printed filter. Data only: quantities and findings are in
:mod:`.verify_quantities`, figures in :mod:`.figures`.
"""

from __future__ import annotations

import functools
import itertools
import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from ctrl_analysis.estimators.kalman import (
    AlphaBetaFilter,
    alpha_beta_from_gain,
    care_residual,
    continuous_steady_state,
    controllability_rank,
    discrete_steady_state,
    discrete_steady_state_batch,
    discretize_noise,
    kalata_gains,
    observability_rank,
    riccati_trajectory,
)
from ctrl_analysis.reporting.report import relative_error
from ctrl_analysis.symbolic.riccati import derive_second_order_gain

from .paper import VERIFY, Verify, physical_a21

__all__ = [
    "NOISE_DESCRIPTION",
    "NOISE_MODELS",
    "GainInterpretation",
    "VerifyData",
    "best_over_sampling_period",
    "compute_verify",
    "fmt_vec",
    "gain_cells_data",
    "gain_interpretations",
    "pendulum_matrices",
    "verify_printed_P",
]

NOISE_MODELS = ("sampled", "per-step", "dwna")
NOISE_DESCRIPTION = {
    "sampled": "sampled continuous noise: Qd = Van Loan ∫ e^{Aτ}ΓQΓᵀe^{Aᵀτ}dτ, Rd = R/T",
    "per-step": "Q, R read as per-step variances with Γ = [0, 1]ᵀ",
    "dwna": "Q, R per-step variances, Γd = [T²/2, T]ᵀ (Kalata's DWNA model)",
}


def pendulum_matrices(a21: float, b2: float = VERIFY.B2):
    """``(A, B, Γ, C)`` of the linear pendulum of §3.1.

    Parameters
    ----------
    a21 : float
        (2,1) entry of A (1/s²).
    b2 : float
        Input gain (1/m).

    Returns
    -------
    A, B, G, C : numpy.ndarray
    """
    A = np.array([[0.0, 1.0], [float(a21), 0.0]])
    B = np.array([[0.0], [float(b2)]])
    G = np.array([[0.0], [1.0]])
    C = np.array([[1.0, 0.0]])
    return A, B, G, C


# ---------------------------------------------------------------------------------------------
# interpretations of the printed K
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class GainInterpretation:
    """One reading of "the steady-state gain of the stated problem" and the (α, β) it gives."""

    kind: str  # 'continuous', 'printed ARE (literal)', 'discrete'
    a21: float
    swapped: bool  # Q and R exchanged
    T: float | None = None
    noise: str = ""
    form: str = ""  # 'filter' (K) or 'predictor' (L = F K)
    beta_rule: str = "beta = k2"  # or 'beta = T k2' (Kalata's dimensionless β)
    alpha: float = math.nan
    beta: float = math.nan
    error: float = math.inf  # max relative error of (α, β) vs the printed K

    @property
    def name(self) -> str:
        parts = [self.kind, f"a21={self.a21:.5g}"]
        if self.T is not None:
            parts += [f"T={self.T:g} s", self.noise, f"{self.form} form", self.beta_rule]
        if self.swapped:
            parts.append("Q,R swapped")
        return ", ".join(parts)


def _discrete(a21: float, Q: float, R: float, T: float, noise: str):
    """One discrete steady state with python-control's dlqe (full argument checks)."""
    A, _, G, C = pendulum_matrices(a21)
    if noise == "sampled":
        F, Qd = discretize_noise(A, G, Q, T)
        return F, discrete_steady_state(F, C, np.eye(2), Qd, R / T)
    F = scipy.linalg.expm(A * T)
    Gd = G if noise == "per-step" else np.array([[T * T / 2.0], [T]])
    return F, discrete_steady_state(F, C, Gd, Q, R)


def _discrete_batch(a21: float, Q: float, R: float, Ts, noise: str):
    """Discrete steady states for every T in ``Ts`` at once (doubling algorithm)."""
    A, _, G, C = pendulum_matrices(a21)
    Ts = np.asarray(Ts, dtype=float)
    if noise == "sampled":
        pairs = [discretize_noise(A, G, Q, T) for T in Ts]
        F = np.stack([f for f, _ in pairs])
        Qd = np.stack([q for _, q in pairs])
        Rd = R / Ts
    else:
        F = scipy.linalg.expm(A[None] * Ts[:, None, None])
        if noise == "per-step":
            Qd = np.broadcast_to(G @ G.T * Q, (Ts.size, 2, 2))
        else:  # dwna
            g = np.stack([Ts * Ts / 2.0, Ts], axis=-1)[:, :, None]
            Qd = g @ np.swapaxes(g, 1, 2) * Q
        Rd = np.full(Ts.size, R)
    return discrete_steady_state_batch(F, C, Qd, Rd)


def _discrete_rows(a21, Q, R, Ts, noise, swapped, K_paper):
    ss = _discrete_batch(a21, Q, R, Ts, noise)
    rows = []
    for i, T in enumerate(np.asarray(Ts, dtype=float)):
        for form, gain in (("filter", ss.K_filter[i]), ("predictor", ss.L_predictor[i])):
            k = gain.ravel()
            for rule, beta in (("beta = k2", k[1]), ("beta = T k2", T * k[1])):
                ab = (float(k[0]), float(beta))
                rows.append(GainInterpretation("discrete", a21, swapped, float(T), noise, form, rule, *ab,
                                               relative_error(ab, K_paper)))
    return rows


def gain_interpretations(a21_values, Q=VERIFY.Q, R=VERIFY.R, T_grid=VERIFY.T_grid, K_paper=VERIFY.K_printed) -> list:
    """(α, β) under every interpretation tried, sorted by the max relative error vs ``K_paper``.

    Continuous filter ARE; the printed (sign-flipped, A↔Aᵀ) ARE taken literally; and discrete
    steady-state gains for each ``T`` in ``T_grid`` × noise model × filter/predictor form ×
    β convention; each for every a21 and with Q, R as given or swapped.
    """
    rows = []
    for a21, swapped in itertools.product(a21_values, (False, True)):
        q, r = (R, Q) if swapped else (Q, R)
        A, _, G, C = pendulum_matrices(a21)
        k = continuous_steady_state(A, C, G, q, r).K.ravel()
        rows.append(GainInterpretation("continuous", a21, swapped, alpha=k[0], beta=k[1],
                                       error=relative_error(k, K_paper)))
        # printed ARE 0 = −PA − AᵀP + PCᵀR⁻¹CP − ΓQΓᵀ  ⇔  the filter ARE of Aᵀ
        k = continuous_steady_state(A.T, C, G, q, r).K.ravel()
        rows.append(GainInterpretation("printed ARE (literal)", a21, swapped, alpha=k[0], beta=k[1],
                                       error=relative_error(k, K_paper)))
        for noise in NOISE_MODELS:
            rows += _discrete_rows(a21, q, r, T_grid, noise, swapped, K_paper)
    return sorted(rows, key=lambda g: g.error)


def best_over_sampling_period(a21_values, Q=VERIFY.Q, R=VERIFY.R, sweep=VERIFY.T_sweep,
                              K_paper=VERIFY.K_printed) -> GainInterpretation:
    """The discrete interpretation closest to ``K_paper`` when T is swept over ``sweep`` (evidence only)."""
    Ts = np.geomspace(sweep[0], sweep[1], int(sweep[2]))
    rows = []
    for a21, swapped, noise in itertools.product(a21_values, (False, True), NOISE_MODELS):
        q, r = (R, Q) if swapped else (Q, R)
        rows += _discrete_rows(a21, q, r, Ts, noise, swapped, K_paper)
    return min(rows, key=lambda g: g.error)


# ---------------------------------------------------------------------------------------------
# the printed P
# ---------------------------------------------------------------------------------------------


def verify_printed_P(P_printed, P_bars: dict, R: float = VERIFY.R) -> dict:
    """Is the printed matrix a covariance of the 2-state system, and does any 2×2 block match P̄?"""
    P = np.asarray(P_printed, dtype=float)
    n = P.shape[0]
    asym = np.abs(P - P.T)
    i, j = np.unravel_index(np.argmax(asym), asym.shape)
    eig_sym = np.linalg.eigvalsh(0.5 * (P + P.T))
    P_alt = P.copy()
    P_alt[j, i] = P[i, j] if abs(P[i, j]) > abs(P[j, i]) else P[j, i]  # the other reading of the pair
    P_alt[i, j] = P_alt[j, i]
    eig_alt = np.linalg.eigvalsh(P_alt)
    blocks = {}
    for name, Pbar in P_bars.items():
        best = (math.inf, None)
        for r1, r2 in itertools.combinations(range(n), 2):
            sub = P[np.ix_((r1, r2), (r1, r2))]
            err = float(np.linalg.norm(sub - Pbar) / np.linalg.norm(Pbar))
            if err < best[0]:
                best = (err, (r1 + 1, r2 + 1))
        blocks[name] = {"closest_principal_block": best[1], "relative_frobenius_error": best[0]}
    symmetric = bool(asym.max() <= 1e-9 * max(1.0, np.abs(P).max()))
    return {
        "shape": list(P.shape),
        "symmetric": symmetric,
        "max_asymmetry": float(asym.max()),
        "asymmetric_entry": [int(i) + 1, int(j) + 1],
        "asymmetric_values": [float(P[i, j]), float(P[j, i])],
        "eig_symmetric_part": eig_sym.tolist(),
        "min_eig_symmetric_part": float(eig_sym.min()),
        "min_eig_if_symmetrised_with_larger_entry": float(eig_alt.min()),
        "K_from_first_column": (P[:2, 0] / R).tolist(),
        "blocks": blocks,
        "is_covariance_of_2_state_system": bool(P.shape == (2, 2) and symmetric and eig_sym.min() >= 0),
    }


# ---------------------------------------------------------------------------------------------
# everything the verify part computes, in one record
# ---------------------------------------------------------------------------------------------


@dataclass
class VerifyData:
    """What :func:`compute_verify` returns: matrices, steady states, checks, interpretations."""

    P: Verify
    a21: float
    A: np.ndarray
    B: np.ndarray
    G: np.ndarray
    C: np.ndarray
    ranks: dict
    cont: object
    cont_alt: object
    are_res: np.ndarray
    k_sym: np.ndarray
    k_sym_alt: np.ndarray
    lit: object
    lit_poles: np.ndarray
    printed_res: np.ndarray
    t: np.ndarray
    traj: dict
    end_err: dict
    Pcheck: dict
    rows: list
    sweep_best: GainInterpretation
    poles_printed: dict
    abf: dict
    discrete: dict
    bode_filters: dict
    omega: np.ndarray


def _steady_states(P: Verify, a21: float):
    A, B, G, C = pendulum_matrices(a21, P.B2)
    cont = continuous_steady_state(A, C, G, P.Q, P.R, require="observable")
    cont_alt = continuous_steady_state(pendulum_matrices(P.a21_printed)[0], C, G, P.Q, P.R)
    deriv = derive_second_order_gain(samples=((a21, P.root_check_q), (P.a21_printed, P.root_check_q)))
    lit = continuous_steady_state(A.T, C, G, P.Q, P.R)  # PA + AᵀP − PCᵀR⁻¹CP + ΓQΓᵀ = 0
    # residual of the filter solution P̄ in the printed equation (−PA − AᵀP + PCᵀR⁻¹CP − ΓQΓᵀ)
    printed_res = -(cont.P @ A + A.T @ cont.P - cont.P @ C.T @ C @ cont.P / P.R + G @ G.T * P.Q)
    return dict(A=A, B=B, G=G, C=C, cont=cont, cont_alt=cont_alt,
                are_res=care_residual(A, C, G, P.Q, P.R, cont.P),
                k_sym=deriv.numeric(a21, P.Q / P.R), k_sym_alt=deriv.numeric(P.a21_printed, P.Q / P.R),
                lit=lit, lit_poles=np.linalg.eigvals(A - lit.K @ C), printed_res=printed_res,
                ranks={"rank[Γ, AΓ]": controllability_rank(A, G), "rank[C; CA]": observability_rank(A, C),
                       "rank[B, AB]": controllability_rank(A, B)})


def _discrete_alpha_beta(P: Verify, a21: float) -> dict:
    """Discrete α-β gains at ``T_alpha_beta`` (sampled noise) and Kalata's tracking index."""
    T = P.T_alpha_beta
    _F, dss = _discrete(a21, P.Q, P.R, T, "sampled")
    alpha, beta = alpha_beta_from_gain(dss.K_filter, T)
    # tracking index of the double-integrator part: continuous noise averaged over T has variances Q/T, R/T
    Lam = math.sqrt(P.Q / T) * T**2 / math.sqrt(P.R / T)
    ka, kb = kalata_gains(Lam)
    F0 = np.array([[1.0, T], [0.0, 1.0]])
    dwna = discrete_steady_state(F0, np.array([[1.0, 0.0]]), np.array([[T * T / 2], [T]]), P.Q / T, P.R / T)
    a0, b0 = alpha_beta_from_gain(dwna.K_filter, T)
    return dict(T=T, dss=dss, alpha=alpha, beta=beta, Lam=Lam, kalata=(ka, kb), dwna=(a0, b0))


def compute_verify(P: Verify = VERIFY) -> VerifyData:
    """Run every computation of the verify part (§2, §4) with the settings in ``P``."""
    a21 = P.a21
    s = _steady_states(P, a21)
    a21_values = (a21, P.a21_printed)
    t = np.linspace(0.0, P.riccati_t_end, P.riccati_n_t)
    traj = {name: riccati_trajectory(s["A"], s["C"], s["G"], P.Q, P.R, np.array(P0), t, rtol=P.riccati_rtol)
            for name, P0 in P.riccati_P0}
    cont = s["cont"]
    end_err = {name: float(np.linalg.norm(Pt[-1] - cont.P) / np.linalg.norm(cont.P)) for name, Pt in traj.items()}
    Pcheck = verify_printed_P(np.array(P.P_printed), {"P_bar(a21=g·B)": cont.P, "P_bar(a21=2.6149)": s["cont_alt"].P},
                              R=P.R)
    rows = gain_interpretations(a21_values, P.Q, P.R, P.T_grid, P.K_printed)
    sweep_best = best_over_sampling_period(a21_values, P.Q, P.R, P.T_sweep, P.K_printed)
    Kp = np.array(P.K_printed)[:, None]
    poles = {name: np.linalg.eigvals(pendulum_matrices(a)[0] - Kp @ s["C"]) for name, a in
             (("a21 = g·B", a21), ("a21 = 2.6149", P.a21_printed))}
    abf = {T: AlphaBetaFilter(P.K_printed[0], P.K_printed[1], T, F=scipy.linalg.expm(s["A"] * T),
                              require_stable=False) for T in (0.001, P.T_alpha_beta, 0.1)}
    import control as ct

    omega = np.geomspace(P.bode_omega[0], P.bode_omega[1], int(P.bode_omega[2]))
    bode = {}
    for name, a, ss_ in ((f"a21 = g·B = {a21:.4g}", a21, cont), ("a21 = 2.6149", P.a21_printed, s["cont_alt"])):
        Aa = pendulum_matrices(a)[0]
        bode[f"{name}, K = {fmt_vec(ss_.K)}"] = ct.ss(Aa - ss_.K @ s["C"], ss_.K, np.eye(2), np.zeros((2, 1)))
    return VerifyData(P=P, a21=a21, **s, t=t, traj=traj, end_err=end_err, Pcheck=Pcheck, rows=rows,
                      sweep_best=sweep_best, poles_printed=poles, abf=abf, discrete=_discrete_alpha_beta(P, a21),
                      bode_filters=bode, omega=omega)


def gain_cells_data(P: Verify = VERIFY):
    """What the §4 gain cell needs, cheaply (the box exploration): the continuous gain and the closest interpretation.

    Cached on the values they depend on (not on tolerances or other settings of ``P``).

    Returns
    -------
    (K_cont, closest) : (list, GainInterpretation)
    """
    return _gain_cells(P.B2, P.g, P.a21_printed, P.Q, P.R, tuple(P.T_grid), tuple(P.K_printed))


@functools.lru_cache(maxsize=8)
def _gain_cells(B2, g, a21_printed, Q, R, T_grid, K_printed):
    a21 = physical_a21(B2, g)[1]
    A, _B, G, C = pendulum_matrices(a21, B2)
    cont = continuous_steady_state(A, C, G, Q, R, require="observable")
    rows = gain_interpretations((a21, a21_printed), Q, R, T_grid, K_printed)
    return cont.K.ravel().tolist(), rows[0]


def fmt_vec(v, digits=4):
    """``[v0, v1, ...]`` with ``digits`` significant digits (for finding texts)."""
    return "[" + ", ".join(f"{float(x):.{digits}g}" for x in np.ravel(v)) + "]"
