"""Impact-boundary map in the (U*, M*) plane (paper, Fig. 4).

Every grid point is one classified run (:func:`fsicas.run.run_case`) of the contact-free
scene, stopped at the first contact (H* = 1/10, f = 0.14, zeta = 0.01, N = 10 by
default). Points run in parallel in a :class:`concurrent.futures.ProcessPoolExecutor`;
each worker builds the (guarded) model once, since U* and M* are parameters and the
structure is shared. Each finished point is appended at once as one JSON line to the
results file, so an interrupted map resumes where it stopped: points already in the file
are skipped. The linear stability boundary ``U*_c(M*)`` is the first Hopf point of the steady branch.
"""
from __future__ import annotations

import json
import os
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .hopf import critical_velocity
from .model import build_model
from .outcome import Criteria
from .run import guarded_model, run_case
from .scene import Scene
from .simulate import Settings

__all__ = ["MAP_SCENE", "MapResult", "impact_map", "stability_boundary", "load_points"]

MAP_SCENE = Scene(mstar=1.0, ustar=5.0, hstar=0.1, friction=0.14, k0=0.0, kl=1.0, zeta=0.01,
                  modes=10)
_WORKER = {}


@dataclass(frozen=True)
class MapResult:
    """Points (dicts with ustar, mstar, outcome, ...) and the linear boundary."""

    points: list
    boundary: dict
    wall_time: float
    computed: int

    def counts(self) -> dict:
        out = {}
        for p in self.points:
            out[p["outcome"]] = out.get(p["outcome"], 0) + 1
        return out

    def to_json(self) -> dict:
        return {"points": len(self.points), "computed": self.computed, "counts": self.counts(),
                "boundary": self.boundary, "wall_time": self.wall_time}


def _key(ustar: float, mstar: float) -> tuple[float, float]:
    return (round(float(ustar), 10), round(float(mstar), 10))


def load_points(path) -> dict:
    """Points already in a results file, keyed by (U*, M*); broken last lines ignored."""
    done = {}
    path = Path(path)
    if not path.exists():
        return done
    for line in path.read_text().splitlines():
        try:
            row = json.loads(line)
            done[_key(row["ustar"], row["mstar"])] = row
        except (json.JSONDecodeError, KeyError):
            continue
    return done


def _init(scene, t_end, settings, criteria):
    _WORKER.update(scene=scene, t_end=t_end, settings=settings, criteria=criteria,
                   model=guarded_model(scene)[0])


def _point(ustar: float, mstar: float) -> dict:
    w = _WORKER
    scene = w["scene"].replace(ustar=float(ustar), mstar=float(mstar))
    try:
        run = run_case(scene, w["t_end"], settings=w["settings"], criteria=w["criteria"],
                       model=w["model"])
    except Exception as err:  # a point that cannot run is data, not a crash of the map
        return {"ustar": ustar, "mstar": mstar, "outcome": "error", "message": str(err)}
    row = run.to_json()
    row.update(ustar=float(ustar), mstar=float(mstar))
    return row


def impact_map(ustars, mstars, path, *, scene: Scene = MAP_SCENE, t_end: float = 30.0,
               settings: Settings = Settings(rtol=1e-7, atol=1e-9, dt_out=2e-3, chunk=1.0),
               workers: int | None = None, progress=None) -> MapResult:
    """Classify every (U*, M*) of the grid; results appended to ``path`` (JSON lines).

    ``workers``: processes (default: the local cores). ``progress(done, total)`` is
    called after each point.
    """
    ustars, mstars = np.atleast_1d(ustars).astype(float), np.atleast_1d(mstars).astype(float)
    if ustars.size == 0 or mstars.size == 0:
        raise ValueError("ustars and mstars must not be empty")
    if not (np.all(mstars > 0) and np.all(np.isfinite(ustars))):
        raise ValueError("mstars must be > 0 and ustars finite")
    if not t_end > 0:
        raise ValueError(f"t_end must be > 0, got {t_end}")
    start = time.perf_counter()
    criteria = Criteria(stop_on_contact=True)
    done = load_points(path)
    todo = [(u, m) for m in mstars for u in ustars if _key(u, m) not in done]
    workers = workers or os.cpu_count() or 1
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a") as out, ProcessPoolExecutor(
            max_workers=workers, initializer=_init,
            initargs=(scene.replace(contact=False), t_end, settings, criteria)) as pool:
        futures = [pool.submit(_point, u, m) for u, m in todo]
        for k, fut in enumerate(as_completed(futures), start=1):
            row = fut.result()
            out.write(json.dumps(row) + "\n")
            out.flush()
            done[_key(row["ustar"], row["mstar"])] = row
            if progress:
                progress(k, len(todo))
    points = [done[_key(u, m)] for m in mstars for u in ustars]
    boundary = stability_boundary(scene, mstars, ustars)
    return MapResult(points, boundary, time.perf_counter() - start, len(todo))


def stability_boundary(scene: Scene, mstars, ustars) -> dict:
    """Critical U* per M* of the contact-free model: the first Hopf point of the steady
    branch (:func:`fsicas.hopf.critical_velocity`), searched up to 1.5 x the largest U*
    of the map."""
    base = scene.replace(contact=False)
    model = build_model(base)
    u_max = 1.5 * float(np.max(ustars))
    out = {"mstar": [], "ustar_crit": [], "omega": []}
    for m in mstars:
        h = critical_velocity(base.replace(mstar=float(m)), model, ustar_max=u_max)
        out["mstar"].append(float(m))
        out["ustar_crit"].append(None if h is None else h.ustar)
        out["omega"].append(None if h is None else h.omega)
    return out
