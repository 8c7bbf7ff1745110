"""White-box on purpose: the condensed Newton solver of collocated cycles
(``continuation._cycles.condensed``, its chain and interval stacks) against independent
routes: dense LAPACK solves of the explicitly assembled matrix, SuperLU of the sparse
route's Jacobian, the Floquet condensation of the sparse Jacobian, and whole branches
continued with the sparse solver."""

import casadi as ca
import numpy as np
import pytest

import continuation as C
from continuation._cycles import floquet
from continuation._cycles.chain import Chain
from continuation._cycles.condensed import BorderedCollocation, CondensedLU
from continuation._driver.newton import factorize
from continuation._linalg.sparse import append_row

from .conftest import van_der_pol_ring as _ring


def _rel(a, b) -> float:
    a, b = np.asarray(a), np.asarray(b)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(a)), 1e-300))


def _mass(n=6):
    """A state-dependent mass ``M(x) = I + 0.1 diag(x)^2 + 0.05 (ones)`` (dense)."""
    x, p = ca.SX.sym("x", n), ca.SX.sym("p", 2)
    return ca.Function("M", [x, p], [ca.DM.eye(n) + 0.1 * ca.diag(x ** 2) + 0.05])


def _backward(A, B, x) -> float:
    """``max |A x - B x| / (max |A| max |x|)``: two routes to a product, at round-off."""
    return float(np.max(np.abs(A @ x - B @ x)) / (np.max(np.abs(A)) * np.max(np.abs(x))))


def _problem(ntst, ncol, solver, mass=False, n=6):
    guess = lambda t: np.column_stack([2 * np.cos(2 * np.pi * t), -2 * np.sin(2 * np.pi * t)]
                                      * (n // 2))
    return C.CycleProblem(_ring(n), guess, 6.6, {"mu": 1.0, "k": 0.2}, "mu",
                          M=_mass(n) if mass else None,
                          settings=C.CollocationSettings(ntst=ntst, ncol=ncol,
                                                         linear_solver=solver))


@pytest.mark.parametrize("ntst, ncol, mass", [(7, 3, False), (8, 4, True), (13, 2, True),
                                              (2, 4, False)])
def test_condensed_solve_equals_dense_lapack_on_the_sparse_routes_matrix(ntst, ncol, mass):
    """Odd and even NTST (the pairwise reduction carries an odd equation), NTST = 2, a
    state-dependent mass, one and several right-hand sides."""
    prob = _problem(ntst, ncol, "condensed", mass)
    rng = np.random.default_rng(ntst)
    X = prob.X0 * (1 + 0.01 * rng.standard_normal(prob.X0.size))
    tau = rng.standard_normal(X.size)
    A = prob.bordered_jacobian(X, tau)
    assert isinstance(A, BorderedCollocation)
    dense = append_row(C.CycleProblem.jacobian(prob, X), tau).toarray()   # sparse route
    assert _rel(dense, A.toarray()) < 1e-15
    assert _rel(dense, A.tocsc().toarray()) < 1e-15
    lu = factorize(A)
    for b in (rng.standard_normal(X.size), rng.standard_normal((X.size, 3))):
        exact = np.linalg.solve(dense, b)
        assert _rel(exact, lu.solve(b)) < 1e-11
        assert _backward(dense, A, exact) < 1e-15


def test_transposed_solves_are_refused():
    prob = _problem(9, 3, "condensed")
    lu = factorize(prob.bordered_jacobian(prob.X0, np.ones(prob.X0.size)))
    with pytest.raises(NotImplementedError, match="trans"):
        lu.solve(np.ones(prob.X0.size), trans="T")


def _chain(decades: float, N: int = 21, n: int = 4, k: int = 2):
    """A cyclic chain ``v_{i+1} = -A_i v_i + ...`` (``C_i = I``) whose monodromy has
    multipliers ``10^(+-decades)``, its borders, and its dense matrix."""
    rng = np.random.default_rng(5)
    rates = np.array([1.0, 0.0, -1.0, 0.15]) * decades * np.log(10) / N
    A = np.empty((N, n, n))
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    for i in range(N):                                         # v_{i+1} = -A_i v_i
        A[i] = -Q @ np.diag(np.exp(rates)) @ Q.T @ (np.eye(n) + 1e-3 * rng.standard_normal((n, n)))
    G = rng.standard_normal((N, n, k))
    Bv, By = rng.standard_normal((N, k, n)), rng.standard_normal((k, k))
    dense = np.zeros((N * n + k, N * n + k))
    for i in range(N):
        j = (i + 1) % N
        dense[i * n:(i + 1) * n, i * n:(i + 1) * n] = A[i]
        dense[i * n:(i + 1) * n, j * n:(j + 1) * n] += np.eye(n)
        dense[i * n:(i + 1) * n, N * n:] = G[i]
    dense[N * n:, :N * n] = Bv.transpose(1, 0, 2).reshape(k, N * n)
    dense[N * n:, N * n:] = By
    return A, G, Bv, By, dense, rng


def _chain_backward_error(A, C_, G, Bv, By, dense, rng, dense_rows=0) -> float:
    N, n, k = G.shape
    chain = Chain.of(A, C_, G, dense_rows)
    factors = chain.bordered(Bv, By)
    rhs = rng.standard_normal((N * n + k, 2))
    v, y = chain.solve(factors, rhs[:N * n].reshape(N, n, 2), rhs[N * n:])
    x = np.concatenate([v.reshape(N * n, 2), y])
    return np.max(np.abs(dense @ x - rhs)) / (np.max(np.abs(dense)) * np.max(np.abs(x)))


@pytest.mark.parametrize("unit", [False, True])
@pytest.mark.parametrize("dense_rows", [0, 40])
def test_chain_reduction_is_stable_where_a_transfer_recursion_is_not(unit, dense_rows):
    """A chain whose monodromy has multipliers 1e+-20 (a recursion over the transfer
    maps, single shooting, loses everything there): the pairwise QR reduction solves it
    with a backward error at round-off, also when told its ``C_i`` are identities
    (``C = None``: its maps, ``|A_i| ~ 9``, are too large for the identity pivot), down
    to one equation or to the dense LU of the equations left (here 11 of them, 46 rows,
    where another QR level would cost more)."""
    A, G, Bv, By, dense, rng = _chain(20.0)
    C_ = None if unit else np.broadcast_to(np.eye(A.shape[1]), A.shape)
    assert _chain_backward_error(A, C_, G, Bv, By, dense, rng, dense_rows) < 1e-14
    assert len(Chain.of(A, C_, G, dense_rows).levels) == (5 if dense_rows == 0 else 1)
    mono = np.eye(A.shape[1])
    for Ai in A:
        mono = -Ai @ mono
    assert np.max(np.abs(np.linalg.eigvals(mono))) > 1e19           # really that hard


@pytest.mark.parametrize("scale", [1.0, 1e3])
def test_identity_pivots_solve_a_chain_of_bounded_maps_to_round_off(scale):
    """Multipliers 1e+-0.5 over 21 maps: with ``C = None`` every level whose pairs' maps
    stay within ``UNIT_GROWTH`` is eliminated by its identity pivots (products of maps),
    the rest by QR; the backward error stays at round-off, as with QR alone. With states of
    disparate scales (``D v``, ``D = diag(1, scale, 1, scale)``: maps ``D A D^-1`` of
    norm ~ ``scale``, as a beam's modal displacements and velocities give) the growth is
    judged in the natural units: the same pairs take the pivot, and the solution mapped
    back keeps its round-off backward error (QR's, not invariant under the scaling,
    grows with it: measured 2.6e-14 at 1e3)."""
    from continuation._cycles.chain import UNIT_GROWTH
    A, G, Bv, By, dense, rng = _chain(0.5)
    N, n, k = G.shape
    assert np.abs(A).sum(axis=2).max() ** 2 < UNIT_GROWTH / 4    # two levels at least
    D = np.array([1.0, scale, 1.0, scale])
    As, Gs, Bvs = D[:, None] * A / D[None, :], D[:, None] * G, Bv / D[None, None, :]
    errors = []
    for C_ in (None, np.broadcast_to(np.eye(n), A.shape)):
        chain = Chain.of(As, C_, Gs, dense_rows=0)
        rhs = rng.standard_normal((N * n + k, 2))
        z = rhs[:N * n].reshape(N, n, 2) * D[None, :, None]        # the scaled equations
        v, y = chain.solve(chain.bordered(Bvs, By), z, rhs[N * n:])
        x = np.concatenate([(v / D[None, :, None]).reshape(N * n, 2), y])
        errors.append(np.max(np.abs(dense @ x - rhs)) / (np.max(np.abs(dense))
                                                        * np.max(np.abs(x))))
    assert errors[0] < 1e-15 and errors[1] < 1e-15 * scale
    by_pivot = [level.a0.shape[0] for level, _ in Chain.of(As, None, Gs, 0).levels
                if hasattr(level, "a0")]
    assert sum(by_pivot) >= 10 + 5                  # the first two levels at least
    assert scale == 1.0 or np.abs(As).sum(axis=2).max() > UNIT_GROWTH


def test_multipliers_from_the_factorization_equal_the_sparse_floquet_condensation():
    prob = _problem(10, 4, "condensed", mass=True)
    X = C.ContinuationIterator(prob, C.PALC(), C.ContinuationSettings()).start().X
    mu = prob.multipliers(X)                        # from the tangent's factorization
    J = C.CycleProblem.jacobian(prob, X)
    ref = floquet.multipliers(floquet.transfer_matrices(J, prob.vf.n, prob.ntst,
                                                          prob.ncol), "pencil")
    assert _rel(ref, mu) < 1e-11
    full = prob.transfer_matrices(X, full=True)
    assert _rel(floquet.transfer_matrices(J, prob.vf.n, prob.ntst, prob.ncol, full=True),
                full) < 1e-12


@pytest.mark.parametrize("mass", [False, True])
def test_branches_by_condensation_equal_the_sparse_solvers(mass):
    """Same points, tangents, Newton iterations and multipliers along a branch."""
    settings = C.ContinuationSettings(ds=0.05, ds_max=0.2, max_steps=8)
    branches = {s: C.continuation(_problem(12, 4, s, mass), settings=settings)
                for s in ("sparse", "condensed")}
    a, b = branches["sparse"], branches["condensed"]
    assert len(a) == len(b) == settings.max_steps + 1
    assert np.array_equal(a.iterations, b.iterations)
    assert _rel(a.par("mu"), b.par("mu")) < 1e-10
    assert _rel(a.x, b.x) < 1e-10 and _rel(a.columns["period"], b.columns["period"]) < 1e-10
    assert _rel(np.array(a.eigenvalues), np.array(b.eigenvalues)) < 1e-9


def test_a_singular_interval_falls_back_to_superlu_of_the_whole_matrix():
    prob = _problem(6, 3, "condensed")
    rng = np.random.default_rng(1)
    A = prob.bordered_jacobian(prob.X0, rng.standard_normal(prob.X0.size))
    A.J.__dict__["_factorization"] = (None, None)  # as if an M_i were singular
    assert A.J.maps is None
    lu = A.factorize()
    assert not isinstance(lu, CondensedLU)
    b = rng.standard_normal(prob.X0.size)
    assert _rel(np.linalg.solve(A.toarray(), b), lu.solve(b)) < 1e-11


def test_linear_solver_setting_and_its_automatic_choice():
    with pytest.raises(ValueError, match="linear_solver must be 'auto', 'condensed' or "
                                         "'sparse', got 'lu'"):
        C.CollocationSettings(linear_solver="lu")
    with pytest.raises(ValueError, match="needs jacobian = 'blocks'"):
        C.CollocationSettings(linear_solver="condensed", jacobian="graph")
    # 'auto': interval blocks of up to 100 rows (6 states x NCOL 4 = 24 here) condense;
    # larger ones when dense (a 40-state field with a dense mass, 160 rows) or banded (a
    # 40-state ring, 160 rows, banded once its states are reordered), not when sparse
    # without a band (40 states coupled at scattered distances: SuperLU keeps them sparse)
    assert _problem(8, 4, "auto").condensed
    assert _problem(8, 4, "auto", mass=True, n=40).condensed
    x, p = ca.SX.sym("x", 40), ca.SX.sym("p", 2)
    ring = ca.vertcat(x[1:], x[0]) - p[0] * x + p[1] * ca.vertcat(x[-1], x[:-1]) ** 3
    scattered = p[0] * x + p[1] * ca.vertcat(*[x[(7 * i + 3) % 40] - x[(13 * i + 5) % 40] ** 3
                                               for i in range(40)])
    for f, condensed in ((ring, True), (scattered, False)):
        prob = C.CycleProblem(ca.Function("F", [x, p], [f]),
                              lambda t: np.ones((np.size(t), 40)), 1.0,
                              {"mu": 1.0, "k": 0.2}, "mu",
                              settings=C.CollocationSettings(ntst=8, ncol=4))
        assert prob.condensed == condensed


@pytest.mark.parametrize("m", [1, 5, 16, 40])
def test_stacked_lu_solves_equal_numpy(m):
    """The LUs of a stack (LAPACK, each matrix transposed in place) against NumPy's solve
    of each: one and several right-hand sides, matrices that need row exchanges (zero
    diagonals), and an exactly singular one among regular ones (reported, not solved)."""
    from continuation._linalg.stacks import StackLU
    rng = np.random.default_rng(m)
    A = rng.standard_normal((6, m, m))
    A[:, np.arange(m), np.arange(m)] = 0.0
    A[:, 0, m - 1] = A[:, m - 1, 0] = 3.0
    lu = StackLU.of(A)
    for r in (1, 3):
        b = rng.standard_normal((6, m, r))
        x = lu.solve(b)
        for i in range(6):
            assert _rel(x[i], np.linalg.solve(A[i], b[i])) < 1e-12 * np.linalg.cond(A[i])
    A[4, :, -1] = 0.0
    assert StackLU.of(A) is None


@pytest.mark.parametrize("n, ncol", [(1, 2), (4, 4), (12, 4)])
def test_dense_interval_factors_and_solves_equal_numpy(n, ncol):
    """Dense interval matrices (terms on patterns and dense) against NumPy's solve of
    each: the maps ``Z_i`` and solves of one and several right-hand sides, on matrices
    that need row exchanges (zero diagonals); an exactly singular ``M_i`` among regular
    ones is reported."""
    from continuation._cycles.condensed import CollocationJacobian
    from continuation._cycles.intervals import PointwiseTerm
    ntst, k, m = 9, 2, n * ncol
    rng = np.random.default_rng(m)
    dense = PointwiseTerm(rng.standard_normal((ntst * ncol, n * n)),
                          rng.standard_normal((ntst * ncol, ncol + 1)))
    terms = _chain_terms(n, ntst, ncol, rng)[1] + (dense,)     # on patterns, and dense
    extra = rng.standard_normal((ntst, m, k))
    blocks = _explicit_blocks(terms, n, ntst, ncol)
    blocks[:, np.arange(m), n + np.arange(m)] = 0.0       # row exchanges are needed
    J = CollocationJacobian(n, ntst, ncol, terms, extra, np.zeros(ntst * m))
    J.__dict__["blocks"] = blocks
    b = rng.standard_normal((ntst, m, 4))
    x1, x4 = J.intervals.solve(b[:, :, :1]), J.intervals.solve(b)
    for i in range(ntst):
        M, tol = blocks[i, :, n:], 1e-12 * np.linalg.cond(blocks[i, :, n:])
        assert _rel(J.maps[i], np.linalg.solve(M, np.hstack([blocks[i, :, :n], extra[i]]))) \
            < tol
        assert _rel(x4[i], np.linalg.solve(M, b[i])) < tol
        assert _rel(x1[i], np.linalg.solve(M, b[i, :, :1])) < tol
    blocks[4, :, n] = 0.0                    # interval 4's first column: singular
    J = CollocationJacobian(n, ntst, ncol, terms, extra, np.zeros(ntst * m))
    J.__dict__["blocks"] = blocks
    assert J.maps is None and J.intervals is None


def _block_pattern(n, ncol, prow, pcol):
    """The structural pattern of an interval matrix ``M_i`` (``m x m``): every block
    (point ``k``, node ``l = 1 .. NCOL``) has the pointwise pattern."""
    S = np.zeros((n, n), bool)
    S[prow, pcol] = True
    return np.kron(np.ones((ncol, ncol), bool), S)


@pytest.mark.parametrize("coupling", ["chain", "ring", "shuffled chain", "dense"])
def test_interval_band_holds_every_entry_of_the_interval_matrices(coupling):
    """Reordered by the band's rows and columns, the interval matrix of the pattern has
    no entry outside ``lower`` / ``upper`` off-diagonals (checked on the explicit
    pattern); a chain's band is its distance of coupling times NCOL, plus NCOL - 1; a
    dense pattern has no band."""
    from continuation._cycles.intervals import interval_band
    n, ncol = 30, 4
    near = {"chain": (-2, -1, 0, 1, 2), "ring": (-1, 0, 1), "shuffled chain": (-1, 0, 1),
            "dense": tuple(range(-n + 1, n))}[coupling]
    pairs = [(i, i + d) for i in range(n) for d in near
             if coupling == "ring" or 0 <= i + d < n]
    prow, pcol = (np.array([a for a, _ in pairs]), np.array([b % n for _, b in pairs]))
    if coupling == "shuffled chain":                 # the states in a random order
        order = np.random.default_rng(3).permutation(n)
        prow, pcol = order[prow], order[pcol]
    band = interval_band(n, ncol, prow, pcol)
    if coupling == "dense":
        assert band is None
        return
    assert sorted(band.order) == list(range(n * ncol))
    S = _block_pattern(n, ncol, prow, pcol)[band.order][:, band.order]
    i, j = np.nonzero(S)
    assert (i - j).max() <= band.lower and (j - i).max() <= band.upper
    if coupling == "chain":
        assert band.lower == band.upper == 2 * ncol + ncol - 1
    else:                                            # a ring / shuffled chain: RCM finds
        assert band.lower <= 2 * ncol + ncol - 1     # a band of width 2 or less


def _explicit_blocks(terms, n, ntst, ncol):
    """The interval blocks of pointwise terms, assembled from each point's dense matrix:
    block ``(k, l)`` of interval ``i`` is ``sum_t weights_t[i NCOL + k, l] A_t``."""
    m = n * ncol
    blocks = np.zeros((ntst, m, m + n))
    for t in terms:
        for point in range(ntst * ncol):
            A = np.zeros((n, n))
            if t.rows is None:
                A[:] = t.values[point].reshape(n, n)
            else:
                A[t.rows, t.cols] = t.values[point]
            i, k = divmod(point, ncol)
            for l in range(ncol + 1):
                blocks[i, k * n:(k + 1) * n, l * n:(l + 1) * n] += t.weights[point, l] * A
    return blocks


def _chain_terms(n, ntst, ncol, rng):
    """A matrix on a nearest-neighbour pattern and one on its diagonal (a mass), with
    random values and weights, as pointwise terms."""
    from continuation._cycles.intervals import PointwiseTerm
    pairs = [(i, i + d) for i in range(n) for d in (-1, 0, 1) if 0 <= i + d < n]
    prow, pcol = np.array([a for a, _ in pairs]), np.array([b for _, b in pairs])
    K, diag = ntst * ncol, np.arange(n)
    return (prow, pcol), tuple(
        PointwiseTerm(rng.standard_normal((K, r.size)), rng.standard_normal((K, ncol + 1)),
                      r, c) for r, c in ((prow, pcol), (diag, diag)))


def test_interval_blocks_are_the_sum_of_their_pointwise_terms():
    """Dense blocks (terms on a pattern, and dense row by row) and the band layout
    (``M_i`` reordered in LAPACK's band storage, node 0's columns) against the blocks
    assembled from every point's dense matrix."""
    from continuation._cycles.condensed import CollocationJacobian
    from continuation._cycles.intervals import PointwiseTerm, interval_band
    n, ncol, ntst = 12, 3, 4
    m, rng = n * ncol, np.random.default_rng(1)
    (prow, pcol), terms = _chain_terms(n, ntst, ncol, rng)
    dense = PointwiseTerm(rng.standard_normal((ntst * ncol, n * n)),
                          rng.standard_normal((ntst * ncol, ncol + 1)))
    for ts in (terms, terms + (dense,)):
        J = CollocationJacobian(n, ntst, ncol, ts, np.zeros((ntst, m, 1)), np.zeros(ntst * m))
        assert _rel(J.blocks, _explicit_blocks(ts, n, ntst, ncol)) < 1e-15
    band = interval_band(n, ncol, prow, pcol)
    J = CollocationJacobian(n, ntst, ncol, terms, np.zeros((ntst, m, 1)), np.zeros(ntst * m),
                            band)
    ab, left = J.band_blocks()
    explicit, o, d = _explicit_blocks(terms, n, ntst, ncol), band.order, band.lower + band.upper
    r, c = np.nonzero(np.ones((m, m)))
    inside = (r - c <= band.lower) & (c - r <= band.upper)
    for i in range(ntst):
        M = explicit[i, :, n:][o][:, o]
        assert not M[~inside.reshape(m, m)].any()            # the band holds every entry
        assert np.array_equal(ab[i, c[inside], d + r[inside] - c[inside]],
                              M[r[inside], c[inside]])
        assert np.array_equal(left[i], explicit[i, :, :n][o])


def test_banded_interval_factors_and_solves_equal_dense_lapack():
    """The band route (LAPACK's band LU, the permutations) against NumPy on the same
    interval matrices: the maps ``Z_i`` and solves of one and several right-hand sides,
    which need row exchanges; singular blocks are reported."""
    from continuation._cycles.condensed import CollocationJacobian
    from continuation._cycles.intervals import PointwiseTerm, interval_band
    n, ncol, ntst, k = 12, 3, 5, 2
    m, rng = n * ncol, np.random.default_rng(0)
    (prow, pcol), terms = _chain_terms(n, ntst, ncol, rng)
    band = interval_band(n, ncol, prow, pcol)
    assert band is not None
    extra = rng.standard_normal((ntst, m, k))
    J = CollocationJacobian(n, ntst, ncol, terms, extra, np.zeros(ntst * m), band)
    Z = J.maps
    assert np.any(J.intervals.piv != np.arange(ntst * m))           # rows were exchanged
    blocks = _explicit_blocks(terms, n, ntst, ncol)
    b = rng.standard_normal((ntst, m, 4))
    x1, x4 = J.intervals.solve(b[:, :, :1]), J.intervals.solve(b)
    for i in range(ntst):
        M = blocks[i, :, n:]
        expected = np.linalg.solve(M, np.hstack([blocks[i, :, :n], extra[i]]))
        assert _rel(Z[i], expected) < 1e-11
        assert _rel(x4[i], np.linalg.solve(M, b[i])) < 1e-11
        assert _rel(x1[i], np.linalg.solve(M, b[i, :, :1])) < 1e-11
    first = terms[0]
    values = first.values.copy()
    values[2 * ncol:3 * ncol, pcol == 5] = 0.0          # column 5 of interval 2's nodes 1..
    singular = (PointwiseTerm(values, first.weights * (np.arange(ncol + 1) > 0),
                              first.rows, first.cols),)
    J = CollocationJacobian(n, ntst, ncol, singular, extra, np.zeros(ntst * m), band)
    assert J.maps is None and J.intervals is None


def _oscillator_chain(n=24):
    """``n / 2`` Van der Pol oscillators in a line, each coupled to its neighbours (free
    ends): banded interval matrices. ``p = (mu, k)``."""
    x, p = ca.SX.sym("x", n), ca.SX.sym("p", 2)
    u, v = x[0::2], x[1::2]
    left = ca.vertcat(u[0], u[:-1])
    right = ca.vertcat(u[1:], u[-1])
    f = ca.vertcat(*[ca.vertcat(v[i], p[0] * (1 - u[i] ** 2) * v[i] - u[i]
                                + p[1] * (left[i] - 2 * u[i] + right[i]))
                     for i in range(n // 2)])
    return ca.Function("F", [x, p], [f])


def test_banded_condensation_equals_dense_lapack_and_the_sparse_branch():
    """A chain whose interval matrices are banded (96 rows, 11 off-diagonals each side):
    the band route's solves against LAPACK on the sparse route's matrix, and a branch
    against the sparse solver's (points, Newton iterations, multipliers)."""
    n = 24
    guess = lambda t: np.column_stack([2 * np.cos(2 * np.pi * t),
                                       -2 * np.sin(2 * np.pi * t)] * (n // 2))

    def problem(solver):
        return C.CycleProblem(_oscillator_chain(n), guess, 6.6, {"mu": 1.0, "k": 0.3},
                              "mu", settings=C.CollocationSettings(ntst=9, ncol=4,
                                                                   linear_solver=solver))
    prob = problem("auto")
    assert prob.condensed and prob.system.compiled.band is not None
    rng = np.random.default_rng(5)
    X = prob.X0 * (1 + 0.01 * rng.standard_normal(prob.X0.size))
    tau = rng.standard_normal(X.size)
    dense = append_row(C.CycleProblem.jacobian(prob, X), tau).toarray()
    lu = factorize(prob.bordered_jacobian(X, tau))
    for b in (rng.standard_normal(X.size), rng.standard_normal((X.size, 3))):
        assert _rel(np.linalg.solve(dense, b), lu.solve(b)) < 1e-11
    settings = C.ContinuationSettings(ds=0.05, ds_max=0.2, max_steps=5)
    a, b = (C.continuation(problem(s), settings=settings) for s in ("sparse", "auto"))
    assert len(a) == len(b) == settings.max_steps + 1
    assert np.array_equal(a.iterations, b.iterations)
    assert _rel(a.par("mu"), b.par("mu")) < 1e-10 and _rel(a.x, b.x) < 1e-10
    assert _rel(np.array(a.eigenvalues), np.array(b.eigenvalues)) < 1e-9


def test_a_band_is_taken_where_it_is_narrower_than_the_blocks_and_they_exceed_the_loops():
    """Two-state cells coupled to their neighbours (distance 2, 11 off-diagonals at NCOL
    = 4, storage 34): no band at 32 rows or where the storage exceeds the rows, a band at
    40 rows."""
    from continuation._cycles.intervals import BAND_MIN_ROWS, interval_band

    def chain(n):
        pairs = [(i, i + d) for i in range(n) for d in (-2, -1, 0, 1, 2) if 0 <= i + d < n]
        return np.array([a for a, _ in pairs]), np.array([b for _, b in pairs])
    assert BAND_MIN_ROWS == 32
    assert interval_band(8, 4, *chain(8)) is None                  # 32 rows
    band = interval_band(10, 4, *chain(10))                         # 40 rows
    assert (band.lower, band.upper) == (11, 11) and 2 * 11 + 11 + 1 <= 40
    assert interval_band(8, 8, *chain(8)) is None        # 64 rows, storage 3 * 23 + 1
