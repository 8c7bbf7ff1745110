"""Impacting limit cycles versus U* by adaptive collocation: a second route beside shooting.

The cycle is continued in Π by orthogonal collocation (``continuation.CycleProblem``,
block-assembled sparse Jacobian) of the model *with* the smoothed contact law
(``Scene.contact_smoothing`` > 0: the softplus of width σ eps is C-infinity, so the
collocation polynomial converges at its order once the mesh resolves the contact layer).
The mesh is re-equidistributed at every accepted point (``adapt_every``): its intervals
concentrate at the impacts; NTST is fixed during a run (a few hundred intervals).

Start: a cycle's state at phase 0, its period and pressure drop, as for the shooting
route (:func:`fsicas.cycles.impacting_cycles` says where starts come from); one period is integrated from it
(CVODES) and the start mesh equidistributed on that guess (``mesh_passes`` passes).

Per point the measures of the shooting route (:class:`ImpactPoint`) plus NTST and the
library's a-posteriori error indicator; extrema of the collocation polynomial, exact in
t, contact intervals counted on ``samples`` points per mesh interval. Quadrature: a
branch whose points' estimate exceeds ``quadrature_tol`` (default
``IMPACT_QUADRATURE_TOL``) is computed once more on the adequate model of its worst cycle.

Special cycles (``detect``): folds, period doublings and Neimark-Sacker points, located
on the arclength and refined by Newton on their minimally extended systems
(``continuation.CycleFold``, ``PeriodDoubling``, ``NeimarkSacker``); branch points (a
multiplier through +1 where the branch does not turn: symmetric cycles giving way to
asymmetric ones), by Newton on the cycles that keep the channel's mirror
(``continuation.locate_symmetry_breaking``). :mod:`fsicas.cycles.branch_switching`
switches at them onto the period-doubled and the asymmetric cycles.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np
import scipy.interpolate

import continuation as C

from ..linear.adapter import PI, TIME_SCALE, field_parameters, flutter_field, speed_window
from ..linear.steady import steady_state
from ..model.accuracy import IMPACT_QUADRATURE_TOL
from ..model.assembly import Model, build_model
from ..scene import Scene
from .gauge import PolynomialGauge, quadrature_controlled
from .impacting import ImpactBranch, ImpactPoint, check_speeds, shooting_points
from .records import START_FAILED, branch_end, check_settings

__all__ = ["CollocationImpactSettings", "CollocatedImpactPoint", "CollocatedImpactBranch",
           "collocation_branch", "impacting_collocation_problem", "ImpactKind"]

ImpactKind = Literal["regular", "fold", "pd", "ns", "bp"]
"""A branch point ("regular") or a special cycle: "fold" (a second multiplier at +1),
"pd" (a multiplier at -1), "ns" (a complex pair on the unit circle), "bp" (a second
multiplier at +1 where the branch does not turn: cycles that break the channel's
symmetry branch off)."""

#: the multiplier each kind of special cycle puts on the unit circle (None: a complex one)
_CRITICAL = {"fold": 1.0, "pd": -1.0, "ns": None, "bp": 1.0}
#: how far (relative, in U*) the branch point of a pitchfork's vertex may lie from the turn
VERTEX_SHIFT = 1e-3
#: the minimally extended system of each kind of special cycle
_CONDITIONS = {"fold": C.CycleFold, "pd": C.PeriodDoubling, "ns": C.NeimarkSacker}


@dataclass(frozen=True)
class CollocationImpactSettings:
    """``ntst``/``ncol``: collocation mesh (NTST fixed during the run); ``adapt_every``:
    re-equidistribute every so many accepted points (0 = never); ``mesh_passes``:
    equidistribution passes of the start mesh on the integrated guess; ``tol``: Newton
    tolerance (inf-norm of the collocation residual); ``ds``/``ds_max``: arclength steps
    (Euclidean norm of all node values, 100 T and Π: scale by about √(NTST/20));
    ``max_points``: branch points; ``samples``: samples per mesh interval for the
    measurements; ``guess_samples``/``guess_tol``: outputs and CVODES tolerance of the
    integrated start period; ``detect``: detect, locate and refine folds, period
    doublings and Neimark-Sacker points (multipliers at every point); ``max_turn``:
    largest angle (rad) between successive tangents, else the step is retried shorter
    (``continuation.ContinuationSettings.max_turn``, 0 = off: past the contacts the
    branch folds sharply, and a step over such a fold came back oriented backwards);
    ``refine_ntst``: special cycles, once located, are rebuilt on a mesh of this many
    intervals and ``refine_ncol`` points (0: ``ncol``), equidistributed on one
    integrated period of the located cycle, and located again, then ``refine_passes``
    times re-meshed on their own error and located again, the one of smallest
    ``flow_defect`` kept: critical multipliers of a smaller discretization error (0: on
    the branch's mesh); ``quadrature_tol``: the bound of the quadrature estimate (module
    docstring; None: no control)."""

    ntst: int = 200
    ncol: int = 4
    adapt_every: int = 1
    mesh_passes: int = 3
    tol: float = 1e-9
    ds: float = 0.05
    ds_max: float = 1.0
    max_points: int = 20
    samples: int = 16
    guess_samples: int = 20000
    guess_tol: float = 1e-10
    detect: bool = True
    max_turn: float = 0.3
    refine_ntst: int = 0
    refine_ncol: int = 6
    refine_passes: int = 3
    quadrature_tol: float | None = IMPACT_QUADRATURE_TOL

    def __post_init__(self):
        check_settings(self, integers=("ntst", "ncol", "max_points", "samples", "guess_samples"),
                       positives=("tol", "ds", "ds_max", "guess_tol") + (
                           () if self.quadrature_tol is None else ("quadrature_tol",)),
                       nonnegative_integers=("adapt_every", "mesh_passes", "refine_ntst",
                                             "refine_ncol", "refine_passes"))
        if not (2 <= self.ncol <= 7 and self.refine_ncol in (0, *range(2, 8))):
            raise ValueError("CollocationImpactSettings.ncol must be in 2..7 and refine_ncol "
                             f"0 (ncol) or in 2..7, got {self.ncol!r} and {self.refine_ncol!r}")
        if not isinstance(self.detect, bool):
            raise ValueError("CollocationImpactSettings.detect must be a bool, got "
                             f"{self.detect!r}")
        if not (isinstance(self.max_turn, (int, float)) and 0 <= self.max_turn <= np.pi):
            raise ValueError("CollocationImpactSettings.max_turn must be an angle in [0, pi] "
                             f"(0: off), got {self.max_turn!r}")


@dataclass(frozen=True)
class CollocatedImpactPoint(ImpactPoint):
    """An impacting cycle by collocation: the shooting route's measures, plus ``ntst``,
    ``ncol`` and ``error_estimate`` (the library's indicator max_i h_i^(NCOL+1) |u^(NCOL+1)|_i)."""

    _complex = ("multipliers", "section_multipliers")

    ntst: int = 0
    ncol: int = 4
    error_estimate: float = 0.0
    kind: ImpactKind = "regular"
    #: a special cycle refined by Newton on its minimally extended system (False: where
    #: that Newton failed, the location on the arclength)
    located: bool = True
    #: of a located special cycle: the n - 1 non-trivial multipliers of the Poincare map
    #: (``continuation``'s ``section_multipliers``; a fold's multiplier at +1 is not split
    #: from the trivial one there; of a branch point, those of the mirror's symmetric
    #: split, ``continuation.symmetric_multipliers``); empty elsewhere
    section_multipliers: np.ndarray = field(repr=False,
                                            default_factory=lambda: np.zeros(0, complex))
    #: of a located special cycle: ``|Phi f - f| / |f|`` (``continuation``'s
    #: ``flow_defect``), how near +1 its discretization can put a multiplier; NaN elsewhere
    flow_defect: float = float("nan")

    @property
    def critical_multiplier(self) -> complex | None:
        """The non-trivial multiplier nearest +1 (fold, branch point: the Poincare map's,
        ``section_multipliers``, as the monodromy's pair there is split), -1 (period
        doubling) or, among the complex ones, the unit circle (Neimark-Sacker; these two
        the monodromy's, on which the located condition is written: the section adds the
        ``flow_defect``); None for a regular point."""
        if self.kind not in _CRITICAL:
            return None
        target = _CRITICAL[self.kind]
        mu = self.section_multipliers if target == 1.0 and len(self.section_multipliers) \
            else self.nontrivial_multipliers
        distance = np.abs(np.abs(mu) - 1) + (mu.imag == 0) if target is None else \
            np.abs(mu - target)
        return complex(mu[np.argmin(distance)])


@dataclass(frozen=True)
class CollocatedImpactBranch(ImpactBranch):
    """Collocation branch in U* from a start cycle; ``status`` as for the shooting route;
    ``special``: its located special cycles (:class:`CollocatedImpactPoint` of kind
    "fold", "pd", "ns" or "bp"), in the order met."""

    @property
    def max_error_estimate(self) -> float:
        """The largest collocation error indicator of its points (0 without points)."""
        return max((p.error_estimate for p in self.points), default=0.0)

    @classmethod
    def from_json(cls, d: dict) -> "CollocatedImpactBranch":
        return cls(Scene.from_dict(d["scene"]), d["eps"],
                   [CollocatedImpactPoint.from_json(p) for p in d["points"]], d["status"],
                   d["message"], d["wall_time"],
                   [CollocatedImpactPoint.from_json(p) for p in d.get("special", [])])


def impacting_collocation_problem(scene: Scene, state, period: float, pressure_drop: float,
                                  *, model: Model | None = None,
                                  settings: CollocationImpactSettings = CollocationImpactSettings()
                                  ) -> C.CycleProblem:
    """The collocation problem of the cycle through ``state`` (phase 0) with ``period``
    (units of T) at ``pressure_drop`` on ``scene`` (contact on), with the start mesh
    equidistributed on one integrated period. Raises RuntimeError if that integration
    fails (e.g. the gap closes)."""
    model = model or build_model(scene)
    vf = flutter_field(model)
    params = field_parameters(vf, model, steady_state(scene, model), scene, pressure_drop)
    orbit = _integrated_orbit(vf, np.asarray(state, float), period * TIME_SCALE, params, settings)
    cs = C.CollocationSettings(ntst=settings.ntst, ncol=settings.ncol, floquet="schur",
                               adapt_every=settings.adapt_every)
    problem = C.CycleProblem(vf, orbit, period * TIME_SCALE, params, PI, settings=cs)
    for _ in range(settings.mesh_passes):
        mesh = problem.remesh(problem.X0)[0].mesh
        problem = C.CycleProblem(vf, orbit, period * TIME_SCALE, params, PI, settings=cs,
                                 mesh=mesh)
    return problem


def collocation_branch(scene: Scene, state, period: float, pressure_drop: float, *,
                       model: Model | None = None, ustar_min: float = 0.0,
                       ustar_max: float = 12.0, direction: int = 1,
                       settings: CollocationImpactSettings = CollocationImpactSettings()
                       ) -> CollocatedImpactBranch:
    """Continue the cycle through ``state`` (phase 0) with ``period`` (units of T) at
    ``pressure_drop`` by adaptive collocation in U* on ``scene`` (contact on, smoothed:
    ``contact_smoothing`` > 0), over the speeds |U*| in [``ustar_min``, ``ustar_max``]
    of the scene's flow direction. ``direction`` = +1 continues towards larger speed
    |U*|. The collocation route of :func:`fsicas.cycles.impacting_cycles`; the arguments
    are those of :func:`fsicas.cycles.impacting.shooting_branch`."""
    check_speeds(ustar_min, ustar_max)
    start = time.perf_counter()
    check_smooth(scene)
    model = model or build_model(scene)
    try:
        problem = impacting_collocation_problem(scene, state, period, pressure_drop,
                                                model=model, settings=settings)
    except RuntimeError as err:                  # CVODES failure, e.g. a gap closing
        return failed_branch(scene, model, START_FAILED.format(err), start)
    return continued_branch(scene, model, problem, (ustar_min, ustar_max), direction, settings, start)


def check_smooth(scene: Scene) -> None:
    """ValueError unless ``scene`` has the smoothed contact law collocation needs."""
    if not (scene.contact and scene.contact_smoothing > 0):
        raise ValueError("impacting cycles by collocation need scene.contact = True and "
                         "scene.contact_smoothing > 0 (a smooth contact law)")


def failed_branch(scene, model, message, start) -> CollocatedImpactBranch:
    """The empty branch of status "failed" with ``message``, timed from ``start``."""
    return CollocatedImpactBranch(scene, scene.contact_gap, [], "failed", message,
                                  time.perf_counter() - start)


def continued_branch(scene, model, problem, ustar_range, direction, settings, start
                     ) -> CollocatedImpactBranch:
    """The branch of ``problem`` in U* within ``ustar_range``, its special cycles refined
    (once more on the adequate model of its worst cycle: module docstring)."""
    def compute(on):
        if on is model:
            return _continued(scene, model, problem, ustar_range, direction, settings, start)
        finer = problem.on_field(flutter_field(on), problem.X0)[0]
        return _continued(scene.replace(quad_nodes=on.scene.n_quad), on, finer, ustar_range,
                          direction, settings, start)
    return quadrature_controlled(compute, model, settings.quadrature_tol)


def _continued(scene, model, problem, ustar_range, direction, settings, start) -> tuple:
    """:func:`continued_branch` on ``model``, and its gauge."""
    gauge = PolynomialGauge(model, steady_state(scene, model).x, scene.contact_gap,
                            settings.samples)
    once = (lambda problem, X: "reached max_points = 1") if settings.max_points == 1 else None
    branch = C.continuation(problem, record=gauge.record, stop=once, settings=_steps(
        scene, model, *ustar_range, direction, settings))
    finer = lambda point: impacting_collocation_problem(         # noqa: E731
        scene, point.state, point.period, point.pressure_drop, model=model,
        settings=replace(settings, ntst=settings.refine_ntst,
                         ncol=settings.refine_ncol or settings.ncol))
    special = [_refined(problem, sp, gauge, settings, finer) for sp in branch.special_points
               if sp.kind in _CRITICAL]
    return _result(scene, scene.contact_gap, branch, special, settings,
                   time.perf_counter() - start), gauge


def _refined(problem, sp, gauge, settings, finer) -> "CollocatedImpactPoint":
    """A special cycle located on the arclength, refined by Newton on its minimally
    extended system (a branch point: on the symmetric cycles of the channel's mirror; so
    is a turn whose direction breaks the mirror, the vertex of a pitchfork, unless that
    fails), then (``settings.refine_ntst``) once more on the finer mesh of ``finer(point)``; the
    arclength location (``located=False``) where the first fails (a branch point of an
    asymmetric channel: there is no such system), the branch mesh's where the second
    does."""
    point = _first_located(*problem.at(sp), sp.kind, gauge, settings)
    if point is None:
        square, X = problem.at(sp)
        section = dict(section_multipliers=square.section_multipliers(X),
                       flow_defect=square.flow_defect(X)) if sp.kind == "bp" else {}
        return CollocatedImpactPoint.from_columns(sp.record, None, kind=sp.kind,
                                                  located=False, **section)
    if settings.refine_ntst:
        try:
            fine = finer(point)
        except RuntimeError:                     # the integrated guess failed
            return point
        point = _first_located(fine, fine.X0, point.kind, gauge, settings,
                               settings.refine_passes) or point
    return point


def _first_located(problem, X, kind, gauge, settings, passes=0) -> "CollocatedImpactPoint | None":
    """:func:`_located` of ``kind``; of a fold that may be the vertex of a pitchfork
    (:func:`_pitchfork_vertex`), first as the branch point there, kept where its Newton
    stays at the turn (U* within ``VERTEX_SHIFT`` relative)."""
    if kind == "fold" and _pitchfork_vertex(problem, X, gauge.model.mirror):
        point = _located(problem, X, "bp", gauge, settings, passes)
        turn = gauge.ustar(problem, X)
        if point is not None and abs(point.ustar - turn) <= VERTEX_SHIFT * abs(turn):
            return point
    return _located(problem, X, kind, gauge, settings, passes)


def _pitchfork_vertex(problem, X, mirror) -> bool:
    """Whether the turn of the branch at ``X`` may be the vertex of a pitchfork, where
    asymmetric cycles meet the symmetric ones at their branch point: the direction of
    the turn (the null vector of G_(U,T)) breaks the mirror more than it keeps it,
    ``|v(t) + R v(t - 1/2)| < |v(t) - R v(t - 1/2)|`` (a fold of symmetric cycles keeps
    it). A cycle that does not keep the mirror itself is no vertex (the branch point's
    Newton would refuse it), and costs no factorization here."""
    if not C.keeps_symmetry(problem, X, mirror):
        return False
    square = C.CycleCurveProblem(problem, X, problem.free, C.CycleFold())
    v, t = square.condition.null_vector(square, square.X0), problem.times()
    u, image = problem.evaluate(v, t), problem.evaluate(v, t - 0.5) @ mirror.T
    return bool(np.linalg.norm(u + image) < np.linalg.norm(u - image))


def _located(problem, X, kind, gauge, settings, passes=0) -> "CollocatedImpactPoint | None":
    """The special cycle of ``kind`` by Newton from ``X`` (:func:`_locate`), then
    ``passes`` times on a mesh equidistributing the located cycle's error (the
    equidistribution does not settle: the one of smallest ``flow_defect`` is kept), with
    its non-trivial multipliers; None where the first Newton fails."""
    found = []
    for k in range(passes + 1):
        try:
            square, result, multipliers, cycle = _locate(problem, X, kind, gauge.model.mirror,
                                                         C.NewtonSettings(tol=settings.tol))
        except (ValueError, np.linalg.LinAlgError):
            break
        if not result.converged:
            break
        found.append((square.flow_defect(result.X), k, square, result.X, multipliers))
        if k < passes:                           # the next pass: re-meshed on this cycle
            problem, X = cycle.remesh(result.X)
    if not found:
        return None
    defect, _, square, X, multipliers = min(found)
    return CollocatedImpactPoint.from_columns(
        gauge.record(square, X), None, kind=kind,
        section_multipliers=multipliers(X), flow_defect=defect)


def _locate(problem, X, kind, mirror, newton) -> tuple:
    """``(square, result, multipliers, cycle)``: Newton on the minimally extended system of
    ``kind`` (a branch point: on the cycles that keep ``u(t + T/2) = R u(t)``, the
    channel's mirror ``R``, where the broken ones branch off; ValueError if the channel
    or the cycle is not symmetric) and ``multipliers(X)``, the n - 1 non-trivial ones
    (the Poincare map's; of a branch point the symmetric split's, the breaking one
    apart from the trivial one); ``cycle``: the cycle problem of the located cycle's mesh."""
    if kind == "bp":
        sym, result = C.locate_symmetry_breaking(problem, X, mirror, 0.5, newton)
        return sym, result, lambda X: C.symmetric_multipliers(sym, X, mirror)[1], sym
    square, result = C.locate_cycle(problem, X, _CONDITIONS[kind](), newton)
    return square, result, square.section_multipliers, problem


def _integrated_orbit(vf, x0, period, params, settings):
    """``t -> x`` on [0, 1): one integrated period (``guess_samples`` outputs), a periodic
    cubic spline through them (the end point replaced by the start: the guess closes)."""
    shoot = C.ShootingSettings(abstol=settings.guess_tol, reltol=settings.guess_tol)
    x = shooting_points(vf, x0, period, params, settings.guess_samples, shoot)
    t = np.linspace(0.0, 1.0, settings.guess_samples + 1)
    spline = scipy.interpolate.CubicSpline(t, np.vstack([x, x[:1]]), bc_type="periodic")
    return lambda s: spline(np.asarray(s, float) % 1.0)


def _steps(scene, model, ustar_min, ustar_max, direction, settings) -> C.ContinuationSettings:
    """Arclength steps in Π between the steady Π at the speeds ``ustar_min`` and
    ``ustar_max``, ``direction`` towards larger (+1) or smaller speed
    (:func:`fsicas.linear.adapter.speed_window`)."""
    bounds, pi_direction = speed_window(scene, model, ustar_min, ustar_max, direction)
    return C.ContinuationSettings(
        ds=settings.ds, ds_min=1e-8, ds_max=settings.ds_max, direction=pi_direction,
        max_steps=max(settings.max_points - 1, 1), bounds={PI: bounds},
        newton=C.NewtonSettings(tol=settings.tol), compute_eigenvalues=settings.detect,
        detect=settings.detect, max_turn=settings.max_turn)


def _result(scene, eps, branch, special, settings, wall_time) -> CollocatedImpactBranch:
    """The branch's points as :class:`CollocatedImpactPoint` records, with the status."""
    points = [CollocatedImpactPoint.from_columns(branch.columns, k) for k in range(len(branch.s))]
    points = points[:settings.max_points]
    return CollocatedImpactBranch(scene, eps, points,
                                  branch_end(branch.status, points, settings.max_points),
                                  branch.message, wall_time, special)
