"""How the snoring onset of a physical configuration moves with every physical parameter.

The onset airflow and frequency of a physical configuration are

    Q_c = U*_c(pi) (L / T) b (H1 + H2),      f_c = omega_c(pi) / (2 pi T),
    T = L^2 sqrt(rho_s e / D),  D = E e^3 / (12 (1 - nu^2)),

with the nondimensional parameters ``pi = (M* = rho_f L / (rho_s e), H1/L, H2/L, f, zeta)``
(and e/L, nu for a Timoshenko beam). The derivatives of ``U*_c`` and ``omega_c`` in
``pi`` come from :func:`fsicas.linear.sensitivity.onset_sensitivity` (implicit functions
on the Hopf system, exact; the heights and a Timoshenko beam's shape by differences),
the rest is the chain rule through these closed forms. An elasticity is
``d ln Q_c / d ln theta``: a 1 % stiffer palate (E) moves the onset airflow by
``elasticity(E)`` %. With a viscosity instead of a friction, ``f = f(Re)`` at the onset's
own flow (``Re = rho_f U_c (H1 + H2) / (2 mu)``), and the fixed point is differentiated
too: ``d ln U_c = (A + phi k R) / (1 - phi k)`` with ``A`` the derivative at fixed f,
``phi = d ln U*_c / d ln f``, ``k = d ln f / d ln Re`` (-1 laminar, -1/4 turbulent) and
``R = d ln Re / d ln theta`` at fixed flow.

A static divergence (the usual onset of reversed flow, U* < 0: Q_c < 0, and
``d ln Q_c = d ln |Q_c|``) has no frequency: its ``d ln U*_c`` come from
:func:`fsicas.linear.sensitivity.divergence_sensitivity`, its frequency elasticities are
None, and at a pitchfork the heights move together only (``gap``, no H1, H2).
"""
from __future__ import annotations

from dataclasses import dataclass, field


from .hopf import HopfPoint
from .onset import onset_at_own_flow
from .sensitivity import divergence_sensitivity, onset_sensitivity
from ..model.assembly import Model, build_model
from ..physical import KEYS, MEANING, Flow, Physical
from ..scene import TIMOSHENKO, Scene
from ..units import friction_from_reynolds

__all__ = ["Sensitivity", "PalateSensitivity", "DesignError", "palate_sensitivity",
           "physical_onset", "physical_scene", "viscous_friction", "USTAR_MAX"]

#: Onset search bound in U* (raised with the target flow).
USTAR_MAX = 40.0


class DesignError(ValueError):
    """The query has no answer: no onset, or no change within the search range reaches
    the target."""


@dataclass(frozen=True)
class Sensitivity:
    """How the onset moves with one parameter ``name`` (``value`` in ``unit``, SI):
    elasticities ``flow`` = d ln Q_c / d ln theta and ``frequency`` = d ln f_c / d ln theta,
    and the same per unit of theta (``flow_per_unit``, ``frequency_per_unit``; for
    parameters that may be 0, the damping); the frequency ones None for a divergence."""

    name: str
    value: float
    unit: str
    flow: float
    frequency: float | None
    flow_per_unit: float
    frequency_per_unit: float | None

    def to_json(self) -> dict:
        return {"value": self.value, "unit": self.unit, "meaning": MEANING.get(self.name, ""),
                "flow_elasticity": self.flow, "frequency_elasticity": self.frequency,
                "flow_per_unit": self.flow_per_unit,
                "frequency_per_unit": self.frequency_per_unit}


@dataclass(frozen=True)
class PalateSensitivity:
    """The onset of a physical configuration and its sensitivities, by parameter."""

    onset_flow: float            # m^3/s
    onset_velocity: float        # m/s
    frequency: float             # Hz
    hopf: HopfPoint = field(repr=False)
    scene: Scene = field(repr=False)
    parameters: dict = field(default_factory=dict)     # name -> Sensitivity

    def to_json(self) -> dict:
        return {"onset_flow_l_min": self.onset_flow * 60e3,
                "onset_velocity_m_s": self.onset_velocity, "frequency_hz": self.frequency,
                "kind": self.hopf.kind, "ustar_crit": self.hopf.ustar, "mstar": self.scene.mstar,
                "dominant_mode": self.hopf.dominant_mode,
                "sensitivities": {k: s.to_json() for k, s in self.parameters.items()}}


def palate_sensitivity(physical: Physical, *, ustar_max: float = USTAR_MAX,
                       **overrides) -> PalateSensitivity:
    """The onset of ``physical`` and its sensitivity to every physical parameter (module
    doc); ``overrides``: nondimensional Scene fields (modes, direction, ...) as in
    :meth:`Physical.scene`. DesignError when there is no onset below ``ustar_max``."""
    scene, model, onset = physical_onset(physical, overrides, ustar_max)
    s = onset_sensitivity(scene, model, onset) if onset.kind == "flutter" else \
        divergence_sensitivity(scene, model, onset)
    v = dict(physical.values)
    v.update(H1=physical.H1, H2=physical.H2)
    pi_u, pi_w = _nondimensional(s, v, scene)
    viscous = viscous_friction(physical, overrides)
    kappa = _friction_slope(physical, scene, onset) if viscous else 0.0
    names = [k for k in KEYS if k in v and k not in ("gap", "flow")] + ["H1", "H2"]
    if "gap" in s.values:                  # a pitchfork: both heights together only
        names = [n for n in names if n not in ("H1", "H2")] + ["gap"]
        v.setdefault("gap", physical.H1)
    names = list(dict.fromkeys(n for n in names if not (viscous and n == "friction")))
    out = {name: _parameter(name, v, physical, scene, s, pi_u, pi_w, kappa) for name in names}
    if physical.H1 == physical.H2 and "gap" in v and "H1" in out:     # both channels
        out["gap"] = _sensitivity("gap", v["gap"], out["H1"].flow + out["H2"].flow,
                                  _sum(out["H1"].frequency, out["H2"].frequency))
    sc = scene.scales
    return PalateSensitivity(sc.m3_per_s(onset.ustar), sc.m_per_s(onset.ustar),
                             sc.hz(onset.omega), onset, scene, out)


def _sum(a, b):
    return None if a is None or b is None else a + b


def _parameter(name, v, physical, scene, s, pi_u, pi_w, kappa) -> Sensitivity:
    """The Sensitivity to ``name``: per ln theta (per unit of zeta, which may be 0), at
    fixed f, then (``kappa`` != 0: a viscous friction) through the fixed point."""
    nu, gap = v["nu"], physical.H1 + physical.H2
    # d ln T, d ln (L / T), d ln (b (H1 + H2)), d ln Re by ln theta (closed forms)
    ln_T = {"E": -0.5, "e": -1.0, "L": 2.0, "rho_s": 0.5, "nu": -nu ** 2 / (1 - nu ** 2)}
    ln_area = {"b": 1.0, "H1": physical.H1 / gap, "H2": physical.H2 / gap, "gap": 1.0}
    ln_re = {"rho_f": 1.0, "H1": physical.H1 / gap, "H2": physical.H2 / gap, "gap": 1.0,
             "viscosity": -1.0}
    A = pi_u.get(name, 0.0) + (name == "L") - ln_T.get(name, 0.0)          # ln U_c
    B = None if pi_w is None else pi_w.get(name, 0.0) - ln_T.get(name, 0.0)  # ln f_c
    d_u, d_w = A, B
    if kappa:
        phi_u = scene.friction * s.d_ln_ustar["friction"]
        d_u = (A + phi_u * kappa * ln_re.get(name, 0.0)) / (1 - phi_u * kappa)
        if B is not None:
            phi_w = scene.friction * s.d_ln_omega["friction"]
            d_w = B + phi_w * kappa * (ln_re.get(name, 0.0) + d_u)
    return _sensitivity(name, v[name], d_u + ln_area.get(name, 0.0), d_w,
                        per_unit=name == "zeta")


def _sensitivity(name: str, value: float, flow: float, frequency: float | None,
                 per_unit: bool = False) -> Sensitivity:
    """From the derivatives by ln theta (by theta itself with ``per_unit``); ``frequency``
    None for a divergence (no frequency)."""
    w = 0.0 if frequency is None else frequency
    if per_unit:
        unit_q, unit_w = flow, w
        flow, w = value * flow, value * w
    else:
        unit_q, unit_w = (flow / value, w / value) if value else (0.0, 0.0)
    none = frequency is None
    return Sensitivity(name, float(value), KEYS[name] or "-", float(flow),
                       None if none else float(w), float(unit_q), None if none else float(unit_w))


def _nondimensional(s, v: dict, scene: Scene) -> tuple[dict, dict | None]:
    """``d ln U*_c / d ln theta`` and ``d ln omega_c / d ln theta`` (None for a divergence)
    through the nondimensional parameters (by zeta itself for the damping, which may be
    0; ``gap``: both heights together, at a pitchfork)."""
    d_ln_pi = {"mstar": {"rho_f": 1, "L": 1, "rho_s": -1, "e": -1},
               "h1": {"H1": 1, "L": -1}, "h2": {"H2": 1, "L": -1},
               "gap": {"gap": 1, "L": -1}, "friction": {"friction": 1}}
    if scene.beam == TIMOSHENKO:
        d_ln_pi.update(slenderness={"e": 1, "L": -1}, poisson={"nu": 1})
    flutter = bool(s.d_ln_omega)
    pi_u, pi_w = {}, {}
    for pi, by in d_ln_pi.items():
        if pi not in s.values:
            continue
        eu, ew = s.elasticity(pi)
        for name, power in by.items():
            pi_u[name] = pi_u.get(name, 0.0) + power * eu
            pi_w[name] = pi_w.get(name, 0.0) + power * (ew or 0.0)
    pi_u["zeta"], pi_w["zeta"] = s.d_ln_ustar["zeta"], s.d_ln_omega.get("zeta")   # per unit
    return pi_u, pi_w if flutter else None


def _friction_slope(physical: Physical, scene: Scene, hopf: HopfPoint) -> float:
    """``d ln f / d ln Re`` of Eq. (15) at the onset's Reynolds number."""
    flow = Flow.of("velocity", scene.scales.m_per_s(hopf.ustar))
    _, re = physical.friction(flow)
    return -1.0 if friction_from_reynolds(re) == 12.0 / re else -0.25


# -- the onset of a physical configuration ------------------------------------------------
def viscous_friction(physical: Physical, overrides: dict) -> bool:
    """Whether the friction of ``physical`` comes from its viscosity at the flow."""
    return "viscosity" in physical.values and "friction" not in physical.scene_fields \
        and overrides.get("friction") is None


def physical_scene(physical: Physical, flow: Flow | None, overrides: dict) -> Scene:
    """The scene at ``flow`` (with a viscosity: at the friction of that flow)."""
    if viscous_friction(physical, overrides) and flow is None:
        flow = Flow.of("velocity", 1.0)
    return physical.scene(flow, **overrides)


def physical_onset(physical: Physical, overrides: dict, ustar_max, model: Model | None = None):
    """``(scene, model, onset)`` of ``physical`` (the first loss of stability, flutter or
    divergence); with a viscosity, at the
    onset's own friction. ``model`` is reused when it has the scene's structure.
    DesignError when there is no onset below ``ustar_max``."""
    scene = physical_scene(physical, None, overrides)
    if model is None or not _fits(model, scene):
        model = build_model(scene)
    viscous = viscous_friction(physical, overrides)
    scene, hopf, _ = onset_at_own_flow(scene, model, ustar_max, physical if viscous else None)
    if hopf is None:
        raise DesignError(f"{physical.source}: no onset of instability below U* = {ustar_max:g}; "
                          "nothing to design")
    return scene, model, hopf


def _fits(model: Model, scene: Scene) -> bool:
    try:
        model.require_structure(scene)
    except ValueError:
        return False
    return True


