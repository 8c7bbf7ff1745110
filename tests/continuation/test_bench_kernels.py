"""benchmarks/bench_kernels.py is importable and its small cases run: both backends
give the same Jacobian and every timing is recorded (no time is asserted)."""

import pytest


@pytest.mark.parametrize("coupling", ["mx", "global", "chain"])
def test_bench_kernels_small_case(models, coupling):
    bench = models.benchmark("bench_kernels")
    result = bench.run_case(6, 4, 3, 1, coupling)
    assert result["diff"] < 1e-10
    for backend in bench.BACKENDS:
        t = result["times"][backend]
        assert set(t) == {"jac", "res", "step", "kernel", "lu"}
        assert 0 < t["kernel"] and 0 < t["lu"] and t["kernel"] + t["lu"] <= 1
    assert bench.row(result).count("|") == bench.HEADER.count("|")
