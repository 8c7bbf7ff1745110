"""Collocation kernels: pointwise blocks ('blocks') vs whole-graph CasADi AD ('graph').

System: a ring of n / 2 Van der Pol oscillators ``x_j'' - mu (1 - x_j^2) x_j' + x_j =
kappa c_j(x)`` with nearest-neighbour coupling (``chain``, sparse ``F_x``) or
mean-field coupling (``global``, dense ``F_x`` like a modal model), both SX; ``mx``
is the mean-field ring written with dense matrix products and kept MX
(``VectorField(expand=False)``, as a modal model is); p = (mu, kappa). The synchronous Van der Pol cycle is an exact solution; it is
corrected once at mu = 1 and every timing is taken there.

Printed per (n, NTST) and backend, medians over interleaved repetitions (the two
backends alternate inside each repetition, so machine noise hits both alike):

* ``jac`` one sparse Jacobian ``[G_U, G_T, G_p]``, ``res`` one residual;
* ``step`` one corrector iteration: residual, Jacobian, bordering ``[G_X; tau^T]``,
  sparse LU (``_driver.newton.factorize``, SuperLU) and one solve;
* ``kernel``, ``LU``, ``rest``: fractions of ``step`` inside the CasADi calls, inside
  SuperLU (factorization and solve), and in the remaining Python/NumPy work.

Model rows (``--modes``): the flutter model (``fsicas``, MX field, n = 2N + 2 states,
15 parameters) from its first Hopf point at M* = 1, the cycle branch in the scaled
pressure drop; per variant (``graph``, ``blocks+mx``, ``blocks+compiled``) the cost of
one continuation point (corrector, tangent, Floquet multipliers) over a few points,
the variants stepping in turn from the same start; ``build`` is the first build of the
problem and its first Jacobian (for ``compiled`` the C compilation into an empty
cache), ``load`` the same with the libraries cached. A shooting row (``--shooting``)
times corrector iterations of blocks vs graph shooting Jacobians. The model rows live
in ``bench_kernels_model.py`` (they import fsicas).

    python benchmarks/bench_kernels.py [--sizes 8 20 42 80] [--ntsts 10 20 40 80]
        [--ntst 20] [--scaling-n 20] [--ncol 4] [--reps 5] [--coupling mx global chain]
        [--modes 4 10 20] [--points 4] [--shooting 4] [--no-generic]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from typing import NamedTuple

# single-threaded BLAS, as in bench_cycles.py (must be set before NumPy loads)
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import casadi as ca  # noqa: E402
import numpy as np  # noqa: E402

import continuation as C  # noqa: E402
from continuation._driver.newton import factorize  # noqa: E402
from continuation._linalg.sparse import append_row  # noqa: E402

BACKENDS = ("graph", "blocks")


def oscillator_ring(n: int, coupling: str = "global") -> ca.Function:
    """``F(x, p)``, ``x = (x_1, y_1, ..., x_m, y_m)``, ``m = n / 2``, ``p = (mu, kappa)``:
    ``x_j' = y_j``, ``y_j' = mu (1 - x_j^2) y_j - x_j + kappa c_j``, ``c_j`` the ring
    Laplacian (chain) or ``mean(x) - x_j`` (global)."""
    if n % 2:
        raise ValueError(f"n must be even, got {n}")
    x, p = ca.SX.sym("x", n), ca.SX.sym("p", 2)
    u, v = x[0::2], x[1::2]
    m = n // 2
    if coupling == "chain":
        c = ca.vertcat(*[u[(j - 1) % m] - 2 * u[j] + u[(j + 1) % m] for j in range(m)])
    else:
        c = ca.sum1(u) / m - u
    fv = p[0] * (1 - u ** 2) * v - u + p[1] * c
    return ca.Function("F", [x, p], [ca.vec(ca.horzcat(v, fv).T)])


def oscillator_ring_mx(n: int) -> ca.Function:
    """The global ring as an MX function with the dense coupling matrix
    ``C = ones / m - I`` as one matrix product (the structure of a modal model:
    dense matrix blocks times the state, kept MX)."""
    m = n // 2
    x, p = ca.MX.sym("x", n), ca.MX.sym("p", 2)
    Su, Sv = (ca.DM(np.eye(n)[k::2]) for k in (0, 1))
    u, v = ca.mtimes(Su, x), ca.mtimes(Sv, x)
    c = ca.mtimes(ca.DM(np.full((m, m), 1.0 / m) - np.eye(m)), u)
    fv = p[0] * (1 - u ** 2) * v - u + p[1] * c
    return ca.Function("F", [x, p], [ca.mtimes(Su.T, v) + ca.mtimes(Sv.T, fv)])


def field(n: int, coupling: str) -> C.VectorField:
    """The VectorField of ``coupling`` ('chain', 'global' as SX, 'mx': global kept MX)."""
    if coupling == "mx":
        return C.VectorField(oscillator_ring_mx(n), None, ("mu", "kappa"), expand=False)
    return C.VectorField(oscillator_ring(n, coupling), None, ("mu", "kappa"))


def synchronous_guess(n: int):
    """``t -> x(t)``: every oscillator on the harmonic guess of radius 2."""
    def guess(t):
        t = np.atleast_1d(t)
        one = np.c_[2 * np.cos(2 * np.pi * t), -2 * np.sin(2 * np.pi * t)]
        return np.tile(one, (1, n // 2))
    return guess


class Case(NamedTuple):
    """One corrected cycle problem of one backend and its build time."""

    backend: str
    problem: object
    X: np.ndarray
    tau: np.ndarray
    build: float


def make_case(vf, n: int, ntst: int, ncol: int, backend: str) -> Case:
    """Build the problem (timed: compiling the graph or the kernel) and correct it."""
    s = C.CollocationSettings(ntst=ntst, ncol=ncol, jacobian=backend)
    t0 = time.perf_counter()
    prob = C.CycleProblem(vf, synchronous_guess(n), 6.66, {"mu": 1.0, "kappa": 0.1}, "mu",
                          settings=s)
    build = time.perf_counter() - t0
    step = C.ContinuationIterator(prob, C.PALC(), C.ContinuationSettings()).start()
    if step is None:
        raise RuntimeError(f"start point of n = {n}, NTST = {ntst} did not converge")
    return Case(backend, prob, step.X, step.tau, build)


class Timed:
    """A callable that accumulates the wall time spent in ``fun``."""

    def __init__(self, fun):
        self.fun, self.total = fun, 0.0

    def __call__(self, *args):
        t0 = time.perf_counter()
        try:
            return self.fun(*args)
        finally:
            self.total += time.perf_counter() - t0


class TimedKernel:
    """A :class:`continuation._cycles.blocks.PointKernel` whose ``evaluate`` is timed."""

    def __init__(self, kernel):
        self.kernel, self.total = kernel, 0.0

    def __getattr__(self, name):
        return getattr(self.kernel, name)

    def evaluate(self, *args, **kw):
        t0 = time.perf_counter()
        try:
            return self.kernel.evaluate(*args, **kw)
        finally:
            self.total += time.perf_counter() - t0


def instrument(case: Case) -> list:
    """Wrap the CasADi calls of ``case``'s compiled system in timers (idempotent)."""
    compiled = case.problem.system.compiled
    if case.backend == "graph":
        if not isinstance(compiled._g, Timed):
            compiled._g, compiled._jy, compiled._jp = (
                Timed(compiled._g), Timed(compiled._jy), Timed(compiled._jp))
        return [compiled._g, compiled._jy, compiled._jp]
    if not isinstance(compiled.kernel, TimedKernel):
        compiled.kernel = TimedKernel(compiled.kernel)
    return [compiled.kernel]


def once(fun) -> float:
    t0 = time.perf_counter()
    fun()
    return time.perf_counter() - t0


def corrector_iteration(case: Case, timers: list) -> dict:
    """Times of one corrector iteration split into kernel, LU and the rest."""
    prob, X, tau = case.problem, case.X, case.tau
    before = sum(t.total for t in timers)
    t0 = time.perf_counter()
    r = np.append(prob.residual(X), 0.0)
    A = append_row(prob.system.jacobian(X), tau)
    t1 = time.perf_counter()
    lu = factorize(A)
    lu.solve(r)
    t2 = time.perf_counter()
    kernel = sum(t.total for t in timers) - before
    return {"step": t2 - t0, "kernel": kernel, "lu": t2 - t1}


def measure(cases: list, reps: int) -> dict:
    """Medians per backend of ``jac``, ``res``, ``step`` and its split, interleaved."""
    timers = {c.backend: instrument(c) for c in cases}
    rows = {c.backend: {"jac": [], "res": [], "step": [], "kernel": [], "lu": []}
            for c in cases}
    for _ in range(reps):
        for c in cases:
            row = rows[c.backend]
            row["jac"].append(once(lambda: c.problem.system.jacobian(c.X)))
            row["res"].append(once(lambda: c.problem.residual(c.X)))
            for key, value in corrector_iteration(c, timers[c.backend]).items():
                row[key].append(value)
    return {b: summary(row) for b, row in rows.items()}


def summary(row: dict) -> dict:
    """Medians of ``jac``, ``res``, ``step``; the kernel and LU fractions of the summed
    step times (fractions of medians need not add up)."""
    out = {k: float(np.median(row[k])) for k in ("jac", "res", "step")}
    total = float(np.sum(row["step"]))
    out["kernel"] = float(np.sum(row["kernel"])) / total
    out["lu"] = float(np.sum(row["lu"])) / total
    return out


def check_equal(cases: list) -> float:
    """``max |J_graph - J_blocks| / max |J_graph|`` at the corrected point."""
    g, b = (c.problem.system.jacobian(cases[0].X).toarray() for c in cases)
    return float(np.max(np.abs(g - b)) / np.max(np.abs(g)))


def run_case(n: int, ntst: int, ncol: int, reps: int, coupling: str) -> dict:
    """Build both backends on one VectorField, check them equal, time them."""
    vf = field(n, coupling)
    cases = [make_case(vf, n, ntst, ncol, b) for b in BACKENDS]
    cases[1] = cases[1]._replace(X=cases[0].X, tau=cases[0].tau)
    cases[1].problem.system.D = cases[0].problem.system.D.copy()
    out = {"n": n, "ntst": ntst, "diff": check_equal(cases),
           "nnz": cases[1].problem.system.jacobian(cases[0].X).nnz,
           "build": {c.backend: c.build for c in cases}}
    out["times"] = measure(cases, reps)
    return out


HEADER = ("| n | NTST | nnz | build graph / blocks [s] | jac graph / blocks [ms] | ratio "
          "| res graph / blocks [ms] | ratio | step graph / blocks [ms] | ratio "
          "| kernel / LU / rest (graph) | kernel / LU / rest (blocks) | max rel. diff |")


def split(t: dict) -> str:
    k, lu = t["kernel"], t["lu"]
    return f"{k:.0%} / {lu:.0%} / {1 - k - lu:.0%}"


def row(result: dict) -> str:
    """One Markdown table row of ``run_case``'s result."""
    g, b = result["times"]["graph"], result["times"]["blocks"]
    ms = lambda key: f"{1e3 * g[key]:.2f} / {1e3 * b[key]:.2f} | {g[key] / b[key]:.1f}x"
    build = result["build"]
    return (f"| {result['n']} | {result['ntst']} | {result['nnz']:,} | "
            f"{build['graph']:.2f} / {build['blocks']:.2f} | {ms('jac')} | {ms('res')} | "
            f"{ms('step')} | {split(g)} | {split(b)} | {result['diff']:.1e} |")


def table(title: str, pairs, ncol: int, reps: int, coupling: str) -> None:
    print(f"\n### {title}\n")
    print(HEADER)
    print("|" + " --- |" * (HEADER.count("|") - 1))
    for n, ntst in pairs:
        print(row(run_case(n, ntst, ncol, reps, coupling)), flush=True)


def machine() -> str:
    load = os.getloadavg()
    return f"{os.cpu_count()} cores, load average {load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f}"


def parse_args(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[8, 20, 42, 80])
    ap.add_argument("--ntst", type=int, default=20)
    ap.add_argument("--ntsts", type=int, nargs="+", default=[10, 20, 40, 80])
    ap.add_argument("--scaling-n", type=int, default=20)
    ap.add_argument("--ncol", type=int, default=4)
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--coupling", choices=tuple(COUPLINGS), nargs="+",
                    default=["mx", "global"])
    ap.add_argument("--modes", type=int, nargs="*", default=[])
    ap.add_argument("--points", type=int, default=4)
    ap.add_argument("--shooting", type=int, nargs="*", default=[])
    ap.add_argument("--no-generic", action="store_true")
    return ap.parse_args(argv)


COUPLINGS = {"mx": "MX field, dense coupling matrix (kept MX)",
             "global": "SX field, mean-field coupling (dense F_x)",
             "chain": "SX field, nearest-neighbour coupling (sparse F_x)"}


def main(argv=None) -> None:
    args = parse_args(argv)
    t0 = time.perf_counter()
    print(f"Machine: {machine()}; NCOL = {args.ncol}, {args.reps} repetitions")
    for coupling in ([] if args.no_generic else args.coupling):
        label = COUPLINGS[coupling]
        table(f"{label}: scaling with n (NTST = {args.ntst})",
              [(n, args.ntst) for n in args.sizes], args.ncol, args.reps, coupling)
        table(f"{label}: scaling with NTST (n = {args.scaling_n})",
              [(args.scaling_n, m) for m in args.ntsts], args.ncol, args.reps, coupling)
    if args.modes or args.shooting:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        import bench_kernels_model as flutter        # needs fsicas
        flutter.model_table(args.modes, args.ntst, args.points)
        flutter.shooting_table(args.shooting, args.reps)
    print(f"\nTotal {time.perf_counter() - t0:.0f} s; machine at the end: {machine()}")


if __name__ == "__main__":
    main()
