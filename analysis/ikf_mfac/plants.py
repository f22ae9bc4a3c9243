"""The plants and references of Examples 1 and 2 as discrete blocks and arrays."""

from __future__ import annotations

import math

import numpy as np

from ctrl_analysis.engine.blocks import DiscreteBlock
from ctrl_analysis.engine.kernels import KernelBlock, Kernels, Layout

PLANT = Layout("switch_k")
AT = PLANT.at  # parameter offsets, a numba constant

__all__ = ["SwitchedPlant", "plant_output", "plant_start_state", "plant_update", "reference", "reference_next"]


def plant_update(t, x, u, p, x_next):
    """Eq. (38)/(40) for one run; ``p`` packed by :data:`PLANT`.

    Parameters
    ----------
    t : float
        The paper's sample ``k`` of the update ``y(k) -> y(k+1)``.
    x : numpy.ndarray
        ``(y(k), y(k−1), y(k−2), u(k−1))``.
    u : numpy.ndarray
        ``(u(k),)``.
    p : numpy.ndarray
        ``[switch_k]`` (``inf``: one plant for all ``k``).
    x_next : numpy.ndarray
        Next state, written in place.
    """
    y, y1, y2, u1, uk = x[0], x[1], x[2], x[3], u[0]
    if t <= p[AT.switch_k]:
        x_next[0] = y / (1.0 + y * y) + uk * uk * uk                           # (38)/(40), k <= 500
    else:
        r = 1.0 + math.floor(t / 500.0 + 0.5)                                 # r(k) = 1 + round(k/500)
        x_next[0] = (y * y1 * y2 * u1 * (y2 - 1.0) + r * uk) / (1.0 + y1 * y1 + y2 * y2)  # (38), k > 500
    x_next[1] = y
    x_next[2] = y1
    x_next[3] = uk


def plant_output(t, x, u, p, y):
    """The plant's output ``y(k)``, the first state (kernel).

    Parameters
    ----------
    t, x, u, p
        Time, state, input and parameters of one run.
    y : numpy.ndarray
        Output, written in place.
    """
    y[0] = x[0]


class SwitchedPlant(KernelBlock, DiscreteBlock):
    """Eq. (38) (and (40) with ``switch_k=None``): a SISO plant whose structure changes at ``switch_k``.

    ``y(k+1) = y(k)/(1 + y(k)²) + u(k)³`` for ``k <= switch_k``, and for ``k > switch_k``::

        y(k+1) = (y(k) y(k−1) y(k−2) u(k−1) (y(k−2) − 1) + r(k) u(k)) / (1 + y(k−1)² + y(k−2)²)

    with ``r(k) = 1 + round(k/500)`` (MATLAB ``round``: half away from zero, so r = 2 for
    501 <= k <= 749 and r = 3 from k = 750). The time ``t`` the loop passes is the paper's ``k``.

    Block signals: input ``u``; states ``y``, ``y[-1]``, ``y[-2]``, ``u[-1]``; output ``y``.
    """

    inputs = ("u",)
    states = ("y", "y[-1]", "y[-2]", "u[-1]")
    outputs = ("y",)
    feedthrough = False
    kernels = Kernels(output=plant_output, update=plant_update, columns=False)  # branches on k against switch_k

    def __init__(self, switch_k: int | None = 500):
        self.switch_k = math.inf if switch_k is None else int(switch_k)
        self.kernel_params = PLANT.pack(switch_k=float(self.switch_k))


def reference_next(kind: str, k) -> np.ndarray:
    """``y*(k+1)`` at the paper's samples ``k`` (eq. (39) ``"step"``, eq. (41) ``"sine"``)."""
    k = np.asarray(k, dtype=float)
    if kind == "step":
        return np.where(k <= 500, 1.0, -1.0)                                      # (39)
    if kind == "sine":
        return 3.0 * np.sin(k * np.pi / 150.0) + np.cos(k * np.pi / 300.0)        # (41)
    raise ValueError(f"kind must be 'step' or 'sine', got {kind!r}")


def reference(kind: str, n: int) -> np.ndarray:
    """``y*(k)`` for ``k = 1..n`` (from ``y*(k+1)`` at ``k − 1``)."""
    return reference_next(kind, np.arange(n))


def plant_start_state(plant: SwitchedPlant, y_init: float, u_init: float, k_start: int) -> np.ndarray:
    """Plant state at ``k_start``: ``y(1:k_start−1) = y_init``, ``u = u_init`` before, then the plant itself.

    The given samples end at ``k_start − 1``; the plant's own update from there (with
    ``u(k_start − 1) = u_init``) gives ``y(k_start)``.
    """
    x = np.array([[y_init, y_init, y_init, u_init]])
    return plant.update(float(k_start - 1), x, np.array([[u_init]]))[0]
