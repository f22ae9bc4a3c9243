"""The simulation engine: a :class:`~ctrl_analysis.engine.loop.Loop` of blocks and the policies of one simulation.

:class:`Save` (what a simulation stores) and :class:`Execution` (how it runs) are the two records
:meth:`Loop.simulate <ctrl_analysis.engine.loop.Loop.simulate>` takes besides its inputs (``policies.py``
needs only numpy, so importing them here costs nothing a module of the engine does not already load).
"""

from .policies import Execution, Save

__all__ = ["Execution", "Save"]
