"""Kernels of the compiled layer for many small matrices side by side (numba, cached on
disk): the interval matrices of a collocated cycle stored ``(m, w, N)``, the ``N``
intervals along the last axis, so that every operation of an elimination or a solve runs
over all intervals in the innermost loop (contiguous: vectorized), where one interval
after the other works on rows of a few elements. :func:`side_lu` and :func:`side_solve`
(dense, partial pivoting in every interval), :func:`side_band_solve` (with LAPACK's band
LU of every interval).

Called by the loops of ``_jit`` only, which records the hash of this file
(``_jit.KERNEL_SOURCES``, checked by a test): numba's disk cache notices edits of a
function's own file only.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: the compiled functions: nopython, cached on disk, releasing the GIL
jit = njit(cache=True, nogil=True)


@jit
def side_lu(a, m, piv) -> bool:
    """The LU with partial pivoting of every ``a[:m, :m, i]`` in place, its row operations
    applied to the columns ``a[:, m:, i]``, which then hold ``A_i^-1 a[:, m:, i]``.

    ``a``: ``(m, w, N)``, the ``N`` matrices side by side, so that every operation runs
    over the intervals in the innermost loop (contiguous: vectorized), where a loop over
    the intervals would work on rows of a few elements; ``piv``: ``(m, N)`` int32, row
    ``j`` was swapped with ``piv[j, i]`` at step ``j`` (the rows of ``L`` too, as LAPACK
    does). False when a pivot is exactly zero."""
    f = np.empty(a.shape[2])
    for j in range(m):
        if not _side_pivot(a, j, m, piv):
            return False
        aj = a[j]
        for i in range(f.size):
            f[i] = 1.0 / aj[j, i]
        for r in range(j + 1, m):
            ar = a[r]
            mult = ar[j]
            for i in range(f.size):
                mult[i] *= f[i]
            for c in range(j + 1, a.shape[1]):
                x, y = ar[c], aj[c]
                for i in range(f.size):
                    x[i] -= mult[i] * y[i]
    for r in range(m - 1, -1, -1):              # U^-1 on the columns beyond m
        ar = a[r]
        for c2 in range(r + 1, m):
            u, below = ar[c2], a[c2]
            for c in range(m, a.shape[1]):
                x, y = ar[c], below[c]
                for i in range(f.size):
                    x[i] -= u[i] * y[i]
        for c in range(m, a.shape[1]):
            x, d = ar[c], ar[r]
            for i in range(f.size):
                x[i] /= d[i]
    return True


@jit
def _side_pivot(a, j, m, piv) -> bool:
    """Step ``j`` of :func:`side_lu`'s pivoting: in every matrix the row of the largest
    ``|a[r, j]|``, ``r >= j``, swapped with row ``j`` (all columns); False if it is zero."""
    N = a.shape[2]
    big, p = np.abs(a[j, j]), np.full(N, j, np.int32)
    for r in range(j + 1, m):
        col = a[r, j]
        for i in range(N):
            if abs(col[i]) > big[i]:
                big[i], p[i] = abs(col[i]), r
    aj = a[j]
    for i in range(N):
        if big[i] == 0.0:
            return False
        piv[j, i] = p[i]
        if p[i] != j:
            ap = a[p[i]]
            for c in range(a.shape[1]):
                aj[c, i], ap[c, i] = ap[c, i], aj[c, i]
    return True


@jit
def side_solve(a, piv, b) -> None:
    """``b_i <- A_i^-1 b_i`` for every ``i`` with the factors of :func:`side_lu` (``a``:
    ``(m, w, N)``, its first ``m`` columns); ``b``: ``(N, m, r)``, C-ordered."""
    m, N, r = a.shape[0], a.shape[2], b.shape[2]
    t = np.empty((m, N))
    for c in range(r):
        for j in range(m):
            for i in range(N):
                t[j, i] = b[i, j, c]
        for j in range(m):
            tj = t[j]
            for i in range(N):
                p = piv[j, i]
                if p != j:
                    tj[i], t[p, i] = t[p, i], tj[i]
        for j in range(1, m):
            tj, aj = t[j], a[j]
            for l in range(j):
                x, y = aj[l], t[l]
                for i in range(N):
                    tj[i] -= x[i] * y[i]
        for j in range(m - 1, -1, -1):
            tj, aj = t[j], a[j]
            for l in range(j + 1, m):
                x, y = aj[l], t[l]
                for i in range(N):
                    tj[i] -= x[i] * y[i]
            d = aj[j]
            for i in range(N):
                tj[i] /= d[i]
        for j in range(m):
            for i in range(N):
                b[i, j, c] = t[j, i]


@jit
def side_band_solve(ab, piv, b, order, kl, ku) -> None:
    """:func:`band_solve` of every interval at once: ``b_i <- A_i^-1 b_i`` with LAPACK's
    band LU of every ``A_i[order][:, order]`` side by side (``ab``: ``(m, 2 kl + ku + 1,
    N)``, ``ab[:, :, i]`` the storage of :func:`band_solve`; ``piv``: ``(m, N)``,
    1-based); ``b``: ``(N, m, r)`` in the original order, C-ordered."""
    m, N, d = ab.shape[0], ab.shape[2], kl + ku
    t = np.empty((m, N))
    for c in range(b.shape[2]):
        for j in range(m):
            for i in range(N):
                t[j, i] = b[i, order[j], c]
        for j in range(m - 1):                   # L: the interchanges and multipliers
            tj = t[j]
            for i in range(N):
                p = piv[j, i] - 1
                if p != j:
                    tj[i], t[p, i] = t[p, i], tj[i]
            for s in range(1, min(kl, m - 1 - j) + 1):
                x, f = t[j + s], ab[j, d + s]
                for i in range(N):
                    x[i] -= f[i] * tj[i]
        for r in range(m - 1, -1, -1):           # U: kl + ku super-diagonals
            tr = t[r]
            for j in range(r + 1, min(m, r + d + 1)):
                f, y = ab[j, d + r - j], t[j]
                for i in range(N):
                    tr[i] -= f[i] * y[i]
            u = ab[r, d]
            for i in range(N):
                tr[i] /= u[i]
        for j in range(m):
            for i in range(N):
                b[i, order[j], c] = t[j, i]
