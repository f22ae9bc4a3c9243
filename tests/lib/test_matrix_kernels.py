"""The matrix-shaped kernels rewritten on :mod:`ctrl_analysis.engine.matrix` give the numbers of the index loops
they replaced, bit for bit (issue 29, item 4).

The old kernels (``DiscreteKalmanFilter``, ``LinearKalmanFilter``, ``RecursiveLeastSquaresBlock`` before the
rewrite) are kept below verbatim, bar their docstrings and names; blocks that run them are compared with the
library's blocks kernel by kernel (one run in Python, compiled, and on the batch's columns) and in loops on both
engines, several seeds, with per-run parameters: ``assert_array_equal``, never a tolerance.
"""

import numpy as np
import pytest

from ctrl_analysis.engine import Execution
from ctrl_analysis.engine.kernels import Kernels, Layout, as_int, jitable
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.kalman import DiscreteKalmanFilter, LinearKalmanFilter
from ctrl_analysis.identification import RecursiveLeastSquaresBlock

# the layouts' heads before the rewrite (the arrays followed at hand-computed offsets)
KF_AT = Layout("n", "has_b", "R").at
KF_ARRAYS = 3
LKF_AT = Layout("n", "R").at
LKF_ARRAYS = 2
RLS_AT = Layout("n", "forgetting", "max_trace", "projected").at
RLS_BOUNDS = 4


# ------------------------------------------------------------------ the old kernels, verbatim
@jitable
def old_kf_at(p):
    n = as_int(p[KF_AT.n])
    return n, KF_ARRAYS, KF_ARRAYS + n, KF_ARRAYS + n + n * n, KF_ARRAYS + n + 2 * n * n


def old_kalman_output(t, x, u, p, y):
    n, h, _, _, _ = old_kf_at(p)
    s, o = (x, 0) if x.shape[0] > 0 else (u, n + n * n)
    S = p[KF_AT.R]  # S(k) = h P hᵀ + R
    for i in range(n):
        ph = 0.0
        for j in range(n):
            ph = ph + s[n + i * n + j] * p[h + j]
        S = S + p[h + i] * ph
    r = u[o]  # innovation y(k) − h x̂(k|k−1)
    for i in range(n):
        r = r - p[h + i] * s[i]
    for i in range(n):
        ph = 0.0
        for j in range(n):
            ph = ph + s[n + i * n + j] * p[h + j]
        y[i] = s[i] + (ph / S) * r  # K(k) = P hᵀ / S(k)


def old_kalman_update(t, x, u, p, x_next):
    n, h, oF, oQ, ob = old_kf_at(p)
    S = p[KF_AT.R]
    for i in range(n):
        ph = 0.0
        for j in range(n):
            ph = ph + x[n + i * n + j] * p[h + j]
        S = S + p[h + i] * ph
    r = u[0]
    for i in range(n):
        r = r - p[h + i] * x[i]
    for i in range(n):  # x̂(k+1|k) = F x̂(k|k) + b u(k)
        acc = 0.0
        for j in range(n):
            ph = 0.0
            for m in range(n):
                ph = ph + x[n + j * n + m] * p[h + m]
            acc = acc + p[oF + i * n + j] * (x[j] + (ph / S) * r)
        x_next[i] = acc + u[1] * p[ob + i] if as_int(p[KF_AT.has_b]) else acc
    for i in range(n):  # P(k+1|k) = F P(k|k) Fᵀ + Qd, P(k|k) = P − K S Kᵀ
        for j in range(n):
            acc = 0.0 + p[oQ + i * n + j]
            for k in range(n):
                fp = 0.0
                for m in range(n):
                    km, kk = 0.0, 0.0
                    for q in range(n):
                        km = km + x[n + m * n + q] * p[h + q]
                        kk = kk + x[n + k * n + q] * p[h + q]
                    fp = fp + p[oF + i * n + m] * (x[n + m * n + k] - (km / S) * (kk / S) * S)
                acc = acc + fp * p[oF + j * n + k]
            x_next[n + i * n + j] = acc


@jitable
def old_lkf_at(p):
    n = as_int(p[LKF_AT.n])
    F = LKF_ARRAYS
    return n, F, F + n * n, F + n * n + n, F + n * n + 2 * n


@jitable
def old_lkf_filter(x, u, p, W):
    n, F, G, H, Q = old_lkf_at(p)
    Pp, K, xf = n * n, 2 * n * n, 2 * n * n + n  # offsets in W
    # x̂(k|k−1) = F x̂(k−1) + G u(k−1)
    for i in range(n):
        acc = 0.0
        for j in range(n):
            acc += p[F + i * n + j] * x[j]
        W[xf + i] = acc + u[1] * p[G + i]
    # P(k|k−1) = F P Fᵀ + Q
    for i in range(n):
        for k in range(n):
            acc = 0.0
            for j in range(n):
                acc += p[F + i * n + j] * x[n + j * n + k]
            W[i * n + k] = acc
    for i in range(n):
        for m in range(n):
            acc = 0.0
            for k in range(n):
                acc += W[i * n + k] * p[F + m * n + k]
            W[Pp + i * n + m] = acc + p[Q + i * n + m]
    # K = P(k|k−1) Hᵀ / (H P(k|k−1) Hᵀ + R);  x̂(k) = x̂(k|k−1) + K (y − H x̂(k|k−1))
    S = 0.0
    yp = 0.0
    for i in range(n):
        acc = 0.0
        for j in range(n):
            acc += W[Pp + i * n + j] * p[H + j]
        W[K + i] = acc
        S += acc * p[H + i]
        yp += W[xf + i] * p[H + i]
    for i in range(n):
        W[K + i] = W[K + i] / (S + p[LKF_AT.R])
        W[xf + i] = W[xf + i] + W[K + i] * (u[0] - yp)


def old_lkf_update(t, x, u, p, x_next):
    n, _, _, H, _ = old_lkf_at(p)
    Pp, K, xf = n * n, 2 * n * n, 2 * n * n + n
    W = np.empty((2 * n * n + 2 * n,) + x.shape[1:])
    old_lkf_filter(x, u, p, W)
    # P(k) = (I − K H) P(k|k−1) (I − K H)ᵀ + K R Kᵀ
    for i in range(n):
        x_next[i] = W[xf + i]
        for k in range(n):
            acc = 0.0
            for j in range(n):
                acc += ((1.0 if i == j else 0.0) - W[K + i] * p[H + j]) * W[Pp + j * n + k]
            W[i * n + k] = acc
    for i in range(n):
        for m in range(n):
            acc = 0.0
            for k in range(n):
                acc += W[i * n + k] * ((1.0 if m == k else 0.0) - W[K + m] * p[H + k])
            x_next[n + i * n + m] = acc + p[LKF_AT.R] * W[K + i] * W[K + m]


def old_lkf_output(t, x, u, p, y):
    n, _, _, H, _ = old_lkf_at(p)
    W = np.empty((2 * n * n + 2 * n,) + x.shape[1:])
    old_lkf_filter(x, u, p, W)
    acc = 0.0
    for i in range(n):
        acc += W[2 * n * n + n + i] * p[H + i]
    y[0] = acc


@jitable
def old_rls_gain(x, u, p, out):
    n = int(p[RLS_AT.n])
    for i in range(n):
        acc = 0.0
        for j in range(n):
            acc = acc + x[n + i * n + j] * u[1 + j]
        out[i] = acc
    hPh = 0.0
    hth = 0.0
    for i in range(n):
        hPh = hPh + u[1 + i] * out[i]
        hth = hth + u[1 + i] * x[i]
    return p[RLS_AT.forgetting] + hPh, u[0] - hth


@jitable
def old_rls_theta(x, p, out, den, innov):
    n = int(p[RLS_AT.n])
    lo, hi = RLS_BOUNDS, RLS_BOUNDS + n  # the offsets of rls_layout's lower, upper
    for i in range(n):
        v = x[i] + out[i] / den * innov
        # projection onto the box lower <= θ <= upper (NaN stays NaN, as np.clip; infinite bounds: identity)
        v = p[lo + i] if v < p[lo + i] else v
        out[i] = p[hi + i] if v > p[hi + i] else v


def old_rls_update(t, x, u, p, x_next):
    n = int(p[RLS_AT.n])
    lam = p[RLS_AT.forgetting]
    den, innov = old_rls_gain(x, u, p, x_next)  # R h in x_next[:n] until θ(k) overwrites it
    # R(k) = (R − D (R h)ᵀ) / λ with D = R h / den, then symmetrised: 0.5 (R(k) + R(k)ᵀ)
    for i in range(n):
        d = x_next[i] / den
        for j in range(n):
            x_next[n + i * n + j] = (x[n + i * n + j] - d * x_next[j]) / lam
    for i in range(n):
        for j in range(i, n):
            v = 0.5 * (x_next[n + i * n + j] + x_next[n + j * n + i])
            x_next[n + i * n + j] = v
            x_next[n + j * n + i] = v
    # anti-windup: trace R(k) <= max_trace, R(k) scaled by min(1, max_trace / trace) (NaN propagates, as
    # np.minimum); a scale of 1 (no cap) is exact. Conditional expressions, not if statements, keep numba lean.
    tr = 0.0
    for i in range(n):
        tr = tr + x_next[n + i * n + i]
    s = p[RLS_AT.max_trace] / tr if p[RLS_AT.max_trace] > 0.0 else 1.0
    s = 1.0 if s >= 1.0 else s
    for i in range(n * n):
        x_next[n + i] = x_next[n + i] * s
    old_rls_theta(x, p, x_next, den, innov)


def old_rls_output(t, x, u, p, y):
    den, innov = old_rls_gain(x, u, p, y)
    old_rls_theta(x, p, y, den, innov)




class OldKF(DiscreteKalmanFilter):
    kernels = Kernels(output=old_kalman_output, update=old_kalman_update)


class OldLKF(LinearKalmanFilter):
    kernels = Kernels(output=old_lkf_output, update=old_lkf_update)


class OldRLS(RecursiveLeastSquaresBlock):
    kernels = Kernels(output=old_rls_output, update=old_rls_update, columns=False)


# ------------------------------------------------------------------ cases
def _spd(rng, n, scale=1.0):
    M = rng.normal(size=(n, n))
    return scale * (M @ M.T + 0.5 * np.eye(n))


def _stable(rng, n):
    F = rng.normal(size=(n, n))
    return 0.9 * F / max(1.0, np.max(np.abs(np.linalg.eigvals(F))))


def kf_case(rng, cls, n=3, with_b=True):
    kw = {"b": rng.normal(size=n)} if with_b else {}
    blk = cls(_stable(rng, n), rng.normal(size=n), _spd(rng, n, 0.1), 0.5, P0=_spd(rng, n), **kw)
    return blk, "R", rng.uniform(0.1, 2.0)


def lkf_case(rng, cls, n=4):
    blk = cls(_stable(rng, n), rng.normal(size=n), rng.normal(size=n), _spd(rng, n, 0.01), 1.0, P0=_spd(rng, n))
    return blk, "R", rng.uniform(0.1, 2.0)


def rls_case(rng, cls, n=3):
    blk = cls(n, forgetting=0.98, P0=100.0, lower=[-1.0, -np.inf, 0.0], upper=[1.0, 2.0, np.inf], max_trace=150.0)
    return blk, "forgetting", rng.uniform(0.9, 1.0)


CASES = {
    "kalman": (kf_case, DiscreteKalmanFilter, OldKF),
    "kalman-no-b": (lambda rng, cls: kf_case(rng, cls, n=2, with_b=False), DiscreteKalmanFilter, OldKF),
    "kalman-1": (lambda rng, cls: kf_case(rng, cls, n=1), DiscreteKalmanFilter, OldKF),
    "lkf": (lkf_case, LinearKalmanFilter, OldLKF),
    "rls": (rls_case, RecursiveLeastSquaresBlock, OldRLS),
}


def _pair(name, seed):
    build, new, old = CASES[name]
    a, b = build(np.random.default_rng(seed), new), build(np.random.default_rng(seed), old)
    assert np.array_equal(a[0].kernel_params, b[0].kernel_params)
    return a, b


def _state_and_inputs(blk, rng, B):
    """Random states around the initial one (a covariance block kept symmetric positive definite) and inputs."""
    x0 = blk.initial_state()
    x = np.tile(x0, (B, 1))
    n = round((-1 + np.sqrt(1 + 4 * x0.size)) / 2)  # [x̂ (n), P (n²)]
    x[:, :n] += rng.normal(size=(B, n))
    for b in range(B):
        x[b, n:] = (x0[n:].reshape(n, n) + _spd(rng, n, 0.1)).ravel()
    return x, rng.normal(size=(B, len(blk.inputs)))


# ------------------------------------------------------------------ kernel by kernel
@pytest.mark.parametrize("name", sorted(CASES))
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_kernels_equal_the_old_ones_bit_for_bit(name, seed):
    from ctrl_analysis.engine import codegen

    (new, _, _), (old, _, _) = _pair(name, seed)
    rng = np.random.default_rng(100 + seed)
    for B in (1, 7, 70):  # 70 >= ROWS_COMPILED_MIN: a kernel that is not run on columns runs compiled rows
        x, u = _state_and_inputs(new, rng, B)
        for kind in ("output", "update"):
            np.testing.assert_array_equal(getattr(new, kind)(0.0, x, u), getattr(old, kind)(0.0, x, u))
            fn_new, fn_old = getattr(new.kernels, kind), getattr(old.kernels, kind)
            width = len(new.outputs) if kind == "output" else x.shape[1]
            for fn_n, fn_o in ((fn_new, fn_old), (codegen._jit(fn_new), codegen._jit(fn_old))):
                a, b = np.empty((B, width)), np.empty((B, width))
                for r in range(B):
                    fn_n(0.0, x[r], u[r], new.kernel_params, a[r])
                    fn_o(0.0, x[r], u[r], old.kernel_params, b[r])
                np.testing.assert_array_equal(a, b)
            # per-run parameters on the columns (the numpy engine's call)
            P = np.tile(new.kernel_params, (B, 1))
            np.testing.assert_array_equal(new.batched(kind, 0.0, x, u, P), old.batched(kind, 0.0, x, u, P))


# ------------------------------------------------------------------ in loops, both engines
@pytest.mark.parametrize("name", sorted(CASES))
@pytest.mark.parametrize("engine", ["numpy", "compiled"])
def test_loops_equal_the_old_kernels_bit_for_bit(name, engine):
    for seed in (3, 4):
        (new, pname, _), (old, _, _) = _pair(name, seed)
        rng = np.random.default_rng(seed)
        B, N = 6, 40
        ext = {s: rng.normal(size=(N, B)) for s in new.inputs}
        per_run = np.array([_pair(name, seed + 10 + b)[0][2] for b in range(B)])  # one value per run
        res = {}
        for key, blk in (("new", new), ("old", old)):
            loop = Loop([place(blk, "blk")], 0.1)
            res[key] = loop.simulate(N, inputs=ext, params={"blk": {pname: per_run}},
                                     execution=Execution(engine=engine))
        for s in res["new"].signals:
            np.testing.assert_array_equal(res["new"].signals[s], res["old"].signals[s], err_msg=s)
        for s in res["new"].final_states:
            np.testing.assert_array_equal(res["new"].final_states[s], res["old"].final_states[s], err_msg=s)
        assert np.all(np.isfinite(res["new"].final_states["blk"]))
