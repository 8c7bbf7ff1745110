"""Figures of time integrations: a run, the impact map, impacting cycles.

- :func:`plot_run`: tip displacement, flow rates and impact force against time.
- :func:`plot_map`: Fig. 4, outcomes on the (U*, M*) grid with the linear boundary.
- :func:`plot_cycle`, :func:`plot_cycles` (from :mod:`fsicas.plots.impacting`): Figs. 6–9
  of one settled cycle, or of several cases side by side.
"""
from __future__ import annotations

import numpy as np

from ..linear.stretches import boundary_function, branch_lines
from ..model.contact import reference_force
from ..model.patch import penetration
from .backend import NONDIM, PALETTE, finish, outcome_words, probe_label, styled, subplots
from .impacting import cycle_view, cycle_window, plot_cycle, plot_cycles, return_period
from .cycles import draw_curves, draw_switched, mark_cases
from .linear import draw_boundary

__all__ = ["plot_run", "plot_map", "plot_cycle", "plot_cycles", "cycle_view", "cycle_window",
           "return_period"]

#: Colour and marker of each outcome on the map (Okabe–Ito; the paper's limit cycles
#: orange, contact blue).
_MARKERS = {"decay": (PALETTE[2], "o"), "lco": (PALETTE[4], "o"), "contact": (PALETTE[0], "s"),
            "impacting_lco": (PALETTE[3], "D"), "impacting_nonperiodic": (PALETTE[5], "D"),
            "unsettled": ("0.55", "^"), "error": ("k", "x")}
#: Neighbouring boundary samples whose frequencies differ by more than this factor lie on
#: two branches: their line is broken there.
_FREQUENCY_JUMP = 1.25


@styled
def plot_run(run, path=None):
    """Tip displacement / (H*/2), flow rates and impact force / F0 against time. Returns
    the Figure."""
    tr, model = run.trajectory, run.model
    fig, axes = subplots(3, 1, figsize=(6.0, 5.6), sharex=True)
    ax = axes[:, 0]
    ax[0].plot(tr.t, tr.tip / (model.scene.hstar / 2), lw=0.7)
    for y in (-1.0, 1.0):
        ax[0].axhline(y, color="k", ls="--", lw=0.7)
    ax[0].set_ylabel(f"{probe_label(model.x_ref)}/(H^*L/2)$ {NONDIM}")
    ax[0].set_title(f"$U^*$ = {run.scene.ustar:g}, $M^*$ = {run.scene.mstar:g}, "
                    f"$N$ = {run.scene.modes}: {outcome_words(run.outcome.outcome)}")
    ax[1].plot(tr.t, tr.x[:, -2], lw=0.7, label="$Q_1$ (above)")
    ax[1].plot(tr.t, tr.x[:, -1], lw=0.7, label="$Q_2$ (below)")
    ax[1].set_ylabel("flow rate $Q_c$ (units of $L^2/T$)")
    ax[1].legend(loc="upper right")    # moved off the data if it covers any
    total = penetration(model, tr.x, tr.p).load
    ax[2].plot(tr.t, total / reference_force(model), lw=0.7, color=PALETTE[1])
    if not np.any(total > 0):                # say why the panel is empty
        law = "contact law on" if run.scene.contact else "contact law off"
        ax[2].text(0.5, 0.5, f"no wall contact in this run ({law})", ha="center",
                   va="center", transform=ax[2].transAxes)
    ax[2].set_ylabel(f"impact force $F/F_0$ {NONDIM}")
    ax[2].set_xlabel("time $t$ (units of $T$)")
    return finish(fig, path)


@styled
def plot_map(result, path=None, linear=None, curves=None, cases=(), switched=()):
    """Fig. 4: outcome of each (U*, M*) point and the linear stability boundary.

    ``linear``: a dense :class:`~fsicas.linear.boundary.StabilityBoundary` of the map's
    scene (contact-free), drawn per branch and broken at its mode switches; without it,
    the map's own boundary samples (``result.boundary``), broken where the frequency
    jumps between neighbours (a mode switch between them). ``curves``: a
    :class:`~fsicas.cycles.curves.CurveMap` (grazing and fold-of-cycles curves; with
    ``linear`` the band of contact-free cycles shaded); ``cases``: ``[(label, U*, M*)]``
    marked; ``switched``: the fold curves started at the boundary's generalized Hopf
    points (:class:`~fsicas.cycles.bautin.SwitchedCurve`), drawn with their points.
    Returns the Figure."""
    fig, axes = subplots(figsize=(6.4, 3.9))
    ax = axes[0][0]
    for kind, (color, marker) in _MARKERS.items():
        pts = [(p["ustar"], p["mstar"]) for p in result.points if p["outcome"] == kind]
        if pts:
            u, m = np.array(pts).T
            ax.scatter(u, m, s=22, color=color, marker=marker, label=outcome_words(kind),
                       zorder=3)
    if linear is not None and branch_lines(linear):
        draw_boundary(ax, linear)
    else:
        _sampled_boundary(ax, result.boundary)
    if curves is not None:
        draw_curves(ax, curves, boundary_function(linear) if linear is not None else None)
    draw_switched(ax, switched, labelled_fold=curves is not None and bool(curves.fold))
    mark_cases(ax, cases)
    _map_limits(ax, result.points)
    ax.set(yscale="log", xlabel=f"flow velocity $U^*$ {NONDIM}", ylabel=f"mass ratio $M^*$ {NONDIM}")
    scene = result.scene
    if scene is not None:
        zeta = f"{scene.zeta:g}" if np.isscalar(scene.zeta) else "per mode"
        flow = ", reversed flow ($U^* < 0$)" if scene.direction == "reverse" else ""
        ax.set_title(fr"$H^*$ = {scene.hstar:g}, $f$ = {scene.friction:g}, $\zeta$ = {zeta}, "
                     f"$N$ = {scene.modes}{flow}")
    fig.legend(*ax.get_legend_handles_labels(), loc="outside right upper")   # off the points
    return finish(fig, path)


def _map_limits(ax, points) -> None:
    """The axes just around the map's points (M* logarithmic)."""
    ms = [p["mstar"] for p in points]
    if ms:
        ax.set_ylim(min(ms) / 1.25, max(ms) * 1.25)
    us = [p["ustar"] for p in points]
    if us:
        pad = 0.04 * (max(us) - min(us) or 1.0)
        ax.set_xlim(min(us) - pad, max(us) + pad)


def _sampled_boundary(ax, boundary: dict) -> None:
    """The map's boundary samples, lines broken at frequency jumps and where divergence
    (omega = 0) and flutter meet."""
    rows = [(u, m, w) for u, m, w in zip(boundary["ustar_crit"], boundary["mstar"],
                                         boundary.get("omega", [None] * len(boundary["mstar"])))
            if u is not None]
    if not rows:
        return
    rows.sort(key=lambda r: r[1])
    pieces, current = [], [rows[0]]
    for prev, row in zip(rows[:-1], rows[1:]):
        w0, w1 = prev[2], row[2]
        if w0 is not None and w1 is not None and (
                (w0 == 0) != (w1 == 0)          # divergence (omega = 0) beside flutter
                or (w0 and w1 and max(w0, w1) / min(w0, w1) > _FREQUENCY_JUMP)):
            pieces.append(current)
            current = []
        current.append(row)
    pieces.append(current)
    for k, piece in enumerate(pieces):
        u, m, _ = np.array(piece, dtype=float).T
        ax.plot(u, m, "k.-", lw=1.5, ms=5, zorder=2,
                label="linear stability boundary" if k == 0 else None)
