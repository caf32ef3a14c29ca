"""Capsules and boxes in contact, against what is computed apart from the code: gaps against
SciPy's minimisation of the distance between the shapes, forces against differences of the
Hertz potential of those gaps in random charts, resting penetrations against the weight shared
by the ends or corners, head-on impacts against the calibrated restitution, and the energy of
a box bouncing on its corners."""

from __future__ import annotations

import itertools
import math
from fractions import Fraction

import numpy as np
import pytest
from scipy.optimize import brentq, minimize, minimize_scalar
from scipy.spatial import ConvexHull
from scipy.spatial.transform import Rotation

import mbd3d as mb
from mbd3d.model import constraints
from mbd3d.model.equations import generalized_forces
from mbd3d.numerics.compiled import shapes as core

G = 9.81


def _rotation(chart: np.ndarray, g: np.ndarray) -> np.ndarray:
    """``A = A0 A(g)``, ``g = tan(phi / 2) axis``, through SciPy's rotation vectors."""
    norm = np.linalg.norm(g)
    rotvec = np.zeros(3) if norm == 0 else 2.0 * math.atan(norm) * g / norm
    return chart @ Rotation.from_rotvec(rotvec).as_matrix()


def _segment_point(a, b, p) -> float:
    found = minimize_scalar(lambda s: np.linalg.norm(a + s * (b - a) - p), bounds=(0.0, 1.0),
                            method="bounded", options={"xatol": 1e-13})
    return min(found.fun, np.linalg.norm(p - a), np.linalg.norm(p - b))


def _segment_segment(a, b, c, d) -> float:
    def distance2(x):
        return float(np.sum((a + x[0] * (b - a) - c - x[1] * (d - c)) ** 2))

    best = min((minimize(distance2, start, method="L-BFGS-B", bounds=[(0, 1), (0, 1)],
                         options={"ftol": 1e-30, "gtol": 1e-14})
                for start in ([0.5, 0.5], [0.0, 0.0], [1.0, 1.0], [0.0, 1.0], [1.0, 0.0])),
               key=lambda r: r.fun)
    return math.sqrt(best.fun)


def _box_point(centre, A, half, p) -> float:
    """Signed distance of ``p`` from the box: outside, SciPy's minimum over the box's points;
    inside, minus the depth below the nearest face."""
    local = A.T @ (p - centre)
    if np.all(np.abs(local) <= half):
        return -float(np.min(half - np.abs(local)))
    found = minimize(lambda x: float(np.sum((x - local) ** 2)), np.zeros(3), method="L-BFGS-B",
                     bounds=list(zip(-half, half)), options={"ftol": 1e-30, "gtol": 1e-14})
    return math.sqrt(found.fun)


def _box_segment(centre, A, half, a, b) -> float:
    """Signed distance of the segment ``[a, b]`` from the box: where the segment runs through
    the box, minus the least translation that parts them, the distance from the origin to the
    boundary of the box less the segment (the convex hull of the corners less the ends, by
    Qhull); else SciPy's least squared distance over the segment's and the box's points."""
    la, lb = A.T @ (a - centre), A.T @ (b - a) + A.T @ (a - centre)
    dim = len(half)
    corners = np.array(list(itertools.product(*[(-h, h) for h in half])))
    hull = ConvexHull(np.vstack([corners - la, corners - lb]))
    # facets n . x + offset <= 0 inside, n unit outward: the origin's distance to each
    inside = -hull.equations[:, -1]
    if np.all(inside > 0.0):
        return -float(np.min(inside))

    def distance2(x):
        return float(np.sum((x[1:] - la - x[0] * (lb - la)) ** 2))

    best = min((minimize(distance2, np.r_[t, np.zeros(dim)], method="L-BFGS-B",
                         bounds=[(0, 1)] + list(zip(-half, half)),
                         options={"ftol": 1e-30, "gtol": 1e-14})
                for t in (0.0, 0.5, 1.0)), key=lambda r: r.fun)
    return math.sqrt(best.fun)


def _exact_segment_distance(a, b, c, d) -> float:
    """The least distance between segments ``[a, b]`` and ``[c, d]`` in exact rational
    arithmetic on the given floats: the least of the squared distance's stationary point inside
    the unit square of the parameters and its least values along the four edges (the squared
    distance is convex, so one of them is the minimum), rounded once at the end."""
    a, b, c, d = ([Fraction(float(x)) for x in v] for v in (a, b, c, d))
    d1, d2 = [y - x for x, y in zip(a, b)], [y - x for x, y in zip(c, d)]
    r = [x - y for x, y in zip(a, c)]

    def dot(u, v):
        return sum(x * y for x, y in zip(u, v))

    def squared(s, t):
        v = [ri + s * x - t * y for ri, x, y in zip(r, d1, d2)]
        return dot(v, v)

    def clamp(x):
        return min(max(x, Fraction(0)), Fraction(1))

    A, B, C, E, F = dot(d1, d1), dot(d1, d2), dot(d1, r), dot(d2, d2), dot(d2, r)
    candidates = [(s, clamp((B * s + F) / E)) for s in (Fraction(0), Fraction(1))]
    candidates += [(clamp((B * t - C) / A), t) for t in (Fraction(0), Fraction(1))]
    if A * E != B * B:
        s, t = (B * F - C * E) / (A * E - B * B), (A * F - B * C) / (A * E - B * B)
        if 0 <= s <= 1 and 0 <= t <= 1:
            candidates.append((s, t))
    return math.sqrt(min(squared(s, t) for s, t in candidates))


def test_closest_points_between_segments_against_exact_arithmetic():
    """The distance of the kernel's closest points against the exact least distance, for 300
    pairs of every sort (crossing, skew, end to end) and for pairs at angles from 1e-14 to
    1e-6 rad (below about 1e-8 rad they count as parallel, and the distance is within 1e-8 of
    the length), at sizes from 1 mm to 1 km (what counts as parallel does not depend on the
    size); where parallel segments overlap, the points are the middle of the overlap, square
    across."""
    rng = np.random.default_rng(3)
    c_i, c_j = np.zeros(3), np.zeros(3)
    for k in range(300 + 9 * 20):
        a, b, c, d = rng.normal(size=(4, 3)) * 10.0 ** (3 * (k % 3 - 1))
        bound = 1e-12 * np.abs([a, b, c, d]).max()
        if k >= 300:
            angle = 10.0 ** (-14 + (k - 300) // 20)
            u = b - a
            w = np.cross(u, rng.normal(size=3))
            d = c + rng.uniform(0.3, 2) * (u + angle * np.linalg.norm(u) * w / np.linalg.norm(w))
            bound = 2e-8 * max(np.linalg.norm(u), np.linalg.norm(d - c))
        core.closest_between_segments(a, b, c, d, c_i, c_j)
        s = (c_i - a) @ (b - a) / ((b - a) @ (b - a))
        t = (c_j - c) @ (d - c) / ((d - c) @ (d - c))
        assert -1e-12 <= s <= 1 + 1e-12 and -1e-12 <= t <= 1 + 1e-12
        np.testing.assert_allclose(c_i, a + s * (b - a), rtol=0, atol=bound)
        np.testing.assert_allclose(c_j, c + t * (d - c), rtol=0, atol=bound)
        exact = _exact_segment_distance(a, b, c, d)
        assert np.linalg.norm(c_j - c_i) == pytest.approx(exact, abs=bound), k
    a, b = np.zeros(3), np.array([2.0, 0.0, 0.0])
    for shift, middle in ((0.3, 1.05), (-0.4, 0.55), (1.9, 1.95), (-1.45, 0.025)):
        c, d = np.array([shift, 0.2, 0.0]), np.array([shift + 1.5, 0.2, 0.0])
        for ends in ((c, d), (d, c)):
            core.closest_between_segments(a, b, *ends, c_i, c_j)
            np.testing.assert_allclose(c_i, [middle, 0.0, 0.0], rtol=0, atol=1e-15)
            np.testing.assert_allclose(c_j, [middle, 0.2, 0.0], rtol=0, atol=1e-15)
    # parallel, apart along the line: the nearer ends
    c, d = np.array([2.5, 0.2, 0.0]), np.array([3.5, 0.2, 0.0])
    core.closest_between_segments(a, b, c, d, c_i, c_j)
    np.testing.assert_allclose([c_i, c_j], [b, c], rtol=0, atol=1e-15)
    c, d = np.array([-1.0, 0.2, 0.0]), np.array([-2.0, 0.2, 0.0])
    core.closest_between_segments(a, b, c, d, c_i, c_j)
    np.testing.assert_allclose([c_i, c_j], [a, c], rtol=0, atol=1e-15)


def test_closest_point_of_a_segment_and_a_box_against_scipy():
    rng = np.random.default_rng(5)
    out = np.zeros(3)
    for _ in range(200):
        a, b, p = rng.normal(size=(3, 3))
        core.closest_on_segment(a, b, p, out)
        assert np.linalg.norm(p - out) == pytest.approx(_segment_point(a, b, p), abs=1e-12)
    A = Rotation.random(1, random_state=2).as_matrix()
    half = np.array([0.3, 0.2, 0.5])
    centre, c_i, n = np.array([0.1, -0.2, 0.3]), np.zeros(3), np.zeros(3)
    for k in range(300):
        p = centre + A[0] @ (half * rng.uniform(-1.6, 1.6, size=3))
        distance = core.box_to_point(A, 0, centre, half, p, c_i, n)
        assert distance == pytest.approx(_box_point(centre, A[0], half, p), abs=1e-9)
        local = A[0].T @ (c_i - centre)
        assert np.all(np.abs(local) <= half + 1e-12)  # on the box
        assert np.isclose(np.max(np.abs(local) / half), 1.0, rtol=0, atol=1e-12)  # its surface
        np.testing.assert_allclose(p, c_i + distance * n, rtol=0, atol=1e-12)
        assert np.linalg.norm(n) == pytest.approx(1.0, abs=1e-14)


@pytest.mark.parametrize("dim", [2, 3])
def test_closest_points_of_a_segment_and_a_box_against_scipy_and_qhull(dim):
    """The kernel's signed distance of a segment from a box against :func:`_box_segment`
    (apart: SciPy's least distance; through the box: minus Qhull's least translation that
    parts them), for segments of every sort about a turned box; the points it gives are on the
    segment and on the box's surface, ``distance n`` apart along a unit ``n``. A segment
    lying square above a face is nearest at the middle of what lies over it."""
    rng = np.random.default_rng(7 + dim)
    A = np.zeros((1, 3, 3))
    A[0, :dim, :dim] = Rotation.random(random_state=dim).as_matrix()[:dim, :dim]
    if dim == 2:
        A[0, :2, :2] = [[math.cos(0.7), -math.sin(0.7)], [math.sin(0.7), math.cos(0.7)]]
    half = np.array([0.3, 0.2, 0.5])[:dim]
    centre = np.array([0.1, -0.2, 0.3])
    centre[dim:] = 0.0
    c_i, c_j, n = np.zeros(3), np.zeros(3), np.zeros(3)
    inside = 0
    for k in range(400):
        # apart (moved off by a box's size), about it and far through it
        spread, off = ((1.2, 2.0), (1.8, 0.0), (0.7, 0.0))[k % 3]
        shift = half * off * rng.choice([-1.0, 1.0], dim)
        a, e = np.zeros(3), np.zeros(3)
        a[:dim] = centre[:dim] + A[0, :dim, :dim] @ (
            half * rng.uniform(-spread, spread, dim) + shift)
        e[:dim] = centre[:dim] + A[0, :dim, :dim] @ (
            half * rng.uniform(-spread, spread, dim) + shift)
        distance = core.box_to_segment(A, 0, centre, half, a, e, c_i, c_j, n)
        expected = _box_segment(centre[:dim], A[0, :dim, :dim], half, a[:dim], e[:dim])
        assert distance == pytest.approx(expected, abs=1e-9), k
        inside += distance < 0.0
        t = (c_j - a) @ (e - a) / ((e - a) @ (e - a))
        assert -1e-12 <= t <= 1 + 1e-12
        np.testing.assert_allclose(c_j, a + t * (e - a), rtol=0, atol=1e-12)
        local = A[0, :dim, :dim].T @ (c_i[:dim] - centre[:dim])
        assert np.all(np.abs(local) <= half + 1e-12)  # on the box
        assert np.isclose(np.max(np.abs(local) / half), 1.0, rtol=0, atol=1e-12)  # its surface
        np.testing.assert_allclose(c_j, c_i + distance * n, rtol=0, atol=1e-12)
        assert np.linalg.norm(n) == pytest.approx(1.0, abs=1e-14)
    assert 50 < inside < 350
    # lying square above the top face from beyond its left edge to over it: the middle of the
    # part over the face
    top = centre + A[0] @ np.r_[0.0, half[1], 0.0][:3]
    along, up = A[0] @ np.eye(3)[0], A[0] @ np.eye(3)[1]
    a, e = top + 0.1 * up - 0.8 * along, top + 0.1 * up + 0.1 * along
    assert core.box_to_segment(A, 0, centre, half, a, e, c_i, c_j, n) == pytest.approx(0.1)
    np.testing.assert_allclose(c_j, top + 0.1 * up + 0.5 * (0.1 - 0.3) * along, rtol=0,
                               atol=1e-12)
    np.testing.assert_allclose(n, up, rtol=0, atol=1e-12)
    # and 0.05 below the top face, into the box from beyond its left edge: pushed out through
    # the top at the middle of the part inside
    a, e = a - 0.15 * up, e - 0.15 * up
    assert core.box_to_segment(A, 0, centre, half, a, e, c_i, c_j, n) == pytest.approx(-0.05)
    np.testing.assert_allclose(c_j, top - 0.05 * up + 0.5 * (0.1 - 0.3) * along, rtol=0,
                               atol=1e-12)
    np.testing.assert_allclose(n, up, rtol=0, atol=1e-12)


#: the pairs: (first shape, second shape) built on bodies one and two
PAIRS = ["capsule-sphere", "capsule-capsule", "box-sphere", "sphere-box", "box-capsule",
         "capsule-box", "capsule-plane", "box-plane", "sphere-hole", "capsule-hole"]
#: the hole of body two: its radius and axis (body frame)
R_HOLE, AXIS = 0.4, np.array([0.3, 0.8, -0.5]) / np.linalg.norm([0.3, 0.8, -0.5])
R_I, R_J = 0.15, 0.1
ENDS_I = np.array([[-0.4, 0.1, 0.0], [0.5, -0.1, 0.2]])
ENDS_J = np.array([[0.1, -0.3, 0.1], [-0.2, 0.4, -0.1]])
HALF = np.array([0.3, 0.2, 0.25])
#: the box's rounding: its corners and edges are spheres and cylinders of this radius
R_BOX = 0.03
CENTRE_I, CENTRE_J = np.array([0.05, -0.1, 0.02]), np.array([0.1, 0.05, -0.03])
NORMAL = np.array([0.2, -0.3, -1.0]) / np.linalg.norm([0.2, -0.3, -1.0])


def _pair(kind: str, law):
    b = mb.ModelBuilder(dim=3)
    one = b.add_body("one", mass=2.0, inertia=np.diag([0.1, 0.2, 0.3]), position=(0, 0, 0))
    two = b.add_body("two", mass=3.0, inertia=np.diag([0.3, 0.2, 0.4]), position=(0, 0, 3.0))
    first, second = kind.split("-")
    shapes = {"capsule": lambda body, ends, r: mb.Capsule(body, r, ends=ends),
              "sphere": lambda body, ends, r: mb.Sphere(body, r, point=ends[0]),
              "box": lambda body, ends, r: mb.Box(body, 2 * HALF, point=CENTRE_I,
                                                  radius=R_BOX),
              "plane": lambda body, ends, r: mb.Plane(body, normal=NORMAL, point=CENTRE_J),
              "hole": lambda body, ends, r: mb.Hole(body, R_HOLE, point=CENTRE_J, axis=AXIS)}
    b.add(mb.Contact("touch", shapes[first](one, ENDS_I, R_I),
                     shapes[second](two, ENDS_J, R_J), law=law))
    return b.build()


def _gap(kind, q, charts) -> float:
    """The gap of the pair written from the shapes' definitions."""
    A1, A2 = _rotation(charts[0], q[3:6]), _rotation(charts[1], q[9:12])
    on1 = lambda u: q[0:3] + A1 @ u  # noqa: E731
    on2 = lambda u: q[6:9] + A2 @ u  # noqa: E731
    first, second = kind.split("-")
    if kind == "capsule-sphere":
        return _segment_point(on1(ENDS_I[0]), on1(ENDS_I[1]), on2(ENDS_J[0])) - R_I - R_J
    if kind == "capsule-capsule":
        return _segment_segment(on1(ENDS_I[0]), on1(ENDS_I[1]), on2(ENDS_J[0]),
                                on2(ENDS_J[1])) - R_I - R_J
    if kind == "box-sphere":
        return _box_point(on1(CENTRE_I), A1, HALF, on2(ENDS_J[0])) - R_BOX - R_J
    if kind == "sphere-box":  # the box is body two's, centred at CENTRE_I of it
        return _box_point(on2(CENTRE_I), A2, HALF, on1(ENDS_I[0])) - R_BOX - R_I
    if kind == "box-capsule":
        return _box_segment(on1(CENTRE_I), A1, HALF, on2(ENDS_J[0]), on2(ENDS_J[1])) - R_BOX - R_J
    if kind == "capsule-box":
        return _box_segment(on2(CENTRE_I), A2, HALF, on1(ENDS_I[0]), on1(ENDS_I[1])) - R_BOX - R_I
    if second == "hole":  # the pin's centre off the axis, square to it
        h, P = A2 @ AXIS, on2(CENTRE_J)
        centres = [on1(e) for e in ENDS_I[:2 if first == "capsule" else 1]]
        return np.array([R_HOLE - R_I - np.linalg.norm((np.eye(3) - np.outer(h, h)) @ (c - P))
                         for c in centres])
    m, P = A2 @ NORMAL, on2(CENTRE_J)
    if first == "capsule":
        points, radius = [on1(e) for e in ENDS_I], R_I
    else:
        points = [on1(CENTRE_I + (2 * np.array(s) - 1) * HALF) for s in np.ndindex(2, 2, 2)]
        radius = R_BOX
    return np.array([m @ (c - P) - radius for c in points])


def _overlapping(kind, rng, deep=False):
    """Random charts and rotations, body two moved until the pair overlaps by 1 to 3 mm (the
    deepest row, for a plane), or ``deep`` by 20 to 22 cm (a sphere's centre inside a box)."""
    charts = np.tile(np.eye(3), (3, 1, 1))
    charts[:2] = Rotation.random(2, random_state=rng.integers(1000)).as_matrix()
    q = np.zeros(12)
    q[3:6], q[9:12] = rng.normal(size=3) * 0.6, rng.normal(size=3) * 0.6
    depth = rng.uniform(0.20, 0.22) if deep else rng.uniform(1e-3, 3e-3)
    if kind.endswith("hole"):  # the hole's axis put R_HOLE - R_I + depth from the pin's centre
        A2 = _rotation(charts[1], q[9:12])
        h = A2 @ AXIS
        across = np.cross(h, rng.normal(size=3))
        centre = q[0:3] + _rotation(charts[0], q[3:6]) @ ENDS_I[0]
        hole = (centre - (R_HOLE - R_I + depth) * across / np.linalg.norm(across)
                + rng.normal() * 0.2 * h)
        q[6:9] = hole - A2 @ CENTRE_J
        return q, charts
    if kind.endswith("plane"):  # the plane moved along its normal
        q[6:9] += (np.min(_gap(kind, q, charts)) + depth) * (_rotation(charts[1], q[9:12])
                                                             @ NORMAL)
        return q, charts
    direction = rng.normal(size=3)
    direction /= np.linalg.norm(direction)
    # from where a core point of each shape coincide (deep inside each other) outwards
    anchors = {"capsule": (ENDS_I[0], ENDS_J[0]), "sphere": (ENDS_I[0], ENDS_J[0]),
               "box": (CENTRE_I, CENTRE_I)}
    first, second = kind.split("-")
    start = (_rotation(charts[0], q[3:6]) @ anchors[first][0]
             - _rotation(charts[1], q[9:12]) @ anchors[second][1])

    def gap_at(s):
        x = q.copy()
        x[6:9] = start + s * direction
        return _gap(kind, x, charts) + depth

    q[6:9] = start + brentq(gap_at, 0.0, 3.0, xtol=1e-15) * direction
    return q, charts


@pytest.mark.filterwarnings("ignore::mbd3d.ContactWarning")  # the drawing is any overlap
@pytest.mark.parametrize("kind", PAIRS + ["box-sphere deep", "sphere-box deep",
                                          "box-capsule deep", "capsule-box deep"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_gap_and_force_follow_the_shapes_distance_and_the_hertz_potential(kind, seed):
    """The gap against SciPy's minimised distance (deep: the sphere's centre inside the box,
    below its nearest face); at rest the force is conservative, Q = -dV/dq with V = sum K
    delta^(5/2) / (5/2) over the touching rows."""
    K = 4e6
    kind, deep = kind.split(" ")[0], kind.endswith("deep")
    model = _pair(kind, mb.HertzContact(stiffness=K))
    q, charts = _overlapping(kind, np.random.default_rng(seed), deep)
    states = mb.contact_states(model, q, charts=charts)
    expected_gap = np.atleast_1d(_gap(kind, q, charts))
    assert not deep or expected_gap[0] < -R_BOX - max(R_I, R_J)  # the centre is in the box
    np.testing.assert_allclose(states.gap, expected_gap, rtol=0, atol=1e-9)

    def V(x):
        delta = np.maximum(-np.atleast_1d(_gap(kind, x, charts)), 0.0)
        return float(np.sum(K * delta ** 2.5 / 2.5))

    h = 1e-6
    expected = np.array([-(V(q + h * e) - V(q - h * e)) / (2 * h) for e in np.eye(12)])
    Q = generalized_forces(model, 0.0, constraints.frames(model, q, np.zeros(12), charts))
    np.testing.assert_allclose(Q, expected, rtol=0, atol=2e-5 * np.abs(expected).max())
    assert np.abs(expected).max() > 1.0  # the rows overlap and push


@pytest.mark.parametrize("dim", [2, 3])
def test_parallel_capsules_touch_at_the_middle_of_what_they_share(dim):
    """Two capsules (stadiums in the plane) lying one on the other, offset along their axes:
    the closest points are not unique, and the contact acts at the middle of the overlap,
    square to the axes."""
    b = mb.ModelBuilder(dim=dim)
    lower = b.add_body("lower", mass=1.0, inertia=0.1 if dim == 2 else np.eye(3) * 0.1,
                       position=(0.0, 0.0) + (0.0,) * (dim - 2))
    upper = b.add_body("upper", mass=1.0, inertia=0.1 if dim == 2 else np.eye(3) * 0.1,
                       position=(0.3, 0.19) + (0.0,) * (dim - 2))
    along = lambda x: (x, 0.0) + (0.0,) * (dim - 2)  # noqa: E731
    b.add(mb.Contact("stack", mb.Capsule(lower, 0.1, ends=[along(-0.5), along(1.0)]),
                     mb.Capsule(upper, 0.1, ends=[along(-0.5), along(0.5)]),
                     law=mb.LinearContact(stiffness=1e5, damping=0.0)))
    with pytest.warns(mb.ContactWarning, match="overlap by 0.01 m"):
        model = b.build()
    states = mb.contact_states(model, model.q0)
    # the upper one spans -0.2 to 0.8 of the lower one's -0.5 to 1
    np.testing.assert_allclose(states.point[0], [0.3, 0.095, 0.0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(states.normal[0], [0.0, 1.0, 0.0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(states.normal_force, [1e5 * 0.01], rtol=1e-12, atol=0)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_pin_hangs_in_its_hole_at_the_clearance_plus_its_weights_dent(dim):
    """A revolute clearance joint: a link hanging by a pin of radius 0.02 m in a hole of
    0.021 m in the ground, a linear law of stiffness K: at rest the pin touches the bottom of
    the hole, its centre the clearance plus m g / K below the hole's, and it carries the
    weight. Planar: a circle in a circle; spatial: a sphere in a horizontal cylinder."""
    m, K, r_pin, r_hole = 1.2, 2e6, 0.02, 0.021
    b = mb.ModelBuilder(dim=dim, gravity=(0.0, -G) + (0.0,) * (dim - 2))
    link = b.add_body("link", mass=m, inertia=0.01 if dim == 2 else np.eye(3) * 0.01,
                      position=(0.0,) * dim)
    hole = (mb.Hole(b.ground, r_hole) if dim == 2 else
            mb.Hole(b.ground, r_hole, axis=(0.0, 0.0, 1.0)))
    b.add(mb.Contact("clearance", mb.Sphere(link, r_pin), hole,
                     law=mb.LinearContact(stiffness=K, damping=0.0)))
    model = b.build()
    rest = mb.static_equilibrium(model)
    assert rest.q[0, 1] == pytest.approx(-(r_hole - r_pin) - m * G / K, abs=1e-12)
    states = mb.contact_states(model, rest.q[0])
    assert states.normal_force[0] == pytest.approx(m * G, rel=1e-10)
    np.testing.assert_allclose(states.normal[0], [0.0, -1.0, 0.0], rtol=0, atol=1e-12)
    # the point midway between the hole's wall and the pin's bottom, m g / K below it
    assert states.point[0, 1] == pytest.approx(-(r_hole + 0.5 * m * G / K), abs=1e-12)


def test_a_shaft_in_a_bearing_rests_on_both_ends_sharing_its_weight():
    """A capsule in a horizontal hole touches the hole's wall at both ends, each carrying its
    share of the weight by the lever rule about the centre of mass (0.5 and 0.3 m)."""
    m, K = 2.0, 1e6
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G))
    shaft = b.add_body("shaft", mass=m, inertia=np.diag([1e-3, 0.05, 0.05]), position=(0, 0, 0))
    b.add(mb.Contact("bearing", mb.Capsule(shaft, 0.05, ends=[(-0.3, 0, 0), (0.5, 0, 0)]),
                     mb.Hole(b.ground, 0.051, axis_at=(1.0, 0.0, 0.0)),
                     law=mb.LinearContact(stiffness=K, damping=0.0)))
    model = b.build()
    rest = mb.static_equilibrium(model)
    states = mb.contact_states(model, rest.q[0])
    np.testing.assert_allclose(states.normal_force, [m * G * 0.5 / 0.8, m * G * 0.3 / 0.8],
                               rtol=1e-9, atol=0)
    assert states.names == ["bearing[end a]", "bearing[end b]"]


def test_the_box_and_capsule_rows_are_named_by_corner_and_end():
    model = _pair("box-plane", mb.LinearContact(stiffness=1e5, damping=0.0))
    names = mb.contact_states(model, model.q0).names
    assert names[0] == "touch[corner ---]" and names[-1] == "touch[corner +++]"
    assert len(names) == 8
    model = _pair("capsule-plane", mb.LinearContact(stiffness=1e5, damping=0.0))
    assert mb.contact_states(model, model.q0).names == ["touch[end a]", "touch[end b]"]
    b = mb.ModelBuilder(dim=2)
    box = b.add_body("box", mass=1.0, inertia=0.01, position=(0.0, 0.099))
    b.add(mb.Contact("floor", mb.Box(box, (0.4, 0.2)), mb.Plane(b.ground, normal=(0.0, 1.0)),
                     law=mb.LinearContact(stiffness=1e5, damping=0.0)))
    with pytest.warns(mb.ContactWarning, match=r"contact 'floor\[corner \+-\]': the shapes "
                                               r"overlap by 0\.001 m"):
        b.build()


def test_a_sphere_given_first_against_a_box_reports_in_the_order_given():
    """(Sphere, Box) is evaluated as (Box, Sphere): the normal reported is still from the first
    shape (the sphere on body one) to the second, the friction on the second."""
    model = _pair("sphere-box", mb.HertzContact(stiffness=4e6))
    q, charts = _overlapping("sphere-box", np.random.default_rng(4))
    states = mb.contact_states(model, q, charts=charts)
    sphere = q[0:3] + _rotation(charts[0], q[3:6]) @ ENDS_I[0]
    # the sphere's deepest point lies on the far side of the normal from it
    assert states.normal[0] @ (states.point[0] - sphere) > 0.0
    Q = generalized_forces(model, 0.0, constraints.frames(model, q, np.zeros(12), charts))
    np.testing.assert_allclose(Q[6:9], states.normal_force[0] * states.normal[0], rtol=1e-12,
                               atol=0)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_box_rests_on_its_lower_corners_sharing_its_weight(dim):
    """A linear law of stiffness K: a box lying on the floor sinks by m g / (c K) with c its
    lower corners (2 in the plane, 4 in space) and stays level."""
    m, K = 3.0, 2e5
    b = mb.ModelBuilder(dim=dim, gravity=(0.0,) * (dim - 1) + (-G,))
    size = (0.4, 0.2) if dim == 2 else (0.4, 0.3, 0.2)
    up = np.zeros(dim)
    up[-1] = 0.1
    box = b.add_body("box", mass=m, inertia=0.02 if dim == 2 else np.diag([0.02, 0.03, 0.04]),
                     position=up)
    b.add(mb.Contact("floor", mb.Box(box, size), mb.Plane(b.ground, normal=up / 0.1),
                     law=mb.LinearContact(stiffness=K, damping=0.0)))
    model = b.build()
    rest = mb.static_equilibrium(model)
    corners = 2 ** (dim - 1)
    assert rest.q[0, dim - 1] == pytest.approx(0.1 - m * G / (corners * K), abs=1e-12)
    # level: each lower corner carries its share (sliding and turning about the vertical are
    # free, and any of those positions is a rest)
    charts = None if rest.charts is None else rest.charts[0]
    force = mb.contact_states(model, rest.q[0], charts=charts).normal_force
    np.testing.assert_allclose(np.sort(force)[-corners:], m * G / corners, rtol=1e-10, atol=0)
    np.testing.assert_allclose(np.sort(force)[:-corners], 0.0, rtol=0, atol=0)
    assert rest.stats["stability"] == ["neutral"]


def test_a_capsule_lying_on_the_floor_rests_on_both_ends():
    m, K, r = 2.0, 1e5, 0.05
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G))
    rod = b.add_body("rod", mass=m, inertia=np.diag([1e-3, 0.05, 0.05]), position=(0, 0, r))
    b.add(mb.Contact("floor", mb.Capsule(rod, r, ends=[(-0.3, 0, 0), (0.5, 0, 0)]),
                     mb.Plane(b.ground, normal=(0, 0, 1)),
                     law=mb.LinearContact(stiffness=K, damping=0.0)))
    model = b.build()
    rest = mb.static_equilibrium(model)
    # the ends share the weight by the lever rule about the centre of mass: 0.5 and 0.3 m
    states = mb.contact_states(model, rest.q[0])
    np.testing.assert_allclose(states.normal_force, [m * G * 0.5 / 0.8, m * G * 0.3 / 0.8],
                               rtol=1e-10, atol=0)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_plank_hinged_at_one_end_rests_on_a_box_edge_by_the_moment_balance(dim):
    """A plank (a capsule of radius r) hinged to the ground at its end leans on the top edge
    ``E = (D, H)`` of a fixed box (planar: its corner), pressing it by a linear law of
    stiffness K: at rest the contact's moment about the hinge, ``K (r - d) (E . u)`` with ``d
    = D sin(theta) - H cos(theta)`` the edge's distance from the plank's axis ``u``, balances
    the weight's ``m g L / 2 cos(theta)`` (solved by Brent's method apart from the model); the
    force is square to the plank, at the edge."""
    m, L, r, K, D, H = 2.0, 1.0, 0.02, 1e6, 0.5, 0.3
    touching = brentq(lambda a: D * math.sin(a) - H * math.cos(a) - r, 0.0, 1.5)
    drawn = touching - 1e-4  # pressed in a little
    b = mb.ModelBuilder(dim=dim, gravity=(0.0, -G) + (0.0,) * (dim - 2))
    pad = (0.0,) * (dim - 2)
    axis = np.array([math.cos(drawn), math.sin(drawn)])
    pose = ({"angle": drawn} if dim == 2 else
            {"orientation": Rotation.from_rotvec([0, 0, drawn]).as_matrix()})
    plank = b.add_body("plank", mass=m, position=tuple(0.5 * L * axis) + pad,
                       inertia=m * L ** 2 / 12 if dim == 2 else np.diag([1e-4, 1.0, 1.0])
                       * m * L ** 2 / 12, **pose)
    b.add(mb.joints.Revolute("hinge", b.ground, plank, at=(0.0, 0.0) + pad,
                             **({} if dim == 2 else {"axis": (0.0, 0.0, 1.0)})))
    step = mb.Box(b.ground, (0.4, 0.3) + (0.2,) * (dim - 2), at=(D + 0.2, H - 0.15) + pad)
    b.add(mb.Contact("lean", step, mb.Capsule(plank, r, ends=[(-L / 2, 0.0) + pad,
                                                              (L / 2, 0.0) + pad]),
                     law=mb.LinearContact(stiffness=K, damping=0.0)))
    with pytest.warns(mb.ContactWarning, match="contact 'lean': the shapes overlap"):
        model = b.build()
    rest = mb.static_equilibrium(model)

    def moments(a):
        return (K * (r - (D * math.sin(a) - H * math.cos(a))) * (D * math.cos(a)
                + H * math.sin(a)) - m * G * L / 2 * math.cos(a))
    expected = brentq(moments, touching - 0.1, touching, xtol=1e-15)
    tip = np.asarray(rest.point("plank", (L / 2, 0.0) + pad))[0]
    assert math.atan2(tip[1], tip[0]) == pytest.approx(expected, abs=1e-10)
    charts = None if rest.charts is None else rest.charts[0]
    states = mb.contact_states(model, rest.q[0], charts=charts)
    u = np.array([math.cos(expected), math.sin(expected)])
    force = m * G * L / 2 * math.cos(expected) / (u @ [D, H])
    assert states.normal_force[0] == pytest.approx(force, rel=1e-9)
    np.testing.assert_allclose(states.normal[0][:2], [-u[1], u[0]], rtol=0, atol=1e-9)
    # midway between the edge and the plank's surface, pressed delta = F / K below it
    np.testing.assert_allclose(states.point[0][:2], np.array([D, H]) - force / K / 2
                               * np.array([-u[1], u[0]]), rtol=0, atol=1e-12)


def _head_on(first, second, law, closing=2.0):
    """Two free bodies of 1 kg closing at ``closing`` m/s along x, centres 1.25 m apart, no
    gravity; the measured restitution."""
    b = mb.ModelBuilder(dim=3)
    inertia = np.eye(3) * 0.1
    left = b.add_body("left", mass=1.0, inertia=inertia, position=(-0.625, 0, 0),
                      velocity=(closing / 2, 0, 0))
    right = b.add_body("right", mass=1.0, inertia=inertia, position=(0.625, 0, 0),
                       velocity=(-closing / 2, 0, 0))
    b.add(mb.Contact("pair", first(left), second(right), law=law))
    res = mb.forward_dynamics(b.build(), [0.0, 0.3], method="DOP853", rtol=1e-11, atol=1e-13)
    return (res.qd[-1, 6] - res.qd[-1, 0]) / closing, res


@pytest.mark.parametrize("pair", ["sphere on a capsule", "crossed capsules", "sphere on a box",
                                  "capsule on a box"])
@pytest.mark.parametrize("e", [0.3, 0.8])
def test_head_on_impacts_rebound_with_the_calibrated_restitution(pair, e):
    """Chrono's restitution test with the spheres replaced: struck at its middle, square to
    its axis or face, a capsule or a box takes the impact as a sphere would, so the law's
    calibration to e holds exactly and no body turns (a capsule lying along a box's face is
    pushed at the middle of what faces it)."""
    sphere = lambda body: mb.Sphere(body, 0.5)  # noqa: E731
    across_y = lambda body: mb.Capsule(body, 0.5, ends=[(0, -0.4, 0), (0, 0.4, 0)])  # noqa
    across_z = lambda body: mb.Capsule(body, 0.5, ends=[(0, 0, -0.4), (0, 0, 0.4)])  # noqa
    box = lambda body: mb.Box(body, (1.0, 0.8, 0.6))  # noqa: E731
    first, second = {"sphere on a capsule": (sphere, across_y),
                     "crossed capsules": (across_y, across_z),
                     "sphere on a box": (box, sphere), "capsule on a box": (box, across_y)}[pair]
    law = mb.LinearContact(stiffness=1e5, restitution=e)
    measured, res = _head_on(first, second, law)
    assert measured == pytest.approx(e, abs=1e-8)
    np.testing.assert_allclose(res.qd[-1, [3, 4, 5, 9, 10, 11]], 0.0, rtol=0, atol=1e-9)


def test_a_box_bouncing_on_its_corners_keeps_its_energy():
    """An undamped linear law: a box dropped tilted onto the floor strikes corner after corner
    (rows that open and close) and keeps its energy, which only the integrator's error
    changes."""
    m, K = 2.0, 1e6
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G))
    tilt = Rotation.from_rotvec([0.3, -0.2, 0.1])
    box = b.add_body("box", mass=m, inertia=np.diag([0.02, 0.03, 0.04]), position=(0, 0, 0.4),
                     orientation=tilt.as_matrix(), angular_velocity=(1.0, 0.5, -2.0))
    b.add(mb.Contact("floor", mb.Box(box, (0.3, 0.2, 0.1)), mb.Plane(b.ground, normal=(0, 0, 1)),
                     law=mb.LinearContact(stiffness=K, damping=0.0)))
    model = b.build()
    res = mb.forward_dynamics(model, np.linspace(0.0, 1.5, 301), method="DOP853", rtol=1e-10,
                              atol=1e-12)
    charts = [None] * len(res.t) if res.charts is None else res.charts
    kinetic = np.array([mb.kinetic_energy(model, q, qd, c)
                        for q, qd, c in zip(res.q, res.qd, charts)])
    total = kinetic + np.array([mb.potential_energy(model, q, c) for q, c in zip(res.q, charts)])
    assert np.ptp(kinetic) > 1.0  # it fell and struck
    np.testing.assert_allclose(total, total[0], rtol=0, atol=1e-8 * np.ptp(kinetic))


def test_a_capsule_tumbling_across_a_box_edge_keeps_its_energy():
    """An undamped linear law: a rod dropped turning onto a fixed box strikes it near an edge
    with its end, then another edge with its middle (the nearest points moving along the rod
    and over the box's faces and edges) and tumbles off, keeping its energy, which only the
    integrator's error changes."""
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G))
    rod = b.add_body("rod", mass=1.5, inertia=np.diag([2e-3, 0.05, 0.05]),
                     position=(0.12, 0.02, 0.15),
                     orientation=Rotation.from_rotvec([0.1, 0.35, 0.8]).as_matrix(),
                     angular_velocity=(1.0, -2.0, 0.5))
    b.add(mb.Contact("edge", mb.Box(b.ground, (0.4, 0.4, 0.2), at=(-0.1, 0.0, -0.1)),
                     mb.Capsule(rod, 0.03, ends=[(-0.3, 0, 0), (0.3, 0, 0)]),
                     law=mb.LinearContact(stiffness=1e6, damping=0.0)))
    model = b.build()
    res = mb.forward_dynamics(model, np.linspace(0.0, 1.0, 201), method="DOP853", rtol=1e-10,
                              atol=1e-12)
    kinetic = np.array([mb.kinetic_energy(model, q, qd, c)
                        for q, qd, c in zip(res.q, res.qd, res.charts)])
    total = kinetic + np.array([mb.potential_energy(model, q, c)
                                for q, c in zip(res.q, res.charts)])
    assert np.max(res.contacts().normal_force) > 500.0  # it struck
    assert res.body("rod").position[-1, 2] < -1.0  # and fell off
    np.testing.assert_allclose(total, total[0], rtol=0, atol=1e-10 * np.ptp(kinetic))


def test_bad_shapes_are_named():
    law = mb.LinearContact(stiffness=1e5, damping=0.0)
    cases = [
        (lambda one: mb.Capsule(one, 0.1, ends=[(0, 0, 0), (0, 0, 0)]), "ends coincide"),
        (lambda one: mb.Capsule(one, 0.1, ends=[(0, 0, 0)]), "two points"),
        (lambda one: mb.Capsule(one, 0.1), "ends in the body frame"),
        (lambda one: mb.Capsule(one, -0.1, ends=[(0, 0, 0), (1, 0, 0)]), "radius"),
        (lambda one: mb.Box(one, (0.1, 0.0, 0.2)), "edge lengths must be > 0"),
        (lambda one: mb.Box(one, (0.1, 0.2)), "box size"),
        (lambda one: mb.Box(one, (0.1, 0.1, 0.1), radius=-1.0), "radius must be >= 0"),
    ]
    for shape, words in cases:
        b = mb.ModelBuilder(dim=3)
        one = b.add_body("one", mass=1.0, inertia=np.eye(3) * 0.1, position=(0, 0, 0))
        two = b.add_body("two", mass=1.0, inertia=np.eye(3) * 0.1, position=(0, 0, 2))
        b.add(mb.Contact("touch", shape(one), mb.Plane(two, normal=(0, 0, 1)), law=law))
        with pytest.raises(mb.ModelError, match=words) as info:
            b.build()
        assert "contact 'touch'" in str(info.value)
    holes = [(lambda two: mb.Hole(two, 0.05, axis=(0, 0, 1)), "the pin must be narrower"),
             (lambda two: mb.Hole(two, 0.5), "the hole's axis"),
             (lambda two: mb.Hole(two, 0.5, axis=(0, 0, 1), axis_at=(0, 0, 1)), "the hole's axis")]
    for hole, words in holes:
        b = mb.ModelBuilder(dim=3)
        one = b.add_body("one", mass=1.0, inertia=np.eye(3) * 0.1, position=(0, 0, 0))
        two = b.add_body("two", mass=1.0, inertia=np.eye(3) * 0.1, position=(0, 0, 2))
        b.add(mb.Contact("pin", mb.Sphere(one, 0.1), hole(two), law=law))
        with pytest.raises(mb.ModelError, match=f"contact 'pin': .*{words}"):
            b.build()
    with pytest.raises(mb.ModelError, match="no contact between a Box and a Hole; the pairs "
                       "are Box-Box, Box-Capsule"):
        mb.Contact("boxes", mb.Box(one, (1, 1, 1)), mb.Hole(two, 0.1, axis=(0, 0, 1)), law=law)
    b = mb.ModelBuilder(dim=3)
    one = b.add_body("one", mass=1.0, inertia=np.eye(3) * 0.1, position=(0, 0, 0))
    b.add(mb.Contact("sharp", mb.Box(one, (1, 1, 1)), mb.Plane(b.ground, normal=(0, 0, 1),
                                                               at=(0, 0, -1)),
                     law=mb.HertzContact(young_modulus=2e11, poisson_ratio=0.3,
                                         restitution=0.5)))
    with pytest.raises(mb.ModelError, match="contact 'sharp': Hertz's stiffness needs a curved"):
        b.build()


def test_capsules_and_boxes_round_trip_through_a_model_file(tmp_path):
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G))
    rod = b.add_body("rod", mass=1.0, inertia=np.diag([1e-3, 0.05, 0.05]), position=(0, 0, 0.5))
    crate = b.add_body("crate", mass=2.0, inertia=np.diag([0.02, 0.03, 0.04]),
                       position=(1.0, 0, 0.5))
    floor = mb.Plane(b.ground, normal=(0, 0, 1))
    law = mb.LinearContact(stiffness=1e5, restitution=0.5)
    b.add(mb.Contact("rod floor", mb.Capsule(rod, 0.05, ends=[(-0.3, 0, 0), (0.3, 0, 0)]),
                     floor, law=law, friction=0.3))
    b.add(mb.Contact("crate floor", mb.Box(crate, (0.3, 0.2, 0.1), radius=0.01), floor,
                     law=law))
    b.add(mb.Contact("rod crate", mb.Box(crate, (0.3, 0.2, 0.1)), mb.Sphere(rod, 0.05),
                     law=law))
    b.add(mb.Contact("rod across crate", mb.Capsule(rod, 0.05, ends=[(-0.3, 0, 0), (0.3, 0, 0)]),
                     mb.Box(crate, (0.3, 0.2, 0.1), radius=0.01), law=law, friction=0.2))
    b.add(mb.Contact("pin", mb.Sphere(rod, 0.02, at=(0.3, 0.0, 0.5)),
                     mb.Hole(crate, 0.03, at=(0.3, 0.0, 0.5), axis_at=(0.0, 1.0, 0.0)), law=law))
    model = b.build()
    path = tmp_path / "shapes.yaml"
    again = mb.load(mb.save(model, path))
    t = np.linspace(0.0, 0.5, 11)
    one = mb.forward_dynamics(model, t, method="DOP853", rtol=1e-9)
    two = mb.forward_dynamics(again, t, method="DOP853", rtol=1e-9)
    np.testing.assert_array_equal(one.q, two.q)
    assert mb.contact_states(again, two.q[-1]).names == mb.contact_states(model, one.q[-1]).names
