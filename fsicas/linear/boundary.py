"""Stability boundary in the (M*, U*) plane as the lower envelope of the curves of onsets:
Hopf curves (flutter) and divergence curves (a real eigenvalue crosses zero).

1. Seeds: at a few M* (one per decade by default) every Hopf point and every divergence
   of the steady branch up to ``ustar_max`` is found by continuation in U*
   (:func:`fsicas.linear.hopf.onset_points`).
2. Each one not already on a traced curve starts its curve (:mod:`fsicas.linear.curves`):
   a two-parameter continuation of the Hopf curve in (log10 M*, Δp/M*), or the
   divergence followed in log10 M*, both ways, inside the window.
3. At each requested M*, the boundary is the lowest U* over all curves (the first loss of
   stability along U*, ``kind`` "flutter" or "divergence"). Each point is then refined at
   that M* (a one-parameter Hopf location, started just below the envelope, which also
   gives its l1, or the divergence solved there).
4. Where the lowest branch changes (scanned along the traced curves), two curves cross
   (a double-Hopf point: U* continuous, the frequency jumps) or a curve folds back in M*
   (U* jumps). Its position is bisected on the traced curves (linear between exact Hopf
   points), about 1 % in M*. (Bisection with one-parameter onsets was tried and is not
   reliable: near a crossing two Hopf points fall into one continuation step.)

For reversed flow (U* < 0) every U* of the result is negative; lowest, ``ustar_max``
and the ceiling are speeds |U*|.
"""
from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from .curves import (Envelope, OnsetCurve, onset_on_curve, trace_divergence_curve,
                     trace_hopf_curve)
from .hopf import (Criticality, CriticalVelocityError, ModalTruncationWarning, Onset,
                   first_onset, onset_points)
from .stability import eigenvalues
from .steady import SteadyStateError, steady_state
from .switches import ModeSwitch, located_switches
from .truncation import TRUNCATION_RTOL, finer_modes, truncation_error
from ..model.assembly import Model, build_model
from ..scene import Scene

__all__ = ["BoundaryPoint", "OnsetCurve", "ModeSwitch", "StabilityBoundary",
           "stability_boundary"]


@dataclass(frozen=True)
class BoundaryPoint:
    """The stability boundary at one M*: the lowest curve of onsets there, of ``kind``
    "flutter" or "divergence" (then omega = freq_ratio = 0, no l1).

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
    kind: str | None = None
    #: after a refinement: relative change of U*_c with twice the modes
    truncation: float | None = None

    def to_json(self) -> dict:
        """``fsicas boundary --json`` point: mstar, kind, ustar_crit, omega, freq_ratio, branch;
        where a curve was found also refined (and missed when true), and after a refinement
        l1, criticality and dominant_mode."""
        out = {"mstar": self.mstar, "kind": self.kind, "ustar_crit": self.ustar_crit,
               "omega": self.omega,
               "freq_ratio": self.freq_ratio, "branch": self.branch}
        if self.ustar_crit is None:
            return out
        out["refined"] = self.refined
        if self.missed:
            out["missed"] = True
        if self.refined:
            out.update(dominant_mode=self.dominant_mode, truncation=self.truncation)
            if self.kind == "flutter":
                out.update(l1=self.l1, criticality=self.criticality)
        return out


@dataclass(frozen=True)
class StabilityBoundary:
    scene: Scene
    points: list[BoundaryPoint]
    curves: list[OnsetCurve] = field(repr=False)
    switches: list[ModeSwitch]
    wall_time: float
    #: the refined points whose truncation error exceeds its tolerance, said once
    warnings: list = field(default_factory=list)

    @property
    def truncation(self) -> float:
        """The largest truncation error of the refined points (inf where one was not
        estimated, 0 without refined points)."""
        return max((math.inf if p.truncation is None else p.truncation
                    for p in self.points if p.refined), default=0.0)

    def to_json(self) -> dict:
        return {"points": [p.to_json() for p in self.points], "warnings": self.warnings,
                "switches": [vars(s) for s in self.switches],
                "curves": [{"branch": c.index, "kind": c.kind, "mstar": c.mstar.tolist(),
                            "ustar": c.ustar.tolist(),
                            "omega": c.omega.tolist()} for c in self.curves],
                "wall_time": self.wall_time}


def stability_boundary(scene: Scene, mstars, model: Model | None = None,
                       ustar_max: float = 40.0, seeds=None, refine: bool = True,
                       headroom: float = 1.3, full_curves: bool = False) -> StabilityBoundary:
    """The stability boundary U*_c(M*) at ``mstars`` with its curves and mode switches.

    Curves are traced below ``headroom`` times the highest onset found at the seeds; a
    Hopf curve that stays above that everywhere cannot be the lowest one. Each half of a
    curve also ends where it rises above ``headroom`` times the lowest curve traced
    before it, unless ``full_curves`` (every curve up to the ceiling, e.g. to draw the
    whole family; slower)."""
    mstars = np.sort(np.asarray(mstars, dtype=float))
    if mstars.size == 0 or np.any(~np.isfinite(mstars)) or np.any(mstars <= 0):
        raise ValueError(f"mstars must be finite and > 0, got {mstars}")
    start = time.perf_counter()
    model = model or build_model(scene)
    lo, hi = math.log10(mstars[0]), math.log10(mstars[-1])
    seeds = _default_seeds(lo, hi) if seeds is None else np.asarray(seeds, float)
    window = (lo - 0.05, hi + 0.05)
    ceiling, found = _seed_points(scene, model, seeds, ustar_max, headroom)
    search = lambda m: onset_points(scene.replace(mstar=float(m)), model, ustar_max,
                                    ustar_stop=1.05 * ceiling)
    curves: list[OnsetCurve] = []
    cut = None if full_curves else headroom
    _add_curves(scene, model, curves, found, window, ceiling, cut)
    points = [_boundary_point(scene, model, curves, m, refine) for m in mstars]
    searched = set()
    for _ in range(MAX_RESEEDS):   # curves the seeds missed: searched where they show
        missed = {p.mstar for p in points if p.missed} | \
            set(_unstable_below(scene, model, curves, lo, hi, ceiling))
        missed -= searched
        if not missed:
            break
        searched |= missed
        _add_curves(scene, model, curves, [search(m) for m in sorted(missed)], window,
                    ceiling, cut)
        points = [_boundary_point(scene, model, curves, m, refine) for m in mstars]
    switches = located_switches(scene, model, curves, lo, hi)
    return StabilityBoundary(scene, points, curves, switches, time.perf_counter() - start,
                             _truncation_warnings(scene, points) + _untraced(curves))


def _untraced(curves) -> list:
    """A warning for each onset curve that could not be traced (no points)."""
    return [f"an onset curve could not be traced ({c.message}); the boundary points rest "
            "on the other curves, each checked by the eigenvalues below it"
            for c in curves if not c.mstar.size]


def _truncation_warnings(scene: Scene, points) -> list:
    """One warning (also a ModalTruncationWarning) naming the refined points whose
    truncation error is above :data:`TRUNCATION_RTOL` or was not estimated."""
    bad = [p for p in points if p.refined and (p.truncation is None
                                               or p.truncation > TRUNCATION_RTOL)]
    if not bad:
        return []
    where = ", ".join(f"{p.mstar:.4g} (" + ("not relocated with twice the modes" if p.truncation
                                             is None else f"{p.truncation:.2g}") + ")"
                      for p in bad)
    note = (f"{len(bad)} boundary points move with twice the modes (N = {scene.modes} -> "
            f"{finer_modes(scene.modes)}) by more than {TRUNCATION_RTOL:g} (relative), or "
            f"could not be relocated there: at M* = {where}; raise modes (--modes auto)")
    warnings.warn(note, ModalTruncationWarning, stacklevel=3)
    return [note]


#: Rounds of searches for curves the seeds missed.
MAX_RESEEDS = 4
#: Spacing in decades of the grid of log10 M* (its multiples, whatever the requested M*)
#: on which the steady state just below the envelope is checked to be stable.
CHECK_STEP = 0.01


def _unstable_below(scene, model, curves, lo: float, hi: float, ceiling: float) -> list:
    """M* in the middle of each run of grid points (:data:`CHECK_STEP`) in [lo, hi] where
    the steady state at 0.99 x the envelope (x the ceiling where no curve passes) is
    unstable: a lower curve was not traced there."""
    envelope, grid = Envelope(curves), _check_grid(lo, hi)
    bad = np.zeros(grid.size, dtype=bool)
    for k, lm in enumerate(grid):
        lowest = envelope.lowest(lm)
        at = scene.replace(mstar=float(10 ** lm),
                           ustar=0.99 * (lowest[0] if lowest else scene.flow_sign * ceiling))
        try:
            bad[k] = eigenvalues(model, steady_state(at, model))[0].real > 0
        except SteadyStateError:
            continue
    edges = np.flatnonzero(np.diff(np.r_[False, bad, False].astype(int)))
    return [float(10 ** grid[(a + b - 1) // 2]) for a, b in zip(edges[::2], edges[1::2])]


def _check_grid(lo: float, hi: float) -> np.ndarray:
    """The multiples of :data:`CHECK_STEP` in [lo, hi], and lo and hi."""
    inner = np.arange(math.ceil(lo / CHECK_STEP), math.floor(hi / CHECK_STEP) + 1) * CHECK_STEP
    return np.unique(np.r_[lo, inner[(inner > lo) & (inner < hi)], hi])


def _seed_points(scene, model, seeds, ustar_max, headroom):
    """The ceiling ``min(ustar_max, headroom * highest first onset)`` over the seeds
    (curves above it cannot be lowest) and each seed's Hopf points up to 1.05 times it
    (the margin: none is in the step that ends a run).

    A search up to ``ustar_stop`` takes the steps of one up to ``ustar_max`` (only its
    end differs), so a seed's first onset is the first point of its search whenever that
    search found one: only the highest seed (usually the highest onset) gets a separate
    first-onset search, and a search is repeated only when a later seed raises the
    ceiling above where it stopped."""
    search = lambda i, top: onset_points(scene.replace(mstar=float(seeds[i])), model,
                                         ustar_max, ustar_stop=top)
    first = lambda i: [first_onset(scene.replace(mstar=float(seeds[i])), model, ustar_max)]
    onsets, found, last = {}, {}, len(seeds) - 1
    _note_onset(onsets, last, first(last))
    while True:
        ceiling = min(ustar_max, headroom * max(onsets.values(), default=ustar_max))
        todo = [i for i in range(len(seeds)) if i not in found or found[i][0] < 1.05 * ceiling]
        if not todo:
            break
        for i in todo:
            found[i] = (1.05 * ceiling, search(i, 1.05 * ceiling))
            if found[i][1]:
                onsets.setdefault(i, abs(found[i][1][0].ustar))
            elif i not in onsets and 1.05 * ceiling < ustar_max:   # its onset is higher
                _note_onset(onsets, i, first(i))
    if not onsets:
        raise CriticalVelocityError(f"no onset below U* = {ustar_max} at any seed M* {seeds}")
    return ceiling, [found[i][1] for i in range(len(seeds))]


def _note_onset(onsets: dict, i: int, points) -> None:
    if points and points[0] is not None:
        onsets[i] = abs(points[0].ustar)


def _add_curves(scene, model, curves, found, window, ceiling, cut) -> None:
    """Trace the curve of every found onset below ``ceiling`` not yet on a curve; with
    ``cut`` each half ends where it can no longer be lowest (:func:`_envelope_check`)."""
    envelope = Envelope(curves)
    check = None if cut is None else lambda: _envelope_check(envelope, cut)
    for points in found:
        for h in points:
            if abs(h.ustar) <= ceiling and not any(_on_curve(scene, model, c, h) for c in curves):
                first = _next_piece(curves)
                if h.kind == "divergence":
                    curves.append(trace_divergence_curve(scene, model, h, len(curves), window,
                                                         ceiling, first, check))
                    continue
                stop = None if check is None else lambda: _hopf_stop(check(), scene.hstar)
                curves.append(trace_hopf_curve(scene, model, h, len(curves), window, ceiling,
                                               first, stop))


def _next_piece(curves) -> int:
    """The first piece id past every traced curve's (one of a single point has no piece
    but keeps its id)."""
    return max(((int(c.pieces.max()) if c.pieces.size else c.first_piece) + 1
                for c in curves), default=0)


def _envelope_check(envelope: Envelope, headroom: float):
    """``check(ustar, log10_mstar)`` of one half of a curve: true (a message) when the
    half rises (U* increasing) above ``headroom`` times the lowest curve traced before at
    its M*. A stretch that high cannot be the lowest curve, like one above the ceiling."""
    last = []

    def check(u: float, log_m: float):
        u = abs(u)
        rising, last[:] = bool(last) and u > last[0], [u]
        if not rising:
            return False
        us, _ = envelope.crossings(log_m)
        return bool(us.size) and u > headroom * np.abs(us).min() and \
            f"rose above {headroom:g} x the lowest traced curve"

    return check


def _hopf_stop(check, hstar: float):
    """``check`` as a ``continuation`` stop predicate of a Hopf curve's half."""
    def stop(problem, X):
        n = problem.vf.n
        return check(float(X[n - 2: n].sum() / hstar), float(X[len(X) - 1]))
    return stop


def _default_seeds(lo: float, hi: float) -> np.ndarray:
    count = max(2, int(math.ceil(hi - lo)) + 1)
    return np.logspace(lo, hi, count)


def _on_curve(scene, model, curve: OnsetCurve, h: Onset, rtol: float = 0.1) -> bool:
    """Does onset h lie on the traced curve? Its kind, and a crossing at its M* within
    ``rtol`` in U* and frequency (the curve's interpolation: ~1 % off between samples,
    more near a fold) whose exact onset (:func:`onset_on_curve`) is h to 1e-6."""
    log_m = math.log10(h.mstar)
    near = [k for u, w, k in curve.crossings(log_m) if abs(u - h.ustar) <= rtol * abs(h.ustar)
            and abs(w - h.omega) <= rtol * max(h.omega, 1e-300)]
    if curve.kind != h.kind or not near:
        return False
    exact = (onset_on_curve(scene, model, curve, k, log_m) for k in near)
    return any(e is not None and abs(e.ustar - h.ustar) <= 1e-6 * abs(h.ustar) for e in exact)


def _boundary_point(scene, model, curves, mstar, refine) -> BoundaryPoint:
    log_m = math.log10(mstar)
    lowest = Envelope(curves).lowest(log_m)
    if lowest is None:
        return BoundaryPoint(float(mstar))
    u, w, piece = lowest
    point = BoundaryPoint(float(mstar), float(u), float(w), float(w / model.omega_1), int(piece))
    if not refine:
        return point
    curve = next(c for c in curves if piece in set(c.pieces.tolist()))
    point = replace(point, kind=curve.kind)
    h = onset_on_curve(scene, model, curve, piece, log_m)
    if h is None:
        return point
    below = scene.replace(mstar=float(mstar), ustar=0.99 * h.ustar)
    if eigenvalues(model, steady_state(below, model))[0].real > 0:
        return replace(point, missed=True)   # a curve below this one was not traced
    error = truncation_error(scene.replace(mstar=float(mstar)), model, h)
    point = replace(point, ustar_crit=h.ustar, omega=h.omega, freq_ratio=h.freq_ratio,
                    dominant_mode=h.dominant_mode, refined=True,
                    truncation=None if math.isnan(error) else error)
    if h.kind == "flutter":
        point = replace(point, l1=h.l1, criticality=h.criticality)
    return point
