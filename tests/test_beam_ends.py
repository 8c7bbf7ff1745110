"""Beam ends other than the cantilever: closed-form Euler–Bernoulli modes (frequencies,
boundary conditions, orthonormality, running integrals, the beam equation), and the FE
and Timoshenko routes converging to them."""
import numpy as np
import pytest
import scipy.optimize

from fsicas import Scene
from fsicas.model.assembly import build_model, modal_basis
from fsicas.model.beam import uniform_betas, uniform_modes
from fsicas.model.beam_fe import nonuniform_beam_modes
from fsicas.model.beam_timoshenko import TimoshenkoBeam
from fsicas.model.beam_timoshenko_fe import timoshenko_fe_modes
from fsicas.model.quadrature import gauss_legendre
from fsicas.profile import Profile
from fsicas.scene import BEAM_ENDS, load_scene

HELD = ("clamped-clamped", "pinned-pinned", "clamped-pinned")
#: beta L of the issue (Blevins' tables), to the digits given.
PUBLISHED = {"clamped-clamped": [4.730041, 7.853205, 10.995608],
             "pinned-pinned": list(np.pi * np.arange(1, 4)),
             "clamped-pinned": [3.926602, 7.068583]}
#: Textbook characteristic functions and the n-th root's bracket centre / pi.
TEXTBOOK = {"clamped-clamped": (lambda b: np.cos(b) * np.cosh(b) - 1.0, 0.5),
            "clamped-pinned": (lambda b: np.tan(b) - np.tanh(b), 0.25),
            "pinned-pinned": (lambda b: np.sin(b), 0.0)}


@pytest.mark.parametrize("ends", HELD)
def test_published_roots(ends):
    beta = uniform_betas(len(PUBLISHED[ends]), ends)
    assert np.allclose(beta, PUBLISHED[ends], rtol=0, atol=5e-7)


@pytest.mark.parametrize("ends", HELD)
def test_roots_match_brent_on_the_textbook_equation(ends):
    f, offset = TEXTBOOK[ends]
    for n, b in enumerate(uniform_betas(12, ends), start=1):
        centre = (n + offset) * np.pi
        ref = scipy.optimize.brentq(f, centre - 0.3, centre + 0.3, xtol=1e-15, rtol=1e-15)
        assert abs(b - ref) <= 1e-12 * ref


@pytest.mark.parametrize("ends", HELD)
def test_orthonormal_to_1e_12_up_to_mode_100(ends):
    x, w = gauss_legendre(600)
    m = uniform_modes(100, x, ends)
    gram = (m.phi * w) @ m.phi.T
    assert np.abs(gram - np.eye(100)).max() < 1e-12


@pytest.mark.parametrize("ends", HELD)
@pytest.mark.parametrize("n_modes", [5, 400])
def test_boundary_conditions(ends, n_modes):
    """phi(0) = 0, phi'(0) = 0 (clamped) or phi''(0) = 0 (pinned); at x = 1 phi = 0 and
    phi' = 0 (clamped) or phi'' = 0 (pinned); derivatives relative to beta^k. At mode
    400 (beta ~ 1260) no cancellation of cosh and sinh: still round-off."""
    m = uniform_modes(n_modes, np.array([0.0, 1.0]), ends)
    b = np.sqrt(m.omega)[:, None]
    root, end = ends.split("-")
    held = lambda name, field: field if name == "clamped" else m.ddphi / b**2
    for at, name in ((0, root), (1, end)):
        assert np.abs(m.phi[:, at]).max() < 1e-11
        assert np.abs(held(name, m.dphi / b)[:, at]).max() < 1e-11
    first = m.dphi[:, 0] if root == "pinned" else m.ddphi[:, 0]
    assert np.all(first > 0)


@pytest.mark.parametrize("ends", HELD)
def test_running_integrals_against_quadrature(ends):
    """Phi = ∫_0^x phi and Psi = ∫_x^1 phi against Gauss rules on [0, x] and [x, 1]."""
    xs = np.array([0.0, 0.13, 0.5, 0.77, 1.0])
    m = uniform_modes(8, xs, ends)
    g, w = gauss_legendre(80)
    for k, x in enumerate(xs):
        head = uniform_modes(8, x * g, ends).phi @ (x * w)
        tail = uniform_modes(8, x + (1 - x) * g, ends).phi @ ((1 - x) * w)
        assert np.abs(m.Phi[:, k] - head).max() < 1e-13
        assert np.abs(m.Psi[:, k] - tail).max() < 1e-13


@pytest.mark.parametrize("ends", HELD)
def test_derivatives_and_beam_equation_by_finite_differences(ends):
    """Central differences (h = 1e-4): phi' of phi, phi'' of phi', and phi'''' as the
    second difference of phi'' equals beta^4 phi."""
    x, h = np.linspace(0.05, 0.95, 19), 1e-4
    at = lambda z: uniform_modes(4, z, ends)
    m, plus, minus = at(x), at(x + h), at(x - h)
    b = np.sqrt(m.omega)[:, None]
    assert np.abs((plus.phi - minus.phi) / (2 * h) - m.dphi).max() / b.max() < 1e-6
    assert np.abs((plus.dphi - minus.dphi) / (2 * h) - m.ddphi).max() / b.max()**2 < 1e-6
    d4 = (plus.ddphi - 2 * m.ddphi + minus.ddphi) / h**2
    assert np.abs(d4 - b**4 * m.phi).max() / b.max()**4 < 1e-5


@pytest.mark.parametrize("ends", HELD)
def test_textbook_shape_at_low_modes(ends):
    """The overflow-free form against the textbook one where the latter is accurate."""
    x = np.linspace(0, 1, 21)
    m = uniform_modes(3, x, ends)
    for n, b in enumerate(np.sqrt(m.omega)):
        z = b * x
        if ends == "pinned-pinned":
            ref = np.sqrt(2) * np.sin(z)
        else:
            s = (np.cosh(b) - np.cos(b)) / (np.sinh(b) - np.sin(b))
            ref = np.cosh(z) - np.cos(z) - s * (np.sinh(z) - np.sin(z))
        assert np.abs(m.phi[n] - ref).max() < 1e-9


@pytest.mark.parametrize("ends", HELD)
def test_fe_modes_converge_at_fourth_order(ends):
    """Hermite FE frequencies and shapes go to the closed form as h^4 (ratio 16 per
    halving of h), with the same signs."""
    x = np.linspace(0, 1, 11)
    ex = uniform_modes(4, x, ends)
    err = []
    for n_el in (40, 80):
        fe = nonuniform_beam_modes(4, x, n_elements=n_el, ends=ends)
        err.append((np.abs(fe.omega / ex.omega - 1).max(), np.abs(fe.phi - ex.phi).max(),
                    np.abs(fe.Psi - ex.Psi).max()))
    (w1, p1, i1), (w2, p2, i2) = err
    assert w2 < 5e-6 and p2 < 1e-5 and i2 < 1e-8
    assert 12 < w1 / w2 < 20 and 12 < p1 / p2 < 20


@pytest.mark.parametrize("ends", HELD)
def test_fe_modes_of_a_tapered_beam_are_mass_orthonormal(ends):
    """A linear taper t = 1 - x/2: ∫ t phi_i phi_j = delta_ij on a Gauss rule aligned
    with the elements, and the held ends hold."""
    taper = lambda z: 1.0 - 0.5 * z
    n_el = 40
    g, w = gauss_legendre(6)
    x = (np.arange(n_el)[:, None] + g[None, :]).ravel() / n_el
    m = nonuniform_beam_modes(5, x, thickness=taper, n_elements=n_el, ends=ends)
    gram = (m.phi * (np.tile(w, n_el) / n_el * taper(x))) @ m.phi.T
    assert np.abs(gram - np.eye(5)).max() < 1e-11
    assert np.abs(nonuniform_beam_modes(5, np.array([0.0, 1.0]), thickness=taper,
                                        n_elements=n_el, ends=ends).phi).max() < 1e-12


def test_timoshenko_pinned_pinned_matches_its_closed_form():
    """sin(n pi x) is exact for the pinned–pinned Timoshenko beam:
    (S k^2 - w^2)(k^2 + S - r^2 w^2) = S^2 k^2, k = n pi (lower root)."""
    beam = TimoshenkoBeam(0.05)
    S, r2, k = beam.shear, beam.rotary, np.arange(1, 6) * np.pi
    B, C = k**2 + S + r2 * S * k**2, S * k**4
    exact = np.sqrt(2 * C / (B + np.sqrt(B**2 - 4 * r2 * C)))
    fe = timoshenko_fe_modes(5, np.zeros(1), beam, ends="pinned-pinned").omega
    assert np.allclose(fe, exact, rtol=1e-8, atol=0)


@pytest.mark.parametrize("ends", HELD)
def test_timoshenko_goes_to_euler_bernoulli_as_slenderness_squared(ends):
    """The shear correction omega/omega_EB - 1 ~ -c s^2: it quarters when s halves."""
    exact = uniform_betas(3, ends) ** 2
    d = [timoshenko_fe_modes(3, np.zeros(1), TimoshenkoBeam(s), ends=ends).omega / exact - 1
         for s in (0.02, 0.01)]
    assert np.all(d[0] < 0) and np.all(np.abs(d[0] / d[1] - 4) < 0.1)
    x = np.linspace(0, 1, 11)
    thin = timoshenko_fe_modes(3, x, TimoshenkoBeam(0.002), ends=ends)
    assert np.abs(thin.phi - uniform_modes(3, x, ends).phi).max() < 1e-4


def test_scene_ends_validated_and_read_from_files(tmp_path):
    with pytest.raises(ValueError, match="ends must be one of clamped-free, clamped-clamped"):
        Scene(ends="free-free")
    assert "ends" not in Scene().to_dict()
    scene = Scene(ends="pinned-pinned")
    assert Scene.from_dict(scene.to_dict()) == scene
    path = tmp_path / "plate.toml"
    path.write_text('mstar = 2.0\nends = "clamped-clamped"\n')
    assert load_scene(path).ends == "clamped-clamped"


@pytest.mark.parametrize("ends", BEAM_ENDS)
def test_modal_basis_routes_every_ends(ends):
    """Uniform: the closed form; tapered: FE; Timoshenko: FE unless clamped-free."""
    x = np.array([0.0, 0.5, 1.0])
    scene = Scene(modes=3, ends=ends)
    assert np.array_equal(modal_basis(scene, x).phi, uniform_modes(3, x, ends).phi)
    fe = modal_basis(scene.replace(thickness=Profile.linear(1.0, 0.8)), x)
    assert np.abs(fe.phi[:, 0]).max() == 0.0 and fe.omega[0] > 0
    timo = modal_basis(scene.replace(beam="timoshenko", slenderness=0.01), x)
    assert np.all(np.abs(timo.omega / uniform_betas(3, ends) ** 2 - 1) < 1e-2)
    model = build_model(scene)
    assert model.basis.n_modes == 3


@pytest.mark.parametrize("ends", HELD)
def test_timoshenko_fe_running_integrals_against_quadrature(ends):
    """Phi and Psi of the Timoshenko FE modes against Gauss rules on the elements (the
    shape is a piecewise quintic: 6 nodes per element integrate it exactly)."""
    beam, n_el = TimoshenkoBeam(0.05), 24
    g, w = gauss_legendre(6)
    nodes = (np.arange(n_el)[:, None] + g[None, :]).ravel() / n_el
    phi = timoshenko_fe_modes(4, nodes, beam, ends=ends).phi
    cells = (phi * np.tile(w, n_el) / n_el).reshape(4, n_el, 6).sum(axis=2)
    edges = np.arange(n_el + 1) / n_el
    m = timoshenko_fe_modes(4, edges, beam, ends=ends)
    head = np.hstack([np.zeros((4, 1)), np.cumsum(cells, axis=1)])
    assert np.abs(m.Phi - head).max() < 1e-13
    assert np.abs(m.Psi - (head[:, -1:] - head)).max() < 1e-13
    assert np.abs(m.phi[:, [0, -1]]).max() < 1e-12            # both ends held
