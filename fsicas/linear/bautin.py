"""Generalized Hopf (Bautin) points of the flutter boundary: where the first Lyapunov
coefficient l1 of the onset changes sign along a Hopf curve, so the onset changes from
supercritical (l1 < 0) to subcritical (l1 > 0). There a fold-of-cycles curve is born, on
the side where l1 l2 < 0 (l2 the second Lyapunov coefficient): for l2 < 0 the subcritical
side holds the hysteresis between the fold of cycles and the Hopf curve.

The Hopf curve through a located Hopf point is continued in (Π, log10 M*) with the
detection of ``continuation`` on (its ``'gh'`` points, located on l1 = 0, carry l2). A
point of the curve lies on the boundary only where that curve is the lowest onset: each
point is checked against the one-parameter onset at its M* (:func:`first_onset`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import continuation as C

from ..model.assembly import Model
from ..scene import Scene
from .adapter import LOG_M, PI, TIME_SCALE
from .hopf import HopfPoint, first_onset, flutter_problem

__all__ = ["BautinPoint", "bautin_points"]

#: relative agreement in U* of a point of the curve with the onset at its M*
ON_BOUNDARY_RTOL = 1e-4


@dataclass(frozen=True)
class BautinPoint:
    """A generalized Hopf point: M*, U*, omega (the onset's time scale), the second
    Lyapunov coefficient ``l2`` and whether it lies on the stability boundary."""

    mstar: float
    ustar: float
    omega: float
    l2: float
    on_boundary: bool

    def to_json(self) -> dict:
        return {"mstar": self.mstar, "ustar": self.ustar, "omega": self.omega,
                "l2": self.l2 if math.isfinite(self.l2) else None,
                "on_boundary": self.on_boundary}


def bautin_points(scene: Scene, model: Model, hopf: HopfPoint, window,
                  ustar_max: float = 40.0) -> list[BautinPoint]:
    """The generalized Hopf points of the Hopf curve through ``hopf`` (located at
    ``scene``'s M*) with log10 M* inside ``window``, sorted by M*."""
    problem = flutter_problem(scene.replace(mstar=hopf.mstar), model, ustar_start=0.2)
    found = []
    for direction in (-1, 1):
        settings = C.ContinuationSettings(
            ds=0.05, ds_min=1e-8, ds_max=0.1, max_steps=400, direction=direction,
            bounds={LOG_M: tuple(window), PI: (0.0, _pi_bound(hopf, ustar_max))},
            compute_eigenvalues=False)            # l1 (the 'gh' test) needs none
        branch = C.continuation(C.HopfCurveProblem.from_point(problem, hopf.point, LOG_M),
                                settings=settings)
        found += [_bautin(scene, model, point, ustar_max) for point in branch.special("gh")
                  if point.status == "converged"]
    return sorted(found, key=lambda b: b.mstar)


def _pi_bound(hopf: HopfPoint, ustar_max: float) -> float:
    """Π at U* = ``ustar_max`` (Π ∝ U*²) with a margin."""
    return 1.5 * hopf.point.params[PI] * (ustar_max / hopf.ustar) ** 2


def _bautin(scene, model, point, ustar_max) -> BautinPoint:
    mstar = 10 ** point.params[LOG_M]
    ustar = float(point.x[-2:].sum() / scene.hstar)
    onset = first_onset(scene.replace(mstar=mstar), model, ustar_max)
    on = onset is not None and onset.kind == "flutter" and \
        abs(onset.ustar - ustar) <= ON_BOUNDARY_RTOL * ustar
    return BautinPoint(float(mstar), ustar, float(point.data["omega"] * TIME_SCALE),
                       float(point.data.get("l2", math.nan)), bool(on))
