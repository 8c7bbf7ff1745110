"""Figure of a radiated sound (:mod:`fsicas.timedomain.sound`): the pressure signal and
its spectrogram in dB SPL."""
from __future__ import annotations

import numpy as np

from ..timedomain.sound import P_REF
from .backend import finish, styled, subplots

__all__ = ["plot_sound"]

#: Frequencies shown: up to this many harmonics of the fundamental (or 2 kHz without one).
_SHOWN_HARMONICS = 25


def _spectrogram(sound):
    """Times (s), frequencies (Hz) and levels (dB re 20 µPa, RMS per bin) of Hann
    segments at least four periods (and 0.1 s) long."""
    from scipy.signal import spectrogram
    span = max(0.1, 4 * (sound.period_s or 0.0))
    seg = int(min(sound.pressure.size, max(256, span * sound.rate)))
    f, t, s = spectrogram(sound.pressure, fs=sound.rate, window="hann", nperseg=seg,
                          noverlap=seg * 3 // 4, scaling="spectrum")
    return t, f, 10 * np.log10(np.maximum(s, 1e-30) / P_REF**2)


@styled
def plot_sound(sound, path=None, title: str | None = None):
    """The pressure at the listener over the first periods (or the whole signal) and the
    spectrogram of the whole signal. Returns the Figure."""
    fig, axes = subplots(2, 1, figsize=(6.0, 5.0))
    ax = axes[:, 0]
    shown = sound.pressure.size if sound.source != "cycle" else \
        min(sound.pressure.size, int(4 * sound.period_s * sound.rate))
    ax[0].plot(np.arange(shown) / sound.rate, sound.pressure[:shown] * 1e3, lw=0.7)
    ax[0].set_xlabel("time from the start of the sound (s)")
    ax[0].set_ylabel(f"pressure $p$ at $r$ = {sound.distance_m:g} m (mPa)")
    f0, ci = sound.fundamental_hz, sound.fundamental_ci_hz
    pitch = "" if f0 is None else f", fundamental {f0:.4g} Hz" + (
        "" if ci is None or ci[0] == ci[1] else f" ({ci[0]:.3g}-{ci[1]:.3g} Hz, 95 %)")
    ax[0].set_title(title or f"{sound.spl_db:.1f} dB SPL{pitch}")
    t, f, level = _spectrogram(sound)
    top = min(sound.rate / 2, _SHOWN_HARMONICS * f0 if f0 else 2000.0)
    keep = f <= top
    mesh = ax[1].pcolormesh(t, f[keep], level[keep], shading="nearest", cmap="magma",
                            vmin=np.max(level[keep]) - 60, vmax=np.max(level[keep]))
    fig.colorbar(mesh, ax=ax[1], label="level (dB re 20 µPa)")
    ax[1].set_xlabel("time from the start of the sound (s)")
    ax[1].set_ylabel("frequency (Hz)")
    return finish(fig, path)
