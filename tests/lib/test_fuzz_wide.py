"""The generated fuzz (tests/fuzz_wide.py) on a seeded sample, and the fixes it led to, one test each.

The full run (about 7 000 inputs, a minute) is ``python tests/fuzz_wide.py``; here a seeded sample of it runs
with the same watchdog (worker processes, a time limit per call, a memory cap), so a hang or a crash fails
the test instead of stopping the suite.
"""

from __future__ import annotations

import math
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hang import limit

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import fuzz_wide  # noqa: E402

from ctrl_analysis.engine import Execution

SAMPLE = 800


def test_a_seeded_sample_of_the_generated_fuzz_has_no_crash_hang_obscure_or_silent_input():
    with tempfile.TemporaryDirectory() as d:
        cases = [inp for inp, _ in fuzz_wide.generate(Path(d))]
    chosen = fuzz_wide.sample(len(cases), SAMPLE)
    results = fuzz_wide.run(chosen, soft_s=limit(10), hard_s=limit(40), start_s=limit(120))
    counts, findings = fuzz_wide.summary(cases, results)
    print(f"\nfuzz_wide sample: {len(results)} of {len(cases)} inputs: "
          + ", ".join(f"{counts[c]} {c}" for c in fuzz_wide.CLASSES))
    assert len(results) == SAMPLE and counts["crash"] == 0
    listed = [f"{cls} {inp.label}({inp.arg}={inp.shown}) [{inp.tag}]: {detail}" for inp, cls, detail in findings]
    assert not listed, "\n".join(listed)
    assert counts["clear"] >= 0.95 * (len(results) - counts["valid"])


def test_every_valid_rule_names_a_generated_input():
    """A rule of tests/fuzz_wide_valid.py naming no generated argument is stale (a renamed label or argument)."""
    from fuzz_wide_valid import valid_table

    with tempfile.TemporaryDirectory() as d:
        generated = {(inp.label, inp.arg) for inp, _ in fuzz_wide.generate(Path(d))}
    stale = sorted(place for place in valid_table() if place not in generated)
    assert not stale, stale


# -- the fixes, each on its own -----------------------------------------------------------------------------------
def test_sizes_that_would_hang_are_refused_up_front():
    from ctrl_analysis.controllers.fuzzy import FuzzyController, sum_rule_table
    from ctrl_analysis.engine.ivp import continuous_nlsys
    from ctrl_analysis.engine.memory import chunk_bounds
    from ctrl_analysis.noise import draw_noise, gaussian_noise
    from ctrl_analysis.reporting.report import new_figure

    with pytest.raises(ValueError, match="runs=1000000000000 in chunks of size=3"):
        chunk_bounds(10**12, 3)
    with pytest.raises(ValueError, match="nrows must be <= 100"):
        new_figure(nrows=10**4)
    with pytest.raises(ValueError, match="states must be <= "):
        continuous_nlsys(lambda t, x, u, p: -x, states=10**12, inputs=1)
    with pytest.raises(ValueError, match="n_grid must be <= "):
        FuzzyController(sum_rule_table(7), Ke=1.0, Kec=1.0, Ku=1.0, n_grid=10**12)
    with pytest.raises(MemoryError, match=r"draw_noise\(n_steps=1000000000000"):
        draw_noise([1], 10**12, gaussian_noise(1.0))


def test_a_huge_batch_is_refused_before_its_states_are_allocated():
    import control as ct

    from ctrl_analysis import plants
    from ctrl_analysis.engine import loop as loop_mod

    loop = loop_mod.Loop([loop_mod.place(plants.DiscreteLTI(ct.tf([1.0], [1.0, 1.0]), 0.1), "plant")], dt=0.1)
    with pytest.raises(MemoryError, match=r"Loop.simulate\(n_steps=3, runs=1000000000000\)"):
        loop.simulate(3, inputs={"u": 1.0}, runs=10**12, execution=Execution(engine="numpy"))
    with pytest.raises(TypeError, match="seeds must be an integer"):
        loop.simulate(3, inputs={"u": 1.0}, runs=2, seeds=[math.nan, 2], execution=Execution(engine="numpy"))
    with pytest.raises(TypeError, match=r"inputs\['u'\] must be a number"):
        loop.simulate(3, inputs={"u": np.ones(3) + 1j}, execution=Execution(engine="numpy"))


def test_complex_and_bool_values_are_not_real_numbers():
    from ctrl_analysis._validate import check_array, check_finite

    for value in (np.array([1.0 + 1j]), [1 + 2j], True, np.array([True, False]), np.array(["1.0"])):
        with pytest.raises(TypeError, match="x must be"):
            check_finite("x", value)
        with pytest.raises(TypeError, match="x must be"):
            check_array("x", value)
    assert check_array("x", [1, 2]).dtype == float


def test_finite_arguments_that_overflow_are_a_clear_error_naming_them():
    from ctrl_analysis._validate import finite_result
    from ctrl_analysis.estimators.eso import ExtendedStateObserver
    from ctrl_analysis.estimators.lowpass import LowPassFilter
    from ctrl_analysis.metrics import rmse
    from ctrl_analysis.polynomials import repeated_pole_coefficients

    assert finite_result("a", lambda: (np.ones(2), np.ones((2, 3)))) is not None
    with pytest.raises(ValueError, match="a and b overflow"):
        finite_result("a and b", lambda: 1e300 * 1e300)
    with pytest.raises(ValueError, match="omega and order overflow"):
        LowPassFilter(1e300, 2)
    with pytest.raises(ValueError, match="m and omega overflow"):
        repeated_pole_coefficients(3, 1e300)
    with pytest.raises(ValueError, match="n and omega_o underflow"):
        ExtendedStateObserver.from_bandwidth(2, 1e-300)
    with pytest.raises(ValueError, match="reference and y overflow"):
        rmse([1e300, 0.0], [-1e300, 0.0])
    assert rmse([np.nan, 0.0], [0.0, 0.0]) != 0.0  # NaN of a diverged run still gives NaN, not an error


def test_a_stiff_riccati_trajectory_is_refused_in_bounded_time():
    from ctrl_analysis.estimators.kalman.continuous import riccati_trajectory

    args = ([[0.0, 1.0], [-2.0, -3.0]], [[1.0, 0.0]], [[0.0], [1.0]])
    with pytest.raises(ValueError, match="too stiff"):
        riccati_trajectory(*args, 1e300, 0.1, np.eye(2), [0.0, 0.5, 1.0], rtol=1e-6, atol=1e-9)
    P = riccati_trajectory(*args, 1.0, 0.1, np.eye(2), [0.0, 0.5, 1.0])
    assert P.shape == (3, 2, 2) and np.all(np.isfinite(P))


def test_reporting_arguments_are_checked_by_name():
    from ctrl_analysis.reporting import report, study
    from ctrl_analysis.reporting.claims import plausible_text
    from ctrl_analysis.reporting.verdicts import (
        central_interval,
        claim_verdict,
        digits_tolerance,
    )

    with pytest.raises(TypeError, match="out_dir"):
        report.StudyContext(out_dir=None)
    with pytest.raises(ValueError, match="runs must be <= "):
        report.StudyContext(out_dir=".", runs=10**12)
    with pytest.raises(TypeError, match="low must be a real number"):
        study.span("abc", 2.0, "w")
    with pytest.raises(TypeError, match="options must be a tuple or list"):
        study.choices("abc", "w")
    with pytest.raises(ValueError, match="support must be a share"):
        claim_verdict(-1.0, "holds")
    with pytest.raises(TypeError, match="share must be a real number"):
        central_interval([1.0, 2.0], share="x")
    with pytest.raises(ValueError, match="paper must be finite"):
        digits_tolerance(math.nan, 2)
    with pytest.raises(ValueError, match="p must hold options, fixed, or low and high"):
        plausible_text({"nonsense": 1.0})
    with pytest.raises(TypeError, match="value must be a real array"):
        report.Quantity(id="q", label="q", value="abc")
