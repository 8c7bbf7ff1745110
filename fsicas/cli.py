"""Command line: ``fsicas <command> [scene options] [--scene FILE.toml] [--json]``.

With ``--json`` stdout holds one JSON object and nothing else (a stable contract).
"""
from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

from .beam import clamped_free_betas
from .model import build_model
from .scene import Scene, load_scene
from .steady import SteadyStateError, steady_state

__all__ = ["main"]

# CLI option -> Scene field
_SCENE_OPTIONS = {
    "mstar": float, "ustar": float, "hstar": float, "friction": float, "k0": float,
    "kl": float, "zeta": float, "modes": int, "quad_nodes": int,
    "contact_stiffness": float, "contact_eps": float,
}


def _add_scene_options(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("scene (nondimensional; see docs/model.md)")
    group.add_argument("--scene", metavar="FILE.toml", help="read the scene from a TOML file")
    for name, kind in _SCENE_OPTIONS.items():
        group.add_argument("--" + name.replace("_", "-"), dest=name, type=kind, default=None)
    group.add_argument("--contact", dest="contact", action=argparse.BooleanOptionalAction, default=None)
    parser.add_argument("--json", action="store_true", help="print one JSON object on stdout")


def scene_from_args(args: argparse.Namespace) -> Scene:
    """Scene from --scene FILE and/or the options (options override the file)."""
    values = {k: getattr(args, k) for k in (*_SCENE_OPTIONS, "contact")}
    values = {k: v for k, v in values.items() if v is not None}
    if args.scene:
        return load_scene(args.scene, **values)
    return Scene(**values)


def _cmd_modes(args) -> dict:
    if args.modes is None or args.modes < 1:
        raise ValueError(f"--modes must be an integer >= 1, got {args.modes}")
    beta = clamped_free_betas(args.modes)
    return {"beta": beta.tolist(), "omega": (beta**2).tolist()}


def _cmd_steady(args) -> dict:
    scene = scene_from_args(args)
    model = build_model(scene)
    return steady_state(scene, model).to_json(model)


def _cmd_paper(args) -> dict:
    """The main job: the paper's core numbers on its embedded default configuration."""
    from .paper import run_paper
    return run_paper(out=args.out, quick=args.quick)


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="fsicas", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("modes", help="in-vacuo clamped-free beam modes")
    p.add_argument("--modes", type=int, default=10)
    p.add_argument("--json", action="store_true")
    p.set_defaults(run=_cmd_modes)
    p = sub.add_parser("steady", help="steady state: pressure drop, flow split, static deflection")
    _add_scene_options(p)
    p.set_defaults(run=_cmd_steady)
    p = sub.add_parser("paper", help="reproduce the paper's core results on the embedded default")
    p.add_argument("--out", default="results", help="folder for the report and figures")
    p.add_argument("--quick", action="store_true", help="coarser grids (for a smoke test)")
    p.add_argument("--json", action="store_true")
    p.set_defaults(run=_cmd_paper)
    return parser


def _print_human(result: dict) -> None:
    for key, value in result.items():
        if isinstance(value, list) and value and isinstance(value[0], float):
            value = np.array2string(np.array(value), precision=6, max_line_width=100)
        print(f"{key:>16}: {value}")


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    start = time.perf_counter()
    try:
        result = args.run(args)
    except (ValueError, SteadyStateError) as err:
        if getattr(args, "json", False):
            print(json.dumps({"error": str(err)}))
        else:
            print(f"fsicas {args.command}: error: {err}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(result))
    else:
        _print_human(result)
        print(f"{'wall time':>16}: {time.perf_counter() - start:.3f} s")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
