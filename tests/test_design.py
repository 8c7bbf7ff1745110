"""Designing the palate (fsicas.design, fsicas.linear.sensitivity): the exact onset
sensitivities against finite differences of independently recomputed onsets
(critical_velocity on scenes and physical tables built here), the design query against
closed forms and the eigenvalues, and the ``fsicas design`` command."""

import json
import math
import warnings

import numpy as np
import pytest

import fsicas
from fsicas.cli import main
from fsicas.linear import DesignError, design_for_flow, palate_sensitivity
from fsicas.linear.hopf import ModalTruncationWarning
from fsicas.linear.sensitivity import onset_sensitivity
from fsicas.physical import Physical, load_physical, parse_flow

MODES = 8
STEP = 1e-5          # relative step of the checking differences


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModalTruncationWarning)
        yield


def _onset(scene, model=None):
    h = fsicas.critical_velocity(scene, model or fsicas.build_model(scene))
    return h.ustar, h.omega


def _log_derivative(f, value):
    """Central difference of ``(ln a, ln b) = f(value)`` in ``value``."""
    (a1, b1), (a0, b0) = f(value * (1 + STEP)), f(value * (1 - STEP))
    h = 2 * STEP * value
    return math.log(a1 / a0) / h, math.log(b1 / b0) / h


@pytest.fixture(scope="module")
def sensitivity():
    scene = fsicas.Scene(mstar=1.0, modes=6, zeta=0.01, friction=0.14, k0=0.5, kl=0.8,
                         channel1=fsicas.Profile.constant(0.055),
                         channel2=fsicas.Profile.constant(0.045), hstar=0.1)
    model = fsicas.build_model(scene)
    hopf = fsicas.critical_velocity(scene, model)
    return scene, model, onset_sensitivity(scene, model, hopf)


@pytest.mark.parametrize("name", ["mstar", "friction", "zeta", "k0", "kl"])
def test_exact_onset_derivatives_equal_differences_of_critical_velocity(sensitivity, name):
    """Implicit functions on the Hopf system against onsets located from scratch."""
    scene, model, s = sensitivity
    fd = _log_derivative(lambda v: _onset(scene.replace(**{name: v}), model), s.values[name])
    assert s.d_ln_ustar[name] == pytest.approx(fd[0], rel=1e-6, abs=1e-9)
    assert s.d_ln_omega[name] == pytest.approx(fd[1], rel=1e-6, abs=1e-9)


@pytest.mark.parametrize("name", ["h1", "h2"])
def test_channel_height_derivatives_equal_differences_of_critical_velocity(sensitivity, name):
    """Asymmetric channels (the two heights act differently)."""
    scene, _, s = sensitivity

    def onset(h):
        h1, h2 = (h, 0.045) if name == "h1" else (0.055, h)
        return _onset(scene.replace(hstar=h1 + h2, channel1=fsicas.Profile.constant(h1),
                                    channel2=fsicas.Profile.constant(h2)))

    fd = _log_derivative(onset, s.values[name])     # both are differences: ~1e-8 apart
    assert s.d_ln_ustar[name] == pytest.approx(fd[0], rel=1e-6, abs=1e-6)
    assert s.d_ln_omega[name] == pytest.approx(fd[1], rel=1e-6, abs=1e-6)
    assert abs(s.d_ln_ustar["h1"] - s.d_ln_ustar["h2"]) > 1e-3     # not symmetric here


def _table(physical: Physical, **values) -> dict:
    """The physical table in SI numbers with ``values`` changed (heights as H1, H2)."""
    table = {k: v for k, v in physical.values.items() if k != "gap"}
    table.update(H1=physical.H1, H2=physical.H2)
    if "gap" in values:
        gap = values.pop("gap")
        table.update(H1=gap, H2=gap)
    table.update(values)
    return table


def _physical_onset(table: dict, label="check"):
    """``(onset flow m^3/s, frequency Hz)`` of a physical table, from scratch."""
    ph = Physical.from_table(table, label)
    scene = ph.scene(None, modes=MODES)
    u, w = _onset(scene)
    return scene.scales.m3_per_s(u), scene.scales.hz(w)


@pytest.fixture(scope="module")
def palate():
    physical = load_physical("soft_palate")
    return physical, palate_sensitivity(physical, modes=MODES)


@pytest.mark.parametrize("name", ["E", "nu", "rho_s", "e", "L", "b", "H1", "gap", "rho_f",
                                  "friction"])
def test_physical_elasticities_equal_differences_of_the_onset_airflow(palate, name):
    physical, sens = palate
    s = sens.parameters[name]
    fd = _log_derivative(lambda v: _physical_onset(_table(physical, **{name: v})), s.value)
    assert s.value * fd[0] == pytest.approx(s.flow, abs=1e-6)
    assert s.value * fd[1] == pytest.approx(s.frequency, abs=1e-6)


def test_closed_form_elasticities(palate):
    """E and b enter the nondimensional problem not at all: Q_c ~ sqrt(E) b exactly."""
    _, sens = palate
    assert sens.parameters["E"].flow == pytest.approx(0.5, abs=1e-12)
    assert sens.parameters["E"].frequency == pytest.approx(0.5, abs=1e-12)
    assert sens.parameters["b"].flow == pytest.approx(1.0, abs=1e-12)
    assert sens.parameters["b"].frequency == pytest.approx(0.0, abs=1e-12)


def test_damping_from_zero_has_a_per_unit_derivative(palate):
    """zeta = 0 in the preset: the elasticity is 0, the derivative per unit of zeta is
    checked by a one-sided difference (zeta >= 0) of second order (the onset curves
    strongly near zeta = 0: a step of 1e-4 is 3e-5 off, 1e-6 is 3e-9 off)."""
    physical, sens = palate
    s = sens.parameters["zeta"]
    assert s.value == 0.0 and s.flow == 0.0
    h = 1e-6
    q = [_physical_onset(_table(physical, zeta=z))[0] for z in (0.0, h, 2 * h)]
    one_sided = (-3 * math.log(q[0]) + 4 * math.log(q[1]) - math.log(q[2])) / (2 * h)
    assert s.flow_per_unit == pytest.approx(one_sided, rel=1e-5)


@pytest.mark.slow     # 36 s: the fixed point recomputed per elasticity
def test_viscous_friction_fixed_point_is_differentiated():
    """With a viscosity the friction follows the onset's own Reynolds number: the
    elasticities include that loop (checked against the fixed point recomputed)."""
    physical = load_physical("soft_palate")
    table = _table(physical)
    del table["friction"]
    table["viscosity"] = 1.8e-5
    ph = Physical.from_table(table, "viscous")
    sens = palate_sensitivity(ph, modes=MODES)

    def onset(name, value):
        """The fixed point f = f(Re(U_c)) iterated here to round-off."""
        p = Physical.from_table({**table, name: value}, "viscous")
        scene = p.scene(parse_flow("1m/s"), modes=MODES)
        model = fsicas.build_model(scene)
        for _ in range(60):
            hopf = fsicas.critical_velocity(scene, model)
            flow = fsicas.Flow("onset", "velocity", scene.scales.m_per_s(hopf.ustar))
            friction = p.friction(flow)[0]
            if abs(friction - scene.friction) <= 1e-14 * friction:
                break
            scene = scene.replace(friction=friction)
        return scene.scales.m3_per_s(hopf.ustar), scene.scales.hz(hopf.omega)

    for name in ("viscosity", "rho_f", "E"):
        s = sens.parameters[name]
        fd = _log_derivative(lambda v: onset(name, v), s.value)
        assert s.value * fd[0] == pytest.approx(s.flow, abs=1e-5)
        assert s.value * fd[1] == pytest.approx(s.frequency, abs=1e-5)
    assert "friction" not in sens.parameters


def test_design_by_stiffness_and_width_meets_their_closed_forms(palate):
    """Q_c ~ sqrt(E) and ~ b: the designs are E (Q_t/Q_0)^2 and b Q_t/Q_0, and the
    eigenvalues at the design confirm them (stable at 99.5 %, unstable at 100.5 %)."""
    physical, sens = palate
    q0 = sens.onset_flow
    target = parse_flow("6L/min")
    ratio = target.value / q0
    for vary, closed in (("stiffness", physical.values["E"] * ratio ** 2),
                         ("width", physical.values["b"] * ratio)):
        d = design_for_flow(physical, target, vary, modes=MODES)
        assert d.after == pytest.approx(closed, rel=1e-9)
        assert d.onset_flow_after == pytest.approx(target.value, rel=1e-9)
        assert d.verified and d.stable_below and d.unstable_above


def test_weighted_combination_meets_its_closed_form(palate):
    """Stiffer and wider together (weights 1, 1): ln Q = ln Q_0 + (1/2 + 1) s exactly,
    so s = ln(Q_t / Q_0) / 1.5 and both parameters grow by exp(s)."""
    physical, sens = palate
    target = parse_flow("8L/min")
    d = design_for_flow(physical, target, "stiffness=1,width=1", modes=MODES)
    s = math.log(target.value / sens.onset_flow) / 1.5
    E, b = d.changes
    assert (E.parameter, b.parameter) == ("E", "b") and d.weights == (1.0, 1.0)
    assert E.after == pytest.approx(physical.values["E"] * math.exp(s), rel=1e-9)
    assert b.after == pytest.approx(physical.values["b"] * math.exp(s), rel=1e-9)
    assert d.verified
    with pytest.raises(AttributeError, match="several parameters"):
        d.after


def test_stiffening_against_shortening(palate):
    """E up and L down in equal log steps (weights 1, -1), checked by an onset of the
    designed palate computed here."""
    physical, _ = palate
    target = parse_flow("6L/min")
    d = design_for_flow(physical, target, {"E": 1.0, "L": -1.0}, modes=MODES)
    E, L = d.changes
    assert math.log(E.after / E.before) == pytest.approx(-math.log(L.after / L.before),
                                                         rel=1e-12)
    assert E.after > E.before and L.after < L.before and d.verified
    flow, _ = _physical_onset(_table(physical, E=E.after, L=L.after))
    assert flow == pytest.approx(target.value, rel=1e-8)
    out = d.to_json()
    assert [c["parameter"] for c in out["changes"]] == ["E", "L"] and "after" not in out


@pytest.mark.parametrize("vary, message", [
    ("stiffness=1,damping=1", "varies only on its own"),
    ("stiffness=0", "a finite weight other than 0"),
    ("stiffness=1,E=2", "each parameter once"),
    ("stiffness=x", "'x' is not a weight"),
])
def test_bad_combinations_are_refused(palate, vary, message):
    physical, _ = palate
    with pytest.raises(ValueError, match=message):
        design_for_flow(physical, parse_flow("6L/min"), vary, modes=MODES)


def test_design_by_the_gap_is_verified_by_an_independent_onset(palate):
    physical, _ = palate
    target = parse_flow("5L/min")
    d = design_for_flow(physical, target, "gap", modes=MODES)
    flow, _ = _physical_onset(_table(physical, gap=d.after))
    assert flow == pytest.approx(target.value, rel=1e-8)
    assert d.after > physical.values["gap"] and d.verified and d.evaluations > 0
    assert d.frequency_after == pytest.approx(_physical_onset(_table(physical, gap=d.after))[1],
                                              rel=1e-8)


def test_a_design_beyond_the_models_validity_says_so_once(palate):
    """The gap that lifts the onset to 10 L/min is beyond the thin-channel model's validity:
    the design says so once per caveat (each of its scenes warned alike), in Python and
    in its JSON."""
    from fsicas.physical import PhysicalValidityWarning
    physical, _ = palate
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        d = design_for_flow(physical, parse_flow("10L/min"), "gap", modes=MODES)
    said = [str(w.message) for w in caught if issubclass(w.category, PhysicalValidityWarning)]
    assert said and len(said) == len(set(said))
    assert list(d.warnings) == said and d.to_json()["warnings"] == said


def test_design_needs_no_change_below_the_onset_and_says_when_none_reaches(palate):
    physical, _ = palate
    d = design_for_flow(physical, parse_flow("2L/min"), "length", modes=MODES)
    assert d.after == d.before and "no change" in d.note and d.verified is not None
    d = design_for_flow(physical, parse_flow("4.5L/min"), "damping", modes=4)   # from 0
    assert d.before == 0.0 and d.relative_change is None and 0 < d.after < 1 and d.verified
    with pytest.raises(DesignError, match="up to a damping ratio of 1 lifts the onset"):
        design_for_flow(physical, parse_flow("30L/min"), "damping", modes=4)
    with pytest.raises(ValueError, match="--vary 'colour': not a parameter.*allowed: E"):
        design_for_flow(physical, parse_flow("30L/min"), "colour", modes=MODES)


def test_cli_design_json_and_text(capsys):
    code = main(["design", "--physical", "soft_palate", "--modes", str(MODES),
                 "--target-flow", "6L/min", "--vary", "stiffness", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0
    assert out["design"]["verified"] == {"stable_below": True, "unstable_above": True,
                                         "margin": 0.005}
    assert out["design"]["onset_flow_after_l_min"] == pytest.approx(6.0, rel=1e-9)
    assert out["sensitivities"]["E"]["flow_elasticity"] == pytest.approx(0.5, abs=1e-12)
    assert out["meta"]["units"]["onset_flow_l_min"] == "L/min"
    assert main(["design", "--physical", "soft_palate", "--modes", str(MODES)]) == 0
    text = capsys.readouterr().out
    assert "flutter onset at" in text and "Young's modulus" in text and "L/min" in text


@pytest.mark.parametrize("argv, message", [
    (["design"], "--physical PRESET|FILE.toml is needed"),
    (["design", "--physical", "soft_palate", "--vary", "E"], "--target-flow and --vary go "
                                                             "together"),
    (["design", "--physical", "soft_palate", "--target-flow", "3m", "--vary", "E"],
     "--target-flow '3m' has units of"),
    (["design", "--physical", "soft_palate", "--ustar", "3"], "--ustar is derived"),
])
def test_cli_design_refuses_bad_input_before_any_work(capsys, argv, message):
    assert main([*argv, "--json"]) == 2
    assert message in json.loads(capsys.readouterr().out)["error"]


def test_timoshenko_palate_elasticity_of_thickness():
    """A thick palate (e/L = 0.3, Timoshenko modes): thickness and length act through the
    modes too (slenderness by differences of rebuilt models)."""
    physical = load_physical("soft_palate")
    table = _table(physical, e=9e-3)
    ph = Physical.from_table(table, "thick")
    sens = palate_sensitivity(ph, modes=MODES)
    assert "slenderness" in onset_sensitivity(sens.scene, fsicas.build_model(sens.scene),
                                              sens.hopf).d_ln_ustar
    s = sens.parameters["e"]
    fd = _log_derivative(lambda v: _physical_onset({**table, "e": v}), s.value)
    assert s.value * fd[0] == pytest.approx(s.flow, abs=1e-5)
    assert np.isfinite(s.frequency)


def test_the_design_warns_about_its_own_palate_only(palate):
    """The search's trial palates are not the answer: one validity warning, of the design
    (H* = 2 gap / L), not one per trial."""
    from fsicas.physical import PhysicalValidityWarning
    physical, _ = palate
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        d = design_for_flow(physical, parse_flow("10L/min"), "gap", modes=MODES)
    notes = {str(w.message) for w in caught if issubclass(w.category, PhysicalValidityWarning)}
    hstar = 2 * d.after / physical.values["L"]
    assert hstar > 0.2 and notes == {n for n in notes if f"H* = (H1 + H2)/L = {hstar:.3g}" in n}
    assert len(notes) == 1
