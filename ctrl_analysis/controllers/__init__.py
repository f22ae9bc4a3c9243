"""Controllers as blocks: the MFAC family, golden-section adaptive, high-order differential feedback, PD, PID, fuzzy."""

from .differential_feedback import (
    HighOrderDifferentialFeedback,
    gains_from_poles,
    hurwitz_roots,
)
from .fuzzy import FuzzyController, FuzzyLookupController, sum_rule_table
from .golden_section import GOLDEN_L1, GOLDEN_L2, GoldenSectionController
from .mfac import (
    CFDLLaw,
    CFDLPredictor,
    DecreasingGainLaw,
    PPDEstimator,
    UnitDelay,
    ikf_mfac,
    mfac_controller,
)
from .pd import PDFeedforward, bandwidth_gains
from .pid import DiscretePID

__all__ = [
    "GOLDEN_L1",
    "GOLDEN_L2",
    "CFDLLaw",
    "CFDLPredictor",
    "DecreasingGainLaw",
    "DiscretePID",
    "FuzzyController",
    "FuzzyLookupController",
    "GoldenSectionController",
    "HighOrderDifferentialFeedback",
    "PDFeedforward",
    "PPDEstimator",
    "UnitDelay",
    "bandwidth_gains",
    "gains_from_poles",
    "hurwitz_roots",
    "ikf_mfac",
    "mfac_controller",
    "sum_rule_table",
]
