"""Linear stability at a steady state: ``dF/dx v = lambda M v`` (size 2N + 2).

At an equilibrium xdot = 0, so linearizing ``M(x) xdot = F(x)`` gives
``M(x̄) δxdot = F_x(x̄) δx`` exactly: no derivative of M is needed. An eigenvalue
``lambda = sigma + i omega`` is a growth rate sigma and a circular frequency omega in
units of 1/T; ``omega / omega_1`` compares it with the first in-vacuo mode.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from ..model.assembly import Model, build_model, modal_basis
from ..scene import Scene
from .steady import SteadyState, steady_state

__all__ = ["LinearStability", "eigenvalues", "generalized_eigen", "linear_stability",
           "normalized_shape", "steady_eigen"]


def generalized_eigen(J, M) -> tuple[np.ndarray, np.ndarray]:
    """Finite eigenpairs of ``J v = lambda M v`` (dense QZ, ``scipy.linalg.eig(J, M)``),
    sorted by decreasing real part, then decreasing imaginary part (of a conjugate pair,
    the one with Im > 0 comes first). Returns (lambda, V) with V[:, k] for lambda[k]."""
    J, M = np.array(J, dtype=float), np.array(M, dtype=float)      # copies: overwritten
    if not (np.all(np.isfinite(J)) and np.all(np.isfinite(M))):
        raise ValueError("generalized_eigen: J and M must be finite")
    lam, vec = scipy.linalg.eig(J, M, overwrite_a=True, overwrite_b=True, check_finite=False)
    finite = np.isfinite(lam)
    lam, vec = lam[finite], vec[:, finite]
    order = np.lexsort((-lam.imag, -lam.real))
    return lam[order], vec[:, order]


def steady_eigen(model: Model, steady: SteadyState) -> tuple[np.ndarray, np.ndarray]:
    """:func:`generalized_eigen` of ``F_x v = lambda M v`` at a steady state."""
    J = np.array(model.jac_rhs(steady.x, steady.p))
    M = np.array(model.mass(steady.x, steady.p))
    return generalized_eigen(J, M)


def eigenvalues(model: Model, steady: SteadyState) -> np.ndarray:
    """Finite eigenvalues sorted by decreasing real part (then decreasing Im)."""
    return steady_eigen(model, steady)[0]


def normalized_shape(model: Model, vector: np.ndarray, x) -> tuple[np.ndarray, np.ndarray]:
    """Complex deflection y(x) = Σ phi_n v_q,n of an eigenvector, scaled so that its
    largest modulus on ``x`` is 1 and real there; returns (y, scaled eigenvector)."""
    n = model.n_modes
    y = modal_basis(model.scene, x).phi.T @ vector[n:2 * n]
    k = int(np.argmax(np.abs(y)))
    scale = 1.0 / y[k]
    return y * scale, vector * scale


@dataclass(frozen=True)
class LinearStability:
    """Eigen-analysis of one steady state; eigenvalues sorted by decreasing growth rate."""

    scene: Scene
    steady: SteadyState
    eigenvalues: np.ndarray
    vectors: np.ndarray = field(repr=False)
    omega_1: float

    @property
    def stable(self) -> bool:
        return bool(np.all(self.eigenvalues.real < 0))

    @property
    def growth_rate(self) -> np.ndarray:
        return self.eigenvalues.real

    @property
    def omega(self) -> np.ndarray:
        return self.eigenvalues.imag

    @property
    def freq_ratio(self) -> np.ndarray:
        return self.eigenvalues.imag / self.omega_1

    def dominant_modes(self, k: int = 0) -> np.ndarray:
        """In-vacuo modes ranked by their share ``|v_q,n|^2 / Σ|v_q|^2`` in eigenvector k
        (1-based mode numbers)."""
        n = self.scene.modes
        share = np.abs(self.vectors[n:2 * n, k]) ** 2
        return np.argsort(-share) + 1

    def mode_shape(self, model: Model, k: int = 0, x=None) -> dict:
        """Complex mode shape of eigenvalue k on x (default 201 points): y, and the
        flow-rate components Q1, Q2, with max |y| = 1 real."""
        x = np.linspace(0.0, 1.0, 201) if x is None else np.asarray(x, float)
        y, v = normalized_shape(model, self.vectors[:, k], x)
        return {"x": x, "y": y, "Q": v[-2:], "eigenvalue": self.eigenvalues[k]}

    def to_json(self) -> dict:
        return {"eigenvalues": [[float(l.real), float(l.imag)] for l in self.eigenvalues],
                "stable": self.stable, "ustar": self.scene.ustar,
                "pressure_drop": self.steady.pressure_drop}


def linear_stability(scene: Scene, model: Model | None = None) -> LinearStability:
    """Steady state of ``scene`` and the eigen-analysis of its linearization."""
    model = model or build_model(scene)
    steady = steady_state(scene, model)
    lam, vec = steady_eigen(model, steady)
    return LinearStability(scene, steady, lam, vec, model.omega_1)
