"""The augmented equations of motion in one compiled call:

    [M  Cq^T] [qdd]   [Qe + Qv]
    [Cq 0   ] [lam] = [Qd     ]

from the state ``(q, qd)``: frames, body vectors, constraint rows, mass blocks, the quadratic
velocity and gravity forces, the force elements, the drivers' motions, and the solve: LU,
dense or in band storage, or through ``Cq M^-1 Cq^T``
(:mod:`mbd3d.numerics.compiled.range_space`). Forces and motions given as Python functions are
evaluated by the caller and passed in; the caller also solves the system of a model whose
bandwidth is too large for band storage (SuperLU).

Every intermediate array lives in a :class:`~mbd3d.numerics.compiled.structures.Workspace`: the
integrator loop makes one per run segment and evaluates thousands of right-hand sides without
allocating, and a single call (:func:`accelerations_with_parts`) takes one too (one entry
point: each one compiles the whole of the augmented equations into itself once more). A
planar model passes ``charts=None``, and compiles no spatial code.

``status``: 0 solved, 1 singular matrix (dependent rows), 2 non-finite state (or a force or
motion that cannot be evaluated there: the caller evaluates it in Python for the message).
"""

from __future__ import annotations

import numpy as np

from mbd3d.numerics.compiled import jit
from mbd3d.numerics.compiled.bodies import (body_vectors_into, planar_frames_into,
                                            planar_mass_blocks_into, spatial_frames_into,
                                            spatial_mass_blocks_into,
                                            spatial_quadratic_velocity_into)
from mbd3d.numerics.compiled.dense import solve_banded_pattern_into, solve_pattern_into
from mbd3d.numerics.compiled.contact_groups import REPORT_COLUMNS, all_contact_forces_into
from mbd3d.numerics.compiled.forces import (point_forces_into, rotary_forces_into,
                                            spring_forces_into, torques_into)
from mbd3d.numerics.compiled.motions import motion_values_into
from mbd3d.numerics.compiled.range_space import (range_space_solve_factored,
                                                  range_space_solve_into)
from mbd3d.numerics.compiled.rows import constraint_rows_into
from mbd3d.numerics.compiled.structures import BANDED, DENSE, RANGE, SPARSE, contact_count

SOLVED, SINGULAR, NOT_FINITE = 0, 1, 2


@jit
def padded_into(x: np.ndarray, out: np.ndarray) -> None:
    """Write ``x`` (n,) into the rows of ``out`` (bodies + ground, n_coords), ground zero."""
    n_coords = out.shape[1]
    for b in range(out.shape[0] - 1):
        for c in range(n_coords):
            out[b, c] = x[b * n_coords + c]
    out[out.shape[0] - 1, :] = 0.0


@jit
def _finite(x: np.ndarray) -> bool:
    for value in x:
        if not abs(value) < np.inf:
            return False
    return True


@jit
def motions_at(model, work, t: float) -> bool:
    """``(f, f', f'')`` of the drivers' motions into ``work.drivers`` and of the rotation
    drivers' into ``work.phi`` at ``t``; returns whether all are finite."""
    motion_values_into(model.driver_first, model.driver_kinds, model.driver_starts,
                       model.driver_params, t, work.drivers)
    motion_values_into(model.rotation_first, model.rotation_kinds, model.rotation_starts,
                       model.rotation_params, t, work.phi)
    return _finite_rows(work.drivers) and _finite_rows(work.phi)


@jit
def _finite_rows(x: np.ndarray) -> bool:
    for i in range(x.shape[0]):
        for j in range(x.shape[1]):
            if not abs(x[i, j]) < np.inf:
                return False
    return True


@jit
def _contacts_into(contacts, A, axes, omega, Q, Qd, out, power) -> bool:
    """Add the forces of the contacts ``contacts`` (a
    :class:`~mbd3d.numerics.compiled.structures.ContactArrays`) to ``out``; False where a
    normal is undefined. None (a model without contacts) is decided as the caller is compiled,
    so that models without contacts compile none of the contacts' code."""
    if contacts is None:
        return True
    shapes = (contacts.shape_bodies, contacts.shape_points, contacts.shape_values,
              contacts.pair_laws)
    return all_contact_forces_into(A, axes, omega, Q, Qd, contacts.bodies, contacts.points,
                                   contacts.values, contacts.curves, shapes, out,
                                   np.empty((0, REPORT_COLUMNS)), power) < 0


@jit
def forces_into(forces, work, t: float, rhs) -> bool:
    """Add the generalized forces of the force elements ``forces``
    (:class:`~mbd3d.numerics.compiled.structures.ForceArrays`) at ``t`` to ``rhs`` (n,), from the
    frames and coordinates in ``work``; False when a spring's points or two contact spheres'
    centres coincide or an actuator is not finite. A model without compiled force elements
    has a record of empty tables, and returns at once: one type for models with forces and
    without, so that the kernels are not compiled once for each (the contacts, a record or
    None, are the exception: see :mod:`.structures`)."""
    if (forces.spring_bodies.shape[0] == 0 and forces.rotary_bodies.shape[0] == 0
            and forces.point_bodies.shape[0] == 0 and forces.torque_bodies.shape[0] == 0
            and contact_count(forces.contacts) == 0):
        return True
    motion_values_into(forces.spring_first, forces.spring_kinds, forces.spring_starts,
                       forces.spring_params, t, work.spring_actuation)
    motion_values_into(forces.rotary_first, forces.rotary_kinds, forces.rotary_starts,
                       forces.rotary_params, t, work.rotary_actuation)
    if not (_finite_rows(work.spring_actuation) and _finite_rows(work.rotary_actuation)):
        return False
    out = work.forces
    out[:, :] = 0.0
    A, axes, omega, Q, Qd = work.A, work.axes, work.omega, work.Q, work.Qd
    if spring_forces_into(A, axes, omega, Q, Qd, forces.spring_bodies, forces.spring_points,
                          forces.spring_values, work.spring_actuation, out) >= 0:
        return False
    rotary_forces_into(A, axes, omega, Q, Qd, forces.rotary_bodies, forces.rotary_values,
                       forces.rotary_vectors, work.rotary_actuation, out)
    point_forces_into(A, axes, forces.point_bodies, forces.point_points, forces.point_forces,
                      forces.point_body_frame, out)
    torques_into(A, axes, forces.torque_bodies, forces.torque_values, forces.torque_body_frame,
                 out)
    if not _contacts_into(forces.contacts, A, axes, omega, Q, Qd, out, work.contact_power):
        return False
    nc = out.shape[1]
    for b in range(out.shape[0] - 1):
        for c in range(nc):
            rhs[b * nc + c] += out[b, c]
    return True


@jit
def augmented_into(model, work, t, q, qd, charts, extra, phi, drivers):
    """Assemble the augmented equations at ``(t, q, qd)`` of ``model`` (:class:`ModelArrays`)
    in ``work`` (:class:`Workspace`), not solved: the mass blocks ``work.blocks``, the
    Jacobian's entries ``work.data`` and the right-hand side ``work.rhs``; returns the status.

    For a model with parts that are Python objects (``python_parts``) the
    caller gives ``extra`` (n,), the generalized forces of the force elements, and the
    motions ``(f, f', f'')`` of the rotation drivers ``phi`` (k, 3) and of the drivers
    ``drivers`` (n_drivers, 3); otherwise the motions are evaluated here. ``charts``:
    reference rotations of a spatial model's bodies, None for a planar model (which then
    compiles no spatial code: Numba drops the branches decided by ``charts is None``).
    Every model's record has the same type (see
    :mod:`~mbd3d.numerics.compiled.structures`), so these are compiled twice in all: planar
    and spatial.
    """
    if not (_finite(q) and _finite(qd)):
        return NOT_FINITE
    if not model.python_parts:
        if (model.driver_rows.shape[0] or model.rotation_first.shape[0] > 1) and \
                not motions_at(model, work, t):
            return NOT_FINITE
        phi, drivers = work.phi, work.drivers
    if not applied_forces_into(model, work, t, q, qd, charts, extra):
        return NOT_FINITE
    n = q.shape[0]
    yes = n >= 0  # run-time flags (see applied_forces_into)
    no = not yes
    rhs, gamma = work.rhs, work.gamma
    body_vectors_into(work.A, work.axes, work.omega, work.kappa, model.vector_bodies,
                      model.vector_local, yes, work.s, work.J, work.v, work.a)
    constraint_rows_into(model.code, model.bi, model.bj, model.first_row, model.slots,
                         model.coordinate, model.motion, model.real, model.curves, phi, model.n_rows, work.Q, work.Qd,
                         work.s, work.J, work.v, work.a, model.destination, no, yes, yes, no,
                         work.C, work.data, gamma, work.nu, work.row_work, work.row_jacobian)
    driver_rows = model.driver_rows
    for k in range(driver_rows.shape[0]):
        gamma[driver_rows[k]] += drivers[k, 2]
    for i in range(model.n_rows):
        rhs[n + i] = gamma[i]
    return SOLVED


@jit
def accelerations_into(model, work, t, q, qd, charts, extra, phi, drivers):
    """Solve the augmented equations at ``(t, q, qd)`` of ``model`` (:class:`ModelArrays`) in
    ``work`` (:class:`Workspace`): :func:`augmented_into`, then the solve for the model's
    layout; returns the status. ``x = (qdd, lam)`` is ``work.x``; the matrix entries in the
    pattern's order ``work.values`` and the right-hand side ``work.rhs`` are what the caller
    solves for the ``SPARSE`` layout. The factors stay in ``work`` for
    :func:`solve_again_into`."""
    status = augmented_into(model, work, t, q, qd, charts, extra, phi, drivers)
    if status != SOLVED:
        return status
    # nc: coordinates per body, a compile-time constant (a literal where it is passed on)
    if charts is not None:
        nc = 6
    else:
        nc = 3
    return SOLVED if _solve_into(nc, model, work) else SINGULAR


@jit
def solve_again_into(model, work, charts, b, x) -> bool:
    """``[M Cq^T; Cq 0] x = b`` with the matrix :func:`accelerations_into` solved last in
    ``work`` (from its factors where they are kept: the range-space layout; by factoring the
    same entries again otherwise); False for the ``SPARSE`` layout, whose caller solves (its
    entries are ``work.values``). ``work.x`` and ``work.rhs`` are overwritten."""
    if charts is not None:
        nc = 6
    else:
        nc = 3
    if model.layout == RANGE:
        range_space = model.range_space
        range_space_solve_factored(nc, work.blocks, range_space.body_start,
                                   range_space.positions, range_space.row_position,
                                   range_space.bandwidth, b, work.range_jacobian,
                                   work.range_band, work.range_vector, work.range_forces, x)
        return True
    if model.layout == SPARSE:
        return False
    work.rhs[:] = b
    _solve_into(nc, model, work)  # regular: the same matrix was
    x[:] = work.x
    return True


@jit
def frozen_residual_into(model, work, t, q, qd, charts, extra, phi, drivers, x, r) -> int:
    """``r = [Qe + Qv; Qd] - [M Cq^T; Cq 0] x`` at ``(t, q, qd)`` with ``x = (qdd, lam)``
    given (the equations' residual with the accelerations and multipliers held); returns the
    status of :func:`augmented_into`."""
    status = augmented_into(model, work, t, q, qd, charts, extra, phi, drivers)
    if status != SOLVED:
        return status
    n = q.shape[0]
    blocks, data, rhs = work.blocks, work.data, work.rhs
    nc = blocks.shape[1]
    for i in range(rhs.shape[0]):
        r[i] = rhs[i]
    for b in range(blocks.shape[0]):
        for i in range(nc):
            total = 0.0
            for j in range(nc):
                total += blocks[b, i, j] * x[b * nc + j]
            r[b * nc + i] -= total
    for p in range(data.shape[0]):
        row, col = model.jac_rows[p], model.jac_cols[p]
        r[col] -= data[p] * x[n + row]
        r[n + row] -= data[p] * x[col]
    return SOLVED


@jit
def applied_forces_into(model, work, t, q, qd, charts, extra) -> bool:
    """The frames of the bodies at ``(q, qd)`` (``work.Q``, ``work.Qd``, ``work.A``, ...),
    their mass blocks (``work.blocks``) and the generalized forces ``Qe + Qv`` (gravity,
    ``extra``, the quadratic velocity forces and the force elements) into ``work.rhs[:n]``;
    False when a force element cannot be evaluated there. ``charts`` as in
    :func:`accelerations_into`."""
    n = q.shape[0]
    rhs, blocks = work.rhs, work.blocks
    frames_into(work, q, qd, charts)
    weight = model.weight
    for i in range(n):
        rhs[i] = weight[i] + extra[i]
    if charts is not None:
        spatial_mass_blocks_into(work.Gb, model.mass, model.inertia, blocks)
        spatial_quadratic_velocity_into(work.Gb, work.omega_bar, work.kappa, model.inertia,
                                        rhs)
    else:
        planar_mass_blocks_into(model.mass, model.inertia, blocks)
    return forces_into(model.forces, work, t, rhs)


@jit
def frames_into(work, q, qd, charts) -> None:
    """The bodies' padded coordinates and rates at ``(q, qd)`` (``work.Q``, ``work.Qd``) and
    their frames (``work.A``, ``work.axes``, ``work.omega``, ...). ``charts`` as in
    :func:`accelerations_into`."""
    # flags as run-time values: constants would be typed as literals, and every combination
    # compiled again in each callee
    yes = q.shape[0] >= 0
    Q, Qd = work.Q, work.Qd
    padded_into(q, Q)
    padded_into(qd, Qd)
    if charts is not None:
        spatial_frames_into(Q, Qd, charts, yes, work.A, work.axes, work.omega, work.kappa,
                            work.Gb, work.omega_bar)
    else:
        planar_frames_into(Q, Qd, yes, work.A, work.axes, work.omega, work.kappa)


@jit
def _solve_into(nc, model, work) -> bool:
    """Solve the augmented system whose mass blocks, Jacobian values and right-hand side
    :func:`accelerations_into` left in ``work``, for the model's layout; returns whether the
    matrix is regular (the ``SPARSE`` layout: the caller solves)."""
    blocks, data, rhs = work.blocks, work.data, work.rhs
    if model.layout == RANGE:
        range_space = model.range_space
        return range_space_solve_into(
            nc, blocks, data, range_space.slot, range_space.body_start, range_space.positions,
            range_space.row_position, range_space.bandwidth, model.pivot_tolerance, rhs,
            work.range_jacobian, work.range_band, work.range_diagonal, work.range_vector,
            work.range_forces, work.x)
    values = work.values
    n_blocks = blocks.size
    for b in range(blocks.shape[0]):
        for i in range(nc):
            for j in range(nc):
                values[(b * nc + i) * nc + j] = blocks[b, i, j]
    nnz = model.nnz
    for i in range(nnz):
        values[n_blocks + i] = data[i]
        values[n_blocks + nnz + i] = data[i]
    if model.layout == DENSE:
        return solve_pattern_into(model.rows, model.cols, model.entry_scale, model.scale,
                                  values, rhs, model.pivot_tolerance, work.matrix, work.x)
    if model.layout == BANDED:
        return solve_banded_pattern_into(model.flat, model.kl, model.ku, model.perm,
                                         model.entry_scale, model.scale, values, rhs,
                                         model.pivot_tolerance, work.band, work.permuted, work.x)
    return True


@jit
def _result(model, work, status):
    """``(x, status)`` after :func:`accelerations_into`: ``x = (qdd, lam)`` (a new array), or
    for the ``SPARSE`` layout the augmented matrix's entries in the pattern's order followed
    by its right-hand side, for the caller's solve."""
    if model.layout == SPARSE:
        return np.concatenate((work.values, work.rhs)), status
    return work.x.copy(), status


@jit
def accelerations_with_parts(work, t, q, qd, charts, extra, phi, drivers):
    """``(x, status)`` of :func:`accelerations_into` for the model of the workspace ``work``
    (:func:`~mbd3d.numerics.compiled.structures.workspace`): ``extra``, ``phi`` and ``drivers``
    as in :func:`accelerations_into` for a model with parts that are Python objects, the
    model's empty ``no_forces``, ``no_motions`` and ``no_motions`` otherwise; ``x`` as in
    :func:`_result`."""
    model = work.model
    return _result(model, work, accelerations_into(model, work, t, q, qd, charts, extra, phi,
                                                   drivers))
