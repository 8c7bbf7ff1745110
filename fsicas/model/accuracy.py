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
"""
from __future__ import annotations

import numpy as np

from ..scene import MAX_QUAD_NODES
from .assembly import Model, build_model, per_model

__all__ = ["quadrature_error", "finer_model", "relative_error"]


@per_model
def finer_model(model: Model) -> Model:
    """The model of the same scene on twice the quadrature nodes (built once per model)."""
    scene = model.scene
    return build_model(scene.replace(quad_nodes=min(2 * scene.n_quad, MAX_QUAD_NODES)))


def quadrature_error(model: Model, x, p) -> float:
    """The relative quadrature error of ``F`` at the states ``x`` (rows) and parameters
    ``p`` of ``model`` (module docstring)."""
    x = np.atleast_2d(np.asarray(x, dtype=float))
    return relative_error(finer_model(model).rhs.map(len(x))(x.T, p), model.rhs.map(len(x))(x.T, p))


def relative_error(fine, coarse) -> float:
    """``max |fine - coarse| / max |fine|`` (0 where ``fine`` vanishes)."""
    fine, coarse = np.asarray(fine, dtype=float), np.asarray(coarse, dtype=float)
    scale = float(np.max(np.abs(fine)))
    return float(np.max(np.abs(fine - coarse)) / scale) if scale > 0 else 0.0
