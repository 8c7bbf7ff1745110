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
