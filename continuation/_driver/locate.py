"""Location of a special point bracketed by two consecutive branch points.

Points between ``X_a`` and ``X_b`` are parametrized by the arclength-like
``s = tau_a . (X - X_a)``: ``X(s)`` is the PALC corrector from
``X_a + s tau_a``. A smooth test function ``f(X(s))`` is driven to zero by the
Illinois variant of regula falsi, which keeps a bracket and converges
superlinearly; count-type tests (no smooth function) use bisection. The result
is ``'converged'`` when the bracket is below ``settings.locate_tol``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .palc import correct, tangent


@dataclass(frozen=True)
class Located:
    """A located point: ``X``, its tangent, whether the bracket reached the
    tolerance, and (when found by iteration) its arclength ``s = tau_a . (X - X_a)``,
    test-function ``value`` and the corrector's ``iterations``/``residual``."""

    X: np.ndarray
    tau: np.ndarray
    converged: bool
    bracket: float
    message: str = ""
    bracketed: bool = True
    s: float = float("nan")
    value: float = float("nan")
    iterations: int = 0
    residual: float = 0.0


def locate(problem, kind, a, b, settings, function=None) -> Located:
    """Locate ``kind`` between monitored points ``a = (step, info)`` and ``b``;
    ``function(X, tau, lu)`` (smooth, e.g. a user event) replaces the problem's
    test function when given."""
    (sa, ia), (sb, ib) = a, b
    f = function if function is not None else \
        problem.test_function(kind, sa.X, ia, sb.X, ib, settings)
    smooth = f is not None
    if not smooth:
        f = _count_function(problem, kind, ia, settings)
    evaluate = _evaluator(problem, sa, f, settings)
    sb_arc = float(sa.tau @ (sb.X - sa.X))
    lo, hi = evaluate(0.0), evaluate(sb_arc)
    if lo is None or hi is None or lo[3] * hi[3] > 0:
        return Located(sb.X, sb.tau, False, abs(sb_arc),
                       "test function has no sign change on re-evaluation", False, sb_arc)
    return _illinois(evaluate, lo, hi, smooth, settings)


def _evaluator(problem, sa, f, settings):
    """``evaluate(s) -> (s, X, tau, f, NewtonResult)`` on the branch at arclength
    ``s`` from ``sa`` (None if the corrector fails)."""
    def evaluate(s):
        res = correct(problem, sa.X + s * sa.tau, sa.tau, settings.newton)
        if not res.converged:
            return None
        tau, lu = tangent(problem, res.X, sa.tau)
        if tau is None:
            return (s, res.X, sa.tau, 0.0, res)
        return (s, res.X, tau, f(res.X, tau, lu), res)
    return evaluate


def _located(point, converged, width, message="") -> Located:
    """``Located`` from an evaluated ``(s, X, tau, f, NewtonResult)``."""
    s, X, tau, value, res = point
    return Located(X, tau, converged, width, message, True, float(s), float(value),
                   int(res.iterations), float(res.residual))


def _count_function(problem, kind, info_a, settings):
    ref = info_a.counts[kind]
    return lambda X, tau, lu: 1.0 if problem.monitor(X, tau, lu, settings).counts[kind] \
        == ref else -1.0


def _illinois(evaluate, lo, hi, smooth, settings) -> Located:
    """Regula falsi (Illinois) or bisection on ``(s, X, tau, f)`` brackets; where the
    corrector fails at the regula falsi point, the bracket's midpoint is tried (on a
    stiff impacting branch one such failure stopped a location at 6e-4 in arclength)."""
    fa, fb = lo[3], hi[3]
    last = hi
    for _ in range(settings.locate_max_iter):
        width = abs(hi[0] - lo[0])
        if last[3] == 0.0:
            return _located(last, True, 0.0)
        if width <= settings.locate_tol:
            return _located(last, True, width)
        s = hi[0] - fb * (hi[0] - lo[0]) / (fb - fa) if smooth else 0.5 * (lo[0] + hi[0])
        if not min(lo[0], hi[0]) < s < max(lo[0], hi[0]):
            s = 0.5 * (lo[0] + hi[0])
        mid = evaluate(s)
        if mid is None and s != 0.5 * (lo[0] + hi[0]):
            mid = evaluate(0.5 * (lo[0] + hi[0]))   # the corrector failed: bisect instead
        if mid is None:
            break
        if mid[3] * fb < 0:
            lo, fa = hi, fb
        else:
            fa *= 0.5
        hi, fb, last = mid, mid[3], mid
    width = abs(hi[0] - lo[0])
    return _located(last, width <= settings.locate_tol, width,
                    f"location stopped with bracket {width:.3e}")
