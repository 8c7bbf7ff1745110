"""Scene validation, TOML input, physical units."""
import math

import pytest

from fsicas import Profile, Scene, friction_from_reynolds, load_scene
from fsicas.units import Scales

EXAMPLE = "examples/asymmetric.toml"


@pytest.mark.parametrize("changes, field", [
    (dict(mstar=0.0), "mstar"), (dict(mstar=-1.0), "mstar"), (dict(modes=0), "modes"),
    (dict(modes=2.5), "modes"), (dict(friction=-0.1), "friction"), (dict(hstar=0.0), "hstar"),
    (dict(ustar=float("nan")), "ustar"), (dict(k0=-1.0), "k0"), (dict(kl=-1.0), "kl"),
    (dict(zeta=-0.01), "zeta"), (dict(zeta=(0.1, 0.2)), "zeta"),
    (dict(modes=10, quad_nodes=19), "quad_nodes"), (dict(contact_eps=0.0), "contact_eps"),
    (dict(contact_stiffness=0.0), "contact_stiffness"), (dict(contact="yes"), "contact"),
    (dict(channel1=Profile.linear(0.05, -0.01), channel2=Profile.constant(0.05)), "channel1"),
    (dict(channel1=Profile.constant(0.05), channel2=Profile.constant(0.06)), "hstar"),
    (dict(channel2=Profile.table([0, 0.5, 1], [0.05, 0.0, 0.05])), "channel2"),
    (dict(channel1=Profile("parabola", (1.0,))), "channel1.kind"),
    (dict(zeta="0.01"), "zeta"), (dict(zeta=["0.01"] * 10), "zeta"), (dict(zeta=True), "zeta"),
    (dict(mstar="2"), "mstar"), (dict(quad_nodes=40.0), "quad_nodes"),
])
def test_bad_values_name_the_field(changes, field):
    with pytest.raises(ValueError, match=field):
        Scene(**changes)


def test_numpy_scalars_are_stored_as_plain_numbers():
    """NumPy scalars and arrays are accepted and stored as Python floats, ints, tuples."""
    import numpy as np
    s = Scene(mstar=np.float32(2.5), ustar=np.int64(6), modes=np.int64(4),
              zeta=np.array([0.01, 0.02, 0.0, 0.0]), quad_nodes=np.int32(40), contact=np.bool_(False))
    assert type(s.mstar) is float and s.mstar == 2.5 and type(s.ustar) is float
    assert type(s.modes) is int and type(s.quad_nodes) is int and s.contact is False
    assert s.zeta == (0.01, 0.02, 0.0, 0.0) and type(s.zeta[0]) is float
    assert type(Scene(zeta=np.float64(0.02)).zeta) is float
    assert s == Scene(mstar=2.5, ustar=6.0, modes=4, zeta=(0.01, 0.02, 0.0, 0.0), quad_nodes=40)


def test_spline_overshoot_below_zero_is_caught():
    """Positive table values whose spline dips below zero between the points."""
    with pytest.raises(ValueError, match="channel2"):
        Scene(channel2=Profile.table([0, 0.2, 0.25, 1], [0.05, 0.05, 0.002, 0.05]))


def test_defaults_fill_in_quadrature_and_walls():
    s = Scene(modes=7)
    assert s.quad_nodes is None and s.n_quad == 34
    assert s.replace(modes=30).n_quad == 80
    w1, w2 = s.walls
    assert w1(0.3) == w2(0.7) == 0.05
    assert s.straight and s.symmetric
    assert list(s.zeta_modes) == [0.0] * 7


def test_toml_round_trip_and_overrides(tmp_path):
    s = load_scene(EXAMPLE)
    assert s.walls[0](1.0) == pytest.approx(0.05) and s.walls[1](0.5) == pytest.approx(0.045)
    assert not s.straight and not s.symmetric
    assert load_scene(EXAMPLE, ustar=7.0).ustar == 7.0
    assert Scene.from_dict(s.to_dict()) == s


def test_unknown_toml_keys_are_rejected(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("mstar = 1.0\nvelocity = 3.0\n")
    with pytest.raises(ValueError, match="velocity"):
        load_scene(path)
    path.write_text("[channel1]\nkind = 'constant'\nheights = 0.05\nslope = 1\n")
    with pytest.raises(ValueError, match="channel1.*slope"):
        load_scene(path)


def test_physical_units_round_trip():
    """A PVC-like strip in air: check every nondimensional group against its definition."""
    rho_s, E, nu, e, L, rho_f, U0, H = 1400.0, 3e6, 0.45, 1e-3, 0.03, 1.2, 10.0, 1.5e-3
    s = Scene.from_physical(rho_s=rho_s, E=E, nu=nu, e=e, L=L, rho_f=rho_f, U0=U0, H1=H,
                            b=0.02, modes=6)
    D = E * e**3 / (12 * (1 - nu**2))
    assert s.mstar == pytest.approx(rho_f * L / (rho_s * e), rel=1e-14)
    assert s.ustar == pytest.approx(U0 * L * math.sqrt(rho_s * e / D), rel=1e-14)
    assert s.hstar == pytest.approx(2 * H / L, rel=1e-14)
    T = s.scales.time
    assert s.scales.hz(3.516015268500151) == pytest.approx(
        1.875104068711961**2 / (2 * math.pi) * math.sqrt(D / (rho_s * e)) / L**2, rel=1e-12)
    assert s.scales.seconds(1.0) == T and s.scales.pa(1.0) == pytest.approx(D / L**3)
    assert s.scales.mm(0.1) == pytest.approx(3.0)


@pytest.mark.parametrize("changes, field", [
    (dict(nu=0.5), "nu"), (dict(e=0.02), "e = "), (dict(rho_s=-1.0), "rho_s"),
    (dict(H1=0.0), "H1"), (dict(b=1e-4), "b = "), (dict(U0=float("inf")), "U0"),
])
def test_inconsistent_physical_sets_are_rejected(changes, field):
    kw = dict(rho_s=1400.0, E=3e6, nu=0.45, e=1e-3, L=0.03, rho_f=1.2, U0=10.0, H1=1.5e-3, b=0.02)
    kw.update(changes)
    with pytest.raises(ValueError, match=field):
        Scales.from_physical(H2=kw["H1"], **kw)


def test_physical_constructor_refuses_derived_fields():
    with pytest.raises(ValueError, match="ustar"):
        Scene.from_physical(rho_s=1400.0, E=3e6, nu=0.45, e=1e-3, L=0.03, rho_f=1.2, U0=10.0,
                            H1=1.5e-3, b=0.02, ustar=3.0)


def test_friction_from_reynolds_is_eq_15():
    assert friction_from_reynolds(100) == pytest.approx(0.12)
    assert friction_from_reynolds(1e4) == pytest.approx(0.055 * 1e4**-0.25)
    with pytest.raises(ValueError, match="re"):
        friction_from_reynolds(0.0)
