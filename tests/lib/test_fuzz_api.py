"""Fuzz table: every public constructor and function of ``ctrl_analysis``, one argument made bad at a time.

Each case starts from a valid call and replaces one argument with a bad value (a string, a list or
``None`` where a number belongs, NaN, inf, a value outside the documented range, a wrong shape, a
non-callable). The call must raise ``ValueError`` or ``TypeError`` whose message names the argument;
never succeed silently and never raise from inside numpy, scipy or sympy with another type. The
number of inputs tried is printed and recorded (``record_property("fuzz_inputs", n)``).

Coverage is checked too: every class and function in a module's ``__all__`` is either the callable
of a case or listed in :data:`NOT_FUZZED` with the reason. Not fuzzed, on purpose: the per-step
methods that the design keeps unchecked (``rhs``, ``update``, ``output``, ``euler_step``,
``rk4_step``, ``riccati_rhs``, the compiled kernels), the shared validators themselves (tested in
test_validate.py), the CLI (test_cli*.py), result records the library builds, and functions
without arguments or without numeric arguments (the sympy derivations ``derive_*``).
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import math
import pkgutil
import re

import control as ct
import numpy as np

import ctrl_analysis
from ctrl_analysis import (
    _validate,
    cli,
    metrics,
    noise,
    plants,
    polynomials,
    streaming,
)
from ctrl_analysis import identification as ident
from ctrl_analysis.arena import claims, signals
from ctrl_analysis.arena import cli as arena_cli
from ctrl_analysis.arena import figures as arena_figures
from ctrl_analysis.arena import interface as arena_interface
from ctrl_analysis.arena import offline as arena_offline
from ctrl_analysis.arena import recommend as arena_recommend
from ctrl_analysis.arena import record as arena_record
from ctrl_analysis.arena import report_section as arena_report_section
from ctrl_analysis.arena import startup as arena_startup
from ctrl_analysis.controllers import differential_feedback as hodf
from ctrl_analysis.controllers import fuzzy, golden_section, mfac, pd, pid
from ctrl_analysis.engine import (
    Execution,
    blocks,
    engines,
    function_block,
    integrators,
    ivp,
    memory,
    numpy_engine,
    plan,
    policies,
    processes,
    simresult,
)
from ctrl_analysis.engine import batch as engine_batch
from ctrl_analysis.engine import codegen as _kernels
from ctrl_analysis.engine import jit as engine_jit
from ctrl_analysis.engine import kernels as engine_kernels
from ctrl_analysis.engine import layout as engine_layout
from ctrl_analysis.engine import loop as loop_mod
from ctrl_analysis.engine import matrix as engine_matrix
from ctrl_analysis.engine import params as engine_params
from ctrl_analysis.engine import processes as engine_processes
from ctrl_analysis.engine import stepcheck as _stepcheck
from ctrl_analysis.estimators import differential as de
from ctrl_analysis.estimators import eso, levant, lowpass, tracking
from ctrl_analysis.estimators.kalman import (
    _checks,
    alpha_beta,
    ckf,
    continuous,
    discrete,
    ikf,
    scalar,
    singer,
)
from ctrl_analysis.estimators.kalman import filter as kfilter
from ctrl_analysis.reporting import box_cells, report, run_folder, study
from ctrl_analysis.reporting import markdown as report_md
from ctrl_analysis.reporting import sensitivity as sensitivity_module
from ctrl_analysis.reporting.box import Box, Dimension, first_order
from ctrl_analysis.reporting.study import algorithm as study_algorithm
from ctrl_analysis.reporting.verdicts import claim_verdict, printed_tolerance
from ctrl_analysis.runs import chains, cluster, parallel, progress, taskpool
from ctrl_analysis.streaming import _accumulator, _sketch
from ctrl_analysis.symbolic import differential as sym_de
from ctrl_analysis.symbolic import eso as sym_eso
from ctrl_analysis.symbolic import riccati as sym_ric

NAN, INF = math.nan, math.inf
HUGE = 10**12  # a size that would hang (minutes or forever) instead of being refused
HUGE_N = 10**4  # a sympy order that would run for minutes

# -- bad values by kind ------------------------------------------------------------------------
TYPE_BAD = ["abc", None, 1 + 2j]  # not a number at all
REAL = TYPE_BAD + [[1.0, 2.0], NAN, INF, -INF]  # one finite real number
POS = REAL + [0.0, -1.0]
NONNEG = REAL + [-1.0]
INT = ["3", None, 2.5, NAN, [2], True]
ARR = ["abc", None, [[1.0, "x"]]]  # an array (its bad shapes / NaN given per case)
CALLABLE = [3.0, "f", None]
BOOL = ["yes", None, 2]
STR = [None, 3, 1.5]
# vectorised arguments: an array is fine, a string, None, NaN or inf is not
VREAL = TYPE_BAD + [NAN, INF, -INF]
VPOS = VREAL + [0.0, -1.0]
VNONNEG = VREAL + [-1.0]
CHOICE = ["nonsense", 3]


def opt(values):
    """The bad values of an optional argument (``None`` means "not given" there, so it is valid)."""
    return [v for v in values if v is not None]


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
TF2 = ct.tf([[[1.0]], [[1.0]]], [[[1.0, 1.0]], [[1.0, 2.0]]])  # two outputs: not SISO
LPF = lowpass.LowPassFilter(10.0, 2)
PLANT = plants.DiscreteLTI(TF1, 0.1)
NOT_A_BLOCK = [3.0, "block", None, TF1]
RULES = fuzzy.sum_rule_table(7)
FUZZY = fuzzy.FuzzyController(RULES, Ke=1.0, Kec=1.0, Ku=1.0, n_grid=41)
PPD = dict(eta=0.5, mu=1.0, epsilon=1e-5, phi0=2.0, phi_reset=0.5, y0=0.0, u0=0.0)


def _rhs(t, x, u, params):
    return -x


def _pair(x):
    """map_chunks' fn of the table: takes any value (map_chunks passes args on unchanged, so an error is its own,
    not its fn's)."""
    return (x, x)


def _new_result():
    return report.StudyResult(report.StudyInfo("s", "f", "p", "r"))


def _result_quantity(**kw):
    return _new_result().quantity(**kw)


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


def _de_matrices(reading):
    return de.DifferentialEstimator(3, 2.0).estimate_matrices(reading)


def _de_nlsys(reading):
    return de.DifferentialEstimator(3, 2.0).nlsys(reading=reading)


def _eso_tf(wrt):
    return eso.ExtendedStateObserver.from_bandwidth(2, 10.0).disturbance_error_tf(wrt)


def _lpf_derivative(k):
    return LPF.derivative_tf(k)


def _lpf_discretize(h):
    return LPF.discretize(h)


def _lpf_digital(h, channels, initial):
    return LPF.digital(h, channels=channels, initial=initial)


def _dlpf_filter(u):
    return lowpass.DiscreteLowPass(LPF, 0.01).filter(u)


def _block_run(u, x0):
    return PLANT.run(u, x0=x0)


def _block_nlsys(dt, name):
    return PLANT.nlsys(dt, name)


def _cont_nlsys(name):
    return LPF.nlsys(name)


def _loop(**kw):
    return loop_mod.Loop([loop_mod.place(PLANT, "plant")], **kw)


def _loop_simulate(**kw):
    return _loop(dt=0.1).simulate(**kw)


def _layout(fields):
    return engine_kernels.Layout(*fields)


def _layout_pack(**kw):
    return engine_kernels.Layout("a", ("b", 2)).pack(**kw)


def _layout_sized(**kw):
    return engine_kernels.Layout("n", ("a", "n"), ("F", ("n", "n"))).sized(**kw)


def _layout_pack_sized(**kw):
    return engine_kernels.Layout("n", ("a", "n")).pack(**kw)


def _loop_interconnect(name):
    return _loop(dt=0.1).interconnect(name)


def _response_timeresponse(run):
    # the numpy engine: what is fuzzed is to_timeresponse's argument, not worth a compiled loop structure
    return _loop(dt=0.1).simulate(3, inputs={"u": 1.0}, runs=2,
                                  execution=Execution(engine="numpy")).to_timeresponse(run)


def _fuzzy_surface(n_e, n_ec):
    return FUZZY.control_surface(n_e, n_ec)


def _runs_or(default, quick_default):
    return report.StudyContext(out_dir=".", quick=True).runs_or(default, quick_default)


def _save_figure(out_dir, fig, filename, dpi):
    return report.StudyContext(out_dir=out_dir).save_figure(_new_result(), fig, filename, dpi)


def _new_figure(**kw):
    import matplotlib.pyplot as plt

    fig, _ = report.new_figure(**kw)
    plt.close(fig)


def _reconstruction(name, why):
    return _new_result().reconstruction(name, 1.0, why)


def _finding(id, text):
    return _new_result().finding(id, text)


def _merge(part):
    return _new_result().merge(part)


def _draw_noise(seeds, n_steps):
    return noise.draw_noise(seeds, n_steps, noise.gaussian_noise(1.0))


def _staged(target):
    with report.staged_directory(target):
        pass



def build_cases(tmp):
    """(label, callable, valid keyword arguments, {argument: bad values}); files go under ``tmp``."""
    fig = _new_figure_object()
    results = _new_result().to_dict()
    return [
        # symbolic
        ("breakaway_point", sym_de.breakaway_point, dict(n0=5, a=2.0), dict(n0=INT + [1, 400], a=POS)),
        ("breakaway_gain", sym_de.breakaway_gain, dict(n0=5, a=2.0), dict(n0=INT + [1, 400], a=POS)),
        ("locus_gain", sym_de.locus_gain, dict(s_value=-3.0, n0=5, a=2.0),
         dict(s_value=["abc", None, NAN, [INF]], n0=INT, a=POS)),
        ("coefficients_from_zeros", sym_de.coefficients_from_zeros, dict(zeros=[-1.0, -2.0], gain=3.0),
         dict(zeros=[[], None, "abc", [NAN], [-1.0] * HUGE_N], gain=["abc", None, NAN])),
        ("differential_coefficients", sym_de.differential_coefficients, dict(n0=5, a=2.0, K=30.0),
         dict(n0=INT, a=POS, K=POS)),
        ("beta_symbols", sym_eso.beta_symbols, dict(n=2), dict(n=INT + [0, HUGE_N])),
        ("gain_symbols", sym_eso.gain_symbols, dict(n=2), dict(n=INT + [0, HUGE_N])),
        ("characteristic_polynomial", sym_eso.characteristic_polynomial, dict(n=2, high_gain=True),
         dict(n=INT + [0, HUGE_N], high_gain=BOOL)),
        ("characteristic_coefficients", sym_eso.characteristic_coefficients, dict(n=2), dict(n=INT + [0, HUGE_N])),
        ("observer_matrices", sym_eso.observer_matrices, dict(n=2, high_gain=True),
         dict(n=INT + [0, HUGE_N], high_gain=BOOL)),
        ("error_transfer_functions", sym_eso.error_transfer_functions, dict(n=2, high_gain=False),
         dict(n=INT + [0, 7, HUGE_N], high_gain=BOOL)),
        ("error_dc_gains", sym_eso.error_dc_gains, dict(n=2), dict(n=INT + [0, HUGE_N])),
        ("error_scaling_exponents", sym_eso.error_scaling_exponents, dict(n=2), dict(n=INT + [0, HUGE_N])),
        ("bandwidth_polynomial", sym_eso.bandwidth_polynomial, dict(n=2, omega_o=10.0),
         dict(n=INT + [0, HUGE_N], omega_o=opt(POS))),
        ("bandwidth_match", sym_eso.bandwidth_match, dict(beta=[3.0, 3.0, 1.0], epsilon=0.1),
         dict(beta=ARR + [[1.0], [3.0, -3.0, 1.0], [NAN, 3.0, 1.0], [1.0] * HUGE_N], epsilon=opt(POS))),
        ("second_order_gain", sym_ric.second_order_gain, dict(a21=1.0, q=2.0), dict(a21=VREAL, q=VPOS)),
        ("random_walk_gain_closed_form", sym_ric.random_walk_gain_closed_form, dict(q=0.5), dict(q=VNONNEG)),
        ("kalata_gains_closed_form", sym_ric.kalata_gains_closed_form, dict(Lambda=0.5), dict(Lambda=VNONNEG)),
        # polynomials
        ("repeated_pole_coefficients", polynomials.repeated_pole_coefficients, dict(m=3, omega=2.0),
         dict(m=INT + [-1], omega=REAL)),
        # blocks and loops
        ("FunctionBlock", function_block.FunctionBlock, dict(fn=lambda t, u: u, inputs=("a",), outputs=("b",)),
         dict(fn=CALLABLE, inputs=[None, 3, ["a", 3]], outputs=[None, 3, [1.5]])),
        ("StaticGain", blocks.StaticGain, dict(D=[[1.0, -1.0]], inputs=("r", "y"), outputs=("e",)),
         dict(D=ARR + [[1.0, 2.0], [[1.0]], np.ones((2, 2, 2)), [[NAN, 1.0]]], inputs=[None, 3, ["a", 3]],
              outputs=[None, 3, [1.5]])),
        ("SampledBlock", blocks.SampledBlock, dict(block=LPF, dt=0.01, method="rk4", substeps=1),
         dict(block=NOT_A_BLOCK + [PLANT], dt=POS, method=CHOICE, substeps=INT + [0, HUGE])),
        ("signal_names", blocks.signal_names, dict(base="x", n=3), dict(base=[None, 3, ""], n=INT + [-1, HUGE])),
        ("DiscreteBlock.run", _block_run, dict(u=np.ones(5), x0=None),
         dict(u=ARR + [np.ones((5, 2)), np.ones((2, 5, 2, 2))], x0=opt(ARR) + [[1.0, 2.0], np.ones((2, 2, 2))])),
        ("DiscreteBlock.nlsys", _block_nlsys, dict(dt=0.1, name="p"), dict(dt=["abc", NAN, -1.0, 0.0], name=[3])),
        ("ContinuousBlock.nlsys", _cont_nlsys, dict(name="f"), dict(name=[3])),
        ("place", loop_mod.place, dict(block=PLANT, name="plant", inputs=["u"], outputs=["y"]),
         dict(block=NOT_A_BLOCK, name=[None, 3, ""], inputs=[3, ["a", "b"], [3]], outputs=[3, ["a", "b"], [None]])),
        ("Loop", _loop, dict(dt=0.1, method="rk4", substeps=1, outputs=None),
         dict(dt=POS, method=CHOICE, substeps=INT + [0, HUGE], outputs=[3, ["nonsense"], "y"])),
        ("Loop(blocks)", loop_mod.Loop, dict(blocks=[loop_mod.place(PLANT, "plant")], dt=0.1),
         dict(blocks=[None, 3, [], [3.0], [loop_mod.place(PLANT, "p"), loop_mod.place(PLANT, "p")]])),
        ("Loop.simulate", _loop_simulate,
         dict(n_steps=3, inputs={"u": 1.0}, x0=None, runs=2, t0=0.0, seeds=None, save=None,
              execution=Execution(engine="numpy")),
         dict(n_steps=INT + [0], inputs=[3, {"nonsense": 1.0}, {"u": "abc"}, {"u": np.ones(7)}, {"u": NAN}],
              x0=[3, {"nonsense": [0.0]}, {"plant": [NAN]}, {"plant": [1.0, 2.0, 3.0]}],
              runs=opt(INT) + [0], t0=REAL, seeds=[[1, 2, 3], 5], save=[3, "abc", {"keep": ["y"]}],
              execution=[3, "numpy", {"engine": "numpy"}],
              params=[3, "abc", {"nonsense": {}}, {"plant": 3}, {"plant": {"nonsense": 1.0}},
                      {"plant": {"dt": [0.1, 0.2, 0.3]}}, {"plant": {"dt": -1.0}}, {"plant": {"dt": NAN}}])),
        ("Save", policies.Save, dict(keep=None, every=1, states=True),
         dict(keep=[3, [3], "y y"], every=INT + [0, -1], states=BOOL)),
        ("Execution", policies.Execution,
         dict(engine="auto", jobs=1, chunk_runs=None, max_bytes=None, progress=None, bound=1e8),
         dict(engine=CHOICE, jobs=INT + [0], chunk_runs=opt(INT) + [0], max_bytes=opt(POS), progress=[3.0, "f"],
              bound=["abc", None, NAN, -INF, 0.0, [1.0]])),
        ("Layout", _layout, dict(fields=("a", ("b", 2))),
         dict(fields=[(3,), ("a", "a"), ("1x",), (("a", -1),), (("a", "x"),), (("a", "n"), "n"),
                      ("n", "m", ("a", ("n", "m"))), ("n", ("a", ("n", "n", "n"))), (("n", 2), ("a", "n"))])),
        ("Layout.sized", _layout_sized, dict(n=2), dict(n=[-1, 1.5, "abc", None, NAN, True])),
        ("Layout.pack (sized)", _layout_pack_sized, dict(n=2, a=[1.0, 2.0]),
         dict(n=[-1, 1.5, "abc", NAN], a=[[1.0], [1.0, 2.0, 3.0], None])),
        ("Layout.pack", _layout_pack, dict(a=1.0, b=[1.0, 2.0]),
         dict(a=["abc", None, [1.0, 2.0]], b=[3.0, "abc", [1.0, 2.0, 3.0]])),
        ("Loop.interconnect", _loop_interconnect, dict(name="sys"), dict(name=[3])),
        ("LoopResponse.to_timeresponse", _response_timeresponse, dict(run=1), dict(run=INT + [-1, 2])),
        # estimators
        ("DifferentialEstimator", de.DifferentialEstimator, dict(n0=5, a=2.0, K=100.0, reading="state"),
         dict(n0=INT + [1, 400], a=POS, K=opt(POS) + [0.01], reading=CHOICE, allow_unstable=BOOL)),
        ("DifferentialEstimator.estimates", _de_estimates, dict(z=np.zeros(3), y=0.0, reading="state"),
         dict(z=ARR + [np.zeros(4)], y=["abc", None, np.zeros(5)], reading=CHOICE)),
        ("DifferentialEstimator.estimate_matrices", _de_matrices, dict(reading="state"), dict(reading=CHOICE)),
        ("DifferentialEstimator.nlsys", _de_nlsys, dict(reading="state"), dict(reading=CHOICE)),
        ("fal", eso.fal, dict(e=0.5, alpha=0.5, delta=0.1), dict(e=["abc", None], alpha=TYPE_BAD + [NAN], delta=POS)),
        ("ExtendedStateObserver", eso.ExtendedStateObserver,
         dict(gains=[30.0, 300.0, 1000.0], b0=1.0, alpha=[1.0, 0.5, 0.25], delta=0.1, known=None),
         dict(gains=ARR + [[1.0], [1.0, -2.0], [1.0, 1.0, 10.0], _nan_like([30.0, 300.0, 1000.0])],
              b0=REAL, alpha=opt(ARR) + [[0.5], _nan_like([1.0, 0.5, 0.25])], delta=opt(POS), known=[3.0, "f"],
              allow_unstable=BOOL)),
        ("ExtendedStateObserver.from_epsilon", eso.ExtendedStateObserver.from_epsilon,
         dict(n=2, epsilon=0.05, beta=[3.0, 3.0, 1.0]),
         dict(n=INT + [0], epsilon=POS, beta=ARR + [[1.0, 2.0], [3, 3, -1]])),
        ("ExtendedStateObserver.from_bandwidth", eso.ExtendedStateObserver.from_bandwidth, dict(n=2, omega_o=10.0),
         dict(n=INT + [0], omega_o=POS)),
        ("ExtendedStateObserver.disturbance_error_tf", _eso_tf, dict(wrt="derivative"), dict(wrt=CHOICE)),
        ("LowPassFilter", lowpass.LowPassFilter, dict(omega=10.0, order=2), dict(omega=POS, order=INT + [0])),
        ("LowPassFilter.derivative_tf", _lpf_derivative, dict(k=1), dict(k=INT + [-1, 3])),
        ("LowPassFilter.discretize", _lpf_discretize, dict(h=0.01), dict(h=POS)),
        ("LowPassFilter.digital", _lpf_digital, dict(h=0.01, channels=1, initial=0.0),
         dict(h=POS, channels=INT + [0], initial=["abc", NAN, [1.0, 2.0, 3.0]])),
        ("DiscreteLowPass", lowpass.DiscreteLowPass, dict(lowpass=LPF, h=0.01, channels=2, initial=None),
         dict(lowpass=NOT_A_BLOCK + [PLANT], h=POS, channels=INT + [0], initial=["abc", NAN, [1.0, 2.0, 3.0]])),
        ("DiscreteLowPass.filter", _dlpf_filter, dict(u=np.ones(5)), dict(u=ARR + [np.ones((5, 2, 2))])),
        ("fhan", tracking.fhan, dict(x1=0.1, x2=0.0, r=10.0, h0=0.01),
         dict(x1=["abc", None], x2=["abc", None], r=POS, h0=POS)),
        ("TrackingDifferentiator", tracking.TrackingDifferentiator,
         dict(r=10.0, h=0.01, h0=None, substeps=1, x0=None, feedthrough=False),
         dict(r=POS, h=POS, h0=opt(POS), substeps=INT + [0, HUGE], x0=opt(ARR) + [[1.0], [NAN, 0.0]],
              feedthrough=BOOL)),
        ("LevantDifferentiator", levant.LevantDifferentiator,
         dict(order=1, L=2.0, h=0.01, substeps=1, gains=None, x0=None),
         dict(order=INT + [0, 9], L=POS, h=POS, substeps=INT + [0, HUGE], gains=opt(ARR) + [[1.0], [1.1, -1.5]],
              x0=opt(ARR) + [[1.0], [NAN, 0.0]])),
        ("softened_setpoint", tracking.softened_setpoint, dict(softener=LPF, r=np.ones(20), h=0.01, method="zoh"),
         dict(softener=NOT_A_BLOCK + [PLANT], r=ARR + [np.ones((2, 2)), [], _nan_like(np.ones(20))], h=POS,
              method=CHOICE)),
        # Kalman family
        ("controllability_matrix", _checks.controllability_matrix, dict(A=A2, B=G2),
         dict(A=_matrix(A2), B=_matrix(G2))),
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
        ("alpha_beta_gamma_gains", alpha_beta.alpha_beta_gamma_gains, dict(Lambda=0.5),
         dict(Lambda=VPOS + [[1.0, -2.0]])),
        ("singer_transition", singer.singer_transition, dict(decay=0.1), dict(decay=VNONNEG + [[0.1, -2.0]])),
        ("singer_gains", singer.singer_gains, dict(Lambda=0.5, decay=0.1),
         dict(Lambda=VPOS + [[1.0, -2.0]], decay=VNONNEG + [[0.1, -0.2]])),
        ("alpha_beta_stable", alpha_beta.alpha_beta_stable, dict(alpha=0.5, beta=0.2), dict(alpha=REAL, beta=REAL)),
        ("AlphaBetaFilter", alpha_beta.AlphaBetaFilter,
         dict(alpha=0.5, beta=0.2, T=0.1, F=None, b=None, x0=None, require_stable=True),
         dict(alpha=REAL + [3.0], beta=REAL, T=POS, F=opt(_matrix(F2)), b=opt(ARR) + [[1.0, 2.0, 3.0]],
              x0=opt(ARR) + [[1.0, 2.0, 3.0]], require_stable=BOOL)),
        ("DiscreteKalmanFilter", kfilter.DiscreteKalmanFilter,
         dict(F=F2, h=[1.0, 0.0], Qd=0.01 * np.eye(2), R=0.1, b=None, x0=None, P0=None),
         dict(F=_matrix(F2) + [[[1.0, 0.1]]], h=ARR + [[1.0], [NAN, 0.0]], Qd=_matrix(np.eye(2)) + [-np.eye(2)],
              R=POS, b=opt(ARR) + [[1.0, 2.0, 3.0], [NAN, 0.0]], x0=opt(ARR) + [[1.0], [NAN, 0.0]],
              P0=opt(_matrix(np.eye(2))) + [-np.eye(2)])),
        ("ImprovedKalmanFilter", ikf.ImprovedKalmanFilter, dict(Q=1e-3, R=0.1, y0=0.0, P0=1.0),
         dict(Q=VNONNEG + [np.ones((2, 2))], R=VPOS + [np.ones((2, 2))], y0=REAL, P0=NONNEG)),
        ("CharacteristicKalmanFilter", ckf.CharacteristicKalmanFilter, dict(Q=1e-4, R=1.0, P0=1.0, x0=None),
         dict(Q=ARR + [NAN, -1.0, np.ones((7, 7))], R=POS, P0=ARR + [NAN, 0.0, -np.eye(3)],
              x0=opt(ARR) + [[1.0], [NAN, 0.0, 0.0]])),
        ("LinearKalmanFilter", ckf.LinearKalmanFilter,
         dict(F=F2, G=[0.0, 1.0], H=[1.0, 0.0], Q=0.01, R=0.1, P0=1.0, x0=None),
         dict(F=_matrix(F2) + [[[1.0, 0.1]]], G=ARR + [[1.0], [NAN, 1.0]], H=ARR + [[1.0], [NAN, 0.0]],
              Q=ARR + [NAN, -1.0, np.ones((7, 7))], R=POS, P0=ARR + [NAN, 0.0, -np.eye(2)],
              x0=opt(ARR) + [[1.0], [NAN, 0.0]])),
        # controllers
        ("hurwitz_roots", hodf.hurwitz_roots, dict(K=[6.0, 11.0, 6.0]), dict(K=ARR + [[NAN, 1.0], []])),
        ("gains_from_poles", hodf.gains_from_poles, dict(poles=[-1.0, -2.0]),
         dict(poles=ARR + [[NAN], [1j], [], [1.0, -2.0], [0.0], [0.5 + 1j, 0.5 - 1j]])),
        ("HighOrderDifferentialFeedback", hodf.HighOrderDifferentialFeedback, dict(K=[6.0, 11.0, 6.0]),
         dict(K=ARR + [[1.0, -1.0, 1.0], [NAN, 1.0, 1.0], np.ones((2, 2)), []])),
        ("HighOrderDifferentialFeedback.u", _hodf_u, dict(theta=[1.0, 0.0, 0.0], x_hat=[0.0, 0.0, 0.0]),
         dict(theta=ARR + [[1.0], 1.0], x_hat=ARR + [[1.0], 1.0])),
        ("bandwidth_gains", pd.bandwidth_gains, dict(n=2, omega_c=10.0), dict(n=INT + [0], omega_c=POS)),
        ("PDFeedforward", pd.PDFeedforward, dict(b0=2.0, omega_c=10.0, order=2, model=False),
         dict(b0=REAL + [0.0], omega_c=POS, order=INT + [0], model=BOOL)),
        ("PDFeedforward(gains)", pd.PDFeedforward, dict(b0=2.0, gains=[100.0, 20.0], order=2),
         dict(gains=ARR + [[1.0], [1.0, -1.0], [100.0, 20.0, 3.0], [NAN, 1.0]], order=INT + [0, 5])),
        ("PDFeedforward.control", _pd_control, dict(ref=[1.0, 0.0, 0.0], x_hat=[0.0, 0.0, 0.0], f_hat=0.0),
         dict(ref=ARR + [[1.0, 0.0]], x_hat=ARR + [[1.0]], f_hat=["abc", None])),
        ("GoldenSectionController", golden_section.GoldenSectionController,
         dict(k_I=0.1, c2=0.9, c1=1.0, mu=0.1, l1=0.382, l2=0.618),
         dict(k_I=NONNEG, c2=REAL, c1=REAL, mu=NONNEG, l1=REAL, l2=REAL)),
        ("CFDLLaw", mfac.CFDLLaw, dict(rho=0.5, lam=2.0), dict(rho=VPOS + [1.5], lam=VNONNEG)),
        ("CFDLPredictor", mfac.CFDLPredictor, dict(phi0=2.0, u0=1.0, u00=0.25), dict(phi0=REAL, u0=REAL, u00=REAL)),
        ("DecreasingGainLaw", mfac.DecreasingGainLaw, dict(rho=1.0, lam=1.0, e_m=0.5, rearm=True),
         dict(rho=VPOS + [1.5], lam=VNONNEG, e_m=POS, rearm=BOOL)),
        ("PPDEstimator", mfac.PPDEstimator, PPD,
         dict(eta=POS + [2.5], mu=POS, epsilon=POS, phi0=REAL, phi_reset=opt(REAL), y0=REAL, u0=REAL)),
        ("UnitDelay", mfac.UnitDelay, dict(u0=0.0), dict(u0=REAL)),
        ("mfac_controller", mfac.mfac_controller,
         dict(estimator=mfac.PPDEstimator(**PPD), law=mfac.CFDLLaw(0.5, 2.0), output_filter=None, u0=0.0,
              measured="y_m", reference="y_ref_next", control="u"),
         dict(estimator=NOT_A_BLOCK + [PLANT], law=NOT_A_BLOCK, output_filter=[3.0, "f"], u0=REAL,
              measured=STR + [""], reference=STR + [""], control=STR + [""])),
        ("ikf_mfac", mfac.ikf_mfac,
         dict(estimator=mfac.PPDEstimator(**PPD), law=mfac.CFDLLaw(0.5, 2.0), ikf=ikf.ImprovedKalmanFilter(1e-3, 0.1)),
         dict(estimator=NOT_A_BLOCK, law=NOT_A_BLOCK, ikf=NOT_A_BLOCK + [PLANT])),
        ("sum_rule_table", fuzzy.sum_rule_table, dict(n_terms=7, sign=1),
         dict(n_terms=INT + [6, 0], sign=INT + [0, 2])),
        ("FuzzyController", fuzzy.FuzzyController,
         dict(rules=RULES, Ke=1.0, Kec=1.0, Ku=1.0, input_range=6.0, output_range=7.0, n_output_terms=None, n_grid=41),
         dict(rules=ARR + [np.ones((7, 6)) * 0.5, RULES + 0.5, -RULES, np.ones((2, 2, 2))], Ke=POS, Kec=POS, Ku=POS,
              input_range=[v for v in POS if v != [1.0, 2.0]] + [[1.0, 2.0, 3.0], [1.0, -1.0]], output_range=POS,
              n_output_terms=opt(INT) + [0, 5], n_grid=INT + [0])),
        ("FuzzyController.with_params", FUZZY.with_params, dict(Ke=1.0, Kec=1.0, Ku=1.0),
         dict(Ke=POS, Kec=POS, Ku=POS)),
        ("FuzzyController.evaluate", FUZZY.evaluate, dict(e=[0.5, -0.2], ec=[0.1, 0.0]),
         dict(e=["abc", None, [NAN, 0.0], [INF, 0.0], 0.5], ec=["abc", None, [0.0, NAN], [-INF, 0.0]])),
        ("FuzzyController.control_surface", _fuzzy_surface, dict(n_e=5, n_ec=5), dict(n_e=INT + [0], n_ec=INT + [0])),
        ("FuzzyLookupController", fuzzy.FuzzyLookupController, dict(controller=FUZZY, n_points=21),
         dict(controller=NOT_A_BLOCK, n_points=["3", None, 2.5, NAN, True, 0, 1, [2, 3, 4]])),
        ("DiscretePID", pid.DiscretePID, dict(kp=1.0, ki=0.5, kd=0.1, T=0.1, Tf=0.01, u_min=-1.0, u_max=1.0),
         dict(kp=REAL + [-1.0], ki=REAL + [-1.0], kd=REAL + [-1.0], T=POS, Tf=REAL + [-0.1], u_min=["abc", None, 2.0],
              u_max=["abc", None, -2.0])),
        # plants
        ("DiscreteLTI", plants.DiscreteLTI, dict(sys=TF1, dt=0.1, x0=None),
         dict(sys=[3.0, "tf", None, TF2, ct.tf([1.0], [1.0, 1.0], 0.5)], dt=POS,
              x0=opt(ARR) + [[1.0, 2.0], [NAN]])),
        # identification
        ("identifiability", ident.identifiability, dict(H=H_REG, cond_threshold=100.0),
         dict(H=ARR + [np.ones(3), _nan_like(H_REG), np.ones((0, 2))], cond_threshold=POS)),
        ("batch_least_squares", ident.batch_least_squares, dict(H=H_REG, z=Z_REG, strict=False, cond_threshold=100.0),
         dict(H=ARR + [np.ones(3), _nan_like(H_REG)], z=ARR + [np.ones(4), _nan_like(Z_REG)], cond_threshold=POS,
              strict=BOOL, warn=BOOL)),
        ("RecursiveLeastSquaresBlock", ident.RecursiveLeastSquaresBlock,
         dict(n_params=2, forgetting=0.99, P0=100.0, theta0=None, lower=None, upper=None,
              max_trace=None, feedthrough=True),
         dict(n_params=INT + [0], forgetting=REAL + [0.0, 1.5], P0=REAL + [0.0, -np.eye(2), np.ones((3, 3))],
              theta0=opt(ARR) + [[1.0], [NAN, 1.0]], lower=["abc", [1.0, 2.0, 3.0], [NAN, 0.0]],
              upper=["abc", [1.0, 2.0, 3.0], [NAN, 0.0]], max_trace=opt(POS), feedthrough=BOOL)),
        ("RecursiveLeastSquaresBlock(bounds)", ident.RecursiveLeastSquaresBlock,
         dict(n_params=2, lower=[-1.0, -1.0], upper=[1.0, 1.0]), dict(upper=[[-2.0, -2.0]], theta0=[[5.0, 5.0]])),
        ("RecursiveLeastSquares", ident.RecursiveLeastSquares,
         dict(n_params=2, forgetting=0.99, P0=100.0, theta0=None, batch=None, lower=None, upper=None, max_trace=None),
         dict(n_params=INT + [0], forgetting=REAL + [0.0, 1.5], P0=REAL + [0.0, -np.eye(2), np.ones((3, 3))],
              theta0=opt(ARR) + [[1.0], [NAN, 1.0]], batch=opt(INT) + [0], lower=["abc", [1.0, 2.0, 3.0], [NAN, 0.0]],
              upper=["abc", [1.0, 2.0, 3.0], [NAN, 0.0]], max_trace=opt(POS))),
        ("RecursiveLeastSquares.step", _rls_step, dict(h=[1.0, 2.0], z=1.0),
         dict(h=ARR + [[1.0], [NAN, 1.0], [INF, 1.0]], z=["abc", None, NAN, INF, [1.0, 2.0]])),
        ("RecursiveLeastSquares.run", _rls_run, dict(H=H_REG, z=Z_REG),
         dict(H=ARR + [_nan_like(H_REG), np.ones((4, 2))], z=ARR + [_nan_like(Z_REG)])),
        ("ArxRegressor", ident.ArxRegressor, dict(na=2, nb=1, lag=0),
         dict(na=INT + [-1], nb=INT + [-1], lag=INT + [-1])),
        # metrics
        ("mean_abs_error", metrics.mean_abs_error, dict(x=np.ones(5), x_hat=np.zeros(5), axis=0),
         dict(x=["abc", None, np.ones((5, 1)), np.ones(4)], x_hat=["abc", None, np.ones((5, 1))], axis=opt(INT) + [3])),
        ("rmse", metrics.rmse, dict(reference=np.ones(5), y=np.zeros(5), axis=0),
         dict(reference=["abc", None, np.ones((5, 1))], y=["abc", None, np.ones(4)], axis=opt(INT) + [3])),
        ("snr_db", metrics.snr_db, dict(reference=np.ones(5), y=np.zeros(5), axis=0),
         dict(reference=["abc", None, np.ones((5, 1))], y=["abc", None, np.ones(4)], axis=opt(INT) + [3])),
        ("overshoot", metrics.overshoot, dict(t=np.arange(5.0), y=np.ones(5), final=1.0, initial=0.0),
         dict(y=["abc", None], final=REAL + [0.0], initial=REAL + [1.0], axis=opt(INT) + [3])),
        ("settling_time", metrics.settling_time,
         dict(t=np.arange(5.0), y=np.ones(5), final=1.0, initial=0.0, band=0.02),
         dict(t=ARR + [[0.0, 0.0, 1.0, 2.0, 3.0], np.arange(4.0)], y=["abc", None, np.ones(3)], final=REAL + [0.0],
              initial=REAL + [1.0], band=POS, axis=INT + [3])),
        ("mean_std", metrics.mean_std, dict(values=np.arange(4.0), ok=np.ones(4, bool), axis=0),
         dict(values=["abc", None], ok=[np.ones(3, bool), np.array([0, 1]), [1, 0, 1, 0]], axis=INT + [2])),
        ("bandwidth_3db", metrics.bandwidth_3db, dict(sys=TF1, dbdrop=-3.0),
         dict(sys=[3.0, "tf", None], dbdrop=REAL + [3.0])),
        ("resonance_peak", metrics.resonance_peak, dict(sys=TF1, omega=None),
         dict(sys=[3.0, "tf", None], omega=opt(ARR) + [[-1.0, 1.0], [NAN, 1.0]])),
        # simulation engine
        ("run_seeds", noise.run_seeds, dict(base_seed=0, runs=3), dict(base_seed=INT + [-1], runs=INT + [0, HUGE])),
        ("uniform_noise", noise.uniform_noise, dict(low=-1.0, high=1.0),
         dict(low=["abc", None, NAN], high=REAL + [-2.0])),
        ("gaussian_noise", noise.gaussian_noise, dict(std=1.0, mean=0.0),
         dict(std=VNONNEG + [[1.0, -1.0]], mean=["abc", None, NAN])),
        ("draw_noise", _draw_noise,
         dict(seeds=[1, 2], n_steps=10), dict(seeds=[[], None, ["a"], [1.5], [-1]], n_steps=INT + [0])),
        ("simulate_ivp", ivp.simulate_ivp, dict(rhs=_rhs, x0=[1.0], t_eval=[0.0, 0.5, 1.0], rtol=1e-6, atol=1e-9),
         dict(rhs=CALLABLE, x0=ARR + [[NAN]], t_eval=ARR + [[1.0, 0.0], [0.0], [NAN, 1.0]], rtol=POS, atol=POS,
              bound=["abc", None, NAN, -INF, 0.0], method=CHOICE, u=[3.0, "f"])),
        ("continuous_nlsys", ivp.continuous_nlsys, dict(rhs=_rhs, states=2, inputs=1),
         dict(rhs=CALLABLE, output=[3.0, "f"])),
        ("chunk_bounds", memory.chunk_bounds, dict(runs=10, size=3), dict(runs=INT + [-1], size=INT + [0])),
        ("check_result_memory", memory.check_result_memory, dict(nbytes=10.0, limit=100.0, where="x"),
         dict(nbytes=NONNEG, limit=POS)),
        # parallel and progress
        ("chunk_slices(large n)", parallel.chunk_slices, dict(n=HUGE, chunks=4), dict(chunk_size=[1, 1000])),
        ("chunk_slices", parallel.chunk_slices, dict(n=10, chunks=3, chunk_size=None),
         dict(n=INT + [-1], chunks=opt(INT) + [0], chunk_size=opt(INT) + [0])),
        ("check_scheduler_address", parallel.check_scheduler_address, dict(scheduler="tcp://127.0.0.1:8786"),
         dict(scheduler=[None, 3, "", "banana", "tcp://127.0.0.1:0", "tcp://127.0.0.1:99999", "tcp://:8786"])),
        ("gather", parallel.gather, dict(parts=[np.ones(2), np.ones(3)]), dict(parts=[None, 3, []])),
        ("grid_points", parallel.grid_points, dict(grid={"a": [1.0, 2.0]}),
         dict(grid=[None, 3, {}, {"a": []}, {3: [1.0]}])),
        ("map_chunks", parallel.map_chunks, dict(fn=_pair, args=[1.0, 2.0], jobs=1, scheduler=None, desc="",
                                                 unit="chunk"),
         dict(fn=CALLABLE, args=[None, 3], jobs=INT + [0], scheduler=[3, "nonsense"], desc=[None, 3],
              unit=[None, 3, ""])),
        ("drive", chains.drive, dict(fn=_pair, chains={}, jobs=1, scheduler=None, desc="", unit="chunk",
                                       priority=None),
         dict(fn=CALLABLE, chains=[None, 3, {"a": 3}], jobs=INT + [0], scheduler=[3, "nonsense"], desc=[None, 3],
              unit=[None, 3, ""], priority=[3, {"zz": 1}])),
        ("lockstep", chains.lockstep, dict(chains={}), dict(chains=[None, 3, {"a": 3}])),
        ("monte_carlo", parallel.monte_carlo, dict(fn=_seed_rows, seeds=[1, 2, 3], jobs=1, chunk_size=None),
         dict(fn=CALLABLE, seeds=[None, 3, []], jobs=INT + [0], chunk_size=opt(INT) + [0])),
        ("sweep", parallel.sweep, dict(fn=_sweep_fn, grid={"a": [1.0, 2.0]}, seeds=[1, 2], jobs=1, chunk_size=None),
         dict(fn=CALLABLE, grid=[None, 3, {}], seeds=[None, 3, []], jobs=INT + [0], chunk_size=opt(INT) + [0])),
        ("bar", progress.bar, dict(total=3, desc="d", unit="it", stream=None),
         dict(total=opt(INT) + [-1], desc=[None, 3], unit=[None, 3], stream=[3, "f"])),
        ("enabled", progress.enabled, dict(stream=None), dict(stream=[3, "f"])),
        ("set_context", progress.set_context, dict(label="", position=None),
         dict(label=[None, 3], position=["a", 1.5, -1])),
        ("write", progress.write, dict(message="m", stream=None), dict(message=[None, 3], stream=[3, "f"])),
        ("updater", progress.updater, dict(progress=False, total=3, desc="d", unit="it"),
         dict(progress=[None, 3, "f"], total=INT + [-1], desc=[None, 3], unit=[None, 3])),
        # study parameters
        ("printed", study.printed, dict(value=1.0, where="Table 1"), dict(where=STR + [""], value=[[1.0, 2.0], {}])),
        ("reconstructed", study.reconstructed, dict(value=1.0, why="because"), dict(why=STR + [""], value=[[1.0], {}])),
        ("record_parameters", study.record_parameters, dict(result=_new_result(), params=_PARAMS, prefix=""),
         dict(result=[None, 3, {}], params=[None, 3, "x"], prefix=[None, 3])),
        ("reconstructions_of", study.reconstructions_of, dict(params=_PARAMS), dict(params=[None, 3, "x"])),
        ("study_params", study.study_params,
         dict(defaults={"p": _PARAMS}, params={"p": {"k": 3.0}}, result=_new_result()),
         dict(defaults=[None, 3, {"p": 3}, {"p": _Params}], params=[3, "x", {"q": {}}, {"p": {"j": 1.0}}, {"p": 3}],
              result=[3, "x", {}])),
        # report
        ("relative_error", report.relative_error, dict(value=1.0, paper=2.0), dict(value=["abc", None], paper=["abc"])),
        ("compute_verdict", report.compute_verdict, dict(value=1.0, paper=1.0, tolerance=0.1),
         dict(tolerance=["abc", [0.1], NAN, -0.1], diverged=BOOL)),
        ("Quantity", report.Quantity, dict(id="q", label="q", value=1.0, paper=1.0, tolerance=0.1, runs=3, unit="rad"),
         dict(tolerance=["abc", [0.1], NAN, -0.1], runs=opt(INT) + [-1], unit=[None, 3], cell=["", 3],
              runs_diverged=opt(INT) + [-1, 4], id=[None, 3, ""], label=[None, 3])),
        ("StudyInfo", report.StudyInfo, dict(name="s", seed_file="f", paper="p", reproduces="r"),
         dict(name=STR + [""], seed_file=STR, paper=STR, reproduces=STR)),
        ("StudyResult", report.StudyResult, dict(info=report.StudyInfo("s", "f", "p", "r")), dict(info=[None, 3, "s"])),
        ("StudyResult.quantity", _result_quantity, dict(id="q", label="q", value=1.0, paper=1.0),
         dict(tolerance=["abc", NAN, -0.1], runs=opt(INT), unit=[None, 3], id=[None, 3, ""])),
        ("StudyResult.reconstruction", _reconstruction, dict(name="x", why="because"),
         dict(name=STR + [""], why=STR + [""])),
        ("StudyResult.finding", _finding, dict(id="f", text="found"), dict(id=STR + [""], text=STR + [""])),
        ("StudyResult.merge", _merge, dict(part=_new_result()), dict(part=[None, 3, "s", {}])),
        ("StudyContext", report.StudyContext, dict(out_dir=".", runs=3, seed=0, jobs=1),
         dict(runs=opt(INT) + [0], seed=INT + [-1], jobs=INT + [0])),
        ("StudyContext.runs_or", _runs_or, dict(default=100, quick_default=5),
         dict(default=INT + [0], quick_default=opt(INT) + [0])),
        ("StudyContext.save_figure", _save_figure, dict(out_dir=tmp / "figs", fig=fig, filename="fig1.png", dpi=50),
         dict(fig=[None, 3], filename=STR + ["", "../up.png", "a/b.png"], dpi=INT + [0])),
        ("validate_results", report.validate_results, dict(data=results), dict(data=[None, [], "x"])),
        ("read_runtime", report.read_runtime, dict(study_dir=tmp), dict(study_dir=[None, 3, ""])),
        ("count_verdicts", report.count_verdicts, dict(results=results), dict(results=[None, [], {"q": 1}])),
        ("write_text_atomic", report.write_text_atomic, dict(path=tmp / "a.txt", text="x"),
         dict(path=[None, 3, ""], text=[None, 3, b"x"])),
        ("staged_directory", _staged, dict(target=tmp / "staged"), dict(target=[None, 3, ""])),
        ("write_results_json", report.write_results_json, dict(result=_new_result(), out_dir=tmp / "results"),
         dict(result=[None, {}], out_dir=[None, 3, ""])),
        ("new_figure", _new_figure, dict(nrows=1, ncols=2, size=(4.0, 3.0)),
         dict(nrows=INT + [0], ncols=INT + [0], size=ARR + [(4.0,), (0.0, 3.0), (NAN, 3.0)])),
        ("summary_table", report_md.summary_table, dict(results=results), dict(results=[None, [], "x"])),
        ("tally", report_md.tally, dict(results=results), dict(results=[None, [], "x", {"study": "s"}])),
        ("overview_table", report_md.overview_table, dict(results=[results], this_run={}),
         dict(results=[None, 3, [None], ["x"]], this_run=[None, 3, "x"])),
        ("write_report_md", report_md.write_report_md, dict(results=[results], out_dir=tmp / "report"),
         dict(results=[None, 3, [None], ["x"]], out_dir=[None, 3, ""], this_run=[3, "x"], failed=[3, "x"])),
        *_claim_cases(results),
        *_arena_cases(tmp),
        *_streaming_cases(),
    ]


SHAPE = ["x", 1.5, -1, [2, "a"], True]
_STREAMS = {"Moments": lambda: streaming.Moments(shape=2), "Quantiles": lambda: streaming.Quantiles(shape=2, k=16),
            "Histogram": lambda: streaming.Histogram([0.0, 1.0], shape=2), "Counts": lambda: streaming.Counts(shape=2),
            "Keep": lambda: streaming.Keep(2, shape=2)}


def _stream_add(kind, values, exclude=None, start=None):
    acc = _STREAMS[kind]()
    return acc.add(values, start) if kind == "Keep" else acc.add(values, exclude)


def _stream_merge(kind, other):
    return _STREAMS[kind]().merge(other)


def _stream_call(method, **kw):
    acc = streaming.Quantiles(k=16).add(np.arange(40.0)) if method != "var" else streaming.Moments().add(np.ones(3))
    return getattr(acc, method)(**kw)


#: The wrappers' selector arguments (which accumulator, which method): not arguments of the library, so the
#: generated fuzz (tests/fuzz_wide.py) leaves them alone.
_stream_add.harness = _stream_merge.harness = ("kind",)
_stream_call.harness = ("method",)


def _streaming_cases():
    """The accumulators of ctrl_analysis.streaming, their add, merge and results."""
    values = ARR + [3.0, np.ones((3, 4)), np.ones((3, 2, 1))]
    bad_other = [None, 3, "x", streaming.Keep(1), streaming.Moments(shape=3).add(np.ones((1, 3)))]
    cases = [
        ("Moments", streaming.Moments, dict(shape=None, nonfinite="raise"), dict(shape=SHAPE, nonfinite=CHOICE)),
        ("Quantiles", streaming.Quantiles, dict(shape=None, k=64, method="linear", nonfinite="raise"),
         dict(shape=SHAPE, k=INT + [0, 8, HUGE], method=CHOICE + [None], nonfinite=CHOICE)),
        ("Counts", streaming.Counts, dict(shape=None), dict(shape=SHAPE)),
        ("Histogram", streaming.Histogram, dict(edges=[0.0, 1.0], shape=None, nonfinite="raise"),
         dict(edges=ARR + [[1.0], [1.0, 0.0], [0.0, NAN], [[0.0, 1.0]], 2.0], shape=SHAPE, nonfinite=CHOICE)),
        ("Keep", streaming.Keep, dict(runs=3, shape=None),
         dict(runs=["ab", None, -1, 1.5, [1, "a"], [-1], HUGE, [[1, 2]]], shape=SHAPE)),
        ("Moments.add", _stream_add, dict(kind="Moments", values=np.ones((3, 2)), exclude=None),
         dict(values=values + [[[NAN, 1.0]], [[INF, 1.0]]],
              exclude=["x", 3, [1, 0, 1], np.ones(2, bool), [[True] * 3]])),
        ("Quantiles.add", _stream_add, dict(kind="Quantiles", values=np.ones((3, 2)), exclude=None),
         dict(values=values + [[[NAN, 1.0]]], exclude=["x", [1, 0, 1], np.ones(4, bool)])),
        ("Histogram.add", _stream_add, dict(kind="Histogram", values=np.ones((3, 2)), exclude=None),
         dict(values=values + [[[NAN, 1.0]]], exclude=["x", [1, 0, 1], np.ones(4, bool)])),
        ("Counts.add", _stream_add, dict(kind="Counts", values=np.ones((3, 2), bool)),
         dict(values=values + [True, np.ones((3, 2)), np.ones((3, 3), bool)], exclude=[np.ones(3, bool)])),
        ("Keep.add", _stream_add, dict(kind="Keep", values=np.ones((3, 2)), start=None),
         dict(values=values, start=["3", 2.5, NAN, [2], True, -1])),
        ("Quantiles.quantile", _stream_call, dict(method="quantile", q=0.5),
         dict(q=["abc", None, NAN, INF, -0.1, 1.5, [0.5, NAN], [[0.1, 2.0]]])),
        ("Quantiles.percentile", _stream_call, dict(method="percentile", p=50.0),
         dict(p=["abc", None, NAN, -1.0, 100.5, [50.0, INF]])),
        ("Quantiles.bytes_bound", _stream_call, dict(method="bytes_bound", n=10), dict(n=INT + [-1])),
        ("Quantiles.error_bound", streaming.Quantiles.error_bound, dict(n=10, k=4), dict(n=INT + [-1], k=INT + [0])),
        ("Moments.var", _stream_call, dict(method="var", ddof=1), dict(ddof=INT + [-1])),
    ]
    for kind in _STREAMS:
        cases.append((f"{kind}.merge", _stream_merge, dict(kind=kind, other=_STREAMS[kind]()),
                      dict(other=bad_other + [_STREAMS["Quantiles" if kind != "Quantiles" else "Moments"]()])))
    cases.append(("Quantiles.merge (k)", _stream_merge, dict(kind="Quantiles", other=streaming.Quantiles(k=16)),
                  dict(other=[streaming.Quantiles(k=32)])))
    cases.append(("Histogram.merge (edges)", _stream_merge,
                  dict(kind="Histogram", other=streaming.Histogram([0.0, 1.0])),
                  dict(other=[streaming.Histogram([0.0, 2.0])])))
    return cases


def _claim_cases(results):
    """Claims, plausible ranges, the verdict policy and the sensitivity sweep."""
    from ctrl_analysis.reporting import claims as report_claims
    from ctrl_analysis.reporting import sensitivity, verdicts
    from ctrl_analysis.reporting.formatting import summarise
    from ctrl_analysis.reporting.glossary import glossary_lines

    claim = study.Claim("c", "§1", "a claim")
    return [
        ("Claim", study.Claim, dict(id="c", section="§1", statement="s"),
         dict(id=STR + [""], section=STR + [""], statement=STR + [""])),
        ("span", study.span, dict(low=1.0, high=2.0, why="w"),
         dict(low=[NAN, INF, 3.0], high=[NAN, INF, 0.5], why=STR + [""], scale=["cubic", 3], points=INT + [1])),
        ("Plausible", study.Plausible, dict(why="w", options=(1, 2)),
         dict(why=STR + [""], options=[(), [1, 2], "ab"], points=INT + [1])),
        ("choices", study.choices, dict(options=(1, 2), why="w"), dict(options=[()], why=STR + [""])),
        ("fixed", study.fixed, dict(why="w"), dict(why=STR + [""])),
        ("missing_plausible", study.missing_plausible, dict(params=report.StudyContext(".")),
         dict(params=[None, 3, report.StudyContext])),
        ("central_interval", verdicts.central_interval, dict(samples=[1.0, 2.0, 3.0]),
         dict(samples=[[], [1.0, NAN], None], share=[0.0, 1.0, NAN])),
        ("digits_tolerance", verdicts.digits_tolerance, dict(paper=0.95, decimals=2),
         dict(paper=[0.0, NAN, INF], decimals=INT + [-1])),
        ("ClaimResult", verdicts.ClaimResult, dict(claim=claim, holds=True, evidence=("x",)),
         dict(claim=[None, "c"], holds=[3, "yes"], evidence=[(3,), ("",)], note=[3])),
        ("explore", sensitivity.explore, dict(evaluate=_toy_evaluate, params={"p": _ToyParams()}, samples=8),
         dict(evaluate=[None, 3], params=[None, {}, {"p": 3}], jobs=INT + [0], names=[["p.nope"]],
              samples=INT + [0, 1, 10 ** 9], refine=[-1, 31, 1.5], cell_steps=[-1, 41], search_rounds=[-1, 21])),
        ("apply", sensitivity.apply, dict(result=_toy_evaluate({"p": _ToyParams()}),
                                          exploration=sensitivity.explore(_toy_evaluate, {"p": _ToyParams()},
                                                                          samples=8)),
         dict(result=[None, 3], exploration=[None, 3])),
        ("plot_sensitivity", sensitivity.plot_sensitivity, dict(result=_swept(), top=3),
         dict(result=[None, 3, _toy_evaluate({"p": _ToyParams()})], top=INT + [0])),
        ("caption", sensitivity.caption, dict(result=_swept(), detail="x"), dict(result=[None, 3], detail=[3])),
        ("Box", Box, dict(params={"p": _ToyParams()}), dict(params=[None, {}, {"p": 3}], names=[["p.nope"]])),
        ("claim_verdict", claim_verdict, dict(support=0.5, base="holds"), dict(base=["maybe", None, 3])),
        ("printed_tolerance", printed_tolerance, dict(paper=1.25), dict(paper=[None, "x", [], [[1.0]] * 0])),
        ("algorithm", study_algorithm, dict(printed="a", corrected="b", why="w"),
         dict(corrected=["a"], why=["", None])),
        ("scorecard", report_claims.scorecard, dict(results=results), dict(results=[None, 3])),
        ("claim_counts", report_claims.claim_counts, dict(results=results), dict(results=[None, 3])),
        ("checks_and_errata", report_claims.checks_and_errata, dict(results=results), dict(results=[None, 3])),
        ("sensitivity_lines", report_claims.sensitivity_lines, dict(results=results), dict(results=[None, 3])),
        ("plausible_text", report_claims.plausible_text, dict(p={"low": 1.0, "high": 2.0}), dict(p=[3, "x"])),
        ("not_reproduced", report_md.not_reproduced, dict(results=results), dict(results=[None, 3])),
        ("glossary_lines", glossary_lines, dict(text="RMSE"), dict(text=[None, 3])),
        ("summarise", summarise, dict(value=[1, 2]), {}),
    ]


def _arena_csv(path, rows, header="time,y"):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(header + "\n" + "\n".join(",".join(f"{v}" for v in r) for r in rows) + "\n", encoding="utf-8")
    return path


def _arena_cases(tmp):
    """The estimator arena: bound, signals, the algebraic differentiator, the interface and the tuning."""
    from ctrl_analysis.arena import algebraic, bound, signals, tuning

    interface, recommend = arena_interface, arena_recommend

    setup = tuning.Setup(dt=0.01, n=100, transient=0.2)
    case = tuning.Case("sines", "uniform", 0.01, 2.0, (1,))
    pair = bound.adversarial_pair(0.01, 1.0, 0.01, 100, 50)
    y = np.zeros((50, 1))
    csv = tmp / "arena"
    ok = _arena_csv(csv / "ok.csv", [[0.01 * k, math.sin(0.01 * k)] for k in range(30)])
    bad_csv = [csv / "missing.csv", csv, _arena_csv(csv / "one_column.csv", [[0.01 * k] for k in range(30)], "time"),
               _arena_csv(csv / "short.csv", [[0.01 * k, 0.0] for k in range(5)]),
               _arena_csv(csv / "text.csv", [[0.01 * k, "abc"] for k in range(30)]),
               _arena_csv(csv / "nan.csv", [[0.01 * k, NAN] for k in range(30)]),
               _arena_csv(csv / "backwards.csv", [[0.01 * (k % 20), 0.0] for k in range(30)]),
               _arena_csv(csv / "uneven.csv", [[0.01 * k * k, 0.0] for k in range(30)])]
    (csv / "binary.csv").write_bytes(b"\xff\xfe\x00bad")
    bad_csv.append(csv / "binary.csv")
    ints = ["3", None, 2.5, NAN, [2], True]
    settings = dict(signals=("sines",), noises=("uniform",), eps=(0.01,), L=2.0, records=1, setup=setup, rounds=0,
                    families=("algebraic",))
    task = ("algebraic", setup, (case,), [(0, np.array([4.0, 2.0]))], "numpy")
    results = {"quantities": [{"id": "tunings", "value": 3.0}, {"id": "tuning_seconds", "value": 1.0}],
               "findings": [{"text": "a finding"}], "figures": ["a.png"], "captions": {"a.png": "c"}}
    return [
        ("lower_bound", bound.lower_bound, dict(eps=0.01, L=1.0), dict(eps=VPOS, L=VPOS)),
        ("difference_quotient", bound.difference_quotient, dict(y=np.sin(0.01 * np.arange(100)), dt=0.01, eps=0.01,
                                                                L=1.0),
         dict(y=ARR + [np.zeros((2, 2, 2)), [1.0], _nan_like(np.ones(100))], dt=POS, eps=POS, L=POS)),
        ("adversarial_pair", bound.adversarial_pair,
         dict(eps=0.01, L=1.0, dt=0.01, n_samples=100, k_star=50, slope=1.0),
         dict(eps=POS, L=POS, dt=POS, n_samples=ints + [0, -1], k_star=ints + [-1, 100, 5], slope=REAL)),
        ("adversarial_error", bound.adversarial_error, dict(est_d1=np.zeros((100, 2)), pair=pair, k_from=10),
         dict(est_d1=["abc", None, np.zeros((99, 2)), np.zeros((100, 3)), np.zeros(100), np.zeros((100, 2, 1, 1))],
              pair=[None, 3, {}, {"f1": 1.0}], k_from=ints + [-1, 51])),
        ("algebraic_weights", algebraic.algebraic_weights, dict(window=5, degree=2, dt=0.1),
         dict(window=ints + [0, 2], degree=ints + [0, 3], dt=POS)),
        ("algebraic_derivative", algebraic.algebraic_derivative,
         dict(y=np.zeros((20, 2)), windows=[4, 5], degrees=2, dt=0.1),
         dict(y=ARR + [np.zeros(20), np.zeros((20, 2, 1)), _nan_like(np.zeros((20, 2)))],
              windows=["3", None, [4.5, 5], [NAN, 5], [4, 5, 6], [[4, 5]], [0, 5]],
              degrees=["3", None, 1.5, NAN, [1, 2, 2], 0, 3], dt=POS, before=CHOICE + [None, 0])),
        ("make_signal", signals.make_signal, dict(kind="chirp", seed=1, t=np.linspace(0.0, 1.0, 20), L=2.0),
         dict(kind=CHOICE + [None, ["chirp"]], seed=ints + [-1], t=ARR + [[], np.ones((2, 3)), [0.0, NAN]], L=POS)),
        ("add_noise", signals.add_noise, dict(kind="uniform", f=np.zeros(20), eps=0.1, seed=3),
         dict(kind=CHOICE + [None], f=ARR + [[], np.ones((2, 3)), [0.0, INF]], eps=POS, seed=ints + [-1])),
        ("family", interface.family, dict(name="leso2"), dict(name=CHOICE + [None, ["leso2"]])),
        ("scales", interface.scales, dict(eps=0.01, L=4.0, dt=0.002), dict(eps=POS, L=POS, dt=POS)),
        ("substeps_for", interface.substeps_for, dict(omega_dt=[0.5, 2.0]),
         dict(omega_dt=ARR + [[0.0], [-1.0], [9.0], "abc", None])),
        ("estimate", interface.estimate, dict(fam="leso2", P=[[20.0]], y=y, dt=0.01, engine="numpy"),
         dict(fam=CHOICE + [None], P=ARR + [[[20.0, 1.0]], [[NAN]], [[0.0]], [[-20.0]]],
              y=ARR + [np.zeros(50), np.zeros((50, 2)), _nan_like(y)], dt=POS, engine=CHOICE + [None],
              init=CHOICE + [None, 0])),
        ("estimate(algebraic)", interface.estimate, dict(fam="algebraic", P=[[4.0, 2.0]], y=y, dt=0.01),
         dict(P=[[[4.5, 2.0]], [[4.0, 3.0]], [[4.0, 1.5]], [[4.0, 0.0]]])),
        ("Setup", tuning.Setup, dict(dt=0.01, n=100, transient=0.2),
         dict(dt=POS, n=INT + [1, 0], transient=NONNEG + [1.0, 5.0], init=CHOICE + [None, 0])),
        ("Case", tuning.Case, dict(signal="sines", noise="uniform", eps=0.01, L=2.0, seeds=(1, 2)),
         dict(signal=STR + [""], noise=STR + [""], eps=POS, L=POS, seeds=[None, 3, (), [1, 2], (1.5,), (-1,), ("a",)])),
        ("case_records", tuning.case_records, dict(case=case, setup=setup),
         dict(case=[None, 3, "sines"], setup=[None, 3, recommend.QUICK])),
        ("param_values", tuning.param_values, dict(fam=interface.family("td"), z=[[0.0, 0.5]], case=case, setup=setup),
         dict(fam=[None, "td", 3],
              z=ARR + [[[0.0]], [[0.0, 0.5, 1.0]], [[NAN, 0.0]], [[INF, 0.0]], np.zeros((1, 2, 1))],
              case=[None, 3], setup=[None, 3])),
        ("evaluate", tuning.evaluate, dict(task=task),
         dict(task=[None, 3, task[:4], ("nonsense",) + task[1:], task[:1] + (None,) + task[2:],
                    task[:2] + ((),) + task[3:],
                    task[:2] + ((case, tuning.Case("sines", "uniform", 0.01, 2.0, (1, 2))),)
                    + task[3:], task[:3] + (None,) + task[4:], task[:3] + ([(3, [4.0, 2.0])],) + task[4:],
                    task[:3] + ([(0, [4.0])],) + task[4:], task[:3] + ([(0, [NAN, 2.0])],) + task[4:],
                    task[:3] + ([3],) + task[4:], task[:4] + ("nonsense",)])),
        ("tune_family", tuning.tune_family,
         dict(name="algebraic", cases=[case], setup=setup, rounds=0, engine="numpy", jobs=1, scheduler=None),
         dict(name=CHOICE + [None], cases=[None, 3, "sines", [], [3]], setup=[None, 3], rounds=INT + [-1],
              engine=CHOICE, jobs=INT + [0], scheduler=[3, "nonsense"])),
        ("family_chain", tuning.family_chain,
         dict(name="algebraic", cases=[case], setup=setup, rounds=0, engine="numpy", jobs=1),
         dict(name=CHOICE + [None], cases=[None, 3, "sines", [], [3]], setup=[None, 3], rounds=INT + [-1],
              engine=CHOICE, jobs=INT + [0])),
        ("tune_families", tuning.tune_families,
         dict(names=["algebraic"], cases=[case], setup=setup, rounds=0, engine="numpy", jobs=1, scheduler=None),
         dict(names=[None, 3, "algebraic", [], ["nonsense"], ["algebraic", "algebraic"], [None]],
              cases=[None, 3, "sines", [], [3]], setup=[None, 3], rounds=INT + [-1], engine=CHOICE,
              jobs=INT + [0])),
        ("pareto_front", tuning.pareto_front, dict(points=[[1.0, 5.0], [2.0, 2.0], [INF, 1.0]]),
         dict(points=ARR + [[1.0, 2.0], [[1.0, 2.0, 3.0]], [[NAN, 1.0]], np.ones((2, 2, 2))])),
        ("ArenaSettings", recommend.ArenaSettings, settings,
         dict(signals=[None, "sines", (), ("nonsense",)], noises=[None, (), ("nonsense",)],
              eps=[None, 0.01, (), (NAN,), (-0.01,), ("abc",)],
              L=POS, records=INT + [0], setup=[None, 3], rounds=INT + [-1], families=[None, (), ("nonsense",)])),
        ("arena_report_lines", recommend.arena_report_lines, dict(results=results),
         dict(results=[None, 3, "x", [], {"quantities": 3}, {"findings": [3]}, {"figures": [None]},
                       {"quantities": [{"id": "q"}]}])),
        ("read_record", arena_cli.read_record, dict(path=ok), dict(path=[None, 3, ""] + bad_csv)),
        ("read_channels", arena_cli.read_channels, dict(path=ok), dict(path=[None, 3, ""] + bad_csv)),
        *_arena_registry_cases(case, setup),
        *_arena_record_check_cases(),
    ]


def _arena_record_check_cases():
    """The arena's checks of a user's record before its work (a record whose bounds hold, then each bad part)."""
    from ctrl_analysis.arena import recordcheck

    t = 0.01 * np.arange(600)
    y = np.sin(t) + 0.01 * np.random.default_rng(0).uniform(-1, 1, t.size)
    return [
        ("record_estimates", recordcheck.record_estimates, dict(y=y, dt=0.01),
         dict(y=ARR + [np.zeros((2, 3)), [1.0, 2.0], _nan_like(y)], dt=POS, d1=opt(ARR) + [np.zeros(3), _nan_like(y)],
              eps=opt(POS))),
        ("estimated_bounds", recordcheck.estimated_bounds, dict(t=t, y=y),
         dict(t=ARR + [np.zeros((2, 3)), [1.0, 2.0], _nan_like(t)], y=ARR + [np.zeros((2, 3)), _nan_like(y)],
              d1=opt(ARR) + [np.zeros(3), _nan_like(y)])),
        ("work_estimate", recordcheck.work_estimate, dict(n=600, dt=0.01, eps=0.01, L=1.0),
         dict(n=INT + [1, -5], dt=POS, eps=POS, L=POS, derivative=BOOL)),
        ("check_record", recordcheck.check_record, dict(t=t, y=y, d1=None, eps=0.01, L=1.0),
         dict(t=ARR + [t[::-1], t[:10], t ** 2, _nan_like(t)], y=ARR + [y[:-1], np.zeros((600, 2)), _nan_like(y)],
              d1=opt(ARR) + [np.zeros(3), _nan_like(y)], eps=POS, L=POS, where=STR,
              names=[None, "ab", ("a",), (1, 2)])),
    ]


def _fuzz_parabola(seed, dt, n):
    t = dt * np.arange(n)
    return 3.0 * t**2, 6.0 * t, np.full(n, 6.0), 6.0


def _arena_registry_cases(case, setup):
    """Registered signal classes and claim checks (the studies' hooks into the arena)."""
    from ctrl_analysis.arena import claims, signals

    signals.register_signal_class("fuzz-parabola", "3t²", _fuzz_parabola, "f'' = 6")
    check = dict(claim="s/c", winners=("sigma",), losers=("neso",), signals=("sines",), statement="x", how="y")
    table = {"sigma": {case.key: {"rms": 1.0}}, "neso": {case.key: {"rms": 2.0}}}
    return [
        ("register_signal_class", signals.register_signal_class,
         dict(name="fuzz-parabola", description="3t²", generate=_fuzz_parabola, bound_how="f'' = 6"),
         dict(name=STR + ["", "sines"], description=STR + [""], generate=CALLABLE, bound_how=STR + [""])),
        ("simulate_registered", signals.simulate_registered,
         dict(kinds=["fuzz-parabola", "sines"], seeds=[1], t=np.arange(20) * 0.1, jobs=1),
         dict(kinds=[None, 3, "sines", ["nonsense"]], seeds=[None, 3, [-1], [1.5]],
              t=ARR + [[], [0.0, NAN], [0.0, 0.1, 0.3]], jobs=INT + [0])),
        ("native_bound", signals.native_bound, dict(kind="fuzz-parabola", seed=1, t=np.arange(20) * 0.1),
         dict(kind=CHOICE + [None, "sines"], seed=INT + [-1],
              t=ARR + [[], np.ones((2, 3)), [0.0, NAN], [0.0, 0.1, 0.3], [1.0, 1.1, 1.2]])),
        ("ClaimCheck", claims.ClaimCheck, check,
         dict(claim=STR + ["", "noslash", "a/b/c", "/c"], winners=[None, ["sigma"], ("nope",), (3,)],
              losers=[None, ("nope",), ((("algebraic", [2.0, 1.0])),), (("algebraic", (2.0,)),), ()],
              signals=[None, ["sines"], (3,)], statement=STR + [""], how=STR + [""])),
        ("register_claim_check", claims.register_claim_check, dict(check=claims.ClaimCheck(**check)),
         dict(check=[None, 3, check])),
        ("judge_claims", claims.judge_claims,
         dict(result=report.StudyResult(arena_recommend.INFO), cases=[case], table=table, setup=setup,
              checks=[claims.ClaimCheck(**check)], fixed=None),
         dict(result=[None, 3], cases=[None, 3, [3]], table=[None, 3], setup=[None, 3], checks=[3, [3], "x"],
              fixed=[3, {"a": 3}])),
        ("fixed_configurations", claims.fixed_configurations, dict(checks=None), dict(checks=[3, [3], "x"])),
        ("tuned_for_signal", claims.tuned_for_signal, dict(checks=None), dict(checks=[3, [3], "x"])),
        ("arena_claim_links", arena_recommend.arena_claim_links, dict(results={"findings": []}),
         dict(results=[None, 3, "x"])),
    ]


@dataclasses.dataclass(frozen=True)
class _ToyParams:
    k: float = study.reconstructed(1.0, "toy", plausible=study.span(0.5, 3.0, "toy range", points=3))


def _toy_evaluate(params):
    res = report.StudyResult(report.StudyInfo("toy", "", "", ""))
    res.quantity("gain", "gain", params["p"].k, paper=1.0, tolerance=0.1, unit="")
    res.claim(study.Claim("small", "§1", "the gain is below 2"), params["p"].k < 2, evidence=["gain"])
    return res


def _swept():
    from ctrl_analysis.reporting import sensitivity

    res = _toy_evaluate({"p": _ToyParams()})
    sensitivity.apply(res, sensitivity.explore(_toy_evaluate, {"p": _ToyParams()}, samples=8))
    return res


def _new_figure_object():
    from matplotlib.figure import Figure

    return Figure()


def _seed_rows(seeds):
    return np.asarray(seeds, dtype=float)


def _sweep_fn(points, seeds):
    (values,) = points.values()  # the grid's one parameter, whatever its name (names are free)
    return values * np.asarray(seeds, dtype=float)


@dataclasses.dataclass(frozen=True)
class _Params:
    """A parameter record as the studies write them."""

    k: float = study.printed(2.0, "eq. (1)")


_PARAMS = _Params()


#: Public classes and functions deliberately not in the table, with the reason.
NOT_FUZZED = {
    arena_cli.check_args: "takes argparse's parsed Namespace; the CLI's arena tests feed it every bad argument",
    arena_report_section.arena_section: "reads OUT/arena/results.json; the arena CLI tests write both kinds",
    arena_report_section.arena_links: "reads OUT/arena/results.json for REPORT.md; covered with the section",
    arena_record.run_record: "the arena's record run on a checked record (read_record and check_args are fuzzed)",
    arena_record.report_lines: "renders the results.json run_record writes; the CLI's arena tests check it",
    run_folder.RunFolder: "the reproduce command's own bookkeeping; test_cli_faults and test_cli_reliability drive it",
    run_folder.read_results: "reads a results.json back for RunFolder; the CLI fault tests feed it broken files",
    first_order: "a step of explore() on its own sample (explore is fuzzed); SALib checks its arrays",
    box_cells.cell_state: "a step of explore() on the study's own Quantity objects (explore is fuzzed)",
    box_cells.search_cells: "a step of explore() on its own runner and sample (explore is fuzzed)",
    Dimension: "a record Box builds from a study's reconstructions (Box is fuzzed)",
    sensitivity_module.Exploration: "the record explore() returns (explore and apply are fuzzed)",
    blocks.Block: "abstract base class without constructor arguments",
    blocks.ContinuousBlock: "abstract base class without constructor arguments",
    blocks.StaticBlock: "protocol without constructor arguments; given some, a TypeError naming FunctionBlock "
                        "(test_function_block.py)",
    blocks.DiscreteBlock: "abstract base class without constructor arguments (run/nlsys are fuzzed above)",
    loop_mod.Placed: "record built by place(), which is fuzzed",
    engine_kernels.KernelBlock: "mixin without constructor arguments (the blocks using it are fuzzed)",
    engine_kernels.Layout: "fuzzed through _layout (its fields are variadic) and _layout_pack",
    engine_kernels.Kernels: "record of a block's kernel functions and parameters, checked when the block runs "
                            "(check_kernel_reads)",
    engine_kernels.copy_output: "per-step kernel, unchecked by design",
    engine_jit.cache_dir: "takes no arguments (reads $CTRL_ANALYSIS_CACHE)",
    engine_jit.compiled_rows: "engine plumbing: KernelBlock.batched gives it the block's own kernel",
    engine_jit.source_key: "engine plumbing: the runner cache gives it the loop's kernels",
    engine_jit.compile_lock: "engine plumbing: the runner cache gives it the lock file beside a generated runner; "
                             "an unusable path runs unlocked (tests/lib/test_compile_lock.py)",
    pid.pid_output: "per-step kernel, unchecked by design",
    levant.levant_output: "per-step kernel, unchecked by design",
    arena_offline.savgol_smoother: "runner of arena.interface.estimate, which checks its arguments (fuzzed)",
    arena_offline.spline_smoother: "runner of arena.interface.estimate, which checks its arguments (fuzzed)",
    arena_offline.rts_smoother: "runner of arena.interface.estimate, which checks its arguments (fuzzed)",
    arena_startup.startup_calls: "run_arena's plumbing: the calls of its tuned families (test_arena_cli's tiny arena)",
    arena_startup.record_startup: "records run_arena's table in its result (test_arena_cli's tiny arena)",
    levant.levant_update: "per-step kernel, unchecked by design",
    integrators.is_bad: "per-step divergence test, unchecked by design",
    numpy_engine.run_numpy: "internal half of Loop.simulate(execution=Execution(engine='numpy')), whose arguments "
                            "are fuzzed",
    engines.NumpyEngine: "no constructor arguments; run() takes the plan, batch and policies Loop.simulate made",
    engines.CompiledEngine: "built by select_engine from a runner it found; run() as NumpyEngine's",
    engine_processes.ProcessEngine: "built by select_engine for jobs > 1 from a picklable loop; run() as NumpyEngine's",
    engine_processes.in_chunk: "takes no arguments",
    engines.Engine: "a typing.Protocol (the engines' contract)",
    engines.Record: "record of result arrays built by the engines",
    engines.kept_columns: "internal half of Loop.simulate(save=Save(keep=...)), whose keep is fuzzed",
    engines.select_engine: "internal half of Loop.simulate(execution=...), whose engine is fuzzed",
    engine_batch.Batch: "record built by resolve_batch",
    engine_batch.resolve_batch: "internal half of Loop.simulate: its inputs, x0, params, runs, seeds and t0 are fuzzed "
                                "through Loop.simulate",
    plan.Plan: "record built by make_plan",
    plan.make_plan: "built from a Loop, whose constructor is fuzzed",
    integrators.rk4_point: "per-step integrator formula, unchecked by design",
    integrators.rk4_sum: "per-step integrator formula, unchecked by design",
    integrators.rk4_acc: "per-step integrator formula, unchecked by design",
    integrators.rk4_end: "per-step integrator formula, unchecked by design",
    pid.pid_update: "per-step kernel, unchecked by design",
    engine_kernels.as_int: "per-step helper of kernels (a size read from p), unchecked by design",
    engine_kernels.scratch: "per-step helper of kernels (space to work in), unchecked by design",
    engine_kernels.gather: "per-step helper of kernels (a table entry at a computed index), unchecked by design",
    engine_kernels.jitable: "decorator: any function is a valid argument",
    engine_layout.offset: "per-step helper of kernels (a layout field's offset for the size read from p), unchecked "
                          "by design",
    **{getattr(engine_matrix, name): "per-step matrix helper of kernels (views and products), unchecked by design; "
                                     "tests/lib/test_engine_matrix.py checks it against numpy"
       for name in engine_matrix.__all__},
    engine_params.Variant: "record built by resolve",
    engine_params.PerRunBlocks: "built by resolve from blocks the constructor validated (resolve is fuzzed)",
    engine_params.resolve: "internal half of Loop.simulate(params=...), whose params are fuzzed",
    engine_params.split: "internal half of Loop.simulate(params=...), whose params are fuzzed",
    engine_params.runs_of: "internal half of Loop.simulate(params=...): malformed params give None, then resolve's "
    "error",
    engine_params.take: "internal half of Loop.simulate(params=...), whose params are fuzzed",
    engine_params.chunk_functions: "the numpy engine's internals, called with the plan and values it made",
    loop_mod.LoopResponse: "result record built by Loop.simulate",
    simresult.SimResult: "result record built by the simulators",
    simresult.BatchRuns: "the results' shared properties (ok, runs, divergences): no arguments",
    integrators.euler_step: "per-step integrator, unchecked by design",
    integrators.rk4_step: "per-step integrator, unchecked by design",
    continuous.riccati_rhs: "per-step right-hand side, unchecked by design",
    continuous.ContinuousSteadyState: "result record",
    discrete.DiscreteSteadyState: "result record",
    ident.IdentifiabilityReport: "result record built by identifiability()",
    ident.LeastSquaresResult: "result record built by batch_least_squares()",
    ident.IdentifiabilityWarning: "warning category",
    sym_de.BreakawayDerivation: "result record of a sympy derivation",
    sym_de.derive_breakaway: "sympy derivation without arguments",
    sym_de.coefficient_formula: "sympy formula without arguments",
    sym_eso.BandwidthMatch: "result record of bandwidth_match()",
    sym_ric.SecondOrderGainDerivation: "result record of a sympy derivation",
    sym_ric.RandomWalkDerivation: "result record of a sympy derivation",
    sym_ric.KalataDerivation: "result record of a sympy derivation",
    sym_ric.derive_second_order_gain: "sympy derivation checked on fixed samples (test_symbolic_riccati)",
    sym_ric.derive_random_walk_gain: "sympy derivation without arguments",
    sym_ric.derive_kalata_gains: "sympy derivation without arguments",
    parallel.default_jobs: "no arguments",
    cluster.ClusterError: "an exception class, raised by map_chunks on a failing cluster (tests/lib/test_parallel.py)",
    cluster.silence_dask_logs: "no arguments",
    taskpool.pool_available: "no arguments",
    taskpool.driver: "no arguments",
    taskpool.trace_event: "writes only where $CTRL_ANALYSIS_TRACE points; any JSON-serialisable dict is valid",
    taskpool.shared_pool: "its one argument is check_int's (tested in tests/lib/test_taskpool.py); opens processes",
    taskpool.map_on_pool: "internal half of map_chunks in a run's driver, whose arguments are fuzzed",
    parallel.active_cluster: "no arguments",
    parallel.use_cluster: "connects to a Dask cluster; its address checks are check_scheduler_address's (fuzzed), "
                          "an unreachable one is tested in tests/lib/test_cli_cluster.py",
    parallel.picklable: "any object is a valid argument (the answer is the check)",
    processes.simulate_chunks: "internal half of Loop.simulate(execution=Execution(jobs > 1)), whose arguments are "
                               "fuzzed",
    progress.NullBar: "no constructor arguments",
    report.versions: "no arguments",
    fuzzy.triangular_memberships: "per-step arithmetic of FuzzyController.output, unchecked by design",
    fuzzy.piecewise_linear_centroid: "per-step arithmetic of FuzzyController.output, unchecked by design",
    cli.main: "command line, fuzzed in test_cli.py and test_cli_reliability.py",
    arena_interface.Param: "record of the fixed FAMILIES table (a family's runner is coded per name); users pick a "
                           "family by name through family() and estimate(fam=...), both fuzzed",
    arena_interface.Family: "record of the fixed FAMILIES table (a family's runner is coded per name); users pick a "
                            "family by name through family() and estimate(fam=...), both fuzzed",
    arena_recommend.run_arena: "runs every family's tuning and draws three figures (seconds even on the smallest "
                               "settings); its settings are validated by ArenaSettings (fuzzed), its ctx and "
                               "settings types on entry; run end to end in test_arena_cli.py",
    arena_figures.save_all: "figure writer fed the tables run_arena built; run by test_arena_cli.py",
    arena_figures.save_pareto: "figure writer fed the tunings run_arena built; run by test_arena_cli.py",
    chains.pool_here: "a context manager (checks on entering): its jobs and scheduler are map_chunks' checks "
                        "(tests/lib/test_drive.py)",
    taskpool.lane_fields: "no arguments",
    arena_cli.add_parser: "registers the arena subcommand on the CLI's parser (test_arena_cli.py)",
    arena_recommend.default_settings: "no arguments",
    signals.registered_signal_classes: "no arguments",
    signals.signal_classes: "no arguments",
    signals.SignalClass: "record built by register_signal_class (fuzzed)",
    claims.registered_claim_checks: "no arguments",
    alpha_beta.alpha_beta_gamma_output: "compiled per-step kernel (test_arena_abg.py: against the matrix-form filter)",
    alpha_beta.alpha_beta_gamma_update: "compiled per-step kernel (test_arena_abg.py: against the matrix-form filter)",
    singer.singer_update: "compiled per-step kernel (test_singer.py: against the matrix-form filter)",
    arena_cli.main: "command line, fuzzed in test_arena_cli.py (malformed CSV, missing bounds: one line, exit 2); "
                    "its CSV reader read_record is fuzzed here",
    **{getattr(_validate, name): "the shared validators themselves (test_validate.py)" for name in _validate.__all__},
    _accumulator.Accumulator: "the streaming accumulators' base; its add and merge are fuzzed through each of them",
    **{getattr(_sketch, name): "the sketch's internals, called by Quantiles with arrays it made (Quantiles is fuzzed)"
       for name in _sketch.__all__},
    **{getattr(_kernels, name): "compiled per-step kernels and the engine's internals (test_speed_kernels.py)"
       for name in _kernels.__all__},
    **{getattr(module, name): "the engine's internals, called with arrays it made (semantic_cases below)"
       for module in (_stepcheck,) for name in module.__all__},
}


def _public_callables():
    """``{id: "module.name"}`` of every class and function in a module's ``__all__``."""
    found = {}
    modules = [ctrl_analysis] + [importlib.import_module(i.name)
                                 for i in pkgutil.walk_packages(ctrl_analysis.__path__, "ctrl_analysis.")]
    for module in modules:
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name)
            if inspect.isclass(obj) or inspect.isfunction(obj):
                found.setdefault(id(obj), f"{obj.__module__}.{obj.__qualname__}")
    return found


def _names_argument(message: str, arg: str) -> bool:
    return re.search(rf"(?<![A-Za-z0-9_]){re.escape(arg)}(?![A-Za-z0-9_])", message) is not None


def test_every_public_callable_is_fuzzed_or_excused(tmp_path):
    wrapped = {_new_figure: report.new_figure, _staged: report.staged_directory, _draw_noise: noise.draw_noise}
    covered = {id(wrapped.get(fn, fn)) for _, fn, _, _ in build_cases(tmp_path)} | {id(obj) for obj in NOT_FUZZED}
    missing = sorted(name for key, name in _public_callables().items() if key not in covered)
    assert not missing, "public callables neither fuzzed nor listed in NOT_FUZZED:\n" + "\n".join(missing)


# -- cases that are not one bad argument of a valid call ---------------------------------------------
def _copy_output(t, x, u, p, y):
    y[0] = x[0]


def _unfilled_update(t, x, u, p, x_next):
    x_next[0] = x[0] + p[0] * u[0] + p[2]  # p[2]: a slot the block never filled


class _ReadsUnfilledSlot(engine_kernels.KernelBlock, blocks.DiscreteBlock):
    """A user's block whose kernel reads ``p[2]`` while its parameters have two entries."""

    inputs, outputs, states = ("u",), ("y",), ("x",)
    kernels = engine_kernels.Kernels(output=_copy_output, update=_unfilled_update)

    def __init__(self):
        self.kernel_params = np.array([0.5, 0.0])


def _engines_agree(rows, runs, chunk_runs):
    """An IKF with one Q per run (``rows`` of them, through ``params``) on both engines: equal answers,
    or the same error (then raised)."""
    loop = loop_mod.Loop([loop_mod.place(ikf.ImprovedKalmanFilter(Q=0.1, R=1.0), "f")], dt=1.0)
    params, outcome = {"f": {"Q": np.linspace(0.1, 0.5, rows)}}, {}
    inputs = {s: np.ones((4, runs)) for s in loop.external}
    for engine in ("numpy", "compiled"):
        try:
            outcome[engine] = loop.simulate(4, inputs=inputs, params=params,
                                            execution=Execution(engine=engine, chunk_runs=chunk_runs))["y_hat"]
        except ValueError as exc:
            outcome[engine] = str(exc)
    a, b = outcome["numpy"], outcome["compiled"]
    if isinstance(a, str) and a == b:
        raise ValueError(a)
    return not isinstance(a, str) and not isinstance(b, str) and np.array_equal(a, b)


def _ivp_nan_model(t, x, u, params):
    return np.where(t > 0.3, np.nan, -x)


def _ivp_nan_always(t, x, u, params):
    return x * np.nan


def _import_first(module):
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-c", f"import {module}"], capture_output=True, text=True).returncode


def semantic_cases():
    """(label, call, argument the error must name, check of the answer or ``None`` when an error is right)."""
    t5 = np.arange(5.0)
    return [
        ("compiled kernel reading an unfilled parameter slot",
         lambda: loop_mod.Loop([loop_mod.place(_ReadsUnfilledSlot(), "b")], dt=1.0).simulate(
             3, inputs={"u": 1.0}, execution=Execution(engine="compiled")), "kernel", None),
        ("DiscreteLTI.update with a state of the wrong width",
         lambda: PLANT.update(0.0, np.zeros((2, 3)), np.ones((2, 1))), "x", None),
        ("DiscreteLTI.output with an input of the wrong width",
         lambda: PLANT.output(0.0, np.zeros((2, 1)), np.ones((2, 3))), "u", None),
        ("LowPassFilter.rhs with a state of the wrong width",
         lambda: LPF.rhs(0.0, np.zeros((2, 1)), np.ones((2, 1))), "x", None),
        ("StaticGain.output with x and u of different runs",
         lambda: blocks.StaticGain([[1.0]], ("a",), ("b",)).output(0.0, np.zeros((2, 0)), np.ones((3, 1))), "x", None),
        ("FuzzyController.output with an input of the wrong width",
         lambda: FUZZY.output(0.0, np.zeros((2, 0)), np.ones((2, 3))), "u", None),
        ("metrics.settling_time of a signal that is NaN at its end",
         lambda: metrics.settling_time(t5, [0.0, 1.0, 1.0, 1.0, NAN], 1.0), "y", lambda r: math.isnan(r)),
        ("metrics.settling_time of a signal NaN at one sample",
         lambda: metrics.settling_time(t5, [0.0, 1.0, NAN, 1.0, 1.0], 1.0), "y", lambda r: r == 3.0),
        ("simulate_ivp with a model that yields NaN from the start",
         lambda: ivp.simulate_ivp(_ivp_nan_always, [1.0], [0.0, 0.5, 1.0]), "rhs",
         lambda r: bool(r.diverged[0]) and r.diverged_step[0] == 0 and np.isnan(r.x).all()),
        ("simulate_ivp with a model that yields NaN (two runs)",
         lambda: ivp.simulate_ivp(_ivp_nan_model, [[1.0], [2.0]], [0.0, 0.5, 1.0]), "rhs",
         lambda r: bool(np.all(r.diverged)) and list(r.diverged_step) == [1, 1] and np.isnan(r.x[1:]).all()),
        ("numpy engine, per-run parameters, a chunked call",
         lambda: _engines_agree(rows=5, runs=5, chunk_runs=2), "runs", bool),
        ("per-run parameters of 1 run on a batch of 5 (both engines)",
         lambda: _engines_agree(rows=1, runs=5, chunk_runs=None), "runs", None),
        ("per-run parameters of 5 runs on a batch of 4 (both engines)",
         lambda: _engines_agree(rows=5, runs=4, chunk_runs=None), "runs", None),
        ("import ctrl_analysis.engine.ivp as the first import", lambda: _import_first("ctrl_analysis.engine.ivp"),
         "ivp",
         lambda rc: rc == 0),
    ]


def _watchdog(seconds):
    """A context manager raising TimeoutError after ``seconds`` (``None``: no watchdog, as in the test)."""
    import contextlib
    import signal

    @contextlib.contextmanager
    def guard():
        if seconds is None:
            yield
            return

        def fire(signum, frame):
            raise TimeoutError(f"no answer within {seconds} s")

        old = signal.signal(signal.SIGALRM, fire)
        signal.alarm(seconds)
        try:
            yield
        finally:
            signal.alarm(0)
            signal.signal(signal.SIGALRM, old)

    return guard()


def fuzz_table(tmp_path, timeout=None):
    """Every bad input of :func:`build_cases` and :func:`semantic_cases`, classified.

    Returns ``(totals, problems)``: ``totals`` counts ``clear`` (ValueError/TypeError naming the
    argument), ``obscure`` (another exception, or one that does not name the argument), ``silent``
    (accepted, or a wrong answer) and ``hang`` (no answer within ``timeout`` seconds; only counted
    when a timeout is given, by ``python tests/lib/test_fuzz_api.py``, never in the test).
    """
    totals = dict.fromkeys(("clear", "obscure", "silent", "hang"), 0)
    problems = []

    def attempt(label, call, arg, answer=None):
        try:
            with _watchdog(timeout):
                result = call()
            if answer is not None:  # a case whose right outcome is an answer, not an error
                ok = answer(result)
                totals["clear" if ok else "silent"] += 1
                if not ok:
                    problems.append(f"{label}: wrong answer {result!r:.200}")
                return
        except TimeoutError as exc:
            totals["hang"] += 1
            problems.append(f"{label}: hangs ({exc})")
        except (ValueError, TypeError) as exc:
            if _names_argument(str(exc), arg):
                totals["clear"] += 1
            else:
                totals["obscure"] += 1
                problems.append(f"{label}: {type(exc).__name__} does not name {arg!r}: {exc}")
        except Exception as exc:  # noqa: BLE001 - anything else is a finding
            totals["obscure"] += 1
            problems.append(f"{label}: {type(exc).__name__}: {exc}")
        else:
            totals["silent"] += 1
            problems.append(f"{label}: accepted silently")

    for label, fn, valid, bad in build_cases(tmp_path):
        try:
            fn(**valid)  # the starting point is a valid call
        except Exception as exc:  # noqa: BLE001 - a broken starting point makes the case meaningless
            problems.append(f"{label}: the valid starting point fails: {type(exc).__name__}: {exc}")
            continue
        for arg, values in bad.items():
            for value in values:
                attempt(f"{label}({arg}={value!r:.60})", lambda fn=fn, kw=dict(valid, **{arg: value}): fn(**kw), arg)
    for label, call, arg, answer in semantic_cases():
        attempt(label, call, arg, answer)
    return totals, problems


def test_every_public_callable_rejects_bad_arguments_by_name(record_property, tmp_path):
    totals, problems = fuzz_table(tmp_path)
    tried = sum(totals.values())
    record_property("fuzz_inputs", tried)
    print(f"\nfuzz: {tried} bad inputs over {len(build_cases(tmp_path))} public callables and "
          f"{len(semantic_cases())} semantic cases: " + ", ".join(f"{v} {k}" for k, v in totals.items()))
    assert tried >= 1300 and totals["clear"] == tried
    assert not problems, f"{len(problems)} of {tried} inputs:\n" + "\n".join(problems)


# the totals with a watchdog of 20 s per input (hangs counted): python tests/lib/test_fuzz_api.py
if __name__ == "__main__":
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as d:
        found, issues = fuzz_table(Path(d), timeout=20)
    print("\n".join(issues))
    print(", ".join(f"{v} {k}" for k, v in found.items()))
