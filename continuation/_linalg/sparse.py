"""Cheap CSC assembly for the bordered matrices built at every Newton step.

Each function builds its result with one ``csc_matrix`` construction from index
arrays (no intermediate matrices): at a few hundred unknowns the constructions, not
the arithmetic, are the cost.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp


def _csc(A) -> sp.csc_matrix:
    return A if isinstance(A, sp.csc_matrix) else sp.csc_matrix(A)


def append_row(A: sp.csc_matrix, row: np.ndarray) -> sp.csc_matrix:
    """``[A; row^T]`` for a CSC ``A`` and a dense row (one entry per column)."""
    A = _csc(A)
    m, ncol = A.shape
    indptr = A.indptr + np.arange(ncol + 1, dtype=A.indptr.dtype)
    last = indptr[1:] - 1
    keep = np.ones(A.nnz + ncol, dtype=bool)
    keep[last] = False
    data = np.empty(A.nnz + ncol, dtype=np.result_type(A.dtype, row.dtype))
    indices = np.empty(A.nnz + ncol, dtype=A.indices.dtype)
    data[keep], indices[keep] = A.data, A.indices
    data[last], indices[last] = row, m
    return sp.csc_matrix((data, indices, indptr), shape=(m + 1, ncol))


def append_columns(A: sp.csc_matrix, cols: np.ndarray) -> sp.csc_matrix:
    """``[A, cols]`` for a CSC ``A`` and dense columns ``cols`` (m x k), zeros dropped."""
    A = _csc(A)
    return columns_appended(A.data, (A.shape, A.indptr, A.indices), cols)


def columns_appended(values: np.ndarray, pattern: tuple, cols: np.ndarray) -> sp.csc_matrix:
    """``[A, cols]`` for ``A`` given by its nonzeros ``values`` and CCS ``pattern``
    ``(shape, colind, row)``, and dense columns ``cols`` (m x k), zeros dropped."""
    (m, n), colind, row = pattern
    nz = [np.flatnonzero(c) for c in cols.T]
    counts = np.array([len(i) for i in nz], dtype=colind.dtype)
    indptr = np.concatenate([colind, colind[-1] + np.cumsum(counts, dtype=colind.dtype)])
    indices = np.concatenate([row, *nz]).astype(row.dtype)
    data = np.concatenate([values, *[c[i] for c, i in zip(cols.T, nz)]])
    return sp.csc_matrix((data, indices, indptr), shape=(m, n + cols.shape[1]))


@dataclass(frozen=True)
class Layout:
    """A fixed CSC pattern and the permutation ``order`` from assembly order to CSC
    data order: ``csc_matrix((vals[order], indices, indptr), shape)``."""

    shape: tuple
    order: np.ndarray
    indices: np.ndarray
    indptr: np.ndarray

    def matrix(self, vals: np.ndarray) -> sp.csc_matrix:
        """The sparse matrix with assembly-ordered values ``vals``."""
        return sp.csc_matrix((np.take(vals, self.order), self.indices, self.indptr),
                             shape=self.shape, copy=False)


def layout(rows: np.ndarray, cols: np.ndarray, shape: tuple) -> Layout:
    """CSC layout of the (duplicate-free) entries ``(rows, cols)`` in assembly order."""
    order = np.lexsort((rows, cols))
    counts = np.bincount(cols, minlength=shape[1])
    indptr = np.concatenate([[0], np.cumsum(counts)])
    idx = np.int32 if max(shape) < 2 ** 31 - 1 else np.int64
    return Layout(shape, order, rows[order].astype(idx), indptr.astype(idx))


class PatternCache:
    """What was derived from the last ``kept`` sparsity patterns, most recent first (a
    branch re-meshes: a few patterns at a time). A pattern is the ``indptr, indices``
    of a CSC matrix and a ``key`` of whatever else the derived value depends on."""

    def __init__(self, kept: int):
        self.kept, self._entries = kept, []

    def get(self, A: sp.csc_matrix, key=()):
        """The value stored for the pattern of ``A`` and ``key``, else None."""
        for known, indptr, indices, value in self._entries:
            if known == key and np.array_equal(indptr, A.indptr) and \
                    np.array_equal(indices, A.indices):
                return value
        return None

    def put(self, A: sp.csc_matrix, value, key=()):
        """Store ``value`` for the pattern of ``A`` and ``key`` (the oldest beyond
        ``kept`` dropped); returns ``value``."""
        self._entries.insert(0, (key, A.indptr.copy(), A.indices.copy(), value))
        del self._entries[self.kept:]
        return value
