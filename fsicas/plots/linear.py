"""Figures of the linear analysis (paper Figs. 2 and 3)."""
from __future__ import annotations

import numpy as np

from ..linear.boundary import StabilityBoundary
from .backend import pyplot
from ..model.assembly import Model
from ..linear.stability import linear_stability

__all__ = ["plot_boundary", "plot_mode_shapes", "plot_eigenvalues", "plot_boundary_variants"]


def plot_boundary(boundary: StabilityBoundary, path=None):
    """Fig. 2: U*_c(M*) with all traced Hopf curves (left), frequency ratio (middle) and
    the first Lyapunov coefficient l1 along the boundary (right; > 0: subcritical)."""
    plt = pyplot()
    fig, (left, right, crit) = plt.subplots(1, 3, figsize=(15, 4))
    pts = [p for p in boundary.points if p["ustar_crit"] is not None]
    u = _onset_panels(left, right, boundary, pts)
    _criticality_panel(crit, pts)
    top = 1.3 * max(u) if len(u) else 1.0
    left.set(xlabel="M*", ylabel="U*", ylim=(0, top), title="flutter boundary (grey: Hopf curves)")
    right.set(xlabel="M*", ylabel="omega / omega_1", title="frequency at onset")
    fig.tight_layout()
    if path:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


def _onset_panels(left, right, boundary: StabilityBoundary, pts: list[dict]) -> np.ndarray:
    """U*_c (over the grey Hopf curves) and the frequency ratio against M*, one colour per
    branch, subcritical points crossed, mode switches dotted; returns the onsets U*_c."""
    for c in boundary.curves:
        left.semilogx(c.mstar, c.ustar, color="0.8", lw=0.8)
    m = np.array([p["mstar"] for p in pts])
    u = np.array([p["ustar_crit"] for p in pts])
    ratio = np.array([p["freq_ratio"] for p in pts])
    branch = np.array([p["branch"] for p in pts])
    for b in np.unique(branch):
        sel = branch == b
        left.semilogx(m[sel], u[sel], "o-", ms=3, lw=1.5)
        right.semilogx(m[sel], ratio[sel], "o-", ms=3, lw=1.5)
    sub = [p for p in pts if p.get("criticality") == "subcritical"]
    if sub:
        left.semilogx([p["mstar"] for p in sub], [p["ustar_crit"] for p in sub], "kx", ms=5,
                      label="subcritical (l1 > 0)")
        left.legend(loc="upper left", fontsize=8)
    for s in boundary.switches:
        left.axvline(s.mstar, color="0.6", ls=":", lw=0.8)
        right.axvline(s.mstar, color="0.6", ls=":", lw=0.8)
    return u


def _criticality_panel(ax, pts: list[dict]) -> None:
    """The first Lyapunov coefficient l1 along the boundary (symlog)."""
    with_l1 = [p for p in pts if "l1" in p]
    if with_l1:
        ax.semilogx([p["mstar"] for p in with_l1], [p["l1"] for p in with_l1], "k.-")
        ax.set_yscale("symlog", linthresh=1e-3)
        ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set(xlabel="M*", ylabel="l1", title="criticality (l1 > 0: subcritical, hysteresis)")


def plot_mode_shapes(boundary: StabilityBoundary, model: Model, path=None):
    """Fig. 3: complex mode shape (Re blue, Im red, motion grey) at the middle point of
    each branch segment of the boundary."""
    plt = pyplot()
    pts = [p for p in boundary.points if p["ustar_crit"] is not None]
    segments: dict[int, list[dict]] = {}
    for p in pts:
        segments.setdefault(p["branch"], []).append(p)
    chosen = [seg[len(seg) // 2] for seg in segments.values()]
    fig, axes = plt.subplots(1, len(chosen), figsize=(2.6 * len(chosen), 3), squeeze=False)
    for ax, p in zip(axes[0], chosen):
        scene = boundary.scene.replace(mstar=p["mstar"], ustar=p["ustar_crit"])
        analysis = linear_stability(scene, model)
        k = int(np.argmin(np.abs(analysis.eigenvalues - 1j * p["omega"])))
        shape = analysis.mode_shape(model, k)
        for phase in np.linspace(0, 2 * np.pi, 12, endpoint=False):
            ax.plot(shape["x"], (shape["y"] * np.exp(1j * phase)).real, color="0.8", lw=0.6)
        ax.plot(shape["x"], shape["y"].real, "b", label="Re")
        ax.plot(shape["x"], shape["y"].imag, "r", label="Im")
        ax.set(title=f"M*={p['mstar']:.3g}, U*={p['ustar_crit']:.3g}", xlabel="x", ylim=(-1.1, 1.1))
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    if path:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


def plot_eigenvalues(result, scene, path) -> None:
    """Eigenvalue map of a linear stability analysis: growth rate against frequency."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5, 4))
    ax.plot(result.growth_rate, result.omega, "o", ms=4)
    ax.axvline(0, color="k", lw=0.8)
    ax.set(xlabel="growth rate (1/T)", ylabel="omega (1/T)",
           title=f"M*={scene.mstar:g}, U*={scene.ustar:g}, N={scene.modes}")
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_boundary_variants(curves: dict, path) -> None:
    """Several flutter boundaries U*_c(M*) on one axis, labelled by the keys of ``curves``
    (label -> :class:`StabilityBoundary`)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    for label, boundary in curves.items():
        pts = [p for p in boundary.points if p["ustar_crit"] is not None]
        ax.semilogx([p["mstar"] for p in pts], [p["ustar_crit"] for p in pts], ".-", label=label)
    ax.set(xlabel="M*", ylabel="U*_c", title="effect of damping and confinement")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
