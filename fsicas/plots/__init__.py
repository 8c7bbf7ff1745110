"""Figures of results. Matplotlib is imported only when a figure is drawn, through
:func:`fsicas.plots.backend.pyplot`; these functions never select a backend nor change
the global rcParams (each draws in its own ``rc_context``, :mod:`fsicas.plots.backend`),
so in a notebook or an interactive session the user's own backend and settings stay in
charge. Each returns its Figure (saved to ``path`` when given, in the format its name
says: ``.png``, ``.pdf``, ``.svg``, ...)."""

from .backend import pyplot
from .cycles import plot_branch, plot_curves
from .diagram import plot_scene_diagram, plot_window_diagram
from .linear import plot_boundary, plot_boundary_variants, plot_eigenvalues, plot_mode_shapes
from .impacting import CycleView, cycle_view, tip_spectrum
from .timedomain import cycle_window, plot_cycle, plot_cycles, plot_map, plot_run

__all__ = ["pyplot", "plot_boundary", "plot_boundary_variants", "plot_eigenvalues",
           "plot_mode_shapes", "plot_branch", "plot_curves", "plot_cycle", "plot_cycles", "plot_map", "plot_run",
           "cycle_window", "cycle_view", "CycleView", "tip_spectrum", "plot_scene_diagram",
           "plot_window_diagram"]
