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


def test_bench_cycles_runs_the_tools_in_turn(models, monkeypatch):
    """``--repeats`` alternates ours and AUTO and returns every run's times, in order
    (the medians and ratios are taken from them); without AUTO only ours runs."""
    bench = models.benchmark("bench_cycles")
    calls, times = [], iter([1.0, 4.0, 2.0, 5.0, 3.0, 9.0])
    monkeypatch.setattr(bench, "ours", lambda n, points, floquet, backend: calls.append("ours")
                        or {"per_point": next(times)})
    monkeypatch.setattr(bench, "auto", lambda n, points: calls.append("auto")
                        or {"per_point": next(times), "fortran_per_point": 0.5})
    args = bench.argparse.Namespace(repeats=3, points=4, floquet="product", backend="mx",
                                     no_auto=False)
    run, res, ours_t, auto_t, fortran_t = bench.timed(4, args)
    assert calls == ["ours", "auto"] * 3
    assert list(ours_t) == [1.0, 2.0, 3.0] and list(auto_t) == [4.0, 5.0, 9.0]
    assert list(fortran_t) == [0.5] * 3 and run["per_point"] == 3.0
    calls.clear()
    times = iter([7.0, 8.0])
    _, res, ours_t, auto_t, _ = bench.timed(4, bench.argparse.Namespace(
        repeats=2, points=4, floquet="product", backend="mx", no_auto=True))
    assert calls == ["ours", "ours"] and res is None and auto_t.size == 0
    assert list(ours_t) == [7.0, 8.0]
