"""The design query for reversed flow (expiration, U* < 0), whose onset is a static
divergence: its elasticities against finite differences of onsets located from scratch
(critical_velocity on physical tables built here) and against the closed forms of a
static onset, the design ("lift" = |Q_c| grows) against closed forms, an independent
onset and the eigenvalues, and the ``fsicas design`` options of direction."""

import json
import math
import warnings

import pytest

import fsicas
from fsicas.cli import main
from fsicas.linear import DesignError, design_for_flow, palate_sensitivity
from fsicas.linear.hopf import ModalTruncationWarning
from fsicas.linear.sensitivity import divergence_sensitivity
from fsicas.physical import Flow, Physical, load_physical, parse_flow

MODES = 8
STEP = 1e-5          # relative step of the checking differences


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModalTruncationWarning)
        yield


def _table(physical: Physical, **values) -> dict:
    """The physical table in SI numbers with ``values`` changed (heights as H1, H2)."""
    table = {k: v for k, v in physical.values.items() if k != "gap"}
    table.update(H1=physical.H1, H2=physical.H2)
    if "gap" in values:
        gap = values.pop("gap")
        table.update(H1=gap, H2=gap)
    table.update(values)
    return table


def _reversed_onset_flow(table: dict) -> float:
    """The reversed onset's airflow (m^3/s, < 0) of a physical table, from scratch."""
    scene = Physical.from_table(table, "check").scene(None, modes=MODES, direction="reverse")
    return scene.scales.m3_per_s(fsicas.critical_velocity(scene).ustar)


@pytest.fixture(scope="module")
def palate():
    physical = load_physical("soft_palate")
    return physical, palate_sensitivity(physical, modes=MODES, direction="reverse")


def test_reversed_palate_onset_is_a_divergence_without_frequency(palate):
    _, sens = palate
    assert sens.hopf.kind == "divergence" and sens.onset_flow < 0 and sens.frequency == 0.0
    assert sens.hopf.symmetry_breaking and "H1" not in sens.parameters
    out = sens.to_json()
    assert out["kind"] == "divergence" and out["onset_flow_l_min"] < 0
    assert all(s["frequency_elasticity"] is None for s in out["sensitivities"].values())


@pytest.mark.parametrize("name", ["L", "e", "gap", "friction", "nu"])
def test_reversed_elasticities_equal_differences_of_the_onset_airflow(palate, name):
    """d ln |Q_c| / d ln theta against central differences of reversed onsets located
    from scratch (the gap: both heights together, the pitchfork kept symmetric)."""
    physical, sens = palate
    s = sens.parameters[name]
    q1, q0 = (_reversed_onset_flow(_table(physical, **{name: s.value * (1 + k * STEP)}))
              for k in (1, -1))
    assert q1 < 0 and q0 < 0
    assert math.log(q1 / q0) / (2 * STEP) == pytest.approx(s.flow, abs=1e-6)


def test_reversed_closed_form_elasticities(palate):
    """A static onset has no inertia: Q_c ~ sqrt(E / rho_f) b, independent of rho_s and
    of the damping (M* U*^2 alone enters the steady load, so d ln U*_c / d ln M* = -1/2)."""
    _, sens = palate
    p = sens.parameters
    for name, closed in (("E", 0.5), ("rho_f", -0.5), ("b", 1.0), ("rho_s", 0.0)):
        assert p[name].flow == pytest.approx(closed, abs=1e-7), name
    assert abs(p["zeta"].flow_per_unit) < 1e-6


@pytest.mark.slow      # 30 s: three designs, each onset solved by a continuation
def test_reversed_design_lifts_the_onsets_magnitude(palate):
    """|Q_c| ~ sqrt(E): the design is E (Q_t / Q_0)^2, verified by the eigenvalues; by
    the gap, verified by an independent reversed onset; H1 alone is refused (it unfolds
    the pitchfork); a target of the other sign is refused."""
    physical, sens = palate
    target = Flow.of("volume", -2.5 / 60e3)
    d = design_for_flow(physical, target, "stiffness", modes=MODES, direction="reverse")
    assert d.after == pytest.approx(physical.values["E"] * (target.value / sens.onset_flow) ** 2,
                                    rel=1e-9)
    assert d.onset_flow_after == pytest.approx(target.value, rel=1e-9) and d.verified
    g = design_for_flow(physical, target, "gap", modes=MODES, direction="reverse")
    assert g.after > physical.values["gap"] and g.verified
    assert _reversed_onset_flow(_table(physical, gap=g.after)) == pytest.approx(target.value,
                                                                               rel=1e-8)
    none = design_for_flow(physical, Flow.of("volume", -1e-3 / 60e3), "E", modes=MODES,
                           direction="reverse")
    assert none.after == none.before and "no change" in none.note
    with pytest.raises(DesignError, match="vary gap"):
        design_for_flow(physical, target, "H1", modes=MODES, direction="reverse")
    with pytest.raises(ValueError, match="not in the direction"):
        design_for_flow(physical, parse_flow("2.5L/min"), "E", modes=MODES, direction="reverse")


def test_cli_reversed_design_by_direction_or_by_sign(capsys):
    common = ["design", "--physical", "soft_palate", "--modes", "4", "--vary", "E",
              "--json"]
    outs = []
    for extra in (["--direction", "reverse", "--target-flow", "2.5L/min"],
                  ["--target-flow=-2.5L/min"]):
        assert main([*common, *extra]) == 0
        outs.append(json.loads(capsys.readouterr().out))
    for out in outs:
        assert out["kind"] == "divergence" and out["design"]["verified"]["stable_below"]
        assert out["design"]["onset_flow_after_l_min"] == pytest.approx(-2.5, rel=1e-9)
    assert outs[0]["design"]["after"] == pytest.approx(outs[1]["design"]["after"], rel=1e-12)
    assert main([*common, "--direction", "reverse", "--target-flow=-2.5L/min"]) == 2
    assert "negative and a direction" in json.loads(capsys.readouterr().out)["error"]
    assert main(["design", "--physical", "soft_palate", "--modes", "4", "--direction",
                 "reverse"]) == 0
    assert "divergence onset at" in capsys.readouterr().out


@pytest.mark.slow      # 50 s: each perturbed fold located by a continuation
def test_fold_divergence_of_asymmetric_channels_by_differences():
    """Asymmetric channels: the reversed onset is a fold of the steady branch; its
    derivatives (the heights one by one too) against onsets located from scratch."""
    scene = fsicas.Scene(mstar=1.0, ustar=-0.0, modes=6, zeta=0.01, friction=0.14, k0=0.5,
                         kl=0.8, channel1=fsicas.Profile.constant(0.055),
                         channel2=fsicas.Profile.constant(0.045), hstar=0.1)
    model = fsicas.build_model(scene)
    onset = fsicas.critical_velocity(scene, model)
    assert onset.kind == "divergence" and onset.bifurcation == "fold"
    s = divergence_sensitivity(scene, model, onset)
    assert s.d_ln_ustar["mstar"] * s.values["mstar"] == pytest.approx(-0.5, abs=1e-7)

    def onset_at(name, v):
        if name in ("h1", "h2"):
            h1, h2 = (v, 0.045) if name == "h1" else (0.055, v)
            changed = scene.replace(hstar=h1 + h2, channel1=fsicas.Profile.constant(h1),
                                    channel2=fsicas.Profile.constant(h2))
        else:
            changed = scene.replace(**{name: v})
        return fsicas.critical_velocity(changed).ustar

    for name in ("friction", "kl", "h1", "h2"):
        v = s.values[name]
        fd = math.log(onset_at(name, v * (1 + STEP)) / onset_at(name, v * (1 - STEP))) / (2 * STEP * v)
        assert s.d_ln_ustar[name] == pytest.approx(fd, rel=1e-5), name
