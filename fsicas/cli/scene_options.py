"""The scene options shared by the commands: ``--scene FILE.toml`` and one option per
Scene field (options override the file), and the Scene they describe."""
from __future__ import annotations

import argparse

from ..scene import Scene, load_scene

__all__ = ["SCENE_OPTIONS", "add_scene_options", "scene_from_args"]

#: CLI option (``--quad-nodes`` for ``quad_nodes``) -> type, one per Scene field.
SCENE_OPTIONS = {
    "mstar": float, "ustar": float, "hstar": float, "friction": float, "k0": float,
    "kl": float, "zeta": float, "modes": int, "quad_nodes": int,
    "contact_stiffness": float, "contact_eps": float,
}


#: What each scene option means (the defaults are those of :class:`fsicas.Scene`).
SCENE_HELP = {
    "mstar": "mass ratio M* = rho_f L / (rho_s e), in (0, 1e6]",
    "ustar": "mean inlet velocity U* = U0 T / L, |U*| <= 1e4 (negative: reversed flow)",
    "hstar": "total inlet gap H* = (H1(0) + H2(0)) / L, > 0",
    "friction": "Fanning friction coefficient f, >= 0",
    "k0": "singular head loss at the inlet, >= 0",
    "kl": "singular head loss at the outlet, >= 0",
    "zeta": "modal damping ratio (every mode), >= 0",
    "modes": "number of beam modes N, in [1, 200]",
    "quad_nodes": "Gauss-Legendre nodes of the flow integrals, in [2N, 2000]",
    "contact_stiffness": "wall-contact stiffness k* (per unit length, relative to the first "
                         "mode's), > 0",
    "contact_eps": "contact layer eps/H (H = H*/2), in (0, 1)",
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
    group.add_argument("--contact", dest="contact", action=argparse.BooleanOptionalAction,
                       default=None, help="regularized wall impact on or off (default off)")
    parser.add_argument("--json", action="store_true", help="print one JSON object on stdout")


def scene_from_args(args: argparse.Namespace) -> Scene:
    """Scene from --scene FILE and/or the options (options override the file)."""
    values = {k: getattr(args, k, None) for k in (*SCENE_OPTIONS, "contact")}
    values = {k: v for k, v in values.items() if v is not None}
    if args.scene:
        return load_scene(args.scene, **values)
    return Scene(**values)
