"""Estimators as blocks: the differential estimator Σ, the ESO family, the tracking differentiator, Levant's
differentiator, low-pass filters.

The Kalman-type filters are in :mod:`ctrl_analysis.estimators.kalman`.
"""

from . import kalman
from .differential import READINGS, DifferentialEstimator
from .eso import ExtendedStateObserver, fal
from .levant import LevantDifferentiator
from .lowpass import DiscreteLowPass, LowPassFilter
from .tracking import TrackingDifferentiator, fhan, softened_setpoint

__all__ = [
    "READINGS",
    "DifferentialEstimator",
    "DiscreteLowPass",
    "ExtendedStateObserver",
    "LevantDifferentiator",
    "LowPassFilter",
    "TrackingDifferentiator",
    "fal",
    "fhan",
    "kalman",
    "softened_setpoint",
]
