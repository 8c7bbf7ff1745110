"""The modal truncation estimate of the impacting cycles (Figs. 6-9, the main job)."""
import pytest

from fsicas.linear.truncation import TRUNCATION_RTOL
from fsicas.timedomain.impacting_run import TRUNCATION_MEASURES, with_truncation


def _run(modes, period, force, status="success"):
    """The fields of an impacting run's JSON that the estimate reads: period and peak
    force as given, the other measures 1 (or None with the period, the gap closed)."""
    other = None if period is None else 1.0
    return {**dict.fromkeys(TRUNCATION_MEASURES, other), "modes": modes, "period": period,
            "max_impact_force": force, "status": status, "warnings": [],
            "outcome": "impacting_lco" if period else "contact"}


def test_estimate_is_the_relative_change_from_the_coarser_run():
    """|X_N - X_N'| / |X_N| per measure, by hand: period 0.128 against 0.1279 and force
    4000 against 3990 change by 1/1280 and 1/400, both below 1e-2: no warning."""
    out = with_truncation(_run(20, 0.128, 4000.0), _run(10, 0.1279, 3990.0))
    assert out["truncation_error"]["period"] == pytest.approx(1 / 1280, rel=1e-12)
    assert out["truncation_error"]["max_impact_force"] == pytest.approx(1 / 400, rel=1e-12)
    assert out["truncation_modes"] == 10 and out["truncation_tol"] == TRUNCATION_RTOL
    assert out["status"] == "success" and out["warnings"] == []


def test_estimate_above_its_tolerance_warns_and_is_not_success():
    """A peak force that moves by 25 % from N = 10 to 20 (3000 against 4000 F0): warned,
    "unconverged"; the period within tolerance is not named."""
    out = with_truncation(_run(20, 0.128, 4000.0), _run(10, 0.1279, 3000.0))
    assert out["status"] == "unconverged"
    (warning,) = out["warnings"]
    assert "max_impact_force 0.25" in warning and "period" not in warning
    assert out["truncation_error"]["tip_amplitude"] == 0.0
    assert "N = 10" in warning and "N = 20" in warning


def test_missing_estimate_warns_unless_the_run_itself_failed():
    """A cycle whose coarser run shows none (the gap closed) cannot be estimated: warned,
    "unconverged"; a failed run keeps its status and gains no warning."""
    out = with_truncation(_run(20, 0.1, 5000.0), _run(10, None, None, "failed"))
    assert out["truncation_error"] == dict.fromkeys(TRUNCATION_MEASURES, None)
    assert out["status"] == "unconverged"
    (warning,) = out["warnings"]
    assert "not estimated: the N = 10 run shows no cycle (contact)" in warning
    assert "above the tolerance" not in warning
    failed = with_truncation(_run(20, None, None, "failed"), _run(10, 0.1, 4000.0))
    assert failed["status"] == "failed" and failed["warnings"] == []


def test_bad_inputs():
    with pytest.raises(ValueError, match="fewer modes"):
        with_truncation(_run(10, 0.1, 1.0), _run(20, 0.1, 1.0))
    with pytest.raises(ValueError, match="tol"):
        with_truncation(_run(20, 0.1, 1.0), _run(10, 0.1, 1.0), tol=0.0)


@pytest.mark.slow
def test_main_job_cycle_against_twice_its_modes_at_1a():
    """(1a), U* = 7: the main job's cycle (N = CYCLE_MODES = 20, its estimate against
    N = 10) against the independent finer modal discretization, N = 40 (about 10 min).
    The period's estimate (3.4e-3) bounds its difference from N = 40 (3.4e-4); every
    measure whose estimate is within the tolerance agrees with N = 40 within it; those
    above it (the peak force: 3227 against 2128 F0) are named in the warning, and the
    cycle is not "success"."""
    from fsicas.paper import CYCLE_MODES, impacting_cycle
    from fsicas.timedomain.impacting_run import impacting_run
    cycle = impacting_cycle(7.0)
    fine = impacting_run(7.0, 2 * CYCLE_MODES).to_json()
    estimate = cycle["truncation_error"]
    assert cycle["modes"] == 20 and cycle["truncation_modes"] == 10
    difference = {k: abs(cycle[k] - fine[k]) / abs(fine[k]) for k in TRUNCATION_MEASURES}
    assert difference["period"] <= estimate["period"] <= TRUNCATION_RTOL
    assert estimate["max_impact_force"] > TRUNCATION_RTOL
    for k, e in estimate.items():
        if e <= TRUNCATION_RTOL:
            assert difference[k] <= TRUNCATION_RTOL, k
        else:
            assert k in cycle["warnings"][-1], k
    assert cycle["status"] == "unconverged"
