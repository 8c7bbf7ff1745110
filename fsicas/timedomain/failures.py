"""Why a time integration failed, in words: a solver error or a bad sample (not finite,
or a gap that closed), and for a gap that closed with the contact law on, how: one step
across the whole contact layer (no stiffness acts in time) or a law too soft to stop
the beam inside it."""
from __future__ import annotations

import numpy as np

from ..model.contact import gaps, law
from ..model.patch import penetration

__all__ = ["solver_message", "first_bad", "closing"]


def solver_message(err: Exception, t0: float, model, x_last, p) -> str:
    """Why the solver failed, in words; a failed right-hand side is a gap that closed,
    and :func:`closing` says how (``x_last``: the last good state; ``p``: the run's
    parameters)."""
    text = str(err).strip().splitlines()
    if any("RHSFUNC_FAIL" in line or "RES_FAIL" in line for line in text):
        return (f"a gap closed (h_c <= 0) after t = {t0:.6g}: the flow model is "
                f"singular there; {closing(model, x_last, p)}")
    key = [line for line in text if "CV_" in line or "IDA_" in line or "solve_ivp" in line]
    return f"the time integration failed after t = {t0:.6g}: " + (key[-1] if key else text[-1] if text else repr(err))


def first_bad(model, X, times, p) -> tuple[int, str] | None:
    """(index of the first bad sample, message) if a sample is not finite or a gap closed
    (``times``: the samples' times; ``p``: the run's parameters)."""
    finite = np.all(np.isfinite(X), axis=1)
    if not finite.all():
        k = int(np.argmin(finite))
        return k, f"the state is not finite at t = {times[k]:.6g}"
    h = gaps(model, X)
    if h.min() <= 0:
        k = int(np.argmax(h.min(axis=(1, 2)) <= 0))
        last = X[k - 1] if k > 0 else None
        return k, (f"a gap closed (h_c = {h.min():.3g} <= 0) at t = {times[k]:.6g}: the "
                   f"flow model is singular there; {closing(model, last, p)}")
    return None


def closing(model, x_last, p) -> str:
    """How the gap closed, from the last good state: with the contact law on, either one
    step crossed the whole contact layer (the last gap was wider than eps, so no
    stiffness acts in time: the layer must be thicker or the steps shorter) or the law
    did not stop the beam inside it (a stiffer law or a thicker layer). The layer's
    eps is that of the run's parameters ``p`` (a model serves many laws)."""
    if model.impact_rule is None:
        return "the beam reached the wall (turn the contact law on to hold it)"
    eps = law(model, p)[1]
    gap = -np.inf if x_last is None else gaps(model, np.atleast_2d(x_last)).min()
    if gap > eps:
        return (f"the last state before it was {gap / eps:.3g} eps from the wall, outside the "
                f"contact layer (eps = {eps:.3g}): one step crossed the whole layer, where no "
                "contact stiffness can act; make the layer thicker (contact_eps; a tighter "
                "rtol also shortens the steps)")
    return f"the impact load did not stop the beam within the contact layer ({_shortfall(model, x_last, p)})"


def _shortfall(model, x_last, p) -> str:
    """How far the law fell short, from the last state inside the layer: the energy the
    law stored there, about ``0.4 depth ∫ k max(0, eps - h)`` (0.8 d ∫ g for a parabolic
    cap of depth d), against the kinetic energy of the deepest point ``x_c`` in mode 1,
    ``v_c² / (2 φ1(x_c)²)`` (its effective mass 1/φ1², 1/4 at the tip; docs/simulate.md,
    "The paper's contact parameters"). The flow's suction comes on top, so it is an
    estimate: at M* = 1, U* = 7, eps/H = 1e-3 it asks 1.2e10 for k* = 1e8, and 1e10
    holds."""
    n = model.n_modes
    found = penetration(model, np.atleast_2d(x_last), p)
    stored = 0.4 * max(found.depth[0], 0.0) * found.load[0]
    phi = model.basis_at([found.position[0]]).phi[:, 0]
    kinetic = 0.5 * float(phi @ x_last[:n]) ** 2 / phi[0] ** 2
    if not stored < kinetic:
        return "raise contact_stiffness or contact_eps"
    factor = kinetic / stored if stored > 0 else np.inf
    return (f"when the gap closed it had stored {stored:.2g}, against the kinetic energy "
            f"{kinetic:.2g} of the beam at the wall: it needs a thicker layer (contact_eps) "
            f"or a law of the order of {factor:.2g}x stiffer (contact_stiffness; an "
            "estimate from that ratio)")
