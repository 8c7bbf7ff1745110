"""The vector field ``M(x, p) xdot = F(x, p)`` and its exact derivatives.

``F`` and ``M`` are CasADi functions of ``(x, p)``; ``M = None`` means the
identity. All derivatives are obtained by CasADi algorithmic differentiation:

* ``J = dF/dx`` (sparse), ``F_p = dF/dp``;
* the multilinear forms used by normal-form coefficients,
  ``F2(u, v) = D_x^2 F[u, v]``, ``F3(u, v, w) = D_x^3 F[u, v, w]``,
  ``M1(u) y = (D_x M[u]) y`` and ``M2(u, v) y = (D_x^2 M[u, v]) y``.

Every problem takes its field, parameter values and start state from the user through
:func:`make_field`, :func:`param_vector` and :func:`state_vector`.
"""

from __future__ import annotations

from functools import cached_property
from typing import Mapping

import casadi as ca
import numpy as np
import scipy.sparse as sp

from .lifted import Lifted
from .symbolic import BufferedFunction, as_sx_function, symbol_class, to_csc


def _check_function(fun, label: str, n_out_rows: int | None, n_out_cols: int):
    if not isinstance(fun, ca.Function):
        raise ValueError(f"{label} must be a casadi.Function, got {type(fun).__name__}")
    if fun.n_in() != 2 or fun.n_out() != 1:
        raise ValueError(f"{label} must map (x, p) to one output, has "
                         f"{fun.n_in()} inputs and {fun.n_out()} outputs")
    rows, cols = fun.size1_out(0), fun.size2_out(0)
    if cols != n_out_cols or (n_out_rows is not None and rows != n_out_rows):
        raise ValueError(f"{label} output has shape ({rows}, {cols}), expected "
                         f"({n_out_rows if n_out_rows is not None else 'n'}, {n_out_cols})")


def _checked_jacobian(fun, n: int, n_in: int, label: str) -> ca.Function:
    """``fun`` if it maps ``n_in`` inputs (x[n], p[, v[n]]) to an ``n x n`` matrix."""
    if not isinstance(fun, ca.Function) or fun.n_in() != n_in or fun.n_out() != 1:
        raise ValueError(f"{label} must be a casadi.Function of {n_in} inputs with one output")
    if fun.size_in(0) != (n, 1) or fun.size_out(0) != (n, n):
        raise ValueError(f"{label} must map x[{n}] to an {n} x {n} matrix, "
                         f"got {fun.size_in(0)} -> {fun.size_out(0)}")
    return fun


def _checked_mass_action(fun, M, n: int) -> ca.Function:
    """``fun`` if it maps ``(x[n], p, v[n])`` to a column ``M v`` of size n (with ``M``)."""
    if M is None:
        raise ValueError("mass_action needs a mass matrix M (it is M(x, p) v)")
    if not isinstance(fun, ca.Function) or fun.n_in() != 3 or fun.n_out() != 1:
        raise ValueError("mass_action must be a casadi.Function (x, p, v) -> M(x, p) v")
    if fun.size_in(0) != (n, 1) or fun.size_in(2) != (n, 1) or fun.size_out(0) != (n, 1):
        raise ValueError(f"mass_action must map x[{n}], p, v[{n}] to a column of size {n}")
    return fun


class VectorField:
    """``M(x, p) xdot = F(x, p)`` with named parameters, compiled once.

    Parameters
    ----------
    F : casadi.Function ``(x[n], p[k]) -> F[n]``.
    M : casadi.Function ``(x[n], p[k]) -> M[n x n]`` or ``None`` (identity).
    par_names : the ``k`` names of the entries of ``p``, in order.
    expand : expand MX functions to SX (default). SX is fastest for scalar-heavy
        problems; keep MX (``expand=False``) for functions built from dense matrix
        blocks, whose SX expansion multiplies every product out (for a 42-state modal
        model, the Hopf-system Jacobian builds in 0.1 s as MX and 4 s as SX).
    mass_action : optional casadi.Function ``(x, p, v) -> M(x, p) v`` computed without
        forming ``M`` (it must equal ``M v``). Collocation kernels and normal forms then
        differentiate it instead of ``M(x, p) v``: for a modal model whose ``M`` is a sum
        of dense ``N x K x N`` products the matrix-free product is O(N K).
    jacobian : optional casadi.Function ``(x, p) -> dF/dx`` (it must equal the
        derivative of ``F``), used wherever ``dF/dx`` itself is evaluated (``jac_x``, the
        collocation kernels, the Hopf systems) instead of AD of ``F``: for a model whose
        state enters its nonlinear terms through a few linear combinations (a Galerkin or
        modal model) the chain rule through them is several times cheaper.
    mass_action_jacobian : optional casadi.Function ``(x, p, v) -> d(M v)/dx`` (needs
        ``mass_action``), likewise.

    ``M``, ``jacobian`` and ``mass_action_jacobian`` may also be given as
    :class:`Lifted` (``A(p) + P D L``): they are then used as their CasADi functions, and
    the collocation kernel evaluates them at all collocation points at once by dense
    products (``lifted.LiftedBatch``). ``lifted`` holds them by kernel output name
    (``"M"``, ``"Fx"``, ``"Mvx"``).
    """

    def __init__(self, F: ca.Function, M: ca.Function | None, par_names, expand: bool = True,
                 mass_action: ca.Function | None = None, jacobian: ca.Function | None = None,
                 mass_action_jacobian: ca.Function | None = None):
        par_names = tuple(str(s) for s in par_names)
        self.lifted = {}
        M, jacobian, mass_action_jacobian = (
            self._unlifted(key, obj) for key, obj in
            (("M", M), ("Fx", jacobian), ("Mvx", mass_action_jacobian)))
        _check_function(F, "F", None, 1)
        n = F.size1_in(0)
        if F.size2_in(0) != 1 or F.size1_out(0) != n:
            raise ValueError(f"F must map x[{n}] to a column of size {n}, "
                             f"got output {F.size_out(0)}")
        if F.numel_in(1) != len(par_names):
            raise ValueError(f"par_names has {len(par_names)} names but F takes "
                             f"p of size {F.numel_in(1)}")
        if len(set(par_names)) != len(par_names):
            raise ValueError(f"par_names must be unique, got {par_names}")
        if M is not None:
            _check_function(M, "M", n, n)
        keep = (lambda f: f) if not expand else as_sx_function
        self.F = keep(F)
        self.M = None if M is None else keep(M)
        self.mass_action = None if mass_action is None else \
            keep(_checked_mass_action(mass_action, M, n))
        self.jacobian = None if jacobian is None else keep(_checked_jacobian(jacobian, n, 2, "jacobian"))
        if mass_action_jacobian is not None and mass_action is None:
            raise ValueError("mass_action_jacobian needs mass_action")
        self.mass_action_jacobian = None if mass_action_jacobian is None else \
            keep(_checked_jacobian(mass_action_jacobian, n, 3, "mass_action_jacobian"))
        self.n = n
        self.par_names = par_names
        funs = (self.F,) if self.M is None else (self.F, self.M)
        self.sym = symbol_class(*funs)
        self._x = self.sym.sym("x", n)
        self._p = self.sym.sym("p", len(par_names))

    def _unlifted(self, key: str, obj):
        """The CasADi function of ``obj``; a :class:`Lifted` is also kept in ``lifted``."""
        if isinstance(obj, Lifted):
            self.lifted[key] = obj
            return obj.function(key)
        return obj

    # ---- symbolic building blocks (used by augmented problems) -------------
    def F_expr(self, x, p):
        """Symbolic ``F(x, p)``."""
        return self.F(x, p)

    def M_expr(self, x, p):
        """Symbolic ``M(x, p)`` (identity when no mass matrix is given)."""
        return self.sym.eye(self.n) if self.M is None else self.M(x, p)

    def Mv_expr(self, x, p, v):
        """Symbolic ``M(x, p) v``: the ``mass_action`` when given (cheaper to
        differentiate), else the product with :meth:`M_expr`."""
        if self.mass_action is not None:
            return self.mass_action(x, p, v)
        return ca.mtimes(self.M_expr(x, p), v)

    def Fx_expr(self, x, p):
        """Symbolic ``dF/dx``: the given ``jacobian``, else AD of ``F``."""
        if self.jacobian is not None:
            return self.jacobian(x, p)
        return ca.jacobian(self.F_expr(x, p), x)

    def Mvx_expr(self, x, p, v):
        """Symbolic ``d(M v)/dx``: the given ``mass_action_jacobian``, else AD of ``M v``."""
        if self.mass_action_jacobian is not None:
            return self.mass_action_jacobian(x, p, v)
        return ca.jacobian(self.Mv_expr(x, p, v), x)

    @cached_property
    def mass_depends_on_state(self) -> bool:
        """True when ``M`` depends on ``x`` (its derivatives enter normal forms)."""
        return self.M is not None and bool(ca.depends_on(self.M(self._x, self._p), self._x))

    def par_index(self, name: str) -> int:
        """Position of parameter ``name`` in ``p``; ValueError if unknown."""
        if name not in self.par_names:
            raise ValueError(f"unknown parameter {name!r}; known: {self.par_names}")
        return self.par_names.index(name)

    # ---- compiled numeric functions ----------------------------------------
    @cached_property
    def _funs(self):
        x, p = self._x, self._p
        f = self.F(x, p)
        jx, jp = self.Fx_expr(x, p), ca.jacobian(f, p)
        m = self.M_expr(x, p)
        m = self.sym(ca.sparsify(m)) if self.sym is ca.SX else m
        pat = lambda a: ((a.size1(), a.size2()), *map(np.asarray, a.sparsity().get_ccs()))
        buffered = lambda name, out: BufferedFunction(ca.Function(name, [x, p], [out]))
        return {
            "F": buffered("F_num", f),
            "Jx": buffered("Jx", jx.nz[:]), "Jx_pat": pat(jx),
            "Jp": buffered("Jp", ca.densify(jp)),
            "M": buffered("M_num", m.nz[:]), "M_pat": pat(m),
        }

    def rhs(self, x, p) -> np.ndarray:
        """``F(x, p)``."""
        return self._funs["F"](x, p)[0]

    def jac_x(self, x, p) -> sp.csc_matrix:
        """Exact sparse ``J = dF/dx``."""
        return to_csc(self._funs["Jx"](x, p)[0], self._funs["Jx_pat"])

    def jac_p(self, x, p) -> np.ndarray:
        """Exact dense ``dF/dp`` of shape ``(n, k)``."""
        return self._funs["Jp"](x, p)[0].reshape(self.n, len(self.par_names), order="F")

    def mass(self, x, p) -> sp.csc_matrix:
        """Sparse ``M(x, p)`` (identity if none was given)."""
        if self.M is None:
            return sp.identity(self.n, format="csc")
        return to_csc(self._funs["M"](x, p)[0], self._funs["M_pat"])

    # ---- multilinear forms for normal forms --------------------------------
    @cached_property
    def _forms(self):
        S, n = self.sym, self.n
        x, p = self._x, self._p
        u, v, w, y = (S.sym(s, n) for s in "uvwy")
        f = self.F(x, p)
        f2 = ca.jtimes(ca.jtimes(f, x, u), x, v)
        f3 = ca.jtimes(f2, x, w)
        my = self.Mv_expr(x, p, y)
        m1 = ca.jtimes(my, x, u)
        m2 = ca.jtimes(m1, x, v)
        return {
            "F2": ca.Function("F2", [x, p, u, v], [f2]),
            "F3": ca.Function("F3", [x, p, u, v, w], [f3]),
            "M1": ca.Function("M1", [x, p, u, y], [m1]),
            "M2": ca.Function("M2", [x, p, u, v, y], [m2]),
        }

    @cached_property
    def _reduced_forms(self):
        """``H2 .. H5``: the derivatives at ``x`` of ``h(y) = M(x) M(y)^{-1} F(y)`` (so
        that ``M(x) ydot = h(y)`` has the constant mass of the point and the same flow);
        ``h = F`` when ``M`` does not depend on the state, else ``M(y)^{-1}`` is a
        symbolic solve (small systems)."""
        S, n = self.sym, self.n
        x, p, y = self._x, self._p, S.sym("y", n)
        if self.mass_depends_on_state:
            h = ca.mtimes(self.M_expr(x, p), ca.solve(self.M_expr(y, p), self.F(y, p)))
        else:
            h = self.F(y, p)
        args, out, forms = [], h, {}
        for k in range(1, 6):
            args.append(S.sym(f"v{k}", n))
            out = ca.jtimes(out, y, args[-1])
            if k >= 2:
                forms[f"H{k}"] = ca.Function(f"H{k}", [x, p, *args],
                                             [ca.substitute(out, y, x)])
        return forms

    def second_derivative(self, x, p, u, w) -> np.ndarray:
        """``d^2/de^2 F(x + e u, p + e w)`` at ``e = 0`` (CasADi AD; compiled once)."""
        if "_second" not in self.__dict__:
            x_, p_ = self._x, self._p
            u_, w_ = self.sym.sym("u", self.n), self.sym.sym("w", len(self.par_names))
            along = lambda g: ca.jtimes(g, x_, u_) + ca.jtimes(g, p_, w_)
            self._second = BufferedFunction(ca.Function(
                "F_XX", [x_, p_, u_, w_], [ca.densify(along(along(self.F(x_, p_))))]))
        return self._second(x, p, u, w)[0]

    def form(self, name: str, x, p, *vectors) -> np.ndarray:
        """Evaluate a real multilinear form ``F2, F3, M1, M2`` (or ``H2 .. H5`` of
        :attr:`_reduced_forms`) on complex vectors.

        Complex arguments are expanded by multilinearity into real evaluations
        (``f(u_r + i u_i, ...) = Σ i^k f(real or imaginary parts)``), all of them in
        one mapped call of the form.
        """
        coefs, columns = _real_expansion(vectors)
        flat = [c.ravel(order="F") for c in columns]                # CasADi: column-major
        out = self._mapped_form(name, len(coefs))(x, p, *flat)[0]
        return out.reshape(self.n, len(coefs), order="F") @ coefs

    def _mapped_form(self, name: str, count: int) -> BufferedFunction:
        """``self._forms[name].map(count)`` (dense output), built once per (name, count)."""
        key = (name, count)
        cache = self.__dict__.setdefault("_mapped_forms", {})
        if key not in cache:
            form = self._forms[name] if name in ("F2", "F3", "M1", "M2") \
                else self._reduced_forms[name]
            x, p = ca.MX.sym("x", self.n), ca.MX.sym("p", len(self.par_names))
            columns = [ca.MX.sym(f"v{i}", self.n, count) for i in range(form.n_in() - 2)]
            out = ca.densify(form.map(count)(x, p, *columns))      # x, p broadcast
            cache[key] = BufferedFunction(ca.Function(f"{name}_{count}", [x, p, *columns], [out]))
        return cache[key]


def _real_expansion(vectors) -> tuple[np.ndarray, list]:
    """Coefficients ``c_j`` and real argument columns with ``f(z_1..z_k) = Σ_j c_j
    f(columns[:, j])`` for a real multilinear ``f`` (imaginary parts only where nonzero)."""
    terms = [(1.0 + 0j, [])]
    for z in vectors:
        z = np.asarray(z)
        parts = [(1.0, z.real)] + ([(1j, z.imag)] if np.any(z.imag) else [])
        terms = [(c * a, args + [part]) for c, args in terms for a, part in parts]
    coefs = np.array([c for c, _ in terms])
    columns = [np.column_stack([args[i] for _, args in terms]).astype(float)
               for i in range(len(vectors))]
    return coefs, columns


def make_field(F, M, params: Mapping[str, float]) -> VectorField:
    """``F`` itself if it is a VectorField, else ``VectorField(F, M, names)``."""
    if isinstance(F, VectorField):
        if M is not None:
            raise ValueError("M must be None when F is already a VectorField")
        return F
    if not isinstance(params, Mapping):
        raise ValueError(f"params must be a mapping name -> value, got {type(params).__name__}")
    if isinstance(F, ca.Function) and F.n_in() == 2 and F.numel_in(1) != len(params):
        raise ValueError(f"params names {tuple(params)} but F takes p of size "
                         f"{F.numel_in(1)}")
    return VectorField(F, M, tuple(params))


def param_vector(vf: VectorField, params: Mapping[str, float]) -> np.ndarray:
    """Values of ``params`` in the order of ``vf.par_names``; all must be given."""
    if not isinstance(params, Mapping):
        raise ValueError(f"params must be a mapping name -> value, got {type(params).__name__}")
    if set(params) != set(vf.par_names):
        raise ValueError(f"params must name exactly {vf.par_names}, got {tuple(params)}")
    p = np.array([float(params[k]) for k in vf.par_names])
    if not np.all(np.isfinite(p)):
        raise ValueError(f"params must be finite, got {dict(params)}")
    return p


def state_vector(vf: VectorField, x0, label: str = "x0") -> np.ndarray:
    """``x0`` as a finite float vector of size ``n``."""
    x = np.array(x0, dtype=float).ravel()
    if x.size != vf.n or not np.all(np.isfinite(x)):
        raise ValueError(f"{label} must be a finite vector of size {vf.n}, got {x0!r}")
    return x
