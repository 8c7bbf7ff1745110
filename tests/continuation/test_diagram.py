"""The bifurcation diagram by itself, on systems whose branches are known in closed form."""

import casadi as ca
import numpy as np
import pytest

import continuation as C


def _field(expr):
    """``(x, p) -> F`` of ``expr(x, p)`` on three states and one parameter ``mu``."""
    x, p = ca.SX.sym("x", 3), ca.SX.sym("p", 1)
    return ca.Function("F", [x, p], [ca.vertcat(*expr(x, p[0]))])


def _settings(**kw):
    base = dict(ds=0.02, ds_max=0.05, max_steps=200, bounds={"mu": (-0.5, 1.0)})
    return C.ContinuationSettings(**{**base, **kw})


def _pitchfork(x, mu):
    """x' = mu x - x^3 (a pitchfork at mu = 0: x = +-sqrt(mu)), y' = -y, z' = -2 z."""
    return mu * x[0] - x[0] ** 3, -x[1], -2 * x[2]


def test_the_diagram_finds_both_halves_of_a_pitchfork():
    problem = C.EquilibriumProblem(_field(_pitchfork), [0, 0, 0], {"mu": -0.5}, "mu")
    diagram = C.bifurcation_diagram(problem, _settings(), depth=1)
    root = diagram.root
    assert [n.birth.kind for n, _ in root.walk()] == ["start", "bp", "bp"]
    assert abs(root.branch.special("bp")[0].params["mu"]) < 1e-10
    halves = [child.branch for child in root.children]
    assert sorted(np.sign(b.x[1:, 0]).mean() for b in halves) == [-1, 1]
    for b in halves:
        mu, u = b.par("mu"), b.x[:, 0]
        assert b.status == "bound" and mu[-1] > 0.9
        # x = +-sqrt(mu) up to the corrector's residual 1e-10 over |F_x| = 2 mu
        err = np.abs(u - np.sign(u) * np.sqrt(mu))
        assert np.all(err * 2 * mu <= 1.01e-10 + 1e-15)
        assert b.stable.all()
    stable = root.branch.stable                                       # trivial: stable below 0
    assert stable[root.branch.par("mu") < -1e-6].all()
    assert not stable[root.branch.par("mu") > 1e-6].any()


def _hopf(x, mu):
    """r' = r (mu - r^2), theta' = 1 in (x, y), z' = -z: a supercritical Hopf point at
    mu = 0, cycles of radius sqrt(mu), amplitude (peak to peak) 2 sqrt(mu)."""
    r2 = x[0] ** 2 + x[1] ** 2
    return (mu - r2) * x[0] - x[1], x[0] + (mu - r2) * x[1], -x[2]


def test_the_diagram_finds_the_cycles_of_a_hopf_point():
    problem = C.EquilibriumProblem(_field(_hopf), [0, 0, 0], {"mu": -0.5}, "mu")
    diagram = C.bifurcation_diagram(problem, _settings(), depth=1,
                                    cycle_settings=_settings(max_steps=60, ds_max=0.2),
                                    collocation=C.CollocationSettings(ntst=20, ncol=4))
    (node,) = diagram.root.children
    cycles = node.branch
    assert node.birth.kind == "hopf" and cycles.kind == "cycle"
    mu = cycles.par("mu")
    assert np.all(mu > 0) and mu[-1] > 0.5
    _assert_circle(cycles, np.sqrt(mu), (0, 1))
    assert np.max(np.abs(cycles.columns["period"] - 2 * np.pi)) < 1e-8
    assert cycles.stable.all()


def _assert_circle(cycles, radius, plane):
    """The cycles' u(0) (a mesh point) at ``radius`` in ``plane`` (to 5e-8: near the Hopf
    point the radial contraction is weak, and a residual of 1e-10 leaves more); their peak-to-peak
    amplitude, taken on the collocation nodes (NTST NCOL = 80 of them around the circle),
    between 2 radius cos(pi / 80) and 2 radius."""
    assert np.max(np.abs(np.linalg.norm(cycles.x[:, plane], axis=1) - radius)) < 5e-8
    amplitude = cycles.columns["amplitude"]
    assert np.all(amplitude <= 2 * radius * (1 + 1e-8))
    assert np.all(amplitude >= 2 * radius * np.cos(np.pi / 80) * (1 - 1e-8))


def _bp_then_hopf(x, mu):
    """x' = mu x - x^3 (pitchfork at 0); (y, z) rotate with growth x^2 - 1/4 - r^2: no
    Hopf point on x = 0, one at mu = 1/4 on each half x = +-sqrt(mu), whose cycles have
    radius sqrt(mu - 1/4)."""
    g = x[0] ** 2 - 0.25 - x[1] ** 2 - x[2] ** 2
    return mu * x[0] - x[0] ** 3, g * x[1] - x[2], x[1] + g * x[2]


def test_depth_two_reaches_the_hopf_points_of_the_switched_branches():
    problem = C.EquilibriumProblem(_field(_bp_then_hopf), [0, 0, 0], {"mu": -0.5}, "mu")
    kw = dict(cycle_settings=_settings(max_steps=30, ds_max=0.1),
              collocation=C.CollocationSettings(ntst=20, ncol=4))
    shallow = C.bifurcation_diagram(problem, _settings(), depth=1, **kw)
    assert [n.branch.kind for n in shallow.nodes()] == ["equilibrium"] * 3
    record = lambda problem, X: {"x0_mean": float(np.mean(  # noqa: E731
        problem.nodes(X)[:, 0] if problem.kind == "cycle" else X[:1]))}
    diagram = C.bifurcation_diagram(problem, _settings(), depth=2, record=record, **kw)
    nodes = list(diagram.root.walk())
    assert [(n.birth.kind, n.branch.kind, d) for n, d in nodes] == [
        ("start", "equilibrium", 0), ("bp", "equilibrium", 1), ("hopf", "cycle", 2),
        ("bp", "equilibrium", 1), ("hopf", "cycle", 2)]
    assert not diagram.root.branch.special("hopf")
    for half in diagram.root.children:
        (hopf,) = half.branch.special("hopf")
        assert abs(hopf.params["mu"] - 0.25) < 1e-9
        cycles = half.children[0].branch
        mu = cycles.par("mu")
        assert np.all(mu > 0.25) and cycles.stable.all()
        _assert_circle(cycles, np.sqrt(mu - 0.25), (1, 2))
        # the cycles keep the half's x = +-sqrt(mu) (also the record's column)
        side = np.sign(half.branch.x[-1, 0])
        assert np.max(np.abs(cycles.x[:, 0] - side * np.sqrt(mu))) < 1e-8
        assert np.max(np.abs(cycles.columns["x0_mean"] - side * np.sqrt(mu))) < 1e-8


def _bubble(x, mu):
    """x' = mu (1 - mu) x - x^3: two pitchforks, at mu = 0 and mu = 1, joined by one closed
    branch, the circle (mu - 1/2)^2 + x^2 = 1/4."""
    return mu * (1 - mu) * x[0] - x[0] ** 3, -x[1], -x[2]


def test_a_branch_reached_twice_is_kept_once():
    """The circle is reached from both pitchforks, each with two halves, and from the
    circle the trivial branch is reached again at both, with two halves each: one
    circle and one trivial branch are kept; of the other seven switches, three retrace the
    circle and four the trivial branch."""
    problem = C.EquilibriumProblem(_field(_bubble), [0, 0, 0], {"mu": -0.5}, "mu")
    diagram = C.bifurcation_diagram(problem, _settings(bounds={"mu": (-0.5, 1.5)}), depth=2)
    root = diagram.root
    assert [round(p.params["mu"], 9) for p in root.branch.special("bp")] == [0.0, 1.0]
    (circle,) = root.children
    b = circle.branch
    assert b.message.startswith("closed")
    circle_error = np.abs((b.par("mu") - 0.5) ** 2 + b.x[:, 0] ** 2 - 0.25)
    # at the pitchforks F is flat in x: a residual of 1e-10 leaves x off by ~1e-3 there
    assert np.max(circle_error) < 1e-6 and np.max(circle_error[np.abs(b.x[:, 0]) > 0.05]) < 1e-9
    assert b.x[:, 0].max() > 0.49 and b.x[:, 0].min() < -0.49           # all of it
    reasons = sorted(s["reason"] for s in diagram.skipped)
    assert reasons == ["retraces branch 0"] * 4 + ["retraces branch 1"] * 3


def test_save_and_load_keep_the_tree(tmp_path):
    problem = C.EquilibriumProblem(_field(_bp_then_hopf), [0, 0, 0], {"mu": -0.5}, "mu")
    diagram = C.bifurcation_diagram(problem, _settings(), depth=2,
                                    cycle_settings=_settings(max_steps=5, ds_max=0.1),
                                    collocation=C.CollocationSettings(ntst=10, ncol=3))
    path = tmp_path / "diagram.npz"
    diagram.save(path)
    back = C.Diagram.load(path)
    assert back.depth == 2 and back.skipped == diagram.skipped
    pairs = list(zip(diagram.root.walk(), back.root.walk()))
    assert len(pairs) == len(diagram.nodes()) == 5
    for (a, da), (b, db) in pairs:
        assert da == db and a.birth == b.birth and len(a.children) == len(b.children)
        assert np.array_equal(a.branch.x, b.branch.x)
        assert np.array_equal(a.branch.params, b.branch.params)
        kinds = lambda branch: [p.kind for p in branch.special_points]  # noqa: E731
        assert kinds(a.branch) == kinds(b.branch)
        assert a.branch.columns.keys() == b.branch.columns.keys()
    with pytest.raises(ValueError, match="Diagram"):
        C.Diagram.load(_branch_file(tmp_path, diagram))


def _branch_file(tmp_path, diagram):
    path = tmp_path / "branch.npz"
    diagram.root.branch.save(path)
    return path


@pytest.mark.parametrize("kw, name", [({"depth": -1}, "depth"), ({"depth": 1.5}, "depth"),
                                      ({"amplitude": 0.0}, "amplitude"), ({"dp": -1}, "dp"),
                                      ({"switch": ("ns",)}, "switch"),
                                      ({"cycle_settings": 3}, "cycle_settings"),
                                      ({"record": 1}, "record")])
def test_bad_options_are_refused_before_any_work(kw, name):
    problem = C.EquilibriumProblem(_field(_pitchfork), [0, 0, 0], {"mu": -0.5}, "mu")
    with pytest.raises(ValueError, match=name):
        C.bifurcation_diagram(problem, **kw)
    with pytest.raises(ValueError, match="problem"):
        C.bifurcation_diagram("branch")


def test_plot_diagram_draws_every_branch():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from continuation.plotting import plot_diagram

    problem = C.EquilibriumProblem(_field(_pitchfork), [0, 0, 0], {"mu": -0.5}, "mu")
    diagram = C.bifurcation_diagram(problem, _settings(), depth=1)
    fig, ax = plt.subplots()
    plot_diagram(diagram, "mu", 0, ax)
    labels = [line.get_label() for line in ax.get_lines() if not line.get_label().startswith("_")]
    assert labels == ["equilibrium", "equilibrium from bp", "equilibrium from bp"]
    plt.close(fig)


def test_a_period_doubling_is_switched_onto_the_doubled_cycles(models):
    """The half-twisted circle (test_cycles_pd): period doubling at mu = 0 exactly; the
    doubled cycles (r - 1)^2 + z^2 = mu, period 4 pi, found from a cycle branch as root."""
    root = C.CycleProblem(models.half_twisted(), lambda t: np.c_[np.cos(2 * np.pi * t),
                                                                 np.sin(2 * np.pi * t), 0 * t],
                          6.0, {"mu": -0.3}, "mu", settings=C.CollocationSettings(ntst=20, ncol=4))
    diagram = C.bifurcation_diagram(root, C.ContinuationSettings(
        ds=0.05, ds_max=0.3, max_steps=30, bounds={"mu": (-1, 0.3)}), depth=1, amplitude=0.05)
    (node,) = diagram.root.children
    doubled = node.branch
    assert node.birth.kind == "pd" and abs(node.birth.params["mu"]) < 1e-10
    mu = doubled.par("mu")
    assert len(doubled) > 5 and np.all(mu > 0)
    assert np.max(np.abs(doubled.columns["period"] - 4 * np.pi)) < 1e-9
    r = np.hypot(doubled.x[:, 0], doubled.x[:, 1])
    assert np.max(np.abs((r - 1) ** 2 + doubled.x[:, 2] ** 2 - mu)) < 1e-8


def test_a_terminal_event_ends_the_branches_it_applies_to():
    """The cycles of the Hopf normal form end where their radius, measured at u(0), is 1/2
    (mu = 1/4); the equilibria (event function -1) run on to the bound."""
    problem = C.EquilibriumProblem(_field(_hopf), [0, 0, 0], {"mu": -0.5}, "mu")
    half = C.Event("half", lambda problem, X: float(np.hypot(X[0], X[1]) - 0.5)
                   if problem.kind == "cycle" else -1.0, terminal=True)
    diagram = C.bifurcation_diagram(problem, _settings(), depth=1, events=(half,),
                                    cycle_settings=_settings(max_steps=60, ds_max=0.2),
                                    collocation=C.CollocationSettings(ntst=20, ncol=4))
    assert diagram.root.branch.status == "bound"
    (node,) = diagram.root.children
    cycles = node.branch
    assert cycles.status == "event" and len(cycles.special("half")) == 1
    assert abs(cycles.par("mu")[-1] - 0.25) < 1e-8
    with pytest.raises(ValueError, match="events"):
        C.bifurcation_diagram(problem, events=(lambda p, X: 0.0,))


def test_a_cycle_branch_point_is_switched_onto_both_halves():
    """The ring of test_cycle_branch_points: z -> -z symmetric cycles (z = 0) lose their
    stability at MU_BP (closed form) to cycles with z != 0; the diagram leaves the branch
    point away from it (z of one sign) and through it onto the mirror half (the other)."""
    from .test_cycle_branch_points import MU_BP, T, _ring_orbit, _symmetric_ring

    root = C.CycleProblem(_symmetric_ring(), _ring_orbit, T, {"mu": MU_BP - 0.1}, "mu",
                          settings=C.CollocationSettings(ntst=20, ncol=4))
    steps = C.ContinuationSettings(ds=0.02, ds_max=0.05, max_steps=15,
                                   bounds={"mu": (MU_BP - 0.2, MU_BP + 0.1)})
    diagram = C.bifurcation_diagram(root, steps, depth=1)
    (bp,) = diagram.root.branch.special("bp")
    assert abs(bp.params["mu"] - MU_BP) < 1e-6
    halves = diagram.root.children
    assert [(n.birth.kind, n.birth.side) for n in halves] == [("bp", 1), ("bp", -1)]
    z_end = [n.branch.x[-1, 2] for n in halves]
    assert min(abs(z) for z in z_end) > 1e-2 and z_end[0] * z_end[1] < 0
    assert all(n.branch.stable[-1] for n in halves)
