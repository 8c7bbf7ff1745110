"""Plotting is free of side effects on the user's Matplotlib session; only the CLI
selects the file backend."""
import os
import subprocess
import sys

import matplotlib
import pytest

from fsicas import Scene, build_model, linear_stability
from fsicas.cli import main

#: A backend a user could have chosen; not the CLI's Agg, so a library call of
#: ``matplotlib.use("Agg")`` would show.
USER_BACKEND = "pdf"


@pytest.fixture
def user_backend():
    """The session's backend set to USER_BACKEND for the test, restored afterwards."""
    before = matplotlib.get_backend()
    matplotlib.use(USER_BACKEND)
    yield USER_BACKEND
    matplotlib.use(before)


def test_importing_and_drawing_keeps_the_users_backend(user_backend, tmp_path):
    import fsicas.plots
    from fsicas.plots import plot_eigenvalues
    scene = Scene(modes=3)
    plot_eigenvalues(linear_stability(scene, build_model(scene)), scene, tmp_path / "eig.png")
    assert (tmp_path / "eig.png").stat().st_size > 0
    assert matplotlib.get_backend() == user_backend
    assert fsicas.plots.pyplot().get_backend() == user_backend


def test_a_fresh_session_keeps_its_backend_after_drawing(tmp_path):
    """In a new interpreter whose default backend comes from MPLBACKEND (as a notebook's
    does from its kernel), importing fsicas.plots and drawing leaves it unchanged."""
    code = ("import matplotlib, fsicas.plots as fp; from fsicas import Scene, build_model, "
            "linear_stability; s = Scene(modes=3); "
            f"fp.plot_eigenvalues(linear_stability(s, build_model(s)), s, {str(tmp_path / 'e.png')!r}); "
            "print(matplotlib.get_backend())")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                          env={**os.environ, "MPLBACKEND": USER_BACKEND})
    assert done.stdout.strip() == USER_BACKEND


def test_cli_selects_the_file_backend_when_it_writes_a_figure(user_backend, tmp_path, capsys):
    assert main(["modes", "--modes", "2", "--json"]) == 0
    assert matplotlib.get_backend() == user_backend            # no figure: left alone
    assert main(["eig", "--modes", "3", "--plot", str(tmp_path / "e.png"), "--json"]) == 0
    assert matplotlib.get_backend().lower() == "agg"
    assert (tmp_path / "e.png").stat().st_size > 0



def test_return_period_of_an_unsettled_run_is_its_last_tip_return():
    """The period shown for a run without a settled cycle: the last interval between
    upward tip crossings, here of a signal whose period drifts from 0.10 to 0.11."""
    from types import SimpleNamespace

    import numpy as np

    from fsicas.plots.timedomain import return_period
    t = np.linspace(0.0, 2.0, 200001)
    period = 0.10 + 0.005 * t                          # instantaneous period
    phase = np.cumsum(np.r_[0.0, np.diff(t) / period[1:]])
    run = SimpleNamespace(trajectory=SimpleNamespace(t=t, tip=np.sin(2 * np.pi * phase)))
    k = np.flatnonzero(np.diff(np.floor(phase)) > 0)  # completed cycles
    expected = t[k[-1]] - t[k[-2]]
    assert abs(return_period(run) - expected) < 1e-4
    flat = SimpleNamespace(trajectory=SimpleNamespace(t=t, tip=np.zeros_like(t)))
    assert return_period(flat) is None


# --- the figures' content -------------------------------------------------------------

import numpy as np  # noqa: E402


@pytest.fixture(scope="module")
def boundary6():
    """Fig. 2's boundary at N = 6 on 9 M* in [0.03, 30] (refined; about 1.5 s): four mode
    switches (crossings and folds), the stretches of modes 2-5."""
    from fsicas.linear.boundary import stability_boundary
    scene = Scene(mstar=1.0, ustar=5.0, hstar=0.1, friction=0.14, modes=6)
    model = build_model(scene)
    return stability_boundary(scene, np.logspace(-1.5, 1.5, 9), model), model


@pytest.fixture(scope="module")
def lco_view():
    """The last cycle of a contact-free limit cycle (M* = 1, U* = 6.5, zeta = 0.01, N = 4;
    a run of about 0.6 s that settles), as the figures see it."""
    from fsicas.plots import cycle_view
    from fsicas.timedomain.run import run_case
    run = run_case(Scene(mstar=1.0, ustar=6.5, zeta=0.01, modes=4), t_end=20.0)
    assert run.outcome.outcome == "lco"
    return cycle_view(run)


def _panels(fig):
    """The figure's visible data axes (no colour bars)."""
    return [ax for ax in fig.axes if ax.get_visible() and ax.get_label() != "<colorbar>"]


def _branch_lines(ax):
    return [line for line in ax.lines if (line.get_gid() or "").startswith("branch")]


def test_fig2_draws_each_branch_up_to_its_located_switch(boundary6):
    from fsicas.plots import plot_boundary
    boundary, _ = boundary6
    fig = plot_boundary(boundary)
    left, mid, crit = _panels(fig)
    switches = boundary.switches
    assert len(switches) >= 3 and all(s.located for s in switches)
    lines = _branch_lines(left)
    assert len(lines) == len(switches) + 1         # one line per stretch, none across a switch
    for line, (before, after) in zip(lines, zip([None, *switches], [*switches, None])):
        m, u = line.get_data()
        if before is not None:                     # starts at the switch, on its upper branch
            assert m[0] == pytest.approx(before.mstar) and u[0] == pytest.approx(before.ustar_above)
        if after is not None:                      # ends at the switch, on its lower branch
            assert m[-1] == pytest.approx(after.mstar) and u[-1] == pytest.approx(after.ustar_below)
        assert not any(m[0] < s.mstar < m[-1] for s in switches)
        assert len(m) > 8                          # through the traced curve, not only samples
    for line in _branch_lines(mid):                # no jump of frequency inside a stretch
        w = line.get_ydata()
        assert np.all(np.maximum(w[1:], w[:-1]) / np.minimum(w[1:], w[:-1]) < 1.2)
    assert "$M^*$" in left.get_xlabel() and "$U^*_c$" in left.get_ylabel()
    assert r"$\omega/\omega_1$" in mid.get_ylabel() and r"$\ell_1$" in crit.get_ylabel()
    # l1 is not joined across a switch: one line per stretch of one branch
    branches = [p.branch for p in boundary.points if p.l1 is not None]
    stretches = 1 + sum(a != b for a, b in zip(branches[:-1], branches[1:]))
    assert len(crit.lines) - 1 == stretches >= len(switches) + 1      # less the zero line
    assert all("nondim" in ax.get_ylabel() for ax in (left, mid, crit))
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert {"mode 2", "mode 3", "mode 4", "mode 5"} <= set(legend)
    marks = [t.get_text() for t in left.texts]
    assert marks == [f"({c})" for c in "abcde"[:len(lines)]]


def test_fig3_shows_the_marked_points_on_a_labelled_grid(boundary6):
    from fsicas.plots import plot_mode_shapes
    from fsicas.linear.stretches import marked_points
    boundary, model = boundary6
    fig = plot_mode_shapes(boundary, model)
    panels, marks = _panels(fig), marked_points(boundary)
    assert len(panels) == len(marks) == 5
    rows = {ax.get_subplotspec().rowspan.start for ax in panels}
    cols = {ax.get_subplotspec().colspan.start for ax in panels}
    assert len(rows) == 2 and len(cols) == 4
    for ax, (letter, _, p) in zip(panels, marks):
        assert ax.get_title().startswith(f"({letter}) $M^*$ = {p.mstar:.3g}")
        if ax.get_subplotspec().colspan.start == 0:
            assert "$y/" in ax.get_ylabel()
    assert sum("$x/L$" in ax.get_xlabel() for ax in panels) == 4   # bottom of each column
    assert {"real part", "imaginary part", "motion"} <= {t.get_text() for t in fig.legends[0].get_texts()}
    size = fig.get_size_inches()
    assert size[0] / size[1] < 3                   # a grid, not one long row


def test_boundary_variants_break_their_lines_at_switches(boundary6):
    from fsicas.plots import plot_boundary_variants
    boundary, _ = boundary6
    fig = plot_boundary_variants({"reference": boundary})
    left = _panels(fig)[0]
    lines = [line for line in left.lines if "branch" in (line.get_gid() or "")]
    assert len(lines) == len(boundary.switches) + 1
    for line in lines:
        m = line.get_xdata()
        assert not any(m[0] < s.mstar < m[-1] for s in boundary.switches)
    assert "$U^*_c$" in left.get_ylabel() and fig.legends


def _map_result(points, boundary):
    from types import SimpleNamespace
    return SimpleNamespace(points=points, boundary=boundary, scene=Scene(zeta=0.01, modes=6))


def test_fig4_draws_the_dense_boundary_and_keeps_the_legend_off_the_points(boundary6):
    from fsicas.plots import plot_map
    boundary, _ = boundary6
    points = [{"ustar": u, "mstar": m, "outcome": "decay" if u < 6 else "contact"}
              for m in (0.1, 1.0, 10.0) for u in np.linspace(2, 16, 8)]
    fig = plot_map(_map_result(points, {"mstar": [1.0], "ustar_crit": [5.5], "omega": [45.0]}),
                   linear=boundary)
    ax = _panels(fig)[0]
    lines = _branch_lines(ax)
    assert len(lines) == len(boundary.switches) + 1
    assert sum(len(line.get_xdata()) for line in lines) > 50          # dense, not 7 samples
    fig.canvas.draw()
    legend_box, axes_box = fig.legends[0].get_window_extent(), ax.get_window_extent()
    assert legend_box.x0 >= axes_box.x1                               # beside the axes
    assert {"decays to the steady state", "reaches the wall", "linear stability boundary"} <= \
        {t.get_text() for t in fig.legends[0].get_texts()}
    assert "$U^*$" in ax.get_xlabel() and "$M^*$" in ax.get_ylabel()


def test_fig4_without_a_dense_boundary_breaks_the_samples_at_frequency_jumps():
    from fsicas.plots import plot_map
    samples = {"mstar": [0.1, 0.3, 1.0, 3.0, 10.0], "ustar_crit": [3.9, 3.4, 5.5, 7.2, 9.8],
               "omega": [18.0, 18.5, 45.0, 88.0, 99.0]}    # jumps between 0.3, 1 and 3
    fig = plot_map(_map_result([{"ustar": 4.0, "mstar": 1.0, "outcome": "lco"}], samples))
    drawn = [line for line in _panels(fig)[0].lines if line.get_label() != "_nolegend_"
             and line.get_color() == "k"]
    assert [list(line.get_ydata()) for line in drawn] == [[0.1, 0.3], [1.0], [3.0, 10.0]]


def test_tip_spectrum_puts_the_harmonics_on_their_bins():
    """A periodic signal of odd harmonics over a span that is no whole number of periods,
    plus noise 1e-6: every peak above 1e-4 of the largest is a harmonic k f0, and the floor
    between harmonics stays 4 decades down."""
    from fsicas.plots import tip_spectrum
    T, rng = 0.13, np.random.default_rng(0)
    t = np.arange(0.0, 3.37, 2e-5)
    v = sum(np.sin(2 * np.pi * k * t / T + k) / k ** 2 for k in (1, 3, 5, 7, 9))
    f, a = tip_spectrum(t, v + 1e-6 * rng.standard_normal(t.size), T)
    peaks = [k for k in range(1, len(a) - 1) if a[k] > a[k - 1] and a[k] > a[k + 1] and a[k] > 1e-4]
    assert np.allclose(f[peaks], np.round(f[peaks]), atol=1e-9)
    assert set(np.round(f[peaks]).astype(int)) == {1, 3, 5, 7, 9}
    between = (np.abs(f - np.round(f)) >= 0.5) & (f < 12)
    assert a[between].max() < 1e-4


def test_cycle_figure_labels_every_panel_and_shows_every_mode(lco_view, tmp_path):
    from fsicas.plots import plot_cycle
    fig = plot_cycle(lco_view, tmp_path / "cycle.pdf")
    assert (tmp_path / "cycle.pdf").read_bytes()[:5] == b"%PDF-"
    panels = _panels(fig)
    assert len(panels) == 9                       # Figs. 6-9 and the first contact zoomed
    for ax in panels:
        assert ax.get_xlabel() and ax.get_ylabel(), ax.get_title()
        assert "(units of" in ax.get_ylabel() or "nondim" in ax.get_ylabel(), ax.get_ylabel()
    velocities = next(ax for ax in panels if "$r_n$" in ax.get_ylabel())
    assert len(velocities.lines) == lco_view.modes
    title = fig.get_suptitle()
    assert "limit cycle" in title and "_" not in title.replace("$T_0$", "")
    assert "$N$ = 4" in title and "no contact law" in title
    spectrum = next(ax for ax in panels if "spectrum" in ax.get_title())
    f, a = spectrum.lines[0].get_data()
    top = np.argsort([a[k] if a[k] >= max(a[k - 1], a[k + 1]) else 0 for k in range(1, len(a) - 1)])
    strongest = f[1:-1][top[-3:]]
    assert np.allclose(strongest, np.round(strongest), atol=1e-9)     # harmonics of 1/T0
    assert set(np.round(strongest).astype(int)) == {1, 3, 5}           # symmetric cycle: odd


def test_cycles_side_by_side_one_column_per_case(lco_view):
    from dataclasses import replace

    from fsicas.plots import plot_cycles
    other = replace(lco_view, ustar=7.0, outcome="impacting_lco")
    fig = plot_cycles([lco_view, other])
    panels = _panels(fig)
    assert len(panels) == 18
    cols = {ax.get_subplotspec().colspan.start for ax in panels}
    assert cols == {0, 1}
    tops = [ax for ax in panels if ax.get_subplotspec().rowspan.start == 0]
    titles = [ax.get_title() for ax in tops]
    assert titles[0].startswith("(1a) $U^*$ = 6.5") and titles[1].startswith("(1b) $U^*$ = 7")
    assert "impacting limit cycle" in titles[1] and "impacting_lco" not in titles[1]
    assert all(ax.get_ylabel() for ax in panels if ax.get_subplotspec().colspan.start == 0)


def test_vector_output_and_labels_inside_the_figure(tmp_path):
    from fsicas.plots import plot_eigenvalues
    scene = Scene(modes=3, ustar=6.0)
    result = linear_stability(scene, build_model(scene))
    plot_eigenvalues(result, scene, tmp_path / "eig.pdf")
    plot_eigenvalues(result, scene, tmp_path / "eig.svg")
    assert (tmp_path / "eig.pdf").read_bytes()[:5] == b"%PDF-"
    assert b"<svg" in (tmp_path / "eig.svg").read_bytes()[:2000]
    fig = plot_eigenvalues(result, scene)
    fig.canvas.draw()
    ax = fig.axes[0]
    box = ax.yaxis.label.get_window_extent()
    assert box.x0 >= 0 and ax.xaxis.label.get_window_extent().y0 >= 0     # not cut
    assert "\\lambda" in ax.get_xlabel() and "\\lambda" in ax.get_ylabel()


def test_drawing_leaves_the_users_rcparams_alone(boundary6, lco_view):
    from fsicas.plots import plot_boundary, plot_cycle
    before = {k: v for k, v in matplotlib.rcParams.items() if k != "backend"}
    fig = plot_boundary(boundary6[0])
    plot_cycle(lco_view)
    after = {k: v for k, v in matplotlib.rcParams.items() if k != "backend"}
    assert after == before
    assert fig.axes[0].yaxis.label.get_fontsize() == 9                 # the figure's own style
    assert fig.axes[0].yaxis.label.get_fontfamily()[0] == "serif"


def _synthetic_curves():
    """A grazing curve U* = 7 + log10 M* and a fold curve U* = 3.5 at M* in [0.1, 0.3]."""
    from fsicas.cycles.curves import CurveMap, CurvePoint, CycleCurve
    point = lambda m, u: CurvePoint(m, u, 0.1, 0.05, 1.0, True, np.zeros(2))
    graze = [point(m, 7 + np.log10(m)) for m in np.geomspace(0.1, 10, 30)]
    fold = [point(m, 3.5) for m in np.geomspace(0.1, 0.3, 5)]
    return CurveMap([CycleCurve("grazing", graze[10], graze, ("bound", "bound"), "", 0.0)],
                    [CycleCurve("fold", fold[2], fold, ("bound", "stopped"), "", 0.0)],
                    [1.0], [], 0.0)


def test_fig4_draws_the_curves_the_band_and_the_cases(boundary6):
    from fsicas.plots import plot_map
    boundary, _ = boundary6
    points = [{"ustar": 4.0, "mstar": 1.0, "outcome": "lco"}]
    fig = plot_map(_map_result(points, {"mstar": [1.0], "ustar_crit": [5.5], "omega": [45.0]}),
                   linear=boundary, curves=_synthetic_curves(), cases=[("1a", 7.0, 1.0)])
    labels = {t.get_text() for t in fig.legends[0].get_texts()}
    assert {"grazing (first contact)", "fold of cycles", "contact-free cycles",
            "cases of Figs. 6-9"} <= labels
    ax = _panels(fig)[0]
    assert any(t.get_text() == "1a" for t in ax.texts)
    grazing = [line for line in ax.lines if line.get_label() == "grazing (first contact)"]
    assert np.allclose(grazing[0].get_xdata(), 7 + np.log10(grazing[0].get_ydata()))


#: Two curves whose ends stopped for four reasons, with the messages ``_trace`` writes
#: (the continuation's own wording of each status).
_ENDED = (("grazing", ("bound", "max_steps"),
           "lower M*: bound (parameter log10_mstar = -1.00521 left [-1, 1]); higher M*: "
           "max_steps (reached max_steps = 149)"),
          ("fold", ("stopped", "bound"),
           "lower M*: stopped (the cycles reached the wall (min gap below eps)); higher M*: "
           "bound (parameter kinematic_pressure_drop = 8.69577 left [0, 8.448])"))


def test_fig4_legend_names_the_switch_jumps_and_why_each_curve_ends(boundary6):
    from dataclasses import replace

    from fsicas.cycles.curves import CurveMap
    from fsicas.plots import plot_map
    boundary, _ = boundary6
    synthetic = _synthetic_curves()
    grazing, fold = (replace(c, status=status, message=message) for c, (_, status, message)
                     in zip((synthetic.grazing[0], synthetic.fold[0]), _ENDED))
    assert [r for _, r in grazing.ends()] == ["mstar_window", "budget"]
    assert [r for _, r in fold.ends()] == ["wall", "ustar_bound"]
    points = [{"ustar": 4.0, "mstar": 1.0, "outcome": "lco"}]
    fig = plot_map(_map_result(points, {"mstar": [1.0], "ustar_crit": [5.5], "omega": [45.0]}),
                   linear=boundary, curves=CurveMap([grazing], [fold], [1.0], [], 0.0))
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "jump of $U^*_c$ at a branch switch" in labels
    assert {"end: edge of the $M^*$ window", "end: point budget used up (unfinished)",
            "end: its cycles reach the wall", "end: the $U^*$ limit of the map"} <= set(labels)
    ax = _panels(fig)[0]
    jumps = [line for line in ax.lines if line.get_gid() == "mode switch"]
    assert len(jumps) == len(boundary.switches)
    for s, line in zip(boundary.switches, jumps):           # across in U*, at the switch's M*
        assert sorted(line.get_xdata()) == sorted([s.ustar_below, s.ustar_above])
    marks = {line.get_gid(): line.get_xydata().tolist() for line in ax.lines
             if (line.get_gid() or "").startswith("curve end")}
    last = grazing.points[-1]
    assert marks["curve end: budget"] == [[last.ustar, last.mstar]]
    first = fold.points[0]
    assert marks["curve end: wall"] == [[first.ustar, first.mstar]]


def test_curves_give_each_map_point_its_expected_outcome():
    """Below the boundary decay, between the fold curve and the boundary either, from the
    boundary to the grazing curve lco, beyond contact; an outcome across a curve is an
    exception."""
    from fsicas.cycles.curves import expected_outcomes, lowest_ustar
    from fsicas.paper import consistency
    curves = _synthetic_curves()
    hopf = lambda m: np.full(np.shape(m), 4.0)
    assert lowest_ustar(curves.grazing, [1.0, 100.0]) == pytest.approx([7.0, np.nan],
                                                                      nan_ok=True)
    u = [3.0, 3.7, 5.0, 7.5, 5.0]
    m = [1.0, 0.2, 1.0, 1.0, 20.0]
    assert expected_outcomes(curves, hopf, u, m) == ["decay", "bistable", "lco", "contact",
                                                     "unknown"]
    outcomes = ["decay", "lco", "lco", "contact", "contact"]

    class Map:
        points = [{"ustar": a, "mstar": b, "outcome": o} for a, b, o in zip(u, m, outcomes)]
        points += [{"ustar": 5.0, "mstar": 1.0, "outcome": "contact"}]      # across a curve
    report = consistency(Map(), curves, hopf)
    assert report["consistent"] == 5
    assert report["exceptions"] == [{"ustar": 5.0, "mstar": 1.0, "outcome": "contact",
                                     "expected": "lco"}]


def test_the_cycle_branch_figure_says_how_the_branch_ended(tmp_path):
    """The title tells the branch's end in words, not its status code."""
    from fsicas.cycles import CycleSettings, cycle_branch
    from fsicas.plots.cycles import plot_branch
    branch = cycle_branch(Scene(mstar=1.0, zeta=0.01, modes=4), ustar_max=30.0,
                          settings=CycleSettings(max_points=4))
    assert branch.status == "max_points"
    fig = plot_branch(branch, tmp_path / "branch.png")
    assert "stopped at its point budget" in fig.get_suptitle()
    assert "max_points" not in fig.get_suptitle()


def test_a_run_without_contact_says_why_its_force_panel_is_empty():
    """plot_run of a contact-free limit cycle: the impact-force panel says there was no
    wall contact and that the contact law was off, instead of showing a bare zero line."""
    from fsicas.plots import plot_run
    from fsicas.timedomain.run import run_case
    run = run_case(Scene(mstar=1.0, ustar=6.5, zeta=0.01, modes=2), t_end=3.0)
    fig = plot_run(run)
    force = fig.axes[2]
    assert [t.get_text() for t in force.texts] == ["no wall contact in this run (contact law off)"]
    assert not np.any(force.lines[0].get_ydata())


def test_fig4_marks_the_generalized_hopf_points_and_their_fold_curves(boundary6):
    """A fold curve switched onto from a generalized Hopf point is drawn from its point,
    and the point is marked (one legend entry); without branch fold curves the curve is
    labelled as the fold of cycles."""
    from fsicas.cycles.bautin import SwitchedCurve
    from fsicas.linear.codim2 import CodimTwoPoint
    from fsicas.plots import plot_map
    boundary, _ = boundary6
    synthetic = _synthetic_curves()
    gh = CodimTwoPoint("gh", 0.3, 3.5, 40.0, True, {"l2": -1.0})
    switched = [SwitchedCurve(gh, synthetic.fold[0])]
    points = [{"ustar": 4.0, "mstar": 1.0, "outcome": "lco"}]
    result = _map_result(points, {"mstar": [1.0], "ustar_crit": [5.5], "omega": [45.0]})
    fig = plot_map(result, linear=boundary, curves=synthetic, switched=switched)
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels.count("fold of cycles") == 1
    assert "generalized Hopf: $l_1$ = 0, a fold curve is born" in labels
    ax = _panels(fig)[0]
    (mark,) = [line for line in ax.lines if line.get_marker() == "P"]
    assert mark.get_xydata().tolist() == [[3.5, 0.3]]
    fig = plot_map(result, linear=boundary, switched=switched)
    assert "fold of cycles" in [t.get_text() for t in fig.legends[0].get_texts()]


def test_a_long_title_breaks_into_lines_that_fit_a_one_panel_figure():
    from fsicas.plots.backend import styled, subplots, suptitle
    text = (r"complex mode shapes at the marked points of Fig. 2 ($H^*$ = 0.1, $f$ = 0.14, "
            r"$\zeta$ = 0, $N$ = 10, $K_L$ = 1)")

    @styled
    def draw():
        fig, _ = subplots(1, 1, figsize=(2.3, 2.2))
        return fig, suptitle(fig, text)
    fig, title = draw()
    lines = title.get_text().split("\n")
    assert len(lines) >= 3
    assert " ".join(lines) == text                          # every word kept, in order
    assert not any(line.endswith(("=", "$f$")) for line in lines)   # "a = b" not split
    renderer = fig.canvas.get_renderer()
    for line in lines:                                      # each line alone fits the figure
        title.set_text(line)
        assert title.get_window_extent(renderer).width <= fig.bbox.width
    matplotlib.pyplot.close(fig)
