"""Modes of a non-uniform Euler–Bernoulli beam (Hermite-cubic FE), clamped–free by default.

Nondimensional beam on x in [0, 1] with profiles relative to the root, t(x) = thickness,
b(x) = width (t(0) = b(0) = 1 for the uniform beam):

    m(x) = b t,    EI(x) = b t^3,    (EI w'')'' = omega^2 m w,
    w(0) = w'(0) = 0,    EI w''(1) = (EI w'')'(1) = 0.

Weak form (natural free-end conditions): find w in H^2 with w(0) = w'(0) = 0 such that

    ∫_0^1 EI w'' v'' dx = omega^2 ∫_0^1 m w v dx    for all admissible v.

Uniform mesh of ``n_elements`` elements of length h; per node the DOFs are (w, h w'),
a balanced scaling of the usual (w, w').  On an element with local xi in [0, 1]:

    N1 = 1 - 3xi^2 + 2xi^3,  N2 = xi (1 - xi)^2,  N3 = xi^2 (3 - 2xi),  N4 = -xi^2 (1 - xi)
    K_e = (1/h^3) ∫_0^1 EI N'' N''^T dxi,    M_e = h ∫_0^1 m N N^T dxi

(derivatives in xi), integrated by Gauss–Legendre quadrature (6 points per element).

Solve.  Nodal K has condition number ~ h^-4, which costs eigh ~1e-7 relative accuracy on
omega_1 already at 64 elements.  The same discrete space is therefore spanned by the
curvature DOFs c = (w''(x_e+), w''(x_e+1-)) per element (w'' of a clamped C^1 cubic
spline is piecewise linear; w follows by exact double integration, nodal = T c).  There
``K_c = T^T K T`` is block diagonal, ``h ∫ EI L L^T dxi`` with L = (1 - xi, xi), and well
conditioned, and ``M_c = T^T M T``; eigh solves ``M_c c = omega^-2 K_c c`` for the
largest omega^-2.  Same Galerkin eigenpairs, accurate to ~1e-14 relative for omega_1.

Modes are normalized to
``∫ m phi^2 dx = 1`` (the analytic normalization of :mod:`fsicas.beam` when m = 1) with
the tip sign of the analytic modes, ``sign phi_n(1) = (-1)^(n+1)``.  Other ends
(:data:`fsicas.scene.BEAM_ENDS`) constrain the curvature DOFs (a pinned root adds the
root slope): see :func:`_held`; their modes take the root sign of :mod:`.beam`.  ``Phi = ∫_0^x phi``
and ``Psi = ∫_x^1 phi`` are exact for the FE shape (closed-form shape-function integrals).
"""
from __future__ import annotations

import functools
import numbers
from typing import Callable

import numpy as np
import scipy.linalg

from .beam import ModalBasis
from ..scene import CLAMPED_FREE, check_ends

__all__ = ["nonuniform_beam_modes", "default_n_elements"]

Profile = Callable[[np.ndarray], np.ndarray]

N_GAUSS = 6          # exact for m up to degree 5 and EI up to degree 9 (per element)
N_PROFILE_SAMPLES = 1001


def default_n_elements(n_modes: int) -> int:
    """``max(40, 8 n_modes)``: about 16 elements per wavelength of the highest mode."""
    return max(40, 8 * int(n_modes))


# ----------------------------------------------------------------------------- validation
def _is_int(value) -> bool:
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def _check_n_modes(n_modes) -> int:
    if not _is_int(n_modes) or n_modes < 1:
        raise ValueError(f"n_modes must be an integer >= 1, got {n_modes!r}")
    return int(n_modes)


def _check_n_elements(n_elements, n_modes: int) -> int:
    if n_elements is None:
        return default_n_elements(n_modes)
    if not _is_int(n_elements) or n_elements < 2 * n_modes:
        raise ValueError(
            f"n_elements must be an integer >= 2*n_modes = {2 * n_modes} to resolve "
            f"{n_modes} modes, got {n_elements!r}")
    return int(n_elements)


def _check_x(x) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or not np.all(np.isfinite(x)) or np.any(x < 0.0) or np.any(x > 1.0):
        raise ValueError("x must be a 1-D array of finite points in [0, 1]")
    return x


def _sample_profile(name: str, profile: Profile | None, points: np.ndarray) -> np.ndarray:
    """Evaluate a profile at ``points``; must be finite and strictly positive."""
    if profile is None:
        return np.ones_like(points)
    if not callable(profile):
        raise ValueError(f"{name} must be a callable of x or None, got {type(profile).__name__}")
    values = np.asarray(profile(points), dtype=float)
    try:
        values = np.broadcast_to(values, points.shape).copy()
    except ValueError:
        raise ValueError(f"{name}(x) must return an array of the shape of x "
                         f"{points.shape}, got shape {values.shape}") from None
    bad = ~(np.isfinite(values) & (values > 0.0))
    if np.any(bad):
        x_bad = points[bad][0]
        raise ValueError(f"{name}(x) must be finite and strictly positive on [0, 1]; "
                         f"{name}({x_bad:.6g}) = {values[bad][0]!r}")
    return values


# ------------------------------------------------------------------------ shape functions
def _shapes(xi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hermite cubics N(xi) and their xi-derivatives N', N'' (each shape (4, K))."""
    one = np.ones_like(xi)
    N = np.stack([1 - 3 * xi**2 + 2 * xi**3, xi * (1 - xi) ** 2,
                  xi**2 * (3 - 2 * xi), -(xi**2) * (1 - xi)])
    dN = np.stack([6 * xi * (xi - 1), (1 - xi) * (1 - 3 * xi),
                   6 * xi * (1 - xi), xi * (3 * xi - 2)])
    ddN = np.stack([12 * xi - 6 * one, 6 * xi - 4 * one, 6 * one - 12 * xi, 6 * xi - 2 * one])
    return N, dN, ddN


def _shape_integrals(xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``∫_0^xi N`` and ``∫_xi^1 N`` in closed form (each (4, K)), no cancellation.

    ∫_xi^1 uses eta = 1 - xi and the mirror symmetry N1(xi) = N3(eta), N2(xi) = -N4(eta).
    """
    def head(s):
        return np.stack([s - s**3 + s**4 / 2, s**2 / 2 - 2 * s**3 / 3 + s**4 / 4,
                         s**3 - s**4 / 2, -(s**3) / 3 + s**4 / 4])

    h0, h1 = head(xi), head(1.0 - xi)
    tail = np.stack([h1[2], -h1[3], h1[0], -h1[1]])
    return h0, tail


# ------------------------------------------------------------------------ FE assembly
def _gauss_points(n_elements: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Reference Gauss nodes xi_g, weights w_g on [0, 1] and physical points (E, G)."""
    g, w = np.polynomial.legendre.leggauss(N_GAUSS)
    xi, w = 0.5 * (g + 1.0), 0.5 * w
    x_nodes = np.linspace(0.0, 1.0, n_elements + 1)
    return xi, w, x_nodes[:-1, None] + xi[None, :] / n_elements


def _hermite_mass(xi, w, m_q, h) -> np.ndarray:
    """Element mass ``M_e = h ∫_0^1 m N N^T dxi`` (shape (E, 4, 4))."""
    N, _, _ = _shapes(xi)
    return np.einsum("eg,g,ag,bg->eab", m_q, w, N, N) * h


def _hermite_stiffness(xi, w, ei_q, h) -> np.ndarray:
    """Element stiffness ``K_e = h^-3 ∫_0^1 EI N'' N''^T dxi`` (shape (E, 4, 4)).

    Not used by the solver (see :func:`_curvature_stiffness`); kept as the reference
    definition, ``K_c = T^T K T``.
    """
    _, _, ddN = _shapes(xi)
    return np.einsum("eg,g,ag,bg->eab", ei_q, w, ddN, ddN) / h**3


def _assemble(Ae: np.ndarray, first: int = 2) -> np.ndarray:
    """Global nodal matrix from element blocks without the root DOFs before ``first``
    (2: both of the clamped root, w and h w' at 0; 1: w(0) of a pinned root)."""
    n_el = Ae.shape[0]
    dofs = 2 * np.arange(n_el)[:, None] + np.arange(4)[None, :]
    rows = np.broadcast_to(dofs[:, :, None], Ae.shape).ravel()
    cols = np.broadcast_to(dofs[:, None, :], Ae.shape).ravel()
    A = np.zeros((2 * (n_el + 1),) * 2)
    np.add.at(A, (rows, cols), Ae.ravel())
    return A[first:, first:]


def _curvature_stiffness(xi, w, ei_q, h) -> np.ndarray:
    """Stiffness in curvature DOFs: block-diagonal ``h ∫ EI L L^T dxi``, L = (1-xi, xi)."""
    L = np.stack([1.0 - xi, xi])
    blocks = np.einsum("eg,g,ag,bg->eab", ei_q, w, L, L) * h
    return scipy.linalg.block_diag(*blocks)


def _curvature_to_nodal(n_elements: int) -> np.ndarray:
    """T with nodal DOFs ``(w_j, h w'_j)_{j>=1} = T c``, c = (w''(x_e+), w''(x_e+1-))_e.

    Exact double integration of the piecewise-linear curvature from the clamped root:
    ``h w'_{j+1} = h w'_j + h^2 (c0 + c1)/2``, ``w_{j+1} = w_j + h w'_j + h^2 (c0/3 + c1/6)``.
    """
    h = 1.0 / n_elements
    n = 2 * n_elements
    rows = np.arange(n_elements)
    dtheta = np.zeros((n_elements, n))
    dtheta[rows, 2 * rows] = dtheta[rows, 2 * rows + 1] = 0.5 * h**2
    dw = np.zeros((n_elements, n))
    dw[rows, 2 * rows], dw[rows, 2 * rows + 1] = h**2 / 3.0, h**2 / 6.0
    theta = np.cumsum(dtheta, axis=0)                       # h w' at nodes 1..E
    theta_left = np.vstack([np.zeros((1, n)), theta[:-1]])  # h w' at nodes 0..E-1
    T = np.empty((n, n))
    T[0::2] = np.cumsum(theta_left + dw, axis=0)
    T[1::2] = theta
    return T


def _held(ends: str, T: np.ndarray, mass, K_c: np.ndarray):
    """The supports other than the clamped root and free end, on curvature DOFs.

    A pinned root adds its slope DOF ``t = h w'(0)`` (w_j = j t, h w'_j = t, no
    curvature); the held end x = 1 gives the constraint rows w(1) = 0 (and w'(1) = 0 when
    clamped), and the admissible DOFs are ``Z d`` with Z an orthonormal basis of their
    null space. Returns ``T`` mapping the DOFs to the nodal DOFs from h w'(0) on, Z, and
    ``Z^T K Z``, ``Z^T M Z``; ``mass(first)`` is the nodal mass from DOF ``first`` on.
    """
    n_el = T.shape[0] // 2
    if ends.startswith("pinned"):
        slope = np.r_[1.0, np.ravel(np.column_stack([np.arange(1, n_el + 1), np.ones(n_el)]))]
        T = np.column_stack([slope, np.vstack([np.zeros((1, T.shape[1])), T])])
        K_c, M = scipy.linalg.block_diag(0.0, K_c), T.T @ mass(1) @ T
    else:
        T = np.vstack([np.zeros((1, T.shape[1])), T])
        M = T[1:].T @ mass(2) @ T[1:]
    Z = scipy.linalg.null_space(T[-2:] if ends.endswith("clamped") else T[-2:-1])
    return T, Z, Z.T @ K_c @ Z, Z.T @ M @ Z


def _solve(K_c: np.ndarray, M_c: np.ndarray, n_modes: int) -> tuple[np.ndarray, np.ndarray]:
    """Lowest ``n_modes`` of ``K_c c = omega^2 M_c c`` as the largest of ``M_c c = mu K_c c``.

    K_c is well conditioned, so mu = 1/omega^2 carries absolute error ~ eps mu_1 and the
    low frequencies keep relative accuracy ~ eps omega_n^2 / omega_1^2.  Returns omega and
    c scaled to ``c^T M_c c = 1``.
    """
    n = K_c.shape[0]
    mu, C = scipy.linalg.eigh(M_c, K_c, subset_by_index=[n - n_modes, n - 1])
    mu, C = mu[::-1], C[:, ::-1]
    C = C / np.sqrt(np.einsum("ik,ij,jk->k", C, M_c, C))
    return 1.0 / np.sqrt(mu), C


def _orient(V: np.ndarray, C: np.ndarray, ends: str = CLAMPED_FREE
            ) -> tuple[np.ndarray, np.ndarray]:
    """Flip modes as in :mod:`.beam`: ``sign phi_n(1) = (-1)^(n+1)`` for the cantilever,
    else phi''(0) > 0 (clamped root) or phi'(0) > 0 (pinned root)."""
    if ends == CLAMPED_FREE:
        target = np.where(np.arange(V.shape[1]) % 2 == 0, 1.0, -1.0)
        flip = np.where(np.sign(V[-2]) == target, 1.0, -1.0)
    else:
        flip = np.where((V[1] if ends.startswith("pinned") else C[0]) < 0, -1.0, 1.0)
    return V * flip, C * flip


# ------------------------------------------------------------------------ evaluation
def _evaluate(V: np.ndarray, C: np.ndarray, x: np.ndarray) -> dict[str, np.ndarray]:
    """phi, dphi, Phi = ∫_0^x phi, Psi = ∫_x^1 phi from nodal DOFs V (root included);
    ddphi from the curvature DOFs C (linear on each element, no cancellation)."""
    n_elements = C.shape[0] // 2
    h = 1.0 / n_elements
    e = np.minimum((x * n_elements).astype(int), n_elements - 1)
    xi = np.clip(x * n_elements - e, 0.0, 1.0)
    d = V[2 * e[:, None] + np.arange(4)[None, :]]                  # (K, 4, N)
    N, dN, _ = _shapes(xi)
    head, tail = _shape_integrals(xi)
    el_dofs = 2 * np.arange(n_elements)[:, None] + np.arange(4)[None, :]
    w_int = np.array([0.5, 1.0 / 12.0, 0.5, -1.0 / 12.0])           # ∫_0^1 N dxi
    el_int = h * np.einsum("a,ean->en", w_int, V[el_dofs])         # ∫ phi per element
    zero = np.zeros((1, V.shape[1]))
    before = np.vstack([zero, np.cumsum(el_int, axis=0)])
    after = np.vstack([np.cumsum(el_int[::-1], axis=0)[::-1], zero])

    def combine(S):
        return np.einsum("ak,kan->nk", S, d)

    ddphi = (C[2 * e] * (1.0 - xi)[:, None] + C[2 * e + 1] * xi[:, None]).T
    return dict(phi=combine(N), dphi=combine(dN) / h, ddphi=ddphi,
                Phi=before[e].T + h * combine(head), Psi=after[e + 1].T + h * combine(tail))


# ------------------------------------------------------------------------ public API
def nonuniform_beam_modes(n_modes: int, x, thickness: Profile | None = None,
                          width: Profile | None = None,
                          n_elements: int | None = None,
                          ends: str = CLAMPED_FREE) -> ModalBasis:
    """Lowest ``n_modes`` modes of a non-uniform beam with these ``ends``
    (:data:`fsicas.scene.BEAM_ENDS`, default the cantilever), sampled at ``x``.

    Solves ``∫ EI w'' v'' = omega^2 ∫ m w v`` with ``m = b t``, ``EI = b t^3`` (t =
    ``thickness(x)``, b = ``width(x)``, vectorized callables relative to the root, None
    = 1) on ``n_elements`` Hermite-cubic elements (default ``max(40, 8 n_modes)``).
    Modes satisfy ``∫ m phi_i phi_j dx = delta_ij`` and the signs of :func:`_orient`;
    ``Phi``/``Psi`` are the exact running integrals of the FE shape.  Frequencies converge
    as O(h^4); phi, Phi, Psi as O(h^4), dphi as O(h^3), ddphi as O(h^2).
    """
    n_modes = _check_n_modes(n_modes)
    check_ends(ends)
    n_elements = _check_n_elements(n_elements, n_modes)
    x = _check_x(x)
    _sample_profile("thickness", thickness, x)
    b_x = _sample_profile("width", width, x)
    try:
        omega, V, C = _mesh_modes(n_modes, n_elements, thickness, width, ends)
    except TypeError:          # an unhashable profile object: solve without the cache
        omega, V, C = _mesh_modes.__wrapped__(n_modes, n_elements, thickness, width, ends)
    return ModalBasis(x=x, omega=omega.copy(), width=b_x, **_evaluate(V, C, x))


@functools.lru_cache(maxsize=16)
def _mesh_modes(n_modes: int, n_elements: int, thickness, width, ends=CLAMPED_FREE):
    """Frequencies and nodal/curvature mode vectors, solved once per beam and mesh
    (profiles must be hashable: Profile objects and plain functions are)."""
    xi_g, w_g, x_q = _gauss_points(n_elements)
    samples = np.concatenate([np.linspace(0.0, 1.0, N_PROFILE_SAMPLES), x_q.ravel()])
    t_s = _sample_profile("thickness", thickness, samples)
    b_s = _sample_profile("width", width, samples)
    h = 1.0 / n_elements
    t_q = t_s[N_PROFILE_SAMPLES:].reshape(x_q.shape)
    b_q = b_s[N_PROFILE_SAMPLES:].reshape(x_q.shape)
    T = _curvature_to_nodal(n_elements)
    mass_e = _hermite_mass(xi_g, w_g, b_q * t_q, h)
    K_c = _curvature_stiffness(xi_g, w_g, b_q * t_q**3, h)
    if ends == CLAMPED_FREE:
        omega, C = _solve(K_c, T.T @ _assemble(mass_e) @ T, n_modes)
        V, C = _orient(np.vstack([np.zeros((2, n_modes)), T @ C]), C)
    else:
        T, Z, K_d, M_d = _held(ends, T, lambda first: _assemble(mass_e, first), K_c)
        omega, D = _solve(K_d, M_d, n_modes)
        C = Z @ D
        V, C = _orient(np.vstack([np.zeros((1, n_modes)), T @ C]), C[-2 * n_elements:], ends)
    for array in (omega, V, C):
        array.setflags(write=False)
    return omega, V, C
