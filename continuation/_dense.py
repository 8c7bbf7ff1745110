"""Dense kernels of the compiled layer (numba, cached on disk), for C-ordered arrays:
:func:`lu_factor` / :func:`lu_solve`, :func:`qr_eliminate` (the elimination of one
unknown block from a pair of equations), :func:`gemm`, :func:`band_solve` (with
LAPACK's band LU), :func:`kinematic_factor` / :func:`kinematic_solve` (an LU with the
kinematic rows eliminated by block). Blocks of at most ``SMALL`` rows by plain loops
(no per-call overhead), larger ones by LAPACK and BLAS (``_lapack``), 2-3x faster.

They are called by the loops of ``_jit`` only. numba's disk cache notices edits of a
function's own file only, so ``_jit`` records the hash of this file
(``_jit.KERNEL_SOURCES``, checked by a test): an edit here must update its line, which
recompiles the callers.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._lapack import dgemm, dgeqrf, dgetrf, dgetrs, dormqr, dtrsm
from ._lazyjit import SCALE_TOL, SMALL

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
    if r == 1:
        _substitute_column(a, b)
    else:
        _substitute_rows(a, b)


@jit
def _substitute_column(a, b) -> None:
    """``b <- U^-1 L^-1 b`` for one column: dot products along the rows of ``a``."""
    m = a.shape[0]
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


@jit
def _substitute_rows(a, b) -> None:
    """The same for several columns: updates of whole rows of ``b`` (contiguous)."""
    m, r = b.shape
    for i in range(1, m):
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


#: products whose every dimension is at least this go to BLAS (``dgemm``), where its
#: blocked kernels outrun the loops by more than the call costs
GEMM_BLAS = 16


@jit
def gemm(C, A, B, alpha) -> None:
    """``C += alpha A B``, by loops (no allocation, any strides) for the products of the
    structured solves where one dimension is a few border rows or right-hand sides, by
    BLAS where every dimension is at least :data:`GEMM_BLAS` and the rows are contiguous
    (the products of transfer maps in the chain's reduction)."""
    m, q = A.shape
    r = B.shape[1]
    if min(m, q, r) >= GEMM_BLAS and A.strides[1] == B.strides[1] == C.strides[1] == 8:
        _dgemm(C, A, B, alpha)
        return
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


@jit
def _dgemm(C, A, B, alpha) -> None:
    """:func:`gemm` by BLAS: the C-ordered rows are Fortran's columns, so ``C^T += alpha
    B^T A^T``, each array with its row stride as leading dimension."""
    ints = np.array([B.shape[1], A.shape[0], A.shape[1], B.strides[0] // 8,
                     A.strides[0] // 8, C.strides[0] // 8], np.int32)
    trans, scalars = np.array([ord("N")], np.uint8), np.array([alpha, 1.0])
    dgemm(trans.ctypes, trans.ctypes, ints.ctypes, ints[1:].ctypes, ints[2:].ctypes,
          scalars.ctypes, B.ctypes, ints[3:].ctypes, A.ctypes, ints[4:].ctypes,
          scalars[1:].ctypes, C.ctypes, ints[5:].ctypes)


@jit
def band_solve(ab, piv, b, kl, ku) -> None:
    """``b <- A^-1 b`` in place (``b``: ``(m, r)``, C-ordered) with LAPACK's band LU of
    ``A`` (``dgbtrf``; ``ab``: its storage transposed, ``piv`` 1-based), as ``dgbtrs``
    does but with whole rows of ``b`` at a time."""
    m, r = b.shape
    if r == 1:
        _band_solve_column(ab, piv, b[:, 0], kl, ku)
        return
    d = kl + ku                                  # the diagonal's place in a column
    for j in range(m - 1):                       # L: the interchanges and multipliers
        p = piv[j] - 1
        if p != j:
            for c in range(r):
                b[j, c], b[p, c] = b[p, c], b[j, c]
        for t in range(1, min(kl, m - 1 - j) + 1):
            f = ab[j, d + t]
            if f != 0.0:
                for c in range(r):
                    b[j + t, c] -= f * b[j, c]
    for i in range(m - 1, -1, -1):               # U: kl + ku super-diagonals
        for j in range(i + 1, min(m, i + d + 1)):
            f = ab[j, d + i - j]
            if f != 0.0:
                for c in range(r):
                    b[i, c] -= f * b[j, c]
        u = ab[i, d]
        for c in range(r):
            b[i, c] /= u


@jit
def _band_solve_column(ab, piv, x, kl, ku) -> None:
    """:func:`band_solve` for one right-hand side ``x`` (a vector)."""
    m, d = x.size, kl + ku
    for j in range(m - 1):
        p = piv[j] - 1
        if p != j:
            x[j], x[p] = x[p], x[j]
        xj = x[j]
        for t in range(1, min(kl, m - 1 - j) + 1):
            x[j + t] -= ab[j, d + t] * xj
    for i in range(m - 1, -1, -1):
        acc = x[i]
        for j in range(i + 1, min(m, i + d + 1)):
            acc -= ab[j, d + i - j] * x[j]
        x[i] = acc / ab[i, d]


@jit
def kinematic_factor(a, lu, piv, order, nq, D) -> bool:
    """Block LU of an interval matrix ``a`` (``m x m``: row ``k n + s`` the point ``k``
    and state ``s``, column ``l n + s`` the node ``l + 1``) whose rows of the positions
    ``pos = order[:nq]`` are kinematic: ``c_j D1`` (``D1 = D[0]``, the derivative part,
    ``NCOL x NCOL``; ``c_j`` a scale) in the position's own columns, anything ``V_j`` in
    those of its velocity ``vel = order[nq:2 nq]``, zero elsewhere (checked; False if not
    met, or if the Schur complement is singular). Then ``x_q = D1^-1 b_q / c_j - W_j
    x_vel``, ``W_j = D1^-1 V_j / c_j``, and the other states ``order[2 nq:n + nq]`` (the
    velocities at ``order[n + nq:]`` among them) solve ``S x_s = b_s - A_sq x_q(b)``: an
    LU of ``(n - nq) NCOL`` rows, not ``n NCOL``. ``lu`` (``m x m``, contiguous) holds
    ``S`` (factorized), ``A_sq``, ``W``, ``D1^-1``, ``1 / c``; ``piv`` the pivots of S."""
    n, ncol = order.size - 2 * nq, D.shape[1]
    S, Asq, W, Dinv, inv_c = _kinematic_parts(lu, n, nq, ncol)
    ms, ns, Dinv[:] = S.shape[0], n - nq, D[1]
    for j in range(nq):
        inv_c[j] = D[0, 0, 0] / a[order[j], order[j]]
        if not _kinematic_rows(a, order[j], order[nq + j], n, D[0], W[j]):
            return False
        V = W[j].copy()
        W[j] = 0.0
        gemm(W[j], D[1], V, inv_c[j])
    for r in range(ms):                          # S and A_sq, in the order (node, state)
        row, out, left = a[(r // ns) * n + order[2 * nq + r % ns]], S[r], Asq[r]
        for l in range(ncol):
            for t in range(ns):
                out[l * ns + t] = row[l * n + order[2 * nq + t]]
            for j in range(nq):
                left[j * ncol + l] = row[l * n + order[j]]
        for j in range(nq):                      # S[:, (l, vel_j)] -= A_sq[:, (j, :)] W_j
            v = order[n + nq + j]
            for l2 in range(ncol):
                f = left[j * ncol + l2]
                for l in range(ncol):
                    out[l * ns + v] -= f * W[j, l2, l]
    return lu_factor(S, piv[:ms])


@jit
def kinematic_solve(lu, piv, b, order, nq) -> None:
    """``b <- A^-1 b`` in place (``b``: ``(m, r)``, C-ordered) with the factors of
    :func:`kinematic_factor`."""
    n, r = order.size - 2 * nq, b.shape[1]
    ncol, ns = b.shape[0] // n, n - nq
    S, Asq, W, Dinv, inv_c = _kinematic_parts(lu, n, nq, ncol)
    xq, xs = np.zeros((ncol * nq, r)), np.empty((ncol * ns, r))
    for t in range(ncol * ns):                   # (element loops: no view per row)
        row = (t // ns) * n + order[2 * nq + t % ns]
        for c in range(r):
            xs[t, c] = b[row, c]
    for j in range(nq):                          # x_q = D1^-1 b_q / c, position by position
        for l in range(ncol):
            for k in range(ncol):
                f = Dinv[l, k] * inv_c[j]
                for c in range(r):
                    xq[j * ncol + l, c] += f * b[k * n + order[j], c]
    gemm(xs, Asq, xq, -1.0)
    lu_solve(S, piv[:ncol * ns], xs)
    for j in range(nq):                          # x_q -= W_j x_vel
        for l in range(ncol):
            for l2 in range(ncol):
                f, v = W[j, l, l2], l2 * ns + order[n + nq + j]
                for c in range(r):
                    xq[j * ncol + l, c] -= f * xs[v, c]
    for t in range(ncol * ns):
        row = (t // ns) * n + order[2 * nq + t % ns]
        for c in range(r):
            b[row, c] = xs[t, c]
    for t in range(ncol * nq):
        row = (t % ncol) * n + order[t // ncol]
        for c in range(r):
            b[row, c] = xq[t, c]


@jit
def _kinematic_parts(lu, n, nq, ncol):
    """``(S, A_sq, W, D1^-1, 1 / c)`` of :func:`kinematic_factor`, views of the
    contiguous ``lu`` one after the other (``ms m + (nq + 1) NCOL^2 + nq <= m^2``
    entries, ``ms = (n - nq) NCOL``, for ``n >= 3``)."""
    flat, ms, mq = lu.reshape(-1), (n - nq) * ncol, nq * ncol
    s, q, w, d = ms * ms, ms * mq, nq * ncol * ncol, ncol * ncol
    return (flat[:s].reshape(ms, ms), flat[s:s + q].reshape(ms, mq),
            flat[s + q:s + q + w].reshape(nq, ncol, ncol),
            flat[s + q + w:s + q + w + d].reshape(ncol, ncol),
            flat[s + q + w + d:s + q + w + d + nq])


@jit
def _kinematic_rows(a, p, v, n, D1, V) -> bool:
    """Whether the rows ``k n + p`` of ``a`` read ``c D1`` in the columns of state ``p``
    (``c = a[p, p] / D1[0, 0]``, to :data:`SCALE_TOL`) and are zero outside those of
    state ``v``, whose entries go to ``V``."""
    ncol, c = D1.shape[0], a[p, p] / D1[0, 0]
    if c == 0.0 or not np.isfinite(c):
        return False
    for k in range(ncol):
        row = a[k * n + p]
        for l in range(ncol):
            for s in range(n):
                x, own = row[l * n + s], c * D1[k, l]
                if s == v:
                    V[k, l] = x
                elif s == p and abs(x - own) > SCALE_TOL * abs(own):
                    return False        # not c D1 on the position's own columns
                elif s != p and x != 0.0:
                    return False        # a third state
    return True
