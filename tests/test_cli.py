"""Command-line contract: one JSON object on stdout, clear errors."""
import json
import subprocess
import sys

import numpy as np
import pytest

import fsicas
from fsicas.cli import main
from fsicas.cli.ranges import parse_range


def run_json(capsys, argv):
    code = main(argv)
    out = capsys.readouterr().out
    return code, json.loads(out)


def test_modes_json(capsys):
    code, out = run_json(capsys, ["modes", "--modes", "4", "--json"])
    assert code == 0 and set(out) - {"meta"} == {"beta", "omega"}
    assert out["beta"][0] == pytest.approx(1.875104068711961, rel=1e-13)
    assert np.allclose(out["omega"], np.square(out["beta"]), rtol=1e-15)


def test_steady_json_matches_the_closed_form(capsys):
    code, out = run_json(capsys, ["steady", "--mstar", "2", "--ustar", "3", "--modes", "5", "--json"])
    assert code == 0 and set(out) - {"meta"} == {"pressure_drop", "Q", "q", "tip_deflection", "x_ref"}
    assert out["pressure_drop"] == pytest.approx(2 * 9 * (0.5 + 2 * 0.14 / 0.1), rel=1e-14)
    assert out["Q"] == pytest.approx([0.15, 0.15], rel=1e-14) and len(out["q"]) == 5


def test_scene_file_with_overrides(capsys):
    code, out = run_json(capsys, ["steady", "--scene", "examples/asymmetric.toml", "--ustar", "3",
                                  "--json"])
    assert code == 0
    assert (out["Q"][0] + out["Q"][1]) / 0.1 == pytest.approx(3.0, rel=1e-13)
    from fsicas import build_model, load_scene, steady_state
    scene = load_scene("examples/asymmetric.toml", ustar=3.0)
    model = build_model(scene)
    assert out["tip_deflection"] == pytest.approx(model.deflection(steady_state(scene, model).x, [1.0])[0],
                                                  rel=1e-12)


def test_bad_option_gives_a_json_error_and_exit_code(capsys):
    code, out = run_json(capsys, ["steady", "--mstar", "-1", "--json"])
    assert code == 2 and "mstar" in out["error"]


def test_console_script_prints_only_json():
    done = subprocess.run([sys.executable, "-m", "fsicas.cli", "modes", "--modes", "2", "--json"],
                          capture_output=True, text=True, check=True)
    assert json.loads(done.stdout)["omega"][1] == pytest.approx(22.03449156466, rel=1e-10)


def test_paper_quick_writes_report(tmp_path, capsys):
    code = main(["paper", "--quick", "--out", str(tmp_path), "--json"])
    captured = capsys.readouterr()
    out = json.loads(captured.out)
    assert code == 0
    stages = [line for line in captured.err.splitlines() if line.startswith("fsicas paper [")]
    assert [s.split("] ", 1)[1].split(":")[0] for s in stages] == \
        ["Fig. 2 and 3", "Fig. 4", "Figs. 6-9",          # each stage announced on stderr,
         "impacting cycle 1/2", "impacting cycle 2/2"]    # and each impacting run when done
    assert out["steady"]["pressure_drop"] == pytest.approx(out["steady"]["closed_form"], rel=1e-14)
    for name in ("report.json", "fig2_boundary.png", "fig3_modes.png"):
        assert (tmp_path / name).exists()
    meta = out["meta"]
    assert {"created", "fsicas", "casadi", "command", "fields"} <= set(meta)
    assert set(out) - {"version", "meta"} <= set(meta["fields"])   # every field explained
    assert set(meta["units"]) <= set(out)           # and no unit of a field not written
    # each result holds its own scene (none is the report's): Fig. 4 at zeta = 0.01 (the
    # paper's), the cycle with the modes and contact law it was run with
    assert meta["scene"] is None and "scene" not in out
    assert out["steady"]["scene"]["ustar"] == out["steady"]["ustar"]
    assert out["boundary"]["scene"]["zeta"] == 0 and "mstar" not in out["boundary"]["scene"]
    assert out["boundary"]["mstar_values"] == pytest.approx(np.logspace(-1, 1, 7))
    fig4 = out["impact_map"]
    assert fig4["scene"]["zeta"] == 0.01 and fig4["t_end"] == 5.0
    assert fig4["grid"] == {"ustar": [4.0, 9.0], "mstar": [1.0]}
    points = out["boundary"]["points"]
    assert len(points) == 7 and all(p["refined"] and p["omega"] > 0 for p in points)
    assert out["boundary"]["switches"]
    # time domain (Fig. 4, Figs. 6-9): below onset decays, above it reaches the wall
    from fsicas.timedomain.impact_map import load_points
    outcomes = {p["ustar"]: p["outcome"] for p in load_points(tmp_path / "fig4_map.jsonl").values()}
    assert outcomes == {4.0: "decay", 9.0: "contact"}
    assert (tmp_path / "fig4_impact_map.png").exists()
    assert [c["contact"] for c in out["impacting_cycles"]] == [True]
    (cycle,) = out["impacting_cycles"]       # with its truncation against half the modes
    from fsicas.timedomain.impacting_run import TRUNCATION_MEASURES
    assert cycle["truncation_modes"] == 3 and set(cycle["truncation_error"]) == \
        set(TRUNCATION_MEASURES)
    ran = fsicas.Scene.from_dict(cycle["scene"])
    assert (ran.modes, ran.ustar, ran.contact, ran.contact_stiffness, ran.contact_eps, ran.zeta) \
        == (6, 8.5, True, cycle["contact_stiffness"], cycle["contact_eps"], 0.01)
    assert [w for w in out["warnings"] if w.startswith("impacting cycle U* = 8.5")] == \
        [w for w in out["warnings"] if any(w.endswith(c) for c in cycle["warnings"])]
    assert len(out["warnings"]) == len(out["boundary"]["warnings"]) + len(cycle["warnings"])
    # the terminal summary repeats the report's numbers
    from fsicas.paper import summary
    short = summary(out)
    assert short["boundary points"] == 7 and short["impact map (Fig. 4)"] == "1 decay, 1 contact"
    assert short["U*_c at M* = 1"] == next(p["ustar_crit"] for p in points if p["mstar"] == 1.0)


def test_eig_json_is_sorted_and_flags_instability(capsys):
    code, out = run_json(capsys, ["eig", "--mstar", "1", "--ustar", "6", "--modes", "6", "--json"])
    assert code == 0 and len(out["eigenvalues"]) == 14
    re = [e[0] for e in out["eigenvalues"]]
    assert re == sorted(re, reverse=True) and out["stable"] == (re[0] < 0)


def test_boundary_json(capsys):
    code, out = run_json(capsys, ["boundary", "--modes", "6", "--mstar", "0.5,1,2", "--json"])
    assert code == 0 and [p["mstar"] for p in out["points"]] == [0.5, 1.0, 2.0]
    for p in out["points"]:
        assert set(p) >= {"mstar", "ustar_crit", "omega", "freq_ratio", "branch"}


def test_boundary_rejects_bad_ranges(capsys):
    code, out = run_json(capsys, ["boundary", "--mstar", "0:10:5", "--json"])
    assert code == 2 and "mstar" in out["error"]


def test_bad_mstar_grids_fail_clearly():
    """(Moved from test_stability with the parser: the same inputs, the same match.)"""
    for text in ("0,1,10", "-1:10:5", "a,b", "0.1:0:5", ""):
        with pytest.raises(ValueError, match="mstar"):
            parse_range(text, "mstar", log=True)


def test_ranges_keep_each_options_spacing():
    """--mstar ranges are log-spaced (README: ``--mstar 0.01:100:41``), --ustar ranges
    evenly spaced (``--ustar 2:16:15``); lists are taken as given."""
    m = parse_range("0.01:100:41", "mstar", log=True)
    assert m[0] == 0.01 and m[-1] == 100.0 and m[20] == pytest.approx(1.0, rel=1e-15)
    assert np.allclose(np.diff(np.log10(m)), 0.1, rtol=1e-12)
    assert np.array_equal(parse_range("2:16:15", "ustar"), np.arange(2.0, 17.0))
    assert np.array_equal(parse_range("0.5,1,2", "mstar", log=True), [0.5, 1.0, 2.0])
    assert np.array_equal(parse_range("-6.5,0", "ustar"), [-6.5, 0.0])


@pytest.mark.parametrize("text, log", [("1:2", False), ("1:2:0", False), ("a,1", False),
                                       ("nan,1", False), ("0.1:10:x", True), ("1,-2", True)])
def test_bad_ranges_name_the_option_and_the_accepted_forms(text, log):
    with pytest.raises(ValueError) as err:
        parse_range(text, "grid", log=log)
    message = str(err.value)
    assert message.startswith("--grid must be a comma list")
    assert "LO:HI:COUNT" in message and "1 <= COUNT <= 2000" in message and repr(text) in message
    assert ("log-spaced" in message and "> 0" in message) if log else "evenly spaced" in message


def test_map_rejects_a_bad_grid_without_a_traceback(capsys):
    code, out = run_json(capsys, ["map", "--ustar", "4:14", "--json"])
    assert code == 2 and out["error"].startswith("--ustar must be")


@pytest.mark.parametrize("argv, message", [
    (["lco", "--modes", "4", "--out", "{missing}/branch.json"], "--out .* does not exist"),
    (["lco", "--modes", "4", "--out", "{tmp}"], "--out .* is a folder"),
    (["map", "--modes", "4", "--out", "{missing}/map.jsonl"], "--out .* does not exist"),
    (["map", "--modes", "4", "--plot", "{tmp}/fig4.foo"], "--plot .* unknown figure format"),
    (["boundary", "--mstar", "1", "--plot", "{file}/fig2.png"], "--plot .* does not exist"),
    (["paper", "--out", "{file}/results"], "--out .* is a file, not a folder"),
    (["paper", "--out", "{file}"], "--out .* not a folder"),
])
def test_output_paths_are_checked_before_any_work(capsys, tmp_path, monkeypatch, argv, message):
    """A bad --out or --plot is exit status 2 with the option named, before the command's
    computation starts (the analyses are replaced by a tripwire)."""
    import re
    from fsicas.cli import cycles, linear, paper, timedomain

    def tripwire(*args, **kwargs):
        raise AssertionError("the computation started")
    for module, name in ((cycles, "cycle_branch"), (timedomain, "impact_map"),
                         (linear, "stability_boundary"), (paper, "run_paper")):
        if hasattr(module, name):
            monkeypatch.setattr(module, name, tripwire)
    (tmp_path / "a_file").write_text("")
    paths = {"missing": str(tmp_path / "missing"), "tmp": str(tmp_path),
             "file": str(tmp_path / "a_file")}
    code, out = run_json(capsys, [a.format(**paths) for a in argv] + ["--json"])
    assert code == 2 and re.search(message, out["error"]), out


def test_negative_values_may_follow_their_option():
    """``--contact-stiffness -1e6`` and ``--ustar -5:-1:3`` are read as the option's value
    (argparse alone takes them for options and fails with "expected one argument")."""
    from fsicas.cli import _negative_values_attached, build_parser
    argv = ["map", "--ustar", "-5:-1:3", "--mstar", "1", "--t-end", "-1e1"]
    args = build_parser().parse_args(_negative_values_attached(argv))
    assert (args.ustar, args.t_end) == ("-5:-1:3", -10.0)
    args = build_parser().parse_args(_negative_values_attached(
        ["steady", "--contact-stiffness", "-1e6", "--ustar", "-.5", "--json"]))
    assert (args.contact_stiffness, args.ustar, args.json) == (-1e6, -0.5, True)


def test_analysis_warnings_are_in_the_json(capsys, tmp_path):
    """A modal truncation that cannot resolve the onset (N = 4 at M* = 50) is reported in
    the result's "warnings", not lost on stderr."""
    code, out = run_json(capsys, ["map", "--modes", "4", "--mstar", "50:50:1", "--ustar", "4:4:1",
                                  "--t-end", "0.5", "--workers", "1",
                                  "--out", str(tmp_path / "m.jsonl"), "--json"])
    assert code == 0 and any("no onset of instability below U* = 6" in w for w in out["warnings"])


def test_version_and_helpful_scene_options(capsys):
    """--version names fsicas and CasADi; each scene option's help says what it is and its
    default; no raw reStructuredText markup in the help."""
    import fsicas
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0 and f"fsicas {fsicas.__version__}" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        main(["steady", "--help"])
    text = capsys.readouterr().out
    assert "mass ratio M*" in text and "(default 10)" in text and "(default 0.14)" in text
    with pytest.raises(SystemExit):
        main(["--help"])
    assert "``" not in capsys.readouterr().out


def test_zeta_per_mode_on_the_command_line(capsys):
    """``--zeta z1,z2,z3``: one damping ratio per mode, as in a scene file; the eigenvalues
    are those of the Scene with that tuple (and differ from one ratio for all)."""
    assert main(["eig", "--mstar", "1", "--ustar", "5", "--modes", "3",
                 "--zeta", "0.01,0.05,0.1", "--json"]) == 0
    got = np.array([complex(*v) for v in json.loads(capsys.readouterr().out)["eigenvalues"]])
    scene = fsicas.Scene(mstar=1.0, ustar=5.0, modes=3, zeta=(0.01, 0.05, 0.1))
    want = np.asarray(fsicas.linear_stability(scene).eigenvalues)
    assert np.sort_complex(got) == pytest.approx(np.sort_complex(want), rel=1e-12)
    single = fsicas.linear_stability(scene.replace(zeta=0.01)).eigenvalues
    assert np.sort_complex(got) != pytest.approx(np.sort_complex(np.asarray(single)), rel=1e-6)
    assert main(["eig", "--modes", "3", "--zeta", "0.01,0.02", "--json"]) == 2
    assert "one value per mode (3)" in json.loads(capsys.readouterr().out)["error"]
