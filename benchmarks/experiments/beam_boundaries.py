"""The Fig. 2 flutter boundary U*_c(M*) for thick beams: Euler–Bernoulli against
Timoshenko modes at e/L = 0.01, 0.1, 0.3 (nu = 0.45, Cowper kappa).

Paper scene (H* = 0.1, f = 0.14, K0 = 0, KL = 1, zeta = 0), N = 10, 29 log-spaced M* in
[0.01, 100]; one :func:`fsicas.stability_boundary` per beam theory (refined points,
located mode switches). Prints per theory U*_c, omega and omega/omega_1 at M* = 0.1, 1,
10 and the mode switches, and draws ``docs/figures/beam_boundaries.png`` with
:func:`fsicas.plots.linear.plot_boundary_variants` (U*_c and omega/omega_1 against M*,
one colour per theory, lines broken at the switches). omega is in rad per unit T, the
same T for every theory (``docs/beam.md``); omega_1 is each theory's own first in-vacuo
frequency.

    python benchmarks/experiments/beam_boundaries.py [--count 29] [--modes 10] [--out docs/figures/beam_boundaries.png]

(``--modes 16`` or ``24`` with another ``--out``: the truncation check of ``docs/beam.md``.)
"""
from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")   # the shared 2-core machine

import numpy as np  # noqa: E402

from fsicas import build_model, stability_boundary  # noqa: E402
from fsicas.paper import PAPER_SCENE  # noqa: E402
from fsicas.plots.backend import DPI  # noqa: E402
from fsicas.plots.linear import plot_boundary_variants  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
THEORIES = {"Euler–Bernoulli": {}}
THEORIES.update({f"Timoshenko e/L = {s:g}": dict(beam="timoshenko", slenderness=s, poisson=0.45)
                 for s in (0.01, 0.1, 0.3)})
REPORTED = (0.1, 1.0, 10.0)


def boundaries(count: int, modes: int = 10, say=print) -> dict:
    """label -> StabilityBoundary of each theory on ``count`` M* in [0.01, 100]."""
    mstars = np.geomspace(0.01, 100.0, count)
    out = {}
    for label, change in THEORIES.items():
        scene = PAPER_SCENE.replace(modes=modes, **change)
        t0 = time.perf_counter()
        out[label] = stability_boundary(scene, mstars, build_model(scene))
        say(f"  {label}: {time.perf_counter() - t0:.0f} s, "
            f"{len(out[label].switches)} switches")
    return out


def _at(boundary, mstar: float):
    return min(boundary.points, key=lambda p: abs(np.log(p.mstar / mstar)))


def table(curves: dict) -> str:
    """Markdown: per theory U*_c / omega / omega/omega_1 at M* = 0.1, 1, 10 and the
    switches (M*, U*_c below -> above, omega/omega_1 below -> above)."""
    head = "| theory | " + " | ".join(f"M* = {m:g}: U*_c / ω / ω/ω_1" for m in REPORTED)
    rows = [head + " | mode switches at M* |", "|---" * (len(REPORTED) + 2) + "|"]
    for label, b in curves.items():
        cells = []
        for m in REPORTED:
            p = _at(b, m)
            cells.append("—" if p.ustar_crit is None else
                         f"{p.ustar_crit:.3f} / {p.omega:.2f} / {p.freq_ratio:.2f}")
        w1 = next(p.omega / p.freq_ratio for p in b.points if p.ustar_crit is not None)
        sw = ", ".join(f"{s.mstar:.3g} (ω/ω_1 {s.omega_below / w1:.2f} → {s.omega_above / w1:.2f}"
                       + ("" if abs(s.ustar_above - s.ustar_below) < 1e-6 * s.ustar_below
                          else f", U*_c {s.ustar_below:.2f} → {s.ustar_above:.2f}") + ")"
                       for s in b.switches) or "none"
        rows.append(f"| {label} | " + " | ".join(cells) + f" | {sw} |")
    return "\n".join(rows)


def draw(curves: dict, path: Path):
    """The variants figure of :mod:`fsicas.plots.linear`, retitled; Timoshenko e/L = 0.01
    dashed (it lies on Euler–Bernoulli)."""
    fig = plot_boundary_variants(curves)
    left, right = fig.axes[:2]
    left.set_title(f"effect of the beam theory (N = {next(iter(curves.values())).scene.modes})",
                   fontsize=right.title.get_fontsize())
    for ax in (left, right):
        for line in ax.get_lines():
            if str(line.get_gid()).startswith("Timoshenko e/L = 0.01:"):
                line.set_linestyle("--")
    fig.savefig(path, dpi=DPI)
    return fig


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=29, help="M* values in [0.01, 100]")
    parser.add_argument("--modes", type=int, default=10, help="N, the modes kept")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "figures" / "beam_boundaries.png")
    args = parser.parse_args(argv)
    print(f"flutter boundaries, N = {args.modes}, {args.count} M* in [0.01, 100]")
    curves = boundaries(args.count, args.modes)
    print(table(curves))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    draw(curves, args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
