"""Designing the palate: how the snoring onset moves with every physical parameter, and
the smallest change of one that lifts the onset above a target airflow.

**Sensitivities.** The onset airflow and frequency of a physical configuration are

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

**Design query.** The smallest change of one parameter that raises the onset airflow
to a target: from the present value the parameter moves in the direction its elasticity
says raises the onset, in steps of ``DESIGN_STEP`` (10 %), each a full onset (the first
Hopf point of the steady branch, so a switch of the flutter mode is taken into account),
until the onset passes the target; then Brent's method on that step. The answer is
verified by the eigenvalues of the steady state at the design: stable at 99.5 % of the
target flow, unstable at 100.5 %.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

from scipy.optimize import brentq

from .hopf import HopfPoint
from .onset import onset_at_own_flow
from .sensitivity import onset_sensitivity
from .stability import linear_stability
from ..model.assembly import Model, build_model
from ..physical import KEYS, MEANING, Flow, Physical
from ..scene import TIMOSHENKO, Scene
from ..units import friction_from_reynolds

__all__ = ["Sensitivity", "PalateSensitivity", "Design", "DesignError", "palate_sensitivity",
           "design_for_flow", "parameter_name", "with_value", "ALIASES", "DESIGN_STEP",
           "DESIGN_MAX_FACTOR", "VERIFY_MARGIN"]

#: Everyday names of the parameters a design may vary.
ALIASES = {"stiffness": "E", "thickness": "e", "length": "L", "density": "rho_s",
           "width": "b", "damping": "zeta", "fluid_density": "rho_f", "poisson": "nu"}
#: Relative step of the design search, the largest factor it tries, and the margin of
#: the verification (the design's flow times 1 -/+ VERIFY_MARGIN).
DESIGN_STEP, DESIGN_MAX_FACTOR, VERIFY_MARGIN = 0.10, 100.0, 0.005
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
    parameters that may be 0, the damping)."""

    name: str
    value: float
    unit: str
    flow: float
    frequency: float
    flow_per_unit: float
    frequency_per_unit: float

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
                "ustar_crit": self.hopf.ustar, "mstar": self.scene.mstar,
                "dominant_mode": self.hopf.dominant_mode,
                "sensitivities": {k: s.to_json() for k, s in self.parameters.items()}}


def palate_sensitivity(physical: Physical, *, ustar_max: float = USTAR_MAX,
                       **overrides) -> PalateSensitivity:
    """The onset of ``physical`` and its sensitivity to every physical parameter (module
    doc); ``overrides``: nondimensional Scene fields (modes, ...) as in
    :meth:`Physical.scene`. DesignError when there is no onset below ``ustar_max``."""
    scene, model, hopf = _onset(physical, overrides, ustar_max)
    s = onset_sensitivity(scene, model, hopf)
    v = dict(physical.values)
    v.update(H1=physical.H1, H2=physical.H2)
    pi_u, pi_w = _nondimensional(s, v, scene)
    # d ln T, d ln (L / T), d ln (b (H1 + H2)) by ln theta (closed forms)
    nu = v["nu"]
    ln_T = {"E": -0.5, "e": -1.0, "L": 2.0, "rho_s": 0.5, "nu": -nu ** 2 / (1 - nu ** 2)}
    gap = physical.H1 + physical.H2
    ln_area = {"b": 1.0, "H1": physical.H1 / gap, "H2": physical.H2 / gap}
    viscous = _viscous(physical, overrides)
    ln_re = {"rho_f": 1.0, "H1": physical.H1 / gap, "H2": physical.H2 / gap, "viscosity": -1.0}
    phi_u = scene.friction * s.d_ln_ustar["friction"]
    phi_w = scene.friction * s.d_ln_omega["friction"]
    kappa = _friction_slope(physical, scene, hopf) if viscous else 0.0
    names = [k for k in KEYS if k in v and k not in ("gap", "flow")] + ["H1", "H2"]
    names = list(dict.fromkeys(n for n in names if not (viscous and n == "friction")))
    out = {}
    for name in names:
        # per ln theta (per unit of zeta, which may be 0): at fixed f, then the fixed point
        A = pi_u.get(name, 0.0) + (name == "L") - ln_T.get(name, 0.0)      # ln U_c
        B = pi_w.get(name, 0.0) - ln_T.get(name, 0.0)                      # ln f_c
        if viscous:
            d_u = (A + phi_u * kappa * ln_re.get(name, 0.0)) / (1 - phi_u * kappa)
            d_w = B + phi_w * kappa * (ln_re.get(name, 0.0) + d_u)
        else:
            d_u, d_w = A, B
        d_q = d_u + ln_area.get(name, 0.0)
        out[name] = _sensitivity(name, v[name], d_q, d_w, per_unit=name == "zeta")
    if physical.H1 == physical.H2 and "gap" in v:              # both channels together
        out["gap"] = _sensitivity("gap", v["gap"], out["H1"].flow + out["H2"].flow,
                                  out["H1"].frequency + out["H2"].frequency)
    sc = scene.scales
    return PalateSensitivity(sc.m3_per_s(hopf.ustar), sc.m_per_s(hopf.ustar),
                             sc.hz(hopf.omega), hopf, scene, out)


def _sensitivity(name: str, value: float, flow: float, frequency: float,
                 per_unit: bool = False) -> Sensitivity:
    """From the derivatives by ln theta (by theta itself with ``per_unit``)."""
    if per_unit:
        unit_q, unit_w = flow, frequency
        flow, frequency = value * flow, value * frequency
    else:
        unit_q, unit_w = (flow / value, frequency / value) if value else (0.0, 0.0)
    return Sensitivity(name, float(value), KEYS[name] or "-", float(flow), float(frequency),
                       float(unit_q), float(unit_w))


def _nondimensional(s, v: dict, scene: Scene) -> tuple[dict, dict]:
    """``d ln U*_c / d ln theta`` and ``d ln omega_c / d ln theta`` through the
    nondimensional parameters (by zeta itself for the damping, which may be 0)."""
    d_ln_pi = {"mstar": {"rho_f": 1, "L": 1, "rho_s": -1, "e": -1},
               "h1": {"H1": 1, "L": -1}, "h2": {"H2": 1, "L": -1},
               "friction": {"friction": 1}}
    if scene.beam == TIMOSHENKO:
        d_ln_pi.update(slenderness={"e": 1, "L": -1}, poisson={"nu": 1})
    pi_u, pi_w = {}, {}
    for pi, by in d_ln_pi.items():
        eu, ew = s.elasticity(pi)
        for name, power in by.items():
            pi_u[name] = pi_u.get(name, 0.0) + power * eu
            pi_w[name] = pi_w.get(name, 0.0) + power * ew
    pi_u["zeta"], pi_w["zeta"] = s.d_ln_ustar["zeta"], s.d_ln_omega["zeta"]   # per unit
    return pi_u, pi_w


def _friction_slope(physical: Physical, scene: Scene, hopf: HopfPoint) -> float:
    """``d ln f / d ln Re`` of Eq. (15) at the onset's Reynolds number."""
    flow = Flow("onset", "velocity", scene.scales.m_per_s(hopf.ustar))
    _, re = physical.friction(flow)
    return -1.0 if friction_from_reynolds(re) == 12.0 / re else -0.25


# -- the onset of a physical configuration ------------------------------------------------
def _viscous(physical: Physical, overrides: dict) -> bool:
    """Whether the friction comes from the viscosity at the flow."""
    return "viscosity" in physical.values and "friction" not in physical.scene_fields \
        and overrides.get("friction") is None


def _scene(physical: Physical, flow: Flow | None, overrides: dict) -> Scene:
    """The scene at ``flow`` (with a viscosity: at the friction of that flow)."""
    if _viscous(physical, overrides) and flow is None:
        flow = Flow("start", "velocity", 1.0)
    return physical.scene(flow, **overrides)


def _onset(physical: Physical, overrides: dict, ustar_max, model: Model | None = None):
    """``(scene, model, first Hopf point)``; with a viscosity, at the onset's own
    friction. ``model`` is reused when it has the scene's structure."""
    scene = _scene(physical, None, overrides)
    if model is None or not _fits(model, scene):
        model = build_model(scene)
    viscous = _viscous(physical, overrides)
    scene, hopf, _ = onset_at_own_flow(scene, model, ustar_max, physical if viscous else None)
    if hopf is None:
        raise DesignError(f"{physical.source}: no flutter onset below U* = {ustar_max:g}; "
                          "nothing to design")
    return scene, model, hopf


def _fits(model: Model, scene: Scene) -> bool:
    try:
        model.require_structure(scene)
    except ValueError:
        return False
    return True


@dataclass(frozen=True)
class Design:
    """The answer of :func:`design_for_flow`: ``parameter`` from ``before`` to ``after``
    (SI, ``unit``), the onset airflow (m^3/s) and frequency (Hz) before and after, the
    target, and the verification (``stable_below``, ``unstable_above``: the steady state
    at the design at 99.5 % and 100.5 % of the target flow)."""

    parameter: str
    unit: str
    before: float
    after: float
    onset_flow_before: float
    onset_flow_after: float
    frequency_before: float
    frequency_after: float
    target_flow: float
    stable_below: bool
    unstable_above: bool
    evaluations: int
    note: str = ""

    @property
    def relative_change(self) -> float | None:
        """``after / before - 1``; None from a value of 0 (a damping ratio)."""
        return self.after / self.before - 1.0 if self.before else None

    @property
    def verified(self) -> bool:
        return self.stable_below and self.unstable_above

    def to_json(self) -> dict:
        lpm = 60e3
        return {"parameter": self.parameter, "unit": self.unit, "before": self.before,
                "after": self.after, "relative_change": self.relative_change,
                "onset_flow_before_l_min": self.onset_flow_before * lpm,
                "onset_flow_after_l_min": self.onset_flow_after * lpm,
                "frequency_before_hz": self.frequency_before,
                "frequency_after_hz": self.frequency_after,
                "target_flow_l_min": self.target_flow * lpm,
                "verified": {"stable_below": self.stable_below,
                             "unstable_above": self.unstable_above,
                             "margin": VERIFY_MARGIN},
                "evaluations": self.evaluations, "note": self.note}


def parameter_name(vary: str, physical: Physical) -> str:
    """The ``[physical]`` key of ``vary`` (a key or an everyday name); ValueError naming
    the allowed ones."""
    name = ALIASES.get(vary, vary)
    allowed = [k for k in KEYS if k in physical.values and k != "flow"]
    allowed += [h for h in ("H1", "H2") if h not in allowed]
    if name not in allowed:
        raise ValueError(f"--vary {vary!r}: not a parameter of {physical.source} that a design "
                         f"may change; allowed: {', '.join(allowed)} (or "
                         f"{', '.join(a for a, k in ALIASES.items() if k in allowed)})")
    return name


def with_value(physical: Physical, name: str, value: float) -> Physical:
    """``physical`` with the parameter ``name`` set to ``value`` (SI)."""
    values = {**physical.values, name: value}
    H1, H2 = physical.H1, physical.H2
    if name == "gap":
        H1 = H2 = value
    elif name in ("H1", "H2"):
        H1, H2 = (value, H2) if name == "H1" else (H1, value)
    return replace(physical, values=values, H1=H1, H2=H2)


def design_for_flow(physical: Physical, target: Flow, vary: str, *,
                    ustar_max: float = USTAR_MAX, **overrides) -> Design:
    """The smallest change of ``vary`` that raises the onset airflow of ``physical`` to
    ``target`` (module doc), ``overrides`` as in :func:`palate_sensitivity`; verified by
    the eigenvalues at the design."""
    name = parameter_name(vary, physical)
    q_target = target.value if target.kind == "volume" else \
        target.value * physical.values["b"] * physical.gap
    base = palate_sensitivity(physical, ustar_max=ustar_max, **overrides)
    theta0 = physical.values[name] if name in physical.values else getattr(physical, name)
    if base.onset_flow >= q_target:
        return _design(physical, name, theta0, theta0, base, base, q_target, overrides, 0,
                       "the onset is already above the target: no change needed")
    rate = base.parameters[name].flow_per_unit
    if rate == 0.0:
        raise DesignError(f"{name} does not move the onset (its derivative is 0): choose "
                          "another parameter")
    onset = _OnsetFlow(physical, name, q_target, ustar_max, overrides)
    lo, hi = _bracket(onset, theta0, base.onset_flow, rate > 0)
    after = brentq(lambda t: onset(t) - q_target, lo, hi, xtol=1e-12 * abs(hi), rtol=1e-12)
    designed = with_value(physical, name, after)
    bound = max(ustar_max, 2.0 * _ustar_of(designed, q_target, overrides))
    designed = palate_sensitivity(designed, ustar_max=bound, **overrides)
    return _design(physical, name, theta0, after, base, designed, q_target, overrides,
                   onset.evaluations)


class _OnsetFlow:
    """``theta -> Q_c`` (m^3/s) of ``physical`` with the parameter ``name`` at ``theta``,
    its model reused while the structure is the same; counts its evaluations."""

    def __init__(self, physical, name, q_target, ustar_max, overrides):
        self.physical, self.name, self.q_target = physical, name, q_target
        self.ustar_max, self.overrides = ustar_max, overrides
        self.model, self.evaluations = None, 0

    def __call__(self, theta: float) -> float:
        ph = with_value(self.physical, self.name, theta)
        ph.check_validity()
        bound = max(self.ustar_max, 2.0 * _ustar_of(ph, self.q_target, self.overrides))
        scene, self.model, hopf = _onset(ph, self.overrides, bound, self.model)
        self.evaluations += 1
        return scene.scales.m3_per_s(hopf.ustar)


def _bracket(onset: _OnsetFlow, theta0: float, q0: float, up: bool) -> tuple[float, float]:
    """The step ``(lo, hi)`` of the search from ``theta0`` in which the onset airflow
    passes the target (DesignError when none within the search range)."""
    name, q_target = onset.name, onset.q_target
    lo, q_lo, theta = theta0, q0, theta0
    while True:
        theta = _next(name, theta, theta0, up)
        if theta is None:
            reach = "up to a damping ratio of 1" if name == "zeta" else \
                f"within a factor {DESIGN_MAX_FACTOR:g}"
            raise DesignError(f"no {'increase' if up else 'decrease'} of {name} {reach} lifts "
                              f"the onset to {q_target * 60e3:.4g} L/min (it reaches "
                              f"{q_lo * 60e3:.4g} L/min)")
        try:
            q = onset(theta)
        except (DesignError, ValueError) as err:
            raise DesignError(f"the search left the model's range before the onset reached "
                              f"the target ({name} = {theta:.4g}: {err})") from None
        if q >= q_target:
            return lo, theta
        lo, q_lo = theta, q


def _next(name: str, theta: float, theta0: float, up: bool) -> float | None:
    """The next value of the search, ``DESIGN_STEP`` further (a damping ratio from 0
    starts at 0.001); None past ``DESIGN_MAX_FACTOR`` times the start or a damping ratio
    of 1."""
    if name == "zeta" and theta == 0.0:
        return 1e-3 if up else None
    theta = theta * (1 + DESIGN_STEP) if up else theta / (1 + DESIGN_STEP)
    if name == "zeta":
        return theta if theta < 1.0 else None
    return theta if 1 / DESIGN_MAX_FACTOR <= theta / theta0 <= DESIGN_MAX_FACTOR else None


def _ustar_of(physical: Physical, q: float, overrides: dict) -> float:
    """U* of the volume flow ``q`` on ``physical``."""
    return _scene(physical, Flow("q", "volume", q), overrides).ustar


def _design(physical, name, before, after, base, designed, q_target, overrides,
            evaluations, note="") -> Design:
    """The Design, with its verification by eigenvalues at the designed parameter."""
    ph = with_value(physical, name, after)
    checks = []
    for factor in (1 - VERIFY_MARGIN, 1 + VERIFY_MARGIN):
        scene = _scene(ph, Flow("check", "volume", factor * designed.onset_flow), overrides)
        checks.append(linear_stability(scene, build_model(scene)).stable)
    unit = KEYS.get(name) or ("m" if name in ("H1", "H2") else "-")
    return Design(name, unit, float(before), float(after), base.onset_flow, designed.onset_flow,
                  base.frequency, designed.frequency, float(q_target), checks[0], not checks[1],
                  evaluations, note)
