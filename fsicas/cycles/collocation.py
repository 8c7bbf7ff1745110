"""Flutter limit cycles versus U*: collocation continuation from the first Hopf point.

The first Hopf point of the steady branch (:func:`fsicas.linear.hopf.critical_velocity`) is the
start; ``continuation.cycle_from_hopf`` switches onto the cycle branch (normal-form
guess), which is continued by pseudo-arclength collocation in the adapter's parameter
Π = Δp/(100 M*) (``fsicas.linear.adapter``: time in units of T/100, so the library's period is
100 T). Every point is converted back to physical quantities:

- U*: the inlet velocity (Q1 + Q2)/H* of the *steady state at the same pressure drop*
  (time integration holds Δp fixed at the steady value of the requested U*, so a cycle
  "at U*" is the cycle at that Δp);
- period T and angular frequency omega = 2π/T; tip half-amplitude (max − min of y(x_ref, t) over the cycle)/2;
- the Floquet multipliers (condensed monodromy product) and stability (all non-trivial
  multipliers inside the unit circle);
- the minimal gap min_{x,t} h_c(x, t) over the cycle and its ratio to the contact
  distance eps = ``scene.contact_gap``.

Extrema over the cycle are those of the collocation polynomial, exact in t (Newton on
its derivative on every mesh interval, ``continuation.CycleProblem.extrema``), at
``fsicas.model.contact.GAP_POINTS`` along the beam (:mod:`fsicas.cycles.gauge` holds
the rest of the measures). The branch
is one call of ``continuation.continuation``: the library locates cycle folds (the
parameter's tangent component changes sign) and the first contact, a user event
``gap_ratio - 1``, on the arclength with its corrector; its ``record`` hook measures every
point, and it re-meshes every few points (the cycle sharpens as the gap closes). Where a
point's quadrature error exceeds ``CycleSettings.quadrature_tol`` (the flow integrands
sharpen as the gap closes too), the branch goes on from that point on the model with
enough nodes (:func:`fsicas.model.accuracy.adequate_model`; the library's
``CycleProblem.refine``). The run stops at the first contact (the contact-free model ends
there), at ``ustar_max`` or after ``max_points``.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

import continuation as C

from ..linear.adapter import PI, flutter_field, pi_interval, pi_of
from ..linear.hopf import CriticalVelocityError, HopfPoint, first_hopf, flutter_problem
from ..model.accuracy import QUADRATURE_TOL, adequate_model
from ..model.assembly import Model, build_model
from ..scene import Scene
from .gauge import Gauge, PolynomialExtrema, model_parameters
from .records import BranchRecord, CycleMeasures, check_settings

__all__ = ["CycleSettings", "CyclePoint", "CycleBranch", "CycleKind", "CycleStatus",
           "CycleRun", "ProfileGauge", "cycle_branch", "continue_cycles"]

CycleKind = Literal["regular", "fold", "contact"]
"""A branch point, a located cycle fold, or the located first wall contact."""

CycleStatus = Literal["contact", "bound", "max_points", "failed"]
"""Why a collocation branch ended: first contact, U* reached ``ustar_max``, the point
budget, or a corrector failure (``message`` says why)."""


@dataclass(frozen=True)
class CycleSettings:
    """Discretization and stepping. ``ntst``/``ncol``: collocation mesh; ``dp``: start
    offset of Π from the Hopf point; ``ds``/``ds_max``: arclength steps (Euclidean norm of
    all node values); ``tol``: Newton tolerance; ``max_points``: branch points;
    ``adapt_every``: re-mesh (equidistribute the collocation error) every so many points,
    0 = never (the cycle sharpens as the gap closes); ``stop_at_contact``: stop at the
    first contact (else report it and go on, e.g. on a scene with smoothed contact);
    ``quadrature_tol``: from a point whose quadrature error exceeds it, the branch goes on
    with the nodes doubled as often as needed (:func:`fsicas.model.accuracy.adequate_model`),
    None = the model's nodes throughout."""

    ntst: int = 20
    ncol: int = 4
    dp: float = 1e-3
    ds: float = 0.01
    ds_max: float = 0.1
    tol: float = 1e-10
    max_points: int = 300
    adapt_every: int = 5
    stop_at_contact: bool = True
    quadrature_tol: float | None = QUADRATURE_TOL

    def __post_init__(self):
        check_settings(self, integers=("ntst", "ncol", "max_points"),
                       positives=("dp", "ds", "ds_max", "tol") + (
                           () if self.quadrature_tol is None else ("quadrature_tol",)),
                       nonnegative_integers=("adapt_every",))
        if not isinstance(self.stop_at_contact, bool):
            raise ValueError(f"CycleSettings.stop_at_contact must be a bool, "
                             f"got {self.stop_at_contact!r}")
        if self.ntst > C.MAX_NTST:
            raise ValueError(f"ntst must be at most {C.MAX_NTST}, got {self.ntst}")
        if not 2 <= self.ncol <= 7:
            raise ValueError(f"ncol (collocation points per interval) must be in 2..7, got "
                             f"{self.ncol}")

    @property
    def collocation(self) -> C.CollocationSettings:
        """The library's settings of this mesh and re-meshing (multipliers by the default
        periodic Schur route)."""
        return C.CollocationSettings(ntst=self.ntst, ncol=self.ncol, adapt_every=self.adapt_every)


@dataclass(frozen=True)
class CyclePoint(CycleMeasures):
    """One cycle. ``kind``: "regular", "fold" (cycle fold) or "contact" (first contact);
    ``state``: the model state x = (r, q, Q1, Q2) on the cycle at its phase 0 (a start
    point for time integration at ``pressure_drop``); ``located``: False for a special
    point whose location failed (the branch point just past it is reported)."""

    multipliers: np.ndarray = field(repr=False)
    stable: bool = True
    kind: CycleKind = "regular"
    state: np.ndarray = field(repr=False, default=None)
    located: bool = True
    #: relative error of the equations from the flow quadrature over the cycle
    #: (:mod:`fsicas.model.accuracy`; NaN where not measured)
    quadrature_error: float = float("nan")
    #: quadrature nodes (``scene.n_quad``) of the model the point was computed on
    #: (None where not recorded)
    quadrature_nodes: int | None = None

    _derived = ("omega",)

    @property
    def omega(self) -> float:
        """The angular frequency 2π/T (rad per unit T)."""
        return 2 * math.pi / self.period


@dataclass(frozen=True)
class CycleBranch(BranchRecord):
    """Cycles from the first Hopf point on, in order along the branch.

    ``hopf``: the Hopf point (``HopfPoint.to_json()``); ``folds``: located cycle folds;
    ``contact``: the located first contact or None; ``status``: "contact", "bound"
    (U* reached ``ustar_max``), "max_points" or "failed" (``message`` says why)."""

    scene: Scene
    eps: float
    hopf: dict
    points: list
    folds: list
    contact: CyclePoint | None
    status: CycleStatus
    message: str
    wall_time: float

    def to_json(self) -> dict:
        return {"scene": self.scene.to_dict(), "eps": self.eps, "hopf": self.hopf,
                "points": [p.to_json() for p in self.points],
                "folds": [p.to_json() for p in self.folds],
                "contact": None if self.contact is None else self.contact.to_json(),
                "status": self.status, "message": self.message, "wall_time": self.wall_time}

    @classmethod
    def from_json(cls, d: dict) -> "CycleBranch":
        return cls(Scene.from_dict(d["scene"]), d["eps"], d["hopf"],
                   [CyclePoint.from_json(p) for p in d["points"]],
                   [CyclePoint.from_json(p) for p in d["folds"]],
                   None if d["contact"] is None else CyclePoint.from_json(d["contact"]),
                   d["status"], d["message"], d["wall_time"])


def cycle_branch(scene: Scene, model: Model | None = None, *, ustar_max: float = 20.0,
                 settings: CycleSettings = CycleSettings(), hopf: HopfPoint | None = None
                 ) -> CycleBranch:
    """Continue the limit cycles born at the first Hopf point of ``scene`` in U*.

    ``hopf``: that Hopf point if already known (from :func:`critical_velocity` on the
    same model). Raises :class:`CriticalVelocityError` if there is none below
    ``ustar_max``."""
    start = time.perf_counter()
    run = continue_cycles(scene, model, ustar_max=ustar_max, settings=settings, hopf=hopf)
    folds = [_refined_fold(run, sp) for sp in run.branch.special("fold")]
    return _result(scene, run.gauge.eps, run.hopf, run.branch, folds, settings,
                   time.perf_counter() - start)


@dataclass(frozen=True)
class CycleRun:
    """The library's side of :func:`cycle_branch`: its ``branch`` (``continuation.Branch``),
    the Hopf point, the ``gauge`` measuring points (:class:`ProfileGauge`: its ``model``
    is the last, possibly refined one) and :meth:`problem_at`."""

    branch: C.Branch
    hopf: HopfPoint
    gauge: "ProfileGauge"
    problems: dict = field(repr=False)

    def problem_at(self, point: C.SpecialPoint):
        """The collocation problem (mesh, field) a special point's unknowns belong to."""
        return self.problems[np.asarray(point.unknowns, dtype=float).tobytes()]

    def refined_fold(self, point: C.SpecialPoint, tol: float):
        """``(problem, NewtonResult)``: the cycle fold ``point`` refined by Newton on its
        minimally extended system (``continuation.CycleFold``) to ``tol``."""
        return C.locate_cycle(self.problem_at(point), point.unknowns, C.CycleFold(),
                              C.NewtonSettings(tol=tol))


def continue_cycles(scene: Scene, model: Model | None = None, *, ustar_max: float = 20.0,
                    settings: CycleSettings = CycleSettings(), hopf: HopfPoint | None = None
                    ) -> CycleRun:
    """:func:`cycle_branch` as a :class:`CycleRun` (the start of the curves of cycles in
    (M*, U*), :mod:`fsicas.cycles.curves`)."""
    model = model or build_model(scene)
    hopf = hopf or first_hopf(scene, model, ustar_max=ustar_max)
    if hopf is None:
        raise CriticalVelocityError(f"no Hopf point below U* = {ustar_max:g} at M* = {scene.mstar:g}")
    for attempt in range(START_RETRIES + 1):
        run = _continued(scene, model, hopf, settings.dp / 10 ** attempt, settings, ustar_max)
        if run.branch.s.size or "start point" not in run.branch.message:
            break
    return run


#: Retries of the start from the Hopf point, each with a tenth of the offset ``dp`` of
#: the one before: the normal form's amplitude sqrt(|alpha dp / (l1 omega)|) grows without
#: bound as l1 -> 0, and where l1 is small its cubic term no longer sets the amplitude
#: (zeta = 0.01, N = 10: at M* = 0.7, l1 = 0.023, Newton diverged from a guess of tip
#: amplitude 0.012 at dp = 1e-3 and converged from 0.0037 at 1e-4; at M* = 0.75,
#: l1 = 2.6e-4, it converged from dp = 1e-7, tip amplitude 0.0011).
START_RETRIES = 5


def _continued(scene: Scene, model: Model, hopf: HopfPoint, dp: float,
               settings: CycleSettings, ustar_max: float) -> CycleRun:
    """The branch from the Hopf point, started at the offset ``dp`` of Π from it."""
    problem = C.cycle_from_hopf(flutter_problem(scene, model, min(0.2, abs(hopf.ustar) / 2)),
                                hopf.point, dp=dp, settings=settings.collocation)
    gauge = ProfileGauge(model, hopf.x, scene.contact_gap, settings.quadrature_tol)
    if settings.quadrature_tol is not None:
        problem.refine = gauge.refine
    problems = {}

    def record(problem, X):
        problems[np.asarray(X, dtype=float).tobytes()] = problem
        return gauge.record(problem, X)

    contact = C.Event("contact", gauge.contact_function, terminal=settings.stop_at_contact)
    branch = C.continuation(problem, settings=_steps(problem, scene, model, ustar_max, settings),
                            events=[contact], record=record)
    return CycleRun(branch, hopf, gauge, problems)


def _steps(problem, scene, model, ustar_max, settings) -> C.ContinuationSettings:
    """Arclength steps in Π up to the speed ``ustar_max`` (Π < 0 for reversed flow); folds
    detected from the tangent (no multipliers in the library's monitor: the gauge
    computes them once per point)."""
    return C.ContinuationSettings(
        ds=settings.ds, ds_min=1e-9, ds_max=settings.ds_max, direction=problem.hopf_direction,
        max_steps=settings.max_points - 1,
        bounds={PI: pi_interval(0.0, pi_of(scene, model, scene.flow_sign * ustar_max))},
        newton=C.NewtonSettings(tol=settings.tol), compute_eigenvalues=False)


def _result(scene, eps, hopf, branch, folds, settings, wall_time) -> CycleBranch:
    """The branch's points (the located contact is its own record, not a point), its
    ``folds`` and located contact, status and message."""
    points = [CyclePoint.from_columns(branch.columns, k) for k in range(len(branch.s))]
    contacts = [_special(sp, "contact") for sp in branch.special("contact")]
    if branch.status == "event":
        points = points[:-1]
    contact = contacts[0] if contacts else None
    status, message = _status(branch, contact, settings)
    return CycleBranch(scene, eps, hopf.to_json(), points, folds, contact, status, message,
                       wall_time)


def _refined_fold(run: CycleRun, sp) -> CyclePoint:
    """A cycle fold located on the arclength, refined by Newton on its minimally extended
    system (``continuation.CycleFold``: the second multiplier at +1 to the round-off the
    Jordan block allows); the arclength location where that Newton does not converge."""
    square, result = run.refined_fold(sp, 1e-12)
    if not result.converged:
        return _special(sp, "fold")
    return CyclePoint.from_columns(run.gauge.record(square, result.X), None, kind="fold")


def _special(sp, kind: str) -> CyclePoint:
    """A located special point of the library as a cycle point of ``kind``."""
    return CyclePoint.from_columns(sp.record, None, kind=kind, located=sp.status == "converged")


def _status(branch, contact, settings) -> tuple[CycleStatus, str]:
    if contact is not None and settings.stop_at_contact:
        return "contact", f"first contact (min gap = eps) at U* = {contact.ustar:.8g}"
    if branch.status == "bound":
        return "bound", "U* reached ustar_max"
    if branch.status == "max_steps":
        return "max_points", f"reached max_points = {settings.max_points}"
    return "failed", branch.message


class ProfileGauge(Gauge):
    """Measures of X = (nodes, 100 T, Π) on the collocation polynomial, the extrema exact
    (:class:`fsicas.cycles.gauge.PolynomialExtrema`)."""

    def __init__(self, model: Model, x_eq, eps: float, quadrature_tol: float | None):
        super().__init__(model, x_eq, eps)
        self._extrema = PolynomialExtrema(model)
        self.quadrature_tol = quadrature_tol

    def record(self, problem, X) -> dict:
        """The fields of :class:`CyclePoint` at X (branch columns)."""
        y_min, y_max = self.tip_extremes(problem, X)
        gap = self.gap(problem, X)
        return {**self.common(problem, X), "tip_amplitude": (y_max - y_min) / 2,
                "min_gap": gap, "gap_ratio": gap / self.eps}

    def tip_extremes(self, problem, X) -> tuple[float, float]:
        """``(min_t y(x_ref, t), max_t y(x_ref, t))`` (kept for the last X)."""
        return self.kept("tip", problem, X, lambda: self._extrema.tip(problem, X))

    def grazing_condition(self) -> C.Extremum:
        """The cycle's minimal gap equals eps (``continuation.Extremum``)."""
        return self._extrema.gap_condition(self.eps)

    def contact_function(self, problem, X) -> float:
        """``min gap / eps - 1``: zero at the first wall contact."""
        return self.gap(problem, X) / self.eps - 1.0

    def gap(self, problem, X) -> float:
        """min over the cycle of the gap (kept for the last X: event and record share it)."""
        return self.kept("gap", problem, X, lambda: self._extrema.min_gap(problem, X))

    def refine(self, problem, X):
        """``CycleProblem.refine``: None while the quadrature error at X is at most
        ``quadrature_tol``, else the field of the adequate model at X, which the gauge
        measures from then on (the branch goes on from X on it)."""
        if self.quadrature_error(problem, X) <= self.quadrature_tol:
            return None
        self.model, _ = adequate_model(self.model, problem.nodes(X),
                                       model_parameters(self.model, problem, X),
                                       self.quadrature_tol)
        return flutter_field(self.model)
