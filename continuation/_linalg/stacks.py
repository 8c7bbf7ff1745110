"""LU factors of a stack of matrices ``A_i`` by LAPACK (SciPy's ``getrf``/``getrs``, and
``gbtrf``/``gbtrs`` for banded ones), for the solves ``x_i = A_i^-1 b_i`` of every
matrix at once.

NumPy's batched ``linalg.solve`` factorizes at every call and ``linalg.inv`` costs three
times an LU; SciPy's ``lu_factor`` over a stack loops over the matrices in Python too,
with more checks per call. Dense matrices take one ``getrf``/``getrs`` call each. A
C-ordered matrix is the transpose of a Fortran-ordered one: ``getrf`` factorizes
``A_i^T`` in place (no copy) and ``getrs`` solves with its transpose (``trans=1``),
which is ``A_i``. A stack of banded matrices is one banded matrix (:class:`BandStackLU`):
one ``gbtrf`` and one ``gbtrs`` call for the whole stack.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import lapack


class StackLU:
    """``A_i = P_i L_i U_i`` (partial pivoting) of every ``A_i`` of a stack ``(N, m, m)``."""

    def __init__(self, lu: np.ndarray, piv: np.ndarray):
        self.lu, self.piv = lu, piv

    @classmethod
    def of(cls, A: np.ndarray, overwrite: bool = False) -> "StackLU | None":
        """The factors of the stack ``A``; None if an ``A_i`` is singular (a zero pivot).
        ``overwrite``: ``A`` (C-ordered, float) may hold the factors."""
        lu = A if overwrite and A.flags.c_contiguous and A.dtype == np.float64 else \
            np.array(A, dtype=np.float64, order="C")
        piv = np.empty(lu.shape[:2], np.int32)
        for a, p in zip(lu, piv):
            _, p[:], info = lapack.dgetrf(a.T, overwrite_a=True)
            if info != 0:
                return None
        return cls(lu, piv)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """``x_i = A_i^-1 b_i`` for ``b``: ``(N, m, r)``."""
        x = np.empty(b.shape)
        for i, (a, p) in enumerate(zip(self.lu, self.piv)):
            x[i] = lapack.dgetrs(a.T, p, b[i], trans=1)[0]
        return x


class BandStackLU:
    """The LU (partial pivoting) of every banded ``A_i[order][:, order]`` of a stack, ``kl``
    sub- and ``ku`` super-diagonals, given in LAPACK's band storage transposed:
    ``ab[i, c, kl + ku + r - c] = A_i[order][:, order][r, c]`` (``ab``: ``(N, m, 2 kl + ku
    + 1)``, C-ordered; the first ``kl`` entries of each column are room for the fill-in,
    the entries outside ``A_i`` zero); it solves with the ``A_i``.

    The stack is one banded matrix, ``diag(A_0, ..., A_N-1)`` with the same band, and its
    band storage is ``ab`` read as ``(N m, 2 kl + ku + 1)``: one ``gbtrf`` and one
    ``gbtrs`` per call instead of one per matrix. Partial pivoting never leaves a block
    (the rows of the others are exactly zero in its columns), so the factors are those
    of every ``A_i``. Right-hand sides are solved in place in Fortran order, ``(r, N,
    m)`` C-ordered: the ``r`` columns one after the other."""

    def __init__(self, ab: np.ndarray, piv: np.ndarray, kl: int, ku: int, order: np.ndarray):
        self.ab, self.piv, self.kl, self.ku, self.order = ab, piv, kl, ku, order
        self.inverse = np.argsort(order)

    @classmethod
    def of(cls, ab: np.ndarray, kl: int, ku: int, order: np.ndarray) -> "BandStackLU | None":
        """Factorizes ``ab`` in place; None if an ``A_i`` is singular."""
        N, m, width = ab.shape
        _, piv, info = lapack.dgbtrf(ab.reshape(N * m, width).T, kl, ku, overwrite_ab=True)
        return None if info != 0 else cls(ab, piv, kl, ku, order)

    def solve_columns(self, x: np.ndarray) -> np.ndarray:
        """Overwrites ``x`` (``(r, N, m)``, C-ordered, rows in ``order``) with ``x_i =
        (A_i[order][:, order])^-1 x_i``, column by column; returns it."""
        r, N, m = x.shape
        lapack.dgbtrs(self.ab.reshape(N * m, -1).T, self.kl, self.ku, x.reshape(r, N * m).T,
                      self.piv, overwrite_b=True)
        return x

    def solve(self, b: np.ndarray) -> np.ndarray:
        """``x_i = A_i^-1 b_i`` for ``b``: ``(N, m, r)`` (a view of a ``(r, N, m)`` array)."""
        x = self.solve_columns(b.transpose(2, 0, 1).take(self.order, axis=2))
        return x.take(self.inverse, axis=2).transpose(1, 2, 0)
