"""The scene options shared by the commands: ``--scene FILE.toml`` and one option per
Scene field (options override the file), or ``--physical PRESET|FILE.toml`` and
``--flow`` (physical units, docs/units.md), and the Scene they describe."""
from __future__ import annotations

import argparse

from ..physical import Flow, Physical, load_physical, parse_flow, preset_names
from ..scene import DIRECTIONS, MAX_ABS_USTAR, Scene, load_scene

__all__ = ["check_ustar_max", "SCENE_OPTIONS", "BEAM_OPTIONS", "add_scene_options", "add_beam_options",
           "add_direction_option", "beam_fields",
           "scene_values",
           "scene_from_args", "physical_from_args"]

def _zeta(text: str) -> float | tuple[float, ...]:
    """``--zeta``: one damping ratio, or one per mode separated by commas."""
    try:
        return tuple(float(z) for z in text.split(",")) if "," in text else float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number or a comma list of "
                                         "numbers (one per mode)") from None


#: CLI option (``--quad-nodes`` for ``quad_nodes``) -> type, one per Scene field.
SCENE_OPTIONS = {
    "mstar": float, "ustar": float, "hstar": float, "friction": float, "k0": float,
    "kl": float, "zeta": _zeta, "modes": lambda text: text if text == "auto" else int(text),
    "quad_nodes": int,
    "contact_stiffness": float, "contact_eps": float,
}


#: What each scene option means (the defaults are those of :class:`fsicas.Scene`).
SCENE_HELP = {
    "mstar": "mass ratio M* = rho_f L / (rho_s e), in (0, 1e6]",
    "ustar": "mean velocity U* = U0 T / L at the root, |U*| <= 1e4 (negative: reversed "
             "flow; with --direction, the speed |U*|)",
    "hstar": "total inlet gap H* = (H1(0) + H2(0)) / L, > 0",
    "friction": "Fanning friction coefficient f, >= 0",
    "k0": "singular head loss of the opening at the root x = 0 (the inlet of forward flow, "
          "the outlet of reversed flow), >= 0",
    "kl": "singular head loss of the opening at the tip x = 1 (the outlet of forward flow, "
          "the inlet of reversed flow), >= 0",
    "zeta": "modal damping ratio, >= 0: one for every mode, or one per mode (z1,z2,...,zN)",
    "modes": "number of beam modes N, in [1, 200]; onset, boundary: also auto (N doubled "
             "from 10 until the onsets move by less than 1e-2 with twice the modes)",
    "quad_nodes": "Gauss-Legendre nodes of the flow integrals, in [2N, 2000]",
    "contact_stiffness": "wall-contact stiffness k* (per unit length, relative to the first "
                         "mode's), > 0",
    "contact_eps": "contact layer eps/H (H = H*/2), in (0, 1)",
}

#: The beam-theory options (docs/beam.md): option -> (type, help).
BEAM_OPTIONS = {
    "beam": (str, "beam theory: euler-bernoulli (default) or timoshenko (shear and rotary "
                  "inertia, for thick beams; with --physical the default when e/L >= 0.1)"),
    "slenderness": (float, "thickness over length e/L of the Timoshenko beam, in (0, 0.5]"),
    "poisson": (float, "Poisson ratio nu of the Timoshenko beam, in [0, 0.5) (default 0.3)"),
    "shear_coefficient": (float, "shear coefficient kappa of the Timoshenko beam, in (0, 1] "
                                 "(default Cowper's 10(1 + nu)/(12 + 11 nu))"),
    "ends": (str, "beam ends, root then x = 1: clamped-free (default), clamped-clamped, "
                  "pinned-pinned or clamped-pinned"),
}


def add_scene_options(parser: argparse.ArgumentParser, mstar: bool = True) -> None:
    """Add the scene options (without ``--mstar`` if ``mstar`` is false: the command
    takes its own grid of M*) and ``--json`` to ``parser``."""
    group = parser.add_argument_group("scene (nondimensional; see docs/model.md)")
    group.add_argument("--scene", metavar="FILE.toml", help="read the scene from a TOML file")
    defaults = Scene()
    for name, kind in SCENE_OPTIONS.items():
        if name != "mstar" or mstar:
            default = getattr(defaults, name)
            shown = "2N + 20" if default is None else f"{default:g}"
            group.add_argument("--" + name.replace("_", "-"), dest=name, type=kind, default=None,
                               metavar=name.upper(),
                               help=f"{SCENE_HELP[name]} (default {shown})")
    add_direction_option(group)
    group.add_argument("--contact", dest="contact", action=argparse.BooleanOptionalAction,
                       default=None, help="regularized wall impact on or off (default off)")
    add_beam_options(group)
    _add_physical_options(parser)
    parser.add_argument("--json", action="store_true", help="print one JSON object on stdout")


def add_direction_option(group, what: str = "U* and of --flow") -> None:
    """``--direction forward|reverse``: the sign of the speeds ``what`` given."""
    group.add_argument("--direction", choices=DIRECTIONS, default=None,
                       help="flow direction: forward (root to tip, default) or reverse (tip "
                       f"to root, expiration: the sign of {what}; with it give "
                       "their magnitude)")


def add_beam_options(group) -> None:
    """``--beam``, ``--slenderness``, ``--poisson``, ``--shear-coefficient``, ``--ends``."""
    for name, (kind, text) in BEAM_OPTIONS.items():
        group.add_argument("--" + name.replace("_", "-"), dest=name, type=kind, default=None,
                           metavar=name.upper(), help=text)


def beam_fields(args: argparse.Namespace) -> dict:
    """The beam options given on the command line, as Scene fields."""
    return {k: getattr(args, k) for k in BEAM_OPTIONS if getattr(args, k, None) is not None}


def _add_physical_options(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("physical input (SI units; see docs/units.md)")
    group.add_argument("--physical", metavar="PRESET|FILE.toml",
                       help="a [physical] table of material, geometry and fluid (M*, H*, U* "
                       "derived from it; the JSON gains a 'physical' object in Hz, Pa, mm, "
                       f"m/s, L/min); presets: {', '.join(preset_names())}")
    group.add_argument("--flow", metavar="FLOW", help="airflow with its unit: a volume flow "
                       "through both channels (20L/min, 3.3e-4m^3/s) or a mean inlet velocity "
                       "(1.2m/s); default: the flow of the physical input")


def scene_values(args: argparse.Namespace) -> dict:
    """The nondimensional Scene fields given as options (a physical input's overrides)."""
    values = {k: getattr(args, k, None)
              for k in (*SCENE_OPTIONS, *BEAM_OPTIONS, "contact", "direction")}
    return {k: v for k, v in values.items() if v is not None}


def physical_from_args(args: argparse.Namespace) -> tuple[Physical, Flow | None] | None:
    """The physical input of ``--physical`` and the airflow (``--flow`` or the input's
    default), or None without ``--physical``; ValueError for options that conflict."""
    if getattr(args, "physical", None) is None:
        if getattr(args, "flow", None) is not None:
            raise ValueError("--flow needs --physical PRESET|FILE.toml (the cross-section "
                             "converts it); in nondimensional units give --ustar")
        return None
    if args.scene:
        raise ValueError("give --scene (nondimensional) or --physical, not both")
    for name in ("mstar", "ustar", "hstar"):
        if getattr(args, name, None) is not None:
            raise ValueError(f"--{name} is derived from --physical (give the physical values "
                             "or --flow instead)")
    physical = load_physical(args.physical)
    flow = parse_flow(args.flow) if args.flow is not None else physical.flow
    return physical, flow


def scene_from_args(args: argparse.Namespace, need_flow: bool = False) -> Scene:
    """Scene from --scene FILE and/or the options (options override the file), or from
    --physical and --flow (``need_flow``: the command needs an airflow)."""
    physical = physical_from_args(args)
    if physical is not None:
        physical, flow = physical
        if need_flow and flow is None:
            raise ValueError(f"{physical.source} gives no airflow: give --flow (e.g. --flow "
                             "20L/min or --flow 1.2m/s) or flow = ... in its [physical] table")
        return physical.scene(flow, **scene_values(args))
    values = scene_values(args)
    if args.scene:
        return load_scene(args.scene, **values)
    return Scene.from_dict(values)



def check_ustar_max(args: argparse.Namespace) -> None:
    """``--ustar-max`` (the speed |U*| up to which a command searches), when the command
    has it: ValueError unless it lies above the speed the steady branch starts from
    (``fsicas.linear.hopf.USTAR_START``: 0.2, and 0.01 for reversed flow) and at most
    MAX_ABS_USTAR."""
    from ..linear.hopf import USTAR_START
    value = getattr(args, "ustar_max", None)
    signed = (str(getattr(args, name, "") or "").strip() for name in ("ustar", "flow"))
    reverse = getattr(args, "direction", None) == "reverse" or any(
        text.startswith("-") for text in signed)
    start = USTAR_START["reverse" if reverse else "forward"]
    if value is not None and not start < value <= MAX_ABS_USTAR:
        raise ValueError(f"--ustar-max must lie in ({start:g}, {MAX_ABS_USTAR:g}] (the search "
                         f"starts at |U*| = {start:g}{' for reversed flow' if reverse else ''}), "
                         f"got {value}")
