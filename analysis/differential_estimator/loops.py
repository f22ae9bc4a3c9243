"""The loops of Examples 1 and 2, built from library blocks through :class:`~ctrl_analysis.engine.loop.Loop`.

The plants (19) and (20) are study blocks (they are the paper's), kernel-first
(:class:`~ctrl_analysis.engine.kernels.KernelBlock`); Σ, Han's ESO, the low-pass softener and the
differential feedback (18) come from the library; the sensor is a static sum (a
:class:`~ctrl_analysis.engine.blocks.StaticGain`). Every block of the simulated loops has a compiled
kernel, from which its batched methods are derived (Example 2's parameter grid and Σ presets are
per-run values given to the simulation, :func:`example2_params`), so each loop runs as one numba
function, and the study needs three loop structures: Example 1 with RK4 and with Euler (always Σ
beside :data:`OBSERVERS` observers) and Example 2. The same loops give, through
:meth:`Loop.interconnect` and :func:`control.linearize`, the linearisation of Example 2.
"""

from __future__ import annotations

import control as ct
import numpy as np

from ctrl_analysis._validate import check_finite
from ctrl_analysis.controllers.differential_feedback import (
    HighOrderDifferentialFeedback,
)
from ctrl_analysis.engine import Execution, Save
from ctrl_analysis.engine.blocks import (
    ContinuousBlock,
    StaticGain,
    signal_names,
)
from ctrl_analysis.engine.kernels import (
    KernelBlock,
    Kernels,
    Layout,
)
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.differential import DifferentialEstimator
from ctrl_analysis.estimators.eso import ExtendedStateObserver

from .paper import Example1, Example2, han_eso_gains

__all__ = [
    "OBSERVERS",
    "PLANT19",
    "PLANT20",
    "LinearPath",
    "Plant19",
    "Plant20",
    "example1_loop",
    "example2_linear",
    "example2_loop",
    "example2_params",
    "han_eso",
    "impulse_response",
    "max_real_eig",
    "pad_observers",
    "plant19_rhs",
    "plant20_rhs",
    "sensor",
    "simulate_example1",
    "simulate_signals",
]


#: Plant (19)'s kernel parameters.
PLANT19 = Layout("b1", "b2", "w_freq")
AT19 = PLANT19.at


def plant19_rhs(t, x, u, p, dx):
    """Kernel of :class:`Plant19` (one run; on a batch's columns it is the batched method); ``p``: :data:`PLANT19`.

    Branch-free (the sign of ``cos`` as a difference of comparisons) so that ``p`` may also hold one
    row per run, transposed: ``p[k]`` is then a column of the batch.
    """
    c = np.cos(p[AT19.w_freq] * t)
    w = 1.0 * (c > 0) - 1.0 * (c < 0)  # w = sign(cos(ω_w t))
    dx[0] = x[1]  # (19) x1' = x2
    # (19) x2' = -(b1 x1 + b2 x1² x2) + w + ξ
    dx[1] = (w + u[0]) - x[0] * (p[AT19.b1] + p[AT19.b2] * x[0] * x[1])


class Plant19(KernelBlock, ContinuousBlock):
    """Plant (19) of Example 1: ``x1' = x2``, ``x2' = -(b1 x1 + b2 x1² x2) + w + ξ``, ``w = sign(cos(ω_w t))``.

    Input ``xi`` (the process noise ξ, held per step); states and outputs ``x[0]``, ``x[1]`` (``x1``, ``x2``). Kernel
    :func:`plant19_rhs` (the batched methods are derived from it).

    Parameters
    ----------
    p : Example1
        ``b1``, ``b2`` and ``w_freq`` are read from it.
    """

    inputs, outputs, states = ("xi",), ("x[0]", "x[1]"), ("x[0]", "x[1]")
    kernels = Kernels(rhs=plant19_rhs)

    def __init__(self, p: Example1):
        self.b1, self.b2, self.w_freq = float(p.b1), float(p.b2), float(p.w_freq)
        self.kernel_params = PLANT19.pack(b1=self.b1, b2=self.b2, w_freq=self.w_freq)


#: Plant (20)'s kernel parameters.
PLANT20 = Layout("b1", "b2", "b3", "w_amp", "w_freq")
AT20 = PLANT20.at


def plant20_rhs(t, x, u, p, dx):
    """Kernel of :class:`Plant20` (one run; on a batch's columns it is the numpy method); ``p``: :data:`PLANT20`.

    Branch-free (the sign of ``cos`` as a difference of comparisons) so that ``p`` may also hold one
    row per run, transposed: ``p[k]`` is then a column of the batch.
    """
    c = np.cos(p[AT20.w_freq] * t)
    w = 1.0 * (c > 0) - 1.0 * (c < 0)  # w = sign(cos(ω_w t))
    dx[0] = x[1]  # (20) x1' = x2
    dx[1] = x[2]  # (20) x2' = x3
    # (20) x3' = b1 x1 - (b2 - x1²) x2 - b3 x3 |x3| + w_amp w + ξ + u
    dx[2] = (p[AT20.b1] * x[0] - (p[AT20.b2] - x[0] * x[0]) * x[1] - p[AT20.b3] * x[2] * abs(x[2])
             + p[AT20.w_amp] * w + u[1] + u[0])


class Plant20(KernelBlock, ContinuousBlock):
    """Plant (20) of Example 2: ``x''' = b1 x1 - (b2 - x1²) x2 - b3 x3|x3| + w + ξ + u``.

    Inputs ``u`` (control), ``xi`` (process noise); states and outputs ``x[0], x[1], x[2]`` (``x1, x2, x3``). Kernel
    :func:`plant20_rhs` (the batched methods are derived from it). A parameter grid on the batch
    axis is given to the simulation: ``Loop.simulate(params={"plant": {"b": (B, 3) values}})``.

    Parameters
    ----------
    p : Example2
    b : tuple of three floats, optional
        ``(b1, b2, b3)``; default ``p``'s.
    w_amp : float, optional
        Amplitude of ``w = w_amp sign(cos(ω_w t))``; 0 makes the origin an equilibrium.
    """

    inputs, outputs, states = ("u", "xi"), ("x[0]", "x[1]", "x[2]"), ("x[0]", "x[1]", "x[2]")
    kernels = Kernels(rhs=plant20_rhs)

    def __init__(self, p: Example2, b=None, w_amp=None):
        b = check_finite("b", (p.b1, p.b2, p.b3) if b is None else b, shape=(3,))
        self.b1, self.b2, self.b3 = (float(v) for v in b)
        self.w_amp = check_finite("w_amp", p.w_amp if w_amp is None else w_amp, scalar=True)
        self.w_freq = float(p.w_freq)
        self.kernel_params = PLANT20.pack(b1=self.b1, b2=self.b2, b3=self.b3, w_amp=self.w_amp, w_freq=self.w_freq)


def sensor(signal: str = "x[0]") -> StaticGain:
    """``y = x1 + η`` (19)/(20), a static sum: a :class:`~ctrl_analysis.engine.blocks.StaticGain` ``[1, 1]``."""
    return StaticGain([[1.0, 1.0]], inputs=(signal, "eta"), outputs=("y",))


def han_eso(p: Example1, tuning_h: float | None = None) -> ExtendedStateObserver:
    """Han's third-order nonlinear ESO with the step-size gains for ``tuning_h`` (default ``p.eso_tuning_ratio · p.h``).

    ``δ = tuning_h`` when a ``tuning_h`` is given, else ``p.eso_delta`` (``None``: the design step).
    Han's form with ``e = z1 - y`` and minus signs equals the library's ``e = y - z1`` with plus signs
    (fal is odd).
    """
    if tuning_h is None:
        h_t = p.eso_tuning_ratio * p.h
        delta = h_t if p.eso_delta is None else p.eso_delta
    else:
        h_t = delta = tuning_h
    return ExtendedStateObserver(han_eso_gains(h_t), b0=0.0, alpha=list(p.eso_alpha), delta=delta)


def example1_loop(p: Example1, esos=None, *, method: str | None = None, h: float | None = None) -> Loop:
    """Plant (19) + sensor + Σ (outputs ``sig[i]``) + ESOs (outputs ``eso[j][i]``), external ``xi``, ``eta``, ``u_eso``.

    Parameters
    ----------
    p : Example1
    esos : sequence of ExtendedStateObserver, optional
        Observers run side by side on the same ``y`` (default: Han's ESO of :func:`han_eso`);
        ``[]`` runs Σ alone.
    method, h : optional
        Integrator and step (default ``p.method``, ``p.h``).
    """
    esos = [han_eso(p)] if esos is None else list(esos)
    sigma = DifferentialEstimator(p.n0, p.a, reading="state")
    blocks = [place(Plant19(p), "plant"), place(sensor(), "sensor"),
              place(sigma, "sigma", outputs=signal_names("sig", p.n0))]
    for j, eso in enumerate(esos):
        blocks.append(place(eso, f"eso{j}", inputs=["y", "u_eso"], outputs=tuple(f"eso[{j}][{i}]" for i in range(3))))
    return Loop(blocks, p.h if h is None else h, method=p.method if method is None else method)


def example2_loop(p: Example2, a: float | None = None, *, b=None, w_amp=None, sigma_reading=None,
                  extra_gain: float = 0.0) -> Loop:
    """Plant (20) + sensor + Σ + controller (18); external ``theta[0..2]``, ``xi``, ``eta``.

    Built for one configuration; a Σ bandwidth and plant coefficients per run are given to the
    simulation (:func:`example2_params`).

    Parameters
    ----------
    p : Example2
    a : float, optional
        Σ's ``a`` (default ``p.a``).
    b, w_amp :
        Passed to :class:`Plant20` (``b`` default ``p``'s).
    sigma_reading : {"state", "corrected"}, optional
        Σ's estimate reading (default ``p.reading``).
    extra_gain : float
        If non-zero, adds ``extra_gain · (0 - x̂4)`` to ``u``: the reading in which the printed
        trailing 1 multiplies ε4 = θ4 - x̂4 with θ4 = v''' = 0 (a sensitivity of the linear analysis).
    """
    reading = p.reading if sigma_reading is None else sigma_reading
    sigma = DifferentialEstimator(p.n0, p.a if a is None else a, reading="state")
    ctrl = HighOrderDifferentialFeedback(p.K)
    u_name = "u" if extra_gain == 0.0 else "u18"
    blocks = [place(Plant20(p, (p.b1, p.b2, p.b3) if b is None else b, w_amp), "plant"), place(sensor(), "sensor")]
    if reading == "state":
        blocks.append(place(sigma, "sigma"))
    else:  # eq. (11): x̂ = C z + D y, a static gain after Σ's states, so Σ keeps its kernel
        blocks.append(place(sigma, "sigma", outputs=signal_names("z", p.n0)))
        blocks.append(place(StaticGain(_reading_gain(sigma, reading), inputs=(*signal_names("z", p.n0), "y"),
                                       outputs=signal_names("xhat", p.n0)), "reading"))
    blocks.append(place(ctrl, "ctrl", inputs=list(signal_names("theta", 3)) + list(signal_names("xhat", 3)),
                        outputs=[u_name]))
    if extra_gain != 0.0:
        blocks.append(place(StaticGain([[1.0, -extra_gain]], inputs=("u18", "xhat[3]"), outputs=("u",)), "eps4"))
    return Loop(blocks, p.h)


def _reading_gain(est: DifferentialEstimator, reading: str) -> np.ndarray:
    """``[C D]`` of eq. (11)'s reading ``x̂ = C z + D y`` of Σ ``est``."""
    return np.hstack(est.estimate_matrices(reading))


def example2_params(p: Example2, a, b, *, sigma_reading=None) -> dict:
    """Per-run values of :func:`example2_loop`'s blocks for :meth:`~ctrl_analysis.engine.loop.Loop.simulate`.

    Parameters
    ----------
    p : Example2
    a : array_like, shape (B,)
        Σ's ``a`` per run.
    b : tuple of three array_like, shape (B,)
        ``b1``, ``b2``, ``b3`` per run.
    sigma_reading : {"state", "corrected"}, optional
        As in :func:`example2_loop` (the corrected reading's gain follows each run's ``a``).

    Returns
    -------
    dict
        ``{"plant": {"b": (B, 3)}, "sigma": {"a": (B,)}}`` (and ``{"reading": {"D": ...}}``).
    """
    reading = p.reading if sigma_reading is None else sigma_reading
    a = np.asarray(a, dtype=float)
    params = {"plant": {"b": np.column_stack([np.asarray(v, dtype=float) for v in b])}, "sigma": {"a": a}}
    if reading != "state":
        gains = {v: _reading_gain(DifferentialEstimator(p.n0, v, reading="state"), reading) for v in np.unique(a)}
        params["reading"] = {"D": np.stack([gains[v] for v in a])}
    return params


#: Samples (steps × runs) per signal per chunk of :func:`simulate_signals`: about 4 MB a signal.
CHUNK_SAMPLES = 500_000


def simulate_signals(loop: Loop, n_steps: int, keep, *, inputs, runs: int, chunk: int | None = None,
                     bound: float = 1e8, seeds=None, params=None):
    """Run ``loop`` in time chunks (to bound memory), keeping only the signals ``keep``.

    The state is carried exactly from chunk to chunk, so the result equals one long run; ``params``
    (per-run block parameters) are passed to every chunk's :meth:`Loop.simulate`. ``chunk`` (steps)
    defaults to :data:`CHUNK_SAMPLES` samples per signal, at least 2000 steps: a small batch (a box
    evaluation's few runs) runs in one or two calls, a large one in bounded pieces.

    Returns
    -------
    signals : dict of str -> ndarray, shape (N+1, B)
    diverged : ndarray of bool, shape (B,)
    diverged_step : ndarray of int, shape (B,)
        First step at which the run left ``|x| <= bound`` (-1 if never).
    """
    if chunk is None:
        chunk = max(2000, CHUNK_SAMPLES // max(int(runs), 1))
    out = {s: np.empty((n_steps + 1, runs)) for s in keep}
    diverged = np.zeros(runs, dtype=bool)
    step = np.full(runs, -1)
    x0 = None
    for k0 in range(0, n_steps, chunk):
        n = min(chunk, n_steps - k0)
        ins = {s: (v[k0:k0 + n + 1] if isinstance(v, np.ndarray) and v.ndim else v) for s, v in inputs.items()}
        res = loop.simulate(n, inputs=ins, x0=x0, runs=runs, t0=k0 * loop.dt, params=params,
                            save=Save(keep=list(keep), states=False), execution=Execution(bound=bound),
                            seeds=seeds)
        for s in keep:
            out[s][k0:k0 + n + 1] = res[s]
        new = res.diverged & ~diverged
        step[new] = k0 + res.diverged_step[new]
        diverged |= res.diverged
        x0 = {name: np.nan_to_num(x) for name, x in res.final_states.items() if x.shape[1]}
    return out, diverged, step


def example2_linear(p: Example2, a: float | None = None, b1: float | None = None, b2: float | None = None, *,
                    reading: str | None = None, extra_gain: float = 0.0) -> np.ndarray:
    """State matrix of Example 2's loop linearised about the origin (w = 0, no noise), by :func:`control.linearize`.

    The loop of :func:`example2_loop` as a ``control.interconnect`` (plant, sensor, Σ, controller)
    linearised at x = 0, inputs (θ, ξ, η) = 0. ``b3`` drops out (x3|x3| has zero slope at 0).
    """
    b = (p.b1 if b1 is None else b1, p.b2 if b2 is None else b2, p.b3)
    loop = example2_loop(p, a, b=b, w_amp=0.0, sigma_reading=reading, extra_gain=extra_gain)
    sys = loop.interconnect()
    lin = ct.linearize(sys, np.zeros(sys.nstates), np.zeros(sys.ninputs))
    return np.asarray(lin.A)


def max_real_eig(M) -> float:
    """Largest real part of the eigenvalues of ``M``."""
    return float(np.max(np.linalg.eigvals(M).real))


#: Every Example 1 loop runs Σ beside this many observers: one loop structure per integrator (compiled once).
OBSERVERS = 2


def pad_observers(esos) -> list:
    """``esos`` followed by linear ESOs (all poles at -10 rad/s) up to :data:`OBSERVERS` observers.

    The observers do not act on the plant, so an added one changes no other signal (and, linear and
    slow, it does not diverge); it keeps every Example 1 simulation on the structure of the main one.

    Parameters
    ----------
    esos : sequence of ExtendedStateObserver

    Returns
    -------
    list of ExtendedStateObserver
    """
    esos = list(esos)
    return esos + [ExtendedStateObserver.from_bandwidth(2, 10.0)] * max(0, OBSERVERS - len(esos))


def simulate_example1(p: Example1, seeds, noise, esos=None, *, method: str | None = None, chunk: int | None = None):
    """Example 1 over ``seeds`` (one batch row each) with the held noise ``[ξ, η]`` of shape ``(N, B, 2)``.

    The loop carries :func:`pad_observers` ``(esos)``; only the observers ``esos`` are kept.

    Returns ``(signals, diverged, diverged_step)`` of :func:`simulate_signals` with ``x[0]``, ``x[1]``,
    Σ's ``sig[0]``, ``sig[1]`` and each ESO's ``eso[j][0]``, ``eso[j][1]``.
    """
    esos = [han_eso(p)] if esos is None else list(esos)
    loop = example1_loop(p, pad_observers(esos), method=method)
    keep = ["x[0]", "x[1]", "sig[0]", "sig[1]"] + [f"eso[{j}][{i}]" for j in range(len(esos)) for i in (0, 1)]
    n_steps = noise.shape[0]
    inputs = {"xi": noise[:, :, 0], "eta": noise[:, :, 1], "u_eso": 0.0}
    return simulate_signals(loop, n_steps, keep, inputs=inputs, runs=len(seeds), chunk=chunk, bound=p.bound,
                            seeds=seeds)


def impulse_response(sysd, n: int, block: int = 128, outputs=None) -> np.ndarray:
    """First ``n`` samples of a discrete system's impulse response from input 0, ``D, CB, CAB, CA²B, ...``.

    Powers of ``A`` in blocks of ``block`` (a few hundred small products for any ``n``), so no
    polynomial (transfer-function or zero-pole) form is ever formed: those are ill-conditioned for
    Σ's clustered poles near z = 1.

    Parameters
    ----------
    sysd : control.StateSpace
        Discrete-time system.
    n : int
        Samples.
    block : int
        Powers of ``A`` per block.
    outputs : sequence of int, optional
        Outputs to return, shape ``(n, len(outputs))`` (the powers of ``A`` shared); default output 0, shape ``(n,)``.
    """
    rows = [0] if outputs is None else list(outputs)
    A, b = np.asarray(sysd.A), np.asarray(sysd.B)[:, 0]
    G = np.empty((A.shape[0], block))
    for j in range(block):  # A^j B
        G[:, j] = b
        b = A @ b
    A_block = np.linalg.matrix_power(A, block)
    h = np.empty((n, len(rows)))
    h[0] = np.asarray(sysd.D)[rows, 0]
    row = np.asarray(sysd.C)[rows]
    for k in range(1, n, block):  # h_k = C A^(k-1) B
        seg = row @ G
        h[k:k + block] = seg[:, :min(block, n - k)].T
        row = row @ A_block
    return h[:, 0] if outputs is None else h


class LinearPath:
    """Linear estimators (input ``y``) driven by ``y(t) = x1(t) + η_k``, evaluated at the samples without the engine.

    The plant output ``x1`` is smooth: its part of the response uses the first-order-hold
    discretisation (exact for ``x1`` linear between samples); the held noise ``η`` uses the
    zero-order hold (exact). Both by :func:`control.c2d`; the responses are convolutions with the
    discrete impulse responses (:func:`impulse_response`, cut where they have decayed below
    :attr:`TAIL` of their peak) done by FFT over the whole batch, the input spectra computed once
    per FFT length: parameter sweeps of linear estimators cost a few FFTs each. Zero initial state.

    Parameters
    ----------
    x1 : ndarray, shape (N, B)
        Plant output at the samples (finite).
    eta : ndarray, shape (N, B)
        Measurement noise held over each step.
    h : float
        Sampling step.
    """

    #: An impulse response is cut where it has decayed below this fraction of its peak (for every output and
    #: hold): far below the single-precision FFT's resolution, so the convolution is unchanged.
    TAIL = 1e-10

    def __init__(self, x1, eta, h: float):
        self.n = x1.shape[0]
        self.h = float(h)
        from scipy import fft

        self._fft = fft
        # single precision: ~1e-7 relative per sample, far below the Monte Carlo spread, half the memory traffic
        self._inputs = {m: np.asarray(u, dtype=np.float32) for m, u in (("foh", x1), ("zoh", eta))}
        self._spectra = {}

    def spectra(self, nfft: int) -> dict:
        """The inputs' spectra (``foh``: x1, ``zoh``: η) on ``nfft`` points, computed once per length."""
        if nfft not in self._spectra:
            self._spectra[nfft] = {m: self._fft.rfft(u, nfft, axis=0) for m, u in self._inputs.items()}
        return self._spectra[nfft]

    def estimates(self, sys, outputs=(0, 1)) -> list:
        """Outputs ``outputs`` of ``sys`` (a ``control.StateSpace`` whose input 0 is ``y``), each ``(N, B)``."""
        return next(self.estimates_many([sys], outputs))

    def estimates_many(self, systems, outputs=(0, 1)):
        """:meth:`estimates` of several systems, discretised together: yields each system's list of outputs.

        The systems are stacked block-diagonally (input 0 of each driven by ``y``) and discretised once per
        hold: one matrix exponential per hold for a whole parameter sweep, each block the system's own
        discretisation (the exponential of a block-diagonal matrix is block-diagonal). The responses are
        computed system by system as the iterator advances (memory of one system's outputs at a time).
        """
        outputs = list(outputs)
        systems = list(systems)
        A = _block_diag([np.asarray(s.A) for s in systems])
        B = np.concatenate([np.asarray(s.B)[:, :1] for s in systems])
        C = _block_diag([np.asarray(s.C)[outputs] for s in systems])
        D = np.concatenate([np.asarray(s.D)[outputs, :1] for s in systems])
        stacked = ct.ss(A, B, C, D)
        rows = list(range(C.shape[0]))
        g = {method: impulse_response(ct.c2d(stacked, self.h, method=method), self.n, outputs=rows)
             for method in self._inputs}
        # a stable estimator's response decays: a convolution of N samples with a kernel of L needs N + L - 1 points
        big = np.zeros(self.n, dtype=bool)
        for v in g.values():
            a = np.abs(v)
            big |= np.any(a > self.TAIL * a.max(axis=0), axis=1)
        length = int(np.flatnonzero(big)[-1]) + 1 if big.any() else 1
        nfft = self._fft.next_fast_len(self.n + length - 1, real=True)
        return self._responses({m: v[:length] for m, v in g.items()}, nfft, len(systems), len(outputs))

    def _responses(self, g, nfft, n_systems, m):
        spectra = self.spectra(nfft)
        for j in range(n_systems):
            out = []
            for k in range(j * m, (j + 1) * m):
                spec = None
                for method, U in spectra.items():
                    term = U * self._fft.rfft(g[method][:, k].astype(np.float32), nfft)[:, None]
                    spec = term if spec is None else np.add(spec, term, out=spec)  # in place: no extra temporaries
                out.append(self._fft.irfft(spec, nfft, axis=0, overwrite_x=True)[: self.n])
            yield out


def _block_diag(blocks) -> np.ndarray:
    rows = sum(b.shape[0] for b in blocks)
    cols = sum(b.shape[1] for b in blocks)
    M = np.zeros((rows, cols))
    i = j = 0
    for b in blocks:
        M[i:i + b.shape[0], j:j + b.shape[1]] = b
        i, j = i + b.shape[0], j + b.shape[1]
    return M
