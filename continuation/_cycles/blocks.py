"""Collocation residual and sparse Jacobian assembled from pointwise blocks.

The collocation equations of ``collocation`` at the Gauss point ``k`` of
interval ``i`` read (``u_l = u_{i,l}`` the ``NCOL + 1`` node values)

    r_ik = M(u_k, p) u'_k - h_i T F(u_k, p),
    u_k = sum_l P[k, l] u_l,      u'_k = sum_l Dm[k, l] u_l,

so their exact derivatives only need the vector field and its Jacobians at the
``K = NTST NCOL`` collocation points (as AUTO-07p and BifurcationKit assemble them):

    d r_ik / d u_l = (d(M v)/dx |_(u_k, v = u'_k) - h_i T F_x(u_k)) P[k, l] + M(u_k) Dm[k, l],
    d r_ik / d T   = -h_i F(u_k),
    d r_ik / d p   = d(M v)/dp |_(u_k, v = u'_k) - h_i T F_p(u_k),

and the phase row ``c . U`` has the derivative ``c``. ``interval_jacobian`` gives the
same matrix by interval blocks for the condensed Newton solver (``condensed``). One
mapped CasADi call evaluates ``F, M v, F_x, d(M v)/dx, M, F_p, d(M v)/dp`` at all points
(the matrix blocks on the union ``S`` of their structural patterns); the matrix is
assembled by NumPy on a sparsity pattern fixed per ``(NTST, NCOL)``: the CSC index
arrays and the permutation from the assembly order to CSC order are computed once, each
Jacobian is one kernel call, two broadcasts, one ``np.take`` and one CSC construction.
``F_p`` and ``d(M v)/dp`` are only evaluated in the free parameter directions. The
kernel runs in CasADi's virtual machine or as compiled C (``CollocationSettings.backend``,
see :class:`PointKernel`).
"""

from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np
import scipy.sparse as sp

from .collocation import collocation
from .condensed import CollocationJacobian
from .intervals import KINEMATIC_MIN_ROWS, PointwiseTerm, interval_band, kinematic_rows
from .._linalg.sparse import Layout, layout
from .._casadi.lifted import LiftedBatch
from .._casadi.symbolic import (BufferedFunction, as_sx_function, compiled_later, later_as,
                                system)
from ..compilation import default_flags, has_compiler

#: outputs of the Jacobian kernel, in order
KERNEL_OUTPUTS = ("F", "Mv", "Fx", "Mvx", "M", "Fp", "Mvp")

#: 'auto' compiles an SX field's kernel when its values (F, M v) take at most this many
#: instructions (a Brusselator chain of 150 states; its kernels then compile in about
#: 3 s once, cached on disk, and run 1.05-1.3x faster than in the virtual machine)
SX_COMPILE_MAX = 2000

#: 'auto' compiles a function once it has taken this many seconds in the virtual machine
#: (a build takes ~1 s of a spare core, then saves 30-60 % of a call on the flutter model)
COMPILE_AFTER = 2.0


class Pointwise:
    """The single-point expressions of a VectorField in ``(x, v, p)``: ``F``, ``M v``,
    ``F_x``, ``d(M v)/dx``, ``M`` and the union ``pattern`` of the structural patterns
    of the three matrices (they are projected on it)."""

    def __init__(self, vf):
        S, n = vf.sym, vf.n
        self.n, self.n_par = n, len(vf.par_names)
        self.x, self.v, self.p = S.sym("x", n), S.sym("v", n), S.sym("p", self.n_par)
        self.f, m = vf.F_expr(self.x, self.p), vf.M_expr(self.x, self.p)
        self.mv = vf.Mv_expr(self.x, self.p, self.v)
        self.fx, self.mvx = vf.Fx_expr(self.x, self.p), vf.Mvx_expr(self.x, self.p, self.v)
        self.m = ca.sparsify(m) if S is ca.SX else m
        self.pattern = self.fx.sparsity().unite(self.mvx.sparsity()).unite(self.m.sparsity())

    def own_entries(self) -> dict:
        """Per matrix (``Fx``, ``Mvx``, ``M``), the places among the ``pattern``'s
        nonzeros of its own structural nonzeros (the others are zero)."""
        rows, cols = self.pattern.get_triplet()
        union = np.asarray(rows) * self.n + np.asarray(cols)
        out = {}
        for name, a in (("Fx", self.fx), ("Mvx", self.mvx), ("M", self.m)):
            r, c = a.sparsity().get_triplet()
            out[name] = np.flatnonzero(np.isin(union, np.asarray(r) * self.n + np.asarray(c)))
        return out

    def values(self) -> ca.Function:
        """``(x, v, p) -> (F, M v)``."""
        return ca.Function("colloc_point_values", [self.x, self.v, self.p], [self.f, self.mv])

    def jacobians(self, k: int, skip=()) -> ca.Function:
        """``(x, v, p, E) -> KERNEL_OUTPUTS`` with the parameter derivatives in the ``k``
        directions ``E`` (``n_par x k``; forward AD, ``vec`` of ``n x k`` each), without
        the matrices named in ``skip`` (evaluated elsewhere)."""
        nz = lambda a: ca.project(a, self.pattern).nz[:]
        E = type(self.x).sym("E", self.n_par, k)
        dp = lambda e: ca.vec(ca.densify(ca.jtimes(e, self.p, E))) if k else ca.DM(0, 1)
        outputs = dict(F=self.f, Mv=self.mv, Fx=nz(self.fx), Mvx=nz(self.mvx), M=nz(self.m),
                       Fp=dp(self.f), Mvp=dp(self.mv))
        return ca.Function(f"colloc_point_jacobians_{k}", [self.x, self.v, self.p, E],
                           [outputs[name] for name in KERNEL_OUTPUTS if name not in skip])


class PointKernel:
    """``(x[n x K], v[n x K], p) ->`` pointwise values at ``K`` points.

    ``values`` gives ``(F, M v)`` (each ``n x K``); ``jacobians(par_columns)`` gives
    ``KERNEL_OUTPUTS``: ``F, M v``, the nonzeros on the pattern ``rows, cols`` (``s``
    entries, CasADi CCS order) of ``F_x``, ``d(M v)/dx`` and ``M`` (each ``s x K``), and
    ``F_p``, ``d(M v)/dp`` in the directions ``par_columns`` (``vec`` of ``n x k``
    each, ``n k x K``), one function per number ``k`` of directions (the seed is an
    input, so one compiled library serves every single free parameter).

    ``backend`` 'mx': the single-point functions mapped over the points in CasADi's
    virtual machine (expanded to SX when the VectorField is SX); 'compiled': the
    single-point functions compiled to C (``continuation.compilation``, cached on disk
    independently of ``K``) and mapped; ``values`` too, since a corrector evaluates the
    residual at every iterate (the flutter model at N = 10: 0.40 ms against 0.84 ms in
    the virtual machine; N = 40: 2.5 against 3.4 ms). When a function cannot be compiled
    the kernel stays 'mx'. 'auto' loads what the cache holds and compiles the rest in the
    background once it pays (``COMPILE_AFTER``); 'compiled' builds before the first call.
    """

    def __init__(self, vf, K: int, backend: str = "mx", cache_dir=None):
        self.pointwise = Pointwise(vf)
        self.n, self.n_par, self.K = self.pointwise.n, self.pointwise.n_par, K
        rows, cols = self.pointwise.pattern.get_triplet()
        self.rows, self.cols = np.asarray(rows), np.asarray(cols)
        #: per matrix, its own nonzeros: ``(places among the pattern's, rows, cols)``
        #: (int64, for the compiled assembly; a constant mass has no ``Mvx`` entries)
        self.entries = {name: (e, self.rows[e].astype(np.int64), self.cols[e].astype(np.int64))
                        for name, e in self.pointwise.own_entries().items()}
        self.expand, self.cache_dir = vf.sym is ca.SX, cache_dir
        values = self.pointwise.values()
        self.backend, self.wait = _backend(backend, vf, values)   # 'mx' or 'compiled', bool
        self.lifted = {name: LiftedBatch(lifted, K, self._later(lifted.D))
                       for name, lifted in vf.lifted.items()}
        self.values = self._mapped(values)
        self._jacobians, self._seeded = {}, {}
        #: the kinematic rows of the dense interval matrices per NCOL (any mesh)
        self.kinematic: dict = {}

    def jacobians(self, par_columns) -> "SeededKernel":
        """The mapped Jacobian kernel with parameter directions ``par_columns`` (one
        function per number of directions, the directions are an input)."""
        cols = tuple(int(c) for c in par_columns)
        if cols not in self._seeded:
            if len(cols) not in self._jacobians:
                fun = self.pointwise.jacobians(len(cols), skip=tuple(self.lifted))
                self._jacobians[len(cols)] = self._mapped(fun)
            seed = np.eye(self.n_par)[:, list(cols)].ravel(order="F")
            self._seeded[cols] = SeededKernel(self._jacobians[len(cols)], seed,
                                              self._lifted_outputs)
        return self._seeded[cols]

    def _lifted_outputs(self, x, v, p, dense: bool = False) -> dict:
        """The lifted matrices at the points, on the pattern ``rows, cols`` (``K x s``),
        or ``dense`` (``K x n n``, row by row)."""
        args = {"Fx": (x, p), "M": (x, p), "Mvx": (x, p, v)}
        if dense:
            return {name: batch(*args[name]).reshape(self.K, -1)
                    for name, batch in self.lifted.items()}
        return {name: batch(*args[name])[:, self.rows, self.cols]
                for name, batch in self.lifted.items()}

    def _later(self, fun: ca.Function, flags=None, fallback=None):
        """None when the backend is 'mx', else :func:`compiled_later` of ``fun`` once it
        has taken ``COMPILE_AFTER`` seconds (the backend is 'mx' if it cannot be built)."""
        if self.backend != "compiled":
            return None
        return compiled_later(fun, self.cache_dir, flags, self.wait, COMPILE_AFTER, fallback,
                              failed=lambda: setattr(self, "backend", "mx"))

    def _mapped(self, fun: ca.Function) -> BufferedFunction:
        """``fun`` mapped over ``K`` columns of ``x, v`` (the other inputs shared).

        An SX field's map is compiled whole when the backend says so: the loop over the
        points runs in C, where CasADi's map of a compiled point pays a call of about the
        point's own cost at every point (the Brusselator chain's values at 200 points: 50
        against 4 us at 4 states, 166 against 77 us at 80; the library is then keyed by
        ``K`` too, and built with the flags of the SX point function). An MX field's
        point function is compiled once for every ``K`` and mapped (its dense products
        dwarf the call); without compiling, the map runs in the virtual machine
        (expanded to SX when the field is SX)."""
        fun = as_sx_function(fun) if self.expand else fun
        name, shared = fun.name() + f"_{self.K}", list(range(2, fun.n_in()))
        mapped = lambda f: f.map(name, "serial", self.K, shared, [])
        if self.expand:
            whole, vm = mapped(fun), as_sx_function(mapped(fun))
            return BufferedFunction(vm, self._later(whole, default_flags(fun), vm))
        return BufferedFunction(mapped(fun), later_as(self._later(fun), mapped))

    def evaluate(self, fun, x, v, p, **kw) -> list:
        """Outputs of ``fun`` at points ``x, v`` (``(K, n)`` each) as ``(K, size)`` arrays."""
        out = fun(x, v, p, **kw)
        return [o.reshape(self.K, -1) for o in out]


class SeededKernel:
    """A mapped Jacobian kernel called as ``(x, v, p)`` with its seed ``E`` bound; the
    matrices that ``lifted(x, v, p)`` returns (by name) are merged into its outputs."""

    def __init__(self, fun: BufferedFunction, seed: np.ndarray, lifted=None):
        self.fun, self.seed, self.lifted = fun, seed, lifted

    def __call__(self, x, v, p, dense: bool = False) -> list:
        """``KERNEL_OUTPUTS``; with ``dense`` the lifted matrices come dense (``K x n n``)."""
        out = iter(self.fun(x, v, p, self.seed))
        extra = self.lifted(x, v, p, dense) if self.lifted is not None else {}
        return [extra[name] if name in extra else next(out) for name in KERNEL_OUTPUTS]


def _backend(backend: str, vf, values: ca.Function) -> tuple:
    """``(backend, wait)`` for ``vf``: 'auto' is 'compiled' in the background (not
    ``wait``) for MX fields (dense modal blocks, where C pays) and for SX fields whose
    ``values`` (F, M v) take at most ``SX_COMPILE_MAX`` instructions (small straight-line
    code), 'mx' for larger SX fields; 'compiled' waits for the compiler (needs one)."""
    wait = backend == "compiled"
    if backend == "auto":
        small = vf.sym is ca.MX or values.n_instructions() <= SX_COMPILE_MAX
        backend = "compiled" if small else "mx"
    return (backend if backend == "mx" or has_compiler() else "mx"), wait


def point_kernel(vf, K: int, backend: str = "mx") -> PointKernel:
    """The pointwise kernel of ``vf`` at ``K`` points (see :class:`PointKernel`)."""
    return PointKernel(vf, K, backend)


def entries(n: int, ntst: int, ncol: int, prow: np.ndarray, pcol: np.ndarray,
            n_par: int):
    """Rows and columns of ``[G_U, G_T, G_p]`` in assembly order: interval blocks
    ``(i, k, l, s)``, the ``T`` column, the phase row ``c``, then ``n_par`` dense
    parameter columns (collocation rows only). Row of ``(i, k, a)`` is
    ``(i NCOL + k) n + a``; column of node ``(i, l)``, component ``b`` is
    ``((i NCOL + l) mod K) n + b``."""
    K = ntst * ncol
    N = n * K
    i, k, l = np.meshgrid(np.arange(ntst), np.arange(ncol), np.arange(ncol + 1),
                          indexing="ij")
    point = (i * ncol + k)[..., None]
    node = ((i * ncol + l) % K)[..., None]
    rows = [np.broadcast_to(point * n + prow, point.shape[:3] + prow.shape).ravel()]
    cols = [np.broadcast_to(node * n + pcol, node.shape[:3] + pcol.shape).ravel()]
    rows += [np.arange(N), np.full(N, N)]
    cols += [np.full(N, N), np.arange(N)]
    for q in range(n_par):
        rows.append(np.arange(N))
        cols.append(np.full(N, N + 1 + q))
    return np.concatenate(rows), np.concatenate(cols)


class BlockCollocationSystem:
    """The collocation system ``G(Y, p; D)``, ``Y = (U, T)``, ``D = (h, c)``, with the
    interface of ``CompiledSystem`` (``residual``, ``jacobian``, ``n_state``,
    ``n_equations``, ``pattern``), evaluated by pointwise blocks.

    Parameters
    ----------
    kernel : the :class:`PointKernel` of the vector field at ``NTST NCOL`` points.
    ntst, ncol : mesh intervals and collocation points per interval.
    """

    def __init__(self, kernel: PointKernel, ntst: int, ncol: int):
        if kernel.K != ntst * ncol:
            raise ValueError(f"kernel has {kernel.K} points, need ntst * ncol = "
                             f"{ntst * ncol}")
        self.kernel, self.ntst, self.ncol = kernel, ntst, ncol
        self.col = collocation(ncol)
        #: ``P[k, l]`` and ``Dm[k, l]`` of every collocation point ``i NCOL + k``
        self._weights = (np.tile(self.col.P, (ntst, 1)), np.tile(self.col.Dm, (ntst, 1)))
        self._points = _points_operator(self.col.P, self.col.Dm, kernel.n, ntst, ncol)
        self.n_state = self.n_equations = kernel.n * ntst * ncol + 1
        self._layouts: dict = {}
        #: the interval matrices' band (on the pattern; lifted matrices come dense)
        self.band = None if kernel.lifted else interval_band(kernel.n, ncol, kernel.rows,
                                                             kernel.cols)
        base = self._layout(0)
        self.pattern = ((self.n_equations, self.n_state), base.indptr, base.indices)

    def _layout(self, n_par: int) -> Layout:
        """The layout of ``[G_Y, G_p[:, cols]]`` with ``n_par`` columns, built once."""
        if n_par not in self._layouts:
            kr = self.kernel
            rows, cols = entries(kr.n, self.ntst, self.ncol, kr.rows, kr.cols, n_par)
            shape = (self.n_equations, self.n_state + n_par)
            self._layouts[n_par] = layout(rows, cols, shape)
        return self._layouts[n_par]

    def _split(self, Y, D):
        """``U, T, h, c`` and the per-point ``h_i`` (length ``K``)."""
        N = self.n_state - 1
        U, T = np.asarray(Y[:N], dtype=float), float(Y[N])
        h, c = np.asarray(D[:self.ntst], dtype=float), np.asarray(D[self.ntst:], dtype=float)
        return U, T, h, c, np.repeat(h, self.ncol)

    def points(self, U) -> tuple:
        """``(u_k, u'_k)`` at the ``K`` collocation points, each ``(K, n)``:
        ``u_k = sum_l P[k, l] u_l``, ``u'_k = sum_l Dm[k, l] u_l``."""
        x, v = (self._points @ np.asarray(U, dtype=float)).reshape(2, -1, self.kernel.n)
        return x, v

    def residual(self, Y, P, D) -> np.ndarray:
        """``G = (vec(M(u_k) u'_k - h_i T F(u_k)), c . U)``."""
        U, T, h, c, hk = self._split(Y, D)
        x, v = self.points(U)
        F, Mv = self.kernel.evaluate(self.kernel.values, x, v, P)
        out = np.empty(self.n_equations)
        np.subtract(Mv, (hk * T)[:, None] * F, out=out[:-1].reshape(F.shape))
        out[-1] = c @ U
        return out

    def _pointwise(self, Y, P, D, par_columns) -> tuple:
        """``(hk, c, F, W, M, Gp)`` at the collocation points: ``W = d(M v)/dx - h T F_x``
        and ``M`` on the pattern (``K x s``), ``Gp = d(M v)/dp - h T F_p`` in the
        directions ``par_columns`` (``K x k x n``)."""
        U, T, h, c, hk = self._split(Y, D)
        x, v = self.points(U)
        kr, cols = self.kernel, tuple(par_columns)
        F, Mv, Fx, Mvx, M, Fp, Mvp = kr.evaluate(kr.jacobians(cols), x, v, P)
        W = Mvx - (hk * T)[:, None] * Fx
        Gp = (Mvp - (hk * T)[:, None] * Fp).reshape(kr.K, len(cols), kr.n)
        return hk, c, F, W, M, Gp

    def jacobian(self, Y, P, D, par_columns) -> sp.csc_matrix:
        """``[G_Y, G_p[:, par_columns]]`` as one sparse matrix (see the module doc)."""
        hk, c, F, W, M, Gp = self._pointwise(Y, P, D, par_columns)
        W, Mb = (a.reshape(self.ntst, self.ncol, -1) for a in (W, M))
        blocks = np.einsum("iks,kl->ikls", W, self.col.P) + \
            np.einsum("iks,kl->ikls", Mb, self.col.Dm)
        vals = np.concatenate([blocks.ravel(), (-hk[:, None] * F).ravel(), c,
                               Gp.transpose(1, 0, 2).ravel()])
        return self._layout(Gp.shape[1]).matrix(vals)

    def interval_jacobian(self, Y, P, D, par_columns) -> CollocationJacobian:
        """The same matrix by interval blocks (``condensed``): block ``(k, l)`` of
        interval ``i`` is ``W_ik P[k, l] + M_ik Dm[k, l]``, kept as its pointwise terms
        (each matrix on its own pattern), which the factorization assembles into the
        layout it needs (dense or banded)."""
        U, T, h, c, hk = self._split(Y, D)
        x, v = self.points(U)
        kr, cols = self.kernel, tuple(par_columns)
        F, Mv, Fx, Mvx, M, Fp, Mvp = kr.evaluate(kr.jacobians(cols), x, v, P, dense=True)
        n, ntst, ncol = kr.n, self.ntst, self.ncol
        m = n * ncol
        Pk, Dk = self._weights
        terms = []
        for name, values, weights in (("Fx", Fx, Pk * (-hk * T)[:, None]), ("Mvx", Mvx, Pk),
                                      ("M", M, Dk)):
            if name in kr.lifted:                # dense, row by row
                terms.append(PointwiseTerm(values, weights))
            elif kr.entries[name][0].size:
                own, prow, pcol = kr.entries[name]
                if own.size < values.shape[1]:
                    values = values[:, own]
                terms.append(PointwiseTerm(values, weights, prow, pcol))
        Gp = (Mvp - (hk * T)[:, None] * Fp).reshape(kr.K, len(cols), n)
        extra = np.concatenate([(-hk[:, None] * F)[:, :, None], Gp.transpose(0, 2, 1)], axis=2)
        J = CollocationJacobian(n, ntst, ncol, tuple(terms), extra.reshape(ntst, m, -1), c,
                                self.band)
        return J if self.band is not None or m <= KINEMATIC_MIN_ROWS else \
            replace(J, kinematic=self._kinematic_rows(J))

    def _kinematic_rows(self, J: CollocationJacobian):
        """The kinematic rows of dense interval matrices, read once per kernel and NCOL
        from the first Jacobian's (``intervals.kinematic_rows``; checked at every LU)."""
        if self.ncol not in self.kernel.kinematic:
            self.kernel.kinematic[self.ncol] = kinematic_rows(J.blocks, self.col.Dm)
        return self.kernel.kinematic[self.ncol]

    def fill(self) -> float:
        """Nonzero fraction of the interval blocks (of the pointwise pattern in ``n x n``)."""
        return self.kernel.rows.size / self.kernel.n ** 2


def builder(ntst: int, ncol: int, backend: str = "mx"):
    """``builder(vf) -> BlockCollocationSystem``; the pointwise kernel is built once
    per VectorField, number of points ``NTST NCOL`` and backend ('mx' or 'compiled',
    cached with its systems)."""
    def build(vf) -> BlockCollocationSystem:
        K = ntst * ncol
        kernel = system(vf, f"collocation_points_{K}_{backend}",
                        lambda vf: point_kernel(vf, K, backend))
        return BlockCollocationSystem(kernel, ntst, ncol)

    return build


def _points_operator(P, Dm, n: int, ntst: int, ncol: int) -> sp.csr_matrix:
    """The sparse ``(2 K n, K n)`` operator of :meth:`BlockCollocationSystem.points`:
    ``x_ik = sum_l P[k, l] u_(i, l)`` over ``v_ik = sum_l Dm[k, l] u_(i, l)`` at the ``K =
    NTST NCOL`` points (node ``(i, NCOL)`` is ``(i + 1, 0)``, wrapping)."""
    K = ntst * ncol
    w, i, k, l, a = np.meshgrid(np.arange(2), np.arange(ntst), np.arange(ncol),
                                np.arange(ncol + 1), np.arange(n), indexing="ij")
    rows = ((w * K + i * ncol + k) * n + a).ravel()
    cols = (((i * ncol + l) % K) * n + a).ravel()
    values = np.stack([P, Dm])[w, k, l].ravel()
    return sp.csr_matrix((values, (rows, cols)), shape=(2 * K * n, K * n))
