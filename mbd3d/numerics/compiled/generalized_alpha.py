"""Generalized-alpha's Newton iteration for one step, compiled (the method and the iteration
are described in :mod:`mbd3d.analyses.implicit`, which drives the steps).

The unknown is ``q`` at the end of the step; ``qdd = beta' (q - q_hat)`` and ``qd = qd_hat +
gamma' (q - q_hat)``. Each iteration evaluates the frames, the mass blocks, the applied
forces (:func:`~mbd3d.numerics.compiled.accelerations.applied_forces_into`) and the constraint
rows, the penalties, the residual

    r = M qdd + Cq^T (lam + p C) - Qe

(``lam += p (C + Cq dq)`` after each step ``dq``: :func:`_multipliers_step`) and the
iteration matrix ``beta' M + p Cq^T Cq (+ the applied forces' tangent)``, factors it
(dense or banded LU; SuperLU through Python for the other layouts) and updates ``q``. One call
runs the whole iteration of a step, so a step costs a few compiled iterations instead of a
dozen NumPy calls per iteration.
"""

from __future__ import annotations

import math

import numpy as np
from numba import objmode

from mbd3d.numerics.compiled import callbacks, jit, jit_calling_python
from mbd3d.numerics.compiled.accelerations import _finite, applied_forces_into, motions_at
from mbd3d.numerics.compiled.bodies import body_vectors_into
from mbd3d.numerics.compiled.dense import (band_factor, band_solve_into, lu_factor, lu_solve_into,
                                           penalty_scale)
from mbd3d.numerics.compiled.integration import _python_parts
from mbd3d.numerics.compiled.rows import constraint_rows_into
from mbd3d.numerics.compiled.structures import DENSE

#: outcomes of :func:`newton_step`
CONVERGED, NOT_CONVERGED, SINGULAR_MATRIX, NOT_FINITE = 0, 1, 2, 3


@jit_calling_python
def _callback_factor_solve(key, values, r):
    with objmode(x="float64[::1]", status="int64"):
        x, status = callbacks.factor_penalty_and_solve(key, values, r)
    return x, status


@jit
def penalties_into(model, penalty_arrays, blocks, data, beta_prime, relative_penalty, out,
                   norms, diagonal):
    """The penalties ``p`` (one per constraint row) of the augmented Lagrangian into ``out``:
    ``relative_penalty`` times the mass term ``beta' M`` per squared unit of ``Cq``, in the
    model's dimensionless units (coordinates over their scale ``s``, rows over theirs ``r``,
    masses over ``m L^2``): the mean scaled mass diagonal over the mean squared norm of the
    scaled rows that have entries, so that the ratio means the same at any size;
    ``p_i = p~ m L^2 / r_i^2``. ``norms`` (rows) and ``diagonal`` (coordinates): scratch."""
    s = penalty_arrays.coordinate_scale
    r = model.row_scale
    mass_unit = penalty_arrays.mass_unit
    jac_rows, jac_cols = model.jac_rows, model.jac_cols
    m = r.shape[0]
    norms[:] = 0.0
    for p in range(data.shape[0]):
        scaled = data[p] * s[jac_cols[p]] / r[jac_rows[p]]
        norms[jac_rows[p]] += scaled * scaled
    nc = blocks.shape[1]
    for b in range(blocks.shape[0]):
        for c in range(nc):
            k = b * nc + c
            diagonal[k] = blocks[b, c, c] * s[k] * s[k] / mass_unit
    ratio = penalty_scale(diagonal, norms)
    for i in range(m):
        out[i] = relative_penalty * beta_prime * ratio * mass_unit / (r[i] * r[i])


@jit
def iteration_values_into(penalty_arrays, beta_prime, blocks, penalty, data, jac_rows,
                          values):
    """The entries of ``beta' M + Cq^T diag(p) Cq`` in the order of the model's
    :class:`~mbd3d.numerics.patterns.PenaltyPattern` into ``values``: the mass blocks, then the
    products of every pair of Jacobian entries of one row, each added at its target."""
    target, first, second = penalty_arrays.target, penalty_arrays.first, penalty_arrays.second
    values[:] = 0.0
    nc = blocks.shape[1]
    k = 0
    for b in range(blocks.shape[0]):
        for i in range(nc):
            for j in range(nc):
                values[target[k]] += beta_prime * blocks[b, i, j]
                k += 1
    for j in range(first.shape[0]):
        values[target[k + j]] += penalty[jac_rows[first[j]]] * data[first[j]] * data[second[j]]


@jit
def factor_into(penalty_arrays, values, extra, matrix, band, piv, reference) -> bool:
    """Factor ``D A D`` (``D`` the pattern's scale) of the matrix with entries ``values``, plus
    ``extra`` (already scaled, in the storage of the layout: (n, n) dense or the band; empty
    for none), into ``matrix`` (dense) or ``band``, row interchanges into ``piv``; returns
    whether it is regular: every pivot above ``pivot_tolerance`` times the largest entry of
    its own column before factoring. The test is local because the pivots of ``beta' M +
    Cq^T p Cq`` span the penalty ratio times the spread of the masses by design, and a long
    chain spreads them further (a test against the largest pivot refused a 1000-link chain
    whose smallest pivot was still 1e-10 of its column, 1e4 times the tolerance).
    ``reference`` (coordinates): scratch."""
    pattern = penalty_arrays
    if pattern.layout == DENSE:
        matrix[:, :] = 0.0
        for p in range(values.shape[0]):
            matrix[pattern.rows[p], pattern.cols[p]] = values[p] * pattern.entry_scale[p]
        if extra.shape[0]:
            flat = matrix.ravel()
            for i in range(extra.shape[0]):
                flat[i] += extra[i]
        size = matrix.shape[0]
        reference[:] = 0.0
        for i in range(size):
            for j in range(size):
                reference[j] = max(reference[j], abs(matrix[i, j]))
        interchanges, regular = lu_factor(matrix, 0.0)
        for k in range(size):
            regular = regular and abs(matrix[k, k]) > pattern.pivot_tolerance * reference[k]
    else:
        band[:] = 0.0
        for p in range(values.shape[0]):
            band[pattern.flat[p]] = values[p] * pattern.entry_scale[p]
        for i in range(extra.shape[0]):
            band[i] += extra[i]
        size, rows = pattern.scale.shape[0], 2 * pattern.kl + pattern.ku + 1
        reference[:] = 0.0
        for j in range(size):
            for i in range(j * rows, (j + 1) * rows):
                reference[j] = max(reference[j], abs(band[i]))
        interchanges, regular = band_factor(band, size, pattern.kl, pattern.ku, 0.0)
        diagonal = pattern.kl + pattern.ku
        for k in range(size):
            regular = regular and (abs(band[k * rows + diagonal])
                                   > pattern.pivot_tolerance * reference[k])
    piv[:] = interchanges
    return regular


@jit
def solve_factored(penalty_arrays, matrix, band, piv, b, x) -> None:
    """``x = A^-1 b`` from the factors of :func:`factor_into`."""
    pattern = penalty_arrays
    scale = pattern.scale
    n = scale.shape[0]
    if pattern.layout == DENSE:
        for i in range(n):
            x[i] = scale[i] * b[i]
        lu_solve_into(matrix, piv, x)
        for i in range(n):
            x[i] *= scale[i]
    else:
        permuted = np.empty(n)
        perm = pattern.perm
        for i in range(n):
            permuted[i] = scale[perm[i]] * b[perm[i]]
        band_solve_into(band, n, pattern.kl, pattern.ku, piv, permuted)
        for i in range(n):
            x[perm[i]] = scale[perm[i]] * permuted[i]


@jit
def log_abs_determinant(penalty_arrays, matrix, band) -> float:
    """``log |det A|`` from the factors of :func:`factor_into` (``A``, not ``D A D``)."""
    pattern = penalty_arrays
    n = pattern.scale.shape[0]
    total = 0.0
    rows = 2 * pattern.kl + pattern.ku + 1
    for k in range(n):
        pivot = matrix[k, k] if pattern.layout == DENSE else band[k * rows + pattern.kl
                                                                  + pattern.ku]
        total += math.log(abs(pivot)) - 2.0 * math.log(pattern.scale[k])
    return total


@jit
def _residual_into(model, blocks, qdd, rhs, data, lam_effective, r) -> None:
    """``r = M qdd + Cq^T lam_eff - Qe`` (``Qe + Qv`` in ``rhs[:n]``)."""
    nc = blocks.shape[1]
    for b in range(blocks.shape[0]):
        for i in range(nc):
            total = 0.0
            for j in range(nc):
                total += blocks[b, i, j] * qdd[b * nc + j]
            r[b * nc + i] = total - rhs[b * nc + i]
    for p in range(data.shape[0]):
        r[model.jac_cols[p]] += data[p] * lam_effective[model.jac_rows[p]]


@jit
def _multipliers_step(model, data, C, penalty, dq, lam, linear) -> None:
    """The method of multipliers' update after a Newton step ``dq``: ``lam += p (C + Cq dq)``,
    the constraints linearised at the iterate, which is the multipliers' own Newton step.
    Taken with ``C`` at the new iterate instead (its quadratic remainder only), the update
    counts that remainder twice in the next residual, whose step then flips the constraints'
    sign rather than closing them: a step more per time step (3.7 Newton iterations a step
    on the free slider-crank at h = 1e-3, 2.9 with this update, 2.1 with convergence also
    tested at the iterate reached). ``linear``: scratch (m,)."""
    m = linear.shape[0]
    linear[:] = C[:m]
    for p in range(data.shape[0]):
        linear[model.jac_rows[p]] += data[p] * dq[model.jac_cols[p]]
    for i in range(m):
        lam[i] += penalty[i] * linear[i]


@jit
def last_mass_blocks(work) -> np.ndarray:
    """A copy of the mass blocks of the workspace's last evaluation."""
    return work.blocks.copy()


@jit
def newton_step(work, penalty_arrays, key, t, q, q_hat, qd_hat, beta_prime, gamma_prime, lam,
                charts, extra, python_factor, relative_penalty, newton_tol, projection_tol,
                max_iterations, penalty, lam_effective, matrix, band, piv, counters):
    """Newton iterations for ``q`` at the end of a step (see the module doc); ``q`` (the
    predictor on entry) and ``lam`` are updated in place. Returns the outcome
    (:data:`CONVERGED`, ...).

    On convergence ``lam_effective = lam + p C`` at the last iterate, ``penalty`` the
    penalties and the factors of the last iteration matrix are in ``matrix``/``band`` and
    ``piv`` (or, with ``python_factor``, kept by Python: SuperLU, or an ``extra`` tangent
    outside the band). ``extra``: the applied forces' tangent ``K + gamma' D`` in the scaled
    storage of the layout (empty: none). ``counters``: Newton iterations, factorizations.
    ``charts``: None for a planar model (no spatial code compiled).
    """
    model = work.model
    n = model.n
    m = model.n_rows
    qd, qdd, r, dq = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    norms, linear = np.empty(m), np.empty(m)  # the callees' scratch
    diagonal, reference = np.empty(n), np.empty(n)
    values = np.empty(penalty_arrays.rows.shape[0])
    C, data, rhs, blocks = work.C, work.data, work.rhs, work.blocks
    s = penalty_arrays.coordinate_scale
    yes = n >= 0  # run-time flags (see applied_forces_into)
    no = not yes
    previous, settled = np.inf, False
    for iteration in range(max_iterations):
        for i in range(n):
            qdd[i] = beta_prime * (q[i] - q_hat[i])
            qd[i] = qd_hat[i] + gamma_prime * (q[i] - q_hat[i])
        forces, drivers, phi = _python_parts(model, key, t, q, qd, charts)
        if not model.python_parts:
            if not motions_at(model, work, t):
                return NOT_FINITE
            drivers, phi = work.drivers, work.phi
        if not (_finite(q) and applied_forces_into(model, work, t, q, qd, charts, forces)):
            return NOT_FINITE
        body_vectors_into(work.A, work.axes, work.omega, work.kappa, model.vector_bodies,
                          model.vector_local, no, work.s, work.J, work.v, work.a)
        constraint_rows_into(model.code, model.bi, model.bj, model.first_row, model.slots,
                             model.coordinate, model.motion, model.real, model.curves, phi, m, work.Q, work.Qd, work.s,
                             work.J, work.v, work.a, model.destination, yes, yes, no, no, C,
                             data, work.gamma, work.nu, work.row_work, work.row_jacobian)
        driver_rows = model.driver_rows
        for k in range(driver_rows.shape[0]):
            C[driver_rows[k]] -= drivers[k, 0]
        largest = 0.0
        for i in range(m):
            C[i] -= model.c0[i]
            largest = max(largest, abs(C[i]) / model.row_scale[i])
        penalties_into(model, penalty_arrays, blocks, data, beta_prime, relative_penalty,
                       penalty, norms, diagonal)
        for i in range(m):
            lam_effective[i] = lam[i] + penalty[i] * C[i]
        if settled and largest <= projection_tol:
            return CONVERGED  # the last step was small and it closed the constraints
        _residual_into(model, blocks, qdd, rhs, data, lam_effective, r)
        iteration_values_into(penalty_arrays, beta_prime, blocks, penalty, data,
                              model.jac_rows, values)
        counters[1] += 1
        if python_factor:
            x, status = _callback_factor_solve(key, values, r)
            if status != 0:
                return SINGULAR_MATRIX
            for i in range(n):
                dq[i] = -x[i]
        else:
            if not factor_into(penalty_arrays, values, extra, matrix, band, piv, reference):
                return SINGULAR_MATRIX
            solve_factored(penalty_arrays, matrix, band, piv, r, dq)
            for i in range(n):
                dq[i] = -dq[i]
        counters[0] += 1
        if not _finite(dq):
            return NOT_CONVERGED
        _multipliers_step(model, data, C, penalty, dq, lam, linear)
        size = 0.0
        for i in range(n):
            q[i] += dq[i]
            size = max(size, abs(dq[i]) / (s[i] + abs(q[i])))
        rate = size / previous if iteration else np.inf
        # near a singular configuration the multipliers converge only linearly (rate
        # a / (a + p s^2) along a small singular value s): judge the remaining error by the
        # observed rate, as for any linearly convergent iteration
        remaining = size * rate / (1.0 - rate) if rate < 1.0 else np.inf
        settled = min(size, remaining) <= newton_tol
        if settled and largest <= projection_tol:
            return CONVERGED
        if iteration >= 2 and rate > 0.9:
            return NOT_CONVERGED  # diverging or stalled: the caller shortens the step
        previous = size
    return NOT_CONVERGED
