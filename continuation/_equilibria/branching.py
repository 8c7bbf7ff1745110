"""Branch switching at a simple branch point of equilibria (transcritical or pitchfork).

At a simple branch point ``X* = (x*, p*)`` of ``G(X) = F(x, p) = 0`` (``p`` the active
parameter) ``G_X = [F_x, F_p]`` has a two-dimensional null space ``span(phi1, phi2)`` and
a left null vector ``psi``. The branches through ``X*`` leave along the directions
``t = a1 phi1 + a2 phi2`` that solve the algebraic branching equation (Keller; AUTO,
MatCont)

    psi^T G_XX(t, t) = c11 a1^2 + 2 c12 a1 a2 + c22 a2^2 = 0,
    c_jk = psi^T G_XX(phi_j, phi_k),

two real directions when ``c12^2 > c11 c22``. One is the tangent of the branch the point
was found on; the new branch leaves along the other. ``G_XX(u, u)`` is the second
derivative of ``F`` along ``u`` in ``(x, p)`` (CasADi AD). For ``x' = mu x - x^2`` the
directions are ``(0, 1)`` (the trivial branch) and ``(1, 1)`` (``x = mu``); for
``x' = mu x - x^3`` ``(0, 1)`` and ``(1, 0)``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .equilibrium import EquilibriumProblem
from .._driver.branch import SpecialPoint


def equilibrium_from_bp(problem, point: SpecialPoint, *, amplitude: float = 1e-2):
    """The other branch of equilibria through the branch point ``point`` of ``problem``'s
    branch: the guess is ``X* + a t`` along the other root ``t`` of the branching
    equation (the root farther from the point's ``tangent``; a point without one, e.g.
    reloaded from a file, takes the root with the smaller parameter part, a pitchfork's),
    scaled to ``max |t| = 1`` with its largest entry positive; the start corrector fixes
    the amplitude along ``t`` instead of the parameter: ``direction=+1`` continues away
    from the point on the side of the sign of ``amplitude``, and the two signs give the
    two halves of the new branch."""
    if not isinstance(problem, EquilibriumProblem):
        raise ValueError("problem must be the EquilibriumProblem whose branch holds the point")
    if not isinstance(point, SpecialPoint) or point.kind != "bp" or not point.unknowns.size:
        raise ValueError("point must be a located 'bp' SpecialPoint of an equilibrium branch")
    if not (np.isfinite(amplitude) and amplitude != 0):
        raise ValueError(f"amplitude must be a nonzero finite number, got {amplitude!r}")
    X, n = np.asarray(point.unknowns, dtype=float), problem.vf.n
    t = _other_direction(problem, X, np.asarray(point.tangent, dtype=float))
    Y = X + amplitude * t
    params = dict(point.params, **{problem.active: float(Y[-1])})
    new = EquilibriumProblem(problem.vf, Y[:n], params, problem.active)
    new.start_direction = np.sign(amplitude) * t / np.linalg.norm(t)
    return new


def branch_directions(problem, X) -> list:
    """The unit directions ``t`` (in ``X = (x, p)``) of the branches through the simple
    branch point ``X``: the real roots of the branching equation."""
    A = problem.jacobian(X)
    U, _, Vt = np.linalg.svd(A.toarray() if sp.issparse(A) else np.asarray(A))
    psi, (phi1, phi2) = U[:, -1], Vt[-2:]
    x, p, ia = problem.state(X), problem.params(X), problem.vf.par_index(problem.active)

    def c(u):
        w = np.zeros(p.size)
        w[ia] = u[-1]
        return float(psi @ problem.vf.second_derivative(x, p, u[:-1], w))

    c11, c22 = c(phi1), c(phi2)
    c12 = 0.5 * (c(phi1 + phi2) - c11 - c22)
    out = [a1 * phi1 + a2 * phi2 for a1, a2 in _roots(c11, c12, c22)]
    return [t / np.linalg.norm(t) for t in out]


def _roots(c11, c12, c22) -> list:
    """The two directions ``(a1, a2)`` with ``c11 a1^2 + 2 c12 a1 a2 + c22 a2^2 = 0``."""
    disc = c12 ** 2 - c11 * c22
    scale = max(abs(c11), abs(c12), abs(c22))
    if scale == 0 or disc < -1e-10 * scale ** 2:
        raise ValueError("not a simple branch point: the branching equation has no two "
                         f"real roots (c11, c12, c22 = {c11:.3g}, {c12:.3g}, {c22:.3g})")
    # q solves q^2 + 2 c12 q + c11 c22 = 0 without cancellation: (c22, q), (q, c11)
    q = -(c12 + (1.0 if c12 >= 0 else -1.0) * np.sqrt(max(disc, 0.0)))
    return [(c22, q), (q, c11)]


def _other_direction(problem, X, tangent) -> np.ndarray:
    """The root of the branching equation farther from ``tangent`` (none: the one with
    the smaller parameter part)."""
    ts = branch_directions(problem, X)
    if tangent.size == X.size and np.linalg.norm(tangent) > 0:
        key = lambda t: abs(t @ tangent) / np.linalg.norm(tangent)
    else:
        key = lambda t: abs(t[-1])
    t = min(ts, key=key)
    big = t[np.argmax(np.abs(t))]
    return t / big
