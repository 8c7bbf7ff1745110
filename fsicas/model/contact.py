"""Wall contact: the gap geometry, the regularized impact law and its reference force.

Gaps (y positive towards wall 1, ``H_c`` the wall profiles)::

    h_1(x) = H_1(x) - y(x),    h_2(x) = H_2(x) + y(x)

Impact load of wall c on the beam (paper Eq. 16, signs ``s_1 = -1, s_2 = +1``)::

    f_c(x) = s_c k ramp(eps - h_c(x)),   k = k* w_1^2,   eps = (eps/H) H*/2

with ``ramp = max(0, .)`` (the exact law) or its softplus of width ``smoothing * eps``.
One home for these formulas: the CasADi model, the energy balance, the outcome
measures and the cycle gauges all call them, symbolically or on NumPy arrays; the
patch where the load acts is located and integrated in :mod:`fsicas.model.patch`.
"""
from __future__ import annotations

import casadi as ca
import numpy as np

__all__ = ["GAP_POINTS", "WALL_SIGNS", "ramp", "stiffness", "law", "gap", "wall_gaps", "gaps",
           "wall_load", "nodal_impact_load", "nodal_impact_jacobian", "modal_load", "reference_force"]

GAP_POINTS = np.linspace(0.0, 1.0, 101)
"""Points x/L where gaps are sampled by the gauges and the plots (the impact load and
the deepest penetration are located between them: :mod:`fsicas.model.patch`)."""

WALL_SIGNS = (-1.0, 1.0)
"""``s_c``: wall 1 (above, y > 0 closes it) and wall 2 (below)."""

_SYMBOLIC = (ca.SX, ca.MX, ca.DM)


def ramp(v, width: float):
    """``max(0, v)``, or for ``width > 0`` the softplus ``width log(1 + exp(v / width))``.

    Written as ``max(0, v) + width log1p(exp(-|v| / width))``: no overflow, and the two
    kinks cancel, so it is C-infinity. It exceeds max(0, v) by at most width·log 2 (at
    v = 0) and by ``width·exp(-|v|/width)`` away from it. Works on CasADi symbols and on
    NumPy arrays alike.
    """
    lib = ca if isinstance(v, _SYMBOLIC) else np
    exact = ca.fmax(0, v) if lib is ca else np.maximum(0.0, v)
    if isinstance(width, (int, float)) and width == 0:
        return exact
    return exact + width * lib.log1p(lib.exp(-lib.fabs(v) / width))


def stiffness(contact_stiffness, omega_1: float):
    """``k = k* w_1^2``: the paper's k* is relative to the first-mode stiffness."""
    return contact_stiffness * omega_1 ** 2


def law(model, p) -> tuple[float, float]:
    """``(k, eps)`` of the parameter vector ``p`` of ``model`` (never of ``model.scene``,
    whose k*, eps/H are those of the first scene the model was built for); (0, 0) for
    a model without contact, whose equations carry no contact load."""
    p = np.asarray(p, dtype=float).ravel()
    if "contact_stiffness" not in model.parameter_names:
        return 0.0, 0.0
    eps = p[model.index("contact_eps")] * model.scene.hstar / 2
    return stiffness(p[model.index("contact_stiffness")], model.omega_1), eps


def gap(H, y, sign: float):
    """``h_c = H_c + s_c y``: the gap to wall c of profile ``H_c`` at deflection y."""
    return H + sign * y


def wall_gaps(walls, y) -> tuple:
    """``(h_1, h_2) = (H_1 - y, H_2 + y)`` for wall values ``walls = (H_1, H_2)``."""
    return tuple(gap(H, y, s) for H, s in zip(walls, WALL_SIGNS))


def nodal_impact_load(rule, scene, y, k, eps):
    """``W`` at the nodes of the impact ``rule`` (:class:`fsicas.model.impact_rule.ImpactRule`)
    from the deflection ``y`` there, both walls, so that ``∫ Σ_c f_c phi_n = Σ_i W_i
    phi_n(x_i)``: ``Σ_c s_c k rule.nodal(eps - h_c)``. Symbolic or NumPy (states in rows)."""
    ramp_ = _law_ramp(scene, eps)
    return sum(sign * k * rule.nodal(g, ramp_) for sign, g in _penetrations(rule, scene, y, eps))


def nodal_impact_jacobian(rule, scene, y, k, eps):
    """``dW/dy`` of :func:`nodal_impact_load` (symbolic): ``-k Σ_c dW_c/dg_c``, as
    ``g_c = eps - h_c`` falls by ``s_c`` per unit y and ``s_c² = 1``."""
    ramp_ = _law_ramp(scene, eps)
    return -k * sum(rule.nodal_jacobian(g, ramp_) for _, g in _penetrations(rule, scene, y, eps))


def _law_ramp(scene, eps):
    width = scene.contact_smoothing * eps if scene.contact_smoothing else 0.0
    return lambda g: ramp(g, width)


def _penetrations(rule, scene, y, eps):
    """``(s_c, g_c = eps - h_c)`` at the rule's nodes, for both walls."""
    return [(sign, eps - gap(wall(rule.x), y, sign)) for wall, sign in zip(scene.walls, WALL_SIGNS)]


def modal_load(model, x, p) -> np.ndarray:
    """``c_n = ∫ Σ_c f_c phi_n`` by the model's impact rule, f the law of ``p``
    (:func:`law`; the impact term of the equations, in NumPy)."""
    n, basis = model.n_modes, model.contact_basis
    k, eps = law(model, p)
    load = nodal_impact_load(model.impact_rule, model.scene, basis.phi.T @ x[n:2 * n], k, eps)
    return basis.phi @ load


def gaps(model, X, xs=GAP_POINTS) -> np.ndarray:
    """Gaps ``h_c(xs)`` of the states X (rows): shape (samples, 2, len(xs))."""
    n = model.n_modes
    y = np.atleast_2d(X)[:, n:2 * n] @ model.basis_at(xs).phi
    return np.stack(wall_gaps([w(xs)[None, :] for w in model.scene.walls], y), axis=1)


def wall_load(h, sign: float, k, eps, smoothing: float):
    """``f_c = s_c k ramp(eps - h_c)``: the load density of one wall on the beam."""
    return sign * k * ramp(eps - h, smoothing * eps if smoothing else 0.0)


def reference_force(model) -> float:
    """``F0 = m f1² H`` with m = 1, f1 = w1 / 2π, H = H*/2 (the force scale of Fig. 9)."""
    return (model.omega_1 / (2 * np.pi)) ** 2 * model.scene.hstar / 2
