"""Closest points between the core shapes of contacts, compiled: a point, a segment (the core
of a capsule) and a box, in global coordinates embedded in 3D (a planar model's third
components are zero).

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
