"""Block protocols: continuous, discrete and static building blocks that run in the batch engine and in python-control.

Every building block follows python-control's conventions, batched:

* a **continuous block** has ``rhs(t, x, u, params) -> dx/dt`` and ``output(t, x, u, params)``;
* a **discrete block** has ``update(t, x, u, params) -> x_next`` and ``output(t, x, u, params)``;
* a **static block** has only ``output(t, x, u, params)`` (no state; ``x`` has zero columns).

``x`` has shape ``(B, n)`` (``B`` runs side by side, ``n`` the block's states) and ``u`` always has
shape ``(B, m)``, one column per named input, in the order of :attr:`Block.inputs`. Parameters are
fixed when the block is built (validated there); the per-step methods check nothing and create no
Python objects beyond the arrays they return, so a hot path can later be compiled unchanged.

A block names its signals (:attr:`Block.inputs`, :attr:`Block.outputs`, :attr:`Block.states`,
each a tuple of strings, python-control style, e.g. ``"xhat[0]"``) and says whether its output
depends on its input (:attr:`Block.feedthrough`); :class:`ctrl_analysis.engine.loop.Loop` wires blocks by
these names, and :meth:`nlsys` gives the same block as a ``control.nlsys`` (continuous, or discrete
with ``dt``) for :func:`control.interconnect` and :func:`control.input_output_response`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .._validate import (
    check_finite,
    check_in,
    check_int,
    check_names,
    check_positive,
    check_str,
)
from .kernels import KernelBlock, Kernels, Layout
from .stepcheck import checked, unchecked, wrap_step_methods

__all__ = [
    "MAX_SIGNALS",
    "Block",
    "ContinuousBlock",
    "DiscreteBlock",
    "SampledBlock",
    "StaticBlock",
    "StaticGain",
    "UnitDelay",
    "signal_names",
]


#: Most names :func:`signal_names` makes (a vector signal wider than this is a mistake, not a plant).
MAX_SIGNALS = 10**6


def signal_names(base: str, n: int) -> tuple[str, ...]:
    """``("base[0]", ..., "base[n-1]")``, python-control's names for a vector signal.

    Parameters
    ----------
    base : str
        Name of the vector signal.
    n : int
        Its length, from 0 to :data:`MAX_SIGNALS`.

    Returns
    -------
    tuple of str
    """
    base = check_str("base", base)
    n = check_int("n", n, minimum=0)
    if n > MAX_SIGNALS:
        raise ValueError(f"n must be <= {MAX_SIGNALS} (MAX_SIGNALS: names of one vector signal), got {n}")
    return tuple(f"{base}[{i}]" for i in range(n))


class Block:
    """What every block has: signal names, a feedthrough flag and an initial state.

    Subclasses set :attr:`inputs`, :attr:`outputs` and :attr:`states` (tuples of names, as class
    attributes or properties) and override :meth:`output` (default: the whole state).
    """

    #: Input names, in the column order of ``u``.
    inputs: tuple = ()
    #: Output names, in the column order of :meth:`output`'s result.
    outputs: tuple = ()
    #: State names, in the column order of ``x``.
    states: tuple = ()
    #: Whether :meth:`output` depends on ``u`` (direct feedthrough).
    feedthrough: bool = False

    def __init_subclass__(cls, **kwargs):
        # a direct call of output/update/rhs checks the widths of x and u; the engine calls the
        # unwrapped methods (ctrl_analysis.engine.stepcheck), so the hot loop checks nothing
        super().__init_subclass__(**kwargs)
        wrap_step_methods(cls)

    def __new__(cls, *args, **kwargs):
        # the constructor's arguments, for init_args / with_params (pickling restores them from __dict__)
        obj = super().__new__(cls)
        obj.__dict__["_init_call"] = (args, kwargs)
        return obj

    def _bound_args(self):
        """The constructor call that built the block, bound to its signature (defaults filled in)."""
        import inspect

        call = self.__dict__.get("_init_call")
        if call is None:
            raise TypeError(f"{type(self).__name__} records no constructor arguments, so its parameters cannot be "
                            f"changed by name")
        sig = inspect.signature(type(self).__init__)
        sig = sig.replace(parameters=list(sig.parameters.values())[1:])
        bound = sig.bind(*call[0], **call[1])
        bound.apply_defaults()
        return bound

    def init_args(self) -> dict:
        """The arguments the block was built with, by name (defaults filled in).

        Returns
        -------
        dict of str -> value
        """
        return dict(self._bound_args().arguments)

    def with_params(self, **changes) -> Block:
        """A new block of the same class built with some constructor arguments changed.

        What :meth:`Loop.simulate(params=...) <ctrl_analysis.engine.loop.Loop.simulate>` and python-control's
        ``params`` use: the constructor validates the new values, so a per-run value obeys the rules
        of the block's own argument.

        Parameters
        ----------
        **changes
            Constructor arguments by name.

        Returns
        -------
        Block

        Raises
        ------
        ValueError
            If a name is not a constructor argument (or what the constructor raises for the value).
        """
        bound = self._bound_args()
        unknown = sorted(set(changes) - set(bound.arguments))
        if unknown:
            raise ValueError(f"{unknown} are not parameters of {type(self).__name__}; its parameters are "
                             f"{sorted(bound.arguments)}")
        bound.arguments.update(changes)
        return type(self)(*bound.args, **bound.kwargs)

    @property
    def n_states(self) -> int:
        """Number of states ``n`` (the number of columns of ``x``)."""
        return len(self.states)

    def initial_state(self) -> np.ndarray:
        """The block's default initial state (zeros unless a block says otherwise).

        Returns
        -------
        numpy.ndarray, shape (n,)
        """
        return np.zeros(self.n_states)

    def output(self, t, x, u, params=None) -> np.ndarray:
        """The block's outputs at time ``t`` (default: the whole state).

        Parameters
        ----------
        t : float
            Time (s) or sample instant ``t_k``.
        x : numpy.ndarray, shape (B, n)
            States of the ``B`` runs.
        u : numpy.ndarray, shape (B, m)
            Inputs, one column per name in :attr:`inputs`.
        params : dict, optional
            python-control's ``params`` argument; the blocks of this library fix their parameters
            at construction and ignore it.

        Returns
        -------
        numpy.ndarray, shape (B, p)
            One column per name in :attr:`outputs`.
        """
        return x

    # ------------------------------------------------------------------ python-control
    def _io_names(self, inputs, outputs, states, name=None):
        if name is not None:
            check_str("name", name)
        return (list(self.inputs if inputs is None else inputs),
                list(self.outputs if outputs is None else outputs),
                list(self.states if states is None else states))

    def _lifted(self, fn: Callable) -> Callable:
        """``fn`` batched ``(B, n)``/``(B, m)`` -> a python-control callback on 1-D ``x``, ``u``."""
        n, m = self.n_states, len(self.inputs)
        fn = getattr(fn, "unchecked", None) and fn.unchecked.__get__(self) or fn  # shapes made here

        def call(t, x, u, params=None):
            xb = np.asarray(x, dtype=float).reshape(1, n)
            ub = np.asarray(u, dtype=float).reshape(1, m)
            return np.asarray(fn(t, xb, ub, params or None), dtype=float).reshape(-1)

        return call


Block.output = checked(Block.output)


def check_states_declared(block: Block, name: str | None = None) -> None:
    """Raise a ``ValueError`` if a continuous or discrete block never declared its :attr:`~Block.states`.

    A block with state must name its states (``states = ("x",)``, or ``signal_names("x", n)``):
    the engine sizes ``x`` from them. A subclass that forgets them inherits ``Block.states = ()``,
    and its ``update`` or ``rhs`` would then meet a state of zero columns (a numpy broadcast error,
    or a state silently dropped). A block whose state is really empty says so, ``states = ()``.

    Parameters
    ----------
    block : Block
        The block to check (static blocks always pass).
    name : str, optional
        The block's name in a loop, for the message.

    Raises
    ------
    ValueError
        Naming the block and the rule.
    """
    if not isinstance(block, (ContinuousBlock, DiscreteBlock)) or "states" in vars(block):
        return
    for cls in type(block).__mro__:
        if cls is Block:
            break
        if "states" in vars(cls):
            return
    kind = "ContinuousBlock" if isinstance(block, ContinuousBlock) else "DiscreteBlock"
    where = f"block {name!r} ({type(block).__name__})" if name else f"block {type(block).__name__}"
    raise ValueError(f"{where} declares no states: a {kind} must name its states, e.g. states = ('x',) or "
                     f"states = signal_names('x', n) (a class attribute, or set in __init__); one without "
                     f"state declares states = () (or is a StaticBlock)")


class ContinuousBlock(Block):
    """A block with continuous-time state: ``dx/dt = rhs(t, x, u, params)``."""

    def rhs(self, t, x, u, params=None) -> np.ndarray:  # pragma: no cover - abstract
        """The state derivative ``dx/dt`` at time ``t``.

        Parameters
        ----------
        t, x, u, params
            As in :meth:`Block.output`: time, states ``(B, n)``, inputs ``(B, m)``, ignored ``params``.

        Returns
        -------
        numpy.ndarray, shape (B, n)
        """
        raise NotImplementedError

    def nlsys(self, name: str | None = None, *, inputs=None, outputs=None, states=None):
        """This block as a continuous-time ``control.nlsys`` (one trace: ``x`` and ``u`` 1-D).

        Parameters
        ----------
        name : str, optional
            System name for :func:`control.interconnect`.
        inputs, outputs, states : list of str, optional
            Rename the signals (default: :attr:`inputs`, :attr:`outputs`, :attr:`states`).

        Returns
        -------
        control.NonlinearIOSystem
        """
        import control as ct

        ins, outs, sts = self._io_names(inputs, outputs, states, name)
        return ct.nlsys(self._lifted(self.rhs), self._lifted(self.output), inputs=ins, outputs=outs,
                        states=sts, name=name)


class DiscreteBlock(Block):
    """A block with discrete-time state: ``x(k+1) = update(t_k, x(k), u(k), params)``."""

    def update(self, t, x, u, params=None) -> np.ndarray:  # pragma: no cover - abstract
        """The next state ``x(k+1)`` from the state and input at sample ``t_k``.

        Parameters
        ----------
        t, x, u, params
            The sample instant ``t_k``, ``x(k)``, ``u(k)`` and ``params``, as in :meth:`Block.output`.

        Returns
        -------
        x_next : numpy.ndarray, shape (B, n)
            ``x(k+1)`` of every run.
        """
        raise NotImplementedError

    def nlsys(self, dt=True, name: str | None = None, *, inputs=None, outputs=None, states=None):
        """This block as a discrete-time ``control.nlsys`` with sampling period ``dt``.

        python-control's discrete convention matches the block's: ``y[k] = output(t_k, x[k], u[k])``
        and ``x[k+1] = update(t_k, x[k], u[k])``.

        Parameters
        ----------
        dt : float or True
            Sampling period (``True``: unspecified, as in python-control).
        name : str, optional
            System name for :func:`control.interconnect`.
        inputs, outputs, states : list of str, optional
            Rename the signals.

        Returns
        -------
        control.NonlinearIOSystem
        """
        import control as ct

        if dt is not True:
            dt = check_positive("dt", dt)
        ins, outs, sts = self._io_names(inputs, outputs, states, name)
        return ct.nlsys(self._lifted(self.update), self._lifted(self.output), inputs=ins, outputs=outs,
                        states=sts, name=name, dt=dt)

    def run(self, u, x0=None, params=None, t=None):
        """Drive the block open loop with a whole input sequence.

        Parameters
        ----------
        u : array_like, shape (N,), (N, m) or (N, B, m)
            Inputs at the N samples (``(N,)``: one input, one run; ``(N, m)``: one run).
        x0 : array_like, shape (n,) or (B, n), optional
            Initial state (default :meth:`initial_state`).
        t : array_like, shape (N,), optional
            Sample instants passed to the callbacks (default ``0, 1, ..., N-1``).

        Returns
        -------
        y : numpy.ndarray, shape (N, B, p)
            Outputs ``y(k) = output(t_k, x(k), u(k))``.
        x : numpy.ndarray, shape (N+1, B, n)
            States ``x(0) .. x(N)``.
        """
        from .._validate import check_finite

        check_states_declared(self)
        m = len(self.inputs)
        u = np.asarray(check_finite("u", u), dtype=float)
        if u.ndim == 1 and m == 1:
            u = u[:, None, None]
        elif u.ndim == 2 and u.shape[1] == m:
            u = u[:, None, :]
        if u.ndim != 3 or u.shape[2] != m or u.shape[0] < 1:
            raise ValueError(f"u must have shape (N,), (N, {m}) or (N, B, {m}), got {np.shape(u)}")
        N, B = u.shape[:2]
        x = np.array(self.initial_state() if x0 is None else check_finite("x0", x0), dtype=float, ndmin=1)
        if x.shape not in ((self.n_states,), (B, self.n_states)):
            raise ValueError(f"x0 must have shape ({self.n_states},) or ({B}, {self.n_states}), got {x.shape}")
        x = np.array(np.broadcast_to(x, (B, self.n_states)), dtype=float)
        t = np.arange(N, dtype=float) if t is None else check_finite("t", t, shape=(N,))
        xs = np.empty((N + 1, B, self.n_states))
        ys = None
        xs[0] = x
        output, update = unchecked(self, "output"), unchecked(self, "update")
        for k in range(N):
            yk = output(t[k], x, u[k], params)
            if ys is None:
                ys = np.empty((N, B, yk.shape[1]))
            ys[k] = yk
            x = update(t[k], x, u[k], params)
            xs[k + 1] = x
        return ys, xs


class StaticBlock(Block):
    """The protocol of a memoryless block: ``y = output(t, x, u, params)``, no state (``x`` has zero columns).

    A static block is a class that declares its :attr:`~Block.inputs` and :attr:`~Block.outputs` and
    gets its output from kernels (``class Saturation(KernelBlock, StaticBlock)`` with
    ``kernels = Kernels(output=...)``: the way that compiles, as :class:`StaticGain`) or from an
    ``output`` method. It has direct feedthrough unless it says otherwise. A plain Python function
    (a lambda) is wrapped by :class:`~ctrl_analysis.engine.function_block.FunctionBlock` instead:
    ``StaticBlock(fn, inputs, outputs)``, which wrapped one before, is a ``TypeError`` that says so.
    """

    feedthrough = True

    def __new__(cls, *args, **kwargs):
        if cls is StaticBlock and (args or kwargs):
            raise TypeError("StaticBlock is the protocol of a stateless block, not a function wrapper: wrap a "
                            "function with FunctionBlock(fn, inputs, outputs) (ctrl_analysis.engine.function_block), "
                            "or write the block as a class (KernelBlock, StaticBlock) with an output kernel")
        return super().__new__(cls, *args, **kwargs)

    def nlsys(self, dt=None, name: str | None = None, *, inputs=None, outputs=None):
        """This block as a static ``control.nlsys`` (``dt=None``: usable in continuous and discrete loops).

        Parameters
        ----------
        dt : float, True or None
            Sampling period of the system (``None``: either).
        name : str, optional
            System name for :func:`control.interconnect`.
        inputs, outputs : list of str, optional
            Rename the signals.

        Returns
        -------
        control.NonlinearIOSystem
        """
        import control as ct

        ins, outs, _ = self._io_names(inputs, outputs, (), name)
        m = len(ins)
        output = unchecked(self, "output")

        def outfcn(t, x, u, params=None):
            ub = np.asarray(u, dtype=float).reshape(1, m)
            return np.asarray(output(t, np.empty((1, 0)), ub, params or None), dtype=float).reshape(-1)

        return ct.nlsys(None, outfcn, inputs=ins, outputs=outs, name=name, dt=dt)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(inputs={self.inputs}, outputs={self.outputs})"


def gain_output(t, x, u, p, y):
    """Static gain ``y = D u``, the kernel of :class:`StaticGain`: ``y_i = Σ_j D_ij u_j`` summed left to right.

    ``u``: the ``m`` inputs of one run (or the batch's columns), ``p``: ``D`` (``p × m``, row-major),
    ``y``: the ``p`` outputs, written in place; ``t``, ``x`` unused.
    """
    m = u.shape[0]
    for i in range(y.shape[0]):
        acc = 0.0
        for j in range(m):
            acc += p[i * m + j] * u[j]
        y[i] = acc


class StaticGain(KernelBlock, StaticBlock):
    """A static gain ``y = D u`` (sums, differences, scalings, selections), with a compiled kernel.

    The common static blocks of a loop (a measurement ``y + v``, an error ``r - y``, a case switch
    that routes one of several signals) are gains; written as one they run in the compiled engine.
    The kernel is :func:`gain_output`. A gain per run (e.g. which filter a run feeds back) is given to
    the simulation: ``Loop.simulate(params={"name": {"D": (B, p, m) gains}})``.

    Parameters
    ----------
    D : array_like, shape (p, m)
        The gain matrix.
    inputs, outputs : sequence of str
        Signal names: ``m`` inputs, ``p`` outputs.

    Raises
    ------
    ValueError
        If ``D`` is not finite, is not a matrix, or its shape does not match the numbers of inputs
        and outputs.

    Examples
    --------
    >>> import numpy as np
    >>> meas = StaticGain([[1.0, 1.0]], inputs=("y", "v"), outputs=("y_meas",))
    >>> meas.output(0.0, np.zeros((2, 0)), np.array([[1.0, 0.5], [2.0, -1.0]]))
    array([[1.5],
           [1. ]])
    """

    kernels = Kernels(output=gain_output)

    def __init__(self, D, inputs, outputs):
        D = check_finite("D", D)
        ins, outs = check_names("inputs", inputs), check_names("outputs", outputs)
        if not outs:
            raise ValueError("outputs must name at least one signal")
        if D.shape != (len(outs), len(ins)):
            raise ValueError(f"D must have shape (p, m) = ({len(outs)}, {len(ins)}) (outputs, inputs), got "
                             f"{D.shape}; a gain per run is given to "
                             "Loop.simulate(params={name: {'D': (B, p, m)}})")
        self.D = D
        self.inputs, self.outputs, self.feedthrough = ins, outs, bool(ins)
        self.kernel_params = Layout(("D", D.shape)).pack(D=D)  # the kernel's parameters: D, row-major

    def output(self, t, x, u, params=None) -> np.ndarray:
        return (self.with_params(**params) if params else self)._apply(t, u)

    def _apply(self, t, u):
        """``D u`` of every run, the kernel on the batch's columns (a subclass may gate it: analysis/ckf)."""
        return self.batched("output", t, None, u, self.kernel_params)

    def __repr__(self) -> str:
        return f"StaticGain(D shape {self.D.shape}, inputs={self.inputs}, outputs={self.outputs})"


def delay_update(t, x, u, p, x_next):
    """Kernel update of :class:`UnitDelay`: ``u_prev(k+1) = u(k)`` (one run, or the batch's columns)."""
    x_next[0] = u[0]


class UnitDelay(KernelBlock, DiscreteBlock):
    """One-sample delay ``u_prev(k) = u(k−1)``: input ``u``, state and output ``u_prev``.

    Wherever a loop reads a signal of the previous sample (``u(k−1)`` for a characteristic-model Kalman
    filter or an MFAC law; ``place(UnitDelay(), "delay", inputs=["u"], outputs=["u_prev"])``).

    Parameters
    ----------
    u0 : float
        ``u(−1)``, the output at the first sample.

    Examples
    --------
    >>> import numpy as np
    >>> y, _ = UnitDelay(u0=-1.0).run(np.array([1.0, 2.0, 3.0]))
    >>> y[:, 0, 0]
    array([-1.,  1.,  2.])
    """

    inputs, states, outputs, feedthrough = ("u",), ("u_prev",), ("u_prev",), False
    kernels = Kernels(update=delay_update)

    def __init__(self, u0: float = 0.0):
        self.u0 = float(check_finite("u0", u0, scalar=True))
        self.kernel_params = Layout().pack()

    def initial_state(self) -> np.ndarray:
        return np.array([self.u0])

    def __repr__(self) -> str:
        return f"UnitDelay(u0={self.u0:g})"


class SampledBlock(DiscreteBlock):
    """A continuous block integrated over one sample with a fixed step, its input held: a discrete block.

    ``update`` advances ``block`` over ``[t, t + dt]`` with ``substeps`` steps of ``method``
    (:func:`ctrl_analysis.engine.integrators.rk4_step` or :func:`~ctrl_analysis.engine.integrators.euler_step`, the
    engine's own integrators), so ``SampledBlock(sys, dt).nlsys(dt)`` runs in python-control exactly
    as the engine runs ``sys``. Outputs are the continuous block's outputs at the sample instant.

    Parameters
    ----------
    block : ContinuousBlock
    dt : float
        Sampling period (> 0).
    method : {"rk4", "euler"}
    substeps : int
        Integration steps per sample (1 to :data:`~ctrl_analysis.engine.integrators.MAX_SUBSTEPS`).
    """

    def __init__(self, block: ContinuousBlock, dt: float, method: str = "rk4", substeps: int = 1):
        from .integrators import MAX_SUBSTEPS, STEPPERS

        if not isinstance(block, ContinuousBlock):
            raise TypeError(f"block must be a ContinuousBlock, got {type(block).__name__}")
        self.block = block
        self.dt = check_positive("dt", dt, scalar=True)
        self.method = check_in("method", method, STEPPERS)
        self.substeps = check_int("substeps", substeps, minimum=1, maximum=MAX_SUBSTEPS)
        self._step = STEPPERS[method]
        self.inputs, self.outputs, self.states = block.inputs, block.outputs, block.states
        self.feedthrough = block.feedthrough

    def initial_state(self) -> np.ndarray:
        return self.block.initial_state()

    def update(self, t, x, u, params=None) -> np.ndarray:
        h, rhs = self.dt / self.substeps, unchecked(self.block, "rhs")
        for i in range(self.substeps):
            x = self._step(rhs, t + i * h, x, u, h, params)
        return x

    def output(self, t, x, u, params=None) -> np.ndarray:
        return unchecked(self.block, "output")(t, x, u, params)

    def __repr__(self) -> str:
        return f"SampledBlock({self.block!r}, dt={self.dt}, method={self.method!r}, substeps={self.substeps})"
