"""Benchmark of `continuation` on the 1-D Brusselator reaction-diffusion system.

    u_t = d1 u_xx + A - (B + 1) u + u^2 v,   v_t = d2 v_xx + B u - u^2 v,   0 < x < L,
    u = A, v = B / A at x = 0, L,

discretized by second-order finite differences on N interior nodes (n = 2N unknowns,
interleaved so the Jacobian is banded and sparse). The homogeneous state u = A,
v = B / A (nonlinear in A, so the corrector has work to do) is continued in A
downwards at B = 5.3; it loses stability at a Hopf point of the first discrete
Laplacian mode, known in closed form for the *discrete* problem:

    mu1 = (2 / h^2) (1 - cos(pi h / L)),  h = L / (N + 1),
    A_H^2 = B - 1 - (d1 + d2) mu1,  omega_H^2 = A_H^2 B - (A_H^2 + d2 mu1)^2.

For n in {10, 100, 1000} the script prints the time per continuation step
(Newton corrector + tangent + shift-invert eigenvalues, location excluded), the
time per special-point location (detection bracket -> secant -> Newton on the
Hopf system -> first Lyapunov coefficient) and the tolerance reached (max
corrector residual, |A - A_H| and |omega - omega_H| of the located point).

Run:  python benchmarks/bench_continuation.py [--sizes 10 100 1000] [--steps 100]
      [--tols 1e-6 1e-10] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import time

import casadi as ca
import numpy as np
import scipy.sparse as sp

import continuation as C

B, D1, D2, L = 5.3, 0.01, 0.01, 1.0
A0, DA = 2.3, 0.005  # start value of A and its change per step


def brusselator_1d(N: int) -> ca.Function:
    """Discretized Brusselator ``F(x, p)``, ``x = (u1, v1, u2, v2, ...)``, p = (A, B)."""
    x, p = ca.SX.sym("x", 2 * N), ca.SX.sym("p", 2)
    a, b = p[0], p[1]
    u, v = x[0::2], x[1::2]
    h = L / (N + 1)
    lap = sp.diags([1.0, -2.0, 1.0], [-1, 0, 1], shape=(N, N)) / h**2
    lap = ca.DM(lap.tocsc())
    e0 = np.zeros(N)
    e0[0] = e0[-1] = 1.0 / h**2  # Dirichlet boundary values enter the end rows
    fu = D1 * (ca.mtimes(lap, u) + a * e0) + a - (b + 1) * u + u**2 * v
    fv = D2 * (ca.mtimes(lap, v) + b / a * e0) + b * u - u**2 * v
    return ca.Function("F", [x, p], [ca.vec(ca.horzcat(fu, fv).T)])


def exact_hopf(N: int):
    h = L / (N + 1)
    mu1 = 2 / h**2 * (1 - np.cos(np.pi * h / L))
    AH2 = B - 1 - (D1 + D2) * mu1
    return np.sqrt(AH2), np.sqrt(AH2 * B - (AH2 + D2 * mu1) ** 2)


def run(N: int, steps: int, tol: float) -> dict:
    t0 = time.perf_counter()
    F = brusselator_1d(N)
    x0 = np.tile([A0, B / A0], N)
    prob = C.EquilibriumProblem(F, x0, {"A": A0, "B": B}, "A")
    ds = DA * np.sqrt(1 + N * (1 + B**2 / A0**4))  # |dX/dA| at the start
    settings = C.ContinuationSettings(
        ds=ds, ds_max=ds, direction=-1, max_steps=steps, bounds={"A": (1.0, 3.0)},
        newton=C.NewtonSettings(tol=tol), locate_tol=1e-10,
        eigen=C.EigenSettings(nev=8, sigma=0.0, dense_max=1))
    prob.jacobian(prob.X0)  # compile outside the timing of steps
    t_build = time.perf_counter() - t0
    br = C.continuation(prob, settings=settings)
    AH, wH = exact_hopf(N)
    st = br.stats
    n_steps = st["steps"]
    t_loop = st["time_total"] - st.get("time_location", 0.0)
    row = {"n": 2 * N, "tol": tol, "build": t_build, "steps": n_steps, "status": br.status,
           "step_ms": 1e3 * t_loop / (n_steps + 1),
           "newton_it": st["newton_iterations"] / (n_steps + 1),
           "max_res": float(br.residual.max()) if len(br) else float("inf")}
    if not br.special("hopf"):
        return {**row, "message": br.message}
    hopf = br.special("hopf")[0]  # first mode; later modes may follow
    return {**row, "loc_ms": 1e3 * st["time_location"] / st["located"],
            "err_A": abs(hopf.params["A"] - AH), "err_w": abs(hopf.data["omega"] - wH),
            "prec": hopf.precision, "l1": hopf.data.get("l1", float("nan"))}


def best_of(repeat: int, N: int, steps: int, tol: float) -> dict:
    """The run with the smallest time per step among ``repeat`` identical runs."""
    runs = [run(N, steps, tol) for _ in range(max(1, repeat))]
    return min(runs, key=lambda r: r["step_ms"])


def cpu_model() -> str:
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        for line in out.splitlines():
            if line.startswith("Model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[10, 100, 1000])
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--tols", type=float, nargs="+", default=[1e-6, 1e-10])
    parser.add_argument("--repeat", type=int, default=3,
                        help="runs per case; the fastest is reported (shared machines)")
    args = parser.parse_args(argv)
    rows = [best_of(args.repeat, n // 2, args.steps, tol)
            for tol in args.tols for n in args.sizes]
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"machine: {cpu_model()}, {os.cpu_count()} CPUs, load average {load:.2f}, "
          f"Python {platform.python_version()}, casadi {ca.__version__}, "
          f"best of {args.repeat}")
    print("| n | Newton tol | steps | ms/step | Newton it/step | max residual | "
          "ms/location | Hopf precision | abs(A-A_H) | abs(w-w_H) | l1 | build s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        if "message" in r:
            print(f"| {r['n']} | {r['tol']:.0e} | {r['steps']} | {r['step_ms']:.2f} | "
                  f"{r['newton_it']:.2f} | {r['max_res']:.1e} | no Hopf: {r['status']}, "
                  f"{r['message']} |")
            continue
        print(f"| {r['n']} | {r['tol']:.0e} | {r['steps']} | {r['step_ms']:.2f} | "
              f"{r['newton_it']:.2f} | {r['max_res']:.1e} | {r['loc_ms']:.1f} | "
              f"{r['prec']:.1e} | {r['err_A']:.1e} | {r['err_w']:.1e} | {r['l1']:.4g} | "
              f"{r['build']:.2f} |")
    return rows


if __name__ == "__main__":
    main()
