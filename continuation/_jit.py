"""The compiled layer: numba functions, cached on disk (``cache=True``), for the loops over
the many small dense blocks of the condensed collocation solver (``_condensed``), where
a Python loop over LAPACK calls costs more than their arithmetic. Every compiled
function that calls another one lives in this module: numba's cache is invalidated by
edits of a function's own file only (leaves may live elsewhere: ``_lazyjit``). Imported
at first use, so that ``import continuation`` does not import numba.

Dense kernels, for C-ordered arrays: :func:`lu_factor` / :func:`lu_solve`,
:func:`qr_eliminate` (the elimination of one unknown block from a pair of equations)
and :func:`gemm`; blocks of at most ``SMALL`` rows by plain loops (no per-call
overhead), larger ones by LAPACK and BLAS (``_lapack``), 2-3x faster there.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._lapack import dgeqrf, dgetrf, dgetrs, dormqr, dtrsm
from ._lazyjit import SMALL

#: the compiled functions: nopython, cached on disk, releasing the GIL
jit = njit(cache=True, nogil=True)


@jit
def lu_factor(a, piv) -> bool:
    """``a = P L U`` (partial pivoting) in place, for :func:`lu_solve`; ``a``: square,
    C-ordered; ``piv``: int32 of its size. False when a pivot is exactly zero."""
    m = a.shape[0]
    if m > SMALL:                        # a C-ordered a is A^T in Fortran's eyes
        ints = np.array([m, 0], np.int32)
        dgetrf(ints.ctypes, ints.ctypes, a.ctypes, ints.ctypes, piv.ctypes,
               ints[1:].ctypes)
        return ints[1] == 0
    for j in range(m):
        p, big = j, abs(a[j, j])
        for i in range(j + 1, m):
            if abs(a[i, j]) > big:
                p, big = i, abs(a[i, j])
        piv[j] = p
        if p != j:
            for c in range(m):
                a[j, c], a[p, c] = a[p, c], a[j, c]
        if a[j, j] == 0.0:
            return False
        inv = 1.0 / a[j, j]
        for i in range(j + 1, m):
            f = a[i, j] * inv
            a[i, j] = f
            if f != 0.0:
                for c in range(j + 1, m):
                    a[i, c] -= f * a[j, c]
    return True


@jit
def lu_solve(a, piv, b) -> None:
    """``b <- A^-1 b`` in place with the factors of :func:`lu_factor`; ``b``: ``(m, r)``,
    C-ordered."""
    m, r = b.shape
    if m > SMALL:                        # solve with (A^T)^T: dgetrs 'T' on b^T
        bt = np.ascontiguousarray(b.T)
        ints = np.array([m, r, 0], np.int32)
        trans = np.array([ord("T")], np.uint8)
        dgetrs(trans.ctypes, ints.ctypes, ints[1:].ctypes, a.ctypes, ints.ctypes,
               piv.ctypes, bt.ctypes, ints.ctypes, ints[2:].ctypes)
        b[:] = bt.T
        return
    for j in range(m):
        p = piv[j]
        if p != j:
            for c in range(r):
                b[j, c], b[p, c] = b[p, c], b[j, c]
    if r == 1:                           # one column: dot products along rows of a
        for i in range(1, m):
            acc = b[i, 0]
            for j in range(i):
                acc -= a[i, j] * b[j, 0]
            b[i, 0] = acc
        for i in range(m - 1, -1, -1):
            acc = b[i, 0]
            for j in range(i + 1, m):
                acc -= a[i, j] * b[j, 0]
            b[i, 0] = acc / a[i, i]
        return
    for i in range(1, m):                # several: row updates along the rows of b
        for j in range(i):
            f = a[i, j]
            if f != 0.0:
                for c in range(r):
                    b[i, c] -= f * b[j, c]
    for i in range(m - 1, -1, -1):
        for j in range(i + 1, m):
            f = a[i, j]
            if f != 0.0:
                for c in range(r):
                    b[i, c] -= f * b[j, c]
        d = a[i, i]
        for c in range(r):
            b[i, c] /= d


@jit
def qr_eliminate(S, W) -> bool:
    """Eliminate the unknown of the column ``S`` (``p x n``, ``p >= n``) from the rows
    ``[S | W]``: ``S = Q R``, ``W <- Q^T W``, then the top ``n`` rows of ``W`` solved
    with ``R`` (they give the unknown, ``R^-1 Q_top^T W``), the bottom ``p - n`` rows
    are the equations free of it. ``S``, ``W`` C-ordered, overwritten. False when ``R``
    is numerically rank-deficient (``|R_jj| <= n eps max |R_ii|``)."""
    if S.shape[0] > SMALL:
        return _qr_eliminate_lapack(S, W)
    p, n = S.shape
    v, dots = np.empty(p), np.empty(max(n, W.shape[1]))
    for j in range(n):
        norm = np.sqrt(np.sum(S[j:, j] ** 2))
        if norm == 0.0:
            continue                     # a zero column: R_jj = 0, refused below
        alpha = -norm if S[j, j] >= 0.0 else norm
        v[j:] = S[j:, j]
        v[j] -= alpha
        beta = 1.0 / (norm * (norm + abs(S[j, j])))          # 2 / |v|^2
        _reflect(S, v, j, j, n, beta, dots)
        _reflect(W, v, j, 0, W.shape[1], beta, dots)
        S[j, j] = alpha
    if not _full_rank(S, n):
        return False
    for j in range(n - 1, -1, -1):       # top rows <- R^-1 top rows
        W[j] /= S[j, j]
        for i in range(j):
            if S[i, j] != 0.0:
                W[i] -= S[i, j] * W[j]
    return True


@jit
def _qr_eliminate_lapack(S, W) -> bool:
    """:func:`qr_eliminate` by ``dgeqrf``, ``dormqr`` and ``dtrsm`` (Fortran copies)."""
    (p, n), w = S.shape, W.shape[1]
    Sf, Wf = np.asfortranarray(S), np.asfortranarray(W)
    tau = np.empty(n)
    lwork = 64 * max(n, w, 1)
    work = np.empty(lwork)
    ints = np.array([p, n, w, lwork, 0], np.int32)
    dgeqrf(ints.ctypes, ints[1:].ctypes, Sf.ctypes, ints.ctypes, tau.ctypes, work.ctypes,
           ints[3:].ctypes, ints[4:].ctypes)
    chars = np.array([ord("L"), ord("T"), ord("U"), ord("N")], np.uint8)
    dormqr(chars.ctypes, chars[1:].ctypes, ints.ctypes, ints[2:].ctypes, ints[1:].ctypes,
           Sf.ctypes, ints.ctypes, tau.ctypes, Wf.ctypes, ints.ctypes, work.ctypes,
           ints[3:].ctypes, ints[4:].ctypes)
    if not _full_rank(Sf, n):
        return False
    one = np.ones(1)
    dtrsm(chars.ctypes, chars[2:].ctypes, chars[3:].ctypes, chars[3:].ctypes,
          ints[1:].ctypes, ints[2:].ctypes, one.ctypes, Sf.ctypes, ints.ctypes, Wf.ctypes,
          ints.ctypes)
    S[:] = Sf
    W[:] = Wf
    return True


@jit
def _reflect(A, v, j, c0, c1, beta, dots) -> None:
    """``A[j:, c0:c1] <- (I - beta v v^T) A[j:, c0:c1]`` with ``v`` in ``v[j:]``."""
    p = A.shape[0]
    for c in range(c0, c1):
        dots[c] = 0.0
    for i in range(j, p):
        vi = v[i]
        for c in range(c0, c1):
            dots[c] += vi * A[i, c]
    for i in range(j, p):
        f = beta * v[i]
        for c in range(c0, c1):
            A[i, c] -= f * dots[c]


@jit
def _full_rank(R, n) -> bool:
    """Whether the upper triangle of ``R[:n, :n]`` has ``|R_jj| > n eps max |R_ii|``."""
    d = np.abs(np.diag(R[:n, :n]))
    return np.isfinite(d.max()) and d.min() > n * 2.220446049250313e-16 * d.max()


@jit
def gemm(C, A, B, alpha) -> None:
    """``C += alpha A B`` by loops (no allocation, any strides): for the products of the
    structured solves, where one dimension is a few border rows or right-hand sides."""
    m, q = A.shape
    r = B.shape[1]
    if r < 8:                            # few columns: dot products along rows of A
        for i in range(m):
            for j in range(r):
                acc = 0.0
                for l in range(q):
                    acc += A[i, l] * B[l, j]
                C[i, j] += alpha * acc
        return
    for i in range(m):
        for l in range(q):
            f = alpha * A[i, l]
            if f != 0.0:
                for j in range(r):
                    C[i, j] += f * B[l, j]


# ---- the condensed solver of collocated cycles (``_condensed``) ---------------------------
@jit
def interval_factors(blocks, extra):
    """``(lu, piv, Z, ok)``: the LU of every ``M_i = blocks[i, :, n:]`` and
    ``Z_i = M_i^-1 [blocks[i, :, :n], extra[i]]``; ok False if an ``M_i`` is singular."""
    ntst, m, cols = blocks.shape
    n, k = cols - m, extra.shape[2]
    lu, piv = np.empty((ntst, m, m)), np.zeros((ntst, m), np.int32)
    Z = np.empty((ntst, m, n + k))
    for i in range(ntst):
        lu[i] = blocks[i, :, n:]
        if not lu_factor(lu[i], piv[i]):
            return lu, piv, Z, False
        Z[i, :, :n], Z[i, :, n:] = blocks[i, :, :n], extra[i]
        lu_solve(lu[i], piv[i], Z[i])
    return lu, piv, Z, True


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
            if ident[2 * j] and _scaled_growth(A[2 * j + 1], A[2 * j], work) <= UNIT_GROWTH:
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
def _scaled_growth(a1, a0, work) -> float:
    """An upper bound of the Perron root of ``B = |a1| |a0|`` (Collatz-Wielandt,
    ``max_i (B x)_i / x_i`` after power steps from ``x = 1``): ``|B|_inf`` in a diagonal
    scaling, which judges badly scaled states (modal displacements, velocities) fairly.
    Loops on ``work`` (``3 x n``): no allocation, no BLAS call (both cost more here)."""
    n, (x, t, y), bound = a0.shape[0], work, np.inf
    x[:] = 1.0
    for _ in range(6):
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
def condensed_solve(lu, piv, Z, border_w, schedule, Qb, H, Zt, shares, flu, fpiv, b):
    """``x`` with ``A x = b`` (``b``: ``(N + k, r)``) from the factors of
    :class:`CondensedLU`."""
    ntst, m = lu.shape[0], lu.shape[1]
    n = Z.shape[2] - border_w.shape[1]
    p, N, r = m - n, ntst * m, b.shape[1]
    z = b[:N].copy().reshape(ntst, m, r)
    s = b[N:].copy()
    for i in range(ntst):
        lu_solve(lu[i], piv[i], z[i])                # M_i^-1 r_i
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
