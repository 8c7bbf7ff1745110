"""Periodic orbits, whatever their discretization (collocation, shooting): the
shared unknowns' checks and the detection of their special cycles.

Along a branch, Floquet multipliers replace eigenvalues; the trivial multiplier's
distance to 1 is recorded in ``tests['trivial_error']``; the tests below count the
non-trivial ones as those of the Poincare map (``section_multipliers``: a fold's
Jordan pair at +1, split by the discretization, is not mistaken for a complex pair),
``tests['n_unstable']`` those outside the unit circle (``Branch.stable``):

* fold of cycles: ``tau_p`` changes sign (located by Illinois on ``tau_p``);
* period doubling: the number of real multipliers ``< -1`` changes (located
  on ``floquet.crossing(mu, -1)``, which changes sign with the multiplier that
  crosses);
* Neimark-Sacker: the number of complex multipliers with ``|mu| > 1``
  changes, and with it the number outside the circle (a complex pair that meets on
  the real axis outside the circle is none; located on ``|mu| - 1``);
* branch point ("bp"): a real multiplier crosses +1 where the branch does not turn
  (the number of real multipliers ``> 1`` changes parity, ``tau_p`` keeps its sign;
  located on ``floquet.crossing(mu, +1)``). In a system with a
  symmetry, this is where cycles that break it branch off (a pitchfork of cycles);
  ``cycle_from_bp`` switches onto them.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

from . import floquet
from .._casadi.vectorfield import make_field, param_vector
from .._driver.problem import Description, PointInfo, Problem


class PeriodicProblem(Problem):
    """Shared detection hooks of periodic-orbit problems (collocation, shooting).

    Subclasses provide ``period(X)``, ``state(X)``, ``transfer_matrices(X)``,
    ``multipliers(X)`` and ``settings.unstable_tol``.
    """

    kind = "cycle"
    verified_kinds = ("pd", "ns", "bp")
    monitor_uses_lu = False

    #: unit row fixing the start amplitude along a critical direction (branch
    #: switching); None keeps the parameter fixed at the start
    start_direction = None

    def _setup(self, F, M, params, active, period, settings, settings_type) -> np.ndarray:
        """Check ``settings`` and ``period``; set the field, the settings and the active
        parameter; return the parameter vector."""
        if not isinstance(settings, settings_type):
            raise ValueError(f"settings must be a {settings_type.__name__}")
        if not (np.isfinite(period) and period > 0):
            raise ValueError(f"period must be a positive finite number, got {period!r}")
        self.vf = make_field(F, M, params)
        self.settings = settings
        self.free = (active,) if isinstance(active, str) else tuple(active)
        self.active = self.free[-1]
        self.free_idx = tuple(self.vf.par_index(name) for name in self.free)
        self._kept = {}                          # name -> (X, value) of the last point
        return param_vector(self.vf, params)

    def kept(self, name: str, X, compute) -> np.ndarray:
        """``compute()``, kept for the last ``X`` under ``name`` (the monitor and a
        ``record`` callback ask at the same point); a copy."""
        last = self._kept.get(name)
        if last is None or not np.array_equal(last[0], X):
            last = self._kept[name] = (np.array(X), compute())
        return last[1].copy()

    def frame(self, X) -> np.ndarray:
        return np.arange(len(X))

    def section_multipliers(self, X) -> np.ndarray:
        """The non-trivial multipliers, of the Poincare map on the section normal to
        the flow ``M(u0)^-1 F(u0)`` at ``u0 = state(X)`` (``floquet``): a fold's
        multiplier at +1 as accurate as the others (the monodromy's pair is not). The
        section's map is formed from the product, so its tiny multipliers are replaced by
        as many of the smallest of :meth:`multipliers` (``floquet.accurate_tail``),
        accurate relative to their size with the periodic Schur route."""
        return self.kept("section_multipliers", X, lambda: floquet.accurate_tail(
            floquet.section_multipliers(self.monodromy(X), self.flow(X)),
            self.multipliers(X)))

    def flow_defect(self, X) -> float:
        """``|Phi f - f| / |f|`` with ``f`` the flow at ``u(0)`` (:meth:`flow`): how far
        the discretized monodromy is from mapping the flow onto itself, as the exact one
        does. It bounds what the discretization can show at +1: a fold's Poincare
        multiplier (:meth:`section_multipliers`) is only that close to 1, and the
        monodromy's pair there splits by about its square root."""
        f = self.flow(X)
        return float(np.linalg.norm(self.monodromy(X) @ f - f) / np.linalg.norm(f))

    def monodromy(self, X) -> np.ndarray:
        """``Phi = A_{N-1} ... A_0`` of :meth:`transfer_matrices` (kept for the last ``X``:
        the multipliers and the section's share it)."""
        return self.kept("monodromy", X, lambda: floquet.monodromy(self.maps(X)))

    def maps(self, X) -> np.ndarray:
        """:meth:`transfer_matrices` kept for the last ``X`` (the monodromy and the
        periodic Schur sweeps share them; a sparse Jacobian's maps cost a solve)."""
        return self.kept("maps", X, lambda: self.transfer_matrices(X))

    def floquet_multipliers(self, X, method: str) -> np.ndarray:
        """Floquet multipliers by ``method`` ('product': of :meth:`monodromy`; 'pencil':
        of the transfer matrices) sorted by decreasing modulus, kept for the last ``X``."""
        if method == "product":
            compute = lambda: floquet.product_multipliers(self.monodromy(X))  # noqa: E731
        elif method == "schur":                 # the maps only if the sweeps need them
            compute = lambda: floquet.schur_multipliers(  # noqa: E731
                lambda: self.maps(X), self.monodromy(X))
        else:
            compute = lambda: floquet.multipliers(self.transfer_matrices(X), method)  # noqa: E731
        return self.kept("multipliers", X, compute)

    def flow(self, X) -> np.ndarray:
        """``u'(0) = M(u0)^-1 F(u0)`` (time in units of T), ``u0 = state(X)``."""
        u0, p = self.state(X), self.params(X)
        return np.atleast_1d(spla.spsolve(self.vf.mass(u0, p).tocsc(), self.vf.rhs(u0, p)))

    def start_row(self) -> np.ndarray:
        if self.start_direction is None:
            return super().start_row()
        return np.asarray(self.start_direction, dtype=float)

    # -- detection hooks ---------------------------------------------------------------
    def monitor(self, X, tau, lu, settings) -> PointInfo:
        tests = {"fold": float(tau[-1])}
        if not settings.compute_eigenvalues:
            return PointInfo(np.zeros(0, dtype=complex), tests)
        mu, rest = self.multipliers(X), self.section_multipliers(X)
        tests["trivial_error"] = float(np.min(np.abs(mu - 1.0)))
        tests["n_unstable"] = float(np.sum(np.abs(rest) > 1.0 + self.settings.unstable_tol))
        real = rest.imag == 0
        counts = {"pd": int(np.sum(real & (rest.real < -1.0))),
                  "ns": int(np.sum(~real & (np.abs(rest) > 1.0))),
                  "bp": int(np.sum(real & (rest.real > 1.0)))}
        return PointInfo(mu, tests, counts)

    def events(self, a: PointInfo, b: PointInfo) -> list:
        kinds = ["fold"] if a.tests["fold"] * b.tests["fold"] < 0 else []
        if not kinds and "bp" in a.counts and "bp" in b.counts \
                and (a.counts["bp"] - b.counts["bp"]) % 2:
            kinds.append("bp")              # a real multiplier through +1, no turn
        changed = [k for k in ("pd", "ns")
                   if k in a.counts and k in b.counts and a.counts[k] != b.counts[k]]
        if "ns" in changed and sum(a.counts.values()) == sum(b.counts.values()):
            changed.remove("ns")            # a pair met on the real axis outside the circle
        return kinds + changed

    def test_function(self, kind, X_a, info_a, X_b, info_b, settings):
        if kind == "fold":
            return lambda X, tau, lu: float(tau[-1])
        if kind in ("pd", "bp"):
            target = -1.0 if kind == "pd" else 1.0
            return lambda X, tau, lu: floquet.crossing(self.section_multipliers(X), target)
        if kind == "ns":
            return lambda X, tau, lu: float(
                floquet.nearest_complex_modulus(self.section_multipliers(X)) - 1)
        return None

    def describe(self, kind, X, tau, settings) -> Description:
        data = {"period": self.period(X), "X": [float(v) for v in X]}
        if kind in ("pd", "ns", "bp"):
            mu = self.section_multipliers(X)
            m = mu[np.argmin(np.abs(np.abs(mu) - 1) + (mu.imag == 0))] if kind == "ns" else \
                floquet.nearest_real(mu, -1.0 if kind == "pd" else 1.0)
            data.update({"multiplier_re": float(np.real(m)), "multiplier_im": float(np.imag(m))})
        return Description(X, "converged", 0.0, data)
