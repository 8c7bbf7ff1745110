"""Clamped–free Timoshenko modes (shear and rotary inertia) of a uniform plate strip.

Per unit width: bending stiffness ``D = E e^3 / (12 (1 - nu^2))``, shear stiffness
``kappa G e`` with ``G = E / (2 (1 + nu))`` (kappa: Cowper's rectangle value
``10 (1 + nu) / (12 + 11 nu)`` by default), mass ``rho_s e`` and rotary inertia
``rho_s e^3 / 12``. In the units of :mod:`fsicas.units` (x by L, t by
``T = L^2 sqrt(rho_s e / D)``), with slenderness ``s = e / L``, deflection w and
cross-section rotation psi::

    w_tt - S (w' - psi)' = p,        r^2 psi_tt - psi'' - S (w' - psi) = 0,
    S = kappa G e L^2 / D = 6 kappa (1 - nu) / s^2,      r^2 = s^2 / 12,
    w(0) = psi(0) = 0,     psi'(1) = 0,     w'(1) - psi(1) = 0.

S -> infinity, r -> 0 gives ``w_tt + w'''' = p`` (Euler–Bernoulli, omega_n = beta_n^2).

Modes. ``e^(lambda x)`` solves the harmonic problem when ``mu = lambda^2`` is a root of
``mu^2 + omega^2 (r^2 + 1/S) mu - omega^2 (1 - omega^2 r^2 / S) = 0``: mu_2 < 0 always
(wavenumber beta = sqrt(-mu_2)), mu_1 > 0 below the cut-off ``omega_c = sqrt(S) / r``
(dimensionally ``sqrt(kappa G e / (rho_s I))``) and mu_1 < 0 above it, where the second
(rotation–shear) branch of the spectrum starts. With ``ch = cosh(sqrt(mu) x)`` and
``sh = sinh(sqrt(mu) x) / sqrt(mu)`` (entire in mu: cos and sin / k for mu < 0) each
root gives the pair ``(w, psi) = (mu sh, (q + mu) ch)`` and ``(ch, (q + mu) sh)``,
``q = omega^2 / S``, so nothing degenerates at the cut-off. The clamped end leaves a
2 x 2 determinant; with ``mu sh^2 - ch^2 = -1`` it reads exactly

    det = -2 A - A (mu_1 + mu_2) sh_1 sh_2 + ((q + mu_1)^2 + (q + mu_2)^2) ch_1 ch_2,
    A = (q + mu_1)(q + mu_2),

and the characteristic function is ``det / ((q + mu_1)^2 + (q + mu_2)^2)``, divided by
``ch_1 = cosh(sqrt(mu_1))`` below the cut-off: no cancellation, no overflow, continuous
through omega_c, ``cos(beta) + 1 / cosh(beta)`` in the thin limit.

Roots: sign changes on a grid whose steps advance the total phase ``beta + sqrt(-mu_1)``
(the second term above the cut-off) by at most pi/24, refined by Brent; the grid ends at
the Euler–Bernoulli omega_N, an upper bound of the Timoshenko omega_N (Rayleigh: the
Euler–Bernoulli kinematics psi = w' are admissible), and the count is checked again on a
grid twice as fine. Both branches are counted in one increasing sequence.

Shapes: null vector of the 4 x 4 boundary matrix in a bounded basis (``e^(-alpha x)``
and ``e^(alpha (x - 1))`` instead of ch_1, sh_1 when alpha = sqrt(mu_1) > 1), normalized
by the full mass, ``∫ w^2 + r^2 psi^2 dx = 1``, with sign w_n(1) = (-1)^(n+1). The
modal equations then keep unit modal mass and ``omega_n^2`` stiffness; the flow load
projects on w. Running integrals from the shear strain ``gamma = w' - psi`` as in
:mod:`.beam` (``-omega^2 w = S gamma'`` and gamma(1) = 0): ``Psi = ∫_x^1 w = gamma / q``
term by term in closed form, ``Phi = ∫_0^x w`` likewise.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from .beam import ModalBasis, clamped_free_betas
from .quadrature import gauss_legendre
from ..units import MAX_BEAM_RATIO

__all__ = ["TimoshenkoBeam", "TimoshenkoShapes", "cowper_shear_coefficient",
           "timoshenko_characteristic", "timoshenko_frequencies", "timoshenko_shapes",
           "timoshenko_modes"]

#: Largest phase step of the root-bracketing grid (roots are about pi apart in phase).
PHASE_STEP = np.pi / 24
MAX_SLENDERNESS = MAX_BEAM_RATIO


def cowper_shear_coefficient(nu: float) -> float:
    """Cowper's shear coefficient of a rectangle, ``10 (1 + nu) / (12 + 11 nu)``."""
    return 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu)


@dataclass(frozen=True)
class TimoshenkoBeam:
    """Slenderness e/L in (0, 0.5], Poisson ratio in [0, 0.5), shear coefficient kappa
    in (0, 1] (None: Cowper's rectangle value)."""

    slenderness: float
    poisson: float = 0.3
    shear_coefficient: float | None = None

    def __post_init__(self):
        s, nu, k = self.slenderness, self.poisson, self.shear_coefficient
        if not (np.isfinite(s) and 0.0 < s <= MAX_SLENDERNESS):
            raise ValueError(f"slenderness (e/L) must lie in (0, {MAX_SLENDERNESS}], got {s!r}")
        if not (np.isfinite(nu) and 0.0 <= nu < 0.5):
            raise ValueError(f"poisson (nu) must lie in [0, 0.5), got {nu!r}")
        if k is not None and not (np.isfinite(k) and 0.0 < k <= 1.0):
            raise ValueError(f"shear_coefficient (kappa) must lie in (0, 1], got {k!r}")

    @property
    def kappa(self) -> float:
        k = self.shear_coefficient
        return cowper_shear_coefficient(self.poisson) if k is None else float(k)

    @property
    def shear(self) -> float:
        """``S = kappa G e L^2 / D = 6 kappa (1 - nu) / s^2``."""
        return 6.0 * self.kappa * (1.0 - self.poisson) / self.slenderness**2

    @property
    def rotary(self) -> float:
        """``r^2 = s^2 / 12``, the rotary inertia relative to the mass (times L^2)."""
        return self.slenderness**2 / 12.0

    @property
    def cutoff(self) -> float:
        """``omega_c = sqrt(S) / r``: above it the second branch of the spectrum."""
        return float(np.sqrt(self.shear / self.rotary))


def _exponents(beam: TimoshenkoBeam, omega):
    """``(q, mu_1, mu_2)``, computed without cancellation (mu_1 from the product)."""
    w2, S, r2 = omega**2, beam.shear, beam.rotary
    b = w2 * (r2 + 1.0 / S) + omega * np.sqrt(w2 * (r2 - 1.0 / S) ** 2 + 4.0)
    return w2 / S, 2.0 * w2 * (1.0 - w2 * r2 / S) / b, -b / 2.0


def _ch_sh(mu, x):
    """``cosh(k x)`` and ``sinh(k x) / k``, ``k = sqrt(mu)`` (cos, sin / k for mu < 0)."""
    k = np.sqrt(np.abs(mu))
    z = k * x
    small = z < 1e-8
    zs = np.where(small, 1.0, z)
    if mu >= 0:
        return np.cosh(z), x * np.where(small, 1.0 + z**2 / 6.0, np.sinh(zs) / zs)
    return np.cos(z), x * np.where(small, 1.0 - z**2 / 6.0, np.sin(zs) / zs)


def timoshenko_characteristic(beam: TimoshenkoBeam, omega) -> np.ndarray:
    """The stable characteristic function (module doc) at omega > 0; its zeros are the
    natural frequencies."""
    omega = np.asarray(omega, dtype=float)
    q, m1, m2 = _exponents(beam, omega)
    beta = np.sqrt(-m2)
    ch2, sh2 = np.cos(beta), np.sin(beta) / beta
    norm = (q + m1) ** 2 + (q + m2) ** 2
    A, sigma = (q + m1) * (q + m2) / norm, m1 + m2
    k = np.sqrt(np.abs(m1))
    grow = m1 > 0
    ks = np.where(k > 1e-8, k, 1.0)
    with np.errstate(over="ignore"):
        w = np.where(grow, 1.0 / np.cosh(np.minimum(k, 700.0)), 1.0)
    t = np.where(k > 1e-8, np.where(grow, np.tanh(ks), np.sin(ks)) / ks, 1.0)
    c = np.where(grow, 1.0, np.cos(k))
    return -2.0 * A * w - A * sigma * t * sh2 + c * ch2


def _phase(beam: TimoshenkoBeam, omega):
    _, m1, m2 = _exponents(beam, omega)
    return np.sqrt(-m2) + np.sqrt(np.maximum(-m1, 0.0))


def _grid(beam: TimoshenkoBeam, top: float, step: float) -> np.ndarray:
    """Points in (0, top] at most ``step`` apart in phase (bisecting where needed)."""
    w = np.linspace(0.0, top, 257)[1:]
    w = np.r_[1e-9 * top, w]
    for _ in range(80):
        gaps = np.diff(_phase(beam, w)) > step
        if not gaps.any():
            return w
        w = np.sort(np.r_[w, 0.5 * (w[:-1] + w[1:])[gaps]])
    raise RuntimeError("the root-bracketing grid did not converge")


def _brackets(beam: TimoshenkoBeam, w: np.ndarray, f: np.ndarray) -> list[tuple]:
    """Sign changes of f on the grid, plus the pairs of close roots hidden between two
    grid points: a local extremum of |f| without a sign change is located (bounded
    Brent) and, if f changes sign there, gives two brackets."""
    out = [(w[i], w[i + 1]) for i in np.nonzero(np.signbit(f[:-1]) != np.signbit(f[1:]))[0]]
    a = np.abs(f)
    same = (np.signbit(f[:-2]) == np.signbit(f[1:-1])) & (np.signbit(f[1:-1]) == np.signbit(f[2:]))
    dips = np.nonzero((a[1:-1] < a[:-2]) & (a[1:-1] < a[2:]) & same)[0] + 1
    for i in dips:
        sign = 1.0 if f[i] > 0 else -1.0
        fun = lambda z: sign * float(timoshenko_characteristic(beam, z))
        z = minimize_scalar(fun, bounds=(w[i - 1], w[i + 1]), method="bounded",
                            options={"xatol": 1e-14 * w[i]}).x
        if fun(z) < 0:
            out += [(w[i - 1], z), (z, w[i + 1])]
    return sorted(out)


def _roots(beam: TimoshenkoBeam, top: float, step: float) -> np.ndarray:
    w = _grid(beam, top, step)
    f = timoshenko_characteristic(beam, w)
    fun = lambda z: float(timoshenko_characteristic(beam, z))
    return np.array([brentq(fun, lo, hi, xtol=1e-300, rtol=1e-15, maxiter=200)
                     for lo, hi in _brackets(beam, w, f)])


def _first_roots(n_modes: int, beam: TimoshenkoBeam, step: float) -> np.ndarray:
    """At least ``n_modes`` roots: the interval doubles up to the Euler–Bernoulli
    omega_N, an upper bound of the Timoshenko omega_N."""
    bound = float(clamped_free_betas(n_modes)[-1] ** 2) * (1.0 + 1e-9) + 1e-6
    top = min(bound, 4.0 * n_modes * float(clamped_free_betas(1)[0] ** 2))
    while True:
        roots = _roots(beam, top, step)
        if len(roots) >= n_modes or top >= bound:
            return roots
        top = min(bound, 2.0 * top)


def timoshenko_frequencies(n_modes: int, beam: TimoshenkoBeam) -> np.ndarray:
    """The first ``n_modes`` natural circular frequencies (units of 1/T), both branches
    in one increasing sequence; RuntimeError if a twice finer grid counts differently."""
    if int(n_modes) != n_modes or n_modes < 1:
        raise ValueError(f"n_modes must be a positive integer, got {n_modes!r}")
    return _frequencies(int(n_modes), beam).copy()


@functools.lru_cache(maxsize=64)
def _frequencies(n_modes: int, beam: TimoshenkoBeam) -> np.ndarray:
    roots = _first_roots(n_modes, beam, PHASE_STEP)
    if len(roots) < n_modes:
        raise RuntimeError(f"found {len(roots)} Timoshenko roots below the Euler–Bernoulli "
                           f"omega_{n_modes}, expected at least {n_modes}")
    check = _roots(beam, roots[n_modes - 1] * (1.0 + 1e-9), PHASE_STEP / 2)
    if len(check) != n_modes or not np.allclose(check, roots[:n_modes], rtol=1e-12, atol=0):
        raise RuntimeError(f"Timoshenko roots: {n_modes} on the grid, {len(check)} on a "
                           "grid twice as fine (closely spaced roots)")
    return roots[:n_modes]


class TimoshenkoShapes(NamedTuple):
    """Mode data at x (arrays (N, K)): deflection ``phi`` and its x-derivatives, rotation
    ``psi`` and ``dpsi`` (the bending curvature), ``Phi = ∫_0^x phi``, ``Psi = ∫_x^1 phi``."""

    omega: np.ndarray
    phi: np.ndarray
    dphi: np.ndarray
    ddphi: np.ndarray
    psi: np.ndarray
    dpsi: np.ndarray
    Phi: np.ndarray
    Psi: np.ndarray


#: Column fields: phi, dphi, ddphi, psi, dpsi, g (Psi = -Σ c g), G (Phi = Σ c G).
_FIELDS = 7


def _pair(mu: float, q: float, x: np.ndarray) -> np.ndarray:
    """The two columns ``(mu sh, (q+mu) ch)`` and ``(ch, (q+mu) sh)``, shape (2, 7, K)."""
    ch, sh = _ch_sh(mu, x)
    half = _ch_sh(mu, x / 2)[1]
    p = q + mu
    first = [mu * sh, mu * ch, mu**2 * sh, p * ch, p * mu * sh, ch, 2.0 * mu * half**2]
    second = [ch, mu * sh, mu * ch, p * sh, p * ch, sh, sh]
    return np.array([first, second])


def _exponentials(mu: float, q: float, x: np.ndarray) -> np.ndarray:
    """Columns ``(lambda, q + mu) e^(lambda (x - x0))`` for lambda = -alpha (x0 = 0) and
    +alpha (x0 = 1), bounded by 1 on [0, 1], shape (2, 7, K)."""
    a = np.sqrt(mu)
    out = []
    for lam, x0 in ((-a, 0.0), (a, 1.0)):
        e = np.exp(lam * (x - x0))
        grow = np.expm1(lam * x) if x0 == 0.0 else e - np.exp(-a)
        out.append([lam * e, mu * e, lam * mu * e, (q + mu) * e, lam * (q + mu) * e, e, grow])
    return np.array(out)


def _columns(beam: TimoshenkoBeam, omega: float, x: np.ndarray) -> np.ndarray:
    """The four basis solutions at x, shape (4, 7, K)."""
    q, m1, m2 = _exponents(beam, float(omega))
    first = _exponentials(m1, q, x) if m1 > 1.0 else _pair(m1, q, x)
    return np.concatenate([first, _pair(m2, q, x)])


def _coefficients(beam: TimoshenkoBeam, omega: float) -> np.ndarray:
    """Null vector of the boundary matrix: w(0), psi(0), psi'(1), gamma(1) / (-q)."""
    ends = _columns(beam, omega, np.array([0.0, 1.0]))
    B = np.array([ends[:, 0, 0], ends[:, 3, 0], ends[:, 4, 1], ends[:, 5, 1]])
    B /= np.abs(B).max(axis=1, keepdims=True)
    return np.linalg.svd(B)[2][-1]


def _mode(beam: TimoshenkoBeam, omega: float, sign: float, x: np.ndarray, nodes,
          weights) -> np.ndarray:
    """One mode's 7 fields at x (the g row replaced by Psi), mass-normalized, with
    ``sign(phi(1)) = sign``."""
    c = _coefficients(beam, omega)
    at = lambda points: np.einsum("k,kfj->fj", c, _columns(beam, omega, points))
    quad = at(nodes)
    c = c / np.sqrt(weights @ (quad[0] ** 2 + beam.rotary * quad[3] ** 2))
    c = c * sign * np.sign(at(np.array([1.0]))[0, 0])
    fields = np.einsum("k,kfj->fj", c, _columns(beam, omega, x))
    fields[5] = -fields[5]
    return fields


def timoshenko_shapes(n_modes: int, x, beam: TimoshenkoBeam) -> TimoshenkoShapes:
    """The first ``n_modes`` clamped–free Timoshenko modes and their integrals at x."""
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or not np.all(np.isfinite(x)) or np.any(x < 0.0) or np.any(x > 1.0):
        raise ValueError("x must be a 1-D array of finite points in [0, 1]")
    omega = timoshenko_frequencies(n_modes, beam)
    _, m1, m2 = _exponents(beam, omega[-1])
    wave = np.sqrt(-m2) + np.sqrt(abs(m1))
    nodes, weights = gauss_legendre(int(80 + 2 * wave))
    modes = np.array([_mode(beam, w, (-1.0) ** n, x, nodes, weights)
                      for n, w in enumerate(omega)])
    return TimoshenkoShapes(omega, *(modes[:, i] for i in (0, 1, 2, 3, 4, 6, 5)))


def timoshenko_modes(n_modes: int, x, beam: TimoshenkoBeam) -> ModalBasis:
    """:func:`timoshenko_shapes` as a :class:`~.beam.ModalBasis` (``ddphi`` = w'')."""
    m = timoshenko_shapes(n_modes, x, beam)
    return ModalBasis(x=np.asarray(x, dtype=float), omega=m.omega, phi=m.phi, dphi=m.dphi,
                      ddphi=m.ddphi, Phi=m.Phi, Psi=m.Psi)
