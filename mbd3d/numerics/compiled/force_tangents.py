"""The applied forces' tangent ``K + w D`` (``K = -dQe/dq``, ``D = -dQe/dqd``, ``w`` the
integrator's velocity weight, generalized-alpha's ``gamma'``), compiled, for the force elements
of :mod:`~.compiled.forces` whose tangent is known in closed form:

- a spring-damper-actuator between points ``p_i``, ``p_j`` with ``d = p_j - p_i = l e`` and
  tension ``T``: ``G^T H G`` with ``G = [-J_i, J_j]`` (``J`` the points' Jacobians) and
  ``H = (k + w c) e e^T + (T / l)(I - e e^T)``, the spring and damper along the line and the
  turning of the line under tension;
- a rotational spring-damper with axis ``a``: ``(k + w c) G^T G`` with ``G = [-a^T X_i,
  a^T X_j]`` (``X`` the bodies' rotation axes, :mod:`.bodies`'s ``axes``), exact in the plane;
- a point force ``F`` at offset ``s`` or a torque (moment ``tau = s x F``, or the torque)
  on a body: its generalized force on rotation coordinate ``c`` is ``X_c . tau``, whose
  derivative along ``d`` is ``(dX_c/dg_d) . tau + X_c . dtau/dg_d``, exact: a force fixed in
  global axes turns its moment with the point (``dtau/dg_d = (X_d x s) x F``), one fixed in
  the body turns with it (``dtau/dg_d = X_d x tau``, and ``dF/dg_d = X_d x F`` on the
  translations); with Rodrigues parameters ``g`` relative to the chart ``A0``,
  ``X = A0 2 (I + [g]x) / (1 + g.g)``, so ``dX_c/dg_d = -2 g_d X_c / (1 + g.g) + 2 A0 (e_d x
  e_c) / (1 + g.g)`` (zero in the plane);
- the compliant contacts and joint stops: their laws' slopes through each pair's velocity
  Jacobian (:func:`.contacts.contact_tangents_into`, with what it leaves out), a contact
  group's for the pairs its broad phase finds at the state
  (:func:`.contact_groups.group_tangents`).

Left out of the springs' (the iteration that uses the tangent converges without them, a
little slower): the change of the point Jacobians and of a spatial hinge's axis with the
rotations, and of the damper's rate with the positions. A tangent is a set of blocks, one per
element, over the coordinates of its bodies; :func:`blocks_into` adds them, scaled, to the
storage of the iteration matrix's layout (dense, or LAPACK's band) that
:func:`.generalized_alpha.factor_into` takes.
"""

from __future__ import annotations

import numpy as np

from mbd3d.numerics.compiled import jit
from mbd3d.numerics.compiled.accelerations import frames_into
from mbd3d.numerics.compiled.contact_groups import group_tangents
from mbd3d.numerics.compiled.contact_table import GROUP
from mbd3d.numerics.compiled.contacts import (_pair_jacobian, _turn_jacobian,
                                              contact_tangents_into)
from mbd3d.numerics.compiled.forces import _turn, point_force, spring_line
from mbd3d.numerics.compiled.motions import motion_values_into
from mbd3d.numerics.compiled.structures import DENSE, contact_count

__all__ = ["spring_tangent_blocks", "rotary_tangent_blocks", "point_tangent_blocks",
           "torque_tangent_blocks", "blocks_into", "tangent_fits",
           "force_tangent_into", "has_tangent"]


@jit
def spring_tangent_blocks(A, axes, omega, Q, Qd, bodies, points, values, actuation, weight):
    """The blocks ``G^T H G`` (k, 2 nc, 2 nc) of the translational spring-damper-actuators of
    :func:`.forces.spring_forces_into` (same arguments; ``weight`` the damping's weight), over
    the coordinates of ``(bodies[k, 0], bodies[k, 1])``. An element whose points coincide has
    no direction: its block is zero (its force's evaluation names it)."""
    nc = Q.shape[1]
    blocks = np.zeros((bodies.shape[0], 2 * nc, 2 * nc))
    s_i, s_j, d, rate_vector = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)
    G, HG = np.empty((3, 2 * nc)), np.empty((3, 2 * nc))
    for k in range(bodies.shape[0]):
        i, j = bodies[k, 0], bodies[k, 1]
        length = spring_line(A, omega, Q, Qd, bodies, points, k, s_i, s_j, d, rate_vector)
        if length < 1e-12:
            continue
        rate = 0.0
        for x in range(3):
            d[x] /= length  # the direction e from here on
            rate += d[x] * rate_vector[x]
        tension = values[k, 0] * (length - values[k, 2]) + values[k, 1] * rate + actuation[k, 0]
        along, across = values[k, 0] + weight * values[k, 1], tension / length
        _pair_jacobian(axes, i, j, s_i, s_j, G)
        # H G = (along - across) e (e^T G) + across G
        for c in range(2 * nc):
            projection = d[0] * G[0, c] + d[1] * G[1, c] + d[2] * G[2, c]
            for x in range(3):
                HG[x, c] = (along - across) * d[x] * projection + across * G[x, c]
        for r in range(2 * nc):
            for c in range(2 * nc):
                blocks[k, r, c] = G[0, r] * HG[0, c] + G[1, r] * HG[1, c] + G[2, r] * HG[2, c]
    return blocks


@jit
def rotary_tangent_blocks(A, axes, bodies, values, vectors, weight):
    """The blocks ``(k + w c) G^T G`` (k, 2 nc, 2 nc) of the rotational spring-dampers of
    :func:`.forces.rotary_forces_into` (same arguments, ``weight`` the damping's weight)."""
    dim = A.shape[1]
    nc = dim + axes.shape[2]
    blocks = np.zeros((bodies.shape[0], 2 * nc, 2 * nc))
    f_i, g_i, axis, G = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(2 * nc)
    turn = np.zeros((3, 2 * nc))
    for k in range(bodies.shape[0]):
        i, j = bodies[k, 0], bodies[k, 1]
        if dim == 2:
            axis[0], axis[1], axis[2] = 0.0, 0.0, 1.0
        else:
            _turn(A, i, vectors[k, 0], f_i)
            _turn(A, i, vectors[k, 1], g_i)
            for x in range(3):
                y, z = (x + 1) % 3, (x + 2) % 3
                axis[x] = f_i[y] * g_i[z] - f_i[z] * g_i[y]
        _turn_jacobian(axes, i, j, turn)
        for c in range(2 * nc):
            G[c] = axis[0] * turn[0, c] + axis[1] * turn[1, c] + axis[2] * turn[2, c]
        stiffness = values[k, 0] + weight * values[k, 1]
        for r in range(2 * nc):
            for c in range(2 * nc):
                blocks[k, r, c] = stiffness * G[r] * G[c]
    return blocks


@jit
def _moment_block_into(Q, axes, charts, b, tau, dtau, dim, block) -> None:
    """``block[dim + c, dim + d] = -(dX_c/dg_d) . tau - X_c . dtau[:, d]`` (see the module
    doc) of body ``b`` (``charts``: None in the plane, where ``X`` is constant)."""
    rotations = axes.shape[2]
    for c in range(rotations):
        for d in range(rotations):
            value = 0.0
            for x in range(3):
                value -= axes[b, x, c] * dtau[x, d]
            if charts is not None and b < charts.shape[0]:
                f = 2.0 / (1.0 + Q[b, 3] ** 2 + Q[b, 4] ** 2 + Q[b, 5] ** 2)
                along = 0.0
                for x in range(3):
                    along += axes[b, x, c] * tau[x]
                value += f * Q[b, 3 + d] * along
                if c != d:  # (e_d x e_c) . (A0^T tau): the third axis, signed
                    k = 3 - c - d
                    sign = 1.0 if (d - c) % 3 == 2 else -1.0
                    value -= f * sign * (charts[b, 0, k] * tau[0] + charts[b, 1, k] * tau[1]
                                         + charts[b, 2, k] * tau[2])
            block[dim + c, dim + d] = value


@jit
def point_tangent_blocks(A, axes, Q, charts, bodies, points, forces, body_frame):
    """The blocks (k, nc, nc) of the point forces of :func:`.forces.point_forces_into` (same
    arguments, and the coordinates ``Q`` and the charts, None in the plane), over the
    coordinates of ``bodies[k]``."""
    dim = points.shape[1]
    nc = dim + axes.shape[2]
    blocks = np.zeros((bodies.shape[0], nc, nc))
    s, F, tau = np.zeros(3), np.zeros(3), np.zeros(3)
    dtau = np.zeros((3, axes.shape[2]))
    for k in range(bodies.shape[0]):
        b = bodies[k]
        point_force(A, bodies, points, forces, body_frame, k, s, F)
        for x in range(3):
            y, z = (x + 1) % 3, (x + 2) % 3
            tau[x] = s[y] * F[z] - s[z] * F[y]
        for d in range(axes.shape[2]):
            X = axes[b, :, d]
            for x in range(3):
                y, z = (x + 1) % 3, (x + 2) % 3
                if body_frame[k]:
                    dtau[x, d] = X[y] * tau[z] - X[z] * tau[y]
                    if x < dim:  # the force turns with the body
                        blocks[k, x, dim + d] = -(X[y] * F[z] - X[z] * F[y])
                else:  # (X_d x s) x F
                    u_y = X[z] * s[x] - X[x] * s[z]
                    u_z = X[x] * s[y] - X[y] * s[x]
                    dtau[x, d] = u_y * F[z] - u_z * F[y]
        _moment_block_into(Q, axes, charts, b, tau, dtau, dim, blocks[k])
    return blocks


@jit
def torque_tangent_blocks(A, axes, Q, charts, bodies, torques, body_frame):
    """The blocks (k, nc, nc) of the torques of :func:`.forces.torques_into` (same arguments,
    and ``Q`` and the charts as in :func:`point_tangent_blocks`)."""
    dim = A.shape[1]
    nc = dim + axes.shape[2]
    blocks = np.zeros((bodies.shape[0], nc, nc))
    n = np.zeros(3)
    dtau = np.zeros((3, axes.shape[2]))
    for k in range(bodies.shape[0]):
        b = bodies[k]
        for x in range(3):
            n[x] = torques[k, x]
            if body_frame[k]:
                n[x] = (A[b, x, 0] * torques[k, 0] + A[b, x, 1] * torques[k, 1]
                        + A[b, x, 2] * torques[k, 2])
        for d in range(axes.shape[2]):
            for x in range(3):
                y, z = (x + 1) % 3, (x + 2) % 3
                dtau[x, d] = ((axes[b, y, d] * n[z] - axes[b, z, d] * n[y]) if body_frame[k]
                              else 0.0)
        _moment_block_into(Q, axes, charts, b, n, dtau, dim, blocks[k])
    return blocks


@jit
def _band_position(penalty_arrays, row: int, col: int) -> int:
    """Where entry ``(row, col)`` of the matrix lies in the flattened band storage of the
    iteration matrix (LAPACK's, column order, of the permuted matrix), or -1 outside the
    band."""
    pattern = penalty_arrays
    prow, pcol = pattern.inverse[row], pattern.inverse[col]
    offset = prow - pcol
    if offset > pattern.kl or -offset > pattern.ku:
        return -1
    return pattern.kl + pattern.ku + offset + pcol * (2 * pattern.kl + pattern.ku + 1)


@jit
def blocks_into(penalty_arrays, bodies, blocks, extra) -> bool:
    """Add ``blocks`` (k, p nc, p nc) over the coordinates of bodies ``bodies[k]`` (k, p)
    (padded indices: the ground's, last, has none), scaled as the iteration matrix is (``D B
    D``), into ``extra``: (n, n) flattened for the dense layout, the band otherwise. Returns
    False where an entry lies outside the band (the rest is added)."""
    pattern = penalty_arrays
    d = pattern.scale
    n = d.shape[0]
    size = blocks.shape[1]
    nc = size // bodies.shape[1]
    fits = True
    for k in range(blocks.shape[0]):
        for r in range(size):
            row = bodies[k, r // nc] * nc + r % nc
            if row >= n:
                continue
            for c in range(size):
                col = bodies[k, c // nc] * nc + c % nc
                if col >= n:
                    continue
                value = d[row] * blocks[k, r, c] * d[col]
                if pattern.layout == DENSE:
                    extra[row * n + col] += value
                else:
                    position = _band_position(pattern, row, col)
                    if position < 0:
                        fits = False
                    else:
                        extra[position] += value
    return fits


@jit
def has_tangent(work) -> bool:
    """Whether ``work``'s model has compiled force elements (with a tangent)."""
    forces = work.model.forces
    return (forces.spring_bodies.shape[0] + forces.rotary_bodies.shape[0]
            + forces.point_bodies.shape[0] + forces.torque_bodies.shape[0]
            + contact_count(forces.contacts) > 0)


@jit
def tangent_fits(penalty_arrays, work) -> bool:
    """Whether the tangent of the compiled force elements of ``work``'s model lies inside the
    iteration matrix's band (always, for the dense layout): decided by the elements' bodies
    alone; a contact group's pairs are found as the bodies move, so only a dense matrix
    takes them."""
    forces, nc = work.model.forces, work.Q.shape[1]
    extra = np.zeros(0 if penalty_arrays.layout == DENSE
                     else penalty_arrays.scale.shape[0]
                     * (2 * penalty_arrays.kl + penalty_arrays.ku + 1))
    if penalty_arrays.layout == DENSE:
        return True
    ones = np.ones((1, 2 * nc, 2 * nc))
    for bodies in (forces.spring_bodies, forces.rotary_bodies, _contact_bodies(forces.contacts)):
        for k in range(bodies.shape[0]):
            if bodies[k, 0] < 0 or not blocks_into(penalty_arrays, bodies[k:k + 1], ones,
                                                   extra):
                return False
    return True


@jit
def _contact_bodies(contacts):
    """The body pairs (k, 2) of the contact table's rows, -1 for a contact group's row (its
    pairs change as the bodies move); none without contacts."""
    if contacts is None:
        return np.zeros((0, 2), dtype=np.int64)
    bodies = contacts.bodies.copy()
    for k in range(bodies.shape[0]):
        if contacts.values[k, 0] == GROUP:
            bodies[k, 0] = -1
    return bodies


@jit
def _contact_tangents_into(contacts, penalty_arrays, A, axes, omega, Q, Qd, weight,
                           extra) -> None:
    """Add the tangent of the contacts and joint stops ``contacts`` (None: none; decided as
    the caller is compiled, see :mod:`~.compiled.accelerations`) into ``extra``."""
    if contacts is None:
        return
    nc = Q.shape[1]
    bodies = contacts.bodies
    blocks = np.empty((bodies.shape[0], 2 * nc, 2 * nc))
    contact_tangents_into(A, axes, omega, Q, Qd, bodies, contacts.points, contacts.values,
                          contacts.curves, weight, blocks)
    blocks_into(penalty_arrays, bodies, blocks, extra)
    shapes = (contacts.shape_bodies, contacts.shape_points, contacts.shape_values,
              contacts.pair_laws)
    for k in range(bodies.shape[0]):
        if contacts.values[k, 0] == GROUP:
            pairs, more = group_tangents(A, axes, omega, Q, Qd, k, contacts.points,
                                         contacts.curves, shapes, weight, nc)
            blocks_into(penalty_arrays, pairs, more, extra)


@jit
def force_tangent_into(work, penalty_arrays, t, q, qd, charts, weight, extra) -> None:
    """The tangent ``K + weight D`` of the model's compiled force elements at ``(t, q, qd)``
    into ``extra`` (the storage of :func:`blocks_into`; the elements lie in the band, see
    :func:`tangent_fits`). ``charts``: None for a planar model. Uses ``work``'s frames."""
    forces = work.model.forces
    extra[:] = 0.0
    if not has_tangent(work):
        return
    frames_into(work, q, qd, charts)
    A, axes, omega, Q, Qd = work.A, work.axes, work.omega, work.Q, work.Qd
    motion_values_into(forces.spring_first, forces.spring_kinds, forces.spring_starts,
                       forces.spring_params, t, work.spring_actuation)
    blocks_into(penalty_arrays, forces.spring_bodies,
                spring_tangent_blocks(A, axes, omega, Q, Qd, forces.spring_bodies,
                                      forces.spring_points, forces.spring_values,
                                      work.spring_actuation, weight), extra)
    blocks_into(penalty_arrays, forces.rotary_bodies,
                rotary_tangent_blocks(A, axes, forces.rotary_bodies, forces.rotary_values,
                                      forces.rotary_vectors, weight), extra)
    bodies = forces.point_bodies
    blocks_into(penalty_arrays, bodies.reshape((bodies.shape[0], 1)),
                point_tangent_blocks(A, axes, Q, charts, bodies, forces.point_points,
                                     forces.point_forces, forces.point_body_frame), extra)
    bodies = forces.torque_bodies
    blocks_into(penalty_arrays, bodies.reshape((bodies.shape[0], 1)),
                torque_tangent_blocks(A, axes, Q, charts, bodies, forces.torque_values,
                                      forces.torque_body_frame), extra)
    _contact_tangents_into(forces.contacts, penalty_arrays, A, axes, omega, Q, Qd, weight,
                           extra)
