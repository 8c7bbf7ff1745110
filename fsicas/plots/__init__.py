"""Figures of results (Matplotlib is imported only when a figure is drawn)."""

from .linear import plot_boundary, plot_mode_shapes
from .timedomain import plot_cycle, plot_map, plot_run

__all__ = ["plot_boundary", "plot_mode_shapes", "plot_cycle", "plot_map", "plot_run"]
