"""Studies (fsicas.studies, ``fsicas study``): the points a study file describes, rows
equal to the analyses run directly, resume after SIGKILL without lost, repeated or mixed
rows, local processes against a Dask cluster, and refusals before any work."""

import csv
import json
import os
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import fsicas
from fsicas.cli import main
from fsicas.studies import load_study, run_study, study_point

ONSET = """
description = "palate onsets"
analysis = "onset"
physical = "soft_palate"
[scene]
modes = 4
[grid]
E = ["1 kPa", "3 kPa"]
e = {start = "2 mm", stop = "3 mm", num = 3}
"""

SAMPLE = """
analysis = "onset"
[scene]
modes = 4
[sample]
size = 5
seed = 3
mstar = {distribution = "loguniform", low = 0.1, high = 10.0}
friction = {distribution = "normal", mean = 0.14, std = 0.01}
"""


# The in-process tests run the points on one thread: CasADi's model building and the
# warnings a point records are not thread-safe (a study runs on processes).


def _write(tmp_path, text, name="s.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _table(path) -> tuple[dict, list[dict]]:
    """The study's header (the results file's first line) and the table's rows, read by
    the plain CSV reader of the standard library."""
    with open(path.with_suffix(".jsonl")) as fh:
        header = json.loads(fh.readline())["header"]
    with open(path, newline="") as fh:
        return header, list(csv.DictReader(fh))


def test_grid_points_are_every_combination_in_si_units(tmp_path):
    study = load_study(_write(tmp_path, ONSET))
    assert [(p["E"], p["e"]) for p in study.points] == \
        [(E, e) for E in (1000.0, 3000.0) for e in (0.002, 0.0025, 0.003)]
    assert study.header["points"] == 6 and len(study.header["points_sha256"]) == 64


def test_a_sample_is_the_same_in_every_run_and_follows_its_distributions(tmp_path):
    a, b = (load_study(_write(tmp_path, SAMPLE, f"{k}.toml")) for k in "ab")
    assert a.points == b.points
    rng = np.random.default_rng(3)                      # the documented draw, by hand
    mstar = np.exp(rng.uniform(np.log(0.1), np.log(10.0), 5))
    friction = rng.normal(0.14, 0.01, 5)
    assert [p["mstar"] for p in a.points] == pytest.approx(mstar, rel=1e-15)
    assert [p["friction"] for p in a.points] == pytest.approx(friction, rel=1e-15)


def test_rows_equal_the_analysis_run_directly(tmp_path):
    """The physical study's rows against onsets computed here from the preset."""
    study = load_study(_write(tmp_path, ONSET))
    rows = run_study(study, tmp_path / "t.csv", executor=ThreadPoolExecutor(1), progress=False)
    palate = fsicas.load_physical("soft_palate")
    for row in rows:
        table = {**palate.raw, "E": row["E"], "e": row["e"]}
        scene = fsicas.Physical.from_table(table, "check").scene(None, modes=4)
        hopf = fsicas.critical_velocity(scene)
        assert row["ustar_crit"] == pytest.approx(hopf.ustar, rel=1e-12)
        assert row["onset_flow_l_min"] == pytest.approx(scene.scales.l_per_min(hopf.ustar),
                                                        rel=1e-12)
        assert row["error"] == ""
    header, written = _table(tmp_path / "t.csv")
    assert header["analysis"] == "onset" and header["points"] == 6
    assert [int(r["index"]) for r in written] == list(range(6))
    assert float(written[4]["ustar_crit"]) == rows[4]["ustar_crit"]     # repr round trip


def test_resume_computes_only_the_missing_points_and_refuses_another_study(tmp_path):
    study = load_study(_write(tmp_path, SAMPLE))
    first = run_study(study, tmp_path / "t.csv", executor=ThreadPoolExecutor(1), progress=False)
    lines = (tmp_path / "t.jsonl").read_text().splitlines()
    (tmp_path / "t.jsonl").write_text("\n".join(lines[:3]) + "\n" + lines[3][:20])   # torn
    calls = []

    class Counting(ThreadPoolExecutor):
        def submit(self, fn, *args):
            calls.append(args[1])
            return super().submit(fn, *args)

    again = run_study(study, tmp_path / "t.csv", executor=Counting(1), progress=False)
    assert sorted(calls) == [2, 3, 4] and again == first
    other = load_study(_write(tmp_path, SAMPLE.replace("seed = 3", "seed = 4"), "o.toml"))
    with pytest.raises(ValueError, match="points_sha256"):
        run_study(other, tmp_path / "t.csv", executor=ThreadPoolExecutor(1), progress=False)


def test_sound_rows_equal_the_sound_of_the_same_run(tmp_path):
    """The sound analysis against run_case and trajectory_sound called here."""
    from fsicas.timedomain.integrators import Settings
    from fsicas.timedomain.sound import trajectory_sound
    text = ('analysis = "sound"\nphysical = "soft_palate"\n[scene]\nmodes = 4\nzeta = 0.01\n'
            'contact = true\ncontact_stiffness = 1e8\ncontact_eps = 0.1\n[settings]\n'
            't_end = 6.0\n[grid]\nflow = ["6 L/min"]\n')
    row = study_point(load_study(_write(tmp_path, text)), 0)
    scene = fsicas.load_physical("soft_palate").scene(
        fsicas.parse_flow("6 L/min"), modes=4, zeta=0.01, contact=True, contact_stiffness=1e8,
        contact_eps=0.1)
    run = fsicas.run_case(scene, 6.0, settings=Settings(rtol=1e-7, atol=1e-9, dt_out=2e-4,
                                                         chunk=1.0))
    assert row["outcome"] == run.outcome.outcome == "impacting_nonperiodic" and row["error"] == ""
    traj = run.trajectory
    sound = trajectory_sound(traj, scene.scales, 0.3, t_start=traj.t[-1] * 2 / 3)
    assert row["spl_db"] == pytest.approx(sound.spl_db, rel=1e-9)
    assert row["fundamental_hz"] == pytest.approx(sound.fundamental_hz, rel=1e-9)
    assert (row["fundamental_lo_hz"], row["fundamental_hi_hz"]) == pytest.approx(
        sound.fundamental_ci_hz, rel=1e-9)
    assert all(w in row["warnings"] for w in sound.warnings)


def test_a_point_that_fails_is_a_row_with_its_error(tmp_path):
    """A value refused only when its point runs (a physical study's channels too wide
    for the model: each point's H* is known once its scene is made) is that row's error;
    a nondimensional value out of range is refused when the file is read
    (tests/test_bad_inputs.py)."""
    wide = load_study(_write(tmp_path, 'analysis = "onset"\nphysical = "soft_palate"\n'
                                       '[grid]\ngap = ["150 mm"]\n'))   # H* = (150 + 150)/30
    row = study_point(wide, 0)
    assert "H* = (H1 + H2)/L = 10 > 0.5" in row["error"] and "ustar_crit" not in row
    study = load_study(_write(tmp_path, 'analysis = "onset"\n[scene]\nmodes = 2\n'
                                        '[grid]\nmstar = [1.0]\n'))
    row = study_point(study, 0)               # N = 2: no onset resolved
    assert row["error"] == "" and not row["found"] and "N = 2 modes" in row["warnings"]


def test_sigkill_and_restart_lose_and_repeat_no_row(tmp_path):
    """``fsicas study`` killed with SIGKILL while it writes, then run again to the end:
    every point once, and the rows equal those of an uninterrupted run."""
    text = ONSET.replace('["1 kPa", "3 kPa"]', '["1 kPa", "2 kPa", "3 kPa", "4 kPa"]') \
        .replace("num = 3", "num = 5")
    path = _write(tmp_path, text)
    argv = [sys.executable, "-m", "fsicas.cli", "study", str(path), "--workers", "1",
            "--out", str(tmp_path / "k.csv"), "--quiet"]
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    results, deadline = tmp_path / "k.jsonl", time.time() + 120
    while time.time() < deadline:
        if results.exists() and len(results.read_text().splitlines()) >= 4:
            break
        time.sleep(0.05)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    partial = len(results.read_text().splitlines()) - 1
    assert 3 <= partial < 20, "the kill did not land mid-study"
    assert subprocess.run(argv).returncode == 0
    lines = [json.loads(line) for line in results.read_text().splitlines()[1:]]
    assert sorted(r["index"] for r in lines) == list(range(20))        # none lost or repeated
    clean = run_study(load_study(path), tmp_path / "c.csv", executor=ThreadPoolExecutor(1),
                      progress=False)
    assert _table(tmp_path / "k.csv")[1] == _table(tmp_path / "c.csv")[1]
    assert sorted(lines, key=lambda r: r["index"]) == clean


def test_local_processes_and_a_dask_cluster_give_identical_tables(tmp_path):
    distributed = pytest.importorskip("distributed")
    study = load_study(_write(tmp_path, SAMPLE))
    run_study(study, tmp_path / "local.csv", workers=2, progress=False)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        run_study(study, tmp_path / "dask.csv", executor=client.get_executor(), progress=False)
    assert (tmp_path / "local.csv").read_text() == (tmp_path / "dask.csv").read_text()


def test_cli_study_json_and_resume(tmp_path, capsys):
    path = _write(tmp_path, SAMPLE)
    out = tmp_path / "cli.csv"
    assert main(["study", str(path), "--out", str(out), "--workers", "2", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["rows"] == 5 and result["errors"] == 0 and result["table"] == str(out)
    assert result["study"]["points"] == 5 and "meta" in result
    before = out.read_text()
    assert main(["study", str(path), "--out", str(out)]) == 0         # all there: no work
    assert "5 points of the onset analysis" in capsys.readouterr().out
    assert out.read_text() == before


@pytest.mark.parametrize("text, message", [
    ('analysis = "flutter"\n[grid]\nmstar = [1.0]\n', "analysis must be one of onset, outcome, sound"),
    ('analysis = "onset"\n', "give either a [grid] or a [sample] table"),
    ('analysis = "onset"\n[grid]\ncolour = [1.0]\n', "'colour' is not a Scene field"),
    ('analysis = "onset"\nphysical = "soft_palate"\n[grid]\nE = ["3 m"]\n',
     "E: '3 m' is not in units of Pa"),
    ('analysis = "onset"\n[settings]\nt_end = 3.0\n[grid]\nmstar = [1.0]\n',
     "not settings of 'onset'"),
    ('analysis = "onset"\n[sample]\nsize = 3\nmstar = {distribution = "beta"}\n',
     "distribution must be one of uniform"),
    ('analysis = "onset"\n[sample]\nsize = 3\nmstar = {distribution = "uniform", low = 2.0, '
     'high = 1.0}\n', "need 0 < low < high"),
    ('analysis = "onset"\n[grid]\nmstar = [1.0, 2.0, 1.0]\n', "grid.mstar repeats 1"),
    ('analysis = "onset"\n[grid]\nmstar = {start = 1.0, stop = 1.0, num = 2}\n', "grid.mstar repeats 1"),
])
def test_bad_study_files_are_refused_before_any_work(tmp_path, capsys, text, message):
    assert main(["study", str(_write(tmp_path, text)), "--json"]) == 2
    assert message in json.loads(capsys.readouterr().out)["error"]


@pytest.mark.parametrize("out, message", [("t.txt", "must end in .csv or .parquet"),
                                          ("nowhere/t.csv", "does not exist")])
def test_bad_table_paths_are_refused_before_any_work(tmp_path, capsys, out, message):
    path = _write(tmp_path, SAMPLE)
    assert main(["study", str(path), "--out", str(tmp_path / out), "--json"]) == 2
    assert message in json.loads(capsys.readouterr().out)["error"]
    assert not (tmp_path / "t.jsonl").exists()


def test_parquet_table(tmp_path):
    study = load_study(_write(tmp_path, SAMPLE))
    try:
        import pyarrow.parquet as pq
    except ImportError:
        with pytest.raises(ValueError, match="needs pyarrow"):
            run_study(study, tmp_path / "t.parquet", executor=ThreadPoolExecutor(1))
        return
    rows = run_study(study, tmp_path / "t.parquet", executor=ThreadPoolExecutor(1),
                     progress=False)
    table = pq.read_table(tmp_path / "t.parquet")
    assert table.column("ustar_crit").to_pylist() == [r["ustar_crit"] for r in rows]
    assert json.loads(table.schema.metadata[b"fsicas_study"])["points"] == 5


def test_shipped_example_studies_load():
    root = Path(__file__).resolve().parents[1] / "examples" / "studies"
    onset, fig4 = load_study(root / "palate_onset.toml"), load_study(root / "fig4_map.toml")
    assert len(onset.points) == 200 and onset.physical == "soft_palate"
    assert len(fig4.points) == 105 and fig4.analysis == "outcome"
    assert 0.1 * 0.999 < min(p["mstar"] for p in fig4.points) < 0.1 * 1.001


def test_summary_of_a_table_is_its_median_and_spread():
    """0, 1, ..., 100: median 50, 5th and 95th percentiles 5 and 95 (closed form);
    failed rows, booleans and the index enter no statistic; text columns are counted."""
    from fsicas.studies import summarize
    rows = [{"index": i, "found": True, "flow": float(i), "kind": "flutter" if i % 4 else
             "divergence", "error": None} for i in range(101)]
    rows.append({"index": 101, "flow": 1e9, "error": "no steady state"})
    s = summarize(rows)
    assert (s["points"], s["failed"]) == (102, 1)
    assert set(s["columns"]) == {"flow", "kind"}
    flow = s["columns"]["flow"]
    assert (flow["count"], flow["median"], flow["p05"], flow["p95"], flow["min"], flow["max"]) \
        == (101, 50.0, 5.0, 95.0, 0.0, 100.0)
    assert s["columns"]["kind"]["values"] == {"divergence": 26, "flutter": 75}


@pytest.mark.parametrize("body, named", [
    ('analysis = "outcome"\n[settings]\nt_end = -1\n[grid]\nustar = [6.0]', "t_end"),
    ('analysis = "outcome"\n[settings]\nt_end = "abc"\n[grid]\nustar = [6.0]', "t_end"),
    ('analysis = "outcome"\n[settings]\nrtol = 0.5\n[grid]\nustar = [6.0]', "rtol"),
    ('analysis = "onset"\n[settings]\nustar_max = inf\n[grid]\nmstar = [1.0]', "ustar_max"),
    ('analysis = "onset"\n[scene]\nmodes = 10000\n[grid]\nmstar = [1.0]', "modes"),
    ('analysis = "sound"\n[grid]\nustar = [6.0]', "physical"),
])
def test_nonsense_settings_are_refused_when_the_study_is_read(tmp_path, body, named):
    """Not one error row per point after the pool has started: refused by load_study."""
    path = tmp_path / "s.toml"
    path.write_text(body + "\n")
    with pytest.raises(ValueError, match=named):
        load_study(path)


def test_a_sweep_over_the_contact_law_equals_separate_runs(tmp_path):
    """Points that differ in k* share one model (the contact law is a parameter of it),
    yet each reports its own force: every row equals a run of its scene alone, on its own
    model (before: the second point's force was computed with the first point's k*)."""
    text = ('analysis = "outcome"\n[scene]\nmstar = 1.0\nustar = 7.0\nmodes = 4\n'
            'zeta = 0.01\ncontact = true\ncontact_eps = 0.1\n'
            '[grid]\ncontact_stiffness = [3e4, 1e5]\n')
    study = load_study(_write(tmp_path, text))
    rows = [study_point(study, i) for i in range(2)]
    from fsicas.timedomain.integrators import Settings
    from fsicas.timedomain.run import sweep_model
    scenes = [fsicas.Scene(**study.scene, **point) for point in study.points]
    assert sweep_model(scenes[0]) is sweep_model(scenes[1])
    s = study.settings
    settings = Settings(rtol=s["rtol"], atol=s["atol"], dt_out=s["dt_out"], chunk=1.0)
    for row, scene in zip(rows, scenes):
        alone = fsicas.run_case(scene, s["t_end"], settings=settings).to_json()
        assert row["outcome"] == alone["outcome"] == "impacting_lco" and row["error"] == ""
        for key in ("max_impact_force", "period", "tip_amplitude", "first_contact_time"):
            assert row[key] == pytest.approx(alone[key], rel=1e-9), key
    assert rows[1]["max_impact_force"] > 1.2 * rows[0]["max_impact_force"]
