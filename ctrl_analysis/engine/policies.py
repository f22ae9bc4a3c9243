"""What a simulation keeps (:class:`Save`) and how it is executed (:class:`Execution`).

Two small frozen records that :meth:`Loop.simulate <ctrl_analysis.engine.loop.Loop.simulate>` takes in
place of the keyword options it once hid in ``**options``: ``save=Save(keep=["y"], every=10,
states=False)``, ``execution=Execution(engine="numpy", jobs=4)``. Each validates its fields when
it is made, naming the field and the rule, so a wrong value fails where it is written, and one
record can be reused for many calls (its checks are not repeated). :data:`MOVED` says where each
keyword of the older signature went.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import check_bool, check_callable, check_in, check_int, check_names, check_positive, check_real

__all__ = ["ENGINES", "MOVED", "Execution", "Save"]

#: The engines :class:`Execution` can name.
ENGINES = ("auto", "numpy", "compiled")

#: Where each keyword argument of the older ``Loop.simulate`` moved.
MOVED = {
    "keep": "save=Save(keep=...)",
    "store_signals": "save=Save(keep=...)",
    "every": "save=Save(every=...)",
    "store_states": "save=Save(states=...)",
    "engine": "execution=Execution(engine=...)",
    "jobs": "execution=Execution(jobs=...)",
    "chunk_runs": "execution=Execution(chunk_runs=...)",
    "max_bytes": "execution=Execution(max_bytes=...)",
    "progress": "execution=Execution(progress=...)",
    "bound": "execution=Execution(bound=...)",
}


def moved_message(names) -> str:
    """One line saying where the older keyword arguments ``names`` of ``Loop.simulate`` moved.

    Parameters
    ----------
    names : iterable of str
        Keywords of the older signature (keys of :data:`MOVED`).

    Returns
    -------
    str
    """
    return "Loop.simulate: " + "; ".join(f"{n}= moved to {MOVED[n]}" for n in names) + \
        " (from ctrl_analysis.engine import Save, Execution)"


@dataclass(frozen=True)
class Save:
    """What a simulation stores.

    Parameters
    ----------
    keep : sequence of str, optional
        Signals kept in the response (default: all); fewer save memory in large batches. Unknown
        names are refused by :meth:`~ctrl_analysis.engine.loop.Loop.simulate`, which knows the loop.
    every : int
        Keep every ``every``-th sample only (instants ``t0, t0 + every dt, ...``; default 1: all):
        a Monte Carlo that needs a metric need not pay for storing the whole trajectory.
    states : bool
        Keep the state trajectory (``False`` saves memory; the final states are always kept).

    Raises
    ------
    TypeError, ValueError
        Naming the field and the rule (``every`` an integer >= 1, ``keep`` names, ``states`` a bool).

    Examples
    --------
    >>> Save(keep=["y"], every=10, states=False).keep
    ('y',)
    """

    keep: tuple | None = None
    every: int = 1
    states: bool = True

    def __post_init__(self):
        if self.keep is not None:
            object.__setattr__(self, "keep", tuple(dict.fromkeys(check_names("keep", self.keep))))
        object.__setattr__(self, "every", check_int("every", self.every, minimum=1))
        object.__setattr__(self, "states", check_bool("states", self.states))


@dataclass(frozen=True)
class Execution:
    """How a simulation runs: which engine, over how many processes, in which chunks.

    Parameters
    ----------
    engine : {"auto", "numpy", "compiled"}
        ``"numpy"``: the blocks' batched methods. ``"compiled"``: one numba function for the whole
        loop built from the blocks' kernels (:mod:`ctrl_analysis.engine.codegen`); needs a kernel
        for every block and no callable input. ``"auto"``: compiled when possible (the environment
        variable ``CTRL_ANALYSIS_ENGINE=numpy`` makes ``"auto"`` mean numpy). The choice depends on
        the loop only, never on the batch size; the two engines agree to rounding (bit for bit
        without ``pow``).
    jobs : int
        Processes the batch is split over (:func:`ctrl_analysis.runs.parallel.map_chunks`); the result
        equals ``jobs=1`` bit for bit. Needs a picklable loop and no callable input.
    chunk_runs : int, optional
        Step the batch in chunks of at most this many runs (default: chosen from ``max_bytes``).
    max_bytes : float, optional
        Memory allowed for the working arrays of one chunk (default
        :data:`~ctrl_analysis.engine.memory.CHUNK_BYTES`).
    progress : callable, bool or None
        ``progress(n)`` is called as work completes, ``n`` counting run-samples; ``None``: a bar of
        its own for long simulations when stderr is a terminal; ``False``: none.
    bound : float
        A run whose state leaves ``|x| <= bound`` or becomes non-finite is flagged (``inf``: only
        non-finite values).

    Raises
    ------
    TypeError, ValueError
        Naming the field and the rule.

    Examples
    --------
    >>> Execution(engine="numpy", jobs=2).jobs
    2
    """

    engine: str = "auto"
    jobs: int = 1
    chunk_runs: int | None = None
    max_bytes: float | None = None
    progress: object = None
    bound: float = 1e8

    def __post_init__(self):
        check_in("engine", self.engine, ENGINES)
        object.__setattr__(self, "jobs", check_int("jobs", self.jobs, minimum=1))
        if self.chunk_runs is not None:
            object.__setattr__(self, "chunk_runs", check_int("chunk_runs", self.chunk_runs, minimum=1))
        if self.max_bytes is not None:
            object.__setattr__(self, "max_bytes", float(check_positive("max_bytes", self.max_bytes, scalar=True)))
        if not isinstance(self.progress, bool):
            check_callable("progress", self.progress, "progress(n)", optional=True)
        bound = check_real("bound", self.bound)
        if not bound > 0:
            raise ValueError(f"bound must be > 0 (inf disables the bound, not the finiteness test), got {bound}")
        object.__setattr__(self, "bound", float(bound) if np.isfinite(bound) else np.inf)


#: The policies :meth:`Loop.simulate <ctrl_analysis.engine.loop.Loop.simulate>` uses when given none.
DEFAULT_SAVE = Save()
DEFAULT_EXECUTION = Execution()
