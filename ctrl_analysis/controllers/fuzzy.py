"""Two-input Mamdani fuzzy controller (min–max inference, centroid) and its interpolated lookup table.

A classical two-dimensional fuzzy controller: the error ``e`` and its rate ``ec`` are quantised
onto symmetric universes ``[−X_e, X_e]``, ``[−X_ec, X_ec]`` (factors ``Ke``, ``Kec``, clipped at the
ends), fuzzified with evenly spaced triangular terms, combined by a rule table with ``min`` (AND and
Mamdani implication) and ``max`` (aggregation), defuzzified by the centroid of the aggregated
output set on ``[−Y, Y]`` and scaled by ``Ku``. Nothing here is specific to a plant or a paper.

Both controllers are stateless discrete kernel-first blocks
(:class:`~ctrl_analysis.engine.kernels.KernelBlock`) with direct feedthrough (inputs ``e``,
``ec``, output ``u``): in a :class:`~ctrl_analysis.engine.loop.Loop` their output is computed at
each sample and held, i.e. the controller is sampled. :class:`FuzzyLookupController` precomputes
the control surface on a grid (the classical query table) and interpolates it bilinearly.

Each equation is written once, in the kernels :func:`mamdani_output`, :func:`lookup_output` and
their helpers, which every method runs (on the batch's columns: the kernels do not branch on a
value) as does the compiled engine; the centroid sums in ``np.sum``'s order (:func:`_centroid`).
"""

from __future__ import annotations

import numpy as np

from .._validate import check_finite, check_int, check_positive
from ..engine.blocks import DiscreteBlock
from ..engine.kernels import (
    KernelBlock,
    Kernels,
    Layout,
    as_int,
    gather,
    jitable,
    rows_compiled,
    scratch,
)

__all__ = [
    "FuzzyController",
    "FuzzyLookupController",
    "piecewise_linear_centroid",
    "sum_rule_table",
    "triangular_memberships",
]

#: Most grid points, terms or table points along one axis (a larger grid takes minutes and gigabytes).
MAX_POINTS = 10_000


# ------------------------------------------------------------ the equations, once
@jitable
def _triangle(x, c, w):
    """Triangular membership ``μ(x) = max(0, 1 − |x − c| / w)`` (centre ``c``, half-support ``w``)."""
    return np.maximum(0.0, 1.0 - np.abs(x - c) / w)


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
    return _triangle(x[:, None], centers[None, :], width)


#: numpy's pairwise summation (``np.sum`` along a row), which :func:`_centroid` repeats: a range of at most this
#: many terms is summed with 8 interleaved accumulators, a longer one halved (at a multiple of 8), recursively.
_PW_BLOCK = 128


@jitable
def _segment(z, oz, dz, mu, g):
    """Moment and area over ``dz`` of segment ``g`` of ``mu`` on the grid ``z[oz:]``, ``μ`` linear from ``a = mu[g]`` to
    ``b = mu[g + 1]``: ``∫ μ = dz (a + b)/2``, ``∫ z μ = dz [z_g (a + b)/2 + dz (a + 2b)/6]`` (``dz`` cancels)."""
    a, b = mu[g], mu[g + 1]
    area = 0.5 * (a + b)
    return z[oz + g] * area + dz * (a + 2.0 * b) / 6.0, area


@jitable
def _block_sums(z, oz, dz, mu, lo, m, acc):
    """Moment and area summed over the segments ``lo .. lo + m − 1`` (``m <= _PW_BLOCK``) as numpy sums a block:
    8 accumulators (``acc[0:8]`` moments, ``acc[8:16]`` areas) take every 8th term and are added pairwise,
    the last ``m % 8`` terms (all of them when ``m < 8``, only a whole sum that short) left to right."""
    num, den, i = 0.0, 0.0, 0
    if m >= 8:
        for r in range(8):
            acc[r], acc[8 + r] = _segment(z, oz, dz, mu, lo + r)
        i = 8
        while i < m - m % 8:
            for r in range(8):
                mo, ar = _segment(z, oz, dz, mu, lo + i + r)
                acc[r] = acc[r] + mo
                acc[8 + r] = acc[8 + r] + ar
            i += 8
        num = ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]))
        den = ((acc[8] + acc[9]) + (acc[10] + acc[11])) + ((acc[12] + acc[13]) + (acc[14] + acc[15]))
    for g in range(lo + i, lo + m):
        mo, ar = _segment(z, oz, dz, mu, g)
        num, den = num + mo, den + ar
    return num, den


@jitable
def _centroid(z, oz, mu, n):
    """Centroid ``∫ z μ dz / ∫ μ dz`` of the piecewise-linear ``mu[0 .. n − 1]`` on the uniform grid ``z[oz:oz + n]``.

    The one source of the centroid; ``mu[g]`` is a number (one run) or a row of the batch's columns. Its
    two sums over the ``n − 1`` segments are taken as ``np.sum`` takes them along a row (:data:`_PW_BLOCK`,
    :func:`_block_sums`), without recursion (a jitable helper cannot recurse): a stack of ranges to sum,
    one of sums done.
    """
    dz = z[oz + 1] - z[oz]
    depth, m = 1, n - 1  # how deep the halving goes (the longer, right half first)
    while m > _PW_BLOCK:
        m -= m // 2 - (m // 2) % 8
        depth += 1
    acc = scratch(16, mu[0])
    sums = scratch(2 * depth + 2, mu[0])  # (moment, area) of each range summed and not yet added to its sibling
    lo_s, m_s, split = (np.empty(2 * depth + 1, np.int64), np.empty(2 * depth + 1, np.int64),
                        np.zeros(2 * depth + 1, np.int64))
    lo_s[0], m_s[0] = 0, n - 1
    top, sp = 0, 0
    while top >= 0:
        lo, m = lo_s[top], m_s[top]
        if m <= _PW_BLOCK:  # a block: its sums onto the stack
            sums[sp], sums[sp + 1] = _block_sums(z, oz, dz, mu, lo, m, acc)
            sp += 2
            top -= 1
        elif split[top] == 0:  # halve: the right half and the left half still to sum (the left first)
            split[top] = 1
            h = m // 2 - (m // 2) % 8
            lo_s[top + 1], m_s[top + 1], split[top + 1] = lo + h, m - h, 0
            lo_s[top + 2], m_s[top + 2], split[top + 2] = lo, h, 0
            top += 2
        else:  # both halves summed: left + right
            sp -= 2
            sums[sp - 2] = sums[sp - 2] + sums[sp]
            sums[sp - 1] = sums[sp - 1] + sums[sp + 1]
            top -= 1
    return (0.0 + sums[0]) / (0.0 + sums[1])  # np.sum starts from 0.0


def piecewise_linear_centroid(z, mu):
    """Centroid ``∫ z μ(z) dz / ∫ μ(z) dz`` of the piecewise-linear interpolant of samples ``μ`` on a uniform grid.

    Exact for a piecewise-linear membership whose kinks lie on the grid (the integral of each
    segment's trapezoid is summed); this is what :func:`skfuzzy.defuzz` (``'centroid'``) computes.
    The same code as the controller's kernel (the segments summed in numpy's pairwise order).

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
    z = np.asarray(z, dtype=float)
    return _centroid(z, 0, np.asarray(mu, dtype=float).T, z.size)


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


#: The head both controllers' kernel parameters start with: the factors and the input universes.
SCALING = Layout("Ke", "Kec", "Ku", "X_e", "X_ec")
SC = SCALING.at  # parameter offsets, a numba constant


@jitable
def _quantise(u, p):
    """``(E, EC) = (sat(Ke·e, ±X_e), sat(Kec·ec, ±X_ec))`` of ``u = [e, ec]``, ``p`` headed by :data:`SCALING`."""
    return (np.minimum(np.maximum(p[SC.Ke] * u[0], -p[SC.X_e]), p[SC.X_e]),
            np.minimum(np.maximum(p[SC.Kec] * u[1], -p[SC.X_ec]), p[SC.X_ec]))


def _no_update(t, x, u, p, x_next):
    """A stateless block's update: nothing to write."""


#: The fixed head of :func:`mamdani_output`'s parameters: :data:`SCALING`, sizes, term widths; the
#: arrays of :func:`mamdani_layout` follow.
MAMDANI = Layout(*zip(SCALING.names, SCALING.shapes, strict=True), "n_e", "n_ec", "n_u", "n_grid", "w_e", "w_ec")
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
    return Layout(*zip(MAMDANI.names, MAMDANI.shapes, strict=True), ("c_e", n_e), ("c_ec", n_ec),
                  ("rules", (n_e, n_ec)),
                  ("z", n_grid), ("mu_u", (n_grid, n_u)))


@jitable
def _mamdani_at(p):
    """Sizes from ``p``, offsets of the layout's arrays: ``(n_e, n_ec, n_u, n_grid, c_e, c_ec, rules, z, mu_u)``."""
    n_e, n_ec, n_u, n_g = as_int(p[AT.n_e]), as_int(p[AT.n_ec]), as_int(p[AT.n_u]), as_int(p[AT.n_grid])
    o_r = _M_ARRAYS + n_e + n_ec
    o_z = o_r + n_e * n_ec
    return n_e, n_ec, n_u, n_g, _M_ARRAYS, _M_ARRAYS + n_e, o_r, o_z, o_z + n_g


@jitable
def _aggregate(E, EC, p, agg):
    """The aggregated output set ``agg[g] = max_{i,j} min(μ_Ei(E), μ_ECj(EC), μ_U[rule[i,j]](z_g))``, written in place
    (min–max inference: rule firing ``min`` (AND), Mamdani implication ``min``, aggregation ``max``)."""
    n_e, n_ec, n_u, n_g, o_ce, o_cec, o_r, _, o_mu = _mamdani_at(p)
    mu_ec = scratch(n_ec, EC)
    for j in range(n_ec):
        mu_ec[j] = _triangle(EC, p[o_cec + j], p[AT.w_ec])  # μ_ECj(EC)
    act = scratch(n_u, E)  # per output term: max over its rules of min(μ_Ei(E), μ_ECj(EC))
    for i in range(n_e):
        mu_e = _triangle(E, p[o_ce + i], p[AT.w_e])  # μ_Ei(E)
        for j in range(n_ec):
            k = as_int(p[o_r + i * n_ec + j])  # the output term of rule (i, j)
            act[k] = np.maximum(act[k], np.minimum(mu_e, mu_ec[j]))
    for g in range(n_g):  # implication min, aggregation max
        a = 0.0
        for k in range(n_u):
            a = np.maximum(a, np.minimum(act[k], p[o_mu + g * n_u + k]))
        agg[g] = a


def mamdani_output(t, x, u, p, y):
    """The kernel of :class:`FuzzyController`: ``y[0] = Ku · centroid(aggregated set)`` of ``u = [e, ec]``.

    Scalar indexing and no branch on a value: one run in the compiled engine, the batch's columns in
    the block's batched methods (NaN in, NaN out).

    Parameters
    ----------
    t, x : float, numpy.ndarray
        Time and state (unused; the block is stateless).
    u : numpy.ndarray, shape (2,)
        ``[e, ec]`` in physical units.
    p : numpy.ndarray
        :attr:`FuzzyController.kernel_params`, laid out by :func:`mamdani_layout`.
    y : numpy.ndarray, shape (1,)
        ``u`` of the controller, written in place.
    """
    E, EC = _quantise(u, p)  # sat(Ke e, ±X_e), sat(Kec ec, ±X_ec)
    _, _, _, n_g, _, _, _, o_z, _ = _mamdani_at(p)
    agg = scratch(n_g, E)
    _aggregate(E, EC, p, agg)
    y[0] = p[AT.Ku] * _centroid(p, o_z, agg, n_g)  # centre of gravity on the output grid z


#: The fixed head of :func:`lookup_output`'s parameters: :data:`SCALING`, grid sizes, first points and
#: steps; the table ``U`` (``n_e × n_ec``, row-major) follows (:func:`lookup_layout`).
LOOKUP = Layout(*zip(SCALING.names, SCALING.shapes, strict=True), "n_e", "n_ec", "E0", "EC0", "dE", "dEC")
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
    return Layout(*zip(LOOKUP.names, LOOKUP.shapes, strict=True), ("U", (n_e, n_ec)))


def lookup_output(t, x, u, p, y):
    """The kernel of :class:`FuzzyLookupController`: ``y[0] = Ku · bilinear(U, E, EC)`` of ``u = [e, ec]``.

    Scalar indexing and no branch on a value (the cell is clipped with ``fmax``/``fmin``, so a NaN
    input takes cell 0 and gives NaN): one run in the compiled engine, the batch's columns in the
    block's batched methods.

    Parameters
    ----------
    t, x, u, y
        As :func:`mamdani_output`: no state, ``u = [e, ec]`` in physical units, the control written into ``y[0]``.
    p : numpy.ndarray
        :attr:`FuzzyLookupController.kernel_params`, laid out by :func:`lookup_layout`.
    """
    n_e, n_ec = as_int(p[LT.n_e]), as_int(p[LT.n_ec])
    E, EC = _quantise(u, p)  # sat(Ke e, ±X_e), sat(Kec ec, ±X_ec)
    fe = (E - p[LT.E0]) / p[LT.dE]  # grid coordinates
    fc = (EC - p[LT.EC0]) / p[LT.dEC]
    i = np.fmin(np.fmax(np.floor(fe), 0.0), n_e - 2.0)  # the cell [i, i + 1] × [j, j + 1]
    j = np.fmin(np.fmax(np.floor(fc), 0.0), n_ec - 2.0)
    a, b = fe - i, fc - j
    o = _L_ARRAYS + np.int64(i) * n_ec + np.int64(j)  # U[i, j] in lookup_layout
    y[0] = p[LT.Ku] * ((1.0 - a) * ((1.0 - b) * gather(p, o) + b * gather(p, o + 1))
                       + a * ((1.0 - b) * gather(p, o + n_ec) + b * gather(p, o + n_ec + 1)))


class _FuzzyBlock(KernelBlock, DiscreteBlock):
    """What both fuzzy blocks share: signals (``e``, ``ec`` in, ``u`` out, no state), quantisation, evaluation."""

    inputs = ("e", "ec")
    outputs = ("u",)
    states = ()
    feedthrough = True
    #: Parameters of the kernel with unit factors ``Ke = Kec = Ku = 1`` (inputs already quantised).
    _unit_params: np.ndarray

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
        return _quantise((np.asarray(e, dtype=float), np.asarray(ec, dtype=float)), self.kernel_params)

    def evaluate(self, e, ec):
        """Control ``u`` for physical inputs: the output kernel at each point (:meth:`_at_points`).

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
        """
        e = np.asarray(check_finite("e", e), dtype=float)
        ec = np.asarray(check_finite("ec", ec), dtype=float).reshape(-1)
        if ec.size != e.size:
            raise ValueError(f"e and ec must have the same number of points, got {e.size} and {ec.size}")
        return self._at_points(self.kernel_params, e, ec).reshape(e.shape)

    def _at_points(self, p, e, ec):
        """The output kernel with parameters ``p`` at the points ``(e[k], ec[k])``, flattened: compiled from
        ``_COMPILED_MIN`` points on (numba available), else on the points as the batch's columns; bit for bit alike."""
        u = np.stack([np.asarray(e, dtype=float).reshape(-1), np.asarray(ec, dtype=float).reshape(-1)], axis=1)
        out = np.empty((len(u), 1))
        if len(u) >= _COMPILED_MIN and rows_compiled(self.kernels.output, 0.0, np.empty((len(u), 0)), u, p, out):
            return out[:, 0]
        return self.batched("output", 0.0, None, u, p)[:, 0]


#: From this many points on, :meth:`_FuzzyBlock._at_points` (evaluate, infer, control_surface, lookup) runs
#: the compiled kernel (compiling it costs more than the numpy path saves on fewer points).
_COMPILED_MIN = 2000


class FuzzyController(_FuzzyBlock):
    """Two-input Mamdani fuzzy controller: triangular terms, min–max inference, centroid defuzzification.

    ``u = Ku · centroid( max_{i,j} min( min(μ_Ei(E), μ_ECj(EC)), μ_U[rule[i,j]] ) )`` with
    ``E = sat(Ke·e, ±X_e)``, ``EC = sat(Kec·ec, ±X_ec)``. Terms are evenly spaced triangles whose
    outermost peaks sit at the universe ends (a partition of unity on each input universe); the
    output universe ``[−Y, Y]`` is sampled on ``n_grid`` points and the centroid is that of the
    piecewise-linear aggregated set (:func:`piecewise_linear_centroid`).

    A stateless discrete block with direct feedthrough: inputs ``e``, ``ec``; output ``u``. Its
    kernel is :func:`mamdani_output`; the batched methods apply it to the batch's columns.

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

    kernels = Kernels(output=mamdani_output, update=_no_update)

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
        n_u = (int(rules.max()) + 1 if n_output_terms is None
               else check_int("n_output_terms", n_output_terms, minimum=2, maximum=MAX_POINTS))
        if rules.min() < 0 or rules.max() >= n_u:
            raise ValueError(f"rules must hold output term indices in [0, {n_u - 1}] (n_output_terms={n_u}), "
                             f"got [{rules.min()}, {rules.max()}]")
        self.n_u = n_u
        self.n_grid = check_int("n_grid", n_grid, minimum=3, maximum=MAX_POINTS)
        self.c_e = np.linspace(-self.X_e, self.X_e, rules.shape[0])
        self.c_ec = np.linspace(-self.X_ec, self.X_ec, rules.shape[1])
        self.c_u = np.linspace(-self.Y, self.Y, n_u)
        self.w_e, self.w_ec, self.w_u = (self.c_e[1] - self.c_e[0], self.c_ec[1] - self.c_ec[0],
                                         self.c_u[1] - self.c_u[0])
        self.z = np.linspace(-self.Y, self.Y, self.n_grid)
        self.mu_u = triangular_memberships(self.z, self.c_u, self.w_u)  # (N, n_u)
        self.kernel_params = self._pack(self.Ke, self.Kec, self.Ku)
        self._unit_params = self._pack(1.0, 1.0, 1.0)

    def _pack(self, Ke, Kec, Ku) -> np.ndarray:
        """The parameter vector of :func:`mamdani_output` with the factors ``Ke``, ``Kec``, ``Ku``."""
        n_e, n_ec = self.rules.shape
        return mamdani_layout(n_e, n_ec, self.n_u, self.n_grid).pack(
            Ke=Ke, Kec=Kec, Ku=Ku, X_e=self.X_e, X_ec=self.X_ec, n_e=n_e, n_ec=n_ec, n_u=self.n_u,
            n_grid=self.n_grid, w_e=self.w_e, w_ec=self.w_ec, c_e=self.c_e, c_ec=self.c_ec, rules=self.rules,
            z=self.z, mu_u=self.mu_u)

    def infer(self, E, EC):
        """Defuzzified output on the output universe (before ``Ku``) for quantised inputs.

        The kernel :func:`mamdani_output` with unit factors (``Ke = Kec = Ku = 1``).

        Parameters
        ----------
        E, EC : ndarray, shape (B,)
            Quantised inputs (inside the universes; values outside are saturated at its ends).

        Returns
        -------
        ndarray, shape (B,)
            Centroid of ``max_{i,j} min(min(μ_Ei(E), μ_ECj(EC)), μ_U[rule[i,j]])``.
        """
        return self._at_points(self._unit_params, E, EC)

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
            Output on the output universe (multiply by ``Ku`` for physical units): :meth:`infer` on the grid.
        """
        E = np.linspace(-self.X_e, self.X_e, check_int("n_e", n_e, minimum=2, maximum=MAX_POINTS))
        EC = np.linspace(-self.X_ec, self.X_ec, check_int("n_ec", n_ec, minimum=2, maximum=MAX_POINTS))
        EE, CC = np.meshgrid(E, EC, indexing="ij")
        return E, EC, self.infer(EE.ravel(), CC.ravel()).reshape(E.size, EC.size)

    def __repr__(self) -> str:
        return (f"FuzzyController({self.rules.shape[0]}×{self.rules.shape[1]} rules, {self.n_u} output terms, "
                f"Ke={self.Ke:g}, Kec={self.Kec:g}, Ku={self.Ku:g})")


class FuzzyLookupController(_FuzzyBlock):
    """A fuzzy controller's control surface precomputed on a grid and interpolated bilinearly.

    The classical query table: :meth:`FuzzyController.control_surface` on an ``n × n`` grid of the
    quantised universes, then ``u = Ku · bilinear(U, E, EC)`` per sample (kernel
    :func:`lookup_output`). Between grid points the error against direct inference is bounded by
    the surface's curvature (tested in ``tests/lib/test_fuzzy.py``); at grid points it is exact.

    Parameters
    ----------
    controller : FuzzyController
    n_points : int or (int, int)
        Grid points per input universe (>= 2).

    Block signals as :class:`FuzzyController` (inputs ``e``, ``ec``; output ``u``; no state).
    """

    kernels = Kernels(output=lookup_output, update=_no_update)

    def __init__(self, controller: FuzzyController, n_points=121):
        if not isinstance(controller, FuzzyController):
            raise TypeError(f"controller must be a FuzzyController, got {type(controller).__name__}")
        n = np.asarray(n_points, dtype=object)
        if n.shape not in ((), (1,), (2,)):
            raise ValueError(f"n_points must be one integer or two, got {n_points!r}")
        n_e, n_ec = (check_int("n_points", v, minimum=2, maximum=MAX_POINTS) for v in np.broadcast_to(n, (2,)))
        self.controller = controller
        self.E, self.EC, self.U = controller.control_surface(n_e, n_ec)
        self.dE, self.dEC = self.E[1] - self.E[0], self.EC[1] - self.EC[0]
        self.kernel_params = self._pack(controller.Ke, controller.Kec, controller.Ku)
        self._unit_params = self._pack(1.0, 1.0, 1.0)

    def _pack(self, Ke, Kec, Ku) -> np.ndarray:
        """The parameter vector of :func:`lookup_output` with factors ``Ke``, ``Kec``, ``Ku``: grid and table."""
        fc = self.controller
        return lookup_layout(self.E.size, self.EC.size).pack(
            Ke=Ke, Kec=Kec, Ku=Ku, X_e=fc.X_e, X_ec=fc.X_ec, n_e=self.E.size, n_ec=self.EC.size,
            E0=self.E[0], EC0=self.EC[0], dE=self.dE, dEC=self.dEC, U=self.U)

    def lookup(self, E, EC):
        """Bilinear interpolation of the table at quantised inputs, before ``Ku``.

        The kernel :func:`lookup_output` with unit factors (``Ke = Kec = Ku = 1``).

        Parameters
        ----------
        E, EC : ndarray, shape (B,)
            Quantised inputs (inside the universes; values outside are saturated at its ends; NaN gives NaN).

        Returns
        -------
        ndarray, shape (B,)
        """
        return self._at_points(self._unit_params, E, EC)

    def __repr__(self) -> str:
        return f"FuzzyLookupController({self.controller!r}, {self.E.size}×{self.EC.size} grid)"
