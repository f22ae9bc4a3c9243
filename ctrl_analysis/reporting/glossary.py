"""The glossary of REPORT.md: every term the report uses, listed at its end when it occurs."""

from __future__ import annotations

import re

__all__ = ["GLOSSARY", "glossary_lines"]

#: Terms the report uses; a term is listed when it occurs in the report.
GLOSSARY = {
    "agrees / differs": "the paper's value lies inside / outside the reproduced band: the central 95 % of the Monte "
                        "Carlo runs for a number from one noisy simulation, half a unit of the last printed digit "
                        "(the relative tolerance shown; |value − paper| / |paper|, element-wise maximum for vectors) "
                        "for a deterministic one. *Differs* means no point of the plausible box reaches it.",
    "reachable": "the paper's value lies outside the band at the chosen reconstructions but inside it at some other "
                 "point of the plausible box (the point is recorded): the paper's number is consistent with a value "
                 "it does not print.",
    "new": "a quantity the paper does not print (a sweep, an ablation, a claim put into numbers).",
    "diverged": "at least half the runs of that quantity diverged (a state left the divergence bound); the "
                "count is shown.",
    "percentile": "for a number from one noisy simulation, the share of the reproduced Monte Carlo runs below "
                  "the paper's value (p = 50 % is the median run).",
    "lost in extraction": "a cell the paper printed whose value did not survive the extraction of the paper's "
                          "text from its PDF; reproduced without a verdict.",
    "check": "an algebraic identity or a check of the paper's own arithmetic, listed apart from the reproduced "
             "cells and never counted as a reproduction.",
    "claim": "a statement the paper makes (a comparison, a ranking, a property), judged on computed quantities "
             "over the plausible box: holds, fails, depends (its support lies between the policy's thresholds), "
             "or untestable (the measure is below its own noise floor, or the method cannot run as printed).",
    "support": "the share of the plausible box (a Latin hypercube sample, all reconstructions varied jointly) where a "
               "claim holds, with its binomial standard error.",
    "plausible box": "the product of the plausible ranges of a study's reconstructions, printed values fixed; "
                     "every claim and printed cell is judged over it.",
    "Sobol' index": "first-order variance-based sensitivity index: the share of the variance of a claim's verdict "
                    "(1 holds, 0 fails) over the box explained by one reconstruction alone (SALib's RBD-FAST on "
                    "the box sample); a reconstruction drives a verdict when its index is at least 0.05 and above "
                    "what chance reaches (the largest index when the verdicts are shuffled, 95th percentile).",
    "nearest flip": "the point of the plausible box nearest the chosen values where a claim's verdict changes, "
                    "located by bisection between the chosen point and the nearest sample of the other verdict.",
    "algorithm axis": "the paper's printed algorithm against the project's correction of it; each claim is "
                      "judged under both, and the scorecard says when it holds only with one.",
    "beyond the paper": "a test the project adds (e.g. a tuning-fair comparison the paper never made), judged like "
                        "a claim but not counted among the paper's.",
    "plausible range": "the values of a reconstruction a reader of the paper could reasonably have chosen; "
                       "together they span the plausible box.",
    "paper text": "the text extracted from the paper's PDF (shared/seeds/), from which the study was built.",
    "paper cell": "one number printed in the paper (a table entry or a value in the text). A cell may be "
                  "reproduced under several readings; the headline counts score it once, by its primary reading.",
    "primary reading": "the reading of an ambiguous method the study considers the paper's intent; the other "
                       "readings of the same cell are listed but not counted.",
    "reconstruction": "a value or choice the paper does not print (or prints wrongly), chosen by the study "
                      "and justified.",
    "state reading": "reading an estimator's output as its state vector (x̂ = z) rather than the corrected "
                     "output formula the paper prints.",
    "literal": "the method run exactly as printed, even where that is ill-posed or diverges.",
    "well-posed": "the smallest change to the printed method that makes it solvable (e.g. a regression "
                  "whose columns are identifiable), used as the primary reading when the literal one fails.",
    "predictor form": "a Kalman filter written with the one-step prediction x̂(k+1|k) as its state.",
    "DWNA": "discrete white-noise acceleration: the process-noise model of an α-β tracker, Q = σ² G Gᵀ "
            "with G = [T²/2, T]ᵀ.",
    "Kalata index": "the tracking index Λ = σ_w T² / σ_v of an α-β filter, which fixes its steady-state "
                    "gains (α, β).",
    "PPD": "pseudo-partial derivative φ(k) of MFAC's compact-form dynamic linearisation, "
           "Δy(k+1) = φ(k) Δu(k), estimated on line.",
    "CFDL": "compact-form dynamic linearisation, the data model behind MFAC.",
    "MFAC": "model-free adaptive control (Hou): a controller built on the CFDL data model and its "
            "estimated PPD.",
    "TD": "tracking differentiator (Han): a nonlinear filter giving a smoothed signal and its derivative.",
    "IKF": "the improved Kalman filter of the ikf-mfac paper, a scalar random-walk Kalman filter on the "
           "measured output.",
    "CKF": "characteristic-model-based Kalman filter: a Kalman filter on the second-order characteristic "
           "model x(k) = f1 x(k−1) + f2 x(k−2) + g0 u(k−1) whose coefficients are identified on line.",
    "LPF": "low-pass filter.",
    "RLS": "recursive least squares (with forgetting factor λ).",
    "ESO": "extended state observer (Han): an observer whose extra state estimates the total disturbance.",
    "LESO": "linear ESO with gains in bandwidth form, poles at −ω_o.",
    "MESO": "modified ESO (meso paper): an ESO with a model term XᵀΘ whose parameters Θ are identified by "
            "least squares (LSM) on batches of data, so its extended state only carries what the model misses.",
    "ARE / DARE": "algebraic / discrete algebraic Riccati equation, whose solution gives a Kalman filter's "
                  "steady-state gain.",
    "α-β filter": "a two-state (position, rate) tracking filter with constant gains α and β.",
    "RK4": "the classical fourth-order Runge-Kutta integrator (fixed step).",
    "ZOH": "zero-order hold: a sampled signal held constant over each sampling period.",
    "LSM": "least-squares method (batch identification).",
    "fal": "Han's nonlinear gain function fal(e, α, δ): |e|^α sign(e) outside |e| < δ, linear inside.",
    "Σ": "the differential state estimator of the differential-estimator paper, a chain of integrators "
         "with poles designed at the root-locus breakaway point.",
    "est_xi / track_xi": "the meso tables' columns: mean |estimation error| of x_i, and mean |tracking error| of "
                         "x_i, over the run.",
    "RMSE": "root-mean-square error.",
    "NESO": "nonlinear ESO: an ESO whose correction terms use Han's fal function instead of linear gains.",
    "D-MFAC": "the ikf-mfac paper's disturbance-rejection MFAC: CFDL-MFAC with a disturbance-compensation term "
              "re-armed by the band rule (36).",
    "trajectory-equivalent Θ": "a parameter vector Θ that gives the same model output XᵀΘ along the simulated "
                               "trajectory as the true one, although it differs from it, because the regressor "
                               "columns are (nearly) collinear there.",
    "column-scaled condition number": "the condition number of a regression matrix after scaling each column to "
                                      "unit norm: it measures collinearity, not the columns' units.",
    "breakaway point": "the point on the real axis where two branches of a root locus meet and leave it; Σ's gain "
                       "is chosen there so its poles are real and repeated.",
    "golden-section law": "the characteristic-model controller u_l = −(l1 f1 e(k) + l2 f2 e(k−1)) / g0 with the "
                          "golden-section coefficients l1 = 0.382, l2 = 0.618.",
    "SNR": "signal-to-noise ratio, 10 lg(Σ y*² / Σ e²) in dB.",
    "mean ± std": "mean and standard deviation over the Monte Carlo runs that did not diverge.",
}


#: Patterns of glossary terms whose name is not the text they stand for.
_GLOSSARY_PATTERNS = {"est_xi / track_xi": r"(?:est|track)_x\d", "Kalata index": r"Kalata"}


def glossary_lines(text: str) -> list[str]:
    """The report's glossary: the terms of :data:`GLOSSARY` that occur in ``text`` (or in their definitions).

    Parameters
    ----------
    text : str
        The report's text.

    Returns
    -------
    list of str
        Markdown lines (empty when no term occurs).
    """
    if not isinstance(text, str):
        raise TypeError(f"text must be a string, got {type(text).__name__}")
    def used_in(term):
        if term in _GLOSSARY_PATTERNS:
            return re.search(_GLOSSARY_PATTERNS[term], text)
        return any(re.search(rf"(?<![A-Za-z]){re.escape(t.strip())}(?![A-Za-z])", text) for t in term.split("/"))

    used = [(term, what) for term, what in GLOSSARY.items() if used_in(term)]
    # terms the listed definitions themselves use (e.g. MFAC's CFDL and PPD)
    text = text + " " + " ".join(what for _, what in used)
    used = [(term, what) for term, what in GLOSSARY.items() if used_in(term)]
    if not used:
        return []
    return ["## Glossary", "", *[f"- **{term}**: {what}" for term, what in used], ""]


