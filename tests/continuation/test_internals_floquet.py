"""White-box on purpose: the Floquet condensation of ``continuation._cycles.floquet``, its
dense and sparse routes and its kept layouts, against each other and against interval
blocks read from the dense Jacobian."""

import numpy as np
import pytest
import scipy.sparse as sp

import continuation as C
from continuation._cycles import floquet

from .conftest import cycle_from_circle, ring


def test_dense_and_sparse_condensation_agree(monkeypatch):
    """Both condensation paths of the sparse Jacobian (batched dense for small or
    well-filled blocks, SuperLU on the block diagonal of the others) give the same transfer
    matrices, and so do the maps of the condensed Newton solver."""
    F, e = ring(), 0.5
    prob, X = cycle_from_circle(F, e, 12, 3, 2 * np.pi / np.sqrt(1 - e ** 2))
    J = C.CycleProblem.jacobian(prob, X)
    n, ntst, ncol = prob.vf.n, prob.ntst, prob.ncol
    calls = []
    monkeypatch.setattr(floquet, "sparse_transfer_matrices",
                        lambda *a, f=floquet.sparse_transfer_matrices: calls.append(1) or f(*a))
    dense = floquet.transfer_matrices(J, n, ntst, ncol, full=True)
    assert not calls
    monkeypatch.setattr(floquet, "DENSE_ALWAYS", 0)
    monkeypatch.setattr(floquet, "DENSE_MAX", 0)
    sparse = floquet.transfer_matrices(J, n, ntst, ncol, full=True)
    assert calls
    assert np.max(np.abs(dense - sparse)) < 1e-12 * np.max(np.abs(dense))
    assert prob.condensed
    condensed = prob.transfer_matrices(X, full=True)
    assert np.max(np.abs(dense - condensed)) < 1e-12 * np.max(np.abs(dense))


def test_transfer_matrices_on_a_kept_layout_and_with_duplicate_entries(monkeypatch):
    """The interval layout of a Jacobian's pattern is found once and reused: a second
    Jacobian of the same pattern with other values gives its own maps (equal to the dense
    route's on it), and a non-canonical Jacobian (entries split into duplicates) gives
    the same maps as the canonical one, by both routes."""
    F, e = ring(), 0.5
    prob, X = cycle_from_circle(F, e, 12, 3, 2 * np.pi / np.sqrt(1 - e ** 2))
    J = sp.csc_matrix(C.CycleProblem.jacobian(prob, X))
    n, ntst, ncol = prob.vf.n, prob.ntst, prob.ncol
    other = J.copy()
    other.data = other.data * (1.0 + 0.1 * np.sin(np.arange(other.nnz)))
    cols = [slice(J.indptr[j], J.indptr[j + 1]) for j in range(J.shape[1])]
    split = sp.csc_matrix((np.concatenate([np.r_[0.25 * J.data[c], 0.75 * J.data[c]]
                                           for c in cols]),
                           np.concatenate([np.r_[J.indices[c], J.indices[c]] for c in cols]),
                           2 * J.indptr), shape=J.shape)
    assert not split.has_canonical_format
    assert floquet._Layout.of(J, n, ntst, ncol) is floquet._Layout.of(other, n, ntst, ncol)
    for dense_limit in (None, 0):
        if dense_limit == 0:
            monkeypatch.setattr(floquet, "DENSE_ALWAYS", 0)
            monkeypatch.setattr(floquet, "DENSE_MAX", 0)
        maps = [floquet.transfer_matrices(A, n, ntst, ncol, full=True)
                for A in (J, other, J, split)]
        blocks = [floquet.block_transfer_matrices(_dense_blocks(A, n, ntst, ncol), n, True)
                  for A in (J, other)]
        scale = np.abs(maps[0]).max()
        assert np.abs(maps[0] - blocks[0]).max() < 1e-12 * scale
        assert np.abs(maps[1] - blocks[1]).max() < 1e-12 * scale
        assert np.abs(maps[1] - maps[0]).max() > 1e-3 * scale     # its own values
        assert np.abs(maps[2] - maps[0]).max() < 1e-13 * scale
        assert np.abs(maps[3] - maps[0]).max() < 1e-12 * scale


def _dense_blocks(J, n, ntst, ncol):
    """``[B_L, B_R]`` of every interval read from the dense Jacobian (independent of
    the sparse layout): rows of interval ``i``, columns of its nodes 0..NCOL wrapped."""
    D = J.toarray()
    m, N = n * ncol, n * ncol * ntst
    out = np.empty((ntst, m, m + n))
    for i in range(ntst):
        cols = (i * m + np.arange(m + n)) % N
        out[i] = D[i * m:(i + 1) * m][:, cols]
    return out


def test_section_multipliers_need_a_flow_direction():
    with pytest.raises(ValueError, match="flow direction"):
        floquet.section_multipliers(np.eye(2), np.zeros(2))     # at an equilibrium


def _chain(mu, ntst, rng, coupling=1.0):
    """``A_i = Q_{i+1} R_i Q_i^T`` (``Q_ntst = Q_0``, random orthogonal ``Q_i``, ``R_i``
    upper triangular with diagonal ``|mu|^(1/ntst)``, the signs on ``R_0``, and random
    couplings scaled by the smaller of their two diagonal entries): the product's
    eigenvalues are exactly ``mu``, and each is well conditioned relative to its size
    under relative perturbations of the factors."""
    n = len(mu)
    Q = [np.linalg.qr(rng.standard_normal((n, n)))[0] for _ in range(ntst)]
    Q.append(Q[0])
    A = []
    for i in range(ntst):
        d = np.abs(mu) ** (1.0 / ntst) * (np.sign(mu) if i == 0 else 1.0)
        R = np.diag(d) + coupling * np.triu(rng.standard_normal((n, n)), 1) \
            * np.minimum.outer(np.abs(d), np.abs(d))
        A.append(Q[i + 1] @ R @ Q[i].T)
    return np.array(A)


@pytest.mark.parametrize("ntst", [7, 40])
def test_schur_multipliers_of_a_chain_spanning_1e20_to_1e_minus_20(ntst):
    """Known eigenvalues from 1e20 down to 1e-20 (a negative one among them): the periodic
    Schur route gets each to 1e-10 relative (measured below 1e-13); the explicit product
    keeps the largest and loses every one below about 1e-16 times it."""
    mu = np.array([1e20, 3e10, 1.0, -2e-5, 7e-12, 1e-20])
    A = _chain(mu, ntst, np.random.default_rng(ntst))
    got = floquet.multipliers(A, "schur")
    assert got.shape == (6,) and np.all(got.imag == 0)
    assert np.max(np.abs(got / mu - 1)) < 1e-10
    prod = floquet.multipliers(A, "product")
    assert abs(prod[0] / mu[0] - 1) < 1e-10
    assert np.all(np.abs(prod[-3:] / mu[-3:] - 1) > 1e-2)


def test_schur_sweeps_that_do_not_converge_say_so(monkeypatch):
    """Moduli 1e12 .. 1e-12 a few per cent apart need many sweeps: cut to one, the route
    warns instead of returning blocks it has not separated as if it had."""
    mu = np.geomspace(1e12, 1e-12, 40) * np.linspace(1.0, 1.03, 40)
    A = _chain(np.sort(mu)[::-1], 20, np.random.default_rng(5), coupling=3.0)
    monkeypatch.setattr(floquet, "SCHUR_SWEEPS", 1)
    with pytest.warns(UserWarning, match="did not separate"):
        floquet.multipliers(A, "schur")


def test_schur_multipliers_with_complex_pairs_and_close_moduli():
    """A complex pair at 1e10, real ones at 1 and 0.99 (close moduli: no separation by
    the iteration needed), a pair at 1e-15 and a real one at -1e-18, each to 1e-10."""
    rng, n, ntst = np.random.default_rng(3), 7, 30
    rot = lambda r, a: r * np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])  # noqa: E731
    Q = [np.linalg.qr(rng.standard_normal((n, n)))[0] for _ in range(ntst)]
    Q.append(Q[0])
    A = []
    for i in range(ntst):
        D = np.zeros((n, n))
        D[:2, :2] = rot(1e10 ** (1 / ntst), 0.3 / ntst)
        D[2, 2], D[3, 3] = 1.0, 0.99 ** (1 / ntst)
        D[4:6, 4:6] = rot(1e-15 ** (1 / ntst), 2.0 / ntst)
        D[6, 6] = (-1.0 if i == 0 else 1.0) * 1e-18 ** (1 / ntst)
        E = 0.01 * np.triu(rng.standard_normal((n, n)), 1)
        E[0, 1] = E[4, 5] = 0.0
        A.append(Q[i + 1] @ (D + E) @ Q[i].T)
    exact = np.array([1e10 * np.exp(0.3j), 1e10 * np.exp(-0.3j), 1, 0.99,
                      1e-15 * np.exp(2j), 1e-15 * np.exp(-2j), -1e-18])
    got = floquet.multipliers(np.array(A), "schur")
    for m in exact:
        assert np.min(np.abs(got - m)) < 1e-10 * abs(m)


def test_schur_multipliers_of_a_stiff_linear_periodic_system():
    """``x' = (K' + Q(t) D Q(t)^T) x`` with ``Q(t) = W exp(2 pi t K / T) W^T`` periodic
    (``K`` skew, integer frequencies) and ``D = diag(-1000, -300, -10, 0.5, 1)``: its
    transfer maps are ``Q(t_{i+1}) exp(D h) Q(t_i)^T`` and its Floquet multipliers
    ``exp(D T)`` exactly. With ``T = 0.04`` the smallest is ``exp(-40) = 4e-18``."""
    import scipy.linalg as sla
    lam, T, ntst = np.array([-1000.0, -300.0, -10.0, 0.5, 1.0]), 0.04, 50
    rng = np.random.default_rng(5)
    W = np.linalg.qr(rng.standard_normal((5, 5)))[0]
    K = np.zeros((5, 5))
    K[0, 1], K[2, 3] = -1.0, -3.0
    K = W @ (K - K.T) @ W.T
    t = np.linspace(0.0, T, ntst + 1)
    Q = [sla.expm(2 * np.pi * s / T * K) for s in t]
    A = np.array([Q[i + 1] @ np.diag(np.exp(lam * T / ntst)) @ Q[i].T for i in range(ntst)])
    exact = np.exp(lam * T)[::-1]
    got = floquet.multipliers(A, "schur")
    assert np.max(np.abs(got / exact - 1)) < 1e-10


def test_section_multipliers_take_their_small_tail_from_the_schur_route():
    """``accurate_tail``: the Poincare map's tiny multipliers (formed product: garbage)
    are replaced by the monodromy's smallest ones; the large ones and the trivial one are
    kept."""
    rest = np.array([0.5, 3e-17 + 1e-17j, 3e-17 - 1e-17j], dtype=complex)
    mu = np.array([1.0, 0.5, 1e-12, 1e-20], dtype=complex)
    got = floquet.accurate_tail(rest, mu)
    assert np.array_equal(got, [0.5, 1e-12, 1e-20])
    assert np.array_equal(floquet.accurate_tail(rest[:1], mu[:2]), rest[:1])
    # an unstable 1e10 and a fold's pair near +1: the section's 1 + 1e-9 is kept
    rest = np.array([1e10, 1 + 1e-9, 2e-9], dtype=complex)
    mu = np.array([1e10, 1 + 3e-5, 1 - 3e-5, 1e-14], dtype=complex)
    assert np.array_equal(floquet.accurate_tail(rest, mu), [1e10, 1 + 1e-9, 1e-14])
