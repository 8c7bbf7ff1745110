"""Impacting limit cycles versus U*: multiple shooting through the first wall contact.

Collocation (:mod:`fsicas.cycles`) follows the flutter cycles up to the first contact;
past it the stiff penalty law (k* = 1e8, eps/H = 1e-2, smoothed by ``contact_smoothing``)
acts for a small fraction of the period and a fixed collocation mesh does not resolve it
(docs/cycles.md, limitations). Here the cycles are continued by multiple shooting
(``continuation.ShootingProblem``: ``m`` segments of the flow of ``M^{-1} F`` integrated
by CVODES, whose adaptive steps resolve each impact, and its forward sensitivities for
the exact Jacobian), on the same reparametrised field as the Hopf and collocation
analyses (``fsicas.linear.adapter.flutter_field``: parameter Π = Δp/(100 M*), time in units of
T/100), with the contact law on.

The Jacobian is the library's block route (``ShootingSettings(jacobian="blocks")``):
all segments integrated in one mapped call with CVODES forward sensitivities in the
n + 2 directions (x_i, T, Π) only, over ``ImpactSettings.threads`` threads, and kept
for the last point, so the Floquet multipliers reuse the tangent's Jacobian. By default
(``sensitivities="fast"``) the sensitivity equations are formed from the model's own
Jacobians (``continuation._cycles.shooting.rate_function``); ``"exact"`` lets CasADi
differentiate ``M^{-1} F`` in all n + 2 directions and in its Newton matrix, 15x slower
at N = 10. Both routes integrate the same residual; their Jacobians and multipliers
differ by integration error only: against a reference at tolerance 1e-13, at N = 10
and tol = 1e-10 both are off by 3.9e-9 (Jacobian) and 1.3e-8 (multipliers) and differ
from each other by 7e-10 and 6e-11; tightening ``tol`` to 1e-12 makes "fast" 17-30x
more accurate and still 8x faster than "exact" at 1e-10
(``benchmarks/bench_shooting_accuracy.py``, ``docs/performance.md``).

Start points: a contact-free collocation cycle shortly before contact
(:func:`pre_contact_start` of a :func:`fsicas.cycles.cycle_branch`) or the settled cycle
of a time integration (:func:`cycle_from_trajectory`, which finds sub-harmonic cycles of
several tip swings). Per point: U* (inlet velocity of the steady state at the same Δp,
as in :mod:`fsicas.cycles`), period, tip half-amplitude, minimal gap over the cycle and
its ratio to eps, contact intervals per period (separate intervals with a gap below eps
somewhere, both walls), Floquet multipliers and stability, wall time; the extrema are
taken on ``samples`` outputs per segment (not refined).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Literal

import casadi as ca
import numpy as np

import continuation as C

from ..checks import finite_number, require
from ..linear.adapter import PI, TIME_SCALE, field_parameters, flutter_field, speed_window
from ..model.accuracy import IMPACT_QUADRATURE_TOL
from ..model.assembly import Model, build_model
from ..scene import Scene
from ..linear.steady import steady_state
from .gauge import Gauge, model_parameters, quadrature_controlled
from .records import START_FAILED, BranchRecord, CycleMeasures, branch_end, check_settings

__all__ = ["ImpactSettings", "ImpactPoint", "ImpactBranch", "shooting_branch",
           "cycle_from_trajectory", "pre_contact_start", "shooting_points", "shooting_settings",
           "ImpactStatus", "check_speeds"]

ImpactStatus = Literal["bound", "max_points", "failed"]
"""Why a shooting branch ended: the speed |U*| left [ustar_min, ustar_max], the point
budget, or a failure of the start integration or of the corrector (``message`` says why)."""


@dataclass(frozen=True)
class ImpactSettings:
    """``segments``: shooting segments; ``tol``: CVODES abstol = reltol (the residual and
    its sensitivities); ``newton_tol``: corrector tolerance (inf-norm of the matching
    conditions); ``ds``/``ds_max``: arclength steps (Euclidean norm of the shooting
    points, 100 T and Π); ``max_points``: branch points; ``samples``: output points per
    segment for the measurements (min gap, amplitude, impacts); ``sensitivities``:
    ``"fast"`` or ``"exact"`` (``continuation.ShootingSettings``, module docstring);
    ``threads``: segments integrated in parallel (the same numbers on any count);
    ``quadrature_tol``: the bound of the flow quadrature's error over the cycles (a branch
    above it is computed once more on the adequate model of its worst cycle; None: no
    control)."""

    segments: int = 12
    tol: float = 1e-10
    newton_tol: float = 1e-8
    ds: float = 0.02
    ds_max: float = 0.2
    max_points: int = 20
    samples: int = 2000
    sensitivities: str = "fast"
    threads: int = 2
    quadrature_tol: float | None = IMPACT_QUADRATURE_TOL

    def __post_init__(self):
        check_settings(self, integers=("segments", "max_points", "samples", "threads"),
                       positives=("tol", "newton_tol", "ds", "ds_max") + (
                           () if self.quadrature_tol is None else ("quadrature_tol",)))
        if self.sensitivities not in ("exact", "fast"):
            raise ValueError("ImpactSettings.sensitivities must be 'exact' or 'fast', got "
                             f"{self.sensitivities!r}")


@dataclass(frozen=True)
class ImpactPoint(CycleMeasures):
    """One cycle of the impacting branch (``state``: the model state at phase 0)."""

    impacts: int
    multipliers: np.ndarray = field(repr=False)
    stable: bool = True
    state: np.ndarray = field(repr=False, default=None)
    wall_time: float = 0.0
    #: relative error of the equations from the flow quadrature over the cycle
    #: (:mod:`fsicas.model.accuracy`; NaN where not measured)
    quadrature_error: float = float("nan")
    #: quadrature nodes (``scene.n_quad``) of the model the point was computed on
    quadrature_nodes: int | None = None
    #: the largest total impact load over the cycle / the reference force of Fig. 9, and
    #: 1 - the cycle's mean flow over the steady flow at the same pressure drop
    #: (:meth:`fsicas.cycles.gauge.Gauge.impact_measures`; NaN where not measured)
    peak_force: float = float("nan")
    flow_reduction: float = float("nan")


@dataclass(frozen=True)
class ImpactBranch(BranchRecord):
    """A branch of impacting cycles in U* from a start cycle, by either route
    (:func:`fsicas.cycles.impacting_cycles`). ``status``: "bound" (|U*| left
    [ustar_min, ustar_max]), "max_points" or "failed" (``message`` says why);
    ``special``: its located special cycles in the order met (the collocation route's,
    :class:`~fsicas.cycles.impacting_collocation.CollocatedImpactBranch`; shooting
    locates none)."""

    scene: Scene
    eps: float
    points: list
    status: ImpactStatus
    message: str
    wall_time: float
    special: list = field(default_factory=list)

    @property
    def max_error_estimate(self) -> float:
        """The largest discretization error indicator of its points: 0 here (shooting's
        CVODES steps are error-controlled); the collocation route's mesh indicator."""
        return 0.0

    def to_json(self) -> dict:
        return {"scene": self.scene.to_dict(), "eps": self.eps,
                "points": [p.to_json() for p in self.points], "status": self.status,
                "message": self.message, "wall_time": self.wall_time,
                "special": [p.to_json() for p in self.special]}

    @classmethod
    def from_json(cls, d: dict) -> "ImpactBranch":
        return cls(Scene.from_dict(d["scene"]), d["eps"],
                   [ImpactPoint.from_json(p) for p in d["points"]], d["status"], d["message"],
                   d["wall_time"], [ImpactPoint.from_json(p) for p in d.get("special", [])])


def shooting_branch(scene: Scene, state, period: float, pressure_drop: float, *,
                    model: Model | None = None, ustar_min: float = 0.0, ustar_max: float = 12.0,
                    direction: int = 1, settings: ImpactSettings = ImpactSettings()
                    ) -> ImpactBranch:
    """Continue the cycle through ``state`` (phase 0) with ``period`` (units of T) at
    ``pressure_drop`` by multiple shooting in U*, on ``scene`` (contact on: the
    penalty law acts), over the speeds |U*| in [``ustar_min``, ``ustar_max``] of the
    scene's flow direction (reversed flow: U* < 0, Δp < 0). ``direction`` = +1 continues
    towards larger speed |U*| (|Δp|). The shooting route of
    :func:`fsicas.cycles.impacting_cycles`, which says where starts come from."""
    check_speeds(ustar_min, ustar_max)
    start = time.perf_counter()
    if not scene.contact:
        raise ValueError("impacting cycles by shooting need scene.contact = True (the impact "
                         "law)")
    model = model or build_model(scene)
    state = np.asarray(state, float)

    def compute(on):
        analysed = scene if on is model else scene.replace(quad_nodes=on.scene.n_quad)
        return _shot(analysed, on, state, period, pressure_drop, (ustar_min, ustar_max),
                     direction, settings)
    try:
        branch = quadrature_controlled(compute, model, settings.quadrature_tol)
    except RuntimeError as err:                  # CVODES failure, e.g. a gap closing
        return ImpactBranch(scene, scene.contact_gap, [], "failed", START_FAILED.format(err),
                            time.perf_counter() - start)
    return replace(branch, wall_time=time.perf_counter() - start)


def _shot(scene, model, state, period, pressure_drop, ustar_range, direction, settings):
    """:func:`shooting_branch` on ``model``, and its gauge (RuntimeError if the start
    cycle cannot be integrated)."""
    start = time.perf_counter()
    vf, st = flutter_field(model), steady_state(scene, model)
    params = field_parameters(vf, model, st, scene, pressure_drop)
    shoot = shooting_settings(settings)
    orbit = shooting_points(vf, state, period * TIME_SCALE, params, settings.segments, shoot)
    problem = C.ShootingProblem(vf, orbit, period * TIME_SCALE, params, PI, settings=shoot)
    gauge = _ImpactGauge(model, st.x, scene.contact_gap, settings.samples)
    branch = C.continuation(problem, record=gauge.record, settings=_steps(
        scene, model, *ustar_range, direction, settings))
    return _result(scene, model, branch, settings, time.perf_counter() - start), gauge


def shooting_settings(settings: ImpactSettings) -> C.ShootingSettings:
    """The library's shooting settings of an impacting branch."""
    return C.ShootingSettings(segments=settings.segments, abstol=settings.tol,
                              reltol=settings.tol, floquet="schur", jacobian="blocks",
                              sensitivities=settings.sensitivities, threads=settings.threads)


def check_speeds(ustar_min: float, ustar_max: float) -> None:
    """ValueError unless ``0 <= ustar_min < ustar_max``: the bounds of an impacting
    branch are speeds |U*| (the scene's direction gives the sign of U*)."""
    require(0 <= finite_number("ustar_min", ustar_min) < finite_number("ustar_max", ustar_max),
            "ustar_min and ustar_max are the speeds |U*| the impacting branch stays within "
            "(the scene's direction gives the sign of U*): 0 <= ustar_min < ustar_max, got "
            f"{ustar_min!r} and {ustar_max!r}")


def _steps(scene, model, ustar_min, ustar_max, direction, settings) -> C.ContinuationSettings:
    """Arclength steps in Π between the steady Π at the speeds ``ustar_min`` and
    ``ustar_max``, ``direction`` towards larger (+1) or smaller speed (:func:`speed_window`)."""
    bounds, pi_direction = speed_window(scene, model, ustar_min, ustar_max, direction)
    return C.ContinuationSettings(
        ds=settings.ds, ds_min=1e-6, ds_max=settings.ds_max, direction=pi_direction,
        max_steps=max(settings.max_points - 1, 1), bounds={PI: bounds},
        newton=C.NewtonSettings(tol=settings.newton_tol, max_iter=8), detect=False)


def _result(scene, model, branch, settings, wall_time) -> ImpactBranch:
    """The branch's points as :class:`ImpactPoint` records, with the status."""
    points = [ImpactPoint.from_columns(branch.columns, k) for k in range(len(branch.s))]
    points = points[:settings.max_points]
    return ImpactBranch(scene, scene.contact_gap, points,
                        branch_end(branch.status, points, settings.max_points), branch.message,
                        wall_time)


def pre_contact_start(branch, min_gap_ratio: float = 3.0):
    """The last point of a collocation ``CycleBranch`` (contact-free model) whose min gap
    is at least ``min_gap_ratio`` eps: there the smoothed law's force (width w = σ eps)
    is below exp(-(min_gap_ratio - 1)/σ) of its value at contact, so the cycle is also
    a cycle of the model with contact to that accuracy, and a start for
    :func:`fsicas.cycles.impacting_cycles` (closer to contact works too, e.g. at M* = 1,
    N = 4, k* = 1e8, σ = 0.1 from gap = 1.05 eps, but the start then differs from the
    collocation cycle by 1e-4 in period: the softplus already pushes)."""
    points = [p for p in branch.points if p.gap_ratio >= min_gap_ratio]
    if not points:
        raise ValueError(f"no cycle of the branch has min gap >= {min_gap_ratio} eps")
    return points[-1]


def cycle_from_trajectory(model: Model, t, x, max_subcycles: int = 6, tol: float = 1e-3
                          ) -> tuple[np.ndarray, float, int]:
    """(state, period, sub-cycles) of the settled cycle at the end of a trajectory.

    Upward crossings of the tip through its mean over the last quarter; the period is
    the time over the fewest crossings k (<= ``max_subcycles``) after which the state
    returns within ``tol`` (relative, max-norm), else the k of the closest return."""
    t, x = np.asarray(t, float), np.asarray(x, float)
    y = model.tip_deflection(x)
    y = y - np.mean(y[3 * len(y) // 4:])
    i = np.where((y[:-1] < 0) & (y[1:] >= 0))[0]
    s = -y[i] / (y[i + 1] - y[i])
    tc = t[i] + s * (t[i + 1] - t[i])
    xc = x[i] + s[:, None] * (x[i + 1] - x[i])
    if len(tc) < max_subcycles + 2:
        raise ValueError(f"only {len(tc)} tip crossings: integrate longer")
    miss = [np.max(np.abs(xc[-1] - xc[-1 - k])) / np.max(np.abs(xc[-1])) for k in
            range(1, max_subcycles + 1)]
    ok = [k for k, e in enumerate(miss, 1) if e < tol]
    k = ok[0] if ok else int(np.argmin(miss)) + 1
    return xc[-1], float(tc[-1] - tc[-1 - k]), k


def shooting_points(vf, x0, period, params, m, shoot) -> np.ndarray:
    """The m shooting points along the flow from x0 (one period, m equal segments)."""
    x, q = ca.MX.sym("x", vf.n), ca.MX.sym("q", len(vf.par_names))
    f = ca.solve(vf.M(x, q), vf.F(x, q))
    integ = ca.integrator("guess", "cvodes", {"x": x, "p": q, "ode": period * f}, 0.0,
                          np.arange(1, m) / m, {"abstol": shoot.abstol, "reltol": shoot.reltol,
                                                "disable_internal_warnings": True})
    p = np.array([params[k] for k in vf.par_names])
    xs = np.asarray(integ(x0=x0, p=p)["xf"]).T
    return np.vstack([x0, xs])                   # the orbit at t = 0, 1/m, ..., (m - 1)/m


#: Samples nearest the wall (and as many spread) on which a shooting cycle's quadrature
#: error is measured (:meth:`_ImpactGauge.states`).
QUADRATURE_STATES = 200


class _ImpactGauge(Gauge):
    """Measures of shooting unknowns X = (x_0..x_{m-1}, 100 T, Π) on ``samples`` outputs
    per segment (not refined), as branch columns (the fields of :class:`ImpactPoint`)."""

    def __init__(self, model: Model, x_eq, eps: float, samples: int):
        super().__init__(model, x_eq, eps)
        self.samples, self.t_last = samples, time.perf_counter()

    def sampled(self, problem, X) -> np.ndarray:
        """The cycle's ``samples`` outputs per segment (kept for the last X)."""
        return self.kept("samples", problem, X, lambda: problem.sample(X, self.samples)[1])

    def states(self, problem, X) -> np.ndarray:
        """The samples the quadrature error is measured on: the
        :data:`QUADRATURE_STATES` nearest the wall (the flow integrals are sharpest
        where the gap is narrowest) and as many spread over the cycle."""
        x = self.sampled(problem, X)
        nearest = np.argsort(self.min_gap(x))[:QUADRATURE_STATES]
        spread = np.linspace(0, len(x) - 1, min(len(x), QUADRATURE_STATES)).astype(int)
        return x[np.union1d(nearest, spread)]

    def record(self, problem, X) -> dict:
        """The columns of one branch point (multipliers from the kept Jacobian)."""
        x = self.sampled(problem, X)
        y, gap = self.tip(x), self.min_gap(x)
        inside = gap < self.eps
        impacts = int(np.sum(inside & ~np.roll(inside, 1))) if not inside.all() else 1
        common = self.common(problem, X)
        now = time.perf_counter()
        wall, self.t_last = now - self.t_last, now
        return {**common, "tip_amplitude": float(y.max() - y.min()) / 2,
                "min_gap": float(gap.min()), "gap_ratio": float(gap.min() / self.eps),
                "impacts": impacts, "wall_time": wall,
                **self.impact_measures(x, np.ones(len(x)),   # samples equally spaced in t
                                       model_parameters(self.model, problem, X))}
