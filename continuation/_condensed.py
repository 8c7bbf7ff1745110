"""Newton systems of collocated cycles, solved by condensation of every interval.

The bordered Newton matrix of a collocated cycle (``_collocation``) is

    [ B   E ] [ dU ]   [ r ]        B: the collocation rows of every interval,
    [ beta  ] [ dy ] = [ s ]        E: their columns in y = (T, p_free),
                                    beta: the phase row and the PALC border rows.

The ``m = n NCOL`` rows of interval ``i`` couple its ``NCOL + 1`` nodes: the mesh point
``v_i``, the ``NCOL - 1`` interior nodes ``w_i`` (in no other interval) and the next
mesh point ``v_{i+1}``. With ``M_i = [B_i^w, B_i^R]`` (square, the columns of ``w_i`` and
``v_{i+1}``) factorized by LAPACK's LU with partial pivoting, each interval reads

    [w_i; v_{i+1}] + Z_i [v_i; y] = M_i^-1 r_i,     Z_i = M_i^-1 [B_i^L, E_i],

whose last ``n`` rows are the condensed equations and whose ``-Z_i[:, :n]`` are the
interval's Floquet transfer maps (``_floquet``: the multipliers come with the interval
factorizations, cached on the Jacobian). The border rows are freed of ``w`` by the same
relation. What is left is the reduced system in the mesh points and ``y`` (``n NTST + k``
unknowns, block-cyclic bidiagonal with an identity on one diagonal, dense borders),
reduced pairwise by QR as AUTO-07p's ``REDUCE`` does (:class:`Chain`: stable like a
multiple-shooting system, not a recursion over the transfer maps, which would be single
shooting); the interior nodes follow by back-substitution.

The interval blocks are dense: the route pays where the model couples many components
at every point (a modal model), and is chosen by :func:`condensed_pays`; banded fields
(a discretized PDE) stay on SuperLU of the whole matrix. An interval whose ``M_i`` is
singular (not met in practice: ``M_i`` is the derivative part of the collocation
equations, ``h T F_x`` is small against it) falls back to SuperLU of the whole matrix.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np
from scipy.linalg.lapack import dgetrf, dgetrs

from ._newton import factorize
from ._sparse import layout
from ._threads import single_threaded

#: the condensed route is chosen ('auto') for interval blocks of at least this many rows
#: that are at least this full: below, SuperLU of the whole sparse matrix is as fast or
#: faster (a Python loop over the intervals costs more than it saves), and on banded
#: blocks (a discretized PDE) SuperLU keeps the sparsity the dense blocks would fill in
CONDENSED_MIN_ROWS, CONDENSED_MIN_FILL = 64, 0.5


def condensed_pays(rows: int, fill: float) -> bool:
    """Whether interval blocks of ``rows`` rows and nonzero fraction ``fill`` are solved
    faster by condensation than by SuperLU of the whole matrix (``docs/performance.md``)."""
    return rows >= CONDENSED_MIN_ROWS and fill >= CONDENSED_MIN_FILL


@dataclass(frozen=True, eq=False)
class CollocationJacobian:
    """``G_X = [[B, E], [c, 0]]`` of the collocation system, by interval blocks.

    blocks : ``(NTST, m, m + n)``, ``m = n NCOL``: the rows of interval ``i`` in its
        nodes ``l = 0 .. NCOL`` (node ``NCOL`` is the next interval's first, wrapping);
    extra : ``(NTST, m, k)``: the same rows in the columns of ``T`` and the free
        parameters;
    phase : ``(NTST NCOL n,)``: the phase row ``c`` (zero in ``T`` and ``p``).
    """

    n: int
    ntst: int
    ncol: int
    blocks: np.ndarray
    extra: np.ndarray
    phase: np.ndarray

    @property
    def shape(self) -> tuple:
        N = self.n * self.ntst * self.ncol
        return (N + 1, N + self.extra.shape[2])

    def collocation_times(self, x: np.ndarray) -> np.ndarray:
        """``[B, E] x`` for ``x`` of shape ``(columns,)`` or ``(columns, r)``."""
        n, ntst, ncol = self.n, self.ntst, self.ncol
        N = n * ntst * ncol
        X = x.reshape(x.shape[0], -1)
        nodes = X[:N].reshape(ntst, ncol * n, -1)
        ahead = np.roll(nodes[:, :n], -1, axis=0)               # v_{i+1}
        out = self.blocks @ np.concatenate([nodes, ahead], axis=1) + self.extra @ X[N:]
        return out.reshape((N,) + x.shape[1:])

    def toarray(self) -> np.ndarray:
        """The dense matrix (for checks; the solvers never form it)."""
        cols = self.shape[1]
        return np.vstack([self.collocation_times(np.eye(cols)),
                          np.append(self.phase, np.zeros(cols - self.phase.size))[None]])

    def bordered(self, rows) -> "BorderedCollocation":
        """``[G_X; rows]`` (``rows``: one row or several, dense)."""
        return BorderedCollocation(self, np.atleast_2d(np.asarray(rows, dtype=float)))

    @cached_property
    def interval_lu(self) -> list | None:
        """LAPACK LU factors ``(lu, piv)`` of every ``M_i``; None if one is singular."""
        factors = []
        with single_threaded():
            for M in self.blocks[:, :, self.n:]:
                lu, piv, info = dgetrf(M)
                if info != 0:
                    return None
                factors.append((lu, piv))
        return factors

    @cached_property
    def maps(self) -> np.ndarray | None:
        """``Z_i = M_i^-1 [B_i^L, E_i]``, ``(NTST, m, n + k)``; None if an ``M_i`` is
        singular. ``-Z_i[:, :n]`` maps ``v_i`` to the nodes ``1 .. NCOL`` of interval
        ``i`` at fixed ``T`` and ``p`` (the Floquet transfer, ``_floquet``)."""
        if self.interval_lu is None:
            return None
        rhs = np.concatenate([self.blocks[:, :, :self.n], self.extra], axis=2)
        return self.interval_solve(rhs)

    def interval_solve(self, b: np.ndarray) -> np.ndarray:
        """``M_i^-1 b_i`` for ``b`` of shape ``(NTST, m, r)``."""
        with single_threaded():
            return np.stack([dgetrs(lu, piv, bi)[0]
                             for (lu, piv), bi in zip(self.interval_lu, b)])


@dataclass(frozen=True, eq=False)
class BorderedCollocation:
    """``[G_X; rows]``, square: the Newton and tangent matrix of PALC on a cycle."""

    J: CollocationJacobian
    rows: np.ndarray

    @property
    def shape(self) -> tuple:
        m, cols = self.J.shape
        return (m + self.rows.shape[0], cols)

    def border(self) -> np.ndarray:
        """All rows below the collocation rows: the phase row, then ``rows``."""
        cols = self.shape[1]
        phase = np.append(self.J.phase, np.zeros(cols - self.J.phase.size))
        return np.vstack([phase, self.rows])

    def __matmul__(self, x: np.ndarray) -> np.ndarray:
        return np.concatenate([self.J.collocation_times(x), self.border() @ x])

    def toarray(self) -> np.ndarray:
        return np.vstack([self.J.toarray(), self.rows])

    def tocsc(self):
        """The whole matrix as a sparse matrix (explicit zeros of the blocks kept)."""
        J = self.J
        k = J.extra.shape[2]
        values = np.concatenate([J.blocks.ravel(), J.extra.ravel(), self.border().ravel()])
        return _full_layout(J.n, J.ntst, J.ncol, k).matrix(values)

    def factorize(self):
        """:class:`CondensedLU` of this matrix; SuperLU of the whole matrix if an
        interval's ``M_i`` is singular; None when the matrix is singular."""
        if self.J.maps is None:
            return factorize(self.tocsc())
        return CondensedLU.of(self)


class CondensedLU:
    """Factors of a :class:`BorderedCollocation` by condensation (module doc), with
    ``solve(b)`` like SciPy's ``SuperLU`` (``b``: a vector or a matrix of columns).

    The work on the border rows is a small part (a few products per level), kept apart
    from the chain's factorization."""

    def __init__(self, J: CollocationJacobian, chain: "Chain", border_w, bordered):
        #: the Jacobian (its interval factors and maps ``Z``), the chain of the mesh
        #: points, the border rows' coefficients on the interior nodes
        #: ``(NTST, k, n (NCOL - 1))`` and the chain's bordered factors
        self.J, self.chain, self.border_w, self.bordered = J, chain, border_w, bordered

    @classmethod
    def of(cls, A: BorderedCollocation):
        J = A.J
        n, ntst, p = J.n, J.ntst, J.n * (J.ncol - 1)
        ZR = J.maps[:, p:]                                  # condensed rows (ntst, n, n + k)
        with single_threaded():
            chain = Chain.of(ZR[:, :, :n], np.broadcast_to(np.eye(n), (ntst, n, n)),
                             ZR[:, :, n:])
        return None if chain is None else cls._bordered(J, chain, A.border())

    @classmethod
    def _bordered(cls, J, chain, border):
        n, ntst, ncol, k = J.n, J.ntst, J.ncol, J.extra.shape[2]
        m, p = n * ncol, n * (ncol - 1)
        if border.shape[0] != k:
            raise ValueError(f"the bordered collocation matrix is not square: "
                             f"{border.shape[0]} border rows for {k} extra columns")
        bu = border[:, :ntst * m].reshape(k, ntst, ncol, n).transpose(1, 0, 2, 3)
        border_w = bu[:, :, 1:, :].reshape(ntst, k, p)
        Wv = border_w @ J.maps[:, :p]                        # (ntst, k, n + k)
        with single_threaded():
            bordered = chain.bordered(bu[:, :, 0, :] - Wv[:, :, :n],
                                      border[:, ntst * m:] - Wv[:, :, n:].sum(axis=0))
        return None if bordered is None else cls(J, chain, border_w, bordered)

    def solve(self, b: np.ndarray, trans: str = "N") -> np.ndarray:
        if trans != "N":
            raise NotImplementedError("the condensed factors solve with the matrix only "
                                      "(trans='N')")
        J = self.J
        n, ntst, ncol = J.n, J.ntst, J.ncol
        m, p, N = n * ncol, n * (ncol - 1), n * ntst * ncol
        b = np.asarray(b, dtype=float)
        b2 = b.reshape(b.shape[0], -1)
        z = J.interval_solve(b2[:N].reshape(ntst, m, -1))   # M_i^-1 r_i
        s = b2[N:] - np.einsum("iqw,iwr->qr", self.border_w, z[:, :p])
        v, y = self.chain.solve(self.bordered, z[:, p:], s)
        Zw = J.maps[:, :p]
        w = z[:, :p] - Zw[:, :, :n] @ v - Zw[:, :, n:] @ y
        U = np.concatenate([v, w], axis=1).reshape(N, -1)
        return np.concatenate([U, y]).reshape(b.shape)


@dataclass(frozen=True)
class _Level:
    """One level of :class:`Chain`: ``pairs`` pairs of equations, each eliminating the
    point between them by QR: ``Qb`` (the last ``n`` rows of ``Q^T``, the new
    equation), ``H = R^-1 Q_top^T`` and ``Zt = R^-1 Q_top^T [left, right, y]`` (the
    point from its neighbours)."""

    pairs: int
    odd: bool
    Qb: np.ndarray
    H: np.ndarray
    Zt: np.ndarray


class Chain:
    """The cyclic chain ``A_i v_i + C_i v_{i+1} + G_i y = z_i`` (``i < N``,
    ``v_N = v_0``) reduced pairwise as AUTO-07p does: equations ``2j`` and ``2j + 1``
    share the point ``2j + 1``, which a QR of its stacked column ``[C_2j; A_2j+1]``
    eliminates (the top rows give it from its neighbours, the bottom ``n`` rows a new
    equation between ``v_2j`` and ``v_2j+2``); ``log2 N`` levels, each one batched call
    over its pairs, leave ``(A + C) v_0 + G y = z``. Stable like a QR of each pair (no
    recursion over transfer maps). The ``k`` border rows ``sum_i Bv_i v_i + By y = s``
    that make the system square (:meth:`bordered`) follow the eliminations, and with
    the last equation form an ``n + k`` dense system."""

    def __init__(self, levels: list, last: tuple):
        self.levels, self.last = levels, last

    @classmethod
    def of(cls, A, C, G):
        """``A, C``: ``(N, n, n)``; ``G``: ``(N, n, k)``. None when a pair's column is
        rank-deficient."""
        levels = []
        while A.shape[0] > 1:
            level, (A, C, G) = _reduce(A, C, G)
            if level is None:
                return None
            levels.append(level)
        return cls(levels, (A[0] + C[0], G[0]))

    def bordered(self, Bv, By):
        """``(shares, lu)``: per level the border rows' share ``Bv_mid H`` of the
        eliminated points, and the LU of the final ``n + k`` system; None when it is
        singular. ``Bv``: ``(N, k, n)``, ``By``: ``(k, k)``."""
        n = Bv.shape[2]
        Bv = np.concatenate([Bv, np.zeros((1,) + Bv.shape[1:])])   # point N: none yet
        By = np.array(By, dtype=float)
        shares = []
        for lv in self.levels:
            q = lv.pairs
            mids = Bv[1:2 * q:2]
            Bz = mids @ lv.Zt                      # the border rows once the mids are gone
            kept = Bv[0:2 * q + 1:2].copy()
            kept[:-1] -= Bz[:, :, :n]
            kept[1:] -= Bz[:, :, n:2 * n]
            By = By - Bz[:, :, 2 * n:].sum(axis=0)
            shares.append(mids @ lv.H)
            Bv = np.concatenate([kept, Bv[-1:]]) if lv.odd else kept
        AC, G = self.last
        lu, piv, info = dgetrf(np.block([[AC, G], [Bv[0] + Bv[1], By]]))
        return None if info != 0 else (shares, (lu, piv))

    def solve(self, bordered, z: np.ndarray, s: np.ndarray) -> tuple:
        """``(v, y)`` for right-hand sides ``z`` (``(N, n, r)``) and ``s`` (``(k, r)``),
        with the factors ``bordered`` of :meth:`bordered`; ``v``: ``(N, n, r)``."""
        n = z.shape[1]
        shares, (lu, piv) = bordered
        kept = []
        for lv, Wb in zip(self.levels, shares):        # forward: the new right-hand sides
            q = lv.pairs
            zp = np.concatenate([z[0:2 * q:2], z[1:2 * q:2]], axis=1)       # (q, 2n, r)
            kept.append(zp)
            s = s - np.einsum("jkw,jwr->kr", Wb, zp)
            new = lv.Qb @ zp
            z = np.concatenate([new, z[-1:]]) if lv.odd else new
        x = dgetrs(lu, piv, np.concatenate([z[0], s]))[0]
        v0, y = x[:n], x[n:]
        vals = np.stack([v0, v0])                      # the points v_0 and v_N = v_0
        for lv, zp in zip(reversed(self.levels), reversed(kept)):   # backward: the points
            q = lv.pairs
            mid = lv.H @ zp - lv.Zt[:, :, :n] @ vals[:q] \
                - lv.Zt[:, :, n:2 * n] @ vals[1:q + 1] - lv.Zt[:, :, 2 * n:] @ y
            out = np.empty((2 * q + 1 + lv.odd,) + vals.shape[1:])
            out[0:2 * q + 1:2], out[1:2 * q:2] = vals[:q + 1], mid
            if lv.odd:
                out[-1] = vals[-1]
            vals = out
        return vals[:-1], y


def _reduce(A, C, G):
    """One level of :class:`Chain`: ``(level, (A, C, G))`` of the reduced chain; level
    None when a pair's column is rank-deficient."""
    n, E = A.shape[1], A.shape[0]
    q, odd = E // 2, E % 2 == 1
    a0, c0, g0 = A[0:2 * q:2], C[0:2 * q:2], G[0:2 * q:2]
    a1, c1, g1 = A[1:2 * q:2], C[1:2 * q:2], G[1:2 * q:2]
    Q, R = np.linalg.qr(np.concatenate([c0, a1], axis=1), mode="complete")
    diag = np.abs(np.diagonal(R[:, :n], axis1=1, axis2=2))
    if not np.all(np.isfinite(diag)) or diag.min() <= n * np.finfo(float).eps * diag.max():
        return None, (A, C, G)
    Qt = Q.transpose(0, 2, 1)
    zero = np.zeros_like(a0)
    T = Qt @ np.concatenate([np.concatenate([a0, zero, g0], axis=2),
                             np.concatenate([zero, c1, g1], axis=2)], axis=1)
    HZ = np.linalg.solve(R[:, :n], np.concatenate([Qt[:, :n], T[:, :n]], axis=2))
    bot = T[:, n:]
    new = [bot[:, :, :n], bot[:, :, n:2 * n], bot[:, :, 2 * n:]]
    if odd:
        new = [np.concatenate([x, old[-1:]]) for x, old in zip(new, (A, C, G))]
    return _Level(q, odd, Qt[:, n:], HZ[:, :, :2 * n], HZ[:, :, 2 * n:]), tuple(new)


@lru_cache(maxsize=4)
def _full_layout(n: int, ntst: int, ncol: int, k: int):
    """CSC layout of the whole bordered matrix with dense interval blocks, in the order
    of ``BorderedCollocation.tocsc``: blocks, extra columns, border rows."""
    m, N = n * ncol, n * ntst * ncol
    i, r, c = np.meshgrid(np.arange(ntst), np.arange(m), np.arange(m + n), indexing="ij")
    e_r, e_c = np.meshgrid(np.arange(N), np.arange(k), indexing="ij")
    q, col = np.meshgrid(np.arange(k), np.arange(N + k), indexing="ij")
    rows = np.concatenate([(i * m + r).ravel(), e_r.ravel(), (N + q).ravel()])
    cols = np.concatenate([((i * m + c) % N).ravel(), (N + e_c).ravel(), col.ravel()])
    return layout(rows, cols, (N + k, N + k))
