"""The bifurcation diagram by itself: a branch continued, every simple bifurcation on it
switched onto, and so on recursively to a depth.

The switches (each a public function of the rooms below):

* a branch point ('bp') of equilibria: the other branch through it, both halves
  (``equilibrium_from_bp`` with amplitude ``+a`` and ``-a``);
* a Hopf point of equilibria: the cycles born there (``cycle_from_hopf``, on the side
  of the normal form);
* a period doubling of cycles: the doubled cycles (``cycle_from_pd``);
* a branch point of cycles (a pitchfork, symmetry breaking): the new cycles, away from
  the point and through it onto the mirror half (``cycle_from_bp``, ``direction=+1, -1``).

A branch met twice is kept once: every new branch runs under a ``stop`` predicate that
ends it as soon as two successive points lie on a branch already in the diagram and
its secant runs along that branch's segment (``|cos| >= ALIGNED``); such a run is
dropped and noted in ``Diagram.skipped``. A branch that comes back to its own first
point (a closed loop, e.g. the bubble between two pitchforks) stops there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from .._cycles.cycles import CycleProblem
from .._cycles.switching import cycle_from_bp, cycle_from_hopf, cycle_from_pd
from .._driver.branch import Branch, load_npz, save_npz
from .._driver.driver import continuation
from .._driver.hooks import Event
from .._driver.problem import Problem
from .._driver.settings import ContinuationSettings
from .._equilibria.branching import equilibrium_from_bp
from .._equilibria.equilibrium import EquilibriumProblem

FORMAT = "continuation.Diagram/1"
#: the special-point kinds a diagram can switch at
SWITCHES = ("bp", "hopf", "pd")
#: a point is on a segment of length L when within ``ON_SEGMENT L + atol`` of it
ON_SEGMENT = 0.1
#: |cos| of the angle between two secants that run along each other
ALIGNED = 0.95
#: samples of a cycle over its period in its signature (mean, amplitude)
CYCLE_SAMPLES = 64


@dataclass(frozen=True)
class Birth:
    """How a branch was born: ``kind`` of the special point it was switched from
    ('start' for the root), ``point``: that point's index in the parent's
    ``special_points`` (-1 for the root), ``side``: +1 or -1 (the two halves of a branch
    point's new branch; +1 otherwise), ``params``: the point's parameters."""

    kind: str
    point: int = -1
    side: int = 1
    params: dict = field(default_factory=dict)


@dataclass(frozen=True)
class DiagramNode:
    """A branch of the diagram, how it was born, and the branches switched onto from it."""

    branch: Branch
    birth: Birth
    children: tuple = ()

    def walk(self, depth: int = 0):
        """``(node, depth)`` of this node and its descendants, depth first."""
        yield self, depth
        for child in self.children:
            yield from child.walk(depth + 1)


@dataclass(frozen=True)
class Diagram:
    """The tree of branches of :func:`bifurcation_diagram`.

    root : the first branch's node; depth : the recursion depth asked for;
    skipped : the switches not made, ``{'kind', 'params', 'reason'}`` each (a duplicate
    of a branch already in the diagram, a switch that failed, a kind not switched on
    that kind of branch); warnings : what the user should know (failed branches).
    """

    root: DiagramNode
    depth: int
    skipped: tuple = ()
    warnings: tuple = ()

    def nodes(self) -> list:
        """Every node, depth first from the root."""
        return [node for node, _ in self.root.walk()]

    @property
    def branches(self) -> list:
        return [node.branch for node in self.nodes()]

    def save(self, path) -> None:
        """Write the whole tree to one ``.npz`` file (a JSON header, no pickling)."""
        entries, arrays = [], {}
        for i, (node, depth) in enumerate(self.root.walk()):
            header, arr = node.branch.to_arrays()
            arrays.update({f"b{i}__{k}": v for k, v in arr.items()})
            entries.append({"branch": header, "birth": node.birth.__dict__, "depth": depth,
                            "children": len(node.children)})
        save_npz(path, {"format": FORMAT, "depth": self.depth, "nodes": entries,
                        "skipped": list(self.skipped), "warnings": list(self.warnings)}, arrays)

    @classmethod
    def load(cls, path) -> "Diagram":
        """Read a diagram written by :meth:`save`."""
        header, arrays = load_npz(path, FORMAT)
        flat = []
        for i, entry in enumerate(header["nodes"]):
            arr = {k.split("__", 1)[1]: v for k, v in arrays.items()
                   if k.startswith(f"b{i}__")}
            flat.append((Branch.from_arrays(entry["branch"], arr), Birth(**entry["birth"]),
                         entry["children"]))
        root, _ = _rebuild(flat, 0)
        return cls(root, header["depth"], tuple(header["skipped"]),
                   tuple(header["warnings"]))


def _rebuild(flat, i) -> tuple[DiagramNode, int]:
    """The node at ``flat[i]`` (depth-first order) with its subtree; the next index."""
    branch, birth, count = flat[i]
    children, j = [], i + 1
    for _ in range(count):
        child, j = _rebuild(flat, j)
        children.append(child)
    return DiagramNode(branch, birth, tuple(children)), j


@dataclass(frozen=True)
class _Options:
    settings: ContinuationSettings
    cycle_settings: ContinuationSettings
    collocation: object
    amplitude: float
    dp: float
    switch: tuple
    atol: float
    record: object
    events: tuple


def bifurcation_diagram(problem: Problem, settings: ContinuationSettings | None = None,
                        depth: int = 2, *, cycle_settings: ContinuationSettings | None = None,
                        collocation=None, amplitude: float = 1e-2, dp: float = 1e-3,
                        switch: tuple = SWITCHES, atol: float = 1e-8,
                        record=None, events=()) -> Diagram:
    """Continue ``problem``, switch at every special point of a kind in ``switch`` on its
    branch, continue the new branches and switch on them, to ``depth`` levels below the
    root (0: the root alone); a branch met twice is kept once (module doc).

    settings : of the equilibrium branches (and of the root); ``direction`` orients the
        root only, the switched branches leave their points.
    cycle_settings : of the cycle branches (default ``settings``); collocation : the
        ``CollocationSettings`` of cycles born at Hopf points (default the library's).
    amplitude : the offset along the new branch at a branch point or period doubling;
        dp : the parameter offset of the first cycle at a Hopf point.
    atol : absolute part of the distance under which a point lies on a branch.
    record : ``record(problem, X) -> {name: value}``, the ``record`` callback of every
        branch's :func:`continuation` (its columns; ``problem.kind`` tells the branches'
        kinds apart).
    events : :class:`Event` objects of every branch (a terminal one ends a branch, e.g.
        where its solutions leave the model's domain).
    """
    opts = _options(problem, settings, depth, cycle_settings, collocation, amplitude, dp,
                    switch, atol, record, events)
    found, skipped = [], []
    root = _grow(problem, Birth("start"), opts, depth, found, skipped, settings=opts.settings)
    warnings = [f"the {node.branch.kind} branch born at {node.birth.kind} "
                f"{node.birth.params} failed: {node.branch.message}"
                for node, _ in root.walk() if node.branch.status == "failed"]
    return Diagram(root, depth, tuple(skipped), tuple(warnings))


def _options(problem, settings, depth, cycle_settings, collocation, amplitude, dp, switch,
             atol, record, events) -> _Options:
    """The checked options (ValueError naming the bad one)."""
    if not isinstance(problem, Problem):
        raise ValueError(f"problem must be a continuation Problem, got {type(problem).__name__}")
    if not (isinstance(depth, int) and not isinstance(depth, bool) and depth >= 0):
        raise ValueError(f"depth must be a non-negative integer, got {depth!r}")
    for name, value in (("amplitude", amplitude), ("dp", dp), ("atol", atol)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a positive finite number, got {value!r}")
    switch = tuple(switch)
    if not set(switch) <= set(SWITCHES):
        raise ValueError(f"switch must be kinds among {SWITCHES}, got {switch!r}")
    settings = ContinuationSettings() if settings is None else settings
    for name, value in (("settings", settings), ("cycle_settings", cycle_settings)):
        if value is not None and not isinstance(value, ContinuationSettings):
            raise ValueError(f"{name} must be a ContinuationSettings, got {value!r}")
    if record is not None and not callable(record):
        raise ValueError(f"record must be callable or None, got {record!r}")
    if not all(isinstance(e, Event) for e in events):
        raise ValueError(f"events must be continuation Events, got {events!r}")
    return _Options(settings, cycle_settings or settings, collocation, float(amplitude),
                    float(dp), switch, float(atol), record, tuple(events))


def _grow(problem, birth, opts, depth, found, skipped, settings) -> DiagramNode | None:
    """Continue ``problem`` (None when it retraces a branch of ``found``), then its
    children to ``depth`` more levels."""
    watch = _Watch(problem.kind, found, opts.atol)
    branch = continuation(problem, settings=settings, stop=watch, record=opts.record,
                          events=opts.events)
    if watch.duplicate is not None:
        skipped.append({"kind": birth.kind, "params": birth.params,
                        "reason": f"retraces branch {watch.duplicate}"})
        return None
    found.append((problem.kind, np.array(watch.points)))
    children = []
    for index, point in enumerate(branch.special_points) if depth > 0 else ():
        for child_birth, child, direction in _switches(problem, point, index, opts, skipped):
            child_settings = _settings_for(child, opts, direction)
            node = _grow(child, child_birth, opts, depth - 1, found, skipped, child_settings)
            if node is not None:
                children.append(node)
    return DiagramNode(branch, birth, tuple(children))


def _settings_for(problem, opts, direction) -> ContinuationSettings:
    base = opts.cycle_settings if problem.kind == "cycle" else opts.settings
    return replace(base, direction=direction)


def _switches(problem, point, index, opts, skipped) -> list:
    """``[(birth, new problem, direction)]`` at ``point`` (``skipped`` notes a point of a
    switched kind that could not be switched at, and why)."""
    if point.kind not in opts.switch:
        return []
    births = lambda sides: [Birth(point.kind, index, s, dict(point.params))  # noqa: E731
                            for s in sides]
    try:
        if isinstance(problem, EquilibriumProblem) and point.kind == "bp":
            made = [equilibrium_from_bp(problem, point, amplitude=s * opts.amplitude)
                    for s in (1, -1)]
            return list(zip(births((1, -1)), made, (1, 1)))
        if isinstance(problem, EquilibriumProblem) and point.kind == "hopf":
            cycle = cycle_from_hopf(problem, point, dp=opts.dp, settings=opts.collocation)
            return list(zip(births((1,)), [cycle], [cycle.hopf_direction]))
        if isinstance(problem, CycleProblem) and point.kind == "pd":
            return list(zip(births((1,)), [cycle_from_pd(problem, point,
                                                         amplitude=opts.amplitude)], [1]))
        if isinstance(problem, CycleProblem) and point.kind == "bp":
            made = [cycle_from_bp(problem, point, amplitude=opts.amplitude) for _ in (1, -1)]
            return list(zip(births((1, -1)), made, (1, -1)))
        reason = f"no switch at a {point.kind!r} point of a {type(problem).__name__} branch"
    except (ValueError, ArithmeticError, np.linalg.LinAlgError) as err:
        reason = f"switch failed: {err}"
    skipped.append({"kind": point.kind, "params": dict(point.params), "reason": reason})
    return []


def _signature(problem, X) -> np.ndarray:
    """A point ``X`` of ``problem`` as compared between branches: the state and the free
    parameters of equilibria; of cycles the free parameters, the period, the peak-to-peak
    amplitude and the mean over a period (their states depend on the phase and the
    mesh; the mean tells a cycle from its mirror image)."""
    p = problem.par_dict(X)
    free = np.array([p[k] for k in problem.free])
    if problem.kind != "cycle":
        return np.concatenate([problem.state(X), free])
    u = problem.evaluate(X, np.arange(CYCLE_SAMPLES) / CYCLE_SAMPLES) \
        if hasattr(problem, "evaluate") else problem.state(X)[None, :]   # shooting: u(0)
    return np.concatenate([free, [problem.period(X), np.max(np.ptp(u, axis=0))],
                           u.mean(axis=0)])


class _Watch:
    """The ``stop`` predicate of a new branch: a duplicate once two successive points lie
    along a branch of ``found`` of the same kind; closed once the branch comes back to
    its first point."""

    def __init__(self, kind, found, atol):
        self.others = [sig for k, sig in found if k == kind]
        self.atol, self.points, self.duplicate = atol, [], None

    def __call__(self, problem, X):
        self.points.append(_signature(problem, X))
        if len(self.points) < 2:
            return False
        a, b = self.points[-2], self.points[-1]
        for i, sig in enumerate(self.others):
            if _along(sig, a, b, self.atol):
                self.duplicate = i
                return f"retraces branch {i} of the diagram"
        if len(self.points) > 3 and _on_segment(self.points[0], a, b, self.atol):
            return "closed: back at its first point"
        return False


def _on_segment(q, a, b, atol) -> bool:
    """``q`` on the segment ``[a, b]`` (:func:`_near` of one segment)."""
    return bool(_near(q, np.vstack([a, b]), atol)[0])


def _near(q, sig, atol) -> np.ndarray:
    """For each segment ``[sig_k, sig_k+1]`` of the polyline ``sig``: ``q`` within
    ``ON_SEGMENT |segment| + atol (1 + |q|)`` of it."""
    a, d = sig[:-1], np.diff(sig, axis=0)
    length2 = np.sum(d * d, axis=1)
    t = np.clip(np.einsum("ij,ij->i", q - a, d) / np.where(length2 > 0, length2, 1.0), 0, 1)
    dist = np.linalg.norm(q - a - t[:, None] * d, axis=1)
    return dist <= ON_SEGMENT * np.sqrt(length2) + atol * (1 + float(np.linalg.norm(q)))


def _along(sig, a, b, atol) -> bool:
    """``b - a`` runs along a segment of the polyline ``sig`` (``|cos| >= ALIGNED``) on
    which, or on whose neighbours, both ``a`` and ``b`` lie."""
    d = b - a
    if sig.shape[0] < 2 or sig.shape[1] != a.size or not np.linalg.norm(d):
        return False
    seg = np.diff(sig, axis=0)
    aligned = np.abs(seg @ d) >= ALIGNED * np.linalg.norm(d) * np.linalg.norm(seg, axis=1)
    widen = lambda m: m | np.r_[m[1:], False] | np.r_[False, m[:-1]]  # noqa: E731
    return bool(np.any(aligned & widen(_near(a, sig, atol)) & widen(_near(b, sig, atol))))
