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
the Hopf curve at a generalized Hopf point, l1 = 0, or where the Hopf curve turns back in
M*) or reach the wall (it crosses the grazing curve: beyond, the contact-free model does
not hold).
"""
from __future__ import annotations

import math
import time
from contextlib import nullcontext
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

import continuation as C

from ..linear.adapter import LOG_M, PI, pi_interval, pi_of
from ..linear.hopf import CriticalVelocityError
from ..model.assembly import Model
from ..scene import Scene
from ..workers import local_pool
from .collocation import CycleRun, CycleSettings, ProfileGauge, continue_cycles
from .records import check_settings, plain_value

__all__ = ["CurveKind", "CurveEnd", "CurveSettings", "CurvePoint", "CycleCurve", "CurveMap",
           "grazing_curve",
           "fold_curves", "trace_curve", "cycle_curves", "curve_seeds", "crossings", "lowest_ustar",
           "expected_outcomes"]

CurveKind = Literal["grazing", "fold", "ns"]
"""A curve of grazing cycles (min gap = eps), of cycle folds (LPC) or of torus
bifurcations (Neimark-Sacker)."""

CurveEnd = Literal["mstar_window", "ustar_bound", "bound", "budget", "wall", "hopf", "failed",
                   "stopped"]
"""Why a curve's end stopped (:meth:`CycleCurve.ends`): it left the M* window, passed the
U* bound (``ustar_max``), another bound, used up its points (``max_points``), its cycles
reached the wall or shrank onto the Hopf curve (a fold curve's stop rule), a corrector
failure, another stop."""


@dataclass(frozen=True)
class CurveSettings:
    """``mstar_min``/``mstar_max``: the M* window; ``ds``/``ds_max``: arclength steps
    (Euclidean norm of all node values, log10 M* and Π); ``max_points``: points per
    direction; ``tol``: Newton tolerance; ``min_amplitude``: a fold curve ends where its
    cycles' tip half-amplitude falls below this (they shrink onto the Hopf curve);
    ``quadrature_tol``: the flow quadrature's relative error allowed on the curve's cycles
    (nodes doubled from a point that exceeds it, as on a branch: ``CycleSettings``); the
    default 1e-6 moves the grazing U* at M* = 1 by 1e-7 relative against 1e-8 at a
    quarter of the nodes (320 against 1280), None = the seed's nodes throughout."""

    mstar_min: float = 0.05
    mstar_max: float = 20.0
    ds: float = 0.1
    ds_max: float = 0.5
    max_points: int = 150
    tol: float = 1e-9
    min_amplitude: float = 2e-3
    quadrature_tol: float | None = 1e-6

    def __post_init__(self):
        check_settings(self, integers=("max_points",),
                       positives=("mstar_min", "mstar_max", "ds", "ds_max", "tol",
                                  "min_amplitude") + (
                           () if self.quadrature_tol is None else ("quadrature_tol",)))
        if not self.mstar_min < self.mstar_max:
            raise ValueError(f"CurveSettings.mstar_min must be below mstar_max, got "
                             f"{self.mstar_min!r} and {self.mstar_max!r}")


@dataclass(frozen=True)
class CurvePoint:
    """One cycle of a curve (units: U*, M* nondimensional; period in T); ``state``: the
    model state on the cycle at its phase 0 (a start for time integration)."""

    mstar: float
    ustar: float
    period: float
    tip_amplitude: float
    gap_ratio: float
    stable: bool
    state: np.ndarray = field(repr=False, compare=False, default=None)

    @classmethod
    def from_columns(cls, columns: dict, k: int) -> "CurvePoint":
        names = {"period": "cycle_period"}
        return cls(**{f: plain_value(columns[names.get(f, f)][k])
                      for f in cls.__dataclass_fields__})

    def to_json(self) -> dict:
        return {**{f: getattr(self, f) for f in self.__dataclass_fields__ if f != "state"},
                "state": [float(v) for v in self.state]}

    @classmethod
    def from_json(cls, d: dict) -> "CurvePoint":
        return cls(**{**d, "state": np.asarray(d["state"], dtype=float)})


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

    def ends(self) -> list[tuple[CurvePoint, CurveEnd]]:
        """The curve's first and last point, each with why it stopped there
        (:data:`CurveEnd`, read off ``status`` and the side's part of ``message``)."""
        sides = self.message.split("; higher M*: ")
        sides += [""] * (2 - len(sides))
        return [(point, _end(status, text)) for point, status, text
                in zip((self.points[0], self.points[-1]), self.status, sides)]

    def to_json(self) -> dict:
        return {"kind": self.kind, "seed": self.seed.to_json(),
                "points": [p.to_json() for p in self.points], "status": list(self.status),
                "message": self.message, "wall_time": self.wall_time}

    @classmethod
    def from_json(cls, d: dict) -> "CycleCurve":
        return cls(d["kind"], CurvePoint.from_json(d["seed"]),
                   [CurvePoint.from_json(p) for p in d["points"]],
                   tuple(d["status"]), d["message"], d["wall_time"])


def _end(status: str, text: str) -> CurveEnd:
    """:data:`CurveEnd` of one side of a curve from its branch status and message."""
    if status == "bound":
        return ("mstar_window" if LOG_M in text else "ustar_bound" if PI in text else "bound")
    if status == "stopped":
        return "wall" if "reached the wall" in text else "hopf" if "shrank" in text else "stopped"
    return {"max_steps": "budget", "failed": "failed"}.get(status, "stopped")


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
        flat = lambda curves: [{**p.to_json(), "curve": i}
                               for i, c in enumerate(curves) for p in c.points]
        return {"grazing": flat(self.grazing), "fold": flat(self.fold),
                "curves": {"grazing": [c.to_json() for c in self.grazing],
                           "fold": [c.to_json() for c in self.fold]},
                "seeds": list(self.seeds), "failures": list(self.failures),
                "wall_time": self.wall_time}


def crossings(curve: CycleCurve, mstar) -> np.ndarray:
    """U* of ``curve`` at each ``mstar`` it crosses (linear in log M* between its
    points): ``(M*, U*)`` rows, one per crossing."""
    x = np.log(np.atleast_1d(np.asarray(mstar, dtype=float)))
    m, u = np.log(curve.column("mstar")), curve.column("ustar")
    rows = []
    for k in np.flatnonzero(m[1:] != m[:-1]):
        w = (x - m[k]) / (m[k + 1] - m[k])
        hit = (w >= 0) & (w <= 1)
        rows.append(np.c_[np.flatnonzero(hit), u[k] + w[hit] * (u[k + 1] - u[k])])
    return np.concatenate(rows) if rows else np.zeros((0, 2))


def lowest_ustar(curves: list, mstar, floor=None) -> np.ndarray:
    """At each ``mstar``, the lowest speed |U*| where one of ``curves`` crosses it (linear
    in log M* between curve points; returned signed, < 0 for curves of reversed flow),
    only counting crossings at or above the speed of ``floor`` (an array like ``mstar``);
    NaN where none."""
    sign = -1.0 if any(np.any(c.column("ustar") < 0) for c in curves) else 1.0
    size = np.atleast_1d(np.asarray(mstar)).size
    floor = np.full(size, -np.inf) if floor is None else sign * np.asarray(floor, dtype=float)
    out = np.full(size, np.inf)
    for curve in curves:
        index, value = crossings(curve, mstar).T
        index, value = index.astype(int), sign * value
        keep = value >= floor[index]
        np.minimum.at(out, index[keep], value[keep])
    return sign * np.where(np.isfinite(out), out, np.nan)


def expected_outcomes(curves: CurveMap, hopf, ustar, mstar) -> list:
    """What the curves say a time integration at each (``ustar``, ``mstar``) from the
    perturbed steady state should end in: "decay" below the flutter boundary ``hopf``
    (``hopf(mstar) -> U*_c``), "bistable" between a fold-of-cycles curve and it (the
    steady state and a large cycle both stable: either outcome), "lco" from it to the
    lowest grazing curve above it, "contact" from there on, "unknown" above the boundary
    where no grazing curve crosses the M*. Below, above, lowest: in speed |U*| (the
    ``ustar`` of reversed flow are all <= 0)."""
    u, m = np.asarray(ustar, dtype=float), np.asarray(mstar, dtype=float)
    sign = -1.0 if np.any(u < 0) else 1.0
    critical = hopf(m)
    fold = sign * lowest_ustar(curves.fold, m)
    grazing = sign * lowest_ustar(curves.grazing, m, floor=critical)
    return ["decay" if uk < ck and not fk <= uk else "bistable" if uk < ck else
            "unknown" if np.isnan(gk) else "lco" if uk < gk else "contact"
            for uk, ck, fk, gk in zip(sign * u, sign * np.asarray(critical, dtype=float),
                                      fold, grazing)]


def curve_seeds(switches, mstar_min: float, mstar_max: float) -> list:
    """One seed M* per piece of the flutter boundary (the pieces between its mode
    ``switches`` inside the window, each the cycles of another Hopf curve): the
    geometric middle of each piece."""
    inside = sorted(m for m in switches if mstar_min < m < mstar_max)
    edges = [mstar_min, *inside, mstar_max]
    return [math.sqrt(a * b) for a, b in zip(edges[:-1], edges[1:])]


def cycle_curves(scene: Scene, seeds, *, settings: CurveSettings = CurveSettings(),
                 cycles: CycleSettings = CycleSettings(), ustar_max: float = 20.0,
                 workers: int = 1, progress=None) -> CurveMap:
    """The grazing and fold curves through the cycle branches at the M* ``seeds``, the
    seeds in ``workers`` processes; a curve whose seed lies on a curve of an earlier seed
    is the same curve and kept once. ``progress(text)`` is told of each finished seed (its
    count, and an estimate of the time left)."""
    start = time.perf_counter()
    jobs = [(scene.replace(mstar=float(m)), settings, cycles, ustar_max) for m in seeds]
    found = {"grazing": [], "fold": []}
    failures = []
    with (local_pool(workers) if workers > 1 else nullcontext()) as pool:
        results = pool.map(_seed_curves, jobs) if pool else map(_seed_curves, jobs)
        for done, (mstar, (curves, failed)) in enumerate(zip(seeds, results), 1):
            if progress:
                left = (time.perf_counter() - start) * (len(jobs) - done) / done
                progress(f"seed {done}/{len(jobs)}, the cycle branch at M* = {mstar:.4g}: "
                         f"{len(curves['grazing'])} grazing, {len(curves['fold'])} fold "
                         f"curves" + (f"; about {left:.0f} s left" if done < len(jobs) else ""))
            failures += failed
            for kind, new in curves.items():
                found[kind] += [c for c in new if not _traced(found[kind], c.seed)]
    return CurveMap(found["grazing"], found["fold"], [float(m) for m in seeds], failures,
                    time.perf_counter() - start)


def _seed_curves(job) -> tuple[dict, list]:
    """The curves through the contact and the folds of the branch at one seed (the scene's
    M*) and the failures, as text."""
    scene, settings, cycles, ustar_max = job
    try:
        run = continue_cycles(scene, ustar_max=ustar_max, settings=cycles)
    except CriticalVelocityError as err:
        return {"grazing": [], "fold": []}, [f"M* = {scene.mstar:.4g}: {err}"]
    pi_max = _pi_max(scene, run, ustar_max)
    grazing = [trace_curve(run.gauge, run.problem_at(sp), sp.unknowns, "grazing", settings,
                           pi_max)
               for sp in run.branch.special("contact") if sp.status == "converged"]
    folds, failures = _fold_curves(run, settings, pi_max)
    return {"grazing": grazing, "fold": folds}, failures


def _fold_curves(run: CycleRun, settings: CurveSettings, pi_max: float) -> tuple[list, list]:
    """The fold curves through the run's cycle folds (each refined by Newton on its
    minimally extended system first; a fold on a curve already traced starts none) and
    the failures, as text."""
    curves, failures = [], []
    for sp in run.branch.special("fold"):
        if _traced(curves, _point(sp)):
            continue
        square, result = run.refined_fold(sp, settings.tol)
        if result.converged:
            curves.append(trace_curve(run.gauge, square, result.X, "fold", settings, pi_max))
        else:
            failures.append(f"M* = {run.hopf.mstar:.4g}: fold not refined ({result.message})")
    return curves, failures


def _point(sp) -> CurvePoint:
    """A special point of a branch as a curve point (its M* and U*)."""
    return CurvePoint.from_columns({k: [v] for k, v in sp.record.items()}, 0)


def _traced(curves: list, point: CurvePoint, rtol: float = 5e-3) -> bool:
    """Whether ``point`` (M*, U*) lies on one of ``curves`` (:func:`crossings`)."""
    return any(np.any(np.abs(crossings(c, point.mstar)[:, 1] - point.ustar)
                      <= rtol * abs(point.ustar)) for c in curves)


def grazing_curve(scene: Scene, model: Model | None = None, *,
                  settings: CurveSettings = CurveSettings(),
                  cycles: CycleSettings = CycleSettings(), run: CycleRun | None = None,
                  ustar_max: float = 20.0) -> CycleCurve:
    """The grazing curve through the first contact of the cycle branch at ``scene.mstar``
    (``run``: that branch's :class:`CycleRun` if already computed), for U* below
    ``ustar_max``. Raises ValueError when the branch reaches no contact there."""
    run = run or continue_cycles(scene, model, ustar_max=ustar_max, settings=cycles)
    contacts = [sp for sp in run.branch.special("contact") if sp.status == "converged"]
    if not contacts:
        raise ValueError(f"the cycle branch at M* = {scene.mstar:g} reaches no located wall "
                         f"contact below U* = {ustar_max:g} ({run.branch.message})")
    sp = contacts[0]
    return trace_curve(run.gauge, run.problem_at(sp), sp.unknowns, "grazing", settings,
                       _pi_max(scene, run, ustar_max))


def fold_curves(scene: Scene, model: Model | None = None, *,
                settings: CurveSettings = CurveSettings(),
                cycles: CycleSettings = CycleSettings(), run: CycleRun | None = None,
                ustar_max: float = 20.0) -> list:
    """The fold-of-cycles curves through the cycle folds of the branch at ``scene.mstar``
    (none when flutter there is supercritical and the branch does not fold), each fold
    refined by Newton on its minimally extended system first (a fold that is not refined
    starts no curve)."""
    run = run or continue_cycles(scene, model, ustar_max=ustar_max, settings=cycles)
    return _fold_curves(run, settings, _pi_max(scene, run, ustar_max))[0]


def _pi_max(scene: Scene, run: CycleRun, ustar_max: float) -> float:
    """Π of the speed |U*| = ``ustar_max`` in ``scene``'s direction at the run's M*
    (Π ≈ ±3.3 U*² / 100 at any M*, < 0 for reversed flow: the bound of the curves in
    U*), on the run's last model (its quadrature possibly refined)."""
    model = run.gauge.model
    return pi_of(scene.replace(mstar=run.hopf.mstar, quad_nodes=model.scene.n_quad), model,
                 scene.flow_sign * ustar_max)


def trace_curve(base: ProfileGauge, problem, X, kind: CurveKind, settings: CurveSettings,
                pi_max: float) -> CycleCurve:
    """Continue the curve of ``kind`` through the cycle ``X`` of ``problem`` both ways,
    inside the M* window and between Π = 0 and ``pi_max`` (< 0 for reversed flow),
    measured by a gauge like ``base`` (its model, steady state and eps)."""
    start = time.perf_counter()
    gauge = ProfileGauge(base.model, base.x_eq, base.eps, settings.quadrature_tol)
    condition = {"grazing": gauge.grazing_condition, "fold": C.CycleFold,
                 "ns": C.NeimarkSacker}[kind]()
    halves = []
    for direction in (-1, 1):
        curve = C.CycleCurveProblem(problem, X, (PI, LOG_M), condition)
        curve.refine = gauge.refine if gauge.quadrature_tol is not None else None
        halves.append(C.continuation(curve, settings=_steps(settings, direction, pi_max),
                                     record=gauge.record, stop=_stop(kind, gauge, settings)))
    down, up = ([CurvePoint.from_columns(b.columns, k) for k in range(len(b.s))]
                for b in halves)
    message = "; ".join(f"{side}: {b.status} ({b.message})"
                        for side, b in zip(("lower M*", "higher M*"), halves))
    return CycleCurve(kind, up[0], down[::-1] + up[1:], (halves[0].status, halves[1].status),
                      message, time.perf_counter() - start)


def _steps(settings: CurveSettings, direction: int, pi_max: float) -> C.ContinuationSettings:
    window = (math.log10(settings.mstar_min), math.log10(settings.mstar_max))
    return C.ContinuationSettings(
        ds=settings.ds, ds_min=1e-9, ds_max=settings.ds_max, direction=direction,
        max_steps=settings.max_points - 1, bounds={LOG_M: window, PI: pi_interval(0.0, pi_max)},
        newton=C.NewtonSettings(tol=settings.tol), compute_eigenvalues=False)


def _stop(kind: CurveKind, gauge: ProfileGauge, settings: CurveSettings):
    """A fold curve's stop rule: its cycles shrank onto the Hopf curve, or reached the wall
    (past the grazing curve the contact-free model no longer describes the beam)."""
    if kind != "fold":
        return None

    def ended(problem, X):
        low, high = gauge.tip_extremes(problem, X)
        if (high - low) / 2 < settings.min_amplitude:
            return f"the cycles shrank below tip amplitude {settings.min_amplitude:g}"
        if gauge.gap(problem, X) < gauge.eps:
            return "the cycles reached the wall (min gap below eps)"
        return False

    return ended
