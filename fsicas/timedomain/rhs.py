"""Compiled right-hand sides of time integration: the explicit ODE with time and the
pressure schedule as inputs, and the CasADi integrator objects of each route.

Extended parameters ``pe = (p, sched, t_offset)``: Δp in p is replaced by the schedule's
``Δp(t_offset + t)``. IDAS integrates ``x' = z, 0 = M(x) z − F(x)``; CVODES and SciPy
integrate ``xdot = M(x)^{-1} F(x)`` with the Jacobian of :func:`explicit_ode`.
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from .breathing import N_SCHEDULE_PARAMS, schedule_expression
from ..model import contact
from ..model.assembly import Model
from ..model.contact import GAP_POINTS

__all__ = ["ode_symbols", "explicit_ode", "implicit_residual", "compiled_route"]


def ode_symbols(model: Model):
    """Symbols and the explicit ODE of the model with time and schedule as inputs.

    Extended parameters ``pe = (p, sched, t_offset)``: Δp in p is replaced by the
    schedule's Δp(t_offset + t).
    """
    nx, npar = model.n_state, len(model.parameter_names)
    x = ca.MX.sym("x", nx)
    pe = ca.MX.sym("pe", npar + N_SCHEDULE_PARAMS + 1)
    t = ca.MX.sym("t")
    p, sched, t0 = pe[:npar], pe[npar:npar + N_SCHEDULE_PARAMS], pe[-1]
    i = model.index("pressure_drop")
    p_t = ca.vertcat(p[:i], schedule_expression(t0 + t, sched), p[i + 1:])
    return x, pe, t, p_t, _nan_if_closed(model, x, model.rhs(x, p_t))


def explicit_ode(model: Model, x, pe, t, p_t, F):
    """``xdot = M⁻¹F`` as a call to a Function of (x, pe, t) whose Jacobian CasADi does not
    derive by AD through M, and a Function ``J(t, x, pe)`` of that Jacobian's x-block:

        d(M⁻¹F)/dy = M⁻¹ (F_y − ∂(M v)/∂y |_{v = xdot}),   y in (x, pe, t),

    where the derivative of M enters only through the matrix-free ``M v``: O(N K) per
    direction instead of O(N² K) (x-block 3.5 instead of 18 ms at N = 40), and the
    x-block is the model's lifted ``F_x − d(M v)/dx`` (:mod:`fsicas.model.equations`)
    instead of AD in 2N + 2 directions. It is the
    Function's ``custom_jacobian``, so CVODES's Newton matrix uses it too (7.8 instead of
    17.6 ms per evaluation at N = 40: CVODES gets all three blocks).
    """
    M = model.mass(x, p_t)
    xdot = ca.solve(M, F)
    args = [x, pe, t]

    def jacobian(y):
        v = ca.MX.sym("v", model.n_state)
        dMv = ca.Function("dMv", [*args, v], [ca.jacobian(model.mass_action(x, p_t, v), y)])
        return ca.solve(M, ca.jacobian(F, y) - dMv(*args, xdot))

    # the x-block from the model's lifted Jacobians (where a gap is closed F, and so the
    # right-hand side, is NaN and the solver stops whatever this block holds)
    x_block = ca.solve(M, model.jac_rhs(x, p_t) - model.jac_mass_action(x, p_t, xdot))
    rest = jacobian(ca.vertcat(pe, t))
    blocks = [x_block, *ca.horzsplit(rest, [0, pe.numel(), pe.numel() + 1])]
    custom = ca.Function("jac_xdot", [*args, ca.MX.sym("out", model.n_state)], blocks,
                         ["x", "pe", "t", "out_xdot"], ["jac_xdot_x", "jac_xdot_pe", "jac_xdot_t"])
    f = ca.Function("xdot", args, [xdot], ["x", "pe", "t"], ["xdot"],
                    {"custom_jacobian": custom, "jac_penalty": 0, "never_inline": True})
    return f(x, pe, t), ca.Function("J", [t, x, pe], [x_block])


def implicit_residual(model: Model, x, z, pe, t, p_t, F):
    """``M(x) z − F(x)`` (the matrix-free ``M z``) as a call to a Function whose Jacobian
    is given, not derived by AD: ``d/dx = d(M z)/dx − F_x`` from the model's lifted
    Jacobians, ``d/dz = M``, the ``pe``- and ``t``-blocks by AD (through ``p_t`` only)."""
    args = [x, z, pe, t]
    residual = model.mass_action(x, p_t, z) - F
    rest = ca.jacobian(residual, ca.vertcat(pe, t))
    blocks = [model.jac_mass_action(x, p_t, z) - model.jac_rhs(x, p_t), model.mass(x, p_t),
              *ca.horzsplit(rest, [0, pe.numel(), pe.numel() + 1])]
    custom = ca.Function("jac_res", [*args, ca.MX.sym("out", model.n_state)], blocks,
                         ["x", "z", "pe", "t", "out_res"],
                         ["jac_res_x", "jac_res_z", "jac_res_pe", "jac_res_t"])
    f = ca.Function("res", args, [residual], ["x", "z", "pe", "t"], ["res"],
                    {"custom_jacobian": custom, "jac_penalty": 0, "never_inline": True})
    return f(*args)


def _nan_if_closed(model: Model, x, F):
    """F, or NaN once a gap at the check points or the nodes is <= 0.

    The flow is singular at ``h_c = 0``; NaN makes the solver's error test fail at once,
    so a closing gap ends the chunk with a solver error (reported) in a few steps
    instead of an endless step-size collapse.
    """
    n = model.n_modes
    xs = np.union1d(GAP_POINTS, model.basis.x)
    y = ca.mtimes(model.basis_at(xs).phi.T, x[n:2 * n])
    h = contact.wall_gaps([np.asarray(w(xs), float) for w in model.scene.walls], y)
    gap = ca.fmin(ca.mmin(h[0]), ca.mmin(h[1]))
    return ca.if_else(gap > 0, F, np.nan * ca.DM.ones(F.shape[0]))


def compiled_route(model: Model, s, span: float, n_out: int) -> dict:
    """The CasADi objects of an :class:`~fsicas.timedomain.integrators.Integrator`'s route
    for settings ``s`` (method, tolerances, step limit) on the output grid of one chunk,
    by the Integrator's private field name."""
    x, pe, t, p_t, F = ode_symbols(model)
    grid = list(np.linspace(0.0, span, n_out + 1)[1:])
    opts = {"abstol": s.atol, "reltol": s.rtol, "max_num_steps": s.max_steps,
            "disable_internal_warnings": True, "regularity_check": True}
    if s.method == "idas":   # needs no Jacobian of M⁻¹F (0.12 s to build at N = 40)
        z = ca.MX.sym("z", model.n_state)
        dae = {"x": x, "z": z, "p": pe, "t": t, "ode": z,
               "alg": implicit_residual(model, x, z, pe, t, p_t, F)}
        return {"_idas": (dae, grid, {**opts, "calc_ic": False, "suppress_algebraic": True}),
                "_zfun": ca.Function("z0", [x, pe, t], [ca.solve(model.mass(x, p_t), F)])}
    xdot, jac = explicit_ode(model, x, pe, t, p_t, F)
    if s.method == "cvodes":
        return {"_fn": ca.integrator("sim", "cvodes", {"x": x, "p": pe, "t": t, "ode": xdot},
                                     0.0, grid, opts)}
    return {"_rhs": ca.Function("f", [t, x, pe], [xdot]), "_jac": jac}
