"""Physical input: a ``[physical]`` table of SI values (or strings with units), named
presets shipped with the package, an airflow given as a velocity or a volume flow, and
the Scene they describe (through :meth:`fsicas.Scene.from_physical`).

A TOML file (or a preset, ``fsicas/presets/NAME.toml``)::

    description = "what this is, and where the numbers come from"
    preset = "soft_palate"        # optional: start from a preset, override its values
    modes = 10                    # optional: nondimensional Scene fields
    [physical]
    E = "3 kPa"                   # a number is SI (Pa here), a string carries its unit
    nu = 0.45
    rho_s = "1040 kg/m^3"
    e = "2.5 mm"
    L = "30 mm"
    b = "35 mm"
    gap = "2 mm"                  # each channel; or H1 and H2 (channel 1 above the beam)
    rho_f = "1.2 kg/m^3"
    friction = 0.14               # Fanning f; or viscosity = "1.8e-5 Pa*s"
    zeta = 0.0
    flow = "30 L/min"             # the default airflow (velocity or volume flow)

The airflow ``Q`` (both channels) and the mean inlet velocity ``U0`` are tied by the
inlet cross-section: ``Q = U0 b (H1 + H2)``. Units are read by Pint.
"""
from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources

from .checks import read_toml
from .scene import MAX_LOSS, Scene
from .units import friction_from_reynolds

try:  # Python >= 3.11
    import tomllib
except ModuleNotFoundError:  # pragma: no cover
    import tomli as tomllib

__all__ = ["Flow", "Physical", "PhysicalValidityWarning", "load_physical", "parse_flow",
           "parse_quantity", "preset_names", "HSTAR_WARN", "HSTAR_MAX"]

#: H* above which the bulk-flow (long-wave) model is used beyond the paper's range
#: (H* = 1/20 to 1/5): a warning. Above HSTAR_MAX the channels are not thin against the
#: beam and the model is refused.
HSTAR_WARN, HSTAR_MAX = 0.2, 0.5

#: Keys of the ``[physical]`` table -> the unit their numbers are in (``""``: none).
KEYS = {"E": "Pa", "nu": "", "rho_s": "kg/m^3", "e": "m", "L": "m", "b": "m", "H1": "m",
        "H2": "m", "gap": "m", "rho_f": "kg/m^3", "friction": "", "viscosity": "Pa*s",
        "zeta": "", "flow": None}
#: What each key is (for messages and docs).
MEANING = {"E": "Young's modulus", "nu": "Poisson ratio", "rho_s": "beam density",
           "e": "thickness", "L": "length", "b": "width", "H1": "channel 1 height (above)",
           "H2": "channel 2 height (below)", "gap": "height of each channel",
           "rho_f": "fluid density", "friction": "Fanning friction coefficient",
           "viscosity": "dynamic viscosity of the fluid", "zeta": "modal damping ratio",
           "flow": "default airflow"}
REQUIRED = ("E", "nu", "rho_s", "e", "L", "b", "rho_f")
#: Nondimensional Scene fields a physical file may set at its top level (the others are
#: derived from the physical values).
SCENE_FIELDS = ("friction", "k0", "kl", "zeta", "modes", "quad_nodes", "contact",
                "contact_stiffness", "contact_eps", "contact_smoothing", "ends")


class PhysicalValidityWarning(UserWarning):
    """A physical input inside the model's limits but outside the range it was checked on."""


@lru_cache(maxsize=1)
def _registry():
    import pint    # imported on first use: 0.3 s, only for physical input
    return pint.UnitRegistry()


#: A quantity as written: one number (``3``, ``-2.5``, ``1e-3``), then a unit whose only
#: digits are small powers (``m^3/s``, ``kg/m**3``). No arithmetic: pint evaluates
#: expressions, and ``10**10**8`` would run for hours before anything is said.
_QUANTITY = re.compile(r"^\s*(?P<number>[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)"
                       r"\s*(?P<unit>(?:[A-Za-zµμΩ°%_ ()*/.]|(?:\^|\*\*)-?\d{1,2}(?!\d))*)\s*$")
_MAX_TEXT = 100


def _quantity(text: str, what: str, hint: str = "a number with a unit, e.g. 3 kPa"):
    """Pint quantity of ``text`` (a number, then its unit); ValueError naming ``what``
    if it does not parse or is not a finite value."""
    match = _QUANTITY.match(text) if len(text) <= _MAX_TEXT else None
    if match is None:
        raise ValueError(f"{what}: cannot read {text!r}: give {hint} (one number, then a "
                         "unit: 3e3 Pa, not 3 * 10**3 Pa)")
    number = float(match["number"])
    if not math.isfinite(number):
        raise ValueError(f"{what}: {text!r} is not a finite value")
    try:
        q = number * _registry().Unit(match["unit"].strip() or "dimensionless")
    except Exception as err:    # pint raises many kinds (tokenize, syntax, undefined unit)
        reason = f" ({err})" if str(err) else ""
        raise ValueError(f"{what}: cannot read {text!r}{reason}; give {hint}") from None
    return q


def parse_quantity(value, unit: str, what: str) -> float:
    """``value`` in ``unit`` (SI): a number is taken as already in it, a string such as
    ``"3 kPa"`` is converted; ValueError naming ``what`` for a wrong kind of unit."""
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise ValueError(f"{what} must be a number (SI) or a string with a unit, got {value!r}")
    if not isinstance(value, str):
        number = float(value)
    else:
        q = _quantity(value, what)
        try:
            number = float(q.to(unit or "dimensionless").magnitude)
        except Exception:   # pint's DimensionalityError
            raise ValueError(f"{what}: {value!r} is not in units of {unit or 'a pure number'} "
                             f"(it is {q.dimensionality})") from None
    if not math.isfinite(number):
        raise ValueError(f"{what}: {value!r} is not a finite value in {unit or 'a pure number'}")
    return number


@dataclass(frozen=True)
class Flow:
    """An airflow: a mean inlet velocity (m/s) or a volume flow through both channels
    (m^3/s), as given in ``text``."""

    text: str
    kind: str       # "velocity" or "volume"
    value: float    # SI: m/s or m^3/s

    @classmethod
    def of(cls, kind: str, value: float) -> "Flow":
        """The flow of ``value`` (m/s or m^3/s), its text in m/s or L/min."""
        text = f"{value:.4g} m/s" if kind == "velocity" else f"{value * 6e4:.4g} L/min"
        return cls(text, kind, value)

    def velocity(self, b: float, gap: float) -> float:
        """Mean inlet velocity U0 = Q / (b (H1 + H2)) in m/s."""
        return self.value if self.kind == "velocity" else self.value / (b * gap)


def parse_flow(text, option: str = "--flow") -> Flow:
    """``20L/min``, ``3.3e-4m^3/s`` (volume flow) or ``1.2m/s`` (velocity), != 0 and
    signed (< 0: from the tip to the root, expiration); ValueError naming ``option``
    otherwise."""
    hint = "a velocity (e.g. 1.2m/s) or a volume flow (e.g. 20L/min, 3.3e-4m^3/s)"
    if not isinstance(text, str) or not text.strip():
        raise ValueError(f"{option} must be {hint}, got {text!r}")
    q = _quantity(text, option, hint)
    for kind, unit in (("velocity", "m/s"), ("volume", "m^3/s")):
        if q.check(unit):
            value = float(q.to(unit).magnitude)
            if not value != 0:
                raise ValueError(f"{option} must be nonzero (negative: reversed flow), got "
                                 f"{text!r}")
            return Flow(text.strip(), kind, value)
    unit = "no unit" if q.dimensionless else f"units of {q.dimensionality}"
    raise ValueError(f"{option} {text!r} has {unit}: give {hint}")


# -- presets and files -------------------------------------------------------------------
def _preset_folder():
    return resources.files("fsicas") / "presets"


def preset_names() -> list[str]:
    """Names of the presets shipped with the package (``fsicas/presets/NAME.toml``)."""
    return sorted(p.name[:-5] for p in _preset_folder().iterdir() if p.name.endswith(".toml"))


def _read_toml(source: str) -> tuple[dict, str]:
    """The TOML document of a preset name or a file path, and its label."""
    is_file = source.endswith(".toml") or "/" in source or "\\" in source
    if not is_file:
        if source not in preset_names():
            raise ValueError(f"--physical {source!r}: no such preset (presets: "
                             f"{', '.join(preset_names())}; or give a FILE.toml)")
        return tomllib.loads((_preset_folder() / f"{source}.toml").read_text("utf-8")), source
    return read_toml(source, "physical file"), source


def load_physical(source: str) -> "Physical":
    """The physical input of a preset name (``soft_palate``) or a TOML file (``x.toml``);
    a file's ``preset = NAME`` starts from that preset and overrides its values."""
    doc, label = _read_toml(source)
    base = doc.pop("preset", None)
    table = doc.pop("physical", None)
    if not isinstance(table, dict):
        raise ValueError(f"{label}: needs a [physical] table (keys: {', '.join(KEYS)})")
    description = doc.pop("description", "")
    if base is not None:
        if not isinstance(base, str) or "/" in base or base.endswith(".toml"):
            raise ValueError(f"{label}: preset must be the name of a preset, got {base!r}")
        parent = load_physical(base)
        table = {**parent.raw, **table}
        doc = {**parent.scene_fields, **doc}
        description = description or parent.description
    return Physical.from_table(table, label, str(description), doc)


# -- the physical configuration ----------------------------------------------------------
#: Keys whose values must be > 0, and those that must be >= 0.
_POSITIVE = ("E", "rho_s", "e", "L", "b", "H1", "H2", "gap", "rho_f", "viscosity")
_NON_NEGATIVE = ("friction", "zeta")


def _check_signs(values: dict, label: str) -> None:
    """ValueError naming the first key of ``values`` of the wrong sign."""
    for key, value in values.items():
        if (key in _POSITIVE and not value > 0) or (key in _NON_NEGATIVE and not value >= 0):
            bound = "> 0" if key in _POSITIVE else ">= 0"
            raise ValueError(f"{label}: {key} ({MEANING[key]}) must be {bound}, got {value:g} "
                             f"{KEYS[key]}".rstrip())


def _heights(values: dict, label: str) -> tuple[float, float]:
    if "gap" in values and ("H1" in values or "H2" in values):
        raise ValueError(f"{label}: give either gap (each channel) or H1 and H2, not both")
    if "gap" in values:
        return values["gap"], values["gap"]
    if "H1" not in values:
        raise ValueError(f"{label}: the channel heights are missing: give gap = ... (each "
                         "channel) or H1 = ... and H2 = ...")
    return values["H1"], values.get("H2", values["H1"])


@dataclass(frozen=True)
class Physical:
    """One physical configuration in SI units; :meth:`scene` gives its Scene."""

    source: str
    description: str
    values: dict            # SI numbers of the [physical] table (without flow)
    H1: float
    H2: float
    flow: Flow | None       # the default airflow
    scene_fields: dict = field(default_factory=dict)   # nondimensional Scene fields
    raw: dict = field(default_factory=dict, repr=False)  # the table as written

    @classmethod
    def from_table(cls, table: dict, label: str, description: str = "",
                   scene_fields: dict | None = None) -> "Physical":
        extra = sorted(set(scene_fields or {}) - set(SCENE_FIELDS))
        if extra:
            raise ValueError(f"{label}: unknown top-level keys {extra}; allowed: description, "
                             f"preset, {', '.join(SCENE_FIELDS)} and the [physical] table")
        unknown = sorted(set(table) - set(KEYS))
        if unknown:
            raise ValueError(f"{label}: unknown [physical] keys {unknown}; allowed: "
                             + ", ".join(f"{k} ({MEANING[k]})" for k in KEYS))
        values = {k: parse_quantity(v, KEYS[k], f"{label}: {k} ({MEANING[k]})")
                  for k, v in table.items() if k != "flow"}
        missing = [k for k in REQUIRED if k not in values]
        if missing:
            raise ValueError(f"{label}: [physical] lacks {', '.join(missing)} "
                             f"({', '.join(MEANING[k] for k in missing)})")
        if "friction" in values and "viscosity" in values:
            raise ValueError(f"{label}: give friction or viscosity, not both")
        _check_signs(values, label)
        H1, H2 = _heights(values, label)
        flow = None if "flow" not in table else parse_flow(table["flow"], f"{label}: flow")
        return cls(label, description, values, H1, H2, flow, dict(scene_fields or {}), dict(table))

    def to_json(self) -> dict:
        """The input in SI units, each key with its unit (``_pa``, ``_kg_m3``, ``_m``)."""
        suffix = {"Pa": "_pa", "kg/m^3": "_kg_m3", "m": "_m", "Pa*s": "_pa_s", "": ""}
        out = {k + suffix[KEYS[k]]: v for k, v in self.values.items() if k != "gap"}
        out.update(H1_m=self.H1, H2_m=self.H2,
                   default_flow=None if self.flow is None else self.flow.text)
        return out

    @property
    def gap(self) -> float:
        """H1 + H2 at the inlet, m."""
        return self.H1 + self.H2

    def velocity(self, flow: Flow | None) -> float:
        """Mean inlet velocity in m/s of ``flow`` (0 for None)."""
        return 0.0 if flow is None else flow.velocity(self.values["b"], self.gap)

    def friction(self, flow: Flow | None) -> tuple[float, float | None]:
        """Fanning f and the Reynolds number it was taken at (None when f is given):
        ``Re = rho_f U0 h / mu`` with h = (H1 + H2)/2, f from Eq. (15)."""
        v = self.values
        if "viscosity" not in v:
            return v.get("friction", Scene.friction), None
        if flow is None:
            raise ValueError(f"{self.source}: the friction is taken from the viscosity at the "
                             "airflow: give --flow (e.g. --flow 20L/min) or flow = ... in [physical]")
        re = v["rho_f"] * abs(self.velocity(flow)) * (self.gap / 2) / v["viscosity"]
        if not re > 0:
            raise ValueError(f"{self.source}: the friction is taken from the viscosity at the "
                             "airflow, and the airflow is zero: give a flow > 0")
        f = friction_from_reynolds(re)
        if f > MAX_LOSS:
            raise ValueError(f"{self.source}: viscosity = {v['viscosity']:g} Pa*s gives the "
                             f"Reynolds number {re:.3g} at this airflow, and the friction "
                             f"f = 12/Re = {f:.3g} is beyond {MAX_LOSS:g}: give the fluid's "
                             "viscosity (air: 1.8e-5 Pa*s)")
        return f, re

    def scene(self, flow: Flow | None = None, **overrides) -> Scene:
        """The Scene at ``flow`` (default: none, U* = 0); ``overrides`` are nondimensional
        Scene fields (modes, zeta, friction, ...) that win over the file's."""
        v = self.values
        fields = {**self.scene_fields, **{k: x for k, x in overrides.items() if x is not None}}
        if "zeta" in v and "zeta" not in fields:
            fields["zeta"] = v["zeta"]
        if "friction" not in fields:
            fields["friction"] = self.friction(flow)[0]
        self.check_validity()
        try:
            return Scene.from_physical(rho_s=v["rho_s"], E=v["E"], nu=v["nu"], e=v["e"], L=v["L"],
                                       rho_f=v["rho_f"], U0=self.velocity(flow), H1=self.H1,
                                       H2=self.H2, b=v["b"], **fields)
        except (ValueError, TypeError) as err:
            raise ValueError(f"{self.source}: {_explain(err, flow)}") from None

    def check_validity(self) -> None:
        """Refuse (ValueError) or warn about inputs beyond the model's validity, with what
        to change: channels not thin against the beam (H* = (H1 + H2)/L)."""
        L, hstar = self.values["L"], self.gap / self.values["L"]
        if hstar > HSTAR_MAX:
            raise ValueError(
                f"{self.source}: H* = (H1 + H2)/L = {hstar:.3g} > {HSTAR_MAX:g}: the channels are "
                "not thin against the beam, and the 1D bulk-flow (long-wave) model does not "
                f"apply; narrow the channels to H1 + H2 < {HSTAR_MAX * L * 1e3:.3g} mm or "
                "give a longer L")
        if hstar > HSTAR_WARN:
            warnings.warn(
                f"{self.source}: H* = (H1 + H2)/L = {hstar:.3g} is beyond the range the model "
                f"was checked on (H* <= {HSTAR_WARN:g}, paper: 1/20 to 1/5); the bulk-flow "
                "(long-wave) approximation loses accuracy as H* grows: read the results as "
                "estimates", PhysicalValidityWarning, stacklevel=3)


def _explain(err: Exception, flow: Flow | None) -> str:
    """A Scene error on a derived value, said in the terms of the physical input."""
    text = str(err)
    if text.startswith("ustar") and flow is not None:
        return f"the airflow {flow.text} gives a U* out of range ({text}): give a smaller --flow"
    if text.startswith("direction") and flow is not None:
        return (f"the airflow {flow.text} is negative and a direction is given: give the "
                "flow's magnitude with the direction, or a signed flow alone")
    if text.startswith("mstar"):
        return f"the mass ratio M* = rho_f L / (rho_s e) derived from the input: {text}"
    return text
