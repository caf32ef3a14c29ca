"""The constraint primitives: the rows ``C``, their Jacobian, ``gamma`` and ``-C_t`` of every
primitive instance of a model in one loop.

Formulas of Haug, *Computer-Aided Kinematics and Dynamics of Mechanical Systems* (1989), written
against body vectors (``s = A v`` with Jacobian ``J``, rate ``v`` and acceleration term ``a``;
see :mod:`.bodies`), so that they serve planar and spatial bodies; the conventions and what each
primitive means are in :mod:`mbd3d.model.primitives`. ``d = r_j - r_i`` joins two body points,
``gamma = -(Cq qd)_q qd`` is the velocity-dependent right-hand side of the acceleration
equation. Every instance has bodies ``i`` and ``j`` (the ground is the last body row) and up to
three body vectors (``slots``: rows of the vector table).
"""

from __future__ import annotations

import math

import numpy as np

from mbd3d.numerics.compiled import jit
from mbd3d.numerics.compiled.curves import periodic_curve

#: primitive codes, in the order of mbd3d.model.primitives.PRIMITIVES
(POINT, DOT1, DOT2, DISTANCE, COORDINATE, ANGLE, ROTATION, GEAR, RACK, CAM_POINT, CAM_FACE,
 GEAR_MESH, DISC_ON_PLANE) = range(13)


@jit
def _put(data, dest, row, side, col, nc, value):
    """Jacobian entry of ``row`` for body ``side`` (0: i, 1: j), coordinate ``col``."""
    p = dest[(2 * row + side) * nc + col]
    if p >= 0:
        data[p] = value


@jit
def data_at(data, dest, row, side, col, nc):
    """The Jacobian entry :func:`_put` wrote (zero for the ground's, which are left out)."""
    p = dest[(2 * row + side) * nc + col]
    return data[p] if p >= 0 else 0.0


@jit
def _dot(x, i, y, j, dim):
    total = 0.0
    for c in range(dim):
        total += x[i, c] * y[j, c]
    return total


@jit
def _rotation_vectors(s, J, v, a, fi, gi, phi, velocities, u, uJ, uv, ua, w, wv):
    """``u = A_i (g cos(phi) - f sin(phi))`` and ``w = A_i (f cos(phi) + g sin(phi))`` of the
    rotation driver, from the parts of ``f_i`` and ``g_i`` (each is linear in them)."""
    c, sn = math.cos(phi), math.sin(phi)
    dim, n_rot = s.shape[1], J.shape[2]
    for x in range(dim):
        u[x] = c * s[gi, x] - sn * s[fi, x]
        w[x] = c * s[fi, x] + sn * s[gi, x]
        for col in range(n_rot):
            uJ[x, col] = c * J[gi, x, col] - sn * J[fi, x, col]
        if velocities:
            uv[x] = c * v[gi, x] - sn * v[fi, x]
            ua[x] = c * a[gi, x] - sn * a[fi, x]
            wv[x] = c * v[fi, x] + sn * v[gi, x]


@jit
def mesh_phase(x_i, y_i, x_j, y_j, z_i, z_j, phase):
    """Phase of a spatial gear mesh [rad], zero where the teeth mesh as in the drawing:
    ``-(z_i beta_i + z_j beta_j) - phase`` with ``beta = atan2(y, x)`` each gear's angle of the
    carrier-fixed line (see :class:`mbd3d.model.primitives.GearMesh`)."""
    return -(z_i * math.atan2(y_i, x_i) + z_j * math.atan2(y_j, x_j)) - phase


@jit
def mesh_phases(x_i, y_i, x_j, y_j, real):
    """:func:`mesh_phase` of k meshes, (k,) each, ``real`` (k, 4)."""
    out = np.empty(x_i.shape[0])
    for e in range(out.shape[0]):
        out[e] = mesh_phase(x_i[e], y_i[e], x_j[e], y_j[e], real[e, 0], real[e, 1], real[e, 2])
    return out


@jit
def _line_angle_rates(d, dd, s, v, a, si, sj, pf, pg, dim):
    """``x = d . f`` and ``y = d . g`` of a gear (slots ``pf``, ``pg``), and the rate and the
    velocity part of the second derivative of ``beta = atan2(y, x)``."""
    x = y = x1 = y1 = x2 = y2 = 0.0
    for c in range(dim):
        d2 = a[sj, c] - a[si, c]
        x += d[c] * s[pf, c]
        y += d[c] * s[pg, c]
        x1 += dd[c] * s[pf, c] + d[c] * v[pf, c]
        y1 += dd[c] * s[pg, c] + d[c] * v[pg, c]
        x2 += d2 * s[pf, c] + 2.0 * dd[c] * v[pf, c] + d[c] * a[pf, c]
        y2 += d2 * s[pg, c] + 2.0 * dd[c] * v[pg, c] + d[c] * a[pg, c]
    squared = max(x * x + y * y, 1e-300)
    rate = (x * y1 - y * x1) / squared
    return rate, (x * y2 - y * x2) / squared - rate * 2.0 * (x * x1 + y * y1) / squared


@jit
def mesh_turn_speeds(kind, bi, bj, slots, real, Q, Qd, s, v, a):
    """``|z_i beta_i'| + |z_j beta_j'|`` [rad/s] of every spatial gear mesh (zero for the other
    instances), (k,): how fast the terms of the mesh's phase change, each gear's share. Over
    a step of position analysis whose guess errs by less than their change, a phase error of
    ``pi`` (a tooth's worth of the reduced ratio) needs a change of at least ``pi``."""
    dim = s.shape[1]
    out = np.zeros(kind.shape[0])
    d = np.empty(dim)
    dd = np.empty(dim)
    for e in range(kind.shape[0]):
        if kind[e] != GEAR_MESH:
            continue
        i, j, si, sj = bi[e], bj[e], slots[e, 4], slots[e, 5]
        for x in range(dim):
            d[x] = Q[j, x] + s[sj, x] - Q[i, x] - s[si, x]
            dd[x] = Qd[j, x] + v[sj, x] - Qd[i, x] - v[si, x]
        rate_i = _line_angle_rates(d, dd, s, v, a, si, sj, slots[e, 0], slots[e, 1], dim)[0]
        rate_j = _line_angle_rates(d, dd, s, v, a, si, sj, slots[e, 2], slots[e, 3], dim)[0]
        out[e] = abs(real[e, 0] * rate_i) + abs(real[e, 1] * rate_j)
    return out


@jit
def _disc_on_plane(data, dest, row, nc, dim, n_rot, Q, s, J, v, a, slot, radius, i, j, value,
                   jacobian, gamma, C, G, omega, w, w_rate, t2):
    """A thin disc (body j, axis slot 2, its body axes slots 3 to 5) rolling without slipping
    on a fixed plane (the ground, body i: unit normal slot 0, an in-plane unit vector slot 1).

    Row 0, holonomic: the lowest rim point touches the plane, ``k . R - r n_a`` with
    ``n_a = |a x k|``. Rows 1 and 2, nonholonomic (velocity level, ``c`` = 0): the disc's
    material point at the contact, ``w = r (a_k a - k) / n_a`` from the centre, stands still
    along the plane's in-plane axes ``t_1``, ``t_2 = k x t_1``: ``t . (R' + omega x w) = 0``.
    ``omega x w`` is the rate of ``w`` frozen in the body, ``sum_m (e_m . w) e_m'``, so the
    body axes give its Jacobian, and ``gamma = -(d/dt B) q'`` from their acceleration terms.
    """
    k0, t0, pa = slot[0], slot[1], slot[2]
    a_k = a_rate = a_acc = 0.0
    for x in range(dim):
        a_k += s[pa, x] * s[k0, x]
    normal = math.sqrt(max(1.0 - a_k * a_k, 1e-300))  # |a x k|: zero for a disc lying flat
    if value:
        height = 0.0
        for x in range(dim):
            height += s[k0, x] * (Q[j, x] - Q[i, x])
        C[row] = height - radius * normal
    # the contact's offset from the centre, and the second in-plane axis
    for x in range(dim):
        w[x] = radius * (a_k * s[pa, x] - s[k0, x]) / normal
    t2[0] = s[k0, 1] * s[t0, 2] - s[k0, 2] * s[t0, 1]
    t2[1] = s[k0, 2] * s[t0, 0] - s[k0, 0] * s[t0, 2]
    t2[2] = s[k0, 0] * s[t0, 1] - s[k0, 1] * s[t0, 0]
    # the contact offset's components on the body axes (frozen in the body for B)
    share0 = s[slot[3], 0] * w[0] + s[slot[3], 1] * w[1] + s[slot[3], 2] * w[2]
    share1 = s[slot[4], 0] * w[0] + s[slot[4], 1] * w[1] + s[slot[4], 2] * w[2]
    share2 = s[slot[5], 0] * w[0] + s[slot[5], 1] * w[1] + s[slot[5], 2] * w[2]
    if jacobian:
        for x in range(dim):
            _put(data, dest, row, 0, x, nc, -s[k0, x])
            _put(data, dest, row, 1, x, nc, s[k0, x])
            _put(data, dest, row + 1, 0, x, nc, -s[t0, x])
            _put(data, dest, row + 1, 1, x, nc, s[t0, x])
            _put(data, dest, row + 2, 0, x, nc, -t2[x])
            _put(data, dest, row + 2, 1, x, nc, t2[x])
        for col in range(n_rot):
            lift = 0.0
            along_1 = 0.0
            along_2 = 0.0
            for x in range(dim):
                lift += s[k0, x] * J[pa, x, col]
                turned = (share0 * J[slot[3], x, col] + share1 * J[slot[4], x, col]
                          + share2 * J[slot[5], x, col])
                along_1 += s[t0, x] * turned
                along_2 += t2[x] * turned
            _put(data, dest, row, 1, dim + col, nc, radius * a_k / normal * lift)
            _put(data, dest, row + 1, 1, dim + col, nc, along_1)
            _put(data, dest, row + 2, 1, dim + col, nc, along_2)
    if gamma:
        for x in range(dim):
            a_rate += s[k0, x] * v[pa, x]
            a_acc += s[k0, x] * a[pa, x]
        G[row] = -radius * (a_rate * a_rate / normal ** 3 + a_k * a_acc / normal)
        # omega = (sum_m e_m x e_m') / 2 from the body axes
        for x in range(dim):
            omega[x] = 0.0
        for m in range(3):
            e = slot[3 + m]
            omega[0] += 0.5 * (s[e, 1] * v[e, 2] - s[e, 2] * v[e, 1])
            omega[1] += 0.5 * (s[e, 2] * v[e, 0] - s[e, 0] * v[e, 2])
            omega[2] += 0.5 * (s[e, 0] * v[e, 1] - s[e, 1] * v[e, 0])
        # w' (the contact moving round the rim): r d/dt[(a_k a - k) / n_a]
        normal_rate = -a_k * a_rate / normal
        for x in range(dim):
            w_rate[x] = (radius * (a_rate * s[pa, x] + a_k * v[pa, x]) - normal_rate * w[x]) / normal
        # d/dt(B) q' = t . V, V = sum_m (e_m . w) a_m - omega x (omega x w - w'); the bracket
        # goes in place of w'
        for x in range(3):
            w_rate[x] = (omega[(x + 1) % 3] * w[(x + 2) % 3] - omega[(x + 2) % 3] * w[(x + 1) % 3]
                         - w_rate[x])
        along_1 = 0.0
        along_2 = 0.0
        for x in range(3):
            turned = (share0 * a[slot[3], x] + share1 * a[slot[4], x] + share2 * a[slot[5], x]
                      - (omega[(x + 1) % 3] * w_rate[(x + 2) % 3]
                         - omega[(x + 2) % 3] * w_rate[(x + 1) % 3]))
            along_1 += s[t0, x] * turned
            along_2 += t2[x] * turned
        G[row + 1] = -along_1
        G[row + 2] = -along_2


@jit
def row_work_size(dim: int, n_rot: int) -> int:
    """Length of the scratch array of :func:`constraint_rows_into`."""
    return 7 * dim


@jit
def constraint_rows(kind, bi, bj, first_row, slots, coordinate, motion, real, curves, phi,
                    n_rows, Q, Qd, s, J, v, a, dest, nnz, value, jacobian, gamma, rate):
    """Evaluate every instance: returns ``c (m,)``, the Jacobian values at positions ``dest``
    (``nnz``,), ``gamma (m,)`` and ``-C_t`` of time-dependent rows (m,), with zero-length
    arrays for the parts not asked for (see :func:`constraint_rows_into`)."""
    dim = s.shape[1]
    C = np.empty(n_rows if value else 0)
    data = np.empty(nnz if jacobian else 0)
    G = np.empty(n_rows if gamma else 0)
    nu = np.empty(n_rows if rate else 0)
    work = np.empty(row_work_size(dim, Q.shape[1] - dim))
    constraint_rows_into(kind, bi, bj, first_row, slots, coordinate, motion, real, curves, phi,
                         n_rows, Q, Qd, s, J, v, a, dest, value, jacobian, gamma, rate, C, data,
                         G, nu,
                         work, np.empty((dim, Q.shape[1] - dim)))
    return C, data, G, nu


@jit
def constraint_rows_into(kind, bi, bj, first_row, slots, coordinate, motion, real, curves, phi,
                         n_rows, Q, Qd, s, J, v, a, dest, value, jacobian, gamma, rate, C, data, G,
                         nu, work, uJ):
    """Evaluate every instance into ``C`` (m,) (``c(q)`` only: the caller subtracts the rows'
    constants and prescribed motions), ``data`` (the Jacobian values at positions ``dest``),
    ``G`` (``gamma``, m) and ``nu`` (``-C_t`` of time-dependent rows, zero elsewhere), each
    when asked for; ``work``: scratch of :func:`row_work_size`, ``uJ`` of (dim, n_rot).

    ``Q``, ``Qd`` (bodies + ground, n_coords): coordinates and rates (``Qd`` is read only for
    ``gamma``); ``real`` (k, 4): real parameters of the instances (gears, racks, cams);
    ``curves``: the cams' periodic curves (see :mod:`.curves`);
    ``phi`` (k_motion, 3): ``(f, f', f'')`` of the rotation drivers' motions.
    """
    dim = s.shape[1]
    nc = Q.shape[1]
    n_rot = nc - dim
    if value:
        C[:] = 0.0
    if jacobian:
        data[:] = 0.0
    if gamma:
        G[:] = 0.0
    if rate:
        nu[:] = 0.0
    d = work[0:dim]
    dd = work[dim:2 * dim]
    u = work[2 * dim:3 * dim]
    uv = work[3 * dim:4 * dim]
    ua = work[4 * dim:5 * dim]
    w = work[5 * dim:6 * dim]
    wv = work[6 * dim:7 * dim]
    si = sj = 0
    for e in range(kind.shape[0]):
        k, i, j, row = kind[e], bi[e], bj[e], first_row[e]
        p0, p1, p2 = slots[e, 0], slots[e, 1], slots[e, 2]
        if (k == POINT or k == DOT2 or k == DISTANCE or k == GEAR or k == RACK
                or k == CAM_POINT or k == CAM_FACE or k == GEAR_MESH):
            # the body points: slots (p0, p1) for a point pair, (p1, p2) after dot-2's vector,
            # (p2, p1) after a flat face's normal (the cam's centre on body i is p2), (p4, p5)
            # after a gear mesh's four vectors
            if k == DOT2 or k == RACK:
                si, sj = p1, p2
            elif k == CAM_FACE:
                si, sj = p2, p1
            elif k == GEAR_MESH:
                si, sj = slots[e, 4], slots[e, 5]
            else:
                si, sj = p0, p1
            for x in range(dim):
                d[x] = Q[j, x] + s[sj, x] - Q[i, x] - s[si, x]
                if gamma:
                    dd[x] = Qd[j, x] + v[sj, x] - Qd[i, x] - v[si, x]
        if k == POINT:
            for x in range(dim):
                r = row + x
                if value:
                    C[r] = -d[x]
                if jacobian:
                    _put(data, dest, r, 0, x, nc, 1.0)
                    _put(data, dest, r, 1, x, nc, -1.0)
                    for col in range(n_rot):
                        _put(data, dest, r, 0, dim + col, nc, J[si, x, col])
                        _put(data, dest, r, 1, dim + col, nc, -J[sj, x, col])
                if gamma:
                    G[r] = a[sj, x] - a[si, x]
        elif k == DOT1:
            if value:
                C[row] = _dot(s, p0, s, p1, dim)
            if jacobian:
                for col in range(n_rot):
                    di = 0.0
                    dj = 0.0
                    for x in range(dim):
                        di += s[p1, x] * J[p0, x, col]
                        dj += s[p0, x] * J[p1, x, col]
                    _put(data, dest, row, 0, dim + col, nc, di)
                    _put(data, dest, row, 1, dim + col, nc, dj)
            if gamma:
                G[row] = -(_dot(s, p1, a, p0, dim) + _dot(s, p0, a, p1, dim)
                           + 2.0 * _dot(v, p0, v, p1, dim))
        elif k == DOT2 or k == RACK:
            if value:
                total = 0.0
                for x in range(dim):
                    total += s[p0, x] * d[x]
                C[row] = total
            if jacobian:
                for x in range(dim):
                    _put(data, dest, row, 0, x, nc, -s[p0, x])
                    _put(data, dest, row, 1, x, nc, s[p0, x])
                for col in range(n_rot):
                    di = 0.0
                    dj = 0.0
                    for x in range(dim):
                        di += d[x] * J[p0, x, col] - s[p0, x] * J[si, x, col]
                        dj += s[p0, x] * J[sj, x, col]
                    _put(data, dest, row, 0, dim + col, nc, di)
                    _put(data, dest, row, 1, dim + col, nc, dj)
            if gamma:
                total = 0.0
                for x in range(dim):
                    total += (d[x] * a[p0, x] + 2.0 * v[p0, x] * dd[x]
                              + s[p0, x] * (a[sj, x] - a[si, x]))
                G[row] = -total
            if k == RACK:
                # planar rack (i) and pinion (j): plus radius * (theta_j - theta_i), linear in
                # q, so nothing is added to gamma
                radius = real[e, 0]
                if value:
                    C[row] += radius * (Q[j, nc - 1] - Q[i, nc - 1])
                if jacobian:
                    _put(data, dest, row, 0, nc - 1, nc,
                         data_at(data, dest, row, 0, nc - 1, nc) - radius)
                    _put(data, dest, row, 1, nc - 1, nc,
                         data_at(data, dest, row, 1, nc - 1, nc) + radius)
        elif k == DISTANCE:
            length = 0.0
            for x in range(dim):
                length += d[x] * d[x]
            # a zero length is refused when the model is built; the floor only avoids 0/0 in
            # an iterate that passes through coincidence
            length = max(math.sqrt(length), 1e-300)
            if value:
                C[row] = length
            if jacobian:
                for x in range(dim):
                    _put(data, dest, row, 0, x, nc, -d[x] / length)
                    _put(data, dest, row, 1, x, nc, d[x] / length)
                for col in range(n_rot):
                    di = 0.0
                    dj = 0.0
                    for x in range(dim):
                        di -= d[x] * J[si, x, col]
                        dj += d[x] * J[sj, x, col]
                    _put(data, dest, row, 0, dim + col, nc, di / length)
                    _put(data, dest, row, 1, dim + col, nc, dj / length)
            if gamma:
                along = 0.0
                squared = 0.0
                relative = 0.0
                for x in range(dim):
                    along += d[x] * dd[x]
                    squared += dd[x] * dd[x]
                    relative += d[x] * (a[sj, x] - a[si, x])
                along /= length
                G[row] = -(relative / length + (squared - along * along) / length)
        elif k == COORDINATE:
            col = coordinate[e]
            if value:
                C[row] = Q[j, col]
            if jacobian:
                _put(data, dest, row, 1, col, nc, 1.0)
        elif k == ANGLE:
            # theta_j - theta_i of planar bodies: linear in q, so gamma is zero
            if value:
                C[row] = Q[j, nc - 1] - Q[i, nc - 1]
            if jacobian:
                _put(data, dest, row, 0, nc - 1, nc, -1.0)
                _put(data, dest, row, 1, nc - 1, nc, 1.0)
        elif k == GEAR:
            # planar gear pair: C = kappa (d x e(psi)), e the unit vector at the angle
            # psi = a theta_i + b theta_j - c, which the rolling of the pitch circles keeps
            # along the centre line d (see mbd3d.model.primitives.Gear)
            ra, rb, kappa = real[e, 0], real[e, 1], real[e, 3]
            psi = ra * Q[i, nc - 1] + rb * Q[j, nc - 1] - real[e, 2]
            e0, e1 = math.cos(psi), math.sin(psi)
            cross = d[0] * e1 - d[1] * e0
            along = d[0] * e0 + d[1] * e1
            if value:
                C[row] = kappa * cross
            if jacobian:
                _put(data, dest, row, 0, 0, nc, -kappa * e1)
                _put(data, dest, row, 0, 1, nc, kappa * e0)
                _put(data, dest, row, 1, 0, nc, kappa * e1)
                _put(data, dest, row, 1, 1, nc, -kappa * e0)
                _put(data, dest, row, 0, nc - 1, nc, kappa * (
                    along * ra - (J[si, 0, 0] * e1 - J[si, 1, 0] * e0)))
                _put(data, dest, row, 1, nc - 1, nc, kappa * (
                    along * rb + J[sj, 0, 0] * e1 - J[sj, 1, 0] * e0))
            if gamma:
                psi_rate = ra * Qd[i, nc - 1] + rb * Qd[j, nc - 1]
                relative = ((a[sj, 0] - a[si, 0]) * e1 - (a[sj, 1] - a[si, 1]) * e0)
                G[row] = -kappa * (relative + 2.0 * (dd[0] * e0 + dd[1] * e1) * psi_rate
                                   - cross * psi_rate * psi_rate)
        elif k == GEAR_MESH:
            # spatial gear pair: C = size sin(Phi), Phi the mesh phase of the gears' angles
            # beta = atan2(d . g, d . f) of the line d joining their centres (fixed in their
            # carrier); f, g span each gear's plane (slots p0, p1 on i; p2, p3 on j)
            z_i, z_j, size = real[e, 0], real[e, 1], real[e, 3]
            p3 = slots[e, 3]
            x_i = y_i = x_j = y_j = 0.0
            for x in range(dim):
                x_i += d[x] * s[p0, x]
                y_i += d[x] * s[p1, x]
                x_j += d[x] * s[p2, x]
                y_j += d[x] * s[p3, x]
            n_i = max(x_i * x_i + y_i * y_i, 1e-300)
            n_j = max(x_j * x_j + y_j * y_j, 1e-300)
            mesh = mesh_phase(x_i, y_i, x_j, y_j, z_i, z_j, real[e, 2])
            cosine, sine = math.cos(mesh), math.sin(mesh)
            if value:
                C[row] = size * sine
            if jacobian:
                # dPhi/dd (in u) and the coefficients of d in dPhi/df and dPhi/dg of each gear
                fi_, gi_ = z_i * y_i / n_i, -z_i * x_i / n_i
                fj_, gj_ = z_j * y_j / n_j, -z_j * x_j / n_j
                for x in range(dim):
                    u[x] = -(z_i * (x_i * s[p1, x] - y_i * s[p0, x]) / n_i
                             + z_j * (x_j * s[p3, x] - y_j * s[p2, x]) / n_j)
                    _put(data, dest, row, 0, x, nc, -size * cosine * u[x])
                    _put(data, dest, row, 1, x, nc, size * cosine * u[x])
                for col in range(n_rot):
                    di = 0.0
                    dj = 0.0
                    for x in range(dim):
                        di += d[x] * (fi_ * J[p0, x, col] + gi_ * J[p1, x, col]) - u[x] * J[si, x, col]
                        dj += d[x] * (fj_ * J[p2, x, col] + gj_ * J[p3, x, col]) + u[x] * J[sj, x, col]
                    _put(data, dest, row, 0, dim + col, nc, size * cosine * di)
                    _put(data, dest, row, 1, dim + col, nc, size * cosine * dj)
            if gamma:
                rate_i, acc_i = _line_angle_rates(d, dd, s, v, a, si, sj, p0, p1, dim)
                rate_j, acc_j = _line_angle_rates(d, dd, s, v, a, si, sj, p2, p3, dim)
                mesh_rate = -(z_i * rate_i + z_j * rate_j)
                G[row] = size * (cosine * (z_i * acc_i + z_j * acc_j) + sine * mesh_rate ** 2)
        elif k == DISC_ON_PLANE:
            _disc_on_plane(data, dest, row, nc, dim, n_rot, Q, s, J, v, a, slots[e], real[e, 0],
                           i, j, value, jacobian, gamma, C, G, u, uv, ua, wv)
        elif k == CAM_POINT:
            # follower point j on the cam's pitch curve r(phi) (polar about the cam's centre,
            # phi in the cam's frame): C = |d| - r(phi), phi = angle(d) - theta_i
            distance = max(math.sqrt(d[0] * d[0] + d[1] * d[1]), 1e-300)
            u0, u1 = d[0] / distance, d[1] / distance
            angle = math.atan2(d[1], d[0]) - Q[i, nc - 1]
            r, r1, r2 = periodic_curve(curves, int(real[e, 0]), int(real[e, 1]), angle)
            if value:
                C[row] = distance - r
            # g = u - r' w / |d| (w = u turned by 90 degrees): the pitch curve's normal
            g0, g1 = u0 + r1 * u1 / distance, u1 - r1 * u0 / distance
            if jacobian:
                _put(data, dest, row, 0, 0, nc, -g0)
                _put(data, dest, row, 0, 1, nc, -g1)
                _put(data, dest, row, 1, 0, nc, g0)
                _put(data, dest, row, 1, 1, nc, g1)
                _put(data, dest, row, 0, nc - 1, nc, r1 - g0 * J[si, 0, 0] - g1 * J[si, 1, 0])
                _put(data, dest, row, 1, nc - 1, nc, g0 * J[sj, 0, 0] + g1 * J[sj, 1, 0])
            if gamma:
                r0, r1_ = a[sj, 0] - a[si, 0], a[sj, 1] - a[si, 1]
                radial = u0 * dd[0] + u1 * dd[1]
                turning = u0 * dd[1] - u1 * dd[0]  # w . d'
                rate_phi = turning / distance - Qd[i, nc - 1]
                G[row] = -(u0 * r0 + u1 * r1_
                           + (dd[0] * dd[0] + dd[1] * dd[1] - radial * radial) / distance
                           - r2 * rate_phi * rate_phi
                           - r1 * ((u0 * r1_ - u1 * r0) / distance
                                   - 2.0 * radial * turning / (distance * distance)))
        elif k == CAM_FACE:
            # a flat face of j (unit normal n, slot p0, towards the cam) touching the cam whose
            # support function is h(psi): C = n . (c - P) - h(psi), psi = theta_j - theta_i
            # + psi_0; here d = P - c
            psi = Q[j, nc - 1] - Q[i, nc - 1] + real[e, 2]
            h, h1, h2 = periodic_curve(curves, int(real[e, 0]), int(real[e, 1]), psi)
            n0, n1 = s[p0, 0], s[p0, 1]
            if value:
                C[row] = -(n0 * d[0] + n1 * d[1]) - h
            if jacobian:
                _put(data, dest, row, 0, 0, nc, n0)
                _put(data, dest, row, 0, 1, nc, n1)
                _put(data, dest, row, 1, 0, nc, -n0)
                _put(data, dest, row, 1, 1, nc, -n1)
                _put(data, dest, row, 0, nc - 1, nc, n0 * J[si, 0, 0] + n1 * J[si, 1, 0] + h1)
                _put(data, dest, row, 1, nc - 1, nc, -(n0 * J[sj, 0, 0] + n1 * J[sj, 1, 0])
                     - (d[0] * J[p0, 0, 0] + d[1] * J[p0, 1, 0]) - h1)
            if gamma:
                rate_psi = Qd[j, nc - 1] - Qd[i, nc - 1]
                G[row] = (a[p0, 0] * d[0] + a[p0, 1] * d[1]
                          + 2.0 * (v[p0, 0] * dd[0] + v[p0, 1] * dd[1])
                          + n0 * (a[sj, 0] - a[si, 0]) + n1 * (a[sj, 1] - a[si, 1])
                          + h2 * rate_psi * rate_psi)
        elif k == ROTATION:
            # dot-1 of u (body i, turned by phi) and f_j (slot p2): C = sin(theta - phi)
            f, f1, f2 = phi[motion[e], 0], phi[motion[e], 1], phi[motion[e], 2]
            _rotation_vectors(s, J, v, a, p0, p1, f, gamma, u, uJ, uv, ua, w, wv)
            fj_u = 0.0
            fj_w = 0.0
            for x in range(dim):
                fj_u += s[p2, x] * u[x]
                fj_w += s[p2, x] * w[x]
            if value:
                C[row] = fj_u
            if jacobian:
                for col in range(n_rot):
                    di = 0.0
                    dj = 0.0
                    for x in range(dim):
                        di += s[p2, x] * uJ[x, col]
                        dj += u[x] * J[p2, x, col]
                    _put(data, dest, row, 0, dim + col, nc, di)
                    _put(data, dest, row, 1, dim + col, nc, dj)
            if gamma:
                dot1 = 0.0
                mixed = 0.0
                for x in range(dim):
                    dot1 += s[p2, x] * ua[x] + u[x] * a[p2, x] + 2.0 * uv[x] * v[p2, x]
                    mixed += s[p2, x] * wv[x] + w[x] * v[p2, x]
                G[row] = -dot1 + 2.0 * f1 * mixed + fj_u * f1 * f1 + fj_w * f2
            if rate:
                nu[row] = fj_w * f1
