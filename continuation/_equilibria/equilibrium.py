"""Equilibria ``F(x, p) = 0`` of ``M(x, p) xdot = F(x, p)`` in one parameter.

Test functions along the branch, for ``X = (x, p)`` and tangent ``tau``:

* fold (limit point): ``tau_p`` changes sign;
* simple branch point: ``sign det [G_X; tau^T]`` changes;
* Hopf: the number of eigenvalues of ``J v = lambda M v`` with ``Re > 0`` changes by a
  nonzero even number (a complex pair crossed; a complex pair turning into two real ones
  keeps the count); it is located on ``Re lambda(s) = 0`` of the crossing eigenvalue, and
  rejected if the refined point is a neutral saddle (``kappa <= 0``).

Folds and Hopf points are then refined by Newton on the square fold/Hopf systems of
``systems`` (one free parameter), with the first Lyapunov coefficient at Hopf points.

:class:`StationaryProblem` is what equilibria share with the Hopf and fold curves
(``curves``): a state ``x`` in the first unknowns, the eigenvalues of ``J v = lambda M v``
there, which also cap the step.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np
import scipy.sparse as sp

from . import eigen
from .lyapunov import first_lyapunov, hopf_eigenvectors
from .systems import equilibrium_system, fold_system, hopf_system
from .._casadi.symbolic import bound
from .._casadi.vectorfield import make_field, param_vector, state_vector
from .._driver.branch import SpecialPoint
from .._driver.newton import newton
from .._driver.problem import Description, PointInfo, Problem
from .._driver.settings import ContinuationSettings


class StationaryProblem(Problem):
    """A curve of stationary states: ``X = (x, ..., p_free)``, the state ``x`` first;
    monitored by the eigenvalues of ``J v = lambda M v`` at ``x`` (which also cap the
    step) and the branch-point test."""

    def frame(self, X) -> np.ndarray:
        """The state ``x`` and the free parameters."""
        N, nf = len(X), len(self.free)
        return np.r_[0:self.vf.n, N - nf:N]

    def matrices(self, X):
        """``J = F_x`` and ``M`` at the state and parameters of ``X``."""
        x, p = self.state(X), self.params(X)
        return self.vf.jac_x(x, p), self.vf.mass(x, p)

    def eigenvalues(self, X, settings: ContinuationSettings) -> np.ndarray:
        """Generalized eigenvalues of ``J v = lambda M v`` at ``X``."""
        if not settings.compute_eigenvalues:
            return np.zeros(0, dtype=complex)
        J, M = self.matrices(X)
        return eigen.eigenvalues(J, M, settings.eigen)

    def monitor(self, X, tau, lu, settings) -> PointInfo:
        tests = super().monitor(X, tau, lu, settings).tests
        return PointInfo(self.eigenvalues(X, settings), tests)

    def step_limit(self, a: PointInfo, b: PointInfo, ds: float, settings) -> float | None:
        """By ``settings.eigen_step`` (``eigen.step_limit``): no complex eigenvalue moving
        towards the imaginary axis lands much past it."""
        if not (settings.eigen_step and len(a.eigenvalues) and len(b.eigenvalues)):
            return None
        return eigen.step_limit(a.eigenvalues, b.eigenvalues, ds, settings.eigen_step,
                                settings.eigen.imag_tol)


class EquilibriumProblem(StationaryProblem):
    """Branch of equilibria ``F(x, p) = 0`` in the parameter ``active``.

    Parameters
    ----------
    F : casadi.Function ``(x, p) -> F`` or a prebuilt :class:`VectorField`.
    x0 : initial guess of the equilibrium (corrected before continuing).
    params : ``{name: value}`` of all parameters, in the order of ``p``.
    active : name of the continuation parameter.
    M : casadi.Function ``(x, p) -> M`` (``None``: identity).
    """

    kind = "equilibrium"
    builder = staticmethod(equilibrium_system)
    verified_kinds = ("hopf",)

    #: the start corrector's row (None: the parameter is fixed); set by branch switching
    start_direction = None

    def __init__(self, F, x0, params: Mapping[str, float], active: str, *, M=None):
        vf = make_field(F, M, params)
        p0 = param_vector(vf, params)
        x = state_vector(vf, x0)
        super().__init__(vf, (active,), np.append(x, p0[vf.par_index(active)]), p0)
        self.active, self._last = active, None

    def start_row(self) -> np.ndarray:
        if self.start_direction is None:
            return super().start_row()
        return np.asarray(self.start_direction, dtype=float)

    def jacobian(self, X):
        """``G_X``, kept for :meth:`matrices` at the same ``X`` (first n columns: ``J``)."""
        A = super().jacobian(X)
        self._last = (np.array(X), A)
        return A

    def matrices(self, X):
        """``J, M`` at ``X``; ``J`` from the last Jacobian if taken at ``X`` (the tangent's)."""
        if self._last is not None and np.array_equal(self._last[0], X):
            return self._last[1][:, : self.vf.n], self.vf.mass(self.state(X), self.params(X))
        return super().matrices(X)

    def monitor(self, X, tau, lu, settings) -> PointInfo:
        base = super().monitor(X, tau, lu, settings)
        tests = {"fold": float(tau[-1]), **base.tests}
        counts = {}
        if settings.compute_eigenvalues:
            counts["hopf"] = eigen.count_unstable(base.eigenvalues)
            counts["hopf_complex"] = eigen.count_complex_unstable(
                base.eigenvalues, settings.eigen.imag_tol)
        return PointInfo(base.eigenvalues, tests, counts)

    def events(self, a: PointInfo, b: PointInfo) -> list:
        kinds = [k for k in super().events(a, b) if k not in ("hopf", "hopf_complex")]
        if "hopf" in a.counts and "hopf" in b.counts:
            jump = a.counts["hopf"] - b.counts["hopf"]
            jump_c = a.counts["hopf_complex"] - b.counts["hopf_complex"]
            if (jump != 0 and jump % 2 == 0) or jump_c != 0:
                kinds.append("hopf")  # candidate; rejected if Re lambda keeps its sign
        return kinds

    def crossings(self, kind, a: PointInfo, b: PointInfo) -> int:
        """Hopf: half the change of the count of unstable complex eigenvalues (pairs)."""
        c = "hopf_complex"
        return max(1, abs(a.counts.get(c, 0) - b.counts.get(c, 0)) // 2) if kind == "hopf" else 1

    def test_function(self, kind, X_a, info_a, X_b, info_b, settings):
        if kind == "fold":
            return lambda X, tau, lu: float(tau[-1])
        if kind == "hopf":
            return _hopf_function(self, info_a, info_b, settings)
        return super().test_function(kind, X_a, info_a, X_b, info_b, settings)

    def describe(self, kind, X, tau, settings) -> Description:
        if kind == "fold":
            return _refine_fold(self, X, settings)
        if kind == "hopf":
            return _refine_hopf(self, X, settings)
        return super().describe(kind, X, tau, settings)


def _hopf_function(problem, info_a, info_b, settings):
    """``Re`` of the eigenvalue nearest to the crossing one, as a function of X."""
    tol = settings.eigen.imag_tol
    ref = eigen.crossing_eigenvalue(info_a.eigenvalues, info_b.eigenvalues, tol)
    if ref is None:
        return lambda X, tau, lu: 1.0  # no complex eigenvalue: nothing crosses

    def f(X, tau, lu):
        ev = problem.eigenvalues(X, settings)
        ev = ev[ev.imag > tol]
        return float(eigen.nearest(ev, ref).real) if ev.size else 1.0

    return f


def real_null_vector(J) -> np.ndarray:
    """Real ``v`` with ``J v ~ 0``, ``|v| = 1``."""
    q = eigen.eigenvector(J, sp.identity(J.shape[0], format="csc"), 0.0)
    q = q * np.exp(-1j * np.angle(q[np.argmax(np.abs(q))]))
    v = q.real
    return v / np.linalg.norm(v)


def _refine_fold(problem, X, settings) -> Description:
    """Newton on ``F = 0, J v = 0, c.v = 1`` with the active parameter free."""
    vf = problem.vf
    J, _ = problem.matrices(X)
    v = real_null_vector(J)
    sysf = bound(vf, "fold", problem.params(X), v, problem.free, fold_system)
    Y0 = np.concatenate([problem.state(X), v, X[-1:]])
    res = newton(sysf.residual, sysf.jacobian, Y0, settings.newton, polish=3)
    if not res.converged:
        return Description(X, "guess", res.residual, {}, "fold refinement: " + res.message)
    Xr = np.append(res.X[: vf.n], res.X[-1])
    data = _fold_coefficient(vf, Xr[:-1], problem.params(Xr), res.X[vf.n: 2 * vf.n])
    return Description(Xr, "converged", res.residual, data)


def _fold_coefficient(vf, x, p, v) -> dict:
    """Fold normal-form coefficient ``a = psi^T F2(v, v) / (2 psi^T M v)``.

    ``J v = 0`` with ``|v| = 1``, ``psi^T J = 0``: on the centre manifold ``x = x0 + y v``
    of ``M xdot = F`` the reduced equation is ``ydot = a y^2 + O(y^3, dp)``; ``M1`` terms
    vanish since ``A v = 0``. The sign of ``a`` refers to ``v`` oriented with its largest
    entry positive."""
    J, M = vf.jac_x(x, p), vf.mass(x, p)
    v = v / np.linalg.norm(v)
    psi = eigen.left_eigenvector(J, M, 0.0)
    psi = (psi * np.exp(-1j * np.angle(psi[np.argmax(np.abs(psi))]))).real
    denom = psi @ (M @ v)
    if denom == 0:
        return {}
    return {"a": float(psi @ vf.form("F2", x, p, v, v).real / (2 * denom))}


def hopf_start(J, M, omega):
    """Initial ``(v, w, kappa, c)`` of the Hopf system from ``J q = i omega M q``."""
    q, _ = hopf_eigenvectors(sp.csc_matrix(J, dtype=complex),
                             sp.csc_matrix(M, dtype=complex), omega)
    return hopf_vectors(q, omega)


def hopf_vectors(q, omega):
    """``(v, w, kappa, c)`` from an eigenvector ``q`` of ``i omega``.

    The phase of ``q`` is chosen so that ``Re q . Im q = 0`` and
    ``|Re q| >= |Im q|``; then ``v = Re q``, ``w = -omega Im q``,
    ``kappa = omega^2``, ``c = v / |v|^2`` satisfy ``c.v = 1, c.w = 0``.
    """
    q = q / np.linalg.norm(q)
    q = q * np.exp(-0.5j * np.angle(q @ q))
    if np.linalg.norm(q.real) < np.linalg.norm(q.imag):
        q = 1j * q
    v, w = q.real, -omega * q.imag
    return v, w, omega ** 2, v / (v @ v)


def hopf_point(problem: "EquilibriumProblem", x, omega: float, settings=None):
    """Locate a Hopf point from a guess: Newton on the Hopf system with the active
    parameter free, started from state ``x`` at the problem's parameter values and the
    eigenvector of ``J q = i omega M q`` (omega: a guess of the critical frequency, which
    picks the eigenvalue — not the one nearest the axis). Returns a SpecialPoint with
    ``omega`` and ``l1`` in ``data``; status 'guess' with the residual if Newton fails."""
    settings = settings or ContinuationSettings()
    if not (np.isfinite(omega) and omega > 0):
        raise ValueError(f"omega must be positive, got {omega!r}")
    X = np.append(state_vector(problem.vf, x, "x"), problem.X0[-1])
    desc = _refine_hopf(problem, X, settings, omega0=float(omega))
    return SpecialPoint("hopf", 0, problem.state(desc.X), problem.par_dict(desc.X),
                        desc.status, float(desc.precision), desc.data, desc.message)


def _refine_hopf(problem, X, settings, omega0: float | None = None) -> Description:
    """Newton on the Hopf system (active parameter free), then ``omega, l1``."""
    vf = problem.vf
    J, M = problem.matrices(X)
    if omega0 is None:
        ev = eigen.eigenvalues(J, M, settings.eigen)
        ev = ev[ev.imag > settings.eigen.imag_tol]
        if not ev.size:
            return Description(X, "rejected", 0.0, {}, "no complex eigenvalue: not a Hopf point")
        omega0 = float(ev[np.argmin(np.abs(ev.real))].imag)
    v, w, kappa, c = hopf_start(J, M, omega0)
    sysh = bound(vf, "hopf", problem.params(X), c, problem.free, hopf_system)
    Y0 = np.concatenate([problem.state(X), v, w, [kappa], X[-1:]])
    res = newton(sysh.residual, sysh.jacobian, Y0, settings.newton, polish=3)
    if not res.converged:
        return Description(X, "guess", res.residual, {"omega": omega0},
                           "Hopf refinement: " + res.message)
    Xr = np.append(res.X[: vf.n], res.X[-1])
    if res.X[3 * vf.n] <= 0:
        return Description(Xr, "rejected", res.residual, {}, "neutral saddle, not Hopf")
    omega = float(np.sqrt(res.X[3 * vf.n]))
    data = {"omega": omega, **_lyapunov_data(vf, Xr[:-1], problem.params(Xr), omega)}
    return Description(Xr, "converged", res.residual, data)


def _lyapunov_data(vf, x, p, omega) -> dict:
    try:
        return {"l1": first_lyapunov(vf, x, p, omega)}
    except RuntimeError as err:  # singular M or J: no normal form
        return {"l1_error": str(err)}
