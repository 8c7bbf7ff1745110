"""The main job: the paper's core results on its embedded default configuration.

Default (paper, Figs. 2 and 4): H* = 1/10, f = 0.14, K0 = 0, KL = 1, N = 10 modes.
Writes ``report.json`` and ``stability_scan.png`` to the output folder.
"""
from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
import scipy.optimize

from . import __version__
from .beam import clamped_free_betas
from .model import build_model
from .scene import Scene
from .stability import eigenvalues
from .steady import steady_state, straight_pressure_drop

__all__ = ["PAPER_SCENE", "run_paper", "critical_velocity_scan"]

PAPER_SCENE = Scene(mstar=1.0, ustar=5.0, hstar=0.1, friction=0.14, k0=0.0, kl=1.0,
                    zeta=0.0, modes=10)


def _growth(model, scene, ustar):
    lam = eigenvalues(model, steady_state(scene.replace(ustar=ustar), model))
    return lam[0]


def critical_velocity_scan(scene: Scene, model, u_grid) -> dict:
    """First U* on ``u_grid`` where the leading growth rate turns positive, refined by Brent."""
    rates = [_growth(model, scene, u).real for u in u_grid]
    for k in range(1, len(u_grid)):
        if rates[k - 1] < 0 <= rates[k]:
            u_c = scipy.optimize.brentq(lambda u: _growth(model, scene, u).real,
                                        u_grid[k - 1], u_grid[k], xtol=1e-10)
            lam = _growth(model, scene, u_c)
            omega = abs(lam.imag)
            return {"mstar": scene.mstar, "ustar_crit": u_c, "omega": omega,
                    "freq_ratio": omega / clamped_free_betas(1)[0] ** 2, "rates": rates}
    return {"mstar": scene.mstar, "ustar_crit": None, "rates": rates}


def run_paper(out="results", quick: bool = False) -> dict:
    """Compute the report and write it (and a figure) to ``out``."""
    start = time.perf_counter()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    scene = PAPER_SCENE
    model = build_model(scene)
    beta = clamped_free_betas(scene.modes)
    steady = steady_state(scene, model)
    u_grid = np.linspace(0.5, 20.0, 14 if quick else 40)
    mstars = [0.1, 1.0, 10.0] if quick else [0.1, 0.3, 1.0, 3.0, 10.0]
    scans = [critical_velocity_scan(scene.replace(mstar=m), model, u_grid) for m in mstars]
    report = {
        "version": __version__,
        "scene": scene.to_dict(),
        "omega_invacuo": (beta**2).tolist(),
        "steady": {"ustar": scene.ustar, "pressure_drop": steady.pressure_drop,
                   "closed_form": straight_pressure_drop(scene), "Q": steady.Q.tolist()},
        "critical": [{k: v for k, v in s.items() if k != "rates"} for s in scans],
        "wall_time": time.perf_counter() - start,
    }
    (out / "report.json").write_text(json.dumps(report, indent=2))
    _plot_scans(u_grid, scans, out / "stability_scan.png")
    return report


def _plot_scans(u_grid, scans, path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4))
    for s in scans:
        ax.plot(u_grid, s["rates"], label=f"M* = {s['mstar']:g}")
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set_xlabel("U*")
    ax.set_ylabel("leading growth rate (1/T)")
    ax.set_title("H* = 1/10, f = 0.14, K0 = 0, KL = 1, N = 10")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
