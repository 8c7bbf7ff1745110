"""White-box on purpose: the collocation polynomial of ``continuation._cycles.collocation``
(its Lagrange basis, phase condition, extrema and minimizer) against polynomials known in
closed form, exact integrals and dense sampling."""

import numpy as np
import pytest

from continuation._cycles.collocation import (evaluate, extrema, lagrange, minimizer,
                                              phase_coefficients)


def test_lagrange_basis_reproduces_polynomials_and_their_derivatives():
    """Σ_l p(x_l) L_l(s) = p(s) and Σ_l p(x_l) L_l'(s) = p'(s) for every polynomial of
    degree <= NCOL on the NCOL + 1 equispaced nodes (NCOL = 1..7), to rounding."""
    rng = np.random.default_rng(3)
    s = rng.random(40)
    for ncol in range(1, 8):
        nodes = np.linspace(0.0, 1.0, ncol + 1)
        p = np.polynomial.Polynomial(rng.standard_normal(ncol + 1))
        V, dV = lagrange(nodes, s)
        assert np.max(np.abs(V @ p(nodes) - p(s))) < 1e-13 * np.max(np.abs(p(s)))
        assert np.max(np.abs(dV @ p(nodes) - p.deriv()(s))) < 1e-12 * np.max(np.abs(p.deriv()(s)))
        assert np.allclose(lagrange(nodes, nodes)[0], np.eye(ncol + 1), atol=1e-15)


@pytest.mark.parametrize("ncol", [2, 4, 7])
def test_phase_coefficients_integrate_the_phase_condition_exactly(ncol):
    """``c . U = int_0^1 <u, v'> dt`` for the piecewise polynomials through the node values
    ``U`` and ``V`` on a non-uniform mesh; independent route: on each interval the
    interpolating polynomials in the local time (Chebyshev series through the
    ``NCOL + 1`` equispaced nodes) and their product integrated exactly, where the
    code uses Gauss quadrature (exact for this degree)."""
    rng = np.random.default_rng(ncol)
    n, ntst = 3, 7
    mesh = np.concatenate([[0.0], np.sort(rng.random(ntst - 1)), [1.0]])
    U, V = rng.standard_normal((2, ntst * ncol * n))
    nodes = np.linspace(0.0, 1.0, ncol + 1)

    def pieces(W):
        w = np.vstack([W.reshape(-1, n), W[:n]])        # node NCOL of the last: node 0
        return [[np.polynomial.Chebyshev.fit(nodes, w[i * ncol:(i + 1) * ncol + 1, j], ncol,
                                             domain=[0, 1])
                 for j in range(n)] for i in range(ntst)]
    exact = 0.0
    for pu, pv in zip(pieces(U), pieces(V)):            # dt = h ds, v'(t) = p_v'(s) / h
        for a, b in zip(pu, pv):
            integral = (a * b.deriv()).integ()
            exact += integral(1.0) - integral(0.0)
    c = phase_coefficients(V, n, ntst, ncol)
    assert abs(c @ U - exact) < 1e-12 * max(1.0, abs(exact))


def test_extrema_of_the_collocation_polynomial_match_dense_sampling():
    """``extrema`` (Newton on each interval's polynomial) equals the extremes of the same
    piecewise polynomial sampled at 400 001 times, to the sampling's resolution, also
    where the extremum sits on a mesh point (cos at t = 0) or inside an interval."""
    ntst, ncol, n = 20, 4, 3
    t = np.linspace(0, 1, ntst * ncol, endpoint=False)
    U = np.column_stack([np.cos(2 * np.pi * t), np.cos(4 * np.pi * t + 0.2) ** 3,
                         np.sin(2 * np.pi * t) ** 5]).ravel()
    mesh = np.sort(np.concatenate([[0.0, 1.0], np.random.default_rng(1).uniform(0, 1, ntst - 1)]))
    A = np.vstack([np.eye(n), np.random.default_rng(0).normal(size=(4, n))])
    lo, hi = extrema(U, mesh, ncol, n, A)
    dense = evaluate(U, mesh, ncol, n, np.linspace(0, 1, 400001)) @ A.T
    scale = np.abs(dense).max()
    # never beyond the polynomial's true extremes, and no sample beyond them
    assert np.all(lo <= dense.min(axis=0) + 1e-14) and np.all(hi >= dense.max(axis=0) - 1e-14)
    assert np.max(np.abs(lo - dense.min(axis=0))) < 1e-9 * scale
    assert np.max(np.abs(hi - dense.max(axis=0))) < 1e-9 * scale


def test_minimizer_over_many_rows_matches_dense_sampling():
    """``minimizer`` (only the intervals that can beat a row's best sample are polished)
    finds ``min_{t, j} (A u(t))_j`` of 200 rows of a cycle to the resolution of 400 001
    samples, where it is taken, and the least of ``extrema``'s row minima."""
    ntst, ncol, n = 20, 4, 3
    t = np.linspace(0, 1, ntst * ncol, endpoint=False)
    U = np.column_stack([np.cos(2 * np.pi * t), np.sin(6 * np.pi * t + 0.3),
                         np.cos(4 * np.pi * t) ** 2]).ravel()
    mesh = np.linspace(0.0, 1.0, ntst + 1)
    A = np.random.default_rng(2).normal(size=(200, n))
    value, i, s, j = minimizer(U, mesh, ncol, n, A)
    times = np.linspace(0, 1, 400001)
    dense = evaluate(U, mesh, ncol, n, times) @ A.T
    scale = np.abs(dense).max()
    assert value <= dense.min() + 1e-14 and abs(value - dense.min()) < 1e-9 * scale
    k, j_dense = np.unravel_index(np.argmin(dense), dense.shape)
    assert j == j_dense and abs(mesh[i] + s * (mesh[i + 1] - mesh[i]) - times[k]) < 1e-4
    assert value == extrema(U, mesh, ncol, n, A)[0].min()
