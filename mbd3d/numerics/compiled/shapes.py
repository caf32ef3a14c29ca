"""Closest points between the core shapes of contacts, compiled: a point, a segment (the core
of a capsule) and a box, in global coordinates embedded in 3D (a planar model's third
components are zero); and on a cam's surface, a periodic curve ``rho(phi) = r(phi) e(phi)``
polar about its centre (:mod:`.curves`), in the cam's frame: the point closest to a point,
and the support point farthest along a direction.

A contact between two shapes with radii ``r_i`` and ``r_j`` around their cores (a sphere is a
point with a radius, a capsule a segment with one, a box a box with a rounding radius) has the
gap ``|c_j - c_i| - r_i - r_j`` between the closest points ``c_i``, ``c_j`` of the cores, and
its normal along ``c_j - c_i``. At closest points the gap's rate is the normal component of
the material points' relative velocity (the envelope rule: sliding the points along the cores
changes the distance only to second order), which the contact force's virtual work relies on.
"""

from __future__ import annotations

import math

import numpy as np

from mbd3d.numerics.compiled import jit
from mbd3d.numerics.compiled.curves import periodic_curve

#: below this fraction of the product of their squared lengths (sin^2 of their angle), two
#: segments count as parallel: about where rounding leaves the general solution's denominator
#: (a difference of two nearly equal products) no correct digit
_PARALLEL = 1e-16


@jit
def _clamp(x: float) -> float:
    return 0.0 if x < 0.0 else (1.0 if x > 1.0 else x)


@jit
def closest_on_segment(a, b, p, out) -> None:
    """``out`` = the point of segment ``[a, b]`` (3,) closest to ``p`` (3,)."""
    along, length2 = 0.0, 0.0
    for x in range(3):
        along += (p[x] - a[x]) * (b[x] - a[x])
        length2 += (b[x] - a[x]) ** 2
    s = _clamp(along / length2)
    for x in range(3):
        out[x] = a[x] + s * (b[x] - a[x])


@jit
def closest_between_segments(a_i, b_i, a_j, b_j, c_i, c_j) -> None:
    """``c_i``, ``c_j`` = closest points of segments ``[a_i, b_i]`` and ``[a_j, b_j]`` (3,).

    The minimum of ``|a_i + s d_i - a_j - t d_j|`` over ``s, t`` in [0, 1], clamped edge by
    edge (Ericson, *Real-Time Collision Detection*, 5.1.9). Where the segments are parallel the
    closest points are not unique; the middle of their overlap is taken, so that a capsule
    lying along another is pushed at the middle of what they share. Parallel means within
    about 1e-8 rad, where the distance found exceeds the least by at most about 1e-8 of the
    segments' length (beyond it the general solution is exact to rounding)."""
    a = b = c = e = f = 0.0
    for x in range(3):
        d_i, d_j, r = b_i[x] - a_i[x], b_j[x] - a_j[x], a_i[x] - a_j[x]
        a += d_i * d_i
        b += d_i * d_j
        c += d_i * r
        e += d_j * d_j
        f += d_j * r
    denominator = a * e - b * b
    if denominator <= _PARALLEL * a * e:
        # where the ends of j fall along i, and the middle of the part of i they span
        t_a, t_b = -c / a, (b - c) / a
        low, high = max(0.0, min(t_a, t_b)), min(1.0, max(t_a, t_b))
        s = 0.5 * (low + high) if low <= high else (0.0 if high < 0.0 else 1.0)
        for x in range(3):
            c_i[x] = a_i[x] + s * (b_i[x] - a_i[x])
        closest_on_segment(a_j, b_j, c_i, c_j)
        return
    s = _clamp((b * f - c * e) / denominator)
    t = (b * s + f) / e
    if t < 0.0:
        t, s = 0.0, _clamp(-c / a)
    elif t > 1.0:
        t, s = 1.0, _clamp((b - c) / a)
    for x in range(3):
        c_i[x] = a_i[x] + s * (b_i[x] - a_i[x])
        c_j[x] = a_j[x] + t * (b_j[x] - a_j[x])


@jit
def box_to_point(A, b, centre, half, p, c_i, n) -> float:
    """The signed distance [m] of ``p`` (3,) from the box of body ``b`` centred at ``centre``
    (3, global) with half sizes ``half`` (dim,) along the body's axes ``A[b]``, with ``c_i``
    the box's surface point nearest ``p`` and ``n`` the unit outward normal there (towards
    ``p``). Inside the box the distance is minus the depth below the nearest face, and ``n``
    that face's normal."""
    dim = half.shape[0]
    inside, nearest, depth, side = True, 0, math.inf, 1.0
    lx = np.zeros(3)  # p in the box's axes
    for x in range(dim):
        value = 0.0
        for y in range(dim):
            value += A[b, y, x] * (p[y] - centre[y])
        lx[x] = value
        if abs(value) > half[x]:
            inside = False
        if half[x] - abs(value) < depth:
            nearest, depth = x, half[x] - abs(value)
    if inside:
        side = 1.0 if lx[nearest] >= 0.0 else -1.0
        lx[nearest] = side * half[nearest]
    else:
        for x in range(dim):
            lx[x] = min(max(lx[x], -half[x]), half[x])
    distance = 0.0
    for y in range(3):
        c_i[y] = centre[y]
        for x in range(dim):
            if y < dim:
                c_i[y] += A[b, y, x] * lx[x]
        n[y] = p[y] - c_i[y]
        distance += n[y] * n[y]
    if inside:
        for y in range(3):
            n[y] = side * A[b, y, nearest] if y < dim else 0.0
        return -depth
    distance = math.sqrt(distance)
    for y in range(3):
        n[y] /= distance
    return distance


@jit
def _angle_on_curve(curves, offset: int, count: int, x: float, y: float,
                    closest: bool) -> float:
    """The angle ``phi`` [rad] of a point of the curve stored at ``offset`` (``count``
    intervals), by Newton's method on ``phi`` from the polar angle of ``(x, y)``: with
    ``closest``, the point closest to ``d = (x, y)``, where the squared distance's slope
    ``(rho - d) . rho'`` vanishes; else the support point farthest along the unit ``u = (x,
    y)``, where ``-u . rho'`` does. ``rho' = r' e + r e_perp``, ``rho'' = (r'' - r) e + 2 r'
    e_perp``. Where the slope's derivative is not clearly positive (``d`` beyond the centre
    of curvature; a flat or hollow stretch) the step is the slope over ``|rho'|^2`` (closest)
    or ``r`` (support) instead: downhill all the same."""
    phi = math.atan2(y, x)
    for _ in range(60):
        r, r1, r2 = periodic_curve(curves, offset, count, phi)
        c, s = math.cos(phi), math.sin(phi)
        tx, ty = r1 * c - r * s, r1 * s + r * c
        vx, vy = (r2 - r) * c - 2.0 * r1 * s, (r2 - r) * s + 2.0 * r1 * c
        if closest:
            wx, wy = r * c - x, r * s - y
            scale = tx * tx + ty * ty
            slope, bend = wx * tx + wy * ty, scale + wx * vx + wy * vy
        else:
            scale = r
            slope, bend = -(x * tx + y * ty), -(x * vx + y * vy)
        step = -slope / (bend if bend > 0.25 * scale else scale)
        step = max(-0.5, min(0.5, step))
        phi += step
        if abs(step) <= 1e-15:
            break
    return phi


@jit
def _cam_point(A, b, centre, curve, phi: float, out) -> tuple:
    """``out`` = the global point of cam ``b``'s surface at ``phi`` (``curve = (curves, offset,
    count)``); returns ``(r, r')`` there."""
    r, r1, _ = periodic_curve(curve[0], curve[1], curve[2], phi)
    c, s = math.cos(phi), math.sin(phi)
    for x in range(2):
        out[x] = centre[x] + A[b, x, 0] * r * c + A[b, x, 1] * r * s
    out[2] = 0.0
    return r, r1


@jit
def cam_to_point(A, b, centre, curve, p, c_i, n) -> float:
    """The signed distance from the global point ``p`` to the surface of planar cam ``b``
    centred at ``centre`` (``curve = (curves, offset, count)``), positive outside: ``c_i`` its
    closest point, ``n`` the surface's outward normal there, ``(r e - r' e_perp) / sqrt(r^2 +
    r'^2)``."""
    dx = A[b, 0, 0] * (p[0] - centre[0]) + A[b, 1, 0] * (p[1] - centre[1])  # A^T (p - c)
    dy = A[b, 0, 1] * (p[0] - centre[0]) + A[b, 1, 1] * (p[1] - centre[1])
    phi = _angle_on_curve(curve[0], curve[1], curve[2], dx, dy, True)
    r, r1 = _cam_point(A, b, centre, curve, phi, c_i)
    c, s = math.cos(phi), math.sin(phi)
    size = math.sqrt(r * r + r1 * r1)
    nx, ny = (r * c + r1 * s) / size, (r * s - r1 * c) / size
    distance = nx * (dx - r * c) + ny * (dy - r * s)
    for x in range(2):
        n[x] = A[b, x, 0] * nx + A[b, x, 1] * ny
    n[2] = 0.0
    return distance


@jit
def cam_to_line(A, b, centre, curve, P, m, c_i, n) -> float:
    """The gap ``m . (X - P)`` from the line through ``P`` with unit normal ``m`` (global,
    pointing at the cam) to planar cam ``b``'s support point ``X = c_i`` along ``-m``, and
    ``n = -m`` (from the cam to the line)."""
    ux = -(A[b, 0, 0] * m[0] + A[b, 1, 0] * m[1])  # -m in the cam's axes
    uy = -(A[b, 0, 1] * m[0] + A[b, 1, 1] * m[1])
    phi = _angle_on_curve(curve[0], curve[1], curve[2], ux, uy, False)
    _cam_point(A, b, centre, curve, phi, c_i)
    gap = 0.0
    for x in range(3):
        gap += m[x] * (c_i[x] - P[x])
        n[x] = -m[x]
    return gap
