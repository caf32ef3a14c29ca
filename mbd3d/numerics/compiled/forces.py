"""Applied forces as generalized forces, compiled: spring-damper-actuators (translational and
rotational), point forces and torques, each kind for all its elements in one loop.

The generalized force of a force ``F`` at body vector ``s`` (global components, the point's
offset from the body's reference point) is ``F`` on the translation coordinates and
``(axes[:, c] x s) . F`` on rotation coordinate ``c``; of a torque ``n`` (global components,
planar: ``(0, 0, n_z)``) it is ``axes[:, c] . n`` (see :mod:`.bodies` for ``axes``). Each
function adds into ``out`` (bodies + ground, n_coords); the ground's row is discarded by the
caller. Frames are those of :mod:`.bodies` (``A``, ``axes``, ``omega``) with the coordinates
``Q`` and rates ``Qd`` (bodies + ground rows).
"""

from __future__ import annotations

import math

import numpy as np

from mbd3d.numerics.compiled import jit


@jit
def _turn(A, b, u, out):
    """``out = A[b] u`` embedded in 3D (a zero third component in the plane)."""
    dim = u.shape[0]
    out[2] = 0.0
    for i in range(dim):
        total = 0.0
        for j in range(dim):
            total += A[b, i, j] * u[j]
        out[i] = total


@jit
def _add_force(axes, b, s, F, out):
    """Add the generalized force of ``F`` (3,) acting at offset ``s`` (3,) of body ``b``."""
    dim = out.shape[1] - axes.shape[2]
    for i in range(dim):
        out[b, i] += F[i]
    for c in range(axes.shape[2]):
        x, y, z = axes[b, 0, c], axes[b, 1, c], axes[b, 2, c]
        out[b, dim + c] += ((y * s[2] - z * s[1]) * F[0] + (z * s[0] - x * s[2]) * F[1]
                            + (x * s[1] - y * s[0]) * F[2])


@jit
def _add_torque(axes, b, n, scale, out):
    """Add the generalized force of the torque ``scale n`` (3,) on body ``b``."""
    dim = out.shape[1] - axes.shape[2]
    for c in range(axes.shape[2]):
        out[b, dim + c] += scale * (axes[b, 0, c] * n[0] + axes[b, 1, c] * n[1]
                                    + axes[b, 2, c] * n[2])


@jit
def _point(A, Q, b, u, out):
    """``out`` = the global position of body point ``u`` of body ``b``, embedded in 3D."""
    _turn(A, b, u, out)
    for x in range(u.shape[0]):
        out[x] += Q[b, x]


@jit
def _velocity(Qd, omega, dim, b, s, out):
    """``out`` = the velocity of the material point at offset ``s`` (3,) from body ``b``'s
    reference point (``dim`` translation coordinates)."""
    w = omega[b]
    for x in range(3):
        y, z = (x + 1) % 3, (x + 2) % 3
        out[x] = (Qd[b, x] if x < dim else 0.0) + w[y] * s[z] - w[z] * s[y]


@jit
def _add_pair(axes, i, j, s_i, s_j, F, out) -> None:
    """``F`` on body j at offset ``s_j`` and ``-F`` on body i at ``s_i`` (``F`` is negated)."""
    _add_force(axes, j, s_j, F, out)
    for x in range(3):
        F[x] = -F[x]
    _add_force(axes, i, s_i, F, out)


@jit
def spring_line(A, omega, Q, Qd, bodies, points, k, s_i, s_j, d, rate_vector) -> float:
    """The line of spring ``k`` (of :func:`spring_forces_into`): its points' offsets ``s_i``,
    ``s_j`` from their bodies' reference points, ``d = p_j - p_i`` and its rate
    ``rate_vector`` (3, global), and its length [m]."""
    dim = points.shape[2]
    i, j = bodies[k, 0], bodies[k, 1]
    _turn(A, i, points[k, 0], s_i)
    _turn(A, j, points[k, 1], s_j)
    length = 0.0
    for x in range(3):
        y, z = (x + 1) % 3, (x + 2) % 3
        Ri = Q[i, x] if x < dim else 0.0
        Rj = Q[j, x] if x < dim else 0.0
        d[x] = Rj + s_j[x] - Ri - s_i[x]
        length += d[x] * d[x]
        vi = (Qd[i, x] if x < dim else 0.0) + omega[i, y] * s_i[z] - omega[i, z] * s_i[y]
        vj = (Qd[j, x] if x < dim else 0.0) + omega[j, y] * s_j[z] - omega[j, z] * s_j[y]
        rate_vector[x] = vj - vi
    return math.sqrt(length)


@jit
def point_force(A, bodies, points, forces, body_frame, k, s, F) -> None:
    """Point force ``k`` (of :func:`point_forces_into`): its point's offset ``s`` from its
    body's reference point and the force ``F`` (3, global)."""
    b = bodies[k]
    _turn(A, b, points[k], s)
    if body_frame[k]:
        _turn(A, b, forces[k], F)
    else:
        F[2] = 0.0
        for x in range(forces.shape[1]):
            F[x] = forces[k, x]


@jit
def spring_forces_into(A, axes, omega, Q, Qd, bodies, points, values, actuation, out) -> int:
    """Translational spring-damper-actuators between point ``points[k, 0]`` of body
    ``bodies[k, 0]`` and ``points[k, 1]`` of ``bodies[k, 1]`` (body frames), ``values[k] =
    (stiffness, damping, free length)``, ``actuation[k, 0]`` the actuator's tension [N] (the
    rows of motion values ``(f, f', f'')``): the
    tension ``T = k (l - l0) + c dl/dt + actuation`` pulls the points together. Returns -1,
    or the first element whose points coincide (the force's direction is undefined)."""
    s_i, s_j = np.zeros(3), np.zeros(3)
    d, rate_vector, F = np.zeros(3), np.zeros(3), np.zeros(3)
    for k in range(bodies.shape[0]):
        i, j = bodies[k, 0], bodies[k, 1]
        length = spring_line(A, omega, Q, Qd, bodies, points, k, s_i, s_j, d, rate_vector)
        if length < 1e-12:
            return k
        rate = (d[0] * rate_vector[0] + d[1] * rate_vector[1] + d[2] * rate_vector[2]) / length
        tension = values[k, 0] * (length - values[k, 2]) + values[k, 1] * rate + actuation[k, 0]
        for x in range(3):
            F[x] = tension * d[x] / length
        _add_force(axes, i, s_i, F, out)
        for x in range(3):
            F[x] = -F[x]
        _add_force(axes, j, s_j, F, out)
    return -1


@jit
def rotary_forces_into(A, axes, omega, Q, Qd, bodies, values, vectors, actuation, out) -> None:
    """Rotational spring-damper-actuators: the torque ``-k (phi - phi0) - c dphi/dt +
    actuation[k, 0]`` [N m] on body ``bodies[k, 1]`` about the hinge (the opposite on
    ``bodies[k, 0]``), ``values[k] = (k, c, phi0)``. Planar (``vectors`` empty): ``phi =
    theta_j - theta_i``, unwrapped. Spatial: ``vectors[k] = (f_i, g_i, f_j)`` in the body
    frames, ``phi`` the angle from ``f_i`` to ``f_j`` about ``f_i x g_i`` within half a turn
    of ``phi0``."""
    planar = vectors.shape[0] == 0
    f_i, g_i, f_j, axis = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)
    for k in range(bodies.shape[0]):
        i, j = bodies[k, 0], bodies[k, 1]
        if planar:
            stretch = Q[j, 2] - Q[i, 2] - values[k, 2]
            rate = Qd[j, 2] - Qd[i, 2]
            axis[0], axis[1], axis[2] = 0.0, 0.0, 1.0
        else:
            _turn(A, i, vectors[k, 0], f_i)
            _turn(A, i, vectors[k, 1], g_i)
            _turn(A, j, vectors[k, 2], f_j)
            along = f_j[0] * f_i[0] + f_j[1] * f_i[1] + f_j[2] * f_i[2]
            across = f_j[0] * g_i[0] + f_j[1] * g_i[1] + f_j[2] * g_i[2]
            stretch = math.atan2(across, along) - values[k, 2]
            # angles are known modulo a turn: the branch nearest the free angle
            stretch = math.atan2(math.sin(stretch), math.cos(stretch))
            for x in range(3):
                y, z = (x + 1) % 3, (x + 2) % 3
                axis[x] = f_i[y] * g_i[z] - f_i[z] * g_i[y]
            rate = 0.0
            for x in range(3):
                rate += (omega[j, x] - omega[i, x]) * axis[x]
        torque = -values[k, 0] * stretch - values[k, 1] * rate + actuation[k, 0]
        _add_torque(axes, j, axis, torque, out)
        _add_torque(axes, i, axis, -torque, out)


@jit
def point_forces_into(A, axes, bodies, points, forces, body_frame, out) -> None:
    """Forces ``forces[k]`` [N] at points ``points[k]`` (body frame) of ``bodies[k]``, in
    global axes or, where ``body_frame[k]``, in the body's axes."""
    s, F = np.zeros(3), np.zeros(3)
    for k in range(bodies.shape[0]):
        point_force(A, bodies, points, forces, body_frame, k, s, F)
        _add_force(axes, bodies[k], s, F, out)


@jit
def torques_into(A, axes, bodies, torques, body_frame, out) -> None:
    """Torques ``torques[k]`` [N m] (3,; planar ``(0, 0, n)``) on ``bodies[k]``, in global
    axes or, where ``body_frame[k]``, in the body's axes (spatial bodies)."""
    n = np.zeros(3)
    for k in range(bodies.shape[0]):
        b = bodies[k]
        if body_frame[k]:
            for x in range(3):
                n[x] = (A[b, x, 0] * torques[k, 0] + A[b, x, 1] * torques[k, 1]
                        + A[b, x, 2] * torques[k, 2])
        else:
            for x in range(3):
                n[x] = torques[k, x]
        _add_torque(axes, b, n, 1.0, out)
