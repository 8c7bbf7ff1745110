"""The one way fsicas plotting code gets Matplotlib's pyplot.

Library code never selects a backend (``matplotlib.use``): in a notebook or an
interactive session the user's backend stays in charge, so figures keep displaying.
Only the command line (:mod:`fsicas.cli`) picks a non-interactive backend, itself,
before it writes a figure file.
"""
from __future__ import annotations

__all__ = ["FILE_BACKEND", "pyplot", "select_file_backend"]

#: The backend the command line uses to write figure files (no display needed).
FILE_BACKEND = "Agg"


def pyplot():
    """``matplotlib.pyplot``, imported on first use (so ``import fsicas`` stays light)."""
    import matplotlib.pyplot as plt
    return plt


def select_file_backend() -> None:
    """Switch Matplotlib to the non-interactive file backend.

    For programs that only write figure files (the ``fsicas`` command); library
    functions never call this."""
    import matplotlib
    matplotlib.use(FILE_BACKEND)
