"""The command line describes itself: the ``meta`` of every JSON (versions, time, command
line, scene, settings, units), what it tells on stderr (progress bars on a terminal only,
``--quiet``, ``--verbose``) and docs/cli.md, generated from the parser."""
import io
import json
import subprocess
import sys
from datetime import datetime, timedelta, timezone
from pathlib import Path

import casadi
import numpy as np
import pytest
import scipy

import fsicas
from fsicas import Scene
from fsicas.cli import build_parser, main
from fsicas.cli.meta import NONDIM
from fsicas.cli.reference import cli_reference

ROOT = Path(__file__).resolve().parents[1]

#: command line -> (scene it describes or None, settings the meta must hold)
CASES = {
    "modes": (["modes", "--modes", "3"], None, {"modes": 3}),
    "steady": (["steady", "--mstar", "2", "--ustar", "3", "--modes", "3"],
               Scene(mstar=2.0, ustar=3.0, modes=3), {}),
    "eig": (["eig", "--ustar", "6", "--modes", "3"], Scene(ustar=6.0, modes=3), {"plot": None}),
    "boundary": (["boundary", "--modes", "3", "--mstar", "1"], Scene(modes=3),
                 {"ustar_max": 40.0, "no_refine": False, "mstar_values": [1.0]}),
    "simulate": (["simulate", "--modes", "3", "--ustar", "4", "--t-end", "0.5"],
                 Scene(ustar=4.0, modes=3), {"t_end": 0.5, "method": "idas",
                                             "integrator": {"method": "idas"}}),
    "lco": (["cycles", "--modes", "3", "--zeta", "0.01", "--max-points", "3"],
            Scene(zeta=0.01, modes=3), {"max_points": 3, "cycle_settings": {"max_points": 3}}),
    "onset": (["onset", "--modes", "3"], Scene(modes=3), {"ustar_max": None}),
}


def run(capsys, argv):
    code = main(argv)
    captured = capsys.readouterr()
    return code, json.loads(captured.out), captured.err


def check_meta(meta: dict, argv: list, scene, settings: dict) -> None:
    assert (meta["fsicas"], meta["casadi"], meta["numpy"], meta["scipy"]) == \
        (fsicas.__version__, casadi.__version__, np.__version__, scipy.__version__)
    created = datetime.fromisoformat(meta["created"])
    assert created.utcoffset() == timedelta(0)
    assert abs(datetime.now(timezone.utc) - created) < timedelta(minutes=5)
    assert meta["command"] == "fsicas " + " ".join(argv)
    assert meta["scene"] == (None if scene is None else scene.to_dict())
    for key, value in settings.items():
        if isinstance(value, dict):
            assert value.items() <= meta["settings"][key].items(), key
        else:
            assert meta["settings"][key] == value, key


@pytest.mark.parametrize("name", sorted(CASES))
def test_every_commands_json_carries_its_meta(capsys, name):
    argv, scene, settings = CASES[name]
    argv = argv + ["--json"]
    code, out, err = run(capsys, argv)
    assert code == 0 and err == ""          # not a terminal: no bars, no stage lines
    meta = out["meta"]
    check_meta(meta, argv, scene, settings)
    units = meta["units"]
    assert set(units) <= set(out), "units of fields the result does not have"
    assert {k for k in out if isinstance(out[k], float)} <= set(units) | {"friction", "hstar", "l1"}
    assert json.loads(json.dumps(meta)) == meta


def test_units_name_the_nondimensional_scales(capsys):
    _, out, _ = run(capsys, ["simulate", "--modes", "3", "--ustar", "4", "--t-end", "0.5", "--json"])
    units = out["meta"]["units"]
    assert NONDIM == "nondimensional (units of L, T = L^2 sqrt(rho_s e / D))"
    assert "units of T = L^2 sqrt(rho_s e / D)" in units["period"]
    assert "units of L" in units["tip_amplitude"] and units["wall_time"] == "seconds"
    _, out, _ = run(capsys, ["steady", "--modes", "3", "--json"])
    assert "D / L^3" in out["meta"]["units"]["pressure_drop"]


def test_map_and_error_json_carry_meta(capsys, tmp_path):
    argv = ["map", "--modes", "3", "--ustar", "4:4:1", "--mstar", "1:1:1", "--t-end", "0.5",
            "--workers", "1", "--out", str(tmp_path / "m.jsonl"), "--json"]
    code, out, err = run(capsys, argv)
    assert code == 0 and err == "" and out["points"] == 1
    from fsicas.timedomain.impact_map import MAP_SCENE
    check_meta(out["meta"], argv, MAP_SCENE.replace(modes=3),
               {"t_end": 0.5, "ustar_values": [4.0], "mstar_values": [1.0]})
    code, out, _ = run(capsys, ["steady", "--mstar", "-1", "--json"])
    assert code == 2 and "mstar" in out["error"]
    assert out["meta"]["scene"] is None and out["meta"]["settings"]["mstar"] == -1.0


def test_lco_out_file_carries_meta_and_still_loads(capsys, tmp_path):
    path = tmp_path / "branch.json"
    argv = ["lco", "--modes", "3", "--zeta", "0.01", "--max-points", "3", "--out", str(path),
            "--json"]
    code, out, _ = run(capsys, argv)
    saved = json.loads(path.read_text())
    check_meta(saved["meta"], argv, Scene(zeta=0.01, modes=3), {"out": str(path)})
    branch = fsicas.CycleBranch.load(path)
    assert [p.ustar for p in branch.points] == [p["ustar"] for p in out["points"]]


def test_progress_is_silent_when_stderr_is_not_a_terminal():
    done = subprocess.run([sys.executable, "-m", "fsicas.cli", "boundary", "--modes", "3",
                           "--mstar", "1", "--json"], capture_output=True, text=True, check=True)
    assert done.stderr == "" and json.loads(done.stdout)["points"]


class Terminal(io.StringIO):
    def isatty(self):
        return True


@pytest.mark.parametrize("quiet", [False, True])
def test_bars_on_a_terminal_unless_quiet(capsys, monkeypatch, tmp_path, quiet):
    """On a terminal the continuation library's bars show (lco) and the impact map's;
    ``--quiet`` hides both; stdout stays one JSON object."""
    extra = ["--quiet"] if quiet else []
    for argv in (["lco", "--modes", "3", "--zeta", "0.01", "--max-points", "3"],
                 ["map", "--modes", "3", "--ustar", "4:4:1", "--mstar", "1:1:1", "--t-end", "0.5",
                  "--workers", "1", "--out", str(tmp_path / "m.jsonl")]):
        (tmp_path / "m.jsonl").unlink(missing_ok=True)
        terminal = Terminal()
        monkeypatch.setattr(sys, "stderr", terminal)
        assert main(argv + extra + ["--json"]) == 0
        json.loads(capsys.readouterr().out)
        shown = terminal.getvalue()
        bar = "cycle continuation" if argv[0] == "lco" else "impact map"
        assert (bar not in shown and "%|" not in shown) if quiet else bar in shown, shown


def test_verbose_tells_stages_and_solver_statistics(capsys):
    code, out, err = run(capsys, ["--verbose", "boundary", "--modes", "3", "--mstar", "1", "--json"])
    lines = err.splitlines()
    assert code == 0 and all(line.startswith("fsicas boundary [") for line in lines)
    assert "stability boundary at 1 M*" in lines[0] and lines[-1].endswith("] done")
    assert any("continuation equilibrium:" in line and "Newton iterations" in line for line in lines)
    code, out, err = run(capsys, ["boundary", "--modes", "3", "--mstar", "1", "--json", "-q"])
    assert code == 0 and err == "" and out["points"]


def test_quiet_silences_the_stage_lines_of_paper(capsys, monkeypatch, tmp_path):
    """``fsicas paper`` announces its stages on stderr by default, not with ``--quiet``;
    its report's meta is the command line's (with the report's fields)."""
    from fsicas.cli import paper
    from fsicas.paper import PAPER_SCENE
    seen = {}

    def fake_run_paper(out, quick, meta, progress):
        seen["meta"] = meta
        progress("Fig. 2 and 3: the flutter boundary")
        return {"version": fsicas.__version__, "meta": {**meta, "fields": {}}}
    monkeypatch.setattr(paper, "run_paper", fake_run_paper)
    for flags, stages in (([], 1), (["--quiet"], 0), (["-v"], 2)):
        argv = ["paper", "--quick", "--out", str(tmp_path), "--json", *flags]
        code, out, err = run(capsys, argv)
        assert code == 0 and len(err.splitlines()) == stages, err
        assert all(line.startswith("fsicas paper [") for line in err.splitlines())
        check_meta(out["meta"], argv, PAPER_SCENE, {"quick": True})
        assert "fields" in out["meta"] and seen["meta"]["command"] == out["meta"]["command"]


def test_global_options_before_or_after_the_command():
    parse = build_parser().parse_args
    assert parse(["--quiet", "eig"]).quiet and parse(["eig", "--quiet"]).quiet
    assert parse(["-v", "lco"]).verbose and not parse(["lco"]).verbose
    with pytest.raises(SystemExit):
        parse(["eig", "--quiet", "--verbose"])


def test_docs_cli_md_is_generated_from_the_parser():
    """docs/cli.md is ``python3 -m fsicas.cli.reference``'s output: regenerate it when an
    option changes. It names every command and option, without reST markup."""
    text = (ROOT / "docs" / "cli.md").read_text()
    assert text == cli_reference(), "docs/cli.md is stale: run python3 -m fsicas.cli.reference"
    assert "``" not in text
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    for name, command in sub.choices.items():
        assert f"## fsicas {name}" in text or f"alias: {name}" in text
        for action in command._actions:
            for option in () if action.dest == "help" else action.option_strings:
                assert f"`{option}" in text, (name, option)


def test_reference_writer_takes_a_file_and_answers_help(tmp_path, monkeypatch, capsys):
    """``python3 -m fsicas.cli.reference FILE`` writes the reference there; ``--help``
    prints the usage and writes nothing."""
    from fsicas.cli.reference import main
    monkeypatch.chdir(tmp_path)
    main(["out.md"])
    assert (tmp_path / "out.md").read_text() == cli_reference()
    with pytest.raises(SystemExit) as exit_:
        main(["--help"])
    assert exit_.value.code == 0 and "usage:" in capsys.readouterr().out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.md"]


def _strict(text: str):
    """``json.loads`` that refuses NaN and Infinity (as strict readers do)."""
    def refuse(token):
        raise AssertionError(f"non-standard JSON token {token}")
    return json.loads(text, parse_constant=refuse)


def test_written_files_hold_no_nan_and_say_where_it_was(tmp_path):
    """A command's --out JSON and a results file write a non-finite number as null; the
    JSON file's warnings name the place."""
    from fsicas.cli.meta import write_json
    from fsicas.results_file import ResultsFile
    args = build_parser().parse_args(["modes", "--modes", "2"])
    write_json(tmp_path / "out.json", {"a": {"b": [1.0, float("nan")]}, "c": float("inf")}, args)
    data = _strict((tmp_path / "out.json").read_text())
    assert data["a"]["b"] == [1.0, None] and data["c"] is None
    assert any("a.b[1]: nan" in w and "c: inf" in w for w in data["warnings"])
    with ResultsFile(tmp_path / "r.jsonl", {"kind": "test"}) as f:
        f.append({"x": float("nan"), "y": 2.0})
    lines = (tmp_path / "r.jsonl").read_text().splitlines()
    assert _strict(lines[-1]) == {"x": None, "y": 2.0}
