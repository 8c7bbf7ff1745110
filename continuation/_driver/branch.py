"""The result of a continuation: points, stability, special points, statistics.

Plain data with NumPy columns; ``save``/``load`` use one ``.npz`` file holding
arrays plus a JSON header (no pickling).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

FORMAT = "continuation.Branch/1"

#: why a continuation run ended (``Branch.status``):
#: 'max_steps' (``settings.max_steps`` points computed), 'bound' (a free parameter
#: left ``settings.bounds``), 'failed' (the corrector failed at ``ds_min``, the start
#: point did not converge), 'event' (a terminal :class:`Event` was located; the
#: branch ends at it), 'stopped' (the ``stop`` predicate returned True or a message, or a
#: kind of ``ContinuationSettings.stop_at`` was found)
Status = Literal["max_steps", "bound", "failed", "event", "stopped"]

#: special-point kinds of the built-in problems (user events may not reuse them)
BUILTIN_KINDS = ("fold", "hopf", "bp", "bt", "gh", "hh", "zh", "pd", "ns", "lpc", "cpc", "r1",
                 "r2", "r3", "r4", "lppd", "lpns", "pdns", "nsns", "gpd", "ch")


@dataclass(frozen=True)
class SpecialPoint:
    """A special point between points ``index - 1`` and ``index`` of a branch.

    kind : 'fold', 'hopf', 'bp' (equilibria); 'bt', 'gh', 'hh', 'zh' (curves);
        'fold', 'pd', 'ns' (cycles); 'cpc', 'gpd', 'ch', 'r1'..'r4', 'lppd', 'lpns', 'pdns', 'nsns',
        'lpc', 'pd', 'ns' (curves of cycles, ``cycle_curves``); or the name of a user
        :class:`Event`.
    status : 'converged' (located and refined to tolerance) or 'guess'.
    precision : residual of the refining Newton solve, or the arclength
        bracket of the location when not refined.
    data : scalar characteristics, e.g. ``omega`` and ``l1`` at a Hopf point, the
        ``bracket``; the real scalar values of the ``record`` callback at the point;
        for user events also ``s`` (arclength from point ``index - 1``) and
        ``value`` (the event function there).
    record : everything the ``record`` callback returned at the point, arrays
        included (not saved by ``to_json``/``Branch.save``: its scalars are in ``data``).
    unknowns : the problem's unknowns ``X`` at the point (empty when not known).
    tangent : the branch's unit tangent in those unknowns at the branch point before it
        (not at the point: at a branch point it is undefined; empty when not known;
        branch switching tells the branch it came along from the one it leaves on).
    """

    kind: str
    index: int
    x: np.ndarray
    params: dict
    status: str
    precision: float
    data: dict = field(default_factory=dict)
    message: str = ""
    record: dict = field(default_factory=dict, repr=False, compare=False)
    unknowns: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False, compare=False)
    tangent: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False, compare=False)

    def to_json(self) -> dict:
        return {"kind": self.kind, "index": self.index, "params": self.params,
                "status": self.status, "precision": self.precision,
                "data": self.data, "message": self.message}


@dataclass(frozen=True)
class Branch:
    """Points of a continued curve and what was found along it.

    x : (N, n) states; params : (N, k) parameter values (columns ``par_names``);
    s : arclength; ds : step that reached each point; iterations, residual :
    Newton work and final residual per point; eigenvalues : list of N arrays of
    generalized eigenvalues (sorted by decreasing real part); tests : test
    function columns (and the values of the user events, under their names);
    columns : problem-specific columns (e.g. ``period``) and those of the
    ``record`` callback; status : why the run stopped, a :data:`Status`
    ('max_steps', 'bound', 'failed', 'event', 'stopped'); message : says why in
    words; failure : residual, iterations and ds of a failed corrector; stats :
    solver statistics.
    """

    kind: str
    par_names: tuple
    free: tuple
    x: np.ndarray
    params: np.ndarray
    s: np.ndarray
    ds: np.ndarray
    iterations: np.ndarray
    residual: np.ndarray
    eigenvalues: list
    tests: dict
    columns: dict
    special_points: list
    status: Status
    message: str
    failure: dict = field(default_factory=dict)
    stats: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return self.x.shape[0]

    def par(self, name: str) -> np.ndarray:
        """Column of parameter ``name``."""
        if name not in self.par_names:
            raise ValueError(f"unknown parameter {name!r}; known: {self.par_names}")
        return self.params[:, self.par_names.index(name)]

    @property
    def n_unstable(self) -> np.ndarray:
        """Number of eigenvalues with positive real part at each point (for
        cycles: non-trivial Floquet multipliers outside the unit circle)."""
        if "n_unstable" in self.tests:
            return self.tests["n_unstable"].astype(int)
        return np.array([int(np.sum(ev.real > 0)) for ev in self.eigenvalues])

    @property
    def stable(self) -> np.ndarray:
        """True where all computed eigenvalues have negative real part."""
        return self.n_unstable == 0

    def special(self, kind: str) -> list:
        """Special points of one kind."""
        return [p for p in self.special_points if p.kind == kind]

    # -- file I/O ---------------------------------------------------------------
    def save(self, path) -> None:
        """Write the branch to ``path`` (.npz with a JSON header)."""
        save_npz(path, *self.to_arrays())

    @classmethod
    def load(cls, path) -> "Branch":
        """Read a branch written by :meth:`save`."""
        return cls.from_arrays(*load_npz(path, FORMAT))

    def to_arrays(self) -> tuple[dict, dict]:
        """``(header, arrays)``: the branch as a JSON-ready header and named NumPy arrays
        (what :meth:`save` writes; a file of several branches prefixes the names)."""
        sizes = np.array([ev.size for ev in self.eigenvalues], dtype=int)
        flat = np.concatenate(self.eigenvalues) if self.eigenvalues else np.zeros(0, complex)
        arrays = {"x": self.x, "params": self.params, "s": self.s, "ds": self.ds,
                  "iterations": self.iterations, "residual": self.residual,
                  "eig_sizes": sizes, "eig_values": flat.astype(complex),
                  "sp_x": np.array([p.x for p in self.special_points]).reshape(
                      len(self.special_points), self.x.shape[1])}
        arrays.update({f"test_{k}": v for k, v in self.tests.items()})
        arrays.update({f"col_{k}": v for k, v in self.columns.items()})
        header = {"format": FORMAT, "kind": self.kind, "par_names": list(self.par_names),
                  "free": list(self.free), "status": self.status, "message": self.message,
                  "failure": {k: v for k, v in self.failure.items() if k != "X"},
                  "stats": self.stats, "special_points":
                      [p.to_json() for p in self.special_points]}
        return header, arrays

    @classmethod
    def from_arrays(cls, header: dict, arr: dict) -> "Branch":
        """The branch of :meth:`to_arrays`' ``(header, arrays)``."""
        splits = np.cumsum(arr["eig_sizes"])[:-1]
        eigs = list(np.split(arr["eig_values"], splits)) if arr["eig_sizes"].size else []
        sps = [SpecialPoint(d["kind"], d["index"], arr["sp_x"][i], d["params"],
                            d["status"], d["precision"], d["data"], d["message"])
               for i, d in enumerate(header["special_points"])]
        pick = lambda prefix: {k[len(prefix):]: v for k, v in arr.items()  # noqa: E731
                               if k.startswith(prefix)}
        return cls(header["kind"], tuple(header["par_names"]), tuple(header["free"]),
                   arr["x"], arr["params"], arr["s"], arr["ds"], arr["iterations"],
                   arr["residual"], eigs, pick("test_"), pick("col_"), sps,
                   header["status"], header["message"], header["failure"],
                   header["stats"])


def save_npz(path, header: dict, arrays: dict) -> None:
    """``arrays`` and the JSON ``header`` in one ``.npz`` file (no pickling)."""
    with open(path, "wb") as fh:
        np.savez(fh, header=np.array(json.dumps(header)), **arrays)


def load_npz(path, fmt: str) -> tuple[dict, dict]:
    """``(header, arrays)`` of a file of :func:`save_npz` whose header's format is ``fmt``."""
    with np.load(path, allow_pickle=False) as data:
        header = json.loads(str(data["header"]))
        if header.get("format") != fmt:
            raise ValueError(f"{path} is not a {fmt} file")
        return header, {k: data[k] for k in data.files if k != "header"}
