"""Cycles with one more equation: located special cycles and codimension-one curves.

A collocated cycle ``X = (U, T, p_free)`` with ``k`` free parameters satisfies the
``m`` collocation and phase equations ``G(X) = 0`` (``cycles``). One more scalar
equation ``g(X) = 0`` (a :class:`~.conditions.Condition`: grazing, fold, period doubling,
torus) makes, with one free parameter, a square system that *locates* a special cycle by
Newton (:func:`locate_cycle`) and, with two, a curve of such cycles continued by the same
PALC (:class:`CycleCurveProblem`).

Codimension-two points on a curve (``compute_eigenvalues=True``). Each condition
pins some multipliers of the Poincare map (``section_multipliers``): the fold's real one
nearest +1, the doubling's nearest -1, the torus pair ``mu(X), conj mu(X)``; the grazing
curve none. The others ("the rest") crossing +1, -1 or the unit circle (a complex pair)
are the codimension-two points (:attr:`Condition.crossings`), detected by the parity of
the count of real ones beyond +-1 (a complex pair meeting on the real axis changes it by
two) and the count of complex ones outside the circle, and located on
``floquet.crossing(rest, +-1)`` and ``|mu| - 1`` of the complex one nearest the circle:

========================  ==========  ===========  ============  ======================
curve                     rest at +1  rest at -1   rest pair     condition's own tests
========================  ==========  ===========  ============  ======================
fold (LPC)                ``r1``      ``lppd``     ``lpns``      ``cpc``
period doubling (PD)      ``lppd``    ``r2``       ``pdns``      ``gpd``
Neimark-Sacker (NS)       ``lpns``    ``pdns``     ``nsns``      ``r3``, ``r4``, ``ch``
grazing (``Extremum``)    ``lpc``     ``pd``       ``ns``
========================  ==========  ===========  ============  ======================

``r1``/``r2``: a second multiplier at +1 / -1 (1:1, 1:2 resonance); ``lppd``, ``lpns``,
``pdns``, ``nsns``: fold-flip, fold-Neimark-Sacker, flip-Neimark-Sacker, double
Neimark-Sacker; on a grazing curve, where it meets the fold, doubling and torus curves.
``cpc`` (cusp of cycles): the fold's quadratic normal-form coefficient
``a = w^T G_YY[v, v]`` (``v, w`` the bordered null vectors, ``Y = (U, T)``) and ``gpd``
(generalized period doubling): the doubled cycles' cubic coefficient, and ``ch``
(Chenciner): the torus bifurcation's first Lyapunov coefficient, change sign
(``normal_forms``). ``r3``, ``r4``: the torus pair's angle, ``cos theta + 1/2`` and
``cos theta`` (``mu = e^{+-i theta}``: 1:3 and 1:4 resonance). Not detected: 1:1 / 1:2
resonance *on a torus curve*, where the pair meets on the real axis and the curve ends.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from . import floquet
from .conditions import Condition
from .cycles import CycleProblem
from .._linalg.sparse import append_row
from .._driver.newton import NewtonResult, newton
from .._driver.problem import Description, PointInfo
from .._driver.settings import NewtonSettings


class CycleCurveProblem(CycleProblem):
    """Collocated cycles with the free parameters ``free`` and one more equation
    ``condition``: with two free parameters a curve (the last is the continuation
    parameter), with one a square system (:func:`locate_cycle`).

    Built from a one-parameter cycle ``problem`` at ``X`` (same field, mesh and
    settings; the sparse linear solver, since ``g``'s row is dense). Re-meshing and
    ``refine`` work as for the cycle. ``columns`` adds ``condition`` (``g``)."""

    def __init__(self, problem: CycleProblem, X, free, condition: Condition):
        settings = replace(problem.settings, linear_solver="sparse")
        super().__init__(problem.vf, lambda t: problem.evaluate(X, t), problem.period(X),
                         problem.par_dict(X), tuple(free), settings=settings, mesh=problem.mesh)
        self.refine = problem.refine
        self.condition = condition.bind(self, self.X0)

    def cycle_jacobian(self, X) -> sp.csc_matrix:
        """``G_X`` of the collocation and phase equations (without ``g``; the last one
        is reused at the same ``X``)."""
        last = self._last_jacobian
        if last is not None and np.array_equal(last[0], X):
            return last[1]
        return CycleProblem.jacobian(self, X)

    def residual(self, X) -> np.ndarray:
        return np.append(super().residual(X), self.condition.value(self, X))

    def jacobian(self, X) -> sp.csc_matrix:
        J = self.cycle_jacobian(X)
        return append_row(J, self.condition.gradient(self, X))

    def accept(self, X) -> None:
        super().accept(X)
        self.condition.accept(self, X)

    def _rebuilt(self, X, vf, settings, mesh):
        cycle = CycleProblem(vf, lambda t: self.evaluate(X, t), self.period(X),
                             self.par_dict(X), self.free, settings=settings, mesh=mesh)
        new = CycleCurveProblem(cycle, cycle.X0, self.free, self.condition)
        new.refine = self.refine
        return new, new.X0.copy()

    def columns(self, X) -> dict:
        return {**super().columns(X), "condition": float(self.residual(X)[-1])}

    @property
    def verified_kinds(self) -> tuple:
        return self.condition.crossings

    def rest(self, X) -> np.ndarray:
        """The Poincare multipliers other than those the condition pins (module doc)."""
        return self.kept("rest", X, lambda: self.condition.rest(
            self, X, self.section_multipliers(X)))

    def monitor(self, X, tau, lu, settings) -> PointInfo:
        """Turns of the curve in its continuation parameter ('fold'); with the
        multipliers (``compute_eigenvalues``), the codimension-two points (module doc)."""
        tests = {"fold": float(tau[-1])}
        if not settings.compute_eigenvalues:
            return PointInfo(np.zeros(0, dtype=complex), tests)
        rest, (plus, minus, pair) = self.rest(X), self.condition.crossings
        real = rest.imag == 0
        tests["n_unstable"] = float(np.sum(np.abs(rest) > 1.0 + self.settings.unstable_tol))
        tests.update(self.condition.tests(self, X))
        counts = {plus: int(np.sum(real & (rest.real > 1.0))),
                  minus: int(np.sum(real & (rest.real < -1.0))),
                  pair: int(np.sum(~real & (np.abs(rest) > 1.0)))}
        return PointInfo(self.multipliers(X), tests, counts)

    def events(self, a: PointInfo, b: PointInfo) -> list:
        plus, minus, pair = self.condition.crossings
        own = [k for k in ("fold", *self.condition.test_names)
               if k in a.tests and k in b.tests and a.tests[k] * b.tests[k] < 0]
        real = [k for k in (plus, minus) if k in a.counts and k in b.counts
                and (a.counts[k] - b.counts[k]) % 2]
        moved = pair in a.counts and pair in b.counts and a.counts[pair] != b.counts[pair] \
            and sum(a.counts.values()) != sum(b.counts.values())
        return own + real + ([pair] if moved else [])

    def test_function(self, kind, X_a, info_a, X_b, info_b, settings):
        plus, minus, pair = self.condition.crossings
        if kind == "fold":
            return lambda X, tau, lu: float(tau[-1])
        if kind in (plus, minus):
            target = 1.0 if kind == plus else -1.0
            return lambda X, tau, lu: floquet.crossing(self.rest(X), target)
        if kind == pair:
            return lambda X, tau, lu: floquet.nearest_complex_modulus(self.rest(X)) - 1.0
        return lambda X, tau, lu: self.condition.test(self, X, kind)

    def describe(self, kind, X, tau, settings) -> Description:
        """The point, its period, mesh and unknowns; at a crossing the multiplier of the
        rest that crosses, at ``r3``/``r4`` the torus pair's, at ``cpc`` the fold's
        coefficient (``multiplier_re``, ``multiplier_im``, ``coefficient``)."""
        found = CycleProblem.describe(self, "fold", X, tau, settings)
        plus, minus, pair = self.condition.crossings
        if kind in (plus, minus):
            m = floquet.nearest_real(self.rest(X), 1.0 if kind == plus else -1.0)
        elif kind == pair:
            rest = self.rest(X)
            cplx = rest[rest.imag > 0]
            m = cplx[np.argmin(np.abs(np.abs(cplx) - 1.0))] if cplx.size else np.nan
        elif kind in ("r3", "r4"):
            m = self.condition.multiplier_at(self, X)
        else:
            m = None
        if m is not None:
            found.data.update({"multiplier_re": float(np.real(m)),
                               "multiplier_im": float(np.imag(m))})
        if kind == "cpc":
            found.data["coefficient"] = self.condition.test(self, X, "cpc")
        return found


def locate_cycle(problem: CycleProblem, X, condition: Condition,
                 settings: NewtonSettings = NewtonSettings()) -> tuple[CycleCurveProblem,
                                                                       NewtonResult]:
    """The special cycle ``condition`` defines, by Newton on the square system (cycle
    equations and ``g``) in ``problem``'s unknowns, from ``X`` (e.g. a point located
    on the arclength). Returns the square problem and the Newton outcome."""
    square = CycleCurveProblem(problem, X, problem.free, condition)
    return square, newton(square.residual, square.jacobian, square.X0, settings)
