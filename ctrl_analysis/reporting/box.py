"""The plausible box of a study: its reconstructions as dimensions, points in it, segments between points.

A study's reconstructions with a plausible range (:func:`~ctrl_analysis.reporting.study.span`,
:func:`~ctrl_analysis.reporting.study.choices`) are the dimensions of its *plausible box*; the printed values
stay fixed. A point of the box has a coordinate in [0, 1] per dimension; :class:`Box` maps points to the
study's parameter objects, samples the box (a Latin hypercube, ``scipy.stats.qmc``) and
interpolates along segments for bisection. :mod:`ctrl_analysis.reporting.sensitivity` judges the verdicts on it.

Examples
--------
>>> from dataclasses import dataclass
>>> from ctrl_analysis.reporting.study import choices, reconstructed, span
>>> @dataclass(frozen=True)
... class P:
...     k: float = reconstructed(1.0, "not printed", plausible=span(0.1, 10.0, "a decade either side", scale="log"))
...     rule: str = reconstructed("a", "ambiguous", plausible=choices(("b",), "the other reading"))
>>> box = Box({"p": P()})
>>> [d.name for d in box.dims], box.chosen.round(3).tolist()
(['p.k', 'p.rule'], [0.5, 0.25])
>>> box.params_at([1.0, 0.9])["p"]
P(k=10.0, rule='b')
"""

from __future__ import annotations

import dataclasses
import functools
import math
import warnings

import numpy as np

from .study import Plausible, reconstructions_of

__all__ = ["PERMUTATIONS", "Box", "Dimension", "first_order"]

#: Shuffles of the verdicts behind :func:`first_order`'s chance level (a permutation test).
PERMUTATIONS = 20
PERMUTATION_SEED = 20261127


def _same(a, b) -> bool:
    if a is None or b is None:  # np.asarray(None, dtype=float) is nan, never close to itself
        return a is b
    try:
        return bool(np.all(np.isclose(np.asarray(a, dtype=float), np.asarray(b, dtype=float), rtol=1e-9, atol=0)))
    except (TypeError, ValueError):
        return a == b


def _json(v):
    """A value as results.json shows it: floats to 6 significant digits, tuples as lists."""
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return float(f"{float(v):.6g}") if math.isfinite(float(v)) else None
    if isinstance(v, (tuple, list)):
        return [_json(x) for x in v]
    return v


@dataclasses.dataclass(frozen=True)
class Dimension:
    """One reconstruction of the box: where it lives in the study's parameters, its chosen value and its range.

    A point of the box has a coordinate ``u`` in [0, 1] per dimension: an interval maps it linearly (or
    geometrically on a log scale, rounded on an integer one), a set of alternatives maps equal sub-intervals
    to the chosen value and to each other option. ``nan`` stands for the chosen value.

    Parameters
    ----------
    name : str
        ``"prefix.field"`` (results.json's reconstruction name).
    prefix, field : str
        The parameter object's key in ``params`` and the dataclass field.
    chosen : object
        The study's chosen value.
    plausible : Plausible
        Its plausible range.
    """

    name: str
    prefix: str
    field: str
    chosen: object
    plausible: Plausible

    @property
    def continuous(self) -> bool:
        """An interval (True) or a set of alternatives (False).

        Returns
        -------
        bool
        """
        return self.plausible.low is not None

    @functools.cached_property
    def levels(self) -> tuple:
        """The alternatives of a discrete dimension, the chosen value first.

        Returns
        -------
        tuple
        """
        return (self.chosen,) + tuple(o for o in self.plausible.options if not _same(o, self.chosen))

    def value(self, u: float):
        """The value at coordinate ``u`` (``nan``: the chosen value).

        Parameters
        ----------
        u : float

        Returns
        -------
        object
        """
        if not math.isfinite(u):
            return self.chosen
        u = min(max(float(u), 0.0), 1.0)
        if not self.continuous:
            levels = self.levels
            return levels[min(int(u * len(levels)), len(levels) - 1)]
        lo, hi = float(self.plausible.low), float(self.plausible.high)
        if self.plausible.scale == "log":
            return float(lo * (hi / lo) ** u)
        x = lo + u * (hi - lo)
        return round(x) if self.plausible.scale == "int" else float(x)

    def coordinate(self, value) -> float:
        """The coordinate of ``value`` (``nan`` when it is not inside the range, e.g. a chosen ``None``).

        Parameters
        ----------
        value : object

        Returns
        -------
        float
        """
        if not self.continuous:
            for i, level in enumerate(self.levels):
                if _same(level, value):
                    return (i + 0.5) / len(self.levels)
            return math.nan
        try:
            x = float(value)
        except (TypeError, ValueError):
            return math.nan
        lo, hi = float(self.plausible.low), float(self.plausible.high)
        if not (lo <= x <= hi) or not math.isfinite(x):
            return math.nan
        if self.plausible.scale == "log":
            return math.log(x / lo) / math.log(hi / lo)
        return (x - lo) / (hi - lo)


class Box:
    """The plausible box of a study's parameter objects: its dimensions, its algorithm axis, points in it.

    Parameters
    ----------
    params : dict
        ``{prefix: frozen parameter dataclass}`` as the study's ``evaluate(params)`` takes it.
    names : collection of str, optional
        Vary only these reconstructions (e.g. a ``--quick`` run); the others stay at their chosen values.

    Raises
    ------
    TypeError
        If ``params`` is not a dict of dataclass instances.
    ValueError
        If ``names`` names no varied reconstruction, or the algorithm fields disagree on which algorithm is chosen.
    """

    def __init__(self, params: dict, names=None):
        if not isinstance(params, dict) or not params or not all(
                dataclasses.is_dataclass(p) and not isinstance(p, type) for p in params.values()):
            raise TypeError("params must be a non-empty dict {prefix: dataclass instance}")
        if names is not None and (isinstance(names, (str, bytes)) or
                                  not isinstance(names, (set, frozenset, list, tuple))):
            raise TypeError(f"names must be a collection of dimension names, got {names!r:.80}")
        self.params = dict(params)
        dims, algos = [], []
        for prefix, obj in params.items():
            for rec in reconstructions_of(obj):
                plaus = rec.get("plausible")
                if plaus is None or not plaus.varied:
                    continue
                name = f"{prefix}.{rec['name']}" if prefix else rec["name"]
                dim = Dimension(name, prefix, rec["name"], rec["value"], plaus)
                if plaus.axis == "algorithm":
                    algos.append(dim)
                elif names is None or name in names:
                    dims.append(dim)
        if names is not None:
            unknown = set(names) - {d.name for d in dims}
            if unknown:
                raise ValueError(f"names {sorted(unknown)} are not varied reconstructions of params")
        self.dims = tuple(dims)
        self.algorithm_dims = tuple(algos)
        chosen = {("printed" if _same(d.chosen, d.plausible.options[0]) else
                   "corrected" if _same(d.chosen, d.plausible.options[1]) else "other") for d in algos}
        if len(chosen) > 1 or "other" in chosen:
            raise ValueError("the algorithm axis' fields must all be at their printed, or all at their corrected "
                             f"value, got {[(d.name, d.chosen) for d in algos]}")
        #: the algorithm of the chosen point ("printed" / "corrected"), None without an algorithm axis
        self.algorithm = chosen.pop() if chosen else None

    @property
    def algorithms(self) -> tuple:
        """The algorithms sampled, the chosen one first (``(None,)`` without an algorithm axis).

        Returns
        -------
        tuple
        """
        if self.algorithm is None:
            return (None,)
        return (self.algorithm, "corrected" if self.algorithm == "printed" else "printed")

    @property
    def chosen(self) -> np.ndarray:
        """The chosen point's coordinates (``nan`` where the chosen value is not inside the range).

        Returns
        -------
        numpy.ndarray
        """
        return np.array([d.coordinate(d.chosen) for d in self.dims], dtype=float)

    def sample(self, n: int, seed: int) -> np.ndarray:
        """A Latin hypercube sample of ``n`` points (``n`` rounded up to a power of two), shape ``(n, dims)``.

        Each coordinate has exactly one point in each of its ``n`` equal strata, and the coordinates are paired at
        random. A scrambled Sobol' sample spreads the points more evenly, but its coordinates are paired by
        structure: at 64 points a reconstruction that cannot act then shows a first-order index above the
        permutation test's chance level on about a third of the claims (11 of 30 seeded toy claims with 12 idle
        reconstructions), against 2 of 30 with a Latin hypercube, where the permutation test's null (the verdict
        independent of the coordinate)
        holds (:func:`first_order`).

        Parameters
        ----------
        n : int
        seed : int

        Returns
        -------
        numpy.ndarray
        """
        from scipy.stats import qmc

        m = max(int(math.ceil(math.log2(max(n, 2)))), 1)
        if not self.dims:
            return np.zeros((0, 0))
        return qmc.LatinHypercube(len(self.dims), seed=seed).random(2 ** m)

    def values(self, u) -> dict:
        """``{name: value}`` at coordinates ``u``.

        Parameters
        ----------
        u : array_like

        Returns
        -------
        dict
        """
        return {d.name: d.value(x) for d, x in zip(self.dims, np.asarray(u, dtype=float), strict=True)}

    def params_at(self, u, algorithm: str | None = None) -> dict:
        """The study's ``params`` with every dimension at coordinate ``u`` and the algorithm axis at ``algorithm``.

        Parameters
        ----------
        u : array_like
        algorithm : {"printed", "corrected"}, optional
            Default: the chosen one.

        Returns
        -------
        dict
        """
        changes: dict = {}
        for d, x in zip(self.dims, np.asarray(u, dtype=float), strict=True):
            if math.isfinite(x):
                changes.setdefault(d.prefix, {})[d.field] = d.value(x)
        if algorithm is not None and algorithm != self.algorithm:
            for d in self.algorithm_dims:
                changes.setdefault(d.prefix, {})[d.field] = d.plausible.options[0 if algorithm == "printed" else 1]
        out = dict(self.params)
        for prefix, fields in changes.items():
            out[prefix] = dataclasses.replace(out[prefix], **fields)
        return out

    def interpolate(self, u0, u1, t: float) -> np.ndarray:
        """The point a fraction ``t`` along the segment ``u0 → u1``.

        An interval moves linearly; an alternative (or an end at the chosen value, ``nan``) switches at ``t = 1/2``.

        Parameters
        ----------
        u0, u1 : array_like
        t : float

        Returns
        -------
        numpy.ndarray
        """
        u0, u1 = np.asarray(u0, dtype=float), np.asarray(u1, dtype=float)
        out = np.where(t < 0.5, u0, u1)
        for i, d in enumerate(self.dims):
            if d.continuous and math.isfinite(u0[i]) and math.isfinite(u1[i]):
                out[i] = u0[i] + t * (u1[i] - u0[i])
        return out

    def distance(self, u0, u1) -> float:
        """Distance between two points: coordinates in [0, 1], an alternative that differs counts 1/2.

        Parameters
        ----------
        u0, u1 : array_like

        Returns
        -------
        float
        """
        return float(self.distances(np.asarray(u0, dtype=float)[None], np.asarray(u1, dtype=float)[None])[0, 0])

    def distances(self, A, B) -> np.ndarray:
        """:meth:`distance` between every row of ``A`` and every row of ``B`` (vectorised), shape ``(len(A), len(B))``.

        Parameters
        ----------
        A, B : array_like, shape (n, dims)

        Returns
        -------
        numpy.ndarray
        """
        A, B = np.atleast_2d(np.asarray(A, dtype=float)), np.atleast_2d(np.asarray(B, dtype=float))
        total = np.zeros((A.shape[0], B.shape[0]))
        for i, d in enumerate(self.dims):
            a, b = A[:, i][:, None], B[:, i][None, :]
            if d.continuous:
                fa, fb = np.isfinite(a), np.isfinite(b)
                with np.errstate(invalid="ignore"):
                    diff = np.where(fa & fb, np.abs(a - b), np.where(fa == fb, 0.0, 0.5))
            else:
                diff = np.where(self._level(d, a) == self._level(d, b), 0.0, 0.5)
            total += diff * diff
        return np.sqrt(total)

    @staticmethod
    def _level(d, u) -> np.ndarray:
        """Index in ``d.levels`` of the alternative at coordinates ``u`` (``nan``: 0, the chosen value)."""
        n = len(d.levels)
        with np.errstate(invalid="ignore"):
            idx = np.minimum(np.floor(np.clip(u, 0.0, 1.0) * n), n - 1)
        return np.where(np.isfinite(u), idx, 0.0)

    def discrete_keys(self, U) -> list:
        """:meth:`discrete_key` of every row of ``U`` (the alternatives' indexes).

        Points with equal keys differ only along intervals.

        Parameters
        ----------
        U : array_like, shape (n, dims)

        Returns
        -------
        list of tuple
        """
        U = np.atleast_2d(np.asarray(U, dtype=float))
        cols = [self._level(d, U[:, i]) for i, d in enumerate(self.dims) if not d.continuous]
        return [tuple(c[k] for c in cols) for k in range(U.shape[0])]

    def discrete_key(self, u) -> tuple:
        """The alternatives taken at ``u`` (points with equal keys differ only along intervals).

        Parameters
        ----------
        u : array_like

        Returns
        -------
        tuple
        """
        return self.discrete_keys(np.asarray(u, dtype=float)[None])[0]

    def changed(self, u) -> dict:
        """``{name: value}`` of the dimensions whose value at ``u`` differs from the chosen one.

        Parameters
        ----------
        u : array_like

        Returns
        -------
        dict
        """
        out = {}
        for d, x in zip(self.dims, np.asarray(u, dtype=float), strict=True):
            v = d.value(x)
            if not _same(v, d.chosen):
                out[d.name] = _json(v)
        return out


def first_order(box, U, y) -> list:
    """First-order Sobol' indices of ``y`` over the box sample ``U`` (SALib's RBD-FAST on given data), largest first.

    Parameters
    ----------
    box : Box
    U : numpy.ndarray
        The sample's coordinates, shape ``(n, dims)``.
    y : numpy.ndarray
        One value per point (``nan`` where there is none: left out).

    Returns
    -------
    list of dict
        ``{"reconstruction", "S1", "noise", "significant"}`` per dimension: ``noise`` is what chance reaches (the
        95th percentile of the largest index over all reconstructions when ``y`` is shuffled against the points,
        :data:`PERMUTATIONS` times), ``significant`` an index of at least 0.05 above it; empty when fewer than
        16 finite values or ``y`` is constant.
    """
    ok = np.isfinite(y)
    if ok.sum() < 16 or np.ptp(y[ok]) == 0 or not box.dims:
        return []
    from SALib.analyze import rbd_fast

    problem = {"num_vars": len(box.dims), "names": [d.name for d in box.dims], "bounds": [[0.0, 1.0]] * len(box.dims)}
    X, Y = U[ok], y[ok].astype(float)
    # M harmonics: 4 from 64 points on; fewer on a smoke test's small sample (the bias correction divides by 1 - 2M/N)
    m = max(1, min(4, int(ok.sum()) // 16))

    def indices(values):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return np.asarray(rbd_fast.analyze(problem, X, values, M=m, num_resamples=0, seed=1)["S1"], dtype=float)

    s1 = indices(Y)
    # what chance alone reaches: the largest index over every reconstruction when the verdicts are shuffled
    # against the points (a permutation test, family-wise over the reconstructions); at 64 points RBD-FAST gives a
    # reconstruction that cannot act an index of 0.1-0.16 now and then
    rng = np.random.default_rng(PERMUTATION_SEED)
    null = [np.nanmax(indices(rng.permutation(Y))) for _ in range(PERMUTATIONS)]
    noise = float(np.quantile(null, 0.95))
    rows = [{"reconstruction": d.name, "S1": round(float(v), 3), "noise": round(noise, 3),
             "significant": bool(v >= 0.05 and v > noise)}
            for d, v in zip(box.dims, s1, strict=True) if math.isfinite(float(v))]
    return sorted(rows, key=lambda r: -r["S1"])
