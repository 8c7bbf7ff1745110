"""Floquet multipliers of a collocated cycle by condensation of the interior unknowns.

The linearized collocation equations of interval ``i`` (``T`` and ``p``
fixed, ``v_{i,l}`` the node perturbations) read
``B_L v_{i,0} + B_R (v_{i,1}, ..., v_{i,NCOL}) = 0`` with ``B = d r_i / d u_i``
the rows of the exact sparse Jacobian of the collocation system (either backend; it contains the ``(D_x M[v]) u'``
terms of a state-dependent mass). Eliminating the interior and right nodes gives the
transfer ``v_{i+1,0} = A_i v_{i,0}``, ``A_i = -(B_R^{-1} B_L)[last n rows]``,
and the monodromy matrix of the discretized variational equation is
``A_{N-1} ... A_0``. Its eigenvalues (the multipliers) are computed without
forming the product (``method='pencil'``) as the finite eigenvalues of the
block-cyclic pencil

    A_i v_i - v_{i+1} = 0  (i < N-1),      A_{N-1} v_{N-1} = mu v_0,

by the QZ algorithm (size ``n NTST``; ``n (NTST - 1)`` infinite eigenvalues
are discarded, ``O((n NTST)^3)``); ``method='product'`` forms the product
(``O(n^3 NTST)``) and loses every multiplier smaller than about ``1e-16`` times the
largest. ``method='schur'`` (:func:`schur_multipliers`) computes a periodic Schur
form of the factors, ``A_i Q_i = Q_{i+1} R_i`` with ``R_i`` upper triangular, by
sequences of QR factorizations (orthogonal iteration on the chain, started from the
product's ordered eigenvectors), and reads each multiplier as the product of the
``R_i``'s diagonal entries (1x1 or 2x2 blocks): a backward error of each factor
of the order of the rounding unit, whatever the spread of the multipliers
(``O(n^3 NTST)`` per sweep, usually one or two sweeps).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.linalg.lapack import dgeqrf as _geqrf, dorgqr as _orgqr

from .._linalg.sparse import PatternCache
from .._linalg.threads import single_threaded
from .._driver.newton import factorize

#: interval systems up to this size are always solved densely (one batched LAPACK
#: solve with one BLAS thread); up to ``DENSE_MAX`` when their blocks are at least
#: ``DENSE_FILL`` full (a modal model couples all n components at every point: dense
#: LAPACK is 20x faster than SuperLU there), larger or sparser ones (a discretized
#: PDE with a banded ``F_x``) by one SuperLU of their block diagonal
DENSE_ALWAYS, DENSE_MAX, DENSE_FILL = 96, 1024, 0.25


def transfer_matrices(J, n: int, ntst: int, ncol: int, full: bool = False) -> np.ndarray:
    """``A_i`` (shape ``(ntst, n, n)``) with ``v_{i+1,0} = A_i v_{i,0}``, from the
    sparse collocation Jacobian ``J`` (rows of interval ``i`` are
    ``i n NCOL .. (i+1) n NCOL``); with ``full`` the ``(ntst, n NCOL, n)`` maps to all
    nodes ``v_{i,1..NCOL}``. Small or well-filled blocks (``DENSE_ALWAYS``,
    ``DENSE_MAX``, ``DENSE_FILL``) are solved by one batched dense solve with one BLAS
    thread (``_linalg.threads``; at n = 82, NCOL = 4, NTST = 20: 0.13 s, against 2.5 s by
    SuperLU per interval), the others by one SuperLU factorization of the block
    diagonal ``diag(B_R)`` (:func:`sparse_transfer_matrices`). Where the blocks' entries
    sit in ``J`` is found once per sparsity pattern (:class:`_Layout`)."""
    J = sp.csc_matrix(J)
    if not J.has_canonical_format:                   # duplicates summed, on a copy
        J = J.copy()
        J.sum_duplicates()
    layout = _Layout.of(J, n, ntst, ncol)
    values = J.data[layout.take]
    if layout.dense:
        m = n * ncol
        B = np.zeros((ntst, m, m + n))
        B.reshape(-1)[layout.rows * (m + n) + layout.local] = values   # no duplicates
        return block_transfer_matrices(B, n, full)
    out = sparse_transfer_matrices(layout, values)
    return out if full else out[:, -n:, :]


def block_transfer_matrices(blocks: np.ndarray, n: int, full: bool = False) -> np.ndarray:
    """The same from the dense interval blocks ``[B_L, B_R]`` (``(ntst, n NCOL, n (NCOL +
    1))``): ``A_i = -(B_R^{-1} B_L)``, one batched LAPACK solve."""
    with single_threaded():
        out = np.linalg.solve(blocks[:, :, n:], -blocks[:, :, :n])
    return out if full else out[:, -n:, :]


def sparse_transfer_matrices(layout: "_Layout", values: np.ndarray) -> np.ndarray:
    """``-(B_R^{-1} B_L)`` of every interval ``(ntst, n NCOL, n)`` from the values of the
    interval blocks' entries (in the order of ``layout``): ``diag(B_R)`` is one sparse
    matrix (its column ordering is computed once per pattern, ``_driver.newton.factorize``), and
    as it is block diagonal, one solve with the stacked ``B_L`` (``N x n``) gives all
    maps (a solve of many columns, ``_driver.newton.LU``)."""
    n, N = layout.n, layout.m * layout.ntst
    right, indptr, indices, left, L_rows, L_cols = layout.sparse
    R = sp.csc_matrix((values[right], indices, indptr), shape=(N, N))
    L = np.zeros((N, n))
    L[L_rows, L_cols] = values[left]
    with single_threaded():
        lu = factorize(R)
        if lu is None:
            raise np.linalg.LinAlgError("singular interval block of the collocation Jacobian")
        return -lu.solve(L).reshape(layout.ntst, layout.m, n)


@dataclass(frozen=True, eq=False)
class _Layout:
    """Where the entries of the interval blocks ``[B_L, B_R]`` (``n NCOL x n (NCOL +
    1)``, the last interval's right node wrapped to the first node) sit in a collocation
    Jacobian of one sparsity pattern: ``J.data[take]`` are their values, in rows ``rows``
    and block columns ``local``; ``fill``: the blocks' nonzero fraction."""

    n: int
    ntst: int
    m: int
    take: np.ndarray
    rows: np.ndarray
    local: np.ndarray
    fill: float

    @classmethod
    def of(cls, J: sp.csc_matrix, n: int, ntst: int, ncol: int) -> "_Layout":
        """The layout of ``J``'s pattern (found among the last few, else computed)."""
        key = (n, ntst, ncol)
        known = _layouts.get(J, key)
        if known is not None:
            return known
        m, N = n * ncol, n * ncol * ntst
        c = np.repeat(np.arange(J.shape[1]), np.diff(J.indptr))
        keep = (J.indices < N) & (c < N)
        local = (c - (J.indices // m) * m) % N             # column within interval r // m
        take = np.flatnonzero(keep & (local < m + n))
        return _layouts.put(J, cls(n, ntst, m, take, J.indices[take], local[take],
                                   take.size / (m * ntst * (m + n))), key)

    @property
    def dense(self) -> bool:
        """Whether the blocks are solved densely (:func:`transfer_matrices`)."""
        return self.m <= DENSE_ALWAYS or (self.m <= DENSE_MAX and self.fill >= DENSE_FILL)

    @cached_property
    def sparse(self) -> tuple:
        """``(right, indptr, indices, left, L_rows, L_cols)``: the CSC pattern of
        ``diag(B_R)``, whose values are ``values[right]`` in that order, and the places
        ``(L_rows, L_cols)`` of ``B_L``'s values ``values[left]`` in the stacked
        ``(N, n)`` matrix."""
        n, m, N = self.n, self.m, self.m * self.ntst
        rows, local = self.rows, self.local
        left, right = np.flatnonzero(local < n), np.flatnonzero(local >= n)
        start = rows[right] - rows[right] % m              # first row (= column) of the block
        order = sp.csc_matrix((np.arange(1.0, right.size + 1),
                               (rows[right], start + local[right] - n)), shape=(N, N))
        return (right[order.data.astype(np.intp) - 1], order.indptr, order.indices, left,
                rows[left], local[left])


#: interval layouts of recent Jacobian patterns
_layouts = PatternCache(kept=4)


def multipliers(A: np.ndarray, method: str = "schur") -> np.ndarray:
    """Eigenvalues of ``A_{N-1} ... A_0``, sorted by decreasing modulus."""
    if method == "product":
        return product_multipliers(monodromy(A))
    if method == "schur":
        return schur_multipliers(A)
    with single_threaded():
        return _by_modulus(_pencil_multipliers(A))


def product_multipliers(mono: np.ndarray) -> np.ndarray:
    """Eigenvalues of the monodromy matrix ``mono``, sorted by decreasing modulus."""
    with single_threaded():
        return _by_modulus(np.linalg.eigvals(mono))


#: sweeps of :func:`schur_multipliers` at most (a sweep is NTST QR factorizations)
SCHUR_SWEEPS = 60
#: off-diagonal blocks of ``Q_0^T Q_N`` below this count as converged (a backward error
#: of this relative size in one factor)
SCHUR_TOL = 1e-12
#: the product's eigenvalues are returned as they are when their moduli span at most this
#: ratio: each is then accurate to about this times the rounding unit relative to its
#: size (times its condition), and the sweeps would only cost time
SCHUR_SPREAD = 1e6
#: multipliers whose moduli lie within this ratio may share a block, read from its
#: formed product (a relative error of about this times the rounding unit)
SCHUR_GROUP = 1e4


def schur_multipliers(A, mono: np.ndarray | None = None) -> np.ndarray:
    """Eigenvalues of ``A_{N-1} ... A_0`` (``A``: ``(N, n, n)``, or a function that
    returns it, called only if the sweeps need it and ``mono`` is given) sorted by
    decreasing modulus, each accurate relative to its own size when the chain is (the
    periodic condition number, not the spread of the multipliers, sets the error).

    The product (``mono``, formed if not given) decides: when the moduli of its
    eigenvalues span at most :data:`SCHUR_SPREAD` they are returned (already accurate
    to about ``1e-10`` relative). Otherwise a periodic Schur form by orthogonal
    iteration on the chain: from an orthonormal ``Q_0``, one sweep factors
    ``A_i Q_i = Q_{i+1} R_i`` (``i = 0 .. N-1``, QR), so ``Phi Q_0 = Q_N R_{N-1} ... R_0``;
    where ``S = Q_0^T Q_N`` is block diagonal (below :data:`SCHUR_TOL` off its blocks: a
    converged basis), the multipliers are the eigenvalues of
    ``S_bb R_{N-1,bb} ... R_{0,bb}`` for each diagonal block ``b`` (1x1: a product of
    scalars, exact to rounding per factor; a larger block, as a complex pair or
    multipliers of nearly equal modulus, from its formed product). The sweeps stop when
    every block's moduli lie within :data:`SCHUR_GROUP` of each other, each starting from
    the last ``Q_N``. ``Q_0`` is the orthonormalized real basis of the product's
    eigenvectors by decreasing modulus; the contracting ones converge at the ratios of
    adjacent moduli per sweep (1 to 16 sweeps in the tests). After :data:`SCHUR_SWEEPS`
    the last blocks are read as they are, with a warning (moduli a few per cent apart)."""
    mono = monodromy(A() if callable(A) else A) if mono is None else mono
    if mono.shape[0] == 0:
        return np.zeros(0, dtype=complex)
    with single_threaded():
        mu, V = np.linalg.eig(mono)
        if _spread(mu) <= SCHUR_SPREAD:
            return _by_modulus(mu)
        A = np.asarray(A() if callable(A) else A, dtype=float)
        Q0 = _ordered_basis(mu, V)
        for _ in range(SCHUR_SWEEPS):
            Q, R = _sweep(A, Q0)
            S = Q0.T @ Q
            mu = [_block_eigenvalues(S, R, b) for b in _diagonal_blocks(S)]
            if all(m.size == 1 or _spread(m) <= SCHUR_GROUP for m in mu):
                break
            Q0 = Q
        else:
            _warn_unseparated(np.concatenate(mu))
        return _by_modulus(np.concatenate(mu))


def _warn_unseparated(mu: np.ndarray) -> None:
    warnings.warn(f"Floquet multipliers: the periodic Schur sweeps did not separate the "
                  f"multipliers in {SCHUR_SWEEPS} sweeps (moduli {_spread(mu):.1e} apart, "
                  "some nearly equal); those below about 1e-16 times the largest may be "
                  "inaccurate")


def _sweep(A: np.ndarray, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(Q_N, R)`` with ``A_i Q_i = Q_{i+1} R_i`` from ``Q_0 = Q`` (LAPACK's QR directly:
    ``np.linalg.qr`` costs twice as much at n = 2)."""
    R = np.empty_like(A)
    for i in range(A.shape[0]):
        qr, tau, _, _ = _geqrf(A[i] @ Q)
        R[i] = np.triu(qr)
        Q = _orgqr(qr, tau)[0]
    return Q, R


def _ordered_basis(mu: np.ndarray, V: np.ndarray) -> np.ndarray:
    """An orthonormal basis whose leading ``k`` columns span the product's eigenvectors
    ``V`` of the ``k`` largest moduli (real and imaginary parts of a complex pair)."""
    cols = []
    for k in np.argsort(-np.abs(mu), kind="stable"):
        if mu[k].imag == 0:
            cols.append(V[:, k].real)
        elif mu[k].imag > 0:
            cols += [V[:, k].real, V[:, k].imag]
    cols += list(np.eye(V.shape[0]))                     # completes a defective basis
    return np.linalg.qr(np.column_stack(cols))[0]


def _diagonal_blocks(S: np.ndarray) -> list:
    """The finest partition of ``0 .. n-1`` into consecutive blocks such that ``S`` is
    block upper triangular up to :data:`SCHUR_TOL` (``|S[k:, :k]| <= tol`` at each
    split ``k``)."""
    n = S.shape[0]
    low = np.maximum.accumulate(np.abs(np.tril(S, -1)), axis=1)      # max over cols <= j
    low = np.maximum.accumulate(low[::-1], axis=0)[::-1]             # and rows >= i
    k = np.arange(1, n)
    cut = [0, *k[low[k, k - 1] <= SCHUR_TOL], n]
    return [slice(a, b) for a, b in zip(cut[:-1], cut[1:])]


def _block_product(S: np.ndarray, R: np.ndarray, b: slice) -> np.ndarray:
    P = S[b, b]
    for Ri in R[::-1]:
        P = P @ Ri[b, b]
    return P


def _spread(mu: np.ndarray) -> float:
    """``max |mu| / min |mu|`` (inf with a zero)."""
    a = np.abs(mu)
    return float(a.max() / a.min()) if a.min() > 0 else np.inf


def _block_eigenvalues(S: np.ndarray, R: np.ndarray, b: slice) -> np.ndarray:
    if b.stop - b.start == 1:               # sign and log-modulus: no under/overflow
        d = np.concatenate([[S[b.start, b.start]], R[:, b.start, b.start]])
        if np.any(d == 0):
            return np.zeros(1, dtype=complex)
        return np.array([np.prod(np.sign(d)) * np.exp(np.sum(np.log(np.abs(d))))],
                        dtype=complex)
    return np.linalg.eigvals(_block_product(S, R, b)).astype(complex)


def section_multipliers(mono: np.ndarray, f: np.ndarray) -> np.ndarray:
    """The ``n - 1`` multipliers of the Poincare map on the hyperplane through ``u(0)``
    normal to the flow ``f = u'(0)``, sorted by decreasing modulus: the eigenvalues of
    ``Q^T Phi Q``, ``Phi = A_{N-1} ... A_0`` (``mono``) and ``Q`` an orthonormal basis
    of ``f^perp``.

    The map's Jacobian is ``(I - f f^T / |f|^2) Phi`` on the section; as ``Phi f = f``,
    its eigenvalues are the non-trivial multipliers. They are not coupled to the trivial
    one: at a fold of cycles ``Phi`` has a Jordan block at +1, and a discretization
    error ``e`` of ``Phi f = f`` splits that pair by ``O(sqrt e)``, while the section's
    multiplier at +1 moves by ``O(e)``. Formed by the product (strongly contracting
    multipliers are only accurate relative to the largest)."""
    f = np.asarray(f, dtype=float)
    if f.shape != (mono.shape[0],) or not np.linalg.norm(f) > 0:
        raise ValueError(f"f must be a nonzero flow direction of length {mono.shape[0]}")
    with single_threaded():
        Q = np.linalg.qr(np.column_stack([f, np.eye(f.size)]))[0][:, 1:f.size]
        return _by_modulus(np.linalg.eigvals(Q.T @ mono @ Q))


#: section multipliers below this times the largest multiplier are taken from the
#: monodromy's multipliers (:func:`accurate_tail`)
SECTION_SMALL = 1e-6


def accurate_tail(rest: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """The Poincare map's multipliers ``rest`` (``n - 1`` by decreasing modulus, from the
    formed product: each only accurate to about ``1e-16`` times the largest) with those
    below :data:`SECTION_SMALL` times the largest ``|mu|`` (and below 0.1: the ones near
    the unit circle, where the section's matter, are never touched) replaced by as many
    of the smallest non-trivial multipliers of ``mu`` (all ``n`` by decreasing modulus;
    the one nearest +1 left out; from :func:`schur_multipliers` accurate relative to
    their own size)."""
    rest, mu = np.array(rest, dtype=complex), np.asarray(mu, dtype=complex)
    if rest.size == 0 or mu.size != rest.size + 1:
        return rest
    mu = np.delete(mu, np.argmin(np.abs(mu - 1.0)))
    level = min(SECTION_SMALL * np.abs(mu).max(initial=1.0), 0.1)
    k = int(min(np.sum(np.abs(rest) < level), np.sum(np.abs(mu) < level)))
    if k:
        rest[rest.size - k:] = mu[mu.size - k:]
    return rest


def monodromy(A: np.ndarray) -> np.ndarray:
    """``Phi = A_{N-1} ... A_0``, by products of adjacent pairs (one batched product per
    level)."""
    A = np.asarray(A, dtype=float)
    while A.shape[0] > 1:
        q = A.shape[0] // 2
        pairs = A[1:2 * q:2] @ A[0:2 * q:2]
        A = np.concatenate([pairs, A[2 * q:]]) if A.shape[0] % 2 else pairs
    return A[0].copy() if A.shape[0] else np.eye(A.shape[1])


def _by_modulus(mu: np.ndarray) -> np.ndarray:
    return mu[np.argsort(-np.abs(mu), kind="stable")]


def _pencil_multipliers(A: np.ndarray) -> np.ndarray:
    N, n, _ = A.shape
    L = np.zeros((N * n, N * n))
    R = np.zeros_like(L)
    for i in range(N):
        L[i * n:(i + 1) * n, i * n:(i + 1) * n] = A[i]
        if i < N - 1:
            L[i * n:(i + 1) * n, (i + 1) * n:(i + 2) * n] = -np.eye(n)
    R[(N - 1) * n:, :n] = np.eye(n)
    ab = sla.eig(L, R, right=False, homogeneous_eigvals=True)
    alpha, beta = ab[0], ab[1]
    scale = np.abs(beta) / np.hypot(np.abs(alpha), np.abs(beta))
    keep = np.argsort(-scale)[:n]
    return alpha[keep] / beta[keep]


def crossing(mu: np.ndarray, target: float) -> float:
    """``prod_k (mu_k - target) / (1 + |mu_k|)``: real (a complex pair contributes
    ``|mu - target|^2 / (1 + |mu|)^2 > 0``), continuous, and of changing sign exactly
    where a real multiplier passes ``target`` (+1 or -1), whichever one it is (the real
    multiplier *nearest* the target may be another one on either side of a step)."""
    return float(np.real(np.prod((mu - target) / (1.0 + np.abs(mu)))))


def nearest_real(mu: np.ndarray, target: float) -> float:
    """The real multiplier nearest ``target`` (the real part nearest, if none is real)."""
    real = mu[mu.imag == 0]
    pool = real if real.size else mu.real
    return float(np.real(pool[np.argmin(np.abs(pool - target))]))


def nearest_complex_modulus(mu: np.ndarray) -> float:
    """The modulus, nearest 1, of the complex multipliers (1 if there are none)."""
    cplx = mu[mu.imag > 0]
    return float(np.abs(cplx[np.argmin(np.abs(np.abs(cplx) - 1.0))])) if cplx.size else 1.0
