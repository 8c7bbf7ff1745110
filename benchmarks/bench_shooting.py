"""One impacting-cycle shooting continuation point: the working tree against an earlier
revision, side by side in one run.

    python benchmarks/bench_shooting.py [--baseline 1ba3c13] [--modes 4 10] [--repeats 3]
        [--variants exact1 exact2 fast2] [--starts starts.json]

Scene: M* = 1, zeta = 0.01, H* = 1/10, f = 0.14, the contact law on (k* = 1e8,
eps/H = 1e-2, smoothing 0.1), ``ImpactSettings`` defaults (12 segments, CVODES at
abstol = reltol = 1e-10, Newton tolerance 1e-8). The start cycles are made once with
the working tree: the collocation branch up to contact, its last cycle with a min gap
>= 1.05 eps, then shooting steps (ds = 0.02) until the first cycle that touches the
wall (gap < eps, impacts >= 1); ``--starts`` keeps them in a file for later runs.

Each measurement is a fresh process (``baseline.run_child``) on one tree: it builds the
problem at that cycle as its tree's shooting route does (at the baseline
``fsicas.impacting._BlockShooting``, in the working tree ``continuation.ShootingProblem``
with ``shooting_settings(ImpactSettings(sensitivities=..., threads=...))``), corrects
the start point once (``ContinuationIterator.start``: also builds CasADi's derived
integrators) and then times one continuation point: ``advance`` (predictor, corrector,
tangent) and the Floquet multipliers. The variants run in turn (old, then each working
tree variant) ``--repeats`` times; printed are the median time of each, the median of
the pairwise ratios old/variant (the speed-up, robust to a machine whose speed drifts),
the share of the point spent in the residual and Jacobian calls (the integrations) and
the largest relative difference to the old tree's results (period, Π of the new point,
moduli of the 6 largest multipliers). Variants: ``exact1``/``exact2`` the default
sensitivities on 1 / 2 threads, ``fast1``/``fast2`` ``sensitivities="fast"``.
The machine's ``uptime`` load is printed before and after each N.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
from pathlib import Path

import numpy as np

from baseline import ROOT, Baseline, run_child

IMPACT = dict(contact=True, contact_stiffness=1e8, contact_eps=1e-2, contact_smoothing=0.1)

CHILD = """
import json, math, sys, time
import numpy as np
import fsicas
import continuation as C
N, start, variant = int(sys.argv[1]), json.load(open(sys.argv[2])), sys.argv[3]
IMPACT = dict(contact=True, contact_stiffness=1e8, contact_eps=1e-2, contact_smoothing=0.1)
scene = fsicas.Scene(mstar=1.0, zeta=0.01, modes=N, ustar=start["ustar"], **IMPACT)
model = fsicas.build_model(scene)
try:
    from fsicas.cycles import impacting as I
    from fsicas.linear.adapter import LOG_M, PI, PI_SCALE, TIME_SCALE, flutter_field
    from fsicas.linear.steady import steady_state
    old = False
except ImportError:
    import fsicas.impacting as I
    from fsicas.hopf import LOG_M, PI, PI_SCALE, TIME_SCALE, flutter_field
    from fsicas.steady import steady_state
    old = True
vf, st = flutter_field(model), steady_state(scene, model)
values = dict(zip(model.parameter_names, st.p))
params = {PI: start["pressure_drop"] / (scene.mstar * PI_SCALE), LOG_M: math.log10(scene.mstar)}
params.update({k: values[k] for k in vf.par_names[2:]})
T, x0 = start["period"] * TIME_SCALE, np.array(start["state"])
if old:
    shoot = C.ShootingSettings(segments=12, abstol=1e-10, reltol=1e-10, floquet="product")
    problem = I._BlockShooting(vf, I._shooting_points(vf, x0, T, params, 12, shoot), T, params,
                               PI, shoot)
else:
    shoot = I.shooting_settings(I.ImpactSettings(sensitivities=variant[:-1],
                                                 threads=int(variant[-1])))
    problem = C.ShootingProblem(vf, I.shooting_points(vf, x0, T, params, 12, shoot), T, params,
                                PI, settings=shoot)
inside = [0.0]
def timed(f):
    def call(X):
        t0 = time.perf_counter()
        try:
            return f(X)
        finally:
            inside[0] += time.perf_counter() - t0
    return call
problem.residual, problem.jacobian = timed(problem.residual), timed(problem.jacobian)
steps = C.ContinuationSettings(ds=0.02, ds_min=1e-6, ds_max=0.2, direction=1, max_steps=5,
                               newton=C.NewtonSettings(tol=1e-8, max_iter=8), detect=False)
it = C.ContinuationIterator(problem, C.PALC(), steps)
first = it.start()
inside[0] = 0.0
t0 = time.perf_counter()
step = it.advance(first)
mu = problem.multipliers(step.X)
t = time.perf_counter() - t0
top = np.sort(np.abs(mu))[::-1][:6]
print(json.dumps({"time": t, "inside": inside[0], "iterations": step.iterations,
                  "value": [problem.period(step.X), float(step.X[-1]), *map(float, top)]}))
"""

STARTS = """
import json, sys
import numpy as np
import fsicas
from fsicas.cycles import cycle_branch
from fsicas.cycles import impacting_cycles
from fsicas.cycles.impacting import ImpactSettings, pre_contact_start
N = int(sys.argv[1])
IMPACT = dict(contact=True, contact_stiffness=1e8, contact_eps=1e-2, contact_smoothing=0.1)
base = fsicas.Scene(mstar=1.0, zeta=0.01, modes=N, contact_eps=1e-2)
s = pre_contact_start(cycle_branch(base, ustar_max=10.0), 1.05)
scene = base.replace(ustar=s.ustar, **IMPACT)
br = impacting_cycles(scene, s, method="shooting",
                      settings=ImpactSettings(max_points=12, ds=0.02, ds_max=0.2,
                                              sensitivities="fast"))
p = next(p for p in br.points if p.gap_ratio < 1 and p.impacts >= 1)
print(json.dumps({"time": 0.0, "value": [], "start": {
    "state": [float(v) for v in p.state], "period": p.period,
    "pressure_drop": p.pressure_drop, "ustar": p.ustar, "gap_ratio": p.gap_ratio,
    "impacts": p.impacts}}))
"""


def load() -> str:
    return "load average " + " ".join(f"{v:.1f}" for v in os.getloadavg())


def starts(modes, path: Path | None) -> dict:
    """The impacting start cycle of each N (made with the working tree, cached in ``path``)."""
    known = json.loads(path.read_text()) if path and path.exists() else {}
    for n in modes:
        if str(n) not in known:
            known[str(n)] = run_child(ROOT, STARTS, [n])["start"]
    if path:
        path.write_text(json.dumps(known))
    return known


def row(n, old, new, name) -> str:
    """One Markdown row: medians, pairwise speed-up, integrator share, max rel. difference."""
    t_old = np.array([r["time"] for r in old])
    t_new = np.array([r["time"] for r in new])
    ref = np.array([r["value"] for r in old])
    diff = max(float(np.max(np.abs(np.array(r["value"]) - a) / np.abs(a)))
               for r, a in zip(new, ref))
    share = lambda runs: np.median([r["inside"] / r["time"] for r in runs])
    its = "/".join(str(r["iterations"]) for r in new)
    return (f"| {n} | {name} | {1e3 * np.median(t_old):.0f} | {1e3 * np.median(t_new):.0f} | "
            f"{np.median(t_old / t_new):.1f}x | {100 * share(old):.0f}% / {100 * share(new):.0f}% "
            f"| {its} | {diff:.1e} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", default="1ba3c13")
    ap.add_argument("--modes", type=int, nargs="+", default=[4, 10])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--variants", nargs="+", default=["exact1", "exact2", "fast2"],
                    choices=["exact1", "exact2", "fast1", "fast2"])
    ap.add_argument("--starts", type=Path, default=None, help="cache of the start cycles")
    args = ap.parse_args()
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, python "
          f"{platform.python_version()}; baseline {args.baseline}; {load()}", flush=True)
    known = starts(args.modes, args.starts)
    print("| N | variant | old ms | new ms | old/new (median of pairs) | in integrations old / new "
          "| Newton iterations | max rel. diff |\n|---|---|---|---|---|---|---|---|", flush=True)
    with Baseline(args.baseline) as base, tempfile.TemporaryDirectory() as tmp:
        for n in args.modes:
            start = Path(tmp) / f"start{n}.json"
            start.write_text(json.dumps(known[str(n)]))
            print(f"<!-- N = {n}: start U* = {known[str(n)]['ustar']:.6f}, gap/eps = "
                  f"{known[str(n)]['gap_ratio']:.3f}; {load()} -->", flush=True)
            runs = {v: [] for v in ["old", *args.variants]}
            for _ in range(args.repeats):
                for v in runs:
                    runs[v].append(run_child(base.path if v == "old" else ROOT, CHILD,
                                             [n, start, v]))
                    print(f"<!-- N = {n} {v}: {runs[v][-1]['time']:.2f} s -->", file=sys.stderr,
                          flush=True)
            for v in args.variants:
                print(row(n, runs["old"], runs[v], v), flush=True)
            print(f"<!-- after N = {n}: {load()} -->", flush=True)


if __name__ == "__main__":
    main()
