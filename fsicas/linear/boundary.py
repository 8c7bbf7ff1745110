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
"""
from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from .curves import OnsetCurve, onset_on_curve, trace_divergence_curve, trace_hopf_curve
from .hopf import Criticality, CriticalVelocityError, Onset, first_onset, onset_points
from .stability import eigenvalues
from .steady import steady_state
from .switches import locate_switch
from ..model.assembly import Model, build_model
from ..scene import Scene

__all__ = ["BoundaryPoint", "OnsetCurve", "ModeSwitch", "StabilityBoundary",
           "stability_boundary"]

@dataclass(frozen=True)
class BoundaryPoint(Mapping):
    """The stability boundary at one M*: the lowest curve of onsets there, of ``kind``
    "flutter" or "divergence" (then omega = freq_ratio = 0, no l1).

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
    kind: str | None = None

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
            out.update(dominant_mode=self.dominant_mode)
            if self.kind == "flutter":
                out.update(l1=self.l1, criticality=self.criticality)
        return out

    def __getitem__(self, key: str):
        return self.to_json()[key]

    def __iter__(self):
        return iter(self.to_json())

    def __len__(self) -> int:
        return len(self.to_json())


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
    #: solved on its defining equation (:mod:`fsicas.linear.switches`), else bracketed
    #: on the traced curves
    located: bool = False


@dataclass(frozen=True)
class StabilityBoundary:
    scene: Scene
    points: list[BoundaryPoint]
    curves: list[OnsetCurve] = field(repr=False)
    switches: list[ModeSwitch]
    wall_time: float

    def to_json(self) -> dict:
        return {"points": [p.to_json() for p in self.points],
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
    for _ in range(3):   # a refinement that starts unstable reveals a curve the seeds missed
        missed = [p.mstar for p in points if p.missed]
        if not missed:
            break
        found = [search(m) for m in missed]
        _add_curves(scene, model, curves, found, window, ceiling, cut)
        points = [_boundary_point(scene, model, curves, m, refine) for m in mstars]
    switches = [locate_switch(scene, model, curves, sw) for sw in _switches(curves, lo, hi)]
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
                onsets.setdefault(i, found[i][1][0].ustar)
            elif i not in onsets and 1.05 * ceiling < ustar_max:   # its onset is higher
                _note_onset(onsets, i, first(i))
    if not onsets:
        raise CriticalVelocityError(f"no onset below U* = {ustar_max} at any seed M* {seeds}")
    return ceiling, [found[i][1] for i in range(len(seeds))]


def _note_onset(onsets: dict, i: int, points) -> None:
    if points and points[0] is not None:
        onsets[i] = points[0].ustar


def _add_curves(scene, model, curves, found, window, ceiling, cut) -> None:
    """Trace the curve of every found onset below ``ceiling`` not yet on a curve; with
    ``cut`` each half ends where it can no longer be lowest (:func:`_envelope_check`)."""
    envelope = _Envelope(curves)
    check = None if cut is None else lambda: _envelope_check(envelope, cut)
    for points in found:
        for h in points:
            if h.ustar <= ceiling and not any(_on_curve(c, h) for c in curves):
                first = curves[-1].pieces[-1] + 1 if curves else 0
                if h.kind == "divergence":
                    curves.append(trace_divergence_curve(scene, model, h, len(curves), window,
                                                         ceiling, first, check))
                    continue
                stop = None if check is None else lambda: _hopf_stop(check(), scene.hstar)
                curves.append(trace_hopf_curve(scene, model, h, len(curves), window, ceiling,
                                               first, stop))


class _Envelope:
    """The segments of all traced curves stacked (in curve order), for their crossings
    at one log10 M*; restacked when curves are added."""

    def __init__(self, curves: list):
        self.curves, self._count, self._ends = curves, -1, None

    def _at(self, log_m: float):
        """Indices of the segments that cross log_m, and the interpolation weights."""
        if self._count != len(self.curves):
            parts = [c.segments for c in self.curves]
            self._ends = [np.concatenate([p[k][j] for p in parts]) for k in range(3) for j in (0, 1)]
            self._pieces = np.concatenate([c.pieces for c in self.curves])
            self._count = len(self.curves)
        a, b = self._ends[:2]
        i = np.flatnonzero(((a - log_m) * (b - log_m) <= 0) & (a != b))
        return i, (log_m - a[i]) / (b[i] - a[i])

    def crossings(self, log_m: float) -> tuple[np.ndarray, np.ndarray]:
        """U* and omega of every traced curve at log10 M* = log_m (linear interpolation)."""
        if not self.curves:
            return np.zeros(0), np.zeros(0)
        i, t = self._at(log_m)
        _, _, ua, ub, wa, wb = self._ends
        return ua[i] + t * (ub[i] - ua[i]), wa[i] + t * (wb[i] - wa[i])

    def lowest(self, log_m: float):
        """(U*, omega, piece) of the lowest crossing at log_m (the first of equal ones),
        or None."""
        u, w = self.crossings(log_m)
        if not u.size:
            return None
        k = int(np.argmin(u))
        return float(u[k]), float(w[k]), int(self._pieces[self._at(log_m)[0][k]])


def _envelope_check(envelope: _Envelope, headroom: float):
    """``check(ustar, log10_mstar)`` of one half of a curve: true (a message) when the
    half rises (U* increasing) above ``headroom`` times the lowest curve traced before at
    its M*. A stretch that high cannot be the lowest curve, like one above the ceiling."""
    last = []

    def check(u: float, log_m: float):
        rising, last[:] = bool(last) and u > last[0], [u]
        if not rising:
            return False
        us, _ = envelope.crossings(log_m)
        return bool(us.size) and u > headroom * us.min() and \
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


def _on_curve(curve: OnsetCurve, h: Onset, rtol: float = 2e-2) -> bool:
    """Does onset h lie on the traced curve (same kind, U* and frequency at its M*)?"""
    return curve.kind == h.kind and any(abs(u - h.ustar) <= rtol * h.ustar and abs(w - h.omega) <= rtol * h.omega
               for u, w, _ in curve.crossings(math.log10(h.mstar)))


def _boundary_point(scene, model, curves, mstar, refine) -> BoundaryPoint:
    log_m = math.log10(mstar)
    lowest = _Envelope(curves).lowest(log_m)
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
    point = replace(point, ustar_crit=h.ustar, omega=h.omega, freq_ratio=h.freq_ratio,
                    dominant_mode=h.dominant_mode, refined=True)
    if h.kind == "flutter":
        point = replace(point, l1=h.l1, criticality=h.criticality)
    return point


def _switches(curves, lo: float, hi: float) -> list[ModeSwitch]:
    """Every change of the lowest piece on [lo, hi] (log10 M*), scanned on a fine grid of
    the traced curves (no new solves) and bisected to round-off in log10 M*."""
    out, envelope = [], _Envelope(curves)
    grid = np.linspace(lo, hi, 801)
    lowest = [envelope.lowest(lm) for lm in grid]
    for k in range(len(grid) - 1):
        a, b = lowest[k], lowest[k + 1]
        if a is not None and b is not None and a[2] != b[2]:
            out += _cell_switches(envelope, a[2], b[2], grid[k], grid[k + 1])
    return out


def _cell_switches(envelope, piece: int, end: int, lo: float, hi: float) -> list[ModeSwitch]:
    """The switches inside one grid cell [lo, hi] from ``piece`` (lowest at lo) to
    ``end`` (lowest at hi), one after the other: a change to another trace of the same
    branch (two pieces overlapping: same U* and frequency) is no switch, but the cell is
    searched on from there."""
    out = []
    for _ in range(MAX_CELL_CHANGES):
        lo, hi_k = _switch_bracket(envelope, piece, lo, hi)
        ua, wa, _ = envelope.lowest(lo)
        ub, wb, above = envelope.lowest(hi_k)
        if abs(ua - ub) > 1e-2 * ub or abs(wa - wb) > 1e-2 * max(wa, wb):
            out.append(ModeSwitch(float(10 ** (0.5 * (lo + hi_k))), float(ua), float(ub),
                                  piece, above, float(wa), float(wb)))
        if above == end:
            break
        piece, lo = above, hi_k
    return out


#: Changes of the lowest piece searched inside one grid cell of the switch scan.
MAX_CELL_CHANGES = 8


def _switch_bracket(envelope, piece: int, lo: float, hi: float) -> tuple[float, float]:
    """Bisect [lo, hi] (``piece`` lowest at lo, not at hi) to where the lowest piece
    changes: a crossing of two Hopf curves, or the fold in M* that ends ``piece``."""
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        lowest = envelope.lowest(mid)
        if lowest is not None and lowest[2] == piece:
            lo = mid
        else:
            hi = mid
    return lo, hi

