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
