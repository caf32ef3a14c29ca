"""The stages of forward sensitivities in one compiled call per step.

After the compiled Runge-Kutta step of the state
(:func:`mbd3d.numerics.compiled.integration.advance`) has been accepted,
:func:`sensitivity_stages_into` takes the same step of the sensitivities ``S = dy/dp`` of every
parameter: at each stage, with the stage's state ``Y`` formed exactly as the step formed it,
the derivative of ``S`` is the change of the right-hand side along the parameter with the state
moving by its sensitivity, ``d/dh f_{p+h}(t, Y + h S)``. It is taken as the formula sheet's 1.1
has it: the stage's accelerations and multipliers ``x = (qdd, lam)`` are solved once (one
right-hand side of the model, whose augmented matrix ``K`` stays factored in its workspace),
and per parameter the right-hand side and the residual ``r = [Qe + Qv; Qd] - K x`` are
differenced with ``x`` held (no solve in them: about two thirds of a right-hand side on the
slider-crank, two fifths on a 100-link chain), then ``dqdd = K^-1 dr`` is one more solve with
``K`` (from the range-space layout's factors, or the same entries factored again). The
differences are fourth-order central ones (:data:`OFFSETS`) over the model's variants (the
model built with the parameter at ``OFFSETS`` steps from its value; see
:class:`mbd3d.model.tangents.ModelTangent`, whose
:meth:`~mbd3d.model.tangents.ModelTangent.along` is the same rule for any quantity evaluated
in Python); an analytic tangent of the residual would replace them where it is written.

Where a step of the variants would move the state further than :data:`REACH` of its scale (a
large sensitivity), the stencil's error would show: the variants at a step ``2**-k`` shorter
are used (``k`` a multiple of 4 up to 16), which the caller makes when the kernel asks for them
(a negative status), or, beyond those or where the parameter has none, the state's change
alone from the model itself plus the parameter's alone from the variants with the state held.

Everything here evaluates what the integrator's right-hand side is made of; the loop over
stages and parameters is what was Python (four calls from Python per stage and parameter, 60 us
of overhead for 4 us of work on the slider-crank).
"""

from __future__ import annotations

import math

import numpy as np

from mbd3d.numerics.compiled import jit
from mbd3d.numerics.compiled.integration import (constraint_residuals_into, derivative,
                                                 frozen_derivative_into, solve_again,
                                                 velocity_derivative_into)
from mbd3d.numerics.compiled.runge_kutta import stage_state

__all__ = ["sensitivity_stages_into", "accelerations_tangent_into", "rows_tangent_into",
           "OFFSETS", "REACH", "REFINE", "LEVELS", "SOLVED"]

#: the stencil's offsets, in steps, of the fourth-order central difference
OFFSETS = (-2.0, -1.0, 1.0, 2.0)
#: the largest move of the state, relative to its scale, per step of the variants
REACH = 1e-3
#: levels of variants per parameter: level ``l`` at a step ``2**-(REFINE l)`` of the first
REFINE, LEVELS = 4, 5
SOLVED = 0


@jit
def _reach(coordinate_scale: np.ndarray, y: np.ndarray, S: np.ndarray) -> float:
    """The largest ``|S_i| / scale_i``: positions against the model's scale, velocities
    against that scale per second plus their own size."""
    n = coordinate_scale.shape[0]
    largest = 0.0
    for i in range(2 * n):
        scale = coordinate_scale[i] if i < n else coordinate_scale[i - n] + abs(y[i])
        largest = max(largest, abs(S[i]) / scale)
    return largest


@jit
def _evaluate_into(model, key, t, y, charts, x, work, F, R, rows) -> int:
    """What the stencil differences at ``(t, y)``: the right-hand side ``F`` and the residual
    ``R`` with ``x`` held (:func:`~mbd3d.numerics.compiled.integration.frozen_derivative_into`)
    or, with ``rows``, the constraints' position and velocity residuals
    (:func:`~mbd3d.numerics.compiled.integration.constraint_residuals_into`) in ``R[:m]`` and
    ``R[m:2m]`` (``F`` zero); returns the status."""
    if rows:
        m = model.n_rows
        F[:] = 0.0
        constraint_residuals_into(model, key, t, y, charts, work, R[:m], R[m:2 * m])
        return SOLVED
    return frozen_derivative_into(model, key, t, y, charts, x, work, F, R)


@jit
def _stencil_into(model, work, key, variants, works, first, use_variants, state_step, step, t,
                  y, S, charts, x, F, R, moved, counts, dF, dR, rows) -> int:
    """``dF += , dR += `` the fourth-order differences, divided by ``step``, of what
    :func:`_evaluate_into` evaluates (``rows``: the constraints' residuals; else the
    right-hand side and the residual with the accelerations and multipliers held at ``x``) at
    ``(t, y + o h S)`` for the offsets ``o`` (``h = state_step``; 0 holds the state), of the
    variants ``first`` to ``first + 3`` (``use_variants``) or of the model itself (in
    ``work``); returns the first failing evaluation's status."""
    n2 = y.shape[0]
    for o in range(4):
        h = OFFSETS[o] * state_step
        for i in range(n2):
            moved[i] = y[i] + h * S[i]
        if use_variants:
            status = _evaluate_into(variants[first + o], key, t, moved, charts, x,
                                    works[first + o], F[o], R[o], rows)
        else:
            status = _evaluate_into(model, key, t, moved, charts, x, work, F[o], R[o], rows)
        counts[0] += 1
        if status != SOLVED:
            return status
    _difference_into(F, step, dF)
    _difference_into(R, step, dR)
    return SOLVED


@jit
def _difference_into(values, step, out) -> None:
    """``out +=`` the fourth-order central difference of ``values`` at :data:`OFFSETS`."""
    for i in range(out.shape[0]):
        out[i] += (8.0 * (values[2, i] - values[1, i]) - (values[3, i] - values[0, i])
                   ) / (12.0 * step)


@jit
def _tangent_into(model, work, key, variants, works, steps, have, refine, j, t, y, S, charts,
                  reach, x, F, R, moved, counts, dF, dR, rows) -> int:
    """``dF``, ``dR``: the derivatives along parameter ``j`` with the state moving by ``S`` of
    the right-hand side and the residual with the accelerations held at ``x`` (see the module
    doc), or with ``rows`` of the constraints' residuals (see :func:`_evaluate_into`); a
    negative status ``-(1 + j LEVELS + level)`` asks for that level's variants.
    ``work``: where the model itself is evaluated."""
    dF[:] = 0.0
    dR[:] = 0.0
    step = steps[j, 0]
    if reach * step <= REACH:
        return _stencil_into(model, work, key, variants, works, j * LEVELS * 4, True, step,
                             step, t, y, S, charts, x, F, R, moved, counts, dF, dR, rows)
    k = REFINE * math.ceil(math.log2(reach * step / REACH) / REFINE)
    level = k // REFINE
    if refine[j] and level < LEVELS:
        if not have[j, level]:
            return -(1 + j * LEVELS + level)
        finer = steps[j, level]
        return _stencil_into(model, work, key, variants, works, (j * LEVELS + level) * 4,
                             True, finer, finer, t, y, S, charts, x, F, R, moved, counts, dF,
                             dR, rows)
    # the state's change alone (the model, a shorter step), then the parameter's alone
    h = REACH / reach
    status = _stencil_into(model, work, key, variants, works, 0, False, h, h, t, y, S, charts,
                           x, F, R, moved, counts, dF, dR, rows)
    if status != SOLVED:
        return status
    return _stencil_into(model, work, key, variants, works, j * LEVELS * 4, True, 0.0, step, t,
                         y, S, charts, x, F, R, moved, counts, dF, dR, rows)


@jit
def _solved_into(model, work, key, t, y, charts, scratch, counts) -> int:
    """The accelerations and multipliers ``x`` at ``(t, y)`` solved into ``scratch[0]``, the
    augmented matrix ``K`` left in ``work`` for :func:`_change_into`; returns the status."""
    x, moved = scratch[0], scratch[3]
    status = derivative(model, key, t, y, charts, moved, work)
    counts[0] += 1
    if status == SOLVED:
        x[:] = work.x
    return status


@jit
def _change_into(model, work, residual_work, key, variants, works, steps, have, refine,
                 coordinate_scale, j, t, y, S, charts, scratch, counts) -> int:
    """Sheet 1.1 for parameter ``j`` at the state solved by :func:`_solved_into`, the state
    moving by ``S``: ``dF`` (``scratch[4]``) the right-hand side's change with ``x`` held and
    ``dx = K^-1 dr`` (``scratch[6]``) the accelerations' and multipliers' change, ``dr`` the
    change of the equations' residual with ``x`` held; returns the status."""
    x, F, R, moved, dF, dR, dx = scratch[:7]
    held = steps.shape[0] < 0  # a run-time False: one compilation with rows_tangent_into's
    status = _tangent_into(model, residual_work, key, variants, works, steps, have, refine, j,
                           t, y, S, charts, _reach(coordinate_scale, y, S), x, F, R, moved,
                           counts, dF, dR, held)
    if status != SOLVED:
        return status
    return solve_again(model, key, work, charts, dR, dx)


@jit
def _rates_into(model, work, residual_work, key, variants, works, steps, have, refine,
                coordinate_scale, m, width, t, y, z, charts, scratch, counts, out) -> int:
    """The sensitivities' part of ``dz/dt`` at the stage ``(t, y)``, ``z`` the stage's
    sensitivities: per parameter ``j`` its columns ``m + j width`` on, ``2n`` of them (the
    integrals' columns are the caller's). The stage's ``x`` is solved once, its matrix
    serving every parameter (:func:`_change_into`); each parameter's derivative of the
    right-hand side is its change with ``x`` held plus that of ``dx``."""
    dF, dx, linear, zero = scratch[4], scratch[6], scratch[7], scratch[8]
    n2 = y.shape[0]
    n = n2 // 2
    status = _solved_into(model, work, key, t, y, charts, scratch, counts)
    if status != SOLVED:
        return status
    for j in range(steps.shape[0]):
        start = m + j * width
        status = _change_into(model, work, residual_work, key, variants, works, steps, have,
                              refine, coordinate_scale, j, t, y, z[start:start + n2], charts,
                              scratch, counts)
        if status != SOLVED:
            return status
        velocity_derivative_into(y[:n], zero, dx[:n], linear, charts)
        for i in range(n):
            out[start + i] = dF[i]
            out[start + n + i] = dF[n + i] + linear[i]
    return SOLVED


@jit
def _scratch(n2: int, size: int) -> tuple:
    """What :func:`_rates_into` works in: ``x, F, R, moved, dF, dR, dx, linear, zero``."""
    n = n2 // 2
    return (np.empty(size), np.empty((4, n2)), np.empty((4, size)), np.empty(n2),
            np.empty(n2), np.empty(size), np.empty(size), np.empty(n), np.zeros(n))


@jit
def accelerations_tangent_into(model, work, residual_work, key, variants, works, steps, have,
                               refine, coordinate_scale, t, y, Z, charts, counts, out) -> int:
    """``out[j]``: the change of the accelerations and multipliers ``(qdd, lam)`` at ``(t,
    y)`` along parameter ``j`` with the state moving by ``Z[j]`` (its sensitivities of ``y =
    (q, v)``), as the stages take it (:func:`_change_into`); arguments as
    :func:`sensitivity_stages_into` takes them; returns the status (a negative one asks for
    finer variants)."""
    scratch = _scratch(y.shape[0], work.x.shape[0])
    status = _solved_into(model, work, key, t, y, charts, scratch, counts)
    if status != SOLVED:
        return status
    for j in range(Z.shape[0]):
        status = _change_into(model, work, residual_work, key, variants, works, steps, have,
                              refine, coordinate_scale, j, t, y, Z[j], charts, scratch, counts)
        if status != SOLVED:
            return status
        out[j, :] = scratch[6]
    return SOLVED


@jit
def rows_tangent_into(model, work, residual_work, key, variants, works, steps, have, refine,
                      coordinate_scale, t, y, Z, charts, counts, out) -> int:
    """``out[j] = (dC, dnu)``: the change of the constraints' position residual ``C(q, t) - c0``
    and velocity residual ``Cq qd + C_t`` at ``(t, y)`` along parameter ``j`` with the state
    moving by ``Z[j]`` (its sensitivities of ``y = (q, v)``): what projecting the
    sensitivities onto the constraints corrects (sheet 1.4). Arguments as
    :func:`accelerations_tangent_into` takes them (the model itself is evaluated in
    ``residual_work``); returns the status (a negative one asks for finer variants)."""
    m = model.n_rows
    x, F, R, moved, dF, dR = _scratch(y.shape[0], max(work.x.shape[0], 2 * m))[:6]
    rows = steps.shape[0] >= 0  # a run-time True (see _change_into)
    for j in range(Z.shape[0]):
        status = _tangent_into(model, residual_work, key, variants, works, steps, have, refine,
                               j, t, y, Z[j], charts, _reach(coordinate_scale, y, Z[j]), x, F,
                               R, moved, counts, dF, dR, rows)
        if status != SOLVED:
            return status
        out[j, :] = dR[:2 * m]
    return SOLVED


@jit
def sensitivity_stages_into(model, work, residual_work, key, variants, works, steps, have,
                            refine, coordinate_scale, m, width, W, C, t_old, step, y_old, K, z,
                            L, charts, first, start, stage_y, stage_z, counts) -> int:
    """The stages ``L[start:]`` of the sensitivities ``z`` through the step ``t_old -> t_old +
    step`` the state took from ``y_old`` with its stages ``K``; returns the status (0; a
    right-hand side's failing status; a negative request for finer variants, see
    :func:`_tangent_into`).

    Parameters
    ----------
    model, work, residual_work, key
        The model's compiled arrays, two workspaces of its own (the stage's matrix stays in
        the first) and the integrator's key.
    variants, works
        Typed lists of the variants' arrays and workspaces, four per level, ``LEVELS`` levels
        per parameter (levels not made yet: any record, ``have`` False).
    steps : (p, LEVELS) ndarray
        The variants' steps [the parameter's unit]; ``have`` (p, LEVELS) which are made,
        ``refine`` (p,) whether a parameter can have finer levels at all.
    coordinate_scale : (n,) ndarray
        What a change of each coordinate is measured against.
    m, width
        The integrals' count (their columns are the caller's) and each parameter's columns.
    W : (rows, n_stored) ndarray
        Each stage's weights after the first, ``C`` (rows,) its time [in steps].
    L : (n_stored, z.size) ndarray
        The stages; ``L[0]`` is computed where ``first`` (and ``start`` is 1), kept otherwise
        (the last stage of the step before).
    start : int
        The first stage computed after ``L[0]``: 1, or past the solution's stage for the
        dense output's extra stages alone (needed only in a step with an output time).
    stage_y, stage_z : (rows + 1, ...) ndarray
        Each stage's state and sensitivities, for the caller's integrals.
    counts : (1,) int64 ndarray
        Right-hand sides and residuals evaluated, added to.
    """
    scratch = _scratch(y_old.shape[0], work.x.shape[0])
    stage_y[0, :] = y_old
    stage_z[0, :] = z
    if first and start == 1:
        status = _rates_into(model, work, residual_work, key, variants, works, steps, have,
                             refine, coordinate_scale, m, width, t_old, y_old, z, charts,
                             scratch, counts, L[0])
        if status != SOLVED:
            return status
    for i in range(start, W.shape[0] + 1):
        stage_state(y_old, K, W[i - 1], i, step, stage_y[i])
        stage_state(z, L, W[i - 1], i, step, stage_z[i])
        status = _rates_into(model, work, residual_work, key, variants, works, steps, have,
                             refine, coordinate_scale, m, width, t_old + C[i - 1] * step,
                             stage_y[i], stage_z[i], charts, scratch, counts, L[i])
        if status != SOLVED:
            return status
    return SOLVED
