"""The codimension-two picture over a window of M*: the stability boundary through the
onsets at COUNT mass ratios (:func:`fsicas.linear.boundary.stability_boundary`: its
curves and mode switches), the generalized Hopf, double Hopf, zero-Hopf and
Bogdanov-Takens points on the Hopf curves through the flutter onsets
(:func:`fsicas.linear.codim2.codim_two_points`; the curve is traced from every flutter
onset, and a point found from several onsets of one curve is kept once), and the curves
switched onto from those on the boundary: a fold-of-cycles curve from each generalized
Hopf point, a torus curve from each double Hopf point
(:func:`fsicas.cycles.bautin.switched_curves`).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..linear.boundary import StabilityBoundary, stability_boundary
from ..linear.codim2 import codim_two_points
from ..linear.hopf import first_onset
from ..model.assembly import Model
from ..scene import Scene
from .bautin import switched_curves
from .collocation import CycleSettings
from .curves import CurveSettings

__all__ = ["WindowDiagram", "window_diagram", "onset_points", "SAME_POINT_RTOL", "KINDS"]

#: the codimension-two points searched on the Hopf curves: generalized Hopf, double Hopf,
#: zero-Hopf (where a Hopf curve crosses a divergence curve), Bogdanov-Takens (where it
#: ends on one, its frequency going to zero)
KINDS = ("gh", "hh", "zh", "bt")
#: two codimension-two points of one kind closer than this in M* and U* (relative) are one
SAME_POINT_RTOL = 1e-6


@dataclass(frozen=True)
class WindowDiagram:
    """``onsets``: ``{mstar, kind, ustar}`` at each M* of the window (kind None: no onset
    below ``ustar_max``); ``points``: the CodimTwoPoints found, sorted by M*; ``curves``:
    the SwitchedCurves born at those on the boundary; ``warnings``; ``boundary``: the
    stability boundary over the window (its curves drawn, its mode switches reported)."""

    mstar_window: tuple
    ustar_max: float
    onsets: tuple
    points: tuple
    curves: tuple
    warnings: tuple
    wall_time: float
    boundary: StabilityBoundary = field(repr=False, compare=False)

    def to_json(self, points: bool = True) -> dict:
        curves = [c.to_json() for c in self.curves]
        if not points:
            curves = [{"point": c["point"], "kind": c["curve"]["kind"],
                       "n_points": len(c["curve"]["points"]), "message": c["curve"]["message"]}
                      for c in curves]
        return {"mstar_window": list(self.mstar_window), "ustar_max": self.ustar_max,
                "onsets": list(self.onsets), "codim2": [p.to_json() for p in self.points],
                "switches": [vars(s) for s in self.boundary.switches],
                "curves": curves, "warnings": list(self.warnings), "wall_time": self.wall_time}


def window_diagram(scene: Scene, model: Model, mstars, *, ustar_max: float = 20.0,
                   cycles: CycleSettings = CycleSettings(), curve_points: int = 40,
                   epsilon: float = 0.02, progress=lambda text: None) -> WindowDiagram:
    """The codimension-two picture of ``scene`` over the M* values ``mstars`` (module doc);
    ``curve_points``: points of each switched curve per direction at most; ``epsilon``:
    the switches' predictor distance along the Hopf curve; ``progress(text)`` is told each
    stage."""
    start = time.perf_counter()
    mstars = np.sort(np.asarray(mstars, dtype=float))
    window = (math.log10(mstars[0]), math.log10(mstars[-1]))
    progress(f"the stability boundary at {mstars.size} M*")
    boundary = stability_boundary(scene, mstars, model, ustar_max)
    onsets, points = onset_points(scene, model, mstars, window, ustar_max, KINDS, progress)
    warnings = list(boundary.warnings)
    settings = CurveSettings(mstar_min=float(mstars[0]), mstar_max=float(mstars[-1]),
                             max_points=curve_points)
    on_boundary = [p for p in sorted(points, key=lambda p: p.mstar) if p.on_boundary]
    progress(f"{len(on_boundary)} curves switched onto from the codimension-two points")
    curves = switched_curves(scene, model, on_boundary, epsilon=epsilon, settings=settings,
                             cycles=cycles, ustar_max=ustar_max) if on_boundary else []
    if any(o["kind"] == "divergence" for o in onsets):
        warnings.append("divergence onsets in the window: the divergence curves are not "
                        "searched for codimension-two points of their own (the zero-Hopf and "
                        "Bogdanov-Takens points where a Hopf curve meets them are; cusps of "
                        "the divergence curves are not)")
    return WindowDiagram((float(mstars[0]), float(mstars[-1])), float(ustar_max), tuple(onsets),
                         tuple(sorted(points, key=lambda p: p.mstar)), tuple(curves),
                         tuple(warnings), time.perf_counter() - start, boundary)


def onset_points(scene: Scene, model: Model, mstars, window, ustar_max: float, kinds,
                 progress=lambda text: None) -> tuple[list, list]:
    """``(onsets, points)``: the onset at each of ``mstars`` (``{mstar, kind, ustar}``) and
    the ``kinds`` of codimension-two points inside ``window`` (log10 M*) on the Hopf curves
    through the flutter onsets, each point once, sorted by M*."""
    onsets, points = [], []
    for m in mstars:
        progress(f"the onset at M* = {m:g}")
        onset = first_onset(scene.replace(mstar=float(m)), model, ustar_max)
        onsets.append({"mstar": float(m), "kind": None if onset is None else onset.kind,
                       "ustar": None if onset is None else float(onset.ustar)})
        if onset is not None and onset.kind == "flutter":
            progress(f"the Hopf curve through the onset at M* = {m:g}")
            points += [p for p in codim_two_points(scene, model, onset, window, ustar_max,
                                                   kinds=kinds) if not _known(p, points)]
    return onsets, sorted(points, key=lambda p: p.mstar)


def _known(point, points) -> bool:
    """``point`` (a CodimTwoPoint) is one of ``points`` (found from another onset)."""
    return any(p.kind == point.kind and abs(p.mstar - point.mstar) <= SAME_POINT_RTOL * p.mstar
               and abs(p.ustar - point.ustar) <= SAME_POINT_RTOL * p.ustar for p in points)
