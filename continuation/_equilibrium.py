"""Equilibria ``F(x, p) = 0`` of ``M(x, p) xdot = F(x, p)`` in one parameter.

Test functions along the branch, for ``X = (x, p)`` and tangent ``tau``:

* fold (limit point): ``tau_p`` changes sign;
* simple branch point: ``sign det [G_X; tau^T]`` changes;
* Hopf: the number of eigenvalues of ``J v = lambda M v`` with ``Re > 0`` changes by a
  nonzero even number (a complex pair crossed; a complex pair turning into two real ones
  keeps the count); it is located on ``Re lambda(s) = 0`` of the crossing eigenvalue, and
  rejected if the refined point is a neutral saddle (``kappa <= 0``).

Folds and Hopf points are then refined by Newton on the square fold/Hopf systems of
``_systems`` (one free parameter), with the first Lyapunov coefficient at Hopf points.
"""

from __future__ import annotations

from typing import Mapping

import casadi as ca
import numpy as np
import scipy.sparse as sp

from . import _eigen
from ._lyapunov import first_lyapunov, hopf_eigenvectors
from ._newton import newton
from ._problem import Description, PointInfo, Problem
from ._sparse import columns_appended
from ._symbolic import BufferedFunction, CompiledSystem
from ._systems import bound
from ._vectorfield import VectorField


def make_field(F, M, params: Mapping[str, float]) -> VectorField:
    """``F`` itself if it is a VectorField, else ``VectorField(F, M, names)``."""
    if isinstance(F, VectorField):
        if M is not None:
            raise ValueError("M must be None when F is already a VectorField")
        return F
    if not isinstance(params, Mapping):
        raise ValueError(f"params must be a mapping name -> value, got {type(params).__name__}")
    if isinstance(F, ca.Function) and F.n_in() == 2 and F.numel_in(1) != len(params):
        raise ValueError(f"params names {tuple(params)} but F takes p of size "
                         f"{F.numel_in(1)}")
    return VectorField(F, M, tuple(params))


def param_vector(vf: VectorField, params: Mapping[str, float]) -> np.ndarray:
    """Values of ``params`` in the order of ``vf.par_names``; all must be given."""
    if not isinstance(params, Mapping):
        raise ValueError(f"params must be a mapping name -> value, got {type(params).__name__}")
    if set(params) != set(vf.par_names):
        raise ValueError(f"params must name exactly {vf.par_names}, got {tuple(params)}")
    p = np.array([float(params[k]) for k in vf.par_names])
    if not np.all(np.isfinite(p)):
        raise ValueError(f"params must be finite, got {dict(params)}")
    return p


def state_vector(vf: VectorField, x0, label: str = "x0") -> np.ndarray:
    """``x0`` as a finite float vector of size ``n``."""
    x = np.array(x0, dtype=float).ravel()
    if x.size != vf.n or not np.all(np.isfinite(x)):
        raise ValueError(f"{label} must be a finite vector of size {vf.n}, got {x0!r}")
    return x


def equilibrium_system(vf: VectorField) -> CompiledSystem:
    """The equilibrium system ``F(x, p) = 0`` of ``_systems``, the field's function inlined
    (:func:`_flat_field`: 2x faster Jacobians for a modal model), ``F_x`` the field's own
    ``jacobian`` when given, ``F_p`` along the free parameters only."""
    x, p = vf.sym.sym("x", vf.n), vf.sym.sym("p", len(vf.par_names))
    f = _flat_field(vf, x, p)[0]
    return FreeDirectionSystem(x, p, vf.sym.sym("D", 0), f, "equilibrium",
                               _state_jacobian(vf, x, p, f), lambda E: ca.jtimes(f, p, E))


class FreeDirectionSystem(CompiledSystem):
    """A :class:`CompiledSystem` with ``G_p`` only along the free parameters: ``along(E)``
    is ``G_p E`` for a symbolic ``(k_p, k)`` ``E``, compiled once per count ``k`` (a modal
    model has 45 parameters, a curve 2 free ones)."""

    def __init__(self, Y, P, D, G, name: str, jy, along):
        rows = ca.vertcat(*G).numel() if isinstance(G, (list, tuple)) else G.numel()
        super().__init__(Y, P, D, G, name, jacobians=(jy, type(Y)(rows, 0)))
        self._symbols, self._along, self._name, self._by_count = (Y, P, D), along, name, {}
        self._n_par = P.numel()

    def _along_free(self, count: int) -> BufferedFunction:
        if count not in self._by_count:
            Y, P, D = self._symbols
            E = type(Y).sym("E", self._n_par, count)
            out = ca.densify(self._along(E))
            self._by_count[count] = BufferedFunction(
                ca.Function(f"{self._name}_jac_p{count}", [Y, P, D, E], [out]))
        return self._by_count[count]

    def jacobian(self, Y, P, D, par_columns) -> sp.csc_matrix:
        """``[G_Y, G_p[:, par_columns]]`` as one sparse matrix."""
        cols = list(par_columns)
        E = np.zeros((self._n_par, len(cols)))
        E[cols, np.arange(len(cols))] = 1.0
        jp = self._along_free(len(cols))(Y, P, D, E.ravel(order="F"))[0]
        return columns_appended(self._jy(Y, P, D)[0], self.pattern,
                                 jp.reshape(self.n_equations, -1, order="F"))


class EquilibriumProblem(Problem):
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
            counts["hopf"] = _eigen.count_unstable(base.eigenvalues)
            counts["hopf_complex"] = _eigen.count_complex_unstable(
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
    ref = _eigen.crossing_eigenvalue(info_a.eigenvalues, info_b.eigenvalues, tol)
    if ref is None:
        return lambda X, tau, lu: 1.0  # no complex eigenvalue: nothing crosses

    def f(X, tau, lu):
        ev = problem.eigenvalues(X, settings)
        ev = ev[ev.imag > tol]
        return float(_eigen.nearest(ev, ref).real) if ev.size else 1.0

    return f


def real_null_vector(J) -> np.ndarray:
    """Real ``v`` with ``J v ~ 0``, ``|v| = 1``."""
    q = _eigen.eigenvector(J, sp.identity(J.shape[0], format="csc"), 0.0)
    q = q * np.exp(-1j * np.angle(q[np.argmax(np.abs(q))]))
    v = q.real
    return v / np.linalg.norm(v)


def _refine_fold(problem, X, settings) -> Description:
    """Newton on ``F = 0, J v = 0, c.v = 1`` with the active parameter free."""
    vf = problem.vf
    J, _ = problem.matrices(X)
    v = real_null_vector(J)
    sysf = bound(vf, "fold", problem.params(X), v, problem.free)
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
    psi = _eigen.left_eigenvector(J, M, 0.0)
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


def hopf_system(vf: VectorField) -> CompiledSystem:
    """The Hopf system of ``_systems`` (``M v``, ``M w`` by the field's mass action when it
    has one) with its Jacobian written from its structure instead of by AD of the residual.

    With ``J = F_x`` the rows ``J v - M w`` and ``J w + kappa M v`` have the x-blocks
    ``D_x(J v) = D_v J`` (symmetry of second derivatives: one directional derivative
    of ``J`` instead of ``n``) minus ``D_x(M w)``, and the linear blocks ``J, -M,
    kappa M, M v``; likewise ``D_p(J v) = D_v F_p``. Equal to the AD Jacobian to
    rounding; for the 22-state modal model of 10 modes 13x cheaper to evaluate (4.5 ->
    0.35 ms, with the field's functions inlined)."""
    x, v, w, c = (vf.sym.sym(name, vf.n) for name in "xvwc")
    kappa, p = vf.sym.sym("kappa"), vf.sym.sym("p", len(vf.par_names))
    f, m = _flat_field(vf, x, p)
    mv, mw = _flat_mass_action(vf, x, p, v, m), _flat_mass_action(vf, x, p, w, m)
    G = [ca.vertcat(f, ca.jtimes(f, x, v) - mw, ca.jtimes(f, x, w) + kappa * mv),
         ca.vertcat(ca.dot(c, v) - 1, ca.dot(c, w))]
    jy = _hopf_jacobian_y(vf, x, v, w, kappa, p, c, f, m)

    def along(E):   # D_p(J v) E = D_v (F_p E), D_p(M w) E
        FpE = ca.jtimes(f, p, E)
        k = E.size2()
        Fpv, Fpw = ca.horzsplit(ca.jtimes(FpE, x, ca.horzcat(v, w)), [0, k, 2 * k])
        Mw_p, Mv_p = ca.jtimes(mw, p, E), ca.jtimes(mv, p, E)
        return ca.vertcat(FpE, Fpv - Mw_p, Fpw + kappa * Mv_p, vf.sym(2, k))

    return FreeDirectionSystem(ca.vertcat(x, v, w, kappa), p, c, G, "hopf", jy, along)


def _flat_field(vf, x, p):
    """``F(x, p)`` and ``M(x, p)`` with MX functions inlined: derivatives of the flat
    graph evaluate 2-3x faster than derivatives through call nodes (same values)."""
    return _inlined(vf, vf.F, x, p), \
        vf.M_expr(x, p) if vf.M is None else _inlined(vf, vf.M, x, p)


def _inlined(vf, fun, *args):
    """``fun(*args)``, inlined (no call node) for an MX field."""
    return fun.call(list(args), True, False)[0] if vf.sym is ca.MX else fun(*args)


def _state_jacobian(vf, x, p, f):
    """``dF/dx``: the field's ``jacobian`` when given (cheaper, also to differentiate
    again), else AD of ``f``."""
    return ca.jacobian(f, x) if vf.jacobian is None else _inlined(vf, vf.jacobian, x, p)


def _flat_mass_action(vf, x, p, y, m):
    """``M(x, p) y`` to differentiate: the field's matrix-free ``mass_action`` when it
    has one, else ``m y``. For the modal model of 40 modes the x-derivative of ``M w,
    M v`` costs 0.7 ms this way and 11 ms through ``m``."""
    return ca.mtimes(m, y) if vf.mass_action is None else _inlined(vf, vf.mass_action, x, p, y)


def _mass_action_x(vf, x, p, ys, m):
    """``[d(M y)/dx for y in ys]`` stacked: the field's ``mass_action_jacobian`` when
    given, else one AD Jacobian of the stacked products."""
    if vf.mass_action_jacobian is not None:
        return ca.vertcat(*[_inlined(vf, vf.mass_action_jacobian, x, p, y) for y in ys])
    return ca.jacobian(ca.vertcat(*[_flat_mass_action(vf, x, p, y, m) for y in ys]), x)


def _hopf_jacobian_y(vf, x, v, w, kappa, p, c, f, m):
    """``G_Y`` of the Hopf system, ``Y = (x, v, w, kappa)`` (:func:`hopf_system`)."""
    n, S = vf.n, vf.sym
    J = _state_jacobian(vf, x, p, f)
    # both directions / both rows in one derivative (shared sweeps: 20 % cheaper)
    Jv, Jw = ca.horzsplit(ca.jtimes(J, x, ca.horzcat(v, w)), [0, n, 2 * n])
    Mw_x, Mv_x = ca.vertsplit(_mass_action_x(vf, x, p, (w, v), m), [0, n, 2 * n])
    O, z, row = S(n, n), S(n, 1), S(1, n)
    return ca.blockcat([
        [J, O, O, z],
        [Jv - Mw_x, J, -m, z],
        [Jw + kappa * Mv_x, kappa * m, J, ca.mtimes(m, v)],
        [row, c.T, row, S(1, 1)],
        [row, row, c.T, S(1, 1)]])


def hopf_point(problem: "EquilibriumProblem", x, omega: float, settings=None):
    """Locate a Hopf point from a guess: Newton on the Hopf system with the active
    parameter free, started from state ``x`` at the problem's parameter values and the
    eigenvector of ``J q = i omega M q`` (omega: a guess of the critical frequency, which
    picks the eigenvalue — not the one nearest the axis). Returns a SpecialPoint with
    ``omega`` and ``l1`` in ``data``; status 'guess' with the residual if Newton fails."""
    from ._branch import SpecialPoint
    from ._settings import ContinuationSettings
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
        ev = _eigen.eigenvalues(J, M, settings.eigen)
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
