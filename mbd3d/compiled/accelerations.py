"""The augmented equations of motion in one compiled call:

    [M  Cq^T] [qdd]   [Qe + Qv]
    [Cq 0   ] [lam] = [Qd     ]

from the state ``(q, qd)``: frames, body vectors, constraint rows, mass blocks, the quadratic
velocity and gravity forces, and the LU solve, dense or in band storage. The caller adds the
forces of force elements (``extra``), the drivers' ``f''`` and the rotation drivers' motions,
which come from Python objects, and solves the system of a model whose bandwidth is too large
for band storage itself (SuperLU).

Every intermediate array lives in a *workspace* (:func:`workspace`): the integrator loop makes
one per run segment and evaluates thousands of right-hand sides without allocating; a single
call (:func:`planar_accelerations`, :func:`spatial_accelerations`) makes its own.

``status``: 0 solved, 1 singular matrix (dependent rows), 2 non-finite state.
"""

from __future__ import annotations

import numpy as np

from mbd3d.compiled import jit
from mbd3d.compiled.bodies import (body_vectors_into, planar_frames_into,
                                   planar_mass_blocks_into, spatial_frames_into,
                                   spatial_mass_blocks_into, spatial_quadratic_velocity_into)
from mbd3d.compiled.dense import solve_banded_pattern_into, solve_pattern_into
from mbd3d.compiled.rows import constraint_rows_into, row_work_size

SOLVED, SINGULAR, NOT_FINITE = 0, 1, 2
#: layouts of the augmented matrix (see mbd3d.linalg): solved here, or by the caller (SuperLU)
DENSE, BANDED, SPARSE = 0, 1, 2


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
def workspace(spatial: bool, n_bodies: int, n_vectors: int, n_rows: int, nnz: int,
              layout: int, kl: int, ku: int):
    """Every intermediate array of :func:`accelerations_into` for a model of these sizes."""
    nc, dim = (6, 3) if spatial else (3, 2)
    n_rot = nc - dim
    b = n_bodies + 1
    n = n_bodies * nc
    size = n + n_rows
    return (np.empty((b, nc)), np.empty((b, nc)), np.empty((b, dim, dim)),
            np.empty((b, 3, n_rot)), np.empty((b, 3)), np.empty(b),
            np.empty((b if spatial else 0, 3, 3)), np.empty((b, 3)),
            np.empty((n_vectors, dim)), np.empty((n_vectors, dim, n_rot)),
            np.empty((n_vectors, dim)), np.empty((n_vectors, dim)),
            np.empty(n_rows), np.empty(nnz), np.empty(n_rows), np.empty(n_rows),
            np.empty(row_work_size(dim, n_rot)), np.empty((n_bodies, nc, nc)),
            np.empty(size), np.empty(n_bodies * nc * nc + 2 * nnz),
            np.empty((size, size) if layout == DENSE else (0, 0)),
            np.empty((2 * kl + ku + 1) * size if layout == BANDED else 0), np.empty(size),
            np.empty(size))


@jit
def _finite(x: np.ndarray) -> bool:
    for value in x:
        if not abs(value) < np.inf:
            return False
    return True


@jit
def accelerations_into(work, spatial, q, qd, charts, extra, mass, inertia, weight, code, bi,
                       bj, first_row, slots, coordinate, motion, vector_bodies, vector_local,
                       n_rows, phi, driver_rows, driver_acceleration, destination, nnz,
                       layout, rows, cols, flat, kl, ku, perm, entry_scale, scale,
                       pivot_tolerance):
    """Solve the augmented equations at ``(q, qd)`` in the workspace ``work``.

    Returns the status; ``x = (qdd, lam)`` is ``work[23]``, the matrix entries in the
    pattern's order ``work[19]`` and the right-hand side ``work[18]`` (what the caller solves
    for the ``SPARSE`` layout). ``extra`` (n,): generalized forces of the force elements;
    ``weight`` (n,): gravity; ``inertia``: tensors (b, 3, 3) (planar bodies: the entry about
    the normal); ``charts``: reference rotations of spatial bodies.
    """
    (Q, Qd, A, axes, omega, kappa, Gb, omega_bar, s, J, v, a, C, data, gamma, nu, row_work,
     blocks, rhs, values, matrix, band, permuted, x) = work
    if not (_finite(q) and _finite(qd)):
        return NOT_FINITE
    n = q.shape[0]
    n_bodies = mass.shape[0]
    padded_into(q, Q)
    padded_into(qd, Qd)
    for i in range(n):
        rhs[i] = weight[i] + extra[i]
    if spatial:
        spatial_frames_into(Q, Qd, charts, True, A, axes, omega, kappa, Gb, omega_bar)
        spatial_mass_blocks_into(Gb, mass, inertia, blocks)
        spatial_quadratic_velocity_into(Gb, omega_bar, kappa, inertia, rhs)
    else:
        planar_frames_into(Q, Qd, True, A, axes, omega, kappa)
        planar_mass_blocks_into(mass, inertia, blocks)
    body_vectors_into(A, axes, omega, kappa, vector_bodies, vector_local, True, s, J, v, a)
    constraint_rows_into(code, bi, bj, first_row, slots, coordinate, motion, phi, n_rows, Q,
                         Qd, s, J, v, a, destination, False, True, True, False, C, data, gamma,
                         nu, row_work)
    for k in range(driver_rows.shape[0]):
        gamma[driver_rows[k]] += driver_acceleration[k]
    for i in range(n_rows):
        rhs[n + i] = gamma[i]
    n_blocks = blocks.size
    flat_blocks = blocks.reshape(n_blocks)
    for i in range(n_blocks):
        values[i] = flat_blocks[i]
    for i in range(nnz):
        values[n_blocks + i] = data[i]
        values[n_blocks + nnz + i] = data[i]
    if layout == DENSE:
        regular = solve_pattern_into(rows, cols, entry_scale, scale, values, rhs,
                                     pivot_tolerance, matrix, x)
    elif layout == BANDED:
        regular = solve_banded_pattern_into(flat, kl, ku, perm, entry_scale, scale, values,
                                            rhs, pivot_tolerance, band, permuted, x)
    else:
        return SOLVED
    return SOLVED if regular else SINGULAR


@jit
def _accelerations(spatial, q, qd, charts, extra, mass, inertia, weight, code, bi, bj,
                   first_row, slots, coordinate, motion, vector_bodies, vector_local, n_rows,
                   phi, driver_rows, driver_acceleration, destination, nnz, layout, rows, cols,
                   flat, kl, ku, perm, entry_scale, scale, pivot_tolerance):
    work = workspace(spatial, mass.shape[0], vector_bodies.shape[0], n_rows, nnz, layout, kl,
                     ku)
    status = accelerations_into(work, spatial, q, qd, charts, extra, mass, inertia, weight,
                                code, bi, bj, first_row, slots, coordinate, motion,
                                vector_bodies, vector_local, n_rows, phi, driver_rows,
                                driver_acceleration, destination, nnz, layout, rows, cols, flat,
                                kl, ku, perm, entry_scale, scale, pivot_tolerance)
    return work[23], status, work[19], work[18]


@jit
def planar_accelerations(q, qd, extra, mass, inertia, weight, code, bi, bj, first_row, slots,
                         coordinate, motion, vector_bodies, vector_local, n_rows, phi,
                         driver_rows, driver_acceleration, destination, nnz, layout, rows, cols,
                         flat, kl, ku, perm, entry_scale, scale, pivot_tolerance):
    """``(x, status, values, rhs)`` of planar bodies: ``x = (qdd, lam)`` (not solved for the
    ``SPARSE`` layout), and the augmented matrix's entries in the pattern's order with its
    right-hand side (see :func:`accelerations_into`)."""
    return _accelerations(False, q, qd, np.zeros((0, 3, 3)), extra, mass, inertia, weight,
                          code, bi, bj, first_row, slots, coordinate, motion, vector_bodies,
                          vector_local, n_rows, phi, driver_rows, driver_acceleration,
                          destination, nnz, layout, rows, cols, flat, kl, ku, perm,
                          entry_scale, scale, pivot_tolerance)


@jit
def spatial_accelerations(q, qd, charts, extra, mass, inertia, weight, code, bi, bj,
                          first_row, slots, coordinate, motion, vector_bodies, vector_local,
                          n_rows, phi, driver_rows, driver_acceleration, destination, nnz,
                          layout, rows, cols, flat, kl, ku, perm, entry_scale, scale,
                          pivot_tolerance):
    """As :func:`planar_accelerations`, for spatial bodies relative to ``charts``."""
    return _accelerations(True, q, qd, charts, extra, mass, inertia, weight, code, bi, bj,
                          first_row, slots, coordinate, motion, vector_bodies, vector_local,
                          n_rows, phi, driver_rows, driver_acceleration, destination, nnz,
                          layout, rows, cols, flat, kl, ku, perm, entry_scale, scale,
                          pivot_tolerance)
