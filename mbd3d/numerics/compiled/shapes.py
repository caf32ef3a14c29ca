"""Closest points between the core shapes of contacts, compiled: a point, a segment (the core
of a capsule) and a box (against a point or a segment), in global coordinates embedded in 3D
(a planar model's third components are zero); and on a cam's surface, a periodic curve
``rho(phi) = r(phi) e(phi)`` polar about its centre (:mod:`.curves`), in the cam's frame: the
point closest to a point, and the support point farthest along a direction.

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
def box_to_segment(A, b, centre, half, a, e, c_i, c_j, n) -> float:
    """The signed distance [m] between the segment ``[a, e]`` (3,) and the box of body ``b``
    (as :func:`box_to_point` takes it), with ``c_j`` the segment's point and ``c_i`` the box's
    point where they are nearest, ``n`` the unit normal from the box to the segment and
    ``c_j = c_i + distance n``. Where those points are not unique (a segment parallel to a
    face), the middle of the segment's is taken, as between parallel segments.

    In the box's axes the segment is ``l(t) = l_a + t l_d``. Apart, its squared distance
    ``sum_x max(|l_x(t)| - h_x, 0)^2`` is convex and piecewise quadratic between the ``t``
    where a coordinate crosses a face, least at one of those or at a stationary point between
    two. Where the segment runs through the box the distance is minus the penetration: the
    least translation that parts them, along the separating axis (of the box's faces' normals
    and their cross products with the segment; planar: the segment's normal) over which
    their projections overlap least (:func:`_penetration`). Both are continuous, zero where
    they touch, and the gap's gradient is ``n`` at ``c_j`` (a conservative force)."""
    dim = half.shape[0]
    la, ld = np.zeros(3), np.zeros(3)  # a and e - a in the box's axes
    for x in range(dim):
        for y in range(dim):
            la[x] += A[b, y, x] * (a[y] - centre[y])
            ld[x] += A[b, y, x] * (e[y] - a[y])
    low, high = 0.0, 1.0  # where the segment runs inside the box, the slabs' clipping
    for x in range(dim):
        if ld[x] == 0.0:
            if abs(la[x]) > half[x]:
                low, high = 1.0, 0.0
        else:
            t_1, t_2 = (-half[x] - la[x]) / ld[x], (half[x] - la[x]) / ld[x]
            low, high = max(low, min(t_1, t_2)), min(high, max(t_1, t_2))
    scale = 0.0
    for x in range(dim):
        scale = max(scale, half[x], abs(la[x]), abs(la[x] + ld[x]))
    if low <= high:
        u, lc = np.zeros(3), np.zeros(3)  # the axis and the segment's point, box axes
        depth = _penetration(la, ld, half, low, high, 1e-13 * scale, u, lc)
        for y in range(3):
            n[y], c_j[y] = 0.0, 0.0
            for x in range(dim):
                if y < dim:
                    n[y] += A[b, y, x] * u[x]
                    c_j[y] += A[b, y, x] * lc[x]
            c_j[y] += centre[y] if y < dim else 0.0
            c_i[y] = c_j[y] + depth * n[y]
        return -depth
    t = _nearest_along(la, ld, half, 1e-13 * scale)
    for y in range(3):
        c_j[y] = a[y] + t * (e[y] - a[y])
    return box_to_point(A, b, centre, half, c_j, c_i, n)


@jit
def _overlap(la, ld, half, u) -> float:
    """How far the segment must move along the unit ``u`` (box axes) to leave the box: the
    box's extent along ``u`` less the segment's least projection on it."""
    extent, near = 0.0, 0.0
    for x in range(half.shape[0]):
        extent += half[x] * abs(u[x])
        near += u[x] * la[x]
    along = 0.0
    for x in range(half.shape[0]):
        along += u[x] * ld[x]
    return extent - min(near, near + along)


@jit
def _penetration(la, ld, half, low: float, high: float, tolerance: float, u, lc) -> float:
    """The least overlap ``delta`` of the segment and the box over the separating axes (box
    axes; the box is centred at the origin), ``u`` its axis (pushing the segment along
    ``+u`` parts them) and ``lc`` the segment's point that leads it: the end deepest along
    ``-u``, the middle of the part inside the box where both are (a segment square to a face's
    normal), or, along a cross product (where the whole segment is square to ``u``), its
    point nearest the box's edge (planar: corner) that leads along ``u``."""
    dim = half.shape[0]
    axes = np.zeros((2 * dim + 6, 3))
    count = 0
    for x in range(dim):
        for sign in (1.0, -1.0):
            axes[count, x] = sign
            count += 1
    size = math.sqrt(ld[0] ** 2 + ld[1] ** 2 + ld[2] ** 2)
    for x in range(dim if dim == 3 else 1):
        w = np.zeros(3)
        if dim == 3:  # e_x x l_d
            w[(x + 1) % 3], w[(x + 2) % 3] = -ld[(x + 2) % 3], ld[(x + 1) % 3]
        else:  # the segment's normal
            w[0], w[1] = -ld[1], ld[0]
        norm = math.sqrt(w[0] ** 2 + w[1] ** 2 + w[2] ** 2)
        if norm > 1e-12 * size:
            for sign in (1.0, -1.0):
                axes[count] = sign * w / norm
                count += 1
    best, depth = 0, math.inf
    for c in range(count):
        overlap = _overlap(la, ld, half, axes[c])
        if overlap < depth:
            best, depth = c, overlap
    for x in range(3):
        u[x] = axes[best, x]
    if best < 2 * dim:
        _leading_point(la, ld, u, low, high, tolerance, lc)
    else:
        _nearest_to_edge(la, ld, half, u, lc)
    return depth


@jit
def _leading_point(la, ld, u, low: float, high: float, tolerance: float, lc) -> None:
    """``lc`` = the segment's end deepest along ``-u`` (a face's normal), or the middle of
    the part inside the box where the ends are level along it."""
    along = u[0] * ld[0] + u[1] * ld[1] + u[2] * ld[2]
    t = 0.5 * (low + high) if abs(along) <= tolerance else (0.0 if along > 0.0 else 1.0)
    for x in range(3):
        lc[x] = la[x] + t * ld[x]


@jit
def _nearest_to_edge(la, ld, half, u, lc) -> None:
    """``lc`` = the segment's point nearest the box's edge (planar: corner) farthest along the
    cross-product axis ``u``: the corner's coordinates have the signs of ``u``'s, the edge runs
    along the axis ``u`` is square to (planar: none)."""
    dim = half.shape[0]
    corner, free = np.zeros(3), -1
    for x in range(dim):
        if u[x] == 0.0 and dim == 3 and free < 0:
            free = x
        corner[x] = half[x] if u[x] >= 0.0 else -half[x]
    # least |la + t ld - corner - s e_free| over t (and s): the segment's point nearest the line
    r, d = np.zeros(3), np.zeros(3)
    for x in range(3):
        r[x] = corner[x] - la[x] if x != free else 0.0
        d[x] = ld[x] if x != free else 0.0
    length2 = d[0] ** 2 + d[1] ** 2 + d[2] ** 2
    t = _clamp((r[0] * d[0] + r[1] * d[1] + r[2] * d[2]) / length2) if length2 > 0.0 else 0.5
    for x in range(3):
        lc[x] = la[x] + t * ld[x]


@jit
def _middle_of_best(ts, values, count: int, tolerance: float) -> float:
    """The middle of the ``ts[:count]`` whose ``values`` are within ``tolerance`` of the
    least: of the stretch where a convex function is least (its candidates bound it)."""
    best = math.inf
    for c in range(count):
        best = min(best, values[c])
    first, last = math.inf, -math.inf
    for c in range(count):
        if values[c] <= best + tolerance:
            first, last = min(first, ts[c]), max(last, ts[c])
    return 0.5 * (first + last)


@jit
def _distance_at(la, ld, half, t: float) -> float:
    """The distance from ``l(t)`` to the box (zero inside it)."""
    squared = 0.0
    for x in range(half.shape[0]):
        squared += max(abs(la[x] + t * ld[x]) - half[x], 0.0) ** 2
    return math.sqrt(squared)


@jit
def _nearest_along(la, ld, half, tolerance: float) -> float:
    """The ``t`` in [0, 1] where ``l(t)``, wholly outside the box, is nearest it: between the
    ``t`` where a coordinate crosses a face the squared distance is a quadratic, each
    coordinate's excess beyond its face affine."""
    dim = half.shape[0]
    breaks = np.empty(2 + 2 * dim)
    breaks[0], breaks[1], count = 0.0, 1.0, 2
    for x in range(dim):
        if ld[x] != 0.0:
            for side in (-1.0, 1.0):
                t = (side * half[x] - la[x]) / ld[x]
                if 0.0 < t < 1.0:
                    breaks[count] = t
                    count += 1
    breaks = np.sort(breaks[:count])
    ts, values = np.empty(2 * count), np.empty(2 * count)
    for c in range(count):
        ts[c], values[c] = breaks[c], _distance_at(la, ld, half, breaks[c])
    found = count
    for c in range(count - 1):
        middle = 0.5 * (breaks[c] + breaks[c + 1])
        along, curvature = 0.0, 0.0  # of sum (s l_x(t) - h_x)^2 over the faces passed
        for x in range(dim):
            l_x = la[x] + middle * ld[x]
            if abs(l_x) > half[x]:
                side = 1.0 if l_x > 0.0 else -1.0
                along += (side * la[x] - half[x]) * side * ld[x]
                curvature += ld[x] * ld[x]
        if curvature > 0.0:
            t = -along / curvature
            if breaks[c] < t < breaks[c + 1]:
                ts[found], values[found] = t, _distance_at(la, ld, half, t)
                found += 1
    return _middle_of_best(ts, values, found, tolerance)


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
