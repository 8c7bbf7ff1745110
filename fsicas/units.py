"""Nondimensionalization: the one place where the conventions live.

Lengths (x, y, heights) by the beam length L; time by ``T = L^2 sqrt(rho_s e / D)`` with
``D = E e^3 / (12 (1 - nu^2))`` the bending stiffness per unit width; pressure by
``D / L^3``; velocity by ``L / T``. The beam then reads ``y_tt + y_xxxx = p2 - p1`` and
the fluid momentum carries the factor ``M* = rho_f L / (rho_s e)``:

    M* [ (h u)_t + (h u^2)_x + f u|u| ] + h p_x = 0,     h_t + (h u)_x = 0.

``U* = U0 L sqrt(rho_s e / D)`` is the mean inlet velocity in units of L/T, and
``w_n = (beta_n L)^2`` the in-vacuo frequencies in rad per unit T. y > 0 points into
channel 1 (above): ``h1 = H1 - y``, ``h2 = H2 + y``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["Scales", "friction_from_reynolds", "thick_beam_message", "THIN_BEAM_RATIO",
           "MAX_BEAM_RATIO"]

#: Largest thickness-to-length ratio e/L of the Euler–Bernoulli (thin) beam: beyond it
#: shear and rotary inertia (Timoshenko) change the modes by more than a few per cent.
THIN_BEAM_RATIO = 0.1
#: Largest e/L of any 1D beam theory (Timoshenko included): beyond it the strip is a
#: 2D elastic body, not a beam.
MAX_BEAM_RATIO = 0.5


@dataclass(frozen=True)
class Scales:
    """SI scales of one physical configuration, to convert results back."""

    length: float      # L [m]
    time: float        # T [s]
    pressure: float    # D / L^3 [Pa]
    width: float = 1.0  # b [m]
    fluid_density: float = 1.0
    beam_mass_per_area: float = 1.0  # rho_s e [kg/m^2]
    gap: float | None = None  # H1 + H2 at the inlet [m]

    @property
    def velocity(self) -> float:
        return self.length / self.time

    def m_per_s(self, ustar: float) -> float:
        """Mean inlet velocity ``U0 = U* L / T`` in m/s."""
        return ustar * self.velocity

    def m3_per_s(self, ustar: float) -> float:
        """Volume flow ``Q = U0 b (H1 + H2)`` in m^3/s (both channels)."""
        if self.gap is None:
            raise ValueError("the volume flow needs the channel heights (gap) of the scales")
        return self.m_per_s(ustar) * self.width * self.gap

    def l_per_min(self, ustar: float) -> float:
        """Volume flow in L/min."""
        return self.m3_per_s(ustar) * 60e3

    def ustar(self, velocity: float) -> float:
        """U* of a mean inlet velocity in m/s."""
        return velocity / self.velocity

    def hz(self, omega: float) -> float:
        """Frequency in Hz of a nondimensional circular frequency."""
        return omega / (2 * math.pi * self.time)

    def pa(self, p: float) -> float:
        return p * self.pressure

    def mm(self, y: float) -> float:
        return y * self.length * 1e3

    def newtons(self, load: float) -> float:
        """A total load over the beam (a nondimensional pressure integrated along it) in
        N over the width: ``load (D / L^3) L b``."""
        return load * self.pressure * self.length * self.width

    def seconds(self, t: float) -> float:
        return t * self.time

    @classmethod
    def from_physical(cls, *, rho_s, E, nu, e, L, b, rho_f, H1, H2, U0) -> "Scales":
        """Check a physical parameter set and return its scales (ValueError names the field)."""
        for name, value in dict(rho_s=rho_s, E=E, e=e, L=L, b=b, rho_f=rho_f, H1=H1, H2=H2).items():
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number (SI units), got {value!r}")
        if not (isinstance(U0, (int, float)) and math.isfinite(U0)):
            raise ValueError(f"U0 must be a finite number (m/s), got {U0!r}")
        if not -1.0 < nu < 0.5:
            raise ValueError(f"nu (Poisson ratio) must lie in (-1, 0.5), got {nu!r}")
        if e > MAX_BEAM_RATIO * L:
            raise ValueError(f"e = {e:g} m is not small against L = {L:g} m (e/L = {e / L:.3g}"
                             f" > {MAX_BEAM_RATIO:g}): beyond the range of 1D beam theory "
                             "(Timoshenko included); give a longer L or a thinner e")
        if b < e:
            raise ValueError(f"b = {b} m is narrower than the thickness e = {e} m: not a plate")
        try:
            D = E * e**3 / (12.0 * (1.0 - nu**2))
            scales = dict(length=L, time=L**2 * math.sqrt(rho_s * e / D), pressure=D / L**3,
                          width=b, fluid_density=rho_f, beam_mass_per_area=rho_s * e, gap=H1 + H2)
        except (OverflowError, ZeroDivisionError):
            scales = {"time": math.inf}
        bad = [k for k, v in scales.items() if not (math.isfinite(v) and v > 0)]
        if bad:
            raise ValueError(f"the physical values give a {bad[0]} scale of "
                             f"{scales[bad[0]]:g}, beyond what a float holds: E = {E:g} Pa, "
                             f"e = {e:g} m, L = {L:g} m, rho_s = {rho_s:g} kg/m^3; give "
                             "values in SI units of a real beam")
        return cls(**scales)


def thick_beam_message(e: float, L: float) -> str:
    """Why an Euler–Bernoulli beam with e/L >= THIN_BEAM_RATIO is refused, and what to do
    instead."""
    limit = THIN_BEAM_RATIO * L
    return (f"e = {e:g} m is not thin against L = {L:g} m (e/L = {e / L:.3g}): the 1D "
            f"Euler–Bernoulli beam of fsicas needs e/L < {THIN_BEAM_RATIO:g}, i.e. e < "
            f"{limit * 1e3:.3g} mm here. Give a thinner effective thickness e (the soft_palate "
            "preset takes 2.5 mm for a 30 mm palate 8-10 mm thick) or a longer L, or use the "
            "thick-beam (Timoshenko) modes, which e/L >= 0.1 needs: beam = 'timoshenko' "
            "(--beam timoshenko, the choice when the beam theory is not given)")


def friction_from_reynolds(re: float, re_transition: float = 2500.0) -> float:
    """Fanning friction coefficient of the paper's Eq. (15).

    ``f = 12 / Re`` (laminar, Re < Re0) and ``f = 0.055 Re^-0.25`` (turbulent).
    Note: at Re = 100 this gives 0.12, while the paper uses f = 0.14 for Re = 100;
    fsicas takes f itself as the input and offers this only as a helper.
    """
    if not (isinstance(re, (int, float)) and math.isfinite(re) and re > 0):
        raise ValueError(f"re (Reynolds number) must be > 0, got {re!r}")
    return 12.0 / re if re < re_transition else 0.055 * re**-0.25
