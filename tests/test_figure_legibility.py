"""Figures a reader understands on their own: no legend over the data (checked on the
drawn figure by sampling every line densely in display coordinates, not by the placement
code's own test), the chattering of a contact shown zoomed (on a cycle whose impacts are
built in the test), the curves' ends and the switch jumps named in Fig. 4's legend,
titles in words."""
import re

import numpy as np
import pytest

from fsicas.plots.impacting import CycleView, first_contact


def _cycle(force, tip=None, flows=None, samples: int = 4001, modes: int = 3) -> CycleView:
    """A cycle of ``samples`` points on t/T0 in [0, 1] with the given impact force and
    tip (default: the tip at the upper wall for t/T0 < 0.45, at the lower after), flow
    rates ``flows`` (default: crossing in every corner of the panel), steady Q = 0.4."""
    tau = np.linspace(0.0, 1.0, samples)
    tip = 0.05 * np.sin(2 * np.pi * (tau + 0.05)) if tip is None else tip
    swing = 0.08 * np.sin(4 * np.pi * tau)
    flows = np.c_[0.4 + swing, 0.4 - swing] if flows is None else flows
    x = np.linspace(0.0, 1.0, 21)
    freq = np.arange(1, 121) / 4.0
    return CycleView(
        ustar=8.5, mstar=1.0, modes=modes, law="contact $k^*$ = 1e+08, eps/H = 0.01",
        outcome="impacting_lco", settled=True, period=0.1155, tau=tau, x=x,
        shapes=np.outer(np.linspace(-1, 1, 5), 0.05 * x ** 2), wall_upper=np.full_like(x, 0.05),
        wall_lower=np.full_like(x, -0.05), r=np.c_[[np.sin(2 * np.pi * (k + 1) * tau)
                                                   for k in range(modes)]].T,
        Q=flows, Q_steady=np.array([0.4, 0.4]), tip=tip,
        tip_velocity=np.gradient(tip, tau), freq=freq,
        spectrum=np.where(np.isclose(freq % 1, 0), 1.0 / freq ** 2, 1e-4),
        rms=np.geomspace(1e-2, 1e-4, modes), force=force)


def _pulses(tau, centres, width=2e-3, height=1000.0):
    """Separate impacts: half-sine pulses of ``width`` (t/T0) at ``centres``."""
    out = np.zeros_like(tau)
    for c in centres:
        inside = np.abs(tau - c) < width / 2
        out[inside] += height * np.cos(np.pi * (tau[inside] - c) / width)
    return out


#: A cycle that chatters: at the upper wall (t/T0 < 0.45) an impact at the cycle's start
#: and four more, a stay cut by the start; at the lower wall three impacts in quick
#: succession, the first contact episode the cycle shows whole.
TAU = np.linspace(0.0, 1.0, 4001)
UPPER, LOWER = (0.0, 0.20, 0.22, 0.25, 0.27), (0.70, 0.72, 0.75)


def _display_points(line, step: float = 0.5) -> np.ndarray:
    """The points of ``line`` in display coordinates, its segments sampled every
    ``step`` pixels (markers as their centres)."""
    xy = line.get_transform().transform(np.asarray(line.get_xydata(), float))
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    if line.get_linestyle() in ("None", "", " ", "none") or len(xy) < 2:
        return xy
    out = [xy[:1]]
    for a, b in zip(xy[:-1], xy[1:]):
        n = max(1, int(np.ceil(np.hypot(*(b - a)) / step)))
        out.append(a + np.outer(np.arange(1, n + 1) / n, b - a))
    return np.concatenate(out)


def _hidden(fig) -> list:
    """(panel, line) pairs whose drawn points (inside the panel) lie under a legend."""
    fig.canvas.draw()
    hits = []
    for ax in fig.axes:
        legend = ax.get_legend()
        if legend is None:
            continue
        box, panel = legend.get_window_extent(), ax.get_window_extent()
        for line in ax.lines:
            p = _display_points(line)
            drawn = p[(p[:, 0] >= panel.x0) & (p[:, 0] <= panel.x1) & (p[:, 1] >= panel.y0)
                      & (p[:, 1] <= panel.y1)]
            inside = ((drawn[:, 0] > box.x0) & (drawn[:, 0] < box.x1) & (drawn[:, 1] > box.y0)
                      & (drawn[:, 1] < box.y1))
            if inside.any():
                hits.append((ax.get_ylabel(), line.get_label()))
    return hits


def _panel(fig, words: str):
    return next(ax for ax in fig.axes if words in ax.get_ylabel() or words in ax.get_title())


@pytest.fixture(scope="module")
def chattering():
    """The chattering cycle (:data:`UPPER`, :data:`LOWER`) drawn alone and side by side
    with itself: (view, Fig. 6-9 of one case, of two cases)."""
    from fsicas.plots import plot_cycle, plot_cycles
    view = _cycle(_pulses(TAU, UPPER + LOWER))
    return view, plot_cycle(view), plot_cycles([view, view])


def test_no_legend_of_figs_6_to_9_hides_data_even_where_curves_fill_the_panel(chattering):
    """The flow rates cross through every corner of their panel (as Q1 and Q2 do at
    U* = 8.5): their legend goes beside the panel; the spectrum's upper right is free:
    its legend stays inside."""
    _, *figures = chattering
    for fig in figures:
        assert _hidden(fig) == []
        flow = _panel(fig, "flow rate")
        assert flow.get_legend().get_window_extent().x0 >= flow.get_window_extent().x1
        spectrum = _panel(fig, "tip-velocity amplitude")
        assert spectrum.get_window_extent().contains(*spectrum.get_legend()
                                                     .get_window_extent().get_points().mean(0))
    labels = [t.get_text() for t in _panel(figures[0], "flow rate").get_legend().get_texts()]
    assert labels == ["$Q_1$ (above)", "$Q_2$ (below)", "steady state"]


def test_the_first_whole_contact_is_zoomed_and_shows_each_impact(chattering):
    view, *figures = chattering
    lo, hi, count = first_contact(view)
    assert count == len(LOWER)                          # the upper stay is cut by the start
    assert lo == pytest.approx(LOWER[0] - 1e-3, abs=3e-4)
    assert hi == pytest.approx(LOWER[-1] + 1e-3, abs=3e-4)
    for fig in figures:
        zooms = [ax for ax in fig.axes if ax.get_title().startswith("first contact")]
        assert zooms
        for zoom in zooms:                               # one per case
            assert "3 impacts" in zoom.get_title()
            x0, x1 = zoom.get_xlim()
            assert x0 < LOWER[0] - 1e-3 and x1 > LOWER[-1] + 1e-3      # the whole episode
            assert x1 - x0 < 0.1                                       # its own time scale
            t, f = zoom.lines[0].get_data()
            peaks = np.flatnonzero((f[1:-1] > f[:-2]) & (f[1:-1] >= f[2:]) & (f[1:-1] > 500))
            assert len(peaks) == 3 and t.min() >= x0 and t.max() <= x1
            assert "t/T_0" in zoom.get_xlabel()
        assert _panel(fig, "impact force").get_xlim() == (0.0, 1.0)
    assert len([ax for ax in figures[1].axes if ax.get_title().startswith("first contact")]) == 2


def test_without_a_whole_episode_the_cut_one_is_shown():
    """A cycle whose only contact is cut by its start still shows it."""
    view = _cycle(_pulses(TAU, (0.0, 0.02, 0.05)))
    lo, hi, count = first_contact(view)
    assert count == 3 and lo == 0.0 and hi == pytest.approx(0.051, abs=3e-4)


CODE = re.compile(r"\b[a-z]+_[a-z_]+\b")          # a status code such as impacting_lco


def _texts(fig) -> list:
    texts = [fig.get_suptitle()] + [t.get_text() for t in fig.texts]
    for ax in fig.axes:
        texts += [ax.get_title(), *(t.get_text() for t in ax.texts)]
        if ax.get_legend() is not None:
            texts += [t.get_text() for t in ax.get_legend().get_texts()]
    for legend in fig.legends:
        texts += [t.get_text() for t in legend.get_texts()]
    return [re.sub(r"\$[^$]*\$", "", t) for t in texts]   # mathtext's subscripts aside


def test_titles_and_legends_use_words_not_status_codes(chattering):
    """No status code (snake_case) in a title, text or legend; a cycle without contact
    says so where its zoom would be."""
    from types import SimpleNamespace

    from fsicas import Scene
    from fsicas.plots import plot_cycle, plot_map
    from fsicas.plots.backend import OUTCOME_WORDS
    view, one, two = chattering
    free = CycleView(**{**view.__dict__, "outcome": "unsettled", "settled": False,
                        "force": np.zeros_like(TAU)})
    assert first_contact(free) is None
    points = [{"ustar": 2.0 + k, "mstar": 1.0, "outcome": kind}
              for k, kind in enumerate(OUTCOME_WORDS)]
    result = SimpleNamespace(points=points, scene=Scene(zeta=0.01, modes=6),
                             boundary={"mstar": [1.0], "ustar_crit": [5.5], "omega": [45.0]})
    three = plot_cycle(free)
    for fig in (one, two, three, plot_map(result)):
        texts = _texts(fig)
        assert not [t for t in texts if CODE.search(t)], texts
    assert "$N$ = 3" in one.get_suptitle() and "$k^*$ = 1e+08" in two.get_suptitle()
    assert "not settled" in three.get_suptitle()
    assert any("no wall contact" in t.get_text() for ax in three.axes for t in ax.texts)


@pytest.mark.slow
def test_a_chattering_run_shows_its_impacts_in_the_zoom(tmp_path):
    """U* = 8.5, N = 6, t_end = 2 (about a minute): the settled impacting cycle hits each
    wall three times in quick succession; the zoom panel shows more than one impact peak,
    each a separate contact interval of the run's own force samples."""
    from fsicas.plots import cycle_view, plot_cycle
    from fsicas.timedomain.impacting_run import impacting_run
    view = cycle_view(impacting_run(8.5, 6, t_end=2.0))
    fig = plot_cycle(view, tmp_path / "cycle.png")
    zoom = next(ax for ax in fig.axes if ax.get_title().startswith("first contact"))
    x0, x1 = zoom.get_xlim()
    on = view.force > 0
    starts = view.tau[1:][on[1:] & ~on[:-1]]
    assert np.sum((starts > x0) & (starts < x1)) > 1
    assert _hidden(fig) == []
