"""The time points of kinematic analysis and inverse dynamics in one compiled call.

For a fully driven mechanism (as many independent rows as coordinates): positions by
Newton-Raphson with backtracking from a guess, then ``Cq qd = -Ct``, ``Cq qdd = Qd`` and
(inverse dynamics) ``Cq^T lam = Qe + Qv - M qdd``, all with one LU of the Jacobian at the
solved positions (dense, or banded with the rows and columns ordered along the mechanism:
:func:`mbd3d.numerics.patterns.jacobian_layout`), scaled to the model's units as
:mod:`mbd3d.numerics.linalg` scales it.
The tests and limits are those of the analyses in Python
(:func:`mbd3d.analyses.position.solve_position`, :mod:`mbd3d.analyses.kinematics`): the
residual of each row against its own limit, the half-turn branches of ``L sin(e)`` rows, the
pivot test, the reciprocal condition number of LAPACK's ``gecon`` (banded: ``gbcon``) and
the velocity guard.
A point that fails any of them returns ``FAILED``, and the caller solves it again in
Python, whose errors name the joints and rows. :func:`kinematic_points` runs a stretch of
time points, each from the second-order Taylor prediction of the last.
"""

from __future__ import annotations

import math

import numpy as np

from mbd3d.numerics.compiled import jit
from mbd3d.numerics.compiled.accelerations import (applied_forces_into, motions_at,
                                                   padded_into)
from mbd3d.numerics.compiled.bodies import (body_vectors_into, planar_frames_into,
                                            spatial_frames_into, spatial_reset_charts)
from mbd3d.numerics.compiled.dense import (band_factor, band_reciprocal_condition,
                                           band_solve_into, band_solve_transpose_into,
                                           lu_factor, lu_solve_into, lu_solve_transpose_into,
                                           reciprocal_condition)
from mbd3d.numerics.compiled.rows import (GEAR, GEAR_MESH, ROTATION, constraint_rows_into,
                                          mesh_phase)

SOLVED, FAILED = 0, 1
#: largest velocity residual accepted at a time point, relative to the velocities' own size
#: (the guard of both paths: mbd3d.analyses.kinematics takes it from here)
VELOCITY_TOLERANCE = 1e-10


@jit
def branch_cosines_into(code, bi, bj, first_row, slots, motion, real, phi, Q, s, cosine,
                        amplitude) -> None:
    """``cos(e)`` and ``L`` of every row of the form ``L sin(e)`` (the spatial rotation
    drivers' ``sin(theta - f)``, the planar gear pairs' ``|d| sin(psi - phi)``, the spatial
    meshes' ``size sin(Phi)``; see :mod:`.rows`) into ``cosine`` and ``amplitude`` (m,); other
    rows get a cosine of one and no amplitude. ``Q``: coordinates of the bodies and the
    ground; ``s``: the body vectors; ``phi``: the rotation drivers' motions."""
    cosine[:] = 1.0
    amplitude[:] = 0.0
    dim, nc = s.shape[1], Q.shape[1]
    for e in range(code.shape[0]):
        k, i, j, row = code[e], bi[e], bj[e], first_row[e]
        p0, p1, p2 = slots[e, 0], slots[e, 1], slots[e, 2]
        if k == ROTATION:
            # w = A_i (f cos(f) + g sin(f)): the row is f_j . u, its cosine f_j . w
            c, sn = math.cos(phi[motion[e], 0]), math.sin(phi[motion[e], 0])
            total = 0.0
            for x in range(dim):
                total += s[p2, x] * (c * s[p0, x] + sn * s[p1, x])
            cosine[row], amplitude[row] = total, 1.0
        elif k == GEAR:
            psi = real[e, 0] * Q[i, nc - 1] + real[e, 1] * Q[j, nc - 1] - real[e, 2]
            d0 = Q[j, 0] + s[p1, 0] - Q[i, 0] - s[p0, 0]
            d1 = Q[j, 1] + s[p1, 1] - Q[i, 1] - s[p0, 1]
            size = max(math.sqrt(d0 * d0 + d1 * d1), 1e-300)
            cosine[row] = (d0 * math.cos(psi) + d1 * math.sin(psi)) / size
            amplitude[row] = size
        elif k == GEAR_MESH:
            si, sj, p3 = slots[e, 4], slots[e, 5], slots[e, 3]
            x_i = y_i = x_j = y_j = 0.0
            for x in range(dim):
                d = Q[j, x] + s[sj, x] - Q[i, x] - s[si, x]
                x_i += d * s[p0, x]
                y_i += d * s[p1, x]
                x_j += d * s[p2, x]
                y_j += d * s[p3, x]
            cosine[row] = math.cos(mesh_phase(x_i, y_i, x_j, y_j, real[e, 0], real[e, 1],
                                              real[e, 2]))
            amplitude[row] = real[e, 3]


@jit
def _frames_into(model, work, q, qd, charts, velocities) -> None:
    """Frames and body vectors of ``(q, qd)`` into ``work`` (``qd`` read with
    ``velocities``)."""
    Q, Qd = work.Q, work.Qd
    padded_into(q, Q)
    if velocities:
        padded_into(qd, Qd)
    if charts is not None:
        spatial_frames_into(Q, Qd, charts, velocities, work.A, work.axes, work.omega,
                            work.kappa, work.Gb, work.omega_bar)
    else:
        planar_frames_into(Q, Qd, velocities, work.A, work.axes, work.omega, work.kappa)
    body_vectors_into(work.A, work.axes, work.omega, work.kappa, model.vector_bodies,
                      model.vector_local, velocities, work.s, work.J, work.v, work.a)


@jit
def _position_rows_into(model, work, q, charts, cosine, amplitude, C) -> None:
    """At ``q``: the Newton residual ``C`` (m,) (``c(q) - c0 - f``, a row ``L sin(e)`` past a
    quarter turn replaced by ``sign(e) L (2 - |sin e|)``, which keeps rising to the half
    turn: see :mod:`mbd3d.analyses.position`), the Jacobian values ``work.data``, ``-Ct``
    (``work.nu``) and the branch rows' cosines."""
    _frames_into(model, work, q, q, charts, False)
    yes = q.shape[0] >= 0  # run-time flags (see accelerations_into)
    no = not yes
    constraint_rows_into(model.code, model.bi, model.bj, model.first_row, model.slots,
                         model.coordinate, model.motion, model.real, model.curves, work.phi,
                         model.n_rows, work.Q, work.Q, work.s, work.J, work.v, work.a,
                         model.destination, yes, yes, no, yes, C, work.data, work.gamma,
                         work.nu, work.row_work, work.row_jacobian)
    driver_rows, drivers = model.driver_rows, work.drivers
    for k in range(driver_rows.shape[0]):
        C[driver_rows[k]] -= drivers[k, 0]
        work.nu[driver_rows[k]] = drivers[k, 1]
    branch_cosines_into(model.code, model.bi, model.bj, model.first_row, model.slots,
                        model.motion, model.real, work.phi, work.Q, work.s, cosine, amplitude)
    for r in range(C.shape[0]):
        C[r] -= model.c0[r]
        if cosine[r] < 0.0:
            sign = 1.0 if C[r] > 0.0 else (-1.0 if C[r] < 0.0 else 0.0)
            C[r] = sign * (2.0 * amplitude[r] - abs(C[r]))


@jit
def _relative_norm(C, row_scale) -> float:
    total = 0.0
    for r in range(C.shape[0]):
        total += (C[r] / row_scale[r]) ** 2
    return math.sqrt(total)


@jit
def _converged(C, q, row_scale, length_rows, positions, tol, length_scale) -> bool:
    """Whether every row's residual is within its limit: ``tol`` relative to the model's
    scale, raised to the rounding level of the coordinates the row sums (see
    :func:`mbd3d.solve_position`)."""
    eps100 = 100.0 * np.finfo(np.float64).eps
    angles = 0.0
    lengths = 0.0
    for c in range(q.shape[0]):
        if positions[c]:
            lengths = max(lengths, abs(q[c]))
        else:
            angles = max(angles, abs(q[c]))
    limit_length = max(tol, eps100 * (1.0 + lengths / length_scale + angles))
    limit_angle = max(tol, eps100 * (1.0 + angles))
    for r in range(C.shape[0]):
        limit = limit_length if length_rows[r] else limit_angle
        if not abs(C[r]) / row_scale[r] <= limit:
            return False
    return True


@jit
def jacobian_storage(n: int, bands: np.ndarray) -> tuple:
    """Room for the factors of a Jacobian (n, n): ``(matrix, band, piv)``, the matrix dense
    where ``bands`` (the layout's ``(kl, ku)``) is negative, else in LAPACK's band storage."""
    kl, ku = bands[0], bands[1]
    if kl < 0:
        return np.empty((n, n)), np.empty(0), np.empty(n, dtype=np.int64)
    return np.empty((0, 0)), np.empty((2 * kl + ku + 1) * n), np.empty(n, dtype=np.int64)


@jit
def _factor_jacobian(model, data, sign, scales, factors):
    """``diag(r) (sign Cq) diag(c)`` factored into ``factors`` (``sign`` per row: -1 flips a
    branch row's Newton direction; ``r``, ``c``: the first two ``scales``), densely or, with
    the rows and columns in the order of the layout of ``scales`` (see
    :func:`mbd3d.numerics.patterns.jacobian_layout`), in band storage. Returns ``(regular,
    |.|_1)``."""
    row_factor, column_factor, flat, bands = scales[0], scales[1], scales[6], scales[7]
    matrix, band, piv = factors
    n = piv.shape[0]
    banded = band.shape[0] > 0
    if banded:
        band[:] = 0.0
    else:
        matrix[:, :] = 0.0
    sums = np.zeros(n)
    rows, cols = model.jac_rows, model.jac_cols
    for p in range(rows.shape[0]):
        r, c = rows[p], cols[p]
        value = sign[r] * data[p] * row_factor[r] * column_factor[c]
        sums[c] += abs(value)
        if banded:
            band[flat[p]] = value
        else:
            matrix[r, c] = value
    if banded:
        pivots, regular = band_factor(band, n, bands[0], bands[1], model.pivot_tolerance)
    else:
        pivots, regular = lu_factor(matrix, model.pivot_tolerance)
    piv[:] = pivots
    return regular, (sums.max() if n else 0.0)


@jit
def _conditioning(scales, factors, norm) -> float:
    """The reciprocal condition number of the factored matrix (``gecon``'s or ``gbcon``'s
    estimate)."""
    matrix, band, piv = factors
    if band.shape[0] == 0:
        return reciprocal_condition(matrix, norm)
    bands = scales[7]
    return band_reciprocal_condition(band, piv.shape[0], bands[0], bands[1], piv, norm)


@jit
def _solve_scaled(scales, factors, b, x, transpose) -> None:
    """``x`` of ``A x = b`` (``transpose``: ``A^T x = b``) from the factors of the scaled
    ``S = R A C``: ``x = C S^-1 R b``, or ``R S^-T C b``; banded, ``S``'s rows and columns
    are taken in the layout's order (``row_at``, ``col_at``: each one's place)."""
    row_factor, column_factor, row_at, col_at = scales[0], scales[1], scales[4], scales[5]
    matrix, band, piv = factors
    inner, outer = (column_factor, row_factor) if transpose else (row_factor, column_factor)
    n = x.shape[0]
    if band.shape[0] == 0:
        for i in range(n):
            x[i] = inner[i] * b[i]
        if transpose:
            lu_solve_transpose_into(matrix, piv, x)
        else:
            lu_solve_into(matrix, piv, x)
        for i in range(n):
            x[i] *= outer[i]
        return
    into, back = (col_at, row_at) if transpose else (row_at, col_at)
    y = np.empty(n)
    for i in range(n):
        y[into[i]] = inner[i] * b[i]
    kl, ku = scales[7][0], scales[7][1]
    if transpose:
        band_solve_transpose_into(band, n, kl, ku, piv, y)
    else:
        band_solve_into(band, n, kl, ku, piv, y)
    for i in range(n):
        x[i] = outer[i] * y[back[i]]


@jit
def newton_into(model, work, q, charts, scales, tol, length_scale, max_iterations, factors):
    """Solve ``C(q, t) = 0`` from ``q`` (overwritten), the motions already in ``work``:
    Newton steps shortened by halving until the rows' norm decreases (the iteration of
    :func:`mbd3d.solve_position`), each factoring the Jacobian into ``factors``. Returns
    whether it converged; ``work.data`` and ``work.nu`` then hold ``Cq`` and ``-Ct`` at the
    solution."""
    n, m = q.shape[0], model.n_rows
    cosine, amplitude, sign = np.empty(m), np.empty(m), np.empty(m)
    C, C_try, dq, q_try = np.empty(m), np.empty(m), np.empty(n), np.empty(n)
    row_scale = model.row_scale
    _position_rows_into(model, work, q, charts, cosine, amplitude, C)
    norm = _relative_norm(C, row_scale)
    for iteration in range(max_iterations + 1):
        if _converged(C, q, row_scale, scales[2], scales[3], tol, length_scale):
            return True
        if iteration == max_iterations:
            return False
        for r in range(m):
            sign[r] = -1.0 if cosine[r] < 0.0 else 1.0
            C_try[r] = -C[r]
        regular, _ = _factor_jacobian(model, work.data, sign, scales, factors)
        if not regular:
            return False
        _solve_scaled(scales, factors, C_try, dq, False)
        step = 1.0
        while True:
            for c in range(n):
                q_try[c] = q[c] + step * dq[c]
            _position_rows_into(model, work, q_try, charts, cosine, amplitude, C_try)
            norm_try = _relative_norm(C_try, row_scale)
            if norm_try < (1.0 - 1e-4 * step) * norm:  # False for NaN
                break
            step *= 0.5
            if step < 1e-6:
                return False
        q[:] = q_try
        C[:] = C_try
        norm = norm_try
    return False


@jit
def velocities_regular(model, data, nu, qd) -> bool:
    """Whether ``Cq qd = -Ct`` holds to :data:`VELOCITY_TOLERANCE` of the size of its
    terms, each row over its scale (the velocity guard of
    :mod:`mbd3d.analyses.kinematics`), and ``qd`` is finite."""
    m = model.n_rows
    terms, residual = np.abs(nu), -nu
    rows, cols = model.jac_rows, model.jac_cols
    for p in range(rows.shape[0]):
        product = data[p] * qd[cols[p]]
        terms[rows[p]] += abs(product)
        residual[rows[p]] += product
    size = 0.0
    for r in range(m):
        size = max(size, terms[r] / model.row_scale[r])
    for c in range(qd.shape[0]):
        if not abs(qd[c]) < np.inf:
            return False
    for r in range(m):
        if not abs(residual[r]) / model.row_scale[r] <= VELOCITY_TOLERANCE * size:
            return False
    return True


@jit
def _accelerations_into(model, work, t, q, qd, charts, forces, extra) -> bool:
    """``Qd`` at ``(q, qd)`` into ``work.gamma`` and, with ``forces``, ``Qe + Qv`` into
    ``work.rhs[:n]`` and the mass blocks into ``work.blocks``; False where a force element
    cannot be evaluated."""
    if forces:
        if not applied_forces_into(model, work, t, q, qd, charts, extra):
            return False
        body_vectors_into(work.A, work.axes, work.omega, work.kappa, model.vector_bodies,
                          model.vector_local, forces, work.s, work.J, work.v, work.a)
    else:
        _frames_into(model, work, q, qd, charts, True)
    yes = q.shape[0] >= 0
    no = not yes
    constraint_rows_into(model.code, model.bi, model.bj, model.first_row, model.slots,
                         model.coordinate, model.motion, model.real, model.curves, work.phi,
                         model.n_rows, work.Q, work.Qd, work.s, work.J, work.v, work.a,
                         model.destination, no, no, yes, no, work.C, work.data, work.gamma,
                         work.nu, work.row_work, work.row_jacobian)
    driver_rows = model.driver_rows
    for k in range(driver_rows.shape[0]):
        work.gamma[driver_rows[k]] += work.drivers[k, 2]
    return True


@jit
def kinematic_point(work, t, q, charts, scales, tol, length_scale, max_iterations, forces,
                    qd, qdd, lam, factors):
    """Positions (``q``: the guess, overwritten), velocities ``qd``, accelerations ``qdd``
    and, with ``forces``, the multipliers ``lam`` of the fully driven model of ``work`` at
    ``t``. ``scales``: ``(row factors, column factors, length rows, position coordinates,
    row places, column places, band entries, (kl, ku))`` of the model (see
    :func:`mbd3d.numerics.linalg.jacobian_scaling` and
    :func:`mbd3d.numerics.patterns.jacobian_layout`); ``tol``, the Newton tolerance relative
    to ``length_scale`` [m]; ``factors``: room for the Jacobian's factors
    (:func:`jacobian_storage`). Returns ``(status,
    reciprocal condition number of the scaled Jacobian)``: ``FAILED`` when the motions
    are not finite, Newton does not converge, the Jacobian is singular, the velocities fail
    their guard or a force cannot be evaluated."""
    model = work.model
    n = q.shape[0]
    if not motions_at(model, work, t):
        return FAILED, 0.0
    if not newton_into(model, work, q, charts, scales, tol, length_scale, max_iterations,
                       factors):
        return FAILED, 0.0
    regular, norm = _factor_jacobian(model, work.data, np.ones(n), scales, factors)
    if not regular:
        return FAILED, 0.0
    conditioning = _conditioning(scales, factors, norm)
    _solve_scaled(scales, factors, work.nu, qd, False)
    if not velocities_regular(model, work.data, work.nu, qd):
        return FAILED, conditioning
    if not _accelerations_into(model, work, t, q, qd, charts, forces, np.zeros(n)):
        return FAILED, conditioning
    _solve_scaled(scales, factors, work.gamma, qdd, False)
    if forces:
        # first block row of the augmented equations: Cq^T lam = Qe + Qv - M qdd
        nc = work.Q.shape[1]
        b = work.rhs[:n].copy()
        blocks = work.blocks
        for k in range(blocks.shape[0]):
            for i in range(nc):
                for j in range(nc):
                    b[k * nc + i] -= blocks[k, i, j] * qdd[k * nc + j]
        _solve_scaled(scales, factors, b, lam, True)
    return SOLVED, conditioning


@jit
def _same_charts(out_charts, k, back) -> bool:
    """Whether the points ``k - back`` to ``k - 1`` share their charts (always, planar)."""
    if out_charts.shape[0] == 0:
        return True
    for p in range(k - back, k - 1):
        for b in range(out_charts.shape[1]):
            for i in range(3):
                for j in range(3):
                    if out_charts[p, b, i, j] != out_charts[k - 1, b, i, j]:
                        return False
    return True


@jit
def _predict_into(t, k, out_q, out_qd, out_qdd, out_charts, guess) -> None:
    """The guess of point ``k`` from the points before: ``q + h qd`` plus the accelerations
    integrated twice, as the polynomial through the last three points' ``qdd`` (``a0 + a1 s
    + a2 s^2`` from the last point: ``a0 h^2/2 + a1 h^3/6 + a2 h^4/12``; through two where
    only two share their charts, ``qdd`` alone at the first point), or the last ``q`` where
    that is not finite. Its error is of order ``h^5``: along a robot's 1000-point trajectory
    it lands within Newton's tolerance, so a point takes no Newton step (with ``h^4`` it
    missed by a few 1e-12 and took one). It keeps Newton on the branch of the last point."""
    h = t[k] - t[k - 1]
    back = 3 if k >= 3 and _same_charts(out_charts, k, 3) else (
        2 if k >= 2 and _same_charts(out_charts, k, 2) else 1)
    h1 = t[k - 1] - t[k - 2] if back >= 2 else 1.0
    h2 = t[k - 2] - t[k - 3] if back >= 3 else 1.0
    finite = True
    for c in range(guess.shape[0]):
        a0, a1, a2 = out_qdd[k - 1, c], 0.0, 0.0
        if back >= 2:
            d1 = (out_qdd[k - 1, c] - out_qdd[k - 2, c]) / h1
            a1 = d1
            if back >= 3:
                a2 = (d1 - (out_qdd[k - 2, c] - out_qdd[k - 3, c]) / h2) / (h1 + h2)
                a1 += a2 * h1
        guess[c] = (out_q[k - 1, c] + h * out_qd[k - 1, c]
                    + h * h * (a0 / 2.0 + h * (a1 / 6.0 + h * a2 / 12.0)))
        finite = finite and abs(guess[c]) < np.inf
    if not finite:
        guess[:] = out_q[k - 1]


@jit
def kinematic_points(work, t, start, stop, q, charts, turns, settings, forces, reference,
                     out_q, out_qd, out_qdd, out_lam, out_charts, out_turns):
    """Solve the time points ``t[start:stop]`` with :func:`kinematic_point` into the rows of
    ``out_q``, ``out_qd``, ``out_qdd``, ``out_lam`` (with ``forces``) and, for a spatial model,
    ``out_charts`` and ``out_turns``; ``q`` is the first point's guess, each later one's the
    prediction from the point before.

    ``charts`` (spatial; None for a planar model) and ``turns`` (the charts' quaternions whose
    signs follow the motion; empty for a planar model): reset where a body's Rodrigues
    parameters pass the chart limit, in place. ``settings``: ``(scales, tol, length_scale,
    max_iterations, chart_limit, singular)``, the last the fraction of the first point's
    conditioning (``reference``, set here when ``start`` is 0) below which a position is
    singular. Returns ``(the first point not solved, reference)``: at a point that fails,
    or is singular, the charts and turns are left as before it, for the caller to solve it
    in Python."""
    scales, tol, length_scale, max_iterations, chart_limit, singular = settings
    n = q.shape[0]
    guess, qd, qdd, lam = q.copy(), np.empty(n), np.empty(n), np.empty(n)
    saved_charts, saved_turns = np.empty((0, 3, 3)), turns.copy()
    factors = jacobian_storage(n, scales[7])
    for k in range(start, stop):
        if k > start:
            _predict_into(t, k, out_q, out_qd, out_qdd, out_charts, guess)
        if charts is not None:
            saved_charts = charts.copy()
            saved_turns[:] = turns
            spatial_reset_charts(guess, np.zeros(0), charts, chart_limit, turns)
        status, conditioning = kinematic_point(work, t[k], guess, charts, scales, tol,
                                               length_scale, max_iterations, forces, qd, qdd,
                                               lam, factors)
        if status == SOLVED and k == 0:
            reference = conditioning
        if status != SOLVED or conditioning < singular * reference:
            if charts is not None:
                charts[:] = saved_charts
                turns[:] = saved_turns
            return k, reference
        out_q[k], out_qd[k], out_qdd[k] = guess, qd, qdd
        if forces:
            out_lam[k] = lam
        if charts is not None:
            out_charts[k], out_turns[k] = charts, turns
    return stop, reference
