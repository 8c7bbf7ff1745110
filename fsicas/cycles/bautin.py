"""Curves of cycle bifurcations started at the codimension-two points of the boundary:
fold-of-cycles curves from its generalized Hopf (Bautin) points, torus (Neimark-Sacker)
curves from its double Hopf points.

At a Bautin point of a Hopf curve (``fsicas.linear.codim2``: l1 = 0, l2 != 0) the onset
changes between super- and subcritical, and a curve of folds of cycles (LPC) is born on
the side where l1 l2 < 0: between it and the Hopf curve the steady state and a large
cycle are both stable (hysteresis). ``continuation.lpc_from_gh`` predicts the first fold
from the Bautin normal form at a Hopf point a distance ``epsilon`` along the Hopf curve in
(Π, log10 M*) and corrects it; the curve is then continued in (Π, log10 M*) like the fold
curves found on cycle branches (:func:`fsicas.cycles.curves.trace_curve`), so it needs no
cycle branch that folds first. At a double Hopf point ``continuation.ns_from_hh`` starts
the torus curve of the cycles born on the Hopf curve (its amplitude equations' torus
condition ``mu2 + p21 r1^2 = 0``), continued the same way (no stop rule).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import continuation as C

from ..checks import require_forward
from ..linear.adapter import pi_of
from ..linear.codim2 import CodimTwoPoint, codim_two_points
from ..linear.hopf import first_onset
from ..model.assembly import Model, build_model
from ..scene import Scene
from .collocation import CycleSettings, ProfileGauge
from .curves import CurveSettings, CycleCurve, trace_curve

__all__ = ["SwitchedCurve", "fold_curves_from_bautin", "torus_curves_from_double_hopf",
           "switched_curves"]


@dataclass(frozen=True)
class SwitchedCurve:
    """The ``curve`` born at the codimension-two point ``point`` (its M*, U*, coefficients)."""

    point: CodimTwoPoint
    curve: CycleCurve

    def to_json(self) -> dict:
        return {"point": self.point.to_json(), "curve": self.curve.to_json()}


def fold_curves_from_bautin(scene: Scene, model: Model | None = None, *,
                            mstar_onset: float = 0.5, epsilon: float = 0.02,
                            settings: CurveSettings = CurveSettings(mstar_min=0.15,
                                                                    mstar_max=1.0),
                            cycles: CycleSettings = CycleSettings(),
                            ustar_max: float = 20.0) -> list[SwitchedCurve]:
    """The fold curves from the Bautin points on the boundary inside ``settings``' M*
    window, on the Hopf curve through the flutter onset at ``mstar_onset``; ``epsilon``:
    the predictor's distance along the Hopf curve in (Π, log10 M*); ``cycles``: the
    collocation mesh (``ntst``, ``ncol``), ``adapt_every``."""
    require_forward(scene, "the fold curves of cycles from generalized Hopf points")
    return _switched(scene, model, "gh", mstar_onset, epsilon, settings, cycles, ustar_max)


def torus_curves_from_double_hopf(scene: Scene, model: Model | None = None, *,
                                  mstar_onset: float = 25.0, epsilon: float = 0.01,
                                  settings: CurveSettings = CurveSettings(
                                      mstar_min=24.0, mstar_max=33.0, max_points=10),
                                  cycles: CycleSettings = CycleSettings(),
                                  ustar_max: float = 20.0) -> list[SwitchedCurve]:
    """The torus curves of the cycles born on the Hopf curve through the onset at
    ``mstar_onset`` at its double Hopf points on the boundary (as
    :func:`fold_curves_from_bautin`)."""
    require_forward(scene, "the torus curves")
    return _switched(scene, model, "hh", mstar_onset, epsilon, settings, cycles, ustar_max)


def _switched(scene, model, kind, mstar_onset, epsilon, settings, cycles, ustar_max):
    """The curves switched onto from the ``kind`` points on the boundary."""
    model = model or build_model(scene)
    onset = first_onset(scene.replace(mstar=mstar_onset), model, ustar_max)
    if onset is None or onset.kind != "flutter":
        raise ValueError(f"no flutter onset below U* = {ustar_max:g} at M* = {mstar_onset:g}")
    window = (np.log10(settings.mstar_min), np.log10(settings.mstar_max))
    points = codim_two_points(scene, model, onset, window, ustar_max, kinds=(kind,))
    return switched_curves(scene, model, [p for p in points if p.on_boundary], epsilon=epsilon,
                           settings=settings, cycles=cycles, ustar_max=ustar_max)


def switched_curves(scene: Scene, model: Model, points, *, epsilon: float,
                    settings: CurveSettings, cycles: CycleSettings,
                    ustar_max: float) -> list[SwitchedCurve]:
    """The curve born at each of ``points`` (CodimTwoPoint): the fold-of-cycles curve of a
    'gh' point (``continuation.lpc_from_gh``), the torus curve of an 'hh' point
    (``continuation.ns_from_hh``), traced inside ``settings``' M* window."""
    out = []
    for point in points:
        switch, curve_kind = {"gh": (C.lpc_from_gh, "fold"), "hh": (C.ns_from_hh, "ns")}[point.kind]
        gauge = ProfileGauge(model, point.point.x, scene.contact_gap, settings.quadrature_tol)
        start = switch(point.curve, point.point, epsilon=epsilon, settings=cycles.collocation)
        pi_max = pi_of(scene.replace(mstar=point.mstar), model, scene.flow_sign * ustar_max)
        out.append(SwitchedCurve(point, trace_curve(gauge, start, start.X0, curve_kind, settings,
                                                     pi_max)))
    return out
