"""Nonlinear time integration of ``M(x, p) xdot = F(x, p)`` with wall contact.

Routes (``Settings.method``):

- ``idas`` (default): CasADi's IDAS on the semi-explicit index-1 form
  ``x' = z, 0 = M(x) z − F(x)`` (the implicit form; ``z`` are the time derivatives, started
  consistently). ``M z`` is the matrix-free :attr:`Model.mass_action`, O(N K): the
  residual and its Jacobian never form M, and no linear solve appears inside them.
- ``cvodes``: CasADi's CVODES (BDF, Newton with an exact dense Jacobian) on the explicit
  form ``xdot = M(x)^{-1} F(x)``; the Jacobian includes the derivative of M, through the
  matrix-free ``M v`` (:func:`fsicas.timedomain.rhs.explicit_ode`); about 4x dearer per step than IDAS at N = 40.
- ``radau`` / ``bdf``: SciPy's ``solve_ivp`` with the same compiled right-hand side and its
  exact Jacobian: an independent check and the benchmark's baseline.

Time is an input of the integrator: the pressure drop is ``Δp(t)`` of a
:class:`~fsicas.timedomain.breathing.PressureSchedule`. The run is integrated in chunks of about
``Settings.chunk`` time units, each returning the state on a uniform output grid of step
``dt_out``; after each chunk the samples are checked (finite, both gaps ``h_c > 0`` at
101 points along the beam) and handed to a ``monitor`` (outcome classification) that may
stop the run early. Solver failures (step-size or Newton failures, too much work) are
returned as ``status="failed"`` with the solver's message, never as NaN. What SUNDIALS
prints through CasADi during a call (``res failed: ... NaN detected``, ``the residual
function failed unrecoverably``: a gap closing inside a step, which the solver then
retries with a smaller step or reports) is kept off the terminal and appended to the
solver's error when the call fails (:func:`solver_output`).
"""
from __future__ import annotations

import contextlib
import io
import math
import time
from dataclasses import dataclass, field
from typing import Literal, get_args

import casadi as ca
import numpy as np
import scipy.integrate
from tqdm import tqdm

from ..checks import finite_number, require
from .limits import check_size
from .breathing import PressureSchedule
from .failures import first_bad, solver_message
from .rhs import compiled_route
from ..model.assembly import Model
from ..model.contact import GAP_POINTS, gaps
from ..linear.stability import steady_eigen
from ..linear.steady import SteadyState

__all__ = ["Settings", "Trajectory", "TrajectoryStatus", "Method", "Integrator", "simulate",
           "initial_state", "gaps", "eigenvector_state", "GAP_POINTS"]

#: Integration route (module docstring).
Method = Literal["cvodes", "idas", "radau", "bdf"]
METHODS = get_args(Method)
#: "success": integrated to t_end or stopped by the monitor; "failed": a solver failure
#: or a bad sample (message says which); the samples end at the last good one.
TrajectoryStatus = Literal["success", "failed"]


@dataclass(frozen=True)
class Settings:
    """Integration policy; checked when built (ValueError names the field).

    rtol in [1e-13, 1e-2], atol in (0, 1e-2]; ``dt_out`` output step; ``chunk``: time
    between checks; ``max_steps``: solver steps allowed per chunk. IDAS's Newton test
    also weighs the algebraic derivatives z with atol: far below their round-off
    (atol ≲ 1e-16 for |z| ~ 100) it fails with IDA_CONV_FAIL (reported); use cvodes there.
    """

    method: Method = "idas"
    rtol: float = 1e-8
    atol: float = 1e-10
    dt_out: float = 1e-3
    chunk: float = 0.5
    max_steps: int = 50_000

    def __post_init__(self):
        if self.method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, got {self.method!r}")
        require(1e-13 <= finite_number("rtol", self.rtol) <= 1e-2, f"rtol must lie in [1e-13, 1e-2], got {self.rtol}")
        require(0 < finite_number("atol", self.atol) <= 1e-2, f"atol must lie in (0, 1e-2], got {self.atol}")
        require(finite_number("dt_out", self.dt_out) > 0, f"dt_out must be > 0, got {self.dt_out}")
        require(finite_number("chunk", self.chunk) >= self.dt_out, f"chunk must be >= dt_out, got {self.chunk}")
        require(isinstance(self.max_steps, int) and self.max_steps > 0,
               f"max_steps must be a positive integer, got {self.max_steps!r}")


@dataclass(frozen=True)
class Trajectory:
    """Samples ``x[k]`` at times ``t[k]`` (t[0] = 0 is the initial state).

    status: :data:`TrajectoryStatus` (message says why, t ends at the last good sample);
    stop_reason: "t_end" or the monitor's reason (for the outcome monitor of
    :func:`fsicas.timedomain.run.run_case` an :data:`~fsicas.timedomain.outcome.OutcomeKind`);
    steps: solver steps taken.
    """

    model: Model = field(repr=False)
    t: np.ndarray
    x: np.ndarray
    pressure_drop: np.ndarray
    p: np.ndarray
    status: TrajectoryStatus
    message: str
    stop_reason: str
    steps: int
    wall_time: float
    settings: Settings
    gap_closed: bool = False

    @property
    def failed(self) -> bool:
        return self.status != "success"

    @property
    def tip(self) -> np.ndarray:
        """Tip displacement y(x_ref, t)."""
        return self.model.tip_deflection(self.x)

    @property
    def tip_velocity(self) -> np.ndarray:
        """Tip velocity dy/dt(1, t)."""
        return self.model.tip_velocity(self.x)


def initial_state(model: Model, steady: SteadyState, perturbation=1e-2) -> np.ndarray:
    """Steady state plus a perturbation of the modal displacements.

    ``perturbation``: a scalar a gives ``q_n += a (H*/2) (w_1/w_n)² / 2``: the static
    response to one equal modal force on every mode (the paper's "small perturbation
    force applied to all beam modes"), tip displacement ≈ a H*/2 (mode 1 dominates, the
    lightly damped high modes are barely excited); or an array of N modal displacements.
    Raises ValueError if the perturbed beam touches or crosses a wall.
    """
    n = model.n_modes
    x0 = np.array(steady.x, dtype=float)
    if np.isscalar(perturbation):
        a = finite_number("perturbation", perturbation)
        w = model.basis.omega
        dq = a * model.scene.hstar / 2 * (w[0] / w) ** 2 / 2
    else:
        dq = np.asarray(perturbation, dtype=float)
        require(dq.shape == (n,) and bool(np.all(np.isfinite(dq))),
               f"perturbation must be a scalar or {n} finite modal displacements")
    x0[n:2 * n] += dq
    h = gaps(model, x0)
    require(float(h.min()) > 0, f"perturbation puts the beam through a wall (min gap {h.min():.3g} "
           f"<= 0 at x = {GAP_POINTS[np.argmin(h.min(axis=1)[0])]:.3g}); use a smaller perturbation")
    return x0


def eigenvector_state(model: Model, steady: SteadyState, size: float):
    """Steady state plus ``size`` times the real part of the leading eigenvector, scaled to
    a unit tip deviation; and that eigenvalue (largest real part of ``F_x v = λ M v``)."""
    lam, V = steady_eigen(model, steady)
    v = V[:, 0].real
    v = v / abs(model.tip_deflection(v))
    return _checked_x0(model, steady.x + size * v), lam[0]


@dataclass(frozen=True)
class Integrator:
    """One integrator for one model, method and output grid of a chunk; reusable.

    The CasADi objects of the route are built once in ``__post_init__`` into private,
    non-compared fields (``_idas``, ``_zfun`` for IDAS; ``_fn`` for CVODES; ``_rhs``,
    ``_jac`` for SciPy)."""

    model: Model
    settings: Settings
    span: float
    n_out: int
    _fn: object = field(default=None, init=False, repr=False, compare=False)
    _rhs: object = field(default=None, init=False, repr=False, compare=False)
    _jac: object = field(default=None, init=False, repr=False, compare=False)
    _zfun: object = field(default=None, init=False, repr=False, compare=False)
    _idas: tuple = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self):
        for name, value in compiled_route(self.model, self.settings, self.span, self.n_out).items():
            object.__setattr__(self, name, value)

    def run(self, x0, pe) -> tuple[np.ndarray, int]:
        """States at the chunk's output grid (n_state, n_out) and the solver steps."""
        if self._idas is not None:
            with solver_output():
                return self._run_idas(x0, pe)
        if self._fn is not None:
            with solver_output():
                out = self._fn(x0=x0, p=pe)
            return np.array(out["xf"]), int(self._fn.stats().get("nsteps", 0))
        return self._run_scipy(x0, pe)

    def _run_idas(self, x0, pe):
        """IDAS from the consistent start ``z0 = x'(0) = M⁻¹F``.

        CasADi takes the initial derivative of x from the construction option
        ``init_xdot`` (default 0), so the integrator is built per run with it (about
        4 / 18 / 58 ms at N = 10 / 40 / 80). Starting from x' = 0 instead fails IDAS's first
        error test at tight tolerances; IDACalcIC, the alternative, fails its line search
        when the guess is already consistent.
        """
        dae, grid, opts = self._idas
        z0 = np.array(self._zfun(x0, pe, 0.0)).ravel()
        fn = ca.integrator("sim", "idas", dae, 0.0, grid, {**opts, "init_xdot": list(z0)})
        out = fn(x0=x0, p=pe, z0=z0)
        return np.array(out["xf"]), int(fn.stats().get("nsteps", 0))

    def _run_scipy(self, x0, pe):
        s = self.settings
        def fun(t, x):
            f = np.array(self._rhs(t, x, pe)).ravel()
            if not np.all(np.isfinite(f)):   # NaN marks a closed gap (_nan_if_closed)
                raise RuntimeError(f"solve_ivp ({s.method}): RHSFUNC_FAIL, NaN right-hand side at t = {t}")
            return f

        jac = lambda t, x: np.array(self._jac(t, x, pe))
        grid = np.linspace(0.0, self.span, self.n_out + 1)
        sol = scipy.integrate.solve_ivp(fun, (0.0, self.span), np.asarray(x0, float),
                                        method=s.method.capitalize() if s.method == "radau" else "BDF",
                                        t_eval=grid[1:], rtol=s.rtol, atol=s.atol, jac=jac)
        if sol.status != 0:
            raise RuntimeError(f"solve_ivp ({s.method}): {sol.message}")
        return sol.y, int(sol.t.size and sol.nfev)  # SciPy exposes no step count: report f-evals


def pressure_coefficient(model: Model, steady: SteadyState, schedule: PressureSchedule) -> float:
    """``c = Δp_ss / (U_ref |U_ref|)`` from the steady state at the reference U*."""
    u = schedule.reference_ustar
    if abs(u - steady.scene.ustar) > 1e-12 * max(1.0, abs(u)):
        raise ValueError(f"the steady state is at U* = {steady.scene.ustar}, the schedule's "
                         f"reference U* is {u}: compute the steady state at the reference")
    return steady.pressure_drop / (u * abs(u)) if u != 0 else 0.0


def simulate(model: Model, steady: SteadyState, t_end: float, *, settings: Settings = Settings(),
             schedule: PressureSchedule | None = None, perturbation=1e-2, x0=None,
             monitor=None, integrator: Integrator | None = None,
             progress: bool = False) -> Trajectory:
    """Integrate from the perturbed steady state (or ``x0``) over ``[0, t_end]``.

    ``monitor(t, x) -> str | None`` is called after each chunk with all samples so far;
    a non-None return stops the run with that ``stop_reason``. ``progress``: a tqdm bar
    of the integrated time on stderr. Bad input raises ValueError before any work;
    solver failures give ``status="failed"``.
    """
    schedule = schedule or PressureSchedule.constant(steady.scene.ustar)
    check_size(model.n_state, t_end, settings.dt_out, schedule)
    x0 = initial_state(model, steady, perturbation) if x0 is None else _checked_x0(model, x0)
    n_chunks = max(1, math.ceil(t_end / settings.chunk - 1e-9))
    span = t_end / n_chunks
    n_out = max(1, round(span / settings.dt_out))
    if integrator is None or (integrator.settings, integrator.span, integrator.n_out) != (settings, span, n_out):
        integrator = Integrator(model, settings, span, n_out)
    with tqdm(total=round(t_end, 6), disable=not progress, desc="time integration", unit="T",
              leave=False) as bar:
        return _loop(model, steady, schedule, integrator, x0, n_chunks, monitor, bar)


def _checked_x0(model, x0):
    x0 = np.asarray(x0, dtype=float)
    require(x0.shape == (model.n_state,) and bool(np.all(np.isfinite(x0))),
           f"x0 must hold {model.n_state} finite values")
    require(float(gaps(model, x0).min()) > 0, "x0 puts the beam through a wall (a gap h_c <= 0)")
    return x0


@contextlib.contextmanager
def solver_output():
    """Run a CasADi/SUNDIALS call with what it prints to ``sys.stderr`` captured (CasADi
    writes there through Python): dropped if the call succeeds (retried steps), appended
    to the ``RuntimeError`` if it fails. ``sys.stderr`` is restored on exit."""
    buffer = io.StringIO()
    try:
        with contextlib.redirect_stderr(buffer):
            yield
    except RuntimeError as err:
        printed = buffer.getvalue().strip()
        if not printed:
            raise
        raise RuntimeError(f"{err}\n{printed}") from err


def _loop(model, steady, schedule, integrator, x0, n_chunks, monitor, bar) -> Trajectory:
    start = time.perf_counter()
    coefficient = pressure_coefficient(model, steady, schedule)
    sched = schedule.vector(coefficient)
    span, n_out = integrator.span, integrator.n_out
    ts, xs = [np.zeros(1)], [x0[None, :]]
    steps, status, message, reason = 0, "success", "", "t_end"
    x = x0
    for k in range(n_chunks):
        pe = np.concatenate([steady.p, sched, [k * span]])
        try:
            X, nsteps = integrator.run(x, pe)
        except RuntimeError as err:
            t_good, x_good = _recover(model, integrator, x, pe, k * span)
            last = x_good[-1] if len(x_good) else x
            status, message = "failed", solver_message(err, k * span, model, last, steady.p)
            ts.append(t_good), xs.append(x_good)
            break
        steps += nsteps
        times = k * span + np.linspace(0.0, span, n_out + 1)[1:]
        bad = first_bad(model, X.T, times, steady.p)
        if bad is not None:
            status, message = "failed", bad[1]
            ts.append(times[:bad[0] + 1])
            xs.append(X.T[:bad[0]])
            break
        ts.append(times)
        xs.append(X.T)
        x = X[:, -1]
        bar.update(round(span, 6))
        if monitor is not None:
            reason_now = monitor(np.concatenate(ts), np.concatenate(xs))
            if reason_now:
                reason = reason_now
                break
    t, X = np.concatenate(ts), np.concatenate(xs)
    dp = coefficient * _u_abs_u(schedule.ustar_at(t))
    return Trajectory(model, t, X, dp, steady.p, status, message, reason, steps,
                      time.perf_counter() - start, integrator.settings,
                      gap_closed="gap closed" in message)


def _recover(model, integrator, x, pe, t0, refine=50):
    """Samples of a failed chunk up to the failure.

    The failing chunk is re-run in pieces, the failing piece in smaller pieces, and so on
    (each level at most 20 runs, :func:`_levels`) down to one output step, and the
    failing step in ``refine`` sub-steps: the last samples before a failure (e.g. a
    closing gap) are ``dt_out / refine`` apart, close enough to locate the contact
    (:mod:`fsicas.timedomain.outcome`), at a cost that grows with the logarithm of the
    number of output steps, not with it.
    """
    ts, xs = [np.zeros(0)], [np.zeros((0, model.n_state))]
    for length, samples, count in _levels(integrator.span, integrator.n_out, refine):
        t, X = _runs(model, Integrator(model, integrator.settings, length, samples), x, pe, t0, count)
        ts.append(t), xs.append(X)
        if len(t):
            t0, x = t[-1], X[-1]
    return np.concatenate(ts), np.concatenate(xs)


def _levels(span: float, n_out: int, refine: int) -> list[tuple[float, int, int]]:
    """(run length, output samples per run, runs) of each level of :func:`_recover`: the
    chunk's ``n_out`` output steps split by at most 20 per level (a divisor, so the
    samples stay on the output grid), then one output step in ``refine`` sub-steps."""
    levels, length, samples = [], span, n_out
    while samples > 1:
        k = max(d for d in range(1, 21) if samples % d == 0)
        k = samples if k == 1 else k            # a prime count: one step at a time
        length, samples = length / k, samples // k
        levels.append((length, samples, k))
    return levels + [(length / refine, 1, refine)]


def _runs(model, integrator, x, pe, t0, count):
    """Samples of up to ``count`` successive runs of ``integrator`` from (t0, x), up to the
    first run that fails."""
    ts, xs = [np.zeros(0)], [np.zeros((0, model.n_state))]
    grid = np.linspace(0.0, integrator.span, integrator.n_out + 1)[1:]
    for j in range(count):
        start = t0 + j * integrator.span
        try:
            X, _ = integrator.run(x, np.concatenate([pe[:-1], [start]]))
        except RuntimeError:
            break
        if first_bad(model, X.T, start + grid, pe) is not None:
            break
        x = X[:, -1]
        ts.append(start + grid), xs.append(X.T)
    return np.concatenate(ts), np.concatenate(xs)


def _u_abs_u(u):
    return u * np.abs(u)
