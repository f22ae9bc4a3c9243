"""The skeleton's loop, built from library blocks and wired by signal names.

::

    u ──> [plant: 1/(τ s + 1)] ──y──> (+) ──y_meas──> [filter: digital low-pass] ──> y_hat
                                       ^
                                       v (measurement noise, one column per run)

The plant is a first-order lag, which the library already has as the order-1
:class:`~ctrl_analysis.estimators.lowpass.LowPassFilter` (``ω/(s + ω)`` with ``ω = 1/τ``): reuse,
do not re-code. The sum is a :class:`~ctrl_analysis.engine.blocks.StaticGain` (so the loop can compile and go to
worker processes; a lambda can do neither).
"""

from __future__ import annotations

import numpy as np

from ctrl_analysis.engine.blocks import StaticGain
from ctrl_analysis.engine.loop import Loop, LoopResponse, place
from ctrl_analysis.estimators.lowpass import LowPassFilter
from ctrl_analysis.noise import draw_noise, gaussian_noise

from .paper import Example

__all__ = ["build_loop", "simulate"]


def build_loop(p: Example) -> Loop:
    """The plant, the noisy measurement and the digital low-pass as one :class:`Loop`.

    Parameters
    ----------
    p : Example
        The study's settings.

    Returns
    -------
    Loop
        External inputs ``u`` (plant input) and ``v`` (measurement noise).
    """
    plant = LowPassFilter(1.0 / p.tau, order=1)
    sensor = StaticGain([[1.0, 1.0]], inputs=("y", "v"), outputs=("y_meas",))  # y_meas = y + v
    lpf = LowPassFilter(p.omega_f, order=1).digital(p.h)
    return Loop([
        place(plant, "plant", inputs=["u"], outputs=["y"]),
        place(sensor, "sensor"),
        place(lpf, "filter", inputs=["y_meas"], outputs=["y_hat"]),
    ], dt=p.h)


def simulate(p: Example, seeds) -> LoopResponse:
    """A unit step into the plant, one run per seed (the noise of run ``b`` drawn from ``seeds[b]``).

    Parameters
    ----------
    p : Example
        The study's settings.
    seeds : sequence of int
        One seed per run.

    Returns
    -------
    LoopResponse
        Signals ``u``, ``y``, ``v``, ``y_meas``, ``y_hat`` of shape ``(N + 1, B)``.
    """
    n_steps = round(p.t_end / p.h)
    v = draw_noise(seeds, n_steps, gaussian_noise(p.sigma_v))[:, :, 0]
    return build_loop(p).simulate(n_steps, inputs={"u": 1.0, "v": v}, seeds=list(seeds))


def steady_window(p: Example, res: LoopResponse) -> np.ndarray:
    """Mask of the sample instants at or after ``p.t_settle`` (the steady state)."""
    return res.t >= p.t_settle - 1e-9
