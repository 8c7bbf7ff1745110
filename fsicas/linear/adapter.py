"""Adapter of the model to the generic ``continuation`` library.

The library's pseudo-arclength steps mix all unknowns in one length, so the whole
(M*, U*) plane is made well scaled: the parameters become

    Π = kinematic_pressure_drop = Δp / (M* PI_SCALE)     (≈ 3.3 U*^2 / PI_SCALE, whatever M*)
    log10_mstar = log10 M*

(then the model's remaining parameters, in order; Π < 0 for reversed flow, U* < 0), and time is measured in units of
T / TIME_SCALE, i.e. the adapted field is ``(TIME_SCALE M(x, p)) xdot = F(x, p)``, so that
Hopf frequencies (20–600 in units of 1/T) and kappa = omega^2 are O(1). The first Lyapunov
coefficient l1 is invariant under that time scaling.
"""
from __future__ import annotations

import math

import casadi as ca
import numpy as np

import continuation as C

from ..model.assembly import Model, per_model
from ..scene import Scene
from .steady import SteadyState, SteadyStateError, steady_state

__all__ = ["PI", "LOG_M", "PI_SCALE", "TIME_SCALE", "reparametrized_field", "flutter_field",
           "pi_of", "speed_window", "pi_interval", "speed", "field_parameters", "steady_ustar",
           "dense"]

PI, LOG_M = "kinematic_pressure_drop", "log10_mstar"
PI_SCALE, TIME_SCALE = 100.0, 100.0


def reparametrized_field(model: Model) -> dict:
    """The model's functions in the parameters ``q = (Δp/(M* PI_SCALE), log10 M*, the
    rest, in order)`` with M multiplied by TIME_SCALE (time in units of T/TIME_SCALE):
    ``F`` of ``(x, q)``, ``Mv`` of ``(x, q, v)``, the lifted ``M``, ``dFdx`` and
    ``dMvdx`` (:class:`continuation.Lifted`), and the names of ``q`` under ``"names"``."""
    rest = [name for name in model.parameter_names if name not in ("pressure_drop", "mstar")]
    names = [PI, LOG_M, *rest]
    x, v = ca.MX.sym("x", model.n_state), ca.MX.sym("v", model.n_state)
    q = ca.MX.sym("p", len(names))
    value = {name: q[i] for i, name in enumerate(names)}
    mstar = 10 ** value[LOG_M]
    value.update(pressure_drop=value[PI] * PI_SCALE * mstar, mstar=mstar)
    p = ca.vertcat(*[value[name] for name in model.parameter_names])
    p_of_q = ca.Function("p_of_q", [q], [p])
    lifted = model.lifted
    return {"names": names,
            "F": ca.Function("F", [x, q], [_inline(model.rhs, x, p)]),
            "Mv": ca.Function("Mv", [x, q, v], [TIME_SCALE * _inline(model.mass_action, x, p, v)]),
            "M": lifted["mass"].reparametrized(p_of_q, TIME_SCALE),
            "dFdx": lifted["jac_rhs"].reparametrized(p_of_q),
            "dMvdx": lifted["jac_mass_action"].reparametrized(p_of_q, TIME_SCALE)}


def _inline(fun: ca.Function, *args):
    """``fun(*args)`` with the model's expression graph inlined, not as a call node: AD
    of the flat graph (the library's Jacobians of F and M v) costs 2-3x less than AD
    through a call of the model's Function (14 vs 34 ms for dF/dx at 80 points, N = 10)."""
    return fun.call(list(args), True, False)[0]


@per_model
def flutter_field(model: Model) -> C.VectorField:
    """The reparametrized VectorField of ``model``, built once per model (the library
    caches its compiled augmented systems on it). Kept as MX: the dense modal blocks
    would be multiplied out by an SX expansion (40x slower to build at N = 10). Its
    ``dF/dx`` and ``d(M v)/dx`` are the model's lifted Jacobians, not AD of ``F``."""
    f = reparametrized_field(model)
    return C.VectorField(f["F"], f["M"], tuple(f["names"]), expand=False, mass_action=f["Mv"],
                         jacobian=f["dFdx"], mass_action_jacobian=f["dMvdx"])


def dense(a) -> np.ndarray:
    """A NumPy array of a sparse or dense matrix."""
    return a.toarray() if hasattr(a, "toarray") else np.asarray(a)


def steady_ustar(vf, p, x_guess, hstar: float, tol: float = 1e-12,
                 max_iter: int = 30) -> tuple[float, np.ndarray]:
    """U* = (Q1 + Q2)/H* of the steady state of the adapted field ``vf`` at parameters p,
    and that state: Newton ``x <- x - F_x(x)^{-1} F(x)`` from ``x_guess`` until
    ``max|F| < tol``, or until an update is at round-off level (``max|dx| <= 1e-13 (1 +
    max|x|)``: where the rounding of F exceeds ``tol``, as the continuation's Newton
    accepts); the inverse of :func:`pi_of`.

    Raises SteadyStateError (naming the residual) if ``max_iter`` iterations do not
    reach ``tol`` or the residual is not finite.
    """
    x = np.asarray(x_guess, dtype=float)
    at_round_off = False
    for iteration in range(max_iter + 1):
        F = np.asarray(vf.rhs(x, p), dtype=float).ravel()
        residual = float(np.max(np.abs(F)))
        if np.isfinite(residual) and (residual < tol or at_round_off):
            return float(x[-2:].sum() / hstar), x
        if iteration == max_iter or not np.isfinite(residual):
            break
        dx = np.linalg.solve(dense(vf.jac_x(x, p)), F)
        x = x - dx
        at_round_off = np.max(np.abs(dx)) <= 1e-13 * (1.0 + np.max(np.abs(x)))
    raise SteadyStateError(f"steady_ustar: Newton did not converge in {max_iter} iterations "
                           f"(residual max|F| = {residual:.3e} >= {tol:.0e})")


def pi_of(scene: Scene, model: Model, ustar: float) -> float:
    """Scaled kinematic pressure drop Δp/(M* PI_SCALE) of the steady state at ``ustar``.

    The analyses continued in Π need Δp to grow with U*; ValueError (before any
    continuation) when it is zero at ``ustar`` != 0 (no friction and no head losses in
    straight channels: the flow exerts no steady load to parametrize by)."""
    pi = steady_state(scene.replace(ustar=ustar), model).pressure_drop / (scene.mstar * PI_SCALE)
    if ustar != 0 and pi == 0:
        raise ValueError(f"the steady pressure drop is zero at U* = {ustar:g} (friction = "
                         f"{scene.friction:g}, k0 = {scene.k0:g}, kl = {scene.kl:g}): the onset, "
                         "boundary and cycle analyses are continued in the pressure drop and "
                         "need friction, k0 or kl > 0 (eig works at any U*)")
    return pi


def speed_window(scene: Scene, model: Model, ustar_min: float, ustar_max: float,
                 direction: int = 1) -> tuple[tuple[float, float], int]:
    """``(bounds, pi_direction)`` of a continuation in Π over the speeds |U*| in
    [``ustar_min``, ``ustar_max``] of ``scene``'s flow: the bounds between the steady Π
    at U* = flow_sign ``ustar_min`` (Π = 0 where ``ustar_min`` is 0) and at U* =
    flow_sign ``ustar_max``, in increasing order (:func:`pi_interval`; Π < 0 for
    reversed flow), and the sign of the first change of Π that ``direction`` asks for
    (+1: towards larger speed |U*|, -1: smaller), ``direction * flow_sign``: Π grows
    with |U*| as sign(U*) U*^2, so towards larger speed Π decreases under reversed flow."""
    sign = scene.flow_sign
    low = pi_of(scene, model, sign * ustar_min) if ustar_min > 0 else 0.0
    return pi_interval(low, pi_of(scene, model, sign * ustar_max)), int(direction * sign)


def pi_interval(a: float, b: float) -> tuple[float, float]:
    """The bounds of a continuation in Π between ``a`` and ``b`` in increasing order
    (Π < 0 for reversed flow)."""
    return min(a, b), max(a, b)


def speed(scene: Scene, x) -> float | np.ndarray:
    """The speed ``|U*| = sign (Q1 + Q2)/H*`` of a state (or of rows of states) of
    ``scene``'s direction (sign -1 for reversed flow): the analyses search and compare
    speeds, and report the signed U*."""
    u = np.asarray(x, dtype=float)[..., -2:].sum(axis=-1) * (scene.flow_sign / scene.hstar)
    return float(u) if np.ndim(u) == 0 else u


def field_parameters(vf: C.VectorField, model: Model, steady: SteadyState, scene: Scene,
                     pressure_drop: float) -> dict:
    """The parameters of :func:`flutter_field` ``vf`` at ``pressure_drop``: Π, log10 M*,
    and the rest those of the ``steady`` state of ``scene``."""
    values = dict(zip(model.parameter_names, steady.p))
    params = {PI: pressure_drop / (scene.mstar * PI_SCALE), LOG_M: math.log10(scene.mstar)}
    params.update({k: values[k] for k in vf.par_names[2:]})
    return params
