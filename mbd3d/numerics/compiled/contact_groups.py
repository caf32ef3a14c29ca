"""Contact groups, compiled: many shapes of which every pair may touch, evaluated as the
pairs the broad phase (:mod:`.contact_grid`) finds near each other, each as a row of
:mod:`.contacts` built on the fly.

A group is one row ``k`` of the contact table with ``values[k, 0] = GROUP``; its shapes are
rows ``first ... first + count`` of the shape table ``shapes = (bodies, points, values,
laws)`` (:mod:`.contact_grid`), ``(first, count) = points[k, 3, :2]``, and the law of a pair
of shapes of classes ``a``, ``b`` is the row ``laws[offset + a * classes + b]`` of
:mod:`.contact_laws`, ``(offset, classes) = points[k, 2, :2]`` (the laws' constants depend on
the pair's radii and masses: shapes alike share a class). The pair of a capsule and a sphere
is the capsule's row (body i), of a sphere or capsule and a plane the plane's half-space
(body j); a capsule meets a plane at its two ends, two rows.

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
from mbd3d.numerics.compiled.contact_grid import CAPSULE, PLANE, SPHERE, near_pairs
from mbd3d.numerics.compiled.contact_table import (DISSIPATION, GAP, GROUP, POINTS, POTENTIAL,
                                                   REPORT_COLUMNS, SEGMENT_SEGMENT,
                                                   SEGMENT_SPHERE, SPHERE_PLANE, SPHERE_SPHERE)
from mbd3d.numerics.compiled.contacts import (contact_forces_into, pair_into, pair_potential,
                                              pair_power, pair_tangent, report_pair)

#: the order of a pair's shapes: body i's is the lower rank
_RANK = (1, 0, 2)  # SPHERE, CAPSULE, PLANE


@jit
def pair_rows(shapes, k, points, a: int, b: int, rows_points, rows_values) -> tuple:
    """``(i, j, rows)``: the bodies and the rows (1 or 2) of the contact between group ``k``'s
    shapes ``a`` and ``b``, written into ``rows_points`` (2, POINTS, dim) and
    ``rows_values`` (2, 10)."""
    bodies, shape_points, shape_values, laws = shapes
    if _RANK[int(shape_values[b, 0])] < _RANK[int(shape_values[a, 0])]:
        a, b = b, a
    kind_i, kind_j = shape_values[a, 0], shape_values[b, 0]
    offset, classes = int(points[k, 2, 0]), int(points[k, 2, 1])
    law = offset + int(shape_values[a, 2]) * classes + int(shape_values[b, 2])
    rows = 2 if kind_i == CAPSULE and kind_j == PLANE else 1
    for e in range(rows):
        rows_values[e] = laws[law]
        rows_values[e, 1] = shape_values[a, 1]
        rows_values[e, 2] = 0.0 if kind_j == PLANE else shape_values[b, 1]
        rows_points[e] = 0.0
        if kind_j == PLANE:
            rows_values[e, 0] = SPHERE_PLANE
            rows_points[e, 0] = shape_points[a, e]
            rows_points[e, 1:3] = shape_points[b]
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
    return bodies[a], bodies[b], rows


@jit
def _near(A, Q, shapes, points, k):
    first, count = int(points[k, 3, 0]), int(points[k, 3, 1])
    return near_pairs(A, Q, shapes[0], shapes[1], shapes[2], first, count)


@jit
def _group_into(A, axes, omega, Q, Qd, k, points, curves, shapes, out, report, power) -> bool:
    """Group ``k``'s forces into ``out``, its report row and its dissipated power; False
    where two of its shapes' cores meet (the normal is undefined)."""
    vectors, work = np.zeros((7, 3)), np.zeros((6, 3))
    rows_points, rows_values = np.zeros((2, POINTS, points.shape[2])), np.zeros((2, 10))
    pairs = _near(A, Q, shapes, points, k)
    deepest, potential, dissipated = math.inf, 0.0, 0.0
    if report.shape[0] > 0:
        report[k] = 0.0
        report[k, GAP] = math.inf
    for p in range(pairs.shape[0]):
        i, j, rows = pair_rows(shapes, k, points, pairs[p, 0], pairs[p, 1], rows_points,
                               rows_values)
        for e in range(rows):
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
    G, H = np.zeros((3, 2 * nc)), np.zeros((3, 3))
    rows_points, rows_values = np.zeros((2, POINTS, points.shape[2])), np.zeros((2, 10))
    pairs = _near(A, Q, shapes, points, k)
    pair_bodies = np.empty((pairs.shape[0], 2), dtype=np.int64)
    blocks = np.zeros((pairs.shape[0], 2 * nc, 2 * nc))
    for p in range(pairs.shape[0]):
        i, j, rows = pair_rows(shapes, k, points, pairs[p, 0], pairs[p, 1], rows_points,
                               rows_values)
        pair_bodies[p, 0], pair_bodies[p, 1] = i, j
        for e in range(rows):
            pair_tangent(A, axes, omega, Q, Qd, e, i, j, rows_points, rows_values, curves,
                         weight, blocks[p], G, H, vectors, work)
    return pair_bodies, blocks


def empty_shapes(dim: int) -> tuple:
    """The shape table of a model without contact groups."""
    return (np.zeros(0, dtype=np.int64), np.zeros((0, 2, dim)), np.zeros((0, 3)),
            np.zeros((0, 10)))


__all__ = ["pair_rows", "all_contact_forces_into", "groups_into", "group_tangents", "empty_shapes",
           "REPORT_COLUMNS"]
