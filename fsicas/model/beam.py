"""Clamped–free Euler–Bernoulli modes, in a form that stays accurate up to n ~ 1000.

Nondimensional beam on x in [0, 1]: ``phi'''' = beta^4 phi``, phi(0) = phi'(0) = 0,
phi''(1) = phi'''(1) = 0, so ``cos(beta) cosh(beta) = -1`` and ``omega_n = beta_n^2``.
With ``sigma = (cosh b + cos b) / (sinh b + sin b)`` the textbook shape

    phi = cosh(bx) - cos(bx) - sigma (sinh(bx) - sin(bx))

has unit mean square, ``∫_0^1 phi^2 dx = 1``, but cancels catastrophically for large
beta. We write ``cosh z - sigma sinh z = a e^z + (1 - a) e^-z`` with
``a = (1 - sigma)/2 = e^-b (sin b - cos b - e^-b) / (1 - e^-2b + 2 e^-b sin b)``,
so that ``a e^z = e^(z-b) * (...)`` never overflows and nothing cancels.

Running integrals follow from the beam equation itself:
``Phi(x) = ∫_0^x phi = (phi'''(x) - phi'''(0)) / beta^4`` and, since phi'''(1) = 0,
``Psi(x) = ∫_x^1 phi = -phi'''(x) / beta^4``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ModalBasis", "clamped_free_betas", "clamped_free_modes"]


@dataclass(frozen=True)
class ModalBasis:
    """Mode data sampled at points ``x`` (shape (K,)); arrays are (N, K).

    ``phi`` shape, ``dphi`` slope, ``ddphi`` curvature, ``Phi = ∫_0^x phi``,
    ``Psi = ∫_x^1 phi``; ``omega`` the in-vacuo circular frequencies (nondimensional);
    ``width`` the beam width b(x)/b(0) at ``x`` (shape (K,)), which weights the modal
    projection of the pressure load: ``f_n = ∫ b(x) (p2 - p1) phi_n dx``.
    """

    x: np.ndarray
    omega: np.ndarray
    phi: np.ndarray
    dphi: np.ndarray
    ddphi: np.ndarray
    Phi: np.ndarray
    Psi: np.ndarray
    width: np.ndarray | None = None

    @property
    def n_modes(self) -> int:
        return len(self.omega)


def clamped_free_betas(n_modes: int) -> np.ndarray:
    """Roots of ``cos(b) + 1/cosh(b) = 0`` (the stable form of cos b cosh b = -1)."""
    if int(n_modes) != n_modes or n_modes < 1:
        raise ValueError(f"n_modes must be a positive integer, got {n_modes!r}")
    b = (np.arange(1, n_modes + 1) - 0.5) * np.pi
    for _ in range(50):
        sech = 1.0 / np.cosh(np.minimum(b, 700.0))
        f = np.cos(b) + sech
        df = -np.sin(b) - sech * np.tanh(b)
        step = f / df
        b = b - step
        if np.all(np.abs(step) <= 4e-16 * b):
            break
    return b


def _coefficients(beta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return ``c`` with ``a = e^-b c`` and ``sigma = 1 - 2a`` (see module doc)."""
    em = np.exp(-beta)
    c = (np.sin(beta) - np.cos(beta) - em) / (1.0 - em**2 + 2.0 * em * np.sin(beta))
    sigma = 1.0 - 2.0 * em * c
    return c, sigma


def clamped_free_modes(n_modes: int, x: np.ndarray) -> ModalBasis:
    """Evaluate the first ``n_modes`` clamped–free modes and their integrals at ``x``."""
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or np.any(x < 0.0) or np.any(x > 1.0):
        raise ValueError("x must be a 1-D array of points in [0, 1]")
    beta = clamped_free_betas(n_modes)
    c, sigma = _coefficients(beta)
    b, s = beta[:, None], sigma[:, None]
    z = b * x[None, :]
    grow = np.exp(z - b) * c[:, None]          # a e^z
    decay = (1.0 - np.exp(-b) * c[:, None]) * np.exp(-z)   # (1 - a) e^-z
    cos, sin = np.cos(z), np.sin(z)
    phi = grow + decay - cos + s * sin
    dphi = b * (grow - decay + sin + s * cos)
    ddphi = b**2 * (grow + decay + cos - s * sin)
    d3 = b**3 * (grow - decay - sin - s * cos)
    Psi = -d3 / b**4
    Phi = 2.0 * s / b - Psi
    return ModalBasis(x=x, omega=beta**2, phi=phi, dphi=dphi, ddphi=ddphi, Phi=Phi, Psi=Psi)
