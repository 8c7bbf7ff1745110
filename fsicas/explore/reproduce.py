"""The command line and the Python lines that reproduce the explorer's current view."""
from __future__ import annotations

from ..scene import Scene

__all__ = ["command_line", "python_lines"]

#: The Scene fields written out (those the page sets, and k0 where a preset sets it).
FIELDS = ("mstar", "ustar", "hstar", "friction", "k0", "kl", "zeta", "modes")


def _values(scene: Scene) -> dict:
    default = Scene()
    return {k: getattr(scene, k) for k in FIELDS
            if k != "k0" or getattr(scene, k) != getattr(default, k)}


def _beam(scene: Scene) -> dict:
    """The beam fields where the beam is not the default Euler-Bernoulli one."""
    if scene.beam == Scene().beam:
        return {}
    return {"beam": scene.beam, "slenderness": scene.slenderness}


def command_line(scene: Scene, command: str = "eig") -> str:
    """``fsicas <command> --mstar ... --modes ...`` for ``scene``'s values."""
    values = {**_values(scene), **_beam(scene)}
    options = " ".join(f"--{k.replace('_', '-')} {v:g}" if not isinstance(v, str)
                       else f"--{k} {v}" for k, v in values.items())
    return f"fsicas {command} {options} --json"


def python_lines(scene: Scene) -> str:
    """The Python lines that compute the instant view and the onset of ``scene``."""
    args = ", ".join(f"{k}={v!r}" for k, v in {**_values(scene), **_beam(scene)}.items())
    return ("from fsicas import Scene\n"
            "from fsicas.linear import critical_velocity, linear_stability\n"
            f"scene = Scene({args})\n"
            "stability = linear_stability(scene)   # .stable, .eigenvalues\n"
            "onset = critical_velocity(scene)      # .kind, .ustar, .omega, .l1")
