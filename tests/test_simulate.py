"""Time integration against the linear analysis, independent routes, and bad input."""
import re

import numpy as np
import pytest
import scipy.integrate
import scipy.optimize

from fsicas import Scene, build_model, steady_state
from fsicas.model.contact import law
from fsicas.timedomain.breathing import PressureSchedule
from fsicas.timedomain.integrators import Settings, eigenvector_state, gaps, initial_state, simulate
from fsicas.linear.stability import eigenvalues


@pytest.fixture(scope="module")
def model(damped_scene_u7):
    return build_model(damped_scene_u7)


def leading_mode_start(model, steady, size):
    return eigenvector_state(model, steady, size)


def tip_growth_rate(traj, steady, t_from):
    """Log-slope of the positive tip-deviation peaks after ``t_from``."""
    y = traj.tip - traj.model.deflection(steady.x, [1.0])[0]
    k = np.flatnonzero((y[1:-1] > y[:-2]) & (y[1:-1] >= y[2:]) & (y[1:-1] > 0)) + 1
    k = k[traj.t[k] >= t_from]
    return np.polyfit(traj.t[k], np.log(y[k]), 1)[0], 2 * np.pi / np.mean(np.diff(traj.t[k]))


@pytest.mark.parametrize("ustar", [4.0, 7.0])
def test_early_growth_rate_and_frequency_match_the_leading_eigenvalue(model, ustar, damped_scene_u7):
    steady = steady_state(damped_scene_u7.replace(ustar=ustar), model)
    x0, lam = leading_mode_start(model, steady, 1e-6)
    assert lam == pytest.approx(eigenvalues(model, steady)[0], rel=1e-10)
    traj = simulate(model, steady, 1.0, x0=x0, settings=Settings(rtol=1e-10, atol=1e-15, dt_out=2e-4))
    rate, omega = tip_growth_rate(traj, steady, 0.0)
    assert rate == pytest.approx(lam.real, rel=2e-4)      # U*=4: -2.886, U*=7: +3.939 (measured 1e-5)
    assert omega == pytest.approx(abs(lam.imag), rel=5e-4)


def test_onset_of_oscillation_brackets_the_linear_instability(model, damped_scene_u7):
    rate = lambda u: eigenvalues(model, steady_state(damped_scene_u7.replace(ustar=u), model))[0].real
    u_c = scipy.optimize.brentq(rate, 5.0, 6.5, xtol=1e-10)
    growth = []
    for u in (u_c - 0.1, u_c + 0.1):
        steady = steady_state(damped_scene_u7.replace(ustar=u), model)
        x0, lam = leading_mode_start(model, steady, 1e-6)
        traj = simulate(model, steady, 3.0, x0=x0, settings=Settings(rtol=1e-10, atol=1e-15, dt_out=5e-4))
        measured, _ = tip_growth_rate(traj, steady, 0.0)
        growth.append(measured)
        assert measured == pytest.approx(lam.real, abs=5e-4)   # rates -0.2917, +0.2978
    assert growth[0] < -0.05 and growth[1] > 0.05          # stable below, growing above


def test_casadi_and_scipy_routes_agree(model, damped_scene_u7):
    steady = steady_state(damped_scene_u7, model)
    runs = {m: simulate(model, steady, 0.3, settings=Settings(method=m, rtol=1e-10, atol=1e-13, chunk=0.15))
            for m in ("cvodes", "idas", "radau")}
    ref = runs["radau"].x
    n = model.n_modes
    blocks = (slice(0, n), slice(n, 2 * n), slice(2 * n, None))     # r, q, Q
    for m in ("cvodes", "idas"):
        assert runs[m].status == "success", runs[m].message
        for b in blocks:
            err = np.max(np.abs(runs[m].x[:, b] - ref[:, b])) / np.max(np.abs(ref[:, b]))
            assert err < 1e-6, (m, b, err)


def test_schedule_time_input_matches_piecewise_constant_drive(model, damped_scene_u7):
    """A ramp fed as a time input equals chunks of constant Δp in the limit: check Δp(t)."""
    steady = steady_state(damped_scene_u7, model)
    sched = PressureSchedule.ramp(3.0, 7.0, 0.2)
    traj = simulate(model, steady, 0.3, schedule=sched, settings=Settings(chunk=0.1))
    c = steady.pressure_drop / 49.0
    u = np.interp(traj.t, [0.0, 0.2, 0.3], [3.0, 7.0, 7.0])
    assert np.allclose(traj.pressure_drop, c * u**2, rtol=1e-13)
    # the flow follows: total inlet flow rate rises from the U*=3 level towards U*=7
    q = traj.x[:, -2:].sum(axis=1) / damped_scene_u7.hstar
    assert q[0] == pytest.approx(7.0, rel=1e-12)   # starts from the steady state at U_ref
    assert q[np.searchsorted(traj.t, 0.05)] < 6.5


def test_straight_channel_pressure_coefficient_is_exact():
    scene = Scene(mstar=2.0, ustar=5.0, modes=4)
    steady = steady_state(scene)
    c = steady.pressure_drop / 25.0
    assert c == pytest.approx(2.0 * (0.5 + 2 * 0.14 / 0.1), rel=1e-13)
    s = PressureSchedule.breath(5.0, 2.0)
    assert s.ustar_at([0.0, 0.5, 1.0]) == pytest.approx([0.0, 5 * np.sqrt(0.5), 5.0], abs=1e-14)


@pytest.mark.parametrize("kwargs, field", [
    (dict(t_end=0.0), "t_end"), (dict(t_end=-1.0), "t_end"), (dict(t_end=np.nan), "t_end"),
    (dict(perturbation=30.0), "perturbation"),
])
def test_bad_run_input_raises_before_work(model, kwargs, field, damped_scene_u7):
    steady = steady_state(damped_scene_u7, model)
    args = dict(t_end=1.0, perturbation=1e-2) | kwargs
    with pytest.raises(ValueError, match=field):
        simulate(model, steady, args["t_end"], perturbation=args["perturbation"])


@pytest.mark.parametrize("kwargs, field", [
    (dict(rtol=1.0), "rtol"), (dict(rtol=1e-16), "rtol"), (dict(atol=0.0), "atol"),
    (dict(atol=1.0), "atol"), (dict(method="euler"), "method"), (dict(dt_out=-1.0), "dt_out"),
    (dict(max_steps=0), "max_steps"),
])
def test_settings_out_of_range_raise(kwargs, field):
    with pytest.raises(ValueError, match=field):
        Settings(**kwargs)


def test_perturbation_array_shape_checked(model, damped_scene_u7):
    steady = steady_state(damped_scene_u7, model)
    with pytest.raises(ValueError, match="perturbation"):
        initial_state(model, steady, np.zeros(3))


def test_closing_gap_is_a_reported_failure_not_nan(damped_scene_u7, capfd):
    """A contact law too soft for the impact: the gap closes; the run says so, no NaN,
    and nothing of the solver's retries reaches the terminal."""
    scene = damped_scene_u7.replace(ustar=8.0, contact=True, contact_stiffness=1e4, contact_eps=1e-3)
    model = build_model(scene)
    steady = steady_state(scene, model)
    capfd.readouterr()
    traj = simulate(model, steady, 3.0, settings=Settings(rtol=1e-7, atol=1e-9))
    assert traj.status == "failed" and traj.gap_closed and "gap closed" in traj.message
    assert np.all(np.isfinite(traj.x)) and traj.t[-1] < 3.0
    printed = capfd.readouterr()
    assert printed.out == "" and printed.err == ""
    # the last state was inside the layer: the law did not stop the beam there
    assert gaps(model, traj.x[-1:]).min() < scene.contact_gap
    assert "did not stop the beam within the contact layer" in traj.message
    # and says by how much: the energy the law stored, against a fine trapezoid rule of
    # k ∫ max(0, eps - h)² / 2 at the last state, and the ratio to the kinetic energy of
    # the deepest point in mode 1 (effective mass 1/φ1²)
    stored = float(re.search(r"stored ([0-9.e+-]+),", traj.message).group(1))
    xs = np.linspace(0.0, 1.0, 200001)
    k, eps = law(model, steady.p)
    h = gaps(model, traj.x[-1:], xs)[0]
    exact = k * scipy.integrate.trapezoid(np.maximum(0.0, eps - h).sum(axis=0) ** 2, xs) / 2
    assert stored == pytest.approx(exact, rel=0.3)
    assert "thicker layer (contact_eps)" in traj.message
    phi = model.basis_at([xs[np.argmin(h.min(axis=0))]]).phi[:, 0]
    kinetic = 0.5 * (phi @ traj.x[-1, :model.n_modes]) ** 2 / phi[0] ** 2
    factor = float(re.search(r"order of ([0-9.e+-]+)x stiffer", traj.message).group(1))
    assert factor == pytest.approx(kinetic / exact, rel=0.35) and factor > 100


def test_a_step_across_the_whole_contact_layer_is_told_apart(damped_scene_u7):
    """A gap that closes from outside the contact layer (one step crossed it) is not
    blamed on the stiffness."""
    from fsicas.timedomain.failures import closing
    scene = damped_scene_u7.replace(contact=True, contact_stiffness=1e8, contact_eps=1e-3)
    model = build_model(scene)
    x = steady_state(scene, model).x.copy()
    n, eps = model.n_modes, scene.contact_gap
    for gap, words in ((3 * eps, "crossed the whole layer"), (0.5 * eps, "did not stop the beam")):
        bent = x.copy()
        bent[n] += (scene.hstar / 2 - gap) / model.tip.phi[0, 1]
        assert gaps(model, bent[None]).min() == pytest.approx(gap, rel=1e-6)
        assert words in closing(model, bent, model.parameters(scene))
    # the same model run with a ten times thicker layer: 3 eps is inside that layer
    thick = model.parameters(scene.replace(contact_eps=1e-2))
    bent = x.copy()
    bent[n] += (scene.hstar / 2 - 3 * eps) / model.tip.phi[0, 1]
    assert "did not stop the beam" in closing(model, bent, thick)


def test_explicit_jacobian_through_the_mass_action_equals_ad_through_m(damped_scene_u7):
    """``M⁻¹(F_y − ∂(M v)/∂y|_{v=xdot})`` for y = x, pe, t (the SciPy routes' Jacobian and
    CVODES's custom Jacobian) equals CasADi's AD of solve(M, F), at a moving state with
    the contact load on and a time-dependent pressure drop."""
    import casadi as ca
    from fsicas.timedomain.rhs import explicit_ode, ode_symbols
    scene = damped_scene_u7.replace(modes=6, contact=True, contact_stiffness=1e6, contact_eps=1e-2)
    model = build_model(scene)
    steady = steady_state(scene, model)
    x, pe, t, p_t, F = ode_symbols(model)
    xdot, jac = explicit_ode(model, x, pe, t, p_t, F)
    plain = ca.solve(model.mass(x, p_t), F)
    rng = np.random.default_rng(1)
    x0 = steady.x.copy()
    x0[:12] += 1e-3 * rng.normal(size=12)
    phi_tip = model.tip.phi[:, 1]                      # tip 2e-4 from wall 1: inside eps = 5e-4
    x0[6] = (0.05 - 2e-4 - x0[7:12] @ phi_tip[1:]) / phi_tip[0]
    assert 0 < gaps(model, x0).min() < scene.contact_gap
    pv = np.concatenate([steady.p, PressureSchedule.breath(7.0, 2.0).vector(1.0), [0.3]])
    for y in (x, pe, t):
        ad = np.array(ca.Function("ad", [t, x, pe], [ca.jacobian(plain, y)])(0.1, x0, pv))
        custom = [np.array(ca.Function("c", [t, x, pe], [ca.jacobian(xdot, y)])(0.1, x0, pv))]
        if y is x:
            custom.append(np.array(jac(0.1, x0, pv)))
        assert np.all(np.isfinite(ad)) and np.max(np.abs(ad)) > 0
        for c in custom:
            assert np.max(np.abs(c - ad)) < 1e-12 * np.max(np.abs(ad))


def test_progress_bar_of_the_integrated_time_only_when_asked(capsys):
    """``progress=True`` draws a tqdm bar of the integrated time on stderr; the default
    prints nothing."""
    from fsicas import Scene, build_model, steady_state
    from fsicas.timedomain.integrators import simulate
    scene = Scene(mstar=1.0, ustar=4.0, zeta=0.01, modes=4)
    model = build_model(scene)
    st = steady_state(scene, model)
    simulate(model, st, 1.0)
    assert capsys.readouterr().err == ""
    simulate(model, st, 1.0, progress=True)
    assert "time integration" in capsys.readouterr().err
