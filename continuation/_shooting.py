"""Periodic orbits by multiple shooting with a CasADi integrator.

With ``m`` segments and the flow ``phi(x, s; T, p)`` of
``dx/ds = (T/m) M(x, p)^{-1} F(x, p)`` over ``s in [0, 1]`` (CVODES by default),
the unknowns ``X = (x_0, ..., x_{m-1}, T, p)`` satisfy

    phi(x_i, 1; T, p) - x_{i+1} = 0    (i = 0..m-1, x_m = x_0),
    <f_ref, x_0 - x_ref> = 0           (Poincare phase condition),

``x_ref`` the last accepted ``x_0`` and ``f_ref`` the vector field there. The
exact Jacobian comes from the integrator's forward sensitivities (CasADi
differentiates the integrator call), and the diagonal blocks ``d phi / d x_i``
are the transfer matrices whose product is the monodromy matrix, so the
Floquet multipliers use the same block-cyclic pencil as collocation.
``M`` must be invertible (it is solved for symbolically: ``ca.solve``).
"""

from __future__ import annotations

from typing import Mapping

import casadi as ca
import numpy as np
import scipy.sparse as sp

from . import _floquet
from ._cycles import PeriodicProblem, _sample
from ._settings import ShootingSettings
from ._symbolic import CompiledSystem
from ._systems import bound


def flow(vf, settings: ShootingSettings) -> ca.Function:
    """Integrator of ``dx/ds = (T/m) M^{-1} F`` over ``s in [0, 1]``, params ``(T, p)``."""
    x = ca.MX.sym("x", vf.n)
    q = ca.MX.sym("q", 1 + len(vf.par_names))
    T, p = q[0], q[1:]
    f = vf.F(x, p) if vf.M is None else ca.solve(vf.M(x, p), vf.F(x, p))
    opts = {"abstol": settings.abstol, "reltol": settings.reltol,
            "disable_internal_warnings": True} \
        if settings.integrator != "rk" else {"number_of_finite_elements": 200}
    return ca.integrator("flow", settings.integrator,
                         {"x": x, "p": q, "ode": T / settings.segments * f}, 0.0, 1.0, opts)


def builder(settings: ShootingSettings):
    """``builder(vf) -> CompiledSystem`` of the shooting system ``G(x_i, T, p; x_ref, f_ref)``."""

    def build(vf) -> CompiledSystem:
        n, m = vf.n, settings.segments
        xs, T = ca.MX.sym("xs", n * m), ca.MX.sym("T")
        p, D = ca.MX.sym("p", len(vf.par_names)), ca.MX.sym("D", 2 * n)
        phi = flow(vf, settings).map(m)
        xm = ca.reshape(xs, n, m)
        ends = phi(x0=xm, p=ca.repmat(ca.vertcat(T, p), 1, m))["xf"]
        nxt = ca.horzcat(xm[:, 1:], xm[:, :1])
        G = [ca.vec(ends - nxt), ca.dot(D[n:], xs[:n] - D[:n])]
        return CompiledSystem(ca.vertcat(xs, T), p, D, G, f"shooting_{m}")

    return build


class ShootingProblem(PeriodicProblem):
    """Branch of periodic orbits by multiple shooting (same arguments as
    :class:`CycleProblem`, with :class:`ShootingSettings`)."""

    def __init__(self, F, orbit, period: float, params: Mapping[str, float], active: str,
                 *, M=None, settings: ShootingSettings | None = None):
        settings = ShootingSettings() if settings is None else settings
        p0 = self._setup(F, M, params, active, period, settings, ShootingSettings)
        vf, self.segments = self.vf, settings.segments
        xs = _sample(orbit, np.arange(self.segments) / self.segments, vf.n)
        self.X0 = np.concatenate([xs, [float(period), p0[self.free_idx[0]]]])
        key = (f"shooting_{self.segments}_{settings.integrator}_{settings.abstol:g}_"
               f"{settings.reltol:g}")
        self.system = bound(vf, key, p0, self._reference(xs[: vf.n], p0), self.free,
                            builder(settings))

    def residual(self, X) -> np.ndarray:
        """``G(X)``; an integrator failure gives ``inf`` (a failed Newton step, as data)."""
        try:
            return super().residual(X)
        except RuntimeError:
            return np.full(self.system.compiled.n_equations, np.inf)

    def jacobian(self, X):
        """Exact ``G_X`` from the integrator sensitivities (zero, hence singular for
        the corrector, if the integrator fails)."""
        try:
            return super().jacobian(X)
        except RuntimeError:
            return sp.csc_matrix((self.system.compiled.n_equations, len(X)))

    def _reference(self, x, p) -> np.ndarray:
        M = self.vf.mass(x, p).toarray()
        return np.concatenate([x, np.linalg.solve(M, self.vf.rhs(x, p))])

    def points(self, X) -> np.ndarray:
        """Shooting points ``(segments, n)`` at ``t = i / segments``."""
        return np.asarray(X[: self.segments * self.vf.n]).reshape(self.segments, self.vf.n)

    def period(self, X) -> float:
        return float(X[self.segments * self.vf.n])

    def accept(self, X) -> None:
        """Phase reference <- ``x_0`` of the accepted cycle."""
        self.system.D = self._reference(self.state(X), self.params(X))

    def columns(self, X) -> dict:
        return {"period": self.period(X)}

    def transfer_matrices(self, X) -> np.ndarray:
        """``d phi / d x_i`` of every segment (their product is the monodromy matrix)."""
        n, m = self.vf.n, self.segments
        J = self.jacobian(X).tocsr()
        return np.array([J[i * n:(i + 1) * n, i * n:(i + 1) * n].toarray() for i in range(m)])

    def multipliers(self, X) -> np.ndarray:
        """Floquet multipliers sorted by decreasing modulus."""
        return _floquet.multipliers(self.transfer_matrices(X), self.settings.floquet)
