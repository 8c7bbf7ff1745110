"""Matrices with a lifted structure, evaluated at many points by dense products.

Galerkin and modal models evaluate their nonlinear terms at quadrature nodes: the state
enters through a few linear combinations ``z = L x`` and the nodal terms come back
through constant projections. Their Jacobians (and state-dependent mass matrices) then
have the form

    J(x, p) = A(p) + P D(x, p) L,

``P`` (n x G) and ``L`` (Z x n) constant, ``D`` (G x Z) sparse with few nonzeros per
node. :class:`Lifted` holds that structure; its :meth:`Lifted.function` is the plain
CasADi function of ``J`` (for single points and further AD), and :class:`LiftedBatch`
evaluates ``J`` at ``K`` points at once: the nonzeros of ``D`` by one mapped CasADi call,
then

    J_k = A + sum_e D_k[e] P[:, g_e] L[z_e, :]

grouped by the nonzero patterns of the columns ``P[:, g_e]`` and rows ``L[z_e, :]``:
each group is one BLAS product ``(K x m) @ (m x r c)`` with the precomputed products
``P[r, g_e] L[z_e, c]`` (exact: every nonzero of ``D`` is in one group), instead of
``K`` sparse triple products in CasADi's virtual machine.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np
import scipy.sparse as sp

from .symbolic import BufferedFunction, later_as


@dataclass(frozen=True, eq=False)
class Lifted:
    """``A(p) + P D(x, p[, v]) L`` (module docstring).

    D : casadi.Function of the point inputs ``(x, p)`` or ``(x, p, v)`` -> ``G x Z``
        (its sparsity pattern is the structure that is exploited).
    P, L : constant ``n x G`` and ``Z x n`` matrices (dense or SciPy sparse).
    A : casadi.Function ``p -> n x n``, or None for zero.
    """

    D: ca.Function
    P: object
    L: object
    A: ca.Function | None = None

    def __post_init__(self):
        G, Z = self.D.size_out(0)
        n = self.D.size1_in(0)
        if np.shape(self.P) != (n, G) or np.shape(self.L) != (Z, n):
            raise ValueError(f"Lifted: P must be {n} x {G} and L {Z} x {n} for D of shape "
                             f"{G} x {Z}, got {np.shape(self.P)} and {np.shape(self.L)}")
        if self.A is not None and self.A.size_out(0) != (n, n):
            raise ValueError(f"Lifted: A must map p to an {n} x {n} matrix")

    @property
    def n(self) -> int:
        return self.D.size1_in(0)

    def expr(self, *args):
        """Symbolic ``A(p) + P D(args) L`` (``args`` = the inputs of ``D``)."""
        dm = lambda a: ca.DM(sp.csc_matrix(a))
        inline = all(isinstance(a, ca.MX) for a in args)     # flat graph: cheaper AD
        D = self.D.call(list(args), True, False)[0] if inline else self.D(*args)
        out = ca.mtimes(dm(self.P), ca.mtimes(D, dm(self.L)))
        if self.A is None:
            return out
        return (self.A.call([args[1]], True, False)[0] if inline else self.A(args[1])) + out

    def function(self, name: str = "lifted") -> ca.Function:
        """The CasADi function of the matrix, with the inputs of ``D``."""
        args = [ca.MX.sym(f"a{i}", self.D.sparsity_in(i)) for i in range(self.D.n_in())]
        return ca.Function(name, args, [self.expr(*args)])

    def reparametrized(self, p_of_q: ca.Function, scale: float = 1.0) -> "Lifted":
        """The same structure in parameters ``q`` with ``p = p_of_q(q)``, times ``scale``."""
        q = ca.MX.sym("q", p_of_q.sparsity_in(0))
        args = [ca.MX.sym(f"a{i}", self.D.sparsity_in(i)) for i in range(self.D.n_in())]
        inner = list(args)
        inner[1] = p_of_q(q)
        D = ca.Function("D", [args[0], q, *args[2:]], [self.D.call(inner, True, False)[0]])
        A = None if self.A is None else \
            ca.Function("A", [q], [scale * self.A.call([p_of_q(q)], True, False)[0]])
        return Lifted(D, scale * sp.csc_matrix(self.P), self.L, A)


class LiftedBatch:
    """``J`` of a :class:`Lifted` at ``K`` points: ``batch(x, p[, v]) -> (K, n, n)`` with
    ``x``, ``v`` of shape ``(K, n)`` (module docstring)."""

    def __init__(self, lifted: Lifted, K: int, later=None):
        """``later``: None, or a callable giving None until an equivalent function of
        ``lifted.D`` (compiled) is ready, then that function (:class:`BufferedFunction`)."""
        self.lifted, self.K, self.n = lifted, K, lifted.n
        D = lifted.D
        mapped = lambda D: D.map(f"{D.name()}_{K}", "serial", K, [1], [])   # p shared
        self._D = BufferedFunction(mapped(D), later_as(later, mapped))
        A = lifted.A
        self._A = None if A is None else BufferedFunction(
            ca.Function("A_dense", [A.mx_in(0)], [ca.densify(A(A.mx_in(0)))]))
        g, z = (np.asarray(a) for a in D.sparsity_out(0).get_triplet())
        self.groups = _groups(sp.csc_matrix(lifted.P), sp.csr_matrix(lifted.L), g, z)

    def __call__(self, x, p, v=None) -> np.ndarray:
        args = (x, p) if v is None else (x, p, v)
        nz = self._D(*args)[0].reshape(self.K, -1)       # (K, nnz of D)
        out = np.zeros((self.K, self.n, self.n))
        if self._A is not None:
            out += self._A(p)[0].reshape(self.n, self.n, order="F")   # dense A, CCS order
        for entries, rows, cols, products in self.groups:
            block = nz[:, entries] @ products
            out[:, rows, cols] += block.reshape(self.K, rows.size, cols.shape[1])
        return out


def _groups(P: sp.csc_matrix, L: sp.csr_matrix, g: np.ndarray, z: np.ndarray) -> list:
    """``(entries, rows, cols, products)`` per group of the nonzeros ``(g_e, z_e)`` of D
    with the same nonzero rows of ``P[:, g_e]`` and columns of ``L[z_e, :]``;
    ``products[e, (r, c)] = P[r, g_e] L[z_e, c]`` and ``rows`` (r x 1), ``cols``
    (1 x c) index the output block."""
    keys: dict = {}
    for e, (ge, ze) in enumerate(zip(g, z)):
        r = P.indices[P.indptr[ge]:P.indptr[ge + 1]]
        c = L.indices[L.indptr[ze]:L.indptr[ze + 1]]
        if r.size and c.size:
            keys.setdefault((tuple(np.sort(r)), tuple(np.sort(c))), []).append(e)
    groups = []
    Pd, Ld = P.toarray(), L.toarray()
    for (r, c), entries in keys.items():
        r, c, entries = np.array(r), np.array(c), np.array(entries)
        products = np.einsum("re,ec->erc", Pd[np.ix_(r, g[entries])], Ld[np.ix_(z[entries], c)])
        groups.append((entries, r[:, None], c[None, :], products.reshape(entries.size, -1)))
    return groups
