"""What a time integration may cost: checked before it starts, so that no input runs for
hours or exhausts the memory before it says anything (docs/reliability.md)."""
from __future__ import annotations

from ..checks import finite_number, require
from .breathing import PressureSchedule

__all__ = ["check_size", "MAX_TRAJECTORY_BYTES", "SAMPLES_PER_BREATH"]

#: The most memory a trajectory's samples may take (bytes).
MAX_TRAJECTORY_BYTES = 2 * 2 ** 30
#: Output samples a breath period needs at least to be resolved.
SAMPLES_PER_BREATH = 20


def check_size(n_state: int, t_end: float, dt_out: float, schedule: PressureSchedule) -> None:
    """ValueError, before any work, for a run whose samples (``t_end / dt_out`` of
    ``n_state`` values) exceed :data:`MAX_TRAJECTORY_BYTES`, or whose breath period is
    shorter than :data:`SAMPLES_PER_BREATH` output samples (no step could follow it)."""
    require(finite_number("t_end", t_end) > 0, f"t_end must be > 0, got {t_end}")
    samples = t_end / dt_out + 1
    size = samples * n_state * 8
    require(size <= MAX_TRAJECTORY_BYTES,
            f"t_end / dt_out = {samples:.3g} samples of {n_state} states would take "
            f"{size / 2 ** 30:.3g} GiB (at most {MAX_TRAJECTORY_BYTES / 2 ** 30:g} GiB): raise "
            f"dt_out (--dt-out) or shorten t_end (--t-end)")
    if schedule.kind in ("breath", "tidal"):
        require(schedule.period >= SAMPLES_PER_BREATH * dt_out,
                f"the breath period {schedule.period:g} is shorter than {SAMPLES_PER_BREATH} "
                f"output samples of dt_out = {dt_out:g}: give a breath period of at "
                f"least {SAMPLES_PER_BREATH * dt_out:g} (--breath-period)")
