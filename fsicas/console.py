"""The ``fsicas`` command (``[project.scripts]``) and ``python -m fsicas``.

It loads the command line (:mod:`fsicas.cli`, with the numerical libraries: a second or
two on a cold start) inside the same guard as a run, so that Ctrl-C while they load ends
with one line and exit status 130 too, not a traceback.
"""
from __future__ import annotations

import sys

__all__ = ["main"]


def main(argv: list[str] | None = None) -> int:
    """Run ``fsicas`` with ``argv`` (default: the process's arguments)."""
    try:
        from .cli import main as run
    except KeyboardInterrupt:
        print("fsicas: interrupted while starting; nothing was done", file=sys.stderr)
        return 130        # fsicas.cli.EXIT_INTERRUPTED, which could not be loaded
    return run(argv)
