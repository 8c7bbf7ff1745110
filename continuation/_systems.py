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
per VectorField and cached there.
"""

from __future__ import annotations

import casadi as ca

from ._symbolic import BoundSystem, CompiledSystem
from ._vectorfield import VectorField


def system(vf: VectorField, kind: str, builder=None) -> CompiledSystem:
    """Compiled augmented system ``kind``, built once per VectorField.

    ``builder(vf) -> CompiledSystem`` defaults to the built-in kinds
    'equilibrium', 'fold' and 'hopf'; new problem kinds (e.g. periodic orbits)
    pass their own.
    """
    cache = vf.__dict__.setdefault("_systems", {})
    if kind not in cache:
        builder = builder or {"equilibrium": _equilibrium, "fold": _fold, "hopf": _hopf}[kind]
        cache[kind] = builder(vf)
    return cache[kind]


def bound(vf: VectorField, kind: str, p0, D, free, builder=None) -> BoundSystem:
    """``system(vf, kind)`` with parameters ``p0``, data ``D`` and ``free`` names."""
    return BoundSystem(system(vf, kind, builder), p0, D,
                       tuple(vf.par_index(f) for f in free))


def _symbols(vf, *names):
    return [vf.sym.sym(name, vf.n) for name in names]


def _equilibrium(vf):
    (x,) = _symbols(vf, "x")
    p, D = vf.sym.sym("p", len(vf.par_names)), vf.sym.sym("D", 0)
    return CompiledSystem(x, p, D, vf.F_expr(x, p), "equilibrium")


def _fold(vf):
    x, v, c = _symbols(vf, "x", "v", "c")
    p = vf.sym.sym("p", len(vf.par_names))
    f = vf.F_expr(x, p)
    G = [ca.vertcat(f, ca.jtimes(f, x, v)), ca.dot(c, v) - 1]
    return CompiledSystem(ca.vertcat(x, v), p, c, G, "fold")


def _hopf(vf):
    x, v, w, c = _symbols(vf, "x", "v", "w", "c")
    kappa, p = vf.sym.sym("kappa"), vf.sym.sym("p", len(vf.par_names))
    f, m = vf.F_expr(x, p), vf.M_expr(x, p)
    G = [ca.vertcat(f, ca.jtimes(f, x, v) - ca.mtimes(m, w),
                    ca.jtimes(f, x, w) + kappa * ca.mtimes(m, v)),
         ca.vertcat(ca.dot(c, v) - 1, ca.dot(c, w))]
    return CompiledSystem(ca.vertcat(x, v, w, kappa), p, c, G, "hopf")
