"""ctrl-analysis: estimators and controllers from five control papers as python-control building blocks."""

__version__ = "0.1.0"
