"""Figures of the linear analysis (paper Figs. 2 and 3), the eigenvalue map and the
boundary variants.

The stability boundary is drawn branch by branch (:func:`branch_lines`): each stretch on
which one branch of onsets is the lowest (a Hopf branch: flutter, solid; a divergence
branch: dashed) runs through the traced curve's points and the
boundary samples up to the located mode switches at its ends, so no line joins two
branches across a switch; at a fold in M* the jump of U*_c is a dotted connector. A
branch's colour is that of its dominant in-vacuo mode (the same mode, the same colour,
in every figure), and the points (a), (b), ... marked on Fig. 2 are those whose mode
shapes Fig. 3 shows.
"""
from __future__ import annotations

import itertools

import math
from collections import Counter
from dataclasses import dataclass, field
from string import ascii_lowercase

import numpy as np

from ..linear.boundary import StabilityBoundary
from ..linear.stability import linear_stability
from ..model.assembly import Model
from .backend import NONDIM, PALETTE, finish, styled, subplots

__all__ = ["BranchLine", "branch_lines", "draw_boundary", "boundary_function", "marked_points", "mode_color", "plot_boundary",
           "plot_mode_shapes", "plot_eigenvalues", "plot_boundary_variants"]

MSTAR = f"mass ratio $M^*$ {NONDIM}"
USTAR_C = f"critical velocity $U^*_c$ {NONDIM}"
RATIO = fr"frequency $\omega/\omega_1$ {NONDIM}"
#: Grey of the traced Hopf curves and of the connectors at folds.
CURVE_GREY, LINK_GREY = "0.82", "0.35"
#: The legend's words for the dotted jump of U*_c where the boundary switches branch.
SWITCH_WORDS = "jump of $U^*_c$ at a branch switch"


@dataclass(frozen=True)
class BranchLine:
    """One stretch of the stability boundary on which ``branch`` is the lowest, of ``kind``
    "flutter" (a Hopf branch) or "divergence" (omega = 0):
    ``mstar``, ``ustar``, ``omega`` (rad per unit T) along it, ordered by M*, ending at the
    located switches (``start``/``end``: the :class:`~fsicas.linear.boundary.ModeSwitch`
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


def _onsets(boundary: StabilityBoundary) -> list:
    return sorted((p for p in boundary.points if p["ustar_crit"] is not None),
                  key=lambda p: p["mstar"])


def _stretches(boundary, pts):
    """(lo, hi, branch, start switch, end switch) of each stretch, in M* order."""
    inside = [s for s in sorted(boundary.switches, key=lambda s: s.mstar)
              if pts[0]["mstar"] < s.mstar < pts[-1]["mstar"]]
    if not inside:       # no switch located: split where the samples' branch changes
        out, first = [], 0
        for k in range(1, len(pts) + 1):
            if k == len(pts) or pts[k]["branch"] != pts[first]["branch"]:
                out.append((pts[first]["mstar"], pts[k - 1]["mstar"], pts[first]["branch"],
                            None, None))
                first = k
        return out
    edges = [None, *inside, None]
    out = []
    for start, end in zip(edges[:-1], edges[1:]):
        lo = start.mstar if start else pts[0]["mstar"]
        hi = end.mstar if end else pts[-1]["mstar"]
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
            u, w, _ = min(found)
            rows.append((m, u, w))
    return np.array(rows).reshape(-1, 3)


def _stretch_mode(boundary, pieces: set, samples: list) -> int | None:
    """The most frequent dominant mode of the stretch's refined samples, else of the
    traced curve points on its pieces (0: unknown)."""
    modes = [p["dominant_mode"] for p in samples if p.get("dominant_mode")]
    if not modes:
        for c in boundary.curves:
            seg = np.flatnonzero(np.isin(c.pieces, list(pieces)))
            modes += [int(m) for m in c.dominant_mode[seg] if m > 0]
    return Counter(modes).most_common(1)[0][0] if modes else None


def branch_lines(boundary: StabilityBoundary) -> list[BranchLine]:
    """The boundary as stretches of one branch each, drawn up to their switches.

    Inside a stretch the line is the lowest of its pieces: the switches' branch and those
    of its samples (several traced pieces of one branch, which the boundary does not count
    as a switch, make one line)."""
    pts = _onsets(boundary)
    if not pts:
        return []
    lines = []
    for lo, hi, branch, start, end in _stretches(boundary, pts):
        samples = [p for p in pts if lo <= p["mstar"] <= hi]
        pieces = {branch} | {p["branch"] for p in samples}
        dense = _lowest_on_curves(boundary, lo, hi, pieces)
        rows = [dense, np.array([[p["mstar"], p["ustar_crit"], p["omega"]] for p in samples])
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


def draw_boundary(ax, boundary: StabilityBoundary) -> None:
    """The boundary's stretches (U* across, M* up), each up to its switches; the jumps at
    the switches dotted."""
    for k, line in enumerate(branch_lines(boundary)):
        ax.plot(line.ustar, line.mstar, color="k", lw=1.5, zorder=2, gid=f"branch {line.branch}",
                label="linear stability boundary" if k == 0 else None)
    for k, s in enumerate(boundary.switches):
        ax.plot([s.ustar_below, s.ustar_above], [s.mstar] * 2, ":", color=LINK_GREY, lw=0.9,
                label=SWITCH_WORDS if k == 0 else None, gid="mode switch")


def boundary_function(boundary: StabilityBoundary):
    """``U*_c(M*)`` of the drawn boundary (linear in log M* between its points); None
    for a boundary without points."""
    lines = branch_lines(boundary)
    if not lines:
        return None
    rows = np.concatenate([np.c_[line.mstar, line.ustar] for line in lines])
    rows = rows[np.argsort(rows[:, 0], kind="stable")]
    return lambda m: np.interp(np.log(m), np.log(rows[:, 0]), rows[:, 1])


def marked_points(boundary: StabilityBoundary) -> list[tuple[str, BranchLine, dict]]:
    """(letter, stretch, point) for the sample nearest the middle (in log M*) of each
    stretch with samples: the points (a), (b), ... of Fig. 2 whose shapes Fig. 3 shows."""
    out = []
    for line in branch_lines(boundary):
        if not line.samples:
            continue
        mid = 0.5 * (math.log10(line.mstar[0]) + math.log10(line.mstar[-1]))
        p = min(line.samples, key=lambda q: abs(math.log10(q["mstar"]) - mid))
        k = len(out)
        letter = ascii_lowercase[k] if k < 26 else f"a{k}"
        out.append((letter, line, p))
    return out


def mode_color(mode: int | None, fallback: int = 0) -> str:
    """The colour of in-vacuo mode ``mode`` (1-based), the same in every figure."""
    return PALETTE[((mode or fallback + 1) - 1) % len(PALETTE)]


def _omega_1(boundary) -> float:
    """omega_1 from a flutter point of the boundary (1 if it has none)."""
    p = next((p for p in boundary.points if p["ustar_crit"] is not None and p["freq_ratio"]),
             None)
    return p["omega"] / p["freq_ratio"] if p else 1.0


def _scene_words(scene) -> str:
    zeta = f"{scene.zeta:g}" if np.isscalar(scene.zeta) else "per mode"
    return (fr"$H^*$ = {scene.hstar:g}, $f$ = {scene.friction:g}, $\zeta$ = {zeta}, "
            f"$N$ = {scene.modes}")


@styled
def plot_boundary(boundary: StabilityBoundary, path=None):
    """Fig. 2: the critical velocity U*_c(M*) over all traced curves of onsets (left;
    Hopf curves solid, divergence curves dashed), the frequency at onset omega / omega_1
    (middle; 0 for divergence), both drawn per branch up to the mode switches and
    coloured by the dominant mode, and the first Lyapunov coefficient l1
    along the boundary (right; > 0: subcritical). Returns the Figure."""
    fig, axes = subplots(1, 3, figsize=(7.6, 2.7))
    left, mid, crit = axes[0]
    lines = branch_lines(boundary)
    _onset_panels(left, mid, boundary, lines)
    _criticality_panel(crit, _onsets(boundary))
    u = np.concatenate([line.ustar for line in lines]) if lines else np.ones(1)
    left.set(xscale="log", xlabel=MSTAR, ylabel=USTAR_C, ylim=(0, 1.25 * u.max()),
             title="stability boundary")
    mid.set(xscale="log", xlabel=MSTAR, ylabel=RATIO, title="frequency at onset")
    fig.legend(*_legend_entries(left), loc="outside right upper")
    fig.suptitle(_scene_words(boundary.scene))
    return finish(fig, path)


def _legend_entries(ax):
    """Handles and labels of ``ax`` once per label, modes first in mode order."""
    seen = {}
    for h, label in zip(*ax.get_legend_handles_labels()):
        seen.setdefault(label, h)
    key = lambda label: (0, int(label.split()[1])) if label.startswith("mode ") else (1, 0)
    labels = sorted(seen, key=key)
    return [seen[k] for k in labels], labels


def _onset_panels(left, mid, boundary: StabilityBoundary, lines: list[BranchLine]) -> None:
    """U*_c (over the grey Hopf curves) and omega / omega_1 against M*, one line per
    stretch, samples as dots, folds' jumps dotted, the marked points lettered,
    subcritical points crossed."""
    for kind, style, words in (("flutter", "-", "traced Hopf curves"),
                               ("divergence", "--", "traced divergence curves")):
        for k, c in enumerate(c for c in boundary.curves if c.kind == kind):
            left.plot(c.mstar, c.ustar, style, color=CURVE_GREY, lw=0.6, zorder=1,
                      label=words if k == 0 else None)
    w1 = _omega_1(boundary)
    for k, line in enumerate(lines):
        color = mode_color(line.mode, k)
        label = f"mode {line.mode}" if line.mode else f"branch {line.branch}"
        style = "--" if line.kind == "divergence" else "-"
        for ax, y in ((left, line.ustar), (mid, line.omega / w1)):
            ax.plot(line.mstar, y, style, color=color, lw=1.5, label=label,
                    gid=f"branch {line.branch}")
            m = [p["mstar"] for p in line.samples]
            s = [p["ustar_crit"] if ax is left else p["freq_ratio"] for p in line.samples]
            ax.plot(m, s, "o", ms=2.2, color=color, zorder=3)
    for k, s in enumerate(boundary.switches):
        left.plot([s.mstar] * 2, [s.ustar_below, s.ustar_above], ":", color=LINK_GREY, lw=0.8,
                  label=SWITCH_WORDS if k == 0 else None, gid="mode switch")
        mid.plot([s.mstar] * 2, [s.omega_below / w1, s.omega_above / w1], ":", color=LINK_GREY,
                 lw=0.8)
    for letter, line, p in marked_points(boundary):
        left.plot(p["mstar"], p["ustar_crit"], "o", ms=6, mfc="none", mec="k", mew=0.8, zorder=4)
        left.annotate(f"({letter})", (p["mstar"], p["ustar_crit"]), xytext=(0, -7),
                      textcoords="offset points", ha="center", va="top", fontsize=8)
    sub = [p for p in _onsets(boundary) if p.get("criticality") == "subcritical"]
    if sub:
        left.plot([p["mstar"] for p in sub], [p["ustar_crit"] for p in sub], "x", color="k",
                  ms=4, mew=0.8, zorder=5, label=r"subcritical ($\ell_1 > 0$)")


def _criticality_panel(ax, pts: list) -> None:
    """The first Lyapunov coefficient l1 along the boundary (symlog), one line per
    stretch of one branch (l1 jumps where the boundary switches branch: not joined)."""
    with_l1 = [p for p in pts if p.get("l1") is not None]
    for _, stretch in itertools.groupby(with_l1, key=lambda p: p.get("branch")):
        stretch = list(stretch)
        ax.plot([p["mstar"] for p in stretch], [p["l1"] for p in stretch], ".-", color="k",
                lw=0.8, ms=3)
    if with_l1:
        ax.set_yscale("symlog", linthresh=1e-3)
        ax.axhline(0.0, color="0.5", lw=0.6)
    ax.set(xscale="log", xlabel=MSTAR, ylabel=fr"first Lyapunov coeff. $\ell_1$ {NONDIM}",
           title=r"criticality ($\ell_1 > 0$: subcritical)")


@styled
def plot_mode_shapes(boundary: StabilityBoundary, model: Model, path=None, columns: int = 4):
    """Fig. 3: the complex mode shape at each point (a), (b), ... marked on Fig. 2 (one
    per stretch of the boundary), on a grid of ``columns`` panels a row: real part blue,
    imaginary part red, the beam's motion through a cycle grey. Returns the Figure."""
    marks = marked_points(boundary)
    ncols = max(1, min(columns, len(marks)))
    nrows = max(1, math.ceil(len(marks) / ncols))
    fig, axes = subplots(nrows, ncols, figsize=(1.85 * ncols + 0.4, 1.75 * nrows + 0.5),
                         sharex=True, sharey=True)
    for ax, (letter, line, p) in zip(axes.flat, marks):
        _mode_shape_panel(ax, boundary, model, p)
        mode = f", mode {line.mode}" if line.mode else ""
        ax.set_title(f"({letter}) $M^*$ = {p['mstar']:.3g}{mode}\n$U^*_c$ = {p['ustar_crit']:.3g}",
                     fontsize=8)
    for ax in axes.flat[len(marks):]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("position $x/L$")
    for k in range(len(marks), nrows * ncols):   # a bottom panel left empty: label above it
        axes[k // ncols - 1][k % ncols].xaxis.set_tick_params(labelbottom=True)
        axes[k // ncols - 1][k % ncols].set_xlabel("position $x/L$")
    for row in axes:
        row[0].set_ylabel(fr"$y/\max|y|$ {NONDIM}")
    axes[0][0].set(ylim=(-1.15, 1.15), xlim=(0, 1))
    fig.legend(*axes[0][0].get_legend_handles_labels(), loc="outside lower center", ncols=3)
    fig.suptitle(f"complex mode shapes at the marked points of Fig. 2 ({_scene_words(boundary.scene)})")
    return finish(fig, path)


def _mode_shape_panel(ax, boundary, model, p) -> None:
    """Re, Im and the motion of the neutral mode of the Hopf point ``p``."""
    scene = boundary.scene.replace(mstar=p["mstar"], ustar=p["ustar_crit"])
    analysis = linear_stability(scene, model)
    k = int(np.argmin(np.abs(analysis.eigenvalues - 1j * p["omega"])))
    shape = analysis.mode_shape(model, k)
    for j, phase in enumerate(np.linspace(0, 2 * np.pi, 12, endpoint=False)):
        ax.plot(shape["x"], (shape["y"] * np.exp(1j * phase)).real, color=CURVE_GREY, lw=0.6,
                label="motion" if j == 0 else None)
    ax.plot(shape["x"], shape["y"].real, color=PALETTE[0], label="real part")
    ax.plot(shape["x"], shape["y"].imag, color=PALETTE[1], label="imaginary part")
    ax.axhline(0.0, color="k", lw=0.4)


@styled
def plot_eigenvalues(result, scene, path=None):
    """Eigenvalue map of a linear stability analysis: frequency Im(lambda) against growth
    rate Re(lambda); unstable eigenvalues (Re > 0) highlighted. Returns the Figure."""
    fig, axes = subplots(figsize=(4.2, 3.4))
    ax = axes[0][0]
    growth, omega = np.asarray(result.growth_rate), np.asarray(result.omega)
    unstable = growth > 0
    ax.plot(growth[~unstable], omega[~unstable], "o", ms=3.5, color=PALETTE[0], label="stable")
    if unstable.any():
        ax.plot(growth[unstable], omega[unstable], "o", ms=4.5, color=PALETTE[1], label="unstable")
    ax.axvline(0, color="k", lw=0.6)
    ax.set(xlabel=r"growth rate $\mathrm{Re}\,\lambda$ (units of $1/T$)",
           ylabel=r"frequency $\mathrm{Im}\,\lambda$ (rad per unit $T$)",
           title=f"$M^*$ = {scene.mstar:g}, $U^*$ = {scene.ustar:g}, $N$ = {scene.modes}")
    ax.legend(loc="upper right")       # moved off the data if it covers any
    return finish(fig, path)


def _math(label: str) -> str:
    """A plain-text label with its symbols in mathtext (``zeta`` -> zeta, ``H*`` -> H^*)."""
    return label.replace("zeta", r"$\zeta$").replace("H*", "$H^*$")


@styled
def plot_boundary_variants(curves: dict, path=None):
    """Several flutter boundaries on one figure, labelled by the keys of ``curves``
    (label -> :class:`StabilityBoundary`): U*_c and omega / omega_1 against M*, each drawn
    per branch and broken at its mode switches (folds' jumps dotted). Returns the Figure."""
    fig, axes = subplots(1, 2, figsize=(7.0, 2.8))
    left, right = axes[0]
    for k, (label, boundary) in enumerate(curves.items()):
        color, lines = PALETTE[k % len(PALETTE)], branch_lines(boundary)
        w1 = _omega_1(boundary)
        for j, line in enumerate(lines):
            for ax, y in ((left, line.ustar), (right, line.omega / w1)):
                ax.plot(line.mstar, y, "--" if line.kind == "divergence" else "-", color=color, label=_math(label) if j == 0 else None,
                        gid=f"{label}: branch {line.branch}")
                ax.plot([p["mstar"] for p in line.samples],
                        [(p["ustar_crit"] if ax is left else p["freq_ratio"]) for p in line.samples],
                        "o", ms=2, color=color)
        for s in boundary.switches:
            left.plot([s.mstar] * 2, [s.ustar_below, s.ustar_above], ":", color=color, lw=0.7)
            right.plot([s.mstar] * 2, [s.omega_below / w1, s.omega_above / w1], ":", color=color,
                       lw=0.7)
    left.set(xscale="log", xlabel=MSTAR, ylabel=USTAR_C, ylim=(0, None),
             title="effect of damping and confinement")
    right.set(xscale="log", xlabel=MSTAR, ylabel=RATIO, title="frequency at onset")
    fig.legend(*left.get_legend_handles_labels(), loc="outside right upper")
    return finish(fig, path)
