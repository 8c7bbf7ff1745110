"""The main job: the paper's core results on its embedded default configuration.

Default (paper, Fig. 2): H* = 1/10, f = 0.14, K0 = 0, KL = 1, zeta = 0, N = 10 modes.
Writes to the output folder: ``report.json`` (in-vacuo frequencies, steady state against
its closed form, the flutter boundary with frequencies, branches, mode switches and
criticality), ``fig2_boundary.png``, ``fig3_modes.png`` and, unless ``quick``,
``boundary_variants.png`` (zeta = 0.01 and H* in {1/20, 1/5}).
"""
from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from . import __version__
from .beam import clamped_free_betas
from .boundary import stability_boundary
from .figures import _pyplot, plot_boundary, plot_mode_shapes
from .model import build_model
from .scene import Scene
from .steady import steady_state, straight_pressure_drop

__all__ = ["PAPER_SCENE", "run_paper"]

PAPER_SCENE = Scene(mstar=1.0, ustar=5.0, hstar=0.1, friction=0.14, k0=0.0, kl=1.0,
                    zeta=0.0, modes=10)
VARIANTS = {"zeta = 0.01": dict(zeta=0.01), "H* = 1/20": dict(hstar=0.05),
            "H* = 1/5": dict(hstar=0.2)}


def run_paper(out="results", quick: bool = False) -> dict:
    """Compute the report and the figures and write them to ``out``."""
    start = time.perf_counter()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    scene = PAPER_SCENE
    model = build_model(scene)
    steady = steady_state(scene, model)
    mstars = np.logspace(-1, 1, 7) if quick else np.logspace(-2, 2, 33)
    boundary = stability_boundary(scene, mstars, model)
    plot_boundary(boundary, out / "fig2_boundary.png")
    plot_mode_shapes(boundary, model, out / "fig3_modes.png")
    report = {
        "version": __version__,
        "scene": scene.to_dict(),
        "omega_invacuo": (clamped_free_betas(scene.modes) ** 2).tolist(),
        "steady": {"ustar": scene.ustar, "pressure_drop": steady.pressure_drop,
                   "closed_form": straight_pressure_drop(scene), "Q": steady.Q.tolist()},
        "boundary": {k: v for k, v in boundary.to_json().items() if k != "curves"},
    }
    if not quick:
        report["variants"] = _variants(scene, mstars[::2], boundary, out / "boundary_variants.png")
    report["wall_time"] = time.perf_counter() - start
    (out / "report.json").write_text(json.dumps(report, indent=2))
    return report


def _variants(scene, mstars, reference, path) -> dict:
    """Boundaries with structural damping and other confinements, drawn together."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    curves = {"paper (zeta = 0, H* = 1/10)": reference}
    for label, change in VARIANTS.items():
        variant = scene.replace(**change)
        curves[label] = stability_boundary(variant, mstars, build_model(variant), refine=False)
    summary = {}
    for label, b in curves.items():
        pts = [p for p in b.points if p["ustar_crit"] is not None]
        ax.semilogx([p["mstar"] for p in pts], [p["ustar_crit"] for p in pts], ".-", label=label)
        summary[label] = [{"mstar": p["mstar"], "ustar_crit": p["ustar_crit"],
                           "freq_ratio": p["freq_ratio"]} for p in pts]
    ax.set(xlabel="M*", ylabel="U*_c", title="effect of damping and confinement")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return summary
