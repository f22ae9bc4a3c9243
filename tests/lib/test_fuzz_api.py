"""Fuzz table: every public constructor and function of ``ctrl_analysis``, one argument made bad at a time.

Each case starts from a valid call and replaces one argument with a bad value (a string, a list or
``None`` where a number belongs, NaN, inf, a value outside the documented range, a wrong shape, a
non-callable). The call must raise ``ValueError`` or ``TypeError`` whose message names the argument;
never succeed silently and never raise from inside numpy, scipy or sympy with another type. The
number of inputs tried is printed and recorded (``record_property("fuzz_inputs", n)``).

Not fuzzed, on purpose: the per-step kernels that the design keeps unchecked (``euler_step``,
``rk4_step``, ``riccati_rhs``, the ``rhs``/``update`` methods of the blocks), the private
``_validate`` helpers (tested in test_validate.py), the CLI (test_cli*.py), and functions without
numeric arguments (the sympy derivations ``derive_*``, ``coefficient_formula``, ``versions``).
"""

from __future__ import annotations

import math
import re

import control as ct
import numpy as np

from ctrl_analysis import identification as ident
from ctrl_analysis import metrics, report, simulate
from ctrl_analysis.controllers import differential_feedback as hodf
from ctrl_analysis.controllers import pd
from ctrl_analysis.estimators import differential as de
from ctrl_analysis.estimators import eso, lowpass, tracking
from ctrl_analysis.estimators.kalman import _checks, alpha_beta, continuous, discrete, scalar
from ctrl_analysis.symbolic import differential as sym_de
from ctrl_analysis.symbolic import eso as sym_eso
from ctrl_analysis.symbolic import riccati as sym_ric

NAN, INF = math.nan, math.inf

# -- bad values by kind ------------------------------------------------------------------------
TYPE_BAD = ["abc", None, 1 + 2j]  # not a number at all
REAL = TYPE_BAD + [[1.0, 2.0], NAN, INF, -INF]  # one finite real number
POS = REAL + [0.0, -1.0]
NONNEG = REAL + [-1.0]
INT = ["3", None, 2.5, NAN, [2], True]
ARR = ["abc", None, [[1.0, "x"]]]  # an array (its bad shapes / NaN given per case)
CALLABLE = [3.0, "f", None]
# vectorised arguments: an array is fine, a string, None, NaN or inf is not
VREAL = TYPE_BAD + [NAN, INF, -INF]
VPOS = VREAL + [0.0, -1.0]
VNONNEG = VREAL + [-1.0]


def opt(values):
    """The bad values of an optional argument (``None`` means "not given" there, so it is valid)."""
    return [v for v in values if v is not None]
CHOICE = ["nonsense", 3]


def _nan_like(value):
    arr = np.array(value, dtype=float)
    arr.flat[0] = np.nan
    return arr


def _matrix(value):
    """Bad values for a finite matrix argument: NaN entry, strings, wrong shape."""
    return ARR + [_nan_like(value), np.ones((7, 7))]


# -- valid building material ---------------------------------------------------------------------
A2 = [[0.0, 1.0], [-2.0, -3.0]]
C2 = [[1.0, 0.0]]
G2 = [[0.0], [1.0]]
F2 = [[1.0, 0.1], [0.0, 1.0]]
H_REG = np.column_stack([np.linspace(0, 1, 10), np.ones(10)])
Z_REG = 2 * np.linspace(0, 1, 10) + 1
TF1 = ct.tf([1.0], [1.0, 1.0])
PREFILTER = tracking.SetpointPrefilter(2, 10.0)
LPF = lowpass.LowPassFilter(10.0)


def _rhs(t, x, u, params):
    return -x


def _step(k, x, w, params):
    return 0.5 * x


def _quantity(**kw):
    return report.Quantity(**kw)


def _result_quantity(**kw):
    return report.StudyResult(report.StudyInfo("s", "f", "p", "r")).quantity(**kw)


def _rls_step(h, z):
    return ident.RecursiveLeastSquares(2).step(h, z)


def _rls_run(H, z):
    return ident.RecursiveLeastSquares(2).run(H, z)


def _pd_control(ref, x_hat, f_hat):
    return pd.PDFeedforward(b0=2.0, omega_c=10.0).control(ref, x_hat, f_hat)


def _hodf_u(theta, x_hat):
    return hodf.HighOrderDifferentialFeedback([6.0, 11.0, 6.0]).u(theta, x_hat)


def _de_estimates(z, y, reading):
    return de.DifferentialEstimator(3, 2.0).estimates(z, y, reading)


def _de_nlsys(reading):
    return de.DifferentialEstimator(3, 2.0).nlsys(reading=reading)


def _eso_tf(wrt):
    return eso.ExtendedStateObserver.from_bandwidth(2, 10.0).disturbance_error_tf(wrt)


def _ab_step(y, u):
    return alpha_beta.AlphaBetaFilter(0.5, 0.2, 0.1).step(y, u)


def _ab_reset(x0):
    return alpha_beta.AlphaBetaFilter(0.5, 0.2, 0.1).reset(x0)


def _td_reset(x1, x2):
    return tracking.TrackingDifferentiator(10.0, 0.01).reset(x1, x2)


def _td_step(v):
    return tracking.TrackingDifferentiator(10.0, 0.01).step(v)


def _lpf_discretize(h):
    return LPF.discretize(h)


def _lpf_digital(h, initial):
    return LPF.digital(h, initial=initial)


def _dlpf_step(u):
    return lowpass.DiscreteLowPass(LPF, 0.01).step(u)


def _prefilter_derivative(k):
    return PREFILTER.derivative_tf(k)


def _context(runs, seed):
    return report.StudyContext(out_dir=".", runs=runs, seed=seed)


def _new_figure(**kw):
    import matplotlib.pyplot as plt

    fig, _ = report.new_figure(**kw)
    plt.close(fig)


def _runs_or(default, quick_default):
    return report.StudyContext(out_dir=".", quick=True).runs_or(default, quick_default)


# (label, callable, valid keyword arguments, {argument: bad values})
CASES = [
    # symbolic
    ("breakaway_point", sym_de.breakaway_point, dict(n0=5, a=2.0), dict(n0=INT + [1, 400], a=POS)),
    ("breakaway_gain", sym_de.breakaway_gain, dict(n0=5, a=2.0), dict(n0=INT + [1, 400], a=POS)),
    ("locus_gain", sym_de.locus_gain, dict(s_value=-3.0, n0=5, a=2.0), dict(s_value=["abc", None, NAN, [INF]], n0=INT, a=POS)),
    ("coefficients_from_zeros", sym_de.coefficients_from_zeros, dict(zeros=[-1.0, -2.0], gain=3.0),
     dict(zeros=[[], None, "abc", [NAN]], gain=["abc", None, NAN])),
    ("differential_coefficients", sym_de.differential_coefficients, dict(n0=5, a=2.0, K=30.0),
     dict(n0=INT, a=POS, K=POS)),
    ("beta_symbols", sym_eso.beta_symbols, dict(n=2), dict(n=INT + [0])),
    ("gain_symbols", sym_eso.gain_symbols, dict(n=2), dict(n=INT + [0])),
    ("characteristic_polynomial", sym_eso.characteristic_polynomial, dict(n=2, high_gain=True),
     dict(n=INT + [0], high_gain=["yes", None, 2])),
    ("characteristic_coefficients", sym_eso.characteristic_coefficients, dict(n=2), dict(n=INT + [0])),
    ("observer_matrices", sym_eso.observer_matrices, dict(n=2, high_gain=True),
     dict(n=INT + [0], high_gain=["yes", None, 2])),
    ("error_transfer_functions", sym_eso.error_transfer_functions, dict(n=2, high_gain=False),
     dict(n=INT + [0], high_gain=["yes", None, 2])),
    ("error_dc_gains", sym_eso.error_dc_gains, dict(n=2), dict(n=INT + [0])),
    ("error_scaling_exponents", sym_eso.error_scaling_exponents, dict(n=2), dict(n=INT + [0])),
    ("bandwidth_polynomial", sym_eso.bandwidth_polynomial, dict(n=2, omega_o=10.0), dict(n=INT + [0], omega_o=opt(POS))),
    ("bandwidth_match", sym_eso.bandwidth_match, dict(beta=[3.0, 3.0, 1.0], epsilon=0.1),
     dict(beta=ARR + [[1.0], [3.0, -3.0, 1.0], [NAN, 3.0, 1.0]], epsilon=opt(POS))),
    ("second_order_gain", sym_ric.second_order_gain, dict(a21=1.0, q=2.0), dict(a21=VREAL, q=VPOS)),
    ("random_walk_gain_closed_form", sym_ric.random_walk_gain_closed_form, dict(q=0.5), dict(q=VNONNEG)),
    ("kalata_gains_closed_form", sym_ric.kalata_gains_closed_form, dict(Lambda=0.5), dict(Lambda=VNONNEG)),
    # estimators
    ("DifferentialEstimator", de.DifferentialEstimator, dict(n0=5, a=2.0, K=100.0),
     dict(n0=INT + [1, 400], a=POS, K=opt(POS) + [0.01], allow_unstable=["yes", None, 2])),
    ("DifferentialEstimator.estimates", _de_estimates, dict(z=np.zeros(3), y=0.0, reading="state"),
     dict(z=ARR + [np.zeros(4)], y=["abc", None, np.zeros(5)], reading=CHOICE)),
    ("DifferentialEstimator.nlsys", _de_nlsys, dict(reading="state"), dict(reading=CHOICE)),
    ("fal", eso.fal, dict(e=0.5, alpha=0.5, delta=0.1), dict(e=["abc", None], alpha=TYPE_BAD + [NAN], delta=POS)),
    ("ExtendedStateObserver", eso.ExtendedStateObserver,
     dict(gains=[30.0, 300.0, 1000.0], b0=1.0, alpha=[1.0, 0.5, 0.25], delta=0.1, known=None),
     dict(gains=ARR + [[1.0], [1.0, -2.0], [1.0, 1.0, 10.0], _nan_like([30.0, 300.0, 1000.0])],
          b0=REAL, alpha=opt(ARR) + [[0.5], _nan_like([1.0, 0.5, 0.25])], delta=opt(POS), known=[3.0, "f"],
          allow_unstable=["yes", None, 2])),
    ("ExtendedStateObserver.from_epsilon", eso.ExtendedStateObserver.from_epsilon,
     dict(n=2, epsilon=0.05, beta=[3.0, 3.0, 1.0]), dict(n=INT + [0], epsilon=POS, beta=ARR + [[1.0, 2.0], [3, 3, -1]])),
    ("ExtendedStateObserver.from_bandwidth", eso.ExtendedStateObserver.from_bandwidth, dict(n=2, omega_o=10.0),
     dict(n=INT + [0], omega_o=POS)),
    ("ExtendedStateObserver.disturbance_error_tf", _eso_tf, dict(wrt="derivative"), dict(wrt=CHOICE)),
    ("LowPassFilter", lowpass.LowPassFilter, dict(omega_f=10.0, order=2), dict(omega_f=POS, order=INT + [0, 3])),
    ("LowPassFilter.discretize", _lpf_discretize, dict(h=0.01), dict(h=POS)),
    ("LowPassFilter.digital", _lpf_digital, dict(h=0.01, initial=0.0), dict(h=POS, initial=["abc", NAN])),
    ("DiscreteLowPass", lowpass.DiscreteLowPass, dict(lowpass=LPF, h=0.01, shape=(), initial=None),
     dict(lowpass=[3.0, None, "lpf"], h=POS, initial=["abc", NAN])),
    ("DiscreteLowPass.step", _dlpf_step, dict(u=1.0), dict(u=["abc", None, [1.0, 2.0]])),
    ("fhan", tracking.fhan, dict(x1=0.1, x2=0.0, r=10.0, h0=0.01), dict(x1=["abc", None], x2=["abc", None], r=POS,
                                                                        h0=POS)),
    ("TrackingDifferentiator", tracking.TrackingDifferentiator, dict(r=10.0, h=0.01, h0=None, substeps=1),
     dict(r=POS, h=POS, h0=opt(POS), substeps=INT + [0])),
    ("TrackingDifferentiator.reset", _td_reset, dict(x1=0.0, x2=0.0), dict(x1=VREAL, x2=VREAL)),
    ("TrackingDifferentiator.step", _td_step, dict(v=1.0), dict(v=["abc", None, NAN, INF])),
    ("SetpointPrefilter", tracking.SetpointPrefilter, dict(order=2, omega=10.0), dict(order=INT + [0], omega=POS)),
    ("SetpointPrefilter.derivative_tf", _prefilter_derivative, dict(k=1), dict(k=INT + [-1, 3])),
    ("softened_setpoint", tracking.softened_setpoint, dict(softener=PREFILTER, r=np.ones(20), h=0.01, method="zoh"),
     dict(softener=[3.0, None], r=ARR + [np.ones((2, 2)), [], _nan_like(np.ones(20))], h=POS, method=CHOICE)),
    # Kalman family
    ("controllability_matrix", _checks.controllability_matrix, dict(A=A2, B=G2), dict(A=_matrix(A2), B=_matrix(G2))),
    ("observability_matrix", _checks.observability_matrix, dict(A=A2, C=C2), dict(A=_matrix(A2), C=_matrix(C2))),
    ("controllability_rank", _checks.controllability_rank, dict(A=A2, B=G2), dict(A=_matrix(A2), B=_matrix(G2))),
    ("observability_rank", _checks.observability_rank, dict(A=A2, C=C2), dict(A=_matrix(A2), C=_matrix(C2))),
    ("check_controllable", _checks.check_controllable, dict(A=A2, B=G2), dict(A=_matrix(A2), B=_matrix(G2))),
    ("check_observable", _checks.check_observable, dict(A=A2, C=C2), dict(A=_matrix(A2), C=_matrix(C2))),
    ("check_detectable", _checks.check_detectable, dict(A=A2, C=C2), dict(A=_matrix(A2), C=_matrix(C2))),
    ("continuous_steady_state", continuous.continuous_steady_state, dict(A=A2, C=C2, G=G2, Q=1.0, R=0.1),
     dict(A=_matrix(A2), C=_matrix(C2), G=_matrix(G2), Q=NONNEG, R=POS, require=CHOICE)),
    ("continuous_steady_state_gain", continuous.continuous_steady_state_gain, dict(A=A2, C=C2, G=G2, Q=1.0, R=0.1),
     dict(A=_matrix(A2), C=_matrix(C2), G=_matrix(G2), Q=NONNEG, R=POS, require=CHOICE)),
    ("care_residual", continuous.care_residual, dict(A=A2, C=C2, G=G2, Q=1.0, R=0.1, P=np.eye(2)),
     dict(A=_matrix(A2), C=_matrix(C2), G=_matrix(G2), Q=NONNEG, R=POS, P=_matrix(np.eye(2)))),
    ("riccati_trajectory", continuous.riccati_trajectory,
     dict(A=A2, C=C2, G=G2, Q=1.0, R=0.1, P0=np.eye(2), t=[0.0, 0.5, 1.0], rtol=1e-6, atol=1e-9),
     dict(A=_matrix(A2), C=_matrix(C2), G=_matrix(G2), Q=NONNEG, R=POS, P0=_matrix(np.eye(2)) + [-np.eye(2)],
          t=ARR + [[1.0, 0.0], [NAN, 1.0]], rtol=POS, atol=opt(POS))),
    ("discrete_steady_state", discrete.discrete_steady_state, dict(F=F2, H=C2, G=G2, Q=1.0, R=0.1),
     dict(F=_matrix(F2), H=_matrix(C2), G=_matrix(G2), Q=NONNEG, R=POS, require=CHOICE)),
    ("discrete_steady_state_batch", discrete.discrete_steady_state_batch,
     dict(F=np.array([F2]), H=C2, Qd=np.eye(2), R=0.1, tol=1e-12, max_iter=100),
     dict(F=ARR + [np.array(F2), _nan_like([F2])], H=_matrix(C2), Qd=_matrix(np.eye(2)) + [-np.eye(2)],
          R=["abc", None, NAN, -1.0, 0.0], tol=POS, max_iter=INT + [0])),
    ("dare_residual", discrete.dare_residual, dict(F=F2, H=C2, G=G2, Q=1.0, R=0.1, P_prior=np.eye(2)),
     dict(F=_matrix(F2), H=_matrix(C2), G=_matrix(G2), Q=NONNEG, R=POS, P_prior=_matrix(np.eye(2)))),
    ("discretize_noise", discrete.discretize_noise, dict(A=A2, G=G2, Q=1.0, T=0.1),
     dict(A=_matrix(A2), G=_matrix(G2), Q=NONNEG, T=POS)),
    ("random_walk_gain", scalar.random_walk_gain, dict(Q=1.0, R=2.0), dict(Q=VNONNEG, R=VPOS)),
    ("alpha_beta_from_gain", alpha_beta.alpha_beta_from_gain, dict(K=[0.5, 2.0], T=0.1),
     dict(K=ARR + [[1.0], [NAN, 1.0]], T=POS)),
    ("gain_from_alpha_beta", alpha_beta.gain_from_alpha_beta, dict(alpha=0.5, beta=0.2, T=0.1),
     dict(alpha=REAL, beta=REAL, T=POS)),
    ("tracking_index", alpha_beta.tracking_index, dict(sigma_w=1.0, sigma_v=2.0, T=0.1),
     dict(sigma_w=VNONNEG, sigma_v=VPOS, T=VPOS)),
    ("tracking_index_from_gains", alpha_beta.tracking_index_from_gains, dict(alpha=0.5, beta=0.2),
     dict(alpha=VREAL + [1.5], beta=VREAL)),
    ("kalata_gains", alpha_beta.kalata_gains, dict(Lambda=0.5), dict(Lambda=VNONNEG)),
    ("alpha_beta_stable", alpha_beta.alpha_beta_stable, dict(alpha=0.5, beta=0.2), dict(alpha=REAL, beta=REAL)),
    ("AlphaBetaFilter", alpha_beta.AlphaBetaFilter,
     dict(alpha=0.5, beta=0.2, T=0.1, F=None, b=None, x0=None, require_stable=True),
     dict(alpha=REAL + [3.0], beta=REAL, T=POS, F=opt(_matrix(F2)), b=opt(ARR) + [[1.0, 2.0, 3.0]], x0=opt(ARR) + [[1.0, 2.0, 3.0]],
          require_stable=["yes", None, 2])),
    ("AlphaBetaFilter.step", _ab_step, dict(y=1.0, u=0.0), dict(y=["abc", None, NAN, [[1.0]]], u=VREAL + [[[1.0]]])),
    ("AlphaBetaFilter.reset", _ab_reset, dict(x0=[0.0, 0.0]), dict(x0=["abc", [1.0], [NAN, 0.0]])),
    # controllers
    ("hurwitz_roots", hodf.hurwitz_roots, dict(K=[6.0, 11.0, 6.0]), dict(K=ARR + [[NAN, 1.0], []])),
    ("gains_from_poles", hodf.gains_from_poles, dict(poles=[-1.0, -2.0]), dict(poles=ARR + [[NAN], [1j], []])),
    ("HighOrderDifferentialFeedback", hodf.HighOrderDifferentialFeedback, dict(K=[6.0, 11.0, 6.0], n=None),
     dict(K=ARR + [[1.0, -1.0, 1.0], [NAN, 1.0, 1.0], np.ones((2, 2))], n=opt(INT) + [0, 5])),
    ("HighOrderDifferentialFeedback.u", _hodf_u, dict(theta=[1.0, 0.0, 0.0], x_hat=[0.0, 0.0, 0.0]),
     dict(theta=ARR + [[1.0], 1.0], x_hat=ARR + [[1.0], 1.0])),
    ("bandwidth_gains", pd.bandwidth_gains, dict(n=2, omega_c=10.0), dict(n=INT + [0], omega_c=POS)),
    ("PDFeedforward", pd.PDFeedforward, dict(b0=2.0, omega_c=10.0, order=2),
     dict(b0=REAL + [0.0], omega_c=POS, order=INT + [0])),
    ("PDFeedforward(gains)", pd.PDFeedforward, dict(b0=2.0, gains=[100.0, 20.0], order=2),
     dict(gains=ARR + [[1.0], [1.0, -1.0], [100.0, 20.0, 3.0], [NAN, 1.0]], order=INT + [0, 5])),
    ("PDFeedforward.control", _pd_control, dict(ref=[1.0, 0.0, 0.0], x_hat=[0.0, 0.0, 0.0], f_hat=0.0),
     dict(ref=ARR + [[1.0, 0.0]], x_hat=ARR + [[1.0]], f_hat=["abc", None])),
    # identification
    ("identifiability", ident.identifiability, dict(H=H_REG, cond_threshold=100.0),
     dict(H=ARR + [np.ones(3), _nan_like(H_REG), np.ones((0, 2))], cond_threshold=POS)),
    ("batch_least_squares", ident.batch_least_squares, dict(H=H_REG, z=Z_REG, strict=False, cond_threshold=100.0),
     dict(H=ARR + [np.ones(3), _nan_like(H_REG)], z=ARR + [np.ones(4), _nan_like(Z_REG)], cond_threshold=POS,
          strict=["yes", None, 2], warn=["yes", None, 2])),
    ("RecursiveLeastSquares", ident.RecursiveLeastSquares,
     dict(n_params=2, forgetting=0.99, P0=100.0, theta0=None, batch=None),
     dict(n_params=INT + [0], forgetting=REAL + [0.0, 1.5], P0=REAL + [0.0, -np.eye(2), np.ones((3, 3))],
          theta0=opt(ARR) + [[1.0], [NAN, 1.0]], batch=opt(INT) + [0])),
    ("RecursiveLeastSquares.step", _rls_step, dict(h=[1.0, 2.0], z=1.0),
     dict(h=ARR + [[1.0], [NAN, 1.0], [INF, 1.0]], z=["abc", None, NAN, INF, [1.0, 2.0]])),
    ("RecursiveLeastSquares.run", _rls_run, dict(H=H_REG, z=Z_REG),
     dict(H=ARR + [_nan_like(H_REG), np.ones((4, 2))], z=ARR + [_nan_like(Z_REG)])),
    # metrics
    ("mean_abs_error", metrics.mean_abs_error, dict(x=np.ones(5), x_hat=np.zeros(5), axis=0),
     dict(x=["abc", None, np.ones((5, 1)), np.ones(4)], x_hat=["abc", None, np.ones((5, 1))], axis=opt(INT) + [3])),
    ("rmse", metrics.rmse, dict(reference=np.ones(5), y=np.zeros(5), axis=0),
     dict(reference=["abc", None, np.ones((5, 1))], y=["abc", None, np.ones(4)], axis=opt(INT) + [3])),
    ("snr_db", metrics.snr_db, dict(reference=np.ones(5), y=np.zeros(5), axis=0),
     dict(reference=["abc", None, np.ones((5, 1))], y=["abc", None, np.ones(4)], axis=opt(INT) + [3])),
    ("overshoot", metrics.overshoot, dict(t=np.arange(5.0), y=np.ones(5), final=1.0, initial=0.0),
     dict(y=["abc", None], final=REAL + [0.0], initial=REAL + [1.0], axis=opt(INT) + [3])),
    ("settling_time", metrics.settling_time, dict(t=np.arange(5.0), y=np.ones(5), final=1.0, initial=0.0, band=0.02),
     dict(t=ARR + [[0.0, 0.0, 1.0, 2.0, 3.0], np.arange(4.0)], y=["abc", None, np.ones(3)], final=REAL + [0.0],
          initial=REAL + [1.0], band=POS, axis=INT + [3])),
    ("mean_std", metrics.mean_std, dict(values=np.arange(4.0), ok=np.ones(4, bool), axis=0),
     dict(values=["abc", None], ok=[np.ones(3, bool), np.array([0, 1]), [1, 0, 1, 0]], axis=INT + [2])),
    ("bandwidth_3db", metrics.bandwidth_3db, dict(sys=TF1, dbdrop=-3.0), dict(dbdrop=REAL + [3.0])),
    ("resonance_peak", metrics.resonance_peak, dict(sys=TF1, omega=None), dict(omega=opt(ARR) + [[-1.0, 1.0], [NAN, 1.0]])),
    # simulation engine
    ("run_seeds", simulate.run_seeds, dict(base_seed=0, runs=3), dict(base_seed=INT + [-1], runs=INT + [0])),
    ("uniform_noise", simulate.uniform_noise, dict(low=-1.0, high=1.0), dict(low=["abc", None, NAN], high=REAL + [-2.0])),
    ("gaussian_noise", simulate.gaussian_noise, dict(std=1.0, mean=0.0), dict(std=VNONNEG + [[1.0, -1.0]], mean=["abc", None, NAN])),
    ("draw_noise", lambda seeds, n_steps: simulate.draw_noise(seeds, n_steps, simulate.gaussian_noise(1.0)),
     dict(seeds=[1, 2], n_steps=10), dict(seeds=[[], None, ["a"], [1.5], [-1]], n_steps=INT + [0])),
    ("simulate_sampled", simulate.simulate_sampled,
     dict(rhs=_rhs, x0=[1.0, 0.0], h=0.1, n_steps=5, method="rk4", substeps=1, t0=0.0, bound=1e8),
     dict(rhs=CALLABLE, x0=ARR + [[NAN, 0.0], np.ones((2, 2, 2))], h=POS, n_steps=INT + [0], method=CHOICE,
          substeps=INT + [0], t0=REAL, bound=["abc", None, NAN, -INF, 0.0, [1.0]], controller=[3.0, "f"],
          observe=[3.0, "f"], seeds=[[1, 2, 3], 5])),
    ("simulate_discrete", simulate.simulate_discrete, dict(step=_step, x0=[1.0], n_steps=5, bound=1e8),
     dict(step=CALLABLE, x0=ARR + [[NAN]], n_steps=INT + [0], bound=["abc", None, NAN, -INF, 0.0],
          observe=[3.0, "f"], seeds=[[1, 2], 5])),
    ("simulate_ivp", simulate.simulate_ivp, dict(rhs=_rhs, x0=[1.0], t_eval=[0.0, 0.5, 1.0], rtol=1e-6, atol=1e-9),
     dict(rhs=CALLABLE, x0=ARR + [[NAN]], t_eval=ARR + [[1.0, 0.0], [0.0], [NAN, 1.0]], rtol=POS, atol=POS,
          bound=["abc", None, NAN, -INF, 0.0], method=CHOICE, u=[3.0, "f"])),
    ("continuous_nlsys", simulate.continuous_nlsys, dict(rhs=_rhs, states=2, inputs=1),
     dict(rhs=CALLABLE, output=[3.0, "f"])),
    # report
    ("compute_verdict", report.compute_verdict, dict(value=1.0, paper=1.0, tolerance=0.1),
     dict(tolerance=["abc", [0.1], NAN, -0.1])),
    ("Quantity", _quantity, dict(id="q", label="q", value=1.0, paper=1.0, tolerance=0.1, runs=3, unit="rad"),
     dict(tolerance=["abc", [0.1], NAN, -0.1], runs=opt(INT) + [-1], unit=[None, 3], cell=["", 3],
          runs_diverged=opt(INT) + [-1, 4], id=[None, 3, ""], label=[None, 3])),
    ("StudyResult.quantity", _result_quantity, dict(id="q", label="q", value=1.0, paper=1.0),
     dict(tolerance=["abc", NAN, -0.1], runs=opt(INT), unit=[None, 3], id=[None, 3, ""])),
    ("StudyContext", _context, dict(runs=3, seed=0), dict(runs=opt(INT) + [0], seed=INT + [-1])),
    ("StudyContext.runs_or", _runs_or, dict(default=100, quick_default=5),
     dict(default=INT + [0], quick_default=opt(INT) + [0])),
    ("validate_results", report.validate_results, dict(data={"study": "s"}), dict(data=[None, [], "x"])),
    ("count_verdicts", report.count_verdicts, dict(results={"quantities": []}), dict(results=[None, [], {"q": 1}])),
    ("write_results_json", report.write_results_json,
     dict(result=report.StudyResult(report.StudyInfo("s", "f", "p", "r")), out_dir=None), dict(result=[None, {}])),
    ("new_figure", _new_figure, dict(nrows=1, ncols=2, size=(4.0, 3.0)),
     dict(nrows=INT + [0], ncols=INT + [0], size=ARR + [(4.0,), (0.0, 3.0), (NAN, 3.0)])),
]


def _names_argument(message: str, arg: str) -> bool:
    return re.search(rf"(?<![A-Za-z0-9_]){re.escape(arg)}(?![A-Za-z0-9_])", message) is not None


def _expected_failure_for_valid(label, fn, valid):
    """Starting points not run as such: validate_results' is incomplete data, write_results_json's has
    no directory (each bad call fails on its ``result`` before writing anything)."""
    return label in ("validate_results", "write_results_json")


def test_every_public_callable_rejects_bad_arguments_by_name(record_property):
    tried, problems = 0, []
    for label, fn, valid, bad in CASES:
        if not _expected_failure_for_valid(label, fn, valid):
            fn(**valid)  # the starting point is a valid call
        for arg, values in bad.items():
            for value in values:
                tried += 1
                kwargs = dict(valid, **{arg: value})
                try:
                    fn(**kwargs)
                except (ValueError, TypeError) as exc:
                    if not _names_argument(str(exc), arg):
                        problems.append(f"{label}({arg}={value!r}): {type(exc).__name__} does not name "
                                        f"{arg!r}: {exc}")
                except Exception as exc:  # noqa: BLE001 - anything else is a finding
                    problems.append(f"{label}({arg}={value!r}): {type(exc).__name__}: {exc}")
                else:
                    problems.append(f"{label}({arg}={value!r}): accepted silently")
    record_property("fuzz_inputs", tried)
    print(f"\nfuzz: {tried} bad inputs over {len(CASES)} public callables, {len(problems)} problems")
    assert tried >= 800
    assert not problems, f"{len(problems)} of {tried} inputs:\n" + "\n".join(problems)
