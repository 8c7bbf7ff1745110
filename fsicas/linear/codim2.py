"""Codimension-two points of the Hopf curves of the flutter boundary.

* Generalized Hopf (Bautin, ``'gh'``): the first Lyapunov coefficient l1 of the onset
  changes sign along a Hopf curve, so the onset changes from supercritical (l1 < 0) to
  subcritical (l1 > 0). A fold-of-cycles curve is born there on the side where l1 l2 < 0
  (l2 the second Lyapunov coefficient): for l2 < 0 the subcritical side holds the
  hysteresis between the fold of cycles and the Hopf curve.
* Double Hopf (``'hh'``): a second pair crosses the axis on the curve, where two Hopf
  curves (or two branches of one) cross; its amplitude coefficients ``p11 .. p22``, the
  simple/difficult case and whether stable two-frequency motion (a torus) exists near it.

The Hopf curve through a located Hopf point is continued in (Π, log10 M*) with the
detection of ``continuation`` (the points are located on their test functions and carry
their normal-form coefficients in ``data``). A point lies on the boundary only where its
curve is the lowest onset: each is checked against the one-parameter onset at its M*
(:func:`first_onset`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import continuation as C

from ..model.assembly import Model
from ..scene import Scene
from .adapter import LOG_M, PI, TIME_SCALE, pi_interval
from .hopf import HopfPoint, first_onset, flutter_problem

__all__ = ["CodimTwoPoint", "codim_two_points", "ON_BOUNDARY_RTOL"]

#: relative agreement in U* of a point of the curve with the onset at its M*
ON_BOUNDARY_RTOL = 1e-4


@dataclass(frozen=True)
class CodimTwoPoint:
    """A ``kind`` ('gh' or 'hh') point at M*, U*; ``omega`` in the onset's time scale,
    ``on_boundary`` whether it lies on the stability boundary and ``data`` the point's
    normal-form coefficients (``l2``; or ``omega1, omega2, p11 .. p22, theta, delta,
    simple, stable_torus``, the frequencies in the curve's time scale); ``curve`` and
    ``point``: the library's Hopf curve problem and the located special point on it (the
    start of the curves switched onto, e.g. ``continuation.lpc_from_gh``)."""

    kind: str
    mstar: float
    ustar: float
    omega: float
    on_boundary: bool
    data: dict = field(default_factory=dict)
    curve: object = field(default=None, repr=False, compare=False)
    point: object = field(default=None, repr=False, compare=False)

    @property
    def l2(self) -> float:
        return float(self.data.get("l2", math.nan))

    def to_json(self) -> dict:
        finite = {k: v for k, v in self.data.items()
                  if not isinstance(v, float) or math.isfinite(v)}
        return {"kind": self.kind, "mstar": self.mstar, "ustar": self.ustar,
                "omega": self.omega, "on_boundary": self.on_boundary, **finite}


def codim_two_points(scene: Scene, model: Model, hopf: HopfPoint, window,
                     ustar_max: float = 40.0, kinds=("gh", "hh")) -> list[CodimTwoPoint]:
    """The points of ``kinds`` on the Hopf curve through ``hopf`` (located at ``scene``'s
    M*) with log10 M* inside ``window``, sorted by M*. Double Hopf points need the
    eigenvalues at every point of the curve; without 'hh' they are not computed."""
    problem = flutter_problem(scene.replace(mstar=hopf.mstar), model, ustar_start=0.2)
    found = []
    for direction in (-1, 1):
        settings = C.ContinuationSettings(
            ds=0.02, ds_min=1e-8, ds_max=0.05, max_steps=400, direction=direction,
            bounds={LOG_M: tuple(window), PI: pi_interval(0.0, _pi_bound(hopf, ustar_max))},
            compute_eigenvalues="hh" in kinds)
        curve = C.HopfCurveProblem.from_point(problem, hopf.point, LOG_M)
        branch = C.continuation(curve, settings=settings)
        found += [_point(scene, model, curve, p, ustar_max) for p in branch.special_points
                  if p.kind in kinds and p.status == "converged"]
    return sorted(found, key=lambda b: b.mstar)


def _pi_bound(hopf: HopfPoint, ustar_max: float) -> float:
    """Π at the speed |U*| = ``ustar_max`` (Π ∝ U*|U*|, < 0 for reversed flow) with a
    margin."""
    return 1.5 * hopf.point.params[PI] * (ustar_max / hopf.ustar) ** 2


def _point(scene, model, curve, point, ustar_max) -> CodimTwoPoint:
    mstar = float(10 ** point.params[LOG_M])
    ustar = float(point.x[-2:].sum() / scene.hstar)
    onset = first_onset(scene.replace(mstar=mstar), model, ustar_max)
    on = onset is not None and onset.kind == "flutter" and \
        abs(onset.ustar - ustar) <= ON_BOUNDARY_RTOL * abs(ustar)
    data = {k: v for k, v in point.data.items() if k not in ("bracket", "kappa", "omega")}
    return CodimTwoPoint(point.kind, mstar, ustar, float(point.data["omega"] * TIME_SCALE),
                         bool(on), data, curve, point)
