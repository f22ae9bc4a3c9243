"""The simulation engine: a :class:`~ctrl_analysis.engine.loop.Loop` of blocks and the policies of one simulation.

:class:`Save` (what a simulation stores) and :class:`Execution` (how it runs) are the two records
:meth:`Loop.simulate <ctrl_analysis.engine.loop.Loop.simulate>` takes besides its inputs; they are
imported on first use, so ``import ctrl_analysis.engine.<module>`` loads nothing else.
"""

import importlib

_EXPORTS = {"Execution": ".policies", "Save": ".policies"}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'ctrl_analysis.engine' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS))
