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
    # resume: nothing recomputed; a torn last line is ignored and that point redone
    again = impact_map([4.0, 8.0], [1.0], path, scene=SCENE, t_end=10.0, workers=2)
    assert again.computed == 0 and again.points == res.points
    lines = path.read_text().splitlines()
    path.write_text(lines[0] + "\n" + lines[1][:20])
    assert len(load_points(path)) == 1
    third = impact_map([4.0, 8.0], [1.0], path, scene=SCENE, t_end=10.0, workers=1)
    assert third.computed == 1 and {p["outcome"] for p in third.points} == {"decay", "contact"}


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
