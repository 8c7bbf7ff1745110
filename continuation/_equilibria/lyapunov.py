"""First Lyapunov coefficient of a Hopf point of ``M(x) xdot = F(x)``.

Write ``xdot = f(x) = G(x) F(x)`` with ``G = M^{-1}``. At an equilibrium
(``F = 0``), with ``J = F_x``, ``A = f_x = G J``, ``M1(u) = D_x M[u]``,
``M2(u, v) = D_x^2 M[u, v]`` and ``F2, F3`` the multilinear derivatives of F:

    M B_f(u, v)    = b(u, v) = F2(u, v) - M1(u) A v - M1(v) A u
    M C_f(u, v, w) = c(u, v, w) = F3(u, v, w)
                     - M1(u) G F2(v, w) - M1(v) G F2(u, w) - M1(w) G F2(u, v)
                     + sum over {(u,v;w), (u,w;v), (v,w;u)} of
                       [M1(a) G M1(b) + M1(b) G M1(a) - M2(a, b)] A c

(from ``D G[u] = -G M1(u) G`` and
``D^2 G[u, v] = G M1(u) G M1(v) G + G M1(v) G M1(u) G - G M2(u, v) G``).
With ``J q = i omega M q``, ``|q| = 1``, ``phi^T J = i omega phi^T M`` and
``phi^T M q = 1`` (so ``p^H = phi^T M`` is Kuznetsov's left eigenvector of A
with ``<p, q> = 1``), Kuznetsov's formula (Elements of Applied Bifurcation
Theory, 3rd ed., eq. (3.20)/(5.39)) becomes

    l1 = Re[ phi^T c(q, q, qbar) - 2 phi^T b(q, h11) + phi^T b(qbar, h20) ] / (2 omega)
    h11 = J^{-1} b(q, qbar),        A h11 = M^{-1} b(q, qbar)
    h20 = (2 i omega M - J)^{-1} b(q, q),  A h20 = 2 i omega h20 - M^{-1} b(q, q)

and ``A q = i omega q``. When ``M`` does not depend on ``x`` the ``M1, M2``
terms vanish and ``M^{-1}`` is never needed: the formula then also holds for
a constant *singular* ``M`` (semi-explicit index-1 DAEs), which is what the
centre-manifold reduction onto the algebraic constraint gives. The value
depends on the scaling ``|q| = 1``; for
``xdot = mu x - omega y + a x r^2, ydot = omega x + mu y + a y r^2`` it is
``l1 = 2 a / omega``.
"""

from __future__ import annotations

import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .eigen import eigenvector, left_eigenvector
from .._casadi.vectorfield import VectorField


def hopf_eigenvectors(J, M, omega: float):
    """``q`` (``|q| = 1``) and ``phi`` (``phi^T M q = 1``) at ``lambda = i omega``."""
    lam = 1j * omega
    q = eigenvector(J, M, lam)
    phi = left_eigenvector(J, M, lam)
    phi = phi / (phi @ (M @ q))
    return q, phi


def first_lyapunov(vf: VectorField, x, p, omega: float) -> float:
    """First Lyapunov coefficient ``l1`` of the Hopf point ``(x, p, omega)``."""
    J = sp.csc_matrix(vf.jac_x(x, p), dtype=complex)
    M = sp.csc_matrix(vf.mass(x, p), dtype=complex)
    q, phi = hopf_eigenvectors(J, M, omega)
    ctx = _Context(vf, x, p, M)
    qb = q.conj()
    Aq, Aqb = 1j * omega * q, -1j * omega * qb
    b11 = ctx.b(q, Aq, qb, Aqb)
    b20 = ctx.b(q, Aq, q, Aq)
    h11 = spla.splu(J).solve(b11)
    h20 = spla.splu(sp.csc_matrix(2j * omega * M - J)).solve(b20)
    Ah11 = ctx.G(b11)
    Ah20 = 2j * omega * h20 - ctx.G(b20)
    c = ctx.c((q, Aq), (q, Aq), (qb, Aqb))
    total = phi @ c - 2 * phi @ ctx.b(q, Aq, h11, Ah11) + phi @ ctx.b(qb, Aqb, h20, Ah20)
    return float(total.real / (2 * omega))


class _Context:
    """Multilinear forms ``b`` and ``c`` of M times the derivatives of ``f``."""

    def __init__(self, vf, x, p, M):
        self.vf, self.x, self.p = vf, x, p
        self.identity = not vf.mass_depends_on_state  # M1 = M2 = 0
        self._M, self._lu = M, None

    def G(self, y):
        """``M^{-1} y`` (only needed, and M only required invertible, when M
        depends on x; with a constant M the terms ``A h`` are multiplied by zero)."""
        if self.identity:
            return 0 * y
        if self._lu is None:
            self._lu = spla.splu(self._M)
        return self._lu.solve(y)

    def F2(self, u, v):
        return self.vf.form("F2", self.x, self.p, u, v)

    def M1(self, u, y):
        return 0 * y if self.identity else self.vf.form("M1", self.x, self.p, u, y)

    def M2(self, u, v, y):
        return 0 * y if self.identity else self.vf.form("M2", self.x, self.p, u, v, y)

    def b(self, u, Au, v, Av):
        """``b(u, v) = F2(u, v) - M1(u) A v - M1(v) A u``."""
        return self.F2(u, v) - self.M1(u, Av) - self.M1(v, Au)

    def c(self, U, V, W):
        """``c(u, v, w)``; each argument is a pair ``(u, A u)``."""
        (u, _), (v, _), (w, _) = U, V, W
        out = self.vf.form("F3", self.x, self.p, u, v, w)
        if self.identity:
            return out
        for a, (b1, b2) in ((u, (v, w)), (v, (u, w)), (w, (u, v))):
            out = out - self.M1(a, self.G(self.F2(b1, b2)))
        for (a, _), (b, _), (_, Ac) in ((U, V, W), (U, W, V), (V, W, U)):
            out = out + self.M1(a, self.G(self.M1(b, Ac))) \
                + self.M1(b, self.G(self.M1(a, Ac))) - self.M2(a, b, Ac)
        return out
