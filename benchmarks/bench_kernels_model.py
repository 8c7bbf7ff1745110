"""Model rows of ``bench_kernels.py``: collocation and shooting kernels on the flutter
model of fsicas (see the docstring there; run through ``bench_kernels.py --modes``).
"""

from __future__ import annotations

import os
import tempfile
import time

import numpy as np

import continuation as C
from bench_kernels import Case, factorize, instrument, once


class TimedLU:
    """Time spent in the linear algebra of the Newton and tangent systems and of the
    Floquet condensation: SuperLU (``scipy.sparse.linalg.splu`` and the solves of its
    result), the condensed solver (the interval factors and the chain, ``STEPS``) and
    its interval products (the refinement's residuals)."""

    #: ``(module, class, method)`` of the condensed solver's linear algebra
    STEPS = tuple((module, cls, name) for module, cls in (
        ("_stacks", "StackLU"), ("_stacks", "BandStackLU"), ("_intervals", "KinematicLU"))
        for name in ("of", "solve")) + tuple(("_chain", "Chain", name) for name in (
            "of", "bordered", "solve"))

    def __init__(self):
        self.total, self._saved, self._depth = 0.0, {}, 0

    def __enter__(self):
        import importlib

        import scipy.sparse.linalg as spla
        from continuation._cycles.condensed import CollocationJacobian
        timer = self

        class Factor:
            def __init__(self, lu):
                self.lu = lu

            def __getattr__(self, name):
                return getattr(self.lu, name)

            def solve(self, *args, **kw):
                return timer.timed(self.lu.solve, *args, **kw)

        owners = {(module, cls): getattr(importlib.import_module(f"continuation.{module}"),
                                         cls) for module, cls, _ in self.STEPS}
        self._saved = {(spla, "splu"): spla.splu,
                       (CollocationJacobian, "collocation_times"):
                           CollocationJacobian.collocation_times,
                       **{(owners[m, c], name): owners[m, c].__dict__[name]
                          for m, c, name in self.STEPS}}
        splu = spla.splu
        spla.splu = lambda *a, **kw: Factor(self.timed(splu, *a, **kw))
        for m, c, name in self.STEPS:
            fun = owners[m, c].__dict__[name]
            if isinstance(fun, classmethod):
                fun = fun.__func__
                setattr(owners[m, c], name, classmethod(
                    lambda *a, fun=fun: self.timed(fun, *a)))
            else:
                setattr(owners[m, c], name, lambda *a, fun=fun: self.timed(fun, *a))
        times = CollocationJacobian.collocation_times
        CollocationJacobian.collocation_times = lambda *a: self.timed(times, *a)
        return self

    def __exit__(self, *exc):
        for (module, name), fun in self._saved.items():
            setattr(module, name, fun)

    def timed(self, fun, *args, **kw):
        """``fun(*args, **kw)``, timed unless inside a timed call."""
        if self._depth:
            return fun(*args, **kw)
        self._depth += 1
        t0 = time.perf_counter()
        try:
            return fun(*args, **kw)
        finally:
            self.total += time.perf_counter() - t0
            self._depth -= 1


MODEL_VARIANTS = (("graph", "mx"), ("blocks", "mx"), ("blocks", "compiled"))


def flutter_start(modes: int):
    """``(equilibrium problem, Hopf point)`` of the flutter model at M* = 1."""
    import fsicas
    from fsicas.linear.hopf import critical_velocity, flutter_problem
    scene = fsicas.Scene(modes=modes)
    model = fsicas.build_model(scene)
    hopf = critical_velocity(scene, model, ustar_max=20.0)
    return flutter_problem(scene, model, min(0.2, hopf.ustar / 2)), hopf


def flutter_cycle(eq, hopf, jacobian: str, backend: str, ntst: int):
    """The cycle problem from the Hopf point, built and its first Jacobian taken (timed)."""
    t0 = time.perf_counter()
    prob = C.cycle_from_hopf(eq, hopf.point, dp=1e-3, settings=C.CollocationSettings(
        ntst=ntst, ncol=4, floquet="product", jacobian=jacobian, backend=backend))
    prob.jacobian(prob.X0)
    return prob, time.perf_counter() - t0


def cached_load(eq, hopf, ntst: int) -> float:
    """Build time of the compiled variant once its libraries are on disk (new field)."""
    from continuation import compilation
    compilation._REQUESTS.clear()
    eq2, hopf2 = flutter_start(eq.vf.n // 2 - 1)
    return flutter_cycle(eq2, hopf2, "blocks", "compiled", ntst)[1]


def iterators(problems: dict, points: int) -> dict:
    """Per variant, a continuation generator past its start point (the settings of
    ``fsicas.cycles.cycle_branch``)."""
    out = {}
    for key, prob in problems.items():
        s = C.ContinuationSettings(ds=0.01, ds_min=1e-9, ds_max=0.1, max_steps=points,
                                   direction=prob.hopf_direction, detect=False)
        it = iter(C.ContinuationIterator(prob, C.PALC(), s))
        next(it)                                # the start point, not timed
        out[key] = it
    return out


def step_costs(problems: dict, points: int) -> dict:
    """Per variant: median time of one point and the kernel and LU fractions."""
    its = iterators(problems, points)
    kernels = {k: instrument(Case(k[0], p, None, None, 0.0)) for k, p in problems.items()}
    rows = {k: {"point": [], "kernel": 0.0, "lu": 0.0} for k in problems}
    for _ in range(points):
        for key, it in its.items():
            k0 = sum(t.total for t in kernels[key])
            with TimedLU() as lu:
                t0 = time.perf_counter()
                next(it)
                dt = time.perf_counter() - t0
            rows[key]["point"].append(dt)
            rows[key]["kernel"] += sum(t.total for t in kernels[key]) - k0
            rows[key]["lu"] += lu.total
    return {k: {"point": float(np.median(r["point"])), "kernel": r["kernel"] / sum(r["point"]),
                "lu": r["lu"] / sum(r["point"])} for k, r in rows.items()}


def model_case(modes: int, ntst: int, points: int) -> dict:
    """Build the three variants on one flutter field in an empty cache and time them."""
    eq, hopf = flutter_start(modes)
    with tempfile.TemporaryDirectory() as cache:
        os.environ["CONTINUATION_CACHE"] = cache
        built = {v: flutter_cycle(eq, hopf, *v, ntst) for v in MODEL_VARIANTS}
        load = cached_load(eq, hopf, ntst)
        times = step_costs({v: p for v, (p, _) in built.items()}, points)
    backend = built[MODEL_VARIANTS[2]][0].system.compiled.kernel.backend
    return {"N": modes, "build": {v: b for v, (_, b) in built.items()}, "load": load,
            "times": times, "backend": backend}


MODEL_HEADER = ("| N | n | build graph / mx / compiled (cached) [s] | point graph / mx / "
                "compiled [ms] | graph/mx | graph/compiled | mx/compiled | kernel / LU / "
                "rest graph | mx | compiled |")


def model_row(r: dict) -> str:
    """One Markdown row of :func:`model_case`."""
    g, m, c = (r["times"][v] for v in MODEL_VARIANTS)
    b = [r["build"][v] for v in MODEL_VARIANTS]
    sp = lambda t: f"{t['kernel']:.0%} / {t['lu']:.0%} / {1 - t['kernel'] - t['lu']:.0%}"
    tag = "" if r["backend"] == "compiled" else " (no compiler: mx)"
    return (f"| {r['N']} | {2 * r['N'] + 2} | {b[0]:.2f} / {b[1]:.2f} / {b[2]:.1f} "
            f"({r['load']:.2f}){tag} | {1e3 * g['point']:.0f} / {1e3 * m['point']:.0f} / "
            f"{1e3 * c['point']:.0f} | {g['point'] / m['point']:.1f}x | "
            f"{g['point'] / c['point']:.1f}x | {m['point'] / c['point']:.1f}x | {sp(g)} | "
            f"{sp(m)} | {sp(c)} |")


def model_table(modes, ntst: int, points: int) -> None:
    """The Markdown table of :func:`model_case` rows (nothing when ``modes`` is empty)."""
    if not modes:
        return
    print(f"\n### Flutter model: cost per cycle point (NTST = {ntst}, NCOL = 4, "
          f"median of {points} points)\n")
    print(MODEL_HEADER)
    print("|" + " --- |" * (MODEL_HEADER.count("|") - 1))
    for N in modes:
        print(model_row(model_case(N, ntst, points)), flush=True)


SHOOTING = {"graph": dict(jacobian="graph"), "exact": dict(jacobian="blocks"),
            "fast": dict(jacobian="blocks", sensitivities="fast")}


def shooting_row(modes: int, reps: int) -> str:
    """One corrector iteration of a shooting problem from the flutter Hopf cycle, per
    Jacobian route (:data:`SHOOTING`)."""
    eq, hopf = flutter_start(modes)
    cyc = flutter_cycle(eq, hopf, "blocks", "mx", 20)[0]
    X = C.ContinuationIterator(cyc, C.PALC(), C.ContinuationSettings()).start().X
    nodes, T = cyc.nodes(X), X[-2]
    probs = {j: C.ShootingProblem(cyc.vf, nodes, T, cyc.par_dict(X), cyc.active,
                                  settings=C.ShootingSettings(**kw))
             for j, kw in SHOOTING.items()}
    iteration = lambda p, X: factorize(p.bordered_jacobian(X, np.ones(X.size))).solve(
        np.append(p.residual(X), 0.0))
    t = {j: [] for j in probs}
    rng = np.random.default_rng(0)
    for j, p in probs.items():
        iteration(p, p.X0)                      # builds the integrators, not timed
    for _ in range(reps):                       # a new X each time (no cached Jacobian)
        X = probs["graph"].X0 * (1 + 1e-6 * rng.standard_normal(probs["graph"].X0.size))
        for j, p in probs.items():
            t[j].append(once(lambda: iteration(p, X)))
    g, e, f = (float(np.median(t[j])) for j in SHOOTING)
    return (f"| {modes} | {2 * modes + 2} | {1e3 * g:.0f} / {1e3 * e:.0f} / {1e3 * f:.0f} | "
            f"{g / e:.1f}x | {g / f:.1f}x |")


def shooting_table(modes, reps: int) -> None:
    """The Markdown table of :func:`shooting_row` rows (nothing when ``modes`` is empty)."""
    if not modes:
        return
    print("\n### Flutter model: shooting corrector iteration (4 segments, cvodes)\n")
    print("| N | n | graph / blocks exact / blocks fast [ms] | graph/exact | graph/fast |\n"
          "| --- | --- | --- | --- | --- |")
    for N in modes:
        print(shooting_row(N, reps), flush=True)
