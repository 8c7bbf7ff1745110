"""Convergence of the steady state and the modal forces with N and quadrature nodes.

The observed rates are recorded in docs/model.md (section Verification).
"""
import numpy as np
import pytest

from fsicas import build_model, steady_state


def tip_and_dp(scene):
    model = build_model(scene)
    st = steady_state(scene, model)
    return model.deflection(st.x, [1.0])[0], st.pressure_drop


def test_static_deflection_converges_algebraically_in_modes(asymmetric_channels_scene):
    """A static load with a non-zero tip value has modal amplitudes q_n ~ n^-5; the tip
    deflection error then falls like N^-4 or faster (measured: order 4.3–5)."""
    ref_tip, ref_dp = tip_and_dp(asymmetric_channels_scene.replace(modes=64))
    errors = [abs(tip_and_dp(asymmetric_channels_scene.replace(modes=n))[0] - ref_tip) for n in (4, 8, 16)]
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 4.0), orders
    assert errors[-1] < 1e-8 * 1e-3 / abs(ref_tip) * abs(ref_tip) * 1e3  # < 1e-8 absolute


def test_steady_state_is_at_round_off_with_the_default_quadrature(asymmetric_channels_scene):
    """Gauss–Legendre converges exponentially for smooth one-directional flow: 2N + 20 nodes
    (the default) agree with 6N nodes to round-off."""
    scene = asymmetric_channels_scene.replace(modes=10)
    tip_default, dp_default = tip_and_dp(scene)
    tip_fine, dp_fine = tip_and_dp(scene.replace(quad_nodes=60))
    tip_min, dp_min = tip_and_dp(scene.replace(quad_nodes=20))
    assert tip_default == pytest.approx(tip_fine, rel=1e-12)
    assert dp_default == pytest.approx(dp_fine, rel=1e-13)
    assert tip_min == pytest.approx(tip_fine, rel=1e-9)  # even the minimum 2N is close


@pytest.mark.slow
def test_orthonormality_and_steady_state_at_80_modes(asymmetric_channels_scene):
    scene = asymmetric_channels_scene.replace(modes=80)
    tip, dp = tip_and_dp(scene)
    tip_fine, dp_fine = tip_and_dp(scene.replace(quad_nodes=300))
    assert tip == pytest.approx(tip_fine, rel=1e-10) and dp == pytest.approx(dp_fine, rel=1e-12)
