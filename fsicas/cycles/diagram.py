"""The bifurcation diagram of a scene over U*, by ``continuation.bifurcation_diagram``.

The steady branch is continued in Π (:mod:`fsicas.linear.adapter`) from ``ustar_start``
to ``ustar_max``; at its Hopf points the diagram switches onto the limit cycles, at its
branch points (the pitchforks of divergence) onto the deflected steady states, on cycle
branches at period doublings and branch points (symmetry breaking), and so on to
``depth`` levels; a branch reached twice is kept once. Every point is measured by:

- ``ustar``: U* of the undeflected steady state at the point's pressure drop (as every
  cycle branch of fsicas; Newton from the steady branch's state at the nearest Π), so
  that all branches share the horizontal axis;
- ``tip``: the tip deflection y(1) of a steady state; the tip half-amplitude
  (max - min of y(1, t))/2 of a cycle, exact on its collocation polynomial;
- ``stable``: no eigenvalue in the right half plane (steady), no non-trivial Floquet
  multiplier outside the unit circle (cycles).

The diagram is of the contact-free equations (the scene must not have contact): every
branch ends where its solutions first come within eps of a wall (a terminal event
'contact', labelled C; as ``fsicas lco``), past which those equations no longer
describe the beam.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicSpline

import continuation as C

from ..linear.adapter import PI, TIME_SCALE, pi_of, steady_ustar
from ..linear.hopf import flutter_problem
from ..linear.steady import SteadyStateError
from ..model import contact
from ..model.assembly import Model, build_model
from ..scene import Scene
from .collocation import CycleSettings
from .gauge import PolynomialExtrema

__all__ = ["DiagramSettings", "DiagramBranch", "SceneDiagram", "scene_diagram", "LABELS"]

#: What the diagram calls the library's kinds of special points (the figure's labels).
LABELS = {"hopf": "H", "bp": "BP", "fold": "LP", "pd": "PD", "ns": "NS", "contact": "C"}


@dataclass(frozen=True)
class DiagramSettings:
    """``depth``: levels of switching below the steady branch; ``ustar_start``: where the
    steady branch starts; ``max_points``: points of a steady branch at most (its steps
    are at most 1/150 of the Π range); ``cycles``: the cycle branches' mesh and steps
    (``max_points`` per branch; ``dp`` the start offset at a Hopf point)."""

    depth: int = 2
    ustar_start: float = 0.2
    max_points: int = 600
    cycles: CycleSettings = CycleSettings(max_points=150)

    def __post_init__(self):
        if not (isinstance(self.depth, int) and not isinstance(self.depth, bool)
                and 0 <= self.depth <= 5):
            raise ValueError(f"depth must be an integer in 0..5, got {self.depth!r}")
        if not (np.isfinite(self.ustar_start) and self.ustar_start > 0):
            raise ValueError(f"ustar_start must be positive, got {self.ustar_start!r}")
        if not (isinstance(self.max_points, int) and self.max_points >= 2):
            raise ValueError(f"max_points must be an integer >= 2, got {self.max_points!r}")


@dataclass(frozen=True)
class DiagramBranch:
    """One branch of the diagram: ``kind`` 'steady' or 'cycle', ``born`` the kind of point
    it was switched from ('start' for the steady branch) on branch ``parent`` (its index;
    None for the first) with ``side`` +1/-1 (the halves of a branch point's new branch),
    ``depth``; per point ``ustar``, ``tip``, ``stable`` (and the cycles' ``period`` in
    units of T); ``special``: its special points ``{kind, label, ustar, tip, located}``."""

    kind: str
    born: str
    parent: int | None
    side: int
    depth: int
    ustar: np.ndarray
    tip: np.ndarray
    stable: np.ndarray
    period: np.ndarray | None
    special: tuple
    status: str
    message: str

    def to_json(self, points: bool = True) -> dict:
        out = {"kind": self.kind, "born": self.born, "parent": self.parent, "side": self.side,
               "depth": self.depth, "n_points": int(self.ustar.size),
               "ustar_range": [float(self.ustar.min()), float(self.ustar.max())]
               if self.ustar.size else None,
               "special": list(self.special), "status": self.status, "message": self.message}
        if points:
            out.update(ustar=self.ustar.tolist(), tip=self.tip.tolist(),
                       stable=self.stable.tolist(),
                       period=None if self.period is None else self.period.tolist())
        return out


@dataclass(frozen=True)
class SceneDiagram:
    """The diagram of ``scene`` up to ``ustar_max``: its ``branches`` in the tree's depth
    first order (each names its parent), the switches not made (``skipped``: ``{kind,
    ustar, reason}``, duplicates of a branch already found, failures), ``status``
    'failed' when a branch's corrector failed (``warnings`` say which), and the library's
    tree (``diagram``)."""

    scene: Scene
    ustar_max: float
    settings: DiagramSettings
    branches: tuple
    skipped: tuple
    warnings: tuple
    status: str
    wall_time: float
    diagram: C.Diagram = field(repr=False, compare=False)

    def to_json(self, points: bool = True) -> dict:
        return {"ustar_max": self.ustar_max, "depth": self.settings.depth,
                "status": self.status, "branches": [b.to_json(points) for b in self.branches],
                "skipped": list(self.skipped), "warnings": list(self.warnings),
                "wall_time": self.wall_time}


def scene_diagram(scene: Scene, model: Model | None = None, *, ustar_max: float = 20.0,
                  settings: DiagramSettings = DiagramSettings()) -> SceneDiagram:
    """The bifurcation diagram of ``scene`` over U* in (``settings.ustar_start``,
    ``ustar_max``) (module doc). ValueError for a scene with contact or a bad range."""
    if scene.contact:
        raise ValueError("the diagram is of the contact-free equations: drop --contact")
    if not settings.ustar_start < ustar_max:
        raise ValueError(f"ustar_max must exceed ustar_start = {settings.ustar_start:g}, "
                         f"got {ustar_max!r}")
    start = time.perf_counter()
    model = model or build_model(scene)
    root = flutter_problem(scene, model, settings.ustar_start)
    measure = _Measure(model, scene.contact_gap)
    pi_max = pi_of(scene, model, ustar_max)
    diagram = C.bifurcation_diagram(
        root, _steady_steps(pi_max, settings), settings.depth,
        cycle_settings=_cycle_steps(pi_max, settings.cycles),
        collocation=settings.cycles.collocation, dp=settings.cycles.dp,
        record=measure, events=(C.Event("contact", measure.contact, terminal=True),))
    steady = _SteadyUstar(root.vf, diagram.root.branch, scene.hstar)
    branches = _branches(diagram, steady)
    warnings = tuple(f"the {b.kind} branch born at {b.born} on branch {b.parent} failed: "
                     f"{b.message}" for b in branches if b.status == "failed")
    skipped = tuple({"kind": s["kind"], "ustar": steady(s["params"][PI]), "reason": s["reason"]}
                    for s in diagram.skipped)
    return SceneDiagram(scene, float(ustar_max), settings, tuple(branches), skipped,
                        warnings, "failed" if warnings else "ok",
                        time.perf_counter() - start, diagram)


def _steady_steps(pi_max: float, settings: DiagramSettings) -> C.ContinuationSettings:
    """Steps of at most 1/150 of the Π range (as the onset's search: a pocket of
    stability between two Hopf points is not stepped over)."""
    ds_max = pi_max / 150
    return C.ContinuationSettings(ds=ds_max / 4, ds_min=1e-10 * pi_max, ds_max=ds_max,
                                  max_steps=settings.max_points - 1,
                                  bounds={PI: (0.0, pi_max)}, locate_tol=1e-12)


def _cycle_steps(pi_max: float, cycles: CycleSettings) -> C.ContinuationSettings:
    return C.ContinuationSettings(ds=cycles.ds, ds_min=1e-9, ds_max=cycles.ds_max,
                                  max_steps=cycles.max_points - 1, bounds={PI: (0.0, pi_max)},
                                  newton=C.NewtonSettings(tol=cycles.tol))


class _Measure:
    """The ``record`` of every branch: the tip (deflection of a steady state, half
    amplitude of a cycle); and the contact event's function ``min gap / eps - 1``."""

    def __init__(self, model: Model, eps: float):
        self.model, self.eps, self.extrema = model, eps, PolynomialExtrema(model)

    def __call__(self, problem, X) -> dict:
        if problem.kind != "cycle":
            return {"tip": float(self.model.tip_deflection(problem.state(X)))}
        low, high = self.extrema.tip(problem, X)
        return {"tip": (high - low) / 2}

    def contact(self, problem, X) -> float:
        if problem.kind != "cycle":
            gap = contact.gaps(self.model, problem.state(X)[None, :]).min()
        else:
            gap = self.extrema.min_gap(problem, X)
        return float(gap) / self.eps - 1.0


def _branches(diagram: C.Diagram, steady: "_SteadyUstar") -> list:
    """The :class:`DiagramBranch` of every node, U* from the steady branch (the root)."""
    out, parents = [], {}
    for node, depth in diagram.root.walk():
        parents.update({id(child): len(out) for child in node.children})
        b = node.branch
        ustar = np.array([steady(p) for p in b.par(PI)])
        cycle = b.kind == "cycle"
        special = tuple(_special(point, steady) for point in b.special_points)
        out.append(DiagramBranch(
            "cycle" if cycle else "steady", node.birth.kind, parents.get(id(node)),
            node.birth.side, depth, ustar, _column(b, "tip"), np.asarray(b.stable, bool),
            _column(b, "period") / TIME_SCALE if cycle else None, special,
            b.status, b.message))
    return out


def _column(branch: C.Branch, name: str) -> np.ndarray:
    """A column of ``branch`` (empty for a branch without points: its start failed)."""
    return np.asarray(branch.columns.get(name, np.zeros(0)), dtype=float)


def _special(point, steady) -> dict:
    return {"kind": point.kind, "label": LABELS.get(point.kind, point.kind),
            "ustar": steady(point.params[PI]), "tip": point.data.get("tip"),
            "located": point.status == "converged"}


class _SteadyUstar:
    """U* of the undeflected steady state at Π: Newton (:func:`steady_ustar`) from the
    steady branch's state at the nearest Π; where a branch point of the steady states
    makes its Jacobian singular and Newton creeps, the cubic spline of U*(Π) through the
    steady branch's own points (their U* exact)."""

    def __init__(self, vf, root: C.Branch, hstar: float):
        self.vf, self.root, self.hstar = vf, root, hstar
        self.pi, self.column = root.par(PI), root.par_names.index(PI)
        order = np.argsort(self.pi)
        pi, keep = np.unique(self.pi[order], return_index=True)
        self.spline = CubicSpline(pi, root.x[order][keep, -2:].sum(axis=1) / hstar)

    def __call__(self, pi: float) -> float:
        k = int(np.argmin(np.abs(self.pi - pi)))
        p = self.root.params[k].copy()
        p[self.column] = pi
        try:
            return steady_ustar(self.vf, p, self.root.x[k], self.hstar)[0]
        except SteadyStateError:
            return float(self.spline(pi))
