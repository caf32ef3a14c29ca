"""Compliant contacts between shapes on bodies and joint stops, compiled: the gap, the normal
force of the contact law and the regularised Coulomb friction, for all of them in one loop.

Contact ``k`` acts between body ``i = bodies[k, 0]`` and ``j = bodies[k, 1]``; ``kinds[k]``
and its body points ``points[k]`` (body frames):

- ``SPHERE_PLANE``: a sphere (planar: a circle) of radius ``r_i`` centred at ``points[k, 0]``
  of ``i`` against the half-space of ``j`` bounded by the plane (planar: the line) through
  ``points[k, 1]`` with outward unit normal ``points[k, 2]``: ``g = m . (c_i - P) - r_i``;
- ``SPHERE_SPHERE``: spheres (circles) of radii ``r_i``, ``r_j`` centred at ``points[k, 0]``
  of ``i`` and ``points[k, 1]`` of ``j``;
- ``SEGMENT_SPHERE``: a capsule of radius ``r_i`` around the segment from ``points[k, 0]`` to
  ``points[k, 1]`` of ``i`` against the sphere of radius ``r_j`` at ``points[k, 2]`` of ``j``;
- ``SEGMENT_SEGMENT``: two capsules, around ``points[k, 0:2]`` of ``i`` and ``points[k, 2:4]``
  of ``j``;
- ``BOX_SPHERE``: a box along ``i``'s axes centred at ``points[k, 0]`` with half sizes
  ``points[k, 1]``, rounded by ``r_i``, against the sphere at ``points[k, 2]`` of ``j``;
- ``BOX_SEGMENT``: the box (as above) against a capsule of radius ``r_j`` around the segment
  from ``points[k, 2]`` to ``points[k, 3]`` of ``j``;
- ``PIN_IN_HOLE``: a pin, the sphere of radius ``r_i`` at ``points[k, 0]`` of ``i`` (planar:
  a circle), inside a hole of radius ``r_j`` of ``j``, the cylinder about the axis through
  ``points[k, 1]`` along the unit ``points[k, 2]`` (planar: the circle about ``points[k, 1]``,
  the axis zero): ``g = r_j - r_i - |e|`` with ``e`` the pin centre's offset from the axis,
  square to it; the normal ``e / |e|`` pushes the hole outwards and the pin back (none while
  the pin is centred, where ``g`` is the clearance);
- ``CAM_SPHERE``: a planar disc cam of ``i`` whose surface is the periodic curve ``r(phi)``
  (:mod:`.curves`, stored in ``curves`` at offset ``points[k, 3, 0]`` with ``points[k, 3, 1]``
  intervals) polar about ``points[k, 0]`` in ``i``'s axes, against the circle of radius
  ``r_j`` at ``points[k, 1]`` of ``j``: ``g = N . (c_j - X) - r_j`` at the surface's point
  ``X`` closest to the circle's centre ``c_j`` (Newton's method on ``phi`` from ``c_j``'s
  polar angle), ``N`` the surface's outward normal there;
- ``CAM_PLANE``: the cam (as above) against the half-plane of ``j`` bounded by the line
  through ``points[k, 1]`` with outward unit normal ``m = points[k, 2]`` (a flat-faced
  follower): ``g = m . (X - P)`` at the surface's point ``X`` farthest along ``-m`` (its
  support point: Newton's method on ``phi`` from the polar angle of ``-m``), the normal
  ``-m`` as against a plane.

Between sphere, capsule and box cores the gap is ``|c_j - c_i| - r_i - r_j`` at the cores'
closest points ``c_i``, ``c_j`` (:mod:`~.compiled.shapes`; inside a box, minus the depth below its
nearest face; of a segment running through a box, minus the least translation that parts
them).

With ``n`` the unit normal from ``i`` to ``j`` (``-m`` against a plane, ``(c_j - c_i) / |c_j -
c_i|`` between cores, the face's normal inside a box, the separating axis of a segment
through a box, the cam's outward normal ``N``), both
bodies are pushed apart at the point ``x = c_i + (r_i + g / 2) n`` midway between the two
surfaces (in a hole, midway between the pin's surface and the hole's wall; on a cam, ``c_i =
X`` and ``r_i = 0``), each at its own material point there, so that the pair
exerts no net moment. The penetration is ``delta = -g`` and its rate ``delta' = -n . (v_j -
v_i)`` (the material points' velocities at ``x``: the gap's rate by the envelope rule). The
normal force ``F_n`` is that of the law ``values[k] = (kind, r_i, r_j, K, n_K, D, n_D, mu,
v_slip, d)`` (:mod:`~.compiled.contact_laws`); the friction force on ``j`` is ``-mu F_n tanh(|v_t| /
v_slip) v_t / |v_t|`` with ``v_t`` the tangential part of ``v_j - v_i`` (the opposite on
``i``), which dissipates ``mu F_n tanh(|v_t| / v_slip) |v_t|`` [W].

A contact group's row (``GROUP``) stands for the pairs of its many shapes that are near each
other at the state, each evaluated as one of the rows above (:mod:`~.compiled.contact_groups`).

Joint stops keep a joint coordinate ``x`` in ``[lower, upper] = values[k, 1:3]`` by the same
law, ``delta = x - upper`` or ``lower - x``, pushing back along the coordinate (no friction;
the coordinates are those :mod:`mbd3d.io.joint_coordinates` reports):

- ``HINGE_STOP``: the angle of body j about a hinge of body i, planar ``theta_j - theta_i``,
  spatial ``atan2(f_j . g_i, f_j . f_i)`` in (-pi, pi] with ``points[k] = (f_i, g_i, f_j)``
  in the body frames; the torque acts about ``h = f_i x g_i``; the reported point is body
  j's reference point;
- ``SLIDE_STOP``: the slide ``s = h . (P_j - P_i)`` of body j's point ``P_j`` along body i's
  axis ``h`` from ``P_i``, ``points[k] = (u_i, u_j, h_i)`` in the body frames; the force acts
  along ``h`` at ``P_j`` (on body i at its material point there), whose virtual work is the
  force times the slide's variation;
- ``CONE_STOP``: the angle ``atan2(|a_i x a_j|, a_i . a_j)`` in [0, pi] between an axis of
  body i and one of body j, ``points[k] = (a_i, a_j)``, kept below ``upper`` (a spherical
  joint's cone); the torque acts about ``h = a_i x a_j / |a_i x a_j|``, along which the
  angle grows at ``h . (omega_j - omega_i)``.
"""

from __future__ import annotations

import math

import numpy as np

from mbd3d.numerics.compiled import jit
from mbd3d.numerics.compiled.contact_laws import (damping, dissipated_power, law_force,
                                                  law_slopes, normal_force)
from mbd3d.numerics.compiled.contact_table import (
    BOX_SEGMENT, BOX_SPHERE, CAM_PLANE, CAM_SPHERE, CONE_STOP, DISSIPATION, FRICTION, GAP,
    GAP_RATE, GROUP, HINGE_STOP, NORMAL, NORMAL_FORCE, PIN_IN_HOLE, POINT, POINTS, POTENTIAL,
    REPORT_COLUMNS, SEGMENT_SEGMENT, SEGMENT_SPHERE, SLIDE_STOP, SLIP, SPHERE_PLANE,
    SPHERE_SPHERE, is_stop)
from mbd3d.numerics.compiled.forces import _add_pair, _point, _turn, _velocity
from mbd3d.numerics.compiled.joint_stops import _stop_coordinate, _stop_into, _stop_side
from mbd3d.numerics.compiled.shapes import (box_to_point, box_to_segment, cam_to_line,
                                            cam_to_point, closest_between_segments,
                                            closest_on_segment)

#: the table's layout (:mod:`.contact_table`) and the pairs' and rows' kernels
__all__ = ["SPHERE_PLANE", "SPHERE_SPHERE", "SEGMENT_SPHERE", "SEGMENT_SEGMENT", "BOX_SPHERE",
           "BOX_SEGMENT", "PIN_IN_HOLE", "CAM_SPHERE", "CAM_PLANE", "HINGE_STOP", "SLIDE_STOP",
           "CONE_STOP", "GROUP", "POINTS", "GAP", "GAP_RATE", "NORMAL_FORCE", "FRICTION",
           "POINT", "NORMAL", "POTENTIAL", "DISSIPATION", "SLIP", "REPORT_COLUMNS", "pair_into",
           "pair_power", "pair_potential", "report_pair", "contact_forces_into",
           "switches_into", "contact_tangents_into", "pair_tangent"]

@jit
def _normal_and_gap(A, Q, k, kind, i, j, points, values, curves, x_k, n, work) -> float:
    """The unit normal ``n`` from body ``i`` to body ``j``, the contact point ``x_k`` midway
    between the two surfaces and the gap of contact ``k`` (NaN where two cores meet: the
    normal is undefined). ``work`` (6, 3) is scratch."""
    c_i, c_j = work[4], work[5]
    if kind == SPHERE_PLANE:
        _point(A, Q, i, points[k, 0], c_i)
        _point(A, Q, j, points[k, 1], c_j)
        _turn(A, j, points[k, 2], n)
        gap = 0.0
        for x in range(3):
            gap += n[x] * (c_i[x] - c_j[x])
            n[x] = -n[x]
        return _midway(c_i, n, values[k, 1], gap - values[k, 1], x_k)
    if kind == PIN_IN_HOLE:
        return _pin_in_hole(A, Q, k, i, j, points, values, x_k, n, work)
    if kind == CAM_SPHERE or kind == CAM_PLANE:
        # X = c_i on the cam's surface (rounded by nothing): its closest or support point
        _point(A, Q, i, points[k, 0], work[0])
        _point(A, Q, j, points[k, 1], c_j)
        curve = (curves, int(points[k, 3, 0]), int(points[k, 3, 1]))
        if kind == CAM_SPHERE:
            gap = cam_to_point(A, i, work[0], curve, c_j, c_i, n) - values[k, 2]
        else:
            _turn(A, j, points[k, 2], work[1])
            gap = cam_to_line(A, i, work[0], curve, c_j, work[1], c_i, n)
        return _midway(c_i, n, 0.0, gap, x_k)
    if kind == BOX_SPHERE:
        _point(A, Q, i, points[k, 0], work[0])
        _point(A, Q, j, points[k, 2], c_j)
        gap = box_to_point(A, i, work[0], points[k, 1], c_j, c_i, n)
        return _midway(c_i, n, values[k, 1], gap - values[k, 1] - values[k, 2], x_k)
    if kind == BOX_SEGMENT:
        _point(A, Q, i, points[k, 0], work[0])
        _point(A, Q, j, points[k, 2], work[1])
        _point(A, Q, j, points[k, 3], work[2])
        gap = box_to_segment(A, i, work[0], points[k, 1], work[1], work[2], c_i, c_j, n)
        return _midway(c_i, n, values[k, 1], gap - values[k, 1] - values[k, 2], x_k)
    if kind == SPHERE_SPHERE:
        _point(A, Q, i, points[k, 0], c_i)
        _point(A, Q, j, points[k, 1], c_j)
    elif kind == SEGMENT_SPHERE:
        _point(A, Q, i, points[k, 0], work[0])
        _point(A, Q, i, points[k, 1], work[1])
        _point(A, Q, j, points[k, 2], c_j)
        closest_on_segment(work[0], work[1], c_j, c_i)
    else:
        for row in range(4):
            _point(A, Q, i if row < 2 else j, points[k, row], work[row])
        closest_between_segments(work[0], work[1], work[2], work[3], c_i, c_j)
    distance = 0.0
    for x in range(3):
        n[x] = c_j[x] - c_i[x]
        distance += n[x] * n[x]
    distance = math.sqrt(distance)
    if not distance > 0.0:
        return math.nan
    for x in range(3):
        n[x] /= distance
    return _midway(c_i, n, values[k, 1], distance - values[k, 1] - values[k, 2], x_k)


@jit
def _midway(c_i, n, r_i: float, gap: float, x_k) -> float:
    """``x_k = c_i + (r_i + gap / 2) n``, the point midway between the surfaces; returns
    ``gap``."""
    for x in range(3):
        x_k[x] = c_i[x] + (r_i + 0.5 * gap) * n[x]
    return gap


@jit
def _pin_in_hole(A, Q, k, i, j, points, values, x_k, n, work) -> float:
    """The gap of pin ``i`` in hole ``j`` (see the module doc), its normal ``n`` and the
    point ``x_k`` midway between the pin's surface and the hole's wall."""
    pin, centre, axis = work[0], work[1], work[2]
    _point(A, Q, i, points[k, 0], pin)
    _point(A, Q, j, points[k, 1], centre)
    _turn(A, j, points[k, 2], axis)
    along, offset = 0.0, 0.0
    for x in range(3):
        along += axis[x] * (pin[x] - centre[x])
    for x in range(3):
        centre[x] += along * axis[x]  # the axis' point level with the pin
        n[x] = pin[x] - centre[x]
        offset += n[x] * n[x]
    offset = math.sqrt(offset)
    for x in range(3):
        n[x] = n[x] / offset if offset > 0.0 else 0.0
        x_k[x] = centre[x] + 0.5 * (values[k, 1] + values[k, 2] + offset) * n[x]
    return values[k, 2] - values[k, 1] - offset


@jit
def _contact_kinematics(A, omega, Q, Qd, k, i, j, points, values, curves, point, n, s_i, s_j,
                        v_i, v_j, work) -> tuple:
    """``(gap, gap rate)`` of contact ``k`` (a NaN gap: its normal is undefined), with the
    normal ``n``, the ``point`` midway between the surfaces and its offsets ``s_i``, ``s_j``
    from the bodies' reference points, and ``v_j`` the velocity of body j's material point
    there relative to body i's. ``work`` (6, 3) is scratch."""
    dim = points.shape[2]
    gap = _normal_and_gap(A, Q, k, int(values[k, 0]), i, j, points, values, curves, point, n,
                          work)
    for x in range(3):
        s_i[x] = point[x] - (Q[i, x] if x < dim else 0.0)
        s_j[x] = point[x] - (Q[j, x] if x < dim else 0.0)
    _velocity(Qd, omega, dim, i, s_i, v_i)
    _velocity(Qd, omega, dim, j, s_j, v_j)
    rate = 0.0
    for x in range(3):
        v_j[x] -= v_i[x]
        rate += n[x] * v_j[x]
    return gap, rate


@jit
def pair_into(A, axes, omega, Q, Qd, k, i, j, points, values, curves, out, vectors,
              work) -> tuple:
    """Add the generalized forces of shape-pair row ``k`` between bodies ``i`` and ``j`` into
    ``out``; returns ``(gap, gap rate, normal force, friction, slip speed)``, ``friction``
    the friction force per slip velocity [N s/m] (<= 0: it opposes the slip; a NaN gap: the
    normal is undefined, nothing added), with the point midway between the surfaces
    ``vectors[0]``, the normal ``vectors[1]``, the point's offsets from the bodies' reference
    points ``vectors[2:4]`` and the slip velocity ``vectors[5]``. ``vectors`` (7, 3) and
    ``work`` (6, 3) are scratch."""
    point, n, s_i, s_j, v_i, v_j, F = (vectors[0], vectors[1], vectors[2], vectors[3],
                                       vectors[4], vectors[5], vectors[6])
    gap, rate = _contact_kinematics(A, omega, Q, Qd, k, i, j, points, values, curves,
                                    point, n, s_i, s_j, v_i, v_j, work)
    if gap != gap:
        return gap, rate, 0.0, 0.0, 0.0
    force = normal_force(values, k, -gap, -rate)
    slip = 0.0
    for x in range(3):
        v_j[x] -= rate * n[x]
        slip += v_j[x] * v_j[x]
    slip = math.sqrt(slip)
    # tanh(s / v) / s, which tends to 1 / v as the slip vanishes
    scale = values[k, 8]
    weight = math.tanh(slip / scale) / slip if slip > 1e-9 * scale else 1.0 / scale
    friction = -values[k, 7] * force * weight
    for x in range(3):
        F[x] = force * n[x] + friction * v_j[x]
    _add_pair(axes, i, j, s_i, s_j, F, out)
    return gap, rate, force, friction, slip


@jit
def pair_power(values, k, gap: float, rate: float, force: float, friction: float,
               slip: float) -> float:
    """The power [W] pair row ``k``'s damper and friction dissipate (see :func:`pair_into`)."""
    return dissipated_power(values, k, -gap, -rate, force) - friction * slip * slip


@jit
def pair_potential(values, k, gap: float) -> float:
    """The energy [J] in pair row ``k``'s spring at ``gap``."""
    delta = -gap if gap < 0.0 else 0.0
    exponent = values[k, 4] + 1.0
    return values[k, 3] * delta ** exponent / exponent


@jit
def report_pair(report, r, values, k, gap, rate, force, friction, slip, Q, i, vectors) -> None:
    """Report row ``r`` of pair row ``k`` from :func:`pair_into`'s results."""
    dim = 3 if Q.shape[1] == 6 else 2
    report[r, DISSIPATION] = pair_power(values, k, gap, rate, force, friction, slip)
    report[r, GAP], report[r, GAP_RATE], report[r, NORMAL_FORCE] = gap, rate, force
    for x in range(3):
        report[r, FRICTION + x] = friction * vectors[5, x]
        report[r, POINT + x] = vectors[2, x] + (Q[i, x] if x < dim else 0.0)
        report[r, NORMAL + x] = vectors[1, x]
        report[r, SLIP + x] = vectors[5, x]
    report[r, POTENTIAL] = pair_potential(values, k, gap)


@jit
def contact_forces_into(A, axes, omega, Q, Qd, bodies, points, values, curves, out,
                        report, power) -> int:
    """Add the generalized forces of the contacts into ``out`` (bodies + ground, n_coords),
    and, where ``report`` has a row per contact, fill it (see ``REPORT_COLUMNS``); where
    ``power`` has one, the power each dissipates [W] (:func:`dissipated_power`). Returns -1, or
    the first contact whose normal is undefined. Group rows are left to
    :func:`mbd3d.numerics.compiled.contact_groups.groups_into`."""
    vectors, work = np.zeros((7, 3)), np.zeros((6, 3))
    for k in range(bodies.shape[0]):
        i, j = bodies[k, 0], bodies[k, 1]
        if is_stop(values[k, 0]):
            _stop_into(A, axes, omega, Q, Qd, k, i, j, points, values, out, report, power)
            continue
        if values[k, 0] == GROUP:
            continue
        gap, rate, force, friction, slip = pair_into(A, axes, omega, Q, Qd, k, i, j, points,
                                                     values, curves, out, vectors, work)
        if gap != gap:
            return k
        if power.shape[0] > 0:
            power[k] = pair_power(values, k, gap, rate, force, friction, slip)
        if report.shape[0] > 0:
            report_pair(report, k, values, k, gap, rate, force, friction, slip, Q, i, vectors)
    return -1


@jit
def switches_into(A, omega, Q, Qd, bodies, points, values, curves, out) -> None:
    """``out[k]``: a continuous function of the state that is positive exactly while contact
    (or stop) ``k``'s law pushes, ``delta F_n / (K delta^n_K + |c delta'|)`` with the unclipped
    force ``F_n = K delta^n_K + c delta'`` while pressed in (``delta > 0``), else ``delta``
    (<= 0): the integrators end a step where it changes sign, so that no step straddles the
    kink of a touch or a release. It is ``delta`` itself while the damper pushes too (at a
    touch) and wherever the law is undamped, so that the secant which places a step's end on
    it is exact to first order: ``F_n / K``, ``delta^(3/2)`` for Hertz, has no slope where an
    undamped contact opens, and the secant crept towards the release in ever shorter steps;
    it has an infinite one where Tsuji's damping ``delta^(1/4) delta'`` sets in at a touch.
    A rigid row (``K = 0``) gives -1. Where ``out`` has two entries per row, ``out[r + k]`` is
    the penetration ``delta`` itself: it turns negative where a law whose force was clipped at
    zero stops unloading its spring, the kink of the power it dissipates
    (:func:`.contact_laws.dissipated_power`)."""
    point, n = np.zeros(3), np.zeros(3)
    s_i, s_j, v_i, v_j, h = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)
    work = np.zeros((6, 3))
    rows = bodies.shape[0]
    for k in range(rows):
        i, j = bodies[k, 0], bodies[k, 1]
        if values[k, 0] == GROUP:  # a group's touches are not located (see contact_groups)
            out[k] = -1.0
            if out.shape[0] > rows:
                out[rows + k] = -1.0
            continue
        if is_stop(values[k, 0]):
            x, rate = _stop_coordinate(A, omega, Q, Qd, k, i, j, points, values, h, s_i, s_j)
            gap, rate, _ = _stop_side(x, rate, values[k, 1], values[k, 2])
        else:
            gap, rate = _contact_kinematics(A, omega, Q, Qd, k, i, j, points, values, curves,
                                            point, n, s_i, s_j, v_i, v_j, work)
        delta, delta_rate = -gap, -rate
        if out.shape[0] > rows:
            out[rows + k] = -1.0 if values[k, 3] == 0.0 else delta if delta == delta else 0.0
        if values[k, 3] == 0.0:
            out[k] = -1.0  # a rigid row (no law): it never pushes, its impacts are events
            continue
        if not delta > 0.0:
            out[k] = delta if delta == delta else 0.0
            continue
        spring = values[k, 3] * delta ** values[k, 4]
        damper = abs(damping(values, k, delta)[0] * delta_rate)
        # both vanish only where delta^n underflows at rest: the spring pushes, barely
        size = spring + damper
        out[k] = delta * law_force(values, k, delta, delta_rate) / size if size > 0.0 else delta


@jit
def _pair_jacobian(axes, i, j, s_i, s_j, G) -> None:
    """``G`` (3, 2 nc) = ``[-J_i, J_j]``: the velocity of body j's material point at offset
    ``s_j`` relative to body i's at ``s_i`` per coordinate rate, ``J = [I, a_c x s]`` with
    ``a_c`` the global axis of rotation coordinate ``c`` (the map :func:`_add_force` uses)."""
    nc = G.shape[1] // 2
    dim = nc - axes.shape[2]
    G[:, :] = 0.0
    for half, b, s, sign in ((0, i, s_i, -1.0), (1, j, s_j, 1.0)):
        o = half * nc
        for x in range(dim):
            G[x, o + x] = sign
        for c in range(axes.shape[2]):
            a0, a1, a2 = axes[b, 0, c], axes[b, 1, c], axes[b, 2, c]
            G[0, o + dim + c] = sign * (a1 * s[2] - a2 * s[1])
            G[1, o + dim + c] = sign * (a2 * s[0] - a0 * s[2])
            G[2, o + dim + c] = sign * (a0 * s[1] - a1 * s[0])


@jit
def _turn_jacobian(axes, i, j, G) -> None:
    """``G`` (3, 2 nc) = the angular velocity of body j relative to body i per coordinate
    rate (the map :func:`_add_torque` uses)."""
    nc = G.shape[1] // 2
    dim = nc - axes.shape[2]
    G[:, :] = 0.0
    for o, b, sign in ((0, i, -1.0), (nc, j, 1.0)):
        for c in range(axes.shape[2]):
            for x in range(3):
                G[x, o + dim + c] = sign * axes[b, x, c]


@jit
def _turning_normal(axes, Q, i, j, hole: bool, force: float, n, work, s_i, s_j, G, H) -> None:
    """``G``, ``H`` of the turning of a normal that joins two points, ``c_i``, ``c_j`` (the
    cores' closest points, ``work[4:6]``; a pin's centre and the hole's axis level with it,
    ``work[0:2]``), under the normal force: ``G`` their relative velocity, ``H = -+ (F_n / d)
    (I - n n^T - a a^T)`` with ``d = |c_j - c_i|`` and ``a`` the hole's axis (none between
    cores): the cores push apart (a strut's negative stiffness), the hole pulls the pin
    towards its axis (a string's positive one)."""
    dim = G.shape[1] // 2 - axes.shape[2]
    c_i, c_j = (work[0], work[1]) if hole else (work[4], work[5])
    distance = 0.0
    for x in range(3):
        s_i[x] = c_i[x] - (Q[i, x] if x < dim else 0.0)
        s_j[x] = c_j[x] - (Q[j, x] if x < dim else 0.0)
        distance += (c_j[x] - c_i[x]) ** 2
    scale = (1.0 if hole else -1.0) * force / math.sqrt(distance)
    for x in range(3):
        for y in range(3):
            across = (1.0 if x == y else 0.0) - n[x] * n[y]
            if hole:
                across -= work[2, x] * work[2, y]
            H[x, y] = scale * across
    _pair_jacobian(axes, i, j, s_i, s_j, G)


@jit
def contact_tangents_into(A, axes, omega, Q, Qd, bodies, points, values, curves, weight,
                          blocks) -> None:
    """``blocks[k]`` (2 nc, 2 nc), over the coordinates of bodies i and j of contact ``k``:
    ``-dQ/dq - weight dQ/dqd`` of its law, ``G^T H G`` with ``G`` the pair's velocity
    Jacobian (:func:`_pair_jacobian`; a stop's: its coordinate's row). With ``k_n``, ``c_n``
    the law's slopes in ``delta`` and ``delta'``, ``s = |v_t|``, ``e = v_t / s``, ``w =
    tanh(s / v) / s`` and ``P = I - n n^T``::

        H = (k_n + weight c_n) (n n^T - mu w v_t n^T)
            + weight mu F_n (w (P - e e^T) + (1 - tanh^2(s / v)) / v e e^T)

    the law's spring and damper along the normal, the friction's slope in the slip and the
    friction's change with the normal force; between two centres (spheres, capsules, a pin
    in its hole) also the normal's turning as they move (:func:`_turning_normal`). Left
    out, as for the spring-dampers: the normal's turning with a plane, a box or a cam and
    with a hole's axis, and the change of the contact point and of the Jacobians with the positions
    (terms of the size of the force over the shapes' sizes, which change how fast the
    iteration converges, not where)."""
    vectors, work, h = np.zeros((7, 3)), np.zeros((6, 3)), np.zeros(3)
    G = np.zeros((3, blocks.shape[1]))
    H = np.zeros((3, 3))
    for k in range(bodies.shape[0]):
        i, j = bodies[k, 0], bodies[k, 1]
        blocks[k] = 0.0
        if is_stop(values[k, 0]):
            s_i, s_j = vectors[2], vectors[3]
            x, rate = _stop_coordinate(A, omega, Q, Qd, k, i, j, points, values, h, s_i, s_j)
            gap, gap_rate, _ = _stop_side(x, rate, values[k, 1], values[k, 2])
            k_n, c_n = law_slopes(values, k, -gap, -gap_rate)
            if values[k, 0] == SLIDE_STOP:
                _pair_jacobian(axes, i, j, s_i, s_j, G)
            else:
                _turn_jacobian(axes, i, j, G)
            row = h @ G  # the coordinate's rate per coordinate rate
            blocks[k] = (k_n + weight * c_n) * np.outer(row, row)
        elif values[k, 0] != GROUP:
            pair_tangent(A, axes, omega, Q, Qd, k, i, j, points, values, curves, weight,
                         blocks[k], G, H, vectors, work)


@jit
def pair_tangent(A, axes, omega, Q, Qd, k, i, j, points, values, curves, weight, block, G, H,
                 vectors, work) -> None:
    """``block`` (2 nc, 2 nc) of shape-pair row ``k`` (see :func:`contact_tangents_into`),
    left alone where its law does not push; ``G`` (3, 2 nc), ``H`` (3, 3), ``vectors`` (7,
    3) and ``work`` (6, 3) are scratch."""
    point, n, s_i, s_j, v_i, v_j = (vectors[0], vectors[1], vectors[2], vectors[3],
                                    vectors[4], vectors[5])
    gap, rate = _contact_kinematics(A, omega, Q, Qd, k, i, j, points, values, curves,
                                    point, n, s_i, s_j, v_i, v_j, work)
    force = normal_force(values, k, -gap, -rate)
    if force == 0.0:
        return
    k_n, c_n = law_slopes(values, k, -gap, -rate)
    slip = 0.0
    for x in range(3):
        v_j[x] -= rate * n[x]
        slip += v_j[x] * v_j[x]
    slip = math.sqrt(slip)
    scale, mu = values[k, 8], values[k, 7]
    w = math.tanh(slip / scale) / slip if slip > 1e-9 * scale else 1.0 / scale
    w1 = (1.0 - math.tanh(slip / scale) ** 2) / scale
    for x in range(3):
        e_x = v_j[x] / slip if slip > 1e-9 * scale else 0.0
        for y in range(3):
            e_y = v_j[y] / slip if slip > 1e-9 * scale else 0.0
            along = (k_n + weight * c_n) * (n[x] * n[y] - mu * w * v_j[x] * n[y])
            P = (1.0 if x == y else 0.0) - n[x] * n[y]
            H[x, y] = along + weight * mu * force * (w * (P - e_x * e_y) + w1 * e_x * e_y)
    _pair_jacobian(axes, i, j, s_i, s_j, G)
    block += G.T @ H @ G
    if SPHERE_SPHERE <= values[k, 0] <= PIN_IN_HOLE and values[k, 0] != BOX_SPHERE:
        _turning_normal(axes, Q, i, j, values[k, 0] == PIN_IN_HOLE, force, n, work, s_i,
                        s_j, G, H)
        block += G.T @ H @ G
