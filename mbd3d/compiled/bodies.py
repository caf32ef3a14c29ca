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

from mbd3d.compiled import jit
from mbd3d.compiled.rotations import g_bar_inverse_matrix, g_bar_matrix, rodrigues_matrix


@jit
def planar_frames(Q: np.ndarray, Qd: np.ndarray, velocities: bool):
    """``A, axes, omega, kappa`` of planar bodies ``Q`` (b, 3) with rates ``Qd`` (b, 3) (read
    only with ``velocities``)."""
    b = Q.shape[0]
    A = np.empty((b, 2, 2))
    axes = np.zeros((b, 3, 1))
    omega = np.zeros((b, 3))
    for k in range(b):
        c, s = math.cos(Q[k, 2]), math.sin(Q[k, 2])
        A[k, 0, 0] = c
        A[k, 0, 1] = -s
        A[k, 1, 0] = s
        A[k, 1, 1] = c
        axes[k, 2, 0] = 1.0
        if velocities:
            omega[k, 2] = Qd[k, 2]
    return A, axes, omega, np.zeros(b)


@jit
def spatial_frames(Q: np.ndarray, Qd: np.ndarray, charts: np.ndarray, velocities: bool):
    """``A, axes, omega, kappa, G_bar, omega_bar`` of spatial bodies ``Q`` (b, 6) relative to
    their ``charts`` (b, 3, 3): ``A = A0 A(g)`` [5.1], ``omega_bar = G_bar g_dot`` [2.5],
    ``omega = A omega_bar``."""
    b = Q.shape[0]
    A = np.empty((b, 3, 3))
    axes = np.empty((b, 3, 3))
    Gb = np.empty((b, 3, 3))
    omega = np.zeros((b, 3))
    omega_bar = np.zeros((b, 3))
    kappa = np.zeros(b)
    local = np.empty((3, 3))
    for k in range(b):
        g = Q[k, 3:6]
        rodrigues_matrix(g, local)
        for i in range(3):
            for j in range(3):
                A[k, i, j] = (charts[k, i, 0] * local[0, j] + charts[k, i, 1] * local[1, j]
                              + charts[k, i, 2] * local[2, j])
        g_bar_matrix(g, Gb[k])
        for i in range(3):
            for j in range(3):
                axes[k, i, j] = A[k, i, 0] * Gb[k, 0, j] + A[k, i, 1] * Gb[k, 1, j] + A[k, i, 2] * Gb[k, 2, j]
        if velocities:
            for i in range(3):
                omega_bar[k, i] = Gb[k, i, 0] * Qd[k, 3] + Gb[k, i, 1] * Qd[k, 4] + Gb[k, i, 2] * Qd[k, 5]
            for i in range(3):
                omega[k, i] = A[k, i, 0] * omega_bar[k, 0] + A[k, i, 1] * omega_bar[k, 1] + A[k, i, 2] * omega_bar[k, 2]
            kappa[k] = 2.0 * (g[0] * Qd[k, 3] + g[1] * Qd[k, 4] + g[2] * Qd[k, 5]) / (
                1.0 + g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
    return A, axes, omega, kappa, Gb, omega_bar


@jit
def body_vectors(A: np.ndarray, axes: np.ndarray, omega: np.ndarray, kappa: np.ndarray,
                 bodies: np.ndarray, local: np.ndarray, velocities: bool):
    """``s = A v`` of body-frame vectors ``local`` (k, dim) of ``bodies`` (k,), its Jacobian
    with respect to the rotation coordinates (k, dim, n_rot), and with ``velocities`` its
    rate ``omega x s`` and the velocity-dependent part of its second derivative (k, dim; empty
    without)."""
    k, dim = local.shape
    n_rot = axes.shape[2]
    s = np.empty((k, dim))
    J = np.empty((k, dim, n_rot))
    kv = k if velocities else 0
    v = np.empty((kv, dim))
    a = np.empty((kv, dim))
    w = np.zeros(3)
    for r in range(k):
        b = bodies[r]
        w[2] = 0.0
        for i in range(dim):
            total = 0.0
            for j in range(dim):
                total += A[b, i, j] * local[r, j]
            s[r, i] = total
            w[i] = total
        for c in range(n_rot):
            x, y, z = axes[b, 0, c], axes[b, 1, c], axes[b, 2, c]
            J[r, 0, c] = y * w[2] - z * w[1]
            J[r, 1, c] = z * w[0] - x * w[2]
            if dim == 3:
                J[r, 2, c] = x * w[1] - y * w[0]
        if velocities:
            x, y, z = omega[b, 0], omega[b, 1], omega[b, 2]
            ws0 = y * w[2] - z * w[1]
            ws1 = z * w[0] - x * w[2]
            ws2 = x * w[1] - y * w[0]
            kb = kappa[b]
            v[r, 0], v[r, 1] = ws0, ws1
            a[r, 0] = y * ws2 - z * ws1 - kb * ws0
            a[r, 1] = z * ws0 - x * ws2 - kb * ws1
            if dim == 3:
                v[r, 2] = ws2
                a[r, 2] = x * ws1 - y * ws0 - kb * ws2
    return s, J, v, a


@jit
def spatial_mass_blocks(Gb: np.ndarray, mass: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """``blockdiag(m I3, G_bar^T J G_bar)`` per body [3.1], (b, 6, 6) for ``mass`` (b,)."""
    b = mass.shape[0]
    out = np.zeros((b, 6, 6))
    JG = np.empty((3, 3))
    for k in range(b):
        for i in range(3):
            out[k, i, i] = mass[k]
            for j in range(3):
                JG[i, j] = (inertia[k, i, 0] * Gb[k, 0, j] + inertia[k, i, 1] * Gb[k, 1, j]
                            + inertia[k, i, 2] * Gb[k, 2, j])
        for i in range(3):
            for j in range(3):
                out[k, 3 + i, 3 + j] = Gb[k, 0, i] * JG[0, j] + Gb[k, 1, i] * JG[1, j] + Gb[k, 2, i] * JG[2, j]
    return out


@jit
def planar_mass_blocks(mass: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """``diag(m, m, J)`` per body, (b, 3, 3), with ``J = inertia[:, 2, 2]``: the inertia
    tensors (b, 3, 3) of the compiled core, whose entry about the plane normal is a planar
    body's inertia (one argument type for planar and spatial models)."""
    b = mass.shape[0]
    out = np.zeros((b, 3, 3))
    for k in range(b):
        out[k, 0, 0] = mass[k]
        out[k, 1, 1] = mass[k]
        out[k, 2, 2] = inertia[k, 2, 2]
    return out


@jit
def spatial_quadratic_velocity(Gb: np.ndarray, omega_bar: np.ndarray, kappa: np.ndarray,
                               inertia: np.ndarray) -> np.ndarray:
    """``Qv = [0; G_bar^T (-(w x J w) + kappa J w)]``, ``w = omega_bar`` [3.2], (b, 6) for the
    first ``b = len(inertia)`` bodies."""
    b = inertia.shape[0]
    out = np.zeros((b, 6))
    Jw = np.empty(3)
    for k in range(b):
        w0, w1, w2 = omega_bar[k, 0], omega_bar[k, 1], omega_bar[k, 2]
        for i in range(3):
            Jw[i] = inertia[k, i, 0] * w0 + inertia[k, i, 1] * w1 + inertia[k, i, 2] * w2
        t0 = -(w1 * Jw[2] - w2 * Jw[1]) + kappa[k] * Jw[0]
        t1 = -(w2 * Jw[0] - w0 * Jw[2]) + kappa[k] * Jw[1]
        t2 = -(w0 * Jw[1] - w1 * Jw[0]) + kappa[k] * Jw[2]
        for i in range(3):
            out[k, 3 + i] = Gb[k, 0, i] * t0 + Gb[k, 1, i] * t1 + Gb[k, 2, i] * t2
    return out


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
def spatial_rates(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``qd`` from ``(R_dot, omega_bar)`` per body: ``g_dot = G_bar^-1 omega_bar`` [2.4]."""
    out = v.copy()
    G = np.empty((3, 3))
    for k in range(q.shape[0] // 6):
        o = 6 * k
        g_bar_inverse_matrix(q[o + 3:o + 6], G)
        for i in range(3):
            out[o + 3 + i] = G[i, 0] * v[o + 3] + G[i, 1] * v[o + 4] + G[i, 2] * v[o + 5]
    return out


@jit
def spatial_velocity_derivative(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """``d(R_dot, omega_bar)/dt`` from ``qdd``: ``G_bar g_ddot - kappa omega_bar`` [2.8]."""
    out = qdd.copy()
    G = np.empty((3, 3))
    for k in range(q.shape[0] // 6):
        o = 6 * k
        g = q[o + 3:o + 6]
        g_bar_matrix(g, G)
        kappa = 2.0 * (g[0] * qd[o + 3] + g[1] * qd[o + 4] + g[2] * qd[o + 5]) / (
            1.0 + g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
        for i in range(3):
            out[o + 3 + i] = (G[i, 0] * (qdd[o + 3] - kappa * qd[o + 3])
                              + G[i, 1] * (qdd[o + 4] - kappa * qd[o + 4])
                              + G[i, 2] * (qdd[o + 5] - kappa * qd[o + 5]))
    return out


@jit
def spatial_reset_charts(q: np.ndarray, qd: np.ndarray, charts: np.ndarray, limit: float
                         ) -> bool:
    """Move the chart of every body with ``|g| > limit`` (and, so that charts move less often,
    of every body past half of it when one does) to its current orientation [5.2-5.4], in
    place: ``A0 <- A0 A(g)``, ``g <- 0`` and, when ``qd`` is not empty, ``g_dot <- G_bar(g)
    g_dot / 2`` (the same angular velocity). Returns whether a chart moved."""
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
        if qd.shape[0]:
            g_bar_matrix(g, G)
            w0, w1, w2 = qd[o + 3], qd[o + 4], qd[o + 5]
            for i in range(3):
                qd[o + 3 + i] = 0.5 * (G[i, 0] * w0 + G[i, 1] * w1 + G[i, 2] * w2)
        g[0] = g[1] = g[2] = 0.0
    return True
