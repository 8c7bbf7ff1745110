"""Impacting limit cycles by adaptive collocation (fsicas.cycles.impacting_collocation),
against independent routes: collocation of the contact-free model before contact, time
integration (SciPy Radau, IDAS) and multiple shooting (CVODES) after it."""

from dataclasses import replace

import numpy as np
import pytest

from fsicas import Scene
from fsicas.cycles import (CollocatedImpactBranch, CollocationImpactSettings, CycleSettings,
                           ImpactSettings, StartCycle, cycle_branch, impacting_cycles,
                           period_doubled_branch, pre_contact_start,
                           symmetry_broken_branch)
from fsicas.linear.steady import steady_state
from fsicas.model import build_model
from fsicas.model.contact import gaps
from fsicas.timedomain.integrators import Settings, simulate
from fsicas.timedomain.settled import mirror_distance, settled_cycle

#: the start cycle on the scene's nodes, those of the impacting branch (the routes are
#: compared on one model; the quadrature control has its own test)
SCENE_NODES = CycleSettings(quadrature_tol=None)
IMPACT = dict(contact=True, contact_stiffness=1e8, contact_eps=1e-2, contact_smoothing=0.1)


def _mirror(model, scene, point) -> float:
    """``mirror_distance`` of a branch point's cycle (IDAS 1e-11, half a period)."""
    return mirror_distance(model, scene.replace(ustar=point.ustar), point.state, point.period)


def _one_period(model, scene, point, method="radau", rtol=1e-11):
    """Independent integration of one period from the point's state: the relative miss
    of the return, the tip half-amplitude and the min gap over the period (samples)."""
    T = point.period
    traj = simulate(model, steady_state(scene.replace(ustar=point.ustar), model), T,
                    x0=point.state, settings=Settings(method=method, rtol=rtol, atol=1e-13,
                                                      dt_out=T / 40000))
    assert traj.status == "success"
    x = traj.x
    miss = np.max(np.abs(x[-1] - point.state)) / np.max(np.abs(point.state))
    y = model.tip_deflection(x)
    return miss, (y.max() - y.min()) / 2, gaps(model, x).min()


def _through_contact(modes, ustar_max, settings, mstar=1.0):
    """k* = 1e8, eps/H = 1e-2, smoothing 0.1: the impacting branch by collocation from the
    contact-free collocation cycle at gap >= 3 eps (``impacting_cycles`` from the scene);
    (scene, model, branch)."""
    scene = Scene(mstar=mstar, zeta=0.01, modes=modes, **IMPACT)
    model = build_model(scene)
    br = impacting_cycles(scene, model=model, ustar_max=ustar_max,
                          settings=replace(settings, quadrature_tol=None),
                          cycle_settings=SCENE_NODES)
    return br.scene, model, br


@pytest.fixture(scope="module")
def n3_branch():
    """N = 3: five points through the first contact, and the contact-free cycle it
    started from (computed again here, on the contact-free model)."""
    scene, model, br = _through_contact(3, 12.0, CollocationImpactSettings(
        ntst=100, max_points=5, ds=0.1, ds_max=1.0))
    free = Scene(mstar=1.0, zeta=0.01, modes=3, contact_eps=1e-2)
    return pre_contact_start(cycle_branch(free, ustar_max=12.0, settings=SCENE_NODES)), \
        scene, model, br


def test_collocation_passes_first_contact_and_matches_time_integration(n3_branch):
    """The first point is the contact-free collocation cycle (the smoothed force is
    negligible at 3 eps); the branch goes on into the band where the smoothed law acts
    (it holds the min gap above eps up to U* = 6.3 at least: the impact load resolved at
    the tip), and an independent Radau integration (rtol 1e-11) of one period from the
    last cycle's state returns to it, with the same amplitude and min gap."""
    start, scene, model, br = n3_branch
    assert br.status == "max_points" and len(br.points) == 5
    first, last = br.points[0], br.points[-1]
    assert abs(first.ustar - start.ustar) < 1e-8
    assert abs(first.period / start.period - 1) < 1e-6
    assert abs(first.tip_amplitude / start.tip_amplitude - 1) < 1e-5
    assert first.impacts == 0 and first.gap_ratio > 3
    assert np.all(np.diff(br.column("ustar")) > 0)
    assert last.gap_ratio < 1.5
    miss, amplitude, min_gap = _one_period(model, scene, last)
    assert miss < 1e-6
    assert abs(amplitude / last.tip_amplitude - 1) < 1e-6
    assert abs(min_gap / last.min_gap - 1) < 1e-4
    assert all(p.ntst == 100 and p.error_estimate > 0 for p in br.points)


def test_save_load_and_validation(n3_branch, tmp_path):
    _, scene, _, br = n3_branch
    br.save(tmp_path / "b.json")
    back = CollocatedImpactBranch.load(tmp_path / "b.json")
    assert back.column("period").tolist() == br.column("period").tolist()
    assert back.points[-1].ntst == 100 and back.points[-1].impacts == br.points[-1].impacts
    assert np.array_equal(back.points[-1].multipliers, br.points[-1].multipliers)
    with pytest.raises(ValueError, match="ntst"):
        CollocationImpactSettings(ntst=0)
    with pytest.raises(ValueError, match="mesh_passes"):
        CollocationImpactSettings(mesh_passes=-1)
    with pytest.raises(ValueError, match="refine_ncol"):
        CollocationImpactSettings(refine_ncol=8)
    with pytest.raises(ValueError, match="refine_passes"):
        CollocationImpactSettings(refine_passes=-1)
    with pytest.raises(ValueError, match="max_turn"):
        CollocationImpactSettings(max_turn=-0.1)
    with pytest.raises(ValueError, match="detect"):
        CollocationImpactSettings(detect="yes")
    with pytest.raises(ValueError, match="contact_smoothing"):
        impacting_cycles(scene.replace(contact_smoothing=0.0), StartCycle(np.zeros(8), 0.1, 1.0))
    with pytest.raises(ValueError, match="kind 'pd'"):
        period_doubled_branch(scene, br.points[-1])
    with pytest.raises(ValueError, match="kind 'bp'"):
        symmetry_broken_branch(scene, br.points[-1])
    with pytest.raises(ValueError, match="amplitude"):
        symmetry_broken_branch(scene, replace(br.points[-1], kind="bp"), amplitude=-1e-3)


def test_impacting_cycles_say_what_is_missing():
    with pytest.raises(ValueError, match="contact = True and scene.contact_smoothing > 0"):
        impacting_cycles(Scene(mstar=1.0, modes=3))
    with pytest.raises(ValueError, match="do not reach the wall below U. = 5.6"):
        impacting_cycles(Scene(mstar=1.0, zeta=0.01, modes=3, **IMPACT), ustar_max=5.6,
                         cycle_settings=SCENE_NODES)


@pytest.mark.slow
def test_collocation_equals_shooting_at_the_same_ustar():
    """M* = 1, N = 4, U* = 6.8 (unstable period-1 impacting cycle, two contacts): the
    collocation cycle (NTST = 400) and the shooting cycle (12 segments, CVODES 1e-11) at
    the same pressure drop agree in period, amplitude, min gap and multipliers (those of
    collocation converge at the stage order only: measured 1.3e-5 relative at NTST = 300,
    2e-6 at 400; the period to 1e-11)."""
    scene, model, br = _through_contact(4, 6.9, CollocationImpactSettings(
        ntst=200, max_points=40, ds=0.2, ds_max=1.0))
    near = min(br.points, key=lambda p: abs(p.ustar - 6.8))
    target = scene.replace(ustar=6.8)
    dp = steady_state(target, model).pressure_drop
    co = impacting_cycles(target, StartCycle(near.state, near.period, dp), model=model,
                          settings=CollocationImpactSettings(quadrature_tol=None, ntst=400, max_points=1))
    sh = impacting_cycles(target, StartCycle(near.state, near.period, dp), method="shooting",
                          model=model,
                          settings=ImpactSettings(segments=12, tol=1e-11, newton_tol=1e-9,
                                                  max_points=1, quadrature_tol=None))
    c, s = co.points[0], sh.points[0]
    assert abs(c.ustar - 6.8) < 1e-8 and abs(s.ustar - 6.8) < 1e-8
    assert abs(c.period / s.period - 1) < 1e-8
    assert abs(c.tip_amplitude / s.tip_amplitude - 1) < 1e-7
    assert abs(c.gap_ratio / s.gap_ratio - 1) < 1e-5       # shooting: on samples
    assert c.impacts == s.impacts == 2 and not c.stable and not s.stable
    mc, ms = c.nontrivial_multipliers, s.nontrivial_multipliers
    big = np.abs(ms) > 1e-3
    assert np.sum(np.abs(mc) > 1e-3) == np.sum(big)
    assert np.max(np.abs(np.sort_complex(mc[np.abs(mc) > 1e-3]) - np.sort_complex(ms[big]))
                  ) < 1e-5 * np.max(np.abs(ms))


@pytest.mark.slow
def test_subharmonic_cycle_from_time_integration(period3_impacting_run):
    """M* = 1, U* = 7, N = 4: IDAS integration settles on a stable cycle of three tip
    swings with contacts; collocation started from it (the start mesh equidistributed on
    the integrated guess) converges to that cycle: period and amplitude as integrated,
    stable, and the next branch point too."""
    r = period3_impacting_run
    scene, model, period = r.scene, r.model, r.period
    assert r.swings == 3
    br = impacting_cycles(scene, StartCycle(r.state, period, r.run.steady.pressure_drop),
                          model=model, settings=CollocationImpactSettings(quadrature_tol=None,
                              ntst=300, max_points=2, ds=0.1, ds_max=1.0))
    p = br.points[0]
    assert len(br.points) == 2 and abs(p.ustar - 7.0) < 1e-8
    assert abs(p.period / period - 1) < 1e-5
    assert abs(p.tip_amplitude / r.amplitude - 1) < 1e-4
    assert p.gap_ratio < 1 and p.impacts >= 1
    assert all(q.stable for q in br.points)
    miss, amplitude, _ = _one_period(model, scene, p, method="idas", rtol=1e-10)
    assert miss < 1e-5 and abs(amplitude / p.tip_amplitude - 1) < 1e-6


@pytest.mark.slow
def test_fold_of_the_period3_isola_by_its_poincare_multiplier(period3_impacting_run):
    """N = 4, from the period-3 cycle at U* = 7 (about 2 min): the branch turns at the
    upper fold of the period-3 isola, U* = 7.6521. There the monodromy has a Jordan
    block at +1, split by the trivial multiplier's discretization error into
    1 +- 0.04i on NTST = 300, where the Poincare section's multiplier is 8.6e-4 from +1.
    What one mesh can show at +1 is its ``flow_defect`` (|Phi f - f| / |f|): the
    section's multiplier sits within half of it. On a mesh equidistributed on the
    integrated guess that is 2e-5..6e-4 (NTST 600-1200, NCOL 4 or 6); each re-meshing
    on the located cycle's own error lowers it. Rebuilt on NTST = 1200, NCOL = 6 and
    re-meshed three times (``refine_*``), the fold's flow defect is 5e-7, its multiplier
    1.5e-7 from +1 (NCOL = 4: 9e-6 and 5e-7) and the monodromy's pair split by 7e-4.
    The located fold bounds the branch's own points (the turn)."""
    r = period3_impacting_run
    br = impacting_cycles(r.scene, StartCycle(r.state, r.period, r.run.steady.pressure_drop),
                          model=r.model, ustar_max=7.7,
                          settings=CollocationImpactSettings(quadrature_tol=None,
                              ntst=300, max_points=60, ds=0.1, refine_ntst=1200))
    (fold,) = [p for p in br.special if p.kind == "fold"]
    assert fold.located and (fold.ntst, fold.ncol) == (1200, 6)
    assert abs(fold.ustar - 7.6521) < 1e-4
    assert len(fold.section_multipliers) == len(fold.multipliers) - 1
    assert abs(fold.critical_multiplier - 1) < 1e-6
    assert abs(fold.critical_multiplier - 1) < 0.5 * fold.flow_defect
    pair = np.sort(np.abs(fold.multipliers - 1))[:2]
    assert pair[1] > 30 * abs(fold.critical_multiplier - 1)
    ustar = br.column("ustar")
    assert ustar.max() <= fold.ustar + 1e-6 and ustar.max() > fold.ustar - 1e-3
    assert ustar[-1] < ustar.max() - 0.01                  # the branch came back
    back = CollocatedImpactBranch.from_json(br.to_json()).special
    assert [p.critical_multiplier for p in back] == [p.critical_multiplier for p in br.special]


@pytest.fixture(scope="module")
def n4_torus():
    """M* = 1, N = 4, same law, NTST = 100: the period-1 cycle loses stability through a
    complex pair of multipliers where the smoothed law already holds it (min gap 1.27 eps)."""
    scene, model, br = _through_contact(4, 6.7, CollocationImpactSettings(quadrature_tol=None, ntst=100,
                                                                              max_points=12))
    return scene, model, br


def test_neimark_sacker_located_where_shooting_multipliers_cross_the_circle(n4_torus):
    """The loss of stability is a located Neimark-Sacker point (Newton on the minimally
    extended system: the pair on the unit circle); shooting (CVODES, an independent
    discretization) from the located cycle finds its complex pair on the circle to 1e-3,
    i.e. U* to about 2e-5 (|mu| grows by about 60 per unit U* there)."""
    scene, model, br = n4_torus
    (ns,) = br.special
    assert ns.kind == "ns" and ns.located
    rest = ns.nontrivial_multipliers                    # by decreasing modulus
    assert abs(rest[0].imag) > 0.1 and rest[1] == np.conj(rest[0])
    assert np.max(np.abs(np.abs(rest[:2]) - 1)) < 1e-9 and np.abs(rest[2]) < 0.9
    before = [p for p in br.points if p.ustar < ns.ustar]
    after = [p for p in br.points if p.ustar > ns.ustar]
    assert before and after and all(p.stable for p in before) and not any(p.stable for p in after)
    assert 1 < ns.gap_ratio < 1.5 and 6.59 < ns.ustar < 6.62
    back = CollocatedImpactBranch.from_json(br.to_json())
    assert [(p.kind, p.ustar) for p in back.special] == [("ns", ns.ustar)]
    shot = impacting_cycles(scene.replace(ustar=ns.ustar), ns, method="shooting", model=model,
                            settings=ImpactSettings(segments=12, max_points=1,
                                                    quadrature_tol=None))
    (point,) = shot.points
    assert abs(point.period / ns.period - 1) < 1e-6
    mu = point.multipliers
    complex_pair = mu[np.abs(mu.imag) > 1e-3]
    assert complex_pair.size >= 2 and np.min(np.abs(np.abs(complex_pair) - 1)) < 1e-3


def test_period1_impacting_cycles_are_symmetric(n4_torus):
    """The channel is symmetric, and so is the period-1 impacting cycle: half a period
    after its state, an independent integration (IDAS 1e-11) is at its mirror image
    R x = (-r, -r', Q2, Q1), to 1e-8 relative (measured 2.5e-10; not at the state
    itself). Its multipliers are squares of those of the half-period map, so a single
    real multiplier cannot cross -1: such cycles do not period-double (docs/cycles.md)."""
    scene, model, br = n4_torus
    (ns,) = br.special
    assert _mirror(model, scene, ns) < 1e-8
    traj = simulate(model, steady_state(scene.replace(ustar=ns.ustar), model), ns.period / 2,
                    x0=ns.state, settings=Settings(method="idas", rtol=1e-11, atol=1e-13,
                                                   dt_out=ns.period / 2000))
    size = np.max(np.abs(ns.state))
    assert np.max(np.abs(traj.x[-1] - ns.state)) > 0.1 * size


def test_settled_cycle_of_stable_and_unstable_impacting_cycles(n4_torus):
    """The time-integration check (``settled_cycle``: IDAS 1e-10, dense-output returns)
    from the branch's states: a run from the last stable cycle before the Neimark-Sacker
    point stays on it for 30 periods; one from the first cycle past it follows it over 3
    periods (period, amplitude, min gap) and has left it by 30; from the last point
    (|mu| > 3) it is gone."""
    scene, model, br = n4_torus
    (ns,) = br.special
    p = max((p for p in br.points if p.stable), key=lambda p: p.ustar)
    run = settled_cycle(model, scene.replace(ustar=p.ustar), p.state, p.period)
    assert p.ustar < ns.ustar and run.status == "settled" and run.drift < 1e-8
    assert abs(run.period / p.period - 1) < 1e-8 and run.swings == 1
    assert abs(run.tip_amplitude / p.tip_amplitude - 1) < 1e-6
    q = min((q for q in br.points if q.ustar > ns.ustar), key=lambda q: q.ustar)
    assert q.gap_ratio < 1.5 and not q.stable
    short = settled_cycle(model, scene.replace(ustar=q.ustar), q.state, q.period, periods=3)
    assert abs(short.period / q.period - 1) < 1e-7
    assert abs(short.tip_amplitude / q.tip_amplitude - 1) < 1e-6
    assert short.min_gap == pytest.approx(q.min_gap, rel=1e-4)
    long = settled_cycle(model, scene.replace(ustar=q.ustar), q.state, q.period)
    assert long.drift > 100 * short.drift
    far = br.points[-1]
    run = settled_cycle(model, scene.replace(ustar=far.ustar), far.state, far.period)
    assert far.ustar > ns.ustar + 0.05 and run.status == "unsettled" and run.drift > 1e-3
    with pytest.raises(ValueError, match="period"):
        settled_cycle(model, scene, far.state, -1.0)
    with pytest.raises(ValueError, match="periods"):
        settled_cycle(model, scene, far.state, far.period, periods=1)


@pytest.mark.slow
def test_case_1a_at_n10_matches_time_integration():
    """N = 10, NTST = 200 (about 2 min): the period-1 branch through the first contact to
    the paper's case (1a), U* = 7. The cycle at U* = 7 (one collocation point at its
    pressure drop) is stable with 2 contact intervals, and a run from its state
    (``settled_cycle``: IDAS 1e-10, 40 periods) settles on it: period 1e-5, amplitude
    1e-4, peak force 1e-2 (measured 7e-9, 3e-6, 1e-3). On the way the branch loses and
    regains stability at two located Neimark-Sacker points (pair on the circle to 1e-9),
    as its points show."""
    scene, model, br = _through_contact(10, 7.05, CollocationImpactSettings(
        ntst=200, max_points=150))
    near = min(br.points, key=lambda p: abs(p.ustar - 7.0))
    at = scene.replace(ustar=7.0)
    one = impacting_cycles(at, StartCycle(near.state, near.period,
                                          steady_state(at, model).pressure_drop), model=model,
                           settings=CollocationImpactSettings(quadrature_tol=None, ntst=200,
                                                              max_points=1, detect=False))
    (p,) = one.points
    assert abs(p.ustar - 7.0) < 1e-9 and p.stable and p.impacts == 2 and p.gap_ratio < 1
    run = settled_cycle(model, at, p.state, p.period, periods=40)
    assert run.status == "settled" and run.swings == 1
    assert abs(run.period / p.period - 1) < 1e-5
    assert abs(run.tip_amplitude / p.tip_amplitude - 1) < 1e-4
    assert run.peak_force == pytest.approx(p.peak_force, rel=1e-2)
    ns = [s for s in br.special if s.kind == "ns"]
    assert len(ns) == 2 and all(s.located for s in ns)
    for s in ns:
        rest = s.nontrivial_multipliers
        assert abs(abs(rest[0]) - 1) < 1e-9 and rest[0].imag != 0
    lo, hi = sorted(s.ustar for s in ns)
    assert all(q.stable for q in br.points if q.ustar < lo - 1e-3)
    assert not any(q.stable for q in br.points if lo + 1e-3 < q.ustar < hi - 1e-3)
    assert all(q.stable for q in br.points if q.ustar > hi + 1e-3)


@pytest.mark.slow
def test_period_doubling_of_an_asymmetric_cycle_and_its_doubled_branch():
    """With the walls 2 % off centre (H1 = 0.051, H2 = 0.049; N = 4, M* = 0.287, about
    1 min) the cycles are no longer symmetric, and the period-1 impacting cycle (one
    contact per period) period-doubles just past contact: located at U* = 9.2004 with
    its multiplier at -1 to 1e-8, stable before and unstable after. The doubled branch
    (``period_doubled_branch``) leaves it towards larger U* with T = 2 T1 at the
    doubling, stable; a time integration from its last cycle (``settled_cycle``, IDAS
    1e-10) settles on it with two tip swings per period: period 1e-8, amplitude 1e-4,
    peak force 1e-2 (measured 3e-10, 7e-6, 2e-3)."""
    from fsicas.scene import Profile
    base = Scene(mstar=0.287, zeta=0.01, modes=4, contact_eps=1e-2,
                 channel1=Profile.constant(0.051), channel2=Profile.constant(0.049))
    start = pre_contact_start(cycle_branch(base, ustar_max=11.0, settings=SCENE_NODES))
    scene = base.replace(ustar=start.ustar, **IMPACT)
    model = build_model(scene)
    settings = CollocationImpactSettings(quadrature_tol=None, ntst=200, max_points=20, ds=0.1)
    br = impacting_cycles(scene, start, model=model, ustar_max=9.25, settings=settings)
    pd = next(p for p in br.special if p.kind == "pd")
    assert pd.located and abs(pd.ustar - 9.2004) < 1e-3 and pd.impacts == 1
    assert abs(pd.critical_multiplier + 1) < 1e-8
    assert all(p.stable for p in br.points if p.ustar < pd.ustar - 1e-4)
    assert not any(p.stable for p in br.points if pd.ustar + 1e-4 < p.ustar)
    doubled = period_doubled_branch(scene, pd, model=model, ustar_max=9.25,
                                    settings=replace(settings, max_points=25, ds=0.05))
    first, last = doubled.points[0], doubled.points[-1]
    assert abs(first.period / (2 * pd.period) - 1) < 1e-3
    assert all(p.stable and p.ustar > pd.ustar for p in doubled.points)
    assert last.ustar > pd.ustar + 0.03
    run = settled_cycle(model, scene.replace(ustar=last.ustar), last.state, last.period)
    assert run.status == "settled" and run.swings == 2
    assert abs(run.period / last.period - 1) < 1e-8
    assert abs(run.tip_amplitude / last.tip_amplitude - 1) < 1e-4
    assert run.peak_force == pytest.approx(last.peak_force, rel=1e-2)


@pytest.mark.slow
def test_symmetry_breaking_and_period_doubling_in_the_symmetric_channel():
    """N = 4, M* = 3 (about 3 min): past contact a real multiplier of the symmetric cycle
    crosses +1 with no turn, a branch point, located by Newton on the cycles that keep
    the channel's mirror; the switch reaches cycles that are not their
    own mirror image half a period on (the symmetric one is, to 1e-5), stable, and
    checked by time integration; on them a period doubling is located (in the symmetric
    channel, only such cycles can period-double)."""
    scene, model, br = _through_contact(4, 8.7, CollocationImpactSettings(
        ntst=200, max_points=30, ds=0.05, max_turn=0.3), mstar=3.0)
    (bp,) = [p for p in br.special if p.kind == "bp"]
    assert not [p for p in br.special if p.kind == "fold"]
    # by Newton on the cycles that keep the mirror (the arclength put it at 8.6377 +- 1e-3
    # with its multiplier 1e-4 from +1): the breaking multiplier at +1 to 1e-9 (measured
    # 9e-12), and so is one of the whole monodromy's, beside the trivial one (5.6e-7 off)
    assert bp.located and abs(bp.ustar - 8.6377) < 1e-3
    assert abs(bp.critical_multiplier - 1) < 1e-9
    assert np.sort(np.abs(bp.multipliers - 1))[0] < 1e-9
    before = [p for p in br.points if p.ustar < bp.ustar]
    assert before[-1].stable and not [p for p in br.points if p.ustar > bp.ustar][0].stable
    assert _mirror(model, scene, bp) < 1e-5                    # measured 2.6e-7
    sb = symmetry_broken_branch(scene, bp, model=model, ustar_max=8.7, settings=
                                CollocationImpactSettings(quadrature_tol=None, ntst=200, max_points=8, ds=0.05,
                                                          max_turn=0.3))
    p = sb.points[1]
    assert p.stable and p.ustar > bp.ustar and _mirror(model, scene, p) > 1e-3
    run = settled_cycle(model, scene.replace(ustar=p.ustar), p.state, p.period)
    assert run.status == "settled" and abs(run.period / p.period - 1) < 1e-8
    assert abs(run.tip_amplitude / p.tip_amplitude - 1) < 1e-5
    (pd,) = [q for q in sb.special if q.kind == "pd"]
    assert pd.located and abs(pd.critical_multiplier + 1) < 1e-4


def test_critical_multiplier_comes_from_the_map_that_carries_it():
    """At +1 (fold, branch point) the Poincare map's multiplier is taken (the
    monodromy's pair there is split by the square root of the discretization error); at
    -1 and on the unit circle the monodromy's non-trivial one, which the located
    condition pins (the section adds the error of ``Phi f = f``)."""
    from fsicas.cycles.impacting_collocation import CollocatedImpactPoint
    full = np.array([1.0 + 2e-3, 1.0 - 2e-3, -1.0 + 1e-10, 0.6 + 0.8j, 0.6 - 0.8j, 0.1])
    section = np.array([1.0 + 1e-6, -1.0 + 4e-6, 0.6 + 0.8j + 3e-6, 0.6 - 0.8j, 0.1])
    point = CollocatedImpactPoint(ustar=7.0, pressure_drop=1.0, period=0.1, tip_amplitude=0.04,
                                  min_gap=0.0, gap_ratio=1.0, impacts=1, multipliers=full,
                                  section_multipliers=section)
    assert replace(point, kind="regular").critical_multiplier is None
    assert replace(point, kind="fold").critical_multiplier == 1.0 + 1e-6
    assert replace(point, kind="bp").critical_multiplier == 1.0 + 1e-6
    assert replace(point, kind="pd").critical_multiplier == -1.0 + 1e-10
    assert replace(point, kind="ns").critical_multiplier in (0.6 + 0.8j, 0.6 - 0.8j)
    # without the section (a point that was not located): the monodromy's, trivial dropped
    bare = replace(point, kind="fold", section_multipliers=np.zeros(0, complex))
    assert abs(bare.critical_multiplier - 1) == pytest.approx(2e-3)


def test_quadrature_control_of_impacting_cycles(n3_branch):
    """N = 3, the branch of the first test with the default control: computed again on
    the adequate nodes, every point's estimate within IMPACT_QUADRATURE_TOL; one period
    integrated (Radau, rtol 1e-11) from its last cycle on twice those nodes returns to it
    far closer than from the uncontrolled branch's last cycle."""
    from fsicas.model.accuracy import IMPACT_QUADRATURE_TOL
    _, scene, model, plain = n3_branch
    controlled = impacting_cycles(Scene(mstar=1.0, zeta=0.01, modes=3, **IMPACT),
                                  ustar_max=12.0, cycle_settings=SCENE_NODES,
                                  settings=CollocationImpactSettings(
                                      ntst=100, max_points=5, ds=0.1, ds_max=1.0))
    nodes = controlled.points[-1].quadrature_nodes
    assert nodes > model.scene.n_quad and controlled.scene.n_quad == nodes
    assert max(p.quadrature_error for p in controlled.points) <= IMPACT_QUADRATURE_TOL
    assert max(p.quadrature_error for p in plain.points) > IMPACT_QUADRATURE_TOL
    fine = build_model(controlled.scene.replace(quad_nodes=2 * nodes))
    miss = lambda br: _one_period(fine, fine.scene, br.points[-1])[0]
    assert miss(controlled) < 1e-2 * miss(plain)
