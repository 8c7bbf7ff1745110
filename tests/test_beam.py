"""Clamped–free modes: frequencies, boundary conditions, orthonormality, running integrals."""
import numpy as np
import pytest
import scipy.optimize
from scipy.integrate import cumulative_simpson

from fsicas.model.beam import clamped_free_betas, clamped_free_modes
from fsicas.model.quadrature import gauss_legendre

# Published roots of cos(b) cosh(b) = -1 (e.g. Blevins, Formulas for natural frequency).
PUBLISHED = [1.875104068711961, 4.694091132974175, 7.854757438237613, 10.99554073487547,
             14.13716839104647]


def test_first_roots_match_published_values():
    assert np.allclose(clamped_free_betas(5), PUBLISHED, rtol=1e-12, atol=0)


def test_roots_match_an_independent_bracketing_solve_up_to_20():
    """Brent on the textbook form cos b cosh b + 1 = 0, bracketed around (n - 1/2) pi."""
    betas = clamped_free_betas(20)
    for n, b in enumerate(betas, start=1):
        centre = (n - 0.5) * np.pi
        ref = scipy.optimize.brentq(lambda z: np.cos(z) * np.cosh(z) + 1.0,
                                    centre - 0.4, centre + 0.4, xtol=1e-15, rtol=1e-15)
        assert abs(b - ref) <= 1e-9 * ref


def test_roots_follow_the_asymptotic_formula_beyond_20():
    """b_n = (n - 1/2) pi + (-1)^(n+1) 2 e^-b_n (1 + O(e^-b)); exact to round-off for n > 20."""
    betas = clamped_free_betas(100)
    n = np.arange(1, 101)
    asym = (n - 0.5) * np.pi + (-1.0) ** (n + 1) * 2 * np.exp(-(n - 0.5) * np.pi)
    assert np.allclose(betas[5:], asym[5:], rtol=1e-13, atol=0)
    assert np.allclose(betas[20:], (n[20:] - 0.5) * np.pi, rtol=1e-15, atol=0)


def test_orthonormal_on_the_quadrature_for_100_modes():
    x, w = gauss_legendre(220)
    m = clamped_free_modes(100, x)
    gram = (m.phi * w) @ m.phi.T
    assert np.max(np.abs(gram - np.eye(100))) < 1e-10
    # stiffness orthogonality: ∫ phi_i'' phi_j'' = w_i^2 delta_ij
    stiff = (m.ddphi * w) @ m.ddphi.T / np.outer(m.omega, m.omega)
    assert np.max(np.abs(stiff - np.eye(100))) < 1e-10


def test_boundary_conditions_hold_for_100_modes():
    m = clamped_free_modes(100, np.array([0.0, 1.0]))
    beta = np.sqrt(m.omega)
    assert np.max(np.abs(m.phi[:, 0])) < 1e-13
    assert np.max(np.abs(m.dphi[:, 0] / beta)) < 1e-13
    assert np.max(np.abs(m.ddphi[:, 1] / beta**2)) < 1e-13
    assert np.max(np.abs(m.Psi[:, 1])) < 1e-13          # phi'''(1) = 0
    assert np.allclose(np.abs(m.phi[:, 1]), 2.0, rtol=1e-12)  # |phi_n(1)| = 2 for unit mean square


def test_derivatives_and_running_integrals_match_independent_routes():
    x = np.linspace(0.0, 1.0, 40001)
    m = clamped_free_modes(30, x)
    dx = x[1] - x[0]
    inner = slice(1, -1)
    fd = (m.phi[:, 2:] - m.phi[:, :-2]) / (2 * dx)
    assert np.max(np.abs(fd - m.dphi[:, inner]) / np.sqrt(m.omega)[:, None]) < 1e-4
    fd2 = (m.dphi[:, 2:] - m.dphi[:, :-2]) / (2 * dx)
    assert np.max(np.abs(fd2 - m.ddphi[:, inner]) / m.omega[:, None]) < 1e-4
    Phi = cumulative_simpson(m.phi, x=x, initial=0.0, axis=1)
    assert np.max(np.abs(Phi - m.Phi)) < 1e-9
    assert np.allclose(m.Phi + m.Psi, m.Phi[:, -1:], atol=1e-13)


def test_bad_input_is_rejected():
    with pytest.raises(ValueError, match="n_modes"):
        clamped_free_betas(0)
    with pytest.raises(ValueError, match="x must"):
        clamped_free_modes(3, np.array([0.5, 1.5]))
