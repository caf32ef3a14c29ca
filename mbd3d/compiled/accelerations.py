"""The augmented equations of motion in one compiled call:

    [M  Cq^T] [qdd]   [Qe + Qv]
    [Cq 0   ] [lam] = [Qd     ]

from the state ``(q, qd)``: frames, body vectors, constraint rows, mass blocks, the quadratic
velocity and gravity forces, and the LU solve, dense or in band storage. The caller adds the
forces of force elements (``extra``), the drivers' ``f''`` and the rotation drivers' motions,
which come from Python objects, and solves the system of a model whose bandwidth is too large
for band storage itself (SuperLU).

Every intermediate array lives in a :class:`~mbd3d.compiled.structures.Workspace`: the
integrator loop makes one per run segment and evaluates thousands of right-hand sides without
allocating, and a single call (:func:`planar_accelerations`, :func:`spatial_accelerations`)
takes one too. ``spatial`` reaches the functions as a constant from these entry points, so that a
planar model compiles no spatial code and the reverse.

``status``: 0 solved, 1 singular matrix (dependent rows), 2 non-finite state.
"""

from __future__ import annotations

import numpy as np

from mbd3d.compiled import jit
from mbd3d.compiled.bodies import (body_vectors_into, planar_frames_into,
                                   planar_mass_blocks_into, spatial_frames_into,
                                   spatial_mass_blocks_into, spatial_quadratic_velocity_into)
from mbd3d.compiled.dense import solve_banded_pattern_into, solve_pattern_into
from mbd3d.compiled.rows import constraint_rows_into
from mbd3d.compiled.structures import BANDED, DENSE, SPARSE, workspace  # noqa: F401

SOLVED, SINGULAR, NOT_FINITE = 0, 1, 2


@jit
def padded(x: np.ndarray, n_coords: int) -> np.ndarray:
    """``x`` (n,) as rows of ``n_coords`` with a zero row for the ground last."""
    out = np.empty((x.shape[0] // n_coords + 1, n_coords))
    padded_into(x, out)
    return out


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
def accelerations_into(spatial, model, work, q, qd, charts, extra, phi, driver_acceleration):
    """Solve the augmented equations at ``(q, qd)`` of ``model`` (:class:`ModelArrays`) in
    ``work`` (:class:`Workspace`); returns the status.

    ``x = (qdd, lam)`` is ``work.x``; the matrix entries in the pattern's order
    ``work.values`` and the right-hand side ``work.rhs`` are what the caller solves for the
    ``SPARSE`` layout. ``extra`` (n,): generalized forces of the force elements; ``phi``
    (k, 3): the rotation drivers' motions; ``driver_acceleration``: ``f''`` of the drivers;
    ``charts``: reference rotations of spatial bodies.
    """
    if not (_finite(q) and _finite(qd)):
        return NOT_FINITE
    n = q.shape[0]
    # flags as run-time values: constants would be typed as literals, and every combination
    # compiled again in each callee
    yes = n >= 0
    no = not yes
    Q, Qd, rhs, blocks = work.Q, work.Qd, work.rhs, work.blocks
    A, axes, omega, kappa = work.A, work.axes, work.omega, work.kappa
    padded_into(q, Q)
    padded_into(qd, Qd)
    weight = model.weight
    for i in range(n):
        rhs[i] = weight[i] + extra[i]
    if spatial:
        spatial_frames_into(Q, Qd, charts, yes, A, axes, omega, kappa, work.Gb, work.omega_bar)
        spatial_mass_blocks_into(work.Gb, model.mass, model.inertia, blocks)
        spatial_quadratic_velocity_into(work.Gb, work.omega_bar, kappa, model.inertia, rhs)
    else:
        planar_frames_into(Q, Qd, yes, A, axes, omega, kappa)
        planar_mass_blocks_into(model.mass, model.inertia, blocks)
    s, J, v, a = work.s, work.J, work.v, work.a
    body_vectors_into(A, axes, omega, kappa, model.vector_bodies, model.vector_local, yes, s,
                      J, v, a)
    gamma, data = work.gamma, work.data
    constraint_rows_into(model.code, model.bi, model.bj, model.first_row, model.slots,
                         model.coordinate, model.motion, phi, model.n_rows, Q, Qd, s, J, v, a,
                         model.destination, no, yes, yes, no, work.C, data, gamma, work.nu,
                         work.row_work, work.row_jacobian)
    driver_rows = model.driver_rows
    for k in range(driver_rows.shape[0]):
        gamma[driver_rows[k]] += driver_acceleration[k]
    for i in range(model.n_rows):
        rhs[n + i] = gamma[i]
    values = work.values
    nc = blocks.shape[1]
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
        regular = solve_pattern_into(model.rows, model.cols, model.entry_scale, model.scale,
                                     values, rhs, model.pivot_tolerance, work.matrix, work.x)
    elif model.layout == BANDED:
        regular = solve_banded_pattern_into(model.flat, model.kl, model.ku, model.perm,
                                            model.entry_scale, model.scale, values, rhs,
                                            model.pivot_tolerance, work.band, work.permuted,
                                            work.x)
    else:
        return SOLVED
    return SOLVED if regular else SINGULAR


@jit
def _accelerations(spatial, model, work, q, qd, charts, extra, phi, driver_acceleration):
    status = accelerations_into(spatial, model, work, q, qd, charts, extra, phi,
                                driver_acceleration)
    if model.layout == SPARSE:
        # the matrix's entries in the pattern's order and the right-hand side, stacked, for
        # the caller's solve
        return np.concatenate((work.values, work.rhs)), status
    return work.x.copy(), status


@jit
def planar_accelerations(model, work, q, qd, charts, extra, phi, driver_acceleration):
    """``(x, status)`` of :func:`accelerations_into` for a planar model, in the workspace
    ``work``: ``x = (qdd, lam)`` (a new array), or for the ``SPARSE`` layout the augmented
    matrix's entries in the pattern's order followed by its right-hand side."""
    return _accelerations(False, model, work, q, qd, charts, extra, phi, driver_acceleration)


@jit
def spatial_accelerations(model, work, q, qd, charts, extra, phi, driver_acceleration):
    """As :func:`planar_accelerations`, for a spatial model."""
    return _accelerations(True, model, work, q, qd, charts, extra, phi, driver_acceleration)
