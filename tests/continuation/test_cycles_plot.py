"""Plots of cycle branches (period / amplitude axes, PD marker) and of one cycle."""

import matplotlib

matplotlib.use("Agg")

import casadi as ca  # noqa: E402
import numpy as np  # noqa: E402

import continuation as C  # noqa: E402
from continuation.plotting import plot_branch, plot_cycle  # noqa: E402


def test_plot_cycle_branch_and_phase_portrait():
    import matplotlib.pyplot as plt

    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    r2 = x[0] ** 2 + x[1] ** 2
    F = ca.Function("F", [x, p], [ca.vertcat(p[0] * x[0] - x[1] - x[0] * r2,
                                             x[0] + p[0] * x[1] - x[1] * r2)])
    prob = C.CycleProblem(F, lambda t: 0.5 * np.c_[np.cos(2 * np.pi * t),
                                                   np.sin(2 * np.pi * t)],
                          6.3, {"mu": 0.25}, "mu", settings=C.CollocationSettings(ntst=10))
    br = C.continuation(prob, settings=C.ContinuationSettings(max_steps=3))
    fig, (a1, a2) = plt.subplots(1, 2)
    plot_branch(br, y="amplitude", ax=a1)
    assert np.allclose(a1.lines[0].get_ydata(), br.columns["amplitude"])
    step = C.ContinuationIterator(prob, C.PALC(), C.ContinuationSettings()).start()
    plot_cycle(prob, step.X, 0, 1, ax=a2)
    xy = a2.lines[0].get_xydata()
    assert np.allclose(np.hypot(xy[:, 0], xy[:, 1]), 0.5, atol=1e-5)   # r = sqrt(1/4)
    plt.close(fig)
