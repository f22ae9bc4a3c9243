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
   or Euler (:func:`ctrl_analysis.simulate.rk4_step`), the outputs of discrete blocks and the held
   inputs held, the outputs of continuous and static blocks recomputed at every stage;
4. flag runs whose state has left ``|x| <= bound`` or become non-finite (which run, which step).

The batch axis ``B`` runs Monte Carlo seeds or a parameter grid side by side; run ``b`` of a
batch equals the same run alone. Two engines step the loop: ``"numpy"`` calls the blocks' batched
methods; ``"compiled"`` (chosen by ``engine="auto"`` when every block has a per-run kernel, see
:mod:`ctrl_analysis.engine.codegen`) runs one generated numba function with the same sample and stage
order. A batch is stepped in chunks when it is large (results unchanged) and can be split over
processes (``jobs``, :mod:`ctrl_analysis.parallel`). :meth:`Loop.interconnect` builds the same arrangement as a
``control.interconnect`` (all blocks continuous, or all discrete with the loop's ``dt``), and
:meth:`LoopResponse.to_timeresponse` converts one run to a ``control.TimeResponseData``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from .._validate import (
    check_array,
    check_bool,
    check_callable,
    check_finite,
    check_in,
    check_int,
    check_names,
    check_positive,
    check_real,
    check_str,
)
from .blocks import Block, ContinuousBlock, DiscreteBlock, check_states_declared
from .compiled import compiled_for, run_compiled
from .integrators import MAX_SUBSTEPS, STEPPERS
from .memory import CHUNK_BYTES, RESULT_BYTES, check_result_memory, chunk_bounds
from .numpy_engine import run_numpy
from .params import chunk_functions, resolve
from .plan import Plan, make_plan
from .response import LoopResponse

__all__ = ["AUTO_BAR_WORK", "Loop", "LoopResponse", "Placed", "place"]

#: Run-samples (runs x samples) from which :meth:`Loop.simulate` shows a progress bar of its own
#: (when stderr is a terminal): about a second of work on the numpy engine.
AUTO_BAR_WORK = 2_000_000


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
        Integration steps per sample (1 to :data:`~ctrl_analysis.simulate.MAX_SUBSTEPS`).
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
    def _inputs(self, inputs, n_steps, runs):
        """External inputs -> (held arrays (N+1, B), callables); infers B."""
        if inputs is not None and not isinstance(inputs, dict):
            raise TypeError(f"inputs must be a dict of signal name -> value, got {inputs!r:.80}")
        inputs = dict(inputs or {})
        unknown = set(inputs) - set(self.external)
        if unknown:
            raise ValueError(f"inputs names signals that are not external inputs of the loop: {sorted(unknown)}; "
                             f"external inputs are {list(self.external)}")
        missing = [s for s in self.external if s not in inputs]
        if missing:
            raise ValueError(f"inputs must give every external input; missing {missing}")
        B = runs
        held, funcs = {}, {}
        for s, v in inputs.items():
            if callable(v):
                funcs[s] = v
                continue
            try:
                a = check_array(f"inputs[{s!r}]", v)
            except TypeError:
                raise TypeError(f"inputs[{s!r}] must be a number, an array or a callable f(t), got {v!r:.80}") from None
            if a.ndim == 2:
                if B is not None and a.shape[1] != B:
                    raise ValueError(f"input {s!r} has {a.shape[1]} runs, expected {B}")
                B = a.shape[1]
            if a.ndim > 2 or (a.ndim >= 1 and a.shape[0] not in (n_steps, n_steps + 1)):
                raise ValueError(f"inputs[{s!r}] must be a scalar or have shape (N,) or (N, B) with N = {n_steps} "
                                 f"or {n_steps + 1} rows, got shape {a.shape}")
            if not np.all(np.isfinite(a)):
                raise ValueError(f"inputs[{s!r}] must be finite (no NaN or inf)")
            held[s] = a
        return held, funcs, (1 if B is None else B)

    def _x0(self, x0, B, variants=None):
        """The batch's initial states: ``x0`` where given, else each block's ``initial_state()`` under its run-time
        parameters (a per-run ``x0`` given through ``params`` gives each run its own)."""
        x = np.empty((B, self.n_states))
        x0 = dict(x0 or {})
        unknown = set(x0) - set(self.slices)
        if unknown:
            raise ValueError(f"x0 names unknown blocks {sorted(unknown)}; blocks with states are {list(self.slices)}")
        variants = variants or {}
        for p in self.continuous + self.discrete:
            if p.name not in x0 and p.name in variants:
                var = variants[p.name]
                v = np.empty((B, p.block.n_states))
                for block, idx in (var.groups or ((var.block, np.arange(B)),)):
                    v[idx] = np.asarray(block.initial_state(), dtype=float).reshape(-1)
            else:
                v = np.asarray(x0[p.name] if p.name in x0 else p.block.initial_state(), dtype=float)
            n = p.block.n_states
            if v.shape not in ((n,), (B, n)):
                raise ValueError(f"x0[{p.name!r}] must have shape ({n},) or ({B}, {n}), got {v.shape}")
            if not np.all(np.isfinite(v)):
                raise ValueError(f"x0[{p.name!r}] must be finite")
            x[:, self.slices[p.name]] = v
        return x

    def _plan(self) -> Plan:
        """The loop's execution plan (:class:`~ctrl_analysis.engine.plan.Plan`), built once."""
        if getattr(self, "_compiled_plan", None) is None:
            self._compiled_plan = make_plan(self)
        return self._compiled_plan

    def _memory_per_run(self, n_steps, n_stored_signals, store_states):
        """Bytes one run's stored trajectories take (signals, plus states when stored)."""
        width = n_stored_signals + (self.n_states if store_states else 0)
        return 8 * (n_steps + 1) * max(width, 1)

    #: The less common keyword arguments of :meth:`simulate`, with their defaults.
    OPTIONS: ClassVar[dict] = {"t0": 0.0, "bound": 1e8, "store_states": True, "seeds": None, "chunk_runs": None,
                               "max_bytes": None, "progress": None, "store_signals": None}

    def simulate(self, n_steps: int, *, inputs=None, x0=None, params=None, runs: int | None = None, keep=None,
                 every: int = 1, engine: str = "auto", jobs: int = 1, **options) -> LoopResponse:
        """Step the loop ``n_steps`` samples over a batch of runs.

        Parameters
        ----------
        n_steps : int
            Number of samples N; signals and states are returned at N+1 instants.
        inputs : dict of str -> scalar, array or callable
            One entry per external input: a scalar (constant), an array of shape ``(N,)`` (same for
            all runs) or ``(N, B)`` (per run; e.g. a channel of :func:`~ctrl_analysis.simulate.draw_noise`),
            held over each sample; or a callable ``f(t) -> scalar or (B,)`` evaluated at every
            integration stage. Row ``N`` (the last instant) repeats row ``N-1`` if absent.
        x0 : dict of str -> array_like, optional
            Initial state per block name, shape ``(n,)`` or ``(B, n)``; default ``initial_state()``.
        runs : int, optional
            Batch size B when no input or state says it.
        params : dict of block name -> dict of parameter name -> value, optional
            Run-time block parameters (:mod:`ctrl_analysis.engine.params`): constructor arguments of
            the named blocks, changed for this simulation. A value with one axis more than the
            block's own (first axis: the ``B`` runs) differs per run, e.g.
            ``params={"law": {"eta": eta_runs}}``; any other value is shared by every run. Each
            distinct value is validated by the block's constructor; per-run values follow the runs
            into chunks and processes, and give the batch size when nothing else does.
        keep : sequence of str, optional
            Signals kept in the response (default: all); fewer save memory in large batches.
        every : int
            Keep every ``every``-th sample only (instants ``t0, t0 + every dt, ...``; default 1: all):
            a Monte Carlo that needs a metric need not pay for storing the whole trajectory.
        engine : {"auto", "numpy", "compiled"}
            ``"numpy"``: the blocks' batched methods. ``"compiled"``: one numba function for the whole
            loop built from the blocks' kernels (:mod:`ctrl_analysis.engine.codegen`); needs a kernel for
            every block and no callable input. ``"auto"``: compiled when possible
            (the environment variable ``CTRL_ANALYSIS_ENGINE=numpy`` makes ``"auto"`` mean numpy).
            The choice depends on the loop only, never on the batch size, so run ``b`` is the same
            whatever the batch; the two engines agree to rounding (bit for bit without ``pow``).
        jobs : int
            Processes the batch is split over (:func:`ctrl_analysis.parallel.map_chunks`); the
            result equals ``jobs=1`` bit for bit. Needs a picklable loop and no callable input
            (otherwise the batch runs in this process, with a warning for an unpicklable loop).
            With ``jobs=1`` and a process-wide Dask cluster (:func:`ctrl_analysis.parallel.use_cluster`),
            a compiled batch of two runs or more is split over its workers, with the same numbers.

        Other Parameters
        ----------------
        t0 : float
            Time of the first sample (default 0).
        bound : float
            A run whose state leaves ``|x| <= bound`` or becomes non-finite is flagged.
        store_states : bool
            Keep the state trajectory (``False`` saves memory in large batches).
        seeds : list, optional
            Per-run seeds, recorded in the response.
        chunk_runs : int, optional
            Step the batch in chunks of at most this many runs (default: chosen from ``max_bytes``).
            The per-step work of a chunk stays in cache; every run's result is the same bit for bit.
        max_bytes : float, optional
            Memory allowed for the working arrays of one chunk (default
            :data:`ctrl_analysis.simulate.CHUNK_BYTES`); the batch is split into chunks that fit.
        progress : callable, bool or None
            ``progress(n)`` is called as work completes, ``n`` counting run-samples (one run advanced
            one sample; the total is ``B * n_steps``), e.g. a tqdm ``update``. ``None`` (default): a
            progress bar of its own (:func:`ctrl_analysis.progress.bar`, stderr, only when it is a
            terminal) for long simulations (``B * n_steps >= AUTO_BAR_WORK``); ``False``: none.
        store_signals : sequence of str, optional
            The older name of ``keep``.

        Returns
        -------
        LoopResponse

        Raises
        ------
        MemoryError
            If the stored trajectories of the whole batch would exceed
            :data:`~ctrl_analysis.simulate.RESULT_BYTES` (half the physical memory); the message
            says what to change.
        """
        unknown = sorted(set(options) - set(self.OPTIONS))
        if unknown:
            raise TypeError(f"simulate got unknown keyword arguments {unknown}; besides n_steps, inputs, x0, params, "
                            f"runs, keep, every, engine and jobs it takes {sorted(self.OPTIONS)}")
        o = self.OPTIONS | options
        t0, bound, store_states, seeds = o["t0"], o["bound"], o["store_states"], o["seeds"]
        chunk_runs, max_bytes, progress, store_signals = o["chunk_runs"], o["max_bytes"], o["progress"], o["store_signals"]
        n_steps = check_int("n_steps", n_steps, minimum=1)
        if runs is not None:
            runs = check_int("runs", runs, minimum=1)
        bound = check_real("bound", bound)
        if not np.isfinite(bound):
            if bound != np.inf:
                raise ValueError(f"bound must be > 0 (or inf), got {bound}")
        else:
            bound = check_positive("bound", bound)
        t0 = float(check_finite("t0", t0, scalar=True))
        store_states = check_bool("store_states", store_states)
        if x0 is not None and not isinstance(x0, dict):
            raise TypeError(f"x0 must be a dict of block name -> initial state, got {x0!r:.80}")
        if seeds is not None and (isinstance(seeds, (str, bytes)) or not hasattr(seeds, "__len__")):
            raise TypeError(f"seeds must be a sequence of one seed per run, got {seeds!r:.80}")
        if seeds is not None:
            seeds = [check_int("seeds", s, minimum=0) for s in seeds]
        if keep is not None:
            if store_signals is not None:
                raise ValueError("give keep or store_signals (the same thing), not both")
            store_signals = check_names("keep", keep)
        elif store_signals is not None:
            store_signals = check_names("store_signals", store_signals)
        every = check_int("every", every, minimum=1)
        if max_bytes is not None:
            max_bytes = check_positive("max_bytes", max_bytes, scalar=True)
        if not isinstance(progress, bool):
            check_callable("progress", progress, "progress(n)", optional=True)
        held, funcs, B = self._inputs(inputs, n_steps, runs)
        x0_B = max((np.ndim(v) == 2 and np.shape(v)[0]) or 1 for v in (x0 or {}).values()) if x0 else 1
        if B == 1 and x0_B > 1:
            B = x0_B
        if B == 1 and runs is None:
            from .params import runs_of

            B = runs_of(self, params) or 1  # per-run parameters say how many runs
        if seeds is not None and len(seeds) != B:
            raise ValueError(f"seeds must have one entry per run ({B}), got {len(seeds)}")
        plan = self._plan()
        names, col = plan.names, plan.col
        keep = names if store_signals is None else list(dict.fromkeys(store_signals))
        for s in keep:
            if s not in col:
                raise ValueError(f"keep (store_signals) names unknown signal {s!r}; signals are {names}")
        keep_cols = np.array([col[s] for s in keep], dtype=np.intp)
        n_kept = n_steps // every + 1  # stored instants
        per_run = self._memory_per_run(n_kept - 1, len(keep), store_states)
        check_result_memory(per_run * B, RESULT_BYTES, f"Loop.simulate(n_steps={n_steps}, runs={B})")
        variants = resolve(self, params, B)  # validated here, before any work
        x = self._x0(x0, B, variants)  # after the memory check: B runs' states are allocated here
        limit = CHUNK_BYTES if max_bytes is None else check_positive("max_bytes", max_bytes)
        work = 8 * (8 * self.n_states + 2 * len(names)) + per_run  # temporaries + stored rows, per run
        size = B if chunk_runs is None else check_int("chunk_runs", chunk_runs, minimum=1)
        size = max(1, min(size, int(limit // work))) if chunk_runs is None else size
        check_in("engine", engine, ("auto", "numpy", "compiled"))
        jobs = check_int("jobs", jobs, minimum=1)
        from ..parallel import active_cluster, picklable
        from .processes import simulate_chunks


        # over processes, or a process-wide Dask cluster's workers (per-run parameters follow the chunk)
        on_cluster = jobs == 1 and B > 1 and not funcs and active_cluster() is not None \
            and compiled_for(self, engine, funcs, variants) is not None
        if B > 1 and not funcs and (jobs > 1 or on_cluster) and picklable(self):
            opts = {"t0": t0, "params": params, "bound": bound, "store_states": store_states, "store_signals": keep,
                    "every": every, "chunk_runs": chunk_runs, "max_bytes": max_bytes, "engine": engine}
            return simulate_chunks(self, jobs, n_steps, held, x, opts, seeds)
        runner = compiled_for(self, engine, funcs, variants)  # None: the numpy path
        t = t0 + self.dt * np.arange(n_steps + 1)
        store = np.empty((n_kept, B, len(keep)))
        xs = np.empty((n_kept, B, self.n_states)) if store_states else None
        diverged = np.zeros(B, dtype=bool)
        div_step = np.full(B, -1, dtype=int)
        div_where = np.full(B, -1, dtype=int)
        # a callable input returning one value per run is sliced with its chunk
        per_run_funcs = {s for s, f in funcs.items() if np.ndim(f(t[0])) == 1 and np.size(f(t[0])) == B > 1}
        from ..progress import enabled, updater

        auto = progress is None and B * n_steps >= AUTO_BAR_WORK and enabled()
        with updater(progress if callable(progress) else auto, B * n_steps,
                     f"{B} runs x {n_steps} samples", "run-sample") as pbar:
            self._run_chunks(plan, runner, n_steps, t, x, held, funcs, per_run_funcs, variants, bound, keep_cols,
                             (store, xs, every), (diverged, div_step, div_where), chunk_bounds(B, size), pbar)
        sig_store = {s: store[:, :, j] for j, s in enumerate(keep)}
        state_names = [f"{p.name}.{s}" for p in self.continuous + self.discrete for s in p.block.states]
        return LoopResponse(t=t[::every], x=xs, u=None, y=None, diverged=diverged, diverged_step=div_step,
                            seeds=None if seeds is None else list(seeds), bound=bound, signals=sig_store,
                            slices=dict(self.slices), external=self.external, outlist=self.outlist,
                            state_names=state_names, x_final=x, diverged_where=div_where,
                            where_names=state_names + [self._signal_owner(s) for s in plan.names])

    def _signal_owner(self, signal: str) -> str:
        """How a divergence names a signal: the block that outputs it, or the loop's external input."""
        for p in self.placed:
            if signal in p.outputs:
                return f"{p.name}.{signal} (output of block {p.name!r})"
        return f"{signal} (an input of the loop)"

    def _run_chunks(self, plan, runner, n_steps, t, x, held, funcs, per_run_funcs, variants, bound, keep_cols,
                    stored, flags, bounds, progress):
        """Step every chunk ``(lo, hi)`` of the batch (compiled or numpy), reporting run-samples to ``progress``."""
        store, xs, every = stored
        diverged, div_step, div_where = flags
        for lo, hi in bounds:
            f_c = {s: (f if s not in per_run_funcs else (lambda tt, f=f, lo=lo, hi=hi: np.asarray(f(tt))[lo:hi]))
                   for s, f in funcs.items()}
            h_c = {s: (a[:, lo:hi] if a.ndim == 2 else a) for s, a in held.items()}
            if runner is None:
                chunk_plan = replace(plan, **chunk_functions(plan, self._variant_ids(variants), lo, hi - lo))
                run_numpy(self, chunk_plan, n_steps, t, x[lo:hi], h_c, f_c, bound, keep_cols,
                          (store[:, lo:hi], None if xs is None else xs[:, lo:hi], every),
                          (diverged[lo:hi], div_step[lo:hi], div_where[lo:hi]), progress)
                continue
            # compiled: one call per chunk, or (with progress) about 20 calls over its runs (runs are
            # independent: the same numbers either way)
            parts = [(lo, hi)] if progress is None else chunk_bounds(hi - lo, max(1, -(-(hi - lo) // 20)))
            for a, b in parts if progress is None else [(lo + a, lo + b) for a, b in parts]:
                h_p = {s: (v[:, a:b] if v.ndim == 2 else v) for s, v in held.items()}
                run_compiled(self, runner, plan, n_steps, t, x[a:b], h_p, bound, keep_cols, store[:, a:b],
                             None if xs is None else xs[:, a:b], diverged[a:b], div_step[a:b], div_where[a:b], lo=a,
                             every=every)
                if progress is not None:
                    progress((b - a) * n_steps)

    def _variant_ids(self, variants) -> dict:  # the plan holds the placed blocks: id -> Variant
        return {id(p.block): variants[p.name] for p in self.placed if p.name in variants}

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

