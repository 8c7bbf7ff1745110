"""Normal-form coefficients of the codimension-two points of Hopf curves.

Everything is computed for ``M y' = h(y)``: the constant mass ``M = M(x0)`` of the point
and the field ``h(y) = M(x0) M(y)^{-1} F(y)`` (the same flow as ``M(y) y' = F(y)``;
``h = F`` when ``M`` is constant, which may then be singular). ``B, C, D, E`` are the
multilinear forms of ``h`` of order 2 to 5 (``VectorField`` forms ``H2 .. H5``, by CasADi
AD), ``J = F_x``. At an eigenvalue ``i w``: ``J q = i w M q``, ``|q| = 1``,
``phi^T (J - i w M) = 0``, ``phi^T M q = 1`` (``phi^T M`` is Kuznetsov's ``p^H``).

Generalized Hopf (Kuznetsov, Elements of Applied Bifurcation Theory, 3rd ed., §8.3 and
eq. (8.23)): the centre manifold ``y = z q + zbar qbar + sum h_jk z^j zbar^k / (j! k!)``
with the normal form ``z' = i w z + c1 z |z|^2 + c2 z |z|^4`` gives

    (2 i w M - J) h20 = B(q, q),   -J h11 = B(q, qbar),
    (3 i w M - J) h30 = C(q, q, q) + 3 B(q, h20),
    c1 = phi^T R21 / 2,   (i w M - J) h21 = R21 - 2 c1 M q,   phi^T M h21 = 0,
    (2 i w M - J) h31 = R31 - 6 c1 M h20,   -J h22 = R22 - 8 Re(c1) M h11,
    c2 = phi^T R32 / 12,   l1 = Re c1 / w,   l2 = Re c2 / w,

with ``R21 = C(q,q,qb) + B(qb,h20) + 2 B(q,h11)`` and ``R31, R22, R32`` the coefficients of
``z^3 zb, z^2 zb^2, z^3 zb^2`` in ``h(y)`` (below, ``qb = qbar``, ``g = conj(h20)``,
``k = conj(h21)``). For ``w1 = x1 + i x2``, ``w1' = (mu + i w) w1 + a w1|w1|^2 +
b w1|w1|^4`` (``|q| = 1``: ``w1 = sqrt 2 z``): ``l1 = 2 a / w``, ``l2 = 4 b / w``.

Double Hopf (ELBT §8.6, eq. (8.103)): two pairs ``i w1, i w2`` with ``q1, q2``; the normal
form ``z1' = i w1 z1 + G2100 z1|z1|^2 + G1011 z1|z2|^2``, ``z2' = i w2 z2 + G1110 z2|z1|^2
+ G0021 z2|z2|^2`` gives the amplitude equations ``r1' = r1 (mu1 + p11 r1^2 + p12 r2^2)``,
``r2' = r2 (mu2 + p21 r1^2 + p22 r2^2)`` with ``p_jk = Re G``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .eigen import eigenvector, left_eigenvector
from .lyapunov import hopf_eigenvectors


class Centre:
    """The forms and solves at an equilibrium ``(x, p)`` of ``vf``."""

    def __init__(self, vf, x, p):
        self.vf, self.x, self.p = vf, np.asarray(x, float), np.asarray(p, float)
        self.J = sp.csc_matrix(vf.jac_x(x, p), dtype=complex)
        self.M = sp.csc_matrix(vf.mass(x, p), dtype=complex)

    def form(self, *vectors) -> np.ndarray:
        """``B(u, v)``, ``C(u, v, w)``, ... by the number of arguments."""
        return self.vf.form(f"H{len(vectors)}", self.x, self.p, *vectors)

    def solve(self, lam: complex, rhs) -> np.ndarray:
        """``(lam M - J)^{-1} rhs``."""
        return spla.splu(sp.csc_matrix(lam * self.M - self.J)).solve(rhs)

    def pair(self, omega: float):
        """``q, phi`` of ``i omega`` (``|q| = 1``, ``phi^T M q = 1``)."""
        return hopf_eigenvectors(self.J, self.M, omega)

    def bordered(self, omega: float, q, phi, rhs) -> np.ndarray:
        """``h`` with ``(i w M - J) h = rhs``, ``phi^T M h = 0`` (``rhs`` in the range)."""
        n, Mq, pM = self.J.shape[0], self.M @ q, self.M.T @ phi
        A = sp.bmat([[1j * omega * self.M - self.J, Mq[:, None]], [pM[None, :], None]],
                    format="csc")
        return spla.splu(A).solve(np.append(rhs, 0.0))[:n]


def lyapunov_coefficients(vf, x, p, omega: float) -> dict:
    """``{'l1', 'l2'}`` of the Hopf point ``(x, p)`` of frequency ``omega``."""
    c = Centre(vf, x, p)
    q, phi = c.pair(omega)
    h = _second_order(c, omega, q)
    c1, h21 = _third_order(c, omega, q, phi, h)
    h.update(h21=h21)
    return {"l1": float(c1.real / omega), "l2": float(_c2(c, omega, q, phi, c1, h).real / omega)}


def _second_order(c: Centre, omega, q) -> dict:
    qb = q.conj()
    h20 = c.solve(2j * omega, c.form(q, q))
    h11 = c.solve(0.0, c.form(q, qb))
    h30 = c.solve(3j * omega, c.form(q, q, q) + 3 * c.form(q, h20))
    return {"h20": h20, "h11": h11, "h30": h30}


def _third_order(c: Centre, omega, q, phi, h):
    """``c1`` and ``h21``."""
    qb = q.conj()
    r21 = c.form(q, q, qb) + c.form(qb, h["h20"]) + 2 * c.form(q, h["h11"])
    c1 = phi @ r21 / 2
    return c1, c.bordered(omega, q, phi, r21 - 2 * c1 * (c.M @ q))


def _c2(c: Centre, omega, q, phi, c1, h) -> complex:
    """``c2 = phi^T R32 / 12`` after ``h31, h22``."""
    F, qb, Mx = c.form, q.conj(), c.M
    h20, h11, h30, h21 = h["h20"], h["h11"], h["h30"], h["h21"]
    g, k = h20.conj(), h21.conj()
    r31 = F(q, q, q, qb) + 3 * F(q, q, h11) + 3 * F(q, qb, h20) + 3 * F(h20, h11) \
        + F(qb, h30) + 3 * F(q, h21)
    h31 = c.solve(2j * omega, r31 - 6 * c1 * (Mx @ h20))
    r22 = F(q, q, qb, qb) + 4 * F(q, qb, h11) + F(qb, qb, h20) + F(q, q, g) \
        + 2 * F(h11, h11) + 2 * F(q, k) + 2 * F(qb, h21) + F(h20, g)
    h22 = c.solve(0.0, r22 - 8 * c1.real * (Mx @ h11))
    r32 = F(q, q, q, qb, qb) + F(q, q, q, g) + 3 * F(q, qb, qb, h20) + 6 * F(q, q, qb, h11) \
        + F(qb, qb, h30) + 3 * F(q, q, k) + 6 * F(q, qb, h21) + 3 * F(q, g, h20) \
        + 6 * F(q, h11, h11) + 6 * F(qb, h20, h11) + 2 * F(qb, h31) + 3 * F(q, h22) \
        + F(g, h30) + 3 * F(k, h20) + 6 * F(h11, h21)
    return complex(phi @ r32 / 12)


def double_hopf_coefficients(vf, x, p, omega1: float, omega2: float) -> dict:
    """``p11, p12, p21, p22``, ``theta = p12 / p22``, ``delta = p21 / p11``, whether the
    case is ``simple`` (``p11 p22 > 0``) and whether the amplitude equations have a
    ``stable_torus`` (``r1, r2 > 0``: ``det [p] > 0`` and ``min(p11, p22) < 0``: stable
    two-frequency motion on one side of the point; in the difficult case fifth-order
    terms decide what happens to it further away)."""
    c = Centre(vf, x, p)
    (q1, f1), (q2, f2) = c.pair(omega1), c.pair(omega2)
    B, a, b = c.form, q1.conj(), q2.conj()
    h2000, h1100 = c.solve(2j * omega1, B(q1, q1)), c.solve(0.0, B(q1, a))
    h0020, h0011 = c.solve(2j * omega2, B(q2, q2)), c.solve(0.0, B(q2, b))
    h1010 = c.solve(1j * (omega1 + omega2), B(q1, q2))
    h1001 = c.solve(1j * (omega1 - omega2), B(q1, b))
    g2100 = f1 @ (B(q1, q1, a) + B(h2000, a) + 2 * B(h1100, q1)) / 2
    g1011 = f1 @ (B(q1, q2, b) + B(h1010, b) + B(h1001, q2) + B(h0011, q1))
    g1110 = f2 @ (B(q1, a, q2) + B(h1100, q2) + B(h1010, a) + B(h1001.conj(), q1))
    g0021 = f2 @ (B(q2, q2, b) + B(h0020, b) + 2 * B(h0011, q2)) / 2
    p11, p12, p21, p22 = (float(g.real) for g in (g2100, g1011, g1110, g0021))
    return {"omega1": float(omega1), "omega2": float(omega2), "p11": p11, "p12": p12,
            "p21": p21, "p22": p22, "theta": p12 / p22, "delta": p21 / p11,
            "simple": bool(p11 * p22 > 0),
            "stable_torus": bool(p11 * p22 - p12 * p21 > 0 and min(p11, p22) < 0)}


def bogdanov_takens_coefficients(vf, x, p) -> dict:
    """``a, b`` of ``w0' = w1, w1' = a w0^2 + b w0 w1`` at a Bogdanov-Takens point
    (ELBT §8.4, eq. (8.52)): with the Jordan chains ``J q0 = 0, J q1 = M q0`` and
    ``phi1^T J = 0, phi0^T J = phi1^T M``, normalized ``|q0| = 1`` (largest entry
    positive), ``q0^T q1 = 0``, ``phi1^T M q1 = 1``, ``phi0^T M q1 = 0``,

        a = phi1^T B(q0, q0) / 2,   b = phi0^T B(q0, q0) + phi1^T B(q0, q1).

    (``q0 -> -q0`` flips both signs; ``sign(a b)`` is invariant.)"""
    c = Centre(vf, x, p)
    J, M = c.J.real.tocsc(), c.M.real.tocsc()
    U, _, Vt = np.linalg.svd(J.toarray())              # null vectors (dense SVD)
    q0, phi1 = Vt[-1] * np.sign(Vt[-1][np.argmax(np.abs(Vt[-1]))]), U[:, -1]
    q1 = _bordered_real(J, phi1, q0, M @ q0)
    phi0 = _bordered_real(J.T, q0, phi1, M.T @ phi1)
    scale = phi1 @ (M @ q1)
    phi1, phi0 = phi1 / scale, phi0 / scale
    phi0 = phi0 - (phi0 @ (M @ q1)) * phi1
    B00 = c.form(q0, q0).real
    return {"a": float(phi1 @ B00 / 2),
            "b": float(phi0 @ B00 + phi1 @ c.form(q0, q1).real)}


def _bordered_real(A, column, row, rhs) -> np.ndarray:
    """``y`` with ``A y + s column = rhs``, ``row^T y = 0`` (``A`` singular of rank n-1)."""
    K = sp.bmat([[A, column[:, None]], [row[None, :], None]], format="csc")
    return spla.splu(K).solve(np.append(rhs, 0.0))[:-1]


def zero_hopf_coefficients(vf, x, p, omega: float) -> dict:
    """``B, C, D`` of the truncated zero-Hopf normal form (ELBT §8.5, eq. (8.79))
    ``u' = B u^2 + C |z|^2``, ``z' = i omega z + D u z``, and Kuznetsov's ``s = sign(B C)``,
    ``theta = Re D / B``: with ``J q0 = 0`` (``|q0| = 1``, largest entry positive),
    ``phi0^T J = 0``, ``phi0^T M q0 = 1`` and ``q, phi`` of ``i omega``,

        B = phi0^T B(q0, q0) / 2,   C = phi0^T B(q, qbar),   D = phi^T B(q0, q).

    In the amplitude equations ``u' = b1 + u^2 + s r^2``, ``r' = r (b2 + theta u)`` the
    cycle's equilibrium has ``det = -2 s theta r^2``: a torus (a Neimark-Sacker curve of
    the cycles) can be born near the point only when ``s theta < 0``."""
    c = Centre(vf, x, p)
    q0 = _real(eigenvector_at_zero(c.J, c.M, left=False))
    phi0 = _real(eigenvector_at_zero(c.J, c.M, left=True))
    phi0 = phi0 / (phi0 @ (c.M.real @ q0))
    q, phi = c.pair(omega)
    b = float(phi0 @ c.form(q0, q0).real / 2)
    cc = float((phi0 @ c.form(q, q.conj())).real)
    d = complex(phi @ c.form(q0, q))
    return {"B": b, "C": cc, "D_re": d.real, "D_im": d.imag,
            "s": float(np.sign(b * cc)), "theta": d.real / b}


def eigenvector_at_zero(J, M, left: bool) -> np.ndarray:
    """Right (or left, ``phi^T J = 0``) null vector of ``J`` by inverse iteration."""
    return (left_eigenvector if left else eigenvector)(J, M, 0.0)


def _real(v) -> np.ndarray:
    """``v`` rotated to its largest entry real positive, real part, ``|v| = 1``."""
    v = v * np.exp(-1j * np.angle(v[np.argmax(np.abs(v))]))
    return v.real / np.linalg.norm(v.real)
