"""Driver hooks: user events located on the branch, terminal events, per-point
``record`` columns (also across restarts) and the ``stop`` predicate."""

import numpy as np
import pytest

import continuation as C

STUART_LANDAU = dict(a1=0, a2=0, a3=0, b1=0, b2=0, b3=0, c1=-1, c2=-1, d1=-1, d2=-1)


def _fold_problem(models):
    """x' = p - x^2 from (x, p) = (1, 1): the upper branch x = sqrt(p)."""
    return C.EquilibriumProblem(models.scalar(lambda x, p: p[0] - x ** 2), [1.0],
                                {"p": 1.0}, "p")


def _down(max_steps=60, **kw):
    return C.ContinuationSettings(ds=0.05, ds_max=0.1, max_steps=max_steps, direction=-1,
                                  **kw)


def _circle(t):
    t = np.atleast_1d(t)
    return np.c_[np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)]


def _radius_event(terminal):
    """Stuart-Landau cycles are circles of radius sqrt(mu): |x(0)| = 0.5 at mu = 1/4."""
    return C.Event("half", lambda pr, X: float(np.linalg.norm(pr.state(X))) - 0.5, terminal)


def test_event_is_located_like_a_builtin_one(models):
    """x - 0.5 = 0 at p = 1/4 on x = sqrt(p), located to 1e-8 between the two points
    around it, next to the fold at p = 0; record scalars are copied into its data."""
    br = C.continuation(_fold_problem(models), settings=_down(),
                        events=[C.Event("half", lambda pr, X: X[0] - 0.5)],
                        record=lambda pr, X: {"x2": X[0] ** 2})
    assert br.status == "max_steps"
    (half,) = br.special("half")
    assert half.status == "converged" and abs(half.params["p"] - 0.25) < 1e-8
    assert abs(half.x[0] - 0.5) < 1e-8 and half.precision <= 1e-10
    x = br.x[:, 0]
    assert (x[half.index - 1] - 0.5) * (x[half.index] - 0.5) <= 0
    assert abs(half.data["x2"] - 0.25) < 1e-8 and abs(half.data["value"]) < 1e-8
    assert len(br.special("fold")) == 1
    assert np.allclose(br.tests["half"], x - 0.5)


def test_events_are_located_without_builtin_detection(models):
    br = C.continuation(_fold_problem(models), settings=_down(20, detect=False),
                        events=[C.Event("half", lambda pr, X: X[0] - 0.5)])
    assert [p.kind for p in br.special_points] == ["half"]


def test_terminal_event_ends_the_branch_at_the_located_point(models):
    br = C.continuation(_fold_problem(models), settings=_down(),
                        events=[C.Event("half", lambda pr, X: X[0] - 0.5, terminal=True)],
                        record=lambda pr, X: {"x2": X[0] ** 2})
    assert br.status == "event" and "'half'" in br.message
    (half,) = br.special("half")
    assert half.index == len(br) - 1
    assert abs(br.par("p")[-1] - 0.25) < 1e-8 and abs(br.x[-1, 0] - 0.5) < 1e-8
    assert len(br.columns["x2"]) == len(br) and br.special("fold") == []


def test_terminal_event_on_a_cycle_branch_by_shooting(models):
    """Stuart-Landau by shooting from mu = 1 down to the radius-1/2 cycle: mu = 1/4."""
    F = models.hopf_normal_form(STUART_LANDAU)
    sh = C.ShootingProblem(F, _circle, 2 * np.pi, {"mu": 1.0, "w": 1.0}, "mu")
    br = C.continuation(sh, settings=C.ContinuationSettings(ds=0.1, ds_max=0.2, direction=-1,
                                                            max_steps=40),
                        events=[_radius_event(True)])
    assert br.status == "event" and abs(br.par("mu")[-1] - 0.25) < 1e-8
    assert abs(br.columns["period"][-1] - 2 * np.pi) < 1e-8
    assert br.special("half")[0].status == "converged"


def test_record_and_events_across_collocation_restarts(models):
    """adapt_every = 2 re-meshes (driver restarts): one record call and one column
    entry per branch point, taken with each point's own problem; the terminal event
    is still located at mu = 1/4 to 1e-8."""
    F = models.hopf_normal_form(STUART_LANDAU)
    co = C.CycleProblem(F, _circle, 2 * np.pi, {"mu": 1.0, "w": 1.0}, "mu",
                        settings=C.CollocationSettings(ntst=20, ncol=4, adapt_every=2))
    calls = []

    def record(pr, X):
        calls.append(pr)
        return {"T": pr.period(X), "u0": pr.state(X)}

    br = C.continuation(co, settings=C.ContinuationSettings(ds=0.1, ds_max=0.2, direction=-1,
                                                            max_steps=40, detect=False),
                        events=[_radius_event(True)], record=record)
    assert br.stats["restarts"] >= 3 and br.status == "event"
    assert len(calls) == len(br) and len(set(map(id, calls))) == br.stats["restarts"] + 1
    assert np.array_equal(br.columns["T"], br.columns["period"])
    assert br.columns["u0"].shape == (len(br), 2) and np.array_equal(br.columns["u0"], br.x)
    assert abs(br.par("mu")[-1] - 0.25) < 1e-8


def test_stop_predicate_ends_the_branch(models):
    br = C.continuation(_fold_problem(models), settings=_down(),
                        stop=lambda pr, X: X[-1] < 0.5 and "p below 1/2")
    assert br.status == "stopped" and br.message == "p below 1/2"
    assert br.par("p")[-1] < 0.5 <= br.par("p")[-2]
    br = C.continuation(_fold_problem(models), settings=_down(), stop=lambda pr, X: True)
    assert br.status == "stopped" and len(br) == 1 and "True" in br.message


def test_event_branch_round_trips_through_a_file(models, tmp_path):
    br = C.continuation(_fold_problem(models), settings=_down(),
                        events=[C.Event("half", lambda pr, X: X[0] - 0.5, terminal=True)])
    br.save(tmp_path / "b.npz")
    back = C.Branch.load(tmp_path / "b.npz")
    assert back.status == "event" and back.special("half")[0].params == \
        br.special("half")[0].params


def test_hook_validation(models):
    pr = _fold_problem(models)
    with pytest.raises(ValueError, match="Event.name"):
        C.Event("fold", lambda pr, X: 0.0)
    with pytest.raises(ValueError, match="Event.name"):
        C.Event("not a name", lambda pr, X: 0.0)
    with pytest.raises(ValueError, match="Event.function"):
        C.Event("e", 1.0)
    with pytest.raises(ValueError, match="events"):
        C.continuation(pr, events=[lambda pr, X: 0.0])
    with pytest.raises(ValueError, match="distinct"):
        C.continuation(pr, events=[C.Event("e", lambda pr, X: 0.0)] * 2)
    with pytest.raises(ValueError, match="record"):
        C.continuation(pr, record={"a": 1})
    with pytest.raises(ValueError, match="stop"):
        C.continuation(pr, stop=True)
    with pytest.raises(ValueError, match="hopf"):
        C.continuation(pr, settings=_down(2), events=[C.Event("hopf_complex",
                                                               lambda pr, X: 0.0)])


def test_special_points_keep_the_whole_record_and_their_unknowns(models):
    """A located point carries the record's arrays (not only its scalars) and the
    problem's unknowns there: the fold of x' = p - x^2 is at X = (0, 0), the event
    x = 1/2 at X = (1/2, 1/4), with the record evaluated at those X."""
    br = C.continuation(_fold_problem(models), settings=_down(),
                        events=[C.Event("half", lambda pr, X: X[0] - 0.5)],
                        record=lambda pr, X: {"X": np.array(X), "x2": X[0] ** 2})
    (half,), (fold,) = br.special("half"), br.special("fold")
    assert np.allclose(half.unknowns, [0.5, 0.25], atol=1e-8)
    assert np.array_equal(half.record["X"], half.unknowns)
    assert np.allclose(fold.unknowns, [0.0, 0.0], atol=1e-6)
    assert np.array_equal(fold.record["X"], fold.unknowns)
    assert "X" not in half.data and abs(half.data["x2"] - 0.25) < 1e-8


def test_stop_at_ends_the_run_past_the_first_special_point_of_a_kind(models):
    """x' = p - x^2 followed down through its fold at p = 0: with stop_at = ('fold',)
    the run ends at the first point past the fold (it lies between the last two points),
    with the fold located as without stop_at."""
    full = C.continuation(_fold_problem(models), settings=_down())
    short = C.continuation(_fold_problem(models), settings=_down(stop_at=("fold",)))
    (fold,) = short.special("fold")
    assert short.status == "stopped" and "'fold'" in short.message
    assert fold.index == len(short.s) - 1 < len(full.s) - 1
    assert abs(fold.params["p"] - full.special("fold")[0].params["p"]) < 1e-12
    assert abs(fold.params["p"]) < 1e-8
    with pytest.raises(ValueError, match="stop_at"):
        C.ContinuationSettings(stop_at="fold")


def test_observing_hands_over_every_branch_and_overrides_the_progress_bar(models, capsys):
    """Within ``observing`` each run's Branch reaches the callback (nested blocks both
    observe); ``progress=True`` shows the bar although the settings say off, and outside
    the block nothing is observed any more."""
    seen, inner = [], []
    with C.observing(on_branch=seen.append, progress=True):
        first = C.continuation(_fold_problem(models), settings=_down(max_steps=5))
        with C.observing(on_branch=inner.append):
            second = C.continuation(_fold_problem(models), settings=_down(max_steps=5))
    C.continuation(_fold_problem(models), settings=_down(max_steps=5))
    assert seen == [first, second] and inner == [second]
    assert "equilibrium continuation" in capsys.readouterr().err
