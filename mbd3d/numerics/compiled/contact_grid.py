"""The broad phase of a contact group, compiled: which of its shapes are near enough each
other to touch, found on a uniform grid in expected time linear in the number of shapes.

A group's shape ``s`` (rows ``first ... first + count`` of the shape table) is on body
``bodies[s]`` with ``values[s] = (kind, radius, class)`` and body points ``points[s]`` (2,
dim): a ``SPHERE``'s centre (the second row unused), a ``CAPSULE``'s two ends, a ``PLANE``'s
point and outward unit normal, a ``BOX``'s centre and half sizes (along its body's axes).
Each sphere, capsule and box is bounded by a sphere about its centre (a capsule's: its ends'
midpoint, of radius half its length plus its radius; a box's: its half diagonal plus its
rounding). The grid's
cells are cubes (planar: squares) as wide as the widest bounding sphere, so that two
bounding spheres that overlap have their centres in the same or in neighbouring cells. The
shapes are bucketed by a hash of their cell (Teschner et al., "Optimized spatial hashing for
collision detection of deformable objects", VMV 2003) with a counting sort, and each shape
meets only the shapes of its own and its neighbouring cells: a cost linear in the shapes
while each cell holds a bounded number of them. Planes are unbounded: each meets every
sphere and capsule within its bounding radius of the plane's half-space.

Pairs on one body (the ground included) never touch.
"""

from __future__ import annotations

import math

import numpy as np

from mbd3d.numerics.compiled import jit
from mbd3d.numerics.compiled.forces import _point, _turn

#: the kinds of a group's shapes
SPHERE, CAPSULE, PLANE, BOX = 0, 1, 2, 3
#: cell coordinates are clipped to this magnitude (far-flung shapes share the border cells),
#: so that the hash's products stay within 64 bits
_FAR = 1 << 20


@jit
def bounding_spheres(A, Q, bodies, points, values, first: int, count: int, centres,
                     radii) -> float:
    """``centres[s]`` (global, 3D) and ``radii[s]`` of the group's spheres, capsules and
    boxes (``radii`` -1 for a plane); returns the largest radius."""
    a, b = np.zeros(3), np.zeros(3)
    largest = 0.0
    for s in range(count):
        r = first + s
        kind, body = values[r, 0], bodies[r]
        if kind == PLANE:
            radii[s] = -1.0
            continue
        _point(A, Q, body, points[r, 0], a)
        if kind == SPHERE or kind == BOX:
            centres[s] = a
            diagonal = 0.0
            if kind == BOX:
                for x in range(points.shape[2]):
                    diagonal += points[r, 1, x] ** 2
            radii[s] = math.sqrt(diagonal) + values[r, 1]
        else:
            _point(A, Q, body, points[r, 1], b)
            length = 0.0
            for x in range(3):
                centres[s, x] = 0.5 * (a[x] + b[x])
                length += (b[x] - a[x]) ** 2
            radii[s] = 0.5 * math.sqrt(length) + values[r, 1]
        largest = max(largest, radii[s])
    return largest


@jit
def _cell_hash(cx: int, cy: int, cz: int, mask: int) -> int:
    return ((cx * 73856093) ^ (cy * 19349663) ^ (cz * 83492791)) & mask


@jit
def _grow(pairs, n: int):
    """``pairs`` with room for twice as many rows, the first ``n`` kept."""
    wider = np.empty((2 * pairs.shape[0] + 16, 2), dtype=np.int64)
    wider[:n] = pairs[:n]
    return wider


@jit
def _cells(centres, radii, width: float, cells) -> None:
    """Each bounded shape's cell ``cells[s]`` (integer coordinates, clipped to ``_FAR``)."""
    for s in range(centres.shape[0]):
        for x in range(3):
            c = centres[s, x] / width if radii[s] >= 0.0 else 0.0
            c = min(max(c, -_FAR), _FAR) if c == c else 0.0
            cells[s, x] = int(math.floor(c))


@jit
def _buckets(cells, radii, mask: int, starts, order) -> None:
    """Counting sort of the bounded shapes by the hash of their cell: bucket ``h`` holds
    ``order[starts[h]:starts[h + 1]]``."""
    starts[:] = 0
    for s in range(cells.shape[0]):
        if radii[s] >= 0.0:
            starts[_cell_hash(cells[s, 0], cells[s, 1], cells[s, 2], mask) + 1] += 1
    for h in range(mask + 1):
        starts[h + 1] += starts[h]
    fill = starts[:-1].copy()
    for s in range(cells.shape[0]):
        if radii[s] >= 0.0:
            h = _cell_hash(cells[s, 0], cells[s, 1], cells[s, 2], mask)
            order[fill[h]] = s
            fill[h] += 1


@jit
def _overlap(centres, radii, a: int, b: int) -> bool:
    distance = 0.0
    for x in range(3):
        distance += (centres[b, x] - centres[a, x]) ** 2
    return distance <= (radii[a] + radii[b]) ** 2


@jit
def near_pairs(A, Q, bodies, points, values, first: int, count: int):
    """The pairs ``(a, b)`` (shape-table rows, ``a < b``) of the group whose bounding
    spheres overlap, or whose bounded shape comes within its radius of a plane's half-space,
    shapes on one body left out; (p, 2)."""
    centres, radii = np.zeros((count, 3)), np.empty(count)
    largest = bounding_spheres(A, Q, bodies, points, values, first, count, centres, radii)
    pairs, n = np.empty((4 * count + 16, 2), dtype=np.int64), 0
    cells = np.zeros((count, 3), dtype=np.int64)
    size = 1
    while size < 2 * count:
        size *= 2
    starts, order = np.zeros(size + 1, dtype=np.int64), np.empty(count, dtype=np.int64)
    depth = 1 if points.shape[2] == 3 else 0
    if largest > 0.0:
        _cells(centres, radii, 2.0 * largest, cells)
        _buckets(cells, radii, size - 1, starts, order)
    for a in range(count):
        if radii[a] < 0.0:
            continue
        # the cell itself and the neighbours after it: each pair of cells is searched once
        for dx in range(0, 2):
            for dy in range(-1, 2):
                for dz in range(-depth, depth + 1):
                    if dx == 0 and (dy < 0 or dy == 0 and dz < 0):
                        continue
                    cx, cy, cz = cells[a, 0] + dx, cells[a, 1] + dy, cells[a, 2] + dz
                    h = _cell_hash(cx, cy, cz, size - 1)
                    for o in range(starts[h], starts[h + 1]):
                        b = order[o]
                        if ((dx == 0 and dy == 0 and dz == 0 and b <= a) or cells[b, 0] != cx
                                or cells[b, 1] != cy or cells[b, 2] != cz
                                or bodies[first + a] == bodies[first + b]
                                or not _overlap(centres, radii, a, b)):
                            continue
                        if n == pairs.shape[0]:
                            pairs = _grow(pairs, n)
                        pairs[n, 0], pairs[n, 1] = first + min(a, b), first + max(a, b)
                        n += 1
    return _plane_pairs(A, Q, bodies, points, first, centres, radii, pairs, n)


@jit
def _plane_pairs(A, Q, bodies, points, first, centres, radii, pairs, n: int):
    """``pairs[:n]`` and each plane with the bounded shapes that reach its half-space."""
    P, m = np.zeros(3), np.zeros(3)
    for p in range(radii.shape[0]):
        if radii[p] >= 0.0:
            continue
        _point(A, Q, bodies[first + p], points[first + p, 0], P)
        _turn(A, bodies[first + p], points[first + p, 1], m)
        for s in range(radii.shape[0]):
            if radii[s] < 0.0 or bodies[first + s] == bodies[first + p]:
                continue
            height = 0.0
            for x in range(3):
                height += m[x] * (centres[s, x] - P[x])
            if height > radii[s]:
                continue
            if n == pairs.shape[0]:
                pairs = _grow(pairs, n)
            pairs[n, 0], pairs[n, 1] = first + min(s, p), first + max(s, p)
            n += 1
    return pairs[:n]
