"""Cost of the sound synthesis against the time integration it is made from.

Two runs: a settled contact-free limit cycle (M* = 1, U* = 6.5, zeta = 0.01, N = 4, the
3 cm strip of the tests with T = 10 ms) and the soft palate at 8 L/min with the wall
contact on (N = 6, zeta = 0.01, k* = 1e8, eps/H = 0.1). Per run: the integration, the
looped cycle's sound of 2 s at 44.1 kHz (``cycle_sound``) or the trajectory's sound of
its last third (``trajectory_sound``), medians of ``--repeats``.

    python benchmarks/bench_sound.py [--repeats 5]
"""
from __future__ import annotations

import argparse
import os
import time

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

import fsicas  # noqa: E402
from fsicas.timedomain.integrators import Settings  # noqa: E402
from fsicas.timedomain.sound import cycle_sound, trajectory_sound  # noqa: E402
from fsicas.units import Scales  # noqa: E402

STRIP = Scales(length=0.03, time=0.01, pressure=1.0, width=0.03, fluid_density=1.2, gap=0.004)


def median_time(fun, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fun()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)
    print(f"load average {os.getloadavg()[0]:.1f} ({os.cpu_count()} cores)")
    print("| run | integration [s] | sound | synthesis [ms] | samples | level [dB] | fundamental [Hz] |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    scene = fsicas.Scene(mstar=1.0, ustar=6.5, zeta=0.01, modes=4)
    t_run, run = median_time(lambda: fsicas.run_case(scene, 12.0, settings=Settings(
        rtol=1e-8, atol=1e-10, dt_out=1e-3)), 1)
    t_s, s = median_time(lambda: cycle_sound(run.trajectory, STRIP, 0.3, 2.0), args.repeats)
    print(f"| limit cycle, N = 4 | {t_run:.2f} | cycle looped to 2 s | {1e3 * t_s:.1f} | "
          f"{s.pressure.size} | {s.spl_db:.1f} | {s.fundamental_hz:.2f} |", flush=True)
    palate = fsicas.load_physical("soft_palate")
    scene = palate.scene(fsicas.parse_flow("8L/min"), modes=6, zeta=0.01, contact=True,
                         contact_stiffness=1e8, contact_eps=0.1)
    t_run, run = median_time(lambda: fsicas.run_case(scene, 10.0, settings=Settings(
        rtol=1e-7, atol=1e-9, dt_out=2e-4)), 1)
    tr = run.trajectory
    t_s, s = median_time(lambda: trajectory_sound(tr, scene.scales, 0.3,
                                                  t_start=tr.t[-1] * 2 / 3), args.repeats)
    print(f"| soft palate, 8 L/min, contact, N = 6 | {t_run:.2f} | last third of the run | "
          f"{1e3 * t_s:.1f} | {s.pressure.size} | {s.spl_db:.1f} | "
          f"{s.fundamental_hz or float('nan'):.2f} |", flush=True)


if __name__ == "__main__":
    main()
