"""Steady state at a given mean inlet velocity U*: pressure drop, static deflection, flow split.

Unknowns ``z = (q, Q1, Q2, Δp)`` with r = 0; equations: the beam and flow-rate rows of
``F(x, p) = 0`` and ``(Q1 + Q2) / H* = U*``. Newton with CasADi's exact Jacobian (via
SciPy's MINPACK ``hybr``, then Newton polishing to round-off), continued in U* from
rest when the direct solve fails.

For a straight symmetric channel the solution is closed form (``docs/model.md``):
``q = 0``, ``Q1 = Q2 = U* H*/2`` and ``Δp = M* U*|U*| ((K0 + KL)/2 + 2 f / H*)``.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import casadi as ca
import numpy as np
import scipy.optimize

from ..model.assembly import Model, build_model, per_model
from ..scene import Scene

__all__ = ["SteadyState", "SteadyStateError", "steady_state", "straight_pressure_drop"]


class SteadyStateError(RuntimeError):
    """No steady state found; the message says why (residual, U* reached)."""


@dataclass(frozen=True)
class SteadyState:
    """Equilibrium ``x`` (r = 0) at ``pressure_drop``, with the parameter vector ``p``."""

    scene: Scene
    x: np.ndarray
    p: np.ndarray
    pressure_drop: float
    residual: float
    wall_time: float

    @property
    def q(self) -> np.ndarray:
        n = self.scene.modes
        return self.x[n:2 * n]

    @property
    def Q(self) -> np.ndarray:
        return self.x[-2:]

    def to_json(self, model: Model) -> dict:
        return {"pressure_drop": self.pressure_drop, "Q": self.Q.tolist(), "q": self.q.tolist(),
                "tip_deflection": float(model.deflection(self.x, [model.x_ref])[0]),
                "x_ref": model.x_ref}


def straight_pressure_drop(scene: Scene) -> float:
    """Closed-form Δp of a straight channel with a straight beam (exact when symmetric)."""
    h = scene.hstar / 2
    u = scene.ustar
    return scene.mstar * u * abs(u) * ((scene.k0 + scene.kl) / 2 + scene.friction / h)


def steady_state(scene: Scene, model: Model | None = None, tol: float = 1e-12) -> SteadyState:
    """Solve for the equilibrium of ``scene`` at its U* (see module docstring)."""
    model = model or build_model(scene)
    model.require_structure(scene)
    start = time.perf_counter()
    residual_fn, jacobian_fn = _system(model)
    p = model.parameters(scene)
    z = _initial_guess(scene)
    if scene.ustar == 0.0:       # fluid at rest: no load, no flow (the Q rows degenerate)
        return SteadyState(scene, np.zeros(model.n_state), p, 0.0, 0.0, time.perf_counter() - start)
    solution = _solve(residual_fn, jacobian_fn, z, p, scene.ustar, tol)
    if solution is None:
        solution = _homotopy(residual_fn, jacobian_fn, z, p, scene.ustar, tol)
    z, res = solution
    n = scene.modes
    x = np.concatenate([np.zeros(n), z[:n + 2]])
    p = model.parameters(scene, pressure_drop=z[-1])
    return SteadyState(scene, x, p, float(z[-1]), res, time.perf_counter() - start)


@per_model
def _system(model: Model):
    """CasADi residual and Jacobian of the steady system in z = (q, Q, Δp) given (p, U*),
    built once per model."""
    n = model.n_modes
    z = ca.MX.sym("z", n + 3)
    p = ca.MX.sym("p", len(model.parameter_names))
    ustar = ca.MX.sym("ustar")
    i_dp = model.index("pressure_drop")
    p_full = ca.vertcat(p[:i_dp], z[-1], p[i_dp + 1:])
    x = ca.vertcat(ca.MX.zeros(n), z[:n + 2])
    F = model.rhs(x, p_full)
    hstar = model.scene.hstar
    g = ca.vertcat(F[:n], F[2 * n:], (z[n] + z[n + 1]) / hstar - ustar)
    residual = ca.Function("steady", [z, p, ustar], [g])
    jacobian = ca.Function("steady_jac", [z, p, ustar], [ca.jacobian(g, z)])
    return residual, jacobian


def _initial_guess(scene: Scene) -> np.ndarray:
    h1, h2 = (float(w(0.0)) for w in scene.walls)
    Q = scene.ustar * np.array([h1, h2])
    return np.concatenate([np.zeros(scene.modes), Q, [straight_pressure_drop(scene)]])


def _solve(residual_fn, jacobian_fn, z0, p, ustar, tol):
    """MINPACK hybr with exact Jacobian, then up to 3 Newton steps of polishing (none
    once the residual is at rounding level); None if it fails. A guess that already
    solves the system to rounding (the closed form of a symmetric straight channel) is
    taken as it is."""
    fun = lambda z: np.array(residual_fn(z, p, ustar)).ravel()
    jac = lambda z: np.array(jacobian_fn(z, p, ustar))
    z, r = z0, fun(z0)
    if not _at_rounding(r, z):
        z = scipy.optimize.root(fun, z0, jac=jac, method="hybr", options={"xtol": 1e-14}).x
        r = fun(z)
    for _ in range(3):
        if not np.all(np.isfinite(r)):
            return None
        if _at_rounding(r, z):
            break
        z = z - np.linalg.solve(jac(z), r)
        r = fun(z)
    res = float(np.max(np.abs(r)))
    scale = 1.0 + float(np.max(np.abs(z)))
    return (z, res) if np.isfinite(res) and res <= tol * scale * 1e3 else None


def _at_rounding(r, z) -> bool:
    """``max |r| <= 1e-14 (1 + max |z|)``: nothing left for Newton to improve."""
    return bool(np.all(np.isfinite(r)) and np.max(np.abs(r)) <= 1e-14 * (1.0 + np.max(np.abs(z))))


def _homotopy(residual_fn, jacobian_fn, z0, p, ustar, tol, steps: int = 40):
    """Continue in U* from 0 to the target; raise SteadyStateError where it breaks down."""
    z = z0 * 0.0
    for k, u in enumerate(np.linspace(0.0, ustar, steps + 1)[1:], start=1):
        guess = z * (k / max(k - 1, 1)) if k > 1 else z0 / steps
        solution = _solve(residual_fn, jacobian_fn, guess, p, u, tol)
        if solution is None:
            r = np.array(residual_fn(guess, p, u)).ravel()
            raise SteadyStateError(
                f"no steady state found: Newton failed at U* = {u:.6g} on the way to "
                f"U* = {ustar:.6g} (residual {np.max(np.abs(r)):.3e}); the static "
                "deflection may diverge (beam pressed onto a wall) or the flow reverse")
        z = solution[0]
    return solution
