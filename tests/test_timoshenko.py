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


# -- the scene, the model and the CLI on Timoshenko modes -------------------------------
import json  # noqa: E402

from scipy.integrate import simpson  # noqa: E402

from fsicas import Scene, build_model, critical_velocity, flow_fields  # noqa: E402
from fsicas.cli import build_parser, main  # noqa: E402
from fsicas.model import modal_basis  # noqa: E402
from fsicas.profile import Profile  # noqa: E402
from fsicas.scene import load_scene  # noqa: E402

THICK = dict(beam="timoshenko", slenderness=0.3, poisson=0.45)
PALATE = dict(rho_s=1100.0, E=10e3, nu=0.45, L=0.03, rho_f=1.2, U0=1.0, H1=1.5e-3, b=0.02)


def test_euler_bernoulli_scenes_are_unchanged():
    """New fields at their defaults: the dict, equality and hash of today's scenes."""
    keys = ['mstar', 'ustar', 'hstar', 'friction', 'k0', 'kl', 'zeta', 'modes', 'quad_nodes',
            'channel1', 'channel2', 'thickness', 'contact', 'contact_stiffness', 'contact_eps',
            'contact_smoothing']
    assert list(Scene().to_dict()) == keys
    assert Scene(beam="euler-bernoulli") == Scene() and hash(Scene(beam="euler-bernoulli")) == hash(Scene())
    s = Scene(modes=4, **THICK)
    assert s.to_dict()["beam"] == "timoshenko" and Scene.from_dict(s.to_dict()) == s
    assert s != Scene(modes=4) and s != s.replace(poisson=0.3)


@pytest.mark.parametrize("kw, named", [
    (dict(beam="thick"), "beam"), (dict(slenderness=0.3), "slenderness"),
    (dict(poisson=0.4), "poisson"), (dict(shear_coefficient=0.8), "shear_coefficient"),
    (dict(beam="timoshenko"), "slenderness"), ({**THICK, "slenderness": 0.6}, "slenderness"),
    ({**THICK, "slenderness": 0.0}, "slenderness"), ({**THICK, "slenderness": "a"}, "slenderness"),
    ({**THICK, "poisson": 0.5}, "poisson"), ({**THICK, "poisson": -0.1}, "poisson"),
    ({**THICK, "shear_coefficient": 0.0}, "shear_coefficient"),
    ({**THICK, "shear_coefficient": 1.2}, "shear_coefficient"),
])
def test_bad_beam_fields_are_refused_with_the_field(kw, named):
    with pytest.raises(ValueError, match=named):
        Scene(**kw)


def test_toml_and_modal_basis_dispatch(tmp_path):
    path = tmp_path / "thick.toml"
    path.write_text('modes = 5\nbeam = "timoshenko"\nslenderness = 0.3\npoisson = 0.45\n')
    scene = load_scene(path)
    assert scene == Scene(modes=5, **THICK)
    x = np.linspace(0, 1, 7)
    ref = timoshenko_modes(5, x, TimoshenkoBeam(0.3, 0.45))
    assert np.array_equal(modal_basis(scene, x).phi, ref.phi)
    model = build_model(scene)
    assert np.array_equal(model.basis.omega, ref.omega)
    with pytest.raises(ValueError, match="beam, slenderness, poisson"):
        model.require_structure(Scene(modes=5))


def test_from_physical_chooses_timoshenko_for_thick_beams():
    thick = Scene.from_physical(e=9e-3, **PALATE)
    assert thick.beam == "timoshenko" and thick.slenderness == pytest.approx(0.3)
    assert thick.poisson == 0.45 and thick.shear_coefficient is None
    thin = Scene.from_physical(e=2.5e-3, **PALATE)
    assert thin.beam == "euler-bernoulli" and "beam" not in thin.to_dict()
    assert Scene.from_physical(e=2.5e-3, beam="timoshenko", **PALATE).slenderness == pytest.approx(2.5 / 30)
    with pytest.raises(ValueError, match="Euler–Bernoulli .* needs e/L < 0.1"):
        Scene.from_physical(e=9e-3, beam="euler-bernoulli", **PALATE)
    with pytest.raises(ValueError, match="1D beam theory"):
        Scene.from_physical(e=18e-3, **PALATE)
    with pytest.raises(ValueError, match="slenderness is derived"):
        Scene.from_physical(e=9e-3, slenderness=0.2, **PALATE)


def test_beam_rows_are_the_projection_of_the_load_on_phi():
    """Timoshenko modes in the unchanged model: dr/dt + w^2 q = ∫ (p2 - p1) phi_n (the
    load from the independent field route), so the flow load projects on phi alone."""
    scene = Scene(mstar=2.0, ustar=4.0, modes=5, channel1=Profile.linear(0.05, 0.035),
                  channel2=Profile.constant(0.05), **THICK)
    _check_beam_rows_against_the_field_route(scene, seed=1)


def test_critical_velocity_is_lower_on_a_thick_beam():
    """N = 6, M* = 1: the onset of a Timoshenko beam at e/L = 0.3 is below Euler–Bernoulli's."""
    onsets = {}
    for name, kw in (("eb", {}), ("t", THICK)):
        scene = Scene(mstar=1.0, modes=6, **kw)
        onsets[name] = critical_velocity(scene, build_model(scene))
    assert np.isfinite(onsets["t"].ustar) and 0 < onsets["t"].ustar < 0.8 * onsets["eb"].ustar


def _cli(capsys, argv):
    code = main(argv)
    return code, json.loads(capsys.readouterr().out)


def test_cli_modes_and_beam_options_on_every_analysis(capsys):
    code, out = _cli(capsys, ["modes", "--modes", "6", "--beam", "timoshenko",
                              "--slenderness", "0.3", "--poisson", "0.45", "--json"])
    ref = timoshenko_frequencies(6, TimoshenkoBeam(0.3, 0.45))
    assert code == 0 and np.allclose(out["omega"], ref, rtol=1e-14)
    assert np.allclose(np.square(out["beta"]), ref, rtol=1e-14)
    code, out = _cli(capsys, ["modes", "--modes", "3", "--beam", "timoshenko", "--json"])
    assert code == 2 and "slenderness" in out["error"]
    parser = build_parser()
    commands = parser._subparsers._group_actions[0].choices
    for name, command in commands.items():
        if any("--hstar" in a.option_strings for a in command._actions):   # the scene options
            options = {o for a in command._actions for o in a.option_strings}
            assert {"--beam", "--slenderness", "--poisson", "--shear-coefficient"} <= options, name
    code, out = _cli(capsys, ["eig", "--modes", "4", "--ustar", "2", "--beam", "timoshenko",
                              "--slenderness", "0.3", "--poisson", "0.45", "--json"])
    assert code == 0 and out["stable"] is True


# -- non-uniform thickness: locking-free FE ----------------------------------------------
from fsicas.model.beam_fe import nonuniform_beam_modes  # noqa: E402
from fsicas.model.beam_timoshenko_fe import timoshenko_fe_modes  # noqa: E402


@pytest.mark.parametrize("s, tol", [(0.3, 1e-9), (0.1, 1e-7), (0.01, 1e-6)])
def test_uniform_fe_modes_match_the_exact_modes(s, tol):
    """24 elements, N = 10; at e/L = 0.01 a locking element would be far off."""
    x, _ = composite_gauss_legendre(48, 8)
    beam = TimoshenkoBeam(s, 0.45)
    exact, fe = timoshenko_modes(10, x, beam), timoshenko_fe_modes(10, x, beam)
    assert np.allclose(fe.omega, exact.omega, rtol=tol, atol=0)
    for f in ("phi", "Phi", "Psi"):
        assert np.abs(getattr(fe, f) - getattr(exact, f)).max() < 2e-5, f


def test_tapered_fe_modes_integrals_and_thin_limit():
    taper = Profile.linear(1.0, 0.6)
    x = np.linspace(0, 1, 9601)
    fe = timoshenko_fe_modes(6, x, TimoshenkoBeam(0.02, 0.3), thickness=taper)
    run = cumulative_simpson(fe.phi, x=x, initial=0.0, axis=1)
    assert np.abs(fe.Phi - run).max() < 1e-9 and np.abs(fe.Psi - (run[:, -1:] - run)).max() < 1e-9
    eb = nonuniform_beam_modes(6, x, thickness=taper)
    gap = fe.omega / eb.omega - 1
    assert np.all(gap < 0) and np.all(np.diff(gap) < 0) and -1e-3 < gap[0]   # O((beta_n e/L)^2)
    thick = timoshenko_fe_modes(6, x, TimoshenkoBeam(0.3, 0.45), thickness=taper)
    assert np.all(thick.omega < fe.omega)


def test_model_on_a_tapered_thick_beam():
    """Beam rows against the field route; at N = 6 the tapered thick beam flutters before
    the tapered Euler–Bernoulli beam (U*_c 3.99 against 4.56)."""
    taper = Profile.linear(1.0, 0.6)
    scene = Scene(mstar=2.0, ustar=4.0, modes=5, channel1=Profile.linear(0.05, 0.035),
                  channel2=Profile.constant(0.05), thickness=taper, **THICK)
    _check_beam_rows_against_the_field_route(scene, seed=2)
    thick = Scene(mstar=1.0, modes=6, thickness=taper, **THICK)
    thin = Scene(mstar=1.0, modes=6, thickness=taper)
    u_t = critical_velocity(thick, build_model(thick)).ustar
    assert 0 < u_t < 0.95 * critical_velocity(thin, build_model(thin)).ustar


def _fe_frequency_errors(s, elements, n_modes=6):
    """|omega_FE / omega - 1| of the uniform beam (rows: element counts, columns: modes)
    and the rounding floor eps lambda_max / lambda_n of each (lambda_max ~ 2e3 S n_el^2,
    the largest FE eigenvalue, measured: 2.6e8 at e/L = 0.1 and 24 elements)."""
    beam = TimoshenkoBeam(s, 0.45)
    exact = timoshenko_frequencies(n_modes, beam)
    ends = np.array([0.0, 1.0])
    err = np.array([np.abs(timoshenko_fe_modes(n_modes, ends, beam, n_elements=n).omega
                           / exact - 1) for n in elements])
    floor = np.finfo(float).eps * 2e3 * beam.shear * np.asarray(elements)[:, None] ** 2 / exact**2
    return err, floor


@pytest.mark.parametrize("s", [0.1, 0.3])
def test_fe_convergence_order_is_that_of_the_quartic_rotation(s):
    """psi quartic (p = 4) bounds the energy-norm error by h^4, so the eigenvalue (and the
    frequency) error goes as h^(2p) = h^8. On the steps from 6 to 12 and 12 to 24 elements,
    where the finer error stays 10 times above the rounding floor, every one of the first
    6 modes shows an order log2(e_h / e_h/2) >= 7 (observed 7.2-8.0)."""
    elements = (3, 6, 12, 24)
    err, floor = _fe_frequency_errors(s, elements)
    order = np.log2(err[:-1] / err[1:])
    counted = (np.asarray(elements[:-1]) >= 6)[:, None] & (err[1:] >= 10 * floor[1:])
    assert counted.sum() >= 6
    assert np.all(order[counted] >= 7.0) and 7.5 <= np.median(order[counted]) <= 8.5
    assert err[0].max() > 1e-4 and err[-1].max() < 1e-8


@pytest.mark.parametrize("s", [0.1, 0.3])
def test_fe_frequencies_to_1e8_with_32_elements(s):
    """N = 10 with 32 elements: all ten FE frequencies within 1e-8 of the exact ones
    (2.9e-9 at e/L = 0.1, 1.4e-10 at 0.3; 24 elements give 2.8e-8 at 0.1)."""
    beam = TimoshenkoBeam(s, 0.45)
    fe = timoshenko_fe_modes(10, np.array([0.0, 1.0]), beam, n_elements=32)
    assert np.allclose(fe.omega, timoshenko_frequencies(10, beam), rtol=1e-8, atol=0)


def test_map_command_takes_the_beam_options(tmp_path, capsys):
    """``fsicas map --beam timoshenko --slenderness 0.3``: the results file's header holds
    the beam; a bad slenderness is refused before any work, naming the option."""
    import json
    from fsicas.cli import main
    out = tmp_path / "m.jsonl"
    code = main(["map", "--ustar", "2:2:1", "--mstar", "1:1:1", "--modes", "4", "--t-end", "1",
                 "--beam", "timoshenko", "--slenderness", "0.3", "--workers", "1",
                 "--out", str(out), "--json"])
    assert code == 0 and sum(json.loads(capsys.readouterr().out)["counts"].values()) == 1
    assert json.loads(out.read_text().splitlines()[0])["header"]["scene"]["slenderness"] == 0.3
    code = main(["map", "--ustar", "2:2:1", "--mstar", "1:1:1", "--beam", "timoshenko",
                 "--slenderness", "0.9", "--out", str(tmp_path / "n.jsonl"), "--json"])
    assert code == 2 and "slenderness" in json.loads(capsys.readouterr().out)["error"]


def _check_beam_rows_against_the_field_route(scene, seed):
    """dr/dt + w^2 q of the model at a random state equals ∫ (p2 - p1) phi_n of the load
    from the independent field route (N = 5, Δp = 30)."""
    model = build_model(scene)
    rng = np.random.default_rng(seed)
    x0 = np.r_[0.1 * rng.normal(size=5) / np.arange(1, 6) ** 2,
               1e-3 * rng.normal(size=5) / np.arange(1, 6) ** 2, 0.2, 0.15]
    p = model.parameters(pressure_drop=30.0)
    xdot = model.xdot(x0, p)
    grid = np.linspace(0.0, 1.0, 16001)
    load = flow_fields(scene, x0, xdot, 30.0, grid).load
    modes = modal_basis(scene, grid)
    lhs = xdot[:5] + modes.omega**2 * x0[5:10]
    rhs = simpson(modes.phi * load, x=grid)
    assert np.allclose(lhs, rhs, rtol=1e-9, atol=1e-9 * np.max(np.abs(rhs)))
