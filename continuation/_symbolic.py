"""CasADi layer: symbolic types, compiled residuals and their exact sparse Jacobians.

Every continued problem is reduced here to one residual ``G(X) = 0`` with
``G: R^(m+1) -> R^m``, compiled once together with its exact sparse Jacobian
``G_X`` (CasADi algorithmic differentiation). Numerical code only sees NumPy
arrays and ``scipy.sparse.csc_matrix``.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import scipy.sparse as sp


def as_sx_function(fun: ca.Function) -> ca.Function:
    """Return ``fun`` as an SX function when it can be expanded, else unchanged."""
    if fun.is_a("SXFunction"):
        return fun
    try:
        return fun.expand()
    except RuntimeError:
        return fun


def symbol_class(*funs: ca.Function) -> type:
    """``ca.SX`` if every function is an SX function, otherwise ``ca.MX``."""
    return ca.SX if all(f.is_a("SXFunction") for f in funs) else ca.MX


def to_numpy(value) -> np.ndarray:
    """Dense float vector of a CasADi DM (column) value."""
    return np.asarray(ca.DM(value).full(), dtype=float).ravel()


def to_csc(values: np.ndarray, pattern: tuple) -> sp.csc_matrix:
    """Assemble a CSC matrix from CasADi nonzeros and a CCS pattern."""
    shape, colind, row = pattern
    return sp.csc_matrix((values, row, colind), shape=shape)


class CompiledSystem:
    """``G(X; D)`` and its exact sparse Jacobian ``dG/dX``, compiled once.

    Parameters
    ----------
    X : CasADi symbol (column) of the unknowns.
    D : CasADi symbol of fixed data (parameter values, reference vectors), so
        that one compiled system serves every fixed value.
    G : CasADi expression of the residual, a column depending on ``X, D``, or a
        list of row blocks. Blocks are differentiated separately: a few dense
        rows (normalizations ``c.v = 1``) would otherwise defeat the graph
        colouring of the sparse Jacobian and cost seconds at n = 1000.
    name : used to name the CasADi functions.
    """

    def __init__(self, X, D, G, name: str = "G"):
        blocks = list(G) if isinstance(G, (list, tuple)) else [G]
        G = ca.vertcat(*blocks)
        jac = ca.vertcat(*[ca.jacobian(g, X) for g in blocks])
        sparsity = jac.sparsity()
        colind, row = sparsity.get_ccs()
        self.pattern = ((G.numel(), X.numel()), np.asarray(colind), np.asarray(row))
        self.n_unknowns = X.numel()
        self.n_equations = G.numel()
        self._g = ca.Function(name, [X, D], [G])
        self._j = ca.Function(name + "_jac", [X, D], [jac.nz[:]])

    def residual(self, X: np.ndarray, D: np.ndarray) -> np.ndarray:
        """Residual ``G(X; D)``."""
        return to_numpy(self._g(X, D))

    def jacobian(self, X: np.ndarray, D: np.ndarray) -> sp.csc_matrix:
        """Exact sparse Jacobian ``dG/dX`` (m x (m+1) for a curve)."""
        return to_csc(to_numpy(self._j(X, D)), self.pattern)
