"""The compiled layer: numba functions, cached on disk (``cache=True``), for the loops over
the many small dense blocks of the condensed collocation solver (``_condensed``), where
a Python loop over LAPACK calls costs more than their arithmetic: the interval LUs and
maps (dense, banded, or with kinematic rows eliminated), the pairwise reduction of the
mesh-point chain and the solves.
Every compiled function that calls another one lives in this module, on the kernels
of ``_dense`` and ``_side``: numba's cache is invalidated by edits of a function's own
file only, hence :data:`KERNEL_SOURCES` (leaves may live elsewhere: ``_lazyjit``).
Imported at first use, so that ``import continuation`` does not import numba.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._dense import (band_solve, gemm, kinematic_factor, kinematic_solve, lu_factor,
                     lu_solve, qr_eliminate)
from ._lapack import dgbtrf
from ._lazyjit import KINEMATIC, SIDE_BY_SIDE
from ._side import side_band_solve, side_lu, side_solve

#: the first 16 hex digits of the SHA-256 of the kernels' files that the functions here
#: were compiled against; an edit of one of them must update its line (a test checks),
#: so that numba recompiles the callers of the edited kernels
KERNEL_SOURCES = {
    "_dense.py": "feaca131e532c890",
    "_side.py": "f211593479f5059a",
}

#: the compiled functions: nopython, cached on disk, releasing the GIL
jit = njit(cache=True, nogil=True)


# ---- the condensed solver of collocated cycles (``_condensed``) ---------------------------
@jit
def interval_factors(blocks, extra, order, nq, D):
    """``(lu, piv, Z, ok)``: the LU of every ``M_i = blocks[i, :, n:]`` and
    ``Z_i = M_i^-1 [blocks[i, :, :n], extra[i]]``; ok False if an ``M_i`` is singular.
    With ``nq`` kinematic rows (``order``, ``D``: :func:`_dense.kinematic_factor`) their
    block LU, ok False also where an ``M_i`` lacks that structure."""
    ntst, m, cols = blocks.shape
    n, k = cols - m, extra.shape[2]
    lu, piv = np.empty((ntst, m, m)), np.zeros((ntst, m), np.int32)
    Z = np.empty((ntst, m, n + k))
    for i in range(ntst):
        if nq:
            ok = kinematic_factor(blocks[i, :, n:], lu[i], piv[i], order, nq, D)
        else:
            lu[i] = blocks[i, :, n:]
            ok = lu_factor(lu[i], piv[i])
        if not ok:
            return lu, piv, Z, False
        Z[i, :, :n], Z[i, :, n:] = blocks[i, :, :n], extra[i]
        if nq:
            kinematic_solve(lu[i], piv[i], Z[i], order, nq)
        else:
            lu_solve(lu[i], piv[i], Z[i])
    return lu, piv, Z, True


@jit
def band_interval_factors(ab, left, extra, order, kl, ku):
    """:func:`interval_factors` for banded ``M_i``, given in LAPACK's band storage by
    :func:`add_band_blocks` (``ab``: ``M_i[order][:, order]``, whose every entry outside
    ``kl`` sub- and ``ku`` super-diagonals is zero; factorized in place, each
    ``(m, 2 kl + ku + 1)``, the transposed Fortran array) and ``left`` (``B_i^L``, rows
    in ``order``); ``Z_i`` in the original order of the nodes. The factors are returned
    side by side, ``(m, 2 kl + ku + 1, NTST)`` and the pivots ``(m, NTST)``, for the
    solves (``_side.side_band_solve``)."""
    ntst, m = ab.shape[0], ab.shape[1]
    n, k = left.shape[2], extra.shape[2]
    piv = np.zeros((ntst, m), np.int32)
    Z = np.empty((ntst, m, n + k))
    rhs = np.empty((m, n + k))
    ints = np.array([m, kl, ku, 2 * kl + ku + 1, 0], np.int32)
    for i in range(ntst):
        dgbtrf(ints.ctypes, ints.ctypes, ints[1:].ctypes, ints[2:].ctypes, ab[i].ctypes,
               ints[3:].ctypes, piv[i].ctypes, ints[4:].ctypes)
        if ints[4] != 0:
            return ab, piv, Z, False
        for r in range(m):
            for c in range(n):
                rhs[r, c] = left[i, r, c]
            for c in range(k):
                rhs[r, n + c] = extra[i, order[r], c]
        band_solve(ab[i], piv[i], rhs, kl, ku)
        for r in range(m):
            for c in range(n + k):
                Z[i, order[r], c] = rhs[r, c]
    side = np.empty((m, ab.shape[2], ntst))
    for r in range(m):                           # reads strided, writes contiguous:
        for q in range(ab.shape[2]):             # 3x faster than the other way
            for i in range(ntst):
                side[r, q, i] = ab[i, r, q]
    return side, np.ascontiguousarray(piv.T), Z, True


@jit
def side_interval_factors(a, extra, n):
    """:func:`interval_factors` for the ``M_i`` side by side (``_side.side_lu``): ``a``,
    ``(m, m + n + k, NTST)``, holds ``[M_i, B_i^L]`` in its first ``m + n`` columns
    (:func:`add_side_blocks`) and gets ``E_i = extra[i]`` in the last ``k``; returns
    ``(a, piv, Z, ok)``, the factors in ``a`` and ``Z_i`` in the layout of
    :func:`interval_factors`."""
    m, w, ntst = a.shape
    for i in range(ntst):
        for r in range(m):
            for c in range(w - m - n):
                a[r, m + n + c, i] = extra[i, r, c]
    piv = np.zeros((m, ntst), np.int32)
    Z = np.empty((ntst, m, w - m))
    if not side_lu(a, m, piv):
        return a, piv, Z, False
    for i in range(ntst):
        for r in range(m):
            for c in range(w - m):
                Z[i, r, c] = a[r, m + c, i]
    return a, piv, Z, True


@jit
def add_side_blocks(a, values, rows, cols, weights, n, ncol):
    """:func:`add_blocks` into the layout of :func:`side_interval_factors`: row ``k n + a``
    of interval ``i`` at ``a[k n + a, :, i]``, column ``l n + b`` at ``(l - 1) n + b`` for
    the nodes ``l >= 1`` (the columns of ``M_i``), at ``m + b`` for node 0 (the intervals
    innermost: contiguous writes)."""
    m, ntst = n * ncol, a.shape[2]
    for k in range(ncol):
        for l in range(ncol + 1):
            c0 = m if l == 0 else (l - 1) * n
            for e in range(values.shape[1]):
                out = a[k * n + rows[e], c0 + cols[e]]
                for i in range(ntst):
                    out[i] += weights[i * ncol + k, l] * values[i * ncol + k, e]


@jit
def add_blocks(blocks, values, rows, cols, weights, n, ncol):
    """``blocks[i, k n + a, l n + b] += weights[i NCOL + k, l] values[i NCOL + k, e]``
    for the entries ``e = (a, b) = (rows[e], cols[e])`` of a matrix at every point."""
    for point in range(values.shape[0]):
        i, k = point // ncol, point % ncol
        block = blocks[i]
        for l in range(ncol + 1):
            w = weights[point, l]
            if w != 0.0:
                for e in range(values.shape[1]):
                    block[k * n + rows[e], l * n + cols[e]] += w * values[point, e]


@jit
def set_dense_blocks(blocks, values, weights, n, ncol):
    """``blocks[i, k n + a, l n + b] = sum_t weights[t][i NCOL + k, l] values[t][i NCOL +
    k, a n + b]`` for the matrices of the terms ``t`` given dense, row by row (``values``,
    ``weights``: tuples): every entry written once, the row kept in cache between terms."""
    for point in range(values[0].shape[0]):
        i, k = point // ncol, point % ncol
        for l in range(ncol + 1):
            for a in range(n):
                row, c = blocks[i, k * n + a], l * n
                w = weights[0][point, l]
                for b in range(n):
                    row[c + b] = w * values[0][point, a * n + b]
                for t in range(1, len(values)):
                    w = weights[t][point, l]
                    if w != 0.0:
                        for b in range(n):
                            row[c + b] += w * values[t][point, a * n + b]


@jit
def add_band_blocks(ab, left, values, rows, cols, weights, rank, ncol, d):
    """:func:`add_blocks` into the layout of :func:`band_interval_factors`: row ``k n + a``
    (point ``k``, state ``a``) at ``rank[a] NCOL + k``, column ``l n + b`` (node
    ``l >= 1``) at ``c = rank[b] NCOL + l - 1``, entry ``(r, c)`` of ``M_i`` at
    ``ab[i, c, d + r - c]`` (``d = kl + ku``); node 0 into ``left[i, r, b]``. The ranks
    of the pattern are looked up once and the entries addressed in the flat arrays (no
    view per point): twice as fast as per interval."""
    ntst, m, w = ab.shape
    n, size = left.shape[2], values.shape[1]
    first, last = np.empty(size, np.int64), np.empty(size, np.int64)
    for e in range(size):
        first[e], last[e] = rank[rows[e]] * ncol, rank[cols[e]] * ncol - 1
    band, start = ab.reshape(-1), left.reshape(-1)
    for point in range(values.shape[0]):
        i, k = point // ncol, point % ncol
        w0, base = weights[point, 0], i * m * w
        for e in range(size):
            v, r = values[point, e], first[e] + k
            if w0 != 0.0:
                start[(i * m + r) * n + cols[e]] += w0 * v
            for l in range(1, ncol + 1):
                c = last[e] + l
                band[base + c * w + d + r - c] += weights[point, l] * v


#: the largest growth ``rho(|a1| |a0|)`` (:func:`_scaled_growth`) of a pair eliminated
#: by its identity pivot (:func:`_unit_eliminate`); a larger one takes the QR
UNIT_GROWTH = 16.0


@jit
def chain_reduce(A, C, G, schedule, unit):
    """``(Qb, H, Zt, AC, G0, ok)`` of :class:`Chain` (``AC = A + C``, ``G0``: the last
    equation); ok False when a pair's column is rank-deficient. ``unit``: every ``C_i``
    is the identity; pairs whose pivot is still one and whose maps are bounded are then
    eliminated by it (:func:`_unit_eliminate`), the others by a QR."""
    n, k = A.shape[1], G.shape[2]
    pairs = A.shape[0] - 1
    Qb, H = np.empty((pairs, n, 2 * n)), np.empty((pairs, n, 2 * n))
    Zt = np.empty((pairs, n, 2 * n + k))
    S, W, work = np.empty((2 * n, n)), np.empty((2 * n, 4 * n + k)), np.empty((3, n))
    ident = np.full(A.shape[0], unit)                 # whether C_i is the identity
    off = 0
    for level in range(schedule.shape[0]):
        q, odd = schedule[level, 0], schedule[level, 1]
        A2, C2, G2 = np.empty((q + odd, n, n)), np.empty((q + odd, n, n)), \
            np.empty((q + odd, n, k))
        ident2 = np.zeros(q + odd, np.bool_)
        for j in range(q):
            i = off + j
            if ident[2 * j] and _scaled_growth(A[2 * j + 1], A[2 * j], work,
                                               UNIT_GROWTH) <= UNIT_GROWTH:
                _unit_eliminate(A[2 * j], A[2 * j + 1], G[2 * j], G[2 * j + 1],
                                Qb[i], H[i], Zt[i], A2[j], G2[j])
                C2[j], ident2[j] = C[2 * j + 1], ident[2 * j + 1]
                continue
            S[:n], S[n:] = C[2 * j], A[2 * j + 1]
            W[:] = 0.0
            W[:, :2 * n] = np.eye(2 * n)
            W[:n, 2 * n:3 * n], W[:n, 4 * n:] = A[2 * j], G[2 * j]              # [a0, 0, g0]
            W[n:, 3 * n:4 * n], W[n:, 4 * n:] = C[2 * j + 1], G[2 * j + 1]      # [0, c1, g1]
            if not qr_eliminate(S, W):
                return Qb, H, Zt, A[0], G[0], False
            Qb[i], H[i], Zt[i] = W[n:, :2 * n], W[:n, :2 * n], W[:n, 2 * n:]
            A2[j], C2[j], G2[j] = W[n:, 2 * n:3 * n], W[n:, 3 * n:4 * n], W[n:, 4 * n:]
        if odd:
            A2[q], C2[q], G2[q], ident2[q] = A[2 * q], C[2 * q], G[2 * q], ident[2 * q]
        A, C, G, ident = A2, C2, G2, ident2
        off += q
    return Qb, H, Zt, A[0] + C[0], G[0].copy(), True


@jit
def _unit_eliminate(a0, a1, g0, g1, Qb, H, Zt, A2, G2) -> None:
    """The pair ``a0 v_0 + v_1 + g0 y = z_0``, ``a1 v_1 + c1 v_2 + g1 y = z_1`` freed of
    ``v_1`` by its identity pivot (a product of transfer maps: multiple shooting over the
    two intervals): ``v_1 = z_0 - a0 v_0 - g0 y`` (``H = [I, 0]``, ``Zt = [a0, 0, g0]``),
    ``-a1 a0 v_0 + c1 v_2 + (g1 - a1 g0) y = z_1 - a1 z_0`` (``Qb = [-a1, I]``). The
    rounding of ``a1 a0`` is at most ``n eps |a1| |a0|``: a few eps of the identity's
    scale where :func:`_scaled_growth` is within ``UNIT_GROWTH``."""
    n = a0.shape[0]
    Qb[:], H[:], Zt[:], A2[:], G2[:] = 0.0, 0.0, 0.0, 0.0, g1
    for d in range(n):
        H[d, d] = Qb[d, n + d] = 1.0
    Qb[:, :n], Zt[:, :n], Zt[:, 2 * n:] = -a1, a0, g0
    gemm(A2, a1, a0, -1.0)
    gemm(G2, a1, g0, -1.0)


@jit
def _scaled_growth(a1, a0, work, enough) -> float:
    """An upper bound of the Perron root of ``B = |a1| |a0|`` (Collatz-Wielandt,
    ``max_i (B x)_i / x_i`` after power steps from ``x = 1``, at most six, stopping once
    it is at most ``enough``): ``|B|_inf`` in a diagonal scaling, which judges badly
    scaled states (modal displacements, velocities) fairly. Loops on ``work``
    (``3 x n``): no allocation, no BLAS call (both cost more here)."""
    n, (x, t, y), bound = a0.shape[0], work, np.inf
    x[:] = 1.0
    for _ in range(6):
        if bound <= enough:
            break
        t[:], y[:] = 0.0, 0.0
        for i in range(n):
            for j in range(n):
                t[i] += abs(a0[i, j]) * x[j]
        for i in range(n):
            for j in range(n):
                y[i] += abs(a1[i, j]) * t[j]
        top, ratio = y.max(), 0.0
        for i in range(n):
            ratio = max(ratio, y[i] / x[i])
            x[i] = y[i] / max(top, 1e-300) + 1e-12
        bound = min(bound, ratio)
    return bound


@jit
def chain_border(Bv, By, schedule, H, Zt, AC, G0):
    """``(shares, lu, piv, ok)`` of :meth:`Chain.bordered`."""
    N, k, n = Bv.shape
    B = np.zeros((N + 1, k, n))                       # point N (= point 0): none yet
    B[:N] = Bv
    shares, Bz = np.zeros((H.shape[0], k, 2 * n)), np.empty((k, 2 * n + k))
    off = 0
    for level in range(schedule.shape[0]):
        q, odd = schedule[level, 0], schedule[level, 1]
        kept = np.empty((q + 1 + odd, k, n))
        for j in range(q + 1):
            kept[j] = B[2 * j]
        if odd:
            kept[q + 1] = B[2 * q + 1]
        for j in range(q):
            Bz[:] = 0.0
            gemm(Bz, B[2 * j + 1], Zt[off + j], 1.0)   # the border rows once mid is gone
            kept[j] -= Bz[:, :n]
            kept[j + 1] -= Bz[:, n:2 * n]
            By -= Bz[:, 2 * n:]
            gemm(shares[off + j], B[2 * j + 1], H[off + j], 1.0)
        B = kept
        off += q
    final = np.empty((n + k, n + k))
    final[:n, :n], final[:n, n:] = AC, G0
    final[n:, :n], final[n:, n:] = B[0] + B[1], By
    piv = np.zeros(n + k, np.int32)
    return shares, final, piv, lu_factor(final, piv)


@jit
def chain_solve(schedule, Qb, H, Zt, shares, flu, fpiv, z, s):
    """``(v, y)`` of :meth:`Chain.solve`; ``s`` is overwritten."""
    n, r = z.shape[1], z.shape[2]
    ZP = np.empty((Qb.shape[0], 2 * n, r))           # the stacked right-hand sides
    off = 0
    for level in range(schedule.shape[0]):            # forward: the new right-hand sides
        q, odd = schedule[level, 0], schedule[level, 1]
        new = np.zeros((q + odd, n, r))
        for j in range(q):
            ZP[off + j, :n], ZP[off + j, n:] = z[2 * j], z[2 * j + 1]
            gemm(s, shares[off + j], ZP[off + j], -1.0)
            gemm(new[j], Qb[off + j], ZP[off + j], 1.0)
        if odd:
            new[q] = z[2 * q]
        z = new
        off += q
    x = np.empty((n + s.shape[0], r))
    x[:n], x[n:] = z[0], s
    lu_solve(flu, fpiv, x)
    y = x[n:].copy()
    vals = np.empty((2, n, r))
    vals[0], vals[1] = x[:n], x[:n]                   # the points v_0 and v_N = v_0
    for level in range(schedule.shape[0] - 1, -1, -1):    # backward: the points
        q, odd = schedule[level, 0], schedule[level, 1]
        off -= q
        out = np.zeros((2 * q + 1 + odd, n, r))
        for j in range(q + 1):
            out[2 * j] = vals[j]
        for j in range(q):
            Zj, mid = Zt[off + j], out[2 * j + 1]
            gemm(mid, H[off + j], ZP[off + j], 1.0)
            gemm(mid, Zj[:, :n], vals[j], -1.0)
            gemm(mid, Zj[:, n:2 * n], vals[j + 1], -1.0)
            gemm(mid, Zj[:, 2 * n:], y, -1.0)
        if odd:
            out[2 * q + 1] = vals[q + 1]
        vals = out
    return vals[:-1].copy(), y


@jit
def condensed_solve(lu, piv, band, Z, border_w, schedule, Qb, H, Zt, shares, flu, fpiv,
                    b):
    """``x`` with ``A x = b`` (``b``: ``(N + k, r)``) from the factors of
    :class:`CondensedLU`; ``band``: ``(order, kl, ku)`` of the interval factors: of
    :func:`band_interval_factors` (``kl >= 0``), :func:`side_interval_factors` (``kl``
    :data:`SIDE_BY_SIDE`) or :func:`interval_factors` (``kl = -1``; :data:`KINEMATIC`
    with kinematic rows, ``ku`` of them)."""
    order, kl, ku = band
    ntst, m = Z.shape[0], Z.shape[1]
    n = Z.shape[2] - border_w.shape[1]
    p, N, r = m - n, ntst * m, b.shape[1]
    z = b[:N].copy().reshape(ntst, m, r)
    s = b[N:].copy()
    if kl == SIDE_BY_SIDE:                                          # every M_i^-1 r_i
        side_solve(lu, piv, z)
    elif kl >= 0:
        side_band_solve(lu, piv, z, order, kl, ku)
    for i in range(ntst):
        if kl == -1:
            lu_solve(lu[i], piv[i], z[i])
        elif kl == KINEMATIC:
            kinematic_solve(lu[i], piv[i], z[i], order, ku)
        gemm(s, border_w[i], z[i, :p], -1.0)
    v, y = chain_solve(schedule, Qb, H, Zt, shares, flu, fpiv,
                        np.ascontiguousarray(z[:, p:]), s)
    x = np.empty((N + y.shape[0], r))
    for i in range(ntst):
        w = x[i * m + n:(i + 1) * m]
        x[i * m:i * m + n] = v[i]
        w[:] = z[i, :p]
        gemm(w, Z[i, :p, :n], v[i], -1.0)
        gemm(w, Z[i, :p, n:], y, -1.0)
    x[N:] = y
    return x
