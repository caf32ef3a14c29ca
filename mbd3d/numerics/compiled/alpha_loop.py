"""Generalized-alpha's step loop, compiled, for the models whose steps need nothing from Python:
no rigid contacts (their impacts are events) or contacts held at rest, no spatial gear
meshes, no joint friction, no force element given as a Python function or whose tangent is
not compiled (:mod:`.force_tangents`), and a dense or banded iteration matrix. The compliant
contacts' and stops' step rules (:mod:`~.compiled.contact_steps`) run in it.
:mod:`mbd3d.analyses.implicit` drives it and takes the other models' steps itself; the step
is the same (:func:`.generalized_alpha.newton_step`).

A call takes accepted steps until the output time, a budget of steps, or something Python
must do: a step whose Newton iteration fails with an iterate that is not finite or with the
step already at its floor (Python names what cannot be evaluated or why no step converges;
other failures are retried at a quarter of the step here, as Python would), a body that
turned too far in a step (Python warns), a chart to re-reference or a contact that touched
or released (Python restarts the recursion from consistent accelerations). Every accepted
step's end time, positions and singular-position indicator are recorded for
:class:`~mbd3d.analyses.passages.PassageWatch`.
"""

from __future__ import annotations

import math

import numpy as np

from mbd3d.numerics.compiled import jit
from mbd3d.numerics.compiled.contact_steps import accept, retry, step_limit, trapezoid_step
from mbd3d.numerics.compiled.dense import lu_factor
from mbd3d.numerics.compiled.force_tangents import force_tangent_into, has_tangent
from mbd3d.numerics.compiled.generalized_alpha import (CONVERGED, NOT_FINITE,
                                                       log_abs_determinant, newton_step)

#: why :func:`alpha_steps` returned: the output time reached, the budget of steps spent, a
#: step that did not converge (not taken: the state is the last accepted one), a body that
#: turned more than the limit in the last step, a chart to reset
REACHED, PAUSED, NOT_CONVERGED, TURNED, CHARTS = 0, 1, 2, 3, 4


@jit
def _log_abs_det_blocks(blocks) -> float:
    """``sum log |det B|`` over the mass blocks ``B`` (as NumPy's ``slogdet``)."""
    total = 0.0
    for b in range(blocks.shape[0]):
        lu = blocks[b].copy()
        lu_factor(lu, 0.0)
        for k in range(lu.shape[0]):
            size = abs(lu[k, k])
            total += math.log(size) if size > 0.0 else -np.inf
    return total


@jit
def _largest_turn(q, q_old, nb, nc, dim) -> float:
    """The largest change of a body's rotation coordinates in a step [rad] (a Rodrigues
    parameter changes by about half the angle)."""
    largest = 0.0
    for b in range(nb):
        for k in range(b * nc + dim, (b + 1) * nc):
            largest = max(largest, abs(q[k] - q_old[k]) * (2.0 if dim == 3 else 1.0))
    return largest


@jit
def _charts_due(q, nb, limit) -> bool:
    """Whether a body's Rodrigues parameters passed the chart limit (as the body type's
    ``reset_charts`` tests)."""
    for b in range(nb):
        o = 6 * b
        if q[o + 3] ** 2 + q[o + 4] ** 2 + q[o + 5] ** 2 > limit * limit:
            return True
    return False


@jit
def trial_step(t, h, t_end) -> float:
    """The step [s] from ``t`` towards the run's end ``t_end``: ``h``, or what lands on the
    end (past it or within rounding of it), or half the way there instead of a step and a
    sliver (under a twentieth of ``h``)."""
    if t_end - (t + h) < 1e-9 * max(h, 1e-300):
        return t_end - t
    if t_end - (t + h) < 0.05 * h:
        return 0.5 * (t_end - t)
    return h


@jit
def predict_into(coefficients, h, q, qd, qdd, a, shift, q_hat, qd_hat, trial) -> tuple:
    """The step ``h`` from ``(q, qd, qdd, a)``: ``shift = (alpha_f qdd - alpha_m a) / (1 -
    alpha_m)``, the parts ``q_hat``, ``qd_hat`` of the new positions and rates that do not
    depend on the new accelerations, and Newton's first guess ``trial`` (the accelerations
    unchanged); returns ``(beta', gamma')`` (see :mod:`mbd3d.analyses.implicit`).
    ``coefficients``: ``(alpha_m, alpha_f, beta, gamma)``."""
    am, af, beta, gamma = coefficients
    for i in range(q.shape[0]):
        shift[i] = (af * qdd[i] - am * a[i]) / (1.0 - am)
        q_hat[i] = (q[i] + h * qd[i] + h * h * (0.5 - beta) * a[i]
                    + h * h * beta * shift[i])
        qd_hat[i] = qd[i] + h * (1.0 - gamma) * a[i] + h * gamma * shift[i]
    beta_prime = (1.0 - am) / (h * h * beta * (1.0 - af))
    gamma_prime = gamma / (h * beta)
    for i in range(q.shape[0]):
        trial[i] = q_hat[i] + qdd[i] / beta_prime
    return beta_prime, gamma_prime


@jit
def rate_into(gamma_prime, q, q_hat, qd_hat, qd) -> None:
    """The rates ``qd = qd_hat + gamma' (q - q_hat)`` at the step's positions ``q`` (the
    quantities of :func:`predict_into`)."""
    for i in range(q.shape[0]):
        qd[i] = qd_hat[i] + gamma_prime * (q[i] - q_hat[i])


@jit
def rates_into(coefficients, beta_prime, gamma_prime, q, q_hat, qd_hat, shift, qd, qdd,
               a) -> None:
    """The step's new rates ``qd``, accelerations ``qdd`` and ``a`` from its new positions
    ``q`` (the quantities of :func:`predict_into`)."""
    am, af = coefficients[0], coefficients[1]
    rate_into(gamma_prime, q, q_hat, qd_hat, qd)
    for i in range(q.shape[0]):
        qdd[i] = beta_prime * (q[i] - q_hat[i])
        a[i] = shift[i] + (1.0 - af) / (1.0 - am) * qdd[i]


@jit
def alpha_steps(work, penalty_arrays, key, coefficients, settings, times, t_target, h, q, qd,
                qdd, a, lam, charts, penalty, lam_effective, matrix, band, piv, counters,
                q_old, qd_old, out_t, out_indicator, out_q, contact):
    """Accepted steps from ``(times[0], q, qd, qdd, a, lam)`` (updated in place) towards
    ``t_target``, at most ``out_t.shape[0]`` of them.

    ``coefficients``: ``(alpha_m, alpha_f, beta, gamma)``. ``settings``: ``(step, max_step,
    relative_penalty, newton_tol, projection_tol, max_iterations, chart_limit, largest_turn,
    check_turns, steps_before, turn_sample)``. ``times``: ``(t, t_end)`` [s]. ``h``: the next
    step [s]. ``charts``: None for a planar model. ``counters``: Newton iterations,
    factorizations and rejected steps (a step handed back is not counted: Python takes it
    again).
    ``q_old``, ``qd_old``: the last accepted step's start. ``out_t``, ``out_indicator``,
    ``out_q``: per accepted step its end (before it is snapped to ``t_target``), its
    indicator and positions. ``contact``: the compliant contacts' and stops' rules
    ``(state, clock)`` (:mod:`~.compiled.contact_steps`, no columns without contacts), their
    dissipated energies and the last step's times (:func:`.contact_steps.trapezoid_step`) and
    the rows' powers there.

    Returns ``(status, t, t_old, h, h_last, smallest, taken, t_step, turn, switched)``: why
    it returned (see the constants), the time reached, the last step's start, the next
    step, the last step, the shortest step, the steps taken, the last step's end before
    snapping, its largest turn [rad] (where it was checked), and whether a contact row
    touched or released in it (it returns after such a step: Python starts the recursion
    again from consistent accelerations).
    """
    (step, max_step, relative_penalty, newton_tol, projection_tol, max_iterations,
     chart_limit, largest_turn, check_turns, steps_before, turn_sample) = settings
    state, clock, dissipated, dissipated_times, power = contact
    rows = state.shape[1]
    t, t_end = times[0], times[1]
    n = q.shape[0]
    nb, nc, dim = work.blocks.shape[0], work.blocks.shape[1], 3 if charts is not None else 2
    # the force elements' tangent (see .force_tangents), in the iteration matrix's storage
    tangent = has_tangent(work)
    extra = np.zeros((matrix.size + band.size) if tangent else 0)
    q_hat, qd_hat, trial, shift = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    rate = np.empty(n)
    lam_try = np.empty(lam.shape[0])
    t_old, h_last, smallest, t_step, turn = t, 0.0, np.inf, t, 0.0
    taken = 0
    # python_factor as a run-time False: a literal one compiled newton_step once more for
    # each type, beside the type Python calls it with (see accelerations_into)
    python_factor = n < 0
    while taken < out_t.shape[0]:
        h_try = trial_step(t, min(h, step_limit(state, t)), t_end)
        beta_prime, gamma_prime = predict_into(coefficients, h_try, q, qd, qdd, a, shift,
                                               q_hat, qd_hat, trial)
        if tangent:  # at the predictor, as the Python step
            rate_into(gamma_prime, trial, q_hat, qd_hat, rate)
            force_tangent_into(work, penalty_arrays, t + h_try, trial, rate, charts,
                               gamma_prime, extra)
        lam_try[:] = lam
        iterations, factorizations = counters[0], counters[1]
        outcome = newton_step(work, penalty_arrays, key, t + h_try, trial, q_hat, qd_hat,
                              beta_prime, gamma_prime, lam_try, charts, extra,
                              python_factor, relative_penalty, newton_tol, projection_tol,
                              max_iterations, penalty, lam_effective, matrix, band, piv,
                              counters)
        if outcome != CONVERGED:
            if outcome == NOT_FINITE or 0.25 * h_try < 1e-14 * max(1.0, abs(t)):
                # Python names what cannot be evaluated, or why no step converges
                counters[0], counters[1] = iterations, factorizations
                return NOT_CONVERGED, t, t_old, h, h_last, smallest, taken, t_step, turn, False
            counters[2] += 1  # a rejected step: a quarter of it next (see the Python loop)
            h = 0.25 * h_try
            continue
        if rows > 0:  # across a touch or a release: end there (see .contact_steps)
            rate_into(gamma_prime, trial, q_hat, qd_hat, rate)
            shorter = retry(work, state, clock, h_try, trial, rate, charts)
            if shorter > 0.0:
                h = shorter
                continue
        q_old[:] = q
        qd_old[:] = qd
        t_old, h_last, smallest = t, h_try, min(smallest, h_try)
        q[:] = trial
        rates_into(coefficients, beta_prime, gamma_prime, q, q_hat, qd_hat, shift, qd, qdd, a)
        lam[:] = lam_effective
        t += h_try
        t_step = t
        switched = False
        if rows > 0:
            switched = accept(work, state, clock, t, q, qd, charts, power)
            trapezoid_step(dissipated, dissipated_times, t, power)
        out_t[taken], out_q[taken] = t, q
        out_indicator[taken] = (log_abs_determinant(penalty_arrays, matrix, band)
                                - nb * nc * math.log(beta_prime)
                                - _log_abs_det_blocks(work.blocks))
        taken += 1
        steps = steps_before + taken
        status = PAUSED
        if check_turns and (steps <= turn_sample or steps % turn_sample == 0):
            turn = _largest_turn(q, q_old, nb, nc, dim)
            if turn > largest_turn:
                status = TURNED
        # back to the nominal step after a recovery, doubling (see the Python loop)
        h = min(step, max_step, 2.0 * h)
        if abs(t - t_target) <= 1e-12 * max(1.0, abs(t_target)):
            t = t_target
        if t >= t_target and status == PAUSED:
            status = REACHED
        elif charts is not None and status == PAUSED and _charts_due(q, nb, chart_limit):
            status = CHARTS
        if status != PAUSED or switched or taken == out_t.shape[0]:
            return status, t, t_old, h, h_last, smallest, taken, t_step, turn, switched
    return PAUSED, t, t_old, h, h_last, smallest, taken, t_step, turn, False
