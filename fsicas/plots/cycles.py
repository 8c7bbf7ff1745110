"""Figures of limit-cycle branches (collocation continuation, docs/cycles.md)."""
from __future__ import annotations

import numpy as np

from .backend import NONDIM, PALETTE, finish, styled, subplots

__all__ = ["plot_branch"]

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
    fig.suptitle(fr"limit cycles at $M^*$ = {s.mstar:g}, $N$ = {s.modes}, $\zeta$ = {zeta}: "
                 f"branch {branch.status}")
    handles, labels = axes[0][0].get_legend_handles_labels()
    if handles:
        fig.legend(handles, labels, loc="outside right upper")
    return finish(fig, path)


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
