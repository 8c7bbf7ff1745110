"""Every bad command-line input gets a clear error before any work: exit status 2, the
offending option or field named, no traceback, nothing computed.

The inputs are those of ``docs/reliability.md``: each scene option with values out of its
range, not finite, of the wrong type or absurdly large, on four commands; broken scene
files; the options of each command. The analyses are replaced by a tripwire, so a case
that got past validation fails loudly instead of computing.
"""
import json
import os

import pytest

from fsicas.cli import main

#: Scene options: bad values and the name the message must contain.
SCENE_CASES = {
    "--mstar": ["0", "-1", "nan", "inf", "1e308", "abc"],
    "--ustar": ["nan", "inf", "-inf", "1e5", "-1e5", "abc"],
    "--hstar": ["0", "-0.1", "nan", "abc"],
    "--friction": ["-0.1", "nan", "inf", "abc"],
    "--k0": ["-1", "nan", "abc"],
    "--kl": ["-1", "nan", "abc"],
    "--zeta": ["-0.01", "nan", "inf", "abc", "1e308"],
    "--modes": ["0", "-3", "2.5", "1000", "99999999999999999999", "abc"],
    "--quad-nodes": ["5", "100000", "2.5", "-1", "abc"],
    "--contact-stiffness": ["0", "-1e6", "nan", "abc"],
    "--contact-eps": ["0", "1", "1.5", "-1e-3", "nan"],
}
#: The commands that take the scene options (with what else they need).
COMMANDS = {"steady": [], "eig": [], "lco": [], "simulate": ["--t-end", "1"]}


def _scene_cases():
    for command, extra in COMMANDS.items():
        for option, values in SCENE_CASES.items():
            for value in values:
                yield pytest.param([command, *extra, option, value], option.lstrip("-"),
                                   id=f"{command} {option} {value}")


#: Options of the commands: (argv, what the message names).
COMMAND_CASES = [
    (["modes", "--modes", "0"], "modes"), (["modes", "--modes", "100000000"], "modes"),
    (["simulate", "--t-end", "0"], "t-end"), (["simulate", "--t-end", "-1"], "t-end"),
    (["simulate", "--t-end", "nan"], "t-end"), (["simulate", "--t-end", "1", "--rtol", "0.5"], "rtol"),
    (["simulate", "--t-end", "1", "--rtol", "0"], "rtol"),
    (["simulate", "--t-end", "1", "--rtol", "-1e-8"], "rtol"),
    (["simulate", "--t-end", "1", "--atol", "0"], "atol"),
    (["simulate", "--t-end", "1", "--atol", "1"], "atol"),
    (["simulate", "--t-end", "1", "--dt-out", "0"], "dt_out"),
    (["simulate", "--t-end", "1", "--dt-out", "-1e-3"], "dt_out"),
    (["simulate", "--t-end", "1", "--perturbation", "40"], "perturbation"),
    (["simulate", "--t-end", "1", "--schedule", "ramp", "--ramp-time", "0"], "ramp-time"),
    (["simulate", "--t-end", "1", "--schedule", "breath", "--breath-period", "-1"], "breath-period"),
    (["boundary", "--mstar", "0:1:5"], "mstar"), (["boundary", "--mstar", "1:10:0"], "mstar"),
    (["boundary", "--mstar", "1:10:100000"], "mstar"), (["boundary", "--mstar", "a,b"], "mstar"),
    (["boundary", "--mstar", "-1"], "mstar"), (["boundary", "--mstar", "1:10"], "mstar"),
    (["boundary", "--mstar", "nan"], "mstar"),
    (["boundary", "--mstar", "1", "--ustar-max", "0"], "ustar_max"),
    (["boundary", "--mstar", "1", "--ustar-max", "-5"], "ustar_max"),
    (["boundary", "--mstar", "1", "--friction", "0", "--k0", "0", "--kl", "0"], "pressure drop"),
    (["map", "--ustar", "4:14"], "ustar"), (["map", "--ustar", "4:14:0"], "ustar"),
    (["map", "--ustar", "nan"], "ustar"), (["map", "--ustar", "-5:-1:3"], "U*"),
    (["map", "--mstar", "0:1:3"], "mstar"), (["map", "--t-end", "0"], "t_end"),
    (["map", "--workers", "0"], "workers"), (["map", "--modes", "0"], "modes"),
    (["map", "--modes", "1000"], "modes"),
    (["lco", "--max-points", "0"], "max_points"), (["lco", "--ntst", "0"], "ntst"),
    (["lco", "--ncol", "0"], "ncol"), (["lco", "--ustar-max", "-1"], "ustar_max"),
    (["lco", "--contact"], "contact"),
    # beyond the cores only when asked; repeated grid values; a ramp start beyond any U*
    (["map", "--workers", "100000"], "--oversubscribe"),
    (["grazing", "--workers", "100000"], "--oversubscribe"),
    (["map", "--ustar", "4,5,4"], "--ustar repeats 4"), (["map", "--mstar", "1:1:3"], "--mstar repeats 1"),
    (["boundary", "--mstar", "0.5,0.5"], "--mstar repeats 0.5"),
    (["simulate", "--t-end", "1", "--schedule", "ramp", "--ustar-start", "1e308"], "--ustar-start"),
]


def _file_cases(tmp_path):
    """(argv, named) for broken scene files under ``tmp_path``."""
    files = {"invalid": "modes = = 3", "unknown": "heights = [[0.05]]", "string": 'zeta = "abc"',
             "huge": "modes = 99999999999999999999", "float_modes": "modes = 1e30",
             "contact": 'contact = "yes"', "nested": "mstar = [1, 2]",
             "binary": None}
    out = []
    for name, text in files.items():
        path = tmp_path / f"{name}.toml"
        if text is None:
            path.write_bytes(b"\xff\xfe\x00bad")
        else:
            path.write_text(text)
        out.append((["steady", "--scene", str(path)], {"invalid": "TOML", "unknown": "heights",
                    "string": "zeta", "huge": "modes", "float_modes": "modes",
                    "contact": "contact", "nested": "mstar", "binary": "TOML"}[name]))
    (tmp_path / "folder.toml").mkdir()
    out += [(["steady", "--scene", str(tmp_path / "missing.toml")], "no such file"),
            (["steady", "--scene", str(tmp_path / "folder.toml")], "folder")]
    return out


@pytest.fixture
def tripwire(monkeypatch, tmp_path):
    """Every expensive step replaced by a function that fails the test: continuation
    runs, time integration chunks, map points and the map's linear boundary (validation
    inside the library functions before these steps is allowed)."""
    import continuation
    from fsicas.timedomain import integrators
    import importlib
    impact_map = importlib.import_module("fsicas.timedomain.impact_map")

    def tripped(*args, **kwargs):
        raise AssertionError("the computation started")
    monkeypatch.chdir(tmp_path)                   # default output files land there
    monkeypatch.setattr(continuation.ContinuationIterator, "start", tripped)
    monkeypatch.setattr(integrators.Integrator, "run", tripped)
    monkeypatch.setattr(impact_map, "_point", tripped)
    monkeypatch.setattr(impact_map, "stability_boundary", tripped)


def check_refused(capsys, argv, named):
    """Exit status 2, one JSON object with an error naming ``named``; nothing else."""
    try:
        code = main([*argv, "--json"])
    except SystemExit as stop:                # argparse's own errors: usage on stderr
        code, captured = stop.code, capsys.readouterr()
        assert code == 2 and captured.out == "" and "Traceback" not in captured.err
        assert named.replace("_", "-") in captured.err or named in captured.err, captured.err
        return
    captured = capsys.readouterr()
    assert code == 2, captured.out
    error = json.loads(captured.out)["error"]
    assert named in error or named.replace("_", "-") in error, error
    assert "Traceback" not in captured.err


@pytest.mark.parametrize("argv, named", list(_scene_cases()))
def test_scene_option_refused_before_work(capsys, tripwire, argv, named):
    check_refused(capsys, argv, named.replace("-", "_"))


@pytest.mark.parametrize("argv, named", COMMAND_CASES, ids=[" ".join(a) for a, _ in COMMAND_CASES])
def test_command_option_refused_before_work(capsys, tripwire, argv, named):
    check_refused(capsys, argv, named)


def test_broken_scene_files_refused_before_work(capsys, tripwire, tmp_path):
    cases = _file_cases(tmp_path)
    for argv, named in cases:
        check_refused(capsys, argv, named)
    assert len(cases) == 10


def test_at_least_150_inputs_are_tried():
    scene = sum(len(v) for v in SCENE_CASES.values()) * len(COMMANDS)
    assert scene + len(COMMAND_CASES) + 10 >= 150


PNG = b"\x89PNG\r\n\x1a\n" + bytes(range(64))


def _foreign_outputs(tmp_path):
    """(argv, the file it must leave as it was, its bytes) for outputs fsicas did not make."""
    notes = b"my notes\nline two\nlast line without newline"
    study = tmp_path / "s.toml"
    study.write_text('analysis = "onset"\n[grid]\nmstar = [1.0]\n')
    cases = [(["map", "--ustar", "6", "--mstar", "1", "--out", "notes.txt"], "notes.txt", notes),
             (["map", "--ustar", "6", "--mstar", "1", "--out", "fig.png"], "fig.png", PNG),
             (["lco", "--mstar", "1", "--out", "notes.txt"], "notes.txt", notes),
             (["grazing", "--mstar", "1", "--out", "notes.json"], "notes.json", notes),
             (["sound", "--physical", "soft_palate", "--out", "song.wav"], "song.wav", notes),
             (["study", str(study), "--out", "table.csv"], "table.csv", b"a,b\n1,2\n"),
             (["study", str(study), "--out", "t2.csv"], "t2.jsonl", notes)]
    return cases


def test_an_output_fsicas_did_not_make_is_refused_and_left_as_it_was(capsys, tripwire, tmp_path):
    for argv, name, content in _foreign_outputs(tmp_path):
        (tmp_path / name).write_bytes(content)
        check_refused(capsys, argv, "left as it is")
        assert (tmp_path / name).read_bytes() == content, argv


def test_a_fifo_or_folder_as_results_file_is_refused_without_blocking(capsys, tripwire, tmp_path):
    os.mkfifo(tmp_path / "pipe.jsonl")
    check_refused(capsys, ["map", "--ustar", "6", "--mstar", "1", "--out", "pipe.jsonl"],
                  "not a regular file")
    (tmp_path / "folder.png").mkdir()
    check_refused(capsys, ["eig", "--mstar", "1", "--ustar", "6", "--plot", "folder"], "folder")


def test_results_file_refuses_foreign_files_and_repairs_a_torn_header(tmp_path):
    from fsicas.results_file import ResultsFile
    foreign = tmp_path / "fig.png"
    foreign.write_bytes(PNG)
    with pytest.raises(ValueError, match="not a results file"):
        ResultsFile(foreign, {"a": 1}).__enter__()
    assert foreign.read_bytes() == PNG
    torn = tmp_path / "torn.jsonl"
    torn.write_bytes(b'{"header": {"a"')            # killed while writing its header
    with ResultsFile(torn, {"a": 1}) as out:
        out.append({"x": 1})
    assert torn.read_text() == '{"header": {"a": 1}}\n{"x": 1}\n'


def test_outputs_fsicas_made_are_reused(capsys, tmp_path, monkeypatch):
    """An own JSON result is overwritten; an own results file resumed (no work here:
    the map's one point is already in it)."""
    from fsicas.cli.outputs import check_outputs
    import argparse
    own = tmp_path / "branch.json"
    own.write_text(json.dumps({"points": [], "meta": {"fsicas": "0.1.0"}}))
    check_outputs(argparse.Namespace(command="lco", out=str(own), plot=None))
    wav = tmp_path / "snore.wav"
    wav.write_bytes(b"RIFF\x24\x00\x00\x00WAVEfmt ")
    check_outputs(argparse.Namespace(command="sound", out=str(wav), plot=None))


def _physical_file(tmp_path, name, **values):
    lines = ['preset = "soft_palate"', "[physical]"] + [f"{k} = {v}" for k, v in values.items()]
    (tmp_path / name).write_text("\n".join(lines) + "\n")
    return name


def test_hostile_physical_input_gets_a_clear_error_at_once(capsys, tripwire, tmp_path):
    """Arithmetic that would overflow or run for hours in the unit parser, values beyond
    a float, a zero viscosity, nesting that exhausts the recursion: exit 2, no traceback."""
    import time
    cases = [(["onset", "--physical", _physical_file(tmp_path, "a.toml", E='"3 * 10**400 Pa"')],
              "one number, then a unit"),
             (["onset", "--physical", _physical_file(tmp_path, "b.toml", L='"1e300 m"')],
              "beyond what a float holds"),
             (["onset", "--physical", "soft_palate", "--flow", "1 * 10**10**8 m/s"], "--flow"),
             (["onset", "--physical", "soft_palate", "--flow", "1e999 m/s"], "--flow"),
             (["onset", "--physical", _physical_file(tmp_path, "c.toml", E="-3000")], "E"),
             (["onset", "--physical", _physical_file(tmp_path, "d.toml", zeta="-0.1")], "zeta")]
    deep = "a = " + "[" * 5000 + "]" * 5000 + "\n"
    (tmp_path / "deep.toml").write_text(deep)
    cases += [(["onset", "--physical", "deep.toml"], "nested too deeply"),
              (["steady", "--scene", "deep.toml"], "nested too deeply")]
    for argv, named in cases:
        start = time.perf_counter()
        check_refused(capsys, argv, named)
        assert time.perf_counter() - start < 10, argv


def test_a_zero_viscosity_is_refused_naming_it(capsys, tripwire, tmp_path):
    text = (tmp_path / "v.toml")
    text.write_text('[physical]\nE = "3 kPa"\nnu = 0.45\nrho_s = "1040 kg/m^3"\ne = "2.5 mm"\n'
                    'L = "30 mm"\nb = "30 mm"\ngap = "2 mm"\nrho_f = "1.2 kg/m^3"\n'
                    'viscosity = 0\nflow = "20 L/min"\n')
    check_refused(capsys, ["onset", "--physical", "v.toml"], "viscosity (dynamic viscosity")


def test_units_as_written_still_read():
    from fsicas.physical import parse_flow, parse_quantity
    assert parse_quantity("3 kPa", "Pa", "E") == 3000.0
    assert parse_quantity("1040 kg/m^3", "kg/m^3", "rho") == 1040.0
    assert parse_quantity("1.8e-5 Pa*s", "Pa*s", "mu") == 1.8e-5
    assert abs(parse_flow("20L/min").value - 20e-3 / 60) < 1e-15
    assert abs(parse_flow("3e-4 m**3/s").value - 3e-4) < 1e-15
    assert parse_flow("1.2m/s").kind == "velocity"


def test_a_closed_pipe_and_ctrl_c_end_the_command_quietly(tmp_path):
    """``| head`` closes stdout: no traceback, exit 141; SIGINT: one line, exit 130."""
    import signal
    import subprocess
    import sys
    import time
    cmd = [sys.executable, "-m", "fsicas.cli", "modes", "--modes", "50", "--json"]
    reader = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    reader.stdout.close()                            # the reader is gone before the output
    assert reader.wait(timeout=120) == 141
    assert b"Traceback" not in reader.stderr.read()
    run = subprocess.Popen([sys.executable, "-m", "fsicas.cli", "boundary", "--mstar",
                            "0.01:100:400"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True)
    time.sleep(8)
    run.send_signal(signal.SIGINT)
    out, err = run.communicate(timeout=60)
    assert run.returncode == 130 and "Traceback" not in err
    assert err.strip().splitlines()[-1].startswith("fsicas: interrupted")


@pytest.mark.parametrize("argv, named", [
    (["simulate", "--mstar", "1", "--ustar", "6", "--dt-out", "1e-9", "--t-end", "10"], "GiB"),
    (["simulate", "--mstar", "1", "--ustar", "6", "--t-end", "1e12", "--full"], "--t-end"),
    (["simulate", "--ustar", "9", "--schedule", "breath", "--breath-period", "1e-300",
      "--t-end", "1"], "--breath-period"),
    (["lco", "--mstar", "1", "--ntst", "100000"], "ntst must be at most"),
    (["lco", "--mstar", "1", "--through-contact", "--impact-ntst", "100000"], "ntst"),
], ids=["dt-out", "t-end", "breath-period", "ntst", "impact-ntst"])
def test_sizes_that_cannot_fit_are_refused_with_the_way_round(capsys, tripwire, argv, named):
    """Each of these ran for hours or exhausted the memory; refused with the limit."""
    check_refused(capsys, argv, named)


def test_an_unreachable_dask_scheduler_fails_fast_and_clearly(capsys, tripwire, monkeypatch):
    pytest.importorskip("distributed")
    import time
    from fsicas import workers
    monkeypatch.setattr(workers, "DASK_CONNECT_TIMEOUT", 2.0)
    start = time.perf_counter()
    check_refused(capsys, ["map", "--ustar", "6", "--mstar", "1", "--dask", "tcp://127.0.0.1:1",
                           "--out", "m.jsonl"], "no Dask scheduler answered")
    assert time.perf_counter() - start < 30


def test_workers_beyond_the_cores_run_when_asked(monkeypatch):
    """``--oversubscribe`` lets ``--workers`` exceed the cores (the check alone: no work)."""
    from fsicas.workers import check_workers
    monkeypatch.setattr("os.cpu_count", lambda: 2)
    check_workers(None)
    check_workers(2)
    check_workers(8, oversubscribe=True)
    with pytest.raises(ValueError, match="more than the 2 cores.*--workers 2 or fewer"):
        check_workers(3)
    with pytest.raises(ValueError, match=">= 1"):
        check_workers(0, oversubscribe=True)
