"""The model of one scene structure: the CasADi functions of ``M(x, p) xdot = F(x, p)``.

State ``x = (r_1..r_N, q_1..q_N, Q_1, Q_2)``: modal velocities, modal displacements and
the inlet flow rates of channel 1 (above) and 2 (below). The equations (paper Eqs. 7–16,
with the readings of ``docs/model.md``, derived in ``docs/model.md``) and their lifted Jacobians are
written in :mod:`.equations`; here they become a :class:`Model` with the modes, the
quadrature rule and the parameter vector of one scene structure.
"""
from __future__ import annotations

import functools
import weakref
from dataclasses import dataclass, field

import casadi as ca
import numpy as np
import scipy.optimize

from .beam import ModalBasis, uniform_modes
from .beam_timoshenko import TimoshenkoBeam, timoshenko_modes
from .beam_timoshenko_fe import timoshenko_fe_elements, timoshenko_fe_modes
from .equations import LiftedEquations
from .beam_fe import default_n_elements, nonuniform_beam_modes
from .impact_rule import ImpactRule, impact_rule
from .quadrature import composite_gauss_legendre, gauss_legendre
from ..scene import CLAMPED_FREE, CONTACT_PARAMETERS, MODEL_PARAMETERS, STRUCTURE_FIELDS, Scene

__all__ = ["Model", "build_model", "modal_basis", "parameter_names", "per_model", "contact_rule",
           "reference_point"]

#: Structure fields compared by :meth:`Model.require_structure` (``contact`` apart: a
#: model with contact also serves a contact-free scene).
_COMPARED = tuple(f for f in STRUCTURE_FIELDS if f != "contact")


def parameter_names(scene: Scene) -> tuple[str, ...]:
    """Names of the symbolic parameters of the model of ``scene``, in order: the pressure
    drop, then :data:`fsicas.scene.MODEL_PARAMETERS` (those of the contact law only with
    contact; zeta as ``zeta1 .. zetaN``)."""
    names = [name for name in MODEL_PARAMETERS if scene.contact or name not in CONTACT_PARAMETERS]
    return ("pressure_drop",) + tuple(name for name in names if name != "zeta") \
        + tuple(f"zeta{n + 1}" for n in range(scene.modes))


def modal_basis(scene: Scene, x) -> ModalBasis:
    """The scene's beam modes at points x, with its ``ends``: analytic when uniform, FE
    when ``thickness`` is set; Timoshenko (:mod:`.beam_timoshenko`, FE
    :mod:`.beam_timoshenko_fe` when ``thickness`` is set or the ends are not
    clamped–free) when ``beam = "timoshenko"``."""
    x = np.asarray(x, dtype=float)
    if scene.beam == "timoshenko":
        beam = TimoshenkoBeam(scene.slenderness, scene.poisson, scene.shear_coefficient)
        if not _finite_elements(scene):
            return timoshenko_modes(scene.modes, x, beam)
        return timoshenko_fe_modes(scene.modes, x, beam, thickness=scene.thickness,
                                   ends=scene.ends)
    if scene.thickness is None:
        return uniform_modes(scene.modes, x, scene.ends)
    return nonuniform_beam_modes(scene.modes, x, thickness=scene.thickness, ends=scene.ends)


def _finite_elements(scene: Scene) -> bool:
    """Whether the scene's modes are FE modes (piecewise polynomials): a non-uniform
    beam, or a Timoshenko beam with other ends than the cantilever's."""
    return scene.thickness is not None or (scene.beam == "timoshenko"
                                           and scene.ends != CLAMPED_FREE)


def reference_point(scene: Scene) -> float:
    """Where the "tip" measures of a scene are taken: the free end x = 1 of the
    cantilever; with both ends held (y(1) = 0), the largest deflection of the first mode:
    x = 0.5 for a uniform beam with symmetric ends, else the zero of phi_1' around the
    largest sample of |phi_1| on 401 points (Brent, to 1e-12)."""
    if scene.ends == CLAMPED_FREE:
        return 1.0
    if scene.ends in ("clamped-clamped", "pinned-pinned") and scene.thickness is None:
        return 0.5
    grid = np.linspace(0.0, 1.0, 401)
    k = int(np.argmax(np.abs(modal_basis(scene, grid).phi[0])))
    slope = lambda z: float(modal_basis(scene, np.array([z])).dphi[0, 0])
    return float(scipy.optimize.brentq(slope, grid[k - 1], grid[k + 1], xtol=1e-12))


def quadrature_rule(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights of the model's integrals.

    Analytic modes: one Gauss–Legendre rule of ``scene.n_quad`` nodes. FE modes are
    piecewise cubic, so the rule is composite and aligned with the elements, with
    ``ceil(n_quad / elements)`` (at least 4) nodes per element.
    """
    if not _finite_elements(scene):
        return gauss_legendre(scene.n_quad)
    if scene.beam == "timoshenko":     # piecewise quintic w: at least 6 nodes per element
        elements, least = timoshenko_fe_elements(scene.modes), 6
    else:
        elements, least = default_n_elements(scene.modes), 4
    return composite_gauss_legendre(elements, max(least, -(-scene.n_quad // elements)))


def contact_rule(scene: Scene) -> ImpactRule:
    """The rule of the impact load ``∫ f_contact phi_n``, finer with ``scene.n_quad``
    (:mod:`.impact_rule`: the exact law's cell rule, 241 nodes at the default 40; the
    smoothed law's graded towards the cantilever's tip, or uniform when both ends are held)."""
    return impact_rule(scene.n_quad, scene.contact_smoothing, scene.ends == CLAMPED_FREE)


@dataclass(frozen=True, eq=False)
class Model:
    """CasADi functions of one scene structure; parameters are symbolic inputs.

    ``mass(x, p)`` and ``rhs(x, p)`` give M and F; ``jac_rhs(x, p)`` gives dF/dx (from
    the lifted form of the equations: AD of the nodal terms, then sparse products);
    ``mass_action(x, p, v)`` gives ``M(x, p) v`` in O(N K) operations without forming M
    (the implicit residual ``M z − F`` of time integration), ``jac_mass_action(x, p, v)``
    its derivative ``d(M v)/dx``. ``lifted`` holds ``jac_rhs``, ``jac_mass_action`` and
    ``mass`` as :class:`continuation.Lifted` (their structure ``A + P D L``).
    ``tip`` holds the modes at x = [0, 1] (the equations' outlet), ``probe`` those at
    [0, x_ref], the reference point of every "tip" measure (:func:`reference_point`;
    ``probe is tip`` for the cantilever); ``contact_basis`` and ``impact_rule`` are the
    modes at the impact load's own nodes and its rule (:func:`contact_rule`; None without
    contact). Use :meth:`parameters` for the numeric p.
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
    probe: ModalBasis | None = field(default=None, repr=False)
    mass_action: ca.Function = field(default=None, repr=False)
    jac_mass_action: ca.Function = field(default=None, repr=False)
    lifted: dict = field(default_factory=dict, repr=False)
    contact_basis: ModalBasis | None = field(default=None, repr=False)
    impact_rule: ImpactRule | None = field(default=None, repr=False)

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

    @property
    def x_ref(self) -> float:
        """The reference point where "tip" measures are taken (:func:`reference_point`)."""
        return float(self.probe.x[1])

    def tip_deflection(self, x) -> np.ndarray | float:
        """Displacement ``y(x_ref) = Σ phi_n(x_ref) q_n`` at the reference point (the tip
        x = 1 of the cantilever) of one state (a float) or of the rows of an array of
        states."""
        n = self.n_modes
        return _tip(np.asarray(x, dtype=float)[..., n:2 * n], self.probe.phi[:, 1])

    def tip_velocity(self, x) -> np.ndarray | float:
        """Velocity ``dy/dt(x_ref) = Σ phi_n(x_ref) r_n`` of one state or of rows of states."""
        return _tip(np.asarray(x, dtype=float)[..., :self.n_modes], self.probe.phi[:, 1])

    def index(self, name: str) -> int:
        """Position of parameter ``name`` in p."""
        try:
            return self.parameter_names.index(name)
        except ValueError:
            raise ValueError(f"unknown parameter {name!r}; the model has {self.parameter_names}")

    def require_structure(self, scene: Scene) -> None:
        """ValueError unless ``scene`` has this model's structure: every field equal but
        U* and the symbolic parameters (M*, f, K0, KL, ζ, k*, eps/H); a contact-free scene
        may use a model with contact (the guarded runs of :mod:`fsicas.timedomain.run`)."""
        if scene.contact and not self.scene.contact:
            raise ValueError("the scene has contact = true but the model was built without "
                             "contact: build the model from this scene (build_model(scene))")
        differ = [f for f in _COMPARED if getattr(scene, f) != getattr(self.scene, f)]
        if differ:
            raise ValueError(f"the model was built for another scene structure (fields "
                             f"{', '.join(differ)} differ): build the model from this scene "
                             "(build_model(scene))")

    def parameters(self, scene: Scene | None = None, pressure_drop: float = 0.0, **override) -> np.ndarray:
        """Numeric parameter vector from a scene (same structure) plus overrides by name."""
        s = scene or self.scene
        values = {name: getattr(s, name) for name in MODEL_PARAMETERS if name != "zeta"}
        values["pressure_drop"] = pressure_drop
        values.update({f"zeta{n + 1}": z for n, z in enumerate(s.zeta_modes)})
        for name, value in override.items():
            self.index(name)
            values[name] = value
        return np.array([values[name] for name in self.parameter_names], dtype=float)

    def scene_at(self, p) -> Scene:
        """The model's scene with the parameters of the vector ``p`` (all but U*: p holds
        the pressure drop instead): the analysed scene of a run or a cycle, for what needs
        its fields; ``self.scene`` holds those of the first scene of this structure only."""
        value = dict(zip(self.parameter_names, np.asarray(p, dtype=float).ravel()))
        changes = {name: value[name] for name in MODEL_PARAMETERS if name in value}
        changes["zeta"] = tuple(value[f"zeta{n + 1}"] for n in range(self.n_modes))
        return self.scene.replace(**changes)

    @property
    def mirror(self) -> np.ndarray:
        """The channel's mirror ``R``: ``R x = (-r, -q, Q2, Q1)`` (beam reflected, channels
        swapped), an orthogonal involution; a symmetric channel's model is equivariant
        under it, and its symmetric cycles keep ``u(t + T/2) = R u(t)``."""
        n = self.n_modes
        R = np.zeros((2 * n + 2, 2 * n + 2))
        R[range(2 * n), range(2 * n)] = -1.0
        R[2 * n, 2 * n + 1] = R[2 * n + 1, 2 * n] = 1.0
        return R

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
    evaluates faster than SX at every N measured (docs/performance.md). The equations
    are assembled in lifted form (:mod:`.equations`).
    """
    if symbolic not in ("SX", "MX"):
        raise ValueError(f"symbolic must be 'SX' or 'MX', got {symbolic!r}")
    names = parameter_names(scene)
    nodes, weights = quadrature_rule(scene)
    basis = modal_basis(scene, nodes)
    tip = modal_basis(scene, [0.0, 1.0])
    x_ref = reference_point(scene)
    probe = tip if x_ref == 1.0 else modal_basis(scene, [0.0, x_ref])
    impact = None
    if scene.contact:
        rule = contact_rule(scene)
        impact = modal_basis(scene, rule.x), rule
    eqs = LiftedEquations(scene, basis, tip, weights, getattr(ca, symbolic), names, impact)
    x, p, v = eqs.x, eqs.p, eqs.v
    force = eqs.force()
    lifted = {"jac_rhs": eqs.jacobian(), "jac_mass_action": eqs.mass_action_jacobian(),
              "mass": eqs.mass()}
    fun = lambda name, args, out, labels: ca.Function(name, args, [out], labels, [name])
    xp, xpv = ["x", "p"], ["x", "p", "v"]
    return Model(scene=scene, parameter_names=names,
                 mass=fun("M", [x, p], lifted["mass"].expr(x, p), xp),
                 rhs=fun("F", [x, p], force, xp),
                 jac_rhs=fun("dFdx", [x, p], lifted["jac_rhs"].expr(x, p), xp),
                 jac_rhs_p=fun("dFdp", [x, p], ca.jacobian(force, p), xp),
                 basis=basis, weights=weights, tip=tip, probe=probe,
                 mass_action=fun("Mv", [x, p, v], eqs.mass_action(), xpv),
                 jac_mass_action=fun("dMvdx", [x, p, v], lifted["jac_mass_action"].expr(x, p, v), xpv),
                 lifted=lifted, contact_basis=impact and impact[0],
                 impact_rule=impact and impact[1])
