"""Orthogonal collocation of periodic orbits of ``M(x, p) xdot = F(x, p)``.

Time is scaled to ``t in [0, 1]`` with the period ``T`` as an unknown. The
mesh ``0 = t_0 < ... < t_NTST = 1`` has widths ``h_i``; on each interval
``u`` is the Lagrange polynomial through ``NCOL + 1`` equally spaced nodes
``u_{i,l}`` (``l = 0..NCOL``, ``u_{i,NCOL} = u_{i+1,0}``, and
``u_{NTST,0} = u_{0,0}``: periodicity is built in). At the ``NCOL``
Gauss-Legendre points ``z_k`` of each interval (AUTO's collocation):

    M(u(z_k), p) u'(z_k) - T F(u(z_k), p) = 0       (multiplied by h_i)

plus the integral phase condition against a reference cycle ``v``:

    int_0^1 <u(t), v'(t)> dt = 0                     (Gauss quadrature).

Unknowns ``Y = (U, T)``, ``U`` the ``n * NTST * NCOL`` distinct node values;
fixed data ``D = (h, c)`` with ``c`` the quadrature coefficients of the phase
condition, so re-meshing and refreshing the reference never recompile.
The mesh-point values and ``T`` are superconvergent, error ``O(h^(2 NCOL))``;
the profile elsewhere ``O(h^(NCOL+1))``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from .._casadi.symbolic import CompiledSystem


@dataclass(frozen=True)
class Collocation:
    """Reference-interval matrices for ``ncol`` Gauss points.

    ``P[k, l] = L_l(z_k)``, ``Dm[k, l] = L_l'(z_k)``, ``w`` Gauss weights on
    ``[0, 1]``, ``nodes = l / ncol``.
    """

    ncol: int
    nodes: np.ndarray
    z: np.ndarray
    w: np.ndarray
    P: np.ndarray
    Dm: np.ndarray


@lru_cache(maxsize=None)
def collocation(ncol: int) -> Collocation:
    """Lagrange basis on equispaced nodes evaluated at Gauss-Legendre points."""
    g, gw = np.polynomial.legendre.leggauss(ncol)
    z, w = 0.5 * (g + 1), 0.5 * gw
    nodes = np.linspace(0.0, 1.0, ncol + 1)
    P, Dm = lagrange(nodes, z)
    return Collocation(ncol, nodes, z, w, P, Dm)


def lagrange(nodes: np.ndarray, s: np.ndarray):
    """Values and derivatives ``L_l(s_k), L_l'(s_k)`` of the Lagrange basis:

        L_l(s) = prod_{m != l} (s - x_m) / (x_l - x_m),
        L_l'(s) = sum_{j != l} prod_{m != l, j} (s - x_m) / prod_{m != l} (x_l - x_m),

    in closed form on arrays (no polynomial fit per call: the cycle gauges evaluate it
    at every trial time)."""
    x, s = np.asarray(nodes, dtype=float), np.atleast_1d(np.asarray(s, dtype=float))
    m = len(x)
    d = s[:, None] - x[None, :]                                      # (k, m)
    other = ~np.eye(m, dtype=bool)
    denom = np.array([np.prod(x[l] - x[other[l]]) for l in range(m)])
    V = np.stack([np.prod(d[:, other[l]], axis=1) for l in range(m)], axis=1) / denom
    dV = np.stack([sum(np.prod(d[:, other[l] & other[j]], axis=1)
                       for j in range(m) if j != l) for l in range(m)], axis=1) / denom
    return V, dV


def node_times(mesh: np.ndarray, ncol: int) -> np.ndarray:
    """Times of the ``NTST * NCOL`` distinct nodes (``t = 1`` excluded)."""
    h = np.diff(mesh)
    s = np.linspace(0.0, 1.0, ncol + 1)[:-1]
    return (mesh[:-1, None] + h[:, None] * s[None, :]).ravel()


def interval_nodes(U: np.ndarray, n: int, ntst: int, ncol: int) -> np.ndarray:
    """``(ntst, ncol + 1, n)`` node values per interval, periodic wrap included."""
    u = np.asarray(U).reshape(ntst * ncol, n)
    u = np.vstack([u, u[:1]])
    idx = np.arange(ntst)[:, None] * ncol + np.arange(ncol + 1)[None, :]
    return u[idx]


def evaluate(U, mesh: np.ndarray, ncol: int, n: int, t) -> np.ndarray:
    """Values ``(len(t), n)`` of the piecewise polynomial with node values ``U``."""
    t = np.mod(np.atleast_1d(np.asarray(t, dtype=float)), 1.0)
    ntst = len(mesh) - 1
    nodes = interval_nodes(U, n, ntst, ncol)
    i = np.clip(np.searchsorted(mesh, t, side="right") - 1, 0, ntst - 1)
    s = (t - mesh[i]) / (mesh[i + 1] - mesh[i])
    L, _ = lagrange(np.linspace(0.0, 1.0, ncol + 1), s)
    return np.einsum("jl,jlk->jk", L, nodes[i])


def extrema(U, mesh: np.ndarray, ncol: int, n: int, A: np.ndarray,
            samples: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """``min_t`` and ``max_t`` over the cycle of each row of ``A u(t)`` (``A``: m x n).

    On each interval ``A u`` is a polynomial of degree ``NCOL`` in the local time ``s``:
    it is sampled at ``samples`` points per interval, and on every interval the best
    sample is polished by Newton on ``d/ds (A u) = 0`` (the extremum of a polynomial, to
    rounding); a polished value is kept only where it improves the sample.
    """
    coef, s, values = _row_polynomials(U, mesh, ncol, n, A, samples)
    return tuple(sign * _interval_minima(coef, s, sign * values, sign)[1].min(axis=0)
                 for sign in (1.0, -1.0))


def minimizer(U, mesh: np.ndarray, ncol: int, n: int, A: np.ndarray,
              samples: int = 8) -> tuple[float, int, float, int]:
    """``(value, i, s, j)``: ``min_{t, j} (A u(t))_j`` over the cycle (as :func:`extrema`)
    and where it is taken: interval ``i``, local time ``s`` in ``[0, 1]``, row ``j``."""
    coef, s, values = _row_polynomials(U, mesh, ncol, n, A, samples)
    t, low = _interval_minima(coef, s, values, 1.0)
    i, j = np.unravel_index(np.argmin(low), low.shape)
    return float(low[i, j]), int(i), float(t[i, j]), int(j)


def _row_polynomials(U, mesh, ncol, n, A, samples):
    """Monomial coefficients ``(degree, interval, row)`` of the rows of ``A u`` in the
    local time, the sample times and the values there ``(sample, interval, row)``."""
    ntst = len(mesh) - 1
    nodes = interval_nodes(U, n, ntst, ncol) @ np.asarray(A, dtype=float).T  # (ntst, l, m)
    coef = np.einsum("dl,ilm->dim", _monomial_map(ncol), nodes)
    s = np.arange(samples) / samples
    return coef, s, np.einsum("jd,dim->jim", np.vander(s, ncol + 1, increasing=True), coef)


@lru_cache(maxsize=None)
def _monomial_map(ncol: int) -> np.ndarray:
    """``V^-1`` (read-only): monomial coefficients from the values at the ``NCOL + 1``
    equidistant local nodes (``V`` their Vandermonde matrix)."""
    inverse = np.linalg.inv(np.vander(np.linspace(0.0, 1.0, ncol + 1), increasing=True))
    inverse.flags.writeable = False
    return inverse


def _interval_minima(coef, s, v, sign) -> tuple[np.ndarray, np.ndarray]:
    """Per interval and row of ``sign * p`` (``p`` the polynomials ``coef``, ``v`` the
    signed samples): the local time of its minimum and the minimum, by Newton from the
    best sample (kept where it improves the sample).

    Only the intervals whose minimum could be below the row's best sample are polished:
    every time in ``[0, 1]`` lies within ``1 / samples`` of a sample, and ``|p'| <=
    sum_d d |c_d|`` there, so an interval whose best sample exceeds the row's by more
    than that bound keeps its sample (its minimum cannot be the row's)."""
    best = np.argmin(v, axis=0)
    t = s[best]                                             # (interval, row)
    sampled = v.min(axis=0)
    d = np.arange(1, coef.shape[0])[:, None, None] * coef[1:]   # derivative coefficients
    slope = np.abs(d).sum(axis=0) / len(s)
    i, j = np.nonzero(sampled - slope < sampled.min(axis=0))
    d, dd = d[:, i, j], np.arange(1, d.shape[0])[:, None] * d[1:, i, j]
    horner = lambda a, t: np.polynomial.polynomial.polyval(t, a, tensor=False)
    u = t[i, j]
    for _ in range(8):
        curvature = horner(dd, u)
        step = np.divide(horner(d, u), curvature, out=np.zeros_like(u), where=curvature != 0)
        u, last = np.clip(u - step, 0.0, 1.0), u
        if np.array_equal(u, last):                         # converged (or at the ends)
            break
    polished = sign * horner(coef[:, i, j], u)
    better = polished < sampled[i, j]
    t[i[better], j[better]] = u[better]
    sampled[i[better], j[better]] = polished[better]
    return t, sampled


def phase_coefficients(U_ref: np.ndarray, n: int, ntst: int, ncol: int) -> np.ndarray:
    """``c`` with ``c . U = int_0^1 <u, v'> dt`` for the reference ``v = U_ref``.

    ``sum_i sum_k w_k <u(z_ik), v'(z_ik)> h_i``; ``h_i`` cancels against
    ``v' = (1/h_i) sum_l Dm[k, l] v_il``, so the coefficients of interval ``i``'s nodes
    are ``Q v_i`` with ``Q = P^T diag(w) Dm`` (:func:`phase_matrix`).
    """
    v = interval_nodes(U_ref, n, ntst, ncol)               # (ntst, ncol+1, n)
    c = phase_matrix(ncol) @ v                             # (ntst, ncol+1, n)
    out = c[:, :-1, :].copy()
    out[1:, 0, :] += c[:-1, -1, :]
    out[0, 0, :] += c[-1, -1, :]
    return out.reshape(-1)


@lru_cache(maxsize=None)
def phase_matrix(ncol: int) -> np.ndarray:
    """``Q[l', l] = sum_k w_k P[k, l'] Dm[k, l]`` (read-only): the phase condition's
    coefficients of the nodes ``l'`` of an interval from the reference's nodes ``l``."""
    col = collocation(ncol)
    Q = col.P.T @ (col.w[:, None] * col.Dm)
    Q.flags.writeable = False
    return Q


def interval_function(vf, ncol: int) -> ca.Function:
    """``r(u_nodes[n x (ncol+1)], T, p, h) -> [n x ncol]`` collocation residual."""
    col, S, n = collocation(ncol), vf.sym, vf.n
    u, T, h = S.sym("u", n, ncol + 1), S.sym("T"), S.sym("h")
    p = S.sym("p", len(vf.par_names))
    res = []
    for k in range(ncol):
        uk = ca.mtimes(u, ca.DM(col.P[k]))
        duk = ca.mtimes(u, ca.DM(col.Dm[k]))
        lhs = duk if vf.M is None else ca.mtimes(vf.M_expr(uk, p), duk)
        res.append(lhs - h * T * vf.F_expr(uk, p))
    return ca.Function("colloc_interval", [u, T, p, h], [ca.horzcat(*res)])


def builder(ntst: int, ncol: int):
    """``builder(vf) -> CompiledSystem`` of the collocation system ``G(U, T, p; h, c)``."""

    def build(vf) -> CompiledSystem:
        n, S = vf.n, vf.sym
        U, T = S.sym("U", n * ntst * ncol), S.sym("T")
        p, D = S.sym("p", len(vf.par_names)), S.sym("D", ntst + n * ntst * ncol)
        h, c = D[:ntst], D[ntst:]
        u = ca.horzcat(ca.reshape(U, n, ntst * ncol), U[:n])
        blocks = [u[:, i * ncol: i * ncol + ncol + 1] for i in range(ntst)]
        r = interval_function(vf, ncol).map(ntst)(ca.horzcat(*blocks), T, p, h.T)
        return CompiledSystem(ca.vertcat(U, T), p, D,
                              [ca.vec(r), ca.dot(c, U)], f"collocation_{ntst}_{ncol}")

    return build
