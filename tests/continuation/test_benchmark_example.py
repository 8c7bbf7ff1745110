"""The benchmark script is importable and its small case hits the closed form."""

import importlib.util
import pathlib

import numpy as np


def load_bench():
    path = pathlib.Path(__file__).parents[2] / "benchmarks" / "bench_continuation.py"
    spec = importlib.util.spec_from_file_location("bench_continuation", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_benchmark_small_case_matches_discrete_hopf():
    bench = load_bench()
    row = bench.run(5, 80, 1e-10)  # n = 10
    assert row["n"] == 10 and row["max_res"] <= 1e-10
    assert row["err_A"] < 1e-12 and row["err_w"] < 1e-12
    AH, wH = bench.exact_hopf(5)
    assert 2.0 < AH < 2.1 and np.isfinite(wH)
