"""Kalman-type filtering: steady-state gains, Riccati equations, α-β filters, scalar closed forms.

Building blocks, independent of any paper, one topic per module:

* :mod:`._checks` — controllability / observability / detectability ranks and checks (with
  errors that name the argument);
* :mod:`.continuous` — the Kalman–Bucy gain ``K = P Cᵀ R⁻¹`` from the filter ARE
  ``A P + P Aᵀ − P Cᵀ R⁻¹ C P + G Q Gᵀ = 0`` and the Riccati ODE integrated from any ``P(0)``
  (it converges to the ARE solution ``P̄``, not to zero);
* :mod:`.discrete` — the discrete steady-state gain in **filter form** (``K``, the update gain of
  ``x̂(k|k)``) and in **predictor form** (``L = F K``, what ``control.dlqe`` returns), and
  sampled-data noise discretisation (Van Loan);
* :mod:`.alpha_beta` — α-β gains from a 2-state filter gain, Kalata's tracking index and closed
  forms, and the constant-gain α-β filter as a discrete block;
* :mod:`.singer` — the α-β-γ filter of Singer's manoeuvre (first-order Markov acceleration) model: its exact
  transition, steady-state gains and prediction kernel;
* :mod:`.filter` — the time-varying discrete Kalman filter as a discrete block;
* :mod:`.scalar` — the scalar random-walk steady-state gain ``K∞(Q/R)``.

Conventions
-----------
Continuous model: ``ẋ = A x + B u + G w``, ``y = C x + v``, ``E[w wᵀ] = Q δ``, ``E[v vᵀ] = R δ``.
Discrete model: ``x(k+1) = F x(k) + G w(k)``, ``y(k) = H x(k) + v(k)``, ``cov w = Q``, ``cov v = R``.
"""

from ._checks import (
                      check_controllable,
                      check_detectable,
                      check_observable,
                      controllability_matrix,
                      controllability_rank,
                      observability_matrix,
                      observability_rank,
)
from .alpha_beta import (
                      AlphaBetaFilter,
                      alpha_beta_from_gain,
                      alpha_beta_stable,
                      gain_from_alpha_beta,
                      kalata_gains,
                      tracking_index,
                      tracking_index_from_gains,
)
from .ckf import CharacteristicKalmanFilter, LinearKalmanFilter
from .continuous import (
                      ContinuousSteadyState,
                      care_residual,
                      continuous_steady_state,
                      continuous_steady_state_gain,
                      riccati_rhs,
                      riccati_trajectory,
)
from .discrete import (
                      DiscreteSteadyState,
                      dare_residual,
                      discrete_steady_state,
                      discrete_steady_state_batch,
                      discretize_noise,
)
from .filter import DiscreteKalmanFilter
from .ikf import ImprovedKalmanFilter
from .scalar import random_walk_gain

__all__ = [
    "controllability_matrix", "observability_matrix", "controllability_rank", "observability_rank",
    "check_controllable", "check_observable", "check_detectable",
    "ContinuousSteadyState", "continuous_steady_state", "continuous_steady_state_gain", "care_residual",
    "riccati_rhs", "riccati_trajectory",
    "DiscreteSteadyState", "discrete_steady_state", "discrete_steady_state_batch", "dare_residual",
    "discretize_noise",
    "alpha_beta_from_gain", "gain_from_alpha_beta", "tracking_index", "tracking_index_from_gains", "kalata_gains",
    "alpha_beta_stable", "AlphaBetaFilter", "DiscreteKalmanFilter",
    "random_walk_gain",
    "ImprovedKalmanFilter",
    "CharacteristicKalmanFilter", "LinearKalmanFilter",
]
