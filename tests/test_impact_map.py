"""Impact map: parallel points, results file, resume, linear boundary, CLI."""
import json

import pytest

from fsicas.cli import main
from fsicas.timedomain.impact_map import MAP_SCENE, impact_map, load_points

SCENE = MAP_SCENE.replace(modes=6)


def test_map_points_resume_and_boundary(tmp_path):
    path = tmp_path / "map.jsonl"
    res = impact_map([4.0, 8.0], [1.0], path, scene=SCENE, t_end=10.0, workers=2)
    assert res.computed == 2 and len(res.points) == 2
    by_u = {p["ustar"]: p["outcome"] for p in res.points}
    assert by_u[4.0] == "decay"                  # below U*_c (about 5.6 at M* = 1)
    assert by_u[8.0] == "contact"                # paper Fig. 4: M* = 1, U* >= 7 impacts
    u_c = res.boundary["ustar_crit"][0]
    assert 4.0 < u_c < 8.0
    # resume: nothing recomputed; a torn last line is cut off and that point redone
    again = impact_map([4.0, 8.0], [1.0], path, scene=SCENE, t_end=10.0, workers=2)
    assert again.computed == 0 and again.points == res.points
    lines = path.read_text().splitlines()
    assert len(lines) == 3 and "header" in json.loads(lines[0])
    path.write_text(lines[0] + "\n" + lines[1] + "\n" + lines[2][:20])
    assert len(load_points(path)) == 1
    third = impact_map([4.0, 8.0], [1.0], path, scene=SCENE, t_end=10.0, workers=1)
    assert third.computed == 1 and {p["outcome"] for p in third.points} == {"decay", "contact"}
    rows = [json.loads(line) for line in path.read_text().splitlines()]   # all whole
    assert len(rows) == 3 and "header" in rows[0]


def test_map_bad_grid():
    with pytest.raises(ValueError, match="mstars"):
        impact_map([4.0], [-1.0], "unused.jsonl")


def test_cli_map_json(tmp_path, capsys):
    out_file = tmp_path / "m.jsonl"
    code = main(["map", "--ustar", "4:4:1", "--mstar", "1:1:1", "--modes", "4", "--t-end", "5",
                 "--workers", "1", "--out", str(out_file), "--plot", str(tmp_path / "m.png"), "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["points"] == 1 and out["counts"] == {"decay": 1}
    assert (tmp_path / "m.png").exists()


def test_map_on_a_given_executor_matches_local_processes(tmp_path):
    """Any concurrent.futures executor runs the points (here threads; a Dask cluster's
    ``Client.get_executor()`` in a distributed sweep) with the same outcomes."""
    from concurrent.futures import ThreadPoolExecutor
    grid = ([4.0, 8.0], [1.0])
    local = impact_map(*grid, tmp_path / "a.jsonl", scene=SCENE, t_end=10.0, workers=2)
    with ThreadPoolExecutor(max_workers=1) as pool:
        given = impact_map(*grid, tmp_path / "b.jsonl", scene=SCENE, t_end=10.0, executor=pool)
    assert [p["outcome"] for p in given.points] == [p["outcome"] for p in local.points]
    assert given.points[1]["first_contact_time"] == pytest.approx(local.points[1]["first_contact_time"],
                                                                  rel=1e-9)


def test_map_on_a_dask_cluster(tmp_path):
    """The ``parallel`` extra: a local Dask cluster (skipped when Dask is not installed)."""
    distributed = pytest.importorskip("distributed")
    with distributed.Client(processes=False, n_workers=1, threads_per_worker=1,
                            dashboard_address=None) as client:
        res = impact_map([4.0], [1.0], tmp_path / "d.jsonl", scene=SCENE, t_end=10.0,
                         executor=client.get_executor())
    assert [p["outcome"] for p in res.points] == ["decay"]


def test_cli_map_on_a_dask_scheduler(tmp_path, capsys):
    """``fsicas map --dask ADDRESS`` sends the points to a running Dask scheduler."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(processes=False, n_workers=1, threads_per_worker=1,
                                  dashboard_address=None) as cluster:
        code = main(["map", "--ustar", "4:4:1", "--mstar", "1:1:1", "--modes", "4", "--t-end", "5",
                     "--dask", cluster.scheduler_address, "--out", str(tmp_path / "m.jsonl"), "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["computed"] == 1 and out["points"] == 1


def _header_file(path, scene=SCENE, t_end=10.0, points=()):
    """A results file as a map of ``scene`` and ``t_end`` writes it."""
    from fsicas.timedomain.impact_map import map_header
    from fsicas.timedomain.integrators import Settings
    from fsicas.timedomain.outcome import Criteria
    header = map_header(scene, t_end, Settings(rtol=1e-7, atol=1e-9, dt_out=2e-3, chunk=1.0),
                        Criteria(stop_on_contact=True))
    path.write_text("\n".join(json.dumps(r) for r in [{"header": header}, *points]) + "\n")


@pytest.mark.parametrize("change, named", [
    (dict(scene=SCENE.replace(modes=4)), "modes = 4 here 6"),
    (dict(scene=SCENE.replace(zeta=0.02)), "zeta = 0.02 here 0.01"),
    (dict(t_end=20.0), "t_end: file 20.0 here 10.0"),
])
def test_resume_refuses_a_file_of_other_settings_before_work(tmp_path, change, named):
    """A results file written with other modes, damping or t_end is refused, naming what
    differs, before any point runs (no executor is started: a tripwire executor)."""
    path = tmp_path / "map.jsonl"
    _header_file(path, points=[{"ustar": 4.0, "mstar": 1.0, "outcome": "decay"}], **change)
    before = path.read_text()

    class Tripwire:
        def submit(self, *args, **kwargs):
            raise AssertionError("a point was submitted")
    with pytest.raises(ValueError, match=f"other settings .*{named}"):
        impact_map([4.0, 8.0], [1.0], path, scene=SCENE, t_end=10.0, executor=Tripwire())
    assert path.read_text() == before


def test_resume_refuses_records_without_a_header(tmp_path):
    path = tmp_path / "map.jsonl"
    path.write_text(json.dumps({"ustar": 4.0, "mstar": 1.0, "outcome": "decay"}) + "\n")
    with pytest.raises(ValueError, match="no header"):
        impact_map([4.0], [1.0], path, scene=SCENE, t_end=10.0, workers=1)


def test_second_run_on_the_same_file_is_refused_while_the_first_holds_it(tmp_path):
    """The lock: while one run holds the file, another is refused at once."""
    from fsicas.results_file import ResultsFile, read_records
    path = tmp_path / "map.jsonl"
    _header_file(path)
    with ResultsFile(path, read_records(path)[0]):
        with pytest.raises(ValueError, match="being written by another run"):
            impact_map([4.0], [1.0], path, scene=SCENE, t_end=10.0, workers=1)
    with ResultsFile(path, read_records(path)[0]) as again:      # released on exit
        assert again.records == []


def _alive(pid: int) -> bool:
    """Whether process ``pid`` exists and is not a zombie (Linux /proc)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.skipif(not __import__("os").path.exists("/proc/self/task"), reason="Linux /proc")
def test_workers_die_with_a_killed_map(tmp_path, monkeypatch):
    """kill -9 of a process whose pool workers run the map's initializer also ends a
    worker that is busy computing (without it the worker computes on as an orphan); the
    map's local pool uses that initializer."""
    import os
    import signal
    import subprocess
    import sys
    import time
    import importlib
    module = importlib.import_module("fsicas.workers")
    script = ("import os, time\n"
              "from concurrent.futures import ProcessPoolExecutor\n"
              "from fsicas.workers import die_with_parent\n"
              "def busy(x):\n"
              "    t = time.time()\n"
              "    while time.time() - t < 120:\n"
              "        sum(range(10000))\n"
              "if __name__ == '__main__':\n"
              "    with ProcessPoolExecutor(1, initializer=die_with_parent,\n"
              "                             initargs=(os.getpid(),)) as pool:\n"
              "        pool.submit(busy, 1).result()\n")
    (tmp_path / "busy.py").write_text(script)
    parent = subprocess.Popen([sys.executable, str(tmp_path / "busy.py")])
    children_file = f"/proc/{parent.pid}/task/{parent.pid}/children"
    workers, deadline = [], time.time() + 60
    while not workers and time.time() < deadline:
        time.sleep(0.2)
        with open(children_file) as f:
            workers = [int(c) for c in f.read().split()]
    assert workers, "the pool started no worker"
    time.sleep(1.0)                               # the worker is computing
    os.kill(parent.pid, signal.SIGKILL)
    parent.wait()
    deadline = time.time() + 10
    while any(_alive(w) for w in workers) and time.time() < deadline:
        time.sleep(0.1)
    survivors = [w for w in workers if _alive(w)]
    for w in survivors:                           # never leave an orphan behind
        os.kill(w, signal.SIGKILL)
    assert not survivors, "the worker outlived its map"

    used = {}

    class Pool:
        def __init__(self, **kwargs):
            used.update(kwargs)
            raise RuntimeError("pool created")
    monkeypatch.setattr(module, "ProcessPoolExecutor", Pool)
    with pytest.raises(RuntimeError, match="pool created"):
        importlib.import_module("fsicas.timedomain.impact_map").impact_map(
            [4.0], [1.0], tmp_path / "m.jsonl", scene=SCENE, t_end=1.0, workers=1)
    assert used["initializer"] is module.die_with_parent and used["initargs"] == (os.getpid(),)


def test_results_file_records_what_wrote_it_without_comparing_it_on_resume(tmp_path):
    """A new map file's first line carries the versions and the time beside its header;
    a resume from a file written at another time (other ``written_by``) is accepted."""
    from fsicas.results_file import ResultsFile, read_records
    path = tmp_path / "m.jsonl"
    header = {"format": "x", "t_end": 1.0}
    with ResultsFile(path, header, {"fsicas": "0.1.0", "created": "2026-01-01T00:00:00+00:00"}) as f:
        f.append({"ustar": 1.0})
    first = json.loads(path.read_text().splitlines()[0])
    assert first["written_by"]["fsicas"] == "0.1.0" and first["header"] == header
    with ResultsFile(path, header, {"fsicas": "9.9", "created": "2027-01-01T00:00:00+00:00"}) as f:
        assert f.records == [{"ustar": 1.0}]
    assert read_records(path)[0] == header


def test_reversed_map_matches_separate_simulate_runs(tmp_path, capsys):
    """``fsicas map --direction reverse``: each point of a tiny reversed grid (M* = 1,
    below and above the reversed onset, divergence at U* = -0.45) has the outcome and
    first-contact time of a separate ``fsicas simulate --direction reverse`` run (its own
    integrator tolerances), the boundary is the reversed onset of ``onset``, the plot is
    written, and the results file is refused by a forward map of the same points."""
    common = ["--mstar", "1", "--modes", "6", "--t-end", "30"]
    out_file = tmp_path / "rev.jsonl"
    code = main(["map", "--direction", "reverse", "--ustar", "0.3,0.8", *common, "--workers", "1",
                 "--out", str(out_file), "--plot", str(tmp_path / "rev.png"), "--json"])
    mapped = json.loads(capsys.readouterr().out)
    assert code == 0 and mapped["grid"]["ustar"] == [-0.3, -0.8]
    assert mapped["scene"]["direction"] == "reverse" and (tmp_path / "rev.png").exists()
    points = {p["ustar"]: p for p in load_points(out_file).values()}
    scene = ["--hstar", "0.1", "--friction", "0.14", "--k0", "0", "--kl", "1", "--zeta", "0.01"]
    for speed in (0.3, 0.8):
        assert main(["simulate", "--direction", "reverse", "--ustar", str(speed), *scene,
                     *common, "--json"]) == 0
        alone = json.loads(capsys.readouterr().out)
        assert points[-speed]["outcome"] == alone["outcome"]
        if alone["outcome"] == "contact":
            assert points[-speed]["first_contact_time"] == pytest.approx(
                alone["first_contact_time"], rel=1e-3)
    assert {p["outcome"] for p in points.values()} == {"decay", "contact"}
    assert main(["onset", "--direction", "reverse", *scene, "--mstar", "1", "--modes", "6",
                 "--json"]) == 0
    onset = json.loads(capsys.readouterr().out)
    assert mapped["boundary"]["ustar_crit"][0] == pytest.approx(onset["ustar_crit"], rel=1e-6)
    assert -0.8 < onset["ustar_crit"] < -0.3
    with pytest.raises(ValueError, match="direction"):
        impact_map([0.3, 0.8], [1.0], out_file, scene=SCENE, t_end=30.0, workers=1)


def test_map_refuses_a_grid_of_both_directions():
    with pytest.raises(ValueError, match="one direction"):
        impact_map([-1.0, 1.0], [1.0], "unused.jsonl")
