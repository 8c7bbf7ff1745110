"""The nonlinear model against closed forms, the PDEs it came from, FD and symmetry."""
import dataclasses

import casadi as ca
import numpy as np
import pytest
import scipy.integrate
from scipy.integrate import simpson

from fsicas import (Profile, Scene, build_model, clamped_free_modes, flow_fields, steady_state,
                    straight_pressure_drop)
from fsicas.model import contact, modal_basis

TAPERED = dict(channel1=Profile.linear(0.05, 0.035),
               channel2=Profile.table([0.0, 0.5, 1.0], [0.05, 0.06, 0.045]))
SCENE = Scene(mstar=2.0, ustar=4.0, modes=4, friction=0.14, k0=0.3, kl=0.8, zeta=0.02, **TAPERED)


def random_state(scene, seed, velocity_scale=0.2):
    """A non-equilibrium state; small modal velocities keep the flow one-directional."""
    rng = np.random.default_rng(seed)
    n = scene.modes
    decay = 1.0 / np.arange(1, n + 1) ** 2
    r = velocity_scale * rng.normal(size=n) * decay
    q = 1e-3 * rng.normal(size=n) * decay
    Q = np.array([0.2, 0.15]) * (1 + 0.1 * rng.normal(size=2))
    return np.concatenate([r, q, Q])


@pytest.fixture(scope="module")
def model():
    return build_model(SCENE)


# -- closed forms ---------------------------------------------------------------------
@pytest.mark.parametrize("mstar, ustar, f, k0, kl", [
    (1.0, 5.0, 0.14, 0.0, 1.0), (0.05, 12.0, 0.3, 0.5, 0.7), (30.0, 0.7, 0.0, 0.0, 1.0),
    (2.0, -3.0, 0.14, 0.2, 1.0)])
def test_straight_symmetric_steady_state_is_closed_form(mstar, ustar, f, k0, kl):
    """Δp = M* U*|U*| ((K0 + KL)/2 + 2 f / H*), Q1 = Q2 = U* H*/2, no deflection."""
    scene = Scene(mstar=mstar, ustar=ustar, friction=f, k0=k0, kl=kl, modes=6)
    st = steady_state(scene)
    expected = mstar * ustar * abs(ustar) * ((k0 + kl) / 2 + 2 * f / 0.1)
    assert st.pressure_drop == pytest.approx(expected, rel=1e-14, abs=1e-14)
    assert straight_pressure_drop(scene) == pytest.approx(expected, rel=1e-15)
    assert np.allclose(st.Q, ustar * 0.05, rtol=1e-14)
    assert np.max(np.abs(st.q)) < 1e-14


# -- the PDEs and boundary conditions ---------------------------------------------------
def _fields_along_trajectory(model, x0, p, dp, grid, dt):
    """Fields at t - dt, t, t + dt from a tight independent integration of M xdot = F."""
    rhs = lambda t, z: model.xdot(z, p)
    out = []
    for t_end in (-dt, 0.0, dt):
        z = x0 if t_end == 0.0 else scipy.integrate.solve_ivp(
            rhs, (0.0, t_end), x0, method="DOP853", rtol=1e-13, atol=1e-15).y[:, -1]
        out.append(flow_fields(model.scene, z, model.xdot(z, p), dp, grid))
    return out


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_formal_solution_satisfies_continuity_momentum_and_bcs(model, seed):
    """FD in x and t of h, u, p reconstructed independently satisfy Eqs. (4) and (6)."""
    scene, dp, dt = model.scene, 30.0, 2e-5
    x0 = random_state(scene, seed)
    p = model.parameters(pressure_drop=dp)
    grid = np.linspace(0.0, 1.0, 8001)
    before, now, after = _fields_along_trajectory(model, x0, p, dp, grid, dt)
    grad = lambda a: np.gradient(a, grid, edge_order=2)
    for c in range(2):
        h, u, pc = now.h[c], now.u[c], now.p[c]
        h_t = (after.h[c] - before.h[c]) / (2 * dt)
        flux_t = (after.h[c] * after.u[c] - before.h[c] * before.u[c]) / (2 * dt)
        continuity = h_t + grad(h * u)
        momentum = scene.mstar * (flux_t + grad(h * u**2) + scene.friction * u * abs(u)) + h * grad(pc)
        scale = np.max(np.abs(h * grad(pc)))
        assert np.max(np.abs(continuity)) < 1e-5 * max(np.max(np.abs(h_t)), 1e-3)
        assert np.max(np.abs(momentum)) < 1e-5 * scale
        u0, u1 = u[0], u[-1]
        assert pc[0] == pytest.approx(dp - scene.mstar / 2 * (u0**2 + scene.k0 * u0 * abs(u0)), rel=1e-13)
        assert pc[-1] == pytest.approx(-scene.mstar / 2 * (u1**2 - scene.kl * u1 * abs(u1)),
                                       rel=1e-11, abs=1e-11 * scale)


@pytest.mark.parametrize("seed", [0, 4])
def test_beam_rows_are_the_modal_projection_of_the_pressure_load(model, seed):
    """dr/dt + 2 zeta w r + w^2 q = ∫ (p2 - p1) phi_n dx, the load from the fields route."""
    scene, dp = model.scene, 30.0
    x0 = random_state(scene, seed)
    p = model.parameters(pressure_drop=dp)
    xdot = model.xdot(x0, p)
    grid = np.linspace(0.0, 1.0, 16001)
    load = flow_fields(scene, x0, xdot, dp, grid).load
    modes = clamped_free_modes(scene.modes, grid)
    n = scene.modes
    lhs = xdot[:n] + 2 * 0.02 * modes.omega * x0[:n] + modes.omega**2 * x0[n:2 * n]
    rhs = simpson(modes.phi * load, x=grid)
    assert np.allclose(lhs, rhs, rtol=1e-9, atol=1e-9 * np.max(np.abs(rhs)))


def _projection_error(scene, seed, grid):
    model = build_model(scene)
    x0 = random_state(scene, seed)
    p = model.parameters(pressure_drop=30.0)
    xdot = model.xdot(x0, p)
    modes = clamped_free_modes(scene.modes, grid)
    n = scene.modes
    lhs = xdot[:n] + 2 * 0.02 * modes.omega * x0[:n] + modes.omega**2 * x0[n:2 * n]
    load = flow_fields(scene, x0, xdot, 30.0, grid).load
    return np.max(np.abs(lhs - simpson(modes.phi * load, x=grid)))


def test_reversing_flow_converges_algebraically_in_quadrature_nodes():
    """Seed 3 reverses the flow in channel 2: u|u| is only C^1 there, so Gauss–Legendre
    converges algebraically (theory: about n^-3 for a jump in the second derivative)."""
    grid = np.linspace(0.0, 1.0, 64001)
    coarse, fine = (_projection_error(SCENE.replace(quad_nodes=k), 3, grid) for k in (28, 224))
    observed_order = np.log(coarse / fine) / np.log(224 / 28)
    assert observed_order > 2.0
    assert fine < 1e-7 * 20.0


# -- derivatives ---------------------------------------------------------------------------
@pytest.mark.parametrize("seed", [0, 1])
def test_exact_jacobians_match_central_differences(model, seed):
    x0 = random_state(model.scene, seed)
    p0 = model.parameters(pressure_drop=30.0)
    F = lambda x, p: np.array(model.rhs(x, p)).ravel()
    J = np.array(model.jac_rhs(x0, p0))
    Jp = np.array(model.jac_rhs_p(x0, p0))
    for exact, vary, base in ((J, lambda z: F(z, p0), x0), (Jp, lambda z: F(x0, z), p0)):
        fd = np.empty_like(exact)
        for k in range(len(base)):
            step = 1e-6 * max(1.0, abs(base[k]))
            e = np.zeros_like(base)
            e[k] = step
            fd[:, k] = (vary(base + e) - vary(base - e)) / (2 * step)
        assert np.max(np.abs(fd - exact)) < 1e-6 * np.max(np.abs(exact))


@pytest.mark.parametrize("scene", [SCENE, SCENE.replace(contact=True, modes=6),
                                   Scene(mstar=0.3, ustar=6.0, modes=5, thickness=Profile.linear(1.0, 0.6))])
def test_matrix_free_mass_action_equals_the_assembled_mass_matrix(scene):
    """``mass_action(x, p, v)`` (the implicit residual's ``M v``) equals ``M(x, p) @ v``."""
    model = build_model(scene)
    p = model.parameters(pressure_drop=10.0)
    rng = np.random.default_rng(3)
    for seed in range(3):
        x, v = random_state(scene, seed), rng.normal(size=model.n_state)
        dense = np.array(model.mass(x, p)) @ v
        assert np.max(np.abs(np.array(model.mass_action(x, p, v)).ravel() - dense)) < 1e-12 * np.max(np.abs(dense))


LIFTED_SCENES = [SCENE, SCENE.replace(contact=True, modes=6),
                 SCENE.replace(contact=True, contact_smoothing=0.2, modes=5),
                 Scene(mstar=0.3, ustar=6.0, modes=5, thickness=Profile.linear(1.0, 0.6))]


def _pressed_into_contact(model, x):
    """``x`` with its displacements scaled so that the smallest gap at a node is eps/2."""
    n, s = model.n_modes, model.scene
    y = model.basis.phi.T @ x[n:2 * n]
    H = [wall(model.basis.x) for wall in s.walls]
    room = np.where(y > 0, H[0], H[1]) - s.contact_gap / 2     # distance to the wall ahead
    scale = np.min(room / np.abs(y))
    x = x.copy()
    x[n:2 * n] *= scale
    assert contact.gaps(model, x, model.basis.x).min() < s.contact_gap
    return x


def _ad_jacobian(fun, *args):
    """``d fun / d x`` by CasADi AD of the whole expression (the reference route)."""
    sym = [ca.MX.sym(f"a{i}", *np.shape(np.atleast_1d(a))) for i, a in enumerate(args)]
    out = fun.call(sym, True, False)[0]
    return np.array(ca.Function("ad", sym, [ca.jacobian(out, sym[0])])(*args))


@pytest.mark.parametrize("scene", LIFTED_SCENES)
def test_lifted_jacobians_equal_ad_of_the_whole_equations(scene):
    """``jac_rhs`` and ``jac_mass_action`` (chain rule through the nodal values) equal AD of
    ``F`` (the SX model: AD through the impact rule's formulas) and of ``M v`` to rounding,
    also with contact (in and out of it) and FE modes."""
    model = build_model(scene)
    reference = build_model(scene, symbolic="SX")   # the impact rule's formulas, not its
    p = model.parameters(pressure_drop=10.0)        # own Jacobian (MX), differentiated
    rng = np.random.default_rng(5)
    for seed in range(3):
        x, v = random_state(scene, seed), rng.normal(size=model.n_state)
        if scene.contact:                                   # into contact: min gap eps / 2
            x = _pressed_into_contact(model, x)
        J, J_ad = np.array(model.jac_rhs(x, p)), _ad_jacobian(reference.rhs, x, p)
        assert np.max(np.abs(J - J_ad)) < 1e-12 * np.max(np.abs(J_ad))
        Mvx = np.array(model.jac_mass_action(x, p, v))
        Mvx_ad = _ad_jacobian(model.mass, x, p)             # dM/dx (vec) -> contract with v
        Mvx_ref = np.einsum("ijk,j->ik", Mvx_ad.reshape(model.n_state, model.n_state, -1,
                                                        order="F"), v)
        assert np.max(np.abs(Mvx - Mvx_ref)) < 1e-12 * np.max(np.abs(Mvx_ref))


# -- symmetry and the sign of the static deflection ---------------------------------------
def mirror(x, n):
    """Flip y (r, q -> -r, -q) and swap the channels (Q1 <-> Q2)."""
    return np.concatenate([-x[:2 * n], x[2 * n:][::-1]])


def test_mirror_symmetry_of_the_dynamics():
    scene_a = Scene(mstar=1.5, modes=5, channel1=Profile.linear(0.06, 0.05),
                    channel2=Profile.constant(0.04))
    scene_b = scene_a.replace(channel1=scene_a.channel2, channel2=scene_a.channel1)
    ma, mb = build_model(scene_a), build_model(scene_b)
    p = ma.parameters(pressure_drop=40.0)
    for seed in range(3):
        x = random_state(scene_a, seed)
        assert np.allclose(mb.xdot(mirror(x, 5), p), mirror(ma.xdot(x, p), 5), rtol=1e-12, atol=1e-10)
    sa, sb = steady_state(scene_a, ma), steady_state(scene_b, mb)
    assert np.allclose(sb.x, mirror(sa.x, 5), rtol=1e-10, atol=1e-14)
    assert sb.pressure_drop == pytest.approx(sa.pressure_drop, rel=1e-12)


def test_model_mirror_is_the_symmetry_of_a_symmetric_channel():
    """``Model.mirror`` is the mirror above as a matrix (an orthogonal involution); a
    symmetric channel's dynamics (with contact) commute with it, an asymmetric one's do
    not."""
    scene = Scene(mstar=1.5, modes=5, contact=True, contact_eps=1e-2)
    model = build_model(scene)
    R = model.mirror
    p = model.parameters(pressure_drop=40.0)
    assert np.array_equal(R @ R, np.eye(12)) and np.array_equal(R, R.T)
    for seed in range(3):
        x = random_state(scene, seed)
        assert np.array_equal(R @ x, mirror(x, 5))
        assert np.allclose(model.xdot(R @ x, p), R @ model.xdot(x, p), rtol=1e-12, atol=1e-10)
    off = build_model(scene.replace(channel1=Profile.constant(0.06),
                                    channel2=Profile.constant(0.04)))
    x = random_state(scene, 0)
    assert not np.allclose(off.xdot(R @ x, p), R @ off.xdot(x, p), rtol=1e-6, atol=1e-6)


def test_beam_deflects_towards_the_wider_channel():
    """Equal Δp drives faster flow, hence lower pressure, in the wider channel 1 (y > 0)."""
    scene = Scene(mstar=1.0, ustar=4.0, modes=8, channel1=Profile.constant(0.055),
                  channel2=Profile.constant(0.045))
    model = build_model(scene)
    st = steady_state(scene, model)
    assert st.Q[0] > st.Q[1]
    y = model.deflection(st.x, np.linspace(0.05, 1.0, 20))
    assert np.all(y > 0)
    assert (st.Q[0] + st.Q[1]) / scene.hstar == pytest.approx(4.0, rel=1e-14)


def test_contact_pushes_the_beam_away_from_the_wall():
    scene = Scene(modes=3, contact=True, contact_stiffness=1e4, contact_eps=0.2)
    model = build_model(scene)
    n, gap = 3, scene.contact_gap
    x = np.zeros(2 * n + 2)
    x[2 * n:] = 0.25
    x[n] = (0.05 - gap / 2) / 2.0     # mode 1 tip at y = 0.05 - gap/2: inside the layer
    p = model.parameters(pressure_drop=0.0)
    on = np.array(model.rhs(x, p)).ravel()
    off = np.array(model.rhs(x, model.parameters(pressure_drop=0.0, contact_stiffness=1e-12))).ravel()
    grid = np.linspace(0.0, 1.0, 20001)
    modes = clamped_free_modes(n, grid)
    violation = np.maximum(0.0, gap - (0.05 - modes.phi[0] * x[n]))
    expected = -1e4 * modes.omega[0] ** 2 * simpson(modes.phi * violation, x=grid)
    assert expected[0] < 0
    assert np.allclose(on[:n] - off[:n], expected, rtol=2e-2)


def test_only_what_the_scene_needs_is_built():
    plain = build_model(Scene(modes=3))
    assert "contact_stiffness" not in plain.parameter_names
    ops = {plain.rhs.expand().instruction_id(k) for k in range(plain.rhs.expand().n_instructions())}
    assert ca.OP_FMAX not in ops
    with_contact = build_model(Scene(modes=3, contact=True))
    assert with_contact.parameter_names[5:7] == ("contact_stiffness", "contact_eps")
    depends = np.array(ca.DM(with_contact.rhs.jac_sparsity(0, 1), 1))     # pattern of dF/dp
    assert depends[:, with_contact.parameter_names.index("contact_stiffness")].any()


def test_steady_state_refuses_a_model_of_another_structure():
    with pytest.raises(ValueError, match="structure"):
        steady_state(Scene(modes=4), build_model(Scene(modes=5)))


# -- non-uniform beam (FE modes) -------------------------------------------------------------
def test_tapered_beam_rows_are_the_projection_of_the_load():
    """With FE modes of a tapered beam the Psi-trick projection still equals ∫(p2 - p1) phi_n."""
    scene = SCENE.replace(thickness=Profile.linear(1.0, 0.6))
    model = build_model(scene)
    x0 = random_state(scene, 0)
    p = model.parameters(pressure_drop=30.0)
    xdot = model.xdot(x0, p)
    grid = np.linspace(0.0, 1.0, 16001)
    modes = modal_basis(scene, grid)
    n = scene.modes
    lhs = xdot[:n] + 2 * 0.02 * modes.omega * x0[:n] + modes.omega**2 * x0[n:2 * n]
    rhs = simpson(modes.phi * flow_fields(scene, x0, xdot, 30.0, grid).load, x=grid)
    assert np.allclose(lhs, rhs, rtol=1e-8, atol=1e-8 * np.max(np.abs(rhs)))


def test_uniform_thickness_through_fe_reproduces_the_analytic_model():
    """Two routes to the same beam: FE modes with thickness = 1 vs the analytic modes.
    The default mesh (48 elements for N = 6) has frequency errors up to ~1e-7 (O(h^4),
    docs/beam_fe.md), which bounds the agreement."""
    uniform = Scene(mstar=1.0, ustar=4.0, modes=6, channel1=Profile.constant(0.055),
                    channel2=Profile.constant(0.045))
    fe = uniform.replace(thickness=Profile.constant(1.0))
    a, b = steady_state(uniform), steady_state(fe)
    assert b.pressure_drop == pytest.approx(a.pressure_drop, rel=1e-8)
    assert np.allclose(b.q, a.q, rtol=1e-6, atol=1e-6 * np.max(np.abs(a.q)))


def test_thinner_tip_raises_the_static_tip_deflection():
    """A beam thinned towards the tip is more flexible: larger static deflection under the
    same asymmetric flow (EI falls as e^3 while the load is unchanged)."""
    uniform = Scene(mstar=1.0, ustar=4.0, modes=8, channel1=Profile.constant(0.055),
                    channel2=Profile.constant(0.045))
    tapered = uniform.replace(thickness=Profile.linear(1.0, 0.7))
    tip = [build_model(s).deflection(steady_state(s).x, [1.0])[0] for s in (uniform, tapered)]
    assert tip[1] > tip[0] > 0


def test_model_of_another_structure_is_refused_before_work():
    """A prebuilt model must match the scene in every field but U* and the parameters:
    a contact scene on a contact-free model, or other modes or gap, is a ValueError that
    says what to do; a contact-free scene may use a model with contact (guarded runs)."""
    from fsicas.timedomain.run import guarded_model, run_case
    scene = Scene(mstar=1.0, ustar=7.0, zeta=0.01, modes=4)
    plain = build_model(scene)
    contact = scene.replace(contact=True, contact_stiffness=1e8, contact_eps=1e-2)
    with pytest.raises(ValueError, match="contact = true but the model was built without"):
        run_case(contact, 1.0, model=plain)
    for other, field in ((scene.replace(modes=5), "modes"), (scene.replace(hstar=0.2), "hstar"),
                         (scene.replace(quad_nodes=60), "quad_nodes")):
        with pytest.raises(ValueError, match=f"fields {field} differ"):
            steady_state(other, plain)
    guarded = guarded_model(scene)[0]
    assert guarded.scene.contact
    plain.require_structure(scene.replace(ustar=3.0, mstar=9.0, zeta=0.05, friction=0.0))
    guarded.require_structure(scene)


def test_quadrature_error_estimate_tracks_the_true_error_near_the_wall():
    """The estimate (F on n against 2n nodes) equals the error against a rule of 4n
    nodes to 5 % once it is above round-off, grows as the beam nears the wall (tip gap
    3 %, 1 %, 0.3 % of H*/2: 1e-6 to 1e-1 at N = 6 on 32 nodes), and is at round-off far
    from it."""
    from fsicas.model.accuracy import quadrature_error, relative_error
    scene = Scene(mstar=1.0, ustar=6.0, modes=6)
    model = build_model(scene)
    reference = build_model(scene.replace(quad_nodes=4 * scene.n_quad))
    st = steady_state(scene, model)
    n, tip = model.n_modes, model.tip.phi[0, 1]
    errors = []
    for gap_left in (0.5, 0.03, 0.01, 0.003):  # tip gap as a fraction of H*/2
        x = st.x.copy()
        x[n] += (1 - gap_left) * scene.hstar / 2 / tip       # first mode pushes the tip
        estimate = quadrature_error(model, x, st.p)
        true = relative_error(np.array(reference.rhs(x, st.p)), np.array(model.rhs(x, st.p)))
        if gap_left < 0.5:
            assert estimate == pytest.approx(true, rel=0.05)
        errors.append(estimate)
    assert errors[0] < 1e-12 and 1e-7 < errors[1] < errors[2] < errors[3]


def test_quadrature_error_of_many_states_is_that_of_their_plain_evaluations():
    """Over several states (rows) the estimate is ``max_k |F_2n(x_k) - F_n(x_k)| /
    max_k |F_2n(x_k)|`` of the plain per-state calls of the two models (the mapped,
    buffered call must lay out states and components alike), for any row order."""
    from fsicas.model.accuracy import finer_model, quadrature_error
    scene = Scene(mstar=1.0, ustar=6.0, modes=4)
    model = build_model(scene)
    st = steady_state(scene, model)
    n, tip = model.n_modes, model.tip.phi[0, 1]
    x = np.tile(st.x, (5, 1))
    x[:, n] += np.array([0.1, 0.97, 0.5, 0.99, 0.3]) * scene.hstar / 2 / tip
    fine, coarse = finer_model(model), model
    F = lambda m: np.array([np.array(m.rhs(xk, st.p)).ravel() for xk in x])   # noqa: E731
    expected = np.max(np.abs(F(fine) - F(coarse))) / np.max(np.abs(F(fine)))
    assert expected > 1e-8                                  # the near-wall rows dominate
    assert quadrature_error(model, x, st.p) == pytest.approx(expected, rel=1e-12)
    assert quadrature_error(model, x[::-1], st.p) == pytest.approx(expected, rel=1e-12)


def test_one_model_serves_every_value_of_the_parameter_fields():
    """A model built for one scene, given the parameter vector of a scene that differs in
    every parameter field (fsicas.scene.PARAMETER_FIELDS), gives the right-hand side of
    that scene's own model; scene_at recovers the scene's parameters from the vector."""
    from fsicas.scene import PARAMETER_FIELDS, STRUCTURE_FIELDS
    first = Scene(modes=3, contact=True, contact_stiffness=1e4, contact_eps=0.2)
    other = first.replace(ustar=6.0, mstar=2.0, friction=0.2, k0=0.3, kl=0.5,
                          zeta=(0.01, 0.02, 0.03), contact_stiffness=3e4, contact_eps=0.3)
    names = {f.name for f in dataclasses.fields(Scene)} - {"scales"}
    assert set(PARAMETER_FIELDS) | set(STRUCTURE_FIELDS) == names
    assert all(getattr(first, f) != getattr(other, f) for f in PARAMETER_FIELDS)
    shared, own = build_model(first), build_model(other)
    x = np.r_[0.1, -0.2, 0.05, 0.01, -0.02, 0.03, 0.4, 0.35]   # tip deflection near eps
    x[3:6] *= (first.hstar / 2 - 0.5 * other.contact_gap) / shared.tip_deflection(x)
    p = shared.parameters(other, pressure_drop=3.0)
    assert np.array_equal(np.asarray(shared.rhs(x, p)), np.asarray(own.rhs(x, p)))
    assert shared.scene_at(p) == other.replace(ustar=first.ustar)
