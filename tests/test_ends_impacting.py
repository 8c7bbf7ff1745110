"""The smoothed impact law of beams held at both ends, against independent routes.

The rule: the model's impact load (``F`` with the law minus ``F`` with k* = 0) against
``∫ s_c k softplus(eps - h_c) phi_n`` by adaptive ``scipy.integrate.quad`` of the modes
themselves on the located patch (its ends found by ``brentq`` on the modal sum scanned on
20,001 points, the integral taken where the penetration exceeds -40 bend widths: beyond,
the softplus is below 4e-18 of its width).
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from fsicas.model import contact
from fsicas.model.assembly import build_model
from fsicas.model.impact_rule import SMOOTH_CELLS_PER_NODE
from fsicas.model.quadrature import (composite_gauss_legendre, graded_gauss_legendre,
                                     tip_graded_gauss_legendre)
from fsicas.scene import Scene

SCAN = np.linspace(0.0, 1.0, 20001)
SMOOTHING = 0.1
HELD = ["clamped-clamped", "clamped-pinned"]


def held_scene(ends: str, **kw) -> Scene:
    return Scene(ends=ends, modes=8, mstar=1.0, ustar=10.0, contact=True,
                 contact_stiffness=1e8, contact_eps=1e-2, contact_smoothing=SMOOTHING, **kw)


def pressed_states(model, count=5, depth=0.3, seed=1):
    """States whose largest |y| reaches ``depth`` eps into a wall's contact layer,
    anywhere along the span (random modal shapes), the flows of a uniform channel."""
    rng = np.random.default_rng(seed)
    n, scene = model.n_modes, model.scene
    phi = model.basis_at(SCAN).phi
    out = []
    for _ in range(count):
        q = rng.normal(size=n) / (1.0 + np.arange(n)) ** 1.5
        y = q @ phi
        j = int(np.argmax(np.abs(y)))
        q *= (scene.walls[0](SCAN)[j] - scene.contact_gap * (1 - depth)) / abs(y[j])
        x = np.zeros(model.n_state)
        x[n:2 * n], x[-2:] = q, 0.5
        out.append(x)
    return out


def exact_load(model, q, k, eps) -> np.ndarray:
    """``∫ Σ_c s_c k ramp(eps - h_c) phi_n`` by quad on the located patches (module
    docstring), the patch ends (the bend of the law) passed to quad as break points."""
    n, scene = model.n_modes, model.scene
    width = SMOOTHING * eps
    mode = lambda xs, i: float(model.basis_at([xs]).phi[i, 0])
    out = np.zeros(n)
    for wall, s in zip(scene.walls, contact.WALL_SIGNS):
        g = lambda xs: eps - float(wall(np.array([xs]))[0]) - s * float(model.basis_at([xs]).phi[:, 0] @ q)
        values = eps - wall(SCAN) - s * (q @ model.basis_at(SCAN).phi)
        for a, b in _intervals(g, values + 40 * width, lambda xs: g(xs) + 40 * width):
            bends = [e for lo, hi in _intervals(g, values, g) for e in (lo, hi) if a < e < b]
            for m in range(n):
                out[m] += s * k * quad(lambda xs: contact.ramp(g(xs), width) * mode(xs, m), a, b,
                                       points=bends or None, epsabs=0, epsrel=1e-11, limit=400)[0]
    return out


def _intervals(g, values, level):
    """``[(a, b)]`` where ``level > 0``, the ends located by brentq between scan points."""
    on = values > 0
    starts = np.flatnonzero(on & ~np.r_[False, on[:-1]])
    ends = np.flatnonzero(on & ~np.r_[on[1:], False])
    out = []
    for i, j in zip(starts, ends):
        a = 0.0 if i == 0 else brentq(level, SCAN[i - 1], SCAN[i], xtol=1e-15)
        b = 1.0 if j == len(SCAN) - 1 else brentq(level, SCAN[j], SCAN[j + 1], xtol=1e-15)
        out.append((a, b))
    return out


def model_load(model, p, x) -> np.ndarray:
    free = p.copy()
    free[model.index("contact_stiffness")] = 0.0
    n = model.n_modes
    return (np.array(model.rhs(x, p)) - np.array(model.rhs(x, free))).ravel()[:n]


def rule_load(model, q, rule, k, eps) -> np.ndarray:
    """``Σ_i w_i Σ_c s_c k ramp(g_c(x_i)) phi_n(x_i)`` of nodes and weights ``rule``."""
    x, w = rule
    phi = model.basis_at(x).phi
    return sum(phi @ (s * k * w * contact.ramp(eps - wall(x) - s * (q @ phi), SMOOTHING * eps))
               for wall, s in zip(model.scene.walls, contact.WALL_SIGNS))


@pytest.fixture(scope="module", params=HELD)
def pressed(request):
    model = build_model(held_scene(request.param))
    p = model.parameters(pressure_drop=1.0)
    k, eps = contact.law(model, p)
    states = pressed_states(model)
    exact = np.array([exact_load(model, x[model.n_modes:2 * model.n_modes], k, eps)
                      for x in states])
    return model, p, states, exact


def _error(got, exact) -> float:
    return float(np.abs(np.asarray(got) - exact).max() / np.abs(exact).max())


def test_states_press_inside_the_span_away_from_x_ref(pressed):
    model, _, states, _ = pressed
    n = model.n_modes
    where = [SCAN[np.argmax(np.abs(x[n:2 * n] @ model.basis_at(SCAN).phi))] for x in states]
    assert 0.05 < min(where) and max(where) < 0.95
    assert max(abs(w - model.x_ref) for w in where) > 0.1


def test_load_of_the_equations_matches_the_patch_integral(pressed):
    """At the default nodes (n_quad = 36 at N = 8: 360 equal cells) the equations' load
    is within 5e-4 of the exact one (relative to the largest; measured 1.4e-4 and 1.5e-4
    for clamped-clamped and clamped-pinned), on twice the nodes within 1e-6 (3.0e-7,
    2.0e-7); the NumPy modal_load is the same numbers."""
    model, p, states, exact = pressed
    got = np.array([model_load(model, p, x) for x in states])
    assert len(model.impact_rule.x) == 2 * SMOOTH_CELLS_PER_NODE * model.scene.n_quad
    assert _error(got, exact) < 5e-4
    numpy = np.array([contact.modal_load(model, x, p) for x in states])
    assert np.abs(numpy - got).max() < 1e-9 * np.abs(exact).max()
    finer = build_model(model.scene.replace(quad_nodes=2 * model.scene.n_quad))
    assert _error([model_load(finer, p, x) for x in states], exact) < 1e-6


def test_equal_cells_beat_cells_graded_towards_a_point(pressed):
    """With as many nodes, cells graded symmetrically towards x_ref are 10 times worse
    than equal cells (measured 280 and 32 times), the tip's rule 100 times worse than the
    default equal cells (2400, 2500): contact is anywhere in the span."""
    model, p, states, exact = pressed
    n, (k, eps) = model.n_modes, contact.law(model, p)
    m = model.scene.n_quad
    error = lambda rule: _error([rule_load(model, x[n:2 * n], rule, k, eps) for x in states], exact)
    equal = error(composite_gauss_legendre(SMOOTH_CELLS_PER_NODE * m, 2))
    graded = graded_gauss_legendre(m, at=model.x_ref)
    cells = len(graded[0]) // 2
    assert error(graded) > 10 * error(composite_gauss_legendre(cells, 2))
    assert error(tip_graded_gauss_legendre(m)) > 100 * equal


def test_the_cantilever_keeps_its_tip_graded_rule():
    """Bit for bit: the cantilever's smoothed rule is the tip-graded one, which is the
    rule graded towards x = 1."""
    model = build_model(Scene(contact=True, contact_smoothing=SMOOTHING))
    x, w = tip_graded_gauss_legendre(model.scene.n_quad)
    assert np.array_equal(model.impact_rule.x, x) and np.array_equal(model.impact_rule.weights, w)
    for n, points in ((40, 2), (17, 3)):
        assert all(np.array_equal(a, b) for a, b in zip(graded_gauss_legendre(n, points, at=1.0),
                                                         tip_graded_gauss_legendre(n, points)))


@pytest.mark.parametrize("at", [0.0, 0.3, 0.5, 1.0])
def test_graded_rule_integrates_polynomials_and_grades_towards_its_point(at):
    """Two-point Gauss on every cell: exact for cubics; the cells narrowest at ``at``."""
    x, w = graded_gauss_legendre(20, at=at)
    assert np.dot(w, x ** 3 - 2 * x) == pytest.approx(0.25 - 1.0, abs=1e-14)
    assert abs(x[np.argmin(w)] - at) < 1e-3


def test_graded_rule_refuses_a_point_outside_the_beam():
    with pytest.raises(ValueError, match="grading point must lie in"):
        graded_gauss_legendre(10, at=1.5)


@pytest.fixture(scope="module")
def clamped_branch():
    """N = 4, zeta = 0.01, M* = 1, k* = 1e8, eps/H = 1e-2, smoothing 0.1: the impacting
    branch of the clamped-clamped plate by collocation (14 points, about 5 min), from
    its contact-free cycles (subcritical Hopf at U* = 13.049, fold at 12.964, first
    contact at 13.408) on past that first contact."""
    from fsicas.cycles.impacting_collocation import CollocationImpactSettings
    from fsicas.cycles.impacting_routes import impacting_cycles
    scene = held_scene("clamped-clamped", zeta=0.01).replace(modes=4)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        br = impacting_cycles(scene, ustar_max=25.0, settings=CollocationImpactSettings(
            max_points=14, detect=False))
    return scene, br


@pytest.mark.slow
def test_impacting_cycle_of_a_clamped_plate_against_independent_routes(clamped_branch):
    """The last cycle of the branch (U* = 13.436, past the contact-free cycles' first
    contact), on the model of its points' quadrature (n_quad = 112: the control refined
    it), against an IDAS integration of one period from its state (rtol 1e-11, 40,000
    outputs) and against multiple shooting from it. Measured there / at U* = 14.56 (30
    points): the run returns to the state within 2.8e-5 / 4.7e-6 (an unstable cycle,
    |mu| = 2.6), with the tip amplitude at x_ref to 5.6e-6 / 8.5e-7 and the minimal gap
    along the span to 3.6e-4 / 4.3e-6 eps (a gap of 1.7 eps at a wall 100 eps away);
    shooting finds the period to 1e-8 / 5.4e-7, the amplitude to 5.6e-7 / 1e-6, the gap
    to 1e-4 / 1e-5 eps. The wall's load holds the plate 1 to 2 eps off the wall (the
    smoothed law's tail) at x = 0.79, away from x_ref = 0.5 and both ends; no run
    settles on an unstable cycle."""
    from fsicas.cycles.impacting import ImpactSettings
    from fsicas.cycles.impacting_routes import StartCycle, impacting_cycles
    from fsicas.linear.steady import steady_state
    from fsicas.timedomain.integrators import Settings, simulate
    scene, br = clamped_branch
    p = br.points[-1]
    at = scene.replace(ustar=p.ustar, quad_nodes=p.quadrature_nodes)
    model = build_model(at)
    steady = steady_state(at, model)
    traj = simulate(model, steady, p.period, x0=p.state, settings=Settings(
        method="idas", rtol=1e-11, atol=1e-13, dt_out=p.period / 40000))
    assert traj.status == "success" and p.ustar > 13.408 and not p.stable
    x = traj.x
    assert np.max(np.abs(x[-1] - p.state)) / np.max(np.abs(p.state)) < 1e-4
    y = model.tip_deflection(x)
    assert (y.max() - y.min()) / 2 == pytest.approx(p.tip_amplitude, rel=2e-5)
    h = contact.gaps(model, x)
    assert abs(h.min() / scene.contact_gap - p.gap_ratio) < 2e-3
    assert 1.0 < p.gap_ratio < 2.0
    assert 0.7 < contact.GAP_POINTS[np.unravel_index(np.argmin(h), h.shape)[2]] < 0.9
    assert np.abs(contact.modal_load(model, x[np.argmin(h.min(axis=(1, 2)))], steady.p)).max() > 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        (q,) = impacting_cycles(at, StartCycle(p.state, p.period, steady.pressure_drop), model=model,
                                method="shooting", settings=ImpactSettings(
                                    max_points=1, quadrature_tol=None)).points
    assert q.period == pytest.approx(p.period, rel=2e-6)
    assert q.tip_amplitude == pytest.approx(p.tip_amplitude, rel=5e-6)
    assert abs(q.gap_ratio - p.gap_ratio) < 1e-3 and not q.stable
