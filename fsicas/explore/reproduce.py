"""The command line and the Python lines that reproduce the explorer's current view."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene import Scene

__all__ = ["SceneFile", "command_line", "python_lines", "sound_lines"]

#: The Scene fields written out (those the page sets, and k0 where a preset sets it).
FIELDS = ("mstar", "ustar", "hstar", "friction", "k0", "kl", "zeta", "modes")


@dataclass(frozen=True)
class SceneFile:
    """A scene file loaded on the page: its name and its scene (the reference the page's
    values are written against: ``--scene NAME`` and the options that differ)."""

    name: str
    scene: Scene


def _values(scene: Scene, file: SceneFile | None) -> dict:
    """The fields to write: without a file all of :data:`FIELDS` (k0 where it is not the
    default); with one, those that differ from the file's."""
    if file is not None:        # the boxes show 6 digits: a value read back is the file's
        return {k: getattr(scene, k) for k in FIELDS
                if not np.allclose(getattr(scene, k), getattr(file.scene, k), rtol=1e-5, atol=0)}
    default = Scene()
    return {k: getattr(scene, k) for k in FIELDS
            if k != "k0" or getattr(scene, k) != getattr(default, k)}


def _beam(scene: Scene, file: SceneFile | None) -> dict:
    """The beam fields where the beam is not the default Euler-Bernoulli one (nor the
    file's), and its ends where they are not the default clamped-free (nor the file's)."""
    reference = Scene() if file is None else file.scene
    ends = {} if scene.ends == reference.ends else {"ends": scene.ends}
    if (scene.beam, scene.slenderness, scene.poisson) == (reference.beam, reference.slenderness,
                                                          reference.poisson):
        return ends
    poisson = {} if scene.poisson == Scene().poisson else {"poisson": scene.poisson}
    return {"beam": scene.beam, "slenderness": scene.slenderness, **poisson, **ends}


def _option(value) -> str:
    """An option's value as the command line takes it (a per-mode ζ comma-separated: no
    command takes it, a scene file does)."""
    if isinstance(value, str):
        return value
    if isinstance(value, tuple):
        return ",".join(f"{v:g}" for v in value)
    return f"{value:g}"


def command_line(scene: Scene, command: str = "eig", file: SceneFile | None = None,
                 **extra) -> str:
    """``fsicas <command> --mstar ... --modes ...`` for ``scene``'s values (with a scene
    file, ``--scene NAME`` and the values that differ from it); ``extra``: the command's
    own options (``t_end=20``; True for a flag), one of them in place of a scene field of
    the same name (``grazing``'s ``--mstar LO:HI:COUNT``)."""
    values = {**_values(scene, file), **_beam(scene, file)}
    values = {k: v for k, v in values.items() if k not in extra}
    options = [f"--{k.replace('_', '-')} {_option(v)}" for k, v in values.items()]
    options += [f"--{k.replace('_', '-')}" + ("" if v is True else f" {_option(v)}")
                for k, v in extra.items()]
    head = [] if file is None else [f"--scene {file.name}"]
    return " ".join(["fsicas", command, *head, *options, "--json"])


def python_lines(scene: Scene, file: SceneFile | None = None) -> str:
    """The Python lines that compute the instant view and the onset of ``scene``."""
    values = {**_values(scene, file), **_beam(scene, file)}
    args = ", ".join(f"{k}={v!r}" for k, v in values.items())
    if file is None:
        head, make = "from fsicas import Scene", f"Scene({args})"
    else:
        head = "from fsicas.scene import load_scene"
        make = f"load_scene({file.name!r}{', ' if args else ''}{args})"
    return (f"{head}\n"
            "from fsicas.linear import critical_velocity, linear_stability\n"
            f"scene = {make}\n"
            "stability = linear_stability(scene)   # .stable, .eigenvalues\n"
            "onset = critical_velocity(scene)      # .kind, .ustar, .omega, .l1")


def sound_lines(scene: Scene, t_end: float, distance: float, duration: float,
                max_hz: float) -> str:
    """The Python lines that compute the snore of the physical ``scene`` (its scales
    written out) and its spectrum as the page does: the run to ``t_end``, the sound at
    ``distance`` m looped to ``duration`` s, its lines up to ``max_hz``."""
    args = ", ".join(f"{k}={v!r}" for k, v in {**_values(scene, None), **_beam(scene, None)}.items())
    return ("from fsicas import Scene\n"
            "from fsicas.units import Scales\n"
            "from fsicas.timedomain.run import run_case\n"
            "from fsicas.timedomain.sound import cycle_sound, line_spectrum\n"
            f"scene = Scene({args}, scales={scene.scales!r})\n"
            f"run = run_case(scene, {t_end!r})\n"
            f"sound = cycle_sound(run.trajectory, scene.scales, {distance!r}, {duration!r})\n"
            f"hz, spl_db = line_spectrum(sound.pressure, sound.rate, {max_hz!r})")
