"""Periodic orbits by multiple shooting with a CasADi integrator.

With ``m`` segments and the flow ``phi(x, s; T, p)`` of
``dx/ds = (T/m) M(x, p)^{-1} F(x, p)`` over ``s in [0, 1]`` (CVODES by default),
the unknowns ``X = (x_0, ..., x_{m-1}, T, p)`` satisfy

    phi(x_i, 1; T, p) - x_{i+1} = 0    (i = 0..m-1, x_m = x_0),
    <f_ref, x_0 - x_ref> = 0           (Poincare phase condition),

``x_ref`` the last accepted ``x_0`` and ``f_ref`` the vector field there. The
exact Jacobian comes from the integrator's forward sensitivities. By default
(``ShootingSettings.jacobian = 'blocks'``) the segments are integrated once each
(one mapped call, over ``ShootingSettings.threads`` threads) with sensitivities in
the ``n + 1 + n_free`` directions ``(x_i, T, p_free)`` only (the other parameters
enter as a non-differentiated input) and the blocks are assembled sparse;
``'graph'`` lets CasADi differentiate the whole mapped integrator in the directions
of all parameters (the reference; 2x slower at n = 20, see docs/continuation.md).
The diagonal blocks ``d phi / d x_i`` are the transfer matrices whose product is
the monodromy matrix, so the Floquet multipliers use the same periodic Schur route
as collocation; they reuse the last Jacobian (the tangent's) at the same ``X``.

Where the time goes (flutter model with contact, N = 10, one impacting segment at
``abstol = reltol = 1e-10``): CVODES takes ~5x more steps with the sensitivities in
its error test than without; per step, CasADi's augmented Newton evaluates the
sensitivity right-hand side (AD of ``M^{-1} F`` in all 24 directions, ~20 %) and the
second-order term of the augmented Newton matrix (AD of that in 24 directions
again, ~70 %); CVODES itself and Python take the rest. ``sensitivities='fast'``
removes both: the rate's Jacobian by formula (:func:`rate_function`) times all
directions, and no second-order term (15x faster; the two routes differ by
integration error only, 7e-10 relative at 1e-10 where each is 4e-9 off a reference
at 1e-13, see :class:`ShootingSettings`). Compiling the integrator's
functions to C (CasADi's ``jit`` option) keeps 'exact' to the last bit at 3.7x the
speed (N = 4), but compiled for 260 s at N = 4 in every new process, so it is not
offered; threads pay only on an otherwise idle machine (1.8x on 2 cores).
``M`` must be invertible (it is solved for symbolically: ``ca.solve``).
"""

from __future__ import annotations

from typing import Mapping

import casadi as ca
import numpy as np
import scipy.sparse as sp

from .cycles import sample_orbit
from .periodic import PeriodicProblem
from .._casadi.symbolic import CompiledSystem, bound
from .settings import ShootingSettings


def options(settings: ShootingSettings) -> dict:
    """CasADi integrator options of ``settings`` (tolerances for SUNDIALS, a fixed
    grid for 'rk'). CasADi forms forward sensitivities by appending the variational
    equations to the ODE, so SUNDIALS' own ``sensitivity_method``/``fsens_err_con``
    have no effect (measured: identical Jacobians to the last bit)."""
    if settings.integrator == "rk":
        return {"number_of_finite_elements": 200}
    return {"abstol": settings.abstol, "reltol": settings.reltol,
            "disable_internal_warnings": True}


def _rate(vf, x, p):
    """``M(x, p)^{-1} F(x, p)`` (symbolic solve)."""
    return vf.F(x, p) if vf.M is None else ca.solve(vf.M(x, p), vf.F(x, p))


def flow(vf, settings: ShootingSettings) -> ca.Function:
    """Integrator of ``dx/ds = (T/m) M^{-1} F`` over ``s in [0, 1]``, params ``(T, p)``."""
    x = ca.MX.sym("x", vf.n)
    q = ca.MX.sym("q", 1 + len(vf.par_names))
    T, p = q[0], q[1:]
    return ca.integrator("flow", settings.integrator,
                         {"x": x, "p": q, "ode": T / settings.segments * _rate(vf, x, p)},
                         0.0, 1.0, options(settings))


def segment_ode(vf, settings: ShootingSettings, free_idx: tuple) -> dict:
    """ODE of one segment, ``dx/ds = (T/m) M^{-1} F``, whose parameter input is
    ``p = (T, p_free)`` only; the full parameter vector enters as the control
    ``u`` (its free entries unused), which the sensitivities do not differentiate."""
    x = ca.MX.sym("x", vf.n)
    q = ca.MX.sym("q", 1 + len(free_idx))
    u = ca.MX.sym("u", len(vf.par_names))
    p = ca.vertcat(*[q[1 + free_idx.index(i)] if i in free_idx else u[i]
                     for i in range(len(vf.par_names))])
    return {"x": x, "p": q, "u": u, "ode": q[0] / settings.segments * _rate(vf, x, p)}


def fixed_parameters(settings: ShootingSettings, free_idx: tuple, p) -> tuple:
    """The values of the non-free parameters that the 'fast' route fixes in its
    segment integrator (empty for 'exact', whose integrator takes them as input)."""
    if settings.sensitivities == "exact":
        return ()
    return tuple(float(v) for i, v in enumerate(p) if i not in free_idx)


def rate_function(vf, free_idx: tuple, fixed: tuple) -> ca.Function:
    """``R(x, p_free) = M^{-1} F`` (the other parameters fixed at ``fixed``) whose
    derivatives CasADi takes from the custom Jacobian ``[dR/dx, dR/dp_free]`` =
    ``M^{-1} [F_x - d(M v)/dx, F_p - d(M v)/dp]`` at ``v = R`` (the field's
    ``Fx_expr``/``Mvx_expr``): one evaluation per right-hand side, multiplied into
    every sensitivity direction, instead of AD of the solve in each of them."""
    n, values = vf.n, iter(fixed)
    x, r, pf = ca.MX.sym("x", n), ca.MX.sym("r", n), ca.MX.sym("pf", len(free_idx))
    p = ca.vertcat(*[pf[free_idx.index(i)] if i in free_idx else next(values)
                     for i in range(len(vf.par_names))])
    F = vf.F(x, p)
    J = ca.horzcat(vf.Fx_expr(x, p) - (0 if vf.M is None else vf.Mvx_expr(x, p, r)),
                   ca.jacobian(F - (0 if vf.M is None else vf.Mv_expr(x, p, r)), pf))
    if vf.M is not None:
        M = vf.M(x, p)
        F, J = ca.solve(M, F), ca.solve(M, J)
    jac = ca.Function("jac_rate", [x, pf, r], [J[:, :n], J[:, n:]],
                      ["x", "pf", "out_r"], ["jac_r_x", "jac_r_pf"])
    return ca.Function("rate", [x, pf], [F], ["x", "pf"], ["r"],
                       {"custom_jacobian": jac, "jac_penalty": 0, "enable_forward": False,
                        "enable_fd": False, "never_inline": True})


def _segment_integrator(vf, settings: ShootingSettings, free_idx: tuple, fixed: tuple):
    """The integrator of one segment: for 'exact' the ODE of :func:`segment_ode`;
    for 'fast' ``dx/ds = (T/m) R(x, p_free)`` with :func:`rate_function`, without
    the second-order term of the augmented Newton matrix (CasADi's
    ``second_order_correction``: a derivative of the sensitivity equations in all
    directions at every Newton iteration, 70 % of the time of 'exact')."""
    opts = options(settings)
    if settings.sensitivities == "exact":
        return ca.integrator("segment", settings.integrator,
                             segment_ode(vf, settings, free_idx), 0.0, 1.0, opts)
    x, q = ca.MX.sym("x", vf.n), ca.MX.sym("q", 1 + len(free_idx))
    rate = rate_function(vf, free_idx, fixed)
    if settings.integrator != "rk":
        opts = {**opts, "second_order_correction": False}
    return ca.integrator("segment", settings.integrator,
                         {"x": x, "p": q, "ode": q[0] / settings.segments * rate(x, q[1:])},
                         0.0, 1.0, opts)


def segment_jacobian(vf, settings: ShootingSettings, free_idx: tuple, p) -> ca.Function:
    """``(x0 (n, m), (T, p_free), p) -> (xf, [d xf/d x0 of each segment], [d xf/d
    (T, p_free) of each])``: all ``m`` segments (forward sensitivities in
    ``n + 1 + len(free)`` directions each), mapped over ``settings.threads``
    threads; built once per VectorField, settings, free parameters and (for
    'fast') values of the fixed parameters ``p``."""
    cache = vf.__dict__.setdefault("_shooting_segments", {})
    fixed = fixed_parameters(settings, tuple(free_idx), p)
    key = (settings, tuple(free_idx), fixed)
    if key not in cache:
        integ = _segment_integrator(vf, settings, tuple(free_idx), fixed)
        exact = settings.sensitivities == "exact"
        one = integ.factory("segment_jac", ["x0", "p", "u"] if exact else ["x0", "p"],
                            ["xf", "jac:xf:x0", "jac:xf:p"])
        m = settings.segments
        mapped = one.map(m, "thread", settings.threads) if settings.threads > 1 else one.map(m)
        cache[key] = mapped if exact else (lambda x0, q, u, f=mapped: f(x0, q))
    return cache[key]


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
    :class:`CycleProblem`, with :class:`ShootingSettings`).

    The residual integrates all segments without sensitivities. The Jacobian is,
    with ``settings.jacobian == 'blocks'``, assembled from one sensitivity
    integration per segment in the directions ``(x_i, T, p_free)``; with
    ``'graph'``, CasADi's derivative of the whole mapped integrator. Either way the
    last one is kept, so the Floquet multipliers at the tangent's ``X`` reuse it.
    """

    def __init__(self, F, orbit, period: float, params: Mapping[str, float], active: str,
                 *, M=None, settings: ShootingSettings | None = None):
        settings = ShootingSettings() if settings is None else settings
        p0 = self._setup(F, M, params, active, period, settings, ShootingSettings)
        vf, self.segments = self.vf, settings.segments
        xs = sample_orbit(orbit, np.arange(self.segments) / self.segments, vf.n)
        self.X0 = np.concatenate([xs, [float(period), p0[self.free_idx[0]]]])
        key = (f"shooting_{self.segments}_{settings.integrator}_{settings.abstol:g}_"
               f"{settings.reltol:g}")
        self.system = bound(vf, key, p0, self._reference(xs[: vf.n], p0), self.free,
                            builder(settings))
        self._segment = settings.jacobian == "blocks"
        self._samplers, self._last = {}, (None, None)

    def residual(self, X) -> np.ndarray:
        """``G(X)``; an integrator failure gives ``inf`` (a failed Newton step, as data)."""
        try:
            return super().residual(X)
        except RuntimeError:
            return np.full(self.system.compiled.n_equations, np.inf)

    def jacobian(self, X):
        """Exact ``G_X`` from the integrator sensitivities (zero, hence singular for
        the corrector, if the integrator fails)."""
        if not self._segment:
            return self._graph_jacobian(X)
        blocks = self.blocks(X)
        if blocks is None:
            return sp.csc_matrix((self.system.compiled.n_equations, len(X)))
        return self._assemble(*blocks)

    def _graph_jacobian(self, X):
        """CasADi's Jacobian of the whole shooting graph (kept for the last ``X``)."""
        try:
            J = super().jacobian(X)
        except RuntimeError:
            J = sp.csc_matrix((self.system.compiled.n_equations, len(X)))
        self._last = (np.array(X), J)
        return J

    def blocks(self, X):
        """``(A, B)``: ``A[i] = d phi / d x_i`` ``(m, n, n)`` and ``B[i] = d phi /
        d (T, p_free)`` ``(m, n, 1 + n_free)`` of every segment at ``X`` (kept for
        the last ``X``); None if the integrator fails."""
        if self._last[0] is not None and np.array_equal(self._last[0], X):
            return self._last[1]
        q, u = self._segment_args(X)
        segment = segment_jacobian(self.vf, self.settings, self.free_idx, u)
        n, m = self.vf.n, self.segments
        try:
            _, A, B = segment(self.points(X).T, q, u)
            blocks = (A.full().reshape(n, m, n).transpose(1, 0, 2),
                      B.full().reshape(n, m, -1).transpose(1, 0, 2))
        except RuntimeError:
            blocks = None
        self._last = (np.array(X), blocks)
        return blocks

    def _segment_args(self, X):
        """``(T, p_free)`` and the full parameter vector at ``X``."""
        nf = len(self.free)
        return np.r_[self.period(X), X[len(X) - nf:]], self.params(X)

    def _assemble(self, A, B) -> sp.csc_matrix:
        """``[A_i in (i, i), -I in (i, i+1 mod m), B_i in (i, (T, p_free)); f_ref^T in
        (phase, x_0)]`` as one sparse matrix."""
        m, n, nb = B.shape
        seg = np.arange(m)[:, None, None] * n
        r = seg + np.arange(n)[None, :, None]
        eye = np.arange(m * n)
        rows = [np.broadcast_to(r, A.shape), eye, np.broadcast_to(r, B.shape),
                np.full(n, m * n)]
        cols = [np.broadcast_to(seg + np.arange(n)[None, None, :], A.shape),
                (eye + n) % (m * n), np.broadcast_to(m * n + np.arange(nb), B.shape),
                np.arange(n)]
        vals = [A, -np.ones(m * n), B, self.system.D[n:]]
        flat = lambda parts: np.concatenate([np.ravel(v) for v in parts])
        return sp.csc_matrix((flat(vals), (flat(rows), flat(cols))),
                             shape=(m * n + 1, m * n + nb))

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

    def sample(self, X, k: int) -> tuple[np.ndarray, np.ndarray]:
        """``(t, x)``: the cycle at ``k`` outputs per segment, ``t = (i + j/k)/m`` in
        ``[0, 1)`` and ``x`` of shape ``(m k, n)``, integrated without sensitivities
        from each shooting point (``x[i k]`` is the shooting point ``x_i``). Raises
        RuntimeError if the integrator fails."""
        if not (isinstance(k, (int, np.integer)) and not isinstance(k, bool) and k >= 1):
            raise ValueError(f"k must be a positive integer, got {k!r}")
        integ = self._sampler(int(k))
        q, u = self._segment_args(X)
        xs = self.points(X)
        out = [np.c_[x, integ(x0=x, p=q, u=u)["xf"].full()[:, :-1]].T for x in xs]
        t = (np.arange(self.segments)[:, None] + np.arange(k)[None, :] / k).ravel()
        return t / self.segments, np.concatenate(out)

    def _sampler(self, k: int) -> ca.Function:
        """Integrator of one segment with outputs at ``s = 1/k, ..., 1``."""
        if k not in self._samplers:
            ode = segment_ode(self.vf, self.settings, self.free_idx)
            self._samplers[k] = ca.integrator("sampler", self.settings.integrator, ode, 0.0,
                                              np.arange(1, k + 1) / k,
                                              options(self.settings))
        return self._samplers[k]

    def transfer_matrices(self, X) -> np.ndarray:
        """``d phi / d x_i`` of every segment (their product is the monodromy
        matrix), from the last Jacobian when it was taken at ``X``."""
        n, m = self.vf.n, self.segments
        if self._segment:
            blocks = self.blocks(X)
            return np.zeros((m, n, n)) if blocks is None else blocks[0]
        last = self._last
        J = last[1] if last[0] is not None and np.array_equal(last[0], X) \
            else self._graph_jacobian(X)
        J = J.tocsr()
        return np.array([J[i * n:(i + 1) * n, i * n:(i + 1) * n].toarray() for i in range(m)])

    def multipliers(self, X) -> np.ndarray:
        """Floquet multipliers sorted by decreasing modulus (kept for the last ``X``)."""
        return self.floquet_multipliers(X, self.settings.floquet)
