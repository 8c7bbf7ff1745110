"""The benchmark script is importable and its small case hits the closed form."""

import numpy as np


def test_benchmark_small_case_matches_discrete_hopf(models):
    bench = models.benchmark("bench_continuation")
    row = bench.run(5, 80, 1e-10)  # n = 10
    assert row["n"] == 10 and row["max_res"] <= 1e-10
    assert row["err_A"] < 1e-12 and row["err_w"] < 1e-12
    AH, wH = bench.exact_hopf(5)
    assert 2.0 < AH < 2.1 and np.isfinite(wH)
