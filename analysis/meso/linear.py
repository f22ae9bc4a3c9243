"""Linear analysis of the observer (29): bandwidth form, poles, error transfer functions, ε-laws.

Everything here is the linear ESO ``L_i = β_i / ε^i`` of the paper, analysed with sympy and
python-control; no simulation (the ε-scaling of the closed-loop errors is measured on the
situation-1 runs in :mod:`.quantities`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import control as ct
import numpy as np
import sympy as sp

from ctrl_analysis.estimators.eso import ExtendedStateObserver
from ctrl_analysis.symbolic.eso import (
    bandwidth_match,
    characteristic_polynomial,
    error_scaling_exponents,
)

from .paper import PAPER, Paper

__all__ = ["LinearAnalysis", "analyse", "noise_std"]


@dataclass(frozen=True)
class LinearAnalysis:
    """Results of :func:`analyse`."""

    observer: ExtendedStateObserver
    omega_o: float
    char_poly: str
    poles: np.ndarray
    error_dc_gains: list
    law: tuple
    eps: np.ndarray
    noise_std: np.ndarray          # (len(eps), 3) steady std of x̂_i − x_i caused by the measurement noise


def noise_std(paper: Paper, epsilon: float) -> np.ndarray:
    """Steady std of the estimation errors caused by the held measurement noise 0.002·U[−1, 1] (per step).

    For the linear (M)ESO the error obeys ``e' = (A − L C) e − L v`` whatever the control (the input
    cancels), so its noise part is the ZOH discretisation of that system driven by white ``v`` of
    variance ``a²/3`` per step: ``P = A_d P A_dᵀ + B_d σ² B_dᵀ`` (``control.dlyap``). Computed once per
    ``(paper, epsilon)`` (the box asks for it at every point).
    """
    return _noise_std(paper, float(epsilon)).copy()


@functools.lru_cache(maxsize=256)
def _noise_std(paper: Paper, epsilon: float) -> np.ndarray:
    obs = ExtendedStateObserver.from_epsilon(paper.n, epsilon, paper.beta, b0=1.0)
    A, B = obs.ss.A, obs.ss.B[:, :1]
    err = ct.c2d(ct.ss(A, -B, np.eye(A.shape[0]), 0), paper.h, method="zoh")
    var = paper.noise_amp ** 2 / 3.0
    P = ct.dlyap(err.A, var * (err.B @ err.B.T))
    return np.sqrt(np.diag(P))


def analyse(paper: Paper = PAPER, eps_grid=(0.1, 0.05, 0.025, 0.0125)) -> LinearAnalysis:
    """Bandwidth form (sympy), poles and error DC gains (python-control), noise std per ε."""
    obs = ExtendedStateObserver.from_epsilon(paper.n, paper.epsilon, paper.beta, b0=paper.b)
    match = bandwidth_match(paper.beta, epsilon=paper.epsilon)
    betas = dict(zip(sp.symbols("beta1:4", positive=True), paper.beta, strict=True))
    p_sym = characteristic_polynomial(paper.n).subs(betas)
    p_sym = sp.expand(p_sym.subs(sp.Symbol("epsilon", positive=True), sp.nsimplify(paper.epsilon)))
    dc = [float(np.real(g.dcgain())) for g in obs.disturbance_error_tf()]
    eps = np.asarray(eps_grid, dtype=float)
    return LinearAnalysis(observer=obs, omega_o=float(match.omega_o), char_poly=str(p_sym),
                          poles=np.sort_complex(obs.poles), error_dc_gains=dc,
                          law=error_scaling_exponents(paper.n), eps=eps,
                          noise_std=np.array([noise_std(paper, e) for e in eps]))
