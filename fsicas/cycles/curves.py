"""Curves of special cycles in (M*, U*): where wall contact begins, where the cycles fold.

* **Grazing curve**: the contact-free cycle whose minimal gap over the beam (both walls,
  ``fsicas.model.contact.GAP_POINTS``) and the period equals eps, the impact boundary of
  Fig. 4 (``continuation.Extremum`` on the collocation polynomial: one more equation).
* **Fold-of-cycles (LPC) curve**: where the unstable cycles of subcritical flutter turn
  into large stable ones; between it and the Hopf curve a stable steady state coexists
  with a stable cycle (hysteresis). ``continuation.CycleFold``, minimally extended.

Each curve starts at a point of a collocation branch in U* at one M*
(:func:`fsicas.cycles.collocation.continue_cycles`): the located first contact, or a cycle
fold located on the arclength and refined by Newton on the extended system
(``continuation.locate_cycle``). It is continued in (Π, log10 M*) both ways inside the M*
window (``continuation.CycleCurveProblem``: PALC, the mesh re-equidistributed and the flow
quadrature refined as on the branch). Per point: M*, U* (the steady state at the same
pressure drop, as on the branch), period, tip half-amplitude, min gap / eps, stability.
A fold curve ends where its cycles shrink below ``CurveSettings.min_amplitude`` (it meets
the Hopf curve at a generalized Hopf point, l1 = 0).
"""
from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass
from typing import Literal

import numpy as np

import continuation as C

from ..linear.adapter import LOG_M, PI
from ..linear.hopf import CriticalVelocityError
from ..model.assembly import Model, build_model
from ..scene import Scene
from .collocation import CycleRun, CycleSettings, ProfileGauge, continue_cycles
from .records import check_settings, plain_value

__all__ = ["CurveKind", "CurveSettings", "CurvePoint", "CycleCurve", "CurveMap", "grazing_curve",
           "fold_curves", "cycle_curves", "curve_seeds"]

CurveKind = Literal["grazing", "fold"]
"""A curve of grazing cycles (min gap = eps) or of cycle folds (LPC)."""


@dataclass(frozen=True)
class CurveSettings:
    """``mstar_min``/``mstar_max``: the M* window; ``ds``/``ds_max``: arclength steps
    (Euclidean norm of all node values, log10 M* and Π); ``max_points``: points per
    direction; ``tol``: Newton tolerance; ``min_amplitude``: a fold curve ends where its
    cycles' tip half-amplitude falls below this (they shrink onto the Hopf curve)."""

    mstar_min: float = 0.05
    mstar_max: float = 20.0
    ds: float = 0.02
    ds_max: float = 0.3
    max_points: int = 150
    tol: float = 1e-9
    min_amplitude: float = 2e-3

    def __post_init__(self):
        check_settings(self, integers=("max_points",),
                       positives=("mstar_min", "mstar_max", "ds", "ds_max", "tol",
                                  "min_amplitude"))
        if not self.mstar_min < self.mstar_max:
            raise ValueError(f"CurveSettings.mstar_min must be below mstar_max, got "
                             f"{self.mstar_min!r} and {self.mstar_max!r}")


@dataclass(frozen=True)
class CurvePoint:
    """One cycle of a curve (units: U*, M* nondimensional; period in T)."""

    mstar: float
    ustar: float
    period: float
    tip_amplitude: float
    gap_ratio: float
    stable: bool

    @classmethod
    def from_columns(cls, columns: dict, k: int) -> "CurvePoint":
        names = {"period": "cycle_period"}
        return cls(**{f: plain_value(columns[names.get(f, f)][k])
                      for f in cls.__dataclass_fields__})


@dataclass(frozen=True)
class CycleCurve:
    """A curve of special cycles in (M*, U*), in order along it. ``seed``: the cycle it
    started from (a :class:`CurvePoint` at the scene's M*); ``status``: why each end
    stopped (``continuation.Branch.status``: 'bound' = the M* window), ``message``."""

    kind: CurveKind
    seed: CurvePoint
    points: list
    status: tuple
    message: str
    wall_time: float

    def column(self, name: str) -> np.ndarray:
        return np.array([getattr(p, name) for p in self.points])

    def to_json(self) -> dict:
        return {"kind": self.kind, "seed": asdict(self.seed),
                "points": [asdict(p) for p in self.points], "status": list(self.status),
                "message": self.message, "wall_time": self.wall_time}

    @classmethod
    def from_json(cls, d: dict) -> "CycleCurve":
        return cls(d["kind"], CurvePoint(**d["seed"]), [CurvePoint(**p) for p in d["points"]],
                   tuple(d["status"]), d["message"], d["wall_time"])


@dataclass(frozen=True)
class CurveMap:
    """The grazing and fold-of-cycles curves of a scene over an M* window, started from
    the cycle branches at ``seeds`` (M*); ``failures``: the seeds that gave no curve, why."""

    grazing: list
    fold: list
    seeds: list
    failures: list
    wall_time: float

    def to_json(self) -> dict:
        """``grazing`` / ``fold``: the points of all curves, each with ``mstar``, ``ustar``
        and its ``curve`` (index in ``curves[kind]``); ``curves``: each curve whole."""
        flat = lambda curves: [{**asdict(p), "curve": i}
                               for i, c in enumerate(curves) for p in c.points]
        return {"grazing": flat(self.grazing), "fold": flat(self.fold),
                "curves": {"grazing": [c.to_json() for c in self.grazing],
                           "fold": [c.to_json() for c in self.fold]},
                "seeds": list(self.seeds), "failures": list(self.failures),
                "wall_time": self.wall_time}


def curve_seeds(switches, mstar_min: float, mstar_max: float) -> list:
    """One seed M* per piece of the flutter boundary (the pieces between its mode
    ``switches`` inside the window, each the cycles of another Hopf curve): the
    geometric middle of each piece."""
    inside = sorted(m for m in switches if mstar_min < m < mstar_max)
    edges = [mstar_min, *inside, mstar_max]
    return [math.sqrt(a * b) for a, b in zip(edges[:-1], edges[1:])]


def cycle_curves(scene: Scene, seeds, model: Model | None = None, *,
                 settings: CurveSettings = CurveSettings(),
                 cycles: CycleSettings = CycleSettings(), ustar_max: float = 20.0,
                 progress=None) -> CurveMap:
    """The grazing and fold curves through the cycle branches at the M* ``seeds`` (each
    curve traced once: a seed's contact or fold already on a traced curve starts none).
    ``progress(text)`` is told of each seed."""
    start = time.perf_counter()
    model = model or build_model(scene)
    found = {"grazing": [], "fold": []}
    failures = []
    for mstar in seeds:
        if progress:
            progress(f"cycle branch at M* = {mstar:.4g}")
        try:
            run = continue_cycles(scene.replace(mstar=float(mstar)), model,
                                  ustar_max=ustar_max, settings=cycles)
        except CriticalVelocityError as err:
            failures.append(f"M* = {mstar:.4g}: {err}")
            continue
        _add_new(found, run, settings, failures, mstar)
    return CurveMap(found["grazing"], found["fold"], [float(m) for m in seeds], failures,
                    time.perf_counter() - start)


def _add_new(found: dict, run: CycleRun, settings: CurveSettings, failures: list, mstar):
    """The curves through ``run``'s contact and folds that are not traced yet."""
    for sp in run.branch.special("contact"):
        if sp.status == "converged" and not _traced(found["grazing"], sp):
            found["grazing"].append(_trace(run, run.problem_at(sp), sp.unknowns, "grazing",
                                           settings))
    for sp in run.branch.special("fold"):
        if _traced(found["fold"], sp):
            continue
        square, result = C.locate_cycle(run.problem_at(sp), sp.unknowns, C.CycleFold(),
                                        C.NewtonSettings(tol=settings.tol))
        if result.converged:
            found["fold"].append(_trace(run, square, result.X, "fold", settings))
        else:
            failures.append(f"M* = {mstar:.4g}: fold not refined ({result.message})")


def _traced(curves: list, sp, rtol: float = 5e-3) -> bool:
    """Whether the special point ``sp`` (M*, U*) lies on one of ``curves`` (U* linear
    between the curve's points that bracket its M*)."""
    mstar, ustar = sp.record["mstar"], sp.record["ustar"]
    for curve in curves:
        m, u = curve.column("mstar"), curve.column("ustar")
        for k in np.flatnonzero((m[:-1] - mstar) * (m[1:] - mstar) <= 0):
            w = (mstar - m[k]) / (m[k + 1] - m[k]) if m[k + 1] != m[k] else 0.0
            if abs(u[k] + w * (u[k + 1] - u[k]) - ustar) <= rtol * ustar:
                return True
    return False


def grazing_curve(scene: Scene, model: Model | None = None, *,
                  settings: CurveSettings = CurveSettings(),
                  cycles: CycleSettings = CycleSettings(), run: CycleRun | None = None,
                  ustar_max: float = 20.0) -> CycleCurve:
    """The grazing curve through the first contact of the cycle branch at ``scene.mstar``
    (``run``: that branch's :class:`CycleRun` if already computed). Raises ValueError when
    the branch reaches no contact below ``ustar_max``."""
    run = run or continue_cycles(scene, model, ustar_max=ustar_max, settings=cycles)
    contacts = [sp for sp in run.branch.special("contact") if sp.status == "converged"]
    if not contacts:
        raise ValueError(f"the cycle branch at M* = {scene.mstar:g} reaches no located wall "
                         f"contact below U* = {ustar_max:g} ({run.branch.message})")
    sp = contacts[0]
    return _trace(run, run.problem_at(sp), sp.unknowns, "grazing", settings)


def fold_curves(scene: Scene, model: Model | None = None, *,
                settings: CurveSettings = CurveSettings(),
                cycles: CycleSettings = CycleSettings(), run: CycleRun | None = None,
                ustar_max: float = 20.0) -> list:
    """The fold-of-cycles curves through the cycle folds of the branch at ``scene.mstar``
    (none when flutter there is supercritical and the branch does not fold), each fold
    refined by Newton on its minimally extended system first."""
    run = run or continue_cycles(scene, model, ustar_max=ustar_max, settings=cycles)
    curves = []
    for sp in run.branch.special("fold"):
        square, result = C.locate_cycle(run.problem_at(sp), sp.unknowns, C.CycleFold(),
                                        C.NewtonSettings(tol=settings.tol))
        if result.converged:
            curves.append(_trace(run, square, result.X, "fold", settings))
    return curves


def _trace(run: CycleRun, problem, X, kind: CurveKind, settings: CurveSettings) -> CycleCurve:
    """Continue the curve of ``kind`` through the cycle ``X`` of ``problem`` both ways."""
    start = time.perf_counter()
    gauge = ProfileGauge(run.gauge.model, run.hopf.x, run.gauge.quadrature_tol)
    condition = gauge.grazing_condition() if kind == "grazing" else C.CycleFold()
    halves = []
    for direction in (-1, 1):
        curve = C.CycleCurveProblem(problem, X, (PI, LOG_M), condition)
        curve.refine = gauge.refine if gauge.quadrature_tol is not None else None
        halves.append(C.continuation(curve, settings=_steps(settings, direction),
                                     record=gauge.record, stop=_stop(kind, gauge, settings)))
    down, up = ([CurvePoint.from_columns(b.columns, k) for k in range(len(b.s))]
                for b in halves)
    message = "; ".join(f"{side}: {b.status} ({b.message})"
                        for side, b in zip(("lower M*", "higher M*"), halves))
    return CycleCurve(kind, up[0], down[::-1] + up[1:], (halves[0].status, halves[1].status),
                      message, time.perf_counter() - start)


def _steps(settings: CurveSettings, direction: int) -> C.ContinuationSettings:
    window = (math.log10(settings.mstar_min), math.log10(settings.mstar_max))
    return C.ContinuationSettings(
        ds=settings.ds, ds_min=1e-9, ds_max=settings.ds_max, direction=direction,
        max_steps=settings.max_points - 1, bounds={LOG_M: window, PI: (0.0, math.inf)},
        newton=C.NewtonSettings(tol=settings.tol), compute_eigenvalues=False)


def _stop(kind: CurveKind, gauge: ProfileGauge, settings: CurveSettings):
    """A fold curve's stop rule: its cycles shrank onto the Hopf curve."""
    if kind != "fold":
        return None

    def shrunk(problem, X):
        low, high = gauge.tip_extremes(problem, X)
        if (high - low) / 2 < settings.min_amplitude:
            return f"the cycles shrank below tip amplitude {settings.min_amplitude:g}"
        return False

    return shrunk
