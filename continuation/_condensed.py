"""Newton systems of collocated cycles, solved by condensation of every interval.

The bordered Newton matrix of a collocated cycle (``_collocation``) is

    [ B   E ] [ dU ]   [ r ]        B: the collocation rows of every interval,
    [ beta  ] [ dy ] = [ s ]        E: their columns in y = (T, p_free),
                                    beta: the phase row and the PALC border rows.

The ``m = n NCOL`` rows of interval ``i`` couple its ``NCOL + 1`` nodes: the mesh point
``v_i``, the ``NCOL - 1`` interior nodes ``w_i`` (in no other interval) and the next
mesh point ``v_{i+1}``. With ``M_i = [B_i^w, B_i^R]`` (square, the columns of ``w_i`` and
``v_{i+1}``) factorized by LU with partial pivoting, each interval reads

    [w_i; v_{i+1}] + Z_i [v_i; y] = M_i^-1 r_i,     Z_i = M_i^-1 [B_i^L, E_i],

whose last ``n`` rows are the condensed equations and whose ``-Z_i[:, :n]`` are the
interval's Floquet transfer maps (``_floquet``: the multipliers come with the interval
factorizations, cached on the Jacobian). The border rows are freed of ``w`` by the same
relation. What is left is the reduced system in the mesh points and ``y`` (``n NTST + k``
unknowns, block-cyclic bidiagonal with an identity on one diagonal, dense borders),
reduced pairwise by QR (:class:`Chain`: stable like a multiple-shooting system, not a
recursion over the transfer maps, which would be single shooting); the interior nodes
follow by back-substitution.

All loops over intervals and pairs run compiled (``_jit``: numba; a point of a small
system costs a few hundred microseconds, not the milliseconds of a Python loop over
LAPACK calls). Where the pointwise pattern has a narrow band once its states are
reordered (a chain of cells, a discretized PDE in one dimension: ``_intervals``),
the ``M_i`` are factorized banded; small dense ones (at most ``SMALL`` rows) side by
side, every operation over all intervals at once (``_side``). The route pays for dense
interval blocks, for small ones and for banded ones, and is chosen by
:func:`condensed_pays`; large sparse blocks
without a band stay on SuperLU of the whole matrix, which keeps their sparsity. An
interval whose ``M_i`` is singular (not met in practice: ``M_i`` is the derivative part
of the collocation equations, ``h T F_x`` is small against it) falls back to SuperLU of
the whole matrix.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np

from ._intervals import IntervalBand, KinematicRows
from ._lazyjit import SIDE_BY_SIDE, SMALL
from ._newton import factorize
from ._sparse import layout

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


#: the compiled solver's band arguments for dense interval factors, one interval after
#: the other (LAPACK, blocks of more than ``SMALL`` rows) or side by side (loops)
DENSE = (np.zeros(0, np.int64), -1, -1)
SIDE = (np.zeros(0, np.int64), SIDE_BY_SIDE, SIDE_BY_SIDE)
#: the kinematic arguments ``(order, nq, D)`` of ``_jit.interval_factors`` for none
NO_KINEMATIC = (np.zeros(0, np.int64), 0, np.zeros((2, 0, 0)))


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
        (node ``NCOL`` is the next interval's first, wrapping), dense. The terms given
        row by row are summed in one pass that writes every entry once (at N = 40 a
        flutter model's blocks take 43 MB), the others added on their patterns."""
        m, jit = self.n * self.ncol, _compiled()
        dense = [t for t in self.terms if t.rows is None]
        if not dense:
            return self._assembled(np.zeros((self.ntst, m, m + self.n)), jit.add_blocks)
        out = np.empty((self.ntst, m, m + self.n))
        jit.set_dense_blocks(out, tuple(_c(t.values) for t in dense),
                             tuple(_c(t.weights) for t in dense), self.n, self.ncol)
        return self._assembled(out, jit.add_blocks, dense=False)

    def _assembled(self, out: np.ndarray, on_pattern, dense: bool = True) -> np.ndarray:
        """``out`` plus every term on its pattern, added by the compiled kernel
        ``on_pattern`` of the layout of ``out``, and (``dense``) every term given row by
        row, on the full pattern (whose order is that of the rows)."""
        n, ncol = self.n, self.ncol
        for t in self.terms:
            if t.rows is not None:
                on_pattern(out, t.values, t.rows, t.cols, t.weights, n, ncol)
            elif dense:
                on_pattern(out, t.values, *_full_pattern(n), t.weights, n, ncol)
        return out

    def band_blocks(self) -> tuple:
        """``(ab, left)``: the ``M_i`` reordered by the band in LAPACK's band storage
        (:func:`_jit.band_interval_factors`) and the first ``n`` columns of every interval
        (node 0), rows reordered, assembled from the terms (no dense blocks)."""
        b, n, ncol, jit = self.band, self.n, self.ncol, _compiled()
        m = n * ncol
        ab = np.zeros((self.ntst, m, 2 * b.lower + b.upper + 1))
        left = np.zeros((self.ntst, m, n))
        for t in self.terms:
            jit.add_band_blocks(ab, left, t.values, t.rows, t.cols, t.weights, b.rank, ncol,
                                b.lower + b.upper)
        return ab, left

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

    def side_blocks(self) -> np.ndarray:
        """``(m, m + n + k, NTST)``: ``[M_i, B_i^L]`` of every interval side by side
        (:func:`_jit.side_interval_factors`; the last ``k`` columns left for ``E_i``),
        assembled from the terms (no dense blocks)."""
        m, jit = self.n * self.ncol, _compiled()
        a = np.zeros((m, m + self.n + self.extra.shape[2], self.ntst))
        return self._assembled(a, jit.add_side_blocks)

    @property
    def factor_layout(self) -> tuple:
        """The compiled solver's arguments for the layout of :attr:`factors`: banded
        (``band.args``), small dense blocks side by side (:data:`SIDE`, blocks of at most
        ``SMALL`` rows: every operation runs over the intervals at once), dense with the
        kinematic rows eliminated by block (``kinematic.args``, where every ``M_i`` has
        them) or dense one interval after the other (:data:`DENSE`, by LAPACK)."""
        return self._factorization[3]

    @property
    def factors(self) -> tuple | None:
        """``(lu, piv, Z)``: the LU factors of every ``M_i`` (in :attr:`factor_layout`)
        and ``Z_i = M_i^-1 [B_i^L, E_i]`` (``(NTST, m, n + k)``); None if an ``M_i`` is
        singular."""
        lu, piv, Z, _ = self._factorization
        return None if lu is None else (lu, piv, Z)

    @cached_property
    def _factorization(self) -> tuple:
        """``(lu, piv, Z, layout)``, the first three None if an ``M_i`` is singular."""
        extra, jit = _c(self.extra), _compiled()
        if self.band is not None:
            layout = self.band.args
            *out, ok = jit.band_interval_factors(*self.band_blocks(), extra, *layout)
        elif self.n * self.ncol <= SMALL:
            layout = SIDE
            *out, ok = jit.side_interval_factors(self.side_blocks(), extra, self.n)
        else:
            ok = False
            if self.kinematic is not None:
                layout = self.kinematic.args
                *out, ok = jit.interval_factors(self.blocks, extra, layout[0], layout[2],
                                                self.kinematic.D)
            if not ok:                       # no kinematic rows, or an M_i without them
                layout = DENSE
                *out, ok = jit.interval_factors(self.blocks, extra, *NO_KINEMATIC)
        return (*out, layout) if ok else (None, None, None, layout)

    @property
    def maps(self) -> np.ndarray | None:
        """``Z_i``; None if an ``M_i`` is singular. ``-Z_i[:, :n]`` maps ``v_i`` to the
        nodes ``1 .. NCOL`` of interval ``i`` at fixed ``T`` and ``p`` (the Floquet
        transfer, ``_floquet``)."""
        return None if self.factors is None else self.factors[2]


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
        if self.J.factors is None:
            return factorize(self.tocsc())
        return CondensedLU.of(self)


class CondensedLU:
    """Factors of a :class:`BorderedCollocation` by condensation (module doc), with
    ``solve(b)`` like SciPy's ``SuperLU`` (``b``: a vector or a matrix of columns)."""

    def __init__(self, J: CollocationJacobian, chain: "Chain", border_w, bordered):
        #: the Jacobian (its interval factors and maps ``Z``), the chain of the mesh
        #: points, the border rows' coefficients on the interior nodes
        #: ``(NTST, k, n (NCOL - 1))`` and the chain's bordered factors
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
        bu = border[:, :ntst * m].reshape(k, ntst, ncol, n).transpose(1, 0, 2, 3)
        border_w = _c(bu[:, :, 1:, :].reshape(ntst, k, p))
        Wv = border_w @ Z[:, :p]                             # (ntst, k, n + k)
        bordered = chain.bordered(bu[:, :, 0, :] - Wv[:, :, :n],
                                  border[:, ntst * m:] - Wv[:, :, n:].sum(axis=0))
        return None if bordered is None else cls(J, chain, border_w, bordered)

    def solve(self, b: np.ndarray, trans: str = "N") -> np.ndarray:
        if trans != "N":
            raise NotImplementedError("the condensed factors solve with the matrix only "
                                      "(trans='N')")
        b = np.asarray(b, dtype=float)
        lu, piv, Z = self.J.factors
        c = self.chain
        x = _compiled().condensed_solve(lu, piv, self.J.factor_layout, Z, self.border_w,
                                        c.schedule, c.Qb, c.H, c.Zt, *self.bordered,
                                        _c(b.reshape(b.shape[0], -1)))
        return x.reshape(b.shape)


class Chain:
    """The cyclic chain ``A_i v_i + C_i v_{i+1} + G_i y = z_i`` (``i < N``,
    ``v_N = v_0``) reduced pairwise: equations ``2j`` and ``2j + 1`` share the point
    ``2j + 1``, which a QR of its stacked column ``[C_2j; A_2j+1]`` eliminates (the top
    rows give it from its neighbours, the bottom ``n`` rows a new equation between
    ``v_2j`` and ``v_2j+2``); ``log2 N`` levels (``schedule``: pairs and whether an odd
    equation is carried, per level) leave ``(A + C) v_0 + G y = z``. Stable like a QR
    of each pair (no recursion over transfer maps). Per pair, in the order of the levels:
    ``Qb`` (the last ``n`` rows of ``Q^T``, the new equation), ``H = R^-1 Q_top^T`` and
    ``Zt = R^-1 Q_top^T [left, right, y]`` (the point from its neighbours). The ``k``
    border rows ``sum_i Bv_i v_i + By y = s`` that make the system square
    (:meth:`bordered`) follow the eliminations, and with the last equation form an
    ``n + k`` dense system.

    When every ``C_i`` is the identity (the condensed chain, ``C = None``), the first
    level eliminates each pair's point by that identity instead of a QR: one product of
    two adjacent transfer maps, ``v_2j+2 = a_2j+1 a_2j v_2j + ...``, as multiple shooting
    over pairs of intervals does (the higher levels, whose columns are general, keep
    the QR). Half the pairs are on the first level: this halves the reduction's cost."""

    def __init__(self, schedule, Qb, H, Zt, last):
        self.schedule, self.Qb, self.H, self.Zt, self.last = schedule, Qb, H, Zt, last

    @classmethod
    def of(cls, A, C, G):
        """``A, C``: ``(N, n, n)``, ``C`` None for identities (the condensed chain);
        ``G``: ``(N, n, k)``. None when a pair's column is rank-deficient."""
        schedule = _schedule(A.shape[0])
        unit = C is None
        if unit:
            C = np.broadcast_to(np.eye(A.shape[1]), A.shape)
        *factors, ok = _compiled().chain_reduce(*map(_c, (A, C, G)), schedule, unit)
        return cls(schedule, *factors[:3], factors[3:]) if ok else None

    def bordered(self, Bv, By):
        """``(shares, lu, piv)``: per pair the border rows' share ``Bv_mid H`` of the
        eliminated point, and the LU of the final ``n + k`` system; None when it is
        singular. ``Bv``: ``(N, k, n)``, ``By``: ``(k, k)``."""
        *factors, ok = _compiled().chain_border(_c(Bv), _owned(By), self.schedule,
                                                self.H, self.Zt, *self.last)
        return tuple(factors) if ok else None

    def solve(self, bordered, z: np.ndarray, s: np.ndarray) -> tuple:
        """``(v, y)`` for right-hand sides ``z`` (``(N, n, r)``) and ``s`` (``(k, r)``),
        with the factors ``bordered`` of :meth:`bordered`; ``v``: ``(N, n, r)``."""
        return _compiled().chain_solve(self.schedule, self.Qb, self.H, self.Zt, *bordered,
                                       _c(z), _owned(s))


def _compiled():
    """``continuation._jit``, imported at first use (it imports numba)."""
    from . import _jit
    return _jit


def _c(a) -> np.ndarray:
    """``a`` as a writable C-ordered float array, copied only if it is not one (one
    array type for the compiled functions, which then compile once)."""
    return np.require(a, dtype=np.float64, requirements=("C", "W"))


def _owned(a) -> np.ndarray:
    """A copy of ``a`` as :func:`_c` (for the arguments a compiled function overwrites)."""
    return np.array(a, dtype=np.float64, order="C")


@lru_cache(maxsize=64)
def _schedule(N: int) -> np.ndarray:
    """``(levels, 2)``: the pairs of each level of the reduction of ``N`` equations and
    whether it carries an odd last equation (``N - 1`` pairs in all)."""
    levels = []
    while N > 1:
        levels.append((N // 2, N % 2))
        N = N // 2 + N % 2
    out = np.array(levels, dtype=np.int64).reshape(-1, 2)
    out.setflags(write=False)
    return out


@lru_cache(maxsize=16)
def _full_pattern(n: int) -> tuple:
    """``(rows, cols)`` of every entry of an ``n x n`` matrix, row by row (int64)."""
    rows, cols = np.divmod(np.arange(n * n, dtype=np.int64), n)
    return rows, cols


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
