"""Generalized-alpha's step rules at compliant contacts and joint stops, compiled: the same
kernels serve the steps taken from Python (:mod:`mbd3d.analyses.contact_steps`) and those of
the compiled loop (:mod:`.alpha_loop`), so that a contact's steps never need Python between a
touch and a release.

A fixed step longer than a contact lasts steps over most of an impact and returns a wrong
rebound (a ball on a stiff floor, dropped 0.4 m, left at 2.8 m with steps of 10 ms, marked
complete). Each row of the model's contacts and stops has the period of the law's
oscillation in the impact it has or is heading for, ``T`` (at its stiffest, from the closing
speed: :func:`impact_period`), and three rules resolve an impact while leaving the step
alone elsewhere:

- a row heading for a touch limits the step to end just past it, by :data:`BAND` of an
  impact's step ``T /`` :data:`PER_PERIOD` (when its gap closes at its rate and the rate's
  own rate over the last step, :func:`touch_in`): a stiff contact entered deeper than that
  within one implicit step would store energy no step took out;
- a step that touches neither that little past its end nor with a step of ``T /``
  :data:`PER_PERIOD` or less is retried at half the length (an implicit step's end holds the
  contact force already, so it cannot say where the touch was; at most :data:`TRIES`
  times, :func:`retry`);
- while an impact lasts, no step is longer than ``T /`` :data:`PER_PERIOD`; a contact that
  stays closed longer than :data:`IMPACT_PERIODS` periods is resting, and the nominal step
  comes back (the method's damping of high frequencies keeps it stable; :func:`step_limit`).

After a step in which a row touched or released (:func:`accept` says so), the recursion
starts again from consistent accelerations (as after an event): the force jumped inside that
step, and the method's algorithmic accelerations would carry the jump into the next, long
step.

The rules' memory is an array ``state`` (:data:`STATE_ROWS` rows, a column per contact row):
its switching function at the last accepted step's end (``BEFORE``, positive while its law
pushes) and at the step tried (``AFTER``), the time of its touch, its impact period, gap
[m or rad], gap rate and the rate's rate, whether it was apart at the last step's start,
the mass its law is calibrated with (a stop: the moment of inertia) and whether it is rigid
(1: no law, its impacts are events); and ``clock``: the time the gaps were measured at (nan:
none to follow), the retries of the step under way and of the run.
"""

from __future__ import annotations

import math

import numpy as np

from mbd3d.numerics.compiled import jit
from mbd3d.numerics.compiled.accelerations import frames_into
from mbd3d.numerics.compiled.contact_groups import all_contact_forces_into
from mbd3d.numerics.compiled.contacts import (DISSIPATION, GAP, GAP_RATE, GROUP,
                                              REPORT_COLUMNS, switches_into)
from mbd3d.numerics.compiled.integration import first_switch

__all__ = ["PER_PERIOD", "IMPACT_PERIODS", "BAND", "TRIES", "STATE_ROWS", "impact_period",
           "touch_in", "step_limit", "start", "restart", "retry", "accept", "trapezoid_step"]

#: steps per period of an impact's oscillation; how many periods an impact lasts at most
PER_PERIOD, IMPACT_PERIODS = 100, 3
#: a touch lies within BAND of an impact step before its step's end, or its step is an
#: impact step (at most TRIES retries)
BAND, TRIES = 1e-3, 12
#: the rows of ``state`` (see the module's text)
BEFORE, AFTER, TOUCH, PERIOD, GAP_NOW, RATE_NOW, RATE_RATE, WAS_APART, MASS, RIGID = range(10)
#: the number of rows of ``state``
STATE_ROWS = 10
#: the entries of ``clock``
MEASURED, STEP_TRIES, RETRIES = 0, 1, 2


@jit
def impact_period(values, state, k: int, gap: float, gap_rate: float) -> float:
    """The period [s] of row ``k``'s law's oscillation ``2 pi sqrt(m* / k)`` at its stiffest
    in the impact at ``(gap, gap_rate)``: ``k = n K delta^(n - 1)`` at the deeper of the
    penetration now and the one the closing speed reaches against the law's spring, ``((n +
    1) m* v^2 / (2 K))^(1 / (n + 1))`` (damping only shortens it). A rigid row has no
    oscillation, and a group's impacts are not followed (see
    :mod:`~.compiled.contact_groups`): inf."""
    if state[RIGID, k] != 0.0 or values[k, 0] == GROUP:
        return np.inf
    K, n, m = values[k, 3], values[k, 4], state[MASS, k]
    closing = max(-gap_rate, 0.0)
    deepest = ((n + 1.0) * m * closing ** 2 / (2.0 * K)) ** (1.0 / (n + 1.0))
    delta = max(max(-gap, deepest), 1e-300)
    return 2.0 * math.pi * math.sqrt(m / (n * K * delta ** (n - 1.0)))


@jit
def touch_in(gap: float, rate: float, rate_rate: float) -> float:
    """When a gap closes [s] at its rate and the rate's own rate, ``gap + rate s + acc s^2 /
    2 = 0`` with the gap clipped at zero (inf: it does not close; a group's gap is inf)."""
    gap = max(gap, 0.0)
    root = rate * rate - 2.0 * rate_rate * gap
    s = 2.0 * gap / (-rate + math.sqrt(max(root, 0.0)))  # 0/0 is nan: not closing
    if root >= 0.0 and s >= 0.0 and math.isfinite(s):
        return s
    return np.inf


@jit
def step_limit(state, t: float) -> float:
    """The longest step [s] the rows allow at ``t`` (inf: none): an impact's step while a
    closed row's impact lasts, else just past the touch a row heads for, by a little of an
    impact's step."""
    limit = np.inf
    for k in range(state.shape[1]):
        period = state[PERIOD, k]
        if state[BEFORE, k] > 0.0:
            if t - state[TOUCH, k] < IMPACT_PERIODS * period:
                limit = min(limit, period / PER_PERIOD)
        else:
            reach = (touch_in(state[GAP_NOW, k], state[RATE_NOW, k], state[RATE_RATE, k])
                     + 0.5 * BAND * period / PER_PERIOD)
            limit = min(limit, reach)
    return limit


@jit
def _switches_at(contacts, work, q, qd, charts, out) -> None:
    # None (no contacts) is decided as the kernel is compiled: see structures.ContactArrays
    if contacts is not None:
        frames_into(work, q, qd, charts)
        switches_into(work.A, work.omega, work.Q, work.Qd, contacts.bodies, contacts.points,
                      contacts.values, contacts.curves, out)


@jit
def _report_into(contacts, work, report) -> int:
    """The contacts' report at ``work``'s frames into ``report``; -1, or the first row whose
    normal is undefined."""
    if contacts is not None:
        return all_contact_forces_into(
            work.A, work.axes, work.omega, work.Q, work.Qd, contacts.bodies, contacts.points,
            contacts.values, contacts.curves, (contacts.shape_bodies, contacts.shape_points,
                                               contacts.shape_values, contacts.pair_laws),
            np.zeros(work.Q.shape), report, np.zeros(0))
    return -1


@jit
def _values(contacts):
    if contacts is not None:
        return contacts.values
    return np.zeros((0, 1))


@jit
def _measure(work, state, clock, t, q, qd, charts, power, follow: bool) -> int:
    """Gaps and rates at ``(q, qd)`` at ``t``, the power each row dissipates there [W] into
    ``power``, and the rates' rates over the last step where ``follow`` and the rows were
    apart at its start too (else 0); the rows apart get the period of the impact their
    closing speed heads for, and no touch. Returns -1, or the first row whose normal is
    undefined."""
    rows = state.shape[1]
    if rows == 0:
        return -1
    contacts = work.model.forces.contacts
    frames_into(work, q, qd, charts)
    report = np.zeros((rows, REPORT_COLUMNS))
    failed = _report_into(contacts, work, report)
    values = _values(contacts)
    since = clock[MEASURED]
    follow = follow and since == since and t > since
    for k in range(rows):
        rate = report[k, GAP_RATE]
        apart = not state[BEFORE, k] > 0.0
        state[RATE_RATE, k] = 0.0
        if follow and apart and state[WAS_APART, k] != 0.0:
            state[RATE_RATE, k] = (rate - state[RATE_NOW, k]) / (t - since)
        state[GAP_NOW, k], state[RATE_NOW, k] = report[k, GAP], rate
        power[k] = report[k, DISSIPATION]
        if apart:
            state[PERIOD, k] = impact_period(values, state, k, 0.0, rate)
            state[TOUCH, k] = -np.inf
    clock[MEASURED] = t
    return failed


@jit
def restart(work, state, clock, t, q, qd, charts, power) -> int:
    """Go on from ``(q, qd)`` at ``t`` (an event's new state, or new charts): the rows
    measured there, the impacts of the rows still closed going on. Returns as
    :func:`_measure`."""
    if state.shape[1] == 0:
        return -1
    _switches_at(work.model.forces.contacts, work, q, qd, charts, state[BEFORE])
    clock[MEASURED] = np.nan
    return _measure(work, state, clock, t, q, qd, charts, power, False)


@jit
def start(work, state, clock, t, q, qd, charts, power) -> int:
    """Begin at ``(q, qd)`` at ``t``, no impact under way (see :func:`restart`)."""
    state[TOUCH], state[PERIOD] = -np.inf, np.inf
    clock[STEP_TRIES] = 0.0
    return restart(work, state, clock, t, q, qd, charts, power)


@jit
def retry(work, state, clock, h, q, qd, charts) -> float:
    """Half the step ``h`` that reached ``(q, qd)`` when it touched neither within
    :data:`BAND` of an impact step ``T /`` :data:`PER_PERIOD` before its end nor with a
    step that short, or 0: accept it (its rows' switching functions are kept for
    :func:`accept`)."""
    rows = state.shape[1]
    if rows == 0:
        return 0.0
    _switches_at(work.model.forces.contacts, work, q, qd, charts, state[AFTER])
    touched, shortest = False, np.inf  # the impact period of the rows that touched
    for k in range(rows):
        if not state[BEFORE, k] > 0.0 and state[AFTER, k] > 0.0:
            touched, shortest = True, min(shortest, state[PERIOD, k])
    if not touched or clock[STEP_TRIES] >= TRIES:
        return 0.0
    impact_step = shortest / PER_PERIOD
    past = (1.0 - first_switch(state[BEFORE], state[AFTER], 0.0)) * h  # how long it overlapped
    if past <= BAND * impact_step or h <= impact_step:
        return 0.0
    clock[STEP_TRIES] += 1.0
    clock[RETRIES] += 1.0
    return 0.5 * h


@jit
def accept(work, state, clock, t, q, qd, charts, power) -> bool:
    """The step :func:`retry` accepted ended at ``(q, qd)`` at ``t``: the rows that closed
    begin an impact (its period from the closing speed before the touch), those open are
    measured again (and ``power`` filled). Whether a row touched or released in the step:
    the force jumped in it, and the method's recursion should start again there."""
    switched = False
    for k in range(state.shape[1]):
        was_apart, pushes = not state[BEFORE, k] > 0.0, state[AFTER, k] > 0.0
        switched = switched or pushes == was_apart
        if pushes and was_apart:
            state[TOUCH, k] = t
        state[WAS_APART, k] = 1.0 if was_apart else 0.0
        state[BEFORE, k] = state[AFTER, k]
    clock[STEP_TRIES] = 0.0
    _measure(work, state, clock, t, q, qd, charts, power, True)
    return switched


@jit
def trapezoid_step(z, times, t: float, power) -> None:
    """The contacts' dissipated energies over the step from ``times[1]`` to ``t`` by the
    trapezoidal rule (second order, as generalized-alpha), ``power`` [W] the rows' at its end:
    ``z``'s rows are the energies at the step's end and start and the powers there (see
    :func:`mbd3d.analyses.dissipation.hermite`); ``times`` becomes the step's ``(start,
    end)``."""
    for k in range(z.shape[1]):
        z[1, k], z[3, k] = z[0, k], z[2, k]
        z[2, k] = power[k]
        z[0, k] = z[1, k] + 0.5 * (t - times[1]) * (z[2, k] + z[3, k])
    times[0], times[1] = times[1], t
