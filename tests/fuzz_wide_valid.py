"""The generated inputs of tests/fuzz_wide.py that are valid, each with the reason (not bad inputs: accepted).

A generic bad value is bad for most arguments and valid for some: a negative number is a valid initial state,
zero a valid count of past outputs, a complex number a valid point of the s-plane. Each rule below names the
arguments (``"label.arg"``, the label of the starting point in tests/lib/test_fuzz_api.py or fuzz_wide's
engine paths) and the value classes (tags of :func:`fuzz_wide.bad_values`) it makes valid, and says why.
Everything accepted that no rule lists is counted as silent nonsense.
"""

from __future__ import annotations

SIGNAL = "a signal or data value: any real number, negative and zero included, and a record of any length"
MATRIX = "a system or data matrix: entries of any sign (and zero) are valid"
OFFSET = "an initial value, an offset, a start time or a limit: any finite real number (negative, zero) is valid"
GAIN_ANY_SIGN = "documented as any finite real (the table fuzzes it as REAL): zero and negatives are valid"
NONNEG = "documented >= 0: zero is valid"
VECTORISED = "vectorised: an array of values gives an array of answers (documented)"
TEXT = "free text (a name, a label, a description, an id): any string is valid, '' where the default is ''"
NAMES = "signal names are free: any non-empty names are valid, and any number of them"
DEFAULT_NONE = "None is the argument's documented default (the starting call gave another value)"
PROPAGATES = ("per-sample arithmetic on arrays, unchecked by design like rhs/update: NaN and inf of a diverged "
              "run propagate element-wise, and the engine flags that run as diverged")
DIVERGED_SIGNAL = ("a recorded signal: NaN/inf mark a diverged run (check_array's documented rule) and give a "
                   "NaN answer, which the studies count as diverged")
COUNT_ZERO = "a count documented from 0 (no past outputs, no signals, no refinement)"
LARGER_THAN_WORK = ("larger than the work: clipped to it (one chunk for the whole batch, one worker per chunk, "
                    "iterations stop at convergence); nothing is allocated by its size")
SEED = "any non-negative integer is a valid seed (numpy's SeedSequence takes integers of any size)"
BOUND_INF = "inf is documented: no bound (no divergence test, no saturation, an unbounded parameter)"
BOUND_TINY = ("any positive bound is valid; every run passes it and is flagged diverged, its NaN the documented "
              "marker")
VECTOR_SHAPE = ("a vector given as a row, a column or with extra length-1 axes holds the same n entries "
                "(read with np.ravel, deliberately)")
ANY_LENGTH = "any length is valid: no other argument fixes it (a polynomial's order, a number of zeros or poles)"
ANY_VALUE = "any value is valid there: the function stores, formats or passes it on without arithmetic"

#: ``(reason, tags, places)``: ``tags`` space-separated, ``places`` ``"label.arg"`` (the label may hold dots).
RULES = [
    # symbolic and polynomials
    ("a point of the s-plane: complex, negative or zero values are valid (vectorised)",
     "complex list negative zero", ["locus_gain.s_value"]),
    ("a symbolic expansion: any numbers, complex included, are valid zeros and gains, any number of zeros",
     "complex negative zero longer shorter", ["coefficients_from_zeros.zeros", "coefficients_from_zeros.gain"]),
    (ANY_LENGTH, "longer shorter", ["bandwidth_match.beta", "hurwitz_roots.K", "gains_from_poles.poles",
                                    "HighOrderDifferentialFeedback.K"]),
    (VECTORISED, "list", ["second_order_gain.a21", "second_order_gain.q", "random_walk_gain_closed_form.q",
                          "kalata_gains_closed_form.Lambda", "random_walk_gain.Q", "random_walk_gain.R",
                          "tracking_index.sigma_w", "tracking_index.sigma_v", "tracking_index.T",
                          "tracking_index_from_gains.alpha", "tracking_index_from_gains.beta", "kalata_gains.Lambda",
                          "alpha_beta_gamma_gains.Lambda", "fal.e", "fal.alpha", "fhan.x1", "fhan.x2",
                          "PDFeedforward.control.f_hat", "gaussian_noise.std", "lower_bound.eps", "lower_bound.L",
                          "printed_tolerance.paper", "compute_verdict.value", "compute_verdict.paper",
                          "relative_error.value", "relative_error.paper"]),
    ("the entry a21 of the system matrix: any real number", "negative zero", ["second_order_gain.a21"]),
    (NONNEG, "zero", ["random_walk_gain_closed_form.q", "kalata_gains_closed_form.Lambda", "random_walk_gain.Q",
                      "tracking_index.sigma_w", "kalata_gains.Lambda", "continuous_steady_state.Q",
                      "continuous_steady_state_gain.Q", "care_residual.Q", "riccati_trajectory.Q", "dare_residual.Q",
                      "discretize_noise.Q", "ImprovedKalmanFilter.Q", "ImprovedKalmanFilter.P0",
                      "CharacteristicKalmanFilter.Q", "LinearKalmanFilter.Q", "GoldenSectionController.k_I",
                      "GoldenSectionController.mu", "gaussian_noise.std", "check_result_memory.nbytes",
                      "Quantity.tolerance", "StudyResult.quantity.tolerance", "compute_verdict.tolerance",
                      "Quantity.runs_diverged", "Setup.transient", "claim_verdict.support"]),
    (COUNT_ZERO, "zero", ["repeated_pole_coefficients.m", "signal_names.n", "LowPassFilter.derivative_tf.k",
                          "ArxRegressor.na", "ArxRegressor.nb", "ArxRegressor.lag", "continuous_nlsys.states",
                          "continuous_nlsys.inputs", "bar.total", "updater.total", "digits_tolerance.decimals",
                          "explore.refine", "explore.cell_steps", "explore.search_rounds", "set_context.position",
                          "LoopResponse.to_timeresponse.run", "adversarial_error.k_from", "tune_family.rounds",
                          "ArenaSettings.rounds", "family_chain.rounds"]),
    # blocks and loops
    ("a static block without inputs is a source; its names are free, and fn's widths are checked when it runs",
     "empty unknown longer", ["FunctionBlock.inputs", "FunctionBlock.outputs"]),
    (NAMES, "unknown", ["StaticGain.inputs", "StaticGain.outputs", "place.inputs", "place.outputs",
                        "mfac_controller.measured", "mfac_controller.reference", "mfac_controller.control"]),
    (MATRIX, "negative", ["StaticGain.D"]),
    (TEXT, "unknown empty",
     ["signal_names.base", "place.name", "DiscreteBlock.nlsys.name", "ContinuousBlock.nlsys.name",
                             "Loop.interconnect.name", "StudyInfo.name", "StudyInfo.seed_file", "StudyInfo.paper",
                             "StudyInfo.reproduces", "Quantity.id", "Quantity.label", "Quantity.unit", "Quantity.cell",
                             "StudyResult.quantity.id", "StudyResult.quantity.label", "StudyResult.quantity.unit",
                             "StudyResult.reconstruction.name", "StudyResult.reconstruction.why",
                             "StudyResult.finding.id", "StudyResult.finding.text", "Claim.id", "Claim.section",
                             "Claim.statement", "span.why", "Plausible.why", "choices.why", "fixed.why",
                             "algorithm.why",
                             "printed.where", "reconstructed.why", "record_parameters.prefix", "ClaimResult.note",
                             "ClaimResult.evidence", "caption.detail", "glossary_lines.text", "write.message",
                             "bar.desc", "bar.unit", "updater.desc", "updater.unit", "map_chunks.desc",
                             "map_chunks.unit", "drive.desc", "drive.unit",
                             "set_context.label", "write_text_atomic.text", "Case.signal", "Case.noise",
                             "register_signal_class.description", "register_signal_class.bound_how",
                             "register_signal_class.name", "ClaimCheck.statement", "ClaimCheck.how"]),
    ("python-control names the system itself when name is None (its documented default)", "none",
     ["DiscreteBlock.nlsys.name", "ContinuousBlock.nlsys.name", "Loop.interconnect.name"]),
    ("dt=True is python-control's 'discrete, period unspecified' (the documented default)", "bool",
     ["DiscreteBlock.nlsys.dt"]),
    (DEFAULT_NONE, "none", ["Loop.simulate.runs", "Loop.simulate.params", "Loop.simulate[compiled].runs",
                            "Loop.simulate[auto].runs", "LowPassFilter.digital.initial",
                            "DifferentialEstimator.nlsys.reading", "StudyResult.quantity.runs",
                            "StudyResult.quantity.tolerance", "StudyContext.runs_or.quick_default",
                            "compute_verdict.tolerance", "ClaimResult.holds", "claim_verdict.support",
                            "mean_abs_error.axis", "rmse.axis", "snr_db.axis", "overshoot.axis", "plausible_text.p",
                            "StudyResult.quantity.paper", "compute_verdict.paper"]),
    ("a loop that exposes no outputs (interconnect then has none) is valid", "empty", ["Loop.outputs"]),
    ("keep=() stores no signal (only the states, or nothing), documented", "empty", ["Save.keep"]),
    ("Save does not know the loop: any names are a valid keep; Loop.simulate refuses one that is not a signal "
     "of its loop (tests/lib/test_engine_policies.py)", "longer shorter", ["Save.keep"]),
    (OFFSET, "negative zero", ["Loop.simulate.t0", "Loop.simulate[compiled].t0", "Loop.simulate[auto].t0",
                               "LowPassFilter.digital.initial", "DiscreteLowPass.initial",
                               "ImprovedKalmanFilter.y0", "CFDLPredictor.phi0", "CFDLPredictor.u0", "CFDLPredictor.u00",
                               "PPDEstimator.y0", "PPDEstimator.u0", "UnitDelay.u0", "mfac_controller.u0",
                               "DiscretePID.u_min", "DiscretePID.u_max", "uniform_noise.low", "uniform_noise.high",
                               "gaussian_noise.mean", "overshoot.final", "overshoot.initial", "settling_time.initial",
                               "adversarial_pair.slope", "span.low", "TrackingDifferentiator.x0",
                               "AlphaBetaFilter.b", "AlphaBetaFilter.x0", "DiscreteKalmanFilter.b",
                               "DiscreteKalmanFilter.x0", "CharacteristicKalmanFilter.x0", "LinearKalmanFilter.x0",
                               "RecursiveLeastSquaresBlock.theta0", "RecursiveLeastSquaresBlock.lower",
                               "RecursiveLeastSquaresBlock.upper", "RecursiveLeastSquaresBlock(bounds).lower",
                               "RecursiveLeastSquares.theta0", "RecursiveLeastSquares.lower",
                               "RecursiveLeastSquares.upper", "simulate_ivp.x0", "Layout.pack.a", "Layout.pack.b",
                               "digits_tolerance.paper",
                               "printed_tolerance.paper", "compute_verdict.value", "compute_verdict.paper",
                               "relative_error.value", "relative_error.paper", "Quantity.value", "Quantity.paper",
                               "StudyResult.quantity.value", "StudyResult.quantity.paper", "printed.value",
                               "reconstructed.value"]),
    (BOUND_INF, "inf -inf inf-entry", ["Execution.bound", "Loop.simulate[compiled].bound", "Loop.simulate[auto].bound",
                                       "simulate_ivp.bound",
                                       "DiscretePID.u_min", "DiscretePID.u_max", "Layout.pack.a", "Layout.pack.b",
                                       "RecursiveLeastSquaresBlock.upper", "RecursiveLeastSquaresBlock(bounds).upper",
                                       "RecursiveLeastSquares.upper", "pareto_front.points"]),
    (BOUND_TINY, "tiny", ["Execution.bound", "Loop.simulate[compiled].bound", "Loop.simulate[auto].bound"]),
    (LARGER_THAN_WORK, "giant huge", ["Execution.chunk_runs", "Execution.jobs", "chunk_bounds.size",
                                      "discrete_steady_state_batch.max_iter", "chunk_slices(large n).chunk_size",
                                      "chunk_slices.chunks", "chunk_slices.chunk_size", "map_chunks.jobs",
                                      "monte_carlo.jobs", "monte_carlo.chunk_size", "sweep.jobs", "sweep.chunk_size",
                                      "StudyContext.jobs", "explore.jobs", "tune_family.jobs", "tune_families.jobs",
                                      "plot_sensitivity.top",
                                      "drive.jobs", "family_chain.jobs", "simulate_registered.jobs",
                                      "bar.total", "updater.total", "set_context.position"]),
    ("a count of runs, stored and used lazily (chunk_slices only computes slice bounds)", "giant",
     ["chunk_slices(large n).n", "chunk_slices.n", "Quantity.runs", "StudyResult.quantity.runs"]),
    (SEED, "zero giant huge", ["run_seeds.base_seed", "StudyContext.seed", "make_signal.seed", "add_noise.seed",
                               "native_bound.seed"]),
    # estimators
    (PROPAGATES, "nan inf -inf nan-entry inf-entry negative zero",
     ["fal.e", "fhan.x1", "fhan.x2", "PDFeedforward.control.ref", "PDFeedforward.control.x_hat",
      "PDFeedforward.control.f_hat", "HighOrderDifferentialFeedback.u.theta", "HighOrderDifferentialFeedback.u.x_hat",
      "DifferentialEstimator.estimates.z", "DifferentialEstimator.estimates.y"]),
    ("fal is defined for any real exponent: 0 is the sign function, negatives grow near 0 (the table's rule)",
     "negative zero", ["fal.alpha", "ExtendedStateObserver.alpha"]),
    ("x_hat may hold more than n entries (the extended state after them), documented", "longer",
     ["HighOrderDifferentialFeedback.u.x_hat"]),
    (GAIN_ANY_SIGN, "negative zero", ["ExtendedStateObserver.b0", "PDFeedforward.b0", "PDFeedforward(gains).b0",
                                      "DiscretePID.kp", "DiscretePID.ki", "DiscretePID.kd", "DiscretePID.Tf",
                                      "alpha_beta_from_gain.K", "gain_from_alpha_beta.alpha",
                                      "gain_from_alpha_beta.beta", "alpha_beta_stable.alpha", "alpha_beta_stable.beta",
                                      "tracking_index_from_gains.beta", "hurwitz_roots.K", "gains_from_poles.poles"]),
    ("a filter of several channels takes (N,), (N, channels) or (N, B, channels) records of any length",
     "extra-dims negative longer shorter", ["DiscreteLowPass.filter.u"]),
    ("u of shape (N, B, m) is documented: N samples of B runs of m inputs", "extra-dims", ["DiscreteBlock.run.u"]),
    ("a value or a printed value may be an array (documented array_like)", "list",
     ["Quantity.value", "Quantity.paper", "StudyResult.quantity.value", "StudyResult.quantity.paper"]),
    ("samples of any shape are read as one flat sample (np.ravel, documented)", "extra-dims",
     ["central_interval.samples"]),
    (SIGNAL, "zero", ["RecursiveLeastSquares.step.z"]),
    (TEXT, "unknown", ["check_result_memory.where"]),
    ("a single name is one scalar field (Layout('x'))", "str", ["Layout(*fields).fields"]),
    (SIGNAL, "negative longer shorter", ["DiscreteBlock.run.u", "softened_setpoint.r", "RecursiveLeastSquares.step.h",
                                         "RecursiveLeastSquares.step.z", "RecursiveLeastSquares.run.H",
                                         "RecursiveLeastSquares.run.z", "identifiability.H", "batch_least_squares.H",
                                         "batch_least_squares.z", "algebraic_derivative.y", "make_signal.t",
                                         "add_noise.f", "estimate.y", "estimate(algebraic).y", "param_values.z",
                                         "native_bound.t", "resonance_peak.omega", "riccati_trajectory.t",
                                         "simulate_ivp.t_eval", "central_interval.samples", "pareto_front.points",
                                         "FuzzyController.evaluate.e", "FuzzyController.evaluate.ec", "mean_std.values",
                                         "Loop.simulate[numpy, per-run params].y_m",
                                         "Loop.simulate[compiled, per-run params].y_m"]),
    ("a system of another order or with more outputs: the first-order plant's state is one entry, a C or H of "
     "two rows is two outputs, a batch of two F is a batch", "shorter longer",
     ["DiscreteBlock.run.x0", "DiscreteLTI.x0", "observability_matrix.C", "observability_rank.C",
      "check_observable.C", "check_detectable.C", "discrete_steady_state_batch.F", "simulate_ivp.x0",
      "draw_noise.seeds"]),
    (MATRIX, "negative", [f"{f}.{m}" for f, ms in {
        "controllability_matrix": "AB", "observability_matrix": "AC", "controllability_rank": "AB",
        "observability_rank": "AC", "check_controllable": "AB", "check_observable": "A", "check_detectable": "AC",
        "continuous_steady_state": "ACG", "continuous_steady_state_gain": "ACG", "care_residual": "ACGP",
        "riccati_trajectory": "ACG", "discrete_steady_state": "FHG", "dare_residual": "FHG",
        "discretize_noise": "AG", "DiscreteKalmanFilter": "F", "LinearKalmanFilter": "F"}.items() for m in ms]
     + ["discrete_steady_state_batch.F", "discrete_steady_state_batch.H", "dare_residual.P_prior",
        "DiscreteKalmanFilter.h", "LinearKalmanFilter.G", "LinearKalmanFilter.H"]),
    (VECTOR_SHAPE, "extra-dims", ["TrackingDifferentiator.x0", "AlphaBetaFilter.b", "AlphaBetaFilter.x0",
                                  "DiscreteKalmanFilter.h", "DiscreteKalmanFilter.b", "DiscreteKalmanFilter.x0",
                                  "CharacteristicKalmanFilter.x0", "LinearKalmanFilter.G", "LinearKalmanFilter.H",
                                  "LinearKalmanFilter.x0", "alpha_beta_from_gain.K"]),
    ("sum_rule_table's sign is +1 or -1 (documented)", "negative", ["sum_rule_table.sign"]),
    ("input_range may be one range or a pair (e, ec), documented", "list", ["FuzzyController.input_range"]),
    ("n_points may be one count or a pair (n_e, n_ec); [3] is one count for both axes", "list",
     ["FuzzyLookupController.n_points"]),
    ("evaluate is element-wise on arrays of any shape", "extra-dims",
     ["FuzzyController.evaluate.e", "FuzzyController.evaluate.ec"]),
    # metrics
    (DIVERGED_SIGNAL, "nan-entry inf-entry", ["mean_abs_error.x", "mean_abs_error.x_hat", "rmse.reference", "rmse.y",
                                              "snr_db.reference", "snr_db.y", "overshoot.y", "settling_time.y",
                                              "mean_std.values"]),
    (SIGNAL, "negative", ["mean_abs_error.x", "mean_abs_error.x_hat", "rmse.reference", "rmse.y", "snr_db.reference",
                          "snr_db.y", "overshoot.y", "settling_time.y"]),
    ("numpy's axis convention: negative axes count from the end, 0 is the first", "negative zero",
     ["mean_abs_error.axis", "rmse.axis", "snr_db.axis", "overshoot.axis", "settling_time.axis", "mean_std.axis"]),
    ("a response of several runs along other axes, of any length: overshoot takes any shape along axis",
     "extra-dims longer shorter", ["overshoot.y", "mean_std.values", "settling_time.y"]),
    ("t is documented unused by overshoot (kept for a signature shared with settling_time); any real array",
     "none empty extra-dims nan-entry inf-entry negative longer shorter", ["overshoot.t"]),
    ("a final value the response never settles to: the documented answer is NaN (never settles)",
     "negative huge -huge tiny", ["settling_time.final"]),
    ("a drop of -3 dB is the default; any drop in [-300, 0) is valid", "negative", ["bandwidth_3db.dbdrop"]),
    # reporting
    ("any immutable value is a valid field default (numbers, strings, None, NaN): the field stores it",
     "none str complex bool nan inf -inf", ["printed.value", "reconstructed.value"]),
    ("a missing (None) or non-finite reproduced value is documented: it differs from the paper, or marks runs "
     "that all diverged", "none nan inf -inf", ["compute_verdict.value", "relative_error.value", "Quantity.value",
                                                "StudyResult.quantity.value"]),
    ("the paper does not print it: None means a new quantity, documented", "none", ["compute_verdict.paper",
                                                                                     "StudyResult.quantity.paper"]),
    ("a zero or non-finite printed value gets the default tolerance (documented)", "nan inf -inf",
     ["printed_tolerance.paper"]),
    (ANY_VALUE, "none int float empty unknown bytes", ["algorithm.printed", "algorithm.corrected"]),
    ("options may be alternatives of any kind and any number", "extra-dims nan-entry inf-entry str-entry complex "
     "negative longer shorter", ["choices.options"]),
    (ANY_VALUE, "none str empty extra-dims nan-entry inf-entry str-entry complex negative longer shorter",
     ["summarise.value"]),
    (ANY_VALUE, "empty extra-dims nan-entry inf-entry huge-entry complex negative longer shorter str-entry",
     ["map_chunks.args"]),
    ("a path that does not exist yet is created; any non-empty name is valid", "unknown",
     ["StudyContext.out_dir", "StudyContext.save_figure.filename"]),
    ("an empty selection of names explores no dimension (the claims judged at the chosen point only)", "empty",
     ["explore.names", "Box.names"]),
    ("evidence is a tuple of quantity ids of any length", "empty unknown longer", ["ClaimResult.evidence"]),
    ("signals a claim check names are free (checked against the arena's table when judged)", "empty unknown longer",
     ["ClaimCheck.signals"]),
    ("a results dict of any content: unknown keys are ignored by these readers", "unknown",
     ["arena_report_lines.results", "arena_claim_links.results", "judge_claims.table", "grid_points.grid"]),
    ("a registered signal class's name is checked by make_signal when used", "unknown", ["native_bound.kind"]),
    # the arena's record check (issue 28), fuzzed after this list was made
    (TEXT + ": the record's name in the messages", "unknown empty", ["check_record.where"]),
    ("two free-text names of the bounds for the messages (None: 'eps', 'L'); the generated 'longer' value is two",
     "longer", ["check_record.names"]),
    ("a record of any length from 4 samples on: without d1 nothing else fixes its length", "shorter longer",
     ["record_estimates.y"]),
    # the last findings of the generated fuzz (issue 28: the arena, ctrl_analysis/runs/parallel.py)
    (SIGNAL, "negative", ["record_estimates.y"]),
    (SIGNAL + " (a measurement and its derivative)", "negative", ["estimated_bounds.y", "estimated_bounds.d1"]),
    ("a quantile level in [0, 1] (documented): 0 is the smallest value seen", "zero", ["Quantiles.quantile.q"]),
    (("an estimate of f' may be any real number; NaN/inf of a diverged estimator give a NaN/inf error (documented: "
      "'a diverged estimator's error is not finite')"), "negative nan-entry inf-entry", ["adversarial_error.est_d1"]),
    ("a batch of any number of seeds (at least one): one run per seed", "longer shorter",
     ["monte_carlo.seeds", "sweep.seeds"]),
    ("a grid's parameter names are free (fn reads the names the grid gives); a single number is one value",
     "unknown", ["sweep.grid"]),
    ("what to simulate ahead: no class or no seed is nothing to do, a seed given twice is simulated once, and "
     "a record of any length from 2 samples is valid", "empty longer",
     ["simulate_registered.kinds", "simulate_registered.seeds"]),
    ("a record of any length from 2 samples is valid", "shorter", ["simulate_registered.t"]),
    # streaming accumulators
    ("a chunk of any number of runs (runs on axis 0): fewer runs than the starting chunk is a smaller chunk",
     "shorter longer", ["Moments.add.values", "Quantiles.add.values", "Histogram.add.values",
                        "Keep.add.values"]),
    (SIGNAL + ": a run's value or trace (an error, a state) of either sign", "negative",
     ["Moments.add.values", "Quantiles.add.values", "Histogram.add.values", "Keep.add.values"]),
    ("Keep keeps the chosen runs' traces as they are, NaN and inf included (documented): a figure draws "
     "a diverged run too", "inf-entry nan-entry", ["Keep.add.values"]),
    ("documented: the bound for 0 runs is 0 (an empty accumulator)", "zero", ["Quantiles.error_bound.n",
                                                                              "Quantiles.bytes_bound.n"]),
    ("documented: NaN where count <= ddof, as numpy's var with too few values (a valid question, no answer)",
     "huge giant", ["Moments.var.ddof"]),
    ("vectorised: a list of quantiles (or percentiles) gives one answer each, as numpy's quantile does",
     "list longer shorter", ["Quantiles.quantile.q", "Quantiles.percentile.p"]),
    ("the bound on a sketch's bytes for n runs is an integer formula, exact for any n (Python integers): "
     "nothing is allocated by it", "giant huge", ["Quantiles.bytes_bound.n", "Quantiles.error_bound.n"]),
    ("a trailing shape given as one integer is a one-axis shape, numpy's convention (documented); an empty "
     "accumulator's answers are NaN (no runs yet)", "int",
     ["Moments.shape", "Quantiles.shape", "Histogram.shape", "Counts.shape", "Keep.shape"]),
]


import functools


@functools.lru_cache(maxsize=1)
def valid_table() -> dict[tuple[str, str], dict[str, str]]:
    """``{(label, arg): {tag: reason}}`` from :data:`RULES`."""
    table: dict[tuple[str, str], dict[str, str]] = {}
    for reason, tags, places in RULES:
        for place in places:
            label, arg = place.rsplit(".", 1)
            for tag in tags.split():
                table.setdefault((label, arg), {}).setdefault(tag, reason)
    return table
