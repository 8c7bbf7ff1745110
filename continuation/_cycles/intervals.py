"""The interval matrices of a collocated cycle (``condensed``): the pointwise terms
whose sum they are, the order of their rows and columns that makes them banded
where the pointwise pattern allows (a chain of cells, a one-dimensional PDE), and their
kinematic rows (a mechanical system's ``dq/dt = r``), which a block elimination takes
out of their LU.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import reverse_cuthill_mckee

from .._linalg.stacks import StackLU

#: a band is used for interval matrices of more than ``BAND_MIN_ROWS`` rows whose band
#: storage ``2 kl + ku + 1`` is at most their size
BAND_MIN_ROWS = 32


@dataclass(frozen=True, eq=False)
class IntervalBand:
    """An order of the rows and the columns of the interval matrices ``M_i`` that makes
    them banded: ``M_i[order][:, order]`` has ``lower`` sub- and ``upper``
    super-diagonals. A row and a column at the same place are the same point and the
    same node of one state: the states in the order ``states``, each with its ``NCOL``
    rows (points) and columns (nodes ``1 .. NCOL``) together."""

    states: np.ndarray
    ncol: int
    lower: int
    upper: int
    #: :meth:`assembly` per number of intervals and patterns, built once
    _assemblies: dict = field(default_factory=dict, repr=False)

    @cached_property
    def order(self) -> np.ndarray:
        """Place ``rank[a] NCOL + k`` holds row ``k n + a`` (point ``k``, state ``a``) and
        column ``k n + a`` (node ``k + 1``)."""
        n = self.states.size
        return (np.arange(self.ncol)[None, :] * n + self.states[:, None]).ravel()

    @cached_property
    def rank(self) -> np.ndarray:
        """The place of each state in ``states``."""
        rank = np.empty_like(self.states)
        rank[self.states] = np.arange(self.states.size)
        return rank

    @property
    def width(self) -> int:
        """The rows of LAPACK's band storage, ``2 kl + ku + 1``."""
        return 2 * self.lower + self.upper + 1

    def places(self, rows: np.ndarray, cols: np.ndarray) -> tuple:
        """``(M, R)``: where the entries ``(rows[e], cols[e])`` of a pointwise pattern sit,
        for point ``k`` and node ``l``: ``M[k, l - 1, e]`` in the flat band storage of an
        interval (``_linalg.stacks.BandStackLU``; nodes ``1 .. NCOL``), ``R[k, e]`` the row
        (reordered) of its entry in the node 0 columns."""
        ncol, d = self.ncol, self.lower + self.upper
        r = self.rank[rows] * ncol + np.arange(ncol)[:, None]           # (k, e)
        c = self.rank[cols] * ncol + np.arange(ncol)[:, None]           # (l - 1, e)
        return c[None] * self.width + d + r[:, None] - c[None], r

    def assembly(self, patterns: tuple, ntst: int) -> tuple:
        """``(inside, first)``: the places of the entries of pointwise terms on
        ``patterns`` (``(rows, cols)`` each) in the flat band storage of ``ntst`` intervals
        (``(NTST, m, width)``) and in their node 0 columns, ``(n, NTST, m)`` (column by
        column, rows reordered), interval by interval, term after term, each in the order
        of :meth:`places`."""
        key = (ntst,) + tuple(a.tobytes() for pattern in patterns for a in pattern)
        if key not in self._assemblies:
            m = self.ncol * self.states.size
            inside, first = zip(*(self.places(*pattern) for pattern in patterns))
            cols = [np.broadcast_to(c, r.shape) for (_, c), r in zip(patterns, first)]
            i = np.arange(ntst)[:, None]
            self._assemblies[key] = (
                (i * m * self.width + np.concatenate([a.ravel() for a in inside])).ravel(),
                (i * m + np.concatenate([(c * ntst * m + r).ravel() for c, r in
                                         zip(cols, first)])).ravel())
        return self._assemblies[key]


def interval_band(n: int, ncol: int, prow: np.ndarray, pcol: np.ndarray):
    """The :class:`IntervalBand` of interval matrices whose every ``n x n`` block (point
    ``k``, node ``l``) has the pointwise pattern ``(prow, pcol)``, or None when it would
    not pay (``BAND_MIN_ROWS``). The states are ordered by reverse Cuthill-McKee
    of the pattern, and each state's ``NCOL`` rows (points) and columns (nodes
    ``1 .. NCOL``) kept together: a state coupled to states at most ``d`` places away
    gives ``d NCOL + NCOL - 1`` off-diagonals."""
    m = n * ncol
    if prow.size == 0 or m <= BAND_MIN_ROWS:
        return None
    pattern = sp.csr_matrix((np.ones(prow.size), (prow, pcol)), shape=(n, n))
    order = np.asarray(reverse_cuthill_mckee(pattern + pattern.T + sp.eye(n),
                                             symmetric_mode=True), dtype=np.int64)
    place = np.empty(n, np.int64)
    place[order] = np.arange(n)
    reach = place[prow] - place[pcol]
    lower = int(max(reach.max(), 0)) * ncol + ncol - 1
    upper = int(max(-reach.min(), 0)) * ncol + ncol - 1
    if 2 * lower + upper + 1 > m:
        return None
    return IntervalBand(order, ncol, lower, upper)


#: kinematic rows are eliminated in dense interval matrices of more than this many rows
#: (smaller ones take the plain LU, as fast there: ``docs/performance.md``)
KINEMATIC_MIN_ROWS = 48

#: the relative rounding allowed between a kinematic row's entries on its own position
#: and ``c Dm`` (:func:`kinematic_rows`, :meth:`KinematicRows.factorize`)
SCALE_TOL = 1e-15


@dataclass(frozen=True, eq=False)
class KinematicRows:
    """States ``positions[j]`` whose rows in the interval matrices are kinematic,
    ``M_i`` at point ``k`` reading ``Dm[k, l]`` on the position at node ``l``, anything
    on its velocity ``velocities[j]`` and nothing else (``d q/dt = r``, or ``g(r)``:
    ``M`` row ``c e_q``, ``F`` a function of ``r`` alone), so that the positions at the
    nodes ``1 .. NCOL`` follow from the velocities there (:meth:`factorize`).
    ``others``: the remaining states (the velocities among them), ``D1 = Dm[:, 1:]``."""

    positions: np.ndarray
    velocities: np.ndarray
    others: np.ndarray
    D1: np.ndarray

    @cached_property
    def places(self) -> np.ndarray:
        """The place of each position's velocity among :attr:`others`."""
        return np.searchsorted(self.others, self.velocities)

    @cached_property
    def index(self) -> tuple:
        """:attr:`positions`, :attr:`others` and :attr:`places` as indices: a slice where
        they are a range (a view instead of a copy; the mechanical models order their
        states so: positions, velocities, the rest)."""
        return tuple(_as_index(a) for a in (self.positions, self.others, self.places))

    @cached_property
    def distinct(self) -> bool:
        """Whether every position has a velocity of its own."""
        return np.unique(self.velocities).size == self.velocities.size

    @cached_property
    def D1inv(self) -> np.ndarray:
        return np.linalg.inv(self.D1)

    @cached_property
    def gather(self) -> dict:
        """Where position ``j``'s row at point ``k`` has its entries on its own node ``l =
        1 .. NCOL`` (``'own'``) and on its velocity's (``'V'``) in ``blocks[i].ravel()``,
        ``(j, k, l)``."""
        pos, vel = self.positions, self.velocities
        ncol, n = self.D1.shape[0], pos.size + self.others.size
        k, l = np.arange(ncol), np.arange(1, ncol + 1)
        row = (k[None, :, None] * n + pos[:, None, None]) * (ncol + 1) * n + l * n
        return {"own": (row + pos[:, None, None]).ravel(),
                "V": (row + vel[:, None, None]).ravel()}

    def factorize(self, blocks: np.ndarray) -> "KinematicLU | None":
        """:class:`KinematicLU` of the interval matrices ``M_i = blocks[i, :, n:]``
        (``blocks``: ``(NTST, m, m + n)``); None if an ``M_i`` lacks the structure
        (checked exactly) or its Schur complement is singular."""
        return KinematicLU.of(self, blocks)


class KinematicLU:
    """Block LU of interval matrices with :class:`KinematicRows`. Position ``q_j``'s rows
    read ``c_j D1 x_q + V_j x_v = b_q`` (``x_q``, ``x_v``: the position and its velocity
    at the nodes ``1 .. NCOL``), so ``x_q = D1^-1 b_q / c_j - W_j x_v`` with ``W_j = D1^-1
    V_j / c_j``, and the other states ``s`` (the velocities among them) solve the Schur
    complement ``S x_s = b_s - A_sq D1^-1 b_q / c`` with ``S = A_ss - A_sq W``: an LU of
    ``(n - nq) NCOL`` rows instead of ``n NCOL``. The pieces are views of the blocks
    where the states are ranges (:attr:`KinematicRows.index`), else gathered; the
    products are NumPy's batched ones over the stack, the LUs of ``S_i`` LAPACK's
    (:class:`_stacks.StackLU`)."""

    def __init__(self, rows: KinematicRows, S, Asq, W, c):
        #: ``S_i`` factorized, ``A_sq`` ``(NTST, ms, NCOL nq)`` (columns node-major),
        #: ``W`` ``(NTST, nq, NCOL, NCOL)``, ``c`` ``(NTST, nq)``
        self.rows, self.S, self.Asq, self.W, self.c = rows, S, Asq, W, c

    @classmethod
    def of(cls, rows: KinematicRows, blocks: np.ndarray) -> "KinematicLU | None":
        ntst, ncol, nq = blocks.shape[0], rows.D1.shape[0], rows.positions.size
        ms, at, (pos, oth, places) = rows.others.size * ncol, rows.gather, rows.index
        flat = blocks.reshape(ntst, -1)
        own, V = (flat.take(at[key], axis=1).reshape(ntst, nq, ncol, ncol)
                  for key in ("own", "V"))
        c = own[:, :, 0, 0] / rows.D1[0, 0]
        scaled = c[:, :, None, None] * rows.D1
        with np.errstate(invalid="ignore"):
            if not (np.all(np.isfinite(c)) and np.all(c != 0.0) and np.all(
                    np.abs(own - scaled) <= SCALE_TOL * np.abs(scaled))):
                return None
        M = blocks.reshape(ntst, ncol, -1, ncol + 1, blocks.shape[2] // (ncol + 1))[..., 1:, :]
        if np.count_nonzero(_rows(M, pos, 2)) != np.count_nonzero(own) + np.count_nonzero(V):
            return None                                             # a third state
        W = rows.D1inv @ V / c[:, :, None, None]                    # (i, j, b, l)
        S = _block(M, oth, oth).reshape(ntst, ms, ms)               # (i, k, s, l, t)
        Asq = _block(M, oth, pos).reshape(ntst, ms, ncol * nq)
        # S[:, (k, s), (l, v_j)] -= sum_b A_sq[:, (k, s), (b, j)] W_j[b, l]
        T = (Asq.reshape(ntst, ms, ncol, nq).transpose(0, 3, 1, 2) @ W).transpose(0, 2, 3, 1)
        S4 = S.reshape(ntst, ms, ncol, -1)
        if rows.distinct:
            S4[..., places] -= T
        else:                                # positions sharing a velocity: sum them
            np.subtract.at(S4, (Ellipsis, rows.places), T)
        S = StackLU.of(S, overwrite=True)
        return None if S is None else cls(rows, S, Asq, W, c)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """``x_i = M_i^-1 b_i`` for ``b``: ``(NTST, m, r)``."""
        rows, (ntst, m, r) = self.rows, b.shape
        ncol, nq = rows.D1.shape[0], rows.positions.size
        pos, oth, places = rows.index
        n = m // ncol
        b4 = b.reshape(ntst, ncol, n, r)
        xq = rows.D1inv @ b4[:, :, pos].reshape(ntst, ncol, nq * r)
        xq = xq.reshape(ntst, ncol, nq, r) / self.c[:, None, :, None]  # D1^-1 b_q / c
        bs = b4[:, :, oth].reshape(ntst, -1, r)
        xs = self.S.solve(bs - self.Asq @ xq.reshape(ntst, ncol * nq, r))
        xs = xs.reshape(ntst, ncol, n - nq, r)
        xv = xs[:, :, places].transpose(0, 2, 1, 3)                     # (i, j, l, r)
        xq -= (self.W @ xv).transpose(0, 2, 1, 3)                       # x_q -= W_j x_v
        x = np.empty((ntst, ncol, n, r))
        x[:, :, oth], x[:, :, pos] = xs, xq
        return x.reshape(b.shape)


def _as_index(a: np.ndarray):
    """``a`` as a slice where it is a range, else itself."""
    return slice(int(a[0]), int(a[-1]) + 1) if a.size and np.array_equal(
        a, np.arange(a[0], a[-1] + 1)) else a


def _block(M: np.ndarray, rows, cols) -> np.ndarray:
    """``M[:, :, rows][..., cols]`` (``M``: ``(i, k, a, l, b)``; :func:`_as_index`) as a new
    C-ordered array: a copy of a view for two ranges, else one gather."""
    if isinstance(rows, slice) and isinstance(cols, slice):
        return np.ascontiguousarray(M[:, :, rows, :, cols])
    r, c = (np.arange(M.shape[axis])[ix] if isinstance(ix, slice) else ix
            for axis, ix in ((2, rows), (4, cols)))
    return M[:, :, r[:, None, None], np.arange(M.shape[3])[None, :, None], c[None, None, :]]


def _rows(a: np.ndarray, index, axis: int) -> np.ndarray:
    """``a`` at ``index`` (:func:`_as_index`) along ``axis``: a view for a slice."""
    return a[(slice(None),) * axis + (index,)] if isinstance(index, slice) else \
        a.take(index, axis=axis)


def kinematic_rows(blocks: np.ndarray, Dm: np.ndarray) -> KinematicRows | None:
    """The :class:`KinematicRows` of the dense interval blocks ``blocks`` (``(NTST, m,
    m + n)``, their nodes ``0 .. NCOL``, ``Dm``: the collocation's ``NCOL x (NCOL + 1)``
    derivative weights), read from their entries exactly; None if they have none. A
    state that is a velocity is not taken as a position."""
    ntst, m, cols = blocks.shape
    n, ncol = cols - m, Dm.shape[0]
    M = blocks[:, :, n:].reshape(ntst, ncol, n, ncol, n)          # (i, k, a, l, s)
    diagonal = np.diagonal(M, axis1=2, axis2=4)                      # (i, k, l, a)
    scale = diagonal[0, 0, 0] / Dm[0, 1]
    with np.errstate(invalid="ignore"):
        own = np.all(np.abs(diagonal - scale * Dm[None, :, 1:, None]) <= SCALE_TOL *
                     np.abs(diagonal), axis=(0, 1, 2)) & (scale != 0.0)
    coupled = np.any(M != 0.0, axis=(0, 1, 3))                       # (a, s)
    coupled[np.diag_indices(n)] = False
    positions, velocities = [], []
    for a in np.flatnonzero(own & (coupled.sum(axis=1) == 1)):
        b = int(np.flatnonzero(coupled[a])[0])
        if a not in velocities and b not in positions:
            positions.append(int(a))
            velocities.append(b)
    if not positions:
        return None
    others = np.setdiff1d(np.arange(n), positions)
    return KinematicRows(np.array(positions), np.array(velocities), others,
                         np.ascontiguousarray(Dm[:, 1:]))


@dataclass(frozen=True, eq=False)
class PointwiseTerm:
    """One pointwise matrix's share of the interval blocks: block ``(k, l)`` (point
    ``k``, node ``l``) of interval ``i`` gains ``weights[i NCOL + k, l] A``, ``A`` the
    matrix at point ``i NCOL + k``: ``values[i NCOL + k]`` holds its nonzeros at
    ``(rows, cols)``, or all of it row by row (``rows`` None)."""

    values: np.ndarray
    weights: np.ndarray
    rows: np.ndarray | None = None
    cols: np.ndarray | None = None
