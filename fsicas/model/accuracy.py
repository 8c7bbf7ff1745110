"""The quadrature error of the model's flow integrals, estimated by a second rule.

The flow terms are integrals along the beam of functions of the gaps ``h_c(x)``; their
integrands grow sharp where a gap is small, and the default rule (2N + 20 Gauss-Legendre
nodes) can then be too coarse (the cycle amplitude was 7e-5 off at a minimal gap of
6 eps). The estimate compares the right-hand side ``F`` of the model with that of the
same scene on twice the nodes, at given states:

    quadrature_error = max_k |F_2n(x_k) - F_n(x_k)|_inf / max_k |F_2n(x_k)|_inf,

the relative error of the equations themselves (the finer rule is far more accurate than
the difference, Gauss-Legendre converging fast for smooth integrands), a number to report
with a result and to compare with the tolerances it was computed to.

Control: :func:`adequate_model` doubles the nodes until the estimate is at most a
tolerance, by default :data:`QUADRATURE_TOL`.
"""
from __future__ import annotations

import warnings

import numpy as np

import continuation as C

from ..scene import MAX_QUAD_NODES
from .assembly import Model, build_model, per_model

__all__ = ["QUADRATURE_TOL", "IMPACT_QUADRATURE_TOL", "quadrature_error", "finer_model",
           "adequate_model", "relative_error"]

QUADRATURE_TOL = 1e-8
"""Default bound on :func:`quadrature_error` for :func:`adequate_model`: the relative
accuracy the solvers are run to, so that the quadrature is not the largest error of a
result. Time integration runs at rtol = 1e-8 (``fsicas.timedomain.integrators.Settings``);
collocation solves its residual to 1e-10 absolute (``CycleSettings.tol``) on F of size
1-100, and its mesh error at NTST = 20 is ~1e-6 (period at first contact, docs/cycles.md).
The results move less than F: a relative error delta of F moved the first-contact U* of
the cycle branch by 1e-3 delta to 1e-2 delta (N = 4 and 10), so at 1e-8 the quadrature's
share is ~1e-10, while the default rule near the wall (delta up to 2e-2) moved it by
3e-5. A tighter bound would double the nodes for errors already far below the solvers'."""


IMPACT_QUADRATURE_TOL = 1e-4
"""Default bound on :func:`quadrature_error` for runs and cycles with wall impacts: the estimate
there is set by the flow's integrands, sharp where a gap is inside the contact layer
(and for the smoothed law by the impact load's bend, its rule's error falling like n^-2),
and 1e-8 would need over a thousand nodes. At M* = 1, U* = 7, N = 10, k* = 1e8, eps/H = 1e-2 the
default 40 nodes estimate 1.9e-2 with the period 1.5e-5 and the peak force 2.5e-4 off,
80 nodes 6.8e-5 with 5.3e-8 and 6.5e-6 (``benchmarks/bench_quadrature_control.py
--impacting 7``): below 1e-4 the period is within 1e-6 and the peak force within 1e-3."""


@per_model
def finer_model(model: Model) -> Model:
    """The model of the same scene on twice the quadrature nodes (built once per model)."""
    scene = model.scene
    return build_model(scene.replace(quad_nodes=min(2 * scene.n_quad, MAX_QUAD_NODES)))


def quadrature_error(model: Model, x, p) -> float:
    """The relative quadrature error of ``F`` at the states ``x`` (rows) and parameters
    ``p`` of ``model`` (module docstring)."""
    x = np.atleast_2d(np.asarray(x, dtype=float))
    return relative_error(_rhs_at(finer_model(model), x, p), _rhs_at(model, x, p))


@per_model
def _mapped_rhs(model: Model) -> dict:
    """``model.rhs`` mapped over ``count`` states (p shared), by count (filled on use)."""
    return {}


def _rhs_at(model: Model, x: np.ndarray, p) -> np.ndarray:
    """``F(x_k, p)`` of the states ``x`` (rows), flat, in one zero-copy mapped call."""
    cache, count = _mapped_rhs(model), len(x)
    if count not in cache:
        cache[count] = C.BufferedFunction(model.rhs.map(f"F_{count}", "serial", count, [1], []))
    return cache[count](x, p)[0]


def adequate_model(model: Model, x, p, tol: float = QUADRATURE_TOL) -> tuple[Model, float]:
    """The model of ``model``'s scene on enough quadrature nodes for the states ``x``
    (rows) at parameters ``p``: the nodes doubled (:func:`finer_model`, so each model is
    built once per input model) until :func:`quadrature_error` is at most ``tol``.
    Returns that model (``model`` itself when already adequate) and its estimate. At the
    cap :data:`fsicas.scene.MAX_QUAD_NODES` it warns and returns the model on the cap,
    with the estimate of the rule before it (an upper bound: the cap's own estimate would
    compare the cap with itself)."""
    error = quadrature_error(model, x, p)
    while error > tol:
        if 2 * model.scene.n_quad >= MAX_QUAD_NODES:
            return _capped(model, error, tol)
        model = finer_model(model)
        error = quadrature_error(model, x, p)
    return model, error


def _capped(model: Model, error: float, tol: float) -> tuple[Model, float]:
    """The model on MAX_QUAD_NODES nodes, with a warning that ``tol`` was not reached."""
    finest = finer_model(model)
    warnings.warn(f"quadrature error {error:.3g} on {model.scene.n_quad} nodes exceeds tol = "
                  f"{tol:g} and the nodes reached MAX_QUAD_NODES = {MAX_QUAD_NODES}: the model "
                  f"on {finest.scene.n_quad} nodes is used, its error estimated by {error:.3g}",
                  RuntimeWarning, stacklevel=3)
    return finest, error


def relative_error(fine, coarse) -> float:
    """``max |fine - coarse| / max |fine|`` (0 where ``fine`` vanishes)."""
    fine, coarse = np.asarray(fine, dtype=float), np.asarray(coarse, dtype=float)
    scale = float(np.max(np.abs(fine)))
    return float(np.max(np.abs(fine - coarse)) / scale) if scale > 0 else 0.0
