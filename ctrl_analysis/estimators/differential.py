"""The model-free differential state estimator Σ: parameters, linear models and right-hand side.

Σ of order ``n0`` driven by the measured signal ``y`` (states ``z_1..z_n0``)::

    z_i'  = z_(i+1) + a_i (y - z_1),   i = 1..n0-1
    z_n0' = a_n0 (y - z_1)

with ``a_i = K C(n0-1, i-1) a^(i-1)`` (all ``n0 - 1`` open-loop zeros at ``-a``) and, by default,
``K`` the gain that puts a double closed-loop pole at the real-axis breakaway point ``-n0 a``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import control as ct
import numpy as np

from .._validate import check_array, check_in, check_int, check_positive
from ..engine.blocks import ContinuousBlock, signal_names
from ..engine.kernels import KernelBlock, Kernels
from ..symbolic.differential import (
    MAX_ORDER,
    breakaway_gain,
    breakaway_point,
    differential_coefficients,
)

__all__ = ["DifferentialEstimator", "READINGS"]

#: The two ways of reading estimates off Σ: ``"state"`` (x̂_i = z_i) and ``"corrected"``
#: (x̂_i = z_i + a_(i-1) (y - z_1)).
READINGS = ("state", "corrected")


def sigma_rhs(t, z, u, p, dz):
    """Σ, eq. (2): ``z_i' = a_i (y - z_1) + z_(i+1)``, ``z_n0' = a_n0 (y - z_1)``; ``p`` the gains ``a_i``.

    Scalar indexing only: one run in the compiled engine, the batch's columns in the batched methods.
    The order is the state's length; ``p`` is :attr:`DifferentialEstimator.a_coeffs`.

    Parameters
    ----------
    t, z, u, p
        Time (unused), Σ's state, its input ``[y]`` and the gains ``a_i``.
    dz : numpy.ndarray
        The derivative ``z'``, written in place.
    """
    n = z.shape[0]
    e = u[0] - z[0]
    for i in range(n - 1):
        dz[i] = p[i] * e + z[i + 1]  # (2)
    dz[n - 1] = p[n - 1] * e


def sigma_corrected_output(t, z, u, p, y):
    """Eq. (11), corrected reading: ``x̂_1 = z_1``, ``x̂_i = z_i + a_(i-1) (y - z_1)``; arguments as :func:`sigma_rhs`.

    Parameters
    ----------
    t, z, u, p
        As :func:`sigma_rhs`.
    y : numpy.ndarray
        The estimates ``x̂``, written in place.
    """
    e = u[0] - z[0]
    y[0] = z[0]
    for i in range(1, z.shape[0]):
        y[i] = z[i] + p[i - 1] * e  # (11)


#: Σ's kernels per reading: the state reading outputs the state, the corrected one eq. (11).
_KERNELS = {"state": Kernels(rhs=sigma_rhs), "corrected": Kernels(output=sigma_corrected_output, rhs=sigma_rhs)}


@dataclass(frozen=True)
class DifferentialEstimator(KernelBlock, ContinuousBlock):
    """Differential state estimator Σ of order ``n0`` (a chain of integrators with output injection).

    Parameters
    ----------
    n0 : int
        Order of Σ (number of states), ``2 <= n0 <= 30``
        (:data:`ctrl_analysis.symbolic.differential.MAX_ORDER`: beyond it the design gain and the
        poles cannot be computed reliably in double precision). To estimate ``x`` and its first
        ``n - 1`` derivatives, take ``n0 >= n + 1``.
    a : float
        The ``n0 - 1`` open-loop zeros sit at ``-a``; ``> 0`` and finite, in 1/s.
    K : float, optional
        Open-loop gain, ``> 0``. Default: the breakaway design gain ``n0^n0 a / (n0-1)^(n0-1)``,
        which puts a double closed-loop pole at ``-n0 a``.
    reading : {"state", "corrected"}
        Which estimates the block outputs (see :meth:`estimate_matrices`); ``"corrected"`` has
        direct feedthrough from ``y``. The kernels are :func:`sigma_rhs` and, for the corrected
        reading, :func:`sigma_corrected_output`.
    allow_unstable : bool, keyword
        An explicit ``K`` that puts a closed-loop pole in the closed right half-plane raises
        ``ValueError`` unless this is ``True`` (to study an unstable design on purpose). Same opt-out
        as ``ExtendedStateObserver(allow_unstable=...)``; ``AlphaBetaFilter(require_stable=False)``.

    Block signals: input ``y``; states ``z[0]..z[n0-1]``; outputs ``xhat[0]..xhat[n0-1]``.

    Attributes
    ----------
    a_coeffs : numpy.ndarray
        ``[a_1, ..., a_n0]`` (read-only), ``a_i = K C(n0-1, i-1) a^(i-1)``.
    tf : control.TransferFunction
        Closed loop ``Φ(s)``, y -> z_1.
    open_loop_tf : control.TransferFunction
        Open loop ``G(s) = K (s + a)^(n0-1) / s^n0``.
    ss : control.StateSpace
        Input ``y``, states and outputs ``z[0]..z[n0-1]`` (``z[i-1]`` is the paper's ``z_i``).
    poles : numpy.ndarray
        Closed-loop poles, sorted by decreasing real part.

    Raises
    ------
    TypeError
        If ``n0`` is not an integer.
    ValueError
        If ``n0 < 2`` or ``n0 > 30``, ``a`` is not finite and ``> 0``, ``K`` is not finite and
        ``> 0``, or Σ is unstable with ``K`` (and ``allow_unstable`` is not set).

    References
    ----------
    Qi Guoyuan, Chen Zengqiang, Xue Wei, Yuan Zhuzhi, "A new differential state estimator and
    controller for nonlinear stochastic system", Acta Electronica Sinica 32(4), 2004:
    eq. (2) the estimator, (3) Φ(s), (4) G(s), (5)-(6) the coefficients, (8)-(9) the gain,
    (11) and remark (1) the two estimate readings. The coefficient signs and the gain are the
    derived ones (the paper's printed eq. (5) last term and eq. (9) exponent differ).

    Examples
    --------
    >>> import control as ct
    >>> import numpy as np
    >>> est = DifferentialEstimator(5, 2.0)
    >>> est.K
    24.4140625
    >>> float(ct.dcgain(est.tf))
    1.0
    >>> np.round(est.poles[-2:].real, 6)
    array([-10., -10.])
    """

    n0: int
    a: float
    K: float | None = None
    reading: str = "state"
    a_coeffs: np.ndarray = field(init=False, repr=False, compare=False)
    allow_unstable: bool = field(default=False, kw_only=True, repr=False, compare=False)

    def __post_init__(self):
        n0 = check_int("n0", self.n0, minimum=2, maximum=MAX_ORDER)
        a = check_positive("a", self.a, scalar=True)
        explicit_gain = self.K is not None
        k = breakaway_gain(n0, a) if self.K is None else check_positive("K", self.K, scalar=True)
        if not isinstance(self.allow_unstable, (bool, np.bool_)):
            raise TypeError(f"allow_unstable must be True or False, got {self.allow_unstable!r}")
        object.__setattr__(self, "n0", n0)
        object.__setattr__(self, "a", float(a))
        object.__setattr__(self, "K", float(k))
        check_in("reading", self.reading, READINGS)
        coeffs = differential_coefficients(n0, a, k)  # (5)+(6)
        coeffs.setflags(write=False)
        object.__setattr__(self, "a_coeffs", coeffs)
        if explicit_gain and not self.allow_unstable:
            worst = float(self.poles[0].real)
            if worst >= 0:
                raise ValueError(f"K = {k:g} makes Σ unstable (n0 = {n0}, a = {a:g}: closed-loop pole with real "
                                 f"part {worst:.4g} >= 0); pass allow_unstable=True to study it anyway")

    # ------------------------------------------------------------------ linear models
    @property
    def breakaway_point(self) -> float:
        """Real-axis breakaway (break-in) point ``-n0 a`` of the root locus of ``G``, in 1/s."""
        return breakaway_point(self.n0, self.a)

    @property
    def characteristic_polynomial(self) -> np.ndarray:
        """``[1, a_1, ..., a_n0]``: coefficients of ``s^n0 + a_1 s^(n0-1) + ... + a_n0``."""
        return np.concatenate(([1.0], self.a_coeffs))

    @property
    def tf(self) -> ct.TransferFunction:
        """Closed loop y -> z_1, eq. (3)."""
        # (3) Φ(s) = (a_1 s^(n0-1) + ... + a_n0) / (s^n0 + a_1 s^(n0-1) + ... + a_n0)
        return ct.tf(self.a_coeffs, self.characteristic_polynomial, inputs="y", outputs="z[0]")

    @property
    def open_loop_tf(self) -> ct.TransferFunction:
        """Open loop, eq. (4) with (6)."""
        # (4) G(s) = K (s + a)^(n0-1) / s^n0 = (a_1 s^(n0-1) + ... + a_n0) / s^n0
        den = np.zeros(self.n0 + 1)
        den[0] = 1.0
        return ct.tf(self.a_coeffs, den, inputs="e", outputs="z[0]")

    @property
    def A(self) -> np.ndarray:
        """State matrix of eq. (2): ``-a`` in the first column, ones on the superdiagonal."""
        A = np.diag(np.ones(self.n0 - 1), 1)
        A[:, 0] = -self.a_coeffs
        return A

    @property
    def B(self) -> np.ndarray:
        """Input matrix of eq. (2): ``[a_1, ..., a_n0]^T``, shape ``(n0, 1)``."""
        return self.a_coeffs.reshape(-1, 1).copy()

    @property
    def ss(self) -> ct.StateSpace:
        """Eq. (2) as a state-space system: input ``y``, outputs ``z[0]..z[n0-1]``."""
        names = list(self.states)
        # (2) z' = A z + B y, outputs all states
        return ct.ss(self.A, self.B, np.eye(self.n0), np.zeros((self.n0, 1)),
                     inputs="y", states=names, outputs=names)

    @property
    def poles(self) -> np.ndarray:
        """Closed-loop poles (roots of the denominator of Φ), by decreasing real part.

        Computed on the normalised polynomial (``s = a σ``: ``σ^n0 + (K/a) (σ + 1)^(n0-1)``, whose
        coefficients do not span powers of ``a``) and scaled back, so they stay accurate for every
        ``a``; the roots of :attr:`characteristic_polynomial` itself lose accuracy for small ``a``.
        """
        normalised = np.concatenate(([1.0], differential_coefficients(self.n0, 1.0, self.K / self.a)))
        p = self.a * np.roots(normalised)
        return p[np.lexsort((p.imag, -p.real))]

    # ------------------------------------------------------------------ estimates
    def estimate_matrices(self, reading: str = "state") -> tuple[np.ndarray, np.ndarray]:
        """``(C, D)`` with ``x̂ = C z + D y`` for the chosen estimate reading.

        Parameters
        ----------
        reading : {"state", "corrected"}
            ``"state"``: x̂_i = z_i (remark (1), with measurement noise). ``"corrected"``:
            x̂_1 = z_1, x̂_i = z_i + a_(i-1) (y - z_1), i = 2..n0 (eq. 11), i.e. x̂_i = z_(i-1)'.

        Returns
        -------
        C : numpy.ndarray, shape (n0, n0)
        D : numpy.ndarray, shape (n0, 1)

        Notes
        -----
        With the ``"corrected"`` reading, y -> x̂_i is ``s^(i-1) Φ(s)``: biproper for ``i = 2``
        (high-frequency gain ``a_1``) and improper beyond, so measurement noise reaches the
        estimates unfiltered; with ``"state"`` every channel y -> z_i is strictly proper.
        """
        check_in("reading", reading, READINGS)
        C = np.eye(self.n0)
        D = np.zeros((self.n0, 1))
        if reading == "corrected":
            # (11) x̂_i = z_i + a_(i-1) (y - z_1), i = 2..n0
            C[1:, 0] -= self.a_coeffs[:-1]
            D[1:, 0] = self.a_coeffs[:-1]
        return C, D

    def estimates(self, z, y, reading: str = "state") -> np.ndarray:
        """State estimates ``x̂_1..x̂_n0`` from the states ``z`` and the measurement ``y``.

        Parameters
        ----------
        z : array_like, shape (..., n0)
            States of Σ on the last axis (e.g. ``(n0,)``, ``(B, n0)`` or ``(T, n0)``; a
            python-control response has them on the first axis: pass ``resp.states.T``).
        y : array_like
            Measurement, broadcastable to ``z.shape[:-1]`` (a trailing axis of length 1 is allowed).
        reading : {"state", "corrected"}
            See :meth:`estimate_matrices`.

        Returns
        -------
        numpy.ndarray, shape (..., n0)
        """
        z, y = self._check_zy(z, y)
        C, D = self.estimate_matrices(reading)
        return z @ C.T + y[..., None] * D[:, 0]

    # ------------------------------------------------------------------ block protocol
    inputs = ("y",)

    @property
    def states(self) -> tuple:
        return signal_names("z", self.n0)

    @property
    def outputs(self) -> tuple:
        return signal_names("xhat", self.n0)

    @property
    def feedthrough(self) -> bool:
        return self.reading == "corrected"

    @property
    def kernels(self) -> Kernels:
        """The kernels of the block's reading (:func:`sigma_rhs`; the output of the corrected reading)."""
        return _KERNELS[self.reading]

    @property
    def kernel_params(self) -> np.ndarray:
        """The kernels' parameters: the gains :attr:`a_coeffs` (a writable copy, as the compiled engine takes it)."""
        return np.array(self.a_coeffs, dtype=float)

    def nlsys(self, name: str | None = None, reading: str | None = None, **names) -> ct.NonlinearIOSystem:
        """Σ as a ``control.nlsys``: input ``y``, states ``z[0..n0-1]``, outputs ``xhat[0..n0-1]``.

        Parameters
        ----------
        name : str, optional
            System name (for ``control.interconnect``).
        reading : {"state", "corrected"}, optional
            Which estimates the outputs are (default: the block's own ``reading``).
        **names
            ``inputs``, ``outputs``, ``states`` renames, as in :meth:`ContinuousBlock.nlsys`.

        Returns
        -------
        control.NonlinearIOSystem

        Examples
        --------
        >>> import control as ct
        >>> import numpy as np
        >>> est = DifferentialEstimator(3, 5.0)
        >>> sys = est.nlsys(name="sigma")
        >>> resp = ct.input_output_response(sys, np.linspace(0, 1, 101), 1.0)
        >>> bool(abs(resp.outputs[0, -1] - 1) < 1e-2)
        True
        """
        block = self if reading is None or reading == self.reading else replace(self, reading=reading)
        return ContinuousBlock.nlsys(block, name, **names)

    # ------------------------------------------------------------------ helpers
    def _check_zy(self, z, y) -> tuple[np.ndarray, np.ndarray]:
        z = check_array("z", z)
        if z.ndim < 1 or z.shape[-1] != self.n0:
            raise ValueError(f"z must have the {self.n0} states of Σ on its last axis, got shape {z.shape}")
        y = check_array("y", y)
        if y.ndim >= 1 and y.shape[-1] == 1 and y.ndim >= z.ndim:
            y = y[..., 0]  # python-control input vector (1,) or a column (B, 1)
        try:
            if np.broadcast_shapes(y.shape, z.shape[:-1]) != z.shape[:-1]:
                raise ValueError
        except ValueError:
            raise ValueError(
                f"y must be broadcastable to z.shape[:-1] = {z.shape[:-1]}, got shape {y.shape}"
            ) from None
        return z, y
