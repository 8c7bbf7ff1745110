"""The stability boundary per branch: its stretches between the located mode switches.

Each stretch is the part of the boundary on which one branch of onsets (a Hopf branch:
flutter; a divergence branch) is the lowest. It runs through the traced curve's exact
points and the boundary's samples up to the :class:`~fsicas.linear.switches.ModeSwitch`
at each end, so no stretch joins two branches across a switch. Its dominant in-vacuo
mode is the most frequent one of its refined samples. The figures draw these stretches
(:mod:`fsicas.plots.linear`); :func:`boundary_function` reads U*_c(M*) off them and
:func:`marked_points` picks one sample per stretch (the points (a), (b), ... of Fig. 2).
"""
from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field
from string import ascii_lowercase

import numpy as np

from .boundary import BoundaryPoint, StabilityBoundary

__all__ = ["BranchLine", "branch_lines", "boundary_function", "marked_points", "onsets",
           "omega_1"]


@dataclass(frozen=True)
class BranchLine:
    """One stretch of the stability boundary on which ``branch`` is the lowest, of ``kind``
    "flutter" (a Hopf branch) or "divergence" (omega = 0):
    ``mstar``, ``ustar``, ``omega`` (rad per unit T) along it, ordered by M*, ending at the
    located switches (``start``/``end``: the :class:`~fsicas.linear.switches.ModeSwitch`
    at each end, None at the ends of the sampled range). ``samples``: the boundary points
    on it; ``mode``: its dominant in-vacuo mode (None if unknown)."""

    branch: int
    mode: int | None
    mstar: np.ndarray
    ustar: np.ndarray
    omega: np.ndarray
    samples: list = field(default_factory=list)
    start: object = None
    end: object = None
    kind: str = "flutter"


def onsets(boundary: StabilityBoundary) -> list[BoundaryPoint]:
    """The boundary's points where a curve was found, in order of M*."""
    return sorted((p for p in boundary.points if p.ustar_crit is not None),
                  key=lambda p: p.mstar)


def _stretches(boundary, pts):
    """(lo, hi, branch, start switch, end switch) of each stretch, in M* order."""
    inside = [s for s in sorted(boundary.switches, key=lambda s: s.mstar)
              if pts[0].mstar < s.mstar < pts[-1].mstar]
    if not inside:       # no switch located: split where the samples' branch changes
        out, first = [], 0
        for k in range(1, len(pts) + 1):
            if k == len(pts) or pts[k].branch != pts[first].branch:
                out.append((pts[first].mstar, pts[k - 1].mstar, pts[first].branch, None, None))
                first = k
        return out
    edges = [None, *inside, None]
    out = []
    for start, end in zip(edges[:-1], edges[1:]):
        lo = start.mstar if start else pts[0].mstar
        hi = end.mstar if end else pts[-1].mstar
        out.append((lo, hi, start.branch_above if start else end.branch_below, start, end))
    return out


def _lowest_on_curves(boundary, lo: float, hi: float, pieces: set) -> np.ndarray:
    """(M*, U*, omega) rows of the lowest of the traced ``pieces`` at every traced curve
    point strictly inside (lo, hi) (linear between the curves' exact Hopf points, as the
    boundary is defined). Only the stretch's own pieces: next to a located switch the
    interpolated curves may already have changed places."""
    grid = np.unique(np.concatenate([c.mstar for c in boundary.curves] + [np.zeros(0)]))
    rows = []
    for m in grid[(grid > lo) & (grid < hi)]:
        found = [x for c in boundary.curves for x in c.crossings(math.log10(m)) if x[2] in pieces]
        if found:
            u, w, _ = min(found, key=lambda c: abs(c[0]))
            rows.append((m, u, w))
    return np.array(rows).reshape(-1, 3)


def _stretch_mode(boundary, pieces: set, samples: list) -> int | None:
    """The most frequent dominant mode of the stretch's refined samples, else of the
    traced curve points on its pieces (0: unknown)."""
    modes = [p.dominant_mode for p in samples if p.dominant_mode]
    if not modes:
        for c in boundary.curves:
            seg = np.flatnonzero(np.isin(c.pieces, list(pieces)))
            modes += [int(m) for m in c.dominant_mode[seg] if m > 0]
    return Counter(modes).most_common(1)[0][0] if modes else None


def branch_lines(boundary: StabilityBoundary) -> list[BranchLine]:
    """The boundary as stretches of one branch each, up to their switches.

    Inside a stretch the line is the lowest of its pieces: the switches' branch and those
    of its samples (several traced pieces of one branch, which the boundary does not count
    as a switch, make one line)."""
    pts = onsets(boundary)
    if not pts:
        return []
    lines = []
    for lo, hi, branch, start, end in _stretches(boundary, pts):
        samples = [p for p in pts if lo <= p.mstar <= hi]
        pieces = {branch} | {p.branch for p in samples}
        dense = _lowest_on_curves(boundary, lo, hi, pieces)
        rows = [dense, np.array([[p.mstar, p.ustar_crit, p.omega] for p in samples])
                .reshape(-1, 3)]
        if start is not None:
            rows.insert(0, np.array([[start.mstar, start.ustar_above, start.omega_above]]))
        if end is not None:
            rows.append(np.array([[end.mstar, end.ustar_below, end.omega_below]]))
        rows = np.concatenate(rows)
        if not len(rows):
            continue
        rows = rows[np.argsort(rows[:, 0], kind="stable")]
        mode = _stretch_mode(boundary, pieces, samples)
        kind = next((c.kind for c in boundary.curves if branch in set(c.pieces.tolist())),
                    "flutter")
        lines.append(BranchLine(int(branch), mode, rows[:, 0], rows[:, 1], rows[:, 2], samples,
                                start, end, kind))
    return lines


def boundary_function(boundary: StabilityBoundary):
    """``U*_c(M*)`` along the stretches (linear in log M* between their points); None
    for a boundary without points."""
    lines = branch_lines(boundary)
    if not lines:
        return None
    rows = np.concatenate([np.c_[line.mstar, line.ustar] for line in lines])
    rows = rows[np.argsort(rows[:, 0], kind="stable")]
    return lambda m: np.interp(np.log(m), np.log(rows[:, 0]), rows[:, 1])


def marked_points(boundary: StabilityBoundary) -> list[tuple[str, BranchLine, BoundaryPoint]]:
    """(letter, stretch, point) for the sample nearest the middle (in log M*) of each
    stretch with samples: the points (a), (b), ... of Fig. 2 whose shapes Fig. 3 shows."""
    out = []
    for line in branch_lines(boundary):
        if not line.samples:
            continue
        mid = 0.5 * (math.log10(line.mstar[0]) + math.log10(line.mstar[-1]))
        p = min(line.samples, key=lambda q: abs(math.log10(q.mstar) - mid))
        k = len(out)
        letter = ascii_lowercase[k] if k < 26 else f"a{k}"
        out.append((letter, line, p))
    return out


def omega_1(boundary: StabilityBoundary) -> float:
    """omega_1 from a flutter point of the boundary (1 if it has none)."""
    p = next((p for p in boundary.points if p.ustar_crit is not None and p.freq_ratio), None)
    return p.omega / p.freq_ratio if p else 1.0
