"""Timoshenko modes of a beam of non-uniform thickness (locking-free FE), any ends.

Thickness t(x) relative to the root (t(0) = 1), root slenderness s = e(0)/L, units of
the root (:mod:`.beam_timoshenko`): mass t, rotary inertia r^2 t^3, bending stiffness
t^3 and shear stiffness S t, with ``S = 6 kappa (1 - nu) / s^2`` and ``r^2 = s^2 / 12``.
Weak form of the cantilever, w(0) = psi(0) = 0 (the free-end conditions are natural;
other ends of :data:`fsicas.scene.BEAM_ENDS` hold w and, when clamped, psi at their
end, :func:`_held_dofs`)::

    ∫ t^3 psi' dpsi' + S t (w' - psi)(dw' - dpsi) dx
        = omega^2 ∫ t w dw + r^2 t^3 psi dpsi dx.

Elements: w continuous of degree P + 1, psi continuous of degree P (P = 4, Lagrange on
Gauss–Lobatto points). Since w' and psi then lie in the same polynomial space, the
Kirchhoff constraint w' = psi of a thin beam is met exactly by the C^1 splines of degree
P + 1 in the space: no shear locking. Element integrals by 10-point Gauss–Legendre.
Modes: ``eigh(K, M)``, normalized by the full mass (``∫ t phi^2 + r^2 t^3 psi^2 = 1``),
sign phi_n(1) = (-1)^(n+1) (other ends: :func:`_orient`). ``Phi = ∫_0^x phi`` and ``Psi = ∫_x^1 phi`` are exact for
the FE shape (antiderivatives of the element polynomials, accumulated forward and
backward).
"""
from __future__ import annotations

import numpy as np
import scipy.linalg
from numpy.polynomial import legendre

from .beam import ModalBasis
from .beam_timoshenko import TimoshenkoBeam
from ..scene import CLAMPED_FREE, check_ends

__all__ = ["timoshenko_fe_modes", "timoshenko_fe_elements", "DEGREE"]

DEGREE = 4        # psi of degree 4, w of degree 5 per element
N_GAUSS = 10


def timoshenko_fe_elements(n_modes: int) -> int:
    """Default mesh: ``max(24, 2 n_modes)`` elements."""
    return max(24, 2 * int(n_modes))


def _lagrange(degree: int) -> np.ndarray:
    """Monomial coefficients (columns) of the Lagrange basis on the Gauss–Lobatto points
    of [0, 1]: ``L_j(xi) = Σ_k C[k, j] xi^k``."""
    interior = legendre.Legendre.basis(degree).deriv().roots() if degree > 1 else []
    nodes = np.r_[0.0, (np.asarray(interior) + 1.0) / 2.0, 1.0]
    return np.linalg.inv(np.vander(nodes, increasing=True))


def _eval(C: np.ndarray, xi: np.ndarray, derivative: int = 0) -> np.ndarray:
    """Basis (or its derivative in xi) at xi: shape (degree + 1, len(xi))."""
    coef = C
    for _ in range(derivative):
        coef = coef[1:] * np.arange(1, len(coef))[:, None]
    return (xi[:, None] ** np.arange(len(coef))[None, :] @ coef).T


def _integral(C: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """``∫_lo^hi L_j dxi`` (shape (degree + 1, K)) from the antiderivatives."""
    k = np.arange(C.shape[0]) + 1.0
    powers = lambda z: (z[None, :] ** k[:, None]) / k[:, None]
    return (powers(hi) - powers(lo)).T.dot(C).T


def _dofs(n_el: int, degree: int) -> np.ndarray:
    """Global DOF numbers of each element, shape (n_el, degree + 1)."""
    return np.arange(n_el)[:, None] * degree + np.arange(degree + 1)[None, :]


def _assemble(beam: TimoshenkoBeam, thickness, n_el: int, ends: str = CLAMPED_FREE):
    """Global K and M on the DOFs (w, then psi), held DOFs (:func:`_held_dofs`) removed."""
    Cw, Cp = _lagrange(DEGREE + 1), _lagrange(DEGREE)
    xg, wg = legendre.leggauss(N_GAUSS)
    xg, wg = (xg + 1) / 2, wg / 2
    Lw, dLw, Lp, dLp = _eval(Cw, xg), _eval(Cw, xg, 1), _eval(Cp, xg), _eval(Cp, xg, 1)
    nw, h = n_el * (DEGREE + 1) + 1, 1.0 / n_el
    n = nw + n_el * DEGREE + 1
    K, M = np.zeros((n, n)), np.zeros((n, n))
    S, r2 = beam.shear, beam.rotary
    for e, (dw, dp) in enumerate(zip(_dofs(n_el, DEGREE + 1), nw + _dofs(n_el, DEGREE))):
        t = np.asarray(thickness((e + xg) * h), dtype=float) * np.ones_like(xg)
        g = wg * h
        shear = np.vstack([dLw / h, -Lp])            # rows: dw', -dpsi  -> gamma
        idx = np.r_[dw, dp]
        K[np.ix_(idx, idx)] += (shear * (S * t * g)) @ shear.T
        K[np.ix_(dp, dp)] += ((dLp / h) * (t**3 * g)) @ (dLp / h).T
        M[np.ix_(dw, dw)] += (Lw * (t * g)) @ Lw.T
        M[np.ix_(dp, dp)] += (Lp * (r2 * t**3 * g)) @ Lp.T
    keep = np.setdiff1d(np.arange(n), _held_dofs(ends, nw, n))
    return K[np.ix_(keep, keep)], M[np.ix_(keep, keep)], keep, nw


def _held_dofs(ends: str, nw: int, n: int) -> list[int]:
    """The DOFs the supports hold: w(0) always, psi(0) at a clamped root, w(1) at a held
    end x = 1 and psi(1) at a clamped one (w DOFs 0..nw-1, then psi DOFs nw..n-1)."""
    root, end = ends.split("-")
    return ([0] + ([nw] if root == "clamped" else []) + ([nw - 1] if end != "free" else [])
            + ([n - 1] if end == "clamped" else []))


def _orient(full: np.ndarray, ends: str, nw: int) -> np.ndarray:
    """Signs of :mod:`.beam`: ``sign phi_n(1) = (-1)^(n+1)`` for the cantilever, else
    rising from the root (psi > 0 at the first node inside a clamped root's element,
    phi > 0 there at a pinned root)."""
    if ends == CLAMPED_FREE:
        sign = np.sign(full[:, nw - 1]) * (-1.0) ** np.arange(len(full))
    else:
        sign = np.where(full[:, 1 if ends.startswith("pinned") else nw + 1] < 0, -1.0, 1.0)
    return full * sign[:, None]


def _element_of(x: np.ndarray, n_el: int) -> tuple[np.ndarray, np.ndarray]:
    e = np.minimum((x * n_el).astype(int), n_el - 1)
    return e, x * n_el - e


def _fields(vectors: np.ndarray, x: np.ndarray, n_el: int, nw: int) -> dict:
    """phi, dphi, ddphi, Phi, Psi at x of the full DOF vectors (rows)."""
    Cw, h = _lagrange(DEGREE + 1), 1.0 / n_el
    e, xi = _element_of(x, n_el)
    W = vectors[:, _dofs(n_el, DEGREE + 1)]                    # (modes, n_el, P + 2)
    local = W[:, e, :]                                         # (modes, K, P + 2)
    pick = lambda B: np.einsum("mkj,jk->mk", local, B)
    whole = np.einsum("mej,j->me", W, _integral(Cw, np.zeros(1), np.ones(1))[:, 0]) * h
    before = np.concatenate([np.zeros((len(W), 1)), np.cumsum(whole, axis=1)], axis=1)
    after = before[:, -1:] - before
    phi_in = pick(_integral(Cw, np.zeros_like(xi), xi)) * h
    phi_out = pick(_integral(Cw, xi, np.ones_like(xi))) * h
    return dict(phi=pick(_eval(Cw, xi)), dphi=pick(_eval(Cw, xi, 1)) / h,
                ddphi=pick(_eval(Cw, xi, 2)) / h**2, Phi=before[:, e] + phi_in,
                Psi=after[:, e + 1] + phi_out)


def _lowest(K: np.ndarray, M: np.ndarray, n_modes: int):
    """Lowest eigenpairs of ``K v = lam M v`` through the Cholesky factor of the well
    conditioned M (M-orthonormal v)."""
    L = scipy.linalg.cholesky(M, lower=True)
    half = scipy.linalg.solve_triangular(L, K, lower=True)
    A = scipy.linalg.solve_triangular(L, half.T, lower=True)
    lam, y = scipy.linalg.eigh((A + A.T) / 2, subset_by_index=[0, n_modes - 1])
    return lam, scipy.linalg.solve_triangular(L.T, y, lower=False)


def timoshenko_fe_modes(n_modes: int, x, beam: TimoshenkoBeam, thickness=None,
                        n_elements: int | None = None, ends: str = CLAMPED_FREE) -> ModalBasis:
    """The first ``n_modes`` Timoshenko modes of the beam of relative thickness
    ``thickness(x)`` (vectorized callable, None: uniform) with these ``ends``
    (:data:`fsicas.scene.BEAM_ENDS`, default the cantilever) at the points x."""
    check_ends(ends)
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or not np.all(np.isfinite(x)) or np.any(x < 0.0) or np.any(x > 1.0):
        raise ValueError("x must be a 1-D array of finite points in [0, 1]")
    n_el = int(n_elements or timoshenko_fe_elements(n_modes))
    if n_el < max(2, n_modes // 2):
        raise ValueError(f"n_elements must be at least {max(2, n_modes // 2)} for {n_modes} "
                         f"modes, got {n_el}")
    profile = thickness if thickness is not None else (lambda z: np.ones_like(z))
    K, M, keep, nw = _assemble(beam, profile, n_el, ends)
    lam, vec = _lowest(K, M, n_modes)
    full = np.zeros((n_modes, nw + n_el * DEGREE + 1))
    full[:, keep] = vec.T
    full = _orient(full, ends, nw)
    fields = _fields(full, x, n_el, nw)
    return ModalBasis(x=x, omega=np.sqrt(lam), **fields)
