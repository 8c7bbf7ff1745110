"""The radiated sound (fsicas.timedomain.sound, fsicas sound): the monopole's closed form
for a sinusoidal flow, the exact flow derivative against the sampled outlet flow, the
WAV's fundamental, the level of a known sine, the command line and its refusals."""
import contextlib
import io
import json

import numpy as np
import pytest
from scipy.io import wavfile

from fsicas import Scene
from fsicas.cli import main
from fsicas.model.accuracy import IMPACT_QUADRATURE_TOL
from fsicas.timedomain.energy import outlet_flow_rates
from fsicas.timedomain.integrators import Settings
from fsicas.timedomain.run import run_case
from fsicas.timedomain.sound import (AUDIO_RATE, cycle_sound, flow_derivative, line_spectrum,
                                     looped_sound, median_rate, monopole_pressure, spl_db,
                                     write_wav)
from fsicas.units import Scales

#: Scales of a 3 cm strip with T = 10 ms (the M* = 1 cycle then sings at 764 Hz).
SCALES = Scales(length=0.03, time=0.01, pressure=1.0, width=0.03, fluid_density=1.2, gap=0.004)


@pytest.fixture(scope="module")
def lco_run():
    """A settled contact-free limit cycle, N = 4 (about 5 s)."""
    run = run_case(Scene(mstar=1.0, ustar=6.5, zeta=0.01, modes=4), 12.0,
                   settings=Settings(rtol=1e-8, atol=1e-10, dt_out=1e-3))
    assert run.outcome.outcome == "lco"
    return run


def test_sinusoidal_flow_gives_the_closed_form_amplitude():
    """Q(t) = Q̂ sin ωt per unit width: p̂ = ρ ω b Q̂ L² / T / (4π r) in SI units."""
    q_hat, omega, r = 0.02, 2 * np.pi / 0.13, 0.3            # nondimensional Q̂, ω
    t = np.linspace(0.0, 0.26, 401)
    sound = looped_sound(t, q_hat * omega * np.cos(omega * t), 0.0, 0.13, SCALES, r, 0.5)
    q_si = q_hat * SCALES.width * SCALES.length**2 / SCALES.time      # m^3/s
    expected = SCALES.fluid_density * (omega / SCALES.time) * q_si / (4 * np.pi * r)
    assert sound.harmonics_pa[0] == pytest.approx(expected, rel=1e-6)
    assert max(sound.harmonics_pa[1:]) < 1e-6 * expected
    assert np.max(np.abs(sound.pressure)) == pytest.approx(expected, rel=1e-6)
    assert sound.fundamental_hz == pytest.approx(1 / (0.13 * SCALES.time), rel=1e-12)
    assert monopole_pressure(4 * np.pi, 1.0, 1.0) == pytest.approx(1.0)


def test_spl_of_a_known_sine():
    t = np.arange(AUDIO_RATE) / AUDIO_RATE
    p = 0.2 * np.sin(2 * np.pi * 440 * t)
    assert spl_db(p) == pytest.approx(20 * np.log10(0.2 / np.sqrt(2) / 20e-6), abs=1e-9)
    assert spl_db(np.sqrt(2) * 20e-6 * np.sin(2 * np.pi * 440 * t)) == pytest.approx(0.0, abs=1e-9)


def test_line_spectrum_of_two_known_sines():
    """Each line of a sum of sines on the bins reads its own level (the mean left out);
    between them, far below."""
    t = np.arange(2 * AUDIO_RATE) / AUDIO_RATE
    p = 3.0 + 0.2 * np.sin(2 * np.pi * 440 * t) + 0.02 * np.sin(2 * np.pi * 1000.5 * t)
    hz, db = line_spectrum(p, AUDIO_RATE, max_hz=2000.0)
    assert hz[-1] == 2000.0 and hz[1] == 0.5
    for f, a in ((440.0, 0.2), (1000.5, 0.02)):
        assert db[np.flatnonzero(hz == f)[0]] == pytest.approx(spl_db(a * np.sin(2 * np.pi * f * t)),
                                                                abs=1e-6)
    assert db[0] < 0 and db[np.flatnonzero(hz == 700.0)[0]] < 0


def test_flow_derivative_is_the_time_derivative_of_the_outlet_flow(lco_run):
    """xdot route against second-order central differences of the sampled outlet flow
    over the settled part: the difference is the differences' own O(h²) error (it grows
    4x when the step doubles), 3e-3 of the signal at 200 samples per period."""
    tr = lco_run.trajectory
    half = tr.t.size // 2
    g = flow_derivative(tr)
    total = outlet_flow_rates(tr).sum(axis=1)
    errors = []
    for step in (1, 2):
        fd = np.gradient(total[::step], tr.t[::step], edge_order=2)
        errors.append(np.max(np.abs(fd - g[::step])[half // step:-2]))
    assert errors[1] / errors[0] == pytest.approx(4.0, rel=0.1)
    assert errors[0] < 5e-3 * np.max(np.abs(g))


def _peak_frequency(samples, rate, lo, hi):
    """Frequency of the largest Hann-windowed spectral peak in [lo, hi] Hz (zero padded,
    parabolic refinement of the log magnitude)."""
    n = 1 << 22
    spec = np.abs(np.fft.rfft(samples * np.hanning(samples.size), n))
    f = np.fft.rfftfreq(n, 1 / rate)
    band = np.flatnonzero((f >= lo) & (f <= hi))
    j = band[np.argmax(spec[band])]
    a, b, c = np.log(spec[j - 1:j + 2])
    return f[j] + 0.5 * (a - c) / (a - 2 * b + c) * (f[1] - f[0])


def _magnitude(samples, rate, frequency):
    """|sum_k w_k p_k exp(-2 pi i f t_k)| / n, w the Hann window: the spectrum at f."""
    t = np.arange(samples.size) / rate
    return abs(np.sum(samples * np.hanning(samples.size)
                      * np.exp(-2j * np.pi * frequency * t))) / samples.size


def test_wav_pitch_of_a_symmetric_cycle_is_two_over_the_period(lco_run, tmp_path):
    """Symmetric channels: the total flow repeats each half cycle, so the file has no
    line at 1/T (below 1e-2 of the second harmonic): its fundamental is 2/T, and its
    strongest line (the WAV read back, its own FFT) is the one reported as dominant."""
    sound = cycle_sound(lco_run.trajectory, SCALES, 0.3, 0.5)
    path = tmp_path / "lco.wav"
    factor = write_wav(sound, path)
    rate, counts = wavfile.read(path)
    assert rate == AUDIO_RATE and counts.dtype == np.int16
    assert np.max(np.abs(counts * factor - sound.pressure)) <= 0.5 * factor + 1e-15
    f0 = 1 / (lco_run.outcome.period * SCALES.time)
    samples = counts.astype(float)
    found = _peak_frequency(samples, rate, 0.5 * f0, rate / 2 - 1)
    assert sound.dominant_hz == pytest.approx(found, rel=1e-4)
    assert sound.fundamental_hz == pytest.approx(2 * f0, rel=1e-3)
    assert _magnitude(samples, rate, f0) < 1e-2 * _magnitude(samples, rate, 2 * f0)


def _sound_cli(*extra):
    """``(exit code, JSON)`` of ``fsicas sound`` on one breath of the soft palate."""
    argv = ["sound", "--physical", "soft_palate", "--flow", "25L/min", "--modes", "4",
            "--breath", "--duration", "1", "--dt-out", "5e-4", *extra, "--json"]
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(argv)
    return code, json.loads(out.getvalue())


@pytest.fixture(scope="module")
def breath(tmp_path_factory):
    """The default breath (quadrature controlled), with its WAV and figure."""
    folder = tmp_path_factory.mktemp("breath")
    wav, png = folder / "snore.wav", folder / "spec.png"
    code, out = _sound_cli("--out", str(wav), "--plot", str(png))
    return code, out, wav, png


@pytest.fixture(scope="module")
def coarse_breath():
    """The same breath on the scene's 28 nodes (``--quadrature-tol none``)."""
    return _sound_cli("--quadrature-tol", "none")


def test_cli_writes_the_wav_and_json(breath):
    code, out, wav, png = breath
    assert code == 0, out
    for key in ("fundamental_hz", "fundamental_ci_hz", "spl_db", "harmonics_pa", "distance_m",
                "meta", "wav_pa_per_count", "onset_s", "offset_s"):
        assert key in out
    assert out["distance_m"] == 0.3 and len(out["harmonics_pa"]) == 10
    # the breath's quadrature is controlled to a contact run's bound: 28 nodes are 3.7e-3
    # off, the breath is run again on more (56 or 112: the estimate at 56 is near the bound)
    assert out["quadrature_tol"] == IMPACT_QUADRATURE_TOL and out["quadrature_nodes"] in (56, 112)
    assert out["quadrature_error"] <= IMPACT_QUADRATURE_TOL and out["status"] == "success"
    assert out["meta"]["units"]["spl_db"].startswith("dB SPL")
    rate, counts = wavfile.read(wav)
    assert rate == 44100 and counts.size == pytest.approx(44100, abs=2)
    assert np.max(np.abs(counts)) == 32767 and png.stat().st_size > 0
    p = counts * out["wav_pa_per_count"]
    assert spl_db(p) == pytest.approx(out["spl_db"], abs=0.01)
    # the dominant line is the WAV's strongest (its own FFT, zero padded), to 1/4 bin
    found = _peak_frequency(counts.astype(float), rate, 1.0, rate / 2 - 1)
    assert out["dominant_hz"] == pytest.approx(found, abs=0.25 * rate / counts.size)


def test_an_irregular_snore_says_how_sure_its_pitch_is(breath, coarse_breath):
    """This breath bounces irregularly on the walls (returns 10 to 60 ms apart): its
    fundamental, the median return rate, is a statistic. Its interval holds the value of
    the same breath on another quadrature (28 nodes against 56 or 112: the motion differs
    after the first bounces), and the run warns of it."""
    fine, coarse = breath[1], coarse_breath[1]
    for out in (fine, coarse):
        lo, hi = out["fundamental_ci_hz"]
        assert lo < out["fundamental_hz"] < hi and hi - lo > 0.05 * out["fundamental_hz"]
        assert any("snore is irregular" in w and f"{lo:.4g}-{hi:.4g} Hz" in w
                   for w in out["warnings"]), out["warnings"]
    assert fine["fundamental_hz"] != pytest.approx(coarse["fundamental_hz"], rel=1e-3)
    lo, hi = fine["fundamental_ci_hz"]
    assert lo <= coarse["fundamental_hz"] <= hi


def test_median_rate_interval_covers_the_true_median():
    """Intervals drawn from a log-normal law with median 20 ms, 20 at a time: the 95 %
    interval of the median rate holds the true 50 Hz in 90 to 99 % of 300 samples (the
    percentile bootstrap of a median of 20 covers about 95 %), and a regular train's
    interval is its rate."""
    rng = np.random.default_rng(1)
    hits = 0
    for _ in range(300):
        rate, (lo, hi) = median_rate(0.02 * np.exp(0.4 * rng.standard_normal(20)))
        assert lo < rate < hi
        hits += lo <= 50.0 <= hi
    assert 0.90 * 300 <= hits <= 0.99 * 300
    assert median_rate(np.full(7, 0.025)) == (40.0, (40.0, 40.0))
    assert median_rate([0.02, 0.03])[1] == (0.0, np.inf)


@pytest.mark.parametrize("argv, option", [
    (["sound", "--modes", "4"], "--physical"),
    (["sound", "--physical", "soft_palate", "--distance", "0"], "--distance"),
    (["sound", "--physical", "soft_palate", "--duration", "-1"], "--duration"),
    (["sound", "--physical", "soft_palate", "--out", "snore.mp3"], "--out"),
    (["sound", "--physical", "soft_palate", "--out", "/nonexistent/x.wav"], "--out"),
    (["sound", "--physical", "soft_palate", "--plot", "spec.xyz"], "--plot"),
    (["sound", "--physical", "soft_palate", "--flow", "20kg"], "--flow"),
    (["sound", "--physical", "soft_palate", "--mstar", "1"], "--mstar"),
    (["sound", "--physical", "soft_palate", "--quadrature-tol", "2"], "--quadrature-tol"),
    (["sound", "--physical", "soft_palate", "--quadrature-tol", "abc"], "--quadrature-tol"),
])
def test_bad_inputs_are_refused(capsys, argv, option):
    assert main([*argv, "--json"]) == 2
    error = json.loads(capsys.readouterr().out)["error"]
    assert option in error


def test_quadrature_not_controlled_when_asked(coarse_breath):
    """``--quadrature-tol none``: one run on the scene's 28 nodes, its error reported
    (3.7e-3 here) and not judged; the default run repeats it on 56 nodes
    (test_cli_writes_the_wav_and_json)."""
    code, out = coarse_breath
    assert code == 0 and out["quadrature_nodes"] == 28 and out["quadrature_tol"] is None
    assert out["quadrature_error"] > IMPACT_QUADRATURE_TOL and out["status"] == "success"


def test_the_default_run_is_long_enough_for_the_sound_asked(capsys, monkeypatch):
    """Without --t-end the run settles for 20 T, or covers --duration after 10 T of start-up
    when the sound is longer (the harvester's T is 0.047 s: 2 s are 42 T)."""
    import fsicas.cli.sound as sound_cli
    asked = {}

    def stop(scene, t_end, **kwargs):
        asked["T"], asked["t_end"] = scene.scales.time, t_end
        raise ValueError("stopped by the test")
    monkeypatch.setattr(sound_cli, "run_case", stop)
    for preset, extra in (("harvester", []), ("soft_palate", []), ("harvester", ["--t-end", "30"])):
        assert main(["sound", "--physical", preset, *extra, "--json"]) == 2
        capsys.readouterr()
        heard = 2.0 / asked["T"]
        expected = 30.0 if extra else max(20.0, heard + 10.0)
        assert asked["t_end"] == pytest.approx(expected, rel=1e-12)
        if preset == "harvester" and not extra:
            assert heard > 20 and asked["t_end"] > heard
