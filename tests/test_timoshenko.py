"""Timoshenko modes: thin limit, independent solutions, orthonormality, running integrals,
root counting on both branches, and the model on a thick beam."""
import numpy as np
import pytest
import scipy.linalg
from scipy.integrate import cumulative_simpson, solve_ivp
from scipy.optimize import brentq

from fsicas.model.beam import clamped_free_modes
from fsicas.model.beam_timoshenko import (TimoshenkoBeam, cowper_shear_coefficient,
                                          timoshenko_frequencies, timoshenko_modes,
                                          timoshenko_shapes)
from fsicas.model.quadrature import composite_gauss_legendre


# -- independent solutions of w'' - psi' = -omega^2 w / S, psi'' + S (w' - psi) = -omega^2 r^2 psi
def _shoot(beam, omega):
    """det of the free-end conditions (psi'(1), S gamma(1)) of the two solutions with
    w(0) = psi(0) = 0, by DOP853 on y = (w, psi, psi', v = S gamma)."""
    S, r2 = beam.shear, beam.rotary

    def rhs(x, y):
        w, psi, m, v = y
        return [psi + v / S, m, -omega**2 * r2 * psi - v, -omega**2 * w]

    ends = [solve_ivp(rhs, (0, 1), y0, method="DOP853", rtol=1e-13, atol=1e-15).y[:, -1]
            for y0 in ([0, 0, 1, 0], [0, 0, 0, 1])]
    return ends[0][2] * ends[1][3] - ends[1][2] * ends[0][3]


def _shooting_roots(beam, omegas):
    """Brent on the shooting determinant, bracketed around each given root (+-2 %)."""
    return np.array([brentq(lambda z: _shoot(beam, z), w * 0.98, w * 1.02, xtol=1e-14,
                            rtol=1e-14) for w in omegas])


def _chebyshev_eigenvalues(beam, n=160):
    """omega^2 of a Chebyshev collocation of the two-field equations (boundary rows
    replace the equations at the ends): sorted finite real positive eigenvalues."""
    k = np.arange(n + 1)
    t = np.cos(np.pi * k / n)
    c = np.r_[2.0, np.ones(n - 1), 2.0] * (-1.0) ** k
    T = np.tile(t, (n + 1, 1)).T
    D = np.outer(c, 1 / c) / (T - T.T + np.eye(n + 1))
    D -= np.diag(D.sum(axis=1))
    D *= -2.0                      # x = (1 - t) / 2 maps t in [-1, 1] to x in [0, 1]
    x, I, Z = (1 - t) / 2, np.eye(n + 1), np.zeros((n + 1, n + 1))
    S, r2 = beam.shear, beam.rotary
    K = np.block([[-S * D @ D, S * D], [-S * D, -D @ D + S * I]])
    M = np.block([[I, Z], [Z, r2 * I]])
    i0, i1 = np.argmin(x), np.argmax(x)
    rows = {i0: np.r_[I[i0], Z[i0]], n + 1 + i0: np.r_[Z[i0], I[i0]],
            i1: np.r_[D[i1], -I[i1]], n + 1 + i1: np.r_[Z[i1], D[i1]]}
    for row, values in rows.items():
        K[row], M[row] = values, 0.0
    lam = scipy.linalg.eigvals(K, M)
    lam = lam[np.isfinite(lam)]
    lam = lam[(np.abs(lam.imag) < 1e-6 * np.abs(lam)) & (lam.real > 0)].real
    return np.sort(lam)


# -- thin limit ------------------------------------------------------------------------
def test_thin_limit_equals_euler_bernoulli():
    """The Timoshenko correction is O((beta_n e/L)^2): at e/L = 1e-4 the first mode agrees
    to 1e-8 and every mode's difference shrinks 1e4 times at e/L = 1e-6, where all 10
    modes (frequencies and sign-aligned shapes) agree to 1e-8."""
    x, _ = composite_gauss_legendre(20, 10)
    eb = clamped_free_modes(10, x)
    gaps = {}
    for s in (1e-4, 1e-6):
        beam = TimoshenkoBeam(s, 0.3)
        t = timoshenko_modes(10, x, beam)
        gaps[s] = np.abs(t.omega / eb.omega - 1)
        if s == 1e-6:
            assert gaps[s].max() <= 1e-8
            for f in ("phi", "dphi", "Phi", "Psi"):
                ref = getattr(eb, f)
                assert np.abs(getattr(t, f) - ref).max() <= 1e-8 * np.abs(ref).max(), f
    assert gaps[1e-4][0] <= 1e-8
    assert np.allclose(gaps[1e-4] / gaps[1e-6], 1e4, rtol=1e-3)


# -- independent solutions -------------------------------------------------------------
@pytest.mark.parametrize("s, nu", [(0.1, 0.45), (0.3, 0.45), (0.3, 0.0)])
def test_frequencies_match_a_shooting_solution(s, nu):
    beam = TimoshenkoBeam(s, nu)
    omega = timoshenko_frequencies(8, beam)
    ref = _shooting_roots(beam, omega)
    assert np.allclose(omega, ref, rtol=1e-8, atol=0)


@pytest.mark.parametrize("s, nu", [(0.1, 0.45), (0.3, 0.45), (0.5, 0.0)])
def test_forty_roots_counted_on_both_branches(s, nu):
    """N = 40 reaches far above the cut-off sqrt(S)/r (second branch): the roots equal the
    Chebyshev eigenvalues one by one (1e-6; a count with no gap or duplicate)."""
    beam = TimoshenkoBeam(s, nu)
    omega = timoshenko_frequencies(40, beam)
    assert omega[-1] > 2 * beam.cutoff and np.all(np.diff(omega) > 1e-6 * omega[1:])
    lam = _chebyshev_eigenvalues(beam)
    ref = np.sqrt(lam[:41])
    assert np.allclose(omega, ref[:40], rtol=1e-6, atol=0)
    assert ref[40] > omega[-1] * (1 + 1e-6)


def test_cowper_and_validation():
    assert cowper_shear_coefficient(0.3) == pytest.approx(10 * 1.3 / (12 + 3.3))
    beam = TimoshenkoBeam(0.3, 0.45)
    assert beam.shear == pytest.approx(6 * beam.kappa * 0.55 / 0.09)
    assert beam.cutoff == pytest.approx(np.sqrt(beam.shear * 12) / 0.3)
    for bad, name in ((dict(slenderness=0.6), "slenderness"), (dict(slenderness=0.0), "slenderness"),
                      (dict(slenderness=0.2, poisson=0.5), "poisson"),
                      (dict(slenderness=0.2, shear_coefficient=1.5), "shear_coefficient")):
        with pytest.raises(ValueError, match=name):
            TimoshenkoBeam(**bad)


# -- shapes ----------------------------------------------------------------------------
@pytest.mark.parametrize("s, n", [(0.1, 20), (0.3, 40)])
def test_mass_orthonormal_and_stiffness_orthogonal(s, n):
    """∫ phi_m phi_n + r^2 psi_m psi_n = delta (1e-12) and ∫ psi_m' psi_n' + S gamma_m gamma_n
    = omega_n^2 delta, on a composite rule independent of the module's."""
    x, w = composite_gauss_legendre(60, 16)
    beam = TimoshenkoBeam(s, 0.45)
    m = timoshenko_shapes(n, x, beam)
    mass = (m.phi * w) @ m.phi.T + beam.rotary * (m.psi * w) @ m.psi.T
    assert np.abs(mass - np.eye(n)).max() <= 1e-12
    gamma = m.dphi - m.psi
    stiff = (m.dpsi * w) @ m.dpsi.T + beam.shear * (gamma * w) @ gamma.T
    assert np.abs(stiff - np.diag(m.omega**2)).max() <= 1e-11 * m.omega[-1] ** 2


def test_boundary_conditions_derivatives_and_signs():
    beam = TimoshenkoBeam(0.3, 0.45)
    ends = timoshenko_shapes(12, np.array([0.0, 1.0]), beam)
    assert np.abs(ends.phi[:, 0]).max() < 1e-13 and np.abs(ends.psi[:, 0]).max() < 1e-12
    assert np.abs(ends.dpsi[:, 1]).max() < 1e-11
    assert np.abs(ends.dphi[:, 1] - ends.psi[:, 1]).max() < 1e-12
    assert np.array_equal(np.sign(ends.phi[:, 1]), (-1.0) ** np.arange(12))
    x = np.linspace(0.05, 0.95, 19)
    h = 1e-5
    m, up, dn = (timoshenko_shapes(6, x + d, beam) for d in (0.0, h, -h))
    for f, df in (("phi", "dphi"), ("dphi", "ddphi"), ("psi", "dpsi")):
        fd = (getattr(up, f) - getattr(dn, f)) / (2 * h)
        assert np.abs(fd - getattr(m, df)).max() <= 1e-7 * np.abs(getattr(m, df)).max(), f


@pytest.mark.parametrize("s", [0.1, 0.3])
def test_running_integrals_and_uniform_load(s):
    """Phi, Psi against cumulative Simpson; the modal force of a uniform load,
    ∫ phi_n = Phi_n(1) = Psi_n(0), against Gauss quadrature of phi (1e-13)."""
    beam = TimoshenkoBeam(s, 0.45)
    x = np.linspace(0, 1, 4001)
    m = timoshenko_modes(10, x, beam)
    run = cumulative_simpson(m.phi, x=x, initial=0.0, axis=1)
    assert np.abs(m.Phi - run).max() < 1e-10
    assert np.abs(m.Psi - (run[:, -1:] - run)).max() < 1e-10
    nodes, w = composite_gauss_legendre(40, 16)
    load = timoshenko_modes(10, nodes, beam).phi @ w
    assert np.allclose(m.Phi[:, -1], load, rtol=0, atol=1e-13)
    assert np.allclose(m.Psi[:, 0], load, rtol=0, atol=1e-13)
