"""Flow fields along the channels from a state and its time derivative (NumPy, any x).

This evaluates the formal solution point-wise, on a grid of the caller's choice, by
cumulative Simpson integration — a route independent of the model's Gauss–Legendre
projection, used for plots and to verify the model against the PDEs (4) and BCs (6):

    u_c = (Q_c - G_c)/h_c,  p_c = P0 - M*/2 K0 u_c0|u_c0| - M*[∫_0^x g_c + u_c^2/2],
    g_c = (dQ_c/dt - dG_c/dt)/h_c + u_c (f|u_c| - dh_c/dt)/h_c,   with PL = 0, P0 = Δp.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import cumulative_simpson

from .assembly import modal_basis
from ..scene import Scene

__all__ = ["FlowFields", "flow_fields"]


@dataclass(frozen=True)
class FlowFields:
    """Fields at points ``x``; arrays indexed [channel, point] for h, u, p."""

    x: np.ndarray
    y: np.ndarray
    h: np.ndarray
    u: np.ndarray
    p: np.ndarray

    @property
    def load(self) -> np.ndarray:
        """Net pressure load on the beam, p2 - p1 (positive pushes the beam up, y > 0)."""
        return self.p[1] - self.p[0]


def flow_fields(scene: Scene, state, state_dot, pressure_drop: float, x=None) -> FlowFields:
    """Heights, velocities and pressures of both channels at points ``x`` (default 2001)."""
    x = np.linspace(0.0, 1.0, 2001) if x is None else np.asarray(x, dtype=float)
    if x[0] != 0.0 or np.any(np.diff(x) <= 0):
        raise ValueError("x must start at 0 and increase strictly")
    n = scene.modes
    state, state_dot = np.asarray(state, float), np.asarray(state_dot, float)
    r, q, Q = state[:n], state[n:2 * n], state[2 * n:]
    rdot, Qdot = state_dot[:n], state_dot[2 * n:]
    modes = modal_basis(scene, x)
    y, ydot = modes.phi.T @ q, modes.phi.T @ r
    h, u, p = [], [], []
    for c, s in ((0, -1.0), (1, 1.0)):
        hc = scene.walls[c](x) + s * y
        uc = (Q[c] - s * modes.Phi.T @ r) / hc
        gc = (Qdot[c] - s * modes.Phi.T @ rdot) / hc + uc * (scene.friction * abs(uc) - s * ydot) / hc
        u_in = uc[0]
        pc = pressure_drop - scene.mstar * (scene.k0 / 2 * u_in * abs(u_in)
                                            + cumulative_simpson(gc, x=x, initial=0.0) + uc**2 / 2)
        h.append(hc), u.append(uc), p.append(pc)
    return FlowFields(x, y, np.array(h), np.array(u), np.array(p))
