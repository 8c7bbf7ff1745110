"""The sound of the flutter: the acoustic monopole of the airway's outlet volume flow.

The fluctuating volume flow leaving the channels radiates as a compact monopole in free
field: at the listener distance r,

    p(r, t) = ρ_f / (4π r) · d/dt [b (Q1 + Q2)](t − r/c),

with ``Q1 + Q2`` the outlet flow rates per unit width (:func:`fsicas.timedomain.energy.outlet_flow_rates`;
their sum is the inlet total ``x[-2] + x[-1]``, the beam only moves fluid between the
channels) and b the width. The time derivative is exact at each output sample:
``d/dt (Q1 + Q2) = ẋ[-2] + ẋ[-1]`` with ``ẋ = M⁻¹F`` (:func:`fsicas.timedomain.returns.xdot_rows`).
In SI units ``dQ/dt = b L² / T² · d(Q1* + Q2*)/dt*`` (``Scales``: L, T, b, ρ_f).

Signals (:class:`Sound`, sampled at :data:`AUDIO_RATE` by default):

- :func:`cycle_sound`: one settled cycle (the last between two Poincaré returns; a limit
  cycle or an impacting one) looped to the duration by a periodic cubic spline of the
  exact derivative samples;
- :func:`trajectory_sound`: the whole trajectory (e.g. a breathing schedule, whose snore
  onset and offset are heard) by a cubic spline of the same samples.

docs/sound.md states the model, its assumptions and limits.
"""
from __future__ import annotations

import functools
import time
from dataclasses import dataclass, replace

import numpy as np
from scipy.interpolate import CubicSpline

from ..linear.steady import steady_state
from ..units import Scales
from .breathing import PressureSchedule
from .integrators import Settings, initial_state, simulate
from .returns import cycles, poincare_returns, xdot_rows
from .outcome import Criteria, classify
from .run import Run, controlled_run, guarded_model, quadrature_tolerance

__all__ = ["Sound", "AUDIO_RATE", "P_REF", "SOUND_SPEED", "HARMONICS", "HARMONIC_FLOOR",
           "flow_derivative", "monopole_pressure", "spl_db", "harmonic_amplitudes", "pitch",
           "median_rate", "CONFIDENCE", "PITCH_RTOL",
           "strongest_line", "line_spectrum", "looped_sound", "cycle_sound", "trajectory_sound",
           "breath_run", "write_wav"]

#: Audio sample rate (Hz), reference pressure of dB SPL (Pa), speed of sound in air (m/s).
AUDIO_RATE, P_REF, SOUND_SPEED = 44100, 20e-6, 343.0
#: Harmonics reported.
HARMONICS = 10
#: Uniform points per period on which the harmonics are taken.
_PERIOD_POINTS = 4096
#: Harmonics weaker than this fraction of the strongest (-40 dB) are absent from the
#: spectrum: the fundamental is the largest common divisor of the present ones.
HARMONIC_FLOOR = 1e-2
#: Confidence level of a trajectory's fundamental (the median return rate), and the
#: relative width of its interval above which the pitch is called uncertain.
CONFIDENCE, PITCH_RTOL = 0.95, 0.05


@dataclass(frozen=True)
class Sound:
    """A radiated pressure signal ``pressure`` (Pa) at ``distance_m``, sampled at
    ``rate`` Hz; ``fundamental_hz`` (the lowest frequency of which the cycle's present
    harmonics are multiples, :func:`pitch`: 2/T for the symmetric cycle of a symmetric
    channel; None without a cycle), ``dominant_hz`` (the strongest line of the spectrum
    of ``pressure`` itself, :func:`strongest_line`; None for silence), ``spl_db``  (RMS level, dB re 20 µPa), ``harmonics_pa`` (amplitudes of the first
    :data:`HARMONICS` harmonics of the cycle, Pa), ``source`` ("cycle" or "trajectory"),
    ``period_s`` and, for a trajectory, ``onset_s`` and ``offset_s`` (first and last time
    the level over :data:`HEARD_WINDOW` exceeds :data:`HEARD_FRACTION` of its largest);
    a trajectory's fundamental is that of the median period between the tip's Poincaré
    returns while heard, its harmonics those of the cycle of that period nearest it, and
    ``fundamental_ci_hz`` the :data:`CONFIDENCE` interval of that median (a bootstrap of
    the returns, :func:`median_rate`): an irregular snore's pitch is a statistic, and
    ``warnings`` says so when the interval is wider than :data:`PITCH_RTOL` of it."""

    rate: int
    pressure: np.ndarray
    fundamental_hz: float | None
    dominant_hz: float | None
    spl_db: float
    harmonics_pa: tuple
    distance_m: float
    source: str
    period_s: float | None
    onset_s: float | None = None
    offset_s: float | None = None
    fundamental_ci_hz: tuple | None = None
    warnings: tuple = ()

    @property
    def duration_s(self) -> float:
        return self.pressure.size / self.rate

    def to_json(self) -> dict:
        return {"fundamental_hz": self.fundamental_hz, "dominant_hz": self.dominant_hz,
                "spl_db": self.spl_db,
                "harmonics_pa": list(self.harmonics_pa), "distance_m": self.distance_m,
                "sample_rate_hz": self.rate, "duration_s": self.duration_s,
                "source": self.source, "period_s": self.period_s,
                "peak_pa": float(np.max(np.abs(self.pressure))) if self.pressure.size else 0.0,
                "rms_pa": _rms(self.pressure), "onset_s": self.onset_s, "offset_s": self.offset_s,
                "fundamental_ci_hz": (None if self.fundamental_ci_hz is None
                                      else list(self.fundamental_ci_hz)),
                "warnings": list(self.warnings)}


def flow_derivative(traj, idx=None) -> np.ndarray:
    """``d/dt (Q1 + Q2)`` (nondimensional, per unit width) at the samples ``idx`` (all by
    default), from ``ẋ = M⁻¹F`` at each sample's pressure drop."""
    idx = np.arange(len(traj.t)) if idx is None else np.asarray(idx)
    xdot = _xdot_rows(traj, idx)
    return xdot[:, -2] + xdot[:, -1]


def monopole_pressure(dqdt, fluid_density: float, distance: float) -> np.ndarray:
    """``p = ρ_f / (4π r) · dQ/dt`` (Pa) of a volume-flow derivative in m³/s²."""
    return fluid_density / (4 * np.pi * distance) * np.asarray(dqdt, dtype=float)


def _pressure_scale(scales: Scales, distance: float) -> float:
    """Pa per unit of the nondimensional ``d(Q1 + Q2)/dt`` (per unit width)."""
    dqdt = scales.width * scales.length**2 / scales.time**2
    return float(monopole_pressure(dqdt, scales.fluid_density, distance))


def spl_db(pressure) -> float:
    """Sound pressure level of the RMS of ``pressure`` (Pa), dB re 20 µPa."""
    rms = _rms(pressure)
    return float(20 * np.log10(rms / P_REF)) if rms > 0 else -np.inf


def _rms(p) -> float:
    p = np.asarray(p, dtype=float)
    return float(np.sqrt(np.mean(p**2))) if p.size else 0.0


def harmonic_amplitudes(one_period, count: int = HARMONICS) -> tuple:
    """Amplitudes (units of the input) of harmonics 1..count of a signal sampled
    uniformly over exactly one period (endpoint excluded)."""
    c = np.fft.rfft(np.asarray(one_period, dtype=float)) / len(one_period)
    amp = 2 * np.abs(c[1:count + 1])
    return tuple(float(a) for a in np.pad(amp, (0, count - amp.size)))


def pitch(one_period, period_s: float) -> tuple[float, float]:
    """``(fundamental, strongest line)`` in Hz of the periodic signal sampled uniformly
    over one period of ``period_s`` seconds (endpoint excluded): of its harmonics n/T,
    the strongest, and as the fundamental ``g/T``, g the largest common divisor of the
    harmonics at least :data:`HARMONIC_FLOOR` of the strongest (g = 2 when the signal
    repeats each half period, as the total flow of a symmetric cycle does)."""
    lines = np.abs(np.fft.rfft(np.asarray(one_period, dtype=float))[1:])
    present = np.flatnonzero(lines >= HARMONIC_FLOOR * lines.max()) + 1
    return int(np.gcd.reduce(present)) / period_s, (int(np.argmax(lines)) + 1) / period_s


def median_rate(intervals, confidence: float = CONFIDENCE) -> tuple[float, tuple[float, float]]:
    """``(1 / median, (lo, hi))``: the rate of the median of the intervals between returns
    and its ``confidence`` interval, by the percentile bootstrap of the median
    (``scipy.stats.bootstrap``, a fixed seed: the same returns give the same interval).
    The returns of an irregular motion are taken as a sample of its intervals; with
    fewer than three the interval is unbounded."""
    from scipy.stats import bootstrap
    x = np.asarray(intervals, dtype=float)
    rate = 1.0 / float(np.median(x))
    if x.size < 3 or np.ptp(x) == 0:
        return rate, ((0.0, np.inf) if x.size < 3 else (rate, rate))
    ci = bootstrap((x,), np.median, confidence_level=confidence, method="percentile",
                   n_resamples=4999, rng=np.random.default_rng(0)).confidence_interval
    return rate, (1.0 / float(ci.high), 1.0 / float(ci.low))


def _pitch_warning(fundamental: float, ci: tuple, intervals, dominant) -> tuple:
    """The warning of a trajectory's fundamental whose interval is wider than
    :data:`PITCH_RTOL` of it (none otherwise)."""
    lo, hi = ci
    if hi - lo <= PITCH_RTOL * fundamental:
        return ()
    ms = 1e3 * np.asarray(intervals)
    line = "" if dominant is None else (f"; the strongest line ({dominant:.4g} Hz) of such a "
                                        "broadband spectrum is no steadier")
    return (f"the snore is irregular (the tip's returns {ms.min():.3g} to {ms.max():.3g} ms "
            f"apart, {ms.size} while heard): its fundamental {fundamental:.4g} Hz is their "
            f"median rate, {lo:.4g}-{hi:.4g} Hz at {CONFIDENCE:.0%} confidence; another run "
            f"of it (another mesh, tolerance or start) lands elsewhere in that range{line}",)


def strongest_line(pressure, rate: int) -> float | None:
    """The frequency (Hz) of the strongest line of the spectrum of ``pressure`` sampled
    at ``rate``: the largest bin of its Hann-windowed FFT (the mean left out), refined
    by the parabola through the log magnitudes of it and its neighbours (to a fraction
    of the bin width 1/duration); None for silence."""
    p = np.asarray(pressure, dtype=float)
    spectrum = np.abs(np.fft.rfft((p - p.mean()) * np.hanning(p.size)))
    j = int(np.argmax(spectrum[1:-1])) + 1 if spectrum.size > 2 else 0
    if j == 0 or spectrum[j] == 0:
        return None
    a, b, c = np.log(np.maximum(spectrum[j - 1:j + 2], 1e-300))
    shift = 0.5 * (a - c) / (a - 2 * b + c) if a - 2 * b + c < 0 else 0.0
    return float((j + shift) * rate / p.size)


def line_spectrum(pressure, rate: int, max_hz: float | None = None
                  ) -> tuple[np.ndarray, np.ndarray]:
    """The spectrum of ``pressure`` (Pa) sampled at ``rate``: frequencies (Hz, up to
    ``max_hz``) and the level of each line in dB SPL, ``10 log10(P_k / P_REF^2)`` with
    ``P_k`` the line's mean square (the Hann-windowed periodogram of the signal less its
    mean, scaled so that a sinusoid of amplitude A on a line reads ``A^2 / 2``)."""
    from scipy.signal import periodogram
    hz, power = periodogram(np.asarray(pressure, dtype=float), fs=rate, window="hann",
                            detrend="constant", scaling="spectrum")
    keep = slice(None) if max_hz is None else hz <= max_hz
    return hz[keep], 10 * np.log10(np.maximum(power[keep], 1e-30) / P_REF**2)


def _check(distance, duration, rate) -> None:
    if not (np.isfinite(distance) and distance > 0):
        raise ValueError(f"distance must be > 0 (m), got {distance}")
    if not (np.isfinite(duration) and duration > 0):
        raise ValueError(f"duration must be > 0 (s), got {duration}")
    if not (isinstance(rate, (int, np.integer)) and rate >= 1000):
        raise ValueError(f"rate must be an integer >= 1000 (Hz), got {rate!r}")


def _last_cycle(traj) -> tuple[float, float]:
    """Start and end (nondimensional) of the last cycle between two Poincaré returns of
    the tip (the dense-output return times; ValueError if there are fewer than two)."""
    model = traj.model
    start = int(np.searchsorted(traj.t, traj.t[-1] - 0.5 * (traj.t[-1] - traj.t[0])))
    t, X = traj.t[start:], traj.x[start:]
    cyc = cycles(t, X, model, lambda i: _xdot_rows(traj, start + np.asarray(i)))
    if cyc is None or cyc.times.size < 2:
        raise ValueError("the run has no cycle to sound (fewer than two returns of the tip "
                         "in its second half): it decayed or did not settle; raise the flow "
                         "or the integration time")
    return float(cyc.times[-2]), float(cyc.times[-1])


def _xdot_rows(traj, idx) -> np.ndarray:
    return xdot_rows(traj.model, traj.x[idx], traj.p, traj.pressure_drop[idx])


def _periodic_spline(t, dqdt, t_a: float, t_b: float) -> CubicSpline:
    """Periodic cubic spline of the samples ``dqdt`` at ``t`` in [t_a, t_b) (shifted to
    start at 0), closed by the first sample's value one period later."""
    k = np.flatnonzero((t >= t_a) & (t < t_b))
    if k.size < 8:
        raise ValueError(f"the cycle holds {k.size} output samples; refine the output step")
    s = np.r_[t[k], t[k[0]] + (t_b - t_a)] - t[k[0]]
    return CubicSpline(s, np.r_[dqdt[k], dqdt[k[0]]], bc_type="periodic")


def looped_sound(t, dqdt, t_a: float, t_b: float, scales: Scales, distance: float = 0.3,
                 duration: float = 2.0, rate: int = AUDIO_RATE) -> Sound:
    """The sound of one period [t_a, t_b) of the samples ``dqdt`` of ``d(Q1 + Q2)/dt``
    (nondimensional, per unit width) at times ``t``, looped to ``duration`` seconds."""
    _check(distance, duration, rate)
    t, dqdt = np.asarray(t, dtype=float), np.asarray(dqdt, dtype=float)
    spline, period = _periodic_spline(t, dqdt, t_a, t_b), t_b - t_a
    scale = _pressure_scale(scales, distance)
    t_audio = np.arange(int(round(duration * rate))) / rate - distance / SOUND_SPEED
    p = scale * spline(np.mod(t_audio / scales.time, period))
    one = scale * spline(np.arange(_PERIOD_POINTS) * period / _PERIOD_POINTS)
    period_s = period * scales.time
    return Sound(rate, p, *pitch(one, period_s), spl_db(one), harmonic_amplitudes(one),
                 distance, "cycle", period_s)


def cycle_sound(traj, scales: Scales, distance: float = 0.3, duration: float = 2.0,
                rate: int = AUDIO_RATE, cycle: tuple[float, float] | None = None) -> Sound:
    """The sound of the last settled cycle of ``traj`` (or of ``cycle`` = (t_a, t_b),
    nondimensional), looped to ``duration`` seconds (module docstring)."""
    _check(distance, duration, rate)
    t_a, t_b = _last_cycle(traj) if cycle is None else cycle
    k = np.flatnonzero((traj.t >= t_a) & (traj.t < t_b))
    dqdt = np.zeros(traj.t.size)
    dqdt[k] = flow_derivative(traj, k)
    return looped_sound(traj.t, dqdt, t_a, t_b, scales, distance, duration, rate)


def trajectory_sound(traj, scales: Scales, distance: float = 0.3, rate: int = AUDIO_RATE,
                     t_start: float = 0.0) -> Sound:
    """The sound of the whole trajectory from ``t_start`` (nondimensional), resampled at
    ``rate``, with the snore's onset, offset, fundamental and harmonics (:class:`Sound`)."""
    duration = (traj.t[-1] - t_start) * scales.time
    _check(distance, duration, rate)
    scale = _pressure_scale(scales, distance)
    # the flow's derivative only where it is heard: from the retarded start on
    first = np.searchsorted(traj.t, t_start - distance / SOUND_SPEED / scales.time) - 2
    k = np.arange(max(first, 0), traj.t.size)
    spline = CubicSpline(traj.t[k], flow_derivative(traj, k))
    t_audio = t_start * scales.time + np.arange(int(duration * rate)) / rate - distance / SOUND_SPEED
    p = np.where(t_audio >= 0, scale * spline(np.maximum(t_audio, 0.0) / scales.time), 0.0)
    onset, offset = _heard(p, rate, t_audio[0])
    dominant = strongest_line(p, rate)
    if onset is None:
        return Sound(rate, p, None, dominant, spl_db(p), (0.0,) * HARMONICS, distance,
                     "trajectory", None)
    sel = (traj.t >= onset / scales.time) & (traj.t <= offset / scales.time)
    returns, _ = poincare_returns(traj.t[sel], traj.tip[sel])
    if returns.size < 3:
        return Sound(rate, p, None, dominant, spl_db(p), (0.0,) * HARMONICS, distance,
                     "trajectory", None, onset, offset)
    periods = np.diff(returns)
    j = int(np.argmin(np.abs(periods - np.median(periods))))
    one = scale * spline(returns[j] + np.arange(_PERIOD_POINTS) * periods[j] / _PERIOD_POINTS)
    period_s = float(np.median(periods)) * scales.time
    fundamental = pitch(one, period_s)[0]
    g = round(fundamental * period_s)       # fundamental = g / median period (pitch)
    intervals_s = periods * scales.time
    _, (lo, hi) = median_rate(intervals_s)
    ci = (g * lo, g * hi)
    return Sound(rate, p, fundamental, dominant, spl_db(p), harmonic_amplitudes(one),
                 distance, "trajectory", period_s, onset, offset, ci,
                 _pitch_warning(fundamental, ci, intervals_s, dominant))


#: Window (s) of the level that tells when a snore is heard, and the fraction of the
#: largest level it must reach.
HEARD_WINDOW, HEARD_FRACTION = 0.1, 0.1


def _heard(p, rate: int, t0: float) -> tuple[float | None, float | None]:
    """First and last time (s; window starts) at which the RMS over
    :data:`HEARD_WINDOW` exceeds :data:`HEARD_FRACTION` of its largest value."""
    n = max(1, int(HEARD_WINDOW * rate))
    windows = p[:p.size // n * n].reshape(-1, n)
    if not windows.size:
        return None, None
    level = np.sqrt(np.mean(windows**2, axis=1))
    loud = np.flatnonzero(level > HEARD_FRACTION * level.max()) if level.max() > 0 else []
    if not len(loud):
        return None, None
    return t0 + loud[0] * n / rate, t0 + (loud[-1] + 1) * n / rate


def breath_run(scene, t_end: float, settings: Settings = Settings(), perturbation=1e-2,
               progress: bool = False, quadrature_tol: float | str | None = "auto",
               repeat: bool = True) -> Run:
    """One breath of ``t_end`` (nondimensional): ``U*(t) = scene.ustar |sin(π t / t_end)|``
    (:class:`~fsicas.timedomain.breathing.PressureSchedule`), started from rest (no flow,
    no pressure drop: a consistent start) with the beam perturbed as by
    :func:`~fsicas.timedomain.integrators.initial_state`, run to the end and classified.
    ``quadrature_tol`` ("auto" as in :func:`~fsicas.timedomain.run.run_case`): the bound
    of the flow quadrature's error over the breath, measured at the peak's parameters
    on its states (the integrals sharpen as the gap closes): above it the breath is run
    again on the adequate nodes (up to three times; the soft palate at 25 L/min, N = 4,
    1 s: 3.7e-3 on 28 nodes in 15 s, 5.8e-5 on 56 in 21 s); with ``repeat=False`` it is
    only judged (status "unconverged" with a warning above it)."""
    start = time.perf_counter()
    tol = quadrature_tolerance(quadrature_tol, Criteria(), settings.rtol, scene.contact)
    once = functools.partial(_breath_once, t_end=t_end, settings=settings,
                             perturbation=perturbation, progress=progress)
    run = once(scene, guarded_model(scene)[0])
    run = controlled_run(run, once, tol, repeat)
    return replace(run, wall_time=time.perf_counter() - start)


def _breath_once(scene, model, *, t_end, settings, perturbation, progress) -> Run:
    """:func:`breath_run` once on ``model``."""
    start = time.perf_counter()
    steady = steady_state(scene, model)
    x0 = initial_state(model, steady, perturbation) - np.asarray(steady.x, dtype=float)
    x0[-2:] = 0.0
    traj = simulate(model, steady, t_end, settings=settings, x0=x0, progress=progress,
                    schedule=PressureSchedule.breath(scene.ustar, t_end))
    return Run(scene, model, steady, traj, classify(traj, steady), time.perf_counter() - start)


def write_wav(sound: Sound, path) -> float:
    """Write ``sound`` as a 16-bit mono WAV normalized to its peak; returns the scale
    factor in Pa per count (the pressure is ``count × factor``)."""
    from scipy.io import wavfile
    peak = float(np.max(np.abs(sound.pressure))) if sound.pressure.size else 0.0
    factor = peak / 32767 if peak > 0 else 1.0
    wavfile.write(path, sound.rate, np.round(sound.pressure / factor).astype(np.int16))
    return factor
