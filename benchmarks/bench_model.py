"""Cost of the model functions: build, evaluation of M, F, dF/dx; plain vs compiled.

    python benchmarks/bench_model.py [--modes 10 20 40 80] [--cache-dir DIR]

Prints markdown tables (see docs/performance.md):
1. per N (quad_nodes = 2N + 20): build time and one evaluation of M, F and dF/dx
   (median over repeats) for SX-built, MX-built and compiled C functions (C from the
   SX build when its largest function has at most --sx-limit instructions, and C from
   the MX build); first-run compile time and cached load time separately;
2. compiler flags -O1/-O2/-O3 at N = 20 (compile time vs evaluation time);
3. N = 20 with 40/80/160 quadrature nodes: cost and the error of the modal force F
   against a converged reference (400 nodes) at a random non-equilibrium state.
A fresh temporary cache is used unless --cache-dir is given, so compile times are real.
"""
from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import tempfile
import time
import timeit

import casadi
import numpy as np

from fsicas import Scene, build_model
from fsicas.model.codegen import compile_function, compile_model

FUNCS = (("M", "mass"), ("F", "rhs"), ("dF/dx", "jac_rhs"))


def per_call(fn, x, p, budget=0.3, repeat=11) -> float:
    """Median seconds per call of fn(x, p), with ~budget seconds spent."""
    t0 = time.perf_counter()
    fn(x, p)
    one = max(time.perf_counter() - t0, 1e-7)
    number = max(1, int(budget / repeat / one))
    times = timeit.repeat(lambda: fn(x, p), number=number, repeat=repeat)
    return statistics.median(times) / number


def state(model, seed=0) -> np.ndarray:
    """Non-equilibrium state: deflection ~30 % of the gap, small r, Q > 0 (no reversal)."""
    rng = np.random.default_rng(seed)
    n, s = model.n_modes, model.scene
    k = np.arange(1, n + 1)
    q = 0.006 * rng.standard_normal(n) / k**2
    r = 0.01 * rng.standard_normal(n) / k
    Q = s.ustar * np.array([float(w(0.0)) for w in s.walls]) * (1 + 0.1 * rng.random(2))
    x = np.concatenate([r, q, Q])
    xs = np.linspace(0, 1, 501)
    y = model.deflection(x, xs)
    assert np.min(s.walls[0](xs) - y) > 0 and np.min(s.walls[1](xs) + y) > 0
    return x


def us(t):
    return f"{t * 1e6:,.1f}"


def row(cells):
    print("| " + " | ".join(str(c) for c in cells) + " |", flush=True)


def header(names):
    row(names)
    row(["---"] * len(names))


def timed_build(scene, symbolic):
    t0 = time.perf_counter()
    model = build_model(scene, symbolic)
    return model, time.perf_counter() - t0


def timed_compile(model, cache):
    t0 = time.perf_counter()
    fast = compile_model(model, cache_dir=cache)
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    fast = compile_model(model, cache_dir=cache)
    return fast, first, time.perf_counter() - t0


def evals(model, x, p):
    return [us(per_call(getattr(model, attr), x, p)) for _, attr in FUNCS]


def modes_table(modes, cache, sx_limit):
    print("\n### Cost per N (quad_nodes = 2N + 20); times of one call in µs\n")
    header(["N", "variant", "build [s]", "compile, 1st run [s]", "load, cached [s]",
            "M [µs]", "F [µs]", "dF/dx [µs]"])
    for n in modes:
        scene = Scene(modes=n)
        sx, t_sx = timed_build(scene, "SX")
        mx, t_mx = timed_build(scene, "MX")
        x, p = state(sx), sx.parameters(pressure_drop=1.0)
        row([n, "SX", f"{t_sx:.2f}", "", "", *evals(sx, x, p)])
        row([n, "MX", f"{t_mx:.2f}", "", "", *evals(mx, x, p)])
        size = max(getattr(sx, a).n_instructions() for a in ("mass", "rhs", "jac_rhs", "jac_rhs_p"))
        if size <= sx_limit:
            fast, first, load = timed_compile(sx, cache)
            row([n, "C from SX", "", f"{first:.1f}", f"{load:.3f}", *evals(fast, x, p)])
        else:
            row([n, "C from SX", "", f"skipped ({size / 1e6:.1f} M instructions)", "",
                 "", "", ""])
        fast, first, load = timed_compile(mx, cache)
        row([n, "C from MX", "", f"{first:.1f}", f"{load:.3f}", *evals(fast, x, p)])
        del sx, mx, fast


def flags_table(cache):
    print("\n### Compiler flags at N = 20 (gcc; compile time [s] / one call [µs])\n")
    header(["function", "C source [MB]", "-O1", "-O2", "-O3"])
    scene = Scene(modes=20)
    sx, mx = build_model(scene, "SX"), build_model(scene, "MX")
    x, p = state(sx), sx.parameters(pressure_drop=1.0)
    for label, fn in (("F (SX)", sx.rhs), ("F (MX)", mx.rhs),
                      ("M (MX)", mx.mass), ("dF/dx (MX)", mx.jac_rhs)):
        with tempfile.TemporaryDirectory() as tmp:
            gen = casadi.CodeGenerator("probe.c", {"with_header": False})
            gen.add(fn)
            size = os.path.getsize(gen.generate(tmp + os.sep)) / 1e6
        cells = []
        for flag in ("-O1", "-O2", "-O3"):
            t0 = time.perf_counter()
            fast = compile_function(fn, cache_dir=cache, flags=[flag])
            cells.append(f"{time.perf_counter() - t0:.1f} / {us(per_call(fast, x, p))}")
        row([label, f"{size:.2f}", *cells])


def nodes_table(nodes, reference):
    print(f"\n### N = 20, quadrature nodes; error of F vs {reference} nodes "
          "(max |ΔF| / max |F|, beam rows and flow rows)\n")
    header(["nodes", "build SX [s]", "F SX [µs]", "dF/dx SX [µs]", "build MX [s]",
            "F MX [µs]", "dF/dx MX [µs]", "error F beam", "error F flow"])
    ref = build_model(Scene(modes=20, quad_nodes=reference), "MX")
    x = state(ref)
    p = ref.parameters(pressure_drop=1.0)
    f_ref = np.array(ref.rhs(x, p)).ravel()
    beam, flow = slice(0, 20), slice(40, 42)
    for k in nodes:
        scene = Scene(modes=20, quad_nodes=k)
        sx, t_sx = timed_build(scene, "SX")
        mx, t_mx = timed_build(scene, "MX")
        f = np.array(sx.rhs(x, p)).ravel()
        err = [np.max(np.abs(f[s] - f_ref[s])) / np.max(np.abs(f_ref[s])) for s in (beam, flow)]
        row([k, f"{t_sx:.2f}", us(per_call(sx.rhs, x, p)), us(per_call(sx.jac_rhs, x, p)),
             f"{t_mx:.2f}", us(per_call(mx.rhs, x, p)), us(per_call(mx.jac_rhs, x, p)),
             f"{err[0]:.1e}", f"{err[1]:.1e}"])


def machine() -> str:
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        name = next((l.split(":", 1)[1].strip() for l in out.splitlines()
                     if l.startswith("Model name")), platform.processor())
    except OSError:
        name = platform.processor()
    return f"{name}, {os.cpu_count()} cores, Python {platform.python_version()}, " \
           f"CasADi {casadi.__version__}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--modes", type=int, nargs="+", default=[10, 20, 40, 80])
    ap.add_argument("--nodes", type=int, nargs="+", default=[40, 80, 160])
    ap.add_argument("--reference-nodes", type=int, default=400)
    ap.add_argument("--sx-limit", type=int, default=500_000,
                    help="compile SX-built functions only up to this many instructions")
    ap.add_argument("--no-flags", action="store_true", help="skip the compiler-flag table")
    ap.add_argument("--cache-dir", default=None, help="default: a fresh temporary directory")
    args = ap.parse_args(argv)
    start = time.perf_counter()
    print(f"Machine: {machine()}")
    with tempfile.TemporaryDirectory(prefix="fsicas-bench-") as tmp:
        cache = args.cache_dir or tmp
        modes_table(args.modes, cache, args.sx_limit)
        if not args.no_flags:
            with tempfile.TemporaryDirectory(prefix="fsicas-flags-") as own:
                flags_table(own)          # own cache: no hits from the first table
        nodes_table(args.nodes, args.reference_nodes)
    print(f"\nTotal benchmark time: {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
