"""Cycles that keep a symmetry, and the branch points where cycles breaking it branch off.

A field equivariant under an orthogonal involution ``S`` (``F(S x) = S F(x)``,
``M(S x) S = S M(x)``) has cycles that keep it, either in space, ``u(t) = S u(t)``
(``shift = 0``), or in space and time, ``u(t + T/2) = S u(t)`` (``shift = 1/2``: e.g. a
beam swinging symmetrically between two walls). Where a multiplier of such a cycle
crosses +1 with a Floquet solution that breaks the symmetry (``v = -S v``, or
``v(t + T/2) = -S v(t)``: a multiplier of the half-period map ``S Phi(T/2)`` through
-1), cycles that break it branch off in a pitchfork. It is a branch point of the
cycle equations, where the fold's extended system is singular; restricted to symmetric
cycles it is a regular point, which :func:`locate_symmetry_breaking` finds by Newton.

The collocation equations on a mesh that the symmetry maps onto itself (any mesh for
``shift = 0``; ``mesh_(j + NTST/2) = mesh_j + 1/2`` for ``shift = 1/2``) are equivariant
under ``Sigma``, the symmetry acting on the node values (``I (x) S``, or the two halves
of the period swapped and mapped by ``S``). With ``E_+`` and ``E_-`` orthonormal bases
of the node vectors ``Sigma`` keeps and reverses, the symmetric cycles ``U = E_+ Y``
solve the collocation equations iff ``E_+^T G(E_+ Y, T, p) = 0``, and the collocation
Jacobian ``G_U`` is block diagonal, its symmetry-breaking block ``A = E_-^T G_U E_-``
singular exactly at the branch point (the trivial Floquet solution is symmetric, so
``A`` is regular elsewhere). The square system in ``Z = (Y, T, p)``: those equations,
the phase condition and ``g = 0``, ``g`` from the bordered ``A`` as for a period
doubling (``cycle_curves``), ``g_X`` by the Hessian of ``w^T G`` in the direction
``E_- v``.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from . import floquet
from .conditions import bordered_solve, jacobian_derivative, matrix_null_vectors
from .cycles import CycleProblem
from .mesh import FLOOR, next_derivative
from .._driver.newton import NewtonResult, newton
from .._driver.settings import NewtonSettings

#: largest ``|u(t + shift T) - S u(t)|`` of a start cycle (relative to ``max |u|``) and
#: of the field's equivariance (relative to ``1 + max |F|``) accepted
SYMMETRY_TOL, EQUIVARIANCE_TOL = 1e-2, 1e-8


def locate_symmetry_breaking(problem: CycleProblem, X, symmetry, shift: float = 0.5,
                             settings: NewtonSettings = NewtonSettings()
                             ) -> tuple[CycleProblem, NewtonResult]:
    """The branch point of the cycle ``X`` of ``problem`` (one free parameter) where
    cycles breaking the symmetry ``u(t + shift T) = symmetry u(t)`` branch off, by
    Newton on the symmetric cycles' square system (module doc), from ``X`` (symmetric
    to ``SYMMETRY_TOL``, e.g. a branch point located on the arclength).

    The cycle is first rebuilt symmetric, ``(u(t) + S u(t - shift)) / 2``, on a mesh the
    symmetry maps onto itself that equidistributes the error of ``X`` (NTST rounded up
    to even for ``shift = 1/2``). Returns that problem and the Newton outcome, whose
    ``X`` is the whole cycle's unknowns on it. Raises ValueError for a ``symmetry``
    that is not an orthogonal involution, a field not equivariant under it, or a
    cycle that does not keep it."""
    S = _checked_symmetry(symmetry, problem.vf.n, shift)
    if len(problem.free) != 1:
        raise ValueError(f"the cycle problem must have one free parameter, has {problem.free}")
    sym = _symmetric_problem(problem, np.asarray(X, dtype=float), S, shift)
    return sym, _BranchPointSystem(sym, S, shift).solve(settings)


def symmetric_multipliers(problem: CycleProblem, X, symmetry, shift: float = 0.5
                          ) -> tuple[complex, np.ndarray]:
    """``(trivial, rest)``: the Floquet multipliers of a symmetric cycle ``X`` on a mesh
    the symmetry maps onto itself, from the maps that keep and break it (``shift = 0``:
    the monodromy's blocks on ``S``'s eigenspaces; ``1/2``: the squares of the
    half-period map ``S Phi(T/2)``'s), with the trivial one (of the symmetric part,
    nearest +1) apart from the ``n - 1`` others (by decreasing modulus): a multiplier
    at +1 that breaks the symmetry is not mistaken for the trivial one."""
    S = _checked_symmetry(symmetry, problem.vf.n, shift)
    if shift:
        _check_symmetric_mesh(problem.mesh)
    maps = problem.transfer_matrices(np.asarray(X, dtype=float))
    if shift:                   # the half-period map S A_{h-1} ... A_0's, periodic Schur
        mu = floquet.schur_multipliers(np.concatenate([maps[: problem.ntst // 2],
                                                       np.asarray(S, float)[None]]))
        trivial = int(np.argmin(np.abs(mu - 1.0)))
        keep, rest = mu ** 2, np.zeros(0, complex)
    else:                       # every map keeps S's eigenspaces: the chains restricted
        plus, minus = _eigenspaces(S)
        keep = floquet.schur_multipliers(plus.T @ maps @ plus) if plus.shape[1] \
            else np.zeros(0, complex)
        rest = floquet.schur_multipliers(minus.T @ maps @ minus) if minus.shape[1] \
            else np.zeros(0, complex)
        trivial = int(np.argmin(np.abs(keep - 1.0)))
    rest = np.concatenate([np.delete(keep, trivial), rest]).astype(complex)
    return complex(keep[trivial]), rest[np.argsort(-np.abs(rest), kind="stable")]


class _BranchPointSystem:
    """The square system of :func:`locate_symmetry_breaking` on the symmetric problem
    ``sym``: residual and Jacobian in ``Z = (Y, T, p)``, the whole cycle ``P Z``."""

    def __init__(self, sym: CycleProblem, S, shift):
        plus, minus = _node_bases(S, sym.n_nodes, shift)
        self.sym, self.N, self.minus = sym, sym.n_nodes * sym.vf.n, minus
        self.rows = sp.block_diag([plus.T, sp.eye(1)], format="csr")   # sym. rows, phase
        self.P = sp.block_diag([plus, sp.eye(2)], format="csc")        # Z -> X
        self.Z0 = self.P.T @ sym.X0
        A = self._breaking_block(sym.jacobian(sym.X0))
        self.c, self.b = matrix_null_vectors(A)
        self._last = None

    def _breaking_block(self, J) -> sp.csc_matrix:
        """``A = E_-^T G_U E_-``."""
        return sp.csc_matrix(self.minus.T @ J[: self.N, : self.N] @ self.minus)

    def _at(self, Z) -> tuple:
        """``(X, G, J, v, w, g)`` at ``Z`` (kept for the last ``Z``)."""
        if self._last is None or not np.array_equal(self._last[0], Z):
            X = self.P @ Z
            J = self.sym.jacobian(X)
            v, w, g = bordered_solve(self._breaking_block(J), self.b, self.c)
            self._last = (np.array(Z), (X, self.sym.residual(X), J, v, w, float(g)))
        return self._last[1]

    def residual(self, Z) -> np.ndarray:
        _, G, _, _, _, g = self._at(Z)
        return np.append(self.rows @ G, g)

    def jacobian(self, Z) -> sp.csc_matrix:
        X, _, J, v, w, _ = self._at(Z)
        d = np.zeros(X.size)
        d[: self.N] = self.minus @ v
        H = jacobian_derivative(self.sym.jacobian, X, d)
        g_X = -(H[: self.N].T @ (self.minus @ w))
        return sp.vstack([self.rows @ J @ self.P, sp.csr_matrix(g_X @ self.P)], format="csc")

    def solve(self, settings: NewtonSettings) -> NewtonResult:
        result = newton(self.residual, self.jacobian, self.Z0, settings)
        return replace(result, X=self.P @ result.X)


def _checked_symmetry(symmetry, n: int, shift) -> np.ndarray:
    S = np.asarray(symmetry, dtype=float)
    if shift not in (0, 0.5):
        raise ValueError(f"shift must be 0 (u = S u) or 0.5 (u(t + T/2) = S u(t)), got {shift!r}")
    if S.shape != (n, n) or not np.allclose(S @ S, np.eye(n), atol=1e-12) \
            or not np.allclose(S, S.T, atol=1e-12):
        raise ValueError(f"symmetry must be an orthogonal involution (S = S^T, S S = I) of "
                         f"shape ({n}, {n})")
    return S


def keeps_symmetry(problem: CycleProblem, X, symmetry, shift: float = 0.5) -> bool:
    """Whether the cycle ``X`` keeps ``u(t + shift T) = symmetry u(t)`` to
    ``SYMMETRY_TOL`` of ``max |u|`` at the nodes: the start cycles
    :func:`locate_symmetry_breaking` and :func:`symmetric_multipliers` accept."""
    S = _checked_symmetry(symmetry, problem.vf.n, shift)
    return _defect(problem, X, S, shift)[0] <= SYMMETRY_TOL


def _defect(problem, X, S, shift) -> tuple[float, np.ndarray]:
    """``(max |u(t) - S u(t - shift)| / max |u|, u)`` at the problem's node times."""
    t = problem.times()
    u, image = problem.evaluate(X, t), problem.evaluate(X, t - shift) @ S.T
    return float(np.max(np.abs(u - image)) / np.max(np.abs(u))), u


def _symmetric_problem(problem, X, S, shift) -> CycleProblem:
    """``X`` rebuilt symmetric on a mesh the symmetry maps onto itself, after checking
    that the cycle keeps the symmetry and the field respects it."""
    defect, u = _defect(problem, X, S, shift)
    if defect > SYMMETRY_TOL:
        raise ValueError(f"the cycle does not keep the symmetry: |u(t) - S u(t - {shift:g} T)|"
                         f" = {defect:.2g} max |u| (> {SYMMETRY_TOL:g} max |u|)")
    _check_equivariant(problem, X, u[:: max(1, len(u) // 16)], S)
    ntst = problem.ntst + (problem.ntst % 2 if shift else 0)
    mesh = _symmetric_mesh(problem, X, ntst) if shift else problem.mesh
    orbit = lambda s: 0.5 * (problem.evaluate(X, s)                     # noqa: E731
                             + problem.evaluate(X, np.asarray(s) - shift) @ S.T)
    settings = replace(problem.settings, ntst=ntst, adapt_every=0)
    return CycleProblem(problem.vf, orbit, problem.period(X), problem.par_dict(X),
                        problem.free, settings=settings, mesh=mesh)


def _check_equivariant(problem, X, states, S) -> None:
    """ValueError unless ``F(S x) = S F(x)``, ``F_x(S x) S = S F_x(x)`` and
    ``M(S x) S = S M(x)`` at ``states`` (what the symmetric system needs on the cycle)."""
    vf, p = problem.vf, problem.params(X)
    for x in states:
        F, FS = vf.rhs(x, p), vf.rhs(S @ x, p)
        bad = np.max(np.abs(FS - S @ F))
        for matrix in (vf.jac_x, vf.mass):
            A, AS = (matrix(y, p).toarray() for y in (x, S @ x))
            bad = max(bad, np.max(np.abs(AS @ S - S @ A)))
        if bad > EQUIVARIANCE_TOL * (1.0 + np.max(np.abs(F))):
            raise ValueError("the field is not equivariant under the symmetry on the cycle: "
                             f"|F(S x) - S F(x)|, |F_x(S x) S - S F_x(x)| or "
                             f"|M(S x) S - S M(x)| = {bad:.2g}")


def _symmetric_mesh(problem, X, ntst: int) -> np.ndarray:
    """``ntst`` (even) intervals, ``mesh_(j + ntst/2) = mesh_j + 1/2``, equidistributing
    the error density of ``X`` averaged over the two halves of the period."""
    U, mesh = X[: problem.n_nodes * problem.vf.n], problem.mesh
    h = np.diff(mesh)
    rho = next_derivative(U, mesh, problem.ncol, problem.vf.n) ** (1.0 / (problem.ncol + 1))
    rho = rho + FLOOR * max(float(np.sum(rho * h)), 1e-300)
    t = np.linspace(0.0, 0.5, 64 * ntst + 1)
    piece = lambda s: rho[np.clip(np.searchsorted(mesh, s % 1.0, side="right") - 1,  # noqa: E731
                                  0, len(rho) - 1)]
    density = 0.5 * (piece(t) + piece(t + 0.5))
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (density[1:] + density[:-1]) * np.diff(t))])
    half = np.interp(np.linspace(0.0, cum[-1], ntst // 2 + 1), cum, t)
    half[0], half[-1] = 0.0, 0.5
    return np.concatenate([half, half[1:] + 0.5])


def _check_symmetric_mesh(mesh) -> None:
    ntst = len(mesh) - 1
    if ntst % 2 or not np.allclose(mesh[ntst // 2:], mesh[: ntst // 2 + 1] + 0.5,
                                   rtol=0, atol=1e-14):
        raise ValueError("the mesh is not mapped onto itself by the half-period shift "
                         "(see locate_symmetry_breaking)")


def _eigenspaces(S) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal bases of ``S``'s eigenspaces of +1 and -1."""
    values, vectors = np.linalg.eigh(S)
    return vectors[:, values > 0], vectors[:, values < 0]


def _node_bases(S, nodes: int, shift) -> tuple[sp.csc_matrix, sp.csc_matrix]:
    """``(E_+, E_-)``: orthonormal bases of the node vectors ``Sigma`` keeps and reverses."""
    if not shift:
        plus, minus = _eigenspaces(S)
        eye = sp.eye(nodes, format="csc")
        return sp.kron(eye, plus, format="csc"), sp.kron(eye, minus, format="csc")
    half = nodes // 2
    eye, mapped = sp.eye(half * S.shape[0], format="csc"), sp.kron(sp.eye(half), S)
    stack = lambda sign: sp.vstack([eye, sign * mapped], format="csc") / np.sqrt(2)  # noqa: E731
    return stack(1.0), stack(-1.0)
