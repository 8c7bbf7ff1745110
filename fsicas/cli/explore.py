"""CLI command ``fsicas explore``: serve the live explorer (docs/explore.md) on
127.0.0.1 by default and print its address; ``--host`` binds elsewhere (the user's
explicit choice: anyone who reaches that address can use the page)."""
from __future__ import annotations

import sys

__all__ = ["add_explore_command"]


def add_explore_command(sub) -> None:
    """Add the ``explore`` subcommand."""
    p = sub.add_parser("explore", help="the live explorer: the model in a browser (needs "
                       "the explore extra: pip install -e \".[explore]\")")
    p.add_argument("--host", default="127.0.0.1", help="address to listen on (default "
                   "127.0.0.1: this machine only)")
    p.add_argument("--port", type=int, default=5006, help="port (default 5006)")
    p.add_argument("--physical", metavar="PRESET", default=None,
                   help="start from a physical preset (frequencies in Hz, flows in L/min)")
    p.add_argument("--show", action="store_true", help="open a browser on the page")
    p.set_defaults(run=_cmd_explore, human=lambda result: None, json=False)


def _cmd_explore(args) -> dict:
    if not 0 < args.port < 65536:
        raise ValueError(f"--port must be in [1, 65535], got {args.port}")
    if args.physical is not None:
        from ..physical import load_physical
        load_physical(args.physical)                      # refuses an unknown preset first
    try:
        from ..explore import serve
        import panel  # noqa: F401
    except ImportError as err:
        raise ValueError(f"fsicas explore needs the explore extra ({err.name} is missing): "
                         "pip install -e \".[explore]\"") from None
    ready = lambda url: print(f"fsicas explore: serving {url} (Ctrl-C to stop)", flush=True)
    try:
        serve(args.host, args.port, args.physical, show=args.show, on_ready=ready)
    except KeyboardInterrupt:
        print("fsicas explore: stopped", file=sys.stderr)
    return {}
