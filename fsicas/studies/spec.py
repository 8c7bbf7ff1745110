"""A study: one analysis over a grid or a random sample of parameters, read from TOML.

::

    description = "onset airflow over published palate stiffness and thickness"
    analysis = "onset"            # onset | outcome | sound
    physical = "soft_palate"      # a preset or FILE.toml: the parameters are its [physical]
                                  # keys (SI numbers or strings with units); without it they
                                  # are nondimensional Scene fields
    [scene]                       # fixed nondimensional Scene fields (modes, zeta, ends...)
    modes = 8
    [settings]                    # the analysis' settings (below)
    ustar_max = 40.0
    [grid]                        # every combination: a list, or {start, stop, num, log}
    E = ["1 kPa", "3 kPa", "5 kPa"]
    e = {start = "2 mm", stop = "3 mm", num = 3}
    # or a random sample (uncertain tissue properties), instead of [grid]:
    [sample]
    size = 200
    seed = 1
    E = {distribution = "lognormal", median = "3 kPa", sigma = 0.5}
    e = {distribution = "uniform", low = "2 mm", high = "3 mm"}

Distributions: ``uniform`` (low, high), ``loguniform`` (low, high), ``normal`` (mean,
std), ``lognormal`` (median, sigma of ln). The points are drawn once, from NumPy's
``default_rng(seed)``, in the order of the keys: a study always has the same points.

Analyses and their settings: ``onset`` (the first Hopf point, i.e. the boundary point at
the point's M*: ``ustar_max``; with a physical input also in L/min, Hz, Pa), ``outcome``
(a time integration classified as decay, limit cycle or contact, with the cycle's
amplitude: ``t_end``, ``rtol``, ``atol``, ``dt_out``; the point needs ``ustar``, or a
``flow`` with a physical input) and ``sound`` (the outcome and the radiated sound's level
and pitch at ``distance`` m; physical input only).
"""
from __future__ import annotations

import hashlib
import itertools
import json
import math
from dataclasses import dataclass, field

import numpy as np

from ..checks import check_points, finite_number, read_toml
from ..physical import KEYS, load_physical, parse_flow, parse_quantity
from ..scene import MAX_ABS_USTAR, Scene
from ..timedomain.integrators import Settings
from ..timedomain.limits import check_size
from ..timedomain.breathing import PressureSchedule

__all__ = ["Study", "load_study", "ANALYSES", "SETTINGS", "DISTRIBUTIONS"]

#: The analyses a study can run, and the settings each takes (with defaults).
SETTINGS = {"onset": {"ustar_max": 40.0},
            "outcome": {"t_end": 30.0, "rtol": 1e-7, "atol": 1e-9, "dt_out": 2e-3},
            "sound": {"t_end": 30.0, "rtol": 1e-7, "atol": 1e-9, "dt_out": 2e-4,
                      "distance": 0.3}}
ANALYSES = tuple(SETTINGS)
DISTRIBUTIONS = {"uniform": ("low", "high"), "loguniform": ("low", "high"),
                 "normal": ("mean", "std"), "lognormal": ("median", "sigma")}
_SCENE_FIELDS = ("mstar", "ustar", "hstar", "friction", "k0", "kl", "zeta", "modes",
                 "quad_nodes", "contact", "contact_stiffness", "contact_eps")
#: The fixed [scene] keys of a study: its parameters' fields, the beam's ends and the
#: flow's direction.
_FIXED_FIELDS = _SCENE_FIELDS + ("ends", "direction")


@dataclass(frozen=True)
class Study:
    """A parsed study: its ``points`` (one dict of parameter values each, SI for a
    physical study) and what each is computed with. ``header`` is everything the results
    depend on (the resume key of :func:`fsicas.studies.run_study`)."""

    source: str
    description: str
    analysis: str
    physical: str | None
    scene: dict
    settings: dict
    points: tuple = field(repr=False)

    @property
    def header(self) -> dict:
        digest = hashlib.sha256(json.dumps(self.points, sort_keys=True).encode()).hexdigest()
        return {"format": "fsicas-study-1", "analysis": self.analysis,
                "physical": self.physical, "scene": self.scene, "settings": self.settings,
                "points": len(self.points), "points_sha256": digest}

    def to_json(self) -> dict:
        return {"source": self.source, "description": self.description, **self.header}


def load_study(path) -> Study:
    """The study of a TOML file; ValueError naming the key for anything wrong."""
    doc = read_toml(path, "study file")
    label = str(path)
    known = {"description", "analysis", "physical", "scene", "settings", "grid", "sample"}
    unknown = sorted(set(doc) - known)
    if unknown:
        raise ValueError(f"{label}: unknown keys {unknown}; allowed: {', '.join(sorted(known))}")
    analysis = doc.get("analysis")
    if analysis not in ANALYSES:
        raise ValueError(f"{label}: analysis must be one of {', '.join(ANALYSES)}, got {analysis!r}")
    physical = doc.get("physical")
    for key in ("physical", "description"):
        if not isinstance(doc.get(key, ""), str):
            raise ValueError(f"{label}: {key} must be a string, got {doc[key]!r}")
    if physical is not None:
        load_physical(physical)                      # refused here if it does not exist
    scene = _table(doc, "scene", label)
    bad = sorted(set(scene) - set(_FIXED_FIELDS))
    if bad:
        raise ValueError(f"{label}: [scene] keys {bad} are not Scene fields of a study; "
                         f"allowed: {', '.join(_FIXED_FIELDS)}")
    settings = {**SETTINGS[analysis], **_table(doc, "settings", label)}
    bad = sorted(set(settings) - set(SETTINGS[analysis]))
    if bad:
        raise ValueError(f"{label}: [settings] {bad} are not settings of {analysis!r}; allowed: "
                         f"{', '.join(SETTINGS[analysis])}")
    _check_values(analysis, physical, scene, settings, label)
    if ("grid" in doc) == ("sample" in doc):
        raise ValueError(f"{label}: give either a [grid] or a [sample] table")
    unit = _units(physical)
    points = _grid(doc["grid"], unit, label) if "grid" in doc else \
        _sample(doc["sample"], unit, label)
    if physical is None:
        _check_points(analysis, points, scene, label)
    if analysis != "onset":
        _check_run_size(points, scene, settings, label)
    return Study(label, doc.get("description", ""), analysis, physical, scene,
                 settings, tuple(points))


def _check_points(analysis: str, points: list, scene: dict, label: str) -> None:
    """The values of a nondimensional study's parameters, checked as Scene fields when the
    file is read (each value, or the extremes of more than 100, every bound being a
    range), and a flow for a time integration: ValueError naming the value."""
    for key in points[0]:
        values = sorted({p[key] for p in points})
        for value in values if len(values) <= 100 else (values[0], values[-1]):
            try:
                Scene.from_dict({**scene, key: value})
            except (ValueError, TypeError) as err:
                raise ValueError(f"{label}: {key} = {value!r}: {err}") from None
    if analysis != "onset" and "ustar" not in points[0] and not scene.get("ustar", 0) != 0:
        raise ValueError(f"{label}: the {analysis} analysis integrates in time at a flow: give "
                         "ustar > 0 (< 0: reversed flow) in [grid], [sample] or [scene] (or "
                         "flow, with physical = ...)")


def _check_run_size(points: list, scene: dict, settings: dict, label: str) -> None:
    """The memory of each point's run (``t_end / dt_out`` samples of its states), checked
    when the file is read: ValueError naming the settings."""
    modes = max(int(p.get("modes", scene.get("modes", Scene.modes))) for p in points)
    try:
        check_size(2 * modes + 2, settings["t_end"], settings["dt_out"], PressureSchedule())
    except ValueError as err:
        raise ValueError(f"{label}: [settings] {err}".replace(" (--dt-out)", "").replace(
            " (--t-end)", "")) from None


def _check_values(analysis: str, physical, scene: dict, settings: dict, label: str) -> None:
    """The [scene] and [settings] values checked as the analyses will use them, when the
    file is read (not as an error row per point): ValueError naming the key."""
    if analysis == "sound" and physical is None:
        raise ValueError(f"{label}: the sound analysis needs physical = ... (the sound "
                         "pressure in Pa at a distance in m)")
    for key, value in settings.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not math.isfinite(value) or value <= 0:
            raise ValueError(f"{label}: [settings] {key} must be a number > 0, got {value!r}")
    if settings.get("ustar_max", 0) > MAX_ABS_USTAR:
        raise ValueError(f"{label}: [settings] ustar_max must be at most {MAX_ABS_USTAR:g}, "
                         f"got {settings['ustar_max']!r}")
    if analysis != "onset":
        try:
            Settings(rtol=settings["rtol"], atol=settings["atol"], dt_out=settings["dt_out"],
                     chunk=max(1.0, settings["dt_out"]))
        except ValueError as err:
            raise ValueError(f"{label}: [settings] {err}") from None
    try:
        Scene.from_dict(scene)
    except (ValueError, TypeError) as err:
        raise ValueError(f"{label}: [scene] {err}") from None


def _table(doc: dict, key: str, label: str) -> dict:
    value = doc.get(key, {})
    if not isinstance(value, dict):
        raise ValueError(f"{label}: [{key}] must be a table")
    return dict(value)


def _units(physical: str | None):
    """``name -> value in SI`` for the parameters of a study (ValueError naming them)."""
    def convert(name: str, value, label: str) -> float:
        if physical is None:
            if name not in _SCENE_FIELDS:
                raise ValueError(f"{label}: {name!r} is not a Scene field (without physical = "
                                 f"... the parameters are Scene fields: {', '.join(_SCENE_FIELDS)})")
            number = finite_number(f"{label}: {name}", value)
            return value if name in ("modes", "quad_nodes") and isinstance(value, int) else number
        if name not in KEYS:
            raise ValueError(f"{label}: {name!r} is not a [physical] key; allowed: "
                             f"{', '.join(KEYS)}")
        if name == "flow":                           # kept as given (velocity or volume)
            if not isinstance(value, str):
                raise ValueError(f"{label}: flow must be a string with its unit (20L/min)")
            parse_flow(value, f"{label}: flow")
            return value.strip()
        return parse_quantity(value, KEYS.get(name) or "", f"{label}: {name}")
    return convert


def _grid(grid: dict, convert, label: str) -> list[dict]:
    if not isinstance(grid, dict) or not grid:
        raise ValueError(f"{label}: [grid] must name at least one parameter")
    axes = {}
    for name, spec in grid.items():
        where = f"{label}: grid.{name}"
        if isinstance(spec, dict):
            need = {"start", "stop", "num"}
            if not need <= set(spec) or set(spec) - need - {"log"}:
                raise ValueError(f"{where} takes start, stop, num (and log = true), got "
                                 f"{sorted(spec)}")
            a, b = convert(name, spec["start"], where), convert(name, spec["stop"], where)
            num = spec["num"]
            if not (isinstance(num, int) and num >= 1):
                raise ValueError(f"{where}.num must be an integer >= 1, got {num!r}")
            check_points(num, where, "give a smaller num")
            values = np.geomspace(a, b, num) if spec.get("log", False) else np.linspace(a, b, num)
            axes[name] = [float(v) for v in values]
        elif isinstance(spec, list) and spec:
            axes[name] = [convert(name, v, where) for v in spec]
        else:
            raise ValueError(f"{where} must be a non-empty list or a {{start, stop, num}} table")
        repeated = sorted({v for v in axes[name] if axes[name].count(v) > 1})
        if repeated:
            raise ValueError(f"{where} repeats {', '.join(f'{v:g}' for v in repeated)}: "
                             "give each value once (each point would be computed again)")
    check_points(math.prod(len(v) for v in axes.values()), f"{label}: [grid]",
                 "give fewer values per parameter, or split the study into several files")
    return [dict(zip(axes, combo)) for combo in itertools.product(*axes.values())]


def _sample(sample: dict, convert, label: str) -> list[dict]:
    sample = dict(sample)
    size, seed = sample.pop("size", None), sample.pop("seed", 0)
    if not (isinstance(size, int) and size >= 1):
        raise ValueError(f"{label}: sample.size must be an integer >= 1, got {size!r}")
    check_points(size, f"{label}: [sample]", "give a smaller size")
    if not isinstance(seed, int):
        raise ValueError(f"{label}: sample.seed must be an integer, got {seed!r}")
    if not sample:
        raise ValueError(f"{label}: [sample] must give a distribution for at least one parameter")
    rng = np.random.default_rng(seed)
    columns = {}
    for name, spec in sample.items():
        where = f"{label}: sample.{name}"
        kind = spec.get("distribution") if isinstance(spec, dict) else None
        if kind not in DISTRIBUTIONS:
            raise ValueError(f"{where}.distribution must be one of {', '.join(DISTRIBUTIONS)}")
        args = DISTRIBUTIONS[kind]
        if set(spec) != {"distribution", *args}:
            raise ValueError(f"{where}: a {kind} distribution takes {', '.join(args)}")
        a = convert(name, spec[args[0]], where)
        b = finite_number(f"{where}.sigma", spec[args[1]]) if kind == "lognormal" else convert(name, spec[args[1]], where)
        columns[name] = _draw(rng, kind, a, b, size, where)
    return [{k: float(v[i]) for k, v in columns.items()} for i in range(size)]


def _draw(rng, kind: str, a: float, b: float, size: int, where: str) -> np.ndarray:
    if kind in ("uniform", "loguniform") and not (a < b) or kind == "loguniform" and a <= 0:
        raise ValueError(f"{where}: need 0 < low < high (loguniform) or low < high")
    if kind in ("normal", "lognormal") and not b > 0:
        raise ValueError(f"{where}: the spread must be > 0")
    if kind == "uniform":
        return rng.uniform(a, b, size)
    if kind == "loguniform":
        return np.exp(rng.uniform(np.log(a), np.log(b), size))
    if kind == "normal":
        return rng.normal(a, b, size)
    return a * np.exp(rng.normal(0.0, b, size))


