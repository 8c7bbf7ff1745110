"""Uniform Euler–Bernoulli modes in closed form, accurate up to n ~ 1000.

Clamped–free (the cantilever) first, then the other ends of :data:`fsicas.scene.BEAM_ENDS`
(:func:`uniform_modes`).

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

Other ends, every mode with unit mean square and a positive first nonzero derivative at
the root (phi''(0) = 2 beta^2 when clamped, phi'(0) = sqrt(2) beta when pinned):

* clamped–clamped, ``cos b cosh b = 1`` (solved as ``cos b - 1/cosh b = 0``), and
  clamped–pinned, ``tan b = tanh b`` (as ``sin b - cos b tanh b = 0``): the shape above
  with ``sigma = (cosh b - cos b) / (sinh b - sin b)``, so
  ``a = e^-b (cos b - sin b - e^-b) / (1 - e^-2b - 2 e^-b sin b)``; the running
  integrals ``Phi = (phi'''(x) - phi'''(0)) / beta^4`` with ``phi'''(0) = -2 sigma beta^3``
  and ``Psi = (phi'''(1) - phi'''(x)) / beta^4``.
* pinned–pinned: ``phi = sqrt(2) sin(beta x)``, ``beta = n pi``,
  ``Phi = 2 sqrt(2) sin^2(beta x / 2) / beta`` and
  ``Psi = 2 sqrt(2) sin(beta (1 + x) / 2) sin(beta (1 - x) / 2) / beta`` (no cancellation).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene import CLAMPED_FREE, check_ends

__all__ = ["ModalBasis", "clamped_free_betas", "clamped_free_modes", "uniform_betas",
           "uniform_modes"]


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


# ------------------------------------------------------------------------ other ends
#: Stable characteristic functions f(b), f'(b) and the offset of their n-th root from n pi.
_CHARACTERISTIC = {
    "clamped-clamped": (lambda b, t, se: np.cos(b) - se,
                        lambda b, t, se: -np.sin(b) + se * t, 0.5),
    "clamped-pinned": (lambda b, t, se: np.sin(b) - np.cos(b) * t,
                       lambda b, t, se: np.cos(b) + np.sin(b) * t - np.cos(b) * se**2, 0.25),
}


def uniform_betas(n_modes: int, ends: str = CLAMPED_FREE) -> np.ndarray:
    """Wavenumbers beta_n (``omega_n = beta_n^2``) of the uniform beam with these ends."""
    if check_ends(ends) == CLAMPED_FREE:
        return clamped_free_betas(n_modes)
    if int(n_modes) != n_modes or n_modes < 1:
        raise ValueError(f"n_modes must be a positive integer, got {n_modes!r}")
    n = np.arange(1, int(n_modes) + 1, dtype=float)
    if ends == "pinned-pinned":
        return n * np.pi
    f, df, offset = _CHARACTERISTIC[ends]
    b = (n + offset) * np.pi
    for _ in range(50):
        bc = np.minimum(b, 700.0)
        t, se = np.tanh(bc), 1.0 / np.cosh(bc)
        step = f(b, t, se) / df(b, t, se)
        b = b - step
        if np.all(np.abs(step) <= 4e-16 * b):
            break
    return b


def _held_modes(beta: np.ndarray, x: np.ndarray) -> dict[str, np.ndarray]:
    """Clamped–clamped and clamped–pinned shapes (module doc) with their integrals."""
    em = np.exp(-beta)
    c = (np.cos(beta) - np.sin(beta) - em) / (1.0 - em**2 - 2.0 * em * np.sin(beta))
    sigma = 1.0 - 2.0 * em * c
    b, s, c = beta[:, None], sigma[:, None], c[:, None]
    xs = np.concatenate([x, [1.0]])
    z = b * xs[None, :]
    grow = np.exp(z - b) * c
    decay = (1.0 - np.exp(-b) * c) * np.exp(-z)
    cos, sin = np.cos(z), np.sin(z)
    d3 = b**3 * (grow - decay - sin - s * cos)
    phi = grow + decay - cos + s * sin
    dphi = b * (grow - decay + sin + s * cos)
    ddphi = b**2 * (grow + decay + cos - s * sin)
    Phi = d3 / b**4 + 2.0 * s / b
    Psi = (d3[:, -1:] - d3) / b**4
    return {k: v[:, :-1] for k, v in dict(phi=phi, dphi=dphi, ddphi=ddphi, Phi=Phi,
                                          Psi=Psi).items()}


def _pinned_modes(beta: np.ndarray, x: np.ndarray) -> dict[str, np.ndarray]:
    """Pinned–pinned shapes ``sqrt(2) sin(beta x)`` with their integrals."""
    b, r2 = beta[:, None], np.sqrt(2.0)
    z = b * x[None, :]
    return dict(phi=r2 * np.sin(z), dphi=r2 * b * np.cos(z), ddphi=-r2 * b**2 * np.sin(z),
                Phi=2.0 * r2 * np.sin(z / 2) ** 2 / b,
                Psi=2.0 * r2 * np.sin((b + z) / 2) * np.sin((b - z) / 2) / b)


def uniform_modes(n_modes: int, x: np.ndarray, ends: str = CLAMPED_FREE) -> ModalBasis:
    """The first ``n_modes`` modes of the uniform beam with these ends, at ``x``."""
    if check_ends(ends) == CLAMPED_FREE:
        return clamped_free_modes(n_modes, x)
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or np.any(x < 0.0) or np.any(x > 1.0):
        raise ValueError("x must be a 1-D array of points in [0, 1]")
    beta = uniform_betas(n_modes, ends)
    fields = (_pinned_modes if ends == "pinned-pinned" else _held_modes)(beta, x)
    return ModalBasis(x=x, omega=beta**2, **fields)
