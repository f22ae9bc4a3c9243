"""ctrl-analysis: estimators and controllers from five control papers as python-control building blocks.

Here: the block protocol (:mod:`ctrl_analysis.engine.blocks`), :class:`Loop` wiring blocks by signal
names over a batch of Monte Carlo runs, and per-run seeds and noise. The blocks themselves are in
:mod:`ctrl_analysis.estimators` (and its :mod:`~ctrl_analysis.estimators.kalman`),
:mod:`ctrl_analysis.controllers`, :mod:`ctrl_analysis.plants` and :mod:`ctrl_analysis.identification`;
the sympy derivations in :mod:`ctrl_analysis.symbolic`. Those load python-control, scipy or sympy,
so ``import ctrl_analysis`` (and the command line) does not import them: ``import
ctrl_analysis.controllers`` does.
"""

import importlib

__version__ = "0.1.0"

#: name -> the module it comes from, imported on first use (PEP 562): ``import ctrl_analysis`` itself loads
#: nothing heavy, so the command line can settle the process's settings (one BLAS thread) before numpy loads
_EXPORTS = {
    **dict.fromkeys(("Block", "ContinuousBlock", "DiscreteBlock", "SampledBlock", "StaticBlock", "StaticGain",
                     "UnitDelay", "signal_names"), ".engine.blocks"),
    "FunctionBlock": ".engine.function_block",
    **dict.fromkeys(("Loop", "LoopResponse", "place"), ".engine.loop"),
    **dict.fromkeys(("Execution", "Save"), ".engine.policies"),
    **dict.fromkeys(("draw_noise", "gaussian_noise", "run_seeds", "uniform_noise"), ".noise"),
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'ctrl_analysis' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS))
