"""The onset (flutter or divergence) of a physical configuration whose friction depends
on the flow.

With a viscosity instead of a fixed friction (``fsicas.physical``), the Fanning f of
Eq. (15) depends on the Reynolds number of the airflow, so the onset is that of the
friction taken at the onset's own flow: a fixed point, found by successive onsets
(:func:`critical_velocity` reuses the model, f being a parameter).
"""
from __future__ import annotations

from ..physical import Flow, Physical
from ..scene import Scene
from .hopf import Onset, critical_velocity

__all__ = ["onset_at_own_flow", "FRICTION_STEPS", "FRICTION_RTOL"]

#: Fixed-point steps at most, and the relative change of f that ends them.
FRICTION_STEPS, FRICTION_RTOL = 12, 1e-6


def onset_at_own_flow(scene: Scene, model, ustar_max: float, physical: Physical | None = None
                      ) -> tuple[Scene, Onset | None, float | None]:
    """The onset of ``scene`` below ``ustar_max`` (:func:`critical_velocity`: the first
    loss of stability, ``.kind`` "flutter" or "divergence"); with ``physical`` (whose
    friction comes from a viscosity) the friction is taken at the onset's own flow, from
    the scene's, by fixed-point steps. Returns the scene with that friction, the onset
    (None if there is none) and the Reynolds number of the last step (None without
    ``physical``)."""
    hopf = critical_velocity(scene, model, ustar_max)
    reynolds = None
    for _ in range(FRICTION_STEPS if physical is not None else 0):
        if hopf is None:
            break
        flow = Flow.of("velocity", scene.scales.m_per_s(hopf.ustar))
        friction, reynolds = physical.friction(flow)
        if abs(friction - scene.friction) <= FRICTION_RTOL * scene.friction:
            break
        scene = scene.replace(friction=friction)
        hopf = critical_velocity(scene, model, ustar_max)
    return scene, hopf, reynolds
