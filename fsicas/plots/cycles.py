"""Figures of limit-cycle branches (collocation continuation, docs/cycles.md)."""
from __future__ import annotations

import numpy as np

from .backend import pyplot

__all__ = ["plot_branch"]

_PANELS = (("tip_amplitude", "tip half-amplitude / L"), ("period", "period / T"))


def plot_branch(branch, path) -> None:
    """Tip half-amplitude and period against U*: stable solid, unstable dashed; folds
    (triangles) and the first contact (star)."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
    for ax, (name, label) in zip(axes, _PANELS):
        _branch_panel(ax, branch, name)
        ax.set(xlabel="U*", ylabel=label)
    s = branch.scene
    fig.suptitle(f"M* = {s.mstar:g}, N = {s.modes}, zeta = {s.zeta}: {branch.status}")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _branch_panel(ax, branch, name: str) -> None:
    """One column of the branch against U*, with its folds, first contact and onset."""
    u, stable, y = branch.column("ustar"), branch.column("stable"), branch.column(name)
    for flag, style in ((True, "-"), (False, "--")):
        ax.plot(u, np.where(stable == flag, y, np.nan), "k" + style, lw=1.2)
    for p in branch.folds:
        ax.plot(p.ustar, getattr(p, name), "v", color="tab:blue")
    if branch.contact is not None:
        ax.plot(branch.contact.ustar, getattr(branch.contact, name), "*", ms=10, color="tab:red")
    ax.axvline(branch.hopf["ustar_crit"], color="0.6", lw=0.8)
