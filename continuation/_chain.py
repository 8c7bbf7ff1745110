"""The cyclic chain of the mesh points of a condensed collocated cycle (``_condensed``),
reduced pairwise by QR, level by level, every level one batched NumPy call per step."""

from __future__ import annotations

import numpy as np

from ._stacks import StackLU

#: the largest growth ``rho(|a1| |a0|)`` (:func:`_scaled_growth`) of a pair eliminated
#: by its identity pivot; a larger one takes the QR
UNIT_GROWTH = 16.0


class Chain:
    """The cyclic chain ``A_i v_i + C_i v_{i+1} + G_i y = z_i`` (``i < N``,
    ``v_N = v_0``) reduced pairwise: equations ``2j`` and ``2j + 1`` share the point
    ``2j + 1``, which a QR of its stacked column ``[C_2j; A_2j+1]`` eliminates (the top
    rows give it from its neighbours, the bottom ``n`` rows a new equation between
    ``v_2j`` and ``v_2j+2``); ``log2 N`` levels (an odd last equation carried to the
    next) leave ``(A + C) v_0 + G y = z``. Stable like a QR of each pair (no recursion
    over transfer maps). Per level, for each pair: ``Qb`` (the last ``n`` rows of
    ``Q^T``, the new equation), ``H = R^-1 Q_top^T`` and ``Zt = R^-1 Q_top^T [left,
    right, y]`` (the point from its neighbours), each a stack over the level's pairs.
    The ``k`` border rows ``sum_i Bv_i v_i + By y = s`` that make the system square
    (:meth:`bordered`) follow the eliminations, and with the last equation form an
    ``n + k`` dense system.

    When every ``C_i`` is the identity (the condensed chain, ``C = None``), a pair whose
    ``C_2j`` is still the identity and whose maps are bounded (:data:`UNIT_GROWTH`) is
    freed of its point by that pivot instead of a QR: one product of two adjacent
    transfer maps, ``v_2j+2 = a_2j+1 a_2j v_2j + ...``, as multiple shooting over pairs
    of intervals does. Half the pairs are on the first level: this halves the
    reduction's cost."""

    def __init__(self, levels, last):
        #: per level ``(Qb, H, Zt, odd)``; the last equation ``(A + C, G)``
        self.levels, self.last = levels, last

    @classmethod
    def of(cls, A, C, G):
        """``A, C``: ``(N, n, n)``, ``C`` None for identities (the condensed chain);
        ``G``: ``(N, n, k)``. None when a pair's column is rank-deficient."""
        n, levels = A.shape[1], []
        ident = np.full(A.shape[0], C is None)          # whether C_i is the identity
        if C is None:
            C = np.broadcast_to(np.eye(n), A.shape)
        while A.shape[0] > 1:
            q, odd = divmod(A.shape[0], 2)
            a0, c0, g0 = A[0:2 * q:2], C[0:2 * q:2], G[0:2 * q:2]
            a1, c1, g1 = A[1:2 * q:2], C[1:2 * q:2], G[1:2 * q:2]
            pivot = ident[0:2 * q:2].copy()
            if pivot.any():
                pivot[pivot] = _bounded(a1[pivot], a0[pivot])
            Qb = np.zeros((q, n, 2 * n))
            H, Zt = np.zeros((q, n, 2 * n)), np.zeros((q, n, 2 * n + G.shape[2]))
            A2, C2, G2 = np.empty_like(a0), c1.copy(), np.empty_like(g0)
            if pivot.any():                  # v_1 = z_0 - a0 v_0 - g0 y, by the identity
                a1p = a1[pivot]
                Qb[pivot, :, :n], Qb[pivot, :, n:] = -a1p, np.eye(n)
                H[pivot, :, :n] = np.eye(n)
                Zt[pivot, :, :n], Zt[pivot, :, 2 * n:] = a0[pivot], g0[pivot]
                A2[pivot], G2[pivot] = -a1p @ a0[pivot], g1[pivot] - a1p @ g0[pivot]
            qr = ~pivot
            if qr.any():
                factors = _qr_eliminate(c0[qr], a1[qr], a0[qr], c1[qr], g0[qr], g1[qr])
                if factors is None:
                    return None
                Qb[qr], H[qr], Zt[qr], A2[qr], C2[qr], G2[qr] = factors
            levels.append((Qb, H, Zt, odd))
            ident2 = pivot & ident[1:2 * q:2]           # C2 = c1 where eliminated by pivot
            if odd:
                A2, C2, G2, ident2 = (np.concatenate([X2, X[-1:]]) for X2, X in
                                      ((A2, A), (C2, C), (G2, G), (ident2, ident)))
            A, C, G, ident = A2, C2, G2, ident2
        return cls(levels, (A[0] + C[0], G[0]))

    def bordered(self, Bv, By):
        """``(shares, lu)``: per level and pair the border rows' share ``Bv_mid H`` of the
        eliminated point, and the LU of the final ``n + k`` system; None when it is
        singular. ``Bv``: ``(N, k, n)``, ``By``: ``(k, k)``."""
        N, k, n = Bv.shape
        B = np.concatenate([Bv, np.zeros((1, k, n))])     # point N (= point 0): none yet
        By, shares = By.copy(), []
        for Qb, H, Zt, odd in self.levels:
            q = H.shape[0]
            mid = B[1:2 * q:2]
            Bz = mid @ Zt                                 # the border rows once mid is gone
            kept = B[0::2].copy() if not odd else np.concatenate([B[0:2 * q + 1:2],
                                                                   B[-1:]])
            kept[:q] -= Bz[:, :, :n]
            kept[1:q + 1] -= Bz[:, :, n:2 * n]
            By -= Bz[:, :, 2 * n:].sum(axis=0)
            shares.append(mid @ H)
            B = kept
        AC, G0 = self.last
        final = np.block([[AC, G0], [B[0] + B[1], By]])
        lu = StackLU.of(final[None], overwrite=True)
        return None if lu is None else (shares, lu)

    def solve(self, bordered, z: np.ndarray, s: np.ndarray) -> tuple:
        """``(v, y)`` for right-hand sides ``z`` (``(N, n, r)``) and ``s`` (``(k, r)``),
        with the factors ``bordered`` of :meth:`bordered`; ``v``: ``(N, n, r)``."""
        shares, lu = bordered
        n = z.shape[1]
        stacked = []                                       # forward: the new equations
        for (Qb, H, Zt, odd), share in zip(self.levels, shares):
            q = H.shape[0]
            ZP = np.concatenate([z[0:2 * q:2], z[1:2 * q:2]], axis=1)    # (q, 2n, r)
            s = s - np.einsum("qkc,qcr->kr", share, ZP)
            new = Qb @ ZP
            z = np.concatenate([new, z[-1:]]) if odd else new
            stacked.append(ZP)
        x = lu.solve(np.concatenate([z[0], s])[None])[0]
        v0, y = x[:n], x[n:]
        vals = np.stack([v0, v0])                          # the points v_0 and v_N = v_0
        for (Qb, H, Zt, odd), ZP in zip(reversed(self.levels), reversed(stacked)):
            q = H.shape[0]
            out = np.empty((2 * q + 1 + odd,) + v0.shape)
            out[0:2 * q + 1:2] = vals[:q + 1]
            out[1:2 * q:2] = H @ ZP - Zt[:, :, :n] @ vals[:q] - Zt[:, :, n:2 * n] @ \
                vals[1:q + 1] - Zt[:, :, 2 * n:] @ y
            if odd:
                out[-1] = vals[-1]
            vals = out
        return vals[:-1], y


def _qr_eliminate(c0, a1, a0, c1, g0, g1):
    """``(Qb, H, Zt, A2, C2, G2)`` of pairs ``a0 v_0 + c0 v_1 + g0 y = z_0``, ``a1 v_1 +
    c1 v_2 + g1 y = z_1`` (stacks over the pairs) freed of ``v_1`` by the QR of
    ``[c0; a1] = Q R``; None when an ``R`` is numerically rank-deficient (``|R_jj| <= n
    eps max |R_ii|``)."""
    q, n, k = a0.shape[0], a0.shape[1], g0.shape[2]
    Q, R = np.linalg.qr(np.concatenate([c0, a1], axis=1), mode="complete")
    d = np.abs(np.diagonal(R[:, :n], axis1=1, axis2=2))
    if not (np.all(np.isfinite(d)) and np.all(d.min(axis=1) > n * np.finfo(float).eps
                                               * d.max(axis=1))):
        return None
    W = np.zeros((q, 2 * n, 4 * n + k))                    # [I | a0, 0, g0; 0, c1, g1]
    W[:, :, :2 * n] = np.eye(2 * n)
    W[:, :n, 2 * n:3 * n], W[:, n:, 3 * n:4 * n] = a0, c1
    W[:, :n, 4 * n:], W[:, n:, 4 * n:] = g0, g1
    QtW = Q.transpose(0, 2, 1) @ W
    top = np.linalg.solve(R[:, :n], QtW[:, :n])            # R^-1 Q_top^T W
    bottom = QtW[:, n:]
    return (bottom[:, :, :2 * n], top[:, :, :2 * n], top[:, :, 2 * n:],
            bottom[:, :, 2 * n:3 * n], bottom[:, :, 3 * n:4 * n], bottom[:, :, 4 * n:])


def _bounded(a1, a0) -> np.ndarray:
    """Per pair, whether the Perron root of ``B = |a1| |a0|`` is at most
    :data:`UNIT_GROWTH`, by an upper bound (Collatz-Wielandt, ``max_i (B x)_i / x_i``
    after power steps from ``x = 1``, at most six): ``|B|_inf`` in a diagonal scaling,
    which judges badly scaled states (modal displacements, velocities) fairly. The
    rounding of ``a1 a0`` is then at most a few eps of the identity's scale."""
    a1, a0 = np.abs(a1), np.abs(a0)
    x = np.ones(a0.shape[:2] + (1,))
    bound = np.full(a0.shape[0], np.inf)
    for _ in range(6):
        y = a1 @ (a0 @ x)
        bound = np.minimum(bound, (y / x).max(axis=(1, 2)))
        if np.all(bound <= UNIT_GROWTH):
            break
        x = y / np.maximum(y.max(axis=1, keepdims=True), 1e-300) + 1e-12
    return bound <= UNIT_GROWTH
