"""Impact map: parallel points, results file, resume, linear boundary, CLI."""
import json

import pytest

from fsicas.cli import main
from fsicas.impact_map import MAP_SCENE, impact_map, load_points

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
