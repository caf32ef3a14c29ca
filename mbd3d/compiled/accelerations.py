"""The augmented equations of motion in one compiled call:

    [M  Cq^T] [qdd]   [Qe + Qv]
    [Cq 0   ] [lam] = [Qd     ]

from the state ``(q, qd)``: frames, body vectors, constraint rows, mass blocks, the quadratic
velocity and gravity forces, and (for a dense model) the LU solve. The caller adds the forces
of force elements (``extra``), the drivers' ``f''`` and the rotation drivers' motions, which
come from Python objects, and solves a sparse model's system itself (banded LAPACK).

``status``: 0 solved, 1 singular matrix (dependent rows), 2 non-finite state.
"""

from __future__ import annotations

import numpy as np

from mbd3d.compiled import jit
from mbd3d.compiled.bodies import (body_vectors, planar_frames, planar_mass_blocks,
                                   spatial_frames, spatial_mass_blocks,
                                   spatial_quadratic_velocity)
from mbd3d.compiled.dense import solve_banded_pattern, solve_pattern
from mbd3d.compiled.rows import constraint_rows

SOLVED, SINGULAR, NOT_FINITE = 0, 1, 2
#: layouts of the augmented matrix (see mbd3d.linalg): solved here, or by the caller (SuperLU)
DENSE, BANDED, SPARSE = 0, 1, 2


@jit
def padded(x: np.ndarray, n_coords: int) -> np.ndarray:
    """``x`` (n,) as rows of ``n_coords`` with a zero row for the ground last."""
    n_bodies = x.shape[0] // n_coords
    out = np.zeros((n_bodies + 1, n_coords))
    for b in range(n_bodies):
        for c in range(n_coords):
            out[b, c] = x[b * n_coords + c]
    return out


@jit
def _finite(x: np.ndarray) -> bool:
    for value in x:
        if not abs(value) < np.inf:
            return False
    return True


@jit
def _solve(Q, Qd, A, axes, omega, kappa, blocks, forces, code, bi, bj, first_row, slots,
           coordinate, motion, vector_bodies, vector_local, n_rows, phi, driver_rows,
           driver_acceleration, destination, nnz, layout, rows, cols, flat, kl, ku, perm,
           entry_scale, scale, pivot_tolerance):
    s, J, v, a = body_vectors(A, axes, omega, kappa, vector_bodies, vector_local, True)
    _, data, gamma, _ = constraint_rows(code, bi, bj, first_row, slots, coordinate, motion,
                                        phi, n_rows, Q, Qd, s, J, v, a, destination, nnz,
                                        False, True, True, False)
    for k in range(driver_rows.shape[0]):
        gamma[driver_rows[k]] += driver_acceleration[k]
    n_blocks = blocks.size
    values = np.empty(n_blocks + 2 * nnz)
    values[:n_blocks] = blocks.ravel()
    values[n_blocks:n_blocks + nnz] = data
    values[n_blocks + nnz:] = data
    rhs = np.concatenate((forces, gamma))
    if layout == DENSE:
        x, regular = solve_pattern(rows, cols, entry_scale, scale, values, rhs, pivot_tolerance)
    elif layout == BANDED:
        x, regular = solve_banded_pattern(flat, kl, ku, perm, entry_scale, scale, values, rhs,
                                          pivot_tolerance)
    else:
        return np.empty(0), SOLVED, values, rhs
    return x, SOLVED if regular else SINGULAR, values, rhs


@jit
def planar_accelerations(q, qd, extra, mass, inertia, weight, code, bi, bj, first_row, slots,
                         coordinate, motion, vector_bodies, vector_local, n_rows, phi,
                         driver_rows, driver_acceleration, destination, nnz, layout, rows, cols,
                         flat, kl, ku, perm, entry_scale, scale, pivot_tolerance):
    """``(x, status, values, rhs)``: ``x = (qdd, lam)`` (empty for the ``SPARSE`` layout), and
    the augmented matrix's entries in the pattern's order with its right-hand side.
    ``extra`` (n,): generalized forces of the force elements; ``weight`` (n,): gravity."""
    if not (_finite(q) and _finite(qd)):
        return np.empty(0), NOT_FINITE, np.empty(0), np.empty(0)
    Q, Qd = padded(q, 3), padded(qd, 3)
    A, axes, omega, kappa = planar_frames(Q, Qd, True)
    return _solve(Q, Qd, A, axes, omega, kappa, planar_mass_blocks(mass, inertia),
                  weight + extra, code, bi, bj, first_row, slots, coordinate, motion,
                  vector_bodies, vector_local, n_rows, phi, driver_rows, driver_acceleration,
                  destination, nnz, layout, rows, cols, flat, kl, ku, perm, entry_scale, scale,
                  pivot_tolerance)


@jit
def spatial_accelerations(q, qd, charts, extra, mass, inertia, weight, code, bi, bj,
                          first_row, slots, coordinate, motion, vector_bodies, vector_local,
                          n_rows, phi, driver_rows, driver_acceleration, destination, nnz,
                          layout, rows, cols, flat, kl, ku, perm, entry_scale, scale,
                          pivot_tolerance):
    """As :func:`planar_accelerations`, for spatial bodies relative to ``charts``; the
    quadratic velocity forces are added to ``weight + extra``."""
    if not (_finite(q) and _finite(qd)):
        return np.empty(0), NOT_FINITE, np.empty(0), np.empty(0)
    Q, Qd = padded(q, 6), padded(qd, 6)
    A, axes, omega, kappa, Gb, omega_bar = spatial_frames(Q, Qd, charts, True)
    forces = (weight + extra
              + spatial_quadratic_velocity(Gb, omega_bar, kappa, inertia).ravel())
    return _solve(Q, Qd, A, axes, omega, kappa, spatial_mass_blocks(Gb, mass, inertia), forces,
                  code, bi, bj, first_row, slots, coordinate, motion, vector_bodies,
                  vector_local, n_rows, phi, driver_rows, driver_acceleration, destination,
                  nnz, layout, rows, cols, flat, kl, ku, perm, entry_scale, scale,
                  pivot_tolerance)
