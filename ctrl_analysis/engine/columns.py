"""The :class:`ColumnKernels` mixin: a block's numpy methods are its compiled kernel applied to the batch's columns.

Re-exported as :class:`ctrl_analysis.engine.blocks.ColumnKernels` (where blocks import it from).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

__all__ = ["ColumnKernels"]


class ColumnKernels:
    """Mixin: a block whose numpy methods are its compiled kernel applied to the batch's columns.

    One source per equation: the block's equations are written once, as plain scalar-indexed
    module-level functions ``output(t, x, u, p, y)`` and ``update(t, x, u, p, x_next)`` (discrete)
    or ``rhs(t, x, u, p, dx)`` (continuous) with ``x[i]``-style indexing and no per-value branches.
    Called on one run's vectors they are the compiled engine's kernel
    (:class:`~ctrl_analysis.engine.kernels.BlockKernel`); called on the transposed batch arrays
    (``x.T``, ``u.T``, ``p.T``, ``out.T``) they are the block's numpy methods. A block using the
    mixin lists its functions' names in ``column_kernels`` (keys ``"output"`` and ``"update"`` or
    ``"rhs"``; names looked up in the block's module) and sets ``self._p``: its parameter vector
    (values per run are given to ``Loop.simulate(params=...)``; a ``(B, n_p)`` array, one row per run,
    ties the block to one batch size, see :class:`~ctrl_analysis.engine.codegen.BlockKernel`).

    Put the mixin first among the bases (``class F(ColumnKernels, DiscreteBlock)``).
    """

    column_kernels: ClassVar[dict] = {}

    def _column_fns(self) -> dict:
        cls = type(self)
        fns = cls.__dict__.get("_column_fns_cache")
        if fns is None:
            import sys

            module = sys.modules[cls.__module__]
            fns = {kind: getattr(module, name) for kind, name in cls.column_kernels.items()}
            cls._column_fns_cache = fns
        return fns

    def _on_columns(self, kind, t, x, u, width):
        out = np.empty((x.shape[0], width))
        self._column_fns()[kind](t, x.T, u.T, self._p.T, out.T)
        return out

    def output(self, t, x, u, params=None) -> np.ndarray:
        """The output, the ``"output"`` kernel on the batch's columns.

        Parameters
        ----------
        t : float
        x : numpy.ndarray, shape (B, n)
        u : numpy.ndarray, shape (B, m)
        params : ignored

        Returns
        -------
        numpy.ndarray, shape (B, len(outputs))
        """
        return self._on_columns("output", t, x, u, len(self.outputs))

    def update(self, t, x, u, params=None) -> np.ndarray:
        """The next state, the ``"update"`` kernel on the batch's columns (discrete blocks).

        Parameters
        ----------
        t : float
        x : numpy.ndarray, shape (B, n)
        u : numpy.ndarray, shape (B, m)
        params : ignored

        Returns
        -------
        numpy.ndarray, shape (B, n)
        """
        return self._on_columns("update", t, x, u, x.shape[1])

    def rhs(self, t, x, u, params=None) -> np.ndarray:
        """The state derivative, the ``"rhs"`` kernel on the batch's columns (continuous blocks).

        Parameters
        ----------
        t : float
        x : numpy.ndarray, shape (B, n)
        u : numpy.ndarray, shape (B, m)
        params : ignored

        Returns
        -------
        numpy.ndarray, shape (B, n)
        """
        return self._on_columns("rhs", t, x, u, x.shape[1])

    def kernel(self):
        """The compiled engine's kernel: the functions named in ``column_kernels`` and ``self._p``.

        Returns
        -------
        ctrl_analysis.engine.kernels.BlockKernel
        """
        from .kernels import BlockKernel

        return BlockKernel(params=self._p, **self._column_fns())
