"""Run time against error of a classified run (``run_case`` with its early stop).

Prints, per case, the wall time of ``run_case`` (integration, monitoring and the outcome),
the time integrated until the outcome was decided, and the error of the reported tip
amplitude against the same run continued to t = 20 (settled to round-off), next to the
``convergence`` the run reported. Run it against two checkouts in turn to compare:

    PYTHONPATH=/path/to/other/checkout python benchmarks/bench_classify.py
"""
import inspect
import json
import time

from fsicas import Scene
from fsicas.timedomain.integrators import Settings
from fsicas.timedomain.run import run_case

CASES = {"lco U*=6.5 N=10": Scene(mstar=1.0, ustar=6.5, zeta=0.01, modes=10),
         "decay U*=4 N=10": Scene(mstar=1.0, ustar=4.0, zeta=0.01, modes=10)}
SETTINGS = Settings(rtol=1e-8, atol=1e-10)


def main(repeats: int = 3) -> None:
    plain = {"quadrature_tol": None} if "quadrature_tol" in inspect.signature(run_case).parameters else {}
    for name, scene in CASES.items():
        reference = run_case(scene, 20.0, settings=SETTINGS, stop_early=False, **plain).outcome
        times = []
        for _ in range(repeats):
            start = time.perf_counter()
            run = run_case(scene, 20.0, settings=SETTINGS, **plain)
            times.append(time.perf_counter() - start)
        o = run.outcome
        error = None if o.tip_amplitude is None else abs(o.tip_amplitude / reference.tip_amplitude - 1)
        print(json.dumps({"case": name, "outcome": o.outcome, "wall_time_min": min(times),
                          "t_decided": float(run.trajectory.t[-1]), "amplitude_error": error,
                          "reported_convergence": o.convergence}))


if __name__ == "__main__":
    main()
