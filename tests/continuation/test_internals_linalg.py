"""White-box on purpose: the linear algebra under the driver (``continuation._linalg``
and the SuperLU factors of ``continuation._driver.newton``) against dense NumPy and
LAPACK, and the one BLAS thread of a run."""

from itertools import permutations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from threadpoolctl import threadpool_info, threadpool_limits

from continuation._driver.newton import factorize
from continuation._driver.problem import _det_sign, _parity
from continuation._linalg import threads
from continuation._linalg.sparse import PatternCache, append_columns, append_row


def test_factorization_with_reused_ordering_matches_a_fresh_splu():
    rng = np.random.default_rng(0)
    A = (sp.random(300, 300, density=0.02, random_state=1) + 0.5 * sp.identity(300)).tocsc()
    first = factorize(A)
    B = A.copy()
    B.data = rng.standard_normal(B.nnz)             # same pattern: ordering reused
    reused = factorize(B)
    assert not np.array_equal(reused.q, np.arange(300))
    b = rng.standard_normal(300)
    for lu, M in ((first, A), (reused, B)):
        fresh = spla.splu(M, permc_spec="MMD_AT_PLUS_A")
        for trans in ("N", "T"):
            x, x0 = lu.solve(b, trans=trans), fresh.solve(b, trans=trans)
            assert np.max(np.abs(x - x0)) < 1e-12 * np.max(np.abs(x0))
        assert _det_sign(lu) == np.sign(np.linalg.det(M.toarray()))


def test_solves_of_many_columns_equal_dense_lapack():
    """``LU.solve`` of many columns, on unsymmetric matrices that need row pivoting (a
    zero diagonal), at the first factorization of a pattern and on its kept ordering,
    equals LAPACK's dense solve and the column-by-column solve."""
    rng = np.random.default_rng(3)
    for seed in range(6):
        m = int(rng.integers(5, 120))
        A = sp.random(m, m, density=0.1, random_state=seed) + sp.eye(m, k=1) + \
            sp.diags(rng.choice([0.0, 2.0], m))
        A = sp.csc_matrix(A)
        dense = A.toarray()
        if np.linalg.cond(dense) > 1e8:
            continue
        B = rng.standard_normal((m, 8 + seed))
        for lu in (factorize(A), factorize(A)):          # new pattern, kept ordering
            x = lu.solve(B)
            by_columns = np.column_stack([lu.solve(B[:, j]) for j in range(B.shape[1])])
            scale = np.abs(x).max()
            assert np.abs(x - np.linalg.solve(dense, B)).max() < 1e-11 * scale
            assert np.abs(x - by_columns).max() < 1e-12 * scale


def test_permutation_parity_matches_determinant():
    for n in range(1, 6):
        for perm in permutations(range(n)):
            assert _parity(perm) == round(np.linalg.det(np.eye(n)[list(perm)]))


def test_sparse_bordering_helpers_match_dense():
    rng = np.random.default_rng(0)
    for seed in range(20):
        m, n = rng.integers(1, 30), rng.integers(1, 30)
        A = sp.random(m, n, density=rng.uniform(0, 0.5), format="csc", random_state=seed)
        row = rng.standard_normal(n)
        cols = rng.standard_normal((m, 3))
        cols[rng.random((m, 3)) < 0.3] = 0.0
        assert np.array_equal(append_row(A, row).toarray(), np.vstack([A.toarray(), row]))
        assert np.array_equal(append_columns(A, cols).toarray(), np.hstack([A.toarray(), cols]))


def test_pattern_cache_matches_patterns_and_keys_and_keeps_the_newest():
    """A value is found again for the same pattern (any values) and key only; a
    pattern of equal nonzero count but other places, or another key, is a miss; the
    oldest entry goes when more than ``kept`` are stored."""
    cache = PatternCache(kept=2)
    A = sp.csc_matrix(np.array([[1.0, 0.0], [2.0, 3.0]]))
    moved = sp.csc_matrix(np.array([[1.0, 4.0], [0.0, 3.0]]))
    assert A.nnz == moved.nnz
    assert cache.put(A, "a") == "a"
    assert cache.get(sp.csc_matrix(A * 7.0)) == "a"
    assert cache.get(moved) is None and cache.get(A, key=(1,)) is None
    cache.put(A, "a1", key=(1,))
    cache.put(moved, "m")
    assert cache.get(moved) == "m" and cache.get(A, key=(1,)) == "a1"
    assert cache.get(A) is None                          # the oldest of three, dropped


def test_nested_single_threaded_contexts_limit_once_and_restore_once():
    """An inner ``single_threaded`` (a Floquet routine inside a run) leaves the outer
    limit in place on exit; the outer one restores the caller's pools."""
    def counts():
        return [pool["num_threads"] for pool in threadpool_info()]
    with threadpool_limits(2):
        before = counts()
        with threads.single_threaded():
            with threads.single_threaded():
                assert all(n == 1 for n in counts())
            assert all(n == 1 for n in counts())
        assert counts() == before


def test_single_threaded_sets_no_limit_where_every_pool_has_one_thread(monkeypatch):
    """Pools at one thread already (``OPENBLAS_NUM_THREADS=1``): nothing is limited or
    restored (a limit costs more than a point's small eigenproblem); with two threads
    the limit is set."""
    calls = []
    real = type(threads._controller()).limit
    monkeypatch.setattr(type(threads._controller()), "limit",
                        lambda self, **kw: calls.append(kw) or real(self, **kw))
    with threadpool_limits(1):
        with threads.single_threaded():
            pass
    assert calls == []
    with threadpool_limits(2):
        with threads.single_threaded():
            pass
    assert calls == [{"limits": 1}]
