"""The one way fsicas plotting code gets Matplotlib's pyplot, and the figures' style.

Library code never selects a backend (``matplotlib.use``) and never changes the global
``rcParams``: in a notebook or an interactive session the user's backend and settings
stay in charge, so figures keep displaying as the user set them up. Every figure function
draws inside :func:`styled` (a ``matplotlib.rc_context``: the publication style holds
while the figure is drawn and saved, and the user's settings come back afterwards). Only
the command line (:mod:`fsicas.cli`) picks a non-interactive backend, itself, before it
writes a figure file.

The style: serif text with STIX mathtext (the fonts of the journals' TeX look, shipped
with Matplotlib), 9-pt labels, the Okabe–Ito colour-blind-safe palette, constrained
layout (labels are never cut), fonts embedded in PDF output as TrueType. A figure is
written in the format its file name says (``.png``, ``.pdf``, ``.svg``, ...).
"""
from __future__ import annotations

import functools
import re
from pathlib import Path

from ..timedomain.outcome import OUTCOME_WORDS, outcome_words   # for titles and legends

__all__ = ["FILE_BACKEND", "PALETTE", "OUTCOME_WORDS", "NONDIM", "probe_label", "pyplot", "select_file_backend", "suptitle",
           "styled", "subplots", "finish", "outcome_words"]

#: The backend the command line uses to write figure files (no display needed).
FILE_BACKEND = "Agg"

#: Okabe & Ito's colour-blind-safe palette (black first is left out: it marks the
#: reference lines; the yellow comes last, it is faint on white).
PALETTE = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000",
           "#F0E442")

#: The unit suffix of a nondimensional quantity's axis label.
NONDIM = "(nondim.)"


def probe_label(x_ref: float, what: str = "y", noun: str = "") -> str:
    """Where a "tip" quantity is measured, for labels, the math left open for the caller:
    ``tip {noun}$y(L)`` at the free tip, else ``{noun}$y(0.5\\,L)`` (x_ref:
    :func:`fsicas.model.assembly.reference_point`)."""
    if x_ref == 1.0:
        return f"tip {noun}${what}(L)"
    return f"{noun}${what}({x_ref:.3g}\\,L)"


#: Raster resolution of saved figures (vector formats ignore it).
DPI = 200

_STYLE = {
    "font.family": "serif",
    "font.serif": ["STIXGeneral", "DejaVu Serif"],
    "mathtext.fontset": "stix",
    "font.size": 9,
    "axes.titlesize": 9,
    "axes.labelsize": 9,
    "legend.fontsize": 8,
    "xtick.labelsize": 8,
    "ytick.labelsize": 8,
    "figure.titlesize": 10,
    "axes.linewidth": 0.7,
    "lines.linewidth": 1.2,
    "lines.markersize": 4,
    "xtick.direction": "in",
    "ytick.direction": "in",
    "xtick.top": True,
    "ytick.right": True,
    "legend.frameon": False,
    "axes.prop_cycle": None,      # filled on first use (needs matplotlib's cycler)
    "pdf.fonttype": 42,
    "ps.fonttype": 42,
    "savefig.dpi": DPI,
}


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


def _style() -> dict:
    from cycler import cycler
    return {**_STYLE, "axes.prop_cycle": cycler(color=PALETTE)}


def styled(draw):
    """Decorator: run a figure function inside ``rc_context`` with the fsicas style, so
    the figure gets it and the user's rcParams are untouched."""
    @functools.wraps(draw)
    def wrapper(*args, **kwargs):
        plt = pyplot()
        with plt.rc_context(_style()):
            return draw(*args, **kwargs)
    return wrapper


def subplots(nrows: int = 1, ncols: int = 1, **kwargs):
    """``plt.subplots`` with constrained layout (call inside :func:`styled`)."""
    kwargs.setdefault("layout", "constrained")
    kwargs.setdefault("squeeze", False)
    return pyplot().subplots(nrows, ncols, **kwargs)


def suptitle(fig, text: str):
    """``fig.suptitle(text)``, broken into lines at the spaces outside ``$...$`` and
    ``a = b`` wherever a line would be wider than the figure (a one-panel figure keeps its
    whole title)."""
    title = fig.suptitle(text)
    renderer, width = fig.canvas.get_renderer(), 0.98 * fig.bbox.width
    lines = [""]
    words = re.findall(r"(?:\$[^$]*\$|[^ $])+", text.replace(" = ", "\0=\0"))
    for word in (w.replace("\0", " ") for w in words):      # "a = 1" stays on one line
        title.set_text(f"{lines[-1]} {word}".strip())
        if lines[-1] and title.get_window_extent(renderer).width > width:
            lines.append(word)
        else:
            lines[-1] = f"{lines[-1]} {word}".strip()
    title.set_text("\n".join(lines))
    return title


def finish(fig, path=None):
    """Keep every legend of ``fig`` off its panel's data
    (:func:`fsicas.plots.legends.settle_legends`), write ``fig`` to ``path`` (format from
    the file name; PNG if it has none) and release it from pyplot; without a path leave
    it open. Returns the figure, which stays usable (inspect it, save it again)."""
    from .legends import settle_legends
    settle_legends(fig)
    if path is not None:
        fig.savefig(Path(path))
        pyplot().close(fig)
    return fig


