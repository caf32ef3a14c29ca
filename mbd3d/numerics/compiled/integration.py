"""The explicit integrators' loop, compiled: steps, error control, chart resets, drift checks
and step-collapse checks run here, and control returns to Python only when a step passes an
output time, the constraints have drifted past their tolerance, the run is over, or something
failed.

The state is ``y = (q, v)``: the coordinates and the velocities the body type integrates
(:meth:`mbd3d.model.body.BodyType.velocities`: the angular velocity in body axes for spatial bodies,
which a chart reset leaves unchanged). A chart reset therefore changes ``q`` and the rates part
of the first stage ``f`` only, and the method goes on with its step: it is not restarted.

``model`` is the model as the loop takes it (a
:class:`~mbd3d.numerics.compiled.structures.ModelArrays`) and ``work`` the scratch of one evaluation
(:func:`~mbd3d.numerics.compiled.structures.workspace`).
"""

from __future__ import annotations

import numpy as np
from numba import objmode

from mbd3d.numerics.compiled import callbacks, jit, jit_calling_python
from mbd3d.numerics.compiled.accelerations import (NOT_FINITE, SOLVED, accelerations_into,
                                                   frozen_residual_into, motions_at,
                                                   padded_into, solve_again_into)
from mbd3d.numerics.compiled.bodies import (body_vectors_into, planar_frames_into,
                                            spatial_frames_into, spatial_rates_into,
                                            spatial_reset_charts, spatial_velocity_derivative_into)
from mbd3d.numerics.compiled.contacts import switches_into
from mbd3d.numerics.compiled.rows import constraint_rows_into
from mbd3d.numerics.compiled.runge_kutta import (DOP853_INTERPOLANT, dop853_coefficients,
                                                 error_norm, polynomial_coefficients, stage_state,
                                                 step_factor)
from mbd3d.numerics.compiled.structures import contact_count

#: why :func:`advance` returned (bit flags, except the failures): a step passed the output
#: time, the constraints drifted, the step collapsed, the step count to check for stiffness
#: was reached, the budget of steps per call was spent (so that Python sees interrupts and
#: draws progress)
OUTPUT, DRIFTED, COLLAPSED, CHECK_STIFFNESS, PAUSED = 1, 2, 4, 64, 128
#: failures: the step became too small for the floating-point spacing of t, a singular
#: matrix, a non-finite state
STEP_TOO_SMALL, SINGULAR, DIVERGED = 8, 16, 32
#: counters in ``stats``
STEPS, RHS_EVALUATIONS, CHART_RESETS, REJECTED = 0, 1, 2, 3
#: a trial step whose stages could not be evaluated is retried this many times shorter
_FAILED_STEP_FACTOR = 0.25
#: a step across a contact's touch or release is retried shorter until the switch lies in
#: this last fraction of it (at most _SWITCH_TRIES times), so that the kink of the contact
#: force falls between steps instead of inside one, where no error estimate sees it
_SWITCH_BAND, _SWITCH_TRIES = 1e-3, 8
#: a switching function this close to zero at both ends of a step, relative to the largest
#: coordinate (or 1), is rounding: a box's corner skimming the floor at zero penetration flips
#: its sign at 1e-17 m, and steps cut at every flip never got past it
_SWITCH_NOISE = 64.0 * np.finfo(np.float64).eps


@jit_calling_python
def _callback_parts(key, t, q, qd, charts):
    with objmode(extra="float64[::1]", drivers="float64[:, ::1]", phi="float64[:, ::1]"):
        extra, drivers, phi = callbacks.parts(key, t, q, qd, charts)
    return extra, drivers, phi


@jit_calling_python
def _callback_accelerations(key, t, q, qd, charts):
    with objmode(x="float64[::1]", status="int64"):
        x, status = callbacks.accelerations(key, t, q, qd, charts)
    return x, status


@jit_calling_python
def _callback_solve(key, values, rhs):
    with objmode(x="float64[::1]", status="int64"):
        x, status = callbacks.solve(key, values, rhs)
    return x, status


@jit
def _python_parts(model, key, t, q, qd, charts):
    """Force elements' generalized forces and the motions ``(f, f', f'')`` of the drivers and
    of the rotation drivers, from Python for a model with parts that are Python objects
    (placeholders otherwise: the compiled functions evaluate them)."""
    if model.python_parts:
        return _callback_parts(key, t, q, qd, charts)
    return model.no_forces, model.no_drivers, model.no_motions


@jit
def derivative(model, key, t, y, charts, out, work):
    """``out = dy/dt`` at ``(t, y)`` in the workspace ``work``; returns the solve's status
    (0: solved). ``charts``: the reference rotations of a spatial model's bodies, None for a
    planar model (see :func:`advance`). Solved, ``work.x`` holds ``(qdd, lam)`` (but for a
    model whose accelerations Python solves) and ``work`` the matrix for
    :func:`solve_again`."""
    n = model.n
    q = y[:n]
    qd = out[:n]
    _coordinate_rates_into(q, y[n:], qd, charts)
    extra, drivers, phi = _python_parts(model, key, t, q, qd, charts)
    if model.python_accelerations:
        x, status = _callback_accelerations(key, t, q, qd, charts)
    else:
        status = accelerations_into(model, work, t, q, qd, charts, extra, phi, drivers)
        x = work.x
        if status == SOLVED and not model.solved_here:
            x, status = _callback_solve(key, work.values, work.rhs)
            work.x[:] = x
    if status != SOLVED:
        return status
    velocity_derivative_into(q, qd, x[:n], out[n:], charts)
    return SOLVED


@jit
def frozen_derivative_into(model, key, t, y, charts, x, work, out, r) -> int:
    """``out = dy/dt`` at ``(t, y)`` with the accelerations held at ``x[:n]``, and ``r`` the
    residual of the augmented equations there with ``x = (qdd, lam)`` held
    (:func:`~mbd3d.numerics.compiled.accelerations.frozen_residual_into`): what changes of
    the right-hand side along a direction, the accelerations' change being ``K^-1 dr``
    (:func:`solve_again`); returns the status."""
    n = model.n
    q = y[:n]
    qd = out[:n]
    _coordinate_rates_into(q, y[n:], qd, charts)
    extra, drivers, phi = _python_parts(model, key, t, q, qd, charts)
    status = frozen_residual_into(model, work, t, q, qd, charts, extra, phi, drivers, x, r)
    if status != SOLVED:
        return status
    velocity_derivative_into(q, qd, x[:n], out[n:], charts)
    return SOLVED


@jit
def solve_again(model, key, work, charts, b, x) -> int:
    """``x``: the augmented equations' matrix of the last :func:`derivative` in ``work``
    solved for ``b``; returns the status."""
    if solve_again_into(model, work, charts, b, x):
        return SOLVED
    solution, status = _callback_solve(key, work.values, b)
    if status == SOLVED:
        x[:] = solution
    return status


@jit
def _coordinate_rates_into(q, v, qd, charts) -> None:
    """``qd``: the coordinates' rates from the integrated velocities ``v``."""
    if charts is not None:
        spatial_rates_into(q, v, qd)
    else:
        qd[:] = v


@jit
def velocity_derivative_into(q, qd, qdd, out, charts) -> None:
    """``out``: the integrated velocities' derivative from the accelerations ``qdd`` (affine
    in them: with ``qd = 0``, their linear part)."""
    if charts is not None:
        spatial_velocity_derivative_into(q, qd, qdd, out)
    else:
        out[:] = qdd


@jit
def drift(model, key, t, y, charts, work):
    """Largest position and velocity constraint residual at ``(t, y)``, each row relative to
    its scale (lengths in units of the model's length)."""
    m = model.n_rows
    if m == 0:
        return 0.0
    C, nu = work.C, work.nu
    constraint_residuals_into(model, key, t, y, charts, work, C, nu)
    largest = 0.0
    for r in range(m):
        largest = max(largest, abs(C[r]) / model.row_scale[r], abs(nu[r]) / model.row_scale[r])
    return largest


@jit
def constraint_residuals_into(model, key, t, y, charts, work, C, nu) -> None:
    """``C``: the position rows' residual ``C(q, t) - c0`` and ``nu``: the velocity rows'
    ``Cq qd + C_t`` at ``(t, y)`` [each row's unit]; ``C`` and ``nu`` may be ``work.C`` and
    ``work.nu``."""
    n = model.n
    m = model.n_rows
    q = y[:n]
    qd = np.empty(n)
    _coordinate_rates_into(q, y[n:], qd, charts)
    _, drivers, phi = _python_parts(model, key, t, q, qd, charts)
    if not model.python_parts:
        motions_at(model, work, t)
        drivers, phi = work.drivers, work.phi
    yes = m > 0  # run-time flags (see accelerations_into)
    no = not yes
    Q, A, axes, omega, kappa = work.Q, work.A, work.axes, work.omega, work.kappa
    s, J, v, a, data = work.s, work.J, work.v, work.a, work.data
    padded_into(q, Q)
    if charts is not None:
        spatial_frames_into(Q, Q, charts, no, A, axes, omega, kappa, work.Gb, work.omega_bar)
    else:
        planar_frames_into(Q, Q, no, A, axes, omega, kappa)
    body_vectors_into(A, axes, omega, kappa, model.vector_bodies, model.vector_local, no, s,
                      J, v, a)
    constraint_rows_into(model.code, model.bi, model.bj, model.first_row, model.slots,
                         model.coordinate, model.motion, model.real, model.curves, phi, m, Q,
                         Q, s, J, v, a, model.destination, yes, yes, no, yes, C, data, C, nu,
                         work.row_work, work.row_jacobian)
    c0, jac_rows, jac_cols = model.c0, model.jac_rows, model.jac_cols
    driver_rows = model.driver_rows
    for k in range(driver_rows.shape[0]):
        C[driver_rows[k]] -= drivers[k, 0]
        nu[driver_rows[k]] = drivers[k, 1]
    for r in range(m):
        C[r] -= c0[r]
        nu[r] = -nu[r]
    for p in range(jac_rows.shape[0]):
        nu[jac_rows[p]] += data[p] * qd[jac_cols[p]]


@jit
def switch_count(forces) -> int:
    """How many switching functions the contacts and joint stops of a model's ``forces``
    have: two each (:func:`.contacts.switches_into`)."""
    return 2 * contact_count(forces.contacts)


@jit
def _contact_switches(contacts, A, omega, Q, Qd, out) -> None:
    # None (no contacts) is decided as the kernel is compiled: see structures.ContactArrays
    if contacts is not None:
        switches_into(A, omega, Q, Qd, contacts.bodies, contacts.points, contacts.values,
                      contacts.curves, out)


@jit
def switches(model, y, charts, work, out) -> None:
    """The contacts' switching functions at ``y`` into ``out`` (see
    :func:`.contacts.switches_into`)."""
    n = model.n
    qd = np.empty(n)
    _coordinate_rates_into(y[:n], y[n:], qd, charts)
    Q, Qd, A, axes, omega, kappa = work.Q, work.Qd, work.A, work.axes, work.omega, work.kappa
    padded_into(y[:n], Q)
    padded_into(qd, Qd)
    yes = n >= 0  # a run-time flag (see accelerations_into)
    if charts is not None:
        spatial_frames_into(Q, Qd, charts, yes, A, axes, omega, kappa, work.Gb, work.omega_bar)
    else:
        planar_frames_into(Q, Qd, yes, A, axes, omega, kappa)
    _contact_switches(model.forces.contacts, A, omega, Q, Qd, out)


@jit
def first_switch(before, after, noise: float) -> float:
    """The fraction of a step at which the first switching function changes sign, by linear
    interpolation between its values at the step's ends (2: none does); a change between
    values within ``noise`` of zero is none."""
    earliest = 2.0
    for k in range(before.shape[0]):
        if ((before[k] > 0.0) != (after[k] > 0.0)
                and max(abs(before[k]), abs(after[k])) > noise):
            earliest = min(earliest, before[k] / (before[k] - after[k]))
    return earliest


@jit
def error_scale(spatial, n, y, y_new, atol, rtol):
    """What each component's local error is measured against: ``atol + rtol max(|y|,
    |y_new|)``, except for the Rodrigues parameters of spatial bodies, whose error is measured
    as the orientation error it is: ``dg = (1 + g.g) dq`` with ``dq`` the error of a unit
    quaternion's components (half the angle), so ``(atol + rtol) (1 + g.g)``, largest ``g.g``
    of the step. A chart reset then changes nothing in the norm, and a tolerance means for the
    orientation what it means for a quaternion integration (components of size one), instead
    of tightening as ``g`` passes through zero after every reset."""
    scale = np.empty(2 * n)
    for i in range(2 * n):
        scale[i] = atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol
    if spatial:
        for b in range(n // 6):
            o = 6 * b + 3
            size = max(y[o] ** 2 + y[o + 1] ** 2 + y[o + 2] ** 2,
                       y_new[o] ** 2 + y_new[o + 1] ** 2 + y_new[o + 2] ** 2)
            for i in range(3):
                scale[o + i] = (atol[o + i] + rtol) * (1.0 + size)
    return scale


@jit
def dissipation_arrays(work) -> tuple:
    """``(contact_power, stage_power, dissipated, dense_power)`` of ``work``, the arrays
    themselves, for Python (:mod:`mbd3d.analyses.dissipation`)."""
    return work.contact_power, work.stage_power, work.dissipated, work.dense_power


@jit
def dissipation_error(work, E, E_low, B, stages: int, step: float, rtol: float,
                      dense_kind: int, at_switch: bool) -> float:
    """The step's error in the energy the contacts dissipate, relative to ``atol + rtol
    |energy|`` (``work.dissipated[4]``: the absolute tolerance [J] per row), by the method's
    error weights on the stages' powers: the power need not affect the motion (a contact's
    spring unloading while its force is clipped at zero), so the motion's error alone would
    not shorten the step where it changes fast. Over a step ended just past a switch
    (``at_switch``) the rows whose power jumps at a touch (``work.dissipated[5]``: a
    linear law's damping) are left out: no step would hold their jump within tolerance."""
    P, z = work.stage_power, work.dissipated
    scale = np.empty(P.shape[1])
    for k in range(P.shape[1]):
        new = z[0, k]
        for s in range(stages):
            new += step * B[s] * P[s, k]
        scale[k] = z[4, k] + rtol * max(abs(z[0, k]), abs(new))
        if at_switch and z[5, k] != 0.0:
            scale[k] = np.inf
    return error_norm(P, E, E_low, scale, step, dense_kind)


@jit
def dissipate(work, B, stages: int, step: float) -> None:
    """Add the energy [J] each contact dissipated over the step just accepted to
    ``work.dissipated`` (rows: the energy now and at the step's start, the power now and at
    its start; the last two, set by Python, are kept: :func:`dissipation_error`), by the
    method's own weights ``B`` on its stages' powers (``work.stage_power``, the first the
    power at the step's start): the quadrature the method would make of the energy as a
    state of its own."""
    P, z = work.stage_power, work.dissipated
    if P.shape[1] == 0:
        return
    z[1, :] = z[0]
    z[3, :] = P[0]
    for s in range(stages):
        for k in range(P.shape[1]):
            z[0, k] += step * B[s] * P[s, k]
    z[2, :] = P[stages]


@jit
def advance(model, key, tableau, t, y, f, h, t_output, t_bound, rtol, atol, max_step,
            charts, turns, constraint_tol, chart_limit, recent, stats, drift_stats, K, y_old,
            dense, collapse, check_at, budget, work):
    """Step from ``(t, y)`` with first stage ``f`` and next step ``h`` until a step passes
    ``t_output``, ends at ``t_bound``, leaves the constraints drifted past
    ``constraint_tol``, collapses (a step below ``collapse`` times the longest of ``recent``),
    or fails; also after step number ``check_at`` and after ``budget`` steps. ``y``, ``f``,
    ``charts``, ``recent``, ``stats``, ``drift_stats`` (largest drift, last drift), ``K``
    and ``y_old`` are updated in place; with ``OUTPUT``, ``dense`` holds the last step's
    dense-output coefficients.

    ``turns`` (bodies, 4): the charts as quaternions whose signs follow the motion (see
    :func:`.bodies.spatial_reset_charts`; empty for a planar model).
    ``charts`` (bodies, 3, 3): the reference rotations of a spatial model's bodies, None for a
    planar model. Numba compiles a function once per type of its arguments and drops the
    branches an argument's type decides (``charts is None``): a planar model compiles no
    spatial code, and the reverse.

    Returns ``(status, t, t_old, step, h)``: the flags of why it returned, the time reached,
    the last step's start and length, the next step. On a failure ``t`` is the time of the
    failing evaluation and ``y_old`` its state.
    """
    A, B, C, E, E_low, P, A_extra, C_extra, D, dense_kind, error_order = tableau
    n = model.n
    stages = B.shape[0]
    n_recent = recent.shape[0]
    t_old = t
    step = 0.0
    first = stats[STEPS]
    ys = np.empty(2 * n)
    y_new = np.empty(2 * n)
    rates = np.empty(n)
    n_switch = switch_count(model.forces)
    n_power = work.stage_power.shape[1]
    switch_old, switch_new = np.empty(n_switch), np.empty(n_switch)
    spatial = charts is not None  # a run-time flag, where no spatial-only code depends on it
    while True:
        if charts is not None:
            if spatial_reset_charts(y[:n], np.zeros(0), charts, chart_limit, turns):
                # v and its derivative are unchanged; the rates of g are those of the new chart
                spatial_rates_into(y[:n], y[n:], rates)
                f[:n] = rates
                stats[CHART_RESETS] += 1
        if n_power > 0:
            work.stage_power[0, :] = work.dissipated[2]  # the power at the step's start
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        h_abs = min(h, max_step)
        if h_abs < min_step:
            h_abs = min_step
        if n_switch > 0:
            switches(model, y, charts, work, switch_old)
        tries = 0
        rejected = False
        failure = SOLVED  # the status of the last trial step's failing evaluation
        t_failure = t
        while True:
            if h_abs < min_step:
                if failure != SOLVED:
                    # every step length failed: the state itself is singular or diverged
                    return SINGULAR if failure != NOT_FINITE else DIVERGED, t_failure, t, \
                        step, h_abs
                y_old[:] = y
                return STEP_TOO_SMALL, t, t_old, step, h_abs
            step = h_abs
            t_new = t + step
            if t_new > t_bound:
                t_new = t_bound
                step = t_new - t
            K[0] = f
            status = SOLVED
            for s in range(1, stages + 1):
                last = s == stages  # the step's end, whose derivative is the next first stage
                t_stage = t_new if last else t + C[s] * step
                state = y_new if last else ys
                stage_state(y, K, B if last else A[s], s, step, state)
                status = derivative(model, key, t_stage, state, charts, K[s], work)
                stats[RHS_EVALUATIONS] += 1
                if status != SOLVED:
                    failure, t_failure = status, t_stage
                    y_old[:] = state
                    break
                work.stage_power[s, :] = work.contact_power
            if status != SOLVED:
                # a trial step too long for the motion can leave the stages so far off that
                # the matrix is singular or the state not finite there: a rejected step, not
                # the end of the run, which only ends if the shortest step fails too
                h_abs = step * _FAILED_STEP_FACTOR
                rejected = True
                stats[REJECTED] += 1
                continue
            scale = error_scale(spatial, n, y, y_new, atol, rtol)
            error = error_norm(K, E, E_low, scale, step, dense_kind)
            if error < 1.0 and n_switch > 0 and tries < _SWITCH_TRIES:
                switches(model, y_new, charts, work, switch_new)
                noise = _SWITCH_NOISE * max(1.0, np.max(np.abs(y[:n])))
                fraction = first_switch(switch_old, switch_new, noise)
                if fraction < 1.0 - _SWITCH_BAND and fraction * step > min_step:
                    # end the step just past the switch (secant on the switching function)
                    h_abs = step * fraction * (1.0 + 0.5 * _SWITCH_BAND)
                    tries += 1
                    rejected = True
                    stats[REJECTED] += 1
                    continue
            if error < 1.0 and n_power > 0:
                # the contacts' dissipated energy, as if it were a state, once the step ends
                # at the first switch (a linear law's power jumps at a touch: past it, no step
                # would hold the jump within tolerance)
                error = max(error, dissipation_error(work, E, E_low, B, stages, step, rtol,
                                                     dense_kind, tries > 0))
            if error < 1.0:
                factor = step_factor(error, error_order)
                if rejected:
                    factor = min(1.0, factor)
                h = step * factor
                break
            h_abs = step * step_factor(error, error_order)
            rejected = True
            stats[REJECTED] += 1
        t_old = t
        y_old[:] = y
        f_old = f.copy()
        y[:] = y_new
        f[:] = K[stages]
        t = t_new
        stats[STEPS] += 1
        dissipate(work, B, stages, step)
        flags = 0
        # a step far shorter than the recent ones: the index-1 accelerations grow without
        # bound at a singular position, and Python checks the Jacobian there
        longest = 0.0
        for k in range(n_recent):
            longest = max(longest, recent[k])
        recent[stats[STEPS] % n_recent] = step
        if step < collapse * longest:
            flags |= COLLAPSED
        residual = drift(model, key, t, y, charts, work)
        drift_stats[0] = max(drift_stats[0], residual)
        drift_stats[1] = residual
        if residual > constraint_tol:
            flags |= DRIFTED
        if stats[STEPS] == check_at:
            flags |= CHECK_STIFFNESS
        if stats[STEPS] - first >= budget:
            flags |= PAUSED
        if t >= t_output or t >= t_bound:
            flags |= OUTPUT
            if dense_kind == DOP853_INTERPOLANT:
                # the interpolant's three extra stages
                for r in range(C_extra.shape[0]):
                    s = stages + 1 + r
                    stage_state(y_old, K, A_extra[r], s, step, ys)
                    status = derivative(model, key, t_old + C_extra[r] * step, ys,
                                        charts, K[s], work)
                    stats[RHS_EVALUATIONS] += 1
                    if status != SOLVED:
                        y_old[:] = ys
                        return SINGULAR if status != NOT_FINITE else DIVERGED, \
                            t_old + C_extra[r] * step, t_old, step, h
                    work.stage_power[s, :] = work.contact_power
                dense[:] = dop853_coefficients(K, D, y_old, y, f_old, f, step)
                if n_power > 0:  # the dissipated energy's interpolant, of the same stages
                    z = work.dissipated
                    work.dense_power[:dense.shape[0], :] = dop853_coefficients(
                        work.stage_power, D, z[1], z[0], z[3], z[2], step)
            else:
                dense[:] = polynomial_coefficients(K, P, stages + 1)
                if n_power > 0:
                    work.dense_power[:dense.shape[0], :] = polynomial_coefficients(
                        work.stage_power, P, stages + 1)
        if flags:
            return flags, t, t_old, step, h
