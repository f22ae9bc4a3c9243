"""Every kernel-first library block: its derived batched methods equal its compiled kernel, bit for bit.

The batched ``output`` / ``update`` / ``rhs`` of a :class:`~ctrl_analysis.engine.kernels.KernelBlock`
call the block's kernels (on the batch's columns, or run by run); the compiled engine calls the same
functions compiled by numba. This holds the two equal, with shared parameters and with one parameter
row per run (what ``Loop.simulate(params=...)`` gives the engines).
"""

from __future__ import annotations

import numpy as np
import pytest

from ctrl_analysis import identification
from ctrl_analysis.controllers import (
    differential_feedback,
    fuzzy,
    golden_section,
    mfac,
    pd,
)
from ctrl_analysis.engine import codegen as _kernels
from ctrl_analysis.engine.kernels import ROWS_COMPILED_MIN

pytestmark = pytest.mark.skipif(not _kernels.available(), reason="numba is not installed")


def _mfac_inputs(rng, B, n, m):
    """States and inputs that reach every branch of the MFAC kernels (tiny Δu, sign flips, bands)."""
    x = rng.standard_normal((B, n))
    u = rng.standard_normal((B, m))
    if n == 3 and m == 2:  # PPDEstimator: |Δu| <= ε and φ̂ of the other sign
        u[::7, 1] = x[::7, 2] + 1e-7
        x[::5, 0] = -x[::5, 0]
    return x, u


def _band_states(rng, B, n, m):
    """DecreasingGainLaw: (in_band, armed) in {0, 1}, an age, errors on both sides of e_m."""
    x = np.column_stack([rng.integers(0, 2, B), rng.integers(0, 2, B), rng.integers(0, 9, B)]).astype(float)
    return x, rng.standard_normal((B, m))


def _rls_states(rng, B, n, m):
    """RecursiveLeastSquaresBlock (3 parameters): θ near the box, R symmetric positive definite."""
    M = rng.normal(size=(B, 3, 3))
    R = M @ M.transpose(0, 2, 1) + 0.1 * np.eye(3)
    x = np.concatenate([rng.uniform(-1.2, 1.2, (B, 3)), R.reshape(B, 9)], axis=1)
    return x, rng.normal(size=(B, m)) * [3.0, 1.0, 1.0, 1.0]


def _golden_states(rng, B, n, m):
    """GoldenSectionController: started or not, errors growing and shrinking, ĝ0 away from zero."""
    x = rng.standard_normal((B, n))
    x[:, 3] = rng.integers(0, 2, B)
    u = rng.standard_normal((B, m))
    u[:, 4] = rng.uniform(0.5, 2.0, B)
    return x, u


def _fuzzy_inputs(rng, B, n, m):
    """(e, ec) inside and beyond the universes of :func:`_mamdani` (saturation), one NaN run."""
    u = rng.standard_normal((B, m)) * [4.0, 15.0]
    u[3, 0] = np.nan
    return np.zeros((B, n)), u


def _mamdani(Ke=2.0):
    return fuzzy.FuzzyController(fuzzy.sum_rule_table(7), Ke=Ke, Kec=0.5, Ku=3.0, n_grid=41)


def _hurwitz_gains(r, B):
    return [differential_feedback.gains_from_poles(-r.uniform(1.0, 5.0, 3)) for _ in range(B)]


# (id, block, n states, n inputs, inputs generator, {parameter: per-run values generator})
CASES = [
    ("UnitDelay", lambda: mfac.UnitDelay(0.3), 1, 1, _mfac_inputs, {}),
    ("PPDEstimator", lambda: mfac.PPDEstimator(0.7, 1.0, 1e-5, 2.0, 0.5), 3, 2, _mfac_inputs,
     {"eta": lambda r, B: r.uniform(0.1, 1.0, B), "mu": lambda r, B: r.uniform(0.5, 2.0, B)}),
    ("CFDLLaw", lambda: mfac.CFDLLaw(0.5, 2.0), 0, 4, _mfac_inputs,
     {"rho": lambda r, B: r.uniform(0.1, 1.0, B), "lam": lambda r, B: r.uniform(0.5, 3.0, B)}),
    ("DecreasingGainLaw", lambda: mfac.DecreasingGainLaw(0.5, 2.0, 0.8), 3, 4, _band_states,
     {"rho": lambda r, B: r.uniform(0.1, 1.0, B), "e_m": lambda r, B: r.uniform(0.2, 1.5, B)}),
    ("DecreasingGainLaw-no-rearm", lambda: mfac.DecreasingGainLaw(0.5, 2.0, 0.8, rearm=False), 3, 4, _band_states,
     {"lam": lambda r, B: r.uniform(0.5, 3.0, B)}),
    ("CFDLPredictor", lambda: mfac.CFDLPredictor(2.0, 0.5, 0.1), 3, 2, _mfac_inputs, {}),
    ("ArxRegressor", lambda: identification.ArxRegressor(2, 1, lag=0), 3, 2, _mfac_inputs, {}),
    ("ArxRegressor-lag2", lambda: identification.ArxRegressor(1, 3, lag=2), 8, 2, _mfac_inputs, {}),
    ("RecursiveLeastSquaresBlock", lambda: identification.RecursiveLeastSquaresBlock(
        3, 0.98, lower=[-1, -1, -1], upper=[1, 1, 1], max_trace=4.0), 12, 4, _rls_states,
     {"forgetting": lambda r, B: r.uniform(0.9, 1.0, B), "max_trace": lambda r, B: r.uniform(1.0, 10.0, B)}),
    ("RecursiveLeastSquaresBlock-hold", lambda: identification.RecursiveLeastSquaresBlock(3, 1.0, feedthrough=False),
     12, 4, _rls_states, {}),
    ("GoldenSectionController", lambda: golden_section.GoldenSectionController(0.1, 0.9, mu=0.05), 4, 5,
     _golden_states, {"k_I": lambda r, B: r.uniform(0.0, 0.5, B), "c2": lambda r, B: r.uniform(0.5, 1.0, B)}),
    ("PDFeedforward", lambda: pd.PDFeedforward(2.0, omega_c=10.0), 0, 6, _mfac_inputs,
     {"b0": lambda r, B: r.uniform(1.0, 3.0, B), "omega_c": lambda r, B: r.uniform(5.0, 20.0, B)}),
    ("PDFeedforward-model-n3", lambda: pd.PDFeedforward(3.0, gains=[6.0, 11.0, 6.0], order=3, model=True),
     4, 13, _mfac_inputs, {"b0": lambda r, B: r.uniform(1.0, 3.0, B)}),
    ("HighOrderDifferentialFeedback", lambda: differential_feedback.HighOrderDifferentialFeedback([6.0, 11.0, 6.0]),
     0, 6, _mfac_inputs, {"K": _hurwitz_gains}),
    ("FuzzyController", _mamdani, 0, 2, _fuzzy_inputs,
     {"Ke": lambda r, B: r.uniform(0.5, 4.0, B), "Ku": lambda r, B: r.uniform(1.0, 3.0, B)}),
    ("FuzzyLookupController", lambda: fuzzy.FuzzyLookupController(_mamdani(), 11), 0, 2, _fuzzy_inputs,
     {"controller": lambda r, B: [_mamdani(Ke) for Ke in r.uniform(0.5, 4.0, B)]}),
]


def _compiled_per_run(fn, t, x, u, P, width):
    jit = _kernels._jit(fn)
    out = np.empty((x.shape[0], width))
    for b in range(x.shape[0]):
        jit(t, x[b], u[b], P if P.ndim == 1 else P[b], out[b])
    return out


# 40 runs: a kernel that branches per value runs row by row in Python; from ROWS_COMPILED_MIN on, compiled
@pytest.mark.parametrize("B", [40, ROWS_COMPILED_MIN + 6], ids=["python-rows", "compiled-rows"])
@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_derived_batched_methods_equal_the_compiled_kernels_bit_for_bit(case, B):
    _, make, n, m, draw, per_run = case
    block = make()
    rng = np.random.default_rng(11)
    t = 3.0
    x, u = draw(rng, B, n, m)
    assert block.kernel_params.ndim == 1 and x.shape[1] == block.n_states and u.shape[1] == len(block.inputs)
    rows = np.stack([block.with_params(**{k: g(rng, 1)[0] for k, g in per_run.items()}).kernel_params
                     for _ in range(B)])
    kinds = [("output", len(block.outputs))]
    for kind in ("update", "rhs"):
        if getattr(block.kernels, kind) is not None:
            kinds.append((kind, n))
    for P in (block.kernel_params, rows) if per_run else (block.kernel_params,):  # rows: run-time values
        for kind, width in kinds:
            numpy_out = block.batched(kind, t, x, u, P)
            compiled = _compiled_per_run(getattr(block.kernels, kind), t, x, u, P, width)
            assert np.array_equal(numpy_out, compiled, equal_nan=True), (kind, P.ndim)
