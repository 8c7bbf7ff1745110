"""The nonlinear beam–bulk-flow model in mass-matrix form ``M(x, p) xdot = F(x, p)``.

State ``x = (r_1..r_N, q_1..q_N, Q_1, Q_2)``: modal velocities, modal displacements and
the inlet flow rates of channel 1 (above, s_1 = -1) and 2 (below, s_2 = +1). With
``h_c = H_c + s_c y`` and ``G_c = ∫_0^x dh_c/dt = s_c Σ Phi_n r_n`` the formal solutions
(paper Eqs. 7–12, corrected per ERRATA, derived in ``docs/model.md``) read

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

All integrals are Gauss–Legendre sums over the scene's nodes. u|u| is C^1, so F is
smooth except for the contact kink ``max(0, eps - h_c)``.
"""
from __future__ import annotations

import functools
import weakref
from dataclasses import dataclass, field

import casadi as ca
import numpy as np
import scipy.sparse as sp

from . import contact
from .beam import ModalBasis, clamped_free_modes
from .beam_fe import default_n_elements, nonuniform_beam_modes
from .quadrature import composite_gauss_legendre, gauss_legendre
from ..scene import Scene

__all__ = ["Model", "build_model", "modal_basis", "parameter_names", "per_model"]

_FLOW_PARAMS = ("pressure_drop", "mstar", "friction", "k0", "kl")
_CONTACT_PARAMS = ("contact_stiffness", "contact_eps")


def parameter_names(scene: Scene) -> tuple[str, ...]:
    """Names of the symbolic parameters of the model of ``scene``, in order."""
    contact = _CONTACT_PARAMS if scene.contact else ()
    return _FLOW_PARAMS + contact + tuple(f"zeta{n + 1}" for n in range(scene.modes))


def modal_basis(scene: Scene, x) -> ModalBasis:
    """The scene's beam modes at points x: analytic when uniform, FE when ``thickness`` is set."""
    x = np.asarray(x, dtype=float)
    if scene.thickness is None:
        return clamped_free_modes(scene.modes, x)
    return nonuniform_beam_modes(scene.modes, x, thickness=scene.thickness)


def quadrature_rule(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights of the model's integrals.

    Analytic modes: one Gauss–Legendre rule of ``scene.n_quad`` nodes. FE modes are
    piecewise cubic, so the rule is composite and aligned with the elements, with
    ``ceil(n_quad / elements)`` (at least 4) nodes per element.
    """
    if scene.thickness is None:
        return gauss_legendre(scene.n_quad)
    elements = default_n_elements(scene.modes)
    return composite_gauss_legendre(elements, max(4, -(-scene.n_quad // elements)))


@dataclass(frozen=True, eq=False)
class Model:
    """CasADi functions of one scene structure; parameters are symbolic inputs.

    ``mass(x, p)`` and ``rhs(x, p)`` give M and F; ``jac_rhs(x, p)`` gives dF/dx (from
    the lifted form of the equations: AD of the nodal terms, then sparse products);
    ``mass_action(x, p, v)`` gives ``M(x, p) v`` in O(N K) operations without forming M
    (the implicit residual ``M z − F`` of time integration), ``jac_mass_action(x, p, v)``
    its derivative ``d(M v)/dx``.
    ``tip`` maps x to (y(1), dy/dt(1)). Use :meth:`parameters` for the numeric p.
    Models compare and hash by identity (caches keyed by a model die with it).
    """

    scene: Scene
    parameter_names: tuple[str, ...]
    mass: ca.Function
    rhs: ca.Function
    jac_rhs: ca.Function
    jac_rhs_p: ca.Function
    basis: ModalBasis = field(repr=False)
    weights: np.ndarray = field(repr=False)
    tip: ModalBasis = field(repr=False)
    mass_action: ca.Function = field(default=None, repr=False)
    jac_mass_action: ca.Function = field(default=None, repr=False)

    @property
    def n_modes(self) -> int:
        return self.scene.modes

    @property
    def n_state(self) -> int:
        return 2 * self.scene.modes + 2

    @property
    def omega_1(self) -> float:
        """First in-vacuo circular frequency omega_1 (units of 1/T): ``beta_1^2`` for the
        uniform beam, the lowest FE eigenvalue's root for a non-uniform one."""
        return float(self.basis.omega[0])

    def tip_deflection(self, x) -> np.ndarray | float:
        """Tip displacement ``y(1) = Σ phi_n(1) q_n`` of one state (a float) or of the rows
        of an array of states."""
        n = self.n_modes
        return _tip(np.asarray(x, dtype=float)[..., n:2 * n], self.tip.phi[:, 1])

    def tip_velocity(self, x) -> np.ndarray | float:
        """Tip velocity ``dy/dt(1) = Σ phi_n(1) r_n`` of one state or of rows of states."""
        return _tip(np.asarray(x, dtype=float)[..., :self.n_modes], self.tip.phi[:, 1])

    def index(self, name: str) -> int:
        """Position of parameter ``name`` in p."""
        try:
            return self.parameter_names.index(name)
        except ValueError:
            raise ValueError(f"unknown parameter {name!r}; the model has {self.parameter_names}")

    def parameters(self, scene: Scene | None = None, pressure_drop: float = 0.0, **override) -> np.ndarray:
        """Numeric parameter vector from a scene (same structure) plus overrides by name."""
        s = scene or self.scene
        values = dict(pressure_drop=pressure_drop, mstar=s.mstar, friction=s.friction, k0=s.k0,
                      kl=s.kl, contact_stiffness=s.contact_stiffness, contact_eps=s.contact_eps)
        values.update({f"zeta{n + 1}": z for n, z in enumerate(s.zeta_modes)})
        for name, value in override.items():
            self.index(name)
            values[name] = value
        return np.array([values[name] for name in self.parameter_names], dtype=float)

    def split(self, x) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(r, q, Q) views of a state vector."""
        x = np.asarray(x, dtype=float)
        n = self.n_modes
        return x[:n], x[n:2 * n], x[2 * n:]

    def basis_at(self, xs) -> ModalBasis:
        """The scene's modes at the points ``xs`` (see :func:`modal_basis`)."""
        return modal_basis(self.scene, xs)

    def deflection(self, x, xs) -> np.ndarray:
        """Beam deflection y(xs) = Σ phi_n(xs) q_n."""
        _, q, _ = self.split(x)
        return self.basis_at(xs).phi.T @ q

    def xdot(self, x, p) -> np.ndarray:
        """Solve M xdot = F for the time derivative at (x, p)."""
        return np.linalg.solve(np.array(self.mass(x, p)), np.array(self.rhs(x, p)).ravel())


def _tip(modal, phi_tip) -> np.ndarray | float:
    """``modal @ phi_tip``: a float for one vector, an array for rows."""
    y = modal @ phi_tip
    return float(y) if np.ndim(y) == 0 else y


def per_model(build):
    """Decorator: ``build(model)`` runs once per live :class:`Model` (Models hash by
    identity); the entry dies with its model. ``build`` must return objects that hold no
    reference back to the model (CasADi Functions built from it do not)."""
    cache = weakref.WeakKeyDictionary()

    @functools.wraps(build)
    def get(model):
        if model not in cache:
            cache[model] = build(model)
        return cache[model]

    return get


# -- assembly -------------------------------------------------------------------------
def build_model(scene: Scene, symbolic: str = "MX") -> Model:
    """Build the CasADi model of ``scene``'s structure (N, nodes, walls, contact).

    MX (the default) keeps the constant modal matrices as dense blocks: it builds and
    evaluates faster than SX at every N measured (docs/performance.md).
    """
    if symbolic not in ("SX", "MX"):
        raise ValueError(f"symbolic must be 'SX' or 'MX', got {symbolic!r}")
    sym = getattr(ca, symbolic)
    names = parameter_names(scene)
    nodes, weights = quadrature_rule(scene)
    basis = modal_basis(scene, nodes)
    tip = modal_basis(scene, [0.0, 1.0])
    n = scene.modes
    x, p, v = sym.sym("x", 2 * n + 2), sym.sym("p", len(names)), sym.sym("v", 2 * n + 2)
    par = {name: p[i] for i, name in enumerate(names)}
    lifted = _Lifted(scene, basis, tip, weights)
    force, jac = lifted.force(x, par)
    mass_v, jac_mass_v = lifted.mass_action(x, par, v)
    fun = lambda name, args, out, labels: ca.Function(name, args, [out], labels, [name])
    return Model(scene=scene, parameter_names=names,
                 mass=fun("M", [x, p], lifted.mass(x, par), ["x", "p"]),
                 rhs=fun("F", [x, p], force, ["x", "p"]),
                 jac_rhs=fun("dFdx", [x, p], jac, ["x", "p"]),
                 jac_rhs_p=fun("dFdp", [x, p], ca.jacobian(force, p), ["x", "p"]),
                 basis=basis, weights=weights, tip=tip,
                 mass_action=fun("Mv", [x, p, v], mass_v, ["x", "p", "v"]),
                 jac_mass_action=fun("dMvdx", [x, p, v], jac_mass_v, ["x", "p", "v"]))


class _Lifted:
    """The model in lifted form: the state enters the nonlinear terms only through the
    nodal values ``z = L x = (y, dy/dt, ∫_0^x dy/dt at the K nodes, Q_1, Q_2, y(1),
    ∫_0^1 dy/dt)``, and the nonlinear terms ``g(z)`` (one value per node, or a scalar)
    reach the equations through constant projections::

        F = A x + P g(L x),           dF/dx = A + P (dg/dz) L
        M v = (v_r, v_q, 0) + P_m m(y, a, v_Q),   d(M v)/dx = P_m (dm/dy) phi^T

    with ``a = Σ Phi_m v_r,m`` at the nodes. ``dg/dz`` has one nonzero per node and
    nodal variable (plus the columns of the scalars), so CasADi's AD takes it in 7
    directions instead of n = 2N + 2, and the products with the sparse ``P``, ``L``
    are the O(N^2 K) work of the Jacobian itself.
    """

    def __init__(self, scene, basis, tip, weights):
        self.scene, self.basis, self.tip, self.w = scene, basis, tip, weights
        self.n, self.K = scene.modes, len(weights)
        phi, Phi, n, K = basis.phi, basis.Phi, self.n, self.K
        zero = lambda rows, cols=None: np.zeros((rows, cols if cols is not None else n))
        state = lambda r, q, Q: np.hstack([r, q, Q])
        self.L = _sparse(np.vstack([
            state(zero(K), phi.T, zero(K, 2)), state(phi.T, zero(K), zero(K, 2)),
            state(Phi.T, zero(K), zero(K, 2)), state(zero(2), zero(2), np.eye(2)),
            state(zero(1), tip.phi[:, 1:].T, zero(1, 2)),
            state(tip.Phi[:, 1:].T, zero(1), zero(1, 2))]))
        beam = np.hstack([basis.Psi, phi, zero(n, 2 * K), tip.Phi[:, 1:], zero(n, 2)])
        flow = np.hstack([zero(2, 2 * K), np.kron(np.eye(2), -weights), zero(2, 1), np.eye(2)])
        self.P = _sparse(np.vstack([beam, zero(n, 4 * K + 3), flow]))
        self.P_m = _sparse(np.vstack([np.hstack([basis.Psi, zero(n, 2 * K)]), zero(n, 3 * K),
                                      np.hstack([zero(2, K), np.kron(np.eye(2), weights)])]))

    def force(self, x, par):
        """``F`` and ``dF/dx`` (module docstring)."""
        n = self.n
        zeta = ca.vertcat(*[par[f"zeta{k + 1}"] for k in range(n)])
        omega = self.basis.omega
        r, q = x[:n], x[n:2 * n]
        linear = ca.vertcat(-2 * zeta * omega * r - omega**2 * q, r, ca.DM.zeros(2))
        A = ca.blockcat([[-ca.diag(2 * zeta * omega), ca.DM(-np.diag(omega**2)), ca.DM(n, 2)],
                         [ca.DM.eye(n), ca.DM(n, n), ca.DM(n, 2)],
                         [ca.DM(2, n), ca.DM(2, n), ca.DM(2, 2)]])
        z = type(x).sym("z", self.L.size1())
        g = self._nodal_force(z, par)
        lift = ca.mtimes(self.L, x)
        g_x, dg = (ca.substitute(e, z, lift) for e in (g, ca.jacobian(g, z)))
        return linear + ca.mtimes(self.P, g_x), A + ca.mtimes(self.P, ca.mtimes(dg, self.L))

    def _nodal_force(self, z, par):
        """``g = (a, b, gt_1, gt_2, c, s_1, s_2)``: the nodal loads ``a`` (on Psi) and ``b``
        (on phi), the nodal ``gt_c`` (on the flow rows, ``-∫ gt_c``), the inlet load ``c``
        (on Phi(1)) and the flow rows' scalar terms ``s_c`` (paper Eqs. 11–16)."""
        K, mstar, w = self.K, par["mstar"], self.w
        kin = dict(y=z[:K], ydot=z[K:2 * K], run=z[2 * K:3 * K], y_tip=z[3 * K + 2],
                   run_tip=z[3 * K + 3])
        a, b, c, gts, rows = 0, 0, 0, [], []
        for ch, s in enumerate(contact.WALL_SIGNS):
            h, _, u, gt, u_in, u_out = _channel(self.scene, self.basis, w, z[3 * K + ch], ch, s,
                                                par["friction"], kin)
            a -= mstar * s * w * gt
            b -= mstar * s * w * u**2 / 2
            c -= mstar * s * par["k0"] / 2 * u_in * ca.fabs(u_in)
            gts.append(gt)
            rows.append(par["pressure_drop"] / mstar
                        - (par["k0"] * u_in * ca.fabs(u_in) + par["kl"] * u_out * ca.fabs(u_out)) / 2)
            if self.scene.contact:
                b += w * _contact_density(self.scene, self.basis, h, s, par)
        return ca.vertcat(a, b, *gts, c, *rows)

    def mass(self, x, par):
        """M from its (r, q, Q) blocks (module docstring of the model)."""
        n, basis, mstar = self.n, self.basis, par["mstar"]
        Phi, Psi = basis.Phi, basis.Psi
        mass_rr, mass_rQ, mass_Qr, mass_QQ = ca.DM.eye(n), [], [], []
        for s, wh in zip(contact.WALL_SIGNS, self._inverse_gaps(x)):
            mass_rQ.append(mstar * s * ca.mtimes(Psi, wh))
            mass_rr = mass_rr - mstar * ca.mtimes(Psi, ca.mtimes(ca.diag(wh), Phi.T))
            mass_Qr.append(-s * ca.mtimes(Phi, wh).T)
            mass_QQ.append(ca.sum1(wh))
        return _blocks(n, mass_rr, mass_rQ, mass_Qr, mass_QQ)

    def _inverse_gaps(self, x):
        """``w / h_c`` at the nodes for both channels."""
        y = ca.mtimes(self.basis.phi.T, x[self.n:2 * self.n])
        return [self.w / contact.gap(wall(self.basis.x), y, s)
                for wall, s in zip(self.scene.walls, contact.WALL_SIGNS)]

    def mass_action(self, x, par, v):
        """``M v`` and ``d(M v)/dx`` without forming M, with ``a = Σ Phi_m v_r,m``::

            beam:   v_r + M* Σ_c Psi (w/h_c) (s_c v_Q,c − a)
            kinematics: v_q
            Q row:  Σ_k (w/h_c)_k (v_Q,c − s_c a_k)
        """
        n, basis = self.n, self.basis
        vr, vq, vQ = v[:n], v[n:2 * n], v[2 * n:]
        a = ca.mtimes(basis.Phi.T, vr)
        y = type(x).sym("y", self.K)
        m_beam, m_rows = 0, []
        for c, (wall, s) in enumerate(zip(self.scene.walls, contact.WALL_SIGNS)):
            inv_h = 1.0 / contact.gap(wall(basis.x), y, s)
            m_beam += self.w * inv_h * (s * vQ[c] - a)
            m_rows.append(inv_h * (vQ[c] - s * a))
        m = ca.vertcat(par["mstar"] * m_beam, *m_rows)
        y_x = ca.mtimes(basis.phi.T, x[n:2 * n])
        m_x, dm = (ca.substitute(e, y, y_x) for e in (m, ca.jacobian(m, y)))
        value = ca.vertcat(vr, vq, ca.DM.zeros(2)) + ca.mtimes(self.P_m, m_x)
        dy_dx = self.L[:self.K, :]
        return value, ca.mtimes(self.P_m, ca.mtimes(dm, dy_dx))


def _sparse(a: np.ndarray) -> ca.DM:
    """A constant CasADi matrix holding only the nonzeros of ``a``."""
    return ca.DM(sp.csc_matrix(a))


def _channel(scene, basis, w, Q_c, c, s, f, kin):
    """Flow of channel c at the nodes: ``h_c = H_c + s_c y``, ``w/h_c``,
    ``u_c = (Q_c − s_c ∫_0^x dy/dt)/h_c``, ``gt_c = u_c (f|u_c| − s_c dy/dt)/h_c`` and the
    inlet and outlet velocities u_c0, u_c1."""
    wall = scene.walls[c]
    h = contact.gap(wall(basis.x), kin["y"], s)
    inv_h = 1.0 / h
    u = (Q_c - s * kin["run"]) * inv_h
    gt = u * (f * ca.fabs(u) - s * kin["ydot"]) * inv_h
    u_in = Q_c / float(wall(0.0))
    u_out = (Q_c - s * kin["run_tip"]) / (float(wall(1.0)) + s * kin["y_tip"])
    return h, w * inv_h, u, gt, u_in, u_out                   # w * inv_h: quadrature weight / h


def _blocks(n, mass_rr, mass_rQ, mass_Qr, mass_QQ):
    """M from its (r, q, Q) blocks."""
    zeros = ca.DM.zeros(n, n)
    mass = ca.blockcat([
        [mass_rr, zeros, ca.horzcat(*mass_rQ)],
        [zeros, ca.DM.eye(n), ca.DM.zeros(n, 2)],
        [ca.vertcat(mass_Qr[0], mass_Qr[1]), ca.DM.zeros(2, n), ca.diag(ca.vertcat(*mass_QQ))],
    ])
    return mass


def _contact_density(scene, basis, h, s, par):
    """The impact load density ``f_c`` of wall c at the nodes (:mod:`.contact`)."""
    k = contact.stiffness(par["contact_stiffness"], basis.omega[0])
    eps = par["contact_eps"] * scene.hstar / 2
    return contact.wall_load(h, s, k, eps, scene.contact_smoothing)
