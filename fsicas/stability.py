"""Linear stability at a steady state: ``dF/dx v = lambda M v`` (size 2N + 2).

At an equilibrium xdot = 0, so linearizing ``M(x) xdot = F(x)`` gives
``M(x̄) δxdot = F_x(x̄) δx`` exactly: no derivative of M is needed.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg

from .model import Model
from .steady import SteadyState

__all__ = ["eigenvalues"]


def eigenvalues(model: Model, steady: SteadyState) -> np.ndarray:
    """Finite eigenvalues sorted by decreasing real part (growth rate; Im = omega)."""
    J = np.array(model.jac_rhs(steady.x, steady.p))
    M = np.array(model.mass(steady.x, steady.p))
    lam = scipy.linalg.eigvals(J, M)
    lam = lam[np.isfinite(lam)]
    return lam[np.lexsort((-lam.imag, -lam.real))]
