"""Physical units end to end: presets, the [physical] table, --flow, the onset command and
the 'physical' JSON object of each command, checked against conversions written out
here from the formulas (not through fsicas.units):

    D = E e^3 / (12 (1 - nu^2)),  T = L^2 sqrt(rho_s e / D),  pressure D / L^3,
    velocity L / T,  Q = U0 b (H1 + H2),  M* = rho_f L / (rho_s e),  H* = (H1 + H2) / L.
"""
import json
import math
from pathlib import Path

import pytest

from fsicas.cli import main
from fsicas.physical import (PhysicalValidityWarning, load_physical, parse_flow,
                             preset_names)

try:  # Python >= 3.11
    import tomllib
except ModuleNotFoundError:  # pragma: no cover
    import tomli as tomllib

#: The shipped soft-palate preset in SI units (fsicas/presets/soft_palate.toml).
PALATE = dict(E=3000.0, nu=0.45, rho_s=1040.0, e=2.5e-3, L=0.03, b=0.03, H=2e-3, rho_f=1.2,
              friction=0.14, flow_l_min=20.0)


def hand_scales(E, nu, rho_s, e, L, b, H, rho_f, **_):
    """T, pressure, velocity scales, M*, H* and the cross-section of a symmetric channel."""
    D = E * e**3 / (12 * (1 - nu**2))
    T = L**2 * math.sqrt(rho_s * e / D)
    return dict(T=T, pressure=D / L**3, velocity=L / T, mstar=rho_f * L / (rho_s * e),
                hstar=2 * H / L, area=b * 2 * H)


def run(capsys, argv):
    code = main([*argv, "--json"])
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err
    return code, json.loads(captured.out)


@pytest.fixture
def tripwire(monkeypatch):
    """Continuation and time integration fail the test if they start."""
    import continuation
    from fsicas.timedomain import integrators

    def tripped(*args, **kwargs):
        raise AssertionError("the computation started")
    monkeypatch.setattr(continuation.ContinuationIterator, "start", tripped)
    monkeypatch.setattr(integrators.Integrator, "run", tripped)


def test_onset_of_the_palate_preset_is_the_nondimensional_answer_converted(capsys):
    s = hand_scales(**PALATE)
    code, out = run(capsys, ["onset", "--physical", "soft_palate"])
    assert code == 0 and out["found"]
    ph = out["physical"]
    inputs = dict(ph["inputs"])
    assert inputs.pop("default_flow") == "20 L/min"
    assert inputs == pytest.approx(dict(
        E_pa=PALATE["E"], nu=PALATE["nu"], rho_s_kg_m3=PALATE["rho_s"], e_m=PALATE["e"],
        L_m=PALATE["L"], b_m=PALATE["b"], rho_f_kg_m3=PALATE["rho_f"], friction=0.14, zeta=0.0,
        H1_m=PALATE["H"], H2_m=PALATE["H"]), rel=1e-12)
    assert out["mstar"] == pytest.approx(s["mstar"], rel=1e-12)
    assert out["hstar"] == pytest.approx(s["hstar"], rel=1e-12)
    common = ["--mstar", repr(s["mstar"]), "--hstar", repr(s["hstar"]), "--friction", "0.14",
              "--modes", "10"]
    code, boundary = run(capsys, ["boundary", *common])
    point = boundary["points"][0]
    code, eig = run(capsys, ["eig", *common, "--ustar", repr(point["ustar_crit"])])
    onset_velocity = point["ustar_crit"] * s["velocity"]
    assert ph["onset_velocity_m_s"] == pytest.approx(onset_velocity, rel=1e-6)
    assert ph["onset_flow_l_min"] == pytest.approx(onset_velocity * s["area"] * 60e3, rel=1e-6)
    assert ph["onset_flow_m3_s"] == pytest.approx(onset_velocity * s["area"], rel=1e-6)
    assert ph["frequency_hz"] == pytest.approx(point["omega"] / (2 * math.pi * s["T"]), rel=1e-6)
    assert ph["pressure_drop_pa"] == pytest.approx(eig["pressure_drop"] * s["pressure"], rel=1e-6)
    assert ph["criticality"] == point["criticality"] == out["criticality"]
    breathing = PALATE["flow_l_min"] / 60e3 / s["area"]          # m/s
    assert ph["reference_velocity_m_s"] == pytest.approx(breathing, rel=1e-12)
    assert out["ustar_reference"] == pytest.approx(breathing / s["velocity"], rel=1e-12)
    assert ph["margin_flow_l_min"] == pytest.approx(ph["onset_flow_l_min"] - 20.0, rel=1e-9)
    assert ph["flutters_at_reference"] is (20.0 >= ph["onset_flow_l_min"])
    first = 1.875104068711961**2 / (2 * math.pi * s["T"])
    assert ph["scales"]["first_mode_hz"] == pytest.approx(first, rel=1e-12)


def test_onset_margin_follows_the_given_flow(capsys):
    code, low = run(capsys, ["onset", "--physical", "soft_palate", "--flow", "1L/min"])
    onset = low["physical"]["onset_flow_l_min"]
    assert code == 0 and low["physical"]["flutters_at_reference"] is False
    assert low["physical"]["margin_flow_l_min"] == pytest.approx(onset - 1.0, rel=1e-9)
    assert low["physical"]["margin_ratio"] == pytest.approx(onset / 1.0, rel=1e-6)


def test_onset_prints_sentences_without_json(capsys):
    assert main(["onset", "--physical", "soft_palate"]) == 0
    text = capsys.readouterr().out
    assert "L/min" in text and "Hz" in text and "Pa" in text and "critical" in text


def test_viscous_friction_is_taken_at_the_onset_flow(capsys):
    """The harvester gives a viscosity: f = 12/Re (laminar) at the onset's own velocity."""
    code, out = run(capsys, ["onset", "--physical", "harvester", "--modes", "6"])
    ph = out["physical"]
    re = 1.2 * ph["onset_velocity_m_s"] * 2.5e-3 / 1.8e-5
    assert re < 2500 and ph["reynolds"] == pytest.approx(re, rel=1e-4)
    assert out["friction"] == pytest.approx(12 / re, rel=1e-4)


@pytest.mark.parametrize("text, kind, si", [
    ("20L/min", "volume", 20e-3 / 60), ("20 L/min", "volume", 20e-3 / 60),
    ("3.3e-4m^3/s", "volume", 3.3e-4), ("0.5 l/s", "volume", 0.5e-3),
    ("1.2m/s", "velocity", 1.2), ("120 cm/s", "velocity", 1.2), ("4.32 km/h", "velocity", 1.2),
])
def test_flow_units_are_read(text, kind, si):
    flow = parse_flow(text)
    assert flow.kind == kind and flow.value == pytest.approx(si, rel=1e-12)


@pytest.mark.parametrize("text", ["20kg", "abc", "20", "", "0 L/min", "nan m/s", "3 Pa",
                                  "m/s", "(", "1 (m/s", "[1,2] m/s"])
def test_bad_flow_units_name_the_option(text):
    with pytest.raises(ValueError, match="--flow"):
        parse_flow(text)


def test_volume_flow_and_velocity_give_the_same_scene():
    palate = load_physical("soft_palate")
    s = hand_scales(**PALATE)
    u0 = 20e-3 / 60 / s["area"]
    by_volume = palate.scene(parse_flow("20L/min"))
    by_velocity = palate.scene(parse_flow(f"{u0!r}m/s"))
    assert by_volume.ustar == pytest.approx(by_velocity.ustar, rel=1e-12)
    assert by_volume.ustar == pytest.approx(u0 / s["velocity"], rel=1e-12)


@pytest.mark.parametrize("argv", [
    ["onset", "--physical", "soft_palate", "--flow", "20kg"],
    ["eig", "--physical", "soft_palate", "--flow", "abc"],
    ["simulate", "--t-end", "1", "--physical", "soft_palate", "--flow", "20"],
    ["eig", "--flow", "20L/min"],
])
def test_bad_flow_on_the_command_line_is_refused_before_work(capsys, tripwire, argv):
    code, out = run(capsys, argv)
    assert code == 2 and "--flow" in out["error"]


def test_presets_load_and_ship_as_package_data():
    names = preset_names()
    assert {"soft_palate", "reed", "harvester"} <= set(names)
    root = Path(__file__).resolve().parents[1]
    pyproject = tomllib.loads((root / "pyproject.toml").read_text())
    assert "presets/*.toml" in pyproject["tool"]["setuptools"]["package-data"]["fsicas"]
    for name in names:
        text = (root / "fsicas" / "presets" / f"{name}.toml").read_text()
        assert "Sources" in text, name
        physical = load_physical(name)
        scene = physical.scene(physical.flow)
        assert physical.description and physical.flow is not None
        assert physical.values["e"] < 0.1 * physical.values["L"]
        assert scene.scales is not None and scene.ustar > 0


def test_units_in_the_table_equal_si_numbers(tmp_path):
    path = tmp_path / "si.toml"
    path.write_text("[physical]\nE = 3000\nnu = 0.45\nrho_s = 1040\ne = 0.0025\nL = 0.03\n"
                    "b = 0.03\ngap = 0.002\nrho_f = 1.2\nfriction = 0.14\nflow = '20 L/min'\n")
    si = load_physical(str(path)).scene(parse_flow("20L/min"))
    preset = load_physical("soft_palate").scene(parse_flow("20L/min"))
    assert si.mstar == pytest.approx(preset.mstar, rel=1e-14)
    assert si.ustar == pytest.approx(preset.ustar, rel=1e-14)
    assert si.scales.time == pytest.approx(preset.scales.time, rel=1e-14)


@pytest.mark.parametrize("physical, named", [
    ('E = "3 kg"', "E"), ('e = "abc"', "e"), ('colour = "red"', "colour"),
    ('viscosity = "1.8e-5 Pa*s"', "friction or viscosity"), ('nu = 0.5', "nu"),
    ('E = -3', "E"),
])
def test_bad_tables_are_refused_with_the_key(tmp_path, physical, named):
    path = tmp_path / "bad.toml"
    path.write_text(f'preset = "soft_palate"\n[physical]\n{physical}\n')
    with pytest.raises(ValueError, match=named):
        load_physical(str(path)).scene()


@pytest.mark.parametrize("e, L", [("9 mm", "30 mm"), ("8 mm", "25 mm"), ("10 mm", "35 mm")])
def test_thick_palate_is_refused_with_what_to_do(capsys, tripwire, tmp_path, e, L):
    """A thick palate takes the Timoshenko modes; asked for Euler–Bernoulli it is refused."""
    path = tmp_path / "thick.toml"
    path.write_text(f'preset = "soft_palate"\n[physical]\ne = "{e}"\nL = "{L}"\n')
    scene = load_physical(str(path)).scene()
    assert scene.beam == "timoshenko" and 0.28 < scene.slenderness < 0.33
    for command in (["onset"], ["eig"], ["boundary"], ["simulate", "--t-end", "1"], ["lco"]):
        code, out = run(capsys, [*command, "--physical", str(path), "--beam", "euler-bernoulli"])
        assert code == 2, command
        message = out["error"]
        assert "Euler–Bernoulli" in message and "e/L < 0.1" in message
        assert "thinner effective thickness" in message and "Timoshenko" in message


def test_wide_channels_warn_then_are_refused(capsys, tripwire, tmp_path):
    wide = tmp_path / "wide.toml"
    wide.write_text('preset = "soft_palate"\n[physical]\ngap = "10 mm"\n')
    code, out = run(capsys, ["onset", "--physical", str(wide)])
    assert code == 2 and "H* = (H1 + H2)/L = 0.667" in out["error"]
    assert "narrow the channels" in out["error"]
    mid = tmp_path / "mid.toml"
    mid.write_text('preset = "soft_palate"\n[physical]\ngap = "4 mm"\n')
    with pytest.warns(PhysicalValidityWarning, match="H\\*"):
        load_physical(str(mid)).scene()


@pytest.mark.parametrize("argv, named", [
    (["eig", "--physical", "soft_palate", "--mstar", "1"], "--mstar"),
    (["eig", "--physical", "soft_palate", "--ustar", "3"], "--ustar"),
    (["onset", "--physical", "soft_palate", "--scene", "x.toml"], "--scene"),
    (["onset", "--physical", "no_such_preset"], "no such preset"),
    (["onset", "--physical", "missing.toml"], "no such file"),
    (["onset", "--physical", "soft_palate", "--ustar-max", "0"], "--ustar-max"),
    (["boundary"], "--mstar"),
])
def test_conflicting_or_missing_inputs_are_refused(capsys, tripwire, argv, named):
    code, out = run(capsys, argv)
    assert code == 2 and named in out["error"], out


def test_eig_and_steady_report_physical_values(capsys):
    s = hand_scales(**PALATE)
    argv = ["--physical", "soft_palate", "--flow", "3L/min", "--modes", "4"]
    code, eig = run(capsys, ["eig", *argv])
    ph = eig["physical"]
    assert ph["velocity_m_s"] == pytest.approx(3e-3 / 60 / s["area"], rel=1e-12)
    assert ph["frequency_hz"] == pytest.approx(
        [im / (2 * math.pi * s["T"]) for _, im in eig["eigenvalues"]], rel=1e-12)
    assert ph["growth_rate_per_s"] == pytest.approx(
        [re / s["T"] for re, _ in eig["eigenvalues"]], rel=1e-12)
    assert ph["pressure_drop_pa"] == pytest.approx(eig["pressure_drop"] * s["pressure"], rel=1e-12)
    code, steady = run(capsys, ["steady", *argv])
    assert steady["physical"]["flow_l_min"] == pytest.approx(3.0, rel=1e-12)
    assert sum(steady["physical"]["channel_flows_l_min"]) == pytest.approx(3.0, rel=1e-9)
    code, plain = run(capsys, ["eig", "--modes", "4"])
    assert "physical" not in plain


def test_boundary_defaults_to_the_physical_mass_ratio(capsys):
    s = hand_scales(**PALATE)
    code, out = run(capsys, ["boundary", "--physical", "soft_palate", "--modes", "6"])
    (point,), (ph,) = out["points"], out["physical"]["points"]
    assert point["mstar"] == pytest.approx(s["mstar"], rel=1e-12)
    assert ph["onset_velocity_m_s"] == pytest.approx(point["ustar_crit"] * s["velocity"], rel=1e-12)
    assert ph["fluid_density_kg_m3"] == pytest.approx(PALATE["rho_f"], rel=1e-12)


def test_impacting_cycles_and_curves_in_physical_units():
    """The impacting part of ``lco`` and the curves of ``grazing`` in SI units from the
    palate's scales: period T t, frequency 1/(T t), gap L y in mm, the velocity U* L / T,
    the peak force (in F0, nondimensional) F0 D b / L^2 in N and, on a curve, the fluid density M* rho_s e / L of each point."""
    from fsicas.physical_report import add_physical
    palate = load_physical("soft_palate")
    scene = palate.scene()
    sc = scene.scales
    impact = {"ustar": 7.0, "period": 0.127, "tip_amplitude": 0.0496, "min_gap": 3e-4,
              "impacts": 2, "peak_force": 5e3, "flow_reduction": 0.058, "stable": True}
    lco = {"hopf": None, "points": [], "folds": [], "contact": None,
           "impacting": {"points": [impact], "reference_force": 0.3,
                         "special": [{**impact, "kind": "ns"}]}}
    physical = add_physical(lco, scene, "lco")["physical"]
    (p,) = physical["impacting"]
    v = palate.values                                  # the peak force from the SI inputs
    D = v["E"] * v["e"] ** 3 / (12 * (1 - v["nu"] ** 2))
    assert p["peak_force_n"] == pytest.approx(5e3 * 0.3 * D * v["b"] / v["L"] ** 2, rel=1e-12)
    assert physical["impacting_special"] == [{**p, "kind": "ns"}]
    assert p["period_s"] == pytest.approx(0.127 * sc.time, rel=1e-12)
    assert p["frequency_hz"] == pytest.approx(1 / (0.127 * sc.time), rel=1e-12)
    assert p["min_gap_mm"] == pytest.approx(3e-4 * sc.length * 1e3, rel=1e-12)
    assert p["velocity_m_s"] == pytest.approx(7.0 * sc.length / sc.time, rel=1e-12)
    point = {"mstar": 0.5, "ustar": 6.5, "period": 0.13, "tip_amplitude": 0.04995,
             "gap_ratio": 1.0, "stable": True}
    hopf = {"mstar": 0.5, "ustar": 5.0, "omega": 46.0, "l1": 0.1}
    out = add_physical({"grazing": [point], "fold": [], "hopf": [hopf]}, scene, "grazing")
    (g,) = out["physical"]["grazing"]
    rho_s_e = sc.beam_mass_per_area
    assert g["fluid_density_kg_m3"] == pytest.approx(0.5 * rho_s_e / sc.length, rel=1e-12)
    assert g["tip_amplitude_mm"] == pytest.approx(0.04995 * sc.length * 1e3, rel=1e-12)
    assert out["physical"]["hopf"][0]["frequency_hz"] == pytest.approx(
        46.0 / (2 * math.pi * sc.time), rel=1e-12)
