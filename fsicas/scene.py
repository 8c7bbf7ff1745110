"""Scene: a frozen, validated description of one configuration (nondimensional).

Units and symbols are those of :mod:`fsicas.units`. Every field is checked in
``__post_init__``, so a Scene that exists is a valid one: bad input raises a
``ValueError`` naming the field before any model is built.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from .checks import finite_number, read_toml, require
from .profile import Profile
from .units import MAX_BEAM_RATIO, THIN_BEAM_RATIO, Scales, thick_beam_message

__all__ = ["Scene", "load_scene", "DIRECTIONS", "directed_ustar", "PARAMETER_FIELDS",
           "MODEL_PARAMETERS", "CONTACT_PARAMETERS", "STRUCTURE_FIELDS", "BEAM_ENDS",
           "check_ends"]


def default_quad_nodes(n_modes: int) -> int:
    """Nodes that integrate products of modes up to n_modes to round-off, with margin."""
    return 2 * n_modes + 20


#: Upper bounds of the sizes and of the values whose excess makes no physical sense here
#: (the paper works at N = 40 and M* in [0.01, 100]): beyond them a run would take hours
#: or run out of memory, or fail later with a misleading message.
MAX_MODES, MAX_QUAD_NODES, MAX_MSTAR, MAX_ABS_USTAR = 200, 2000, 1e6, 1e4
#: The largest modal damping ratio (100 times critical damping; beyond it the damping
#: force overflows rather than describing a structure).
MAX_ZETA = 100.0
#: The widest channels (H* = H/L; the bulk-flow model asks H* << 1, and physical input is
#: held to 0.5), the largest loss coefficients (the paper's f is 0.14) and the stiffest
#: contact law (the paper's k* is 1e6): beyond them the numbers overflow or the
#: eigen-solver fails instead of describing a channel.
MAX_HSTAR, MAX_LOSS, MAX_CONTACT_STIFFNESS = 10.0, 1e4, 1e12

#: Beam theories of :class:`Scene`; e/L beyond MAX_SLENDERNESS is outside 1D beam theory.
EULER_BERNOULLI, TIMOSHENKO = "euler-bernoulli", "timoshenko"
BEAM_THEORIES = (EULER_BERNOULLI, TIMOSHENKO)
MAX_SLENDERNESS = MAX_BEAM_RATIO
#: Beam ends of :class:`Scene`, root (x = 0) then x = 1 (docs/beam.md, "Beam ends").
CLAMPED_FREE = "clamped-free"
BEAM_ENDS = (CLAMPED_FREE, "clamped-clamped", "pinned-pinned", "clamped-pinned")


def check_ends(ends) -> str:
    """``ends`` if it is one of :data:`BEAM_ENDS`, else a ValueError naming them."""
    require(ends in BEAM_ENDS, f"ends must be one of {', '.join(BEAM_ENDS)}, got {ends!r}")
    return ends
#: Beam-theory fields that only the Timoshenko beam uses, with their defaults.
_TIMOSHENKO_FIELDS = ("beam", "slenderness", "poisson", "shear_coefficient")
_DEFAULTS = dict(beam=EULER_BERNOULLI, slenderness=None, poisson=0.3, shear_coefficient=None)

#: Directions of the flow (docs/model.md, "Reversed flow"): "forward" from the clamped
#: root (x = 0) to the tip, U* >= 0; "reverse" from the tip to the root, U* < 0
#: (expiration for the palate, the inverted cantilever).
FORWARD, REVERSE = "forward", "reverse"
DIRECTIONS = (FORWARD, REVERSE)


def directed_ustar(ustar: float, direction: str) -> float:
    """The signed U* of the speed ``ustar`` >= 0 in ``direction`` ("reverse" gives -ustar,
    -0.0 at rest). ValueError for an unknown direction, or a negative ``ustar`` given
    with a direction (the sign would be said twice)."""
    require(direction in DIRECTIONS, f"direction must be one of {', '.join(DIRECTIONS)}, "
            f"got {direction!r}")
    require(finite_number("ustar", ustar) >= 0, f"direction = {direction!r} is given with a "
            f"negative ustar ({ustar}): with a direction give the speed |U*| >= 0, or a signed "
            "ustar (negative: reversed flow) and no direction")
    return -float(ustar) if direction == REVERSE else float(ustar)


#: The Scene fields that are parameters: numeric inputs of a model, which serves every value
#: of them (U* through the pressure drop it sets). ``MODEL_PARAMETERS`` are the model's
#: symbolic inputs by name, in the order of its parameter vector (zeta one entry per
#: mode); ``CONTACT_PARAMETERS`` those of the contact law, inputs of a model with contact
#: only. Every other field but ``scales`` is structure (:data:`STRUCTURE_FIELDS`): a model
#: is built for its values (:func:`fsicas.model.assembly.build_model`).
CONTACT_PARAMETERS = ("contact_stiffness", "contact_eps")
MODEL_PARAMETERS = ("mstar", "friction", "k0", "kl") + CONTACT_PARAMETERS + ("zeta",)
PARAMETER_FIELDS = ("ustar",) + MODEL_PARAMETERS


def min_quad_nodes(n_modes: int) -> int:
    """Fewest nodes accepted: below 2N the mass matrix of mode N is not resolved."""
    return 2 * n_modes


@dataclass(frozen=True)
class Scene:
    """One configuration of the beam–channel system.

    mstar: mass ratio rho_f L / (rho_s e) > 0.     ustar: mean velocity (Q1+Q2)/H* at x = 0,
    signed (< 0: reversed flow, from the tip to the root; :attr:`direction`).
    hstar: total gap at the inlet (H1(0)+H2(0))/L.  friction: Fanning coefficient f >= 0.
    k0, kl: singular head losses of the openings at x = 0 and x = 1 (the inlet and outlet
    of forward flow; the outlet and inlet of reversed flow, docs/model.md).
    zeta: modal damping (scalar or per mode).
    modes: N.  quad_nodes: Gauss–Legendre nodes (default 2N+20, at least 2N).
    channel1/channel2: wall profiles (default: straight, hstar/2 each).
    thickness: beam thickness e(x)/e(0) (default uniform); a non-uniform beam uses the
    Hermite-cubic FE modes of :mod:`fsicas.beam_fe`, m = e, EI = e^3 relative to the root.
    contact: regularized wall impact on/off; contact_stiffness k* (per unit length,
    relative to the first-mode stiffness); contact_eps: eps/H with H = hstar/2.
    contact_smoothing: 0 (default) for the exact kink max(0, v) of the impact law; > 0
    replaces it by the C-infinity softplus of width contact_smoothing * eps
    (docs/simulate.md), for Newton/collocation on impacting cycles.
    beam: "euler-bernoulli" (default) or "timoshenko" (shear and rotary inertia,
    :mod:`fsicas.model.beam_timoshenko`, docs/beam.md), which needs slenderness = e/L in
    (0, 0.5] and takes poisson (nu in [0, 0.5), default 0.3) and shear_coefficient
    (kappa in (0, 1], None: Cowper's 10(1 + nu)/(12 + 11 nu)); these three apply to
    the Timoshenko beam only and ``to_dict`` leaves them out of Euler–Bernoulli scenes;
    with ``thickness`` the Timoshenko modes are the locking-free FE modes of
    :mod:`fsicas.model.beam_timoshenko_fe` (slenderness at the root).
    ends: the supports at the root x = 0 and at x = 1, one of :data:`BEAM_ENDS`:
    "clamped-free" (default, the cantilever), "clamped-clamped", "pinned-pinned",
    "clamped-pinned" (docs/beam.md); ``to_dict`` leaves out the default.
    """

    mstar: float = 1.0
    ustar: float = 5.0
    hstar: float = 0.1
    friction: float = 0.14
    k0: float = 0.0
    kl: float = 1.0
    zeta: float | tuple[float, ...] = 0.0
    modes: int = 10
    quad_nodes: int | None = None
    channel1: Profile | None = None
    channel2: Profile | None = None
    thickness: Profile | None = None
    contact: bool = False
    contact_stiffness: float = 1e6
    contact_eps: float = 1e-3
    contact_smoothing: float = 0.0
    beam: str = "euler-bernoulli"
    slenderness: float | None = None
    poisson: float = 0.3
    shear_coefficient: float | None = None
    ends: str = CLAMPED_FREE
    scales: Scales | None = field(default=None, compare=False)

    def __post_init__(self):
        _validate(self)
        for name in _REALS:       # NumPy scalars and ints stored as plain floats
            object.__setattr__(self, name, float(getattr(self, name)))
        object.__setattr__(self, "modes", int(self.modes))
        object.__setattr__(self, "contact", bool(self.contact))
        if self.quad_nodes is not None:
            object.__setattr__(self, "quad_nodes", int(self.quad_nodes))
        object.__setattr__(self, "zeta", float(self.zeta) if _is_scalar(self.zeta)
                           else tuple(float(z) for z in self.zeta))
        object.__setattr__(self, "poisson", float(self.poisson))
        for name in ("slenderness", "shear_coefficient"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, float(getattr(self, name)))

    # -- derived -------------------------------------------------------------------
    @property
    def n_quad(self) -> int:
        """Quadrature nodes in use: ``quad_nodes`` or the default 2N + 20."""
        return self.quad_nodes or default_quad_nodes(self.modes)

    @property
    def walls(self) -> tuple[Profile, Profile]:
        """The two wall profiles, defaults filled in."""
        half = Profile.constant(self.hstar / 2)
        return (self.channel1 or half, self.channel2 or half)

    @property
    def direction(self) -> str:
        """"forward" (U* >= 0) or "reverse" (U* < 0, and U* = -0.0: at rest, reversed)."""
        return REVERSE if math.copysign(1.0, self.ustar) < 0 else FORWARD

    @property
    def flow_sign(self) -> float:
        """+1 for forward flow, -1 for reverse (:attr:`direction`)."""
        return -1.0 if self.direction == REVERSE else 1.0

    @property
    def zeta_modes(self) -> np.ndarray:
        """Damping ratio of each mode, shape (N,)."""
        return np.broadcast_to(np.asarray(self.zeta, dtype=float), (self.modes,)).copy()

    @property
    def contact_gap(self) -> float:
        """Regularization distance eps = (eps/H) * H*/2, in units of L."""
        return self.contact_eps * self.hstar / 2

    @property
    def straight(self) -> bool:
        return all(p.is_constant for p in self.walls)

    @property
    def symmetric(self) -> bool:
        w1, w2 = self.walls
        return w1 == w2

    def replace(self, **changes) -> "Scene":
        """A new Scene with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict:
        d = {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name != "scales"}
        for name in ("channel1", "channel2", "thickness"):
            if d[name] is not None:
                d[name] = dataclasses.asdict(d[name])
        if isinstance(d["zeta"], tuple):
            d["zeta"] = list(d["zeta"])
        if self.beam == EULER_BERNOULLI:       # the dict of every scene before Timoshenko
            for name in _TIMOSHENKO_FIELDS:
                del d[name]
        if self.ends == CLAMPED_FREE:          # the dict of every cantilever
            del d["ends"]
        return d

    # -- construction --------------------------------------------------------------
    @classmethod
    def from_dict(cls, d: dict) -> "Scene":
        """Build from a mapping (e.g. a TOML document); unknown keys are an error.
        ``direction`` ("forward" or "reverse") sets the sign of the speed ``ustar``
        (:func:`directed_ustar`)."""
        names = {f.name for f in dataclasses.fields(cls)} - {"scales"}
        unknown = set(d) - names - {"direction"}
        if unknown:
            raise ValueError(f"unknown scene keys {sorted(unknown)}; allowed: "
                             f"{sorted(names | {'direction'})}")
        kw = dict(d)
        if "direction" in kw:
            kw["ustar"] = directed_ustar(kw.get("ustar", cls.ustar), kw.pop("direction"))
        for name in ("channel1", "channel2", "thickness"):
            if isinstance(kw.get(name), dict):
                kw[name] = Profile.from_dict(kw[name], name)
        return cls(**kw)

    @classmethod
    def from_physical(cls, *, rho_s, E, nu, e, L, rho_f, U0, H1, H2=None, b=1.0,
                      **nondimensional) -> "Scene":
        """Scene from SI values (kg/m3, Pa, -, m, m, kg/m3, m/s, m, m, m).

        ``D = E e^3 / (12 (1 - nu^2))``, ``T = L^2 sqrt(rho_s e / D)``,
        ``M* = rho_f L / (rho_s e)``, ``U* = U0 T / L``, ``H* = (H1 + H2) / L``.
        H1, H2 are the wall distances at the inlet; other fields pass through. A beam with
        e/L >= 0.1 (not thin) gets the Timoshenko modes unless ``beam`` is given; with
        them slenderness = e/L and poisson = nu (derived: do not pass them). U0 carries
        the flow's sign (< 0: from the tip to the root), or ``direction`` sets it.
        """
        H2 = H1 if H2 is None else H2
        scales = Scales.from_physical(rho_s=rho_s, E=E, nu=nu, e=e, L=L, b=b, rho_f=rho_f,
                                      H1=H1, H2=H2, U0=U0)
        for key in ("mstar", "ustar", "hstar", "channel1", "channel2", "slenderness", "poisson"):
            if key in nondimensional:
                raise ValueError(f"{key} is derived from the physical values; do not pass it")
        nondimensional.update(_physical_beam(nondimensional.pop("beam", None), nu, e, L))
        ustar = U0 * scales.time / L
        if nondimensional.get("direction") is not None:
            ustar = directed_ustar(ustar, nondimensional["direction"])
        nondimensional.pop("direction", None)
        return cls(mstar=rho_f * L / (rho_s * e), ustar=ustar,
                   hstar=(H1 + H2) / L, channel1=Profile.constant(H1 / L),
                   channel2=Profile.constant(H2 / L), scales=scales, **nondimensional)


#: The Scene fields that shape a model (module constants above): all but the parameters.
STRUCTURE_FIELDS = tuple(f.name for f in dataclasses.fields(Scene)
                         if f.name not in PARAMETER_FIELDS and f.name != "scales")


def _physical_beam(beam, nu, e, L) -> dict:
    """The beam fields of a physical input: Timoshenko when asked for or not thin."""
    if beam is None:
        beam = TIMOSHENKO if e >= THIN_BEAM_RATIO * L else EULER_BERNOULLI
    if beam == EULER_BERNOULLI:
        require(e < THIN_BEAM_RATIO * L, thick_beam_message(e, L))
        return {}
    return dict(beam=beam, slenderness=e / L, poisson=nu)


def load_scene(path, **overrides) -> Scene:
    """Read a Scene from a TOML file; keyword overrides win over the file. ValueError
    naming the file when it is missing, a folder, unreadable or not valid TOML."""
    data = read_toml(path, "scene file")
    data.update({k: v for k, v in overrides.items() if v is not None})
    return Scene.from_dict(data)


# -- validation ------------------------------------------------------------------------
#: The real-valued scalar fields of a Scene.
_REALS = ("mstar", "ustar", "hstar", "friction", "k0", "kl", "contact_stiffness", "contact_eps",
          "contact_smoothing")


def _is_scalar(value) -> bool:
    return np.ndim(value) == 0 and not isinstance(value, (list, tuple))


def _validate_zeta(s: Scene) -> None:
    """A finite number >= 0, or one per mode."""
    require(_is_scalar(s.zeta) or isinstance(s.zeta, (list, tuple, np.ndarray)),
            f"zeta must be a number or a list of numbers, got {s.zeta!r}")
    for z in [s.zeta] if _is_scalar(s.zeta) else list(s.zeta):
        finite_number("zeta", z)
    zeta = np.atleast_1d(np.asarray(s.zeta, dtype=float))
    require(zeta.size in (1, s.modes), f"zeta must be a scalar or have one value per mode "
             f"({s.modes}), got {zeta.size} values")
    require(bool(np.all((zeta >= 0) & (zeta <= MAX_ZETA))),
            f"zeta must lie in [0, {MAX_ZETA:g}] (1 is critical damping), got {s.zeta}")


def _validate_channel(s: Scene) -> None:
    """The channels' width H* and the loss coefficients f, K0, KL."""
    require(0 < finite_number("hstar", s.hstar) <= MAX_HSTAR,
            f"hstar must lie in (0, {MAX_HSTAR:g}], got {s.hstar}")
    for name in ("friction", "k0", "kl"):
        require(0 <= finite_number(name, getattr(s, name)) <= MAX_LOSS,
                f"{name} must lie in [0, {MAX_LOSS:g}], got {getattr(s, name)}")


def _validate_beam(s: Scene) -> None:
    """Beam theory, ends and parameters (docs/beam.md)."""
    check_ends(s.ends)
    require(s.beam in BEAM_THEORIES, f"beam must be one of {', '.join(BEAM_THEORIES)}, "
            f"got {s.beam!r}")
    require(0 <= finite_number("poisson", s.poisson) < 0.5,
            f"poisson (nu) must lie in [0, 0.5), got {s.poisson}")
    if s.shear_coefficient is not None:
        require(0 < finite_number("shear_coefficient", s.shear_coefficient) <= 1,
                f"shear_coefficient (kappa) must lie in (0, 1], got {s.shear_coefficient}")
    if s.slenderness is not None:
        require(0 < finite_number("slenderness", s.slenderness) <= MAX_SLENDERNESS,
                f"slenderness (e/L) must lie in (0, {MAX_SLENDERNESS:g}] (beyond it 1D beam "
                f"theory does not apply), got {s.slenderness}")
    if s.beam == EULER_BERNOULLI:
        given = [n for n in _TIMOSHENKO_FIELDS if getattr(s, n) != _DEFAULTS[n]]
        require(not given, f"{', '.join(given)}: only beam = 'timoshenko' uses it; give "
                "beam = 'timoshenko' (--beam timoshenko) or leave it out")
    else:
        require(s.slenderness is not None, "slenderness (e/L) is required with beam = "
                "'timoshenko' (--slenderness)")


def _validate(s: Scene) -> None:
    require(isinstance(s.modes, (int, np.integer)) and not isinstance(s.modes, bool)
             and 1 <= s.modes <= MAX_MODES,
             f"modes must be an integer in [1, {MAX_MODES}], got {s.modes!r}")
    require(0 < finite_number("mstar", s.mstar) <= MAX_MSTAR,
            f"mstar must lie in (0, {MAX_MSTAR:g}], got {s.mstar}")
    require(abs(finite_number("ustar", s.ustar)) <= MAX_ABS_USTAR,
            f"ustar must lie in [-{MAX_ABS_USTAR:g}, {MAX_ABS_USTAR:g}], got {s.ustar}")
    _validate_channel(s)
    _validate_zeta(s)
    if s.quad_nodes is not None:
        require(isinstance(s.quad_nodes, (int, np.integer)) and not isinstance(s.quad_nodes, bool)
                and min_quad_nodes(s.modes) <= s.quad_nodes <= MAX_QUAD_NODES,
                f"quad_nodes must be an integer in [2*modes = {min_quad_nodes(s.modes)}, "
                f"{MAX_QUAD_NODES}] (at least 2 per mode to resolve mode {s.modes}), "
                f"got {s.quad_nodes!r}")
    for name in ("channel1", "channel2", "thickness"):
        profile = getattr(s, name)
        require(profile is None or isinstance(profile, Profile), f"{name} must be a Profile or None")
        if profile is not None:
            profile.validate(name)
    if s.thickness is not None:
        require(abs(float(s.thickness(0.0)) - 1.0) <= 1e-12,
                 f"thickness is relative to the root: thickness(0) must be 1, got {float(s.thickness(0.0))}")
    if s.channel1 is not None or s.channel2 is not None:
        w1, w2 = s.walls
        inlet = float(w1(0.0) + w2(0.0))
        require(abs(inlet - s.hstar) <= 1e-12 * s.hstar,
                 f"hstar ({s.hstar}) must equal H1(0) + H2(0) = {inlet} of the given channels")
    require(isinstance(s.contact, (bool, np.bool_)), f"contact must be true or false, got {s.contact!r}")
    require(0 < finite_number("contact_stiffness", s.contact_stiffness) <= MAX_CONTACT_STIFFNESS,
             f"contact_stiffness must lie in (0, {MAX_CONTACT_STIFFNESS:g}], got {s.contact_stiffness}")
    require(0 < finite_number("contact_eps", s.contact_eps) < 1,
             f"contact_eps (eps/H) must lie in (0, 1), got {s.contact_eps}")
    require(0 <= finite_number("contact_smoothing", s.contact_smoothing) <= 1,
             f"contact_smoothing (width / eps) must lie in [0, 1], got {s.contact_smoothing}")
    _validate_beam(s)
