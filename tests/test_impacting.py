"""Impacting limit cycles by multiple shooting (fsicas.cycles.impacting), against the library's
shooting Jacobian, collocation before contact and time integration after it."""

from dataclasses import replace

import numpy as np
import pytest

import continuation as C
from fsicas import Scene
from fsicas.cycles import CycleSettings
from fsicas.linear.adapter import PI, PI_SCALE, TIME_SCALE, flutter_field
from fsicas.cycles import StartCycle, impacting_cycles
from fsicas.cycles.impacting import ImpactSettings, cycle_from_trajectory, \
    pre_contact_start, shooting_points
from fsicas.model import build_model
from fsicas.timedomain.integrators import Settings, simulate
from fsicas.linear.steady import steady_state

#: the start cycle on the scene's nodes, those of the impacting branch
SCENE_NODES = CycleSettings(quadrature_tol=None)
IMPACT = dict(contact=True, contact_stiffness=1e8, contact_eps=1e-2, contact_smoothing=0.1)
#: four shooting points from 3 eps before the wall to the first impacting cycle (N = 4)
THROUGH = ImpactSettings(max_points=4, ds=0.08, ds_max=0.5)


def test_block_jacobian_equals_library_jacobian():
    """The per-segment sensitivity Jacobian (the library's default) equals the whole-graph
    one (CasADi AD through the mapped integrator) on the model at an arbitrary point,
    N = 2, 3 segments; the closing residual of shooting points from ``shooting_points``
    vanishes."""
    scene = Scene(mstar=1.0, ustar=6.0, zeta=0.01, modes=2, **IMPACT)
    model = build_model(scene)
    vf = flutter_field(model)
    st = steady_state(scene, model)
    params = dict(zip(vf.par_names, [st.pressure_drop / PI_SCALE, 0.0] +
                      [dict(zip(model.parameter_names, st.p))[k] for k in vf.par_names[2:]]))
    shoot = C.ShootingSettings(segments=3, abstol=1e-10, reltol=1e-10, floquet="product")
    x0 = st.x.copy()
    x0[model.n_modes] += 0.02                          # q1: the beam displaced, at rest
    orbit = shooting_points(vf, x0, 0.13 * TIME_SCALE, params, 3, shoot)
    problem = C.ShootingProblem(vf, orbit, 0.13 * TIME_SCALE, params, PI, settings=shoot)
    graph = C.ShootingProblem(vf, orbit, 0.13 * TIME_SCALE, params, PI,
                              settings=replace(shoot, jacobian="graph"))
    X = problem.X0
    r = problem.residual(X)
    assert np.max(np.abs(r[:2 * vf.n])) < 1e-8        # segments 0, 1 continue each other
    J, J0 = problem.jacobian(X), graph.jacobian(X)
    assert J.shape == J0.shape
    assert abs(J - J0).max() < 1e-6 * abs(J0).max()
    assert problem.blocks(X) is problem.blocks(X)      # kept for the multipliers


def test_cycle_from_trajectory_finds_subharmonic_period():
    """A synthetic period-3 signal: three tip swings of different heights."""
    scene = Scene(modes=2)
    model = build_model(scene)
    t = np.linspace(0.0, 6.0, 60001)
    base = np.sin(2 * np.pi * t / 0.1)
    x = np.zeros((t.size, model.n_state))
    tip = model.tip.phi[:, 1]
    x[:, 2] = base * (1 + 0.2 * np.sin(2 * np.pi * t / 0.3)) / tip[0]
    x[:, 0] = np.cos(2 * np.pi * t / 0.3)
    x[:, 1] = np.sin(2 * np.pi * t / 0.3)
    state, period, k = cycle_from_trajectory(model, t, x)
    assert k == 3 and abs(period - 0.3) < 1e-4


def _returns(model, traj):
    """Upward tip crossings of zero: times and states (linear interpolation)."""
    y = traj.x[:, model.n_modes:2 * model.n_modes] @ model.tip.phi[:, 1]
    i = np.where((y[:-1] < 0) & (y[1:] >= 0))[0]
    s = -y[i] / (y[i + 1] - y[i])
    return traj.t[i] + s * (traj.t[i + 1] - traj.t[i]), traj.x[i] + s[:, None] * (traj.x[i + 1] - traj.x[i])


@pytest.mark.slow
def test_shooting_passes_first_contact_onto_unstable_impacting_cycles():
    """M* = 1, N = 4: shooting from a collocation cycle before contact (gap/eps = 3.8)
    reproduces it (independent route: collocation of the contact-free model), passes the
    first contact, and the period-1 impacting cycles beyond are unstable (complex
    multipliers |mu| > 1; the smoothed law already acts within about 1.1 eps, where the
    cycles lose stability before the gap reaches eps): time integration from such a
    cycle's state stays on it for the first period and then leaves it."""
    from fsicas.cycles import cycle_branch
    base = Scene(mstar=1.0, zeta=0.01, modes=4, contact_eps=1e-2)
    start = pre_contact_start(cycle_branch(base, ustar_max=10.0, settings=SCENE_NODES))
    assert 3 < start.gap_ratio < 4
    scene = base.replace(ustar=start.ustar, **IMPACT)
    model = build_model(scene)
    br = impacting_cycles(scene, start, method="shooting", model=model,
                          settings=ImpactSettings(max_points=10, ds=0.02, ds_max=0.2,
                                                  quadrature_tol=None))
    assert br.status == "max_points" and len(br.points) == 10
    first = br.points[0]
    assert abs(first.period / start.period - 1) < 1e-6
    assert abs(first.tip_amplitude / start.tip_amplitude - 1) < 1e-5
    assert abs(first.ustar - start.ustar) < 1e-8
    free = [p for p in br.points if p.gap_ratio > 1.5]
    hit = [p for p in br.points if p.gap_ratio < 1]
    assert free and hit and all(p.stable for p in free) and all(p.impacts == 0 for p in free)
    assert all(not p.stable and p.impacts >= 1 for p in hit)
    assert max(np.abs(hit[-1].nontrivial_multipliers)) > 1.5
    assert np.all(np.diff(br.column("ustar")) > 0)
    # time integration from the last impacting cycle
    p = hit[-1]
    steady = steady_state(scene.replace(ustar=p.ustar), model)
    assert abs(steady.pressure_drop / p.pressure_drop - 1) < 1e-9
    traj = simulate(model, steady, 15 * p.period, x0=p.state,
                    settings=Settings(method="idas", rtol=1e-10, atol=1e-12, dt_out=1e-5))
    assert traj.status == "success"
    t, xs = _returns(model, traj)
    step = np.max(np.abs(np.diff(xs, axis=0)), axis=1) / np.max(np.abs(p.state))
    assert abs((t[1] - t[0]) / p.period - 1) < 1e-4
    assert step[0] < 1e-5 and step[-1] > 100 * step[0]


@pytest.mark.slow
def test_period3_impacting_cycle_matches_time_integration(period3_impacting_run):
    """M* = 1, U* = 7, N = 4, k* = 1e8: time integration settles on an impacting cycle of
    three tip swings; shooting from its last three swings converges to that cycle (period
    and tip amplitude as integrated), stable, and the continuation keeps it stable."""
    r = period3_impacting_run
    period = r.period
    assert r.swings == 3
    br = impacting_cycles(r.scene, StartCycle(r.state, period, r.run.steady.pressure_drop),
                          method="shooting", model=r.model,
                          settings=ImpactSettings(max_points=2, ds=0.05, ds_max=0.5,
                                                  quadrature_tol=None))
    assert len(br.points) == 2
    p = br.points[0]
    assert abs(p.ustar - 7.0) < 1e-8
    assert abs(p.period / period - 1) < 1e-5
    assert abs(p.tip_amplitude / r.amplitude - 1) < 1e-4
    assert p.gap_ratio < 1 and p.impacts >= 1
    assert all(q.stable for q in br.points)
    assert max(np.abs(p.nontrivial_multipliers)) < 0.9


def test_impact_settings_validation():
    with pytest.raises(ValueError, match="segments"):
        ImpactSettings(segments=0)
    with pytest.raises(ValueError, match="tol"):
        ImpactSettings(tol=-1.0)
    with pytest.raises(ValueError, match="sensitivities"):
        ImpactSettings(sensitivities="approximate")
    with pytest.raises(ValueError, match="threads"):
        ImpactSettings(threads=0)
    with pytest.raises(ValueError, match="contact"):
        impacting_cycles(Scene(modes=2), StartCycle(np.zeros(6), 0.1, 1.0), method="shooting")


@pytest.fixture(scope="module")
def through_contact():
    """The first impacting cycles past contact at M* = 1, N = 4 (8 points, about 15 s: the
    smoothed law holds the min gap within 1.13 eps to 1.008 eps from U* = 6.66 to 6.78)."""
    from fsicas.cycles import cycle_branch
    base = Scene(mstar=1.0, zeta=0.01, modes=4, contact_eps=1e-2, contact_smoothing=0.1,
                 contact_stiffness=1e8)
    start = pre_contact_start(cycle_branch(base, ustar_max=8.0, settings=SCENE_NODES))
    scene = base.replace(ustar=start.ustar, contact=True)
    return scene, impacting_cycles(scene, start, method="shooting",
                                   settings=replace(THROUGH, quadrature_tol=None))



def test_peak_force_and_flow_reduction_against_a_time_integration(through_contact):
    """The branch's impact measures (shooting samples) against an IDAS integration of the
    same cycle over one period from its state (another integrator and sampling): peak
    force to 1e-2 (the sampled maximum of a sharp impact), mean flow to 1e-5."""
    from fsicas.model.contact import reference_force
    from fsicas.model.patch import penetration
    scene, branch = through_contact
    before, last = branch.points[0], branch.points[-1]
    assert before.impacts == 0 and before.peak_force == 0.0
    assert last.impacts >= 1 and last.gap_ratio < 1 and last.peak_force > 0
    model = build_model(branch.scene)          # the nodes the branch was computed on
    at = branch.scene.replace(ustar=last.ustar)
    st = steady_state(at, model)
    assert st.pressure_drop == pytest.approx(last.pressure_drop, rel=1e-8)
    traj = simulate(model, st, last.period, x0=last.state,
                    settings=Settings(rtol=1e-10, atol=1e-12, dt_out=last.period / 20000,
                                      chunk=last.period))
    total = penetration(model, traj.x, traj.p).load
    assert total.max() / reference_force(model) == pytest.approx(last.peak_force, rel=1e-2)
    flow = traj.x[:, -2:].sum(axis=1)
    mean = np.trapezoid(flow, traj.t) / (traj.t[-1] - traj.t[0])
    assert 1 - mean / st.x[-2:].sum() == pytest.approx(last.flow_reduction, abs=1e-5)


def test_cli_lco_through_contact(capsys):
    """``fsicas lco --through-contact``: the collocation branch to the wall, then the
    impacting branch on the contact model from 3 eps before it: by collocation (default)
    with its special cycles, at N = 4 the Neimark-Sacker point past the first contact
    (located once more on NTST = 200, ``--special-ntst``), and a warning when the mesh is too coarse (NTST = 10); by shooting (plumbing: one
    point). Without ``--impact-points`` the branch runs on to ``--ustar-max``; a stop
    names the option that made it."""
    import json
    from fsicas.cli import main
    keys = {"ustar", "period", "tip_amplitude", "min_gap", "gap_ratio", "impacts",
            "peak_force", "flow_reduction", "stable", "quadrature_error", "quadrature_nodes"}
    code = main(["lco", "--mstar", "1", "--zeta", "0.01", "--modes", "4", "--ustar-max", "6.7",
                 "--through-contact", "--impact-ntst", "100", "--special-ntst", "200",
                 "--json"])
    out = json.loads(capsys.readouterr().out)
    imp = out["impacting"]
    assert code == 0 and out["status"] == "contact" and imp["route"] == "collocation"
    assert imp["status"] == "bound" and set(imp["points"][0]) == keys
    assert imp["stopped_by"] == "--ustar-max 6.7" and out["stopped_by"] is None
    assert imp["message"] == "reached --ustar-max 6.7"       # no internal parameter names
    assert len(imp["points"]) > 10 and 6.65 < imp["points"][-1]["ustar"] <= 6.7
    assert 0 < imp["max_error_estimate"] < 0.1          # no coarse-mesh warning here
    (ns,) = imp["special"]
    assert ns["kind"] == "ns" and ns["located"] and ns["ntst"] == 200
    assert ns["ncol"] == 6 and 0 < ns["flow_defect"] < 1e-2
    assert set(ns) == keys | {"kind", "located", "ntst", "ncol", "flow_defect",
                                "multiplier"}
    assert abs(np.hypot(*ns["multiplier"]) - 1) < 1e-9 and 6.59 < ns["ustar"] < 6.62
    code = main(["lco", "--mstar", "1", "--zeta", "0.01", "--modes", "4", "--ustar-max", "8",
                 "--through-contact", "--impact-route", "shooting", "--impact-points", "1",
                 "--json"])
    imp = json.loads(capsys.readouterr().out)["impacting"]
    assert code == 0 and imp["status"] == "max_points" and imp["route"] == "shooting"
    assert imp["stopped_by"] == "--impact-points 1" and "raise --impact-points" in imp["message"]
    point = imp["points"][0]
    assert set(point) == keys and imp["special"] == []
    assert point["gap_ratio"] == pytest.approx(3.0, abs=1.0) and imp["eps"] > 0
    capsys.readouterr()
    assert main(["lco", "--mstar", "1", "--zeta", "0.01", "--modes", "4", "--ustar-max", "6.7",
                 "--through-contact", "--impact-points", "10", "--impact-ntst", "10",
                 "--json"]) == 0
    coarse = capsys.readouterr()
    assert json.loads(coarse.out)["impacting"]["max_error_estimate"] > 0.1
    assert "mesh is too coarse" in coarse.err and "--impact-ntst" in coarse.err
    for bad in (["--impact-points", "0"], ["--impact-ntst", "0"], ["--special-ntst", "-1"]):
        assert main(["lco", "--modes", "4", "--through-contact", *bad, "--json"]) == 2


@pytest.mark.slow
def test_quadrature_control_of_shooting_cycles(through_contact):
    """N = 4, the branch of the fixture (28 nodes, no control) computed again with the
    default control: on the adequate nodes every point's estimate is within
    IMPACT_QUADRATURE_TOL (the plain branch's is not); one period integrated by Radau
    (rtol 1e-11) from the last, impacting, cycle on twice those nodes returns to it far
    closer than from the plain branch's last cycle."""
    from fsicas.model.accuracy import IMPACT_QUADRATURE_TOL
    scene, plain = through_contact
    start = plain.points[0]
    controlled = impacting_cycles(scene, start, method="shooting",
                                  settings=THROUGH)
    nodes = controlled.scene.n_quad
    assert nodes > scene.n_quad and {p.quadrature_nodes for p in controlled.points} == {nodes}
    assert max(p.quadrature_error for p in controlled.points) <= IMPACT_QUADRATURE_TOL
    assert max(p.quadrature_error for p in plain.points) > IMPACT_QUADRATURE_TOL
    assert controlled.points[-1].impacts >= 1
    fine = build_model(scene.replace(quad_nodes=2 * nodes))

    def miss(point):
        steady = steady_state(scene.replace(ustar=point.ustar, quad_nodes=2 * nodes), fine)
        traj = simulate(fine, steady, point.period, x0=point.state,
                        settings=Settings(method="radau", rtol=1e-11, atol=1e-13,
                                          dt_out=point.period / 2000))
        assert traj.status == "success"
        return np.max(np.abs(traj.x[-1] - point.state)) / np.max(np.abs(point.state))
    assert miss(controlled.points[-1]) < 1e-2 * miss(plain.points[-1])
