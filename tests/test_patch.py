"""The contact patch: load, deepest penetration and the equations' impact term against
an independent fine trapezoid rule on the modal sum (1e6 points, 1e-6 of L)."""
import numpy as np
import pytest

from fsicas import Scene, build_model
from fsicas.model import contact
from fsicas.model.patch import penetration
from fsicas.profile import Profile

SCENE = Scene(mstar=1.0, ustar=7.0, zeta=0.01, modes=10, contact=True, contact_stiffness=1e8,
              contact_eps=1e-2)
FINE = np.linspace(0.0, 1.0, 1_000_001)


def fine_density(model, X, xs=FINE):
    """``Σ_c s_c k max(0, eps - h_c)`` on ``xs`` (rows: states), straight from the modes."""
    s, n = model.scene, model.n_modes
    y = np.atleast_2d(X)[:, n:2 * n] @ model.basis_at(xs).phi
    k = contact.stiffness(s.contact_stiffness, model.omega_1)
    return sum(sign * k * np.maximum(0.0, s.contact_gap - (wall(xs) + sign * y))
               for wall, sign in zip(s.walls, contact.WALL_SIGNS))


def trapezoid(f, xs=FINE):
    return np.trapezoid(f, xs, axis=-1)


def bent(model, tip_depths, shape):
    """States bent in ``shape`` (modal amplitudes) so that the tip penetrates wall 1 by
    each of ``tip_depths``."""
    n, s = model.n_modes, model.scene
    y_tip = model.tip.phi[:, 1] @ shape
    X = np.zeros((len(tip_depths), 2 * n + 2))
    for row, d in zip(X, tip_depths):
        row[n:2 * n] = shape * (s.hstar / 2 - s.contact_gap + d) / y_tip
    return X


@pytest.fixture(scope="module")
def model():
    return build_model(SCENE)


def test_load_depth_and_position_of_tip_patches(model):
    """Tip patches from 0.02 eps to eps deep (1e-5 to 1e-2 of L long), bent in the first
    three modes: load to 1e-6, depth to 1e-12 of eps, position at the tip."""
    eps = SCENE.contact_gap
    X = bent(model, eps * np.array([0.02, 0.1, 0.5, 1.0]), np.array([1.0, 0.1, -0.03] + [0] * 7))
    patch = penetration(model, X, model.parameters())
    reference = trapezoid(np.abs(fine_density(model, X)))
    assert patch.load == pytest.approx(reference, rel=1e-6)
    assert patch.depth == pytest.approx(eps * np.array([0.02, 0.1, 0.5, 1.0]), abs=1e-12 * eps)
    assert patch.position == pytest.approx(1.0, abs=1e-9)


def test_interior_patch_between_the_grid_points(model):
    """A channel narrowing to its middle, the beam bent in mode 2: the gap is narrowest
    between the points of a 101-point grid, where that grid sees no contact at all."""
    middle = Profile.table([0.0, 0.3, 0.5, 0.7, 1.0], [0.05, 0.05, 0.0301, 0.05, 0.05])
    scene = SCENE.replace(channel1=middle)
    m = build_model(scene)
    n = m.n_modes
    xs = np.linspace(0.0, 1.0, 101)
    X = np.zeros((3, 2 * n + 2))
    X[:, n + 1] = [0.0206816148, 0.0206818240, 0.0206821727]   # mode 2 lifts the middle
    # (amplitudes for depths of about 2e-7, 5e-7 and 1e-6 at x = 0.4913)
    density = fine_density(m, X)
    assert np.all(fine_density(m, X, xs) == 0)         # the 101-point grid misses it
    patch = penetration(m, X, m.parameters())
    reference = trapezoid(np.abs(density))
    assert np.all(reference > 0)
    assert patch.load == pytest.approx(reference, rel=1e-5)
    h = scene.walls[0](FINE) - X[:, n:2 * n] @ m.basis_at(FINE).phi
    assert patch.depth == pytest.approx(scene.contact_gap - h.min(axis=1), abs=1e-6 * scene.contact_gap)
    assert patch.position == pytest.approx(FINE[h.argmin(axis=1)], abs=2e-6)


def test_no_contact_gives_no_load(model):
    X = bent(model, [-0.5 * SCENE.contact_gap, -1e-3 * SCENE.contact_gap], np.eye(10)[0])
    patch = penetration(model, X, model.parameters())
    assert np.all(patch.load == 0) and np.all(patch.depth < 0)


def test_equations_impact_term_against_a_fine_rule(model):
    """The impact term of F (F at k* minus F at k* = 0) is ``∫ f phi_n`` to 1e-3 of its
    largest entry for tip patches 0.05 to 1 eps deep (on the default nodes the flow's
    40-point rule put all of it on one node: errors of 100 %)."""
    eps = SCENE.contact_gap
    X = bent(model, eps * np.array([0.05, 0.3, 1.0]), np.array([1.0, 0.1, -0.03] + [0] * 7))
    p = model.parameters(pressure_drop=1.0)
    free = p.copy()
    free[model.index("contact_stiffness")] = 0.0
    n = model.n_modes
    phi = model.basis_at(FINE).phi
    for x in X:
        x[-2:] = 0.3                                    # some flow; it cancels in the difference
        term = np.array(model.rhs(x, p)).ravel()[:n] - np.array(model.rhs(x, free)).ravel()[:n]
        reference = trapezoid(fine_density(model, x)[0] * phi)
        assert np.max(np.abs(term - reference)) < 1e-3 * np.max(np.abs(reference))


@pytest.mark.slow
def test_run_measures_against_a_fine_rule():
    """M* = 1, U* = 7, k* = 1e8, eps/H = 1e-2 (N = 10, the default rule): the outcome's
    peak force, contact positions and impacts per cycle, measured on its last 4 cycles
    with a 100 001-point trapezoid rule (1000x the former grid's), and its first contact
    time located on that grid: within 1 %, equal, equal, to 1e-9."""
    from scipy.interpolate import BarycentricInterpolator
    from scipy.optimize import brentq

    from fsicas.timedomain.run import run_case
    run = run_case(SCENE, 4.0, quadrature_tol=None)
    o, tr, m = run.outcome, run.trajectory, run.model
    assert o.outcome == "impacting_lco"
    xs = np.linspace(0.0, 1.0, 100_001)
    window = (tr.t >= o.t_settled - 4 * o.period - 1e-9) & (tr.t <= o.t_settled)
    density = np.abs(fine_density(m, tr.x[window], xs))
    load = trapezoid(density, xs)
    assert o.max_impact_force == pytest.approx(load.max() / contact.reference_force(m), rel=1e-2)
    on = load > 0
    starts, ends = np.flatnonzero(on & ~np.r_[False, on[:-1]]), np.flatnonzero(on & ~np.r_[on[1:], False])
    assert o.impacts_per_cycle == starts.size / 4
    deepest = {round(float(xs[np.argmax(density[a:b + 1].max(axis=0))]), 3) for a, b in zip(starts, ends)}
    assert o.contact_positions == sorted(deepest)
    n, eps = m.n_modes, SCENE.contact_gap
    phi = m.basis_at(xs).phi
    min_gap = lambda x: np.min(SCENE.hstar / 2 - np.abs(np.atleast_2d(x)[:, n:2 * n] @ phi))
    k = int(np.argmax([min_gap(x) <= eps for x in tr.x]))
    state = BarycentricInterpolator(tr.t[k - 3:k + 1], tr.x[k - 3:k + 1])
    t_c = brentq(lambda s: min_gap(state(s)) - eps, tr.t[k - 1], tr.t[k], xtol=1e-13)
    assert o.first_contact_time == pytest.approx(t_c, abs=1e-9)
