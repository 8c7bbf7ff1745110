"""Designing the palate: the smallest change of one parameter, or of a weighted
combination, that lifts the snoring onset above a target airflow.

One parameter: from its present value it moves in the direction its sensitivity
(:mod:`fsicas.linear.elasticity`) says raises the onset, in steps of ``DESIGN_STEP``
(10 %), each a full onset (the first Hopf point of the steady branch, so a switch of the
flutter mode on the way is taken into account), until the onset passes the target; then
Brent's method on that step. A damping ratio of 0 starts at 0.001 (and may only grow).

A weighted combination ``{theta_j: w_j}`` (e.g. stiffening by implants against
shortening: ``E = 1, L = -1``) moves all together along ``ln theta_j = ln theta_j0 + w_j s``
with the sign of ``s`` that raises the onset (the directional elasticity
``sum_j w_j e_j``), in steps of ``s`` of ``ln(1 + DESIGN_STEP) / max |w_j|``, then Brent on
``s``: the smallest ``|s|``, the same relative change of each parameter in proportion to
its weight.

The answer is verified by the eigenvalues of the steady state at the design: stable at
99.5 % of the target flow, unstable at 100.5 %.

Reversed flow (expiration, U* < 0): the target flow carries the sign of the onset's
direction (negative), "raising" the onset means that its airflow's magnitude |Q_c| grows
to |target| (the elasticities d ln Q_c / d ln theta = d ln |Q_c| / d ln theta say
which way), and the verification is at 99.5 % and 100.5 % of |Q_c| in that direction.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace

from scipy.optimize import brentq

from .elasticity import (USTAR_MAX, DesignError, PalateSensitivity, palate_sensitivity,
                         physical_onset, physical_scene)
from .stability import linear_stability
from ..model.assembly import build_model
from ..physical import KEYS, Flow, Physical, PhysicalValidityWarning

__all__ = ["Change", "Design", "design_for_flow", "parse_vary", "with_values", "ALIASES",
           "DESIGN_STEP", "DESIGN_MAX_FACTOR", "VERIFY_MARGIN"]

#: Everyday names of the parameters a design may vary.
ALIASES = {"stiffness": "E", "thickness": "e", "length": "L", "density": "rho_s",
           "width": "b", "damping": "zeta", "fluid_density": "rho_f", "poisson": "nu"}
#: Relative step of the design search, the largest factor of change it tries, and the
#: margin of the verification (the design's flow times 1 -/+ VERIFY_MARGIN).
DESIGN_STEP, DESIGN_MAX_FACTOR, VERIFY_MARGIN = 0.10, 100.0, 0.005


@dataclass(frozen=True)
class Change:
    """One parameter of a design: ``before`` and ``after`` in ``unit`` (SI)."""

    parameter: str
    unit: str
    before: float
    after: float

    @property
    def relative_change(self) -> float | None:
        """``after / before - 1``; None from a value of 0 (a damping ratio)."""
        return self.after / self.before - 1.0 if self.before else None

    def to_json(self) -> dict:
        return {"parameter": self.parameter, "unit": self.unit, "before": self.before,
                "after": self.after, "relative_change": self.relative_change}


@dataclass(frozen=True)
class Design:
    """The answer of :func:`design_for_flow`: the ``changes`` (one per parameter varied,
    with its ``weight``), the onset airflow (m^3/s) and frequency (Hz) before and after,
    the target, and the verification (``stable_below``, ``unstable_above``: the steady
    state at the design at 99.5 % and 100.5 % of the onset). ``parameter``, ``unit``,
    ``before``, ``after`` and ``relative_change`` are those of a single change."""

    changes: tuple
    weights: tuple
    onset_flow_before: float
    onset_flow_after: float
    frequency_before: float
    frequency_after: float
    target_flow: float
    stable_below: bool
    unstable_above: bool
    evaluations: int
    note: str = ""
    #: what the designed palate's scenes warned of (e.g. beyond the model's validity), once each
    warnings: tuple = ()

    def _single(self) -> Change:
        if len(self.changes) != 1:
            raise AttributeError("a design of several parameters: see its changes")
        return self.changes[0]

    parameter = property(lambda self: self._single().parameter)
    unit = property(lambda self: self._single().unit)
    before = property(lambda self: self._single().before)
    after = property(lambda self: self._single().after)
    relative_change = property(lambda self: self._single().relative_change)

    @property
    def verified(self) -> bool:
        return self.stable_below and self.unstable_above

    def to_json(self) -> dict:
        lpm = 60e3
        single = self.changes[0].to_json() if len(self.changes) == 1 else {}
        return {**single, "changes": [c.to_json() for c in self.changes],
                "weights": list(self.weights),
                "onset_flow_before_l_min": self.onset_flow_before * lpm,
                "onset_flow_after_l_min": self.onset_flow_after * lpm,
                "frequency_before_hz": self.frequency_before,
                "frequency_after_hz": self.frequency_after,
                "target_flow_l_min": self.target_flow * lpm,
                "verified": {"stable_below": self.stable_below,
                             "unstable_above": self.unstable_above,
                             "margin": VERIFY_MARGIN},
                "evaluations": self.evaluations, "note": self.note,
                "warnings": list(self.warnings)}


def parse_vary(vary, physical: Physical) -> dict:
    """``{[physical] key: weight}`` of ``vary``: a name (a key or an everyday name,
    weight 1), ``"stiffness=1,length=-1"``, or such a mapping; ValueError naming the
    allowed names."""
    if isinstance(vary, str):
        items = []
        for part in vary.split(","):
            name, _, weight = part.strip().partition("=")
            try:
                items.append((name.strip(), float(weight) if weight else 1.0))
            except ValueError:
                raise ValueError(f"--vary {vary!r}: {weight!r} is not a weight (a number)") from None
    else:
        items = list(dict(vary).items())
    allowed = [k for k in KEYS if k in physical.values and k != "flow"]
    allowed += [h for h in ("H1", "H2") if h not in allowed]
    out = {}
    for name, weight in items:
        key = ALIASES.get(name, name)
        if key not in allowed:
            raise ValueError(f"--vary {name!r}: not a parameter of {physical.source} that a "
                             f"design may change; allowed: {', '.join(allowed)} (or "
                             f"{', '.join(a for a, k in ALIASES.items() if k in allowed)})")
        if not (math.isfinite(weight) and weight != 0) or key in out:
            raise ValueError(f"--vary: each parameter once, with a finite weight other than "
                             f"0; got {name}={weight}")
        out[key] = float(weight)
    if len(out) > 1 and "zeta" in out:
        raise ValueError("--vary: the damping ratio (which may be 0) varies only on its own, "
                         "not in a weighted combination")
    return out


def with_values(physical: Physical, values: dict) -> Physical:
    """``physical`` with the parameters of ``values`` set (SI)."""
    new = {**physical.values, **values}
    H1, H2 = values.get("H1", physical.H1), values.get("H2", physical.H2)
    if "gap" in values:
        H1 = H2 = values["gap"]
    return replace(physical, values=new, H1=H1, H2=H2)


def design_for_flow(physical: Physical, target: Flow, vary, *, ustar_max: float = USTAR_MAX,
                    base: PalateSensitivity | None = None, **overrides) -> Design:
    """The smallest change of ``vary`` (:func:`parse_vary`) that raises the onset airflow
    of ``physical`` to ``target`` (module doc; its magnitude, for reversed flow: then
    ``target`` < 0 and ``direction="reverse"``); ``overrides``: nondimensional Scene
    fields (modes, direction, ...); ``base``: :func:`palate_sensitivity` of ``physical`` with them, if
    already computed. Verified by the eigenvalues at the design."""
    weights = parse_vary(vary, physical)
    q_target = target.value if target.kind == "volume" else \
        target.value * physical.values["b"] * physical.gap
    base = base or palate_sensitivity(physical, ustar_max=ustar_max, **overrides)
    overrides = {**overrides, "direction": base.scene.direction}
    _check_direction(q_target, base)
    start = {k: physical.values[k] if k in physical.values else getattr(physical, k)
             for k in weights}
    if abs(base.onset_flow) >= abs(q_target):
        return _design(physical, weights, start, start, base, base, q_target, overrides, 0,
                       "the onset is already at or beyond the target (|Q_c| >= |target|): "
                       "no change needed")
    path = _Path(physical, weights, start, base, q_target, ustar_max, overrides)
    with warnings.catch_warnings():      # the search's trial palates: only the design's count
        warnings.simplefilter("ignore", PhysicalValidityWarning)
        lo, hi = path.bracket()
        s = brentq(lambda s: abs(path.onset(s)) - abs(q_target), lo, hi,
                   xtol=1e-13 * max(abs(hi), 1e-6), rtol=1e-12)
    after = path.values(s)
    designed = with_values(physical, after)
    with warnings.catch_warnings(record=True) as caught:   # each of the designed palate's
        warnings.simplefilter("always")                    # scenes warns alike: say it once
        bound = max(ustar_max, 2.0 * path.ustar_of(designed))
        designed = palate_sensitivity(designed, ustar_max=bound, **overrides)
        design = _design(physical, weights, start, after, base, designed, q_target, overrides,
                         path.evaluations)
    said = {(w.category, str(w.message)): w for w in caught}
    for category, message in said:
        warnings.warn(message, category, stacklevel=2)
    return replace(design, warnings=tuple(message for _, message in said))


def _check_direction(q_target: float, base: PalateSensitivity) -> None:
    """ValueError unless the target flow has the direction of the onset's scene."""
    if q_target * base.scene.flow_sign <= 0:
        raise ValueError(f"the target flow {q_target * 60e3:.4g} L/min is not in the direction "
                         f"of the onset ({base.scene.direction} flow, {base.onset_flow * 60e3:.4g} "
                         "L/min): a target of reversed flow (expiration) is negative, with the "
                         "scene's direction reverse")


class _Path:
    """The parameters along the search variable ``s``, and the onset airflow there (its
    model reused while the structure is the same); counts the onsets computed."""

    def __init__(self, physical, weights, start, base: PalateSensitivity, q_target,
                 ustar_max, overrides):
        self.physical, self.weights, self.start = physical, weights, start
        self.q_target, self.ustar_max, self.overrides = q_target, ustar_max, overrides
        self.model, self.evaluations = None, 0
        self.linear = list(weights) == ["zeta"]            # a damping ratio, maybe 0
        missing = [k for k in weights if k not in base.parameters]
        if missing:
            raise DesignError(f"{', '.join(missing)}: the onset is a symmetry-breaking "
                              "divergence, which unequal heights unfold (not differentiable in "
                              "one height alone): vary gap (both heights together)")
        rate = sum(w * (base.parameters[k].flow_per_unit if self.linear
                        else base.parameters[k].flow) for k, w in weights.items())
        if rate == 0.0:
            raise DesignError(f"{', '.join(weights)} does not move the onset (its derivative "
                              "is 0): choose another parameter or other weights")
        self.sign = 1.0 if rate > 0 else -1.0
        self.step = math.log1p(DESIGN_STEP) / max(abs(w) for w in weights.values())

    def values(self, s: float) -> dict:
        """The parameters at ``s``: the damping ratio itself, or ``ln theta_j0 + w_j s``."""
        if self.linear:
            return {"zeta": s}
        return {k: v * math.exp(self.weights[k] * s) for k, v in self.start.items()}

    def point(self, k: int) -> float | None:
        """``s`` after ``k`` steps (None past the search range)."""
        if not self.linear:
            s = self.sign * k * self.step
            ok = all(1 / DESIGN_MAX_FACTOR <= math.exp(w * s) <= DESIGN_MAX_FACTOR
                     for w in self.weights.values())
            return s if ok else None
        z0 = self.start["zeta"]
        if k == 0:
            return z0
        z = z0 * (1 + DESIGN_STEP) ** (self.sign * k) if z0 else \
            (1e-3 * (1 + DESIGN_STEP) ** (k - 1) if self.sign > 0 else None)
        return z if z is not None and z < 1.0 else None

    def onset(self, s: float) -> float:
        ph = with_values(self.physical, self.values(s))
        ph.check_validity()
        bound = max(self.ustar_max, 2.0 * self.ustar_of(ph))
        scene, self.model, hopf = physical_onset(ph, self.overrides, bound, self.model)
        self.evaluations += 1
        return scene.scales.m3_per_s(hopf.ustar)

    def ustar_of(self, physical: Physical) -> float:
        """|U*| of the target flow on ``physical``."""
        flow = Flow.of("volume", abs(self.q_target))      # its sign: overrides' direction
        return abs(physical_scene(physical, flow, self.overrides).ustar)

    def bracket(self) -> tuple[float, float]:
        """The step of ``s`` in which the onset passes the target (DesignError if none)."""
        lo, q_lo, k = self.point(0), None, 0
        while True:
            k += 1
            s = self.point(k)
            if s is None:
                reach = "up to a damping ratio of 1" if self.linear else \
                    f"within a factor {DESIGN_MAX_FACTOR:g}"
                got = "" if q_lo is None else f" (it reaches {q_lo * 60e3:.4g} L/min)"
                raise DesignError(f"no change of {', '.join(self.weights)} {reach} lifts the "
                                  f"onset to {self.q_target * 60e3:.4g} L/min{got}")
            try:
                q = self.onset(s)
            except (DesignError, ValueError) as err:
                raise DesignError(f"the search left the model's range before the onset "
                                  f"reached the target ({self._say(s)}: {err})") from None
            if abs(q) >= abs(self.q_target):
                return (lo, s) if lo <= s else (s, lo)
            lo, q_lo = s, q

    def _say(self, s: float) -> str:
        return ", ".join(f"{k} = {v:.4g}" for k, v in self.values(s).items())


def _design(physical, weights, before, after, base, designed, q_target, overrides,
            evaluations, note="") -> Design:
    """The Design, with its verification by eigenvalues at the designed parameters."""
    ph = with_values(physical, after)
    scenes = [physical_scene(ph, Flow.of("volume", factor * abs(designed.onset_flow)),
                             overrides) for factor in (1 - VERIFY_MARGIN, 1 + VERIFY_MARGIN)]
    model = build_model(scenes[0])                 # the two differ in the flow only
    checks = [linear_stability(scene, model).stable for scene in scenes]
    unit = lambda k: KEYS.get(k) or ("m" if k in ("H1", "H2") else "-")
    changes = tuple(Change(k, unit(k), float(before[k]), float(after[k])) for k in weights)
    return Design(changes, tuple(weights.values()), base.onset_flow, designed.onset_flow,
                  base.frequency, designed.frequency, float(q_target), checks[0],
                  not checks[1], evaluations, note)
