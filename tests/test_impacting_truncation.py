"""The modal truncation estimate of the impacting cycles (Figs. 6-9, the main job)."""
import pytest

from fsicas.timedomain.impacting_run import TRUNCATION_RTOL, with_truncation


def _run(modes, period, force, status="success"):
    """The fields of an impacting run's JSON that the estimate reads."""
    return {"modes": modes, "period": period, "max_impact_force": force, "status": status,
            "warnings": []}


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
    assert "N = 10" in warning and "N = 20" in warning


def test_missing_estimate_warns_unless_the_run_itself_failed():
    """A cycle whose coarser run shows none (the gap closed) cannot be estimated: warned,
    "unconverged"; a failed run keeps its status and gains no warning."""
    out = with_truncation(_run(20, 0.1, 5000.0), _run(10, None, None, "failed"))
    assert out["truncation_error"] == {"period": None, "max_impact_force": None}
    assert out["status"] == "unconverged" and "not estimated" in out["warnings"][0]
    failed = with_truncation(_run(20, None, None, "failed"), _run(10, 0.1, 4000.0))
    assert failed["status"] == "failed" and failed["warnings"] == []


def test_bad_inputs():
    with pytest.raises(ValueError, match="fewer modes"):
        with_truncation(_run(10, 0.1, 1.0), _run(20, 0.1, 1.0))
    with pytest.raises(ValueError, match="tol"):
        with_truncation(_run(20, 0.1, 1.0), _run(10, 0.1, 1.0), tol=0.0)
