"""The skeleton's quantities and finding, computed from a :class:`LoopResponse`.

Each quantity gives ``unit`` and, with a paper value, a ``tolerance``; a finding's text is made
from the computed numbers, never typed.
"""

from __future__ import annotations

from ctrl_analysis.metrics import mean_std, rmse
from ctrl_analysis.reporting.report import StudyResult

from .loops import steady_window
from .paper import CLAIMS, Example

__all__ = ["judge_claims", "record_noise", "record_step"]


def record_step(result: StudyResult, p: Example, res) -> None:
    """Plant output at ``t = τ`` against the printed ``1 − e^−1`` (deterministic: noise is not fed back).

    Parameters
    ----------
    result : StudyResult
    p : Example
    res : LoopResponse
    """
    k = round(p.tau / p.h)
    value = float(res["y"][k, 0])
    result.quantity("step.y_at_tau", "plant output y(τ) for a unit step", value, paper=p.y_at_tau,
                    tolerance=1e-3, unit="", note="RK4 with the loop's step; the paper rounds to 4 digits")


def record_noise(result: StudyResult, p: Example, res) -> None:
    """Steady-state RMS of ``ŷ − y`` over the runs, against the printed ``σ_v √((1 − a)/(1 + a))``.

    In steady state ``ŷ − y`` is the filtered noise (zero mean), so its RMS estimates the std
    without subtracting a sample mean (which biases the std of a correlated record low).
    Diverged runs are excluded (there are none in this linear loop, but the count is reported).

    Parameters
    ----------
    result : StudyResult
    p : Example
    res : LoopResponse
    """
    w = steady_window(p, res)
    per_run = rmse(res["y"][w], res["y_hat"][w])
    mean, std, n_ok = mean_std(per_run, res.ok)
    paper = p.sigma_v * p.noise_ratio
    result.quantity("filter.noise_std", "steady-state RMS of y_hat − y (the filtered noise std)", float(mean),
                    paper=float(paper),
                    std=float(std), runs=n_ok, tolerance=0.05, unit="",
                    note=f"{int(w.sum())} samples per run from t = {p.t_settle:g} s")
    result.finding("noise-reduction",
                   f"the digital low-pass (ω_f = {p.omega_f:g} rad/s, h = {p.h:g} s) reduces the measurement "
                   f"noise std from {p.sigma_v:g} to {mean:.4g} ± {std:.2g} over {n_ok} runs, "
                   f"{mean / paper - 1:+.1%} from the closed form {paper:.4g}")


def judge_claims(result: StudyResult, p: Example) -> None:
    """Judge :data:`~.paper.CLAIMS` on the recorded quantities (the same code for the run and the sweep).

    Parameters
    ----------
    result : StudyResult
        With ``filter.noise_std`` and ``step.y_at_tau`` recorded.
    p : Example
    """
    claims = {c.id: c for c in CLAIMS}
    noise = result.get("filter.noise_std")
    ratio = p.sigma_v / noise.value
    result.claim(claims["filter-reduces-noise"], ratio >= 3.0, evidence=[noise.id],
                 note=f"the filter divides the noise std by {ratio:.3g} at ω_f = {p.omega_f:g} rad/s")
    step = result.get("step.y_at_tau")
    result.claim(claims["step-unaffected"], step.verdict == "agrees", evidence=[step.id],
                 note=f"y(τ) = {step.value:.4f}")
