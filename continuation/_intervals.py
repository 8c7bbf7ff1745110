"""The interval matrices of a collocated cycle (``_condensed``): the pointwise terms
whose sum they are, the order of their rows and columns that makes them banded
where the pointwise pattern allows (a chain of cells, a one-dimensional PDE), and their
kinematic rows (a mechanical system's ``dq/dt = r``), which a block elimination takes
out of their LU.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import reverse_cuthill_mckee

from ._lazyjit import KINEMATIC, SCALE_TOL

#: a band is used for interval matrices of more than ``BAND_MIN_ROWS`` rows (smaller ones
#: are factorized by plain loops, ``_dense``) whose band storage ``2 kl + ku + 1`` is at
#: most their size (measured at 40 rows with 34: the interval factors 1.35x faster)
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
    def args(self) -> tuple:
        """``(order, kl, ku)`` for the compiled solver."""
        return self.order, self.lower, self.upper


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
#: (measured on blocks of the flutter model's structure, NTST = 20: even at 40 and 48
#: rows, 1.3x faster at 56, 1.5x at 88, 2x at 328)
KINEMATIC_MIN_ROWS = 48


@dataclass(frozen=True, eq=False)
class KinematicRows:
    """States ``positions[j]`` whose rows in the interval matrices are kinematic,
    ``M_i`` at point ``k`` reading ``Dm[k, l]`` on the position at node ``l``, anything
    on its velocity ``velocities[j]`` and nothing else (``d q/dt = r``, or ``g(r)``:
    ``M`` row ``c e_q``, ``F`` a function of ``r`` alone), so that the positions at the
    nodes ``1 .. NCOL`` follow from the velocities there (``_dense.kinematic_factor``).
    ``D1 = Dm[:, 1:]``."""

    positions: np.ndarray
    velocities: np.ndarray
    others: np.ndarray
    D1: np.ndarray

    @cached_property
    def args(self) -> tuple:
        """``(order, kl, ku)`` for the compiled solver: ``order`` the positions, their
        velocities, the other states and the velocities' places among those, ``kl``
        :data:`KINEMATIC`, ``ku`` the number of positions."""
        places = np.searchsorted(self.others, self.velocities)
        order = np.concatenate([self.positions, self.velocities, self.others, places])
        return order.astype(np.int64), KINEMATIC, self.positions.size

    @cached_property
    def D(self) -> np.ndarray:
        """``(D1, D1^-1)``, stacked."""
        return np.stack([self.D1, np.linalg.inv(self.D1)])


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
