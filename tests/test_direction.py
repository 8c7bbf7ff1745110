"""Flow in both directions (docs/model.md, "Reversed flow"): the direction of a scene,
the head losses of reversed flow against independent integrations of the steady
bulk-flow equations, the mirror identity of the flow alone."""
import numpy as np
import pytest
from scipy.integrate import solve_bvp, solve_ivp, trapezoid

from fsicas.model.assembly import build_model
from fsicas.model.fields import flow_fields
from fsicas.linear.steady import steady_state
from fsicas.profile import Profile
from fsicas.scene import Scene


# -- the direction of a scene ------------------------------------------------------------
def test_direction_sets_the_sign_of_the_speed():
    assert Scene.from_dict({"direction": "reverse", "ustar": 3}).ustar == -3.0
    assert Scene.from_dict({"direction": "forward", "ustar": 3}).ustar == 3.0
    assert Scene.from_dict({"direction": "reverse"}).ustar == -Scene().ustar
    assert Scene(ustar=-2).direction == "reverse" and Scene(ustar=2).direction == "forward"
    assert Scene.from_dict({"direction": "reverse", "ustar": 0}).direction == "reverse"
    assert Scene(ustar=-2).flow_sign == -1.0 and Scene().flow_sign == 1.0


@pytest.mark.parametrize("given, words", [
    (dict(direction="reverse", ustar=-3), "negative ustar"),
    (dict(direction="forward", ustar=-3), "negative ustar"),
    (dict(direction="backward"), "direction must be one of forward, reverse")])
def test_contradictory_or_unknown_direction_is_refused(given, words):
    with pytest.raises(ValueError, match=words):
        Scene.from_dict(given)


def test_direction_in_a_scene_file_and_on_the_command_line(tmp_path):
    from fsicas.cli import build_parser
    from fsicas.cli.scene_options import scene_from_args
    path = tmp_path / "s.toml"
    path.write_text('ustar = 4.0\ndirection = "reverse"\n')
    parse = lambda *argv: scene_from_args(build_parser().parse_args(["steady", *argv]))
    assert parse("--scene", str(path)).ustar == -4.0
    assert parse("--scene", str(path), "--direction", "forward").ustar == 4.0
    assert parse("--ustar", "2", "--direction", "reverse").ustar == -2.0
    with pytest.raises(ValueError, match="negative ustar"):
        parse("--ustar=-2", "--direction", "reverse")


def test_physical_flow_carries_its_sign():
    from fsicas.physical import load_physical, parse_flow
    palate = load_physical("soft_palate")
    forward = palate.scene(parse_flow("20L/min"))
    assert palate.scene(parse_flow("-20L/min")).ustar == pytest.approx(-forward.ustar, rel=1e-14)
    assert palate.scene(parse_flow("20L/min"), direction="reverse").ustar == \
        pytest.approx(-forward.ustar, rel=1e-14)
    with pytest.raises(ValueError, match="negative and a direction"):
        palate.scene(parse_flow("-20L/min"), direction="reverse")
    with pytest.raises(ValueError, match="nonzero"):
        parse_flow("0L/min")


# -- the flow alone: head losses by direction, mirror identity ---------------------------
def _upstream_march(H, dH, Q, mstar, f, k0, kl, pl=0.0):
    """Steady bulk flow through a rigid channel of height H(x) with the flow rate Q < 0
    (entering at x = 1): the pressure marched by an ODE solver from the upstream end,
    where the fluid leaves the reservoir PL through the opening of loss KL,
    p(1) = PL - M*/2 (u^2 + KL u^2), along p' = -M* (u u' + f u|u|/H), u = Q/H, to the
    root, where it leaves through the opening of loss K0 into the reservoir
    P0 = p(0) + M*/2 (u^2 - K0 u^2). Returns P0 - PL."""
    u = lambda x: Q / H(x)
    rhs = lambda x, p: [-mstar * (u(x) * (-Q * dH(x) / H(x) ** 2) + f * u(x) * abs(u(x)) / H(x))]
    u1 = u(1.0)
    p1 = pl - mstar / 2 * (u1**2 + kl * u1**2)
    sol = solve_ivp(rhs, (1.0, 0.0), [p1], method="DOP853", rtol=1e-13, atol=1e-14)
    u0 = u(0.0)
    p0 = sol.y[0, -1] + mstar / 2 * (u0**2 - k0 * u0**2)
    return p0 - pl


def _rigid_channel(h_root, h_tip, k0, kl, ustar, **kw):
    """A symmetric channel whose beam is held straight (q = 0, r = 0)."""
    wall = Profile.linear(h_root / 2, h_tip / 2)
    return Scene(hstar=h_root, channel1=wall, channel2=wall, k0=k0, kl=kl, ustar=ustar,
                 modes=4, mstar=0.7, friction=0.14, **kw)


def _model_pressure_drop(scene):
    """Δp that makes the model's flow rows steady with the beam straight and Q from U*:
    the rows are Δp/M* + (the rest), so Δp = -M* (row at Δp = 0)."""
    model = build_model(scene)
    x = np.r_[np.zeros(2 * scene.modes), [scene.ustar * scene.hstar / 2] * 2]
    rows = np.asarray(model.rhs(x, model.parameters(scene, 0.0))).ravel()[-2:]
    return -scene.mstar * rows, x


def test_reversed_flow_head_losses_against_an_upstream_march():
    """Reversed flow (U* < 0): the model's Δp equals the pressure marched from the
    tip, with KL the loss of the fluid entering at the tip and K0 that of the fluid
    leaving at the root (the u|u| terms of Eq. 6 with its sign terms)."""
    scene = _rigid_channel(0.1, 0.06, k0=0.8, kl=0.35, ustar=-3.0)
    H = lambda x: 0.05 - 0.02 * x                      # one channel: half the gap
    dp = _upstream_march(H, lambda x: -0.02 + 0 * x, scene.ustar * 0.05, scene.mstar,
                            scene.friction, scene.k0, scene.kl)
    model_dp, _ = _model_pressure_drop(scene)
    assert dp < 0
    np.testing.assert_allclose(model_dp, dp, rtol=1e-11)


def test_mirror_identity_of_the_flow_alone():
    """A reversed channel is the mirrored forward channel (x -> 1 - x) with K0 and KL
    exchanged: opposite pressure drops, mirrored pressure fields, the same losses."""
    rev = _rigid_channel(0.1, 0.06, k0=0.8, kl=0.35, ustar=-3.0)
    fwd = _rigid_channel(0.06, 0.1, k0=0.35, kl=0.8, ustar=3.0 * 0.1 / 0.06)
    dp_rev, x_rev = _model_pressure_drop(rev)
    dp_fwd, x_fwd = _model_pressure_drop(fwd)
    np.testing.assert_allclose(dp_rev, -dp_fwd, rtol=1e-12)
    s = np.linspace(0.0, 1.0, 2001)
    p_rev = flow_fields(rev, x_rev, 0 * x_rev, dp_rev[0], s).p      # PL = 0, P0 = Δp
    p_fwd = flow_fields(fwd, x_fwd, 0 * x_fwd, dp_fwd[0], s).p
    # upstream reservoir at 0 in both: p_rev - PL_rev = p_fwd(1 - x) - P0_fwd
    np.testing.assert_allclose(p_rev, p_fwd[:, ::-1] - dp_fwd[0], atol=1e-9 * abs(dp_fwd[0]))
    # the same losses: singular K0 u0|u0| + KL u1|u1| (the rows' loss terms) are equal
    u_rev, u_fwd = x_rev[-1] / 0.1, x_fwd[-1] / 0.06
    loss_rev = rev.k0 * u_rev * abs(u_rev) + rev.kl * (x_rev[-1] / 0.06) * abs(x_rev[-1] / 0.06)
    loss_fwd = fwd.k0 * u_fwd * abs(u_fwd) + fwd.kl * (x_fwd[-1] / 0.1) * abs(x_fwd[-1] / 0.1)
    assert loss_rev == pytest.approx(-loss_fwd, rel=1e-14)



def test_reversed_flow_satisfies_the_pdes_and_both_boundary_conditions(channel_pde_check):
    """On non-equilibrium states of reversed flow (Q < 0, Δp < 0, the beam moving) the
    fields rebuilt by the independent route (cumulative Simpson on 8001 points) and
    advanced by DOP853 (rtol 1e-13) satisfy continuity and momentum (4) by central
    differences in x and t, and Eq. 6 with its sign terms at both openings to round-off."""
    scene = Scene(mstar=2.0, ustar=-4.0, modes=4, k0=0.3, kl=0.8, zeta=0.02,
                  channel1=Profile.linear(0.05, 0.035),
                  channel2=Profile.table([0.0, 0.5, 1.0], [0.05, 0.06, 0.045]))
    model = build_model(scene)
    rng = np.random.default_rng(3)
    decay = 1.0 / np.arange(1, 5) ** 2
    x0 = np.r_[0.05 * rng.normal(size=4) * decay, 1e-3 * rng.normal(size=4) * decay,
               -np.array([0.2, 0.15])]
    dp = -30.0
    for h, u, pc, scale in channel_pde_check(scene, model, x0, dp):
        assert np.all(u < 0)
        u0, u1 = u[0], u[-1]      # leaving at the root through K0, entering at the tip through KL
        assert pc[0] == pytest.approx(dp - scene.mstar / 2 * (1 - scene.k0) * u0**2, rel=1e-13)
        assert pc[-1] == pytest.approx(-scene.mstar / 2 * (1 + scene.kl) * u1**2, rel=1e-11,
                                       abs=1e-11 * scale)


# -- the steady state under reversed flow ------------------------------------------------
def _steady_bvp(scene):
    """Steady state of the flexible beam in a straight channel by collocation of the
    beam-flow boundary-value problem (scipy solve_bvp), no modes: state (y, y', y'',
    y''', p1, p2), unknowns (Q1, Q2, Δp); y'''' = p2 - p1 with h_c = H_c + s_c y,
    p_c' = -M* (u_c u_c' + f u_c|u_c|/h_c), Eq. 6 at both ends (P0 = Δp, PL = 0)."""
    H = [w(0.0) for w in scene.walls]
    m, f, k0, kl = scene.mstar, scene.friction, scene.k0, scene.kl
    signs = (-1.0, 1.0)

    def rhs(x, z, par):
        out = [z[1], z[2], z[3], z[5] - z[4]]
        for c, s in enumerate(signs):
            h, u = H[c] + s * z[0], par[c] / (H[c] + s * z[0])
            out.append(-m * (u * (-par[c] * s * z[1] / h**2) + f * u * np.abs(u) / h))
        return np.vstack(out)

    def bc(za, zb, par):
        res = [za[0], za[1], zb[2], zb[3], par[0] + par[1] - scene.ustar * scene.hstar]
        for c, s in enumerate(signs):
            u0, u1 = par[c] / (H[c] + s * za[0]), par[c] / (H[c] + s * zb[0])
            res.append(za[4 + c] - (par[2] - m / 2 * (u0**2 + k0 * u0 * abs(u0))))
            res.append(zb[4 + c] - (0.0 - m / 2 * (u1**2 - kl * u1 * abs(u1))))
        return np.array(res)

    x = np.linspace(0, 1, 201)
    dp0 = scene.mstar * scene.ustar * abs(scene.ustar) * ((k0 + kl) / 2 + 2 * f / scene.hstar)
    z0 = np.zeros((6, x.size))
    z0[4] = z0[5] = dp0 * (1 - x)
    par0 = [scene.ustar * H[0], scene.ustar * H[1], dp0]
    sol = solve_bvp(rhs, bc, x, z0, p=par0, tol=1e-10, max_nodes=100000)
    assert sol.status == 0, sol.message
    return sol


def test_steady_state_under_reversed_flow_against_a_collocated_bvp():
    """An asymmetric straight channel, U* = -4: the modal steady state (N = 16) against
    the collocated beam-flow BVP (tip deflection, Δp, Q1 to the modal truncation)."""
    scene = Scene(hstar=0.1, channel1=Profile.constant(0.055), channel2=Profile.constant(0.045),
                  mstar=1.0, ustar=-4.0, k0=0.6, kl=1.0, modes=16)
    model = build_model(scene)
    st = steady_state(scene, model)
    sol = _steady_bvp(scene)
    tip = float(model.deflection(st.x, [1.0])[0])
    assert st.pressure_drop < 0 and np.all(st.Q < 0)
    assert abs(tip - sol.sol(1.0)[0]) < 1e-5 * abs(tip)
    assert st.pressure_drop == pytest.approx(sol.p[2], rel=1e-6)
    assert st.Q[0] == pytest.approx(sol.p[0], rel=1e-6)


# -- stability under reversed flow -------------------------------------------------------
def _unstable_count(model, scene, ustar):
    from fsicas.linear.stability import eigenvalues
    lam = eigenvalues(model, steady_state(scene.replace(ustar=ustar), model))
    return int(np.sum(lam.real > 0)), float(lam[0].real)


@pytest.fixture(scope="module")
def reversed_cantilever():
    scene = Scene(mstar=1.0, ustar=-1.0, modes=8)
    return scene, build_model(scene)


@pytest.mark.parametrize("hstar", [0.1, 0.05])
def test_reversed_onset_against_a_direct_eigenvalue_scan(reversed_cantilever, hstar):
    """The onset of expiration (U* < 0) against the growth rate of the steady states
    scanned over U* < 0 without continuation: the first U* where an eigenvalue has a
    positive real part, bracketed on the scan and solved by Brent's method. At H* = 0.05
    the steady state is unstable only for |U*| in (0.2385, 1.5788) below the first Hopf
    point (1.853): a window the search must not step over."""
    from scipy.optimize import brentq
    from fsicas.linear.hopf import critical_velocity
    scene, model = reversed_cantilever
    if hstar != scene.hstar:
        scene = scene.replace(hstar=hstar)
        model = build_model(scene)
    onset = critical_velocity(scene, model, ustar_max=40.0)
    grid = -np.linspace(0.05, 2.0, 40)
    rates = [_unstable_count(model, scene, u)[1] for u in grid]
    k = int(np.argmax(np.array(rates) > 0))
    assert k > 0
    ustar = brentq(lambda u: _unstable_count(model, scene, u)[1], grid[k], grid[k - 1],
                   xtol=1e-13, rtol=1e-13)
    assert onset.kind == "divergence" and onset.ustar < 0 and onset.pressure_drop < 0
    assert onset.ustar == pytest.approx(ustar, rel=1e-9)


def test_reversed_onsets_change_the_unstable_count_of_the_scan(reversed_cantilever):
    """Every onset of the reversed branch up to |U*| = 12 is where the count of unstable
    eigenvalues of the scanned steady states changes (by 1 at a divergence, 2 at a Hopf
    point), and the count is constant between them."""
    from fsicas.linear.hopf import onset_points
    scene, model = reversed_cantilever
    points = onset_points(scene, model, ustar_max=12.0)
    assert [p.kind for p in points][:2] == ["divergence", "flutter"]
    edges = [0.0] + [abs(p.ustar) for p in points] + [12.0]
    count = 0
    for p, lo, hi in zip(points, edges[:-2], edges[2:]):
        before = _unstable_count(model, scene, p.ustar * (1 - 1e-7))[0]
        after = _unstable_count(model, scene, p.ustar * (1 + 1e-7))[0]
        assert before == count and abs(after - before) == (1 if p.kind == "divergence" else 2)
        middle = -(abs(p.ustar) + hi) / 2
        assert _unstable_count(model, scene, middle)[0] == after
        count = after


def test_reversed_divergence_pressure_is_independent_of_mstar(reversed_cantilever):
    """A divergence is a loss of static stability, and the steady equations hold M* and
    U* only as M* u^2, fixed by Δp: Δp_c is the same at every M* and U*_c ∝ M*^-1/2
    (a scaling law, not the code's own numbers)."""
    from fsicas.linear.hopf import critical_velocity
    scene, model = reversed_cantilever
    a = critical_velocity(scene, model, ustar_max=10.0)
    b = critical_velocity(scene.replace(mstar=0.1), model, ustar_max=10.0)
    assert b.kind == a.kind == "divergence"
    assert b.pressure_drop == pytest.approx(a.pressure_drop, rel=1e-9)
    assert b.ustar == pytest.approx(a.ustar * np.sqrt(10.0), rel=1e-9)


@pytest.mark.parametrize("mstar", [1e4, 1e6])
def test_reversed_divergence_below_a_hundredth_at_large_mass_ratios(reversed_cantilever, mstar):
    """At M* = 1e4 and 1e6 the reversed divergence lies at |U*| = 0.0045 and 0.00045,
    below the start |U*| = 0.01 of M* <= 1: the search starts at 0.01 / sqrt(M*). Δp_c
    is that of M* = 1 (the scaling law) and the unstable count of the steady states
    steps from 0 to 1 there (direct eigenvalues, no continuation)."""
    from fsicas.linear.hopf import critical_velocity
    scene, model = reversed_cantilever
    a = critical_velocity(scene, model, ustar_max=10.0)
    b = critical_velocity(scene.replace(mstar=mstar), model, ustar_max=10.0)
    assert b.kind == "divergence" and abs(b.ustar) < 0.01
    assert b.pressure_drop == pytest.approx(a.pressure_drop, rel=1e-9)
    heavy = scene.replace(mstar=mstar)
    assert [_unstable_count(model, heavy, b.ustar * f)[0] for f in (1 - 1e-6, 1 + 1e-6)] == [0, 1]


def test_a_reversed_divergence_solved_between_steps_is_located_again():
    """K0 = 1, KL = 0.5, M* = 0.1: the library locates no divergence in the step where
    the reversed branch loses stability; it is solved between the steps and located
    again from 1 % below its speed (a signed start was refused). Against the first sign
    change of the largest growth rate of steady states scanned without continuation."""
    from scipy.optimize import brentq
    from fsicas.linear.hopf import critical_velocity
    scene = Scene(mstar=0.1, ustar=-1.0, hstar=0.1, friction=0.14, k0=1.0, kl=0.5,
                  zeta=0.01, modes=6)
    model = build_model(scene)
    onset = critical_velocity(scene, model, ustar_max=20.0)
    grid = -np.linspace(0.05, 2.0, 40)
    rates = np.array([_unstable_count(model, scene, u)[1] for u in grid])
    k = int(np.argmax(rates > 0))
    assert k > 0
    ustar = brentq(lambda u: _unstable_count(model, scene, u)[1], grid[k], grid[k - 1],
                   xtol=1e-13, rtol=1e-13)
    assert onset.kind == "divergence" and onset.ustar == pytest.approx(ustar, rel=1e-9)


def test_a_fold_far_below_the_search_bound_is_found_on_finer_steps():
    """An asymmetric channel (H1 = 0.55 H*, K0 = KL = 0.5, M* = 1): the reversed branch
    folds at |U*| = 0.37, where the steps of a search up to 40 jumped across the fold onto
    another branch (stability lost with no special point located). The repeated search
    on finer steps returns the fold: a real eigenvalue of the Jacobian at its state is
    zero (direct eigenvalues), and the steady state 1 % below it is stable."""
    from fsicas.linear.hopf import critical_velocity
    from fsicas.linear.stability import generalized_eigen
    scene = Scene(mstar=1.0, ustar=-1.0, hstar=0.1, friction=0.14, k0=0.5, kl=0.5, modes=8,
                  channel1=Profile.constant(0.055), channel2=Profile.constant(0.045))
    model = build_model(scene)
    onset = critical_velocity(scene, model, ustar_max=40.0)
    assert onset.kind == "divergence" and onset.bifurcation == "fold" and onset.ustar < 0
    p = model.parameters(scene.replace(ustar=onset.ustar), pressure_drop=onset.pressure_drop)
    lam, _ = generalized_eigen(model.jac_rhs(onset.x, p), model.mass(onset.x, p))
    real = lam[np.abs(lam.imag) <= 1e-9 * np.abs(lam)].real
    assert np.min(np.abs(real)) < 1e-6 * np.max(np.abs(lam))
    assert _unstable_count(model, scene, 0.99 * onset.ustar)[0] == 0


# -- a breath through zero flow ----------------------------------------------------------
def test_tidal_schedule_goes_through_zero_flow():
    from fsicas.timedomain.breathing import PressureSchedule
    s = PressureSchedule.tidal(2.0, 0.5, period=4.0)
    t = np.array([0.0, 1.0, 2.0, 3.0, 4.0, 5.0])
    np.testing.assert_allclose(s.ustar_at(t), [0.0, 2.0, 0.0, -0.5, 0.0, 2.0], atol=1e-14)
    assert s.reference_ustar == 2.0
    assert PressureSchedule.tidal(0.0, 0.5, 1.0).reference_ustar == -0.5
    with pytest.raises(ValueError, match="tidal breath"):
        PressureSchedule.tidal(-1.0, 0.5, 1.0)


def test_breath_through_zero_flow_against_the_flow_ode():
    """Inspiration then expiration in a straight symmetric channel: the beam stays at
    rest and each channel's flow obeys the scalar ODE of its flow row,
    Q' = h k (U|U| - u|u|), u = Q/h, k = (K0 + KL)/2 + f/h (the schedule's Δp is the
    steady one of U(t)); the integrated Q1 + Q2 (IDAS, rtol 1e-9) through both reversals
    against DOP853 on that ODE (rtol 1e-12), and the volume through the channel over
    the breath, to the integrator's tolerance."""
    from fsicas.timedomain.breathing import PressureSchedule
    from fsicas.timedomain.integrators import Settings, simulate
    scene = Scene(mstar=1.0, ustar=2.0, modes=6, k0=0.3, kl=1.0)
    model = build_model(scene)
    period, h = 4.0, scene.hstar / 2
    schedule = PressureSchedule.tidal(2.0, 0.4, period)      # below the reversed divergence
    traj = simulate(model, steady_state(scene, model), 1.5 * period, schedule=schedule,
                    perturbation=0.0, settings=Settings(rtol=1e-9, atol=1e-12, dt_out=1e-2))
    assert traj.status == "success"
    k = (scene.k0 + scene.kl) / 2 + scene.friction / h
    U = schedule.ustar_at
    ode = solve_ivp(lambda t, Q: h * k * (U(t) * abs(U(t)) - (Q / h) * abs(Q / h)),
                    (0.0, traj.t[-1]), [scene.ustar * h], method="DOP853", rtol=1e-12,
                    atol=1e-15, t_eval=traj.t, max_step=0.01)
    total = traj.x[:, -2:].sum(axis=1)
    assert total.min() < 0 < total.max()                     # it went through zero twice
    assert np.max(np.abs(traj.x[:, :2 * scene.modes])) < 1e-6 * h   # at rest (round-off)
    np.testing.assert_allclose(total, 2 * ode.y[0], atol=1e-7 * np.max(np.abs(total)))
    assert trapezoid(total, traj.t) == pytest.approx(2 * trapezoid(ode.y[0], traj.t), rel=1e-7)


def test_breath_through_zero_flow_with_a_moving_beam_and_its_quadrature_estimate():
    """Whole breaths through an asymmetric channel with the beam moving: the run goes
    through every reversal (IDAS's step control copes with the C^1 u|u|), its quadrature
    estimate includes the samples around each reversal of the inlet flow, and there the
    estimate (F on 2K nodes against K) is within a factor 2 of the error against 8K
    nodes (the flow reverses inside the channel: algebraic convergence)."""
    from fsicas.model.accuracy import quadrature_error, relative_error
    from fsicas.timedomain.breathing import PressureSchedule
    from fsicas.timedomain.run import _spread, run_case
    scene = Scene(mstar=1.0, ustar=3.0, modes=6, zeta=0.01, channel1=Profile.constant(0.055),
                  channel2=Profile.constant(0.045))
    run = run_case(scene, 8.0, schedule=PressureSchedule.tidal(3.0, 1.0, 4.0),
                   perturbation=0.05, stop_early=False)
    traj, model = run.trajectory, run.model
    assert run.status == "success"
    total = traj.x[:, -2:].sum(axis=1)
    assert len(np.flatnonzero(np.diff(np.sign(total)))) == 3    # in, out, in again
    flips = np.flatnonzero(np.any(np.diff(np.sign(traj.x[:, -2:]), axis=0) != 0, axis=1))
    sampled = _spread(traj.x)
    assert all(any(np.array_equal(traj.x[k], row) for row in sampled) for k in flips)
    fine = build_model(model.scene.replace(quad_nodes=8 * model.scene.n_quad))
    rhs = lambda m, x, p: np.asarray(m.rhs(x, p)).ravel()
    ratios = []
    for k in np.r_[flips, flips + 1]:
        p = traj.p.copy()
        p[model.index("pressure_drop")] = traj.pressure_drop[k]
        error = relative_error(rhs(fine, traj.x[k], p), rhs(model, traj.x[k], p))
        if error > 1e-14:                                   # above round-off
            ratios.append(quadrature_error(model, traj.x[k], p) / error)
    assert ratios and 0.5 < min(ratios) and max(ratios) < 2.0


def test_reversed_pitchfork_is_subcritical_and_its_deflected_states_end_at_the_wall(
        reversed_cantilever):
    """Past the reversed divergence the deflected steady states turn back to lower
    speeds, unstable (a subcritical pitchfork), and end where the tip reaches the
    contact layer: |y(1)| = H*/2 - eps there, every state steady (|F| at round-off)."""
    from fsicas.linear.deflected import deflected_branch
    from fsicas.linear.hopf import critical_velocity
    scene, model = reversed_cantilever
    onset = critical_velocity(scene, model, ustar_max=10.0)
    branch = deflected_branch(scene, model, onset, ustar_max=10.0)
    assert branch.status == "wall" and not branch.stable.any()
    assert np.all(np.abs(branch.ustar) < abs(onset.ustar))
    assert abs(branch.tip_deflection[-1]) == pytest.approx(scene.hstar / 2 - scene.contact_gap,
                                                            rel=1e-8)
    for x, dp in zip(branch.states, branch.pressure_drop):
        residual = np.asarray(model.rhs(x, model.parameters(scene, dp))).ravel()
        assert np.max(np.abs(residual)) < 1e-8 * max(1.0, np.max(np.abs(x)))


def test_reversed_boundary_is_the_divergence_scaling_law(reversed_cantilever):
    """The boundary U*_c(M*) of reversed flow over two decades: divergence everywhere
    (no switch), negative, on the law U*_c ∝ M*^-1/2 of a static loss of stability
    through the onset at M* = 1 checked against the eigenvalue scan above."""
    from fsicas.linear.boundary import stability_boundary
    from fsicas.linear.hopf import critical_velocity
    scene, model = reversed_cantilever
    mstars = np.array([0.1, 0.5, 2.0, 10.0])
    boundary = stability_boundary(scene, mstars, model, ustar_max=10.0)
    u1 = critical_velocity(scene, model, ustar_max=10.0).ustar
    assert not boundary.switches and not boundary.warnings
    for p in boundary.points:
        assert p.kind == "divergence" and p.refined and not p.missed
        assert p.ustar_crit == pytest.approx(u1 / np.sqrt(p.mstar), rel=1e-9)


def test_physical_margin_of_a_reversed_onset_is_on_the_magnitudes():
    """An expiration of 1 L/min below a reversed onset of -1.5 L/min keeps a margin of
    +0.5 L/min and does not reach the onset; one of 2 L/min does."""
    from fsicas.physical import load_physical, parse_flow
    from fsicas.physical_report import onset_json
    scales = load_physical("soft_palate").scene(parse_flow("-1L/min")).scales
    u = lambda l_min: l_min / scales.l_per_min(1.0)
    onset = {"ustar_crit": u(-1.5), "mstar": 0.1, "omega": 0.0, "freq_ratio": 0.0,
             "pressure_drop": -1.0, "criticality": None}
    calm = onset_json(scales, onset, u(-1.0), 40.0)
    assert calm["margin_flow_l_min"] == pytest.approx(0.5, rel=1e-12)
    assert calm["flutters_at_reference"] is False
    assert onset_json(scales, onset, u(-2.0), 40.0)["flutters_at_reference"] is True


def test_reversed_flutter_cycles_close_under_an_independent_integration():
    """A narrow-loss channel (f = 0.02) flutters first under reversed flow, subcritically
    (l1 > 0): its cycle branch runs back to lower speeds, and its cycles, integrated over
    their period by DOP853 from their own state (no collocation), return to it."""
    from fsicas.cycles.collocation import CycleSettings, cycle_branch
    scene = Scene(ustar=-1.0, mstar=1.0, modes=6, friction=0.02)
    model = build_model(scene)
    branch = cycle_branch(scene, model, ustar_max=1.0, settings=CycleSettings(max_points=13))
    hopf = branch.hopf
    assert hopf["kind"] == "flutter" and hopf["ustar_crit"] < 0 and hopf["l1"] > 0
    assert all(hopf["ustar_crit"] < pt.ustar < 0 for pt in branch.points)
    for pt in (branch.points[0], branch.points[-1]):
        p = model.parameters(scene, pt.pressure_drop)
        sol = solve_ivp(lambda t, z: model.xdot(z, p), (0.0, pt.period), pt.state,
                        method="DOP853", rtol=1e-11, atol=1e-13)
        assert np.max(np.abs(sol.y[:, -1] - pt.state)) < 1e-6 * np.max(np.abs(sol.y))


def test_a_curve_of_one_point_has_no_piece_and_the_envelope_keeps_the_others():
    """A divergence curve that could not be followed (one point) has no segment and no
    piece, so the pieces of the curves stacked after it stay aligned with their segments
    (the reversed boundary at f = 0.02 picked a wrong piece before)."""
    from fsicas.linear.boundary import _next_piece
    from fsicas.linear.curves import Envelope, OnsetCurve
    one = OnsetCurve(0, np.array([10.0]), np.array([-1.6]), np.zeros(1), np.ones(1, int),
                     "failed", first_piece=3, kind="divergence")
    two = OnsetCurve(1, np.array([50.0, 200.0]), np.array([-0.5, -0.3]), np.array([1.0, 2.0]),
                     np.ones(2, int), "bound", first_piece=4)
    assert one.pieces.size == 0 and _next_piece([one]) == 4 and _next_piece([one, two]) == 5
    u, w, piece = Envelope([one, two]).lowest(2.0)
    t = (2.0 - np.log10(50.0)) / (np.log10(200.0) - np.log10(50.0))
    assert piece == 4 and u == pytest.approx(-0.5 + 0.2 * t, rel=1e-14)


def test_the_cli_searches_a_reversed_onset_below_the_forward_start(run_cli, tmp_path):
    """``--ustar-max`` of reversed flow may lie below the forward start |U*| = 0.2 (the
    reversed search starts at 0.01 / sqrt(M*)): at M* = 1e4 with --ustar-max 0.1 the CLI
    finds the divergence the library finds; below the reversed start it is refused."""
    import json
    from fsicas.linear.hopf import critical_velocity
    argv = ["onset", "--direction", "reverse", "--mstar", "1e4", "--modes", "6", "--json"]
    found = run_cli([*argv, "--ustar-max", "0.1"], tmp_path)
    assert found.returncode == 0, found.stderr
    onset = critical_velocity(Scene(mstar=1e4, ustar=-1.0, modes=6), ustar_max=0.1)
    assert json.loads(found.stdout)["ustar_crit"] == pytest.approx(onset.ustar, rel=1e-9)
    assert onset.kind == "divergence" and -0.01 < onset.ustar < 0
    refused = run_cli([*argv, "--ustar-max", "0.005"], tmp_path)
    assert refused.returncode == 2 and "--ustar-max must lie in (0.01," in json.loads(refused.stdout)["error"]
    forward = run_cli(["onset", "--mstar", "1e4", "--ustar-max", "0.1"], tmp_path)
    assert forward.returncode == 2 and "--ustar-max must lie in (0.2," in forward.stderr


def test_a_reversed_boundary_survives_an_onset_curve_that_cannot_be_traced():
    """f = 0.02, zeta = 0.01, N = 6: one Hopf point of the reversed boundary gives a curve
    whose start does not converge (it raised a KeyError). The boundary says so in its
    warnings, and each of its points is the onset the steady branch finds at that M*
    (critical_velocity, no curves)."""
    from fsicas.linear.boundary import stability_boundary
    from fsicas.linear.hopf import critical_velocity
    scene = Scene(ustar=-1.0, friction=0.02, modes=6, zeta=0.01)
    model = build_model(scene)
    boundary = stability_boundary(scene, np.geomspace(0.1, 10, 6), model)
    failed = [c for c in boundary.curves if not c.mstar.size]
    assert failed and all(c.status == "failed" for c in failed)
    assert any("could not be traced" in w for w in boundary.warnings)
    for p in boundary.points:
        onset = critical_velocity(scene.replace(mstar=p.mstar), model)
        assert p.kind == onset.kind and p.ustar_crit == pytest.approx(onset.ustar, rel=1e-6)
