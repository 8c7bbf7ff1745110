"""The ``"meta"`` object of every JSON the command line prints or writes: what made the
result, when, from what and in which units.

``meta`` holds ``fsicas``, ``casadi``, ``numpy``, ``scipy`` and ``python`` (versions),
``created`` (UTC, ISO 8601), ``command`` (the command line), ``scene``
(:meth:`fsicas.Scene.to_dict` of the scene the command used; None for ``modes``;
``paper``'s main scene, its variants named in the report), ``settings`` (every other option of the command, as
parsed, plus the resolved settings objects where the command builds them) and ``units``
(field of the result -> its unit, for the fields the result has: :func:`with_meta`). This module is the one home of that description;
``fsicas paper`` passes it to :func:`fsicas.paper.run_paper`, which writes it into
``report.json`` with the report's own ``fields``.
"""
from __future__ import annotations

import argparse
import shlex
from dataclasses import asdict, is_dataclass

from .. import strict_json
from ..provenance import provenance, versions, with_meta
from .scene_options import SCENE_OPTIONS, scene_from_args

__all__ = ["NONDIM", "UNITS", "versions", "run_meta", "cli_meta", "record", "with_meta",
           "write_json"]

#: The unit of a nondimensional length or time (docs/model.md).
NONDIM = "nondimensional (units of L, T = L^2 sqrt(rho_s e / D))"
_PRESSURE = "nondimensional (units of D / L^3, D the bending stiffness per unit width)"
_FLOW = "nondimensional (units of L^2 / T per unit width)"
_RATE = "rad per unit T (T = L^2 sqrt(rho_s e / D))"
_TIME = "nondimensional (units of T = L^2 sqrt(rho_s e / D))"
_LENGTH = "nondimensional (units of L)"
_RATIO = "dimensionless"
_PHYSICAL = "SI-derived, as each key says (Hz, Pa, mm, m/s, L/min)"
_WARNINGS = "text"
_WALL = "seconds"
_BRANCH = {"ustar": _RATIO + " (U* = U0 T / L, docs/model.md)",
           "period": _TIME, "omega": _RATE, "tip_amplitude": _LENGTH,
           "gap_ratio": _RATIO + " (min gap / eps)", "eps": _LENGTH + " (contact layer)",
           "hopf": "U* and M* dimensionless, omega " + _RATE + ", pressure_drop " + _PRESSURE}

#: Command -> field of its JSON -> unit. Fields not listed are counts, flags or text.
UNITS = {
    "modes": {"beta": "nondimensional (beta_n L)", "omega": _RATE},
    "steady": {"pressure_drop": _PRESSURE, "Q": _FLOW, "q": _LENGTH + " (modal amplitudes)",
               "tip_deflection": _LENGTH + " (at x_ref)", "x_ref": _LENGTH},
    "eig": {"eigenvalues": "[re, im], " + _RATE, "ustar": _BRANCH["ustar"],
            "pressure_drop": _PRESSURE},
    "boundary": {"points": "mstar, ustar_crit, freq_ratio " + _RATIO + "; omega " + _RATE +
                 "; l1 nondimensional; truncation relative", "switches": "mstar, ustar " +
                 _RATIO},
    "simulate": {"period": _TIME, "omega": _RATE, "tip_amplitude": _LENGTH,
                 "first_contact_time": _TIME, "contact_positions": _LENGTH,
                 "first_contact_position": _LENGTH, "t_end_reached": _TIME,
                 "max_impact_force": "dimensionless (max of the integrated impact force / "
                 "F0, F0 = m f1^2 H, docs/simulate.md)",
                 "mean_flow_reduction": _RATIO + " (fraction of the steady flow rate)",
                 "convergence": _RATIO + " (relative remaining change)",
                 "quadrature_error": _RATIO + " (relative)",
                 "quadrature_tol": _RATIO + " (relative; null: not controlled)"},
    "map": {"boundary": "U*, M* " + _RATIO + "; omega " + _RATE, "grid": "U*, M* " + _RATIO,
            "t_end": _TIME, "scene": "as scene files (docs/model.md)"},
    "lco": {"hopf": _BRANCH["hopf"], "eps": _BRANCH["eps"],
            "points": ", ".join(f"{k} {_BRANCH[k]}" for k in ("ustar", "period", "omega",
                                                              "tip_amplitude", "gap_ratio")),
            "folds": "as points", "contact": "as points"},
    "grazing": {"grazing": f"mstar, ustar, gap_ratio {_RATIO}; period {_TIME}; tip_amplitude "
                f"{_LENGTH}", "fold": "as grazing", "hopf": f"mstar, ustar {_RATIO}; omega "
                f"{_RATE}; l1 nondimensional", "switches": "mstar, ustar " + _RATIO,
                "seeds": "mstar " + _RATIO},
    "diagram": {"branches": f"ustar_range, ustar {_RATIO}; tip {_LENGTH} (deflection of "
                "steady states, half-amplitude of cycles); period {_TIME}",
                "ustar_max": _RATIO, "onsets": f"mstar, ustar {_RATIO}",
                "codim2": f"mstar, ustar {_RATIO}; omega {_RATE}; coefficients nondimensional",
                "curves": f"mstar, ustar {_RATIO}; tip_amplitude {_LENGTH}",
                "mstar_window": _RATIO},
    "onset": {"mstar": _RATIO, "ustar_crit": _BRANCH["ustar"], "pressure_drop": _PRESSURE,
              "omega": _RATE, "freq_ratio": _RATIO + " (omega / omega_1)",
              "ustar_reference": _BRANCH["ustar"], "ustar_max": _BRANCH["ustar"],
              "truncation": _RATIO + " (relative change of ustar_crit with twice the modes)"},
    "paper": {"omega_invacuo": _RATE, "boundary": "as fsicas boundary: omega " + _RATE,
              "variants": "ustar_crit, freq_ratio " + _RATIO,
              "impact_map": f"counts; grid U*, M* {_RATIO}; t_end {_TIME}; boundary as fsicas "
              "map",
              "impacting_cycles": f"period {_TIME}; tip_amplitude {_LENGTH}; truncation_error "
              f"{_RATIO} (relative change with half the modes); t_end {_TIME}; else as "
              "fsicas simulate", "fig4_curves": "counts of map points",
              "steady": f"ustar {_RATIO}; pressure_drop, closed_form {_PRESSURE}; Q {_FLOW}"},
}
_COMMON = {"physical": _PHYSICAL, "warnings": _WARNINGS, "wall_time": _WALL}
_ALIASES = {"cycles": "lco"}
#: Options that are fields of the scene (in ``meta.scene``, not repeated in its settings).
_SCENE_FIELDS = frozenset({*SCENE_OPTIONS, "contact", "direction"})
#: Parsed arguments that are not settings of the command.
_NOT_SETTINGS = frozenset({"command", "run", "human", "json", "quiet", "verbose", "reporter",
                           "argv", "meta_scene", "meta_settings"})


def run_meta(command: str, scene=None, settings: dict | None = None,
             units: dict | None = None) -> dict:
    """``meta`` of one result: versions, UTC time, ``command`` (the command line), the
    ``scene`` (a :class:`fsicas.Scene` or its dict), ``settings`` and ``units``."""
    return {**provenance(), "command": command, "scene": scene.to_dict() if hasattr(scene, "to_dict") else scene,
            "settings": _plain(settings or {}), "units": units or {}}


def record(args: argparse.Namespace, scene=None, **settings) -> None:
    """Tell the meta of this command the scene it used and settings it resolved (e.g. a
    ``CycleSettings``); options need not be recorded, they are read from ``args``."""
    if scene is not None:
        args.meta_scene = scene
    args.meta_settings = {**getattr(args, "meta_settings", {}), **settings}


def cli_meta(args: argparse.Namespace) -> dict:
    """``meta`` of the command ``args`` describes (module docstring)."""
    command = _ALIASES.get(args.command, args.command)
    argv = getattr(args, "argv", None)
    line = "fsicas" + ("" if argv is None else " " + shlex.join(argv))
    scene = _scene(args)
    options = {k: v for k, v in vars(args).items() if k not in _NOT_SETTINGS and
               not (k in _SCENE_FIELDS and (v is None or scene is not None))}
    return run_meta(line, scene, {**options, **getattr(args, "meta_settings", {})},
                    {**UNITS.get(command, {}), **_COMMON})


def write_json(path, data: dict, args: argparse.Namespace, indent: int = 1) -> None:
    """Write ``data`` with its ``meta`` to ``path`` (a file the command line writes), as
    strict JSON: a NaN or infinite number is written as null, and a warning in the file
    names where (:mod:`fsicas.strict_json`)."""
    data, places = strict_json.finite(data)
    if places:
        data["warnings"] = (data.get("warnings") or []) + [strict_json.nonfinite_note(places)]
    data = with_meta(data, strict_json.finite(cli_meta(args))[0])
    with open(path, "w") as f:
        f.write(strict_json.dumps(data, indent=indent))


def _scene(args: argparse.Namespace):
    """The scene the command recorded, else the one its options describe (None if they
    describe none or an invalid one: the error says why)."""
    if getattr(args, "meta_scene", None) is not None:
        return args.meta_scene
    if not hasattr(args, "scene") or args.command == "map":
        return None
    try:
        return scene_from_args(args)
    except Exception:           # the command's own error is reported instead
        return None


def _plain(value):
    """``value`` as JSON data: dataclasses as dicts, arrays and tuples as lists."""
    if is_dataclass(value) and not isinstance(value, type):
        return _plain(asdict(value))
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if hasattr(value, "tolist"):
        return value.tolist()
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    return str(value)
