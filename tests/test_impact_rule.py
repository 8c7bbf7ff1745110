"""The impact load of the equations against an independent integration on the patch.

Reference: the patch ends located by ``scipy.optimize.brentq`` on the modal sum (scanned
on 20,001 points), and ``∫ k (eps - h_c) phi_n`` over the patch by adaptive
``scipy.integrate.quad`` of the modes themselves; the model's load is ``F`` with the law
minus ``F`` with k* = 0 (the load enters F's beam rows only).
"""
from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from fsicas.linear.steady import steady_state
from fsicas.model import contact
from fsicas.model.assembly import build_model
from fsicas.model.impact_rule import ImpactRule
from fsicas.scene import Scene

SCENE = Scene(contact=True, mstar=1.0, ustar=7.0, contact_stiffness=1e8, contact_eps=1e-2)
SCAN = np.linspace(0.0, 1.0, 20001)


def pressed_states(model, count=6, seed=1):
    """States whose deflection reaches into wall 1's contact layer by 0.3 eps at its
    maximum: random modal shapes (mid-beam and tip maxima), the velocities and flows
    of the steady state."""
    rng = np.random.default_rng(seed)
    n, scene = model.n_modes, model.scene
    eps = scene.contact_gap
    phi = model.basis_at(SCAN).phi
    out = []
    for _ in range(count):
        q = rng.normal(size=n) / (1.0 + np.arange(n)) ** 1.5
        y = q @ phi
        q *= (scene.walls[0](SCAN) - eps * 0.7)[np.argmax(y)] / y.max()
        x = np.zeros(model.n_state)
        x[n:2 * n], x[-2:] = q, 0.05
        out.append(x)
    return out


def exact_load(model, x, k, eps) -> np.ndarray:
    """``∫ Σ_c s_c k max(0, eps - h_c) phi_n`` on the located patches (module docstring)."""
    n, scene = model.n_modes, model.scene
    q = x[n:2 * n]
    mode = lambda xs, i: float(model.basis_at([xs]).phi[i, 0])
    out = np.zeros(n)
    for wall, s in zip(scene.walls, contact.WALL_SIGNS):
        g = lambda xs: eps - float(wall(np.array([xs]))[0]) - s * float(model.basis_at([xs]).phi[:, 0] @ q)
        on = eps - wall(SCAN) - s * (q @ model.basis_at(SCAN).phi) > 0
        starts = np.flatnonzero(on & ~np.r_[False, on[:-1]])
        ends = np.flatnonzero(on & ~np.r_[on[1:], False])
        for i, j in zip(starts, ends):
            a = 0.0 if i == 0 else brentq(g, SCAN[i - 1], SCAN[i], xtol=1e-15)
            b = 1.0 if j == len(SCAN) - 1 else brentq(g, SCAN[j], SCAN[j + 1], xtol=1e-15)
            for m in range(n):
                out[m] += s * k * quad(lambda xs: g(xs) * mode(xs, m), a, b, epsabs=0,
                                       epsrel=1e-9, limit=200)[0]
    return out


def model_load(model, p, x) -> np.ndarray:
    free = p.copy()
    free[model.index("contact_stiffness")] = 0.0
    n = model.n_modes
    return (np.array(model.rhs(x, p)) - np.array(model.rhs(x, free))).ravel()[:n]


@pytest.fixture(scope="module")
def setup():
    model = build_model(SCENE)
    steady = steady_state(SCENE, model)
    k, eps = contact.law(model, steady.p)
    states = pressed_states(model)
    exact = np.array([exact_load(model, x, k, eps) for x in states])
    return model, steady.p, states, exact


def test_states_press_mid_beam_and_at_the_tip(setup):
    model, p, states, _ = setup
    n = model.n_modes
    where = [SCAN[np.argmax(x[n:2 * n] @ model.basis_at(SCAN).phi)] for x in states]
    assert min(where) < 0.9 and max(where) == 1.0


def test_load_of_the_equations_matches_the_patch_integral(setup):
    """At the default nodes the equations' impact load is within 1e-4 of the exact one
    (relative to the largest), and the modal_load of NumPy is the same numbers."""
    model, p, states, exact = setup
    got = np.array([model_load(model, p, x) for x in states])
    scale = np.abs(exact).max()
    assert np.abs(got - exact).max() < 1e-4 * scale
    numpy = np.array([contact.modal_load(model, x, p) for x in states])
    assert np.abs(numpy - got).max() < 1e-9 * scale


def test_error_falls_like_the_cell_width_cubed(setup):
    """Doubling the nodes divides the error by at least 5 (O(Δ^3): 8)."""
    model, p, states, exact = setup
    errors = []
    for nodes in (20, 40, 80):
        finer = build_model(SCENE.replace(quad_nodes=nodes))
        got = np.array([model_load(finer, p, x) for x in states])
        errors.append(np.abs(got - exact).max() / np.abs(exact).max())
    assert errors[1] < errors[0] / 5 and errors[2] < errors[1] / 5, errors


def test_no_load_out_of_contact(setup):
    model, p, states, _ = setup
    n = model.n_modes
    x = states[0].copy()
    x[n:2 * n] *= 0.9                        # every gap now wider than eps
    assert np.all(model_load(model, p, x) == 0.0)


@pytest.mark.parametrize("case", ["concave", "convex", "linear", "touching", "bulging"])
def test_cell_weights_against_quad(case):
    """One cell's weights ``∫ max(0, p) ℓ_j`` against adaptive quadrature of the same
    quadratic p, in the shapes the closed form separates (also p > 0 between nodes that
    are all below 0, which the symbolic rule must not skip), NumPy and symbolic; and its
    derivative, by AD and by the rule's own Jacobian, against central differences."""
    g = {"concave": [-1.0, 0.5, -0.2], "convex": [0.3, -0.4, 0.1], "linear": [-0.3, 0.1, 0.5],
         "touching": [-1.0, 0.0, -1.0], "bulging": [-1.0, -0.1, -0.01]}[case]
    rule = ImpactRule(np.linspace(0.0, 1.0, 3))              # one cell, of width 1
    p = lambda t: g[1] + (g[2] - g[0]) / 2 * t + ((g[2] + g[0]) / 2 - g[1]) * t * t
    basis = [lambda t: (t * t - t) / 2, lambda t: 1 - t * t, lambda t: (t * t + t) / 2]
    roots = np.roots([(g[2] + g[0]) / 2 - g[1], (g[2] - g[0]) / 2, g[1]])
    kinks = [r.real for r in roots if abs(r.imag) < 1e-14 and -1 < r.real < 1]
    expected = [quad(lambda t: max(0.0, p(t)) * l(t) / 2, -1, 1, epsabs=1e-15, limit=200,
                     points=kinks or None)[0] for l in basis]
    assert max(expected) > 0 or case == "touching"
    assert rule.nodal(np.array(g), None) == pytest.approx(expected, abs=1e-13)
    sym = ca.MX.sym("g", 3)
    symbolic = np.array(ca.Function("W", [sym], [rule.nodal(sym, None)])(g)).ravel()
    assert symbolic == pytest.approx(expected, abs=1e-13)
    J = np.array(ca.Function("J", [sym], [ca.jacobian(rule.nodal(sym, None), sym)])(g))
    assert np.array(ca.Function("J", [sym], [rule.nodal_jacobian(sym, None)])(g)) == pytest.approx(J, abs=1e-15)
    if case == "touching":        # a double root: the load grows like (g0)^1.5, slope 0
        assert np.all(J == 0.0)
        return
    h = 1e-7
    fd = np.column_stack([(rule.nodal(np.array(g) + h * e, None) - rule.nodal(np.array(g) - h * e, None))
                          / (2 * h) for e in np.eye(3)])
    assert np.isfinite(J).all() and J == pytest.approx(fd, abs=1e-6)
