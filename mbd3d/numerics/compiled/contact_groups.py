"""Contact groups, compiled: many shapes of which every pair may touch, evaluated as the
pairs the broad phase (:mod:`.contact_grid`) finds near each other, each as a row of
:mod:`~.compiled.contacts` built on the fly.

A group is one row ``k`` of the contact table with ``values[k, 0] = GROUP``; its shapes are
rows ``first ... first + count`` of the shape table ``shapes = (bodies, points, values,
laws)`` (:mod:`.contact_grid`), ``(first, count) = points[k, 3, :2]``, and the law of a pair
of shapes of classes ``a``, ``b`` is the row ``laws[offset + a * classes + b]`` of
:mod:`~.compiled.contact_laws`, ``(offset, classes) = points[k, 2, :2]`` (the laws' constants
depend on the pair's radii and masses: shapes alike share a class). The pair of a capsule and a
sphere is the capsule's row (body i), of a box and a sphere or a capsule the box's, of a sphere,
capsule or box and a plane the plane's half-space (body j); a capsule meets a plane at its
two ends, two rows, a box at its corners, and two boxes meet at each corner of either
against the other, rows of their own (as :class:`~mbd3d.Contact` makes them).

A group's row reports the pair deepest in contact (its gap, rate, force, point and normal;
an infinite gap when no pair is near) with the potential energy and the dissipated power of
all its pairs. Its touches and releases are not located by the integrators (its switching
functions stay negative): its steps are set by the error control, or, for generalized-alpha,
by the step given.
"""

from __future__ import annotations

import math

import numpy as np

from mbd3d.numerics.compiled import jit
from mbd3d.numerics.compiled.contact_grid import BOX, CAPSULE, PLANE, SPHERE, near_pairs
from mbd3d.numerics.compiled.contact_table import (BOX_SEGMENT, BOX_SPHERE, DISSIPATION, GAP,
                                                   GROUP, POINTS, POTENTIAL, REPORT_COLUMNS,
                                                   SEGMENT_SEGMENT, SEGMENT_SPHERE,
                                                   SPHERE_PLANE, SPHERE_SPHERE)
from mbd3d.numerics.compiled.contacts import (contact_forces_into, pair_into, pair_potential,
                                              pair_power, pair_tangent, report_pair)

#: the order of a pair's shapes: body i's is the lower rank
_RANK = (1, 0, 2, -1)  # SPHERE, CAPSULE, PLANE, BOX
#: the most rows a pair makes: two boxes, each corner of either against the other
MAX_ROWS = 16


@jit
def pair_rows(shapes, k, points, a: int, b: int, rows_points, rows_values,
              rows_bodies) -> int:
    """The number of rows (up to ``MAX_ROWS``) of the contact between group ``k``'s shapes
    ``a`` and ``b``, written into ``rows_points`` (MAX_ROWS, POINTS, dim), ``rows_values``
    (MAX_ROWS, 10) and their bodies ``i``, ``j`` into ``rows_bodies`` (MAX_ROWS, 2)."""
    bodies, shape_points, shape_values, laws = shapes
    if _RANK[int(shape_values[b, 0])] < _RANK[int(shape_values[a, 0])]:
        a, b = b, a
    kind_i, kind_j = shape_values[a, 0], shape_values[b, 0]
    offset, classes = int(points[k, 2, 0]), int(points[k, 2, 1])
    law = offset + int(shape_values[a, 2]) * classes + int(shape_values[b, 2])
    if kind_i == BOX and (kind_j == PLANE or kind_j == BOX):
        return _corner_rows(shapes, laws[law], a, b, rows_points, rows_values, rows_bodies)
    rows = 2 if kind_i == CAPSULE and kind_j == PLANE else 1
    for e in range(rows):
        rows_bodies[e, 0], rows_bodies[e, 1] = bodies[a], bodies[b]
        rows_values[e] = laws[law]
        rows_values[e, 1] = shape_values[a, 1]
        rows_values[e, 2] = 0.0 if kind_j == PLANE else shape_values[b, 1]
        rows_points[e] = 0.0
        if kind_j == PLANE:
            rows_values[e, 0] = SPHERE_PLANE
            rows_points[e, 0] = shape_points[a, e]
            rows_points[e, 1:3] = shape_points[b]
        elif kind_i == BOX:  # its centre and half sizes, then the sphere's centre or the ends
            rows_values[e, 0] = BOX_SPHERE if kind_j == SPHERE else BOX_SEGMENT
            rows_points[e, 0:2] = shape_points[a]
            rows_points[e, 2:4] = shape_points[b]
        elif kind_i == SPHERE:
            rows_values[e, 0] = SPHERE_SPHERE
            rows_points[e, 0] = shape_points[a, 0]
            rows_points[e, 1] = shape_points[b, 0]
        elif kind_j == SPHERE:
            rows_values[e, 0] = SEGMENT_SPHERE
            rows_points[e, 0:2] = shape_points[a]
            rows_points[e, 2] = shape_points[b, 0]
        else:
            rows_values[e, 0] = SEGMENT_SEGMENT
            rows_points[e, 0:2] = shape_points[a]
            rows_points[e, 2:4] = shape_points[b]
    return rows


@jit
def _corner_rows(shapes, law, a: int, b: int, rows_points, rows_values, rows_bodies) -> int:
    """The rows of box ``a``'s corners against plane ``b``, or of each corner of boxes ``a``
    and ``b`` against the other box (the box is body i of a corner's row), as
    :class:`~mbd3d.Contact` makes them."""
    bodies, shape_points, shape_values, _ = shapes
    dim = rows_points.shape[2]
    plane = shape_values[b, 0] == PLANE
    e = 0
    for corners, other in ((a, b), (b, a)):
        if plane and corners == b:
            break
        for c in range(1 << dim):
            rows_values[e] = law
            rows_points[e] = 0.0
            corner = rows_points[e, 0] if plane else rows_points[e, 2]
            for x in range(dim):
                sign = 1.0 if (c >> (dim - 1 - x)) & 1 else -1.0
                corner[x] = shape_points[corners, 0, x] + sign * shape_points[corners, 1, x]
            if plane:
                rows_values[e, 0], rows_values[e, 1], rows_values[e, 2] = (
                    SPHERE_PLANE, shape_values[a, 1], 0.0)
                rows_points[e, 1:3] = shape_points[b]
                rows_bodies[e, 0], rows_bodies[e, 1] = bodies[a], bodies[b]
            else:
                rows_values[e, 0], rows_values[e, 1], rows_values[e, 2] = (
                    BOX_SPHERE, shape_values[other, 1], shape_values[corners, 1])
                rows_points[e, 0:2] = shape_points[other]
                rows_bodies[e, 0], rows_bodies[e, 1] = bodies[other], bodies[corners]
            e += 1
    return e


@jit
def _near(A, Q, shapes, points, k):
    first, count = int(points[k, 3, 0]), int(points[k, 3, 1])
    return near_pairs(A, Q, shapes[0], shapes[1], shapes[2], first, count)


@jit
def _group_into(A, axes, omega, Q, Qd, k, points, curves, shapes, out, report, power) -> bool:
    """Group ``k``'s forces into ``out``, its report row and its dissipated power; False
    where two of its shapes' cores meet (the normal is undefined)."""
    vectors, work = np.zeros((7, 3)), np.zeros((6, 3))
    rows_points, rows_values, rows_bodies = _row_tables(points.shape[2])
    pairs = _near(A, Q, shapes, points, k)
    deepest, potential, dissipated = math.inf, 0.0, 0.0
    if report.shape[0] > 0:
        report[k] = 0.0
        report[k, GAP] = math.inf
    for p in range(pairs.shape[0]):
        rows = pair_rows(shapes, k, points, pairs[p, 0], pairs[p, 1], rows_points,
                         rows_values, rows_bodies)
        for e in range(rows):
            i, j = rows_bodies[e, 0], rows_bodies[e, 1]
            gap, rate, force, friction, slip = pair_into(A, axes, omega, Q, Qd, e, i, j,
                                                         rows_points, rows_values, curves,
                                                         out, vectors, work)
            if gap != gap:
                return False
            dissipated += pair_power(rows_values, e, gap, rate, force, friction, slip)
            potential += pair_potential(rows_values, e, gap)
            if report.shape[0] > 0 and gap < deepest:
                deepest = gap
                report_pair(report, k, rows_values, e, gap, rate, force, friction, slip, Q,
                            i, vectors)
    if power.shape[0] > 0:
        power[k] = dissipated
    if report.shape[0] > 0:
        report[k, POTENTIAL], report[k, DISSIPATION] = potential, dissipated
    return True


@jit
def all_contact_forces_into(A, axes, omega, Q, Qd, bodies, points, values, curves, shapes,
                            out, report, power) -> int:
    """:func:`.contacts.contact_forces_into` with the contact groups' rows: returns -1, or
    the first row (a group's) where a normal is undefined."""
    failed = contact_forces_into(A, axes, omega, Q, Qd, bodies, points, values, curves, out,
                                 report, power)
    if failed >= 0:
        return failed
    return groups_into(A, axes, omega, Q, Qd, points, values, curves, shapes, out, report,
                       power)


@jit
def groups_into(A, axes, omega, Q, Qd, points, values, curves, shapes, out, report,
                power) -> int:
    """The contact groups' rows of :func:`all_contact_forces_into` alone."""
    for k in range(values.shape[0]):
        if values[k, 0] == GROUP and not _group_into(A, axes, omega, Q, Qd, k, points, curves,
                                                     shapes, out, report, power):
            return k
    return -1


@jit
def group_tangents(A, axes, omega, Q, Qd, k, points, curves, shapes, weight, nc: int) -> tuple:
    """``(pair bodies (p, 2), blocks (p, 2 nc, 2 nc))``: the blocks of
    :func:`.contacts.contact_tangents_into` of the pairs group ``k``'s broad phase finds."""
    vectors, work = np.zeros((7, 3)), np.zeros((6, 3))
    G, H, block = np.zeros((3, 2 * nc)), np.zeros((3, 3)), np.zeros((2 * nc, 2 * nc))
    rows_points, rows_values, rows_bodies = _row_tables(points.shape[2])
    pairs = _near(A, Q, shapes, points, k)
    pair_bodies = np.empty((pairs.shape[0], 2), dtype=np.int64)
    blocks = np.zeros((pairs.shape[0], 2 * nc, 2 * nc))
    for p in range(pairs.shape[0]):
        rows = pair_rows(shapes, k, points, pairs[p, 0], pairs[p, 1], rows_points,
                         rows_values, rows_bodies)
        pair_bodies[p] = rows_bodies[0]
        for e in range(rows):
            i, j = rows_bodies[e, 0], rows_bodies[e, 1]
            block[:, :] = 0.0
            pair_tangent(A, axes, omega, Q, Qd, e, i, j, rows_points, rows_values, curves,
                         weight, block, G, H, vectors, work)
            if i == pair_bodies[p, 0]:
                blocks[p] += block
            else:  # a row with the pair's bodies the other way round: its halves swapped
                blocks[p, :nc, :nc] += block[nc:, nc:]
                blocks[p, :nc, nc:] += block[nc:, :nc]
                blocks[p, nc:, :nc] += block[:nc, nc:]
                blocks[p, nc:, nc:] += block[:nc, :nc]
    return pair_bodies, blocks


@jit
def _row_tables(dim: int) -> tuple:
    """Room for a pair's rows: points, values and bodies."""
    return (np.zeros((MAX_ROWS, POINTS, dim)), np.zeros((MAX_ROWS, 10)),
            np.zeros((MAX_ROWS, 2), dtype=np.int64))


def empty_shapes(dim: int) -> tuple:
    """The shape table of a model without contact groups."""
    return (np.zeros(0, dtype=np.int64), np.zeros((0, 2, dim)), np.zeros((0, 3)),
            np.zeros((0, 10)))


__all__ = ["pair_rows", "all_contact_forces_into", "groups_into", "group_tangents", "empty_shapes",
           "REPORT_COLUMNS"]
