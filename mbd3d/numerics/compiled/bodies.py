"""Body kinematics and inertia terms, one body or body vector per loop iteration.

Planar and spatial bodies differ only in their frames (:func:`planar_frames`,
:func:`spatial_frames`), mass blocks and quadratic velocity forces. Both hand the rest of the
core the same arrays, so that body vectors (:func:`body_vectors`) and the constraint rows are
written once for both:

- ``A`` (b, dim, dim): rotation matrices, body to global components;
- ``axes`` (b, 3, n_rot): column ``c`` is the axis about which a change of rotation coordinate
  ``c`` turns every body vector: ``ds/dq_c = axes[:, c] x s`` (planar: the plane normal;
  spatial: the columns of ``A G_bar`` [2.9, 4.1] of the formula sheet);
- ``omega`` (b, 3): angular velocity in global components (planar: ``(0, 0, theta_dot)``);
- ``kappa`` (b,): ``2 g.g_dot / (1 + g.g)`` (zero for planar bodies), so that the
  velocity-dependent part of ``d2s/dt2`` is ``omega x (omega x s) - kappa omega x s`` [4.3].

Planar vectors are the spatial formulas with a zero third component: every product above then
stays in the plane.
"""

from __future__ import annotations

import math

import numpy as np

from mbd3d.numerics.compiled import jit
from mbd3d.numerics.compiled.rotations import g_bar_matrix, rodrigues_matrix


@jit
def planar_frames_into(Q, Qd, velocities, A, axes, omega, kappa):
    """Write ``A, axes, omega, kappa`` of planar bodies ``Q`` (b, 3) with rates ``Qd`` (b, 3)
    (read only with ``velocities``)."""
    for k in range(Q.shape[0]):
        c, s = math.cos(Q[k, 2]), math.sin(Q[k, 2])
        A[k, 0, 0] = c
        A[k, 0, 1] = -s
        A[k, 1, 0] = s
        A[k, 1, 1] = c
        axes[k, 0, 0] = 0.0
        axes[k, 1, 0] = 0.0
        axes[k, 2, 0] = 1.0
        omega[k, 0] = 0.0
        omega[k, 1] = 0.0
        omega[k, 2] = Qd[k, 2] if velocities else 0.0
        kappa[k] = 0.0


@jit
def planar_frames(Q: np.ndarray, Qd: np.ndarray, velocities: bool):
    """``A, axes, omega, kappa`` of planar bodies (see :func:`planar_frames_into`)."""
    b = Q.shape[0]
    A, axes, omega, kappa = np.empty((b, 2, 2)), np.empty((b, 3, 1)), np.empty((b, 3)), np.empty(b)
    planar_frames_into(Q, Qd, velocities, A, axes, omega, kappa)
    return A, axes, omega, kappa


@jit
def spatial_frames_into(Q, Qd, charts, velocities, A, axes, omega, kappa, Gb, omega_bar):
    """Write ``A, axes, omega, kappa, G_bar, omega_bar`` of spatial bodies ``Q`` (b, 6)
    relative to their ``charts`` (b, 3, 3): ``A = A0 A(g)`` [5.1], ``omega_bar = G_bar
    g_dot`` [2.5], ``omega = A omega_bar``."""
    for k in range(Q.shape[0]):
        x, y, z = Q[k, 3], Q[k, 4], Q[k, 5]
        size = x * x + y * y + z * z
        f = 1.0 / (1.0 + size)
        # A(g) of mbd3d.numerics.compiled.rotations.rodrigues_matrix, entry by entry
        l00, l01, l02 = (1.0 - size + 2.0 * x * x) * f, 2.0 * (x * y - z) * f, 2.0 * (x * z + y) * f
        l10, l11, l12 = 2.0 * (y * x + z) * f, (1.0 - size + 2.0 * y * y) * f, 2.0 * (y * z - x) * f
        l20, l21, l22 = 2.0 * (z * x - y) * f, 2.0 * (z * y + x) * f, (1.0 - size + 2.0 * z * z) * f
        for i in range(3):
            c0, c1, c2 = charts[k, i, 0], charts[k, i, 1], charts[k, i, 2]
            A[k, i, 0] = c0 * l00 + c1 * l10 + c2 * l20
            A[k, i, 1] = c0 * l01 + c1 * l11 + c2 * l21
            A[k, i, 2] = c0 * l02 + c1 * l12 + c2 * l22
        g_bar_matrix(Q[k, 3:6], Gb[k])
        for i in range(3):
            for j in range(3):
                axes[k, i, j] = (A[k, i, 0] * Gb[k, 0, j] + A[k, i, 1] * Gb[k, 1, j]
                                 + A[k, i, 2] * Gb[k, 2, j])
        if velocities:
            for i in range(3):
                omega_bar[k, i] = (Gb[k, i, 0] * Qd[k, 3] + Gb[k, i, 1] * Qd[k, 4]
                                   + Gb[k, i, 2] * Qd[k, 5])
            for i in range(3):
                omega[k, i] = (A[k, i, 0] * omega_bar[k, 0] + A[k, i, 1] * omega_bar[k, 1]
                               + A[k, i, 2] * omega_bar[k, 2])
            kappa[k] = 2.0 * (x * Qd[k, 3] + y * Qd[k, 4] + z * Qd[k, 5]) * f
        else:
            for i in range(3):
                omega_bar[k, i] = 0.0
                omega[k, i] = 0.0
            kappa[k] = 0.0


@jit
def spatial_frames(Q: np.ndarray, Qd: np.ndarray, charts: np.ndarray, velocities: bool):
    """``A, axes, omega, kappa, G_bar, omega_bar`` of spatial bodies (see
    :func:`spatial_frames_into`)."""
    b = Q.shape[0]
    A, axes, Gb = np.empty((b, 3, 3)), np.empty((b, 3, 3)), np.empty((b, 3, 3))
    omega, omega_bar, kappa = np.empty((b, 3)), np.empty((b, 3)), np.empty(b)
    spatial_frames_into(Q, Qd, charts, velocities, A, axes, omega, kappa, Gb, omega_bar)
    return A, axes, omega, kappa, Gb, omega_bar


@jit
def body_vectors_into(A, axes, omega, kappa, bodies, local, velocities, s, J, v, a):
    """Write ``s = A v`` of body-frame vectors ``local`` (k, dim) of ``bodies`` (k,), its
    Jacobian with respect to the rotation coordinates (k, dim, n_rot) and, with
    ``velocities``, its rate ``omega x s`` and the velocity-dependent part of its second
    derivative (k, dim)."""
    k, dim = local.shape
    n_rot = axes.shape[2]
    for r in range(k):
        b = bodies[r]
        # s with a zero third component in the plane, so that the products below are 3D
        w0 = A[b, 0, 0] * local[r, 0] + A[b, 0, 1] * local[r, 1]
        w1 = A[b, 1, 0] * local[r, 0] + A[b, 1, 1] * local[r, 1]
        w2 = 0.0
        if dim == 3:
            w0 += A[b, 0, 2] * local[r, 2]
            w1 += A[b, 1, 2] * local[r, 2]
            w2 = A[b, 2, 0] * local[r, 0] + A[b, 2, 1] * local[r, 1] + A[b, 2, 2] * local[r, 2]
            s[r, 2] = w2
        s[r, 0] = w0
        s[r, 1] = w1
        for c in range(n_rot):
            x, y, z = axes[b, 0, c], axes[b, 1, c], axes[b, 2, c]
            J[r, 0, c] = y * w2 - z * w1
            J[r, 1, c] = z * w0 - x * w2
            if dim == 3:
                J[r, 2, c] = x * w1 - y * w0
        if velocities:
            x, y, z = omega[b, 0], omega[b, 1], omega[b, 2]
            ws0 = y * w2 - z * w1
            ws1 = z * w0 - x * w2
            ws2 = x * w1 - y * w0
            kb = kappa[b]
            v[r, 0], v[r, 1] = ws0, ws1
            a[r, 0] = y * ws2 - z * ws1 - kb * ws0
            a[r, 1] = z * ws0 - x * ws2 - kb * ws1
            if dim == 3:
                v[r, 2] = ws2
                a[r, 2] = x * ws1 - y * ws0 - kb * ws2


@jit
def body_vectors(A: np.ndarray, axes: np.ndarray, omega: np.ndarray, kappa: np.ndarray,
                 bodies: np.ndarray, local: np.ndarray, velocities: bool):
    """``(s, J, v, a)`` of :func:`body_vectors_into` (``v``, ``a`` empty without
    ``velocities``)."""
    k, dim = local.shape
    kv = k if velocities else 0
    s, J = np.empty((k, dim)), np.empty((k, dim, axes.shape[2]))
    v, a = np.empty((kv, dim)), np.empty((kv, dim))
    body_vectors_into(A, axes, omega, kappa, bodies, local, velocities, s, J, v, a)
    return s, J, v, a


@jit
def spatial_mass_blocks_into(Gb, mass, inertia, out):
    """Write ``blockdiag(m I3, G_bar^T J G_bar)`` per body [3.1] into ``out`` (b, 6, 6), for
    ``mass`` (b,) and inertia tensors (b, 3, 3)."""
    for k in range(mass.shape[0]):
        for i in range(6):
            for j in range(6):
                out[k, i, j] = 0.0
        for i in range(3):
            out[k, i, i] = mass[k]
        for i in range(3):
            for j in range(3):
                total = 0.0
                for p in range(3):
                    total += Gb[k, p, i] * (inertia[k, p, 0] * Gb[k, 0, j]
                                            + inertia[k, p, 1] * Gb[k, 1, j]
                                            + inertia[k, p, 2] * Gb[k, 2, j])
                out[k, 3 + i, 3 + j] = total


@jit
def spatial_mass_blocks(Gb: np.ndarray, mass: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """The mass blocks of :func:`spatial_mass_blocks_into`, (b, 6, 6)."""
    out = np.empty((mass.shape[0], 6, 6))
    spatial_mass_blocks_into(Gb, mass, inertia, out)
    return out


@jit
def planar_mass_blocks_into(mass, inertia, out):
    """Write ``diag(m, m, J)`` per body into ``out`` (b, 3, 3), with ``J = inertia[:, 2, 2]``:
    the inertia tensors (b, 3, 3) of the compiled core, whose entry about the plane normal is
    a planar body's inertia (one argument type for planar and spatial models)."""
    for k in range(mass.shape[0]):
        for i in range(3):
            for j in range(3):
                out[k, i, j] = 0.0
        out[k, 0, 0] = mass[k]
        out[k, 1, 1] = mass[k]
        out[k, 2, 2] = inertia[k, 2, 2]


@jit
def planar_mass_blocks(mass: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """The mass blocks of :func:`planar_mass_blocks_into`, (b, 3, 3)."""
    out = np.empty((mass.shape[0], 3, 3))
    planar_mass_blocks_into(mass, inertia, out)
    return out


@jit
def spatial_quadratic_velocity_into(Gb, omega_bar, kappa, inertia, out):
    """Add ``Qv = [0; G_bar^T (-(w x J w) + kappa J w)]``, ``w = omega_bar`` [3.2], of the
    first ``b = len(inertia)`` bodies to ``out`` (6 b,)."""
    for k in range(inertia.shape[0]):
        w0, w1, w2 = omega_bar[k, 0], omega_bar[k, 1], omega_bar[k, 2]
        j0 = inertia[k, 0, 0] * w0 + inertia[k, 0, 1] * w1 + inertia[k, 0, 2] * w2
        j1 = inertia[k, 1, 0] * w0 + inertia[k, 1, 1] * w1 + inertia[k, 1, 2] * w2
        j2 = inertia[k, 2, 0] * w0 + inertia[k, 2, 1] * w1 + inertia[k, 2, 2] * w2
        t0 = -(w1 * j2 - w2 * j1) + kappa[k] * j0
        t1 = -(w2 * j0 - w0 * j2) + kappa[k] * j1
        t2 = -(w0 * j1 - w1 * j0) + kappa[k] * j2
        for i in range(3):
            out[6 * k + 3 + i] += Gb[k, 0, i] * t0 + Gb[k, 1, i] * t1 + Gb[k, 2, i] * t2


@jit
def spatial_quadratic_velocity(Gb: np.ndarray, omega_bar: np.ndarray, kappa: np.ndarray,
                               inertia: np.ndarray) -> np.ndarray:
    """``Qv`` of :func:`spatial_quadratic_velocity_into` per body, (b, 6)."""
    out = np.zeros(6 * inertia.shape[0])
    spatial_quadratic_velocity_into(Gb, omega_bar, kappa, inertia, out)
    return out.reshape(inertia.shape[0], 6)


@jit
def spatial_velocities(q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """``(R_dot, omega_bar)`` per body from ``(q, qd)`` (6 b,): ``omega_bar = G_bar g_dot``."""
    out = qd.copy()
    G = np.empty((3, 3))
    for k in range(q.shape[0] // 6):
        o = 6 * k
        g_bar_matrix(q[o + 3:o + 6], G)
        for i in range(3):
            out[o + 3 + i] = G[i, 0] * qd[o + 3] + G[i, 1] * qd[o + 4] + G[i, 2] * qd[o + 5]
    return out


@jit
def spatial_rates_into(q, v, out):
    """Write ``qd`` from ``(R_dot, omega_bar)`` per body: ``g_dot = G_bar^-1 omega_bar``
    [2.4] (entries of :func:`mbd3d.numerics.compiled.rotations.g_bar_inverse_matrix`)."""
    for k in range(q.shape[0] // 6):
        o = 6 * k
        x, y, z = q[o + 3], q[o + 4], q[o + 5]
        w0, w1, w2 = v[o + 3], v[o + 4], v[o + 5]
        for i in range(3):
            out[o + i] = v[o + i]
        out[o + 3] = 0.5 * ((1.0 + x * x) * w0 + (x * y - z) * w1 + (x * z + y) * w2)
        out[o + 4] = 0.5 * ((y * x + z) * w0 + (1.0 + y * y) * w1 + (y * z - x) * w2)
        out[o + 5] = 0.5 * ((z * x - y) * w0 + (z * y + x) * w1 + (1.0 + z * z) * w2)


@jit
def spatial_rates(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``qd`` of :func:`spatial_rates_into`."""
    out = np.empty_like(v)
    spatial_rates_into(q, v, out)
    return out


@jit
def spatial_velocity_derivative_into(q, qd, qdd, out):
    """Write ``d(R_dot, omega_bar)/dt`` from ``qdd``: ``G_bar g_ddot - kappa omega_bar``
    [2.8] (entries of :func:`mbd3d.numerics.compiled.rotations.g_bar_matrix`)."""
    for k in range(q.shape[0] // 6):
        o = 6 * k
        x, y, z = q[o + 3], q[o + 4], q[o + 5]
        f = 2.0 / (1.0 + x * x + y * y + z * z)
        kappa = (x * qd[o + 3] + y * qd[o + 4] + z * qd[o + 5]) * f
        a0 = qdd[o + 3] - kappa * qd[o + 3]
        a1 = qdd[o + 4] - kappa * qd[o + 4]
        a2 = qdd[o + 5] - kappa * qd[o + 5]
        for i in range(3):
            out[o + i] = qdd[o + i]
        out[o + 3] = f * (a0 + z * a1 - y * a2)
        out[o + 4] = f * (-z * a0 + a1 + x * a2)
        out[o + 5] = f * (y * a0 - x * a1 + a2)


@jit
def spatial_velocity_derivative(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """``d(R_dot, omega_bar)/dt`` of :func:`spatial_velocity_derivative_into`."""
    out = np.empty_like(qdd)
    spatial_velocity_derivative_into(q, qd, qdd, out)
    return out


@jit
def spatial_reset_charts(q: np.ndarray, qd: np.ndarray, charts: np.ndarray, limit: float,
                         turns: np.ndarray) -> bool:
    """Move the chart of every body with ``|g| > limit`` (and, so that charts move less often,
    of every body past half of it when one does) to its current orientation [5.2-5.4], in
    place: ``A0 <- A0 A(g)``, ``g <- 0`` and, when ``qd`` is not empty, ``g_dot <- G_bar(g)
    g_dot / 2`` (the same angular velocity). Returns whether a chart moved.

    ``turns`` (n_bodies + 1, 4), unless empty: the charts as unit quaternions ``(w, x, y,
    z)`` whose sign follows the motion, ``q0 <- q0 (1, g) / sqrt(1 + g.g)`` (the quaternion
    of ``A(g)`` with ``w > 0``, less than half a turn): what keeps a body's quaternion
    continuous however far apart its outputs are."""
    n_bodies = q.shape[0] // 6
    over = False
    for b in range(n_bodies):
        o = 6 * b
        if q[o + 3] ** 2 + q[o + 4] ** 2 + q[o + 5] ** 2 > limit * limit:
            over = True
    if not over:
        return False
    local = np.empty((3, 3))
    G = np.empty((3, 3))
    moved = np.empty((3, 3))
    for b in range(n_bodies):
        o = 6 * b
        g = q[o + 3:o + 6]
        if g[0] ** 2 + g[1] ** 2 + g[2] ** 2 <= 0.25 * limit * limit:
            continue
        rodrigues_matrix(g, local)
        for i in range(3):
            for j in range(3):
                moved[i, j] = (charts[b, i, 0] * local[0, j] + charts[b, i, 1] * local[1, j]
                               + charts[b, i, 2] * local[2, j])
        charts[b] = moved
        if turns.shape[0]:
            # times (1, g), A(g)'s quaternion times sqrt(1 + g.g): the normalisation below,
            # there anyway to keep rounding from accumulating, divides that out too
            w, x, y, z = turns[b, 0], turns[b, 1], turns[b, 2], turns[b, 3]
            bx, by, bz = g[0], g[1], g[2]
            turns[b, 0] = w - x * bx - y * by - z * bz
            turns[b, 1] = w * bx + x + y * bz - z * by
            turns[b, 2] = w * by - x * bz + y + z * bx
            turns[b, 3] = w * bz + x * by - y * bx + z
            size = math.sqrt(turns[b, 0] ** 2 + turns[b, 1] ** 2 + turns[b, 2] ** 2
                             + turns[b, 3] ** 2)
            for c in range(4):
                turns[b, c] /= size
        if qd.shape[0]:
            g_bar_matrix(g, G)
            w0, w1, w2 = qd[o + 3], qd[o + 4], qd[o + 5]
            for i in range(3):
                qd[o + 3 + i] = 0.5 * (G[i, 0] * w0 + G[i, 1] * w1 + G[i, 2] * w2)
        g[0] = g[1] = g[2] = 0.0
    return True
