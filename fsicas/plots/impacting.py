"""Figures of settled (impacting) cycles, paper Figs. 6–9.

:func:`cycle_view` extracts what the figures show of a run's last cycle into a
:class:`CycleView` of plain arrays (it pickles, so worker processes can hand it back);
:func:`plot_cycle` draws one case on 2 x 4 panels, :func:`plot_cycles` several cases side
by side (one column each, one row per quantity), as the paper shows its cases (1a-c):

- beam snapshots y(x, t)/L between the walls (Fig. 6),
- modal velocities r_n(t) of all N modes and flow rates Q_c(t) (Fig. 7),
- tip displacement, tip phase portrait, spectrum of the tip velocity and RMS of the
  modal displacements q_n (Fig. 8),
- total impact force / F0 (Fig. 9) and its first contact episode zoomed
  (:func:`first_contact`): at the cycle's time scale the several impacts of a chattering
  contact merge into one spike,

against t / T0 (T0 the cycle's period). Legends are kept off the data
(:mod:`fsicas.plots.legends`). The spectrum (:func:`tip_spectrum`) averages
Hann-windowed segments of a whole number of periods, so a periodic motion's harmonics
sit on exact bins at integer multiples of f0 = 1/T0 and the floor between them is what
is not periodic.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model.assembly import modal_basis
from ..model.contact import reference_force
from ..model.patch import contact_intervals, penetration
from ..timedomain.returns import poincare_returns
from .backend import (NONDIM, PALETTE, finish, outcome_words, probe_label, pyplot, styled,
                      subplots, suptitle)

__all__ = ["CycleView", "cycle_view", "cycle_window", "return_period", "tip_spectrum",
           "first_contact", "plot_cycle", "plot_cycles"]

TAU = "time $t/T_0$"
#: The quantities of the panels, in the order of :func:`plot_cycles`' rows.
ROWS = ("snapshots", "modal velocities", "flow rates", "tip", "phase portrait", "spectrum",
        "modal rms", "impact force", "first contact")


@dataclass(frozen=True)
class CycleView:
    """What Figs. 6–9 show of one run's last (settled) cycle, as plain arrays.

    ``tau`` = t / T0 over the cycle; ``x`` the beam points (x/L) of ``shapes`` (snapshots
    x points, y/L) and of the walls' positions ``wall_upper`` = H1(x), ``wall_lower`` =
    -H2(x); ``r`` the modal velocities (samples x N, units of L/T); ``Q`` the flow rates
    (samples x 2, units of L^2/T) and ``Q_steady`` those of the steady state; ``tip``,
    ``tip_velocity`` (units of L and L/T); ``freq`` (f / f0) and ``spectrum`` (amplitude of
    the tip velocity, relative to its largest), both at ``x_ref``; ``rms`` of each q_n / L; ``force`` the
    total impact force / F0. ``settled``: False when the run did not settle and the last
    tip return is shown instead."""

    ustar: float
    mstar: float
    modes: int
    #: the contact law in words (stiffness, layer), or "no contact law"
    law: str
    outcome: str
    settled: bool
    period: float
    tau: np.ndarray
    x: np.ndarray
    shapes: np.ndarray
    wall_upper: np.ndarray
    wall_lower: np.ndarray
    r: np.ndarray
    Q: np.ndarray
    Q_steady: np.ndarray
    tip: np.ndarray
    tip_velocity: np.ndarray
    freq: np.ndarray
    spectrum: np.ndarray
    rms: np.ndarray
    force: np.ndarray
    #: where ``tip`` is measured (the model's reference point; 1: the free tip)
    x_ref: float = 1.0

    @property
    def title(self) -> str:
        """The case in words: U*, M*, N, the outcome and the period shown."""
        what = (f"{outcome_words(self.outcome)}, $T_0$ = {self.period:.4g}" if self.settled
                else f"{outcome_words(self.outcome)}, not settled: last tip return "
                     f"$T$ = {self.period:.4g}")
        return (f"$U^*$ = {self.ustar:g}, $M^*$ = {self.mstar:g}, $N$ = {self.modes}, "
                f"{self.law}: {what}")


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


def tip_spectrum(t, v, period: float, periods: int = 20, per_segment: int = 4):
    """Amplitude spectrum of ``v(t)`` over the last whole periods of the run (at most
    ``periods``, at most half the run): resampled to a whole number of samples per period,
    cut into segments of ``per_segment`` periods (half overlapping), each Hann-windowed,
    their powers averaged. Returns (f / f0, amplitude relative to the largest); the
    harmonics k f0 fall on the bins k * per_segment."""
    t, v = np.asarray(t, float), np.asarray(v, float)
    cycles = int(np.floor((t[-1] - t[0]) / period + 1e-9))
    if cycles < 1:
        raise ValueError(f"the run ({t[-1] - t[0]:.4g}) is shorter than one period ({period:.4g})")
    count = max(1, min(periods, cycles // 2 or cycles))
    m = max(1, min(per_segment, count))
    n_per = max(64, int(round(period / np.median(np.diff(t)))))
    grid = t[-1] - count * period + np.arange(count * n_per) * (period / n_per)
    vg = np.interp(grid, t, v)
    length, hop = m * n_per, max(1, m * n_per // 2)
    window = np.hanning(length + 1)[:-1]
    power = np.zeros(length // 2 + 1)
    starts = range(0, vg.size - length + 1, hop)
    for s in starts:
        seg = vg[s: s + length]
        power += np.abs(np.fft.rfft((seg - seg.mean()) * window)) ** 2
    amp = np.sqrt(power / len(starts))
    freq = np.fft.rfftfreq(length, period / n_per) * period
    return freq[1:], amp[1:] / max(amp[1:].max(), 1e-300)


def cycle_view(run, snapshots: int = 24) -> CycleView:
    """The last settled cycle of ``run`` (or, unsettled, its last tip return) for the
    figures."""
    scene, model, tr = run.scene, run.model, run.trajectory
    settled, T = run.outcome.periodic, run.outcome.period
    if not settled:
        T = return_period(run)
        if T is None:
            raise ValueError(f"the run shows no cycle (outcome {run.outcome.outcome})")
    w = cycle_window(run, period=T)
    t, X = tr.t[w], tr.x[w]
    n, xs = scene.modes, np.linspace(0.0, 1.0, 201)
    phi = modal_basis(scene, xs).phi
    picks = np.linspace(0, len(X) - 1, snapshots).astype(int)
    q = X[:, n:2 * n]
    freq, spectrum = tip_spectrum(tr.t, tr.tip_velocity, T)
    force = penetration(model, X, tr.p).load
    upper, lower = scene.walls
    return CycleView(
        ustar=float(scene.ustar), mstar=float(scene.mstar), modes=int(n), law=_law(scene),
        outcome=str(run.outcome.outcome), settled=settled, period=float(T),
        tau=(t - t[0]) / T, x=xs, shapes=X[picks, n:2 * n] @ phi,
        wall_upper=np.asarray(upper(xs)), wall_lower=-np.asarray(lower(xs)),
        r=X[:, :n].copy(), Q=X[:, -2:].copy(), Q_steady=np.asarray(run.steady.x[-2:], float),
        tip=tr.tip[w].copy(), tip_velocity=tr.tip_velocity[w].copy(), freq=freq,
        spectrum=spectrum, rms=np.sqrt(np.mean((q - q.mean(axis=0)) ** 2, axis=0)),
        force=total_force(model, force), x_ref=model.x_ref)


def _law(scene) -> str:
    """The scene's contact law in words (:attr:`CycleView.law`)."""
    if not scene.contact:
        return "no contact law"
    smooth = f", smoothed {scene.contact_smoothing:g}" if scene.contact_smoothing else ""
    return f"contact $k^*$ = {scene.contact_stiffness:.3g}, eps/H = {scene.contact_eps:g}{smooth}"


def total_force(model, total) -> np.ndarray:
    """The total impact force in units of F0 (paper's Fig. 9 scale)."""
    return np.asarray(total) / reference_force(model)


def _view(run_or_view, snapshots: int) -> CycleView:
    return run_or_view if isinstance(run_or_view, CycleView) else cycle_view(run_or_view, snapshots)


def first_contact(view: CycleView) -> tuple[float, float, int] | None:
    """The first contact episode the cycle shows whole: the impacts (the separate
    contact intervals, :func:`fsicas.model.patch.contact_intervals`) of the first half
    cycle with contact, a half cycle being the tip's stay on one side of the channel's
    centre line (between two of its crossings; the cycle's first, cut by its start, only
    if no other has contact). Returns (t/T0 at its first impact's start, t/T0 at its last
    impact's end, the number of impacts); None for a cycle without contact."""
    spans = contact_intervals(view.force)
    if not len(spans):
        return None
    side = np.sign(view.tip)
    halves = np.r_[0, np.cumsum(side[1:] != side[:-1])]     # the half cycle of each sample
    whole = spans[halves[spans[:, 0]] > 0]
    first = (whole if len(whole) else spans)[0, 0]
    episode = spans[halves[spans[:, 0]] == halves[first]]
    return float(view.tau[first]), float(view.tau[episode[-1, 1]]), len(episode)


@styled
def plot_cycle(run, path=None, snapshots: int = 24):
    """Figs. 6–9 of one run's last settled cycle in one figure (3 x 3 panels, the last
    the first contact zoomed); a run without a settled cycle shows its last tip-return
    interval, titled as unsettled. ``run``: a run or its :class:`CycleView`. Returns the
    Figure."""
    view = _view(run, snapshots)
    fig, ax = subplots(3, 3, figsize=(10.5, 7.8))
    panels = dict(zip(ROWS, ax.flat))
    _draw_case(panels, view, colorbar=True, titles=True)
    suptitle(fig, view.title)
    return finish(fig, path)


@styled
def plot_cycles(runs, path=None, labels=None, snapshots: int = 24):
    """Figs. 6–9 of several cases side by side: one column per case (a run or a
    :class:`CycleView`), one row per quantity. ``labels``: the cases' names (default
    (1a), (1b), ...). Returns the Figure."""
    views = [_view(r, snapshots) for r in runs]
    labels = labels or [f"(1{chr(ord('a') + k)})" for k in range(len(views))]
    fig, ax = subplots(len(ROWS), len(views), figsize=(2.9 * len(views) + 0.9, 15.2))
    for k, (view, label) in enumerate(zip(views, labels)):
        _draw_case(dict(zip(ROWS, ax[:, k])), view, colorbar=k == len(views) - 1, titles=False)
        T = f"$T_0$ = {view.period:.4g}" if view.settled else f"not settled, $T$ = {view.period:.4g}"
        ax[0, k].set_title(f"{label} $U^*$ = {view.ustar:g}\n{outcome_words(view.outcome)}, {T}")
    for k in range(1, len(views)):         # one y label and legend per row, on the left
        for row in ax[:, k]:
            row.set_ylabel("")
            if row.get_legend() is not None:
                row.get_legend().remove()
    first = views[0] if views else None
    if first is not None:
        suptitle(fig, f"impacting cycles at $M^*$ = {first.mstar:g}, $N$ = {first.modes}, "
                     f"{first.law}\nFigs. 6 (snapshots), 7 ($r_n$, $Q_c$), 8 (tip, "
                     "walls dashed; spectrum; RMS), 9 (force, its first contact zoomed)")
    return finish(fig, path)


_TITLES = {"snapshots": "beam snapshots (Fig. 6)", "modal velocities": "modal velocities (Fig. 7)",
           "flow rates": "flow rates (Fig. 7)", "tip": "tip displacement, walls dashed (Fig. 8)",
           "phase portrait": "tip phase portrait (Fig. 8)",
           "spectrum": "tip-velocity spectrum (Fig. 8)",
           "modal rms": "RMS of the modal displacements (Fig. 8)",
           "impact force": "impact force (Fig. 9)"}


def _draw_case(panels: dict, view: CycleView, colorbar: bool, titles: bool) -> None:
    """Every panel of one case onto the axes ``panels`` (quantity -> axes)."""
    _snapshots_panel(panels["snapshots"], view)
    _modal_velocity_panel(panels["modal velocities"], view, colorbar)
    _flow_panel(panels["flow rates"], view)
    _tip_panels(panels["phase portrait"], panels["tip"], view)
    _spectrum_panel(panels["spectrum"], view)
    _rms_panel(panels["modal rms"], view)
    _force_panel(panels["impact force"], view, panels["first contact"])
    if titles:
        for name, ax in panels.items():
            if name in _TITLES:
                ax.set_title(_TITLES[name])


def _walls(ax, view: CycleView, along_x: bool) -> None:
    """The walls: their profiles along x, or their positions at x_ref (dashed)."""
    if along_x:
        ax.plot(view.x, view.wall_upper, color="k", lw=1.4)
        ax.plot(view.x, view.wall_lower, color="k", lw=1.4)
    else:
        for y in _walls_at_probe(view):
            ax.axhline(y, color="k", ls="--", lw=0.7)


def _walls_at_probe(view: CycleView) -> tuple[float, float]:
    """The two walls' positions at x_ref."""
    return tuple(float(np.interp(view.x_ref, view.x, w))
                 for w in (view.wall_upper, view.wall_lower))


def _snapshots_panel(ax, view: CycleView) -> None:
    """Fig. 6: beam shapes through the cycle between the walls."""
    for y in view.shapes:
        ax.plot(view.x, y, lw=0.6, color=PALETTE[0])
    _walls(ax, view, along_x=True)
    ax.set(xlabel="position $x/L$", ylabel=f"deflection $y/L$ {NONDIM}", xlim=(0, 1))


def _mode_colors(n: int):
    return pyplot().get_cmap("viridis")(np.linspace(0.0, 0.92, n))


def _modal_velocity_panel(ax, view: CycleView, colorbar: bool) -> None:
    """Fig. 7 (left): the modal velocities of all N modes, coloured by mode number."""
    colors = _mode_colors(view.modes)
    for m in range(view.modes):
        ax.plot(view.tau, view.r[:, m], lw=0.7, color=colors[m], label=f"$r_{{{m + 1}}}$")
    ax.set(xlabel=TAU, ylabel="modal velocity $r_n$ (units of $L/T$)", xlim=(0, 1))
    if colorbar:
        _mode_colorbar(ax, view.modes)


def _mode_colorbar(ax, n: int) -> None:
    """A colour bar of the mode numbers 1..n beside ``ax``."""
    import matplotlib as mpl
    plt = pyplot()
    bounds = np.arange(0.5, n + 1.0)
    cmap = mpl.colors.ListedColormap(_mode_colors(n))
    bar = plt.colorbar(mpl.cm.ScalarMappable(mpl.colors.BoundaryNorm(bounds, n), cmap), ax=ax,
                       fraction=0.06, pad=0.02)
    ticks = np.arange(1, n + 1) if n <= 10 else np.unique(np.linspace(1, n, 5).round().astype(int))
    bar.set_ticks(ticks)
    bar.set_label("mode $n$")


def _flow_panel(ax, view: CycleView) -> None:
    """Fig. 7 (right): the two flow rates over the cycle, their steady values dotted."""
    from matplotlib.lines import Line2D
    for c, label in enumerate(("$Q_1$ (above)", "$Q_2$ (below)")):
        ax.plot(view.tau, view.Q[:, c], color=PALETTE[c], label=label)
        ax.axhline(view.Q_steady[c], color=PALETTE[c], ls=":", lw=0.8)
    ax.set(xlabel=TAU, ylabel="flow rate $Q_c$ (units of $L^2/T$)", xlim=(0, 1))
    handles = [*ax.get_legend_handles_labels()[0], Line2D([], [], color="0.3", ls=":", lw=0.8)]
    ax.legend(handles, ["$Q_1$ (above)", "$Q_2$ (below)", "steady state"], loc="upper right",
              fontsize=7)


def _tip_panels(ax_phase, ax_tip, view: CycleView) -> None:
    """Fig. 8: tip phase portrait and tip displacement over the cycle, the walls dashed."""
    y_tip = f"{probe_label(view.x_ref)}/L$ {NONDIM}"
    ax_phase.plot(view.tip, view.tip_velocity, lw=0.7, color=PALETTE[0])
    for y in _walls_at_probe(view):
        ax_phase.axvline(y, color="k", ls="--", lw=0.7)
    velocity = probe_label(view.x_ref, r"\dot y", "velocity ")
    ax_phase.set(xlabel=y_tip, ylabel=f"{velocity}$ (units of $L/T$)")
    ax_tip.plot(view.tau, view.tip, color=PALETTE[0])
    _walls(ax_tip, view, along_x=False)
    ax_tip.set(xlabel=TAU, ylabel=y_tip, xlim=(0, 1))


def _spectrum_panel(ax, view: CycleView, top: float = 30.0) -> None:
    """Fig. 8: the tip-velocity spectrum against f / f0, the harmonics k f0 marked."""
    keep = view.freq <= top
    f, a = view.freq[keep], view.spectrum[keep]
    ax.semilogy(f, a, lw=0.7, color=PALETTE[0])
    k = np.arange(1, int(top) + 1)
    at = np.interp(k, f, a, left=np.nan, right=np.nan)
    ax.semilogy(k, at, "o", ms=2.5, color=PALETTE[1], label="harmonics $k f_0$")
    floor = max(np.nanmin(a[a > 0]) if np.any(a > 0) else 1e-8, 1e-8)
    ax.set(xlabel="frequency $f/f_0$", ylabel=f"tip-velocity amplitude {NONDIM}",
           xlim=(0, top), ylim=(max(floor, 1e-6), 2.0))
    ax.legend(loc="upper right", fontsize=7)


def _rms_panel(ax, view: CycleView) -> None:
    """Fig. 8: RMS of each modal displacement q_n over the cycle."""
    ax.semilogy(np.arange(1, view.modes + 1), view.rms, "o-", ms=3, color=PALETTE[0])
    ax.set(xlabel="mode $n$", ylabel=f"RMS of $q_n/L$ {NONDIM}")


def _force_panel(ax, view: CycleView, zoom) -> None:
    """Fig. 9: the total impact force / F0 over the cycle, its first contact episode
    shaded and drawn on ``zoom`` at its own time scale."""
    force = f"impact force $F/F_0$ {NONDIM}"
    ax.plot(view.tau, view.force, color=PALETTE[1])
    ax.set(xlabel=TAU, ylabel=force, xlim=(0, 1))
    zoom.set(xlabel=TAU, ylabel=force)
    episode = first_contact(view)
    if episode is None:
        zoom.text(0.5, 0.5, "no wall contact\nin this cycle", transform=zoom.transAxes,
                  ha="center", va="center")
        zoom.set_xlim(0, 1)
        return
    lo, hi, count = episode
    pad = max(0.1 * (hi - lo), 0.01)
    lo, hi = max(0.0, lo - pad), min(1.0, hi + pad)
    ax.axvspan(lo, hi, color="0.88", lw=0, zorder=0)
    shown = (view.tau >= lo) & (view.tau <= hi)
    zoom.plot(view.tau[shown], view.force[shown], color=PALETTE[1], lw=0.8)
    zoom.set_xlim(lo, hi)
    zoom.set_title(f"first contact (shaded), zoomed: {count} impact{'s' * (count > 1)}")
