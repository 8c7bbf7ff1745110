"""The analysis of one study point: a flat row of numbers (and a few words), never an
exception (a point that cannot be computed is a row with its ``error``; the warnings of
its analysis, e.g. a modal truncation too short, are its ``warnings``).

Each worker process keeps the models it built, keyed by structure
(:func:`fsicas.timedomain.run.sweep_model`), so a sweep over parameters that do not
shape the model (M*, f, damping, the flow; E, densities, the length of a thin beam)
builds it once.
"""
from __future__ import annotations

import warnings

from ..linear.design import with_values
from ..linear.onset import onset_at_own_flow
from ..physical import Flow, Physical, load_physical, parse_flow
from ..scene import Scene
from ..timedomain.integrators import Settings
from ..timedomain.outcome import Criteria
from ..timedomain.run import run_case, sweep_model
from ..timedomain.sound import cycle_sound, trajectory_sound
from .spec import Study

__all__ = ["study_point"]



def study_point(study: Study, index: int) -> dict:
    """The row of point ``index`` of ``study``: its parameters, then the results."""
    point = study.points[index]
    row = {"index": index, **point}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            row.update(_ANALYSES[study.analysis](study, point))
            row["error"] = ""
        except Exception as err:       # a point that cannot run is data, not a crash
            row["error"] = f"{type(err).__name__}: {err}"
    row["warnings"] = "; ".join(dict.fromkeys(str(w.message) for w in caught))
    return row


def _scene(study: Study, point: dict) -> tuple[Scene, Physical | None, Flow | None]:
    """The point's scene (and its physical input and airflow, for a physical study)."""
    if study.physical is None:
        return Scene.from_dict({**study.scene, **point}), None, None
    physical = with_values(load_physical(study.physical),
                           {k: v for k, v in point.items() if k != "flow"})
    flow = parse_flow(point["flow"]) if "flow" in point else physical.flow
    return physical.scene(flow, **study.scene), physical, flow


def _onset(study: Study, point: dict) -> dict:
    scene, physical, flow = _scene(study, point)
    viscous = physical is not None and "viscosity" in physical.values and \
        "friction" not in physical.scene_fields and "friction" not in study.scene
    scene, hopf, _ = onset_at_own_flow(scene, sweep_model(scene, guarded=False), study.settings["ustar_max"],
                                       physical if viscous else None)
    row = {"found": hopf is not None, "mstar": scene.mstar, "hstar": scene.hstar,
           "friction": scene.friction}
    keys = ("kind", "ustar_crit", "omega", "pressure_drop", "freq_ratio", "l1", "criticality",
            "dominant_mode", "truncation")
    row.update({k: (hopf.to_json().get(k) if hopf else None) for k in keys})
    if physical is not None:
        sc = scene.scales
        row.update(onset_flow_l_min=sc.l_per_min(hopf.ustar) if hopf else None,
                   onset_velocity_m_s=sc.m_per_s(hopf.ustar) if hopf else None,
                   frequency_hz=sc.hz(hopf.omega) if hopf else None,
                   pressure_drop_pa=sc.pa(hopf.pressure_drop) if hopf else None)
    return row


def _run(study: Study, point: dict):
    """``(scene, physical, run)``: the point's time integration, classified."""
    scene, physical, _ = _scene(study, point)
    if scene.ustar <= 0:
        raise ValueError("the outcome needs a flow: give ustar (or flow, with physical = ...)")
    s = study.settings
    settings = Settings(rtol=s["rtol"], atol=s["atol"], dt_out=s["dt_out"], chunk=1.0)
    run = run_case(scene, s["t_end"], settings=settings, criteria=Criteria(),
                   model=sweep_model(scene))
    return scene, physical, run


def _outcome_row(scene: Scene, physical, run) -> dict:
    out = run.to_json()
    keep = ("outcome", "period", "omega", "tip_amplitude", "contact", "first_contact_time",
            "max_impact_force", "mean_flow_reduction", "settled", "convergence", "status")
    row = {k: out[k] for k in keep}
    row.update(ustar=scene.ustar, mstar=scene.mstar)
    if physical is not None and row["omega"] is not None:
        row["frequency_hz"] = scene.scales.hz(row["omega"])
    return row


def _outcome(study: Study, point: dict) -> dict:
    return _outcome_row(*_run(study, point))


def _sound(study: Study, point: dict) -> dict:
    """The outcome and the radiated sound at ``distance`` (:mod:`fsicas.timedomain.sound`):
    of the settled cycle, or of the last third of a run that oscillates but did not
    settle; none after a decay or a contact-free run's first contact."""
    if study.physical is None:
        raise ValueError("the sound analysis needs physical = ... (Pa at a distance in m)")
    scene, physical, run = _run(study, point)
    row = _outcome_row(scene, physical, run)
    traj, o, r = run.trajectory, run.outcome, study.settings["distance"]
    row.update(spl_db=None, fundamental_hz=None, fundamental_lo_hz=None, fundamental_hi_hz=None,
               dominant_hz=None)
    if o.periodic:
        sound = cycle_sound(traj, scene.scales, r, duration=1.0)
    elif o.outcome in ("unsettled", "impacting_nonperiodic") or (o.outcome == "contact" and
                                                                 scene.contact):
        sound = trajectory_sound(traj, scene.scales, r, t_start=traj.t[-1] * 2 / 3)
    else:
        return row
    lo, hi = sound.fundamental_ci_hz or (None, None)
    row.update(spl_db=sound.spl_db, fundamental_hz=sound.fundamental_hz, fundamental_lo_hz=lo,
               fundamental_hi_hz=hi, dominant_hz=sound.dominant_hz)
    for message in sound.warnings:          # an irregular snore's pitch: the row's warnings
        warnings.warn(message)
    return row


_ANALYSES = {"onset": _onset, "outcome": _outcome, "sound": _sound}
