"""Branch switching onto cycles: from a Hopf point of an equilibrium branch or any
point of a Hopf curve, and
from the period doublings and branch points of a cycle branch.

At a Hopf point ``(x_H, p_H)`` with ``J q = i omega M q`` (``|q| = 1``) and
first Lyapunov coefficient ``l1`` (normalization of ``_equilibria.lyapunov``), the
normal form ``zdot = (i omega + alpha' dp) z + l1 omega z |z|^2`` gives the
small cycle

    x(t) ~ x_eq(p_H + dp) + 2 Re(z e^(2 pi i t) q),   |z|^2 = -alpha' dp / (l1 omega),
    T ~ 2 pi / omega,

with ``alpha' = d Re lambda / dp`` at the Hopf point (central difference on
corrected equilibria). The side of ``dp`` is the one where ``|z|^2 > 0``:
``dp > 0`` for a supercritical Hopf point whose pair crosses to the right with
increasing ``p``. (For ``xdot = mu x - y + a x r^2``, ``l1 = 2a``, ``alpha' = 1``:
``r^2 = 2 |z|^2 = -mu / a``, the exact radius.)
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from .cycles import CycleProblem
from .._driver.branch import SpecialPoint
from .._driver.newton import factorize, newton
from .._driver.settings import EigenSettings, NewtonSettings
from .settings import CollocationSettings
from .._equilibria import eigen
from .._equilibria.curves import HopfCurveProblem
from .._equilibria.lyapunov import first_lyapunov, hopf_eigenvectors


def cycle_from_hopf(problem, point, *, dp: float = 1e-3,
                    settings: CollocationSettings | None = None,
                    active: str | None = None) -> CycleProblem:
    """A :class:`CycleProblem` started on the small cycle born at ``point``.

    ``problem`` is the EquilibriumProblem whose branch holds the Hopf ``point``
    (with ``data['omega']`` and ``data['l1']``), or a HopfCurveProblem and ``point``
    any point of its curve (a SpecialPoint of the curve's branch, or the curve's
    unknowns ``X``) with ``active``, one of the curve's two parameters, the cycle's
    continuation parameter (the other stays fixed; ``l1`` is computed there). ``dp > 0``
    is the size of the parameter offset, its sign is chosen by the normal form. The
    returned problem's ``X0`` is the normal-form guess; ``hopf_direction`` (+1/-1) is
    the side of the Hopf point the cycles live on (use it as ``direction``).
    """
    if isinstance(problem, HopfCurveProblem):
        x_H, p_H, omega, l1, active = hopf_curve_point(problem, point, active)
    else:
        if not isinstance(point, SpecialPoint) or point.kind != "hopf":
            raise ValueError("point must be a 'hopf' SpecialPoint")
        if "l1" not in point.data or "omega" not in point.data:
            raise ValueError(f"point.data must hold 'omega' and 'l1', got {sorted(point.data)}")
        l1, omega, active = float(point.data["l1"]), float(point.data["omega"]), problem.active
        x_H, p_H = point.x, np.array([point.params[k] for k in problem.vf.par_names], float)
    if l1 == 0 or not np.isfinite(l1):
        raise ValueError(f"l1 must be finite and nonzero at the Hopf point, got {l1!r}")
    if not (np.isfinite(dp) and dp > 0):
        raise ValueError(f"dp must be a positive finite number, got {dp!r}")
    vf = problem.vf
    alpha = crossing_speed(vf, x_H, p_H, vf.par_index(active), omega, dp)
    sign = 1.0 if -alpha / (l1 * omega) > 0 else -1.0
    cycle = small_cycle(vf, x_H, p_H, active, omega, sign * dp,
                        np.sqrt(abs(alpha * dp / (l1 * omega))), settings)
    cycle.hopf_direction = int(sign)
    return cycle


def hopf_curve_point(curve: HopfCurveProblem, point, active):
    """``(x, p, omega, l1, active)`` at a point of a Hopf curve (a SpecialPoint with
    its unknowns, or the unknowns ``X``); ``active`` must be one of the curve's two."""
    X = point.unknowns if isinstance(point, SpecialPoint) else np.asarray(point, float)
    if X.size != curve.X0.size:
        raise ValueError(f"the point needs the Hopf curve's {curve.X0.size} unknowns, "
                         f"got {X.size}")
    if active not in curve.free:
        raise ValueError(f"active must be one of the curve's parameters {curve.free}, "
                         f"got {active!r}")
    if curve.kappa(X) <= 0:
        raise ValueError("no Hopf point here: kappa = omega^2 <= 0 (a neutral saddle)")
    omega = float(np.sqrt(curve.kappa(X)))
    x, p = curve.state(X), curve.params(X)
    return x, p, omega, first_lyapunov(curve.vf, x, p, omega), active


def small_cycle(vf, x_H, p_H, active: str, omega: float, dp: float, z: float,
                settings) -> CycleProblem:
    """The cycle ``x_eq(p) + 2 Re(z e^(2 pi i t) q)``, ``T = 2 pi / omega``, at ``p`` =
    ``p_H`` with ``dp`` added to ``active`` (``q`` of the eigenvalue near ``i omega``
    at the equilibrium there, ``|q| = 1``)."""
    p = np.array(p_H, dtype=float)
    p[vf.par_index(active)] += dp
    x_eq = _equilibrium(vf, x_H, p)
    J, M = vf.jac_x(x_eq, p), vf.mass(x_eq, p)
    q, _ = hopf_eigenvectors(sp.csc_matrix(J, dtype=complex), sp.csc_matrix(M, dtype=complex),
                             omega)

    def orbit(t):
        t = np.atleast_1d(t)
        return x_eq[None, :] + 2 * z * np.real(np.exp(2j * np.pi * t)[:, None] * q[None, :])

    params = dict(zip(vf.par_names, map(float, p)))
    return CycleProblem(vf, orbit, 2 * np.pi / omega, params, active, settings=settings)


def _equilibrium(vf, x0, p) -> np.ndarray:
    """Equilibrium near ``x0`` at parameters ``p`` (Newton on ``F = 0``)."""
    res = newton(lambda x: vf.rhs(x, p), lambda x: vf.jac_x(x, p), np.asarray(x0, float),
                 NewtonSettings(tol=1e-12, max_iter=20))
    return res.X


def crossing_speed(vf, x, p, ia, omega, dp) -> float:
    """``d Re lambda / dp`` of the eigenvalue near ``i omega`` (central difference)."""
    h = min(dp, 1e-4) * max(1.0, abs(p[ia]))
    re = []
    for s in (1.0, -1.0):
        pp = p.copy()
        pp[ia] += s * h
        xe = _equilibrium(vf, x, pp)
        ev = eigen.eigenvalues(vf.jac_x(xe, pp), vf.mass(xe, pp), EigenSettings())
        re.append(eigen.nearest(ev, 1j * omega).real)
    return (re[0] - re[1]) / (2 * h)


def floquet_eigenfunction(problem: CycleProblem, X, multiplier: complex) -> np.ndarray:
    """Node values ``(NTST NCOL, n)`` of the real Floquet solution ``v`` with
    ``v(1) = mu v(0)`` for the (real) multiplier nearest ``multiplier``.

    ``v_0`` is the eigenvector of the condensed monodromy ``A_{N-1}...A_0``; the
    other nodes follow from the condensation maps of each interval. Scaled to
    ``max |v| = 1``.
    """
    n = problem.vf.n
    full = problem.transfer_matrices(X, full=True)            # (ntst, n ncol, n)
    mono = np.eye(n)
    for Xi in full:
        mono = Xi[-n:] @ mono
    w, vecs = np.linalg.eig(mono)
    v = np.real(vecs[:, np.argmin(np.abs(w - multiplier))])
    rows = []
    for Xi in full:
        rows.append(np.vstack([v[None, :], (Xi[:-n] @ v).reshape(-1, n)]))
        v = Xi[-n:] @ v
    V = np.vstack(rows)
    return V / np.max(np.abs(V))


def cycle_from_pd(problem: CycleProblem, point: SpecialPoint, *, amplitude: float = 1e-2,
                  settings: CollocationSettings | None = None) -> CycleProblem:
    """The period-doubled branch born at the period-doubling ``point`` of a cycle branch.

    With ``u`` the cycle at the PD point (period ``T``) and ``v`` its Floquet
    solution for ``mu = -1`` (``v(t + T) = -v(t)``), the guess is

        u2(s) = u(2s) + a w(s),   w(s) = +v(2s) (s < 1/2),  -v(2s - 1) (s >= 1/2),

    with period ``2T`` on the point's mesh run through twice (``2 NTST`` intervals, each
    halved: an adapted mesh stays adapted), or uniform on ``settings.ntst`` intervals
    if ``settings`` are given. The start corrector fixes
    the amplitude ``w . (X - X0) = 0`` instead of the parameter (the doubled branch
    is tangent to ``w`` at the PD point), so ``direction=+1`` continues towards
    larger amplitudes.
    """
    problem, X = _switch_point(problem, point, "pd", amplitude)
    V = floquet_eigenfunction(problem, X, -1.0).ravel()

    def doubled(s, which):
        s = np.atleast_1d(s)
        sgn = np.where(s < 0.5, 1.0, -1.0)[:, None]
        w = sgn * problem.evaluate(np.r_[V, 0.0, 0.0], 2 * s)
        return w if which == "w" else problem.evaluate(X, 2 * s) + amplitude * w

    mesh = None if settings else np.concatenate([problem.mesh, 1.0 + problem.mesh[1:]]) / 2
    settings = settings or replace(problem.settings, ntst=2 * problem.ntst)
    new = CycleProblem(problem.vf, lambda s: doubled(s, "u"), 2 * problem.period(X),
                       problem.par_dict(X), problem.active, settings=settings, mesh=mesh)
    w = doubled(new.times(), "w").ravel()
    new.start_direction = np.concatenate([w / np.linalg.norm(w), [0.0, 0.0]])
    return new


def cycle_from_bp(problem: CycleProblem, point: SpecialPoint, *,
                  amplitude: float = 1e-2) -> CycleProblem:
    """The branch of cycles born at the branch point ``point`` of a cycle branch (a
    pitchfork: in a system with a symmetry, the cycles that break it).

    At a branch point ``G_X`` (``X = (U, T, p)``) has two null vectors: the branch's
    own tangent and the new branch's. A pitchfork's new branch leaves at fixed ``p``,
    so its direction ``phi`` is the combination of the two with no parameter part.
    Both come from :func:`_null_pair` (``G_X`` bordered by two random rows); the guess
    is ``X + a phi / max |phi_U|`` on the point's mesh, and the start corrector fixes
    the amplitude along ``phi`` instead of the parameter (``direction=+1`` continues
    towards larger ``a``; ``direction=-1`` passes through the branch point onto the
    mirror branch).
    """
    problem, X = _switch_point(problem, point, "bp", amplitude)
    w1, w2 = _null_pair(problem.jacobian(X))
    phi = w1 * w2[-1] - w2 * w1[-1]                # no part in the active parameter
    rows = problem.n_nodes * problem.vf.n
    phi /= np.max(np.abs(phi[:rows]))
    Y = X + amplitude * phi
    new = CycleProblem(problem.vf, lambda t: problem.evaluate(Y, t), problem.period(Y),
                       problem.par_dict(Y), problem.free, settings=problem.settings,
                       mesh=problem.mesh)
    new.start_direction = np.concatenate([phi[:rows] / np.linalg.norm(phi[:rows]),
                                          np.zeros(len(X) - rows)])
    return new


def _switch_point(problem, point, kind: str, amplitude: float):
    """``problem.at(point)`` once ``point`` is a ``kind`` point of ``problem``'s branch
    and ``amplitude`` positive (else ValueError)."""
    if not isinstance(problem, CycleProblem):
        raise ValueError("problem must be the CycleProblem whose branch holds the point")
    if not isinstance(point, SpecialPoint) or point.kind != kind or "X" not in point.data:
        raise ValueError(f"point must be a {kind!r} SpecialPoint of a cycle branch")
    if not (np.isfinite(amplitude) and amplitude > 0):
        raise ValueError(f"amplitude must be a positive finite number, got {amplitude!r}")
    return problem.at(point)


def _null_pair(J) -> tuple[np.ndarray, np.ndarray]:
    """Two independent vectors of the (near) two-dimensional null space of ``J`` (``m``
    x ``m + 1``, rank ``m - 1`` at a branch point): for random rows ``r``, the bordered
    ``[J; r^T]`` is (nearly) singular, and two steps of inverse iteration with it return
    its null vector, the element of ``null(J)`` with ``r^T w = 0``. The LU keeps the
    fill-reducing ordering of the corrector's bordered matrices (``factorize``): SciPy's
    default ordering pivots on the dense row and fills the factors (a cycle of 1600
    intervals ran out of 24 GB)."""
    rng = np.random.default_rng(0)
    J = sp.csc_matrix(J)
    out = []
    for _ in range(2):
        A = sp.vstack([J, sp.csr_matrix(rng.standard_normal(J.shape[1]))]).tocsc()
        lu = factorize(A)
        if lu is None:
            raise np.linalg.LinAlgError("the bordered Jacobian of the branch point is singular")
        w = lu.solve(rng.standard_normal(J.shape[1]))
        w = lu.solve(w / np.linalg.norm(w))
        out.append(w / np.linalg.norm(w))
    return out[0], out[1]
