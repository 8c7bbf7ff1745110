"""Cycle continuation benchmark: `continuation` collocation vs AUTO-07p.

Model: a chain of N Brusselator cells (n = 2N unknowns), diffusive coupling
d1 = d2 = 1, Dirichlet ends held at the homogeneous state (A, B/A), A = 2.
The homogeneous state loses stability at a Hopf point at
B_H = 1 + A^2 + (d1 + d2) 2 (1 - cos(pi / (N + 1))); the cycle branch born there
is continued in B for a fixed number of points with NTST = 50, NCOL = 4, uniform
mesh (AUTO: IAD = 0), Floquet multipliers at every point (AUTO: ISP = 2).

Printed per n and per tool: time per branch point (the median of ``--repeats`` runs of
each tool taken in turn; the ratio ours/AUTO is the median of the runs' ratios, with
their range: single runs swing by 30 % on a shared machine), the last point's B, and the
errors of its period and of its four largest non-trivial multipliers against a
reference solved by `continuation` with NTST = 200 at the same B (for AUTO: its
point with the largest B inside the B range of our branch; AUTO prints multipliers
with 6 significant digits, which bounds its multiplier error from below).

    python benchmarks/bench_cycles.py --sizes 20 40 80 --points 20 [--repeats 3] [--no-auto]

AUTO-07p is optional (`apt-get install gfortran auto-07p`); without it only the
`continuation` rows are printed.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

# Single-threaded BLAS, like AUTO (OMP_NUM_THREADS=1): on a shared, loaded 2-core
# machine the multithreaded OpenBLAS made the many small solves of the Floquet
# condensation (and SuperLU's solves) 10-100x slower. Must be set before NumPy loads.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

import continuation as C  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))     # the tests load it by path
from common import A, brusselator_chain, hopf_b, params  # noqa: E402,F401


def hopf_start(n: int):
    """``(equilibrium problem, its first Hopf point)`` of the chain of ``n`` states."""
    eq = C.EquilibriumProblem(brusselator_chain(n), np.tile([A, 4.5 / A], n // 2),
                              params(4.5), "B")
    br = C.continuation(eq, settings=C.ContinuationSettings(ds=0.05, ds_max=0.1,
                                                            bounds={"B": (4.0, hopf_b(n) + 0.3)}))
    return eq, br.special("hopf")[0]


def stepper(eq, hopf, floquet: str = "product", max_steps: int = 10 ** 6,
            backend: str = "compiled"):
    """``(cycle problem, step iterator)`` of the benchmark's cycle branch from ``hopf``."""
    cyc = C.cycle_from_hopf(eq, hopf, dp=1e-3, settings=C.CollocationSettings(
        ntst=50, ncol=4, floquet=floquet, backend=backend))
    # AUTO's arclength uses the L2 norm of the profile over [0, 1]; ours is the
    # Euclidean norm of all NTST NCOL node values, sqrt(NTST NCOL) = sqrt(200) larger
    scale = np.sqrt(50 * 4)
    return cyc, C.ContinuationIterator(cyc, C.PALC(), C.ContinuationSettings(
        ds=0.01 * scale, ds_max=0.05 * scale, max_steps=max_steps,
        direction=cyc.hopf_direction))


def ours(n: int, points: int, floquet: str, backend: str = "compiled"):
    """Continue the cycles from the first Hopf point; returns timings and the last X."""
    eq, hopf = hopf_start(n)
    t0 = time.perf_counter()
    cyc, it = stepper(eq, hopf, floquet, points - 1, backend)
    first = it.start()           # the start and one step, untimed: they build the
    mus = [cyc.multipliers(first.X)]   # systems (CasADi functions, compiled kernels)
    second = it.advance(first)
    mus.append(cyc.multipliers(second.X))
    build = time.perf_counter() - t0
    # the points are kept without their factors: a run keeps only the last point's (a
    # list of 20 sets of LU factors would make every point allocate fresh memory)
    steps = [replace(first, lu=None), replace(second, lu=None)]
    step = second
    t0 = time.perf_counter()
    for _ in range(points - 2):
        step = it.advance(step)
        if step is None:
            break
        steps.append(replace(step, lu=None))
        mus.append(cyc.multipliers(step.X))
    per_point = (time.perf_counter() - t0) / max(len(steps) - 2, 1)
    return {"F": cyc.vf, "cyc": cyc, "steps": steps, "mu": mus, "per_point": per_point,
            "build": build, "hopf_B": hopf.params["B"], "stats": it.stats,
            "newton": np.mean([s.iterations for s in steps[1:]])}


def reference(run, B):
    """Period and multipliers at B with NTST = 200 from the nearest cycle of ``run``."""
    cyc = run["cyc"]
    Bs = np.array([cyc.params(s.X)[1] for s in run["steps"]])
    X = run["steps"][int(np.argmin(np.abs(Bs - B)))].X
    ref = C.CycleProblem(run["F"], lambda t: cyc.evaluate(X, t), cyc.period(X), params(B),
                         "B", settings=C.CollocationSettings(ntst=200, ncol=4,
                                                             floquet="product"))
    step = C.ContinuationIterator(ref, C.PALC(), C.ContinuationSettings()).start()
    return ref.period(step.X), ref.multipliers(step.X)


def errors(T, mu, T_ref, mu_ref):
    if len(mu) < 2:
        return abs(T - T_ref), float("nan")          # multipliers not found in the output

    def top(m):
        m = np.delete(m, np.argmin(np.abs(m - 1)))
        return m[np.argsort(-np.abs(m))][:4]
    return abs(T - T_ref), float(np.max(np.abs(top(mu) - top(mu_ref))))


# ---- AUTO-07p -------------------------------------------------------------------------
FORTRAN = """SUBROUTINE FUNC(NDIM,U,ICP,PAR,IJAC,F,DFDU,DFDP)
  IMPLICIT NONE
  INTEGER, INTENT(IN) :: NDIM, ICP(*), IJAC
  DOUBLE PRECISION, INTENT(IN) :: U(NDIM), PAR(*)
  DOUBLE PRECISION, INTENT(OUT) :: F(NDIM)
  DOUBLE PRECISION, INTENT(INOUT) :: DFDU(NDIM,NDIM), DFDP(NDIM,*)
  INTEGER :: N, I
  DOUBLE PRECISION :: A, B, D1, D2, UL, UR, VL, VR, X, Y
  A=PAR(1); B=PAR(2); D1=PAR(3); D2=PAR(4)
  N=NDIM/2
  DO I=1,N
    X=U(2*I-1); Y=U(2*I)
    IF (I==1) THEN
      UL=A; VL=B/A
    ELSE
      UL=U(2*I-3); VL=U(2*I-2)
    ENDIF
    IF (I==N) THEN
      UR=A; VR=B/A
    ELSE
      UR=U(2*I+1); VR=U(2*I+2)
    ENDIF
    F(2*I-1)=A-(B+1)*X+X*X*Y+D1*(UL-2*X+UR)
    F(2*I)=B*X-X*X*Y+D2*(VL-2*Y+VR)
  ENDDO
END SUBROUTINE FUNC

SUBROUTINE STPNT(NDIM,U,PAR,T)
  IMPLICIT NONE
  INTEGER, INTENT(IN) :: NDIM
  DOUBLE PRECISION, INTENT(INOUT) :: U(NDIM),PAR(*)
  DOUBLE PRECISION, INTENT(IN) :: T
  INTEGER :: I
  PAR(1)=2.0d0; PAR(2)=4.5d0; PAR(3)=1.0d0; PAR(4)=1.0d0
  DO I=1,NDIM/2
    U(2*I-1)=PAR(1); U(2*I)=PAR(2)/PAR(1)
  ENDDO
END SUBROUTINE STPNT

SUBROUTINE BCND
END SUBROUTINE BCND
SUBROUTINE ICND
END SUBROUTINE ICND
SUBROUTINE FOPT
END SUBROUTINE FOPT
SUBROUTINE PVLS
END SUBROUTINE PVLS
"""

CONSTANTS = """NDIM={n}, IPS=1, ILP=1, ICP=[2], NTST=50, NCOL=4, IAD=3, ISP=2, ISW=1, IPLT=0
NBC=0, NINT=0, NMX=2000, NPR=10000, MXBF=0, IID=0, ITMX=8, ITNW=7, NWTN=3, JAC=0
EPSL=1e-10, EPSU=1e-10, EPSS=1e-7, DS=0.002, DSMIN=1e-6, DSMAX=0.002, IADS=1
THL={{}}, THU={{}}, UZSTOP={{2: {b_stop}}}
"""

SCRIPT = """import time
eq = run(e='brus', c='brus')
hb = eq('HB1')
t0 = time.perf_counter()
po = run(hb, IPS=2, ICP=[2, 11], NMX={points}, NPR={points}, ISP=2, IAD=0, IID=2,
         DS=0.01, DSMAX=0.05, UZSTOP={{}})
open('timing.txt', 'w').write(str(time.perf_counter() - t0))
"""


def auto(n: int, points: int):
    """Run AUTO-07p; None when it is not installed."""
    exe = shutil.which("auto-07p")
    if exe is None:
        return None
    with tempfile.TemporaryDirectory() as tmp:
        for name, text in (("brus.f90", FORTRAN), ("c.brus", CONSTANTS.format(n=n, b_stop=hopf_b(n) + 0.003)),
                           ("run.auto", SCRIPT.format(points=points))):
            with open(os.path.join(tmp, name), "w") as fh:
                fh.write(text)
        env = {**os.environ, "OMP_NUM_THREADS": "1"}
        out = subprocess.run([exe, "run.auto"], cwd=tmp, env=env, capture_output=True,
                             text=True, timeout=3600).stdout
        wall = float(open(os.path.join(tmp, "timing.txt")).read())
        fortran = [float(t) for t in re.findall(r"Total Time\s+([0-9.E+-]+)", out)][-1]
        rows = [line.split() for line in open(os.path.join(tmp, "fort.7"))
                if re.match(r"^\s+-?2\s+-?\d+\s", line)]
        diag = open(os.path.join(tmp, "fort.9")).read()
    pts = [(abs(int(r[1])), float(r[4]), float(r[-1])) for r in rows]
    return {"per_point": wall / points, "fortran_per_point": fortran / points, "points": pts,
            "diag": diag}


def auto_point(res, B_max):
    """The AUTO point with the largest B <= B_max (else the first): (B, T, multipliers)."""
    inside = [p for p in res["points"] if p[1] <= B_max] or res["points"][:1]
    pt, B, T = max(inside, key=lambda p: p[1])
    mult = re.findall(rf"^\s+2\s+{pt}\s+Multiplier\s+\d+\s+(\S+)\s+(\S+)", res["diag"],
                      re.M)
    return B, T, np.array([float(a) + 1j * float(b) for a, b in mult])


def timed(n: int, args):
    """``(run, res, ours, theirs, fortran)``: ``args.repeats`` runs of ours and of AUTO-07p
    taken in turn (the machine is shared: a single pair of runs swings by 30 %), the
    per-point times of each (AUTO's whole run and its Fortran alone), and the last run of
    each for the errors; ``res`` None without AUTO."""
    ours_t, auto_t, fortran_t, res = [], [], [], None
    for _ in range(args.repeats):
        run = ours(n, args.points, args.floquet, args.backend)
        ours_t.append(run["per_point"])
        res = None if args.no_auto else auto(n, args.points)
        if res is not None:
            auto_t.append(res["per_point"])
            fortran_t.append(res["fortran_per_point"])
    return run, res, np.array(ours_t), np.array(auto_t), np.array(fortran_t)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[20, 40, 80])
    ap.add_argument("--points", type=int, default=20)
    ap.add_argument("--repeats", type=int, default=3,
                    help="runs of each tool, in turn; medians and the median ratio")
    ap.add_argument("--floquet", default="product", choices=["product", "pencil"])
    ap.add_argument("--backend", default="compiled", choices=["compiled", "mx", "auto"],
                    help="how our collocation kernel is evaluated: 'compiled' (C, built "
                         "before the timed points, as AUTO's Fortran is), 'mx' (CasADi's "
                         "virtual machine) or 'auto' (the library's default: the virtual "
                         "machine until its calls have taken 2 s, then C)")
    ap.add_argument("--no-auto", action="store_true")
    args = ap.parse_args(argv)
    print(f"ms/point: median of {args.repeats} runs of each tool, taken in turn; ratio: "
          "median (min-max) of the per-run ratios")
    print("| n | tool | ms/point | last B | period error | multiplier error | note |")
    print("|---|---|---|---|---|---|---|")
    for n in args.sizes:
        run, res, ours_t, auto_t, fortran_t = timed(n, args)
        X = run["steps"][-1].X
        B, T = run["cyc"].params(X)[1], run["cyc"].period(X)
        eT, emu = errors(T, run["mu"][-1], *reference(run, B))
        print(f"| {n} | continuation ({args.floquet}, {args.backend}) | {1e3 * np.median(ours_t):.1f} | "
              f"{B:.5f} | {eT:.1e} | {emu:.1e} | build {run['build']:.2f} s, "
              f"Newton it/point {run['newton']:.1f}, rejected {run['stats']['rejected_steps']}, "
              f"B_H err {abs(run['hopf_B'] - hopf_b(n)):.0e} |", flush=True)
        if res is not None:
            B_a, T_a, mu_a = auto_point(res, B)
            eT, emu = errors(T_a, mu_a, *reference(run, B_a))
            ratio = ours_t / auto_t
            print(f"| {n} | AUTO-07p | {1e3 * np.median(auto_t):.1f} | {B_a:.5f} "
                  f"(last {res['points'][-1][1]:.5f}) | "
                  f"{eT:.1e} | {emu:.1e} | Fortran time {1e3 * np.median(fortran_t):.1f}"
                  f" ms/point; ratio ours/AUTO {np.median(ratio):.2f} "
                  f"({ratio.min():.2f}-{ratio.max():.2f}) |", flush=True)


if __name__ == "__main__":
    main()
