"""The estimator arena: every estimator family tuned fairly on common signals and noise, scored against the bound."""
