"""ctrl-analysis: estimators and controllers from five control papers as python-control building blocks.

Here: the block protocol (:mod:`ctrl_analysis.engine.blocks`), :class:`Loop` wiring blocks by signal
names over a batch of Monte Carlo runs, and per-run seeds and noise. The blocks themselves are in
:mod:`ctrl_analysis.estimators` (and its :mod:`~ctrl_analysis.estimators.kalman`),
:mod:`ctrl_analysis.controllers`, :mod:`ctrl_analysis.plants` and :mod:`ctrl_analysis.identification`;
the sympy derivations in :mod:`ctrl_analysis.symbolic`. Those load python-control, scipy or sympy,
so ``import ctrl_analysis`` (and the command line) does not import them: ``import
ctrl_analysis.controllers`` does.
"""

from .engine.blocks import (
    Block,
    ContinuousBlock,
    DiscreteBlock,
    SampledBlock,
    StaticBlock,
    StaticGain,
    UnitDelay,
    signal_names,
)
from .engine.loop import Loop, LoopResponse, place
from .noise import draw_noise, gaussian_noise, run_seeds, uniform_noise

__version__ = "0.1.0"

__all__ = [
    "Block",
    "ContinuousBlock",
    "DiscreteBlock",
    "Loop",
    "LoopResponse",
    "SampledBlock",
    "StaticBlock",
    "StaticGain",
    "UnitDelay",
    "draw_noise",
    "gaussian_noise",
    "place",
    "run_seeds",
    "signal_names",
    "uniform_noise",
]
