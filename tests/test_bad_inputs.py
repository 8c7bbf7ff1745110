"""Every bad command-line input gets a clear error before any work: exit status 2, the
offending option or field named, no traceback, nothing computed.

The inputs are the catalogue of ``fsicas/cli/bad_inputs.py`` (the table of
docs/reliability.md), run with every expensive step replaced by a tripwire, so a case
that got past validation fails loudly instead of computing; then the files a run must
not damage, the records it reads back, a closed pipe, Ctrl-C and a worker that dies.
"""
import json
import os
from pathlib import Path

import pytest

from fsicas.cli import main
from fsicas.cli.bad_inputs import CASES, GROUPS
from fsicas.cli.reliability import REFUSED, run_case, table, tripwires

#: The default run: every case but most of the scene options' (each option's values are
#: also checked in tests/test_scene.py); every one in the slow test below.
FAST = [c for k, c in enumerate(CASES) if c.group != "scene options" or k % 8 == 0]


@pytest.mark.parametrize("case", FAST, ids=[c.label for c in FAST])
def test_a_fast_subset_of_the_catalogue_is_refused(case):
    """Exit status 2 and a message naming the cause, before any work (a tripwire on
    every expensive step), within 20 s (else a hang)."""
    verdict, message = run_case(case)
    assert verdict == REFUSED, (case.named, message)


@pytest.mark.slow
def test_every_input_of_the_catalogue_is_refused_and_the_table_is_its_own():
    results = [(case, *run_case(case)) for case in CASES]
    assert [(c.label, m) for c, v, m in results if v != REFUSED] == []
    page = (Path(__file__).parents[1] / "docs" / "reliability.md").read_text()
    assert table(results) in page, "run python3 -m fsicas.cli.reliability"


def test_the_table_in_the_manual_counts_the_catalogue():
    """The counts of docs/reliability.md are those of the catalogue (regenerated)."""
    page = (Path(__file__).parents[1] / "docs" / "reliability.md").read_text()
    assert f"The inputs tried ({len(CASES)} in all)" in page
    for group, text in GROUPS.items():
        count = sum(c.group == group for c in CASES)
        assert f"| {text} | {count} | {REFUSED}: {count} |" in page, group


@pytest.fixture
def tripwire(monkeypatch, tmp_path):
    """Every expensive step replaced by a tripwire (:func:`fsicas.cli.reliability.tripwires`),
    in the folder ``tmp_path``."""
    monkeypatch.chdir(tmp_path)                   # default output files land there
    with tripwires():
        yield


def check_refused(capsys, argv, named):
    """Exit status 2, one JSON object with an error naming ``named``; nothing else."""
    try:
        code = main([*argv, "--json"])
    except SystemExit as stop:                # argparse's own errors: usage on stderr
        code, captured = stop.code, capsys.readouterr()
        assert code == 2 and captured.out == "" and "Traceback" not in captured.err
        assert named in captured.err, captured.err
        return
    captured = capsys.readouterr()
    assert code == 2, captured.out
    error = json.loads(captured.out)["error"]
    assert named in error, error
    assert "Traceback" not in captured.err


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
    # as from a shell: SIGINT at its default (a test worker may ignore it, and a child
    # inherits an ignored SIGINT: the interrupt would be lost)
    run = subprocess.Popen([sys.executable, "-m", "fsicas.cli", "--verbose", "boundary",
                            "--mstar", "0.01:100:400"], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, text=True,
                           preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    first = run.stderr.readline()          # the command is at work (imports done, however slow)
    assert first.startswith("fsicas boundary")
    time.sleep(8)                          # past the first continuation steps' compilation
    run.send_signal(signal.SIGINT)
    out, rest = run.communicate(timeout=300)        # 1.3 s on an idle machine
    err = first + rest
    assert run.returncode == 130 and "Traceback" not in err, (out, err)
    assert err.strip().splitlines()[-1].startswith("fsicas: interrupted")


def test_ctrl_c_while_the_command_starts_ends_it_quietly():
    """SIGINT while the libraries load (right after the interpreter is up: the command
    line's imports take 1-2 s): one line and exit 130, as during a run; run as the
    installed ``fsicas`` script runs. (Before the interpreter and the few lines of
    ``fsicas.console`` are up no program can catch it: the script says when they are,
    instead of the test guessing a delay.)"""
    import signal
    import subprocess
    import sys
    import time
    script = ("import sys; from fsicas.console import main; sys.stderr.write('up\\n'); "
              "sys.stderr.flush(); sys.exit(main())")
    run = subprocess.Popen([sys.executable, "-c", script, "boundary", "--mstar", "0.01:100:400"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert run.stderr.readline() == "up\n"
    time.sleep(0.1)        # into main()'s guarded imports (1-2 s), past the call itself
    run.send_signal(signal.SIGINT)
    out, err = run.communicate(timeout=300)
    assert run.returncode == 130 and "Traceback" not in err, err
    assert err.strip().splitlines()[-1].startswith("fsicas: interrupted"), err


def test_the_package_loads_its_wings_on_first_use():
    """``import fsicas`` loads none of the numerical libraries (a fresh interpreter); each
    public name comes from its wing on first use, and every name of ``__all__`` exists."""
    import subprocess
    import sys
    probe = ("import sys, fsicas; heavy = [m for m in ('casadi', 'scipy', 'numpy', 'matplotlib')"
             " if m in sys.modules]; print(heavy); fsicas.Scene; print(fsicas.Scene.__module__);"
             " print(all(hasattr(fsicas, n) for n in fsicas.__all__))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         timeout=300, check=True).stdout.split()
    assert out == ["[]", "fsicas.scene", "True"]


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


def test_a_record_read_back_is_checked_and_its_file_left_as_it_was(tmp_path):
    """A record without a field the run reads, or of another type, or not an object:
    refused naming the file and the line; the file byte for byte as it was written."""
    from fsicas.results_file import ResultsFile
    fields = {"ustar": (int, float), "index": int}
    for record, problem in [('{"index": 0}', "no 'ustar'"),
                            ('{"ustar": true, "index": 0}', "'ustar' is True, not a number"),
                            ('{"ustar": 1.5, "index": 0.0}', "'index' is 0.0, not an integer"),
                            ('"text"', "not a record")]:
        path = tmp_path / "r.jsonl"
        data = f'{{"header": {{"a": 1}}}}\n{{"ustar": 1, "index": 1}}\n{record}\n'.encode()
        path.write_bytes(data)
        with pytest.raises(ValueError, match=f"r.jsonl line 3: .*{problem}"):
            ResultsFile(path, {"a": 1}, fields=fields).__enter__()
        assert path.read_bytes() == data
    path.write_bytes(b'{"header": {"a": 1}}\n\n{"ustar": 2.5, "index": 3}\n')
    with ResultsFile(path, {"a": 1}, fields=fields) as out:
        assert out.records == [{"ustar": 2.5, "index": 3}]


def test_a_worker_that_dies_is_reported_not_a_traceback():
    """A local pool whose worker process exits mid-task: one WorkerLost naming the file."""
    from fsicas.workers import WorkerLost, finished, local_pool
    with local_pool(1) as pool:
        futures = [pool.submit(os._exit, 3)]
        with pytest.raises(WorkerLost, match="saved in out.jsonl: run the same command again"):
            list(finished(futures, "out.jsonl"))


def _children(pid):
    tasks = f"/proc/{pid}/task"
    try:
        return [int(c) for t in os.listdir(tasks) for c in open(f"{tasks}/{t}/children").read().split()]
    except OSError:
        return []


@pytest.mark.slow
def test_a_map_whose_worker_is_killed_resumes_without_lost_or_repeated_points(tmp_path):
    """A real map of 3 points on one worker; the worker killed with SIGKILL during its
    first points: exit 2 with one message, the file whole; the same command then
    computes exactly the missing points (each (U*, M*) once in the file)."""
    import signal
    import subprocess
    import sys
    import time
    cmd = [sys.executable, "-m", "fsicas.cli", "map", "--ustar", "6,7,8", "--mstar", "1",
           "--t-end", "10", "--workers", "1", "--out", "m.jsonl", "--json"]
    run = subprocess.Popen(cmd, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True)
    start = time.time()
    while not _children(run.pid) and time.time() - start < 120:
        time.sleep(0.1)
    time.sleep(2.0)
    os.kill(_children(run.pid)[0], signal.SIGKILL)
    out, err = run.communicate(timeout=120)
    assert run.returncode == 2 and "Traceback" not in err
    assert "a worker process died" in json.loads(out)["error"]
    before = (tmp_path / "m.jsonl").read_text().splitlines()
    assert before[0].startswith('{"header"') and len(before) < 4
    again = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr
    assert json.loads(again.stdout)["computed"] == 4 - len(before)
    rows = [json.loads(line) for line in (tmp_path / "m.jsonl").read_text().splitlines()[1:]]
    assert sorted(r["ustar"] for r in rows) == [6.0, 7.0, 8.0]


def test_a_study_over_the_number_of_modes_keeps_them_integers(tmp_path):
    """``modes = [4, 6]`` in a [grid] are the integers 4 and 6 (they were read as 4.0 and
    6.0, which every point then refused as an error row)."""
    from fsicas.scene import Scene
    from fsicas.studies.spec import load_study
    path = tmp_path / "s.toml"
    path.write_text('analysis = "onset"\n[grid]\nmodes = [4, 6]\nzeta = [0, 1]\n')
    points = load_study(path).points
    assert [p["modes"] for p in points[::2]] == [4, 6] and points[1]["zeta"] == 1.0
    assert all(Scene(**p).modes == p["modes"] for p in points)
