"""Figures of results. Matplotlib is imported only when a figure is drawn, through
:func:`fsicas.plots.backend.pyplot`; these functions never select a backend, so in a
notebook or an interactive session the user's own backend stays in charge."""

from .backend import pyplot
from .cycles import plot_branch
from .linear import plot_boundary, plot_boundary_variants, plot_eigenvalues, plot_mode_shapes
from .timedomain import cycle_window, plot_cycle, plot_map, plot_run

__all__ = ["pyplot", "plot_boundary", "plot_boundary_variants", "plot_eigenvalues",
           "plot_mode_shapes", "plot_branch", "plot_cycle", "plot_map", "plot_run",
           "cycle_window"]
