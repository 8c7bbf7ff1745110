"""Matplotlib helpers: bifurcation diagrams of a :class:`Branch`, cycles in phase space.

Kept apart from the algorithms: importing ``continuation`` never imports
Matplotlib.
"""

from __future__ import annotations

import numpy as np

MARKERS = {"fold": ("s", "LP"), "hopf": ("o", "H"), "bp": ("D", "BP"),
           "bt": ("*", "BT"), "gh": ("P", "GH"), "hh": ("X", "HH"), "zh": ("v", "ZH"),
           "pd": ("^", "PD"), "ns": ("h", "NS"), "lpc": ("s", "LPC"), "cpc": ("<", "CPC"),
           "r1": ("1", "R1"), "r2": ("2", "R2"), "r3": ("3", "R3"), "r4": ("4", "R4"),
           "lppd": ("p", "LPPD"), "lpns": ("H", "LPNS"), "pdns": ("d", "PDNS"),
           "nsns": ("8", "NSNS"), "gpd": (">", "GPD"), "ch": ("*", "CH")}


def _column(branch, spec):
    """Values of ``spec``: parameter name, column name (e.g. 'period', 'amplitude'),
    state index, 'norm' or a callable."""
    if callable(spec):
        return np.asarray(spec(branch), dtype=float)
    if isinstance(spec, str) and spec == "norm":
        return np.linalg.norm(branch.x, axis=1)
    if isinstance(spec, str) and spec in branch.columns:
        return np.asarray(branch.columns[spec], dtype=float)
    if isinstance(spec, str):
        return branch.par(spec)
    if isinstance(spec, (int, np.integer)):
        return branch.x[:, int(spec)]
    raise ValueError(f"axis spec must be a parameter name, a state index, 'norm' or a "
                     f"callable, got {spec!r}")


def _point_value(branch, spec, point):
    if isinstance(spec, str) and spec in branch.par_names:
        return point.params[spec]
    if isinstance(spec, (int, np.integer)):
        return point.x[int(spec)]
    if isinstance(spec, str) and spec == "norm":
        return float(np.linalg.norm(point.x))
    if isinstance(spec, str) and spec in point.data and np.isscalar(point.data[spec]):
        return float(point.data[spec])
    return None


def plot_branch(branch, x=None, y=None, ax=None, *, color=None, label=None,
                special=True, stability=None):
    """Draw ``branch`` on ``ax`` (created if None) and return ``ax``.

    x : horizontal axis, default the continuation parameter ``branch.free[-1]``.
    y : vertical axis, default the first free parameter for two-parameter
        curves and ``'norm'`` (``|x|``) for equilibria.
    stability : solid where stable, dashed where unstable (default: only for
        equilibrium branches).
    """
    import matplotlib.pyplot as plt

    ax = plt.gca() if ax is None else ax
    x = branch.free[-1] if x is None else x
    y = (branch.free[0] if len(branch.free) > 1 else "norm") if y is None else y
    xs, ys = _column(branch, x), _column(branch, y)
    show_stab = (branch.kind in ("equilibrium", "cycle")) if stability is None else stability
    stable = branch.stable if show_stab and len(branch.eigenvalues) else np.ones(len(xs), bool)
    color = color or ax._get_lines.get_next_color()
    for i, (start, stop, st) in enumerate(_segments(stable)):
        ax.plot(xs[start:stop], ys[start:stop], "-" if st else "--", color=color,
                label=label if i == 0 else None)
    if special:
        _special_markers(ax, branch, x, y, color)
    ax.set_xlabel(str(x) if not callable(x) else "")
    ax.set_ylabel(str(y) if not callable(y) else "")
    return ax


def _segments(stable):
    """``(start, stop, stable)`` runs; consecutive runs share an end point."""
    runs, start = [], 0
    for i in range(1, len(stable) + 1):
        if i == len(stable) or stable[i] != stable[start]:
            runs.append((start, min(i + 1, len(stable)), bool(stable[start])))
            start = i
    return runs


def _special_markers(ax, branch, x, y, color):
    for point in branch.special_points:
        px, py = _point_value(branch, x, point), _point_value(branch, y, point)
        if px is None or py is None:
            continue
        marker, text = MARKERS.get(point.kind, ("o", point.kind))
        ax.plot([px], [py], marker, color=color, markeredgecolor="k")
        ax.annotate(text, (px, py), textcoords="offset points", xytext=(4, 4))


def plot_cycle(problem, X, i=0, j=1, ax=None, *, samples=400, **style):
    """Draw the cycle ``X`` of a CycleProblem: component ``j`` against ``i`` (phase
    space), or component ``i`` against time ``t T`` when ``j`` is None. ``X`` is a
    point of the problem (e.g. ``SpecialPoint.data['X']`` or an iterator step)."""
    import matplotlib.pyplot as plt

    ax = plt.gca() if ax is None else ax
    X = np.asarray(X, dtype=float)
    t = np.linspace(0.0, 1.0, samples + 1)
    u = problem.evaluate(X, t)
    if j is None:
        ax.plot(t * problem.period(X), u[:, i], **style)
    else:
        ax.plot(u[:, i], u[:, j], **style)
    return ax


def plot_diagram(diagram, x=None, y=None, ax=None, *, special=True):
    """Draw every branch of a ``Diagram`` on ``ax`` (created if None), one colour per
    branch, solid where stable and dashed where not, special points labelled; return
    ``ax``. ``x``, ``y`` as in :func:`plot_branch`, for every branch (default: the
    continuation parameter against ``'norm'`` for equilibria and ``'amplitude'`` for
    cycles)."""
    import matplotlib.pyplot as plt

    ax = plt.gca() if ax is None else ax
    for node, depth in diagram.root.walk():
        branch = node.branch
        yy = y if y is not None else ("amplitude" if branch.kind == "cycle" else "norm")
        label = f"{branch.kind} from {node.birth.kind}" if depth else f"{branch.kind}"
        plot_branch(branch, x, yy, ax, label=label, special=special, stability=True)
    return ax
