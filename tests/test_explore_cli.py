"""``fsicas explore`` refuses bad options before it serves (exit status 2, one line)."""
import pytest


@pytest.mark.parametrize("argv, message", [
    (["--port", "70000"], "--port must be in [1, 65535], got 70000"),
    (["--physical", "no_such_preset"], "no_such_preset"),
])
def test_explore_refuses_bad_options_before_serving(run_cli, tmp_path, argv, message):
    done = run_cli(["explore", *argv], tmp_path)
    assert done.returncode == 2, done.stderr
    assert message in done.stderr and "Traceback" not in done.stderr
