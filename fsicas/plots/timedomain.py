"""Figures of time integrations: a run, the impact map, impacting cycles.

- :func:`plot_run`: tip displacement, flow rates and impact force against time.
- :func:`plot_map`: Fig. 4, outcomes on the (U*, M*) grid with the linear boundary.
- :func:`plot_cycle`: Figs. 6–9 for one settled cycle: beam snapshots, modal velocities
  and flow rates, tip phase portrait and displacement, tip-velocity spectrum, RMS of the
  modal displacements, impact force / F0 against t / T0.
"""
from __future__ import annotations

import numpy as np

from .backend import pyplot
from ..model.assembly import modal_basis
from ..model.contact import contact_load, reference_force
from ..timedomain.outcome import poincare_returns

__all__ = ["plot_run", "plot_map", "plot_cycle", "cycle_window", "return_period"]

_COLORS = {"decay": "tab:green", "lco": "tab:orange", "contact": "tab:blue",
           "impacting_lco": "tab:purple", "unsettled": "tab:gray", "error": "k"}


def plot_run(run, path) -> None:
    """Tip displacement / (H*/2), flow rates and impact force / F0 against time."""
    plt = pyplot()
    tr, model = run.trajectory, run.model
    fig, ax = plt.subplots(3, 1, figsize=(7, 7), sharex=True)
    ax[0].plot(tr.t, tr.tip / (model.scene.hstar / 2), lw=0.7)
    ax[0].set_ylabel("y(1) / (H*/2)")
    ax[0].set_title(f"{run.outcome.outcome}: U* = {run.scene.ustar:g}, M* = {run.scene.mstar:g}, "
                    f"N = {run.scene.modes}")
    ax[1].plot(tr.t, tr.x[:, -2], lw=0.7, label="Q1")
    ax[1].plot(tr.t, tr.x[:, -1], lw=0.7, label="Q2")
    ax[1].set_ylabel("flow rate")
    ax[1].legend()
    _, total = contact_load(model, tr.x)
    ax[2].plot(tr.t, total / reference_force(model), lw=0.7)
    ax[2].set_ylabel("impact force / F0")
    ax[2].set_xlabel("t (units of T)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_map(result, path) -> None:
    """Fig. 4: outcome of each (U*, M*) point and the linear stability boundary."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8.5, 5))
    for kind, color in _COLORS.items():
        pts = [(p["ustar"], p["mstar"]) for p in result.points if p["outcome"] == kind]
        if pts:
            u, m = np.array(pts).T
            ax.scatter(u, m, s=25, color=color, label=kind)
    b = result.boundary
    ok = [(u, m) for u, m in zip(b["ustar_crit"], b["mstar"]) if u is not None]
    if ok:
        u, m = np.array(ok).T
        ax.plot(u, m, "k.-", lw=1.5, label="linear stability boundary")
    ax.set_yscale("log")
    ax.set_xlabel("U*")
    ax.set_ylabel("M*")
    scene = result.scene
    if scene is not None:
        zeta = scene.zeta if np.isscalar(scene.zeta) else "per mode"
        ax.set_title(f"H* = {scene.hstar:g}, f = {scene.friction:g}, zeta = {zeta}, "
                     f"N = {scene.modes}")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))   # off the points
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def cycle_window(run, cycles: int = 1, period: float | None = None) -> slice:
    """Samples of the last ``cycles`` periods of a run (the settled period, or ``period``)."""
    T = run.outcome.period if period is None else period
    if T is None:
        raise ValueError(f"the run has no settled cycle (outcome {run.outcome.outcome})")
    t = run.trajectory.t
    return slice(int(np.searchsorted(t, t[-1] - cycles * T)), len(t))


def return_period(run) -> float | None:
    """The last interval between upward tip crossings (``poincare_returns``): the period
    to show of a run that hit the wall without settling (perturbed periodic motion)."""
    times, _ = poincare_returns(run.trajectory.t, run.trajectory.tip)
    return float(times[-1] - times[-2]) if len(times) >= 2 else None


def plot_cycle(run, path, snapshots: int = 24) -> None:
    """Figs. 6–9 of one run's last settled cycle in one figure (2 x 4 panels); a run
    without a settled cycle shows its last tip-return interval, titled as unsettled."""
    plt = pyplot()
    scene, T = run.scene, run.outcome.period
    label = f"{run.outcome.outcome}, T0 = {{:.4g}}"
    if T is None:
        T = return_period(run)
        label = f"{run.outcome.outcome}, not settled: last tip return, T = {{:.4g}}"
    w = cycle_window(run, period=T)
    t, X = run.trajectory.t[w], run.trajectory.x[w]
    tau = (t - t[0]) / T
    fig, ax = plt.subplots(2, 4, figsize=(17, 7))
    _snapshots_panel(ax[0, 0], scene, X, snapshots)
    _flow_panels(ax[0, 1], ax[0, 2], run, tau, X)
    _tip_panels(ax[0, 3], ax[1, 0], run.trajectory, w, tau)
    _spectrum(ax[1, 1], run.trajectory, T)
    _rms_and_force_panels(ax[1, 2], ax[1, 3], run.model, tau, X)
    fig.suptitle(f"U* = {scene.ustar:g}, M* = {scene.mstar:g}, N = {scene.modes}: "
                 + label.format(T))
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _snapshots_panel(ax, scene, X, snapshots: int) -> None:
    """Fig. 6: beam shapes through the cycle between the walls at the tip."""
    n, xs = scene.modes, np.linspace(0, 1, 201)
    phi = modal_basis(scene, xs).phi
    for k in np.linspace(0, len(X) - 1, snapshots).astype(int):
        ax.plot(xs, X[k, n:2 * n] @ phi, lw=0.6, color="tab:blue")
    ax.axhline(scene.walls[0](1.0), color="k")
    ax.axhline(-scene.walls[1](1.0), color="k")
    ax.set(title="beam snapshots (Fig. 6)", xlabel="x", ylabel="y")


def _flow_panels(ax_r, ax_q, run, tau, X) -> None:
    """Fig. 7: the first modal velocities and the two flow rates over the cycle."""
    for m in range(min(run.scene.modes, 6)):
        ax_r.plot(tau, X[:, m], lw=0.7, label=f"r{m + 1}")
    ax_r.set(title="modal velocities (Fig. 7)", xlabel="t / T0")
    ax_r.legend(fontsize=7)
    ax_q.plot(tau, X[:, -2], label="Q1")
    ax_q.plot(tau, X[:, -1], label="Q2")
    ax_q.axhline(run.steady.x[-2], color="k", ls=":", lw=0.8)
    ax_q.set(title="flow rates (Fig. 7)", xlabel="t / T0")
    ax_q.legend(fontsize=7)


def _tip_panels(ax_phase, ax_tip, tr, w: slice, tau) -> None:
    """Fig. 8: tip phase portrait and tip displacement over the cycle."""
    tip, vtip = tr.tip[w], tr.tip_velocity[w]
    ax_phase.plot(tip, vtip, lw=0.7)
    ax_phase.set(title="tip phase portrait (Fig. 8)", xlabel="y(1)", ylabel="dy/dt(1)")
    ax_tip.plot(tau, tip)
    ax_tip.set(title="tip displacement (Fig. 8)", xlabel="t / T0")


def _rms_and_force_panels(ax_rms, ax_force, model, tau, X) -> None:
    """Fig. 8: RMS of the modal displacements; Fig. 9: impact force / F0 over the cycle."""
    n = model.scene.modes
    q = X[:, n:2 * n]
    rms = np.sqrt(np.mean((q - q.mean(axis=0)) ** 2, axis=0))
    ax_rms.semilogy(np.arange(1, n + 1), rms, "o-", ms=3)
    ax_rms.set(title="RMS of q_n (Fig. 8)", xlabel="mode n")
    _, total = contact_load(model, X)
    ax_force.plot(tau, total / reference_force(model))
    ax_force.set(title="impact force / F0 (Fig. 9)", xlabel="t / T0")


def _spectrum(ax, tr, T):
    """Spectrum of the tip velocity over the settled part (Hann window)."""
    t0 = tr.t[-1] - min(20 * T, tr.t[-1] / 2)
    k = int(np.searchsorted(tr.t, t0))
    v = tr.tip_velocity[k:] - tr.tip_velocity[k:].mean()
    dt = tr.t[1] - tr.t[0]
    spec = np.abs(np.fft.rfft(v * np.hanning(v.size)))
    freq = np.fft.rfftfreq(v.size, dt) * T
    ax.semilogy(freq[1:], spec[1:] + 1e-300, lw=0.7)
    ax.set(title="tip velocity spectrum (Fig. 8)", xlabel="f T0", xlim=(0, 30))
