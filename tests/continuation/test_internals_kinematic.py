"""White-box on purpose: kinematic rows of the interval matrices (``dq/dt = r`` of a
mechanical system) taken out of their LU by block elimination
(``continuation._cycles.intervals``: ``kinematic_rows``, ``KinematicLU``), against
NumPy's dense solves of the same matrices and against whole branches continued with
SuperLU of the whole matrix."""

import casadi as ca
import numpy as np
import pytest

import continuation as C
from continuation._cycles.collocation import collocation
from continuation._cycles.condensed import CollocationJacobian
from continuation._cycles.intervals import KinematicLU, PointwiseTerm, kinematic_rows
from continuation._linalg.stacks import StackLU

from .conftest import van_der_pol_ring


def _rel(a, b) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def _blocks(n, positions, velocities, ncol, ntst, rng, scale=100.0):
    """Random dense interval blocks ``(NTST, m, m + n)`` whose rows of ``positions`` read
    ``scale Dm`` on their own state, random values on their velocity, zero elsewhere."""
    Dm = collocation(ncol).Dm
    blocks = rng.standard_normal((ntst, ncol, n, ncol + 1, n))       # (i, k, a, l, s)
    for a, v in zip(positions, velocities):
        keep = blocks[:, :, a, :, v].copy()
        blocks[:, :, a] = 0.0
        blocks[:, :, a, :, a] = scale * Dm
        blocks[:, :, a, :, v] = keep
    return blocks.reshape(ntst, ncol * n, (ncol + 1) * n)


@pytest.mark.parametrize("ncol", [3, 4])
def test_kinematic_rows_are_found_exactly(ncol):
    rng = np.random.default_rng(ncol)
    n, positions, velocities = 9, [6, 7, 8], [0, 2, 1]
    blocks = _blocks(n, positions, velocities, ncol, 4, rng)
    found = kinematic_rows(blocks, collocation(ncol).Dm)
    assert found.positions.tolist() == positions
    assert found.velocities.tolist() == velocities
    assert found.others.tolist() == [0, 1, 2, 3, 4, 5]
    assert found.places.tolist() == [0, 2, 1]
    blocks[2, 1 * n + 7, n + 2 * n + 4] = 1e-300        # row (1, 7): a third state
    blocks[1, 1 * n + 8, n + 8] *= 1 + 1e-13             # row (1, 8): not Dm to rounding
    found = kinematic_rows(blocks, collocation(ncol).Dm)
    assert found.positions.tolist() == [6] and found.velocities.tolist() == [0]
    m = n * ncol
    assert kinematic_rows(rng.standard_normal((3, m, m + n)), collocation(ncol).Dm) is None


def test_a_velocity_is_not_taken_as_a_position():
    """``x_0' = x_1, x_1' = x_2`` (a third-order chain): only one of the two is eliminated,
    so that every position's velocity stays among the unknowns of the Schur complement."""
    blocks = _blocks(6, [0, 1], [1, 2], 4, 3, np.random.default_rng(1))
    found = kinematic_rows(blocks, collocation(4).Dm)
    assert found.positions.tolist() == [0] and found.velocities.tolist() == [1]


@pytest.mark.parametrize("n, positions, velocities", [(10, [0, 1, 2, 3], [4, 5, 6, 7]),
                                                      (12, [11, 3], [0, 0])])
def test_the_block_elimination_solves_like_lapack(n, positions, velocities):
    """``Z_i = M_i^-1 [B_i^L, E_i]`` and solves with 1 and 4 right-hand sides against
    ``numpy.linalg.solve`` of every ``M_i``, zero diagonals forcing row exchanges."""
    ncol, ntst, k = 4, 6, 2
    rng = np.random.default_rng(n)
    blocks = _blocks(n, positions, velocities, ncol, ntst, rng)
    others = [s for s in range(n) if s not in positions]
    for i in range(ntst):
        for t in others:
            blocks[i, t, n + t] = 0.0
    rows = kinematic_rows(blocks, collocation(ncol).Dm)
    lu = rows.factorize(blocks)
    assert isinstance(lu, KinematicLU)
    b = rng.standard_normal((ntst, n * ncol, 4))
    for r in (1, 4):
        x = lu.solve(b[:, :, :r])
        for i in range(ntst):
            M = blocks[i, :, n:]
            assert _rel(x[i], np.linalg.solve(M, b[i, :, :r])) < 1e-14 * np.linalg.cond(M)


def test_an_interval_without_the_structure_falls_back_to_dense_factors():
    """The structure is checked at every factorization: a coupling that appears later
    (here in interval 3) sends the Jacobian to the plain LU, with the same solution."""
    n, ncol, ntst = 10, 4, 5
    rng = np.random.default_rng(7)
    blocks = _blocks(n, [0, 1], [5, 6], ncol, ntst, rng)
    rows = kinematic_rows(blocks, collocation(ncol).Dm)
    assert rows.factorize(blocks) is not None
    blocks[3, 2 * n + 1, n + n + 9] = 0.25               # interval 3, row (2, 1), state 9
    assert rows.factorize(blocks) is None
    term = PointwiseTerm(np.zeros((ntst * ncol, n * n)), np.zeros((ntst * ncol, ncol + 1)))
    J = CollocationJacobian(n, ntst, ncol, (term,), rng.standard_normal((ntst, n * ncol, 1)),
                            np.zeros(ntst * n * ncol), kinematic=rows)
    J.__dict__["blocks"] = blocks                        # the matrices under test
    Z = J.maps
    assert isinstance(J.intervals, StackLU)
    for i in range(ntst):
        M = blocks[i, :, n:]
        assert _rel(Z[i], np.linalg.solve(M, np.hstack([blocks[i, :, :n], J.extra[i]]))) \
            < 1e-13 * np.linalg.cond(M)


def _inertia(n):
    """A mass on the velocity rows only, ``1 + 0.1 u_i^2`` on the diagonal and ``0.05``
    coupling every velocity (the position rows stay ``e_u``)."""
    x, p = ca.SX.sym("x", n), ca.SX.sym("p", 2)
    M = ca.SX.eye(n)
    for i in range(1, n, 2):
        M[i, i] = 1 + 0.1 * x[i - 1] ** 2
        for j in range(1, n, 2):
            M[i, j] += 0.05
    return ca.Function("M", [x, p], [M])


def _problem(solver, mass, n=14):
    guess = lambda t: np.column_stack([2 * np.cos(2 * np.pi * t), -2 * np.sin(2 * np.pi * t)]
                                      * (n // 2))
    return C.CycleProblem(van_der_pol_ring(n), guess, 6.6, {"mu": 1.0, "k": 0.2}, "mu",
                          M=_inertia(n) if mass else None,
                          settings=C.CollocationSettings(ntst=12, ncol=4,
                                                         linear_solver=solver))


@pytest.mark.parametrize("mass", [False, True])
def test_branches_with_kinematic_rows_eliminated_equal_the_sparse_solver(mass):
    """Seven Van der Pol oscillators (56-row dense interval matrices, half of their rows
    kinematic), with a state-dependent mass on the velocities: the condensed solves
    against LAPACK on the sparse route's matrix, and a branch against SuperLU's (points,
    Newton iterations, multipliers)."""
    from continuation._driver.newton import factorize
    from continuation._linalg.sparse import append_row
    prob = _problem("condensed", mass)
    rng = np.random.default_rng(3)
    X = prob.X0 * (1 + 0.01 * rng.standard_normal(prob.X0.size))
    tau = rng.standard_normal(X.size)
    A = prob.bordered_jacobian(X, tau)
    lu = factorize(A)
    assert A.J.kinematic.positions.tolist() == [0, 2, 4, 6, 8, 10, 12]
    assert A.J.kinematic.velocities.tolist() == [1, 3, 5, 7, 9, 11, 13]
    assert isinstance(A.J.intervals, KinematicLU)
    dense = append_row(C.CycleProblem.jacobian(prob, X), tau).toarray()
    for b in (rng.standard_normal(X.size), rng.standard_normal((X.size, 3))):
        assert _rel(lu.solve(b), np.linalg.solve(dense, b)) < 1e-11
    settings = C.ContinuationSettings(ds=0.05, ds_max=0.2, max_steps=6)
    a, b = (C.continuation(_problem(s, mass), settings=settings)
            for s in ("sparse", "condensed"))
    assert len(a) == len(b) == settings.max_steps + 1
    assert np.array_equal(a.iterations, b.iterations)
    assert _rel(b.par("mu"), a.par("mu")) < 1e-10 and _rel(b.x, a.x) < 1e-10
    assert _rel(np.array(b.eigenvalues), np.array(a.eigenvalues)) < 1e-9


def test_small_interval_matrices_keep_the_plain_lu():
    """At most ``KINEMATIC_MIN_ROWS`` rows (five oscillators, 40 rows) the elimination
    does not pay: the plain LU."""
    from continuation._cycles.intervals import KINEMATIC_MIN_ROWS
    prob = _problem("condensed", False, n=10)
    assert 10 * 4 <= KINEMATIC_MIN_ROWS
    A = prob.bordered_jacobian(prob.X0, np.ones(prob.X0.size))
    assert A.J.kinematic is None and isinstance(A.J.intervals, StackLU)
