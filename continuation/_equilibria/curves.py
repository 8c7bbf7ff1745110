"""Two-parameter continuation of Hopf and fold curves (codimension-1 curves).

Both are the augmented systems of ``systems`` with two free parameters
``free = (p_a, p_b)``; ``p_b`` is the continuation parameter of the curve.

Codimension-two points are reported by sign changes:

* Hopf curve ``X = (x, v, w, kappa, p_a, p_b)``:
  Bogdanov-Takens ``'bt'``: ``kappa = omega^2`` changes sign (the curve
  continues as a neutral-saddle curve); generalized Hopf ``'gh'``: the first
  Lyapunov coefficient ``l1`` changes sign; double Hopf ``'hh'`` / zero-Hopf
  ``'zh'``: the number of *other* eigenvalues (the tracked pair
  ``+- i omega`` removed) with ``Re > 0`` and ``Im != 0`` / ``Im = 0`` changes.
* Fold curve ``X = (x, v, p_a, p_b)``: Bogdanov-Takens ``'bt'``:
  ``psi^T M v = 0`` with ``J v = 0``, ``J^T psi = 0`` (the zero eigenvalue of
  ``J v = lambda M v`` becomes double); zero-Hopf ``'zh'``: the number of
  complex eigenvalues with ``Re > 0`` changes.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np
import scipy.sparse as sp

from . import eigen
from .equilibrium import StationaryProblem, hopf_start, hopf_vectors, real_null_vector
from .lyapunov import first_lyapunov
from .normal_forms import (bogdanov_takens_coefficients, double_hopf_coefficients,
                           lyapunov_coefficients, zero_hopf_coefficients)
from .systems import fold_system, hopf_system
from .._casadi.vectorfield import VectorField, param_vector, state_vector
from .._driver.newton import factorize
from .._driver.problem import Description, PointInfo


def _free_pair(vf, free):
    free = tuple(free)
    if len(free) != 2 or free[0] == free[1]:
        raise ValueError(f"free must name two different parameters, got {free}")
    for name in free:
        vf.par_index(name)
    return free


class HopfCurveProblem(StationaryProblem):
    """Curve of Hopf points in the parameters ``free = (p_a, p_b)``.

    Parameters
    ----------
    vf : the VectorField; x, params : a Hopf point (state, ``{name: value}``);
    omega : its frequency (``J q = i omega M q``); free : two parameter names.
    """

    kind = "hopf"
    builder = staticmethod(hopf_system)

    def __init__(self, vf: VectorField, x, params: Mapping[str, float], omega: float,
                 free: tuple, *, q=None):
        free = _free_pair(vf, free)
        p, x = param_vector(vf, params), state_vector(vf, x, "x")
        if not (np.isfinite(omega) and omega > 0):
            raise ValueError(f"omega must be positive, got {omega!r}")
        if q is None:
            v, w, kappa, c = hopf_start(vf.jac_x(x, p), vf.mass(x, p), float(omega))
        else:
            v, w, kappa, c = hopf_vectors(np.asarray(q, dtype=complex), float(omega))
        pf = [p[vf.par_index(f)] for f in free]
        super().__init__(vf, free, np.concatenate([x, v, w, [kappa], pf]), p, c)

    @classmethod
    def from_point(cls, problem, point, second: str) -> "HopfCurveProblem":
        """Hopf curve through ``point`` (a 'hopf' SpecialPoint of ``problem``)."""
        if point.kind != "hopf" or "omega" not in point.data:
            raise ValueError(f"point must be a located Hopf point, got kind {point.kind!r}")
        return cls(problem.vf, point.x, point.params, point.data["omega"],
                   (problem.free[-1], second))

    def kappa(self, X) -> float:
        return float(X[3 * self.vf.n])

    def restart(self, X):
        """Rebuild ``c`` from the current ``v, w`` when ``c`` and ``v`` are more
        than 60 degrees apart (``|c| |v| > 2``, since ``c.v = 1``); Hopf part only."""
        n, k = self.vf.n, self.kappa(X)
        v, w, c = X[n: 2 * n], X[2 * n: 3 * n], self.system.D
        if k <= 0 or np.linalg.norm(c) * np.linalg.norm(v) <= 2.0:
            return None
        omega = float(np.sqrt(k))
        new = HopfCurveProblem(self.vf, self.state(X), self.par_dict(X), omega, self.free,
                               q=v - 1j * w / omega)
        return new, new.X0

    def columns(self, X) -> dict:
        k = self.kappa(X)
        return {"kappa": k, "omega": float(np.sqrt(k)) if k > 0 else 0.0}

    def l1(self, X) -> float:
        """First Lyapunov coefficient at ``X`` (0.0 where undefined)."""
        k = self.kappa(X)
        if k <= 0:
            return 0.0
        try:
            return first_lyapunov(self.vf, self.state(X), self.params(X), float(np.sqrt(k)))
        except RuntimeError:
            return 0.0

    def monitor(self, X, tau, lu, settings) -> PointInfo:
        base = super().monitor(X, tau, lu, settings)
        # l1 costs more than a corrector step: only when special points are detected
        l1 = self.l1(X) if settings.detect else 0.0
        tests = {"bt": self.kappa(X), "gh": l1, **base.tests}
        counts = {}
        if settings.compute_eigenvalues:
            others = _remove_tracked(base.eigenvalues, self.kappa(X))
            tol = settings.eigen.imag_tol
            counts["hh"] = int(np.sum((others.real > 0) & (np.abs(others.imag) > tol)))
            counts["zh"] = int(np.sum((others.real > 0) & (np.abs(others.imag) <= tol)))
        return PointInfo(base.eigenvalues, tests, counts)

    def test_function(self, kind, X_a, info_a, X_b, info_b, settings):
        if kind == "bt":
            return lambda X, tau, lu: self.kappa(X)
        if kind == "gh":
            return lambda X, tau, lu: self.l1(X)
        if kind in ("hh", "zh"):
            return self._other_crossing(kind, X_a, info_a, X_b, info_b, settings)
        return super().test_function(kind, X_a, info_a, X_b, info_b, settings)

    def _other_crossing(self, kind, X_a, info_a, X_b, info_b, settings):
        """``Re`` of the other eigenvalue that crosses the axis, as a function of ``X``:
        a complex one (``'hh'``, the pair whose real parts change sign from a to b) or a
        real one (``'zh'``, the one nearest to zero at a or b), followed by nearness."""
        tol = settings.eigen.imag_tol
        others = lambda ev, X: _remove_tracked(ev, self.kappa(X))
        a, b = others(info_a.eigenvalues, X_a), others(info_b.eigenvalues, X_b)
        if kind == "hh":
            ref, keep = eigen.crossing_eigenvalue(a, b, tol), lambda ev: ev.imag > tol
        else:
            real = np.concatenate([a, b])
            real = real[np.abs(real.imag) <= tol]
            ref = real[np.argmin(np.abs(real))] if real.size else None
            keep = lambda ev: np.abs(ev.imag) <= tol
        if ref is None:
            return None

        def f(X, tau, lu):
            ev = others(self.eigenvalues(X, settings), X)
            ev = ev[keep(ev)]
            return float(eigen.nearest(ev, ref).real) if ev.size else 1.0

        return f

    def describe(self, kind, X, tau, settings) -> Description:
        """The located point with ``omega, kappa`` and its normal-form coefficients:
        ``l1, l2`` at a generalized Hopf point, those of
        :func:`normal_forms.double_hopf_coefficients` at a double Hopf point, ``a, b``
        at a Bogdanov-Takens point."""
        data = self.columns(X)
        try:
            if kind == "gh" and data["omega"] > 0:
                data.update(lyapunov_coefficients(self.vf, self.state(X), self.params(X),
                                                  data["omega"]))
            elif kind == "hh":
                data.update(self._double_hopf(X, settings))
            elif kind == "bt":
                data.update(bogdanov_takens_coefficients(self.vf, self.state(X), self.params(X)))
            elif kind == "zh":
                data.update(zero_hopf_coefficients(self.vf, self.state(X), self.params(X),
                                                   data["omega"]))
            else:
                data["l1"] = self.l1(X)
        except (RuntimeError, ValueError, ZeroDivisionError) as err:   # no normal form
            return Description(X, "converged", 0.0, data, f"{kind} coefficients: {err}")
        return Description(X, "converged", 0.0, data)

    def _double_hopf(self, X, settings) -> dict:
        """Coefficients of the double Hopf point at ``X``: the second frequency is the
        other pair nearest to the imaginary axis."""
        ev = _remove_tracked(eigen.eigenvalues(*self.matrices(X), settings.eigen), self.kappa(X))
        ev = ev[ev.imag > settings.eigen.imag_tol]
        omega2 = float(ev[np.argmin(np.abs(ev.real))].imag)
        ratio = max(omega2, self.kappa(X) ** 0.5) / min(omega2, self.kappa(X) ** 0.5)
        if min(abs(ratio - k) for k in (1, 2, 3)) < 1e-2:
            raise RuntimeError(f"strong resonance omega1 : omega2 near 1:{round(ratio)}")
        return double_hopf_coefficients(self.vf, self.state(X), self.params(X),
                                        float(np.sqrt(self.kappa(X))), omega2)


def _remove_tracked(ev: np.ndarray, kappa: float) -> np.ndarray:
    """Eigenvalues without the two nearest to ``+- sqrt(-kappa)``."""
    root = np.sqrt(complex(-kappa))
    keep = np.ones(ev.size, dtype=bool)
    for target in (root, -root):
        idx = np.where(keep)[0]
        if idx.size:
            keep[idx[np.argmin(np.abs(ev[idx] - target))]] = False
    return ev[keep]


class FoldCurveProblem(StationaryProblem):
    """Curve of fold (limit) points in the parameters ``free = (p_a, p_b)``."""

    kind = "fold"
    builder = staticmethod(fold_system)

    def __init__(self, vf: VectorField, x, params: Mapping[str, float], free: tuple,
                 *, v=None):
        free = _free_pair(vf, free)
        p, x = param_vector(vf, params), state_vector(vf, x, "x")
        v = real_null_vector(vf.jac_x(x, p)) if v is None else np.asarray(v) / np.linalg.norm(v)
        pf = [p[vf.par_index(f)] for f in free]
        super().__init__(vf, free, np.concatenate([x, v, pf]), p, v)
        self._d = np.random.default_rng(7).standard_normal(vf.n)

    @classmethod
    def from_point(cls, problem, point, second: str) -> "FoldCurveProblem":
        """Fold curve through ``point`` (a 'fold' SpecialPoint of ``problem``)."""
        if point.kind != "fold":
            raise ValueError(f"point must be a fold point, got kind {point.kind!r}")
        return cls(problem.vf, point.x, point.params, (problem.free[-1], second))

    def restart(self, X):
        """Rebuild ``c = v/|v|`` when ``|c| |v| > 2`` (c and v > 60 degrees apart)."""
        n = self.vf.n
        v, c = X[n: 2 * n], self.system.D
        if np.linalg.norm(c) * np.linalg.norm(v) <= 2.0:
            return None
        new = FoldCurveProblem(self.vf, self.state(X), self.par_dict(X), self.free, v=v)
        return new, new.X0

    def bt_test(self, X) -> float:
        """``psi^T M v / (|psi| |v|)`` from ``[[J^T, v], [d^T, 0]] (psi, g) = e``."""
        n = self.vf.n
        J, M = self.matrices(X)
        v = X[n: 2 * n]
        A = sp.bmat([[J.T, v[:, None]], [self._d[None, :], None]], format="csc")
        lu = factorize(A)
        if lu is None:
            return 0.0
        psi = lu.solve(np.append(np.zeros(n), 1.0))[:n]
        return float(psi @ (M @ v) / (np.linalg.norm(psi) * np.linalg.norm(v)))

    def monitor(self, X, tau, lu, settings) -> PointInfo:
        base = super().monitor(X, tau, lu, settings)
        counts = {}
        if settings.compute_eigenvalues:
            counts["zh"] = eigen.count_complex_unstable(base.eigenvalues,
                                                         settings.eigen.imag_tol)
        return PointInfo(base.eigenvalues, {"bt": self.bt_test(X), **base.tests}, counts)

    def test_function(self, kind, X_a, info_a, X_b, info_b, settings):
        if kind == "bt":
            return lambda X, tau, lu: self.bt_test(X)
        return super().test_function(kind, X_a, info_a, X_b, info_b, settings)

    def describe(self, kind, X, tau, settings) -> Description:
        """The located point; ``a, b`` (:func:`normal_forms.bogdanov_takens_coefficients`)
        at a Bogdanov-Takens point, ``omega`` and those of
        :func:`normal_forms.zero_hopf_coefficients` at a zero-Hopf point."""
        x, p = self.state(X), self.params(X)
        try:
            if kind == "bt":
                return Description(X, "converged", 0.0, bogdanov_takens_coefficients(self.vf, x, p))
            if kind == "zh":
                ev = self.eigenvalues(X, settings)
                ev = ev[ev.imag > settings.eigen.imag_tol]
                omega = float(ev[np.argmin(np.abs(ev.real))].imag)
                data = {"omega": omega, **zero_hopf_coefficients(self.vf, x, p, omega)}
                return Description(X, "converged", 0.0, data)
        except (RuntimeError, ValueError, ZeroDivisionError) as err:   # no normal form
            return Description(X, "converged", 0.0, {}, f"{kind} coefficients: {err}")
        return super().describe(kind, X, tau, settings)
