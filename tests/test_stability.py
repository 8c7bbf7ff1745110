"""Linear stability: eigenvalues, Hopf onset, boundary, criticality, against independent routes."""
import warnings

import casadi as ca
import numpy as np
import pytest
import scipy.linalg
import scipy.optimize

import continuation as C
from fsicas import Profile, Scene, SteadyStateError, build_model, clamped_free_modes, steady_state
from fsicas.linear.boundary import stability_boundary
from fsicas.linear.adapter import flutter_field
from fsicas.linear.hopf import critical_velocity, hopf_points
from fsicas.model.quadrature import gauss_legendre
from fsicas.linear.stability import eigenvalues, linear_stability


def added_mass_frequencies(scene):
    """Independent route: at U* = 0 the beam obeys M_eff q'' + W^2 q = 0 with
    M_eff = I + M* Σ_c [∫ Phi Phi^T / H_c - b_c b_c^T / ∫ 1/H_c], b_c = ∫ Phi / H_c
    (docs/model.md: the Q rows eliminated), so omega^2 = eig(W^2, M_eff)."""
    x, w = gauss_legendre(200)
    modes = clamped_free_modes(scene.modes, x)
    Phi = modes.Phi
    m_eff = np.eye(scene.modes)
    for wall in scene.walls:
        weight = w / wall(x)
        b = Phi @ weight
        m_eff += scene.mstar * ((Phi * weight) @ Phi.T - np.outer(b, b) / weight.sum())
    return np.sqrt(scipy.linalg.eigh(np.diag(modes.omega**2), m_eff, eigvals_only=True))


@pytest.mark.parametrize("mstar", [0.1, 1.0, 10.0])
def test_eigenvalues_at_rest_are_the_added_mass_frequencies(mstar):
    scene = Scene(mstar=mstar, ustar=0.0, modes=8)
    lam = eigenvalues(build_model(scene), steady_state(scene))
    oscillating = np.sort(lam.imag[lam.imag > 1e-6])
    assert np.max(np.abs(lam.real)) < 1e-9 * np.max(np.abs(lam))   # conservative at rest
    assert np.allclose(oscillating, added_mass_frequencies(scene), rtol=1e-10)
    assert np.all(oscillating < clamped_free_modes(8, np.array([1.0])).omega)  # fluid lowers them


def test_vanishing_mass_ratio_gives_the_in_vacuo_frequencies():
    scene = Scene(mstar=1e-10, ustar=0.0, modes=6)
    lam = eigenvalues(build_model(scene), steady_state(scene))
    oscillating = np.sort(lam.imag[lam.imag > 1e-6])
    assert np.allclose(oscillating, clamped_free_modes(6, np.array([1.0])).omega, rtol=1e-9)


def test_mode_shape_is_normalized_and_satisfies_the_eigenproblem():
    scene = Scene(mstar=1.0, ustar=6.0, modes=8)
    model = build_model(scene)
    result = linear_stability(scene, model)
    assert not result.stable and result.growth_rate[0] > 0
    shape = result.mode_shape(model, 0)
    assert np.max(np.abs(shape["y"])) == pytest.approx(1.0, abs=1e-14)
    assert abs(shape["y"][0]) < 1e-14                       # clamped root
    J = np.array(model.jac_rhs(result.steady.x, result.steady.p))
    M = np.array(model.mass(result.steady.x, result.steady.p))
    v = result.vectors[:, 0]
    assert np.linalg.norm(J @ v - result.eigenvalues[0] * M @ v) < 1e-10 * np.linalg.norm(J @ v)


@pytest.fixture(scope="module")
def paper_n10():
    scene = Scene(mstar=1.0, modes=10)
    return scene, build_model(scene)


def test_hopf_point_agrees_with_the_sign_change_of_the_growth_rate(paper_n10):
    """Two routes to U*_c: Hopf location by continuation, and Brent on the leading
    eigenvalue's real part from a direct eigen-solve."""
    scene, model = paper_n10
    h = critical_velocity(scene, model)
    growth = lambda u: eigenvalues(model, steady_state(scene.replace(ustar=u), model))[0].real
    assert growth(0.99 * h.ustar) < 0 < growth(1.01 * h.ustar)
    u_scan = scipy.optimize.brentq(growth, 0.99 * h.ustar, 1.01 * h.ustar, xtol=1e-13)
    assert h.ustar == pytest.approx(u_scan, rel=1e-9)
    lam = eigenvalues(model, steady_state(scene.replace(ustar=h.ustar), model))[0]
    assert h.omega == pytest.approx(abs(lam.imag), rel=1e-9)
    assert h.precision < 1e-9


def test_lyapunov_coefficient_agrees_with_the_explicit_form(paper_n10):
    """l1 of M(x) xdot = F(x) equals l1 of the explicit xdot = M^-1 F (built with a
    symbolic solve, so every derivative takes a different route)."""
    scene, model = paper_n10
    h = critical_velocity(scene, model)
    vf = flutter_field(model)
    x, p = ca.MX.sym("x", model.n_state), ca.MX.sym("p", len(vf.par_names))
    explicit = ca.Function("f", [x, p], [ca.solve(vf.M(x, p), vf.F(x, p))])
    vf_explicit = C.VectorField(explicit, None, vf.par_names)
    pv = np.array([h.point.params[k] for k in vf.par_names])
    l1_explicit = C.first_lyapunov(vf_explicit, h.x, pv, h.point.data["omega"])
    assert h.l1 == pytest.approx(l1_explicit, rel=1e-8)


def test_steady_ustar_stops_at_round_off_when_tol_is_below_it(paper_n10):
    """At the Hopf point's parameters, Newton from a perturbed state finds the steady
    state of the onset U* (``critical_velocity``, from the Hopf system) even when asked
    for a residual below rounding (1e-20): it stops at a round-off-level update instead
    of failing; a non-finite start still raises."""
    from fsicas.linear.adapter import steady_ustar
    scene, model = paper_n10
    h = critical_velocity(scene, model)
    vf = flutter_field(model)
    pv = np.array([h.point.params[k] for k in vf.par_names])
    guess = h.x * (1 + 1e-3 * np.random.default_rng(0).standard_normal(h.x.size))
    ustar, x = steady_ustar(vf, pv, guess, scene.hstar, tol=1e-20)
    assert ustar == pytest.approx(h.ustar, rel=1e-10)
    assert np.max(np.abs(x - h.x)) < 1e-10 * np.max(np.abs(h.x))
    with pytest.raises(SteadyStateError, match="residual"):
        steady_ustar(vf, pv, np.full(h.x.size, np.nan), scene.hstar)


def test_criticality_matches_the_paper_trend(paper_n10):
    """Small M*: subcritical flutter (the beam jumps to large amplitude, cf. the paper's
    finding that every instability ends in contact there); M* = 1: supercritical."""
    scene, model = paper_n10
    assert critical_velocity(scene.replace(mstar=0.05), model).l1 > 0
    assert critical_velocity(scene, model).l1 < 0


def test_onset_converges_with_modes_and_quadrature_error_is_negligible():
    """U*_c at M* = 1 for N = 10, 20, 40: the modal truncation error shrinks, and at N = 10
    the quadrature error (default 2N + 20 nodes vs 4N + 40) is far below it."""
    onset = {n: critical_velocity(Scene(mstar=1.0, modes=n), ustar_max=8.0) for n in (10, 20, 40)}
    fine_quad = critical_velocity(Scene(mstar=1.0, modes=10, quad_nodes=80), ustar_max=8.0)
    e10 = abs(onset[10].ustar - onset[40].ustar)
    e20 = abs(onset[20].ustar - onset[40].ustar)
    assert e20 < e10
    assert abs(onset[10].ustar - fine_quad.ustar) < 1e-3 * e10
    assert onset[40].dominant_mode == onset[10].dominant_mode


@pytest.fixture(scope="module")
def boundary(paper_n10):
    scene, model = paper_n10
    return stability_boundary(scene, np.logspace(-1, 1, 9), model), model


def test_boundary_points_are_refined_hopf_points(boundary):
    b, model = boundary
    for p in b.points:
        assert p.refined
        scene = b.scene.replace(mstar=p.mstar)
        below = eigenvalues(model, steady_state(scene.replace(ustar=0.999 * p.ustar_crit), model))
        above = eigenvalues(model, steady_state(scene.replace(ustar=1.001 * p.ustar_crit), model))
        assert below[0].real < 0 < above[0].real


def test_boundary_jumps_exactly_where_the_lowest_hopf_branch_changes(boundary):
    """Each reported switch separates two branches: 5 % left of it the first Hopf point
    along U* (an independent one-parameter location) has the frequency of the branch
    below, 5 % right that of the branch above (switches are located on the traced curves
    to about 1 % in M*; neighbouring switches are a factor >= 1.8 apart). Crossings of
    two curves keep U* continuous and jump in frequency; folds of a curve jump in U*."""
    b, model = boundary
    assert len(b.switches) >= 2
    nearest = lambda w, s: min((s.omega_below, "below"), (s.omega_above, "above"),
                               key=lambda c: abs(c[0] - w))[1]
    for s in b.switches:
        left = critical_velocity(b.scene.replace(mstar=s.mstar / 1.05), model)
        right = critical_velocity(b.scene.replace(mstar=s.mstar * 1.05), model)
        assert nearest(left.omega, s) == "below" and nearest(right.omega, s) == "above"
        assert abs(s.omega_below - s.omega_above) > 0.05 * s.omega_above or \
            abs(s.ustar_below - s.ustar_above) > 0.05 * s.ustar_above


def test_boundary_is_continuous_between_switches(boundary):
    b, _ = boundary
    switch_m = [s.mstar for s in b.switches]
    for p, q in zip(b.points[:-1], b.points[1:]):
        if not any(p.mstar < m < q.mstar for m in switch_m):
            assert p.branch == q.branch
            assert abs(q.ustar_crit - p.ustar_crit) < 0.5 * p.ustar_crit


def test_the_boundary_does_not_depend_on_how_mstar_is_sampled(boundary):
    """[0.1, 1, 10] gives the switches of 9 points in the same range (to 1e-6), and its
    envelope between the samples (the exact onset on its lowest curve) is the onset of
    an independent one-parameter search at M* = 4.4, 5, 7, where a curve traced from no
    seed (U*_c 10.44, 10.27, 10.39) lies below the one the samples saw (up to 14.1)."""
    from fsicas.linear.curves import Envelope, onset_on_curve
    dense, model = boundary
    sparse = stability_boundary(dense.scene, [0.1, 1.0, 10.0], model)
    assert len(sparse.switches) == len(dense.switches) == 4
    for a, b in zip(sparse.switches, dense.switches):
        assert a.located and b.located
        for key in ("mstar", "ustar_below", "ustar_above", "omega_below", "omega_above"):
            assert getattr(a, key) == pytest.approx(getattr(b, key), rel=1e-6), key
    envelope = Envelope(sparse.curves)
    for m in (4.4, 5.0, 7.0):
        _, _, piece = envelope.lowest(np.log10(m))
        curve = next(c for c in sparse.curves if piece in set(c.pieces.tolist()))
        on_curve = onset_on_curve(dense.scene, model, curve, piece, np.log10(m))
        direct = critical_velocity(dense.scene.replace(mstar=m), model)
        assert on_curve.ustar == pytest.approx(direct.ustar, rel=1e-6)
        assert 10.2 < direct.ustar < 10.5


def test_bad_requests_fail_clearly():
    with pytest.raises(ValueError, match="mstars"):
        stability_boundary(Scene(modes=3), [0.0, 1.0])
    with pytest.raises(ValueError, match="quad_nodes"):
        Scene(modes=20, quad_nodes=30)
    with pytest.raises(ValueError, match="ustar_start"):
        hopf_points(Scene(modes=3), ustar_max=1.0, ustar_start=2.0)
    with pytest.raises(SteadyStateError, match="residual"):
        steady_state(Scene(modes=3, ustar=5.0, channel1=Profile.constant(0.06),
                           channel2=Profile.constant(0.04)), tol=1e-40)


def _growth(scene, model, ustar) -> float:
    """Largest real part of the oscillatory eigenvalues at ``ustar`` (direct eigen-solve
    of the linearization at the steady state, no continuation)."""
    from fsicas.linear.stability import linear_stability
    ev = np.asarray(linear_stability(scene.replace(ustar=float(ustar)), model).eigenvalues)
    return float(ev[np.abs(ev.imag) > 1e-6].real.max())


@pytest.mark.parametrize("mstar", [1.745, 1.75, 1.754])
def test_onset_is_the_first_crossing_in_a_narrow_window_band(mstar):
    """In M* in [1.7448, 1.7541] a narrow unstable window opens below the next branch's
    onset (U*_c ~ 8.7): the onset must be the first sign change of the growth rate on a
    scan of U* (step 0.02 from 0.5, then brentq on the growth rate), to 1e-6."""
    from scipy.optimize import brentq
    from fsicas.linear.hopf import critical_velocity
    scene = Scene(mstar=mstar, modes=10)
    model = build_model(scene)
    us = np.arange(0.5, 9.0, 0.02)
    g = np.array([_growth(scene, model, u) for u in us])
    k = int(np.argmax(g > 0))
    assert g[k] > 0 and np.all(g[:k] < 0)
    first = brentq(lambda u: _growth(scene, model, u), us[k - 1], us[k], xtol=1e-10)
    assert first < 7.5                            # below the next branch's onset
    assert critical_velocity(scene, model).ustar == pytest.approx(first, rel=1e-6)


def test_modal_truncation_too_short_is_warned():
    """N = 4 at M* = 50 finds no onset below U* = 40 (N = 20 has U*_c ~ 18.5): a
    ModalTruncationWarning says so; a resolved onset (N = 10, M* = 1) is not warned."""
    import warnings
    from fsicas.linear.hopf import ModalTruncationWarning
    with pytest.warns(ModalTruncationWarning, match="no onset of instability below U\\* = 40"):
        assert critical_velocity(Scene(modes=4, mstar=50.0), ustar_max=40.0) is None
    with warnings.catch_warnings():
        warnings.simplefilter("error", ModalTruncationWarning)
        assert critical_velocity(Scene(modes=10, mstar=1.0)).truncation < 1e-4


@pytest.mark.parametrize("mstar", [1.0, 30.0])
def test_truncation_estimate_is_the_error_against_many_more_modes(mstar):
    """The onset's truncation estimate (N = 10 against 20, relocated from the N = 10 point)
    is its error against an independent search with N = 40 (from U* = 0.2): 1.2e-5 at
    M* = 1; at M* = 30 the N = 10 onset is 6 % low (a spurious higher-mode branch), and
    the estimate says so and warns."""
    from fsicas.linear.hopf import ModalTruncationWarning
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        onset = critical_velocity(Scene(modes=10, mstar=mstar))
    reference = critical_velocity(Scene(modes=40, mstar=mstar)).ustar
    error = abs(onset.ustar - reference) / reference
    assert onset.truncation == pytest.approx(error, rel=0.05)
    flagged = [w for w in caught if issubclass(w.category, ModalTruncationWarning)]
    assert bool(flagged) == (mstar == 30.0) and (mstar == 1.0 or error > 0.05)


def test_modes_auto_picks_the_modes_the_tolerance_needs(capsys):
    """``fsicas onset --modes auto`` at M* = 30: N = 10 is 6 % low, so N = 20 is taken,
    within 1e-3 of an independent search with N = 40; ``--modes auto`` elsewhere is
    refused by the scene check."""
    import json
    from fsicas.cli import main
    assert main(["onset", "--mstar", "30", "--modes", "auto", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    reference = critical_velocity(Scene(modes=40, mstar=30.0)).ustar
    assert out["modes"] == 20 and out["truncation"] < 1e-2 and not out.get("warnings")
    assert out["ustar_crit"] == pytest.approx(reference, rel=1e-3)
    assert main(["eig", "--modes", "auto", "--json"]) == 2
    assert "modes must be an integer" in capsys.readouterr().out
