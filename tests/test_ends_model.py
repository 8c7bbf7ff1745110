"""The model with other beam ends: the reference point of the "tip" measures, the
model's rows against the field route, and stability (divergence of a clamped plate)."""
import numpy as np
import pytest

from fsicas import Scene
from fsicas.model.assembly import build_model, reference_point
from fsicas.profile import Profile

HELD = ("clamped-clamped", "pinned-pinned", "clamped-pinned")


def test_the_cantilever_probes_its_free_tip_with_the_tip_basis_itself():
    model = build_model(Scene(modes=4))
    assert model.x_ref == 1.0 and model.probe is model.tip


@pytest.mark.parametrize("ends", ("clamped-clamped", "pinned-pinned"))
def test_symmetric_ends_probe_the_middle(ends):
    model = build_model(Scene(modes=4, ends=ends))
    assert model.x_ref == 0.5
    q = np.zeros(model.n_state)
    q[4] = 1.0                                  # q_1 = 1: y = phi_1
    assert model.tip_deflection(q) == pytest.approx(model.basis_at([0.5]).phi[0, 0])
    assert abs(model.deflection(q, [1.0])[0]) < 1e-12


def test_clamped_pinned_probes_the_crest_of_its_first_mode():
    """Against the textbook shape maximized on 2e5 points."""
    b = 3.926602312047919
    s = (np.cosh(b) - np.cos(b)) / (np.sinh(b) - np.sin(b))
    x = np.linspace(0, 1, 200001)
    z = b * x
    crest = x[np.argmax(np.abs(np.cosh(z) - np.cos(z) - s * (np.sinh(z) - np.sin(z))))]
    assert reference_point(Scene(modes=3, ends="clamped-pinned")) == pytest.approx(crest, abs=1e-5)


def test_a_tapered_clamped_plate_probes_off_the_middle():
    """Thinner towards x = 1: lighter and softer there, the crest moves past the middle."""
    scene = Scene(modes=4, ends="clamped-clamped", thickness=Profile.linear(1.0, 0.6))
    x_ref = reference_point(scene)
    model = build_model(scene)
    grid = np.linspace(0, 1, 2001)
    assert x_ref > 0.5 and model.x_ref == x_ref
    assert abs(model.probe.phi[0, 1]) >= np.abs(model.basis_at(grid).phi[0]).max() - 1e-12


def _random_state(scene, seed):
    """A non-equilibrium state; modal velocities small enough that u > 0 everywhere (a
    local reversal puts the kink of u|u| under the rule: algebraic convergence)."""
    rng = np.random.default_rng(seed)
    n = scene.modes
    decay = 1.0 / np.arange(1, n + 1) ** 2
    return np.concatenate([0.02 * rng.normal(size=n) * decay, 1e-3 * rng.normal(size=n) * decay,
                           np.array([0.2, 0.15]) * (1 + 0.1 * rng.normal(size=2))])


@pytest.mark.parametrize("ends", HELD)
@pytest.mark.parametrize("thickness", [None, Profile.linear(1.0, 0.7)])
def test_beam_rows_are_the_projection_of_the_field_load(ends, thickness):
    """dr/dt + 2 zeta w r + w^2 q = ∫ (p2 - p1) phi_n dx with the load of the field route
    (cumulative Simpson of the formal solution on 16001 points): the rows' projection
    with Psi and Phi(1) holds for every ends (the root is held, y(0) = 0, in all)."""
    from scipy.integrate import simpson
    from fsicas import flow_fields
    from fsicas.model.assembly import modal_basis
    scene = Scene(mstar=2.0, ustar=4.0, modes=4, k0=0.3, kl=0.8, zeta=0.02, ends=ends,
                  thickness=thickness, channel1=Profile.linear(0.05, 0.04),
                  channel2=Profile.table([0.0, 0.5, 1.0], [0.05, 0.06, 0.045]))
    model = build_model(scene)
    x0 = _random_state(scene, 3)
    xdot = model.xdot(x0, model.parameters(pressure_drop=30.0))
    grid = np.linspace(0.0, 1.0, 16001)
    modes = modal_basis(scene, grid)
    n = scene.modes
    lhs = xdot[:n] + 2 * 0.02 * modes.omega * x0[:n] + modes.omega**2 * x0[n:2 * n]
    fields = flow_fields(scene, x0, xdot, 30.0, grid)
    assert fields.u.min() > 0
    rhs = simpson(modes.phi * fields.load, x=grid)
    assert np.allclose(lhs, rhs, rtol=1e-9, atol=1e-9 * np.max(np.abs(rhs)))


@pytest.mark.parametrize("ends, mstar", [("clamped-clamped", 1.0), ("pinned-pinned", 0.1),
                                         ("clamped-pinned", 10.0)])
def test_frictionless_held_plates_diverge_at_their_closed_form(ends, mstar):
    """Without friction, y(1) = 0 makes both channels' exit conditions alike, so the flow
    rates stay Q_c = U* H*/2 and the pressure is Bernoulli's, p_c = p_c(0) - M* (u_c^2 -
    u_c0^2)/2 with u_c = Q_c/h_c: the load p2 - p1 = 4 M* U*^2 y / H* is a uniform
    negative stiffness, and the first mode diverges at U*_c = beta_1^2 sqrt(H*/(4 M*))."""
    from fsicas.linear.hopf import critical_velocity
    from fsicas.model.beam import uniform_betas
    scene = Scene(modes=8, mstar=mstar, ends=ends, friction=0.0, k0=0.3, kl=0.8)
    onset = critical_velocity(scene, build_model(scene))
    exact = uniform_betas(1, ends)[0] ** 2 * np.sqrt(scene.hstar / (4 * mstar))
    assert onset.kind == "divergence" and onset.symmetry_breaking and onset.point is not None
    assert onset.ustar == pytest.approx(exact, rel=1e-9)


def test_deflected_branch_of_a_clamped_plate_is_a_pitchfork_measured_at_x_ref():
    """The deflected states born at the divergence: y(x_ref)^2 grows linearly in
    |U* - U*_c| near it (here towards lower U*: subcritical), with y(1) = 0 throughout."""
    from fsicas.linear.deflected import deflected_branch
    scene = Scene(modes=6, mstar=1.0, ends="clamped-clamped", friction=0.0)
    model = build_model(scene)
    onset = _onset(scene)
    branch = deflected_branch(scene, model, onset, ustar_max=2 * onset.ustar)
    assert branch.x_ref == 0.5
    near = np.abs(branch.ustar - onset.ustar) < 0.1 * onset.ustar
    slope = branch.tip_deflection[near] ** 2 / np.abs(branch.ustar[near] - onset.ustar)
    assert near.sum() >= 2 and np.ptp(slope) < 0.05 * slope.max()
    assert np.abs([model.deflection(x, [1.0])[0] for x in branch.states]).max() < 1e-14


def test_clamped_plate_with_friction_diverges_where_a_direct_scan_says():
    """The onset (continuation of the steady branch) against a scan of the eigenvalues
    of steady states solved one by one in U* (steps of 0.1, then bisection on whether a
    real eigenvalue is positive): the first instability is real, a divergence."""
    from fsicas import steady_state
    from fsicas.linear.hopf import critical_velocity
    from fsicas.linear.stability import eigenvalues
    scene = Scene(modes=8, mstar=0.3, ends="clamped-clamped", friction=0.05)
    model = build_model(scene)

    def unstable(u):
        lam = eigenvalues(model, steady_state(scene.replace(ustar=u), model))
        lam = lam[np.isfinite(lam) & (lam.real > 0)]
        assert np.all(np.abs(lam.imag) < 1e-9)            # nothing oscillatory first
        return lam.size > 0

    grid = np.arange(0.5, 20.0, 0.1)
    hi = grid[next(k for k, u in enumerate(grid) if unstable(u))]
    lo = hi - 0.1
    while hi - lo > 1e-9:
        mid = (lo + hi) / 2
        lo, hi = (lo, mid) if unstable(mid) else (mid, hi)
    onset = critical_velocity(scene, model)
    assert onset.kind == "divergence"
    assert onset.ustar == pytest.approx((lo + hi) / 2, rel=1e-8)


def _onset(scene):
    import warnings
    from fsicas.linear.hopf import critical_velocity
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")             # N = 8: the truncation is not the point
        return critical_velocity(scene, build_model(scene))


@pytest.mark.parametrize("ends", HELD)
def test_time_integration_decays_below_the_onset(ends):
    """A run from the perturbed steady state at 0.9 U*_c decays, measured at x_ref."""
    from fsicas.timedomain.run import run_case
    scene = Scene(modes=8, mstar=1.0, ends=ends)
    run = run_case(scene.replace(ustar=0.9 * _onset(scene).ustar), 30.0)
    assert run.status == "success" and run.outcome.outcome == "decay"
    assert run.model.x_ref == reference_point(scene)


@pytest.mark.slow
@pytest.mark.parametrize("ends", HELD)
def test_time_integration_grows_to_the_wall_above_the_onset(ends):
    """At 1.1 U*_c the flutter grows until the beam reaches a wall, away from both ends
    (at x = 0.77, 0.83, 0.82 for clamped-clamped, pinned-pinned, clamped-pinned)."""
    from fsicas.timedomain.run import run_case
    scene = Scene(modes=8, mstar=1.0, ends=ends)
    run = run_case(scene.replace(ustar=1.1 * _onset(scene).ustar), 30.0)
    assert run.status == "success" and run.outcome.outcome == "contact"
    assert 0.05 < run.outcome.first_contact_position < 0.95


@pytest.fixture(scope="module")
def pinned_cycles():
    from fsicas.cycles import CycleSettings, cycle_branch
    scene = Scene(mstar=1.0, zeta=0.01, modes=6, ends="pinned-pinned", contact_eps=1e-2)
    model = build_model(scene)
    return scene, model, cycle_branch(scene, model, settings=CycleSettings(max_points=40))


def test_pinned_plate_cycles_follow_hopf_theory(pinned_cycles):
    """From the Hopf point: period -> 2 pi / omega of the linearization, amplitude at
    x_ref born from zero at U*_c (a supercritical flutter of the pinned plate). The
    branch starts at U* - U*_c = 1.5e-3, where the period is 2.5e-4 off 2 pi / omega:
    the cubic extrapolated to U*_c is held to 1e-5 of it. l1 is small here (-8e-4), so
    the amplitude follows the normal form with its quintic term,
    U* - U*_c = c1 A^2 + c2 A^4: the fit's constant is held to 2 % of the first point's."""
    from fsicas.linear.stability import linear_stability
    scene, model, branch = pinned_cycles
    uc = branch.hopf["ustar_crit"]
    assert branch.hopf["l1"] < 0
    lam = linear_stability(scene.replace(ustar=uc), model).eigenvalues[0]
    near = [p for p in branch.points if 0 < p.ustar - uc < 0.02 * uc]
    assert len(near) >= 8
    mu = np.array([p.ustar - uc for p in near])
    T = np.array([p.period for p in near])
    A = np.array([p.tip_amplitude for p in near])
    T0 = np.polyval(np.polyfit(mu[:8], T[:8], 3), 0.0)
    assert abs(T0 * abs(lam.imag) / (2 * np.pi) - 1) < 1e-5
    assert abs(np.polyfit(A[:8] ** 2, mu[:8], 2)[-1]) < 0.02 * mu[0]


def test_a_study_fixes_the_ends_in_its_scene_table(tmp_path):
    from fsicas.studies.spec import load_study
    path = tmp_path / "plates.toml"
    path.write_text('analysis = "onset"\n[scene]\nmodes = 6\nends = "pinned-pinned"\n'
                    '[grid]\nmstar = [0.1, 1.0]\n')
    study = load_study(str(path))
    assert study.scene["ends"] == "pinned-pinned"
    path.write_text('analysis = "onset"\n[scene]\nends = "free-free"\n[grid]\nmstar = [1.0]\n')
    with pytest.raises(ValueError, match="ends must be one of"):
        load_study(str(path))


def test_a_physical_file_sets_the_ends(tmp_path):
    from pathlib import Path
    import fsicas
    from fsicas.physical import load_physical
    preset = Path(fsicas.__file__).parent / "presets" / "reed.toml"
    path = tmp_path / "plate.toml"
    path.write_text('ends = "clamped-pinned"\n' + preset.read_text())
    physical = load_physical(str(path))
    assert physical.scene(physical.flow).ends == "clamped-pinned"


def test_clamped_plate_flow_satisfies_continuity_momentum_and_end_conditions(channel_pde_check):
    """The fields of the formal solution (cumulative Simpson, 8001 points) at t - dt, t,
    t + dt of a tight integration of M xdot = F: finite differences in x and t satisfy
    the channel equations, and the inlet and outlet pressures their loss conditions,
    for a clamped-clamped plate (its flow rows and beam rows together)."""
    scene = Scene(mstar=2.0, ustar=4.0, modes=4, k0=0.3, kl=0.8, zeta=0.02,
                  ends="clamped-clamped", channel1=Profile.linear(0.05, 0.04),
                  channel2=Profile.table([0.0, 0.5, 1.0], [0.05, 0.06, 0.045]))
    model = build_model(scene)
    x0, dp = _random_state(scene, 1), 30.0
    for h, u, pc, scale in channel_pde_check(scene, model, x0, dp):
        assert pc[0] == pytest.approx(dp - scene.mstar / 2 * (u[0]**2 + scene.k0 * u[0] * abs(u[0])),
                                      rel=1e-13)
        assert pc[-1] == pytest.approx(-scene.mstar / 2 * (u[-1]**2 - scene.kl * u[-1] * abs(u[-1])),
                                       rel=1e-11, abs=1e-11 * scale)


def test_command_line_takes_the_ends(capsys):
    """--ends on modes and onset; the onset of a frictionless clamped plate is its
    closed-form divergence, and a bad value is refused naming ends."""
    import json
    from fsicas.cli import main
    from fsicas.model.beam import uniform_betas
    assert main(["modes", "--modes", "3", "--ends", "clamped-pinned", "--json"]) == 0
    beta = json.loads(capsys.readouterr().out)["beta"]
    assert np.allclose(beta, [3.926602, 7.068583, 10.210176], atol=5e-7)
    assert main(["onset", "--ends", "clamped-clamped", "--friction", "0", "--mstar", "1",
                 "--modes", "6", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    exact = uniform_betas(1, "clamped-clamped")[0] ** 2 * np.sqrt(0.1 / 4)
    assert out["kind"] == "divergence" and out["ustar_crit"] == pytest.approx(exact, rel=1e-9)
    assert main(["steady", "--ends", "free-free", "--json"]) == 2
    assert "ends must be one of" in json.loads(capsys.readouterr().out)["error"]


def test_boundary_of_a_clamped_plate_switches_from_flutter_to_divergence():
    """At f = 0.05 the boundary U*_c(M*) runs on flutter at low M* and on divergence
    above a located switch where the two curves cross (U*_c continuous there); the onset
    on either side of it is of the kind the boundary says."""
    from fsicas.linear.boundary import stability_boundary
    scene = Scene(modes=6, ends="clamped-clamped", friction=0.05)
    model = build_model(scene)
    boundary = stability_boundary(scene, np.array([0.02, 0.05, 0.1]), model)
    assert [p.kind for p in boundary.points] == ["flutter", "flutter", "divergence"]
    (switch,) = boundary.switches
    assert switch.located and 0.05 < switch.mstar < 0.1 and switch.omega_above == 0.0
    assert switch.ustar_above == pytest.approx(switch.ustar_below, rel=1e-8)
    for factor, kind in ((0.98, "flutter"), (1.02, "divergence")):
        onset = _onset(scene.replace(mstar=factor * switch.mstar))
        assert onset.kind == kind
    at = _onset(scene.replace(mstar=0.1))
    assert boundary.points[-1].ustar_crit == pytest.approx(at.ustar, rel=1e-9)


@pytest.mark.parametrize("ends", ["clamped-clamped", "pinned-pinned"])
def test_energy_balance_and_flow_conservation_of_a_growing_flutter(ends):
    """Over a window of a run above the onset, dE/dt = P_fluid - D with P_fluid from the
    field route (fsicas.timedomain.energy), and the outlet flow rates sum to the inlet's.
    At 1.02 U*_c the window [0.5, 1.5] ends well before the flow reverses locally: at 1.05
    U*_c and t = 3 (the pinned plate's gap down to 30 %) the model's 32 nodes miss the
    kink of u|u| (quadrature error 0.05, residual 0.018; with 200 nodes 7e-8)."""
    from fsicas.timedomain.energy import energy_balance, outlet_flow_rates
    from fsicas.timedomain.integrators import Settings
    from fsicas.timedomain.run import run_case
    scene = Scene(mstar=1.0, zeta=0.01, modes=6, ends=ends)
    run = run_case(scene.replace(ustar=1.02 * _onset(scene).ustar), 1.5,
                   settings=Settings(rtol=1e-10, atol=1e-12, dt_out=1e-3, chunk=0.5),
                   stop_early=False, quadrature_tol=None)
    tr = run.trajectory
    assert tr.status == "success"
    eb = energy_balance(tr, 0.5, 1.5)
    assert eb.delta_energy > 0 and eb.fluid_work > eb.dissipation > 0
    assert eb.relative_residual < 1e-6 and run.quadrature_error < 1e-6
    out = outlet_flow_rates(tr)
    assert np.allclose(out.sum(axis=1), tr.x[:, -2:].sum(axis=1), rtol=1e-13, atol=0)


@pytest.mark.parametrize("ends", ["clamped-clamped", "pinned-pinned", "clamped-pinned"])
def test_the_smoothed_impact_law_takes_equal_cells_with_both_ends_held(ends):
    """A held beam touches the walls anywhere inside the span: its smoothed law (of the
    impacting cycles) integrates on equal cells, not on cells graded towards a free tip
    (accuracy: tests/test_ends_impacting.py)."""
    model = build_model(Scene(ends=ends, modes=4, contact=True, contact_smoothing=0.1))
    width = np.diff(model.impact_rule.x[::2])
    assert np.allclose(width, width[0], rtol=0, atol=1e-12)
