"""Switching from a generalized Hopf (Bautin) point of a Hopf curve onto the curve of
folds of cycles (LPC) born there, and from a double Hopf point (:func:`ns_from_hh`) or a
zero-Hopf point (:func:`ns_from_zh`) onto the torus (Neimark-Sacker) curve of the curve's
cycles.

Near the point the normal form (``_equilibria.normal_forms``, ``|q| = 1``) is
``z' = (beta1 + i omega) z + c1 z |z|^2 + c2 z |z|^4`` with ``beta1 = Re lambda``,
``Re c1 = omega l1``, ``Re c2 = omega l2``; its cycles ``|z|^2 = s`` solve
``beta1 + omega l1 s + omega l2 s^2 = 0``, and two of them merge (the LPC) where the
root is double:

    s = |z|^2 = -l1 / (2 l2),   beta1 = omega l1^2 / (4 l2),

which exists on the side of the Hopf curve where ``l1 l2 < 0`` (for the Bautin form
``w' = (mu + i omega) w + a w|w|^2 + b w|w|^4``: ``mu = a^2 / (4 b)``, ``|w|^2 = -a / (2b)``).
The predictor takes the Hopf point ``(x_H, p_H)`` a distance ``epsilon`` along the Hopf
curve from the Bautin point (on that side), its ``l1, l2, omega``, and maps ``beta1``
to the parameter ``active`` by the crossing speed ``d Re lambda / d p_active``; the cycle
``x_eq + 2 Re(z e^(2 pi i t) q)`` with ``|z|^2 = s`` is then corrected onto the fold
(:func:`locate_cycle` with :class:`CycleFold`). Errors of the predictor are of higher
order in ``epsilon``; the corrector removes them.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .conditions import CycleFold, NeimarkSacker
from .cycle_curves import CycleCurveProblem, locate_cycle
from .switching import crossing_speed, cycle_from_hopf, small_cycle
from .._driver.driver import continuation
from .._driver.settings import ContinuationSettings
from .._driver.branch import SpecialPoint
from .._driver.newton import factorize, newton
from .._driver.settings import EigenSettings, NewtonSettings
from .settings import CollocationSettings
from .._equilibria import eigen
from .._equilibria.curves import HopfCurveProblem
from .._equilibria.normal_forms import lyapunov_coefficients
from .._linalg.sparse import append_row


def lpc_from_gh(curve: HopfCurveProblem, point: SpecialPoint, *, epsilon: float = 1e-2,
                active: str | None = None, settings: CollocationSettings | None = None,
                newton_settings: NewtonSettings = NewtonSettings()) -> CycleCurveProblem:
    """The fold-of-cycles curve born at the generalized Hopf ``point`` (a located 'gh'
    SpecialPoint of ``curve``'s branch), as a :class:`CycleCurveProblem` in the curve's
    two parameters at its first located fold (``X0``).

    ``epsilon``: distance in the parameter plane along the Hopf curve from ``point`` to
    the Hopf point the predictor starts from; ``active``: the parameter the predictor
    moves off the Hopf curve (default: the one the curve's tangent moves least). The
    returned problem's last free parameter is the other one; ``away_direction`` (+1/-1)
    is the ``direction`` that continues away from the Bautin point. Raises
    RuntimeError when the corrector fails (try a smaller ``epsilon``).
    """
    X_gh, t, active, other = _start(curve, point, "gh", epsilon, active)
    X_H, l1, l2, omega = _hopf_on_fold_side(curve, X_gh, t, epsilon, newton_settings)
    vf, x_H, p_H = curve.vf, curve.state(X_H), curve.params(X_H)
    beta1 = omega * l1 ** 2 / (4 * l2)
    alpha = crossing_speed(vf, x_H, p_H, vf.par_index(active), omega, abs(beta1))
    guess = small_cycle(vf, x_H, p_H, active, omega, beta1 / alpha,
                        np.sqrt(-l1 / (2 * l2)), settings)
    return _corrected(guess, guess.X0, CycleFold(), newton_settings, curve, X_gh, X_H,
                      (active, other))


def ns_from_hh(curve: HopfCurveProblem, point: SpecialPoint, *, epsilon: float = 1e-2,
               active: str | None = None, settings: CollocationSettings | None = None,
               newton_settings: NewtonSettings = NewtonSettings()) -> CycleCurveProblem:
    """The Neimark-Sacker curve of the cycles born on ``curve`` near its double Hopf
    ``point`` (an 'hh' SpecialPoint with ``p11``, ``p21``), as a :class:`CycleCurveProblem`
    in the curve's two parameters at its first located torus bifurcation (``X0``).

    In the amplitude equations ``r1' = r1 (mu1 + p11 r1^2 + p12 r2^2)``, ``r2' = r2 (mu2 +
    p21 r1^2 + p22 r2^2)`` (pair 1 the curve's) the cycles ``r1^2 = -mu1 / p11`` lose
    stability in ``r2`` (a torus is born) at ``mu2 + p21 r1^2 = 0``. The predictor takes
    the Hopf point ``epsilon`` along the curve (``mu1 = 0``, ``mu2`` the real part of the
    other pair there) and moves ``active`` by ``dp = -mu2 / (a2 - a1 p21 / p11)`` (``a_k =
    d Re lambda_k / d p_active``), on the side where ``r1^2 = -a1 dp / p11 > 0``; the cycle
    is corrected by :func:`locate_cycle` with :class:`NeimarkSacker`. ``active`` and
    ``away_direction`` as for :func:`lpc_from_gh`.
    """
    X_hh, t, active, other = _start(curve, point, "hh", epsilon, active)
    if "p11" not in point.data:
        raise ValueError(f"the double Hopf point has no coefficients ({point.message})")
    X_H, dp, r2, omega1 = _torus_side(curve, X_hh, t, epsilon, active, point.data,
                                      newton_settings)
    guess = small_cycle(curve.vf, curve.state(X_H), curve.params(X_H), active, omega1, dp,
                        np.sqrt(r2), settings)
    return _corrected(guess, guess.X0, NeimarkSacker(), newton_settings, curve, X_hh, X_H,
                      (active, other))


def ns_from_zh(curve: HopfCurveProblem, point: SpecialPoint, *, epsilon: float = 1e-2,
               active: str | None = None, settings: CollocationSettings | None = None,
               max_steps: int = 200,
               newton_settings: NewtonSettings = NewtonSettings()) -> CycleCurveProblem:
    """The Neimark-Sacker curve of the cycles born on ``curve`` near its zero-Hopf
    ``point`` (a 'zh' SpecialPoint with ``s``, ``theta``), as a :class:`CycleCurveProblem`
    in the curve's two parameters at its first located torus bifurcation (``X0``).

    In the amplitude equations ``xi' = beta1 + B xi^2 + C r^2``, ``r' = r (beta2 + Re(D)
    xi + ...)`` the cycles are the equilibria with ``r > 0``; their 2x2 Jacobian has the
    determinant ``-2 C Re(D) r^2``, so a torus is born on them (the trace crossing zero)
    only where ``C Re(D) < 0``, i.e. ``s theta < 0`` (``s = sign(B C)``, ``theta = Re(D) /
    B``); elsewhere a ValueError says so. The unfolding's higher-order terms place the
    curve, so it is found by continuation rather than predicted: from the Hopf point a
    distance ``epsilon`` along the curve (either side), the cycles born there
    (:func:`cycle_from_hopf`) are continued in ``active`` (default: the parameter the
    curve moves least at the point, the one that opens the cycles) for at most
    ``max_steps`` points until a torus bifurcation, which :func:`locate_cycle` refines.
    ``away_direction`` as for :func:`lpc_from_gh`. Raises RuntimeError when no torus
    bifurcation is met (try another ``epsilon``).
    """
    X_zh, t, active, other = _start(curve, point, "zh", epsilon, active)
    if "s" not in point.data or "theta" not in point.data:
        raise ValueError(f"the zero-Hopf point has no coefficients ({point.message})")
    s, theta = float(point.data["s"]), float(point.data["theta"])
    if not s * theta < 0:
        raise ValueError(f"no torus curve at this zero-Hopf point: s theta = {s * theta:.3g}"
                         " >= 0, so the cycles born near it have no Neimark-Sacker "
                         "bifurcation")
    X_H, problem, X = _first_torus(curve, X_zh, t, epsilon, active, settings, max_steps,
                                   newton_settings)
    return _corrected(problem, X, NeimarkSacker(), newton_settings, curve, X_zh, X_H,
                      (active, other))


def _first_torus(curve, X_zh, t, epsilon, active, settings, max_steps, newton_settings):
    """``(X_H, problem, X)``: the Hopf point ``+-epsilon`` along the curve and the first
    torus bifurcation of the cycles born there, continued in ``active``."""
    tried = []
    for sign in (1.0, -1.0):
        X_H = _along(curve, X_zh, t, sign * epsilon, newton_settings)
        if X_H is None:
            continue
        cycles = cycle_from_hopf(curve, X_H, dp=epsilon ** 2, settings=settings,
                                 active=active)
        branch = continuation(cycles, settings=ContinuationSettings(
            ds=epsilon, ds_max=10 * epsilon, max_steps=max_steps,
            direction=cycles.hopf_direction, stop_at=("ns",)))
        torus = branch.special("ns")
        if torus:
            return (X_H, *cycles.at(torus[0]))
        tried.append(f"{branch.status} after {len(branch.s)} points ({branch.message})")
    raise RuntimeError("no torus bifurcation on the cycles born near the zero-Hopf point: "
                       + ("; ".join(tried) or "no Hopf point along the curve"))


def _corrected(guess, X, condition, settings, curve, X0, X_H, free) -> CycleCurveProblem:
    """The curve of ``condition`` in ``free`` through the cycle located from the cycle
    ``X`` of ``guess``; ``away_direction``: the side of the curve's point ``X0`` that its
    Hopf point ``X_H`` (the predictor's) lies on, in the last of ``free``."""
    located, res = locate_cycle(guess, X, condition, settings)
    if not res.converged:
        raise RuntimeError(f"the {type(condition).__name__} cycle was not located near the "
                           f"codimension-two point ({res.message}); try a smaller epsilon")
    out = CycleCurveProblem(located, res.X, free, condition)
    k = curve.vf.par_index(free[-1])
    out.away_direction = 1 if curve.params(X_H)[k] > curve.params(X0)[k] else -1
    return out


def _start(curve, point, kind, epsilon, active):
    """``(X, t, active, other)``: the ``kind`` point's unknowns, the curve's unit tangent
    in its parameters there, the parameter moved off the curve (default: the one ``t``
    moves least) and the other."""
    if not isinstance(point, SpecialPoint) or point.kind != kind or point.unknowns.size == 0:
        raise ValueError(f"point must be a {kind!r} SpecialPoint of a Hopf curve's branch")
    if not (np.isfinite(epsilon) and epsilon > 0):
        raise ValueError(f"epsilon must be a positive finite number, got {epsilon!r}")
    X = np.asarray(point.unknowns, dtype=float)
    t = _curve_tangent(curve, X)[-2:]
    t /= np.linalg.norm(t)
    active = active or curve.free[int(np.argmin(np.abs(t)))]
    if active not in curve.free:
        raise ValueError(f"active must be one of {curve.free}, got {active!r}")
    return X, t, active, curve.free[1 - curve.free.index(active)]


def _torus_side(curve, X_hh, t, epsilon, active, data, settings):
    """``(X_H, dp, r1^2, omega1)``: the Hopf point ``+-epsilon`` along the curve from
    the double Hopf point and the offset of ``active`` to its cycles' torus bifurcation,
    on the side where ``r1^2 > 0`` (see :func:`ns_from_hh`)."""
    p11, p21, omega2 = (float(data[k]) for k in ("p11", "p21", "omega2"))
    vf, ia = curve.vf, curve.vf.par_index(active)
    for sign in (1.0, -1.0):
        X_H = _along(curve, X_hh, t, sign * epsilon, settings)
        if X_H is None:
            continue
        x_H, p_H, omega1 = curve.state(X_H), curve.params(X_H), float(np.sqrt(curve.kappa(X_H)))
        second = eigen.nearest(eigen.eigenvalues(vf.jac_x(x_H, p_H), vf.mass(x_H, p_H),
                                                 EigenSettings()), 1j * omega2)
        a1, a2 = (crossing_speed(vf, x_H, p_H, ia, w, epsilon) for w in (omega1, second.imag))
        dp = -second.real / (a2 - a1 * p21 / p11)
        if -a1 * dp / p11 > 0:
            return X_H, dp, -a1 * dp / p11, omega1
    raise RuntimeError(f"no cycles with a torus bifurcation at distance {epsilon} along the "
                       "curve")


def _curve_tangent(curve, X) -> np.ndarray:
    """Unit null vector of ``G_X`` (``m x (m+1)``) at ``X``."""
    rng = np.random.default_rng(3)
    lu = factorize(sp.csc_matrix(append_row(curve.jacobian(X), rng.standard_normal(X.size))))
    if lu is None:
        raise np.linalg.LinAlgError("the Hopf curve is singular at the Bautin point")
    e = np.zeros(X.size)
    e[-1] = 1.0
    tau = lu.solve(e)
    return tau / np.linalg.norm(tau)


def _along(curve, X0, t, step, settings):
    """The point of the curve with ``t . (p - p0) = step`` (``t`` a unit vector in the
    curve's parameters, ``p0`` those of ``X0``), by Newton from the tangent's guess; None
    if Newton fails or the pair is no longer complex."""
    full = _curve_tangent(curve, X0)
    full /= full[-2:] @ t
    row = np.zeros(X0.size)
    row[-2:] = t
    target = step + t @ X0[-2:]
    res = newton(lambda X: np.append(curve.residual(X), row @ X - target),
                 lambda X: append_row(curve.jacobian(X), row), X0 + step * full, settings)
    return res.X if res.converged and curve.kappa(res.X) > 0 else None


def _hopf_on_fold_side(curve, X_gh, t, epsilon, settings):
    """``(X_H, l1, l2, omega)`` at the Hopf point with ``t . (p - p_gh) = +-epsilon``
    (``t`` the unit tangent in the curve's parameters) on the side where ``l1 l2 < 0``."""
    tried = []
    for sign in (1.0, -1.0):
        X = _along(curve, X_gh, t, sign * epsilon, settings)
        if X is None:
            continue
        omega = float(np.sqrt(curve.kappa(X)))
        c = lyapunov_coefficients(curve.vf, curve.state(X), curve.params(X), omega)
        tried.append((c["l1"], c["l2"]))
        if c["l1"] * c["l2"] < 0:
            return X, c["l1"], c["l2"], omega
    raise RuntimeError(f"no Hopf point with l1 l2 < 0 at distance {epsilon} along the "
                       f"curve (l1, l2 = {tried})")
