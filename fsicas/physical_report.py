"""Results in physical units: the ``"physical"`` object of each command's JSON.

Each function takes the nondimensional JSON of a result and the :class:`fsicas.Scales`
of its scene (``scene.scales``, set when the scene came from physical input) and returns
the same quantities in SI-derived units, the unit stated in each key's suffix:
``_hz`` (frequency ω / (2π T)), ``_per_s`` (growth rate Re λ / T), ``_s`` (time t T),
``_pa`` (pressure Δp D / L^3), ``_mm`` (deflection y L), ``_m_s`` (mean inlet velocity
U* L / T), ``_l_min`` and ``_m3_s`` (volume flow U0 b (H1 + H2) through both channels).
Conversions are those of :mod:`fsicas.units`.
"""
from __future__ import annotations

import math

from .scene import Scene
from .units import Scales

__all__ = ["add_physical", "scales_json", "flow_json", "onset_json", "CONVERTERS"]

#: First in-vacuo clamped-free frequency (beta_1 L)^2, rad per unit T.
OMEGA_1 = 1.875104068711961 ** 2


def _opt(fn, value):
    return None if value is None else fn(value)


def scales_json(sc: Scales) -> dict:
    """The scales of the conversion and the first in-vacuo frequency."""
    return {"length_m": sc.length, "time_s": sc.time, "pressure_pa": sc.pressure,
            "velocity_m_s": sc.velocity, "width_m": sc.width, "gap_m": sc.gap,
            "fluid_density_kg_m3": sc.fluid_density,
            "beam_mass_per_area_kg_m2": sc.beam_mass_per_area,
            "first_mode_hz": sc.hz(OMEGA_1)}


def flow_json(sc: Scales, ustar, prefix: str = "") -> dict:
    """A mean inlet velocity U* as m/s, L/min and m^3/s (None stays None)."""
    return {f"{prefix}velocity_m_s": _opt(sc.m_per_s, ustar),
            f"{prefix}flow_l_min": _opt(sc.l_per_min, ustar),
            f"{prefix}flow_m3_s": _opt(sc.m3_per_s, ustar)}


def _steady(out: dict, scene: Scene, sc: Scales) -> dict:
    q_scale = sc.length * sc.velocity * sc.width * 60e3     # Q_i (units of L^2/T) -> L/min
    return {**flow_json(sc, scene.ustar), "pressure_drop_pa": sc.pa(out["pressure_drop"]),
            "channel_flows_l_min": [Q * q_scale for Q in out["Q"]],
            "tip_deflection_mm": sc.mm(out["tip_deflection"])}


def _eig(out: dict, scene: Scene, sc: Scales) -> dict:
    return {**flow_json(sc, scene.ustar), "pressure_drop_pa": sc.pa(out["pressure_drop"]),
            "growth_rate_per_s": [re / sc.time for re, _ in out["eigenvalues"]],
            "frequency_hz": [sc.hz(im) for _, im in out["eigenvalues"]]}


def _onset_point(sc: Scales, p: dict, ustar_key: str = "ustar_crit") -> dict:
    """One Hopf or boundary point: onset velocity and flow, frequency, fluid density."""
    out = {"mstar": p["mstar"], **flow_json(sc, p.get(ustar_key), "onset_"),
           "frequency_hz": _opt(sc.hz, p.get("omega")),
           "fluid_density_kg_m3": p["mstar"] * sc.beam_mass_per_area / sc.length}
    if p.get("pressure_drop") is not None:
        out["pressure_drop_pa"] = sc.pa(p["pressure_drop"])
    return out


def _switch(sc: Scales, s: dict) -> dict:
    return {"mstar": s["mstar"], **flow_json(sc, s["ustar_below"], "below_"),
            **flow_json(sc, s["ustar_above"], "above_"),
            "frequency_below_hz": sc.hz(s["omega_below"]),
            "frequency_above_hz": sc.hz(s["omega_above"])}


def _boundary(out: dict, scene: Scene, sc: Scales) -> dict:
    """Each point at its own M*: the same beam in a fluid of density M* rho_s e / L."""
    return {"points": [_onset_point(sc, p) for p in out["points"]],
            "switches": [_switch(sc, s) for s in out["switches"]]}


def _cycle(sc: Scales, p: dict) -> dict:
    """A limit cycle (time integration or branch point): period, frequency, amplitude."""
    period = p.get("period")
    return {"period_s": _opt(sc.seconds, period),
            "frequency_hz": _opt(sc.hz, 2 * math.pi / period if period else None),
            "tip_amplitude_mm": _opt(sc.mm, p.get("tip_amplitude"))}


def _simulate(out: dict, scene: Scene, sc: Scales) -> dict:
    return {**flow_json(sc, scene.ustar), **_cycle(sc, out),
            "first_contact_time_s": _opt(sc.seconds, out.get("first_contact_time")),
            "t_end_reached_s": _opt(sc.seconds, out.get("t_end_reached"))}


def _lco_point(sc: Scales, p: dict) -> dict:
    return {**flow_json(sc, p["ustar"]), **_cycle(sc, p)}


def _impact_point(sc: Scales, p: dict, reference_force: float) -> dict:
    """An impacting cycle: as a limit cycle, plus the least gap and the peak impact force
    in N (``reference_force``: F0, nondimensional; impacts per cycle and the flow
    reduction stay dimensionless)."""
    return {**flow_json(sc, p["ustar"]), **_cycle(sc, p),
            "min_gap_mm": _opt(sc.mm, p.get("min_gap")),
            "peak_force_n": _opt(sc.newtons, p["peak_force"] * reference_force)}


def _lco(out: dict, scene: Scene, sc: Scales) -> dict:
    hopf = out.get("hopf")
    result = {"hopf": None if hopf is None else _onset_point(sc, hopf),
              "points": [_lco_point(sc, p) for p in out["points"]],
              "folds": [_lco_point(sc, p) for p in out["folds"]],
              "contact": _opt(lambda p: _lco_point(sc, p), out.get("contact"))}
    if "impacting" in out:
        imp = out["impacting"]
        force = imp.get("reference_force", float("nan"))
        result["impacting"] = [_impact_point(sc, p, force) for p in imp["points"]]
        result["impacting_special"] = [{"kind": p["kind"], **_impact_point(sc, p, force)}
                                       for p in imp.get("special", [])]
    return result


def _curve_point(sc: Scales, p: dict) -> dict:
    """A point of a curve in (M*, U*): at its own M*, i.e. the same beam in a fluid of
    density M* rho_s e / L (as the boundary's points)."""
    return {"mstar": p["mstar"], **flow_json(sc, p["ustar"]),
            "fluid_density_kg_m3": p["mstar"] * sc.beam_mass_per_area / sc.length,
            **_cycle(sc, p)}


def _grazing(out: dict, scene: Scene, sc: Scales) -> dict:
    return {"grazing": [_curve_point(sc, p) for p in out["grazing"]],
            "fold": [_curve_point(sc, p) for p in out["fold"]],
            "hopf": [_onset_point(sc, p, "ustar") for p in out["hopf"]]}


#: command -> conversion of its JSON
CONVERTERS = {"steady": _steady, "eig": _eig, "boundary": _boundary,
              "simulate": _simulate, "lco": _lco, "grazing": _grazing}


def add_physical(out: dict, scene: Scene, command: str) -> dict:
    """``out`` with a ``"physical"`` object when ``scene`` came from physical input
    (``scene.scales``), else ``out`` unchanged."""
    sc = scene.scales
    if sc is None:
        return out
    return {**out, "physical": {**CONVERTERS[command](out, scene, sc), "scales": scales_json(sc)}}


def onset_json(sc: Scales, hopf: dict | None, reference_ustar: float | None,
               ustar_max: float) -> dict:
    """The onset in physical units, and its margin to the reference (breathing) flow:
    ``margin_flow_l_min`` = onset - reference (> 0: the reference flow is below the onset),
    ``margin_ratio`` = onset / reference; ``flutters_at_reference``: reference >= onset
    (False when no onset was found below ``ustar_max`` and the reference lies below it);
    for reversed flow (negative flows) the same on their magnitudes."""
    if hopf is None:
        out = {**flow_json(sc, None, "onset_"), "frequency_hz": None, "pressure_drop_pa": None,
               "criticality": None}
    else:
        out = {**_onset_point(sc, hopf), "criticality": hopf.get("criticality")}
        out.pop("mstar")
        out.pop("fluid_density_kg_m3")
    out.update(flow_json(sc, reference_ustar, "reference_"), margin_flow_l_min=None,
               margin_ratio=None, flutters_at_reference=None)
    if reference_ustar is None:
        return out
    if hopf is None:
        out["flutters_at_reference"] = False if abs(reference_ustar) < ustar_max else None
        return out
    uc = hopf["ustar_crit"]
    sign = 1.0 if uc >= 0 else -1.0
    out.update(margin_flow_l_min=sign * (sc.l_per_min(uc) - sc.l_per_min(reference_ustar)),
               margin_ratio=uc / reference_ustar,
               flutters_at_reference=sign * reference_ustar >= sign * uc)
    return out
