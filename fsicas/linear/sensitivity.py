"""Sensitivities of the flutter onset (U*_c and omega_c) to the scene's parameters.

At a Hopf point the augmented system of ``continuation`` (``F = 0``, ``J v - M w = 0``,
``J w + kappa M v = 0``, two normalizations) defines ``Y = (x, v, w, kappa)`` and the
pressure parameter Π as functions of every other parameter ``q`` of the model. By the
implicit-function theorem their derivatives solve

    [G_Y  G_Π] (dY/dq, dΠ/dq) = -G_q,

with the exact Jacobians (CasADi AD) of the same system the onset was located on; then
``U*_c = (Q1 + Q2)/H*`` and ``omega_c = TIME_SCALE sqrt(kappa)`` follow from ``Y``.
This gives M*, the friction f, the singular losses K0, KL and the damping ζ (all modes
together) exactly. The channel heights H1/L, H2/L and a Timoshenko beam's slenderness e/L
and Poisson ratio are not parameters of the built model (its quadrature and modes carry
them): their derivatives are central differences of the onset relocated by Newton on the
Hopf system of rebuilt models (relative step ``FD_STEP``; the onsets are located to
about 1e-13, so the error is about 1e-8).

The derivatives hold for the Hopf point given, i.e. along its mode: where the first
onset switches to another mode (the boundary's switches), it is not differentiable.

A static divergence (a real eigenvalue crossing zero; the usual onset of reversed flow)
has no frequency: :func:`divergence_sensitivity` gives ``d ln |U*_c| / d q`` alone, by
differences of the divergence relocated (Brent on the real eigenvalue nearest 0 to
round-off, :func:`fsicas.linear.divergence.divergence_at`; a fold of the steady branch,
as in asymmetric channels, by the continuation) on perturbed scenes: central
with the relative step ``FD_STEP``, or one-sided of second order with the step
``FD_STEP`` from a value 0 (k0, kl, zeta).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

import continuation as C

from ..model.assembly import Model, build_model
from ..profile import Profile
from ..scene import CONTACT_PARAMETERS, MODEL_PARAMETERS, TIMOSHENKO, Scene
from .adapter import LOG_M, PI, TIME_SCALE
from .divergence import DivergencePoint, divergence_at
from .hopf import HopfPoint, first_onset, flutter_problem

__all__ = ["OnsetSensitivity", "onset_sensitivity", "divergence_sensitivity", "EXACT",
           "BY_DIFFERENCES", "FD_STEP"]

#: Parameters differentiated exactly (implicit-function theorem) and by differences.
EXACT = tuple(n for n in MODEL_PARAMETERS if n not in CONTACT_PARAMETERS)
BY_DIFFERENCES = ("h1", "h2", "slenderness", "poisson")
#: Relative step of the central differences.
FD_STEP = 1e-4


@dataclass(frozen=True)
class OnsetSensitivity:
    """``d ln U*_c / d q`` and ``d ln omega_c / d q`` for the scene's parameters ``q``:
    ``mstar``, ``friction``, ``k0``, ``kl``, ``zeta`` (added to every mode's), ``h1``,
    ``h2`` (the channel heights H1/L, H2/L) and, for a Timoshenko beam, ``slenderness``
    and ``poisson``. An elasticity is ``q * d ln U*_c / d q``. A divergence (``omega`` =
    0) has no ``d_ln_omega`` (empty)."""

    ustar: float
    omega: float
    d_ln_ustar: dict
    d_ln_omega: dict
    values: dict

    def elasticity(self, name: str) -> tuple[float, float | None]:
        """``(d ln U*_c / d ln q, d ln omega_c / d ln q)`` at the scene's value of q (the
        second None for a divergence)."""
        value, dw = self.values[name], self.d_ln_omega.get(name)
        return value * self.d_ln_ustar[name], None if dw is None else value * dw

    def to_json(self) -> dict:
        return {"ustar_crit": self.ustar, "omega": self.omega,
                "d_ln_ustar": dict(self.d_ln_ustar), "d_ln_omega": dict(self.d_ln_omega),
                "values": dict(self.values)}


def onset_sensitivity(scene: Scene, model: Model, hopf: HopfPoint) -> OnsetSensitivity:
    """The derivatives of the onset ``hopf`` of ``scene`` (located on ``model``)."""
    model.require_structure(scene)
    du, dw = _exact(scene, model, hopf)
    values = _values(scene)
    for name in values:
        if name in BY_DIFFERENCES:
            du[name], dw[name] = _difference(scene, hopf, name, values[name])
    return OnsetSensitivity(hopf.ustar, hopf.omega, du, dw, values)


def divergence_sensitivity(scene: Scene, model: Model, onset: DivergencePoint
                           ) -> OnsetSensitivity:
    """``d ln |U*_c| / d q`` of the static divergence ``onset`` of ``scene`` (located on
    ``model``), by differences of relocated divergences (module doc); no frequency. At a
    symmetry-breaking divergence (a pitchfork of a symmetric channel) unequal heights
    unfold the pitchfork and U*_c is not differentiable in H1 or H2 alone: ``gap`` (both
    heights together, H1/L = H2/L) replaces ``h1`` and ``h2``."""
    model.require_structure(scene)
    values = _values(scene)
    if onset.symmetry_breaking:       # a pitchfork: H1 != H2 unfolds it, d/dh1 undefined
        h = values.pop("h1")
        values.pop("h2")
        values["gap"] = h
    du = {name: _divergence_slope(scene, model, onset, name, value)
          for name, value in values.items()}
    return OnsetSensitivity(onset.ustar, 0.0, du, {}, values)


def _values(scene: Scene) -> dict:
    """The scene's value of each parameter differentiated (zeta: the modes' mean)."""
    h1, h2 = _heights(scene)
    values = {"mstar": scene.mstar, "friction": scene.friction, "k0": scene.k0,
              "kl": scene.kl, "zeta": float(np.mean(scene.zeta_modes)), "h1": h1, "h2": h2}
    if scene.beam == TIMOSHENKO:
        values.update(slenderness=scene.slenderness, poisson=scene.poisson)
    return values


def _divergence_slope(scene: Scene, model: Model, onset: DivergencePoint, name: str,
                      value: float) -> float:
    """``d ln |U*_c| / d q`` at ``q = value``: central differences, or from 0 one-sided
    ``(-3 g(0) + 4 g(h) - g(2h)) / (2h)`` (second order)."""
    h = FD_STEP * value if value else FD_STEP
    steps = (1, -1) if value else (1, 2)
    ln_u = []
    for k in steps:
        perturbed = _perturbed(scene, name, value + k * h)
        on = model if name not in (*BY_DIFFERENCES, "gap") else build_model(perturbed)
        ln_u.append(math.log(abs(_divergence_near(perturbed, on, onset.ustar))))
    if value:
        return (ln_u[0] - ln_u[1]) / (2 * h)
    return (-3 * math.log(abs(onset.ustar)) + 4 * ln_u[0] - ln_u[1]) / (2 * h)


def _exact(scene: Scene, model: Model, hopf: HopfPoint) -> tuple[dict, dict]:
    """``d ln U*_c / d q`` and ``d ln omega / d q`` for ``EXACT`` (implicit functions)."""
    problem = flutter_problem(scene, model, ustar_start=0.2)
    vf = problem.vf
    columns = {"mstar": [LOG_M], "friction": ["friction"], "k0": ["k0"], "kl": ["kl"],
               "zeta": [f"zeta{i + 1}" for i in range(scene.modes)]}
    # one Jacobian of the Hopf system in Y, Π and every parameter named above
    curve = C.HopfCurveProblem.from_point(problem, hopf.point, LOG_M)
    system, X = curve.system, curve.X0
    names = [p for ps in columns.values() for p in ps]
    J = system.compiled.jacobian(X[:system.compiled.n_state], system.params(X), system.D,
                                 [vf.par_index(PI)] + [vf.par_index(p) for p in names]).toarray()
    m = J.shape[0]
    by_name = dict(zip(names, J[:, m:].T))
    rhs = [-sum(by_name[p] for p in ps) for ps in columns.values()]
    dY = sla.lu_solve(sla.lu_factor(J[:, :m]), np.column_stack(rhs))
    n = vf.n
    kappa = float(X[3 * n])
    d_ustar = (dY[n - 2] + dY[n - 1]) / scene.hstar
    d_omega = TIME_SCALE * dY[3 * n] / (2 * math.sqrt(kappa))
    scale = {"mstar": 1 / (scene.mstar * math.log(10))}      # the field's log10 M*
    du = {name: float(d_ustar[k] * scale.get(name, 1.0) / hopf.ustar)
          for k, name in enumerate(columns)}
    dw = {name: float(d_omega[k] * scale.get(name, 1.0) / hopf.omega)
          for k, name in enumerate(columns)}
    return du, dw


def _heights(scene: Scene) -> tuple[float, float]:
    """H1/L and H2/L of straight channels (ValueError for shaped walls)."""
    c1, c2 = scene.walls
    if not (c1.kind == c2.kind == "constant"):
        raise ValueError("the sensitivities to the channel heights need straight channels "
                         "(constant wall profiles)")
    return c1.heights[0], c2.heights[0]


def _perturbed(scene: Scene, name: str, value: float) -> Scene:
    """``scene`` with the parameter ``name`` set to ``value`` (zeta: every mode's damping
    moved by the same amount, to the mean ``value``; gap: both heights H1/L = H2/L)."""
    if name == "zeta":
        shift = value - float(np.mean(scene.zeta_modes))
        return scene.replace(zeta=tuple(float(z) + shift for z in scene.zeta_modes))
    if name in ("h1", "h2", "gap"):
        h1, h2 = _heights(scene)
        h1, h2 = (value, value) if name == "gap" else (value, h2) if name == "h1" else (h1, value)
        return scene.replace(hstar=h1 + h2, channel1=Profile.constant(h1),
                             channel2=Profile.constant(h2))
    return scene.replace(**{name: value})


def _divergence_near(scene: Scene, model: Model, ustar: float) -> float:
    """U* of the divergence of ``scene`` near ``ustar``: a crossing of the straight
    branch by Brent's method (:func:`divergence_at`), else (a fold of the branch, past
    which there is no steady state to bracket with) the first onset located by the
    continuation; RuntimeError if neither is within 1 %."""
    point = divergence_at(scene, model, ustar)
    if point is None:
        point = first_onset(scene, model, 1.5 * abs(ustar))
    if point is None or point.kind != "divergence" or abs(point.ustar / ustar - 1) > 0.01:
        raise RuntimeError(f"the divergence near U* = {ustar:.6g} could not be relocated at "
                           f"{scene}")
    return point.ustar


def _difference(scene: Scene, hopf: HopfPoint, name: str, value: float) -> tuple[float, float]:
    """Central differences of ``ln U*_c`` and ``ln omega_c`` in ``name``."""
    h = FD_STEP * value
    onsets = [_relocated(_perturbed(scene, name, value + s * h), hopf) for s in (1, -1)]
    (u1, w1), (u0, w0) = onsets
    return (math.log(u1 / u0) / (2 * h), math.log(w1 / w0) / (2 * h))


def _relocated(scene: Scene, hopf: HopfPoint) -> tuple[float, float]:
    """``(U*_c, omega_c)`` of the Hopf point near ``hopf`` on ``scene``'s own model, by
    Newton on the Hopf system from the steady state at the old onset."""
    model = build_model(scene)
    problem = flutter_problem(scene, model, ustar_start=abs(hopf.ustar))
    point = C.hopf_point(problem, problem.X0[:-1], hopf.omega / TIME_SCALE)
    if point.status != "converged":
        raise RuntimeError(f"the onset could not be relocated at {scene}: {point.message}")
    return float(point.x[-2:].sum() / scene.hstar), float(point.data["omega"]) * TIME_SCALE
