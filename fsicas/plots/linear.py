"""Figures of the linear analysis (paper Figs. 2 and 3), the eigenvalue map and the
boundary variants.

The stability boundary is drawn stretch by stretch
(:func:`fsicas.linear.stretches.branch_lines`): each stretch on which one branch of onsets is the lowest (a Hopf branch: flutter, solid; a divergence
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

import numpy as np

from ..linear.boundary import StabilityBoundary
from ..linear.stretches import BranchLine, branch_lines, marked_points, omega_1, onsets
from ..linear.stability import linear_stability
from ..model.assembly import Model
from .backend import NONDIM, PALETTE, finish, styled, subplots, suptitle

__all__ = ["draw_boundary", "mode_color", "plot_boundary", "plot_mode_shapes",
           "plot_eigenvalues", "plot_boundary_variants"]

MSTAR = f"mass ratio $M^*$ {NONDIM}"
USTAR_C = f"critical velocity $U^*_c$ {NONDIM}"
RATIO = fr"frequency $\omega/\omega_1$ {NONDIM}"
#: Grey of the traced Hopf curves and of the connectors at folds.
CURVE_GREY, LINK_GREY = "0.82", "0.35"
#: The legend's words for the dotted jump of U*_c where the boundary switches branch.
SWITCH_WORDS = "jump of $U^*_c$ at a branch switch"


def draw_boundary(ax, boundary: StabilityBoundary) -> None:
    """The boundary's stretches (U* across, M* up), each up to its switches; the jumps at
    the switches dotted."""
    for k, line in enumerate(branch_lines(boundary)):
        ax.plot(line.ustar, line.mstar, color="k", lw=1.5, zorder=2, gid=f"branch {line.branch}",
                label="linear stability boundary" if k == 0 else None)
    for k, s in enumerate(boundary.switches):
        ax.plot([s.ustar_below, s.ustar_above], [s.mstar] * 2, ":", color=LINK_GREY, lw=0.9,
                label=SWITCH_WORDS if k == 0 else None, gid="mode switch")


def mode_color(mode: int | None, fallback: int = 0) -> str:
    """The colour of in-vacuo mode ``mode`` (1-based), the same in every figure."""
    return PALETTE[((mode or fallback + 1) - 1) % len(PALETTE)]


def _scene_words(scene) -> str:
    zeta = f"{scene.zeta:g}" if np.isscalar(scene.zeta) else "per mode"
    flow = (f", reversed flow ($U^* < 0$), $K_0$ = {scene.k0:g}, $K_L$ = {scene.kl:g}"
            if scene.direction == "reverse" else "")
    return (fr"$H^*$ = {scene.hstar:g}, $f$ = {scene.friction:g}, $\zeta$ = {zeta}, "
            f"$N$ = {scene.modes}{flow}")


def _ustar_limits(u: np.ndarray, margin: float = 1.25) -> tuple[float, float]:
    """From 0 to ``margin`` times the U* farthest from 0 (below 0 for reversed flow)."""
    far = float(u[np.argmax(np.abs(u))]) if u.size else 1.0
    return (0.0, margin * far) if far >= 0 else (margin * far, 0.0)


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
    _criticality_panel(crit, onsets(boundary))
    u = np.concatenate([line.ustar for line in lines]) if lines else np.ones(1)
    left.set(xscale="log", xlabel=MSTAR, ylabel=USTAR_C, ylim=_ustar_limits(u),
             title="stability boundary")
    mid.set(xscale="log", xlabel=MSTAR, ylabel=RATIO, title="frequency at onset")
    fig.legend(*_legend_entries(left), loc="outside right upper")
    suptitle(fig, _scene_words(boundary.scene))
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
    w1 = omega_1(boundary)
    for k, line in enumerate(lines):
        color = mode_color(line.mode, k)
        label = f"mode {line.mode}" if line.mode else f"branch {line.branch}"
        style = "--" if line.kind == "divergence" else "-"
        for ax, y in ((left, line.ustar), (mid, line.omega / w1)):
            ax.plot(line.mstar, y, style, color=color, lw=1.5, label=label,
                    gid=f"branch {line.branch}")
            m = [p.mstar for p in line.samples]
            s = [p.ustar_crit if ax is left else p.freq_ratio for p in line.samples]
            ax.plot(m, s, "o", ms=2.2, color=color, zorder=3)
    for k, s in enumerate(boundary.switches):
        left.plot([s.mstar] * 2, [s.ustar_below, s.ustar_above], ":", color=LINK_GREY, lw=0.8,
                  label=SWITCH_WORDS if k == 0 else None, gid="mode switch")
        mid.plot([s.mstar] * 2, [s.omega_below / w1, s.omega_above / w1], ":", color=LINK_GREY,
                 lw=0.8)
    for letter, line, p in marked_points(boundary):
        left.plot(p.mstar, p.ustar_crit, "o", ms=6, mfc="none", mec="k", mew=0.8, zorder=4)
        left.annotate(f"({letter})", (p.mstar, p.ustar_crit), xytext=(0, -7),
                      textcoords="offset points", ha="center", va="top", fontsize=8)
    sub = [p for p in onsets(boundary) if p.criticality == "subcritical"]
    if sub:
        left.plot([p.mstar for p in sub], [p.ustar_crit for p in sub], "x", color="k",
                  ms=4, mew=0.8, zorder=5, label=r"subcritical ($\ell_1 > 0$)")


def _criticality_panel(ax, pts: list) -> None:
    """The first Lyapunov coefficient l1 along the boundary (symlog), one line per
    stretch of one branch (l1 jumps where the boundary switches branch: not joined)."""
    with_l1 = [p for p in pts if p.l1 is not None]
    for _, stretch in itertools.groupby(with_l1, key=lambda p: p.branch):
        stretch = list(stretch)
        ax.plot([p.mstar for p in stretch], [p.l1 for p in stretch], ".-", color="k",
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
        ax.set_title(f"({letter}) $M^*$ = {p.mstar:.3g}{mode}\n$U^*_c$ = {p.ustar_crit:.3g}",
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
    suptitle(fig, f"complex mode shapes at the marked points of Fig. 2 ({_scene_words(boundary.scene)})")
    return finish(fig, path)


def _mode_shape_panel(ax, boundary, model, p) -> None:
    """Re, Im and the motion of the neutral mode of the Hopf point ``p``."""
    scene = boundary.scene.replace(mstar=p.mstar, ustar=p.ustar_crit)
    analysis = linear_stability(scene, model)
    k = int(np.argmin(np.abs(analysis.eigenvalues - 1j * p.omega)))
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
        w1 = omega_1(boundary)
        for j, line in enumerate(lines):
            for ax, y in ((left, line.ustar), (right, line.omega / w1)):
                ax.plot(line.mstar, y, "--" if line.kind == "divergence" else "-", color=color, label=_math(label) if j == 0 else None,
                        gid=f"{label}: branch {line.branch}")
                ax.plot([p.mstar for p in line.samples],
                        [(p.ustar_crit if ax is left else p.freq_ratio) for p in line.samples],
                        "o", ms=2, color=color)
        for s in boundary.switches:
            left.plot([s.mstar] * 2, [s.ustar_below, s.ustar_above], ":", color=color, lw=0.7)
            right.plot([s.mstar] * 2, [s.omega_below / w1, s.omega_above / w1], ":", color=color,
                       lw=0.7)
    reverse = any(b.scene.direction == "reverse" for b in curves.values())
    left.set(xscale="log", xlabel=MSTAR, ylabel=USTAR_C, ylim=(None, 0) if reverse else (0, None),
             title="effect of damping and confinement")
    right.set(xscale="log", xlabel=MSTAR, ylabel=RATIO, title="frequency at onset")
    fig.legend(*left.get_legend_handles_labels(), loc="outside right upper")
    return finish(fig, path)
