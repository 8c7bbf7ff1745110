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
* torus (``ch``, Chenciner): with ``mu = e^{i theta}``, ``v`` twisted by ``mu``, the
  periodic ``h11`` of ``G_Y h11 = -G_UU[v, conj v]`` and ``h20`` twisted by ``mu^2``
  (``A(mu^2) h20 = -G_UU[v, v]``), ``c = w^T (G_UUU[v, v, conj v] + 2 G_YY[v, h11] +
  G_UU[conj v, h20])`` over the pairing ``s = w^T A_mu v`` (the derivative of the twisted
  matrix in ``mu``, which stands for the map's ``p^H q``); the first Lyapunov
  coefficient of the Neimark-Sacker point is ``Re(conj(mu) c / s)``. Complex directions
  enter the real Jacobian differences by linearity (``D_(a + ib) = D_a + i D_b``) and
  polarization (``D2_(a + ib) = D2_a - D2_b + i (D2_(a+b) - D2_a - D2_b)``).

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
    H, _ = _differences(problem, X, d, None)
    return float(w @ (H @ d)) / (np.linalg.norm(v) ** 2 * np.linalg.norm(w))


def flip_coefficient(problem, X, v, w) -> float:
    """``c = w^T (G_UUU[v, v, v] + 3 G_YY[v, h2]) / (|v|^3 |w|)`` of the doubling's
    antiperiodic ``v`` (over ``U``) and adjoint ``w`` (module doc)."""
    rows = problem.n_nodes * problem.vf.n
    last = _last_rows(problem, rows + 1)
    d1, d2 = twisted_directions(problem, v, -1.0, len(X))
    J = problem.cycle_jacobian(X)
    (H1, K1), (H2, K2) = (_differences(problem, X, d, J) for d in (d1, d2))
    B = np.where(last, H2 @ d2, H1 @ d1)
    C = np.where(last, K2 @ d2, K1 @ d1)
    h2 = spla.spsolve(J[:, : rows + 1].tocsc(), -B)              # G_Y, periodic
    He, _ = _differences(problem, X, _padded(h2, len(X)), None)
    Bh = np.where(last, He @ d2, He @ d1)
    c = w @ (C + 3.0 * Bh)[:rows]
    return float(c) / (np.linalg.norm(v) ** 3 * np.linalg.norm(w))


def torus_coefficient(problem, X, mu, v, w, twisted_matrix) -> float:
    """The first Lyapunov coefficient ``Re(conj(mu) c / s) / |v|^2`` of the torus pair
    ``mu`` (module doc); ``v`` over ``U``, ``w`` its transposed adjoint,
    ``twisted_matrix(J, nu)`` the collocation ``G_U`` of the Jacobian ``J`` with the wrap
    ``u(1) = nu u(0)``."""
    rows, size = problem.n_nodes * problem.vf.n, len(X)
    last = _last_rows(problem, rows + 1)
    blocks = [twisted_directions(problem, v, mu, size),          # (rows but last, last)
              twisted_directions(problem, np.conj(v), np.conj(mu), size)]
    (v1, v2), (c1, c2) = blocks
    J = problem.cycle_jacobian(X)
    H1, K1 = _complex_differences(problem, X, v1, J)
    H2, K2 = _complex_differences(problem, X, v2, J)
    B_vc = np.real(np.where(last, H2 @ c2, H1 @ c1))              # G_UU[v, conj v]
    B_vv = np.where(last, H2 @ v2, H1 @ v1)
    C = np.where(last, K2 @ c2, K1 @ c1)                          # G_UUU[v, v, conj v]
    h11 = spla.spsolve(J[:, : rows + 1].tocsc(), -B_vc)
    h20 = spla.spsolve(twisted_matrix(J, mu ** 2).tocsc(), -B_vv[:rows])
    H11, _ = _differences(problem, X, _padded(h11, size), None)
    B_h11 = np.where(last, H11 @ v2, H11 @ v1)
    d1, d2 = twisted_directions(problem, h20, mu ** 2, size)
    G1, _ = _complex_differences(problem, X, d1, None)
    G2, _ = _complex_differences(problem, X, d2, None)
    B_h20 = np.where(last, G2 @ c2, G1 @ c1)
    c = w @ (C + 2.0 * B_h11 + B_h20)[:rows]
    last_u, wrap = last[:rows], np.arange(rows) < problem.vf.n
    s = w[last_u] @ (twisted_matrix(J, 1.0)[last_u][:, wrap] @ v[wrap])
    return float(np.real(np.conj(mu) * c / s)) / np.linalg.norm(v) ** 2


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


def _differences(problem, X, d, J0) -> tuple:
    """``(D_d J, D2_d J)`` of ``J = problem.cycle_jacobian`` at ``X`` along ``d``;
    ``J0``: ``J(X)``, or None for ``D_d J`` alone (``D2`` None)."""
    h = STEP * (1.0 + np.max(np.abs(X))) / max(np.max(np.abs(d)), 1e-300)
    J = {j: problem.cycle_jacobian(X + j * h * d) for j in (-2, -1, 1, 2)}
    H = (8 * (J[1] - J[-1]) - (J[2] - J[-2])) / (12 * h)
    if J0 is None:
        return H, None
    K = (16 * (J[1] + J[-1]) - (J[2] + J[-2]) - 30 * J0) / (12 * h ** 2)
    return H, K


def _complex_differences(problem, X, d, J0) -> tuple:
    """:func:`_differences` along a complex ``d`` (module doc)."""
    a, b = np.real(d), np.imag(d)
    Ha, Ka = _differences(problem, X, a, J0)
    if not np.any(b):
        return Ha, Ka
    Hb, Kb = _differences(problem, X, b, J0)
    if J0 is None:
        return Ha + 1j * Hb, None
    Kab = _differences(problem, X, a + b, J0)[1]
    return Ha + 1j * Hb, Ka - Kb + 1j * (Kab - Ka - Kb)


def _padded(v, size) -> np.ndarray:
    out = np.zeros(size, dtype=np.result_type(v, float))
    out[: v.size] = v
    return out
