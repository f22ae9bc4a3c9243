"""The paper's batch least-squares identification of d(t) (Table 1, eq. (9)-(23)) as a discrete block.

Every sample the block appends the MESO's own data to its batch, kept as the Gram matrix of the
regressor vector ``φ = [x̂1, x̂2, 1, x̂3, f, u, K̄]`` (``f = XᵀΘ_used`` the model term fed to the
observer, ``K̄ = b0 u + Σ k_l x̂_l`` of (14)); at the end of every ``N``-sample batch
(:meth:`BatchIdentification.identify`, applied by the caller between batches) it solves the batch
regression of its variant with :func:`ctrl_analysis.identification.batch_least_squares` and
outputs the new Θ, which W(s) smooths before the observer and the controller use it.

Variants (one per run, on the batch axis: :meth:`BatchIdentification.identify` takes them per run;
the per-sample block is the same for every variant):

* ``literal``: the paper's rule, Θ = Σ_i Θ̂_i, each Θ̂_i fitted to the residual x̂3 — (22)-(23) in
  situation 1, (16)-(20) through Λ and X_Θ in situation 2;
* ``wellposed``: re-identify the total disturbance ``x̂3 + XᵀΘ_used`` every batch (no accumulation);
  in situation 2 the full regression is solved only when it passes the identifiability gate
  (column-scaled condition number <= threshold, Theorem 1), else (22) with θ3 held;
* ``direct``: (10) directly on ``[x̂1 x̂2 u 1]`` with the total disturbance (situation 2);
* ``no_const``: ``wellposed`` without the non-model-class column θ_{n+2} (Conclusion 3);
* ``literal_no_const``: ``literal`` without θ_{n+2} (Conclusion 3 under the printed rule; reduced regression only);
* ``none``: no identification (the conventional ESO; Θ ≡ 0).
"""

from __future__ import annotations

import numpy as np

from ctrl_analysis._validate import check_finite, check_in, check_int, check_positive
from ctrl_analysis.engine.blocks import DiscreteBlock, signal_names
from ctrl_analysis.engine.kernels import KernelBlock, Kernels, Layout, jitable
from ctrl_analysis.identification import batch_least_squares, identifiability

__all__ = [
    "LSM",
    "PHI",
    "VARIANTS",
    "BatchIdentification",
    "design",
    "equivalent_theta",
    "exact_report",
    "gram_update",
    "regressor_vector",
    "regressors",
    "solve_batch",
    "solve_many",
    "theta_from_lambda",
]

VARIANTS = ("none", "wellposed", "literal", "direct", "no_const", "literal_no_const")
#: the regressor vector whose Gram matrix the block accumulates
PHI = ("xhat[0]", "xhat[1]", "1", "xhat[2]", "f", "u", "kbar")
_NPHI = len(PHI)
#: largest column-scaled condition number a Gram matrix resolves in double precision (1/sqrt(eps))
GRAM_COND_LIMIT = 1.0 / np.sqrt(np.finfo(float).eps)
#: The kernel parameters of :class:`BatchIdentification`: the batch size, b0 and the controller gains.
LSM = Layout("N", "b0", ("k", 3))
AT = LSM.at


def regressors(xh1, xh2, xh3, u, f, kbar) -> np.ndarray:
    """``φ = [x̂1, x̂2, 1, x̂3, f, u, K̄]`` stacked on the last axis (any leading shape).

    Parameters
    ----------
    xh1, xh2, xh3 : ndarray
        The MESO's estimates.
    u : ndarray
        The control.
    f : ndarray
        ``XᵀΘ_used``, the model term fed to the observer.
    kbar : ndarray
        ``K̄`` of (14).

    Returns
    -------
    ndarray, shape (..., 7)
    """
    return np.stack([xh1, xh2, np.ones_like(xh1), xh3, f, u, kbar], axis=-1)


def design(variant: str, regression: str, full: bool = True, theta3_held: float = 0.0):
    """Columns of the regression ``H`` and the regressand ``z`` as combinations of φ.

    Parameters
    ----------
    variant : str
        One of :data:`VARIANTS` except ``"none"``.
    regression : {"reduced", "full"}
        (22) with θ3 ≡ 0, or (16)-(20) / (10) with θ3.
    full : bool
        ``False``: the situation-2 well-posed fallback, (22) with ``θ3 = theta3_held``.
    theta3_held : float

    Returns
    -------
    T_H : ndarray, shape (p, 7)
        ``H = φ T_Hᵀ``.
    t_z : ndarray, shape (7,)
        ``z = φ t_z``.
    """
    e = np.eye(_NPHI)
    x1, x2, one, x3, f, u, kb = e
    if variant == "literal":
        # (22)-(23): [x̂1 x̂2 1] [θ1 θ2 θ4]ᵀ = x̂3;  (16)-(17): [x̂1 x̂2 K̄ 1] Λ = x̂3
        cols = [x1, x2, one] if regression == "reduced" else [x1, x2, kb, one]
        return np.array(cols), x3
    if variant == "literal_no_const":
        if regression != "reduced":
            raise ValueError("literal_no_const is defined for the reduced regression (22) only")
        return np.array([x1, x2]), x3
    z = x3 + f  # the total disturbance estimate x̂3 + XᵀΘ_used
    if variant == "no_const":
        return np.array([x1, x2]), z
    if variant == "direct":
        # (10) directly: [x̂1 x̂2 u 1] Θ = z
        return np.array([x1, x2, u, one]), z
    if regression == "reduced":
        return np.array([x1, x2, one]), z
    if full:
        # (13)-(20) on the total disturbance: z = λ1 x̂1 + λ2 x̂2 + λ3 (K̄ + f) + λ4
        return np.array([x1, x2, kb + f, one]), z
    # the identifiable part only: z − θ3 u = [x̂1 x̂2 1] [θ1 θ2 θ4]ᵀ
    return np.array([x1, x2, one]), z - theta3_held * u


def theta_from_lambda(lam, k_gains, b0: float) -> np.ndarray:
    """(18)-(19): solve ``X_Θ Θ = b0 Λ`` for Θ (n = 2).

    Parameters
    ----------
    lam : array_like, shape (4,)
        Λ of (15), identified from (16)-(17).
    k_gains : array_like
        Controller gains ``k1, k2`` (first two entries used).
    b0 : float

    Returns
    -------
    ndarray, shape (4,)
        ``[θ1, θ2, θ3, θ4]``.
    """
    k1, k2 = k_gains[0], k_gains[1]
    X_theta = np.array([
        [b0, 0.0, -(k1 + lam[0]), 0.0],
        [0.0, b0, -(k2 + lam[1]), 0.0],
        [0.0, 0.0, 1.0 - lam[2], 0.0],
        [0.0, 0.0, -lam[3], b0],
    ])
    return b0 * np.linalg.solve(X_theta, lam)


def equivalent_theta(theta_true, b: float) -> np.ndarray:
    """Θ that explains the total disturbance on the perfectly tracked trajectory x1 = sin t, x2 = cos t.

    There ``x2' = -x1 = θ1 x1 + θ2 x2 + θ4 + b u``, so ``u = -((1 + θ1) x1 + θ2 x2 + θ4) / b`` lies in
    span{x1, x2, 1} and ``θ3 u`` folds into the other three parameters:
    ``Θ_eq = [θ1 - θ3 (1 + θ1)/b, θ2 (1 - θ3/b), 0, θ4 (1 - θ3/b)]``.
    """
    t1, t2, t3, t4 = np.asarray(theta_true, dtype=float)
    r = t3 / b
    return np.array([t1 - r * (1.0 + t1), t2 * (1.0 - r), 0.0, t4 * (1.0 - r)])


def _lsq(T_H, t_z, G=None, Phi=None, threshold=100.0):
    """Least squares of the design ``(T_H, t_z)`` from a Gram matrix ``G`` or the raw data ``Phi``."""
    if Phi is not None:
        return batch_least_squares(Phi @ T_H.T, Phi @ t_z, warn=False, cond_threshold=threshold)
    T = np.vstack([T_H, t_z])
    Ga = T @ G @ T.T
    # a square root F of the augmented Gram (FᵀF = [H z]ᵀ[H z]) has H's singular values and LS solution
    lam, V = np.linalg.eigh(0.5 * (Ga + Ga.T))
    F = np.sqrt(np.clip(lam, 0.0, None))[:, None] * V.T
    return batch_least_squares(F[:, :-1], F[:, -1], warn=False, cond_threshold=threshold)


def _lsq_many(T, G):
    """:func:`_lsq` from Gram matrices for many runs at once (the same solution to rounding).

    ``T`` (B, p + 1, 7) stacks each run's design ``[T_H; t_z]``, ``G`` (B, 7, 7) its Gram matrix. Returns the
    least-squares solution (B, p) — the minimum-norm one, singular values below ``eps·max(rows, p)·s_max``
    dropped, as ``numpy.linalg.lstsq(rcond=None)`` — with the numerical rank and the column-scaled condition
    number of ``H`` that :func:`ctrl_analysis.identification.identifiability` reports.
    """
    Tt = np.swapaxes(T, 1, 2)
    Ga = T @ G @ Tt
    lam, V = np.linalg.eigh(0.5 * (Ga + np.swapaxes(Ga, 1, 2)))
    F = np.sqrt(np.clip(lam, 0.0, None))[:, :, None] * np.swapaxes(V, 1, 2)
    H, z = F[:, :, :-1], F[:, :, -1]
    rows, p = H.shape[1], H.shape[2]
    U, s, Vt = np.linalg.svd(H, full_matrices=False)
    cut = max(rows, p) * np.finfo(float).eps * s[:, :1]
    rank = np.sum(s > cut, axis=1)
    norms = np.linalg.norm(H, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        ss = np.linalg.svd(H / np.where(norms > 0, norms, 1.0)[:, None, :], compute_uv=False)
        cond = np.where(np.all(norms > 0, axis=1) & (ss[:, -1] > 0), ss[:, 0] / ss[:, -1], np.inf)
        inv = np.where(s > cut, 1.0 / np.where(s > cut, s, 1.0), 0.0)
    theta = np.einsum("bji,bj->bi", Vt, inv * np.einsum("bkj,bk->bj", U, z))
    return theta, cond, rank


def _theta_from_lambda_many(lam, k_gains, b0):
    """:func:`theta_from_lambda` of many runs: ``lam`` (B, 4)."""
    n = lam.shape[0]
    X = np.zeros((n, 4, 4))
    X[:, 0, 0] = X[:, 1, 1] = X[:, 3, 3] = b0
    X[:, 0, 2] = -(k_gains[0] + lam[:, 0])
    X[:, 1, 2] = -(k_gains[1] + lam[:, 1])
    X[:, 2, 2] = 1.0 - lam[:, 2]
    X[:, 3, 2] = -lam[:, 3]
    return b0 * np.linalg.solve(X, lam[:, :, None])[:, :, 0]


def solve_many(variant, regression, theta_cum, k_gains, b0, thresholds, G):
    """:func:`solve_batch` for many runs of one variant at once, from their Gram matrices.

    Parameters
    ----------
    variant : str
        One of :data:`VARIANTS` except ``"none"``.
    regression : {"reduced", "full"}
    theta_cum : ndarray, shape (B, 4)
    k_gains : array_like
    b0 : float
    thresholds : ndarray, shape (B,)
    G : ndarray, shape (B, 7, 7)

    Returns
    -------
    theta : ndarray, shape (B, 4)
        The new Θ per run.
    cond, rank : ndarray, shape (B,)
        Column-scaled condition number and numerical rank of the regression tried first.
    """
    n = G.shape[0]
    T_H, t_z = design(variant, regression)
    p = T_H.shape[0]
    th, cond, rank = _lsq_many(np.broadcast_to(np.vstack([T_H, t_z]), (n, p + 1, _NPHI)), G)
    zero = np.zeros(n)
    if variant in ("literal", "literal_no_const"):
        if variant == "literal_no_const":
            inc = np.stack([th[:, 0], th[:, 1], zero, zero], axis=1)
        elif regression == "reduced":
            inc = np.stack([th[:, 0], th[:, 1], zero, th[:, 2]], axis=1)
        else:
            inc = _theta_from_lambda_many(th, k_gains, b0)
        return theta_cum + inc, cond, rank
    if variant == "no_const":
        return np.stack([th[:, 0], th[:, 1], zero, zero], axis=1), cond, rank
    if variant == "direct":
        return th.copy(), cond, rank
    if regression == "reduced":
        return np.stack([th[:, 0], th[:, 1], zero, th[:, 2]], axis=1), cond, rank
    out = np.empty((n, 4))
    ok = (rank == p) & (cond <= thresholds)
    if ok.any():
        out[ok] = _theta_from_lambda_many(th[ok], k_gains, b0)
    bad = ~ok
    if bad.any():
        # Theorem 1 gate failed: identify only the identifiable part, θ3 held at its current value
        T_H2, tz0 = design(variant, regression, full=False, theta3_held=0.0)
        held = theta_cum[bad, 2]
        t_z2 = tz0[None, :] - held[:, None] * np.eye(_NPHI)[PHI.index("u")][None, :]
        T2 = np.concatenate([np.broadcast_to(T_H2, (held.size,) + T_H2.shape), t_z2[:, None, :]], axis=1)
        red, _, _ = _lsq_many(T2, G[bad])
        out[bad] = np.stack([red[:, 0], red[:, 1], held, red[:, 2]], axis=1)
    return out, cond, rank


def solve_batch(variant, regression, theta_cum, k_gains, b0, threshold, G=None, Phi=None):
    """One batch of one run of the identification.

    Parameters
    ----------
    variant : str
        One of :data:`VARIANTS` except ``"none"``.
    regression : {"reduced", "full"}
    theta_cum : ndarray, shape (4,)
        Current Θ (the literal rule adds to it; the gate fallback holds its θ3).
    k_gains : array_like
        Controller gains.
    b0 : float
    threshold : float
        Identifiability gate on the column-scaled condition number.
    G : ndarray, shape (7, 7), optional
        The batch's Gram matrix of φ (the block's state).
    Phi : ndarray, shape (N, 7), optional
        The batch's raw rows of φ (exact path).

    Returns
    -------
    theta : ndarray, shape (4,)
        The new Θ.
    report : ctrl_analysis.identification.IdentifiabilityReport
        Of the regression tried first.
    """
    T_H, t_z = design(variant, regression)
    res = _lsq(T_H, t_z, G, Phi, threshold)
    th = res.theta
    if variant == "literal":
        # Table 1: Θ = Σ_i Θ̂_i
        inc = (np.array([th[0], th[1], 0.0, th[2]]) if regression == "reduced"
               else theta_from_lambda(th, k_gains, b0))
        return theta_cum + inc, res.report
    if variant == "no_const":
        return np.array([th[0], th[1], 0.0, 0.0]), res.report
    if variant == "literal_no_const":
        return theta_cum + np.array([th[0], th[1], 0.0, 0.0]), res.report
    if variant == "direct":
        return th.copy(), res.report
    if regression == "reduced":
        return np.array([th[0], th[1], 0.0, th[2]]), res.report
    if res.report.well_conditioned:
        return theta_from_lambda(th, k_gains, b0), res.report
    # Theorem 1 gate failed: identify only the identifiable part, θ3 held at its current value
    T_H, t_z = design(variant, regression, full=False, theta3_held=theta_cum[2])
    red = _lsq(T_H, t_z, G, Phi, threshold)
    return np.array([red.theta[0], red.theta[1], theta_cum[2], red.theta[2]]), res.report


def exact_report(variant, regression, Phi, threshold=100.0):
    """:func:`~ctrl_analysis.identification.identifiability` of the first regression on the raw batch ``Phi``."""
    T_H, _ = design(variant, regression)
    return identifiability(Phi @ T_H.T, cond_threshold=threshold)


@jitable(inline="always")  # the kernels call it; numba compiles it into them
def regressor_vector(u, p, phi):
    """``φ = [x̂1, x̂2, 1, x̂3, f, u, K̄]`` of one sample from the block's inputs (scalar-indexed).

    Parameters
    ----------
    u : ndarray
        The inputs ``[x̂1, x̂2, x̂3, u, θ1..θ4]`` (one run's vector, or a batch's columns).
    p : ndarray
        :data:`LSM`: ``N, b0, k1, k2, k3``.
    phi : ndarray
        φ, written in place (7 entries).
    """
    xh1, xh2, xh3, uc = u[0], u[1], u[2], u[3]
    phi[0] = xh1
    phi[1] = xh2
    phi[2] = 1.0
    phi[3] = xh3
    # f = XᵀΘ_used with X = [x̂1, x̂2, u, 1] (the term the observer receives, (29))
    phi[4] = u[4] * xh1 + u[5] * xh2 + u[6] * uc + u[7]
    phi[5] = uc
    # (14) K̄ = b0 u + Σ_l k_l x̂_l
    phi[6] = p[AT.b0] * uc + p[AT.k] * xh1 + p[AT.k + 1] * xh2 + p[AT.k + 2] * xh3


def gram_update(t, x, u, p, x_next):
    """One sample of the batch: ``G += φ φᵀ / N`` (Table 1's batch, as a Gram matrix); the outputs held.

    Parameters
    ----------
    t : float
        Time (unused).
    x : ndarray
        ``[c0..c3, log10_cond, rank, G (49, row-major)]`` (one run's vector, or a batch's columns).
    u : ndarray
        The inputs ``[x̂1, x̂2, x̂3, u, θ1..θ4]``.
    p : ndarray
        :data:`LSM`: ``N, b0, k1, k2, k3``.
    x_next : ndarray
        The next state, written in place; its entries 6..12 serve as φ's scratch before the Gram
        is written.
    """
    for i in range(6):
        x_next[i] = x[i]
    regressor_vector(u, p, x_next[6:13])
    # rows last to first: row 0 (the scratch) is written last, each φ_j read before its entry is written
    for i in range(_NPHI - 1, -1, -1):
        pi = x_next[6 + i]
        for j in range(_NPHI - 1, i - 1, -1):
            inc = pi * x_next[6 + j] / p[AT.N]  # φ_i φ_j / N = φ_j φ_i / N exactly: computed once per pair
            x_next[6 + j * _NPHI + i] = x[6 + j * _NPHI + i] + inc
            x_next[6 + i * _NPHI + j] = x[6 + i * _NPHI + j] + inc


def _held_outputs(t, x, u, p, y):
    """Outputs: the latest LSM result, log10 cond and rank (the state's first 6 entries)."""
    for i in range(y.shape[0]):
        y[i] = x[i]


class BatchIdentification(KernelBlock, DiscreteBlock):
    """Batch least squares every ``N`` samples on the MESO's estimates (discrete block; the variant per run at the end).

    The block's per-sample update only accumulates the batch's Gram matrix of φ (kernel
    :func:`gram_update`; the batched methods are derived from it). The batch-end solve
    (:meth:`identify`: SVD-based least squares, once per ``N`` samples, each run with its own
    variant and identifiability gate) is applied to the block's state by the caller between
    batches: the loop is stepped one batch per :meth:`~ctrl_analysis.engine.loop.Loop.simulate` call and
    :meth:`identify` is applied to the final state before the next call (see
    :func:`analysis.meso.loops.simulate_situation`).

    Parameters
    ----------
    N : int
        Batch size in samples (>= 4).
    h : float
        Sample period (s; recorded, the caller marks the batch ends).
    b0 : float
        Nominal input gain (for K̄ and X_Θ).
    k_gains : array_like, shape (3,)
        Controller gains ``k1, k2, k3`` of (30).
    regression : {"reduced", "full"}

    Block signals: inputs ``xhat[0..2]``, ``u``, ``theta[0..3]`` (the Θ in use); outputs ``c[0..3]``
    (the latest LSM result, input of W(s)), ``log10_cond`` (column-scaled) and ``rank`` of the latest
    batch's first regression (0 before the first batch and for ``none``); states: the
    outputs, then the batch's Gram matrix of φ divided by N (49 entries).

    References
    ----------
    Chen & Gao 2018, Table 1, eq. (9)-(23), Theorem 1. Departures: the batch is accumulated as a
    Gram matrix (same solution; condition numbers above ~1e7 not resolved), the well-posed and
    direct variants (see the module docstring).
    """

    feedthrough = False
    inputs = signal_names("xhat", 3) + ("u",) + signal_names("theta", 4)
    outputs = signal_names("c", 4) + ("log10_cond", "rank")
    states = outputs + tuple(f"G[{i}][{j}]" for i in range(_NPHI) for j in range(_NPHI))
    kernels = Kernels(output=_held_outputs, update=gram_update)

    def __init__(self, N, h, b0, k_gains, regression):
        self.N = check_int("N", N, minimum=4)
        self.h = float(check_positive("h", h))
        self.b0 = check_finite("b0", b0, scalar=True)
        self.k = check_finite("k_gains", k_gains, shape=(3,))
        self.regression = check_in("regression", regression, ("reduced", "full"))
        self.kernel_params = LSM.pack(N=float(self.N), b0=self.b0, k=self.k)

    def phi(self, u) -> np.ndarray:
        """φ of this sample from the block's inputs.

        Parameters
        ----------
        u : ndarray, shape (B, 8)
            The block's inputs.

        Returns
        -------
        ndarray, shape (B, 7)
        """
        phi = np.empty((u.shape[0], _NPHI))
        regressor_vector(u.T, self.kernel_params, phi.T)
        return phi

    def identify(self, x, variants, thresholds) -> None:
        """Batch end: solve every active run's regression from its Gram matrix, reset the Gram (in place).

        Parameters
        ----------
        x : ndarray, shape (B, 55)
            The block's states after the batch's last sample; runs whose Gram matrix is not finite
            (diverged) keep their outputs.
        variants : sequence of str
            One of :data:`VARIANTS` per run (``"none"``: the ESO, no identification).
        thresholds : float or sequence of float
            Identifiability gate (column-scaled condition number) per run.

        Raises
        ------
        ValueError
            If a variant is unknown, a threshold not > 0, or their number is not the runs'.
        """
        B = x.shape[0]
        variants = [check_in("variants", v, VARIANTS) for v in variants]
        thresholds = np.broadcast_to(check_positive("thresholds", thresholds), (B,))
        if len(variants) != B:
            raise ValueError(f"variants must have one entry per run ({B}), got {len(variants)}")
        finite = np.all(np.isfinite(x[:, 6:]), axis=1)
        groups: dict = {}
        for b, variant in enumerate(variants):
            if variant != "none" and finite[b]:
                groups.setdefault(variant, []).append(b)
        for variant, idx in groups.items():
            # every run of a variant at once (solve_batch's solution, vectorised over the runs)
            idx = np.array(idx)
            G = x[idx, 6:].reshape(-1, _NPHI, _NPHI)
            theta, cond, rank = solve_many(variant, self.regression, x[idx, :4], self.k, self.b0, thresholds[idx], G)
            x[idx, :4] = theta
            # log10 keeps the state bounded (the loop flags states beyond its bound as diverged)
            x[idx, 4], x[idx, 5] = np.log10(np.minimum(cond, 1e99)), rank
        x[:, 6:] = 0.0
