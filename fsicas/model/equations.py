"""The equations of the model ``M(x, p) xdot = F(x, p)`` in lifted form.

State ``x = (r_1..r_N, q_1..q_N, Q_1, Q_2)``: modal velocities, modal displacements and
the inlet flow rates of channel 1 (above, s_1 = -1) and 2 (below, s_2 = +1). With
``h_c = H_c + s_c y`` and ``G_c = ∫_0^x dh_c/dt = s_c Σ Phi_n r_n`` the formal solutions
(paper Eqs. 7–12, with the readings of ``docs/model.md``, derived in ``docs/model.md``) read

    u_c = (Q_c - G_c) / h_c
    p_c(x) = P0 - M*/2 K0 u_c0|u_c0| - M* [ ∫_0^x g_c + u_c(x)^2 / 2 ]
    g_c = (dQ_c/dt - s_c Σ Phi_m dr_m/dt) / h_c + gt_c,   gt_c = u_c (f |u_c| - dh_c/dt) / h_c

and give, per channel c and mode n,

    Q row:   dQ_c/dt ∫1/h_c - s_c Σ_m dr_m/dt ∫Phi_m/h_c
                 = Δp/M* - (K0 u_c0|u_c0| + KL u_c1|u_c1|)/2 - ∫ gt_c
    beam:    dr_n/dt + M* Σ_c s_c [dQ_c/dt ∫Psi_n/h_c - s_c Σ_m dr_m/dt ∫Psi_n Phi_m/h_c]
                 = -2 zeta_n w_n r_n - w_n^2 q_n
                   - M* Σ_c s_c [K0/2 u_c0|u_c0| Phi_n(1) + ∫ gt_c Psi_n + ∫ u_c^2 phi_n / 2]
                   + ∫ f_contact phi_n
    kinematics: dq_n/dt = r_n

All integrals are Gauss–Legendre sums over the scene's nodes, but the impact load's
``∫ f_contact phi_n``: its patch is 1e-3 of L long, anywhere along the beam, so it has its
own rule, exact for the law's kink in a quadratic interpolant of the gap on small cells
(:mod:`fsicas.model.impact_rule`). u|u| is C^1, so F is smooth except for the contact kink
``max(0, eps - h_c)``.

The state enters the nonlinear terms only through the nodal values
``z = L x = (y, dy/dt, ∫_0^x dy/dt at the K nodes, Q_1, Q_2, y(1), ∫_0^1 dy/dt, y at the
contact nodes)``, and the
nonlinear terms come back through constant projections (``a = Σ Phi_m v_r,m`` at the
nodes, ``w = (a, v_Q) = L_w v``)::

    F = A x + P g(L x),                     dF/dx    = A + P (dg/dz) L
    M v = E v + P_m m(y, L_w v),            d(M v)/dx = P_m (dm/dy) phi^T,
                                            M        = E + P_m (dm/dw) L_w

``g`` and ``m`` hold one value per node (or a scalar), so their derivatives have a few
nonzeros per node: CasADi's AD takes them in a handful of directions instead of
n = 2N + 2, and the products with the constant ``P``, ``L`` are the O(N^2 K) work of the
matrices themselves. Each matrix is a :class:`continuation.Lifted`, so analyses can
also evaluate it at many points at once by dense products.
"""
from __future__ import annotations

import casadi as ca
import numpy as np
import scipy.sparse as sp

import continuation as C

from . import contact

__all__ = ["LiftedEquations"]


class LiftedEquations:
    """The lifted form (module docstring) of one scene's equations at its quadrature
    ``basis`` (K nodes, ``weights``) and tip modes ``tip``; ``sym`` is ``ca.SX`` or
    ``ca.MX``, ``names`` the model's parameter names."""

    def __init__(self, scene, basis, tip, weights, sym, names, contact_rule=None):
        self.scene, self.basis, self.tip, self.w = scene, basis, tip, weights
        self.n, self.K, self.sym, self.names = scene.modes, len(weights), sym, names
        self.contact_basis, self.impact_rule = contact_rule if contact_rule else (None, None)
        Kc = len(self.impact_rule.x) if contact_rule else 0
        phi, Phi, n, K = basis.phi, basis.Phi, self.n, self.K
        zero = lambda rows, cols=None: np.zeros((rows, cols if cols is not None else n))
        state = lambda r, q, Q: np.hstack([r, q, Q])
        phi_c = self.contact_basis.phi if Kc else zero(n, 0)
        self.L = sp.csc_matrix(np.vstack([
            state(zero(K), phi.T, zero(K, 2)), state(phi.T, zero(K), zero(K, 2)),
            state(Phi.T, zero(K), zero(K, 2)), state(zero(2), zero(2), np.eye(2)),
            state(zero(1), tip.phi[:, 1:].T, zero(1, 2)),
            state(tip.Phi[:, 1:].T, zero(1), zero(1, 2)), state(zero(Kc), phi_c.T, zero(Kc, 2))]))
        self.L_w = sp.csc_matrix(np.vstack([state(Phi.T, zero(K), zero(K, 2)),
                                            state(zero(2), zero(2), np.eye(2))]))
        beam = np.hstack([basis.Psi, phi, zero(n, 2 * K), tip.Phi[:, 1:], zero(n, 2), phi_c])
        flow = np.hstack([zero(2, 2 * K), np.kron(np.eye(2), -weights), zero(2, 1), np.eye(2),
                          zero(2, Kc)])
        self.P = sp.csc_matrix(np.vstack([beam, zero(n, 4 * K + 3 + Kc), flow]))
        self.P_m = sp.csc_matrix(np.vstack([np.hstack([basis.Psi, zero(n, 2 * K)]),
                                            zero(n, 3 * K),
                                            np.hstack([zero(2, K), np.kron(np.eye(2), weights)])]))
        self.E = sp.diags(np.r_[np.ones(2 * n), 0.0, 0.0]).tocsc()
        self.x, self.p = sym.sym("x", 2 * n + 2), sym.sym("p", len(names))
        self.v = sym.sym("v", 2 * n + 2)
        self.par = {name: self.p[i] for i, name in enumerate(names)}

    # -- F ------------------------------------------------------------------------------
    def force(self):
        """``F(x, p)``: the linear part plus ``P g(L x)``."""
        x, n = self.x, self.n
        zeta, omega = self._zeta(), self.basis.omega
        linear = ca.vertcat(-2 * zeta * omega * x[:n] - omega**2 * x[n:2 * n], x[:n],
                            ca.DM.zeros(2))
        z = self.sym.sym("z", self.L.shape[0])
        g = ca.substitute(self._nodal_force(z), z, ca.mtimes(_dm(self.L), x))
        return linear + ca.mtimes(_dm(self.P), g)

    def jacobian(self) -> C.Lifted:
        """``dF/dx = A(p) + P (dg/dz) L``."""
        n = self.n
        zeta, omega = self._zeta(), self.basis.omega
        A = ca.blockcat([[-ca.diag(2 * zeta * omega), ca.DM(-np.diag(omega**2)), ca.DM(n, 2)],
                         [ca.DM.eye(n), ca.DM(n, n), ca.DM(n, 2)],
                         [ca.DM(2, n), ca.DM(2, n), ca.DM(2, 2)]])
        z = self.sym.sym("z", self.L.shape[0])
        if self.impact_rule is None:
            dg = ca.jacobian(self._nodal_force(z), z)
        else:   # the impact block by the rule's own derivative: AD through it is 10-50x dearer
            head, y = 3 * self.K + 4, z[3 * self.K + 4:]
            dg = ca.vertcat(ca.jacobian(self._nodal_force(z, impact=False), z),
                            ca.horzcat(ca.DM(y.numel(), head), self._impact_jacobian(y)))
        dg = ca.substitute(dg, z, ca.mtimes(_dm(self.L), self.x))
        return C.Lifted(ca.Function("dg", [self.x, self.p], [dg]), self.P, self.L,
                        ca.Function("A", [self.p], [A]))

    def _zeta(self):
        return ca.vertcat(*[self.par[f"zeta{k + 1}"] for k in range(self.n)])

    def _nodal_force(self, z, impact: bool = True):
        """``g = (a, b, gt_1, gt_2, c, s_1, s_2, f)``: the nodal loads ``a`` (on Psi) and
        ``b`` (on phi), the nodal ``gt_c`` (on the flow rows, ``-∫ gt_c``), the inlet load
        ``c`` (on Phi(1)), the flow rows' scalar terms ``s_c`` (paper Eqs. 11–16) and the
        impact load ``f`` at the contact rule's nodes (on phi there)."""
        K, par, w = self.K, self.par, self.w
        mstar = par["mstar"]
        kin = dict(y=z[:K], ydot=z[K:2 * K], run=z[2 * K:3 * K], y_tip=z[3 * K + 2],
                   run_tip=z[3 * K + 3])
        a, b, c, gts, rows = 0, 0, 0, [], []
        for ch, s in enumerate(contact.WALL_SIGNS):
            u, gt, u_in, u_out = _channel(self.scene, self.basis, z[3 * K + ch], ch, s,
                                          par["friction"], kin)
            a -= mstar * s * w * gt
            b -= mstar * s * w * u**2 / 2
            c -= mstar * s * par["k0"] / 2 * u_in * ca.fabs(u_in)
            gts.append(gt)
            rows.append(par["pressure_drop"] / mstar
                        - (par["k0"] * u_in * ca.fabs(u_in) + par["kl"] * u_out * ca.fabs(u_out)) / 2)
        loads = [self._impact_load(z[3 * K + 4:])] if impact and self.impact_rule else []
        return ca.vertcat(a, b, *gts, c, *rows, *loads)

    def _impact_load(self, y):
        """``W`` with ``∫ Σ_c f_c phi_n = Σ_i W_i phi_n(x_i)`` at the impact rule's nodes
        (:mod:`.impact_rule`), from the deflection ``y`` there."""
        return contact.nodal_impact_load(self.impact_rule, self.scene, y, *self._law())

    def _impact_jacobian(self, y):
        """``dW/dy`` (:meth:`_impact_load`)."""
        return contact.nodal_impact_jacobian(self.impact_rule, self.scene, y, *self._law())

    def _law(self):
        """``(k, eps)`` of the contact law, symbolic in p."""
        k = contact.stiffness(self.par["contact_stiffness"], self.basis.omega[0])
        return k, self.par["contact_eps"] * self.scene.hstar / 2

    # -- M ------------------------------------------------------------------------------
    def _nodal_mass(self):
        """Symbols ``y`` (K), ``w = (a, v_Q)`` (K + 2) and ``m(y, w)``, linear in w::

            m = (M* Σ_c (w/h_c) (s_c v_Q,c − a),  (v_Q,1 − s_1 a)/h_1,  (v_Q,2 − s_2 a)/h_2)
        """
        y, wv = self.sym.sym("y", self.K), self.sym.sym("w", self.K + 2)
        a, vQ = wv[:self.K], wv[self.K:]
        m_beam, m_rows = 0, []
        for c, (wall, s) in enumerate(zip(self.scene.walls, contact.WALL_SIGNS)):
            inv_h = 1.0 / contact.gap(wall(self.basis.x), y, s)
            m_beam += self.w * inv_h * (s * vQ[c] - a)
            m_rows.append(inv_h * (vQ[c] - s * a))
        return y, wv, ca.vertcat(self.par["mstar"] * m_beam, *m_rows)

    def _nodal_at_state(self, expr, y, wv):
        """``expr(y, w)`` at ``y = phi^T q`` and ``w = L_w v``."""
        y_x = ca.mtimes(self.basis.phi.T, self.x[self.n:2 * self.n])
        return ca.substitute(ca.substitute(expr, y, y_x), wv, ca.mtimes(_dm(self.L_w), self.v))

    def mass_action(self):
        """``M v = E v + P_m m(phi^T q, L_w v)`` (O(N K), M is not formed)."""
        y, wv, m = self._nodal_mass()
        return ca.mtimes(_dm(self.E), self.v) + ca.mtimes(_dm(self.P_m), self._nodal_at_state(m, y, wv))

    def mass_action_jacobian(self) -> C.Lifted:
        """``d(M v)/dx = P_m (dm/dy) L_y`` with ``L_y`` the rows ``y = phi^T q`` of L."""
        y, wv, m = self._nodal_mass()
        dm = self._nodal_at_state(ca.jacobian(m, y), y, wv)
        return C.Lifted(ca.Function("dm_dy", [self.x, self.p, self.v], [dm]), self.P_m,
                        self.L[:self.K, :])

    def mass(self) -> C.Lifted:
        """``M = E + P_m (dm/dw) L_w`` (``m`` is linear in ``w``; ``dm/dw`` depends on y)."""
        y, wv, m = self._nodal_mass()
        dm = self._nodal_at_state(ca.jacobian(m, wv), y, wv)
        E = ca.Function("E", [self.p], [_dm(self.E)])
        return C.Lifted(ca.Function("dm_dw", [self.x, self.p], [dm]), self.P_m, self.L_w, E)


def _dm(a) -> ca.DM:
    """A constant CasADi matrix holding only the nonzeros of ``a``."""
    return ca.DM(sp.csc_matrix(a))


def _channel(scene, basis, Q_c, c, s, f, kin):
    """Flow of channel c at the nodes: ``u_c = (Q_c − s_c ∫_0^x dy/dt)/h_c`` with
    ``h_c = H_c + s_c y``, ``gt_c = u_c (f|u_c| − s_c dy/dt)/h_c`` and the inlet and
    outlet velocities u_c0, u_c1."""
    wall = scene.walls[c]
    inv_h = 1.0 / contact.gap(wall(basis.x), kin["y"], s)
    u = (Q_c - s * kin["run"]) * inv_h
    gt = u * (f * ca.fabs(u) - s * kin["ydot"]) * inv_h
    u_in = Q_c / float(wall(0.0))
    u_out = (Q_c - s * kin["run_tip"]) / (float(wall(1.0)) + s * kin["y_tip"])
    return u, gt, u_in, u_out
