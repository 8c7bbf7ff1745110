"""Impacting limit cycles versus U*: one call for both routes, from any start.

:func:`impacting_cycles` continues the cycles of ``scene`` (its contact law on) in U* by
adaptive collocation of the smoothed law (``method="collocation"``,
:mod:`fsicas.cycles.impacting_collocation`: special cycles located) or by multiple
shooting (``method="shooting"``, :mod:`fsicas.cycles.impacting`), and returns an
:class:`~fsicas.cycles.impacting.ImpactBranch` either way. The start is

- nothing: the contact-free cycles of ``scene`` (:func:`~fsicas.cycles.collocation.cycle_branch`,
  the contact law off) are continued from the Hopf point, and the last of them at least
  ``min_gap_ratio`` eps from the wall (:func:`~fsicas.cycles.impacting.pre_contact_start`),
  a cycle of the model with contact too, starts the impacting branch at its U*;
- such a contact-free :class:`~fsicas.cycles.collocation.CycleBranch`, already computed:
  the same from its cycles;
- one cycle: anything with ``state`` (at phase 0), ``period`` (units of T) and
  ``pressure_drop``, e.g. a :class:`StartCycle` of a settled time integration
  (:func:`~fsicas.cycles.impacting.cycle_from_trajectory`) or a point of another branch,
  continued on ``scene`` as given.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from ..checks import require
from ..model.assembly import Model
from ..scene import Scene
from .collocation import CycleBranch, CycleSettings, cycle_branch
from .impacting import (ImpactBranch, ImpactSettings, check_speeds, pre_contact_start,
                        shooting_branch)
from .impacting_collocation import CollocationImpactSettings, check_smooth, collocation_branch

__all__ = ["ImpactMethod", "StartCycle", "impacting_cycles", "impacting_start",
           "through_contact_law", "THROUGH_STIFFNESS", "THROUGH_EPS", "THROUGH_SMOOTHING"]

ImpactMethod = Literal["collocation", "shooting"]
"""The route of the impacting cycles: adaptive collocation of the smoothed contact law
(the default; special cycles located) or multiple shooting (any contact law)."""

#: each route's settings class and branch function
#: The contact law of the impacting branch where none is given (``fsicas lco
#: --through-contact``, ``fsicas explore``): that of Figs. 6-9 (docs/simulate.md),
#: smoothed (docs/cycles.md).
THROUGH_STIFFNESS, THROUGH_EPS, THROUGH_SMOOTHING = 1e8, 1e-2, 0.1


def through_contact_law(scene: Scene, stiffness: float | None = None,
                        eps: float | None = None) -> Scene:
    """``scene`` with the contact law its cycles are continued through contact on:
    k* = ``stiffness``, eps/H = ``eps`` (:data:`THROUGH_STIFFNESS`, :data:`THROUGH_EPS`
    where None) and its smoothing (:data:`THROUGH_SMOOTHING` where it has none); the
    contact switch itself as it is."""
    return scene.replace(contact_stiffness=stiffness or THROUGH_STIFFNESS,
                         contact_eps=eps or THROUGH_EPS,
                         contact_smoothing=scene.contact_smoothing or THROUGH_SMOOTHING)


_ROUTES = {"collocation": (CollocationImpactSettings, collocation_branch),
           "shooting": (ImpactSettings, shooting_branch)}


@dataclass(frozen=True)
class StartCycle:
    """A cycle to continue from: its ``state`` at phase 0, its ``period`` (units of T, the
    full period of a cycle of several sub-cycles) and the ``pressure_drop`` it runs at."""

    state: np.ndarray = field(repr=False)
    period: float
    pressure_drop: float


def impacting_cycles(scene: Scene, start=None, *, method: ImpactMethod = "collocation",
                     settings: CollocationImpactSettings | ImpactSettings | None = None,
                     model: Model | None = None, ustar_min: float = 0.0,
                     ustar_max: float = 12.0, direction: int = 1,
                     cycle_settings: CycleSettings = CycleSettings(),
                     min_gap_ratio: float = 3.0) -> ImpactBranch:
    """The impacting cycles of ``scene`` (``contact=True``; the collocation route also
    needs ``contact_smoothing`` > 0) from ``start`` (module docstring) with the speed
    |U*| within [``ustar_min``, ``ustar_max``] (reversed flow, U* < 0: the same in
    speed, the points report their signed U*), by ``method``, with ``settings`` of that
    route (its defaults where None). ``direction`` = +1 continues towards larger |U*|;
    ``cycle_settings``: of the contact-free cycles where they are computed here;
    ``model``: ``build_model(scene)`` if already built (it does not depend on U*).

    Raises ValueError for a scene without the contact law the route needs, settings of
    the other route, or contact-free cycles that do not reach the wall below
    ``ustar_max`` or have none ``min_gap_ratio`` eps clear of it."""
    check_speeds(ustar_min, ustar_max)
    kind, route = _route(method, settings)
    if method == "collocation":
        check_smooth(scene)
    elif not scene.contact:
        raise ValueError("impacting cycles by shooting need scene.contact = True (the impact "
                         "law)")
    scene, start = impacting_start(scene, start, ustar_max=ustar_max,
                                   cycle_settings=cycle_settings, min_gap_ratio=min_gap_ratio)
    require(start.pressure_drop * scene.flow_sign >= 0, "the start cycle's pressure drop "
            f"({start.pressure_drop:g}) has the sign of the other flow direction than the "
            f"scene's ({scene.direction}, U* = {scene.ustar:g}): give a start of the scene's "
            "direction (Δp < 0 for reversed flow)")
    return route(scene, start.state, start.period, start.pressure_drop,
                 model=model, ustar_min=ustar_min, ustar_max=ustar_max,
                 direction=direction, settings=kind() if settings is None else settings)


def impacting_start(scene: Scene, start=None, *, ustar_max: float = 12.0,
                    cycle_settings: CycleSettings = CycleSettings(),
                    min_gap_ratio: float = 3.0) -> tuple[Scene, object]:
    """``(scene, cycle)``: where :func:`impacting_cycles` starts from ``start`` (module
    docstring): ``scene`` at the U* of the last contact-free cycle ``min_gap_ratio`` eps
    clear of the wall and that cycle, or ``scene`` and ``start`` as given for one cycle."""
    if start is None:
        start = cycle_branch(scene.replace(contact=False), ustar_max=ustar_max,
                             settings=cycle_settings)
        if start.contact is None:
            raise ValueError(f"the contact-free cycles do not reach the wall below "
                             f"{'|U*|' if scene.direction == 'reverse' else 'U*'} = "
                             f"{ustar_max:g}: raise ustar_max")
    if not isinstance(start, CycleBranch):
        return scene, start
    if start.contact is None:
        raise ValueError("the contact-free cycles do not reach the wall: continue them to a "
                         "higher ustar_max")
    cycle = pre_contact_start(start, min_gap_ratio)
    return scene.replace(ustar=cycle.ustar), cycle


def _route(method: str, settings) -> tuple:
    """(settings class, branch function) of ``method``; ValueError for another method or
    settings of another route."""
    if method not in _ROUTES:
        raise ValueError(f"method must be one of {sorted(_ROUTES)}, got {method!r}")
    kind, route = _ROUTES[method]
    if settings is not None and not isinstance(settings, kind):
        raise ValueError(f"method={method!r} takes {kind.__name__}, got "
                         f"{type(settings).__name__}")
    return kind, route
