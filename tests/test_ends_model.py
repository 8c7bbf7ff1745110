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
