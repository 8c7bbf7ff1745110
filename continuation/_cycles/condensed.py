"""Newton systems of collocated cycles, solved by condensation of every interval.

The bordered Newton matrix of a collocated cycle (``collocation``) is

    [ B   E ] [ dU ]   [ r ]        B: the collocation rows of every interval,
    [ beta  ] [ dy ] = [ s ]        E: their columns in y = (T, p_free),
                                    beta: the phase row and the PALC border rows.

The ``m = n NCOL`` rows of interval ``i`` couple its ``NCOL + 1`` nodes: the mesh point
``v_i``, the ``NCOL - 1`` interior nodes ``w_i`` (in no other interval) and the next
mesh point ``v_{i+1}``. With ``M_i = [B_i^w, B_i^R]`` (square, the columns of ``w_i`` and
``v_{i+1}``) factorized by LU with partial pivoting, each interval reads

    [w_i; v_{i+1}] + Z_i [v_i; y] = M_i^-1 r_i,     Z_i = M_i^-1 [B_i^L, E_i],

whose last ``n`` rows are the condensed equations and whose ``-Z_i[:, :n]`` are the
interval's Floquet transfer maps (``floquet``: the multipliers come with the interval
factorizations, cached on the Jacobian). The border rows are freed of ``w`` by the same
relation. What is left is the reduced system in the mesh points and ``y`` (``n NTST + k``
unknowns, block-cyclic bidiagonal with an identity on one diagonal, dense borders),
reduced pairwise by QR (:class:`Chain`: stable like a multiple-shooting system, not a
recursion over the transfer maps, which would be single shooting); the interior nodes
follow by back-substitution.

Every step runs on whole stacks: the interval LUs by LAPACK, one call per interval
(``_linalg.stacks``: dense, or banded where the pointwise pattern has a narrow band once its
states are reordered, a chain of cells, a discretized PDE in one dimension:
``intervals``; with the kinematic rows of a mechanical system eliminated by block),
the products by NumPy's batched ``matmul``, the chain's QRs by its batched ``qr``, level
by level. The route pays for dense interval blocks, for small ones and for banded ones,
and is chosen by :func:`condensed_pays`; large sparse blocks without a band stay on
SuperLU of the whole matrix, which keeps their sparsity. An interval whose ``M_i`` is
singular (not met in practice: ``M_i`` is the derivative part of the collocation
equations, ``h T F_x`` is small against it) falls back to SuperLU of the whole matrix.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np

from .chain import Chain
from .intervals import IntervalBand, KinematicRows
from .._linalg.sparse import layout
from .._linalg.stacks import BandStackLU, StackLU
from .._driver.newton import factorize

#: the condensed route is chosen ('auto') for interval blocks of at most ``CONDENSED_ROWS``
#: rows, for larger ones at least ``CONDENSED_MIN_FILL`` full and for banded ones: larger
#: sparse blocks without a band are faster on SuperLU, which keeps their sparsity
#: (``docs/performance.md``)
CONDENSED_ROWS, CONDENSED_MIN_FILL = 100, 0.5


def condensed_pays(rows: int, fill: float, banded: bool = False) -> bool:
    """Whether interval blocks of ``rows`` rows and nonzero fraction ``fill`` (``banded``:
    with an :class:`IntervalBand`) are solved faster by condensation than by SuperLU of
    the whole matrix."""
    return rows <= CONDENSED_ROWS or fill >= CONDENSED_MIN_FILL or banded


@dataclass(frozen=True, eq=False)
class CollocationJacobian:
    """``G_X = [[B, E], [c, 0]]`` of the collocation system, by interval blocks.

    terms : the :class:`PointwiseTerm` whose sum are the interval blocks (``blocks``),
        assembled into the layout that the factorization needs (dense, or banded);
    extra : ``(NTST, m, k)``, ``m = n NCOL``: the rows of every interval in the columns
        of ``T`` and the free parameters;
    phase : ``(NTST NCOL n,)``: the phase row ``c`` (zero in ``T`` and ``p``);
    band : an :class:`IntervalBand` of the ``M_i`` (factorized banded), or None (dense).
    kinematic : the :class:`KinematicRows` of dense ``M_i`` (eliminated by block), or None.
    """

    n: int
    ntst: int
    ncol: int
    terms: tuple
    extra: np.ndarray
    phase: np.ndarray
    band: IntervalBand | None = None
    kinematic: KinematicRows | None = None

    @property
    def shape(self) -> tuple:
        N = self.n * self.ntst * self.ncol
        return (N + 1, N + self.extra.shape[2])

    @cached_property
    def blocks(self) -> np.ndarray:
        """``(NTST, m, m + n)``: the rows of interval ``i`` in its nodes ``l = 0 .. NCOL``
        (node ``NCOL`` is the next interval's first, wrapping), dense: block ``(k, l)``
        gains ``weights[i NCOL + k, l] A`` from every term, ``A`` its matrix at point
        ``i NCOL + k``."""
        n, ntst, ncol = self.n, self.ntst, self.ncol
        dense = [t for t in self.terms if t.rows is None]           # given row by row
        if dense:                  # sum_t w_t[i, k, l] A_t[a, b]: one batched product
            values = np.stack([t.values.reshape(ntst, ncol, n, n) for t in dense], axis=3)
            weights = np.stack([t.weights.reshape(ntst, ncol, ncol + 1) for t in dense],
                               axis=3)
            out = weights[:, :, None] @ values                      # (i, k, a, l, b)
        else:
            out = np.zeros((ntst, ncol, n, ncol + 1, n))
        for t in self.terms:
            if t.rows is not None:           # the pattern's entries are distinct
                w = t.weights.reshape(ntst, ncol, ncol + 1, 1)
                out[:, :, t.rows, :, t.cols] += np.moveaxis(
                    w * t.values.reshape(ntst, ncol, 1, -1), 3, 0)
        return out.reshape(ntst, ncol * n, (ncol + 1) * n)

    def band_blocks(self) -> tuple:
        """``(ab, left)``: the ``M_i`` reordered by the band in LAPACK's band storage
        (``_linalg.stacks.BandStackLU``, ``(NTST, m, 2 kl + ku + 1)``) and the first ``n``
        columns of every interval (node 0), rows reordered, ``(NTST, m, n)``."""
        ab, rhs = self._band_system()
        return ab, rhs[:self.n].transpose(1, 2, 0)

    def _band_system(self) -> tuple:
        """``(ab, rhs)``: :meth:`band_blocks`'s ``ab`` and the right-hand sides of the
        maps, ``[B_i^L, E_i]`` with rows reordered, in the band solves' layout ``(n + k,
        NTST, m)``; summed from the terms' entries by one ``bincount`` each (no dense
        blocks)."""
        b, n, ntst, ncol = self.band, self.n, self.ntst, self.ncol
        m, k = n * ncol, self.extra.shape[2]
        inside, first = b.assembly(tuple((t.rows, t.cols) for t in self.terms), ntst)
        w = [t.weights.reshape(ntst, ncol, ncol + 1, 1) for t in self.terms]
        v = [t.values.reshape(ntst, ncol, 1, -1) for t in self.terms]
        nodes = np.concatenate([(wt[:, :, 1:] * vt).reshape(ntst, -1)
                                for wt, vt in zip(w, v)], axis=1)
        node0 = np.concatenate([(wt[:, :, 0] * vt[:, :, 0]).reshape(ntst, -1)
                                for wt, vt in zip(w, v)], axis=1)
        ab = np.bincount(inside, nodes.ravel(), minlength=ntst * m * b.width)
        rhs = np.bincount(first, node0.ravel(), minlength=(n + k) * ntst * m)
        rhs = rhs.reshape(n + k, ntst, m)
        rhs[n:] = self.extra.transpose(2, 0, 1).take(b.order, axis=2)
        return ab.reshape(ntst, m, b.width), rhs

    def collocation_times(self, x: np.ndarray) -> np.ndarray:
        """``[B, E] x`` for ``x`` of shape ``(columns,)`` or ``(columns, r)``."""
        n, ntst, (_, m, _) = self.n, self.ntst, self.blocks.shape
        X = x.reshape(x.shape[0], -1)
        nodes = X[:ntst * m].reshape(ntst, m, -1)     # interval i's rows: its nodes 0..NCOL,
        out = self.blocks[:, :, :m] @ nodes + self.extra @ X[ntst * m:]   # the last the next
        out += self.blocks[:, :, m:] @ np.roll(nodes[:, :n], -1, axis=0)  # interval's first
        return out.reshape((ntst * m,) + x.shape[1:])

    def toarray(self) -> np.ndarray:
        """The dense matrix (for checks; the solvers never form it)."""
        cols = self.shape[1]
        return np.vstack([self.collocation_times(np.eye(cols)),
                          np.append(self.phase, np.zeros(cols - self.phase.size))[None]])

    def bordered(self, rows) -> "BorderedCollocation":
        """``[G_X; rows]`` (``rows``: one row or several, dense)."""
        return BorderedCollocation(self, np.atleast_2d(np.asarray(rows, dtype=float)))

    @property
    def intervals(self):
        """The factors of every ``M_i``, with ``solve(b)``: ``x_i = M_i^-1 b_i`` (``b``:
        ``(NTST, m, r)``); banded (:attr:`band`), with the kinematic rows eliminated
        (:attr:`kinematic`, where every ``M_i`` has them) or dense. None if an ``M_i``
        is singular."""
        return self._factorization[0]

    @property
    def maps(self) -> np.ndarray | None:
        """``Z_i = M_i^-1 [B_i^L, E_i]`` (``(NTST, m, n + k)``); None if an ``M_i`` is
        singular. ``-Z_i[:, :n]`` maps ``v_i`` to the nodes ``1 .. NCOL`` of interval
        ``i`` at fixed ``T`` and ``p`` (the Floquet transfer, ``floquet``)."""
        return self._factorization[1]

    @cached_property
    def _factorization(self) -> tuple:
        """``(intervals, Z)``, both None if an ``M_i`` is singular."""
        n = self.n
        if self.band is not None:
            band = self.band
            ab, rhs = self._band_system()
            lu = BandStackLU.of(ab, band.lower, band.upper, band.order)
            if lu is None:
                return None, None
            return lu, lu.solve_columns(rhs).take(lu.inverse, axis=2).transpose(1, 2, 0)
        M, right = self.blocks[:, :, n:], np.concatenate([self.blocks[:, :, :n], self.extra],
                                                         axis=2)
        lu = None if self.kinematic is None else self.kinematic.factorize(self.blocks)
        if lu is None:                       # no kinematic rows, or an M_i without them
            lu = StackLU.of(M)
        return (None, None) if lu is None else (lu, lu.solve(right))


@dataclass(frozen=True, eq=False)
class BorderedCollocation:
    """``[G_X; rows]``, square: the Newton and tangent matrix of PALC on a cycle."""

    J: CollocationJacobian
    rows: np.ndarray

    @property
    def shape(self) -> tuple:
        m, cols = self.J.shape
        return (m + self.rows.shape[0], cols)

    @cached_property
    def border(self) -> np.ndarray:
        """All rows below the collocation rows: the phase row, then ``rows``."""
        out = np.zeros((1 + self.rows.shape[0], self.shape[1]))
        out[0, :self.J.phase.size], out[1:] = self.J.phase, self.rows
        return out

    def __matmul__(self, x: np.ndarray) -> np.ndarray:
        return np.concatenate([self.J.collocation_times(x), self.border @ x])

    def toarray(self) -> np.ndarray:
        return np.vstack([self.J.toarray(), self.rows])

    def tocsc(self):
        """The whole matrix as a sparse matrix (explicit zeros of the blocks kept)."""
        J = self.J
        k = J.extra.shape[2]
        values = np.concatenate([J.blocks.ravel(), J.extra.ravel(), self.border.ravel()])
        return _full_layout(J.n, J.ntst, J.ncol, k).matrix(values)

    def factorize(self):
        """:class:`CondensedLU` of this matrix; SuperLU of the whole matrix if an
        interval's ``M_i`` is singular; None when the matrix is singular."""
        if self.J.maps is None:
            return factorize(self.tocsc())
        return CondensedLU.of(self)


class CondensedLU:
    """Factors of a :class:`BorderedCollocation` by condensation (module doc), with
    ``solve(b)`` like SciPy's ``SuperLU`` (``b``: a vector or a matrix of columns)."""

    def __init__(self, J: CollocationJacobian, chain: "Chain", border_w, bordered):
        #: the Jacobian (its interval factors and maps ``Z``), the chain of the mesh
        #: points, the border rows' coefficients on the interior nodes
        #: ``(k, NTST n (NCOL - 1))`` and the chain's bordered factors
        self.J, self.chain, self.border_w, self.bordered = J, chain, border_w, bordered

    @classmethod
    def of(cls, A: BorderedCollocation):
        J = A.J
        n, ntst, ncol, k = J.n, J.ntst, J.ncol, J.extra.shape[2]
        m, p = n * ncol, n * (ncol - 1)
        border = A.border
        if border.shape[0] != k:
            raise ValueError(f"the bordered collocation matrix is not square: "
                             f"{border.shape[0]} border rows for {k} extra columns")
        Z = J.maps
        chain = Chain.of(Z[:, p:, :n], None, Z[:, p:, n:])
        if chain is None:
            return None
        bu = border[:, :ntst * m].reshape(k, ntst, ncol, n)
        border_w = bu[:, :, 1:].reshape(k, ntst, p)
        Wv = border_w.transpose(1, 0, 2) @ Z[:, :p]                 # (ntst, k, n + k)
        bordered = chain.bordered(bu[:, :, 0, :].transpose(1, 0, 2) - Wv[:, :, :n],
                                  border[:, ntst * m:] - Wv[:, :, n:].sum(axis=0))
        if bordered is None:
            return None
        return cls(J, chain, np.ascontiguousarray(border_w.reshape(k, ntst * p)), bordered)

    def solve(self, b: np.ndarray, trans: str = "N") -> np.ndarray:
        if trans != "N":
            raise NotImplementedError("the condensed factors solve with the matrix only "
                                      "(trans='N')")
        b = np.asarray(b, dtype=float)
        J = self.J
        n, ntst, Z = J.n, J.ntst, J.maps
        (_, m, _), p = Z.shape, J.n * (J.ncol - 1)
        B = b.reshape(b.shape[0], -1)
        N, r = ntst * m, B.shape[1]
        z = J.intervals.solve(B[:N].reshape(ntst, m, r))            # every M_i^-1 r_i
        w = z[:, :p]
        s = B[N:] - self.border_w @ w.reshape(ntst * p, r)
        v, y = self.chain.solve(self.bordered, z[:, p:], s)
        w -= Z[:, :p, :n] @ v + Z[:, :p, n:] @ y                    # the interior nodes
        x = np.empty((N + y.shape[0], r))
        X = x[:N].reshape(ntst, m, r)
        X[:, :n], X[:, n:], x[N:] = v, w, y
        return x.reshape(b.shape)


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
