"""The impact load of the equations, ``∫_0^1 k ramp(g_c) phi_n dx`` with ``g_c = eps - h_c``,
integrated where the law's kink is.

The patch where ``g_c > 0`` is 5e-4 to 2e-3 of L long, anywhere along the beam, and the
integrand has kinks at its ends: a fixed rule converges only like its cell width squared,
with a constant set by the patch. The exact law (``contact_smoothing = 0``) has its own
rule here, a *cell rule*: [0, 1] is cut into ``C`` equal cells of width Δ; on each,
``g_c`` is replaced by its quadratic interpolant ``p`` at the ends and the midpoint
(``t = -1, 0, 1``, ``x = x_cell + (t + 1) Δ/2``), and the nodal weights

    W_j = Δ/2 ∫_{-1}^{1} max(0, p(t)) ℓ_j(t) dt,     ℓ_j the quadratic Lagrange basis,

are exact: the roots of ``p`` in closed form, the moments ``∫ t^k`` between them. So

    ∫_0^1 max(0, g_c) phi_n dx ≈ Σ_i W_i phi_n(x_i),

the kink located exactly in the interpolant; the error is that of interpolating ``g_c`` and
``phi_n`` (O(Δ^3)), not the kink's. Measured against the exact modal integral on the
located patch: 1.2e-5 of the largest load at 100 cells and 1.3e-6 at 200 for tip impacts
(M* = 1, U* = 7), 1.3e-4 and 4.6e-6 for the soft palate's mid-beam contacts, where a rule
graded towards the tip was 0.77 off (``tests/test_impact_rule.py``).

The smoothed law (``contact_smoothing > 0``, the softplus) has no kink but a bend of width
``smoothing eps`` in g: its nodes are Gauss-Legendre pairs, the rule of the collocation of
impacting cycles. For the cantilever, whose contacts are at its free tip, on cells graded
towards x = 1 (:func:`fsicas.model.quadrature.tip_graded_gauss_legendre`). A beam held at
both ends touches anywhere inside the span (not at the crest x_ref of its first mode: its
flutter's crest is downstream, x = 0.77 for clamped-clamped at 1.1 U*_c), so its rule is
accurate anywhere: :data:`SMOOTH_CELLS_PER_NODE` equal cells per flow node. Measured
against the exact modal integral on the located patch (five states pressed 0.3 eps into
a wall inside the span, smoothing 0.1), relative to the largest load, at N = 10
(n_quad = 40: 400 cells) / twice the nodes: 2.5e-5 / 4.7e-9 clamped-clamped, 3.4e-5 /
1.2e-8 clamped-pinned, 1.0e-5 / 7.9e-9 pinned-pinned. Cells graded symmetrically
towards x_ref (420 nodes) were 5e-3 to 6e-2 off where 210 equal cells were 1.8e-4 to
1e-3, and the tip's rule (230 nodes) 0.36 to 0.71
(``tests/test_ends_impacting.py``).

The formulas work on NumPy arrays (states in rows, nodes in the last axis) and on CasADi
symbols (a column of nodes) alike.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import casadi as ca
import numpy as np
import scipy.sparse as sp

from .quadrature import composite_gauss_legendre, tip_graded_gauss_legendre

__all__ = ["ImpactRule", "impact_rule", "CELLS_PER_NODE", "SMOOTH_CELLS_PER_NODE"]

CELLS_PER_NODE = 3
"""Cells of the cell rule per flow quadrature node (``scene.n_quad``): 120 cells (241
nodes) at the default N = 10, twice as many when the flow's nodes are doubled, so the
quadrature estimate (:mod:`fsicas.model.accuracy`) refines both together."""

SMOOTH_CELLS_PER_NODE = 10
"""Equal cells (two Gauss-Legendre nodes each) of the smoothed law's rule per flow
quadrature node for a beam held at both ends: 400 cells (800 nodes) at the default
n_quad = 40, refined with it (module docstring)."""

_TINY = 1e-300      # keeps sqrt's derivative finite at a double root


@dataclass(frozen=True, eq=False)
class ImpactRule:
    """Nodes ``x`` of the impact load and how the load at them is formed: the cell rule
    (``weights`` None; ``x`` the ends and midpoints of ``cells`` equal cells) or, for the
    smoothed law, the pointwise rule ``W_i = weights_i ramp(g_i)``."""

    x: np.ndarray
    weights: np.ndarray | None = None

    @property
    def cells(self) -> int:
        return (len(self.x) - 1) // 2 if self.weights is None else 0

    def nodal_jacobian(self, g, ramp):
        """``dW/dg`` of :meth:`nodal` for symbolic ``g``: by AD for the pointwise rule
        (diagonal); for the cell rule its closed form (:func:`_cell_rule`; on MX that
        call's own Jacobian, with its skip)."""
        if self.weights is None and isinstance(g, ca.MX):
            return _cell_rule(self.cells).jacobian()(g, 0)
        if self.weights is None:
            return _cell_jacobian(*_cell_values(g, self.cells), self.cells)
        s = type(g).sym("g", g.shape)
        return ca.substitute(ca.jacobian(self.nodal(s, ramp), s), s, g)

    def nodal(self, g, ramp):
        """``W_i`` (module docstring) of the penetrations ``g = eps - h_c`` at the nodes,
        so that ``∫ ramp(g) phi_n ≈ Σ_i W_i phi_n(x_i)``; ``ramp`` is the law's ramp, used
        by the pointwise rule only (the cell rule integrates ``max(0, .)``)."""
        if self.weights is not None:
            return self.weights * ramp(g)
        if isinstance(g, ca.MX):
            return _cell_rule(self.cells)(g)
        if isinstance(g, (ca.SX, ca.DM)):
            return _scattered(_cell_weights(*_cell_values(g, self.cells), ca, ca.if_else),
                              self.cells)
        _, scatter = _scatter(self.cells)
        g = np.asarray(g, dtype=float)
        weights = _cell_weights(g[..., 0:-1:2], g[..., 1::2], g[..., 2::2], np, np.where)
        return sum(w @ s.T for s, w in zip(scatter, weights)) / (2 * self.cells)


def impact_rule(n_quad: int, smoothing: float, free_tip: bool = True) -> ImpactRule:
    """The rule of a scene with ``n_quad`` flow nodes and the law's ``smoothing``, for a
    beam with a free tip x = 1 (the cantilever) or held at both ends (module docstring)."""
    if smoothing and free_tip:
        return ImpactRule(*tip_graded_gauss_legendre(n_quad))
    if smoothing:
        return ImpactRule(*composite_gauss_legendre(SMOOTH_CELLS_PER_NODE * n_quad, 2))
    return ImpactRule(np.linspace(0.0, 1.0, 2 * CELLS_PER_NODE * n_quad + 1))


@functools.lru_cache(maxsize=16)
def _scatter(cells: int):
    """``(picks, scatter)``: constant sparse matrices taking the cells' left end, midpoint
    and right end values from the nodes, and their transposes, which map the three
    per-cell weights back onto the nodes."""
    rows = np.arange(cells)
    pick = lambda cols: sp.csc_matrix((np.ones(cells), (rows, cols)), shape=(cells, 2 * cells + 1))
    picks = pick(2 * rows), pick(2 * rows + 1), pick(2 * rows + 2)
    return picks, tuple(m.T.tocsc() for m in picks)


def _cell_values(g, cells: int) -> tuple:
    """``(g_left, g_mid, g_right)`` of every cell from the symbolic node values ``g``."""
    return tuple(ca.mtimes(ca.DM(m), g) for m in _scatter(cells)[0])


def _scattered(weights, cells: int):
    """``W`` at the nodes from the three symbolic per-cell weights (``Δ/2 = 1/(2 cells)``)."""
    return sum(ca.mtimes(ca.DM(s), w) for s, w in zip(_scatter(cells)[1], weights)) / (2 * cells)


@functools.lru_cache(maxsize=16)
def _cell_rule(cells: int) -> ca.Function:
    """``W(g)`` of the cell rule as one call whose Jacobian (``.jacobian()``, its second
    argument unused) is given, not derived by AD:

        dW_j/dg_k = Δ/2 ∫_{p > 0} ℓ_j ℓ_k dt,

    since ``∂p/∂g_k = ℓ_k`` and the integrand vanishes at the roots that bound the
    positive set (moving them adds nothing). AD through the roots' formulas costs 2-9 ms
    per Jacobian at 120 cells, this 0.05-0.2 ms (CasADi's ``jacobian`` of an expression
    that calls this still seeds it direction by direction: call ``.jacobian()``)."""
    g = ca.MX.sym("g", 2 * cells + 1)
    gl, g0, gr = _cell_values(g, cells)
    load = _scattered(_cell_weights(gl, g0, gr, ca, ca.if_else), cells)
    jac = _cell_jacobian(gl, g0, gr, cells)
    # p exceeds its largest node by at most |c2|/4: where no cell reaches 0, W is 0 and so
    # is its Jacobian, and the switch skips the cells (most calls of a run)
    touch = ca.mmax(ca.fmax(ca.fmax(gl, g0), gr) + ca.fabs((gl + gr) / 2 - g0) / 4) > 0
    skip = lambda e: ca.if_else(touch, e, ca.DM.zeros(e.sparsity()), True)
    out = ca.MX.sym("out", 2 * cells + 1)
    custom = ca.Function("jac_cell_rule", [g, out], [skip(jac)], ["g", "out_W"], ["jac_W_g"])
    return ca.Function("cell_rule", [g], [skip(load)], ["g"], ["W"],
                       {"custom_jacobian": custom, "jac_penalty": 0, "never_inline": True})


def _cell_jacobian(gl, g0, gr, cells: int):
    """``dW/dg`` (:func:`_cell_rule`) from the cells' end and midpoint values, symbolic:
    ``Σ_jk S_j diag(Δ/2 ∫_{p>0} ℓ_j ℓ_k) P_k``, P_k picking node k of each cell and S_j
    scattering the weight j back to the nodes."""
    picks, scatter = _scatter(cells)
    picks = [ca.DM(m) for m in picks]
    mass = _cell_mass(gl, g0, gr, ca, ca.if_else)
    return sum(ca.mtimes(ca.DM(scatter[j]), ca.mtimes(ca.diag(mass[min(j, k), max(j, k)]),
                                                      picks[k]))
               for j in range(3) for k in range(3)) / (2 * cells)


def _positive_set(gl, g0, gr, lib, where):
    """``(c0, c1, c2)`` of the quadratic p through ``(-1, gl), (0, g0), (1, gr)``, the
    ends ``a <= b`` in [-1, 1] of the interval between its real roots (clipped; a = b = 0
    without real roots: computed stably, a linear p has a root at infinity), and whether
    p is concave: p > 0 on (a, b) if concave, on [-1, 1] minus [a, b] if not."""
    c0, c1, c2 = g0, (gr - gl) / 2, (gr + gl) / 2 - g0
    disc = c1 * c1 - 4 * c0 * c2
    q = -(c1 + where(c1 >= 0, 1.0, -1.0) * lib.sqrt(lib.fmax(disc, _TINY))) / 2
    roots = _ratio(c0, q, lib, where), _ratio(q, c2, lib, where)
    clip = lambda t: lib.fmin(lib.fmax(t, -1.0), 1.0)
    real = disc > 0
    a = where(real, clip(lib.fmin(*roots)), 0.0)
    b = where(real, clip(lib.fmax(*roots)), 0.0)
    return (c0, c1, c2), a, b, c2 <= 0


def _cell_weights(gl, g0, gr, lib, where):
    """``∫_{-1}^{1} max(0, p) ℓ_j dt`` for j = left, mid, right of each cell, p the
    quadratic through ``(-1, gl), (0, g0), (1, gr)`` (:func:`_positive_set`)."""
    (c0, c1, c2), a, b, concave = _positive_set(gl, g0, gr, lib, where)
    between = _lagrange_integrals(c0, c1, c2, a, b)
    whole = _lagrange_integrals(c0, c1, c2, -1.0 + 0 * a, 1.0 + 0 * a)
    return tuple(where(concave, inner, full - inner) for inner, full in zip(between, whole))


def _cell_mass(gl, g0, gr, lib, where) -> dict:
    """``∫_{p > 0} ℓ_j ℓ_k dt`` by ``(j, k)``, j <= k (:func:`_positive_set`)."""
    _, a, b, concave = _positive_set(gl, g0, gr, lib, where)
    between, whole = _lagrange_mass(a, b), _lagrange_mass(-1.0, 1.0)
    return {jk: where(concave, between[jk], whole[jk] - between[jk]) for jk in between}


def _moments(a, b) -> list:
    """``∫_a^b t^k dt``, k = 0..4."""
    pa, pb, mu = a, b, []
    for k in range(5):
        mu.append((pb - pa) / (k + 1))
        pa, pb = pa * a, pb * b
    return mu


def _lagrange_mass(a, b) -> dict:
    """``∫_a^b ℓ_j ℓ_k dt`` (ℓ as in :func:`_lagrange_integrals`), by ``(j, k)``, j <= k."""
    mu = _moments(a, b)
    return {(0, 0): (mu[4] - 2 * mu[3] + mu[2]) / 4, (0, 1): (mu[3] - mu[4] + mu[2] - mu[1]) / 2,
            (0, 2): (mu[4] - mu[2]) / 4, (1, 1): mu[0] - 2 * mu[2] + mu[4],
            (1, 2): (mu[1] + mu[2] - mu[3] - mu[4]) / 2, (2, 2): (mu[4] + 2 * mu[3] + mu[2]) / 4}


def _ratio(num, den, lib, where):
    """``num / den``, or ±2 (outside [-1, 1], the sign of num/den with den = 0 read as
    0⁻) where its size is at least 2."""
    den_sign = where(den > 0, 1.0, -1.0)
    far = lib.fabs(num) >= 2 * lib.fabs(den)
    safe = where(den == 0, 1.0, den)
    return where(far, 2.0 * lib.sign(num) * den_sign, num / safe)


def _lagrange_integrals(c0, c1, c2, a, b):
    """``∫_a^b p ℓ_j dt`` for ℓ = ((t² - t)/2, 1 - t², (t² + t)/2), p = c0 + c1 t + c2 t²."""
    mu = _moments(a, b)
    P = [c0 * mu[i] + c1 * mu[i + 1] + c2 * mu[i + 2] for i in range(3)]
    return (P[2] - P[1]) / 2, P[0] - P[2], (P[2] + P[1]) / 2
