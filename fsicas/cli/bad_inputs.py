"""The catalogue of bad and edge inputs that every command must refuse before any work
(docs/reliability.md): each :class:`Case` is a command line, the files it reads, and
what its message must name. :mod:`fsicas.cli.reliability` runs them and writes the
table of docs/reliability.md; ``tests/test_bad_inputs.py`` runs them too.
"""
from __future__ import annotations

import inspect
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Union

__all__ = ["Case", "CASES", "GROUPS"]

#: A file a case reads: its text, its bytes, or a function of the case's folder.
Content = Union[str, bytes, Callable[[Path], str]]


@dataclass(frozen=True)
class Case:
    """``fsicas argv --json`` run in a folder holding ``files``; it must end with exit
    status 2 and a message that contains ``named``. ``group``: its row of the table."""

    group: str
    argv: tuple
    named: str
    files: tuple = ()

    @property
    def label(self) -> str:
        return " ".join(self.argv)


#: The rows of the table, in order: what each group of cases tries.
GROUPS = {
    "scene options": "each scene option (`--mstar --ustar --hstar --friction --k0 --kl --zeta "
                     "--modes --quad-nodes --contact-stiffness --contact-eps`) out of range (0, "
                     "negative, `--contact-eps 1.5`), not finite (`nan`, `inf`), not a number "
                     "(`abc`), absurdly large (`--mstar 1e308`, `--friction 1e300`, `--modes "
                     "99999999999999999999`), of the wrong kind (`--modes 2.5`), on `steady`, "
                     "`eig`, `lco` and `simulate`",
    "simulate": "`simulate`: `--t-end` 0, -1, nan; `--rtol` 0.5, 0, -1e-8; `--atol` 0, 1; `--dt-out` "
                "0, -1e-3; `--perturbation 40`; `--ramp-time 0`; `--breath-period -1`; "
                "`--ustar-start 1e308`",
    "grids": "`boundary`, `map`: grids that are empty, malformed, not finite, negative on a log "
             "scale, too long, or repeat a value (`--ustar 4,5,4`, `--mstar 1:1:3`); a map "
             "of both directions (`--ustar -1:1:3`); "
             "`--ustar-max` 0 or -5; no pressure losses at all",
    "other options": "`map`, `lco`, `modes`, `grazing`, `sound`, `design`, `diagram`: "
                     "`--workers` 0 or beyond the cores without `--oversubscribe`, `--t-end 0`, `--max-points 0`, "
                     "`--ntst 0`, `--ncol` 0 or 100000, `design --vary nonsense`, "
                     "`--target-flow \"1e308 L/min\"`, `--ustar-max` -1 or 1e308, `--modes 100000000`, `sound` without "
                     "`--physical` or with `--duration 1e-300`, `diagram --depth 9`",
    "sizes": "sizes that cannot fit: `simulate --dt-out 1e-9`, `--t-end 1e12 --full`, "
             "`--breath-period 1e-300`; `lco --ntst 100000`, `--impact-ntst 100000`; a map of "
             "2000 x 2000 points; `map --t-end 1e12`",
    "direction": "the flow's direction: `--direction sideways`; a sign given twice (`--direction "
                 "reverse --ustar -2`, `map --direction reverse --ustar -5:-1:3`, `--physical soft_palate --flow=-20L/min --direction "
                 "reverse`, `design --direction reverse --target-flow=-30L/min`); `simulate --schedule tidal --direction reverse`, "
                 "`--expiration-peak` without `--schedule tidal`",
    "scene files": "scene files: missing, a folder, invalid TOML, not UTF-8, nested thousands "
                   "deep, an unknown key, `zeta = \"abc\"`, `direction = \"up\"`, "
                   "`direction = \"reverse\"` with `ustar = -3`, `modes = 1e30`, `contact = \"yes\"`, "
                   "`ends = \"free-free\"`, "
                   "a list or a nested list where a number belongs (`mstar = [[1]]`)",
    "physical input": "physical input: `E = \"3 * 10**400 Pa\"`, `L = \"1e300 m\"`, `--flow "
                      "\"1 * 10**10**8 m/s\"`, `--flow \"1e999 m/s\"`, `E = -3000`, a nested "
                      "list, `viscosity` 0, negative or 1e300, a gap of 150 mm (H* = 10)",
    "study files": "study files: `[settings]` `t_end = -1`, `\"abc\"`, `rtol = 0.5`, `t_end = "
                   "1e12`, `ustar_max = 1e308`; `[scene] modes = 10000`; `sound` without "
                   "`physical`; nested lists in `[grid]`, `[sample]`, `[scene]`, `[settings]`, "
                   "`physical`; values out of range in `[grid]` or `[sample]` (`mstar = -1`, `modes = 2.5`, a "
                   "normal zeta); `outcome` without a flow; 10^7 points (a grid, an axis, a "
                   "sample)",
    "results files": "results files resumed (`map --out`, `study`'s `NAME.jsonl`): a record "
                     "without `ustar` or `index`, a `ustar` that is text, a line that is a list "
                     "or not JSON",
}

_SCENE_VALUES = {
    "--mstar": ["0", "-1", "nan", "inf", "1e308", "abc"],
    "--ustar": ["nan", "inf", "-inf", "1e5", "-1e5", "abc"],
    "--hstar": ["0", "-0.1", "nan", "abc", "1e300"],
    "--friction": ["-0.1", "nan", "inf", "abc", "1e300"],
    "--k0": ["-1", "nan", "abc", "1e300"],
    "--kl": ["-1", "nan", "abc", "1e300"],
    "--zeta": ["-0.01", "nan", "inf", "abc", "1e308"],
    "--modes": ["0", "-3", "2.5", "1000", "99999999999999999999", "abc"],
    "--quad-nodes": ["5", "100000", "2.5", "-1", "abc"],
    "--contact-stiffness": ["0", "-1e6", "nan", "abc", "1e300"],
    "--contact-eps": ["0", "1", "1.5", "-1e-3", "nan"],
}
_SCENE_COMMANDS = {"steady": (), "eig": (), "lco": (), "simulate": ("--t-end", "1")}


def _scene_cases():
    return [Case("scene options", (command, *extra, option, value), option[2:].replace("-", "_"))
            for command, extra in _SCENE_COMMANDS.items()
            for option, values in _SCENE_VALUES.items() for value in values]


_SIM = ("simulate", "--t-end", "1")
#: Options of the commands, by group: (argv, what the message names).
_OPTIONS = {
    "simulate": [(("simulate", "--t-end", v), "t-end") for v in ("0", "-1", "nan")] + [
        ((*_SIM, "--rtol", "0.5"), "rtol"), ((*_SIM, "--rtol", "0"), "rtol"),
        ((*_SIM, "--rtol", "-1e-8"), "rtol"),
        ((*_SIM, "--atol", "0"), "atol"), ((*_SIM, "--atol", "1"), "atol"),
        ((*_SIM, "--dt-out", "0"), "dt_out"), ((*_SIM, "--dt-out", "-1e-3"), "dt_out"),
        ((*_SIM, "--perturbation", "40"), "perturbation"),
        ((*_SIM, "--schedule", "ramp", "--ramp-time", "0"), "ramp-time"),
        ((*_SIM, "--schedule", "breath", "--breath-period", "-1"), "breath-period"),
        ((*_SIM, "--schedule", "ramp", "--ustar-start", "1e308"), "--ustar-start")],
    "grids": [(("boundary", "--mstar", v), "mstar") for v in
              ("0:1:5", "1:10:0", "1:10:100000", "a,b", "-1", "1:10", "nan")] + [
        (("boundary", "--mstar", "1", "--ustar-max", "0"), "--ustar-max"),
        (("boundary", "--mstar", "1", "--ustar-max", "-5"), "--ustar-max"),
        (("boundary", "--mstar", "1", "--friction", "0", "--k0", "0", "--kl", "0"),
         "pressure drop"),
        (("boundary", "--mstar", "0.5,0.5"), "--mstar repeats 0.5")] + [
        (("map", "--ustar", v), "ustar") for v in ("4:14", "4:14:0", "nan")] + [
        (("map", "--ustar", "-1:1:3"), "one direction"), (("map", "--mstar", "0:1:3"), "mstar"),
        (("map", "--ustar", "4,5,4"), "--ustar repeats 4"),
        (("map", "--mstar", "1:1:3"), "--mstar repeats 1")],
    "other options": [
        (("map", "--t-end", "0"), "t_end"), (("map", "--workers", "0"), "workers"),
        (("map", "--modes", "0"), "modes"), (("map", "--modes", "1000"), "modes"),
        (("map", "--workers", "100000"), "--oversubscribe"),
        (("grazing", "--workers", "100000"), "--oversubscribe"),
        (("lco", "--max-points", "0"), "max_points"), (("lco", "--ntst", "0"), "ntst"),
        (("lco", "--ncol", "0"), "ncol"), (("lco", "--ncol", "100000"), "ncol"),
    (("design", "--physical", "soft_palate", "--target-flow", "30L/min", "--vary", "nonsense"),
     "nonsense"),
    (("design", "--physical", "soft_palate", "--target-flow", "1e308 L/min", "--vary", "E"),
     "--target-flow"), (("lco", "--ustar-max", "-1"), "--ustar-max"),
        (("grazing", "--ustar-max", "1e308"), "--ustar-max"),
        (("lco", "--contact"), "contact"), (("onset", "--ustar-max", "1e308"), "--ustar-max"),
        (("modes", "--modes", "0"), "modes"), (("modes", "--modes", "100000000"), "modes"),
        (("sound", "--out", "s.wav"), "--physical"),
        (("sound", "--physical", "soft_palate", "--duration", "1e-300"), "--duration"),
        (("diagram", "--depth", "9"), "--depth"), (("diagram", "--ntst", "0"), "--ntst"),
        (("diagram", "--mstar", "0:1:3"), "--mstar"), (("diagram", "--contact"), "contact")],
    "direction": [
        (("steady", "--direction", "sideways"), "--direction"),
        (("steady", "--direction", "reverse", "--ustar", "-2"), "negative ustar"),
        (("map", "--direction", "reverse", "--ustar", "-5:-1:3"), "negative ustar"),
        (("onset", "--physical", "soft_palate", "--flow=-20L/min", "--direction", "reverse"),
         "negative and a direction"),
        (("design", "--physical", "soft_palate", "--direction", "reverse",
          "--target-flow=-30L/min", "--vary", "E"), "negative and a direction"),
        ((*_SIM, "--schedule", "tidal", "--direction", "reverse"), "tidal"),
        ((*_SIM, "--expiration-peak", "1"), "--expiration-peak")],
    "sizes": [
        (("simulate", "--mstar", "1", "--ustar", "6", "--dt-out", "1e-9", "--t-end", "10"),
         "GiB"),
        (("simulate", "--mstar", "1", "--ustar", "6", "--t-end", "1e12", "--full"), "--t-end"),
        (("simulate", "--ustar", "9", "--schedule", "breath", "--breath-period", "1e-300",
          "--t-end", "1"), "--breath-period"),
        (("lco", "--mstar", "1", "--ntst", "100000"), "ntst must be at most"),
        (("lco", "--mstar", "1", "--through-contact", "--impact-ntst", "100000"), "ntst"),
        (("map", "--ustar", "1:10:2000", "--mstar", "1:10:2000"), "100,000"),
        (("map", "--ustar", "6", "--mstar", "1", "--t-end", "1e12"), "GiB")],
}


def _option_cases():
    return [Case(group, argv, named) for group, cases in _OPTIONS.items() for argv, named in cases]


def _file_cases():
    texts = {"modes = = 3": "TOML", "heights = [[0.05]]": "heights", 'zeta = "abc"': "zeta",
             "modes = 99999999999999999999": "modes", "modes = 1e30": "modes",
             'contact = "yes"': "contact", 'ends = "free-free"': "ends", "mstar = [1, 2]": "mstar", "mstar = [[1]]": "mstar",
             "zeta = [[[0.1]]]": "zeta", "modes = [[3]]": "modes", "hstar = {a = 1}": "hstar",
             "a = " + "[" * 5000 + "]" * 5000: "nested too deeply",
             'direction = "up"': "direction", 'direction = "reverse"\nustar = -3': "negative ustar"}
    cases = [Case("scene files", ("steady", "--scene", "s.toml"), named, (("s.toml", text),))
             for text, named in texts.items()]
    return cases + [
        Case("scene files", ("steady", "--scene", "s.toml"), "TOML", (("s.toml", b"\xff\xfe\x00"),)),
        Case("scene files", ("steady", "--scene", "missing.toml"), "no such file"),
        Case("scene files", ("steady", "--scene", "."), "folder")]


_AIR = ('E = "3 kPa"', "nu = 0.45", 'rho_s = "1040 kg/m^3"', 'e = "2.5 mm"', 'L = "30 mm"',
        'b = "30 mm"', 'gap = "2 mm"', 'rho_f = "1.2 kg/m^3"', 'flow = "20 L/min"')


def _physical_cases():
    preset = {'E = "3 * 10**400 Pa"': "one number, then a unit", 'L = "1e300 m"': "beyond what a float",
              "E = -3000": "E", "zeta = -0.1": "zeta", 'E = [["3 kPa"]]': "E",
              'gap = "150 mm"': "H* = (H1 + H2)/L = 10"}
    own = {"viscosity = 0": "viscosity", "viscosity = -1.8e-5": "viscosity",
           "viscosity = 1e300": "viscosity = 1e+300"}
    files = [('preset = "soft_palate"\n[physical]\n' + line, named) for line, named in preset.items()]
    files += [("\n".join(("[physical]", *_AIR, line)), named) for line, named in own.items()]
    cases = [Case("physical input", ("onset", "--physical", "p.toml"), named, (("p.toml", text),))
             for text, named in files]
    return cases + [Case("physical input", ("onset", "--physical", "soft_palate", "--flow", flow),
                         "--flow") for flow in ("1 * 10**10**8 m/s", "1e999 m/s")]


def _study(text: str) -> str:
    return text.replace("; ", "\n")


def _study_cases():
    onset = 'analysis = "onset"; '
    texts = {
        'analysis = "outcome"; [settings]; t_end = -1; [grid]; ustar = [6.0]': "t_end",
        'analysis = "outcome"; [settings]; t_end = "abc"; [grid]; ustar = [6.0]': "t_end",
        'analysis = "outcome"; [settings]; rtol = 0.5; [grid]; ustar = [6.0]': "rtol",
        'analysis = "outcome"; [settings]; t_end = 1e12; [grid]; ustar = [6.0]': "GiB",
        'analysis = "outcome"; [settings]; dt_out = 1e-12; [grid]; ustar = [6.0]': "GiB",
        'analysis = "outcome"; [scene]; modes = 10000; [grid]; ustar = [6.0]': "modes",
        'analysis = "sound"; [grid]; ustar = [6.0]': "physical",
        onset + "[settings]; ustar_max = 1e308; [grid]; mstar = [1.0]": "ustar_max",
        onset + "[settings]; ustar_max = [[40]]; [grid]; mstar = [1.0]": "ustar_max",
        onset + "[scene]; modes = [[3]]; [grid]; mstar = [1.0]": "modes",
        onset + "[grid]; mstar = [-1.0, 1.0]": "mstar = -1.0",
        onset + "[grid]; modes = [4, 2.5]": "modes = 2.5",
        onset + "[sample]; size = 5; zeta = {distribution = \"normal\", mean = 0, std = 1}": "zeta",
        'analysis = "outcome"; [grid]; mstar = [1.0]': "ustar > 0",
        onset + "[grid]; mstar = [[1, 2]]": "mstar", onset + "[grid]; mstar = [[[1]]]": "mstar",
        onset + "[grid]; mstar = {start = [[1]], stop = 2, num = 3}": "mstar",
        onset + "[grid]; mstar = {start = 1, stop = 2, num = [[3]]}": "num",
        onset + 'physical = "soft_palate"; [grid]; E = [["3 kPa"]]': "E",
        onset + 'physical = [["soft_palate"]]; [grid]; mstar = [1.0]': "physical",
        onset + "description = [[1]]; [grid]; mstar = [1.0]": "description",
        onset + "[sample]; size = 3; mstar = {distribution = \"uniform\", low = [[1]], high = 2}":
            "mstar",
        onset + "[sample]; size = 3; mstar = {distribution = \"lognormal\", median = 1, "
                "sigma = [[0.5]]}": "sigma",
        onset + "[sample]; size = [[3]]; mstar = {distribution = \"uniform\", low = 1, high = 2}":
            "size",
        onset + "[grid]; mstar = {start = 1, stop = 2, num = 10000}; zeta = {start = 0, stop = 1, "
                "num = 1000}": "100,000",
        onset + "[grid]; mstar = {start = 1, stop = 2, num = 10000000}": "100,000",
        onset + "[sample]; size = 10000000; mstar = {distribution = \"uniform\", low = 1, "
                "high = 2}": "100,000",
    }
    return [Case("study files", ("study", "s.toml", "--out", "s.csv"), named,
                 (("s.toml", _study(text)),)) for text, named in texts.items()]


def _map_file(*records: str) -> Callable[[Path], str]:
    """A map's results file for the command line's default map, with ``records``."""
    def write(folder: Path) -> str:
        from ..timedomain.impact_map import MAP_SCENE, impact_map, map_header
        from ..timedomain.outcome import Criteria
        settings = inspect.signature(impact_map).parameters["settings"].default
        header = map_header(MAP_SCENE, 30.0, settings, Criteria(stop_on_contact=True))
        return "\n".join([json.dumps({"header": header}), *records]) + "\n"
    return write


def _study_file(*records: str) -> Callable[[Path], str]:
    """The results file of the study ``s.toml`` of its folder, with ``records``."""
    def write(folder: Path) -> str:
        from ..studies.spec import load_study
        header = load_study(folder / "s.toml").header
        return "\n".join([json.dumps({"header": header}), *records]) + "\n"
    return write


def _records_cases():
    grid = ("map", "--ustar", "6", "--mstar", "1", "--out", "m.jsonl")
    bad = {'{"mstar": 1.0, "outcome": "decay"}': "the record has no 'ustar'",
           '{"ustar": "abc", "mstar": 1.0, "outcome": "decay"}': "the record's 'ustar' is 'abc', not a number",
           "[1, 2]": "not a record", "not json": "not a record"}
    cases = [Case("results files", grid, f"m.jsonl line 2: {named}", (("m.jsonl", _map_file(rec)),))
             for rec, named in bad.items()]
    study = 'analysis = "onset"\n[grid]\nmstar = [1.0, 2.0]\n'
    bad = {'{"mstar": 1.0}': "the record has no 'index'",
           '{"index": "0"}': "the record's 'index' is '0', not an integer"}
    return cases + [Case("results files", ("study", "s.toml", "--out", "s.csv"),
                         f"s.jsonl line 2: {named}", (("s.toml", study), ("s.jsonl", _study_file(rec))))
                    for rec, named in bad.items()]


#: Every case, in the order of :data:`GROUPS`.
CASES = tuple(sorted(_scene_cases() + _option_cases() + _file_cases() + _physical_cases()
                     + _study_cases() + _records_cases(), key=lambda c: list(GROUPS).index(c.group)))
