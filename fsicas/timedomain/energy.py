"""Energy balance of the beam over a time window of a trajectory.

The modal beam equations ``ṙ_n + 2ζ_n w_n r_n + w_n² q_n = f_n + c_n`` (fluid load
``f_n = ∫(p2 − p1) φ_n``, contact load ``c_n``), multiplied by ``r_n = q̇_n`` and
summed, give

    dE/dt = P_fluid + P_contact − D,     E = Σ (r_n² + w_n² q_n²)/2,
    P_fluid = Σ r_n f_n = ∫ (p2 − p1) ẏ dx,  P_contact = Σ r_n c_n,  D = Σ 2ζ_n w_n r_n².

``P_fluid`` is computed by the independent field route (:mod:`fsicas.fields`: pressures
rebuilt point-wise by cumulative Simpson on 2001 points from x and ẋ = M⁻¹F), not from
the model's Gauss projection; ``P_contact`` projects the exact contact law on the model's
nodes (the load the dynamics sees). Powers are integrated in time by Simpson's rule on
the output samples. Over a settled cycle ΔE ≈ 0, so the work of the flow equals the
structural dissipation minus the work of the contact forces.

Flow conservation: the outlet flow rates ``Q_c − s_c Σ Φ_n(1) r_n`` sum to the inlet
total ``Q1 + Q2`` exactly (the beam displaces fluid from one channel into the other), and
their time means over a cycle equal the inlet means (``∫ r_n dt = Δq_n ≈ 0``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import simpson

from ..model import contact
from ..model.fields import flow_fields
from ..model.assembly import modal_basis
from .integrators import Trajectory

__all__ = ["EnergyBalance", "energy_balance", "outlet_flow_rates"]


@dataclass(frozen=True)
class EnergyBalance:
    """Terms over [t_a, t_b]; ``residual = ΔE − (W_fluid + W_contact − dissipation)``."""

    t_a: float
    t_b: float
    delta_energy: float
    fluid_work: float
    contact_work: float
    dissipation: float

    @property
    def residual(self) -> float:
        return self.delta_energy - (self.fluid_work + self.contact_work - self.dissipation)

    @property
    def relative_residual(self) -> float:
        """|residual| relative to the largest term."""
        scale = max(abs(self.fluid_work), abs(self.contact_work), abs(self.dissipation), 1e-300)
        return abs(self.residual) / scale


def _powers(traj: Trajectory, k: int, xs, phi_xs):
    """(P_fluid, P_contact, D, E) at sample k."""
    model = traj.model
    scene, n = model.scene_at(traj.p), model.n_modes
    x = traj.x[k]
    p = traj.p.copy()
    p[model.index("pressure_drop")] = traj.pressure_drop[k]
    xdot = model.xdot(x, p)
    fields = flow_fields(scene, x, xdot, traj.pressure_drop[k], xs)
    r = x[:n]
    ydot = phi_xs.T @ r
    fluid = simpson(fields.load * ydot, x=xs)
    zeta, w = scene.zeta_modes, model.basis.omega
    impact = 0.0
    if scene.contact:
        impact = float(r @ contact.modal_load(model, x, p))
    return fluid, impact, float(np.sum(2 * zeta * w * r**2)), float(np.sum(r**2 + (w * x[n:2 * n])**2) / 2)


def energy_balance(traj: Trajectory, t_a: float, t_b: float, points: int = 2001) -> EnergyBalance:
    """Terms of the beam's energy equation over the samples in [t_a, t_b]."""
    if not t_b > t_a:
        raise ValueError(f"t_b must be > t_a, got {t_a}, {t_b}")
    a, b = np.searchsorted(traj.t, t_a), np.searchsorted(traj.t, t_b, side="right")
    if b - a < 3:
        raise ValueError("the window holds fewer than 3 output samples")
    model = traj.model
    xs = np.linspace(0.0, 1.0, points)
    phi_xs = modal_basis(model.scene, xs).phi
    terms = np.array([_powers(traj, k, xs, phi_xs)
                      for k in range(a, b)])
    t = traj.t[a:b]
    work = [simpson(terms[:, j], x=t) for j in range(3)]
    return EnergyBalance(float(t[0]), float(t[-1]), float(terms[-1, 3] - terms[0, 3]), *map(float, work))


def outlet_flow_rates(traj: Trajectory) -> np.ndarray:
    """``Q_c(1) = Q_c − s_c Σ Φ_n(1) r_n`` per sample, shape (samples, 2)."""
    n = traj.model.n_modes
    run_tip = traj.x[:, :n] @ traj.model.tip.Phi[:, 1]
    return np.stack([traj.x[:, -2] + run_tip, traj.x[:, -1] - run_tip], axis=1)
