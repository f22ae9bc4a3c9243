"""Everything the skeleton study takes from its "paper", and every value it had to choose.

The skeleton has no paper: its printed values are textbook closed forms, so the reproduction can
be checked exactly. A real study lists here every number the paper prints (:func:`printed`, with
where) and every number it does not print but the code needs (:func:`reconstructed`, with why),
in one frozen object; quick settings are made with ``dataclasses.replace``, never by editing it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ctrl_analysis.reporting.study import Claim, fixed, printed, reconstructed, span

__all__ = ["CLAIMS", "EXAMPLE", "QUICK", "Example"]

#: What the "paper" claims, judged by :mod:`.quantities` (a real study lists its paper's comparisons,
#: rankings and properties here, with the section).
CLAIMS = (
    Claim("filter-reduces-noise", "textbook, §2",
          "The digital low-pass reduces the measurement noise std at least threefold"),
    Claim("step-unaffected", "textbook, §1",
          "The plant reaches 63 % of a unit step at t = τ whatever the measurement noise"),
)


@dataclass(frozen=True)
class Example:
    """A first-order lag ``1/(τ s + 1)`` driven by a unit step, measured in white noise, low-pass filtered.

    Attributes
    ----------
    tau : float
        Plant time constant (s).
    sigma_v : float
        Standard deviation of the measurement noise.
    h : float
        Sampling period of the loop and of the digital filter (s).
    t_end : float
        Simulated time (s).
    omega_f : float
        Corner frequency of the first-order digital low-pass (rad/s).
    t_settle : float
        Start of the window in which the filtered noise is measured (s).
    y_at_tau : float
        Printed value of the step response at ``t = τ``.
    """

    tau: float = printed(1.0, "textbook: plant 1/(τ s + 1), τ = 1 s")
    sigma_v: float = printed(0.1, "textbook: measurement noise std 0.1")
    h: float = printed(0.01, "textbook: sampling period 10 ms")
    t_end: float = reconstructed(10.0, "horizon not given; 10 τ so that the window after t_settle holds 500 samples",
                                 plausible=fixed("only sets how many steady samples are averaged; no verdict reads "
                                                 "the horizon itself"))
    omega_f: float = reconstructed(10.0, "filter bandwidth not given; 10× the plant bandwidth 1/τ",
                                   plausible=span(3.0, 30.0, "a corner between 3× and 30× the plant bandwidth is "
                                                  "what a textbook design would pick", scale="log", points=5))
    t_settle: float = reconstructed(5.0, "steady state not defined; from 5 τ the filter's lag error "
                                         "ẏ/ω_f < 7e-4 is negligible beside the filtered noise",
                                    plausible=span(3.0, 5.0,
                                                   "3 τ to 5 τ (95 % to 99.3 % of the step) are the usual 'steady "
                                                   "state' choices",
                                                   points=3))
    y_at_tau: float = printed(0.6321, "textbook: unit-step response at t = τ, 1 − e^−1 ≈ 0.6321")

    @property
    def noise_ratio(self) -> float:
        """Printed noise-reduction ratio of the first-order digital low-pass, ``√((1 − a)/(1 + a))``, a = e^(−ω_f h)."""
        a = math.exp(-self.omega_f * self.h)
        return math.sqrt((1.0 - a) / (1.0 + a))


#: The study's settings.
EXAMPLE = Example()
#: ``--quick``: a shorter horizon (the window after ``t_settle`` keeps 100 samples).
QUICK = Example(t_end=6.0)
