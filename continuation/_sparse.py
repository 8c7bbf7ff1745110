"""Cheap CSC assembly for the bordered matrices built at every Newton step."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp


def append_row(A: sp.csc_matrix, row: np.ndarray) -> sp.csc_matrix:
    """``[A; row^T]`` for a CSC ``A`` and a dense row (one entry per column)."""
    A = sp.csc_matrix(A)
    m, ncol = A.shape
    indptr = A.indptr + np.arange(ncol + 1)
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
    A = sp.csc_matrix(A)
    nz = [np.flatnonzero(c) for c in cols.T]
    indptr = np.concatenate([A.indptr, A.nnz + np.cumsum([len(i) for i in nz])])
    indices = np.concatenate([A.indices, *nz]).astype(A.indices.dtype)
    data = np.concatenate([A.data, *[c[i] for c, i in zip(cols.T, nz)]])
    return sp.csc_matrix((data, indices, indptr), shape=(A.shape[0], A.shape[1] + cols.shape[1]))
