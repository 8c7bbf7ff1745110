"""Impact-boundary map in the (U*, M*) plane (paper, Fig. 4).

Every grid point is one classified run (:func:`fsicas.timedomain.run.run_case`) of the contact-free
scene, stopped at the first contact (H* = 1/10, f = 0.14, zeta = 0.01, N = 10 by
default). Points run in parallel in a :class:`concurrent.futures.ProcessPoolExecutor` on
the local cores, or in any ``concurrent.futures`` executor passed in, e.g. a Dask
cluster's ``Client.get_executor()`` (the ``parallel`` extra) for a distributed sweep;
each worker process builds the (guarded) model once per scene structure, since U* and
M* are parameters. A progress bar (tqdm, on a terminal only) counts the points. Each
finished point is appended at once as one JSON line to the results file
(:class:`fsicas.results_file.ResultsFile`: a header with the scene and settings, a lock
against a second run on the same file, a torn last line repaired), so an interrupted map
resumes where it stopped: points already in the file are skipped, and a file written
with another scene, t_end or settings is refused. Local worker processes end with the
map's process, also when it is killed. The linear stability boundary ``U*_c(M*)`` is the first
loss of stability of the steady branch.

A map has one direction of flow: its U* are all >= 0 (forward) or all <= 0 (reversed
flow, from the tip to the root; docs/model.md "Reversed flow"). A reversed map's points
are runs of the reversed scene, its boundary is searched towards negative U*, and its
results file says ``direction = "reverse"`` in its header (so a forward file is never
resumed by a reversed map nor the other way round).
"""
from __future__ import annotations

import contextlib
import dataclasses
import math
import time
from concurrent.futures import Executor
from dataclasses import dataclass
from typing import Literal, Union

import numpy as np
from tqdm import tqdm

from ..linear.hopf import critical_velocity
from ..model.assembly import build_model
from ..checks import check_points
from ..provenance import provenance
from ..results_file import ResultsFile, read_records
from ..workers import finished, local_pool
from .outcome import Criteria, OutcomeKind
from .run import run_case, sweep_model
from ..scene import Scene
from .breathing import PressureSchedule
from .integrators import Settings
from .limits import check_size

__all__ = ["MAP_SCENE", "MapOutcome", "MapResult", "impact_map", "stability_boundary", "load_points",
           "directed"]

MAP_SCENE = Scene(mstar=1.0, ustar=5.0, hstar=0.1, friction=0.14, k0=0.0, kl=1.0, zeta=0.01,
                  modes=10)
#: The ``outcome`` of a map point: an :data:`~fsicas.timedomain.outcome.OutcomeKind`, or
#: "error" when the point could not run (its ``message`` says why).
MapOutcome = Union[OutcomeKind, Literal["error"]]


@dataclass(frozen=True)
class MapResult:
    """Points (dicts with ustar, mstar, outcome: :data:`MapOutcome`, ...) and the linear
    boundary; ``header``: what every point depends on but its (U*, M*) (the results
    file's, :func:`map_header`: scene fields, t_end, integrator settings, criteria);
    ``grid``: the U* and M* values."""

    points: list
    boundary: dict
    wall_time: float
    computed: int
    #: the map's scene (its U* and M* are those of the grid)
    scene: Scene | None = None
    header: dict | None = None
    grid: dict | None = None

    def counts(self) -> dict[MapOutcome, int]:
        out = {}
        for p in self.points:
            out[p["outcome"]] = out.get(p["outcome"], 0) + 1
        return out

    def to_json(self) -> dict:
        described = {k: v for k, v in (self.header or {}).items() if k != "format"}
        return {**described, "grid": self.grid, "points": len(self.points),
                "computed": self.computed, "counts": self.counts(),
                "boundary": self.boundary, "wall_time": self.wall_time}


#: What a map reads back from each record of its results file.
RECORD_FIELDS = {"ustar": (int, float), "mstar": (int, float), "outcome": str}


def _key(ustar: float, mstar: float) -> tuple[float, float]:
    return (round(float(ustar), 10), round(float(mstar), 10))


def load_points(path) -> dict:
    """Points already in a results file, keyed by (U*, M*); a torn last line ignored."""
    return {_key(row["ustar"], row["mstar"]): row for row in read_records(path)[1]
            if "ustar" in row and "mstar" in row}


def map_header(scene: Scene, t_end: float, settings: Settings, criteria: Criteria) -> dict:
    """Everything a map point depends on but its (U*, M*): the results file's header."""
    fields = {k: v for k, v in scene.replace(contact=False).to_dict().items()
              if k not in ("ustar", "mstar")}
    if scene.direction == "reverse":       # forward headers stay those of every forward map
        fields["direction"] = "reverse"
    return {"format": "fsicas-map-1", "scene": fields, "t_end": float(t_end),
            "settings": dataclasses.asdict(settings), "criteria": dataclasses.asdict(criteria),
            "quadrature_tol": "auto"}


def _point(scene: Scene, ustar: float, mstar: float, t_end: float, settings: Settings,
           criteria: Criteria) -> dict:
    scene = scene.replace(ustar=float(ustar), mstar=float(mstar))
    try:
        run = run_case(scene, t_end, settings=settings, criteria=criteria, model=sweep_model(scene))
    except Exception as err:  # a point that cannot run is data, not a crash of the map
        return {"ustar": ustar, "mstar": mstar, "outcome": "error", "message": str(err)}
    row = run.to_json()
    row.update(ustar=float(ustar), mstar=float(mstar))
    return row


def _grid(ustars, mstars, t_end) -> tuple[np.ndarray, np.ndarray]:
    """The grid as float arrays; ValueError for an empty or invalid grid or t_end."""
    ustars, mstars = np.atleast_1d(ustars).astype(float), np.atleast_1d(mstars).astype(float)
    if ustars.size == 0 or mstars.size == 0:
        raise ValueError("ustars and mstars must not be empty")
    if not (np.all(mstars > 0) and np.all(np.isfinite(ustars))):
        raise ValueError("mstars must be > 0 and ustars finite")
    if not (np.any(ustars != 0) and (np.all(ustars >= 0) or np.all(ustars <= 0))):
        raise ValueError("ustars: a map has one direction of flow: all U* >= 0 (forward) or "
                         "all U* <= 0 (reversed flow), at least one nonzero (the map's linear "
                         f"boundary is searched up to 1.5 x the largest |U*|); got {ustars.tolist()}: "
                         "map each direction into its own results file")
    if not t_end > 0:
        raise ValueError(f"t_end must be > 0, got {t_end}")
    return ustars, mstars


def impact_map(ustars, mstars, path, *, scene: Scene = MAP_SCENE, t_end: float = 30.0,
               settings: Settings = Settings(rtol=1e-7, atol=1e-9, dt_out=2e-3, chunk=1.0),
               workers: int | None = None, executor: Executor | None = None,
               progress=None) -> MapResult:
    """Classify every (U*, M*) of the grid; results appended to ``path`` (JSON lines).
    ``ustars``: signed U*, all of one sign (< 0: a reversed map); ``scene``: the other
    fields (its U* and M* are those of the grid). ``workers``: local processes (default: the local cores), unless ``executor`` (any
    ``concurrent.futures.Executor``, e.g. ``dask.distributed.Client(...).get_executor()``)
    is given, which is used as it is and not shut down. ``progress(done, total)`` is
    called after each point.
    """
    ustars, mstars = _grid(ustars, mstars, t_end)
    check_points(ustars.size * mstars.size, "the map", "give fewer U* or M* values, or "
                 "split the map into several runs (each with its own --out)")
    check_size(2 * scene.modes + 2, t_end, settings.dt_out, PressureSchedule())
    if workers is not None and not (isinstance(workers, int) and workers >= 1):
        raise ValueError(f"workers must be an integer >= 1 (or None: the local cores), got {workers!r}")
    start = time.perf_counter()
    criteria = Criteria(stop_on_contact=True)
    base = directed(scene, ustars).replace(contact=False)
    header = map_header(base, t_end, settings, criteria)
    with ResultsFile(path, header, provenance(), fields=RECORD_FIELDS) as out, \
            contextlib.ExitStack() as stack:
        done = {_key(row["ustar"], row["mstar"]): row for row in out.records}
        todo = [(u, m) for m in mstars for u in ustars if _key(u, m) not in done]
        if executor is None and todo:
            executor = stack.enter_context(local_pool(workers))
        futures = [executor.submit(_point, base, u, m, t_end, settings, criteria) for u, m in todo]
        bar = stack.enter_context(tqdm(total=len(todo), desc="impact map", unit="point", disable=None))
        for k, row in enumerate(finished(futures, path), start=1):
            out.append(row)
            done[_key(row["ustar"], row["mstar"])] = row
            bar.update()
            if progress:
                progress(k, len(todo))
    points = [done[_key(u, m)] for m in mstars for u in ustars]
    boundary = stability_boundary(scene, mstars, ustars)
    return MapResult(points, boundary, time.perf_counter() - start, len(todo), base, header,
                     {"ustar": ustars.tolist(), "mstar": mstars.tolist()})


def directed(scene: Scene, ustars) -> Scene:
    """``scene`` with the direction of the map's U* grid (``ustars``, of one sign): its
    speed |U*| kept, its sign that of the grid."""
    sign = -1.0 if np.any(np.asarray(ustars) < 0) else 1.0
    return scene.replace(ustar=math.copysign(abs(scene.ustar), sign))


def stability_boundary(scene: Scene, mstars, ustars) -> dict:
    """Critical U* per M* of the contact-free model: the onset of the steady branch
    (:func:`fsicas.linear.hopf.critical_velocity`: a Hopf point, or divergence), searched
    in the direction of the map's U* (``ustars``, of one sign) up to 1.5 x their largest
    |U*|; signed (< 0 for a reversed map)."""
    base = directed(scene, ustars).replace(contact=False)
    model = build_model(base)
    u_max = 1.5 * float(np.max(np.abs(ustars)))
    out = {"mstar": [], "ustar_crit": [], "omega": []}
    for m in mstars:
        h = critical_velocity(base.replace(mstar=float(m)), model, ustar_max=u_max)
        out["mstar"].append(float(m))
        out["ustar_crit"].append(None if h is None else h.ustar)
        out["omega"].append(None if h is None else h.omega)
    return out
