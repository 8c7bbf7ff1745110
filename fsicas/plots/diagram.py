"""Figures of bifurcation diagrams (``fsicas diagram``, docs/cli.md)."""
from __future__ import annotations

import numpy as np

from .backend import NONDIM, PALETTE, finish, styled, subplots
from .linear import draw_boundary

__all__ = ["plot_scene_diagram", "plot_window_diagram", "MEASURES"]

#: The measures a diagram can be drawn in: branch field -> axis label.
MEASURES = {"tip": f"tip: deflection (steady), half-amplitude (cycles) {NONDIM}",
            "period": "cycle period (units of $T$)"}


@styled
def plot_scene_diagram(result, path=None, measure: str = "tip"):
    """Every branch of a :class:`fsicas.cycles.diagram.SceneDiagram` against U*, one colour
    per branch, solid where stable and dashed where not, its special points marked and
    labelled (H Hopf, BP branch point, LP fold, PD period doubling, NS torus, C first
    contact of the cycles). ``measure``: 'tip' or 'period' (cycles only). Returns the
    Figure."""
    if measure not in MEASURES:
        raise ValueError(f"measure must be one of {sorted(MEASURES)}, got {measure!r}")
    fig, axes = subplots(figsize=(6.4, 3.9))
    ax = axes[0][0]
    for i, branch in enumerate(result.branches):
        values = branch.period if measure == "period" else branch.tip
        if values is None:
            continue
        color = PALETTE[i % len(PALETTE)]
        _stability_runs(ax, branch.ustar, values, branch.stable, color,
                        f"{i}: {branch.kind}" + ("" if branch.parent is None else
                                                 f" from {branch.born} on {branch.parent}"))
        if measure == "tip":
            _special_marks(ax, branch, color)
    ax.set(xlabel=f"flow velocity $U^*$ {NONDIM}", ylabel=MEASURES[measure])
    fig.legend(*ax.get_legend_handles_labels(), loc="outside right upper")
    return finish(fig, path)


def _stability_runs(ax, x, y, stable, color, label) -> None:
    """Solid where ``stable``, dashed where not; consecutive runs share their end point."""
    start = 0
    for i in range(1, len(x) + 1):
        if i == len(x) or stable[i] != stable[start]:
            stop = min(i + 1, len(x))
            ax.plot(x[start:stop], y[start:stop], "-" if stable[start] else "--",
                    color=color, label=label if start == 0 else None)
            start = i


def _special_marks(ax, branch, color) -> None:
    for point in branch.special:
        if point["tip"] is None or not np.isfinite(point["tip"]):
            continue
        ax.plot([point["ustar"]], [point["tip"]], "o", color=color, markeredgecolor="k",
                markersize=4)
        ax.annotate(point["label"], (point["ustar"], point["tip"]), textcoords="offset points",
                    xytext=(3, 3), fontsize=7)


@styled
def plot_window_diagram(result, path=None):
    """The (U*, M*) plane of a :class:`fsicas.cycles.window.WindowDiagram`: the onset
    curves and the stability boundary, the onsets (flutter dots, divergence squares), the codimension-two points
    labelled (GH, HH; filled where on the boundary) and the curves switched onto from
    them. Returns the Figure."""
    fig, axes = subplots(figsize=(6.4, 3.9))
    ax = axes[0][0]
    for k, curve in enumerate(result.boundary.curves):
        ax.plot(curve.ustar, curve.mstar, color="0.6", lw=0.8, zorder=1,
                label="onset curves (Hopf, divergence)" if k == 0 else None)
    draw_boundary(ax, result.boundary)
    for kind, marker in (("flutter", "o"), ("divergence", "s")):
        on = [o for o in result.onsets if o["kind"] == kind]
        if on:
            ax.plot([o["ustar"] for o in on], [o["mstar"] for o in on], marker, color=PALETTE[0],
                    markersize=3, ls="none", label=f"{kind} onset")
    for i, switched in enumerate(result.curves):
        points = switched.curve.points
        ax.plot([p.ustar for p in points], [p.mstar for p in points], "-.",
                color=PALETTE[(i + 1) % len(PALETTE)],
                label=f"{'fold of cycles' if switched.curve.kind == 'fold' else 'torus'} "
                      f"from {switched.point.kind.upper()} (M* = {switched.point.mstar:.3g})")
    for point in result.points:
        ax.plot([point.ustar], [point.mstar], "D", color="k",
                markerfacecolor="k" if point.on_boundary else "none", markersize=5)
        ax.annotate(point.kind.upper(), (point.ustar, point.mstar), textcoords="offset points",
                    xytext=(4, 4), fontsize=7)
    ax.set(yscale="log", xlabel=f"flow velocity $U^*$ {NONDIM}",
           ylabel=f"mass ratio $M^*$ {NONDIM}")
    if ax.get_legend_handles_labels()[0]:
        fig.legend(*ax.get_legend_handles_labels(), loc="outside right upper")
    return finish(fig, path)
