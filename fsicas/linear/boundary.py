"""Stability boundary in the (M*, U*) plane as the lower envelope of Hopf curves.

1. Seeds: at a few M* (one per decade by default) every Hopf point of the steady branch
   up to ``ustar_max`` is found by continuation in U* (:func:`fsicas.linear.hopf.hopf_points`).
2. Each Hopf point not already on a traced curve starts a two-parameter continuation of
   its Hopf curve in (log10 M*, Δp/M*), both ways, inside the window.
3. At each requested M*, the boundary is the lowest U* over all curves (the first loss of
   stability along U*). Each point is then refined by a one-parameter Hopf location at that
   M*, started just below the envelope, which also gives its l1 (criticality).
4. Where the lowest branch changes (scanned along the traced curves), two curves cross
   (a double-Hopf point: U* continuous, the frequency jumps) or a curve folds back in M*
   (U* jumps). Its position is bisected on the traced curves (linear between exact Hopf
   points), about 1 % in M*. (Bisection with one-parameter onsets was tried and is not
   reliable: near a crossing two Hopf points fall into one continuation step.)
"""
from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

import continuation as C

from .adapter import LOG_M, PI, PI_SCALE, TIME_SCALE, flutter_field
from .hopf import (Criticality, CriticalVelocityError, HopfPoint, dominant_mode, flutter_problem,
                   hopf_point_from, hopf_points)
from .stability import eigenvalues
from .steady import steady_state
from ..model.assembly import Model, build_model
from ..scene import Scene

__all__ = ["BoundaryPoint", "HopfCurve", "ModeSwitch", "StabilityBoundary",
           "stability_boundary"]

@dataclass(frozen=True)
class BoundaryPoint(Mapping):
    """The stability boundary at one M*: the lowest Hopf curve there.

    Also a read-only mapping of its JSON (:meth:`to_json`): ``point["ustar_crit"]``,
    ``"l1" in point`` (only after a refinement) read as on the CLI's JSON.

    ``ustar_crit``, ``omega``, ``freq_ratio`` (= omega/omega_1) and ``branch`` (the piece of
    the lowest curve) are None where no traced curve reaches this M*. ``refined``: the
    values come from a Hopf location at this M* (then ``l1``, ``criticality`` and
    ``dominant_mode`` are set), else they are interpolated on the traced curve.
    ``missed``: the refinement found the steady state already unstable just below, i.e. a
    lower Hopf curve was not traced.
    """

    mstar: float
    ustar_crit: float | None = None
    omega: float | None = None
    freq_ratio: float | None = None
    branch: int | None = None
    refined: bool = False
    missed: bool = False
    l1: float | None = None
    criticality: Criticality | None = None
    dominant_mode: int | None = None

    def to_json(self) -> dict:
        """``fsicas boundary --json`` point: mstar, ustar_crit, omega, freq_ratio, branch;
        where a curve was found also refined (and missed when true), and after a refinement
        l1, criticality and dominant_mode."""
        out = {"mstar": self.mstar, "ustar_crit": self.ustar_crit, "omega": self.omega,
               "freq_ratio": self.freq_ratio, "branch": self.branch}
        if self.ustar_crit is None:
            return out
        out["refined"] = self.refined
        if self.missed:
            out["missed"] = True
        if self.refined:
            out.update(l1=self.l1, criticality=self.criticality, dominant_mode=self.dominant_mode)
        return out

    def __getitem__(self, key: str):
        return self.to_json()[key]

    def __iter__(self):
        return iter(self.to_json())

    def __len__(self) -> int:
        return len(self.to_json())


@dataclass(frozen=True)
class HopfCurve:
    """A traced Hopf curve: arrays along the curve (ordered by arclength). ``status``:
    "bound" when both halves ran to the window's bounds, else the library's status of
    the half that stopped first (``message`` says why)."""

    index: int
    mstar: np.ndarray
    ustar: np.ndarray
    omega: np.ndarray
    dominant_mode: np.ndarray
    status: C.Status
    first_piece: int = 0
    states: np.ndarray = field(default=None, repr=False)   # steady states along the curve
    params: np.ndarray = field(default=None, repr=False)   # adapter parameters along it
    message: str = ""

    def guess(self, log_m: float, piece: int) -> tuple[np.ndarray, np.ndarray, float]:
        """Interpolated (state, params, omega) on ``piece`` at log10 M* = log_m."""
        lm = np.log10(self.mstar)
        for i in np.flatnonzero(self.pieces == piece):   # pieces are per segment
            a, b = lm[i], lm[i + 1]
            if (a - log_m) * (b - log_m) <= 0 and a != b:
                t = (log_m - a) / (b - a)
                mix = lambda arr: arr[i] + t * (arr[i + 1] - arr[i])
                return mix(self.states), mix(self.params), float(mix(self.omega))
        raise ValueError(f"piece {piece} does not reach log10 M* = {log_m}")

    @property
    def pieces(self) -> np.ndarray:
        """Branch id of each segment (length = points - 1): a new id after every fold in M*
        (the lower envelope jumps between pieces, even of one curve)."""
        return self._pieces.copy()

    @cached_property
    def _pieces(self) -> np.ndarray:
        step = np.sign(np.diff(np.log10(self.mstar)))
        turns = np.concatenate([[0], np.cumsum(step[1:] * step[:-1] < 0)])
        return self.first_piece + turns

    @cached_property
    def _segments(self) -> tuple:
        """Ends of the segments in log10 M*, U* and omega (arrays of length points - 1)."""
        lm = np.log10(self.mstar)
        ends = lambda arr: (arr[:-1], arr[1:])
        return ends(lm), ends(self.ustar), ends(self.omega)

    def crossings(self, log_m: float) -> list[tuple[float, float, int]]:
        """(U*, omega, piece) where the curve passes log10 M* = log_m (linear interpolation)."""
        (a, b), (ua, ub), (wa, wb) = self._segments
        i = np.flatnonzero(((a - log_m) * (b - log_m) <= 0) & (a != b))
        t = (log_m - a[i]) / (b[i] - a[i])
        u, w = ua[i] + t * (ub[i] - ua[i]), wa[i] + t * (wb[i] - wa[i])
        return [(float(uk), float(wk), int(pk)) for uk, wk, pk in zip(u, w, self._pieces[i])]


@dataclass(frozen=True)
class ModeSwitch:
    """Where the lowest Hopf branch changes with M*: at a crossing of two Hopf curves
    (a double-Hopf point: ustar_below = ustar_above, the frequency jumps) or at a fold of
    a curve in M* (the boundary itself jumps from ustar_below to ustar_above)."""

    mstar: float
    ustar_below: float
    ustar_above: float
    branch_below: int
    branch_above: int
    omega_below: float
    omega_above: float


@dataclass(frozen=True)
class StabilityBoundary:
    scene: Scene
    points: list[BoundaryPoint]
    curves: list[HopfCurve] = field(repr=False)
    switches: list[ModeSwitch]
    wall_time: float

    def to_json(self) -> dict:
        return {"points": [p.to_json() for p in self.points],
                "switches": [vars(s) for s in self.switches],
                "curves": [{"branch": c.index, "mstar": c.mstar.tolist(), "ustar": c.ustar.tolist(),
                            "omega": c.omega.tolist()} for c in self.curves],
                "wall_time": self.wall_time}


def stability_boundary(scene: Scene, mstars, model: Model | None = None,
                       ustar_max: float = 40.0, seeds=None, refine: bool = True,
                       headroom: float = 1.3) -> StabilityBoundary:
    """The flutter boundary U*_c(M*) at ``mstars`` with its curves and mode switches.

    Curves are traced below ``headroom`` times the highest onset found at the seeds; a
    Hopf curve that stays above that everywhere cannot be the lowest one."""
    mstars = np.sort(np.asarray(mstars, dtype=float))
    if mstars.size == 0 or np.any(~np.isfinite(mstars)) or np.any(mstars <= 0):
        raise ValueError(f"mstars must be finite and > 0, got {mstars}")
    start = time.perf_counter()
    model = model or build_model(scene)
    lo, hi = math.log10(mstars[0]), math.log10(mstars[-1])
    seeds = _default_seeds(lo, hi) if seeds is None else np.asarray(seeds, float)
    window = (lo - 0.05, hi + 0.05)
    ceiling, found = _seed_points(scene, model, seeds, ustar_max, headroom)
    search = lambda m: hopf_points(scene.replace(mstar=float(m)), model, ustar_max,
                                   ustar_stop=1.05 * ceiling)
    curves: list[HopfCurve] = []
    _add_curves(scene, model, curves, found, window, ceiling)
    points = [_boundary_point(scene, model, curves, m, refine) for m in mstars]
    for _ in range(3):   # a refinement that starts unstable reveals a curve the seeds missed
        missed = [p.mstar for p in points if p.missed]
        if not missed:
            break
        found = [search(m) for m in missed]
        _add_curves(scene, model, curves, found, window, ceiling)
        points = [_boundary_point(scene, model, curves, m, refine) for m in mstars]
    switches = _switches(curves, lo, hi)
    return StabilityBoundary(scene, points, curves, switches, time.perf_counter() - start)


def _seed_points(scene, model, seeds, ustar_max, headroom):
    """The ceiling ``min(ustar_max, headroom * highest first onset)`` over the seeds
    (curves above it cannot be lowest) and each seed's Hopf points up to 1.05 times it
    (the margin: none is in the step that ends a run).

    A search up to ``ustar_stop`` takes the steps of one up to ``ustar_max`` (only its
    end differs), so a seed's first onset is the first point of its search whenever that
    search found one: only the highest seed (usually the highest onset) gets a separate
    first-onset search, and a search is repeated only when a later seed raises the
    ceiling above where it stopped."""
    search = lambda i, top, **kw: hopf_points(scene.replace(mstar=float(seeds[i])), model,
                                              ustar_max, ustar_stop=top, **kw)
    onsets, found, last = {}, {}, len(seeds) - 1
    _note_onset(onsets, last, search(last, ustar_max, first_only=True))
    while True:
        ceiling = min(ustar_max, headroom * max(onsets.values(), default=ustar_max))
        todo = [i for i in range(len(seeds)) if i not in found or found[i][0] < 1.05 * ceiling]
        if not todo:
            break
        for i in todo:
            found[i] = (1.05 * ceiling, search(i, 1.05 * ceiling))
            if found[i][1]:
                onsets.setdefault(i, found[i][1][0].ustar)
            elif i not in onsets and 1.05 * ceiling < ustar_max:   # its onset is higher
                _note_onset(onsets, i, search(i, ustar_max, first_only=True))
    if not onsets:
        raise CriticalVelocityError(f"no flutter below U* = {ustar_max} at any seed M* {seeds}")
    return ceiling, [found[i][1] for i in range(len(seeds))]


def _note_onset(onsets: dict, i: int, points) -> None:
    if points:
        onsets[i] = points[0].ustar


def _add_curves(scene, model, curves, found, window, ceiling) -> None:
    """Trace the Hopf curve of every found point below ``ceiling`` not yet on a curve."""
    for points in found:
        for h in points:
            if h.ustar <= ceiling and not any(_on_curve(c, h) for c in curves):
                first = curves[-1].pieces[-1] + 1 if curves else 0
                curves.append(_trace(scene, model, h, len(curves), window, ceiling, first))


def _default_seeds(lo: float, hi: float) -> np.ndarray:
    count = max(2, int(math.ceil(hi - lo)) + 1)
    return np.logspace(lo, hi, count)


def _on_curve(curve: HopfCurve, h: HopfPoint, rtol: float = 2e-2) -> bool:
    """Does Hopf point h lie on the traced curve (same U* and frequency at its M*)?"""
    return any(abs(u - h.ustar) <= rtol * h.ustar and abs(w - h.omega) <= rtol * h.omega
               for u, w, _ in curve.crossings(math.log10(h.mstar)))


def _trace(scene, model, h: HopfPoint, index: int, window, ustar_max, first_piece) -> HopfCurve:
    """Continue the Hopf curve through h both ways inside the (log10 M*, U*) window."""
    problem = flutter_problem(scene.replace(mstar=h.mstar), model, ustar_start=0.2)
    pi_max = _pi_max(h, ustar_max)
    halves, status, message = [], "bound", ""
    for direction in (-1, 1):
        settings = C.ContinuationSettings(
            ds=0.05, ds_min=1e-8, ds_max=0.3, max_steps=300, direction=direction,
            bounds={LOG_M: window, PI: (0.0, pi_max)}, detect=False, compute_eigenvalues=False,
            newton=C.NewtonSettings(tol=1e-8))   # curve points only guide; points are refined
        branch = C.continuation(C.HopfCurveProblem.from_point(problem, h.point, LOG_M),
                                settings=settings, record=_mode_recorder(model))
        if branch.status != "bound" and status == "bound":
            status, message = branch.status, branch.message
        halves.append(branch)
    lower, upper = halves
    join = lambda a, b: np.concatenate([a[::-1], b[1:]])
    x, params = join(lower.x, upper.x), join(lower.params, upper.params)
    kappa = join(lower.columns["kappa"], upper.columns["kappa"])
    keep = kappa > 0           # neutral-saddle stretches are not Hopf points
    x, params, omega = x[keep], params[keep], np.sqrt(kappa[keep])
    names = lower.par_names
    modes = join(lower.columns["mode"], upper.columns["mode"])[keep].astype(int)
    lm = params[:, names.index(LOG_M)]
    return HopfCurve(index, 10 ** lm, x[:, -2:].sum(axis=1) / scene.hstar, omega * TIME_SCALE,
                     modes, status, int(first_piece), x, params, message)


def _mode_recorder(model):
    """``record`` hook of a Hopf curve: the dominant mode of the eigenvector
    ``q = v - i w / omega`` of ``i omega`` carried by the unknowns ``X = (x, v, w, kappa,
    ...)`` (0 where ``kappa <= 0``), instead of an eigen-decomposition per point."""
    n = model.n_modes

    def record(problem, X):
        m, kappa = problem.vf.n, X[3 * problem.vf.n]
        if kappa <= 0:
            return {"mode": 0.0}
        q = X[m: 2 * m] - 1j * X[2 * m: 3 * m] / np.sqrt(kappa)
        return {"mode": float(dominant_mode(model, q[n: 2 * n]))}

    return record


def _pi_max(h: HopfPoint, ustar_max: float) -> float:
    """Π bound equivalent to U* <= ustar_max, scaled from the Hopf point (Π ∝ U*^2)."""
    pi_h = h.pressure_drop / (h.mstar * PI_SCALE)
    return pi_h * (ustar_max / h.ustar) ** 2


def _lowest(curves, log_m):
    best = None
    for c in curves:
        for u, w, piece in c.crossings(log_m):
            if best is None or u < best[0]:
                best = (u, w, piece)
    return best


def _boundary_point(scene, model, curves, mstar, refine) -> BoundaryPoint:
    log_m = math.log10(mstar)
    lowest = _lowest(curves, log_m)
    if lowest is None:
        return BoundaryPoint(float(mstar))
    u, w, piece = lowest
    point = BoundaryPoint(float(mstar), float(u), float(w), float(w / model.omega_1), int(piece))
    if not refine:
        return point
    curve = next(c for c in curves if piece in set(c.pieces.tolist()))
    h = _refine(scene, model, mstar, *curve.guess(log_m, piece))
    if h == "unstable":
        return replace(point, missed=True)
    if h is None:
        return point
    return replace(point, ustar_crit=h.ustar, omega=h.omega, freq_ratio=h.freq_ratio, l1=h.l1,
                   criticality=h.criticality, dominant_mode=h.dominant_mode, refined=True)


def _refine(scene, model, mstar, x, params, omega):
    """Newton on the Hopf system at ``mstar`` from the interpolated curve point; then
    check that the steady state just below is stable (``"unstable"``: a Hopf curve below
    this one was missed). None if Newton fails."""
    names = flutter_field(model).par_names
    values = dict(zip(names, params))
    values[LOG_M] = math.log10(mstar)
    problem = C.EquilibriumProblem(flutter_field(model), x, values, PI)
    located = C.hopf_point(problem, x, omega / TIME_SCALE)
    if located.status != "converged" or located.data.get("omega", 0.0) <= 0:
        return None
    h = hopf_point_from(model, scene, located)
    below = scene.replace(mstar=float(mstar), ustar=0.99 * h.ustar)
    if eigenvalues(model, steady_state(below, model))[0].real > 0:
        return "unstable"
    return h


def _switches(curves, lo: float, hi: float) -> list[ModeSwitch]:
    """Every change of the lowest piece on [lo, hi] (log10 M*), scanned on a fine grid of
    the traced curves (no new solves) and bisected to round-off in log10 M*."""
    out = []
    grid = np.linspace(lo, hi, 801)
    lowest = [_lowest(curves, lm) for lm in grid]
    for k in range(len(grid) - 1):
        a, b = lowest[k], lowest[k + 1]
        if a is None or b is None or a[2] == b[2]:
            continue
        lo, hi = _switch_bracket(curves, a[2], grid[k], grid[k + 1])
        ua, wa, _ = _lowest(curves, lo)
        ub, wb, _ = _lowest(curves, hi)
        if abs(ua - ub) < 1e-2 * ub and abs(wa - wb) < 1e-2 * wb:
            continue     # the same branch traced twice (two pieces overlapping): no switch
        out.append(ModeSwitch(float(10 ** (0.5 * (lo + hi))), float(ua), float(ub),
                              a[2], b[2], float(wa), float(wb)))
    return out


def _switch_bracket(curves, piece: int, lo: float, hi: float) -> tuple[float, float]:
    """Bisect [lo, hi] (``piece`` lowest at lo, not at hi) to where the lowest piece
    changes: a crossing of two Hopf curves, or the fold in M* that ends ``piece``."""
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        lowest = _lowest(curves, mid)
        if lowest is not None and lowest[2] == piece:
            lo = mid
        else:
            hi = mid
    return lo, hi

