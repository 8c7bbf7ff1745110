"""Augmented systems ``G(X; D) = 0`` built symbolically from a VectorField.

With ``J = dF/dx`` (as the directional derivative ``J v = d/de F(x + e v)``):

* equilibrium ``X = (x, p_free)``:  ``F(x, p) = 0``;
* fold (limit point) ``X = (x, v, p_free)``, ``D = c``:
  ``F = 0``, ``J v = 0``, ``c.v - 1 = 0``;
* Hopf ``X = (x, v, w, kappa, p_free)``, ``D = c``:
  ``F = 0``, ``J v - M w = 0``, ``J w + kappa M v = 0``, ``c.v - 1 = 0``,
  ``c.w = 0``. Then ``(M^{-1}J)^2 v = -kappa v`` on the real invariant plane
  ``span(v, w)``: ``kappa = omega^2 > 0`` at a Hopf point (eigenvalues
  ``+- i omega`` of ``J v = lambda M v``), ``kappa < 0`` on a neutral saddle,
  and ``kappa`` changes sign at a Bogdanov-Takens point.

With one free parameter these systems are square (used to locate a point);
with two they define a curve continued by the same PALC. The free parameters
are chosen at evaluation time (``BoundSystem``), so each kind is compiled once
per VectorField and cached there (``symbolic.system``).

The problems use :func:`equilibrium_system`, :func:`fold_system` and :func:`hopf_system`
(its Jacobian written from its structure); :func:`ad_hopf_system` is the same Hopf system
differentiated by CasADi, the reference it is checked against.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import scipy.sparse as sp

from .._linalg.sparse import columns_appended
from .._casadi.symbolic import BufferedFunction, CompiledSystem
from .._casadi.vectorfield import VectorField


def _symbols(vf, *names):
    return [vf.sym.sym(name, vf.n) for name in names]


def fold_system(vf: VectorField) -> CompiledSystem:
    """The fold system, differentiated by CasADi."""
    x, v, c = _symbols(vf, "x", "v", "c")
    p = vf.sym.sym("p", len(vf.par_names))
    f = vf.F_expr(x, p)
    G = [ca.vertcat(f, ca.jtimes(f, x, v)), ca.dot(c, v) - 1]
    return CompiledSystem(ca.vertcat(x, v), p, c, G, "fold")


def ad_hopf_system(vf: VectorField) -> CompiledSystem:
    """The Hopf system, differentiated by CasADi (the reference of :func:`hopf_system`)."""
    x, v, w, c = _symbols(vf, "x", "v", "w", "c")
    kappa, p = vf.sym.sym("kappa"), vf.sym.sym("p", len(vf.par_names))
    f, m = vf.F_expr(x, p), vf.M_expr(x, p)
    G = [ca.vertcat(f, ca.jtimes(f, x, v) - ca.mtimes(m, w),
                    ca.jtimes(f, x, w) + kappa * ca.mtimes(m, v)),
         ca.vertcat(ca.dot(c, v) - 1, ca.dot(c, w))]
    return CompiledSystem(ca.vertcat(x, v, w, kappa), p, c, G, "hopf")


def equilibrium_system(vf: VectorField) -> CompiledSystem:
    """The equilibrium system ``F(x, p) = 0``, the field's function inlined
    (:func:`_flat_field`: 2x faster Jacobians for a modal model), ``F_x`` the field's own
    ``jacobian`` when given, ``F_p`` along the free parameters only."""
    x, p = vf.sym.sym("x", vf.n), vf.sym.sym("p", len(vf.par_names))
    f = _flat_field(vf, x, p)[0]
    return FreeDirectionSystem(x, p, vf.sym.sym("D", 0), f, "equilibrium",
                               _state_jacobian(vf, x, p, f), lambda E: ca.jtimes(f, p, E))


class FreeDirectionSystem(CompiledSystem):
    """A :class:`CompiledSystem` with ``G_p`` only along the free parameters: ``along(E)``
    is ``G_p E`` for a symbolic ``(k_p, k)`` ``E``, compiled once per count ``k`` (a modal
    model has 45 parameters, a curve 2 free ones)."""

    def __init__(self, Y, P, D, G, name: str, jy, along):
        rows = ca.vertcat(*G).numel() if isinstance(G, (list, tuple)) else G.numel()
        super().__init__(Y, P, D, G, name, jacobians=(jy, type(Y)(rows, 0)))
        self._symbols, self._along, self._name, self._by_count = (Y, P, D), along, name, {}
        self._n_par = P.numel()

    def _along_free(self, count: int) -> BufferedFunction:
        if count not in self._by_count:
            Y, P, D = self._symbols
            E = type(Y).sym("E", self._n_par, count)
            out = ca.densify(self._along(E))
            self._by_count[count] = BufferedFunction(
                ca.Function(f"{self._name}_jac_p{count}", [Y, P, D, E], [out]))
        return self._by_count[count]

    def jacobian(self, Y, P, D, par_columns) -> sp.csc_matrix:
        """``[G_Y, G_p[:, par_columns]]`` as one sparse matrix."""
        cols = list(par_columns)
        E = np.zeros((self._n_par, len(cols)))
        E[cols, np.arange(len(cols))] = 1.0
        jp = self._along_free(len(cols))(Y, P, D, E.ravel(order="F"))[0]
        return columns_appended(self._jy(Y, P, D)[0], self.pattern,
                                 jp.reshape(self.n_equations, -1, order="F"))


def hopf_system(vf: VectorField) -> CompiledSystem:
    """The Hopf system (``M v``, ``M w`` by the field's mass action when it
    has one) with its Jacobian written from its structure instead of by AD of the residual.

    With ``J = F_x`` the rows ``J v - M w`` and ``J w + kappa M v`` have the x-blocks
    ``D_x(J v) = D_v J`` (symmetry of second derivatives: one directional derivative
    of ``J`` instead of ``n``) minus ``D_x(M w)``, and the linear blocks ``J, -M,
    kappa M, M v``; likewise ``D_p(J v) = D_v F_p``. Equal to the AD Jacobian to
    rounding; for the 22-state modal model of 10 modes 13x cheaper to evaluate (4.5 ->
    0.35 ms, with the field's functions inlined)."""
    x, v, w, c = (vf.sym.sym(name, vf.n) for name in "xvwc")
    kappa, p = vf.sym.sym("kappa"), vf.sym.sym("p", len(vf.par_names))
    f, m = _flat_field(vf, x, p)
    mv, mw = _flat_mass_action(vf, x, p, v, m), _flat_mass_action(vf, x, p, w, m)
    G = [ca.vertcat(f, ca.jtimes(f, x, v) - mw, ca.jtimes(f, x, w) + kappa * mv),
         ca.vertcat(ca.dot(c, v) - 1, ca.dot(c, w))]
    jy = _hopf_jacobian_y(vf, x, v, w, kappa, p, c, f, m)

    def along(E):   # D_p(J v) E = D_v (F_p E), D_p(M w) E
        FpE = ca.jtimes(f, p, E)
        k = E.size2()
        Fpv, Fpw = ca.horzsplit(ca.jtimes(FpE, x, ca.horzcat(v, w)), [0, k, 2 * k])
        Mw_p, Mv_p = ca.jtimes(mw, p, E), ca.jtimes(mv, p, E)
        return ca.vertcat(FpE, Fpv - Mw_p, Fpw + kappa * Mv_p, vf.sym(2, k))

    return FreeDirectionSystem(ca.vertcat(x, v, w, kappa), p, c, G, "hopf", jy, along)


def _flat_field(vf, x, p):
    """``F(x, p)`` and ``M(x, p)`` with MX functions inlined: derivatives of the flat
    graph evaluate 2-3x faster than derivatives through call nodes (same values)."""
    return _inlined(vf, vf.F, x, p), \
        vf.M_expr(x, p) if vf.M is None else _inlined(vf, vf.M, x, p)


def _inlined(vf, fun, *args):
    """``fun(*args)``, inlined (no call node) for an MX field."""
    return fun.call(list(args), True, False)[0] if vf.sym is ca.MX else fun(*args)


def _state_jacobian(vf, x, p, f):
    """``dF/dx``: the field's ``jacobian`` when given (cheaper, also to differentiate
    again), else AD of ``f``."""
    return ca.jacobian(f, x) if vf.jacobian is None else _inlined(vf, vf.jacobian, x, p)


def _flat_mass_action(vf, x, p, y, m):
    """``M(x, p) y`` to differentiate: the field's matrix-free ``mass_action`` when it
    has one, else ``m y``. For the modal model of 40 modes the x-derivative of ``M w,
    M v`` costs 0.7 ms this way and 11 ms through ``m``."""
    return ca.mtimes(m, y) if vf.mass_action is None else _inlined(vf, vf.mass_action, x, p, y)


def _mass_action_x(vf, x, p, ys, m):
    """``[d(M y)/dx for y in ys]`` stacked: the field's ``mass_action_jacobian`` when
    given, else one AD Jacobian of the stacked products."""
    if vf.mass_action_jacobian is not None:
        return ca.vertcat(*[_inlined(vf, vf.mass_action_jacobian, x, p, y) for y in ys])
    return ca.jacobian(ca.vertcat(*[_flat_mass_action(vf, x, p, y, m) for y in ys]), x)


def _hopf_jacobian_y(vf, x, v, w, kappa, p, c, f, m):
    """``G_Y`` of the Hopf system, ``Y = (x, v, w, kappa)`` (:func:`hopf_system`)."""
    n, S = vf.n, vf.sym
    J = _state_jacobian(vf, x, p, f)
    # both directions / both rows in one derivative (shared sweeps: 20 % cheaper)
    Jv, Jw = ca.horzsplit(ca.jtimes(J, x, ca.horzcat(v, w)), [0, n, 2 * n])
    Mw_x, Mv_x = ca.vertsplit(_mass_action_x(vf, x, p, (w, v), m), [0, n, 2 * n])
    O, z, row = S(n, n), S(n, 1), S(1, n)
    return ca.blockcat([
        [J, O, O, z],
        [Jv - Mw_x, J, -m, z],
        [Jw + kappa * Mv_x, kappa * m, J, ca.mtimes(m, v)],
        [row, c.T, row, S(1, 1)],
        [row, row, c.T, S(1, 1)]])
