"""Normal-form coefficients of the codimension-one bifurcations of collocated cycles, on
their curves (``conditions``): zero where the curve has a codimension-two point.

Everything is the discretized cycle's own algebra: ``G(Y, p) = 0`` (collocation and
phase, ``Y = (U, T)``), the bordered null vectors ``v, w`` of the singular matrix of the
condition, and the multilinear forms of ``G`` along ``v`` taken from Jacobians at
displaced points ``X + j h d``, ``j = -2..2`` (the fourth-order central differences
``D_d J = (8 (J_1 - J_-1) - (J_2 - J_-2)) / 12 h`` and ``D2_d J = (16 (J_1 + J_-1) - (J_2 +
J_-2) - 30 J_0) / 12 h^2``, errors ``O(h^4)``): no derivative beyond the first is
compiled. A twisted vector (the wrap ``u(1) = mu u(0)``) enters the rows of the last
interval with its node 0 times ``mu`` (``twisted_directions``): each row sees only its own
interval's nodes, so the two directions give every row its true form.

* fold (``cpc``, cusp of cycles): ``a = w^T G_YY[v, v]``;
* period doubling (``gpd``, generalized period doubling): the cycles of double period
  are the pitchfork of the antisymmetric ``v`` in the doubled problem, whose cubic
  coefficient is ``c = w^T (G_UUU[v, v, v] + 3 G_YY[v, h2])`` with ``h2`` the symmetric
  (single-period) solution of ``G_Y h2 = -G_UU[v, v]``.

Each is divided by ``|v|^k |w|`` (``k`` its degree in ``v``): its sign along a curve is
what matters, and the bordered ``v, w`` are continuous there.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

#: relative step of the Jacobian differences: O(h^4) truncation against eps / h^2
#: rounding in the second difference, both about 1e-10 (O(h^2) differences left an
#: error of 1e-6 in a located generalized period doubling)
STEP = 1e-3


def fold_coefficient(problem, X, v, w) -> float:
    """``a = w^T G_YY[v, v] / (|v|^2 |w|)`` (``v`` over ``Y = (U, T)``)."""
    d = _padded(v, len(X))
    H, _ = _differences(problem, X, d, second=False)
    return float(w @ (H @ d)) / (np.linalg.norm(v) ** 2 * np.linalg.norm(w))


def flip_coefficient(problem, X, v, w) -> float:
    """``c = w^T (G_UUU[v, v, v] + 3 G_YY[v, h2]) / (|v|^3 |w|)`` of the doubling's
    antiperiodic ``v`` (over ``U``) and adjoint ``w`` (module doc)."""
    rows = problem.n_nodes * problem.vf.n
    last = _last_rows(problem, rows + 1)
    d1, d2 = twisted_directions(problem, v, -1.0, len(X))
    (H1, K1), (H2, K2) = (_differences(problem, X, d) for d in (d1, d2))
    B = np.where(last, H2 @ d2, H1 @ d1)
    C = np.where(last, K2 @ d2, K1 @ d1)
    A = problem.cycle_jacobian(X)[:, : rows + 1].tocsc()          # G_Y, periodic
    h2 = spla.spsolve(A, -B)
    He, _ = _differences(problem, X, _padded(h2, len(X)), second=False)
    Bh = np.where(last, He @ d2, He @ d1)
    c = w @ (C + 3.0 * Bh)[:rows]
    return float(c) / (np.linalg.norm(v) ** 3 * np.linalg.norm(w))


def twisted_directions(problem, v, mu, size: int) -> tuple:
    """``(d1, d2)``: ``v`` (over ``U``) as seen by the rows of every interval but the
    last, and by the last one (node 0 times ``mu``), zero-padded to ``size``."""
    wrap = np.arange(v.size) < problem.vf.n
    return _padded(v, size), _padded(np.where(wrap, mu * v, v), size)


def _last_rows(problem, size: int) -> np.ndarray:
    """The rows of the last interval among ``size`` rows (collocation, then phase)."""
    rows = problem.n_nodes * problem.vf.n
    index = np.arange(size)
    return (index >= rows - problem.vf.n * problem.ncol) & (index < rows)


def _differences(problem, X, d, second: bool = True) -> tuple:
    """``(D_d J, D2_d J)`` of ``J = problem.cycle_jacobian`` at ``X`` along ``d``
    (``D2`` None unless ``second``)."""
    h = STEP * (1.0 + np.max(np.abs(X))) / max(np.max(np.abs(d)), 1e-300)
    J = {j: problem.cycle_jacobian(X + j * h * d) for j in (-2, -1, 1, 2)}
    H = (8 * (J[1] - J[-1]) - (J[2] - J[-2])) / (12 * h)
    if not second:
        return H, None
    K = (16 * (J[1] + J[-1]) - (J[2] + J[-2]) - 30 * problem.cycle_jacobian(X)) / (12 * h ** 2)
    return H, K


def _padded(v, size) -> np.ndarray:
    out = np.zeros(size, dtype=np.result_type(v, float))
    out[: v.size] = v
    return out
