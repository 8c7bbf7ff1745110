"""One classified run of a scene: model, steady state, integration, outcome.

Contact-free scenes are integrated with the contact load present as a *guard*: the load
``k w1² max(0, eps − h_c)`` is exactly zero while every gap exceeds eps, and a
contact-free run stops at the first output sample where a gap reaches eps (paper,
Fig. 4), so up to that sample the trajectory is the contact-free one; between that
sample and the one before, the guard keeps the solver away from the singular flow at
``h_c = 0`` (without it CVODES grinds to a halt on a closing gap instead of stopping).
"""
from __future__ import annotations

import functools
import json
import math
import time
import warnings
from dataclasses import dataclass, replace

import numpy as np

from .breathing import PressureSchedule
from ..model.accuracy import IMPACT_QUADRATURE_TOL, adequate_model, quadrature_error
from ..model.assembly import Model, build_model
from .outcome import Criteria, Monitor, Outcome, classify
from ..scene import STRUCTURE_FIELDS, Scene
from .integrators import Settings, Trajectory, pressure_coefficient, simulate
from ..linear.stability import eigenvalues
from ..linear.steady import SteadyState, steady_state

__all__ = ["Run", "run_case", "guarded_model", "sweep_model", "sensitive_states",
           "controlled_run", "quadrature_tolerance"]


#: Samples of a trajectory at which its quadrature error is estimated, at most.
QUADRATURE_SAMPLES = 400


@dataclass(frozen=True)
class Run:
    scene: Scene
    model: Model
    steady: SteadyState
    trajectory: Trajectory
    outcome: Outcome
    wall_time: float
    #: the bound its quadrature error was controlled to (:func:`run_case`), None if not
    quadrature_tol: float | None = None

    @functools.cached_property
    def quadrature_error(self) -> float:
        """:func:`fsicas.model.accuracy.quadrature_error` over the run: at up to
        :data:`QUADRATURE_SAMPLES` samples spread over it, the last (nearest a contact or
        on the settled cycle) among them, at the steady state's parameters."""
        return quadrature_error(self.model, _spread(self.trajectory.x), self.steady.p)

    @property
    def warnings(self) -> list[str]:
        """What the run's own estimates say against its tolerances."""
        tol = self.quadrature_tol
        if tol is None or not self.quadrature_error > tol:
            return []
        return [f"quadrature error {self.quadrature_error:.2g} on {self.model.scene.n_quad} "
                f"nodes exceeds its tolerance {tol:.2g}: raise quad_nodes"]

    @property
    def status(self) -> str:
        """The trajectory's status, or "unconverged" for a successful trajectory whose
        error estimate exceeds its tolerance (:attr:`warnings`)."""
        status = self.trajectory.status
        return "unconverged" if status == "success" and self.warnings else status

    def to_json(self) -> dict:
        """The ``fsicas simulate --json`` object (keys in docs/simulate.md)."""
        o, tr = self.outcome, self.trajectory
        out = {k: o.to_json()[k] for k in ("outcome", "period", "omega", "tip_amplitude", "contact",
                                            "first_contact_time", "contact_positions",
                                            "max_impact_force", "mean_flow_reduction")}
        out.update(steps=tr.steps, wall_time=self.wall_time, status=self.status, message=tr.message,
                   t_end_reached=float(tr.t[-1]), convergence=o.convergence,
                   settled=o.settled, impacts_per_cycle=o.impacts_per_cycle,
                   first_contact_position=o.first_contact_position,
                   quadrature_error=self.quadrature_error, quadrature_nodes=self.model.scene.n_quad,
                   quadrature_tol=self.quadrature_tol, warnings=self.warnings)
        return out


def guarded_model(scene: Scene) -> tuple[Model, bool]:
    """The model to integrate ``scene`` with, and whether runs stop on contact."""
    if scene.contact:
        return build_model(scene), False
    return build_model(scene.replace(contact=True)), True


#: The models of this process by structure (:func:`sweep_model`).
_SWEEP_MODELS: dict = {}


def sweep_model(scene: Scene, guarded: bool = True) -> Model:
    """The model of ``scene``'s structure (``guarded``: :func:`guarded_model`'s), built
    once per process: the points of a sweep on a worker differ in parameters only, as a
    rule, and reuse it."""
    fields = {k: v for k, v in scene.to_dict().items() if k in STRUCTURE_FIELDS}
    key = (json.dumps(fields, sort_keys=True, default=str), guarded)
    if key not in _SWEEP_MODELS:
        _SWEEP_MODELS[key] = guarded_model(scene)[0] if guarded else build_model(scene)
    return _SWEEP_MODELS[key]


def run_case(scene: Scene, t_end: float, *, settings: Settings = Settings(),
             criteria: Criteria = Criteria(), schedule: PressureSchedule | None = None,
             perturbation=1e-2, model: Model | None = None, stop_early: bool = True,
             quadrature_tol: float | str | None = "auto", repeat: bool = True,
             progress: bool = False) -> Run:
    """Integrate ``scene`` from its perturbed steady state and classify the run.

    ``model``: a prebuilt model (e.g. from :func:`guarded_model`) reused across a sweep.
    ``stop_early``: stop as soon as the outcome is decided (else run to ``t_end``).
    ``quadrature_tol``: when the outcome depends on the flow quadrature
    (:func:`sensitive_states`) and its error there exceeds this, the run is repeated on
    the model with enough nodes (:func:`fsicas.model.accuracy.adequate_model`), up to
    :data:`MAX_REPEATS` times; "auto": :data:`QUADRATURE_PER_SETTLING` times the
    settling tolerance of ``criteria`` at ``settings.rtol`` (1e-5 at rtol 1e-8: a cycle's
    amplitude moved by 0.04 to 0.23 times the equations' relative error, so the
    quadrature stays 4x below what the cycle is settled to), and for a scene with the
    contact law :data:`fsicas.model.accuracy.IMPACT_QUADRATURE_TOL`; None: never.
    ``repeat=False``: measure the error and judge it (status "unconverged" and a warning
    above the tolerance) without repeating the run. ``progress``: a bar of the integrated
    time.
    """
    if not (isinstance(t_end, (int, float)) and np.isfinite(t_end) and t_end > 0):
        raise ValueError(f"t_end must be a finite number > 0, got {t_end!r}")
    quadrature_tol = quadrature_tolerance(quadrature_tol, criteria, settings.rtol, scene.contact)
    start = time.perf_counter()
    stop_on_contact = not scene.contact
    if model is None:
        model, stop_on_contact = guarded_model(scene)
    if criteria.stop_on_contact is None:
        criteria = _with_stop(criteria, stop_on_contact)
    once = functools.partial(_run_once, t_end=t_end, settings=settings, criteria=criteria,
                             schedule=schedule, perturbation=perturbation, stop_early=stop_early,
                             progress=progress)
    run = once(scene, model)
    run = controlled_run(run, once, quadrature_tol, repeat)
    return replace(run, wall_time=time.perf_counter() - start)


def controlled_run(run: Run, once, tol: float | None, repeat: bool = True) -> Run:
    """``run``, repeated by ``once(scene, model)`` on the adequate model while its
    :func:`sensitive_states` need more nodes for ``tol`` (at most :data:`MAX_REPEATS`
    times; not with ``repeat=False``), with ``quadrature_tol = tol``; its
    :attr:`Run.warnings` issued."""
    run = _repeated(run, once, tol) if repeat else replace(run, quadrature_tol=tol)
    for message in run.warnings:
        warnings.warn(message, RuntimeWarning, stacklevel=3)
    return run


def _repeated(run: Run, once, tol: float | None) -> Run:
    """:func:`controlled_run`'s repeats."""
    for _ in range(MAX_REPEATS if tol is not None else 0):
        states = sensitive_states(run)
        if states is None:
            break
        finer = adequate_model(run.model, states, run.steady.p, tol)[0]
        if finer is run.model:
            return replace(run, quadrature_tol=tol)
        run = replace(once(run.scene.replace(quad_nodes=finer.scene.n_quad), finer),
                      quadrature_tol=tol)
    return run


#: Repeats of a run on finer quadrature at most (:func:`run_case`).
MAX_REPEATS = 3
#: The automatic quadrature tolerance of a run per unit of its settling tolerance.
QUADRATURE_PER_SETTLING = 1.0


def quadrature_tolerance(value, criteria: Criteria, rtol: float, contact: bool) -> float | None:
    """``run_case``'s ``quadrature_tol`` as a number or None (ValueError if invalid)."""
    if value == "auto":
        return IMPACT_QUADRATURE_TOL if contact else QUADRATURE_PER_SETTLING * criteria.settling_tol(rtol)
    if value is not None and not (isinstance(value, (int, float)) and 0 < value < 1):
        raise ValueError(f"quadrature_tol must lie in (0, 1), or be 'auto' or None, got {value!r}")
    return value


def sensitive_states(run: Run) -> np.ndarray | None:
    """The samples (at most :data:`QUADRATURE_SAMPLES`) on which the outcome of a run
    depends on the quadrature, or None. A contact-free limit cycle or unsettled run,
    whose amplitude near a wall moves with the rule (1.5e-6 at 40 eps on the default
    nodes, M* = 3); and every run with the contact law on that did not decay: at 40
    nodes an impacting run's equations were 1.9e-2 off, its period 1.5e-5 and its peak
    force 2.5e-4 (80 nodes: 6.8e-5, 5.3e-8, 6.5e-6; docs/simulate.md). A contact-free run stopped by contact is
    not repeated: the estimate grows without bound as the gap closes to eps (a graze
    needed 1280 nodes for 1e-8, 15x the run's cost), so it is reported; nor is a failed
    run."""
    kind = run.outcome.outcome
    if kind == "decay" or (not run.scene.contact and kind not in ("lco", "unsettled")) \
            or run.trajectory.status != "success":
        return None
    return _spread(run.trajectory.x)


def _spread(x: np.ndarray) -> np.ndarray:
    """At most :data:`QUADRATURE_SAMPLES` rows of ``x`` spread over it, the last among them,
    and the two samples around each of the first :data:`QUADRATURE_SAMPLES` reversals of a
    channel's inlet flow (a breath through zero flow): there the flow reverses inside the
    channel, u|u| is only C^1 and the flow integrals converge slowest (docs/model.md)."""
    spread = np.linspace(0, len(x) - 1, min(len(x), QUADRATURE_SAMPLES)).astype(int)
    flips = np.flatnonzero(np.any(np.diff(np.sign(x[:, -2:]), axis=0) != 0, axis=1))
    flips = flips[:QUADRATURE_SAMPLES]
    return x[np.unique(np.r_[spread, flips, flips + 1])]


def _run_once(scene: Scene, model: Model, *, t_end: float, settings: Settings,
              criteria: Criteria, schedule, perturbation, stop_early: bool, progress: bool) -> Run:
    """One run of ``scene`` on ``model`` (:func:`run_case`)."""
    start = time.perf_counter()
    steady = steady_state(_steady_scene(scene, schedule), model)
    settings = sampled_settings(model, steady, settings)
    monitor = None
    if stop_early or criteria.stop_on_contact:
        monitor = Monitor(model, steady, criteria, rtol=settings.rtol, contact_only=not stop_early,
                          pressure=_pressure(model, steady, schedule))
    traj = simulate(model, steady, t_end, settings=settings, schedule=schedule,
                    perturbation=perturbation, monitor=monitor, progress=progress)
    if criteria.stop_on_contact and traj.gap_closed:
        traj = replace(traj, status="success", stop_reason="contact", message=(
            "contact reached: a gap went below eps and then closed (the contact-free flow is "
            "singular at h_c = 0); the samples before are refined to dt_out/50, on which the "
            "contact time is located"))
    decided = monitor is not None and monitor.outcome is not None and traj.stop_reason == monitor.outcome.outcome
    outcome = monitor.outcome if decided else classify(traj, steady, criteria)
    return Run(scene, model, steady, traj, outcome, time.perf_counter() - start)


#: Output samples per period of the leading oscillation of the steady state at least
#: (the classification reads periods and amplitudes off the samples), with ``dt_out``
#: refined at most :data:`MAX_REFINEMENT` times.
SAMPLES_PER_PERIOD, MAX_REFINEMENT = 200, 10


def sampled_settings(model: Model, steady, settings: Settings) -> Settings:
    """``settings`` with ``dt_out`` at most ``T / SAMPLES_PER_PERIOD``, T = 2π / Im λ of
    the oscillatory eigenvalue of largest real part at the steady state (not below
    ``settings.dt_out / MAX_REFINEMENT``), dividing a chunk into a multiple of 20 steps
    (the failure recovery of the integrator splits by 20). With a fixed output step a
    period at M* = 10 had 16 samples and never settled."""
    lam = eigenvalues(model, steady)
    oscillating = lam[np.abs(lam.imag) > 1e-9]
    if not oscillating.size:
        return settings
    lead = oscillating[np.argmax(oscillating.real)]
    dt = max(2 * np.pi / abs(lead.imag) / SAMPLES_PER_PERIOD, settings.dt_out / MAX_REFINEMENT)
    if settings.dt_out <= dt:
        return settings
    steps = 20 * math.ceil(settings.chunk / dt / 20)   # a chunk in a multiple of 20 steps
    return replace(settings, dt_out=settings.chunk / steps)


def _pressure(model: Model, steady, schedule: PressureSchedule | None):
    """``Δp(t)`` of a scheduled run (None for a constant one)."""
    if schedule is None or schedule.kind == "constant":
        return None
    coefficient = pressure_coefficient(model, steady, schedule)
    return lambda t: coefficient * schedule.ustar_at(t) * np.abs(schedule.ustar_at(t))


def _with_stop(criteria: Criteria, stop: bool) -> Criteria:
    return replace(criteria, stop_on_contact=stop)


def _steady_scene(scene: Scene, schedule: PressureSchedule | None) -> Scene:
    """The scene at the schedule's reference U* (the steady state the run starts from)."""
    if schedule is None or schedule.kind == "constant":
        return scene if schedule is None else scene.replace(ustar=schedule.ustar)
    return scene.replace(ustar=schedule.reference_ustar)
