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


def add_scene_options(parser: argparse.ArgumentParser, mstar: bool = True) -> None:
    """Add the scene options (without ``--mstar`` if ``mstar`` is false: the command
    takes its own grid of M*) and ``--json`` to ``parser``."""
    group = parser.add_argument_group("scene (nondimensional; see docs/model.md)")
    group.add_argument("--scene", metavar="FILE.toml", help="read the scene from a TOML file")
    for name, kind in SCENE_OPTIONS.items():
        if name != "mstar" or mstar:
            group.add_argument("--" + name.replace("_", "-"), dest=name, type=kind, default=None)
    group.add_argument("--contact", dest="contact", action=argparse.BooleanOptionalAction, default=None)
    parser.add_argument("--json", action="store_true", help="print one JSON object on stdout")


def scene_from_args(args: argparse.Namespace) -> Scene:
    """Scene from --scene FILE and/or the options (options override the file)."""
    values = {k: getattr(args, k, None) for k in (*SCENE_OPTIONS, "contact")}
    values = {k: v for k, v in values.items() if v is not None}
    if args.scene:
        return load_scene(args.scene, **values)
    return Scene(**values)
