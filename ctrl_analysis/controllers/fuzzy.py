"""Two-input Mamdani fuzzy controller (min–max inference, centroid) and its interpolated lookup table.

A classical two-dimensional fuzzy controller: the error ``e`` and its rate ``ec`` are quantised
onto symmetric universes ``[−X_e, X_e]``, ``[−X_ec, X_ec]`` (factors ``Ke``, ``Kec``, clipped at the
ends), fuzzified with evenly spaced triangular terms, combined by a rule table with ``min`` (AND and
Mamdani implication) and ``max`` (aggregation), defuzzified by the centroid of the aggregated
output set on ``[−Y, Y]`` and scaled by ``Ku``. Nothing here is specific to a plant or a paper.

Both controllers are stateless discrete blocks with direct feedthrough (inputs ``e``, ``ec``,
output ``u``): in a :class:`~ctrl_analysis.engine.loop.Loop` their output is computed at each sample and
held, i.e. the controller is sampled. :class:`FuzzyLookupController` precomputes the control
surface on a grid (the classical query table) and interpolates it bilinearly.
"""

from __future__ import annotations

import math

import numpy as np

from .._validate import check_finite, check_int, check_positive
from ..engine.blocks import DiscreteBlock
from ..engine.kernels import Layout

__all__ = [
    "FuzzyController",
    "FuzzyLookupController",
    "piecewise_linear_centroid",
    "sum_rule_table",
    "triangular_memberships",
]


def triangular_memberships(x, centers, width):
    """Memberships of ``x`` in evenly spaced triangular terms: ``μ_i(x) = max(0, 1 − |x − c_i| / width)``.

    Parameters
    ----------
    x : ndarray, shape (B,) or (N,)
        Points (already clipped to the universe).
    centers : ndarray, shape (n,)
        Term centres (peaks).
    width : float
        Half-support of each triangle (the spacing of the centres for a partition of unity).

    Returns
    -------
    ndarray, shape (B, n)
    """
    return np.maximum(0.0, 1.0 - np.abs(x[:, None] - centers[None, :]) / width)


def piecewise_linear_centroid(z, mu):
    """Centroid ``∫ z μ(z) dz / ∫ μ(z) dz`` of the piecewise-linear interpolant of samples ``μ`` on a uniform grid.

    Exact for a piecewise-linear membership whose kinks lie on the grid (the integral of each
    segment's trapezoid is summed); this is what :func:`skfuzzy.defuzz` (``'centroid'``) computes.

    Parameters
    ----------
    z : ndarray, shape (N,)
        Uniform grid of the output universe.
    mu : ndarray, shape (B, N)
        Aggregated membership, not identically zero in any row.

    Returns
    -------
    ndarray, shape (B,)
    """
    dz = z[1] - z[0]
    a, b = mu[:, :-1], mu[:, 1:]
    # segment [z0, z0 + dz], μ linear from a to b: ∫ μ = dz (a + b)/2, ∫ z μ = dz [z0 (a + b)/2 + dz (a + 2b)/6]
    area = 0.5 * (a + b)
    moment = z[None, :-1] * area + dz * (a + 2.0 * b) / 6.0
    return np.sum(moment, axis=1) / np.sum(area, axis=1)


def sum_rule_table(n_terms: int = 7, sign: int = 1) -> np.ndarray:
    """The rule table ``U = sat(sign·(E + EC))`` of a PD-like fuzzy controller, as output term indices.

    Terms are indexed ``0 .. n−1`` (``n`` odd; e.g. NB NM NS ZO PS PM PB), centred at ``m = (n−1)/2``:
    the rule for input terms ``i``, ``j`` has output term ``m + clip(sign·((i − m) + (j − m)), −m, m)``.

    Parameters
    ----------
    n_terms : int
        Odd number of terms on each universe (>= 3).
    sign : {1, −1}

    Returns
    -------
    ndarray of int, shape (n_terms, n_terms)
    """
    n = check_int("n_terms", n_terms, minimum=3)
    if n % 2 == 0:
        raise ValueError(f"n_terms must be odd, got {n}")
    if isinstance(sign, bool) or sign not in (1, -1):
        raise ValueError(f"sign must be 1 or -1, got {sign!r}")
    m = (n - 1) // 2
    i = np.arange(n) - m
    return (m + np.clip(sign * (i[:, None] + i[None, :]), -m, m)).astype(int)


class _FuzzyBlock(DiscreteBlock):
    """What both fuzzy blocks share: signals (inputs ``e``, ``ec``; output ``u``; no state) and the
    physical-units path ``u = Ku · surface(quantise(e, ec))``; subclasses define :meth:`_surface`."""

    inputs = ("e", "ec")
    outputs = ("u",)
    states = ()
    feedthrough = True

    def _surface(self, E, EC):  # pragma: no cover - abstract
        raise NotImplementedError

    def _scaling(self):
        """The :class:`FuzzyController` whose factors apply."""
        return self

    def evaluate(self, e, ec):
        """Control ``u`` for physical inputs.

        Parameters
        ----------
        e, ec : array_like
            Error and error rate, finite arrays of equal shape.

        Returns
        -------
        ndarray
            ``u``, same shape as ``e``.

        Raises
        ------
        ValueError
            If ``e`` or ``ec`` holds NaN or inf, or their sizes differ.

        Notes
        -----
        From ``_COMPILED_MIN`` points on, and when numba is available, the block's compiled kernel
        (:meth:`kernel`) is applied point by point (the Mamdani controller's kernel gives the
        aggregated set and numpy takes its centroid); bit for bit the numpy method's result
        (``tests/lib/test_fuzzy.py``).
        """
        e = np.asarray(check_finite("e", e), dtype=float)
        ec = np.asarray(check_finite("ec", ec), dtype=float).reshape(-1)
        if ec.size != e.size:
            raise ValueError(f"e and ec must have the same number of points, got {e.size} and {ec.size}")
        if e.size >= _COMPILED_MIN and _compiled_ok():  # many points: the compiled twin of output()
            return self._evaluate_compiled(e.reshape(-1), ec).reshape(e.shape)
        fc = self._scaling()
        E, EC = fc.quantise(e.reshape(-1), ec)
        return (fc.Ku * self._surface(E, EC)).reshape(e.shape)

    def output(self, t, x, u, params=None) -> np.ndarray:
        fc = self._scaling()
        E, EC = fc.quantise(u[:, 0], u[:, 1])
        return (fc.Ku * self._surface(E, EC))[:, None]

    def update(self, t, x, u, params=None) -> np.ndarray:
        return x

    def kernel_params(self, Ke=None, Kec=None, Ku=None) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def _evaluate_compiled(self, e, ec):  # pragma: no cover - abstract
        raise NotImplementedError

    def kernel(self):
        """The compiled engine's kernel (the compiled twin of :meth:`output`; stateless, no update).

        Returns
        -------
        ctrl_analysis.engine.codegen.BlockKernel
        """
        from ..engine.kernels import BlockKernel

        return BlockKernel(output=self._kernel_output, params=self.kernel_params(), update=_no_update)


#: From this many points on, :meth:`_FuzzyBlock.evaluate` and :meth:`FuzzyController.control_surface`
#: use the compiled kernel (compiling it costs more than the numpy path saves on fewer points).
_COMPILED_MIN = 2000


def _compiled_ok() -> bool:
    from ..engine.codegen import available

    return available()


def _apply_kernel(fn, p, e, ec, n_out=1) -> np.ndarray:
    """The jitted kernel ``fn`` evaluated at each point ``(e[k], ec[k])``: shape ``(size, n_out)``."""
    from ..engine.codegen import _jit

    f = _jit(fn)
    x, u = np.empty(0), np.empty(2)
    out = np.empty((e.size, n_out))
    for k in range(e.size):
        u[0], u[1] = e[k], ec[k]
        f(0.0, x, u, p, out[k])
    return out


def _no_update(t, x, u, p, x_next):
    """A stateless block's update: nothing to write."""


#: The fixed head of :func:`mamdani_output`'s parameters: factors, universes, sizes, term widths;
#: the arrays of :func:`mamdani_layout` follow.
MAMDANI = Layout("Ke", "Kec", "Ku", "X_e", "X_ec", "n_e", "n_ec", "n_u", "n_grid", "w_e", "w_ec")
AT = MAMDANI.at  # parameter offsets, a numba constant
_M_ARRAYS = MAMDANI.size


def mamdani_layout(n_e: int, n_ec: int, n_u: int, n_grid: int) -> Layout:
    """The parameters of :func:`mamdani_output`: :data:`MAMDANI`, then the term centres ``c_e``, ``c_ec``, the
    rule table (row-major), the output grid ``z`` and the output memberships ``mu_u`` (``n_grid × n_u``).

    Parameters
    ----------
    n_e, n_ec, n_u, n_grid : int
        Terms of ``e``, of ``ec``, of ``u``; points of the output grid.

    Returns
    -------
    Layout
    """
    return Layout(*zip(MAMDANI.names, MAMDANI.shapes), ("c_e", n_e), ("c_ec", n_ec), ("rules", (n_e, n_ec)),
                  ("z", n_grid), ("mu_u", (n_grid, n_u)))


#: The fixed head of :func:`lookup_output`'s parameters: factors, universes, grid sizes, first points and
#: steps; the table ``U`` (``n_e × n_ec``, row-major) follows (:func:`lookup_layout`).
LOOKUP = Layout("Ke", "Kec", "Ku", "X_e", "X_ec", "n_e", "n_ec", "E0", "EC0", "dE", "dEC")
LT = LOOKUP.at  # parameter offsets, a numba constant
_L_ARRAYS = LOOKUP.size


def lookup_layout(n_e: int, n_ec: int) -> Layout:
    """The parameters of :func:`lookup_output`: :data:`LOOKUP`, then the table ``U`` (``n_e × n_ec``).

    Parameters
    ----------
    n_e, n_ec : int
        Grid points of the two universes.

    Returns
    -------
    Layout
    """
    return Layout(*zip(LOOKUP.names, LOOKUP.shapes), ("U", (n_e, n_ec)))


def mamdani_output(t, x, u, p, y):
    """Compiled twin of :meth:`FuzzyController.output` for one run: ``y[0] = Ku · centroid(...)`` of ``u = [e, ec]``.

    Per-value branches (saturation, the ``min``/``max`` of the inference) make a scalar kernel
    differ from the branch-free numpy method; ``tests/lib/test_fuzzy.py`` holds the two equal
    (to rounding: the centroid's sums are taken in a different order).

    Parameters
    ----------
    t, x : float, numpy.ndarray
        Time and state (unused; the block is stateless).
    u : numpy.ndarray, shape (2,)
        ``[e, ec]`` in physical units.
    p : numpy.ndarray
        :meth:`FuzzyController.kernel_params`, laid out by :func:`mamdani_layout`.
    y : numpy.ndarray, shape (1,) or (n_grid,)
        ``u`` of the controller, written in place; given ``n_grid`` entries, the aggregated output
        set on ``z`` instead (no centroid: numpy's :func:`piecewise_linear_centroid` then gives
        :meth:`FuzzyController.infer` bit for bit, see :meth:`FuzzyController.control_surface`).
    """
    n_e, n_ec, n_u, n_g = int(p[AT.n_e]), int(p[AT.n_ec]), int(p[AT.n_u]), int(p[AT.n_grid])
    E, EC = p[AT.Ke] * u[0], p[AT.Kec] * u[1]  # quantised: sat(Ke e, ±X_e), sat(Kec ec, ±X_ec)
    if E != E or EC != EC:
        for g in range(y.shape[0]):
            y[g] = E + EC
        return
    E, EC = min(max(E, -p[AT.X_e]), p[AT.X_e]), min(max(EC, -p[AT.X_ec]), p[AT.X_ec])
    o_ce = _M_ARRAYS  # the offsets of mamdani_layout's arrays
    o_cec, o_r = o_ce + n_e, o_ce + n_e + n_ec
    o_z = o_r + n_e * n_ec
    o_mu = o_z + n_g
    act = np.zeros(n_u)  # per output term: max over its rules of min(μ_Ei(E), μ_ECj(EC))
    for i in range(n_e):
        me = max(0.0, 1.0 - abs(E - p[o_ce + i]) / p[AT.w_e])
        if me == 0.0:
            continue
        for j in range(n_ec):
            w = min(me, max(0.0, 1.0 - abs(EC - p[o_cec + j]) / p[AT.w_ec]))
            k = int(p[o_r + i * n_ec + j])
            act[k] = max(act[k], w)
    dz = p[o_z + 1] - p[o_z]
    num, den, prev = 0.0, 0.0, 0.0
    for g in range(n_g):  # implication min, aggregation max, centroid of the piecewise-linear set
        agg = 0.0
        for k in range(n_u):
            agg = max(agg, min(act[k], p[o_mu + g * n_u + k]))
        if y.shape[0] > 1:
            y[g] = agg
        elif g > 0:
            area = 0.5 * (prev + agg)
            num += p[o_z + g - 1] * area + dz * (prev + 2.0 * agg) / 6.0
            den += area
        prev = agg
    if y.shape[0] == 1:
        y[0] = p[AT.Ku] * (num / den)


def lookup_output(t, x, u, p, y):
    """Compiled twin of :meth:`FuzzyLookupController.output` for one run: bilinear query table, ``u = [e, ec]``.

    The same arithmetic as :meth:`FuzzyLookupController.lookup` (bit for bit; the cell index is a
    per-value branch, so the numpy method stays branch-free and ``tests/lib/test_fuzzy.py`` holds
    the two equal).

    Parameters
    ----------
    t, x, u
        As :func:`mamdani_output`: ``u = [e, ec]`` (physical units), no state.
    p : numpy.ndarray
        :meth:`FuzzyLookupController.kernel_params`, laid out by :func:`lookup_layout`.
    y : numpy.ndarray, shape (1,)
        ``u`` of the controller, written in place.
    """
    n_e, n_ec = int(p[LT.n_e]), int(p[LT.n_ec])
    E, EC = p[LT.Ke] * u[0], p[LT.Kec] * u[1]  # quantised: sat(Ke e, ±X_e), sat(Kec ec, ±X_ec) (NaN stays NaN)
    E = E if E != E else min(max(E, -p[LT.X_e]), p[LT.X_e])
    EC = EC if EC != EC else min(max(EC, -p[LT.X_ec]), p[LT.X_ec])
    fe = (E - p[LT.E0]) / p[LT.dE]
    fc = (EC - p[LT.EC0]) / p[LT.dEC]
    i = min(max(int(math.floor(fe)), 0), n_e - 2) if fe == fe else 0  # a NaN input: any cell, NaN output
    j = min(max(int(math.floor(fc)), 0), n_ec - 2) if fc == fc else 0
    a, b = fe - i, fc - j
    o = _L_ARRAYS + i * n_ec + j  # U[i, j] in lookup_layout
    y[0] = p[LT.Ku] * ((1.0 - a) * ((1.0 - b) * p[o] + b * p[o + 1])
                   + a * ((1.0 - b) * p[o + n_ec] + b * p[o + n_ec + 1]))


class FuzzyController(_FuzzyBlock):
    """Two-input Mamdani fuzzy controller: triangular terms, min–max inference, centroid defuzzification.

    ``u = Ku · centroid( max_{i,j} min( min(μ_Ei(E), μ_ECj(EC)), μ_U[rule[i,j]] ) )`` with
    ``E = sat(Ke·e, ±X_e)``, ``EC = sat(Kec·ec, ±X_ec)``. Terms are evenly spaced triangles whose
    outermost peaks sit at the universe ends (a partition of unity on each input universe); the
    output universe ``[−Y, Y]`` is sampled on ``n_grid`` points and the centroid is that of the
    piecewise-linear aggregated set (:func:`piecewise_linear_centroid`).

    A stateless discrete block with direct feedthrough: inputs ``e``, ``ec``; output ``u``.

    Parameters
    ----------
    rules : array_like of int, shape (n_e, n_ec)
        Output term index (``0 .. n_u − 1``) for each pair of input terms.
    Ke, Kec, Ku : float, > 0
        Quantisation factors of ``e`` and ``ec`` and the output scale factor.
    input_range : float or (float, float)
        Half-widths ``X_e``, ``X_ec`` of the input universes (> 0).
    output_range : float
        Half-width ``Y`` of the output universe (> 0).
    n_output_terms : int, optional
        Number of output terms (default: ``max(rules) + 1``, at least the table's).
    n_grid : int
        Points of the output universe for the centroid (>= 3).

    Raises
    ------
    ValueError
        A factor or range that is not positive, a rule index out of range.

    References
    ----------
    L.-X. Wang, *A Course in Fuzzy Systems and Control*, Prentice Hall 1997 (Mamdani min
    implication, max aggregation, centre-of-gravity defuzzifier).

    Examples
    --------
    >>> import numpy as np
    >>> fc = FuzzyController(sum_rule_table(7), Ke=1.0, Kec=1.0, Ku=1.0, input_range=6, output_range=6,
    ...                      n_grid=241)
    >>> fc.evaluate(np.array([0.0, 2.0, 1.0]), np.array([0.0, 0.0, 0.0])).round(9) + 0.0
    array([0., 2., 1.])
    """

    def __init__(self, rules, *, Ke, Kec, Ku, input_range=6.0, output_range=7.0, n_output_terms=None,
                 n_grid: int = 281):
        rules = np.asarray(rules)
        if rules.ndim != 2 or rules.shape[0] < 2 or rules.shape[1] < 2 or not np.issubdtype(rules.dtype, np.integer):
            raise ValueError(f"rules must be a 2-D integer table with at least 2×2 entries, got {rules!r}")
        self.rules = rules.copy()
        self.Ke = check_positive("Ke", Ke, scalar=True)
        self.Kec = check_positive("Kec", Kec, scalar=True)
        self.Ku = check_positive("Ku", Ku, scalar=True)
        xr = np.asarray(check_finite("input_range", input_range), dtype=float)
        if xr.shape not in ((), (1,), (2,)):
            raise ValueError(f"input_range must be one number or two (for e and ec), got shape {xr.shape}")
        xr = np.broadcast_to(xr, (2,))
        if np.any(xr <= 0):
            raise ValueError(f"input_range must be > 0, got {input_range!r}")
        self.X_e, self.X_ec = float(xr[0]), float(xr[1])
        self.Y = check_positive("output_range", output_range, scalar=True)
        n_u = int(rules.max()) + 1 if n_output_terms is None else check_int("n_output_terms", n_output_terms, minimum=2)
        if rules.min() < 0 or rules.max() >= n_u:
            raise ValueError(f"rules must hold output term indices in [0, {n_u - 1}] (n_output_terms={n_u}), "
                             f"got [{rules.min()}, {rules.max()}]")
        self.n_u = n_u
        self.n_grid = check_int("n_grid", n_grid, minimum=3)
        self.c_e = np.linspace(-self.X_e, self.X_e, rules.shape[0])
        self.c_ec = np.linspace(-self.X_ec, self.X_ec, rules.shape[1])
        self.c_u = np.linspace(-self.Y, self.Y, n_u)
        self.w_e, self.w_ec, self.w_u = (self.c_e[1] - self.c_e[0], self.c_ec[1] - self.c_ec[0],
                                         self.c_u[1] - self.c_u[0])
        self.z = np.linspace(-self.Y, self.Y, self.n_grid)
        self.mu_u = triangular_memberships(self.z, self.c_u, self.w_u)  # (N, n_u)
        self.masks = np.stack([rules == k for k in range(n_u)])  # (n_u, n_e, n_ec)

    def quantise(self, e, ec):
        """Quantise the inputs: ``(E, EC) = (sat(Ke·e, ±X_e), sat(Kec·ec, ±X_ec))``.

        Parameters
        ----------
        e, ec : ndarray
            Physical error and error rate.

        Returns
        -------
        E, EC : ndarray
            Quantised inputs on the universes.
        """
        return np.clip(self.Ke * e, -self.X_e, self.X_e), np.clip(self.Kec * ec, -self.X_ec, self.X_ec)

    def infer(self, E, EC):
        """Defuzzified output on the output universe (before ``Ku``) for quantised inputs.

        Parameters
        ----------
        E, EC : ndarray, shape (B,)
            Quantised inputs (inside the universes).

        Returns
        -------
        ndarray, shape (B,)
            Centroid of ``max_{i,j} min(min(μ_Ei(E), μ_ECj(EC)), μ_U[rule[i,j]])``.
        """
        mu_e = triangular_memberships(E, self.c_e, self.w_e)  # (B, n_e)
        mu_ec = triangular_memberships(EC, self.c_ec, self.w_ec)  # (B, n_ec)
        w = np.minimum(mu_e[:, :, None], mu_ec[:, None, :])  # rule firing: AND = min
        act = np.max(np.where(self.masks[None], w[:, None], 0.0), axis=(2, 3))  # per output term: max
        agg = np.max(np.minimum(act[:, None, :], self.mu_u[None]), axis=2)  # implication min, aggregation max
        return piecewise_linear_centroid(self.z, agg)

    _surface = infer

    def control_surface(self, n_e: int = 121, n_ec: int = 121):
        """The surface ``U(E, EC)`` on a uniform grid of the quantised universes (the query table).

        Parameters
        ----------
        n_e, n_ec : int
            Grid points per universe (>= 2).

        Returns
        -------
        E : ndarray, shape (n_e,)
        EC : ndarray, shape (n_ec,)
        U : ndarray, shape (n_e, n_ec)
            Output on the output universe (multiply by ``Ku`` for physical units); from
            ``_COMPILED_MIN`` points on (numba available) the aggregation is compiled
            (:func:`mamdani_output`), the centroid numpy's: :meth:`infer` bit for bit.
        """
        E = np.linspace(-self.X_e, self.X_e, check_int("n_e", n_e, minimum=2))
        EC = np.linspace(-self.X_ec, self.X_ec, check_int("n_ec", n_ec, minimum=2))
        EE, CC = np.meshgrid(E, EC, indexing="ij")
        if EE.size >= _COMPILED_MIN and _compiled_ok():  # the compiled twin of infer, unit factors
            U = self._infer_compiled(EE.ravel(), CC.ravel(), 1.0, 1.0)
        else:
            U = self.infer(EE.ravel(), CC.ravel())
        return E, EC, U.reshape(E.size, EC.size)

    _kernel_output = staticmethod(mamdani_output)

    def _infer_compiled(self, e, ec, Ke, Kec):
        """:meth:`infer` of ``quantise(e, ec)`` (factors ``Ke``, ``Kec``): compiled aggregation, numpy centroid."""
        p, out, n = self.kernel_params(Ke, Kec, 1.0), np.empty(e.size), 64  # in blocks: the sets stay in cache
        for lo in range(0, e.size, n):
            agg = _apply_kernel(mamdani_output, p, e[lo:lo + n], ec[lo:lo + n], self.n_grid)
            out[lo:lo + n] = piecewise_linear_centroid(self.z, agg)  # row by row: the same sums as infer's
        return out

    def _evaluate_compiled(self, e, ec):
        return self.Ku * self._infer_compiled(e, ec, self.Ke, self.Kec)

    def kernel_params(self, Ke=None, Kec=None, Ku=None) -> np.ndarray:
        """The parameter vector of :func:`mamdani_output` (factors overridable, e.g. 1 for the surface).

        Parameters
        ----------
        Ke, Kec, Ku : float, optional
            Factors (finite, > 0) to use instead of the controller's.

        Returns
        -------
        numpy.ndarray

        Raises
        ------
        ValueError
            If a factor given is not finite and > 0.
        """
        f = [getattr(self, name) if value is None else check_positive(name, value, scalar=True)
             for name, value in (("Ke", Ke), ("Kec", Kec), ("Ku", Ku))]
        n_e, n_ec = self.rules.shape
        return mamdani_layout(n_e, n_ec, self.n_u, self.n_grid).pack(
            Ke=f[0], Kec=f[1], Ku=f[2], X_e=self.X_e, X_ec=self.X_ec, n_e=n_e, n_ec=n_ec, n_u=self.n_u,
            n_grid=self.n_grid, w_e=self.w_e, w_ec=self.w_ec, c_e=self.c_e, c_ec=self.c_ec, rules=self.rules,
            z=self.z, mu_u=self.mu_u)

    def __repr__(self) -> str:
        return (f"FuzzyController({self.rules.shape[0]}×{self.rules.shape[1]} rules, {self.n_u} output terms, "
                f"Ke={self.Ke:g}, Kec={self.Kec:g}, Ku={self.Ku:g})")


class FuzzyLookupController(_FuzzyBlock):
    """A fuzzy controller's control surface precomputed on a grid and interpolated bilinearly.

    The classical query table: :meth:`FuzzyController.control_surface` on an ``n × n`` grid of the
    quantised universes, then ``u = Ku · bilinear(U, E, EC)`` per sample. Between grid points the
    error against direct inference is bounded by the surface's curvature (tested in
    ``tests/lib/test_fuzzy.py``); at grid points it is exact.

    Parameters
    ----------
    controller : FuzzyController
    n_points : int or (int, int)
        Grid points per input universe (>= 2).

    Block signals as :class:`FuzzyController` (inputs ``e``, ``ec``; output ``u``; no state).
    """

    def __init__(self, controller: FuzzyController, n_points=121):
        if not isinstance(controller, FuzzyController):
            raise TypeError(f"controller must be a FuzzyController, got {type(controller).__name__}")
        n = np.asarray(n_points, dtype=object)
        if n.shape not in ((), (1,), (2,)):
            raise ValueError(f"n_points must be one integer or two, got {n_points!r}")
        n_e, n_ec = (check_int("n_points", v, minimum=2) for v in np.broadcast_to(n, (2,)))
        self.controller = controller
        self.E, self.EC, self.U = controller.control_surface(n_e, n_ec)
        self.dE, self.dEC = self.E[1] - self.E[0], self.EC[1] - self.EC[0]

    def lookup(self, E, EC):
        """Bilinear interpolation of the table at quantised inputs, before ``Ku``.

        Parameters
        ----------
        E, EC : ndarray, shape (B,)
            Quantised inputs (inside the universes; NaN gives NaN).

        Returns
        -------
        ndarray, shape (B,)
        """
        fe = (E - self.E[0]) / self.dE
        fc = (EC - self.EC[0]) / self.dEC
        # clipped after the cast so that a non-finite input gives a valid cell (and a NaN output)
        i = np.clip(np.floor(fe).astype(int), 0, self.E.size - 2)
        j = np.clip(np.floor(fc).astype(int), 0, self.EC.size - 2)
        a, b = fe - i, fc - j
        U = self.U
        return ((1.0 - a) * ((1.0 - b) * U[i, j] + b * U[i, j + 1])
                + a * ((1.0 - b) * U[i + 1, j] + b * U[i + 1, j + 1]))

    _surface = lookup
    _kernel_output = staticmethod(lookup_output)

    def _evaluate_compiled(self, e, ec):
        return _apply_kernel(lookup_output, self.kernel_params(), e, ec)[:, 0]

    def kernel_params(self) -> np.ndarray:
        """The parameter vector of :func:`lookup_output`: the factors, the grid and the table.

        Returns
        -------
        numpy.ndarray
        """
        fc = self.controller
        return lookup_layout(self.E.size, self.EC.size).pack(
            Ke=fc.Ke, Kec=fc.Kec, Ku=fc.Ku, X_e=fc.X_e, X_ec=fc.X_ec, n_e=self.E.size, n_ec=self.EC.size,
            E0=self.E[0], EC0=self.EC[0], dE=self.dE, dEC=self.dEC, U=self.U)

    def _scaling(self):
        return self.controller

    def __repr__(self) -> str:
        return f"FuzzyLookupController({self.controller!r}, {self.E.size}×{self.EC.size} grid)"
