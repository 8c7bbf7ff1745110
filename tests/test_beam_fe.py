"""Hermite-cubic FE modes of non-uniform clamped–free beams (fsicas.model.beam_fe).

Theory used for the bounds below:
* conforming Galerkin (Rayleigh–Ritz) eigenvalues are upper bounds and converge as
  O(h^{2(k+1-m)}) = O(h^4) for cubics (k = 3) and a 4th-order operator (m = 2);
* eigenfunction errors are of the order of the best approximation, i.e. of the cubic
  Hermite interpolation error, whose sharp constants (Birkhoff & Priver 1967) are
  ||e^(j)||_inf <= c_j h^(4-j) ||f''''||_inf with c_0 = 1/384, c_1 = sqrt(3)/216,
  c_2 = 1/12; for a beam mode ||phi''''|| = beta^4 ||phi||.
"""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize
import scipy.special
from numpy.polynomial import legendre

from fsicas.model import beam_fe
from fsicas.model.beam import clamped_free_betas, clamped_free_modes
from fsicas.model.beam_fe import nonuniform_beam_modes

X = np.linspace(0.0, 1.0, 2001)
ORIGIN = np.array([0.0])


def taper(ratio):
    """Linear profile 1 at the root, ``ratio`` at the tip."""
    return lambda x: 1.0 - (1.0 - ratio) * np.asarray(x)


def observed_order(h, err):
    """Least-squares slope of log(err) against log(h)."""
    return np.polyfit(np.log(h), np.log(err), 1)[0]


def ritz_frequencies(n, thickness, width, p=30, n_quad=80):
    """Independent Rayleigh–Ritz: global polynomials with w'' = P_k(2x - 1), w(0) = w'(0) = 0.

    Curvature basis => K well conditioned; spectral convergence for analytic profiles.
    Returns omega and callables for the mass-normalized phi(x) (analytic tip sign) and
    its 4th derivative (the 2nd derivative of the curvature series).
    """
    g, w = legendre.leggauss(n_quad)
    xq, wq = 0.5 * (g + 1.0), 0.5 * w
    basis = [legendre.Legendre.basis(k, domain=[0, 1]) for k in range(p)]
    shapes = [P.integ(2, lbnd=0) for P in basis]
    Wdd = np.array([P(xq) for P in basis])
    W = np.array([S(xq) for S in shapes])
    t, b = thickness(xq), width(xq)
    K = (Wdd * b * t**3 * wq) @ Wdd.T
    M = (W * b * t * wq) @ W.T
    mu, C = scipy.linalg.eigh(M, K, subset_by_index=[p - n, p - 1])
    mu, C = mu[::-1], C[:, ::-1]
    C /= np.sqrt(np.einsum("ik,ij,jk->k", C, M, C))
    C *= np.sign(np.array([S(1.0) for S in shapes]) @ C) * (-1.0) ** np.arange(n)

    def phi(x):
        return C.T @ np.array([S(x) for S in shapes])

    def phi4(x):
        return C.T @ np.array([P.deriv(2)(x) for P in basis])

    return 1.0 / np.sqrt(mu), phi, phi4


# ----------------------------------------------------------------------- (1) uniform beam
def test_uniform_frequencies_converge_at_fourth_order():
    exact = clamped_free_betas(3) ** 2
    n_el = np.array([10, 20, 40, 80])
    err = np.array([nonuniform_beam_modes(3, ORIGIN, n_elements=n).omega / exact - 1.0
                    for n in n_el])
    assert np.all(err > 0.0)                      # Rayleigh–Ritz upper bounds
    for k in range(3):
        assert 3.5 < observed_order(1.0 / n_el, err[:, k]) < 4.5


def test_uniform_frequencies_fine_mesh_1e8():
    exact = clamped_free_betas(5) ** 2
    rel = nonuniform_beam_modes(5, ORIGIN, n_elements=256).omega / exact - 1.0
    # O(h^4): mode 5 at h = 1/256 is ~6.5e-9; roundoff is ~eps * (omega_5/omega_1)^2.
    assert np.all(rel > -1e-13) and np.all(rel < 1e-8)


def test_uniform_default_mesh_resolves_highest_mode():
    n = 30
    basis = nonuniform_beam_modes(n, ORIGIN)       # 8 n elements: beta_n h ~ pi / 8
    rel = basis.omega / clamped_free_betas(n) ** 2 - 1.0
    assert basis.n_modes == n and np.all(np.abs(rel) < 1e-4)


@pytest.mark.parametrize("n_el", [40, 128])
def test_uniform_shapes_within_hermite_interpolation_bounds(n_el):
    n = 5
    h = 1.0 / n_el
    fe = nonuniform_beam_modes(n, X, n_elements=n_el)
    ex = clamped_free_modes(n, X)
    d4 = clamped_free_betas(n) ** 4 * np.abs(ex.phi).max(axis=1)       # ||phi''''||
    bounds = {"phi": h**4 / 384, "dphi": np.sqrt(3) * h**3 / 216, "ddphi": h**2 / 12,
              "Phi": h**4 / 384, "Psi": h**4 / 384}     # |∫ e| <= ||e||_inf on [0, 1]
    for name, c in bounds.items():
        err = np.abs(getattr(fe, name) - getattr(ex, name)).max(axis=1)
        assert np.all(err <= 2.0 * c * d4), name       # factor 2: quasi-optimality slack


def test_uniform_shape_convergence_orders():
    ex = clamped_free_modes(3, X)
    errs = {}
    for n_el in (32, 64, 128):
        fe = nonuniform_beam_modes(3, X, n_elements=n_el)
        for name in ("phi", "dphi", "ddphi", "Phi", "Psi"):
            errs.setdefault(name, []).append(
                np.abs(getattr(fe, name) - getattr(ex, name)).max())
    h = 1.0 / np.array([32, 64, 128])
    expected = {"phi": 4, "dphi": 3, "ddphi": 2, "Phi": 4, "Psi": 4}   # minimum orders
    for name, p in expected.items():
        assert observed_order(h, errs[name]) > p - 0.5, name


def test_tip_sign_and_endpoint_values():
    ex = clamped_free_modes(6, np.array([1.0]))
    for thickness in (None, taper(0.4)):
        fe = nonuniform_beam_modes(6, np.array([0.0, 1.0]), thickness=thickness)
        assert np.array_equal(np.sign(fe.phi[:, 1]), np.sign(ex.phi[:, 0]))
        assert np.all(fe.phi[:, 0] == 0) and np.all(fe.dphi[:, 0] == 0)
        assert np.all(fe.Phi[:, 0] == 0) and np.all(fe.Psi[:, 1] == 0)
        np.testing.assert_allclose(fe.Phi[:, 1], fe.Psi[:, 0], rtol=1e-13, atol=1e-15)


# ----------------------------------------------------------------------- (2) orthonormality
def test_mass_and_stiffness_orthogonality():
    """∫ m phi_i phi_j = delta_ij and ∫ EI phi_i'' phi_j'' = omega_i^2 delta_ij.

    Composite 8-point Gauss on halves of each element: exact for the piecewise
    polynomial integrands (m phi^2 has degree 9 here, EI phi''^2 degree 7).
    """
    n_el, n = 24, 6
    thickness, width = taper(0.5), (lambda x: 1.0 + 0.3 * x**2)
    g, w = legendre.leggauss(8)
    edges = np.linspace(0.0, 1.0, 2 * n_el + 1)
    xq = (edges[:-1, None] + 0.5 * (g + 1.0) * np.diff(edges)[:, None]).ravel()
    wq = np.tile(0.5 * w, 2 * n_el) * np.repeat(np.diff(edges), 8)
    fe = nonuniform_beam_modes(n, xq, thickness=thickness, width=width, n_elements=n_el)
    m, ei = width(xq) * thickness(xq), width(xq) * thickness(xq) ** 3
    gram_m = (fe.phi * m * wq) @ fe.phi.T
    gram_k = (fe.ddphi * ei * wq) @ fe.ddphi.T
    np.testing.assert_allclose(gram_m, np.eye(n), atol=1e-10)
    np.testing.assert_allclose(gram_k / np.outer(fe.omega, fe.omega), np.eye(n), atol=1e-10)
    np.testing.assert_array_equal(fe.width, width(xq))


def test_curvature_basis_is_the_hermite_stiffness():
    """The solver's K_c equals T^T K T of the nodal Hermite assembly."""
    n_el = 12
    xi, w, xq = beam_fe._gauss_points(n_el)
    ei = taper(0.5)(xq) ** 3
    K = beam_fe._assemble(beam_fe._hermite_stiffness(xi, w, ei, 1.0 / n_el))
    T = beam_fe._curvature_to_nodal(n_el)
    K_c = beam_fe._curvature_stiffness(xi, w, ei, 1.0 / n_el)
    assert np.abs(T.T @ K @ T - K_c).max() < 1e-10 * np.abs(K_c).max()


# ----------------------------------------------------------------------- (3) non-uniform
TAPER_T, TAPER_B = taper(0.5), taper(0.7)


def test_ritz_reference_is_converged():
    w30 = ritz_frequencies(5, TAPER_T, TAPER_B, p=30)[0]
    w40 = ritz_frequencies(5, TAPER_T, TAPER_B, p=40)[0]
    np.testing.assert_allclose(w30, w40, rtol=1e-12)


def test_tapered_beam_against_independent_rayleigh_ritz():
    """Linear taper in thickness (1 -> 0.5) and width (1 -> 0.7)."""
    ref, ref_phi, ref_phi4 = ritz_frequencies(4, TAPER_T, TAPER_B)
    n_el = np.array([25, 50, 100, 200])
    err = np.array([nonuniform_beam_modes(4, ORIGIN, TAPER_T, TAPER_B, n).omega / ref - 1.0
                    for n in n_el])
    assert np.all(err > 0.0)
    for k in range(3):
        assert 3.5 < observed_order(1.0 / n_el, err[:, k]) < 4.5
    assert np.all(err[-1, :3] < 1e-8)           # O(h^4), cf. uniform beam at h = 1/200
    fe = nonuniform_beam_modes(4, X, TAPER_T, TAPER_B, n_elements=200)
    d4 = np.abs(ref_phi4(X)).max(axis=1)         # ||phi''''|| of the reference mode
    assert np.all(np.abs(fe.phi - ref_phi(X)).max(axis=1) < 2.0 * d4 / (384 * 200**4))


def kirchhoff_frequencies(order, n):
    """Exact wedge (k = order = 1) / cone (k = 2) frequencies, omega = z^2 / 4 with
    J_k(z) I_k+1(z) + I_k(z) J_k+1(z) = 0 (clamped at s = 1, regular at the tip s = 0).

    With s = 1 - x, (s^(k+2) w'')'' = omega^2 s^k w factorizes as s^k (T - omega)(T + omega) w,
    T w = s^-k (s^(k+1) w')', with regular solutions s^(-k/2) {J_k, I_k}(2 sqrt(omega s)).
    """
    def f(z):
        return (scipy.special.jv(order, z) * scipy.special.iv(order + 1, z)
                + scipy.special.iv(order, z) * scipy.special.jv(order + 1, z))

    z = np.linspace(0.5, 30.0, 3000)
    sign_change = np.nonzero(np.diff(np.sign(f(z))))[0][:n]
    return np.array([scipy.optimize.brentq(f, z[i], z[i + 1]) ** 2 / 4 for i in sign_change])


def test_kirchhoff_wedge_and_cone():
    """Published first frequencies: wedge 5.315, cone 8.719 (Kirchhoff 1879; Blevins).

    A tip thickness eps instead of 0 perturbs m and EI by O(eps) everywhere, hence omega by
    O(eps); eps = 1e-6 and 200 elements (h^4 error < 1e-8) give agreement within 1e-5.
    """
    wedge, cone = kirchhoff_frequencies(1, 3), kirchhoff_frequencies(2, 3)
    assert round(wedge[0], 3) == 5.315 and round(cone[0], 3) == 8.719
    tip = taper(1e-6)
    fe_wedge = nonuniform_beam_modes(3, ORIGIN, thickness=tip, n_elements=200).omega
    fe_cone = nonuniform_beam_modes(3, ORIGIN, thickness=tip, width=tip, n_elements=200).omega
    np.testing.assert_allclose(fe_wedge, wedge, rtol=1e-5)
    np.testing.assert_allclose(fe_cone, cone, rtol=1e-5)


def test_taper_sensitivity_matches_perturbation_theory():
    """d(omega^2)/d(alpha) for t = 1 - alpha x at alpha = 0 (Hellmann–Feynman, analytic modes):

        d(omega_n^2)/d(alpha) = -3 ∫ x phi_n''^2 + omega_n^2 ∫ x phi_n^2.

    It is > 0 for mode 1 (a beam thinning towards the tip stiffens in mode 1) and < 0 for
    modes 2, 3.  The FE central difference (alpha = ±1e-3) has O(alpha^2) ~ 1e-6 error.
    """
    g, w = legendre.leggauss(200)
    xq, wq = 0.5 * (g + 1.0), 0.5 * w
    ex = clamped_free_modes(3, xq)
    slope = -3 * (ex.ddphi**2 * xq * wq).sum(1) + ex.omega**2 * (ex.phi**2 * xq * wq).sum(1)
    assert slope[0] > 0 and np.all(slope[1:] < 0)

    def omega2(alpha):
        return nonuniform_beam_modes(3, ORIGIN, thickness=taper(1 - alpha),
                                     n_elements=200).omega ** 2

    fd = (omega2(1e-3) - omega2(-1e-3)) / 2e-3
    np.testing.assert_allclose(fd, slope, rtol=1e-5)
    assert nonuniform_beam_modes(1, ORIGIN, thickness=taper(0.5)).omega[0] > \
        clamped_free_betas(1)[0] ** 2


def test_exact_scaling_laws():
    """Constant t = c: omega -> c omega, phi -> phi / sqrt(c); constant b = c: phi / sqrt(c)."""
    ref = nonuniform_beam_modes(4, X, n_elements=60)
    c = 0.7
    thin = nonuniform_beam_modes(4, X, thickness=lambda x: c + 0 * x, n_elements=60)
    wide = nonuniform_beam_modes(4, X, width=lambda x: np.full_like(x, 1 / c), n_elements=60)
    np.testing.assert_allclose(thin.omega, c * ref.omega, rtol=1e-12)
    np.testing.assert_allclose(wide.omega, ref.omega, rtol=1e-12)
    for name in ("phi", "dphi", "ddphi", "Phi", "Psi"):
        r = getattr(ref, name)
        np.testing.assert_allclose(getattr(thin, name), r / np.sqrt(c), atol=1e-10 * abs(r).max())
        np.testing.assert_allclose(getattr(wide, name), r * np.sqrt(c), atol=1e-10 * abs(r).max())


def test_courant_fischer_bounds():
    """t_min <= t <= t_max, b = 1: Rayleigh quotients bound omega_n^2 / omega_n,u^2 by
    [t_min^3 / t_max, t_max^3 / t_min] (same FE space, so exact for the discrete values)."""
    def wavy(x):
        return 1.0 + 0.3 * np.sin(3 * np.pi * x)

    ref = nonuniform_beam_modes(6, ORIGIN, n_elements=60).omega ** 2
    lam = nonuniform_beam_modes(6, ORIGIN, thickness=wavy, n_elements=60).omega ** 2
    ratio = lam / ref
    assert np.all(ratio >= 0.7**3 / 1.3) and np.all(ratio <= 1.3**3 / 0.7)


# ----------------------------------------------------------------------- (4) bad inputs
@pytest.mark.parametrize("kwargs, field", [
    (dict(n_modes=0), "n_modes"),
    (dict(n_modes=-2), "n_modes"),
    (dict(n_modes=2.5), "n_modes"),
    (dict(n_modes=True), "n_modes"),
    (dict(n_modes="3"), "n_modes"),
    (dict(n_elements=5), "n_elements"),
    (dict(n_elements=12.0), "n_elements"),
    (dict(x=np.array([-0.1, 0.5])), "x"),
    (dict(x=np.array([0.5, 1.0 + 1e-12])), "x"),
    (dict(x=np.array([0.5, np.nan])), "x"),
    (dict(x=np.zeros((2, 2))), "x"),
    (dict(thickness=lambda x: 1.0 - 2.0 * x), "thickness"),
    (dict(thickness=lambda x: 1.0 - x), "thickness"),
    (dict(thickness=lambda x: np.where(x > 0.5, np.nan, 1.0)), "thickness"),
    (dict(thickness=2.0), "thickness"),
    (dict(thickness=lambda x: np.ones(3)), "thickness"),
    (dict(width=lambda x: x), "width"),
    (dict(width=lambda x: 1.0 - 1.5 * np.exp(-(((x - 0.37) / 0.01) ** 2))), "width"),
    (dict(width="wide"), "width"),
])
def test_bad_inputs_raise_before_assembly(monkeypatch, kwargs, field):
    def no_assembly(*args, **kwargs):
        raise AssertionError("assembly reached with invalid input")

    monkeypatch.setattr(beam_fe, "_hermite_mass", no_assembly)
    monkeypatch.setattr(beam_fe, "_curvature_stiffness", no_assembly)
    args = dict(n_modes=6, x=X)
    args.update(kwargs)
    with pytest.raises(ValueError, match=rf"^{field}\b"):
        nonuniform_beam_modes(**args)


def test_running_integrals_match_quadrature_on_tapered_beam():
    """Phi(x_k) = ∫_0^x_k phi by element-aligned 6-point Gauss (exact for cubics) and
    Phi + Psi = ∫_0^1 phi at every point, including points inside elements."""
    n_el = 20
    g, w = legendre.leggauss(6)
    nodes = np.linspace(0.0, 1.0, n_el + 1)
    xq = (nodes[:-1, None] + 0.5 * (g + 1.0) / n_el).ravel()
    wq = np.tile(0.5 * w / n_el, n_el)
    x = np.concatenate([nodes, np.linspace(0.0, 1.0, 77)])
    fe = nonuniform_beam_modes(4, np.concatenate([x, xq]), TAPER_T, TAPER_B, n_el)
    k = nodes.size
    phi_q = fe.phi[:, x.size:]
    per_element = (phi_q * wq).reshape(4, n_el, 6).sum(axis=2)
    Phi_nodes = np.hstack([np.zeros((4, 1)), np.cumsum(per_element, axis=1)])
    np.testing.assert_allclose(fe.Phi[:, :k], Phi_nodes, atol=1e-13)
    np.testing.assert_allclose(fe.Phi[:, :x.size] + fe.Psi[:, :x.size],
                               np.repeat(Phi_nodes[:, -1:], x.size, 1), atol=1e-13)
