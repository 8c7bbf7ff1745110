"""Figures of limit-cycle branches (collocation continuation, docs/cycles.md)."""
from __future__ import annotations

import numpy as np

from ..cycles.curves import lowest_ustar
from ..linear.stretches import boundary_function
from .backend import NONDIM, PALETTE, finish, styled, subplots, suptitle
from .linear import draw_boundary

__all__ = ["plot_branch", "plot_curves", "draw_curves", "mark_cases"]

#: Line style of each kind of curve of cycles in the (U*, M*) plane.
_CURVE_STYLE = {"grazing": dict(color=PALETTE[5], ls="--", label="grazing (first contact)"),
                "fold": dict(color=PALETTE[1], ls="-.", label="fold of cycles")}

#: Marker and words of each reason a curve's end stopped (:meth:`CycleCurve.ends`).
_END_MARKS = {"mstar_window": ("h", "end: edge of the $M^*$ window"),
              "ustar_bound": (">", "end: the $U^*$ limit of the map"),
              "bound": ("h", "end: a bound of the continuation"),
              "budget": ("X", "end: point budget used up (unfinished)"),
              "wall": ("o", "end: its cycles reach the wall"),
              "hopf": ("v", "end: its cycles shrink onto the Hopf curve"),
              "failed": ("x", "end: solver failure"),
              "stopped": ("D", "end: stopped")}

_PANELS = (("tip_amplitude", f"tip half-amplitude $A/L$ {NONDIM}"),
           ("period", "period (units of $T$)"))


@styled
def plot_branch(branch, path=None):
    """Tip half-amplitude and period against U*: stable solid, unstable dashed; folds
    (triangles), the first contact (star) and the Hopf point (grey line). Returns the
    Figure."""
    fig, axes = subplots(1, 2, figsize=(6.8, 2.8))
    for ax, (name, label) in zip(axes[0], _PANELS):
        _branch_panel(ax, branch, name)
        ax.set(xlabel=f"flow velocity $U^*$ {NONDIM}", ylabel=label)
    s = branch.scene
    zeta = f"{s.zeta:g}" if np.isscalar(s.zeta) else "per mode"
    suptitle(fig, fr"limit cycles at $M^*$ = {s.mstar:g}, $N$ = {s.modes}, $\zeta$ = {zeta}: "
                 + _ENDS[branch.status])
    handles, labels = axes[0][0].get_legend_handles_labels()
    if handles:
        fig.legend(handles, labels, loc="outside right upper")
    return finish(fig, path)


#: How a cycle branch ended, in words (:data:`fsicas.cycles.collocation.CycleStatus`).
_ENDS = {"contact": "up to the first wall contact", "bound": "up to the U* bound",
         "max_points": "stopped at its point budget", "failed": "stopped by a solver failure"}


def _branch_panel(ax, branch, name: str) -> None:
    """One column of the branch against U*, with its folds, first contact and onset."""
    u, stable, y = branch.column("ustar"), branch.column("stable"), branch.column(name)
    for flag, style, label in ((True, "-", "stable"), (False, "--", "unstable")):
        ax.plot(u, np.where(stable == flag, y, np.nan), "k" + style, lw=1.2, label=label)
    for k, p in enumerate(branch.folds):
        ax.plot(p.ustar, getattr(p, name), "v", color=PALETTE[0],
                label="fold" if k == 0 else None)
    if branch.contact is not None:
        ax.plot(branch.contact.ustar, getattr(branch.contact, name), "*", ms=9, color=PALETTE[1],
                label="first wall contact")
    ax.axvline(branch.hopf["ustar_crit"], color="0.6", lw=0.8, label="Hopf point")


def draw_curves(ax, curves, hopf=None) -> None:
    """The grazing and fold-of-cycles curves of a :class:`fsicas.cycles.curves.CurveMap`
    (U* across, M* up) and, given ``hopf(mstar) -> U*_c`` (the flutter boundary), the
    band of contact-free cycles shaded grey: at each M*, from U*_c to the lowest grazing
    curve above it."""
    for kind in ("grazing", "fold"):
        for k, curve in enumerate(getattr(curves, kind)):
            style = dict(_CURVE_STYLE[kind])
            label = style.pop("label")
            ax.plot(curve.column("ustar"), curve.column("mstar"), lw=1.4,
                    label=label if k == 0 else None, zorder=2, **style)
    _curve_ends(ax, curves)
    grazing = [p.mstar for c in curves.grazing for p in c.points]
    if hopf is None or not grazing:
        return
    m = np.geomspace(min(grazing), max(grazing), 400)
    critical = hopf(m)
    ceiling = lowest_ustar(curves.grazing, m, floor=critical)
    ax.fill_betweenx(m, critical, ceiling, where=np.isfinite(ceiling), color="0.85", zorder=0,
                     lw=0, label="contact-free cycles")


def _curve_ends(ax, curves) -> None:
    """A marker at each end of each curve, its shape saying why the curve stopped there
    (:data:`_END_MARKS`), each reason once in the legend."""
    ends = {}
    for curve in [*curves.grazing, *curves.fold]:
        for point, reason in curve.ends():
            ends.setdefault(reason, []).append((point.ustar, point.mstar))
    for reason, points in ends.items():
        marker, words = _END_MARKS[reason]
        u, m = np.array(points).T
        ax.plot(u, m, marker, ls="none", ms=5, mfc="white", mec="k", mew=0.9, zorder=2.5,
                label=words, gid=f"curve end: {reason}")      # under the map's points


def draw_switched(ax, switched, labelled_fold: bool = True) -> None:
    """The fold-of-cycles curves started at generalized Hopf points (``switched``:
    :class:`fsicas.cycles.bautin.SwitchedCurve` of kind 'gh'), in the fold curves' style
    (labelled unless ``labelled_fold`` says the fold curves already are), and each point
    where l1 changes sign on the boundary."""
    style = dict(_CURVE_STYLE["fold"])
    label = style.pop("label")
    for k, item in enumerate(switched):
        curve = item.curve
        ax.plot(curve.column("ustar"), curve.column("mstar"), lw=1.4, zorder=2,
                label=label if k == 0 and not labelled_fold else None, **style)
        ax.plot(item.point.ustar, item.point.mstar, "P", ms=8, mfc=PALETTE[1], mec="k",
                mew=0.8, zorder=3.5, label="generalized Hopf: $l_1$ = 0, a fold curve is born"
                if k == 0 else None)


def mark_cases(ax, cases) -> None:
    """The marked cases ``[(label, U*, M*)]`` (e.g. the paper's (1a)-(1c)): star and label."""
    for k, (label, ustar, mstar) in enumerate(cases):
        ax.plot(ustar, mstar, "*", color="k", ms=9, zorder=4,
                label="cases of Figs. 6-9" if k == 0 else None)
        ax.annotate(label, (ustar, mstar), textcoords="offset points", xytext=(4, 5),
                    fontsize=8)


@styled
def plot_curves(curves, boundary=None, path=None):
    """The (U*, M*) plane: the flutter boundary (``boundary``: a StabilityBoundary),
    the grazing and fold-of-cycles curves, the contact-free band shaded. Returns the
    Figure."""
    fig, axes = subplots(figsize=(6.4, 3.9))
    ax = axes[0][0]
    hopf = None
    if boundary is not None:
        draw_boundary(ax, boundary)
        hopf = boundary_function(boundary)
    draw_curves(ax, curves, hopf)
    ax.set(yscale="log", xlabel=f"flow velocity $U^*$ {NONDIM}",
           ylabel=f"mass ratio $M^*$ {NONDIM}")
    fig.legend(*ax.get_legend_handles_labels(), loc="outside right upper")
    return finish(fig, path)
