"""Augmented systems ``G(X; D) = 0`` built symbolically from a VectorField.

With ``J = dF/dx`` (as the directional derivative ``J v = d/de F(x + e v)``):

* equilibrium ``X = (x, p_free)``:  ``F(x, p) = 0``;
* fold (limit point) ``X = (x, v, p_free)``, ``D = (p, c)``:
  ``F = 0``, ``J v = 0``, ``c.v - 1 = 0``;
* Hopf ``X = (x, v, w, kappa, p_free)``, ``D = (p, c)``:
  ``F = 0``, ``J v - M w = 0``, ``J w + kappa M v = 0``, ``c.v - 1 = 0``,
  ``c.w = 0``. Then ``(M^{-1}J)^2 v = -kappa v`` on the real invariant plane
  ``span(v, w)``: ``kappa = omega^2 > 0`` at a Hopf point (eigenvalues
  ``+- i omega`` of ``J v = lambda M v``), ``kappa < 0`` on a neutral saddle,
  and ``kappa`` changes sign at a Bogdanov-Takens point.

With one free parameter these systems are square (used to locate a point);
with two they define a curve continued by the same PALC. Compiled systems are
cached on the VectorField per (kind, free parameters).
"""

from __future__ import annotations

import casadi as ca

from ._symbolic import CompiledSystem
from ._vectorfield import VectorField


def _params(vf: VectorField, Dp, p_free, free_idx):
    """Parameter vector: fixed values ``Dp`` with the free entries from ``X``."""
    parts = [p_free[free_idx.index(i)] if i in free_idx else Dp[i]
             for i in range(len(vf.par_names))]
    return ca.vertcat(*parts)


def system(vf: VectorField, kind: str, free: tuple) -> CompiledSystem:
    """Compiled augmented system ``kind`` in {'equilibrium','fold','hopf'}."""
    key = (kind, tuple(free))
    cache = vf.__dict__.setdefault("_systems", {})
    if key not in cache:
        builder = {"equilibrium": _equilibrium, "fold": _fold, "hopf": _hopf}[kind]
        cache[key] = builder(vf, tuple(vf.par_index(f) for f in free))
    return cache[key]


def _equilibrium(vf, free_idx):
    S, n, k = vf.sym, vf.n, len(vf.par_names)
    x, pf, Dp = S.sym("x", n), S.sym("pf", len(free_idx)), S.sym("p", k)
    p = _params(vf, Dp, pf, free_idx)
    return CompiledSystem(ca.vertcat(x, pf), Dp, vf.F_expr(x, p), "equilibrium")


def _fold(vf, free_idx):
    S, n, k = vf.sym, vf.n, len(vf.par_names)
    x, v, pf = S.sym("x", n), S.sym("v", n), S.sym("pf", len(free_idx))
    Dp, c = S.sym("p", k), S.sym("c", n)
    p = _params(vf, Dp, pf, free_idx)
    f = vf.F_expr(x, p)
    G = [ca.vertcat(f, ca.jtimes(f, x, v)), ca.dot(c, v) - 1]
    return CompiledSystem(ca.vertcat(x, v, pf), ca.vertcat(Dp, c), G, "fold")


def _hopf(vf, free_idx):
    S, n, k = vf.sym, vf.n, len(vf.par_names)
    x, v, w = S.sym("x", n), S.sym("v", n), S.sym("w", n)
    kappa, pf = S.sym("kappa"), S.sym("pf", len(free_idx))
    Dp, c = S.sym("p", k), S.sym("c", n)
    p = _params(vf, Dp, pf, free_idx)
    f, m = vf.F_expr(x, p), vf.M_expr(x, p)
    G = [ca.vertcat(f, ca.jtimes(f, x, v) - ca.mtimes(m, w),
                    ca.jtimes(f, x, w) + kappa * ca.mtimes(m, v)),
         ca.vertcat(ca.dot(c, v) - 1, ca.dot(c, w))]
    return CompiledSystem(ca.vertcat(x, v, w, kappa, pf), ca.vertcat(Dp, c), G, "hopf")
