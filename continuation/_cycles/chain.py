"""The cyclic chain of the mesh points of a condensed collocated cycle (``condensed``),
reduced pairwise, level by level, every level a few batched NumPy calls over its pairs."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._linalg.stacks import StackLU

#: the largest growth ``rho(|a1| |a0|)`` (:func:`_bounded`) of a pair eliminated by its
#: identity pivot; a level with a larger one takes the QR
UNIT_GROWTH = 16.0

#: the reduction stops at the first level whose equations and border rows make a dense
#: system of at most ``DENSE_ROWS`` rows (a few small levels cost more than its LU), or
#: of at most twice that when the level would take the QR
DENSE_ROWS = 96


class Chain:
    """The cyclic chain ``A_i v_i + C_i v_{i+1} + G_i y = z_i`` (``i < N``,
    ``v_N = v_0``) reduced pairwise: equations ``2j`` and ``2j + 1`` share the point
    ``2j + 1``, which each level eliminates (the point from its neighbours, and a new
    equation between ``v_2j`` and ``v_2j+2``); up to ``log2 N`` levels (an odd last
    equation carried to the next) leave ``L`` equations, down to ``(A + C) v_0 + G y =
    z``. Stable like a QR of each pair (no recursion over transfer maps). The ``k`` border
    rows ``sum_i Bv_i v_i + By y = s`` that make the system square (:meth:`bordered`)
    follow the eliminations, and with the ``L`` equations left form a dense system of
    ``L n + k`` rows (:data:`DENSE_ROWS`, or ``L = 1``), solved by LU.

    A level eliminates its points by the QR of each pair's column ``[C_2j; A_2j+1]``
    (:class:`_Rotations`), or, when every ``C_i`` is still the identity (the condensed
    chain, ``C = None``) and the maps of every pair are bounded (:data:`UNIT_GROWTH`), by
    that identity pivot (:class:`_Pivots`): ``v_2j+1 = z_2j - a_2j v_2j - g_2j y``, one
    product of two adjacent transfer maps, as multiple shooting over pairs of intervals
    does, and the identity stays on the new equations."""

    def __init__(self, levels, last):
        #: per level its elimination (:class:`_Pivots` or :class:`_Rotations`) and whether
        #: it carries an odd last equation; the equations left ``(A, C, G)`` (``C`` None
        #: for identities)
        self.levels, self.last = levels, last

    @classmethod
    def of(cls, A, C, G, dense_rows: int = DENSE_ROWS):
        """``A, C``: ``(N, n, n)``, ``C`` None for identities (the condensed chain);
        ``G``: ``(N, n, k)``; ``dense_rows``: :data:`DENSE_ROWS`. None when a pair's
        column is rank-deficient."""
        levels, (n, k) = [], G.shape[1:]
        while A.shape[0] > 1 and A.shape[0] * n + k > dense_rows:
            q, odd = divmod(A.shape[0], 2)
            a0, a1, g0, g1 = A[0:2 * q:2], A[1:2 * q:2], G[0:2 * q:2], G[1:2 * q:2]
            if C is None and _bounded(a1, a0):
                level, A2, G2, C2 = _Pivots(a0, a1, g0), -(a1 @ a0), g1 - a1 @ g0, None
            elif A.shape[0] * n + k <= 2 * dense_rows:
                break
            else:
                if C is None:
                    C = np.broadcast_to(np.eye(A.shape[1]), A.shape)
                eliminated = _Rotations.of(a0, C[0:2 * q:2], a1, C[1:2 * q:2], g0, g1)
                if eliminated is None:
                    return None
                level, A2, C2, G2 = eliminated
            levels.append((level, odd))
            if odd:
                A2, G2 = np.concatenate([A2, A[-1:]]), np.concatenate([G2, G[-1:]])
                C2 = None if C2 is None else np.concatenate([C2, C[-1:]])
            A, C, G = A2, C2, G2
        return cls(levels, (A, C, G))

    def bordered(self, Bv, By):
        """``(shares, lu)``: per level the border rows' share of its eliminated points,
        and the LU of the dense system of the ``L`` equations left with the border rows
        (``L n + k``); None when it is singular. ``Bv``: ``(N, k, n)``, ``By``: ``(k, k)``."""
        N, k, n = Bv.shape
        B = np.concatenate([Bv, np.zeros((1, k, n))])     # point N (= point 0): none yet
        By, shares = By.copy(), []
        for level, odd in self.levels:
            q = (B.shape[0] - 1) // 2
            kept = B[0::2].copy() if not odd else np.concatenate([B[0:2 * q + 1:2], B[-1:]])
            shares.append(level.border(B[1:2 * q:2], kept, By))
            B = kept
        A, C, G = self.last
        L = A.shape[0]
        B[0] += B[L]                                        # point L is point 0
        final = np.zeros((1, L * n + k, L * n + k))
        F, j = final[0, :L * n, :L * n].reshape(L, n, L, n), np.arange(L)
        F[j, :, j] = A
        F[j, :, (j + 1) % L] += np.eye(n) if C is None else C
        final[0, :L * n, L * n:] = G.reshape(L * n, k)
        final[0, L * n:, :L * n] = B[:L].transpose(1, 0, 2).reshape(k, L * n)
        final[0, L * n:, L * n:] = By
        lu = StackLU.of(final, overwrite=True)
        return None if lu is None else (shares, lu)

    def solve(self, bordered, z: np.ndarray, s: np.ndarray) -> tuple:
        """``(v, y)`` for right-hand sides ``z`` (``(N, n, r)``) and ``s`` (``(k, r)``),
        with the factors ``bordered`` of :meth:`bordered`; ``v``: ``(N, n, r)``."""
        shares, lu = bordered
        n, saved = z.shape[1], []
        for (level, odd), share in zip(self.levels, shares):       # forward
            q = z.shape[0] // 2
            new, s, kept = level.forward(z[0:2 * q:2], z[1:2 * q:2], s, share)
            z = np.concatenate([new, z[-1:]]) if odd else new
            saved.append(kept)
        L, r = z.shape[0], z.shape[2]
        x = lu.solve(np.concatenate([z.reshape(L * n, r), s])[None])[0]
        vals, y = np.empty((L + 1, n, r)), x[L * n:]                # v_0 .. v_L = v_0
        vals[:L], vals[L] = x[:L * n].reshape(L, n, r), x[:n]
        for (level, odd), kept in zip(reversed(self.levels), reversed(saved)):
            q = kept.shape[0]
            out = np.empty((2 * q + 1 + odd, n, r))
            out[0:2 * q + 1:2] = vals[:q + 1]
            out[1:2 * q:2] = level.back(kept, vals[:q], vals[1:q + 1], y)
            if odd:
                out[-1] = vals[-1]
            vals = out
        return vals[:-1], y


@dataclass(frozen=True, eq=False)
class _Pivots:
    """Pairs ``a0 v_0 + v_1 + g0 y = z_0``, ``a1 v_1 + v_2 + g1 y = z_1`` freed of
    ``v_1 = z_0 - a0 v_0 - g0 y`` by its identity pivot: ``-a1 a0 v_0 + v_2 + (g1 - a1
    g0) y = z_1 - a1 z_0``. Stacks over the pairs."""

    a0: np.ndarray
    a1: np.ndarray
    g0: np.ndarray

    def border(self, mid, kept, By) -> np.ndarray:
        """Frees the border rows ``mid`` (on the eliminated points) of them: updates
        ``kept`` (on the kept points) and ``By`` in place; the rows' share of ``z``,
        ``(k, q n)``."""
        q = mid.shape[0]
        kept[:q] -= mid @ self.a0
        By -= np.einsum("qkn,qnc->kc", mid, self.g0)
        return mid.transpose(1, 0, 2).reshape(mid.shape[1], -1)

    def forward(self, z0, z1, s, share) -> tuple:
        """``(z', s', z0)``: the new equations' right-hand sides, the border rows'."""
        s = s - share @ z0.reshape(-1, z0.shape[2])
        return z1 - self.a1 @ z0, s, z0

    def back(self, z0, v_left, v_right, y) -> np.ndarray:
        """The eliminated points from their neighbours."""
        return z0 - self.a0 @ v_left - self.g0 @ y


@dataclass(frozen=True, eq=False)
class _Rotations:
    """Pairs ``a0 v_0 + c0 v_1 + g0 y = z_0``, ``a1 v_1 + c1 v_2 + g1 y = z_1`` freed of
    ``v_1`` by the QR of ``[c0; a1] = Q R``: ``Qb`` (the last ``n`` rows of ``Q^T``, the
    new equation), ``H = R^-1 Q_top^T`` and ``Zt = R^-1 Q_top^T [left, right, y]`` (the
    point from its neighbours), stacks over the pairs."""

    Qb: np.ndarray
    H: np.ndarray
    Zt: np.ndarray

    @classmethod
    def of(cls, a0, c0, a1, c1, g0, g1):
        """``(rotations, A2, C2, G2)``: the eliminations and the new equations; None when
        an ``R`` is numerically rank-deficient (``|R_jj| <= n eps max |R_ii|``)."""
        n = a0.shape[1]
        Q, R = np.linalg.qr(np.concatenate([c0, a1], axis=1), mode="complete")
        d = np.abs(np.diagonal(R[:, :n], axis1=1, axis2=2))
        if not (np.all(np.isfinite(d)) and np.all(d.min(axis=1) > n * np.finfo(float).eps
                                                   * d.max(axis=1))):
            return None
        Qt = Q.transpose(0, 2, 1)            # Q^T W, W = [I | a0, 0, g0; 0, c1, g1]
        QtW = np.concatenate([Qt, Qt[:, :, :n] @ a0, Qt[:, :, n:] @ c1,
                              Qt[:, :, :n] @ g0 + Qt[:, :, n:] @ g1], axis=2)
        top = np.linalg.solve(R[:, :n], QtW[:, :n])        # R^-1 Q_top^T W
        bottom = QtW[:, n:]
        return (cls(bottom[:, :, :2 * n], top[:, :, :2 * n], top[:, :, 2 * n:]),
                bottom[:, :, 2 * n:3 * n], bottom[:, :, 3 * n:4 * n], bottom[:, :, 4 * n:])

    def border(self, mid, kept, By) -> np.ndarray:
        q, n = self.H.shape[:2]
        Bz = mid @ self.Zt                                  # the border rows once mid is gone
        kept[:q] -= Bz[:, :, :n]
        kept[1:q + 1] -= Bz[:, :, n:2 * n]
        By -= Bz[:, :, 2 * n:].sum(axis=0)
        return mid @ self.H

    def forward(self, z0, z1, s, share) -> tuple:
        ZP = np.concatenate([z0, z1], axis=1)                           # (q, 2n, r)
        return self.Qb @ ZP, s - np.einsum("qkc,qcr->kr", share, ZP), ZP

    def back(self, ZP, v_left, v_right, y) -> np.ndarray:
        n = self.H.shape[1]
        Zt = self.Zt
        return self.H @ ZP - Zt[:, :, :n] @ v_left - Zt[:, :, n:2 * n] @ v_right - \
            Zt[:, :, 2 * n:] @ y


def _bounded(a1, a0) -> bool:
    """Whether the Perron root of ``B = |a1| |a0|`` is at most :data:`UNIT_GROWTH` for
    every pair, by an upper bound (Collatz-Wielandt, ``max_i (B x)_i / x_i`` after power
    steps from ``x = 1``, at most six): ``|B|_inf`` in a diagonal scaling, which judges
    badly scaled states (modal displacements, velocities) fairly. The rounding of
    ``a1 a0`` is then at most a few eps of the identity's scale."""
    a1, a0 = np.abs(a1), np.abs(a0)
    y = a1 @ a0.sum(axis=2, keepdims=True)                  # B x, x = 1
    bound = y.max(axis=(1, 2))
    for _ in range(5):
        if np.all(bound <= UNIT_GROWTH):
            return True
        x = y / np.maximum(y.max(axis=1, keepdims=True), 1e-300) + 1e-12
        y = a1 @ (a0 @ x)
        bound = np.minimum(bound, (y / x).max(axis=(1, 2)))
    return bool(np.all(bound <= UNIT_GROWTH))
