"""The kernels' matrix helpers and sized layouts: views that never copy, products in their stated order on one run,
on the batch's columns and compiled (bit for bit), layouts whose arrays are sized by a field."""

import numpy as np
import pytest

from ctrl_analysis.engine import matrix as mx
from ctrl_analysis.engine.kernels import Layout, as_int, jitable, offset

KF = Layout("n", "R", ("h", "n"), ("F", ("n", "n")), ("G", ("n", 2)), ("c", 3))
AT = KF.at


# ------------------------------------------------------------------ layouts sized by a field
def test_a_sized_layout_gives_the_offsets_of_every_size():
    assert AT.n == 0 and AT.R == 1 and AT.h == 2  # before the first sized array: plain offsets
    assert AT.F == (2, 1, 0) and AT.G == (2, 1, 1) and AT.c == (2, 3, 1)
    assert KF.size is None and KF.size_name == "n"
    for n in (0, 1, 2, 5):
        fixed = KF.sized(n=n)
        assert fixed.size_name is None and fixed.size == 2 + n + n * n + 2 * n + 3
        assert tuple(offset(o, n) for o in AT) == tuple(fixed.at)
        assert fixed.shapes[3] == (n, n) and fixed.shapes[4] == (n, 2)
    assert Layout("a", ("b", 2)).sized().at == Layout("a", ("b", 2)).at


def test_a_sized_layout_packs_and_unpacks_like_its_fixed_layout():
    rng = np.random.default_rng(0)
    vals = {"n": 3, "R": 0.5, "h": rng.normal(size=3), "F": rng.normal(size=(3, 3)), "G": rng.normal(size=(3, 2)),
            "c": [1.0, 2.0, 3.0]}
    p = KF.pack(**vals)
    np.testing.assert_array_equal(p, KF.sized(n=3).pack(**vals))
    back = KF.unpack(p)
    for k, v in vals.items():
        np.testing.assert_array_equal(back[k], v)
    with pytest.raises(ValueError, match="shape"):
        KF.pack(**{**vals, "F": np.eye(2)})
    with pytest.raises(ValueError, match="whole number"):
        KF.pack(**{**vals, "n": 2.5})
    with pytest.raises(ValueError, match="missing"):
        KF.pack(R=1.0)


@pytest.mark.parametrize("fields, match", [
    ((("a", "n"), "n"), "before the first array"),
    (("n", "m", ("a", ("n", "m"))), "one size field"),
    (("n", ("a", ("n", "n", "n"))), "at most twice"),
    ((("n", 2), ("a", "n")), "scalar field"),
])
def test_a_size_name_is_checked(fields, match):
    with pytest.raises(ValueError, match=match):
        Layout(*fields)


def test_offset_is_a_compile_time_constant_in_numba():
    numba = pytest.importorskip("numba")

    @numba.njit
    def read(p):
        n = as_int(p[AT.n])
        return p[offset(AT.c, n)], p[offset(AT.R, n)]

    p = KF.pack(n=2, R=0.5, h=[1, 2], F=np.eye(2), G=np.ones((2, 2)), c=[7.0, 8.0, 9.0])
    assert read(p) == (7.0, 0.5)


# ------------------------------------------------------------------ views
def test_views_write_through_on_one_run_and_on_the_columns():
    v = np.arange(12.0)
    M = mx.matrix(v, 2, 2, 3)
    assert M.shape == (2, 3) and M[1, 2] == 7.0
    M[1, 2] = -1.0
    assert v[7] == -1.0
    X = np.arange(36.0).reshape(3, 12)  # three runs; the kernel sees the columns X.T, a transposed view
    C = mx.matrix(X.T, 2, 2, 3)
    assert C.shape == (2, 3, 3) and np.shares_memory(C, X)
    np.testing.assert_array_equal(C[1, 2], X[:, 7])
    C[0, 1] = 0.0
    np.testing.assert_array_equal(X[:, 3], 0.0)
    np.testing.assert_array_equal(mx.vector(X.T, 4, 2), X.T[4:6])
    with pytest.raises(IndexError, match="run past"):
        mx.matrix(v, 8, 2, 3)
    assert mx.scratch_matrix(2, 3, 0.0).shape == (2, 3) and mx.scratch_matrix(2, 3, np.zeros(5)).shape == (2, 3, 5)
    assert mx.scratch_matrices(4, 2, 3, np.zeros(5)).shape == (4, 2, 3, 5)


# ------------------------------------------------------------------ products, in their order
def _loops(A, B, C, x):
    """The products of the helpers as plain loops, in the order the docstrings state."""
    n, k, m = A.shape[0], A.shape[1], B.shape[1]
    AB, ABt_C, C_ABt = np.empty((n, m)), np.empty((n, n)), np.empty((n, n))
    for i in range(n):
        for j in range(m):
            acc = 0.0
            for q in range(k):
                acc = acc + A[i, q] * B[q, j]
            AB[i, j] = acc
        for j in range(n):
            acc, acc2 = 0.0, 0.0 + C[i, j]
            for q in range(k):
                acc = acc + A[i, q] * A[j, q]
                acc2 = acc2 + A[i, q] * A[j, q]
            ABt_C[i, j], C_ABt[i, j] = acc + C[i, j], acc2
    Ax = np.array([sum((A[i, q] * x[q] for q in range(k)), 0.0) for i in range(n)])
    return AB, ABt_C, C_ABt, Ax


@jitable
def _all(A, B, C, x, AB, ABt, ABt_C, C_ABt, Ax, S):
    mx.mat_mul(A, B, AB)
    mx.mat_mul_t(A, A, ABt)
    mx.mat_mul_t_add(A, A, C, ABt_C)
    mx.add_mat_mul_t(C, A, A, C_ABt)
    mx.mat_vec(A, x, Ax)
    S[...] = C
    mx.symmetrize(S)
    return mx.dot(x, x, 0.5), mx.sub_dot(0.5, x, x), mx.trace(C)


@pytest.mark.parametrize("compiled", [False, True])
def test_products_follow_their_stated_order_bit_for_bit(compiled):
    rng = np.random.default_rng(1)
    n, k, m = 3, 4, 2
    A, B, C, x = rng.normal(size=(n, k)), rng.normal(size=(k, m)), rng.normal(size=(n, n)), rng.normal(size=k)
    fn = _all
    if compiled:
        fn = pytest.importorskip("numba").njit(_all)
    outs = [np.empty((n, m)), np.empty((n, n)), np.empty((n, n)), np.empty((n, n)), np.empty(n), np.empty((n, n))]
    d, r, tr = fn(A, B, C, x, *outs)
    AB, ABt_C, C_ABt, Ax = _loops(A, B, C, x)
    for got, want in zip([outs[0], outs[2], outs[3], outs[4]], [AB, ABt_C, C_ABt, Ax], strict=True):
        np.testing.assert_array_equal(got, want)
    np.testing.assert_allclose(outs[1], A @ A.T, rtol=1e-14)
    np.testing.assert_array_equal(outs[5], 0.5 * (C + C.T))
    assert d == sum((x[i] * x[i] for i in range(k)), 0.5)
    want = 0.5
    for i in range(k):
        want = want - x[i] * x[i]
    assert r == want and tr == 0.0 + C[0, 0] + C[1, 1] + C[2, 2]


def test_products_on_the_columns_equal_each_run_bit_for_bit():
    rng = np.random.default_rng(2)
    n, k, m, runs = 3, 4, 2, 5
    A, B, C, x = (rng.normal(size=(runs, n, k)), rng.normal(size=(runs, k, m)), rng.normal(size=(runs, n, n)),
                  rng.normal(size=(runs, k)))
    cols = [np.empty((n, m, runs)), np.empty((n, n, runs)), np.empty((n, n, runs)), np.empty((n, n, runs)),
            np.empty((n, runs)), np.empty((n, n, runs))]
    d, r, tr = _all(*(np.moveaxis(a, 0, -1) for a in (A, B, C, x)), *cols)
    for b in range(runs):
        one = [np.empty((n, m)), np.empty((n, n)), np.empty((n, n)), np.empty((n, n)), np.empty(n), np.empty((n, n))]
        assert _all(A[b], B[b], C[b], x[b], *one) == (d[b], r[b], tr[b])
        for c, o in zip(cols, one, strict=True):
            np.testing.assert_array_equal(c[..., b], o)
