"""The batched interconnect: blocks wired by named signals, stepped together over a batch of runs.

:class:`Loop` is to the engine what :func:`control.interconnect` is to python-control: it takes
blocks (continuous, discrete or static, see :mod:`ctrl_analysis.engine.blocks`) and connects every input
to the output of the same name; the names no block produces are the loop's external inputs. One
sample of period ``dt`` at ``t_k = t0 + k dt`` does, in python-control's callback order:

1. evaluate every block's ``output(t_k, x, u)`` in dependency order (blocks without feedthrough
   first), which gives every signal at ``t_k``; external inputs given as arrays are read at row
   ``k`` and held over the sample, those given as callables ``f(t)`` are evaluated at ``t``;
2. update every discrete block once, ``x(k+1) = update(t_k, x(k), u(k))``;
3. integrate every continuous block over ``[t_k, t_k + dt]`` with ``substeps`` fixed steps of RK4
   or Euler (:func:`ctrl_analysis.engine.integrators.rk4_step`), the outputs of discrete blocks and the held
   inputs held, the outputs of continuous and static blocks recomputed at every stage;
4. flag runs whose state has left ``|x| <= bound`` or become non-finite (which run, which step).

The batch axis ``B`` runs Monte Carlo seeds or a parameter grid side by side; run ``b`` of a
batch equals the same run alone. :meth:`Loop.simulate` resolves its arguments into one
:class:`~ctrl_analysis.engine.batch.Batch` (inputs, initial states, per-run parameters, seeds) and
hands it, with the loop's :attr:`Loop.plan`, to an engine (:mod:`ctrl_analysis.engine.engines`):
``"numpy"`` calls the blocks' batched methods; ``"compiled"`` (chosen by
``Execution(engine="auto")``, the default, when every block has a per-run kernel, see
:mod:`ctrl_analysis.engine.codegen`) runs one generated numba function with the same sample and
stage order. What is stored is a :class:`~ctrl_analysis.engine.policies.Save`, how it runs an
:class:`~ctrl_analysis.engine.policies.Execution`: a batch is stepped in chunks when it is large
(results unchanged) and can be split over processes (``jobs``, :mod:`ctrl_analysis.runs.parallel`).
:meth:`Loop.interconnect` builds the same arrangement as a ``control.interconnect`` (all blocks
continuous, or all discrete with the loop's ``dt``), and :meth:`LoopResponse.to_timeresponse`
converts one run to a ``control.TimeResponseData``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

from .._validate import check_in, check_int, check_names, check_positive, check_str
from .batch import resolve_batch
from .blocks import Block, ContinuousBlock, DiscreteBlock, check_states_declared
from .engines import AUTO_BAR_WORK, select_engine
from .integrators import MAX_SUBSTEPS, STEPPERS
from .plan import Plan, make_plan
from .policies import DEFAULT_EXECUTION, DEFAULT_SAVE, MOVED, Execution, Save, moved_message
from .response import LoopResponse

__all__ = ["AUTO_BAR_WORK", "Execution", "Loop", "LoopResponse", "Placed", "Save", "place"]


def _moved_keywords(simulate):
    """``simulate`` refusing, in one line, the keywords of its older signature (saying where each moved)."""

    @functools.wraps(simulate)
    def checked(self, *args, **kwargs):
        if kwargs.keys() <= _SIMULATE_KEYWORDS:
            return simulate(self, *args, **kwargs)
        moved = [k for k in kwargs if k in MOVED]
        if moved:
            raise TypeError(moved_message(moved))
        return simulate(self, *args, **kwargs)  # Python's own message for any other unknown keyword

    return checked


_SIMULATE_KEYWORDS = frozenset({"inputs", "x0", "params", "runs", "seeds", "t0", "save", "execution"})


def _check_policy(name, value, kind):
    if not isinstance(value, kind):
        raise TypeError(f"{name} must be a ctrl_analysis.engine.{kind.__name__}(...), got {value!r:.80}")
    return value


@dataclass(frozen=True)
class Placed:
    """A block placed in a loop under a name, with its signals (possibly renamed); made by :func:`place`.

    Attributes
    ----------
    block : Block
    name : str
        Unique name in the loop.
    inputs, outputs : tuple of str
        The signals the block reads and writes.
    """

    block: Block
    name: str
    inputs: tuple
    outputs: tuple


def place(block: Block, name: str, *, inputs=None, outputs=None) -> Placed:
    """Put ``block`` into a loop as ``name``, optionally renaming its input/output signals.

    Parameters
    ----------
    block : Block
        A continuous, discrete or static block.
    name : str
        Unique name in the loop (states are reported under it).
    inputs, outputs : sequence of str, optional
        Signal names replacing ``block.inputs`` / ``block.outputs`` (same length and order).

    Returns
    -------
    Placed
        The block with its name and signals, for :class:`Loop`.
    """
    if not isinstance(block, Block):
        raise TypeError(f"block must be a ctrl_analysis.engine.blocks.Block, got {type(block).__name__}")
    if not isinstance(name, str) or not name:
        raise ValueError(f"name must be a non-empty string, got {name!r}")
    ins = tuple(block.inputs) if inputs is None else check_names(f"inputs of {name!r}", inputs,
                                                                  length=len(block.inputs))
    outs = tuple(block.outputs) if outputs is None else check_names(f"outputs of {name!r}", outputs,
                                                                     length=len(block.outputs))
    return Placed(block, name, ins, outs)


class Loop:
    """Blocks wired by named signals, simulated over a batch of runs (see the module docstring).

    Parameters
    ----------
    blocks : sequence of Placed or Block
        The blocks; a bare block is placed under ``"b<i>"`` with its own signal names.
    dt : float
        Sampling period (> 0): discrete blocks update once per sample, continuous blocks are
        integrated over it.
    method : {"rk4", "euler"}
        Fixed-step integrator of the continuous blocks.
    substeps : int
        Integration steps per sample (1 to :data:`~ctrl_analysis.engine.integrators.MAX_SUBSTEPS`).
    outputs : sequence of str, optional
        Signals reported by :meth:`LoopResponse.to_timeresponse` (default: all block outputs).

    Raises
    ------
    ValueError
        Two blocks with one name, a signal produced twice, an algebraic loop (a cycle of
        feedthrough blocks), or a continuous or discrete block that declares no ``states``
        (:func:`~ctrl_analysis.engine.blocks.check_states_declared`).

    Examples
    --------
    A discrete integrator driven by a constant external input ``r``:

    >>> import numpy as np
    >>> from ctrl_analysis.engine.blocks import DiscreteBlock
    >>> class Acc(DiscreteBlock):
    ...     inputs, outputs, states = ("r",), ("s",), ("s",)
    ...     def update(self, t, x, u, params=None):
    ...         return x + u
    >>> res = Loop([place(Acc(), "acc")], dt=1.0).simulate(3, inputs={"r": 2.0}, runs=2)
    >>> res["s"][:, 0]
    array([0., 2., 4., 6.])
    """

    def __init__(self, blocks, dt: float, *, method: str = "rk4", substeps: int = 1, outputs=None):
        self.dt = check_positive("dt", dt, scalar=True)
        self.method = check_in("method", method, STEPPERS)
        self.substeps = check_int("substeps", substeps, minimum=1, maximum=MAX_SUBSTEPS)
        if not isinstance(blocks, (list, tuple)):
            raise TypeError(f"blocks must be a list of blocks (or place(...) results), got {blocks!r:.80}")
        placed = [b if isinstance(b, Placed) else place(b, f"b{i}") for i, b in enumerate(blocks)]
        if not placed:
            raise ValueError("blocks must contain at least one block")
        for p in placed:
            check_states_declared(p.block, p.name)
        names = [p.name for p in placed]
        if len(set(names)) != len(names):
            raise ValueError(f"blocks: block names must be unique, got {names}")
        producer = {}
        for p in placed:
            for s in p.outputs:
                if s in producer:
                    raise ValueError(f"signal {s!r} is produced by both {producer[s]!r} and {p.name!r}")
                producer[s] = p.name
        self.placed = placed
        self.external = tuple(dict.fromkeys(s for p in placed for s in p.inputs if s not in producer))
        self.outlist = tuple(producer) if outputs is None else check_names("outputs", outputs)
        for s in self.outlist:
            if s not in producer and s not in self.external:
                raise ValueError(f"outputs names unknown signal {s!r}")
        self.order = self._evaluation_order(producer)
        # one flat state vector: slices per block, continuous blocks first (they are integrated together)
        cont = [p for p in placed if isinstance(p.block, ContinuousBlock)]
        disc = [p for p in placed if isinstance(p.block, DiscreteBlock)]
        self.slices, start = {}, 0
        for p in cont + disc:
            self.slices[p.name] = slice(start, start + p.block.n_states)
            start += p.block.n_states
        self.n_states = start
        self.n_continuous = sum(p.block.n_states for p in cont)
        self.continuous, self.discrete = cont, disc
        # at integration stages only continuous and static blocks are re-evaluated
        self.stage_order = [p for p in self.order if not isinstance(p.block, DiscreteBlock)]

    def _evaluation_order(self, producer) -> list:
        """Blocks ordered so each feedthrough block comes after the producers of its inputs."""
        by_name = {p.name: p for p in self.placed}
        done, order, visiting = set(), [], set()

        def visit(p):
            if p.name in done:
                return
            if p.name in visiting:
                raise ValueError(f"algebraic loop through block {p.name!r}: a cycle of feedthrough blocks")
            visiting.add(p.name)
            if p.block.feedthrough:
                for s in p.inputs:
                    if s in producer:
                        visit(by_name[producer[s]])
            visiting.discard(p.name)
            done.add(p.name)
            order.append(p)

        for p in self.placed:
            visit(p)
        return order

    # ------------------------------------------------------------------ simulation
    @property
    def plan(self) -> Plan:
        """The loop's execution plan (:class:`~ctrl_analysis.engine.plan.Plan`), built once: what the engines read.

        Returns
        -------
        Plan
        """
        plan = self.__dict__.get("_plan_memo")
        if plan is None:
            plan = self.__dict__["_plan_memo"] = make_plan(self)
        return plan

    def __getstate__(self):  # the plan (and the runner it caches) is rebuilt in another process
        state = dict(self.__dict__)
        state.pop("_plan_memo", None)
        return state

    @_moved_keywords
    def simulate(self, n_steps: int, *, inputs=None, x0=None, params=None, runs: int | None = None, seeds=None,
                 t0: float = 0.0, save: Save | None = None, execution: Execution | None = None) -> LoopResponse:
        """Step the loop ``n_steps`` samples over a batch of runs.

        Parameters
        ----------
        n_steps : int
            Number of samples N; signals and states are returned at N+1 instants.
        inputs : dict of str -> scalar, array or callable
            One entry per external input: a scalar (constant), an array of shape ``(N,)`` (same for
            all runs) or ``(N, B)`` (per run; e.g. a channel of :func:`~ctrl_analysis.noise.draw_noise`),
            held over each sample; or a callable ``f(t) -> scalar or (B,)`` evaluated at every
            integration stage. Row ``N`` (the last instant) repeats row ``N-1`` if absent.
        x0 : dict of str -> array_like, optional
            Initial state per block name, shape ``(n,)`` or ``(B, n)``; default ``initial_state()``.
        params : dict of block name -> dict of parameter name -> value, optional
            Run-time block parameters (:mod:`ctrl_analysis.engine.params`): constructor arguments of
            the named blocks, changed for this simulation. A value with one axis more than the
            block's own (first axis: the ``B`` runs) differs per run, e.g.
            ``params={"law": {"eta": eta_runs}}``; any other value is shared by every run. Each
            distinct value is validated by the block's constructor; per-run values follow the runs
            into chunks and processes, and give the batch size when nothing else does.
        runs : int, optional
            Batch size B when no input, state or parameter says it.
        seeds : sequence of int, optional
            Per-run seeds, recorded in the response.
        t0 : float
            Time of the first sample (default 0).
        save : Save, optional
            What is stored (:class:`~ctrl_analysis.engine.policies.Save`: ``keep`` signals, ``every``
            n-th sample, ``states``); default: every signal and state at every sample.
        execution : Execution, optional
            How it runs (:class:`~ctrl_analysis.engine.policies.Execution`: ``engine``, ``jobs``,
            ``chunk_runs``, ``max_bytes``, ``progress``, ``bound``); default: compiled when every
            block has a kernel, one process, flagged beyond ``|x| > 1e8``.

        Returns
        -------
        LoopResponse

        Raises
        ------
        TypeError
            For a keyword of the older signature (``keep=``, ``engine=``, ...), saying where it moved.
        MemoryError
            If the stored trajectories of the whole batch would exceed
            :data:`~ctrl_analysis.engine.memory.RESULT_BYTES` (half the physical memory); the message
            says what to change.
        """
        n_steps = n_steps if type(n_steps) is int and n_steps >= 1 else check_int("n_steps", n_steps, minimum=1)
        save = DEFAULT_SAVE if save is None else _check_policy("save", save, Save)
        execution = DEFAULT_EXECUTION if execution is None else _check_policy("execution", execution, Execution)
        plan = self.plan
        batch = resolve_batch(plan, n_steps, inputs=inputs, x0=x0, params=params, runs=runs, seeds=seeds, t0=t0,
                              save=save)
        engine = select_engine(plan, batch, execution, loop=self)
        return engine.run(plan, batch, save, execution)

    # ------------------------------------------------------------------ python-control
    def interconnect(self, name: str | None = None):
        """The same arrangement as a ``control.interconnect`` (for one trace).

        All blocks must be continuous (or static), giving a continuous system, or all discrete (or
        static), giving a discrete system with the loop's ``dt``. The system's inputs are the loop's
        external inputs **in the order of** ``self.external`` (the order in which the placed blocks
        first read them, never sorted by name), so row ``i`` of the input array given to
        :func:`control.input_output_response` is ``external[i]``; its outputs are the loop's
        ``outputs``, in that order.

        Parameters
        ----------
        name : str, optional
            System name.

        Returns
        -------
        control.InterconnectedSystem
            With ``input_labels == list(self.external)`` and ``output_labels == list(self.outlist)``.

        Raises
        ------
        ValueError
            If the loop mixes continuous and discrete blocks.
        """
        import control as ct

        if name is not None:
            check_str("name", name)
        has_c, has_d = bool(self.continuous), bool(self.discrete)
        if has_c and has_d:
            raise ValueError("interconnect needs all blocks continuous or all discrete; wrap continuous blocks "
                             "in ctrl_analysis.engine.blocks.SampledBlock to get a discrete-time loop")
        syslist = []
        for p in self.placed:
            if isinstance(p.block, DiscreteBlock):
                syslist.append(p.block.nlsys(self.dt, p.name, inputs=p.inputs, outputs=p.outputs))
            elif isinstance(p.block, ContinuousBlock):
                syslist.append(p.block.nlsys(p.name, inputs=p.inputs, outputs=p.outputs))
            else:
                syslist.append(p.block.nlsys(self.dt if has_d else 0, p.name, inputs=p.inputs, outputs=p.outputs))
        return ct.interconnect(syslist, inplist=list(self.external), outlist=list(self.outlist),
                               inputs=list(self.external), outputs=list(self.outlist), name=name)

