"""Cost of a study point against the analysis run directly.

The palate-onset example (``examples/studies/palate_onset.toml``, its first ``--points``
points) as a study on 1 and 2 local processes, against the same onsets computed in a
plain loop in this process (one model, no files): per point, and the study's overhead
(process start-up, a model per worker, the results file, the table). Then, if Dask is
installed, the same on a local Dask cluster of 2 workers.

    python benchmarks/bench_study.py [--points 40]
"""
from __future__ import annotations

import argparse
import dataclasses
import os
import tempfile
import time
import warnings
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import fsicas  # noqa: E402
from fsicas.studies import load_study, run_study  # noqa: E402

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "studies" / "palate_onset.toml"


def direct(study) -> float:
    """The onsets of the study's points in a plain loop (one model)."""
    palate = fsicas.load_physical(study.physical)
    t0 = time.perf_counter()
    model = None
    for p in study.points:
        scene = fsicas.Physical.from_table({**palate.raw, **p}, "p").scene(None, **study.scene)
        model = model or fsicas.build_model(scene)
        fsicas.critical_velocity(scene, model)
    return time.perf_counter() - t0


def timed_study(study, **kw) -> float:
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        run_study(study, Path(tmp) / "t.csv", progress=False, **kw)
        return time.perf_counter() - t0


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=40)
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    study = load_study(EXAMPLE)
    study = dataclasses.replace(study, points=study.points[:args.points])
    n = len(study.points)
    print(f"load average {os.getloadavg()[0]:.1f} ({os.cpu_count()} cores); {n} onset points, "
          f"N = {study.scene['modes']}")
    print("| route | total [s] | per point [ms] |")
    print("| --- | --- | --- |")
    rows = [("direct loop, 1 process", direct(study)),
            ("study, 1 worker", timed_study(study, workers=1)),
            ("study, 2 workers", timed_study(study, workers=2))]
    try:
        import distributed
        with distributed.LocalCluster(n_workers=2, threads_per_worker=1,
                                      dashboard_address=None) as cluster, \
                distributed.Client(cluster) as client:
            rows.append(("study, Dask (2 local workers)",
                         timed_study(study, executor=client.get_executor())))
    except ImportError:
        pass
    for name, total in rows:
        print(f"| {name} | {total:.2f} | {1e3 * total / n:.0f} |", flush=True)


if __name__ == "__main__":
    main()
