"""benchmarks/bench_cycles.py is importable; its small case hits the closed-form Hopf
point and agrees with the NTST = 200 reference (AUTO is not needed)."""

import numpy as np


def test_bench_cycles_small_case(models):
    bench = models.benchmark("bench_cycles")
    run = bench.ours(4, 4, "product")            # two cells
    assert abs(run["hopf_B"] - bench.hopf_b(4)) < 1e-10
    X = run["steps"][-1].X
    B, T = run["cyc"].params(X)[1], run["cyc"].period(X)
    err_T, err_mu = bench.errors(T, run["mu"][-1], *bench.reference(run, B))
    assert err_T < 1e-9 and err_mu < 1e-8
    assert np.all(np.abs(run["mu"][-1]) > 0)
