"""Small matrix helpers for kernels: views of a flat vector as vectors and matrices, and products in a fixed order.

A kernel works on flat float vectors (its state ``x``, inputs ``u``, parameters ``p``). Where its
maths is matrix-shaped, it views a stretch of a vector as a matrix and writes the equation with
these helpers, so it reads like the equation (filterpy writes ``P = F P Fᵀ + Q``)::

    n = as_int(p[AT.n])
    F = matrix(p, offset(AT.F, n), n, n)      # a Layout field ("F", ("n", "n"))
    P = matrix(x, n, n, n)                    # the state's covariance, row-major after x̂
    FP = scratch_matrix(n, n, u[0])
    mat_mul(F, P, FP)                         # F P
    mat_mul_t_add(FP, F, Q, matrix(x_next, n, n, n))   # P⁺ = F P Fᵀ + Q

Every helper works in both modes a kernel runs in, and is callable from numba-compiled kernels:

* **one run** (the compiled engine, and the batched methods run by run): ``x`` is 1-D, a view is a
  2-D array, an entry a float;
* **the batch's columns** (the batched methods, ``Kernels(columns=True)``): ``x`` is ``(n_x, B)``,
  ``p`` is ``(n_p,)`` shared or ``(n_p, B)`` per run, a view of ``x`` is ``(n, m, B)`` and an entry a
  row of the ``B`` runs' values.

Views never copy: writing into a view of ``x_next`` writes the kernel's result. The products are
plain loops whose sums run left to right in a stated order (starting from ``0.0``), never BLAS: a
run's numbers are bit-identical whatever the batch size and in either engine, and a hand-written
loop in the same order gives the same bits. ``out`` must not be an input of the same call.
"""

from __future__ import annotations

import numpy as np

from .kernels import jitable

__all__ = ["add_mat_mul_t", "dot", "mat_mul", "mat_mul_t", "mat_mul_t_add", "mat_vec", "matrix", "scratch_matrices",
           "scratch_matrix", "sub_dot", "symmetrize", "trace", "vector"]


@jitable
def vector(v, o, n):
    """The ``n`` entries of ``v`` from offset ``o``, as a view.

    Parameters
    ----------
    v : numpy.ndarray, shape (N,) or (N, B)
        A kernel's vector (one run, or the batch's columns).
    o, n : int
        Offset and length.

    Returns
    -------
    numpy.ndarray, shape (n,) or (n, B)
        ``v[o:o + n]`` (a view: writing it writes ``v``).
    """
    return v[o:o + n]


def matrix(v, o, n, m):
    """The ``n·m`` entries of ``v`` from offset ``o``, as a row-major ``(n, m)`` matrix view.

    Parameters
    ----------
    v : numpy.ndarray, shape (N,) or (N, B)
        A kernel's vector (one run, or the batch's columns, where ``v`` may be a transposed view).
    o, n, m : int
        Offset, rows and columns.

    Returns
    -------
    numpy.ndarray, shape (n, m) or (n, m, B)
        A view (writing it writes ``v``); ``M[i, j]`` is ``v[o + i m + j]``.
    """
    _compiled_views  # noqa: B018 - named so that the runners' cache key (engine.jit.source_key) covers it
    s = v[o:o + n * m]
    if s.shape[0] != n * m:
        raise IndexError(f"matrix: {n}x{m} entries from offset {o} run past the vector's {v.shape[0]} entries")
    return s.reshape((n, m) + s.shape[1:])  # splitting the first axis: always a view, never a copy


def scratch_matrix(n, m, like):
    """An ``(n, m)`` matrix of zeros for a kernel to work in, for one run or on the batch's columns.

    As :func:`ctrl_analysis.engine.kernels.scratch`, with two axes.

    Parameters
    ----------
    n, m : int
        Rows and columns.
    like : float or numpy.ndarray
        A per-run value of the kernel (``u[0]``): a number, or the runs' values on the batch's columns.

    Returns
    -------
    numpy.ndarray, shape (n, m) + shape of ``like``
    """
    _compiled_views  # noqa: B018 - named so that the runners' cache key (engine.jit.source_key) covers it
    return np.zeros((n, m) + np.shape(like))


def scratch_matrices(k, n, m, like):
    """``k`` matrices ``(n, m)`` of zeros in one allocation (``W[0]``, ``W[1]``, ...), for one run or the columns.

    Parameters
    ----------
    k, n, m : int
        Count, rows and columns.
    like : float or numpy.ndarray
        A per-run value of the kernel (``u[0]``).

    Returns
    -------
    numpy.ndarray, shape (k, n, m) + shape of ``like``
    """
    _compiled_views  # noqa: B018 - named so that the runners' cache key (engine.jit.source_key) covers it
    return np.zeros((k, n, m) + np.shape(like))


def _compiled_views():
    """:func:`matrix`, :func:`scratch_matrix` and :func:`scratch_matrices` inside numba-compiled kernels (1-D vectors).

    Compiled, ``matrix`` is an intrinsic that only writes the view's pointer, shape and strides:
    ``v[o:o + n m].reshape((n, m))`` calls numba's out-of-line reshape helper, which LLVM cannot
    see through (measured 1.7x slower on the RLS kernel), and a view that counts a reference to
    ``v`` pays an atomic increment and decrement per call (the Kalman kernel 1.5x slower). So the
    view holds no reference: it must not outlive the kernel call, and ``v`` must be an argument of
    the kernel or an array it holds itself (never a view of a scratch array that goes out of use).
    Like every compiled index, unchecked.
    """
    try:
        from llvmlite import ir
        from numba import types
        from numba.core import cgutils
        from numba.extending import intrinsic, overload
        from numba.np.arrayobj import make_array, populate_array
    except ImportError:  # pragma: no cover - numba is optional: the numpy engine needs none of this
        return

    def view(typingctx, v, o, shape):
        """``v`` viewed from offset ``o`` with ``shape`` (a tuple), row-major at ``v``'s stride; no reference held."""
        if not (isinstance(v, types.Array) and v.ndim == 1 and isinstance(shape, types.UniTuple)):
            return None
        ret = types.Array(v.dtype, shape.count, "C" if v.layout == "C" else "A")

        def codegen(context, builder, sig, args):
            ary = make_array(sig.args[0])(context, builder, args[0])
            o = context.cast(builder, args[1], sig.args[1], types.intp)
            dims = [context.cast(builder, d, sig.args[2].dtype, types.intp)
                    for d in cgutils.unpack_tuple(builder, args[2])]
            step = builder.extract_value(ary.strides, 0)
            byte = ir.IntType(8).as_pointer()
            data = builder.bitcast(builder.gep(builder.bitcast(ary.data, byte), [builder.mul(o, step)]),
                                   ary.data.type)
            strides = [step]
            for d in reversed(dims[1:]):
                strides.insert(0, builder.mul(d, strides[0]))
            out = make_array(sig.return_type)(context, builder)
            # no meminfo: the view lives inside the kernel call, while the caller holds v (a counted
            # reference would cost an atomic increment and decrement per view and call)
            populate_array(out, data=data, shape=cgutils.pack_array(builder, dims),
                           strides=cgutils.pack_array(builder, strides), itemsize=ary.itemsize, meminfo=None)
            return out._getvalue()

        return ret(v, o, shape), codegen

    view = intrinsic(view)

    @overload(matrix, inline="always")
    def _matrix(v, o, n, m):
        return lambda v, o, n, m: view(v, o, (n, m))

    @overload(scratch_matrix, inline="always")
    def _scratch_matrix(n, m, like):
        return lambda n, m, like: np.zeros((n, m))

    @overload(scratch_matrices, inline="always")
    def _scratch_matrices(k, n, m, like):
        return lambda k, n, m, like: np.zeros((k, n, m))


_compiled_views()


@jitable
def dot(a, b, c):
    """``c + a₀b₀ + a₁b₁ + …``, summed left to right from ``c``.

    Parameters
    ----------
    a, b : numpy.ndarray, shape (n,) or (n, B)
    c : float or numpy.ndarray, shape (B,)
        The start of the sum (``0.0`` for the plain dot product).

    Returns
    -------
    float or numpy.ndarray, shape (B,)
    """
    acc = c
    for i in range(a.shape[0]):
        acc = acc + a[i] * b[i]
    return acc


@jitable
def sub_dot(c, a, b):
    """``c − a₀b₀ − a₁b₁ − …``, subtracted left to right (a residual ``y − h x``).

    Parameters
    ----------
    c : float or numpy.ndarray, shape (B,)
    a, b : numpy.ndarray, shape (n,) or (n, B)

    Returns
    -------
    float or numpy.ndarray, shape (B,)
    """
    acc = c
    for i in range(a.shape[0]):
        acc = acc - a[i] * b[i]
    return acc


@jitable
def mat_vec(A, x, out):
    """``out = A x``: ``out[i] = 0 + A[i,0] x[0] + A[i,1] x[1] + …``, left to right.

    Parameters
    ----------
    A : numpy.ndarray, shape (n, m) or (n, m, B)
    x : numpy.ndarray, shape (m,) or (m, B)
    out : numpy.ndarray, shape (n,) or (n, B)
        Written in place (not ``x``).

    Returns
    -------
    numpy.ndarray
        ``out``.
    """
    for i in range(A.shape[0]):
        acc = 0.0
        for j in range(A.shape[1]):
            acc = acc + A[i, j] * x[j]
        out[i] = acc
    return out


@jitable
def mat_mul(A, B, out):
    """``out = A B``: ``out[i,j] = 0 + A[i,0] B[0,j] + A[i,1] B[1,j] + …``, left to right.

    Parameters
    ----------
    A : numpy.ndarray, shape (n, k) or (n, k, B)
    B : numpy.ndarray, shape (k, m) or (k, m, B)
    out : numpy.ndarray, shape (n, m) or (n, m, B)
        Written in place (neither ``A`` nor ``B``).

    Returns
    -------
    numpy.ndarray
        ``out``.
    """
    for i in range(A.shape[0]):
        for j in range(B.shape[1]):
            acc = 0.0
            for k in range(A.shape[1]):
                acc = acc + A[i, k] * B[k, j]
            out[i, j] = acc
    return out


@jitable
def mat_mul_t(A, B, out):
    """``out = A Bᵀ``: ``out[i,j] = 0 + A[i,0] B[j,0] + A[i,1] B[j,1] + …``, left to right.

    Parameters
    ----------
    A : numpy.ndarray, shape (n, k) or (n, k, B)
    B : numpy.ndarray, shape (m, k) or (m, k, B)
    out : numpy.ndarray, shape (n, m) or (n, m, B)
        Written in place (neither ``A`` nor ``B``).

    Returns
    -------
    numpy.ndarray
        ``out``.
    """
    for i in range(A.shape[0]):
        for j in range(B.shape[0]):
            acc = 0.0
            for k in range(A.shape[1]):
                acc = acc + A[i, k] * B[j, k]
            out[i, j] = acc
    return out


@jitable
def mat_mul_t_add(A, B, C, out):
    """``out = A Bᵀ + C``: the sum of :func:`mat_mul_t`, then ``+ C[i,j]`` (``F P Fᵀ + Q`` with ``A = F P``).

    Parameters
    ----------
    A : numpy.ndarray, shape (n, k) or (n, k, B)
    B : numpy.ndarray, shape (m, k) or (m, k, B)
    C : numpy.ndarray, shape (n, m) or (n, m, B)
    out : numpy.ndarray, shape (n, m) or (n, m, B)
        Written in place (not ``A`` nor ``B``; ``C`` may be ``out``).

    Returns
    -------
    numpy.ndarray
        ``out``.
    """
    for i in range(A.shape[0]):
        for j in range(B.shape[0]):
            acc = 0.0
            for k in range(A.shape[1]):
                acc = acc + A[i, k] * B[j, k]
            out[i, j] = acc + C[i, j]
    return out


@jitable
def add_mat_mul_t(C, A, B, out):
    """``out = C + A Bᵀ``: ``out[i,j] = 0 + C[i,j] + A[i,0] B[j,0] + …``, left to right (``C`` first).

    Parameters
    ----------
    C : numpy.ndarray, shape (n, m) or (n, m, B)
    A : numpy.ndarray, shape (n, k) or (n, k, B)
    B : numpy.ndarray, shape (m, k) or (m, k, B)
    out : numpy.ndarray, shape (n, m) or (n, m, B)
        Written in place (not ``A`` nor ``B``; ``C`` may be ``out``).

    Returns
    -------
    numpy.ndarray
        ``out``.
    """
    for i in range(A.shape[0]):
        for j in range(B.shape[0]):
            acc = 0.0 + C[i, j]
            for k in range(A.shape[1]):
                acc = acc + A[i, k] * B[j, k]
            out[i, j] = acc
    return out


@jitable
def symmetrize(A):
    """``A = (A + Aᵀ) / 2`` in place: ``0.5 (A[i,j] + A[j,i])`` for ``j >= i``, written to both entries.

    Parameters
    ----------
    A : numpy.ndarray, shape (n, n) or (n, n, B)

    Returns
    -------
    numpy.ndarray
        ``A``.
    """
    n = A.shape[0]
    for i in range(n):
        for j in range(i, n):
            v = 0.5 * (A[i, j] + A[j, i])
            A[i, j] = v
            A[j, i] = v
    return A


@jitable
def trace(A):
    """``0 + A[0,0] + A[1,1] + …``, left to right.

    Parameters
    ----------
    A : numpy.ndarray, shape (n, n) or (n, n, B)

    Returns
    -------
    float or numpy.ndarray, shape (B,)
    """
    acc = 0.0
    for i in range(A.shape[0]):
        acc = acc + A[i, i]
    return acc
