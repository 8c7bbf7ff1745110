"""Flutter limit cycles by collocation continuation (fsicas.cycles), against independent
answers: Hopf theory near onset, direct time integration, the Floquet signature of a
cycle fold, and the geometry of first contact. N = 4 modes keeps each branch at a few
seconds."""
import numpy as np
import pytest
import scipy.integrate

import fsicas
from fsicas.cycles import CycleBranch, CycleSettings, cycle_branch
from fsicas.linear.hopf import critical_velocity
from fsicas.model import build_model
from fsicas.timedomain.outcome import Criteria
from fsicas.timedomain.run import run_case
from fsicas.timedomain.integrators import Settings, gaps
from fsicas.linear.stability import linear_stability

SUPER = fsicas.Scene(mstar=1.0, zeta=0.01, modes=4, contact_eps=1e-2)   # l1 < 0
SUB = fsicas.Scene(mstar=0.2, zeta=0.01, modes=4)        # l1 > 0


@pytest.fixture(scope="module")
def supercritical():
    model = build_model(SUPER)
    return model, cycle_branch(SUPER, model)


def test_period_and_amplitude_follow_hopf_theory(supercritical):
    model, branch = supercritical
    assert branch.hopf["l1"] < 0
    uc = branch.hopf["ustar_crit"]
    # U* of a cycle = U* of the steady state at its Δp: closed form for straight walls
    coef = SUPER.mstar * ((SUPER.k0 + SUPER.kl) / 2 + SUPER.friction / (SUPER.hstar / 2))
    for p in branch.points[::10]:
        assert abs(np.sqrt(p.pressure_drop / coef) / p.ustar - 1) < 1e-10
    # omega_H independently: the flutter eigenvalue of the linearization at U*_c
    lam = linear_stability(SUPER.replace(ustar=uc), model).eigenvalues[0]
    assert abs(lam.real) < 1e-6 * abs(lam.imag)
    near = [p for p in branch.points if p.ustar - uc < 0.02 * uc]
    assert len(near) >= 8 and all(p.stable for p in near)
    mu = np.array([p.ustar - uc for p in near])
    T = np.array([p.period for p in near])
    A = np.array([p.tip_amplitude for p in near])
    assert mu.min() > 0          # supercritical: cycles on the unstable side
    # T(U*) is smooth through the Hopf point: extrapolate to U*_c (cubic, first 8 points;
    # the curvature is strong on the scale of the first points: linear gives 2e-5)
    T0 = np.polyval(np.polyfit(mu[:8], T[:8], 3), 0.0)
    assert abs(T0 * abs(lam.imag) / (2 * np.pi) - 1) < 1e-6
    # A ~ c sqrt(U* - U*_c): fitted exponent on the first decade
    exponent = np.polyfit(np.log(mu[:8]), np.log(A[:8]), 1)[0]
    assert abs(exponent - 0.5) < 0.02


def test_cycle_matches_time_integration(supercritical):
    """The settled 'lco' of direct integration at a branch point's U*."""
    model, branch = supercritical
    point = min(branch.points, key=lambda p: abs(p.ustar - 6.2))
    assert point.min_gap > 10 * branch.eps
    run = run_case(SUPER.replace(ustar=point.ustar), 30.0,
                   settings=Settings(rtol=1e-9, atol=1e-12, dt_out=2e-4),
                   criteria=Criteria(tol=2e-5, cycles=4))
    out = run.outcome
    assert out.outcome == "lco"
    assert abs(out.period / point.period - 1) < 1e-5
    assert abs(out.tip_amplitude / point.tip_amplitude - 1) < 1e-4
    assert point.stable and np.abs(point.nontrivial_multipliers).max() < 1


def test_first_contact_geometry(supercritical):
    """At the located contact the min gap over one period of an independent integration
    from the cycle's state is eps, and (symmetric channel, contact at the tip) the tip
    half-amplitude is H*/2 - eps."""
    model, branch = supercritical
    c = branch.contact
    assert branch.status == "contact" and c is not None and c.kind == "contact" and c.located
    assert abs(c.gap_ratio - 1) < 1e-9
    assert abs(c.tip_amplitude - (SUPER.hstar / 2 - branch.eps)) < 1e-9
    assert all(p.min_gap > branch.eps for p in branch.points)
    assert c.ustar > branch.points[-1].ustar
    model = build_model(SUPER.replace(quad_nodes=c.quadrature_nodes))  # the contact's nodes
    p = model.parameters(SUPER, pressure_drop=c.pressure_drop)
    sol = scipy.integrate.solve_ivp(lambda t, x: model.xdot(x, p), (0, c.period), c.state,
                                    method="DOP853", rtol=1e-12, atol=1e-14, dense_output=True)
    t = np.linspace(0, c.period, 20001)
    X = sol.sol(t).T
    # periodic up to the collocation error (NTST = 20, re-meshed; 1e-6 measured)
    assert np.abs(X[-1] - c.state).max() < 1e-5 * np.abs(c.state).max()
    assert abs(gaps(model, X).min() / branch.eps - 1) < 1e-4


@pytest.fixture(scope="module")
def subcritical():
    model = build_model(SUB)
    hopf = critical_velocity(SUB, model)
    return model, hopf, cycle_branch(SUB, model, hopf=hopf)


def test_subcritical_branch_folds_and_turns_stable(subcritical):
    model, hopf, branch = subcritical
    assert hopf.l1 > 0
    pts, (fold,) = branch.points, branch.folds
    assert fold.kind == "fold" and fold.located
    first = pts[1]
    assert first.ustar < hopf.ustar and not first.stable           # unstable, below U*_c
    lead = first.nontrivial_multipliers[0]
    assert lead.imag == 0 and lead.real > 1                         # a real multiplier > 1
    assert fold.ustar < min(p.ustar for p in pts) + 1e-12           # the turning point in U*
    # it crosses +1 there: with the trivial one, a Jordan block at 1, which a residual r
    # splits into 1 +- O(sqrt(r)) (measured 3e-6)
    assert abs(fold.nontrivial_multipliers[0] - 1) < 1e-4
    after = [p for p in pts if p.tip_amplitude > fold.tip_amplitude * 1.05]
    assert after and all(p.stable for p in after)
    assert all(not p.stable for p in pts if p.tip_amplitude < fold.tip_amplitude * 0.95)
    assert branch.contact is not None and branch.contact.stable


def test_fold_refined_by_newton_on_its_extended_system(subcritical):
    """The fold, refined by Newton on the minimally extended system: the pair of
    multipliers at +1 (the trivial one and the fold's, a Jordan block) has its mean at 1
    to 1e-9 (the mean of a perturbed Jordan pair moves with the perturbation r, each one
    with sqrt(r): 3e-6 here), and it is the turning point of the branch in U*."""
    _, _, branch = subcritical
    (fold,) = branch.folds
    mu = fold.multipliers
    pair = mu[np.argsort(np.abs(mu - 1))[:2]]
    assert abs(np.mean(pair) - 1) < 1e-9 and np.max(np.abs(pair - 1)) < 1e-5
    assert fold.ustar <= min(p.ustar for p in branch.points) + 1e-9
    assert fold.gap_ratio > 1


def test_subcritical_hysteresis_by_integration(subcritical):
    """Between the fold and U*_c the steady state is linearly stable and yet a perturbed
    start on the stable large cycle stays there (direct integration, 60 periods)."""
    model, hopf, branch = subcritical
    window = [p for p in branch.points if p.stable and branch.folds[0].ustar < p.ustar < hopf.ustar]
    p = window[-1]
    assert linear_stability(SUB.replace(ustar=p.ustar), model).stable
    par = model.parameters(SUB, pressure_drop=p.pressure_drop)
    sol = scipy.integrate.solve_ivp(lambda t, x: model.xdot(x, par), (0, 60 * p.period),
                                    p.state * (1 + 1e-3), method="DOP853", rtol=1e-10,
                                    atol=1e-12, dense_output=True)
    t = np.linspace(59 * p.period, 60 * p.period, 4001)
    y = sol.sol(t)[SUB.modes:2 * SUB.modes].T @ model.tip.phi[:, 1]
    assert abs((y.max() - y.min()) / 2 / p.tip_amplitude - 1) < 1e-3


def test_save_load_roundtrip(supercritical, tmp_path):
    _, branch = supercritical
    branch.save(tmp_path / "b.json")
    back = CycleBranch.load(tmp_path / "b.json")
    assert back.to_json() == branch.to_json()
    assert back.contact.state.shape == branch.contact.state.shape


def test_saved_branch_is_strict_json_and_reads_unmeasured_values_back(supercritical, tmp_path):
    """A point whose quadrature error was not measured (NaN) and a multiplier that is not
    finite are written as null (strict JSON, which ``json`` refuses to read as NaN when
    told to) and read back as NaN."""
    import dataclasses
    import json
    _, branch = supercritical
    point = branch.points[0]
    odd = dataclasses.replace(point, quadrature_error=float("nan"),
                              multipliers=np.r_[point.multipliers[:-1], complex(np.inf, 0)])
    dataclasses.replace(branch, points=[odd]).save(tmp_path / "b.json")
    text = (tmp_path / "b.json").read_text()

    def refuse(token):
        raise AssertionError(f"non-standard JSON token {token}")
    data = json.loads(text, parse_constant=refuse)
    assert data["points"][0]["quadrature_error"] is None
    back = CycleBranch.load(tmp_path / "b.json").points[0]
    assert np.isnan(back.quadrature_error) and np.isnan(back.multipliers[-1].real)
    assert np.array_equal(back.multipliers[:-1], point.multipliers[:-1])


def test_no_hopf_point_below_ustar_max_raises():
    with pytest.raises(fsicas.linear.hopf.CriticalVelocityError):
        cycle_branch(SUPER, ustar_max=3.0, settings=CycleSettings(max_points=5))


def test_cli_cycles_json_and_files(tmp_path, capsys):
    """``fsicas lco`` (the contract's name; alias ``cycles``) on the package's parser."""
    import json
    from fsicas.cli import build_parser
    parser = build_parser()
    args = parser.parse_args(["lco", "--mstar", "1", "--zeta", "0.01", "--modes", "4",
                              "--max-points", "12", "--out", str(tmp_path / "b.json"),
                              "--plot", str(tmp_path / "b.png"), "--json"])
    out = json.loads(json.dumps(args.run(args)))
    assert out["status"] == "max_points" and len(out["points"]) == 12
    assert out["hopf"]["l1"] < 0 and out["contact"] is None
    assert all(p["ustar"] > out["hopf"]["ustar_crit"] for p in out["points"])
    assert all(p["stable"] for p in out["points"])
    assert CycleBranch.load(tmp_path / "b.json").points[0].ustar == out["points"][0]["ustar"]
    assert (tmp_path / "b.png").stat().st_size > 0
    with pytest.raises(ValueError, match="contact-free"):
        args.run(parser.parse_args(["cycles", "--contact"]))


def test_branch_reports_its_quadrature_error(supercritical):
    """Every cycle point carries the quadrature error of the equations over the cycle and
    its nodes: at round-off far from the wall, and the same as the model-level estimate
    at the cycle's nodes; towards the first contact, where the wall is near, a point
    over the tolerance is followed by more nodes (tests/test_quadrature_control.py)."""
    from fsicas.model.accuracy import QUADRATURE_TOL, quadrature_error
    model, branch = supercritical
    errors, nodes = branch.column("quadrature_error"), branch.column("quadrature_nodes")
    assert np.all(np.isfinite(errors)) and errors[0] < 1e-12 and nodes[0] == SUPER.n_quad
    over = np.flatnonzero(errors[:-1] > QUADRATURE_TOL)
    assert len(over) and np.all(nodes[over + 1] > nodes[over])
    assert np.isfinite(branch.contact.quadrature_error)
    st = fsicas.steady_state(SUPER.replace(ustar=branch.points[0].ustar), model)
    assert quadrature_error(model, branch.points[0].state, st.p) < 1e-12


@pytest.mark.parametrize("mstar", [0.7, 0.75])
def test_branch_starts_where_l1_is_near_zero(mstar):
    """N = 10, zeta = 0.01: l1 = 0.023 at M* = 0.7, where the normal form's start guess
    (dp = 1e-3) was a quarter of the gap and its Newton diverged; the start is retried
    closer to the Hopf point. The first cycle is a cycle: an IDAS integration over one
    period from its state returns to it (independent of the collocation)."""
    scene = fsicas.Scene(mstar=mstar, zeta=0.01)
    model = build_model(scene)
    branch = cycle_branch(scene, model, settings=CycleSettings(max_points=3))
    assert branch.status == "max_points" and abs(branch.hopf["l1"]) < 0.05
    first = branch.points[0]
    assert abs(first.ustar - branch.hopf["ustar_crit"]) < 1e-2 and first.tip_amplitude < 0.01
    at = scene.replace(ustar=first.ustar)
    st = fsicas.steady_state(at, model)
    traj = fsicas.simulate(model, st, first.period, x0=first.state,
                           settings=Settings(method="idas", rtol=1e-11, atol=1e-13,
                                             dt_out=first.period / 200, chunk=first.period))
    deviation = np.abs(first.state - st.x).max()
    assert np.abs(traj.x[-1] - first.state).max() < 1e-4 * deviation


@pytest.mark.slow
def test_stable_cycles_past_the_fold_near_l1_zero_are_those_of_a_time_integration():
    """M* = 0.7, N = 10, zeta = 0.01 (l1 = 0.023, subcritical): past the fold the branch's
    stable cycles are where a run from the perturbed steady state settles (IDAS, rtol
    1e-9), period and amplitude to the run's convergence."""
    scene = fsicas.Scene(mstar=0.7, zeta=0.01)
    model = build_model(scene)
    branch = cycle_branch(scene, model)
    assert branch.status == "contact" and len(branch.folds) == 1
    p = next(q for q in branch.points if q.stable and q.ustar > branch.hopf["ustar_crit"] + 0.1)
    run = run_case(scene.replace(ustar=p.ustar), 80.0,
                   settings=Settings(method="idas", rtol=1e-9, atol=1e-11, dt_out=1e-3))
    o = run.outcome
    assert o.outcome == "lco" and o.settled
    assert o.period == pytest.approx(p.period, rel=max(o.convergence, 1e-6))
    assert o.tip_amplitude == pytest.approx(p.tip_amplitude, rel=2 * max(o.convergence, 1e-6))
