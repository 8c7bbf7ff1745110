"""CasADi layer: symbolic types, compiled residuals and their exact sparse Jacobians.

Every continued problem is reduced here to one residual ``G(X) = 0`` with
``G: R^(m+1) -> R^m``, compiled once together with its exact sparse Jacobian
``G_X`` (CasADi algorithmic differentiation). Numerical code only sees NumPy
arrays and ``scipy.sparse.csc_matrix``.
"""

from __future__ import annotations

import time

import casadi as ca
import numpy as np
import scipy.sparse as sp

from .._linalg.sparse import columns_appended
from ..compilation import compile_later


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


class BufferedFunction:
    """Call a CasADi Function through its zero-copy buffer: the arguments are copied
    into fixed NumPy arrays and the outputs' nonzeros written into NumPy arrays, with
    no DM conversion (3-5x faster than ``fun(...).full()`` for ~1e5 nonzeros). Errors
    raise ``RuntimeError`` as a plain call does. Returns copies of the outputs.

    ``later``: None, or a callable of the seconds spent so far in calls of ``fun`` that
    gives None until an equivalent function is ready (compiled C,
    ``continuation.compilation.compile_later``), then the function to call from then on;
    it is asked before each call until it gives one."""

    def __init__(self, fun: ca.Function, later=None):
        self.fun, self.later = fun, later
        self._buffer, self.spent = None, 0.0

    def __call__(self, *args) -> list:
        if self.later is not None:
            self._switch()
        if self._buffer is None:
            self._open()
        for a, x in zip(self._args, args):
            a[:] = np.ravel(x)
        start = time.perf_counter()
        self._eval()
        self.spent += time.perf_counter() - start
        return [r.copy() for r in self._res]

    def _open(self):
        f = self.fun
        self._buffer, self._eval = f.buffer()
        self._args = [np.zeros(f.nnz_in(i)) for i in range(f.n_in())]
        self._res = [np.zeros(f.nnz_out(i)) for i in range(f.n_out())]
        for i, a in enumerate(self._args):
            self._buffer.set_arg(i, memoryview(a))
        for i, r in enumerate(self._res):
            self._buffer.set_res(i, memoryview(r))

    def _switch(self):
        fun = self.later(self.spent)
        if fun is not None:
            self.fun, self.later, self._buffer = fun, None, None

    def __getstate__(self):
        return {"fun": self.fun, "later": None, "spent": 0.0, "_buffer": None}


def compiled_later(fun: ca.Function, cache_dir=None, flags=None, wait: bool = False,
                   after: float = 0.0, fallback=None, failed=None):
    """The ``later`` of a :class:`BufferedFunction` that evaluates ``fun`` (or
    ``fallback``): None until ``fun``, once its calls have taken ``after`` seconds, is
    compiled in the background (``continuation.compilation.compile_later``; loaded at
    once when the cache holds it, built before the first call with ``wait``), then the
    compiled function, or ``fallback`` (default ``fun``) if it could not be built (with
    a RuntimeWarning; ``failed()`` is called then)."""
    deferred = compile_later(fun, cache_dir, flags)
    if wait:
        try:
            deferred.wait()
        except (RuntimeError, OSError):
            pass                                      # poll warns and gives fun

    def later(spent: float):
        if not deferred.done and spent < after:
            return None                               # not worth a build (yet)
        ready = deferred.poll()
        if ready is None or deferred.compiled is not None:
            return ready
        if failed is not None:
            failed()
        return fun if fallback is None else fallback

    return later


def later_as(later, wrap):
    """``later`` (see :class:`BufferedFunction`) with ``wrap`` applied to the function it
    gives (e.g. a map over points), or None when ``later`` is None."""
    if later is None:
        return None
    return lambda spent: None if (fun := later(spent)) is None else wrap(fun)


def to_csc(values: np.ndarray, pattern: tuple) -> sp.csc_matrix:
    """Assemble a CSC matrix from CasADi nonzeros and a CCS pattern."""
    shape, colind, row = pattern
    return sp.csc_matrix((values, index_array(row), index_array(colind)), shape=shape)


def index_array(a) -> np.ndarray:
    """``a`` as int32 when its entries fit (scipy's CSC index type for such sizes: the
    constructor then skips a scan of the indices, 3x cheaper at a few thousand)."""
    a = np.asarray(a)
    if a.dtype == np.int32 or (a.size and a.max(initial=0) >= 2 ** 31 - 1):
        return a
    return a.astype(np.int32)


class CompiledSystem:
    """``G(Y, p; D)`` with exact Jacobians ``G_Y`` (sparse) and ``G_p``, compiled once.

    The continued unknowns are ``X = (Y, p_free)``: which parameters are free is
    chosen at evaluation time (columns of ``G_p``), so one compiled system per
    kind serves a one-parameter location and every two-parameter curve.

    Parameters
    ----------
    Y : CasADi symbol of the non-parameter unknowns.
    P : CasADi symbol of the full parameter vector.
    D : CasADi symbol of fixed data (reference vectors).
    G : residual expression, or a list of row blocks. Blocks are differentiated
        separately: a few dense rows (normalizations ``c.v = 1``) would otherwise
        defeat the graph colouring of the sparse Jacobian (seconds at n = 1000).
    name : used to name the CasADi functions.
    jacobians : optional ``(G_Y, G_p)`` expressions equal to the Jacobians of ``G``
        (e.g. written from the structure of an augmented system, much cheaper to
        evaluate than the AD of its second derivatives); default: AD of ``G``.
    """

    def __init__(self, Y, P, D, G, name: str = "G", jacobians=None):
        blocks = list(G) if isinstance(G, (list, tuple)) else [G]
        G = ca.vertcat(*blocks)
        if jacobians is None:
            jy = ca.vertcat(*[ca.jacobian(g, Y) for g in blocks])
            jp = ca.vertcat(*[ca.jacobian(g, P) for g in blocks])
        else:
            jy, jp = jacobians
        jp = ca.densify(jp)
        colind, row = jy.sparsity().get_ccs()
        self.pattern = ((G.numel(), Y.numel()), index_array(colind), index_array(row))
        self.n_state = Y.numel()
        self.n_equations = G.numel()
        self._g = BufferedFunction(ca.Function(name, [Y, P, D], [G]))
        self._jy = BufferedFunction(ca.Function(name + "_jac_y", [Y, P, D], [jy.nz[:]]))
        self._jp = BufferedFunction(ca.Function(name + "_jac_p", [Y, P, D], [jp]))

    def residual(self, Y, P, D) -> np.ndarray:
        """Residual ``G(Y, p; D)``."""
        return self._g(Y, P, D)[0]

    def jacobian(self, Y, P, D, par_columns) -> sp.csc_matrix:
        """``[G_Y, G_p[:, par_columns]]`` as one sparse matrix."""
        jp = self._jp(Y, P, D)[0].reshape(self.n_equations, -1, order="F")
        return columns_appended(self._jy(Y, P, D)[0], self.pattern, jp[:, list(par_columns)])


class BoundSystem:
    """A compiled system with fixed parameters/data and chosen free parameters.

    ``X = (Y, p_free)``; ``params(X)`` is ``p0`` with the free entries from X.
    """

    def __init__(self, compiled: CompiledSystem, p0, D, free_idx):
        self.compiled = compiled
        self.p0 = np.array(p0, dtype=float)
        self.D = np.array(D, dtype=float)
        self.free_idx = tuple(free_idx)
        self.n_unknowns = compiled.n_state + len(self.free_idx)

    def params(self, X) -> np.ndarray:
        p = self.p0.copy()
        p[list(self.free_idx)] = X[len(X) - len(self.free_idx):]
        return p

    def residual(self, X) -> np.ndarray:
        return self.compiled.residual(X[: self.compiled.n_state], self.params(X), self.D)

    def jacobian(self, X) -> sp.csc_matrix:
        return self.compiled.jacobian(X[: self.compiled.n_state], self.params(X), self.D,
                                      self.free_idx)


def system(vf, kind: str, builder) -> CompiledSystem:
    """The compiled system ``kind`` of the VectorField ``vf``, ``builder(vf)`` built once
    per field and kept on it (each problem kind names its own builder)."""
    cache = vf.__dict__.setdefault("_systems", {})
    if kind not in cache:
        cache[kind] = builder(vf)
    return cache[kind]


def bound(vf, kind: str, p0, D, free, builder) -> BoundSystem:
    """``system(vf, kind, builder)`` with parameters ``p0``, data ``D`` and ``free`` names."""
    return BoundSystem(system(vf, kind, builder), p0, D, tuple(vf.par_index(f) for f in free))
