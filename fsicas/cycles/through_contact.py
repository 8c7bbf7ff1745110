"""The impacting branch from the first wall contact, from the scene alone.

The contact-free cycles (:func:`~fsicas.cycles.collocation.cycle_branch`, the scene's
contact law off) are continued from the Hopf point; the last of them at least
``min_gap_ratio`` eps from the wall (:func:`~fsicas.cycles.impacting.pre_contact_start`)
is a cycle of the model with contact too, and starts the impacting branch by adaptive
collocation (:func:`~fsicas.cycles.impacting_collocation.impacting_collocation_branch`)
on the scene with its contact law.
"""
from __future__ import annotations

from ..model.assembly import Model, build_model
from ..scene import Scene
from .collocation import CycleSettings, cycle_branch
from .impacting import pre_contact_start
from .impacting_collocation import (CollocatedImpactBranch, CollocationImpactSettings,
                                    impacting_collocation_branch)

__all__ = ["branch_through_contact"]


def branch_through_contact(scene: Scene, *, model: Model | None = None,
                           ustar_max: float = 12.0,
                           settings: CollocationImpactSettings = CollocationImpactSettings(),
                           cycle_settings: CycleSettings = CycleSettings(),
                           min_gap_ratio: float = 3.0) -> CollocatedImpactBranch:
    """The impacting cycles of ``scene`` (``contact=True``, a smoothed law) from the first
    contact to ``ustar_max``. Raises ValueError if the contact-free cycles do not reach
    the wall below ``ustar_max``, or none of them is ``min_gap_ratio`` eps clear of it.
    ``model``: ``build_model(scene)`` if already built (it does not depend on U*)."""
    if not (scene.contact and scene.contact_smoothing > 0):
        raise ValueError("scene must have contact=True and contact_smoothing > 0 (the law "
                         "the impacting cycles are computed with)")
    free = cycle_branch(scene.replace(contact=False), ustar_max=ustar_max,
                        settings=cycle_settings)
    if free.contact is None:
        raise ValueError(f"the contact-free cycles do not reach the wall below U* = "
                         f"{ustar_max:g}: raise ustar_max")
    start = pre_contact_start(free, min_gap_ratio)
    at_start = scene.replace(ustar=start.ustar)
    return impacting_collocation_branch(at_start, start.state, start.period,
                                        start.pressure_drop, model=model or build_model(scene),
                                        ustar_max=ustar_max, settings=settings)
