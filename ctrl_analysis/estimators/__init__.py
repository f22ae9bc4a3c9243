"""Estimators as blocks: the differential estimator Σ, the ESO family, the tracking differentiator, low-pass filters.

The Kalman-type filters are in :mod:`ctrl_analysis.estimators.kalman`.
"""

from . import kalman
from .differential import READINGS, DifferentialEstimator
from .eso import ExtendedStateObserver, fal
from .lowpass import DiscreteLowPass, LowPassFilter
from .tracking import TrackingDifferentiator, fhan, softened_setpoint

__all__ = [
    "READINGS",
    "DifferentialEstimator",
    "DiscreteLowPass",
    "ExtendedStateObserver",
    "LowPassFilter",
    "TrackingDifferentiator",
    "fal",
    "fhan",
    "kalman",
    "softened_setpoint",
]
