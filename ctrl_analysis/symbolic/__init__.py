"""Sympy derivations, each also returned as a checked numeric function (importing this package imports sympy)."""

from .differential import (
                           breakaway_gain,
                           breakaway_point,
                           coefficients_from_zeros,
                           derive_breakaway,
                           differential_coefficients,
                           locus_gain,
)
from .eso import (
                           bandwidth_match,
                           bandwidth_polynomial,
                           characteristic_coefficients,
                           characteristic_polynomial,
                           error_dc_gains,
                           error_scaling_exponents,
                           error_transfer_functions,
                           observer_matrices,
)
from .riccati import (
                           derive_kalata_gains,
                           derive_random_walk_gain,
                           derive_second_order_gain,
                           kalata_gains_closed_form,
                           random_walk_gain_closed_form,
                           second_order_gain,
)

__all__ = [
    "bandwidth_match",
    "bandwidth_polynomial",
    "breakaway_gain",
    "breakaway_point",
    "characteristic_coefficients",
    "characteristic_polynomial",
    "coefficients_from_zeros",
    "derive_breakaway",
    "derive_kalata_gains",
    "derive_random_walk_gain",
    "derive_second_order_gain",
    "differential_coefficients",
    "error_dc_gains",
    "error_scaling_exponents",
    "error_transfer_functions",
    "kalata_gains_closed_form",
    "locus_gain",
    "observer_matrices",
    "random_walk_gain_closed_form",
    "second_order_gain",
]
