"""Flutter limit cycles versus U*: collocation continuation from the first Hopf point.

The first Hopf point of the steady branch (:func:`fsicas.hopf.critical_velocity`) is the
start; ``continuation.cycle_from_hopf`` switches onto the cycle branch (normal-form
guess), which is continued by pseudo-arclength collocation in the adapter's parameter
Π = Δp/(100 M*) (``fsicas.hopf``: time in units of T/100, so the library's period is
100 T). Every point is converted back to physical quantities:

- U*: the inlet velocity (Q1 + Q2)/H* of the *steady state at the same pressure drop*
  (time integration holds Δp fixed at the steady value of the requested U*, so a cycle
  "at U*" is the cycle at that Δp);
- period T and frequency 2π/T; tip half-amplitude (max − min of y(1, t) over the cycle)/2;
- the Floquet multipliers (condensed monodromy product) and stability (all non-trivial
  multipliers inside the unit circle);
- the minimal gap min_{x,t} h_c(x, t) over the cycle and its ratio to the contact
  distance eps = ``scene.contact_gap``.

Extrema over the cycle are taken on the collocation polynomial (16 samples per mesh
interval, 201 points along the beam) and refined in t by Brent's method. A cycle fold
(the parameter's tangent component changes sign) is located as the extremum of Π along
the arclength; the first contact (min gap = eps) by Brent's root finder on the arclength
between the two points that bracket it; each evaluation there is one PALC corrector
from the earlier point, as the library's own event location does. The mesh is
re-equidistributed every few points (the cycle sharpens as the gap closes). The run stops at the
first contact (the contact-free model ends there), at ``ustar_max`` or after
``max_points``.
"""
from __future__ import annotations

import json
import math
import time
from dataclasses import asdict, dataclass, field, fields, replace

import numpy as np
import scipy.optimize

import continuation as C

from ..linear.hopf import LOG_M, PI, PI_SCALE, TIME_SCALE, CriticalVelocityError, HopfPoint, \
    critical_velocity, flutter_problem, pi_of, steady_ustar
from ..model.assembly import Model, build_model, modal_basis
from ..scene import Scene

__all__ = ["CycleSettings", "CyclePoint", "CycleBranch", "CycleRecord", "BranchRecord", "cycle_branch"]

#: points along the beam where the gap is evaluated (endpoints included)
GAP_POINTS = np.linspace(0.0, 1.0, 201)


@dataclass(frozen=True)
class CycleSettings:
    """Discretization and stepping. ``ntst``/``ncol``: collocation mesh; ``dp``: start
    offset of Π from the Hopf point; ``ds``/``ds_max``: arclength steps (Euclidean norm of
    all node values); ``tol``: Newton tolerance; ``max_points``: branch points;
    ``adapt_every``: re-mesh (equidistribute the collocation error) every so many points,
    0 = never (the cycle sharpens as the gap closes); ``stop_at_contact``: stop at the
    first contact (else report it and go on, e.g. on a scene with smoothed contact)."""

    ntst: int = 20
    ncol: int = 4
    dp: float = 1e-3
    ds: float = 0.01
    ds_max: float = 0.1
    tol: float = 1e-10
    max_points: int = 300
    adapt_every: int = 5
    stop_at_contact: bool = True


class CycleRecord:
    """JSON of a frozen cycle dataclass with array fields ``multipliers`` (complex) and
    ``state``; ``_derived`` names properties written for readers and skipped on reading."""

    _derived: tuple = ()

    @property
    def nontrivial_multipliers(self) -> np.ndarray:
        """All multipliers but the one nearest 1 (the trivial one)."""
        mu = np.asarray(self.multipliers)
        return np.delete(mu, np.argmin(np.abs(mu - 1.0)))

    def to_json(self) -> dict:
        d = {k: v for k, v in asdict(self).items() if k not in ("multipliers", "state")}
        d.update({k: getattr(self, k) for k in self._derived})
        d["state"] = [float(v) for v in self.state]
        d["multipliers"] = [[float(m.real), float(m.imag)] for m in np.asarray(self.multipliers)]
        return d

    @classmethod
    def from_columns(cls, columns: dict, k: int):
        """The record of point ``k`` of a branch whose columns hold every field."""
        return cls(**{f.name: _scalar(columns[f.name][k]) for f in fields(cls)
                      if f.name in columns})

    @classmethod
    def from_json(cls, d: dict):
        d = {k: v for k, v in d.items() if k not in cls._derived}
        d["multipliers"] = np.array([complex(a, b) for a, b in d["multipliers"]])
        d["state"] = np.array(d["state"], dtype=float)
        return cls(**d)


def _scalar(value):
    """A column entry as a plain Python value (arrays are copied)."""
    if isinstance(value, np.ndarray) and value.ndim:
        return value.copy()
    return value.item() if isinstance(value, (np.generic, np.ndarray)) else value


class BranchRecord:
    """A branch of cycle points: ``column(name)`` along it, ``save(path)`` / ``load(path)``
    through its ``to_json`` / ``from_json``."""

    def column(self, name: str) -> np.ndarray:
        """One quantity along the branch, e.g. ``column("ustar")``."""
        return np.array([getattr(p, name) for p in self.points])

    def save(self, path) -> None:
        with open(path, "w") as f:
            json.dump(self.to_json(), f, indent=1)

    @classmethod
    def load(cls, path):
        with open(path) as f:
            return cls.from_json(json.load(f))


@dataclass(frozen=True)
class CyclePoint(CycleRecord):
    """One cycle. ``kind``: "regular", "fold" (cycle fold) or "contact" (first contact);
    ``state``: the model state x = (r, q, Q1, Q2) on the cycle at its phase 0 (a start
    point for time integration at ``pressure_drop``); ``located``: False for a special
    point whose location failed (the branch point just past it is reported)."""

    ustar: float
    pressure_drop: float
    period: float
    tip_amplitude: float
    min_gap: float
    gap_ratio: float
    multipliers: np.ndarray = field(repr=False)
    stable: bool = True
    kind: str = "regular"
    state: np.ndarray = field(repr=False, default=None)
    located: bool = True

    _derived = ("frequency",)

    @property
    def frequency(self) -> float:
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
    status: str
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
    model = model or build_model(scene)
    hopf = hopf or critical_velocity(scene, model, ustar_max=ustar_max)
    if hopf is None:
        raise CriticalVelocityError(f"no Hopf point below U* = {ustar_max:g} at M* = {scene.mstar:g}")
    problem = C.cycle_from_hopf(flutter_problem(scene, model, min(0.2, hopf.ustar / 2)), hopf.point,
                                dp=settings.dp,
                                settings=C.CollocationSettings(ntst=settings.ntst, ncol=settings.ncol,
                                                               floquet="product",
                                                               adapt_every=settings.adapt_every))
    gauge = _Gauge(problem, model, hopf.x)
    steps = C.ContinuationSettings(
        ds=settings.ds, ds_min=1e-9, ds_max=settings.ds_max, direction=problem.hopf_direction,
        max_steps=settings.max_points - 1, bounds={PI: (0.0, pi_of(scene, model, ustar_max))},
        newton=C.NewtonSettings(tol=settings.tol), detect=False)
    points, folds, contact, prev, tau_ref = [], [], None, None, None
    while True:
        iterator = C.ContinuationIterator(problem, C.PALC(), steps, tau_ref)
        restart = None
        for step in iterator:
            if tau_ref is not None and step.ds == 0.0:     # restart point, already recorded
                prev = (step, prev[1])
                continue
            point = gauge.measure(step.X)
            if contact is None and prev is not None and \
                    (prev[1].gap_ratio - 1) * (point.gap_ratio - 1) < 0:
                contact = gauge.locate("contact", prev[0], step, steps.newton)
                if settings.stop_at_contact:
                    break
            if prev is not None and prev[0].tau[-1] * step.tau[-1] < 0:
                folds.append(gauge.locate("fold", prev[0], step, steps.newton))
            points.append(point)
            prev = (step, point)
            restart = problem.restart(step.X) if len(points) < settings.max_points else None
            if restart is not None:
                break
        if restart is None or (contact is not None and settings.stop_at_contact):
            break
        problem, X_new = restart                  # re-meshed: same NTST, equidistributed error
        gauge.problem = problem
        tau_ref = np.zeros(X_new.size)
        tau_ref[-2:] = step.tau[-2:]              # only T and Π keep their meaning
        steps = replace(steps, ds=min(max(iterator.ds, steps.ds_min), steps.ds_max),
                        max_steps=settings.max_points - len(points))
    status, message = _status(iterator, contact, settings)
    return CycleBranch(scene, gauge.eps, hopf.to_json(), points, folds, contact, status, message,
                       time.perf_counter() - start)


def _status(iterator, contact, settings) -> tuple[str, str]:
    if contact is not None and settings.stop_at_contact:
        return "contact", f"first contact (min gap = eps) at U* = {contact.ustar:.8g}"
    if iterator.status == "bound":
        return "bound", "U* reached ustar_max"
    if iterator.status == "max_steps":
        return "max_points", f"reached max_points = {settings.max_points}"
    return "failed", iterator.message


class _Gauge:
    """Physical quantities of collocation unknowns X = (nodes, 100 T, Π)."""

    def __init__(self, problem, model: Model, x_eq):
        self.problem, self.model, self.vf = problem, model, problem.vf
        self.n = model.n_modes
        self.eps = model.scene.contact_gap
        self.tip = model.tip.phi[:, 1]
        self.phi = modal_basis(model.scene, GAP_POINTS).phi          # (N, len(GAP_POINTS))
        self.walls = np.array([w(GAP_POINTS) for w in model.scene.walls])
        self.x_eq = np.asarray(x_eq, dtype=float)

    # -- per point -------------------------------------------------------------------
    def measure(self, X, kind: str = "regular") -> CyclePoint:
        """U*, Δp, T, tip half-amplitude, min gap, multipliers and stability of X."""
        p = self.problem.params(X)
        mu = self.problem.multipliers(X)
        rest = np.delete(mu, np.argmin(np.abs(mu - 1.0)))
        y_max = -self._extremum(X, lambda Q: -(Q @ self.tip))
        y_min = self._extremum(X, lambda Q: Q @ self.tip)
        gap = self._extremum(X, self._gap)
        mstar = 10 ** p[self.vf.par_index(LOG_M)]
        return CyclePoint(ustar=self._ustar(p), pressure_drop=float(X[-1] * PI_SCALE * mstar),
                          period=self.problem.period(X) / TIME_SCALE,
                          tip_amplitude=(y_max - y_min) / 2, min_gap=gap, gap_ratio=gap / self.eps,
                          multipliers=mu, stable=bool(np.all(np.abs(rest) < 1.0)), kind=kind,
                          state=self.problem.state(X).copy())

    def _gap(self, Q) -> np.ndarray:
        """min over x and both channels of h_c(x) for modal displacements Q (rows)."""
        y = Q @ self.phi
        return np.minimum(self.walls[0] - y, self.walls[1] + y).min(axis=1)

    def _extremum(self, X, f) -> float:
        """min_t f(q(t)) over the cycle: on 16 samples per mesh interval, refined by
        bounded Brent between the neighbours of the best sample."""
        q = lambda t: self.problem.evaluate(X, np.atleast_1d(t) % 1.0)[:, self.n:2 * self.n]
        mesh = self.problem.mesh
        t = (mesh[:-1, None] + np.diff(mesh)[:, None] * np.arange(16) / 16).ravel()
        values = f(q(t))
        k = int(np.argmin(values))
        t_lo, t_hi = t[k - 1] if k else t[-1] - 1, t[k + 1] if k + 1 < t.size else 1.0
        res = scipy.optimize.minimize_scalar(lambda t: float(f(q(t))[0]), method="bounded",
                                             bounds=(t_lo, t_hi),
                                             options={"xatol": 1e-12})
        return float(min(res.fun, values[k]))

    def _ustar(self, p) -> float:
        """U* of the steady state at the parameters p (warm-started from the last one)."""
        ustar, self.x_eq = steady_ustar(self.vf, p, self.x_eq, self.model.scene.hstar)
        return ustar

    # -- special points --------------------------------------------------------------
    def locate(self, kind: str, a, b, newton) -> CyclePoint:
        """The ``kind`` ("fold" or "contact") point between steps a and b; if a corrector
        fails or the sign change is lost, b itself with ``located=False``."""
        try:
            return (self.fold if kind == "fold" else self.contact)(a, b, newton)
        except (RuntimeError, ValueError):
            return replace(self.measure(b.X, kind), located=False)

    def _on_arc(self, a, s: float, newton):
        """The branch point at arclength s from step a (PALC corrector)."""
        res = C.correct(self.problem, a.X + s * a.tau, a.tau, newton)
        if not res.converged:
            raise RuntimeError(f"corrector failed while locating a point: {res.message}")
        return res.X

    def fold(self, a, b, newton) -> CyclePoint:
        """Cycle fold between steps a and b: the extremum of Π along the arclength."""
        sign = 1.0 if a.tau[-1] > 0 else -1.0          # Π increases towards the fold: a maximum
        sb = float(a.tau @ (b.X - a.X))
        res = scipy.optimize.minimize_scalar(lambda s: -sign * self._on_arc(a, s, newton)[-1],
                                             method="bounded", bounds=(0.0, sb),
                                             options={"xatol": 1e-10 * abs(sb)})
        return self.measure(self._on_arc(a, res.x, newton), "fold")

    def contact(self, a, b, newton) -> CyclePoint:
        """First contact between steps a and b: min gap = eps, by Brent on the arclength."""
        sb = float(a.tau @ (b.X - a.X))
        gap = lambda s: self._extremum(self._on_arc(a, s, newton), self._gap) - self.eps
        s = scipy.optimize.brentq(gap, 0.0, sb, xtol=1e-14, rtol=1e-12)
        return self.measure(self._on_arc(a, s, newton), "contact")
