"""The shapes a contact is made of, fixed to bodies: a sphere (planar: a circle), a capsule (a
segment with a radius; planar: a stadium), a box along its body's axes (optionally rounded),
a plane (planar: a line) bounding a half-space, a round hole a pin moves in and a planar disc
cam; and how a pair of them becomes the rows of the compiled core
(:mod:`mbd3d.numerics.compiled.contacts`).

A pair is one row, or several where a shape touches at several points at once: a capsule
against a plane at its two ends, a box against a plane at its corners (4 in the plane, 8 in
space), each pushing on its own, so that a capsule or a box lying flat is carried at both ends
or at all its lower corners.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.model.body import Body
from mbd3d.model.cam_profile import CamProfile
from mbd3d.model.forces import resolve_point
from mbd3d.numerics.checks import finite_scalar
from mbd3d.numerics.compiled import contact_grid as grid, contacts as kernel

if TYPE_CHECKING:
    from mbd3d.model.builder import BuildContext

__all__ = ["Sphere", "Plane", "Capsule", "Box", "Hole", "Cam", "PairRows", "Outline",
           "pair_order", "pair_rows", "outline", "shape_core"]


@dataclass(frozen=True)
class Sphere:
    """A sphere (planar model: a circle) of ``radius`` [m] fixed to ``body``, centred at
    ``point`` (body frame [m]) or at ``at`` (global point of the drawing); default the body's
    reference point.

    Parameters
    ----------
    body : Body
        The body it is fixed to.
    radius : float
        [m], positive.
    point : array_like, optional
        Its centre in the body frame [m].
    at : array_like, optional
        Its centre in global coordinates of the drawing [m], instead of ``point``.
    """

    body: Body
    radius: float
    point: Any = None
    at: Any = None


@dataclass(frozen=True)
class Plane:
    """The half-space (planar model: half-plane) of ``body`` bounded by the plane (line)
    through ``point`` (body frame) or ``at`` (drawing) with outward ``normal`` (body frame,
    or ``normal_at`` in the drawing's axes): the side the normal points to is free.

    Parameters
    ----------
    body : Body
        The body it is fixed to.
    normal : array_like, optional
        The outward normal in the body frame.
    point : array_like, optional
        A point of the plane in the body frame [m].
    at : array_like, optional
        A point of the plane in global coordinates of the drawing [m], instead of ``point``.
    normal_at : array_like, optional
        The outward normal in the drawing's axes, instead of ``normal``.
    """

    body: Body
    normal: Any = None
    point: Any = None
    at: Any = None
    normal_at: Any = None


@dataclass(frozen=True)
class Capsule:
    """All points within ``radius`` [m] of the segment between two points fixed to ``body``
    (planar model: a stadium): ``ends`` in the body frame [m] or ``ends_at`` in the drawing,
    two points each. A cylinder with rounded ends; a rod, a pin, a link's outline.

    Parameters
    ----------
    body : Body
        The body it is fixed to.
    radius : float
        [m], positive.
    ends : (2, dim) array_like, optional
        The segment's ends in the body frame [m].
    ends_at : (2, dim) array_like, optional
        The ends in global coordinates of the drawing [m], instead of ``ends``.
    """

    body: Body
    radius: float
    ends: Any = None
    ends_at: Any = None


@dataclass(frozen=True)
class Box:
    """A box fixed to ``body`` with its edges along the body's axes: edge lengths ``size``
    [m] (planar model: a rectangle, two lengths), centred at ``point`` (body frame) or ``at``
    (drawing), default the body's reference point; its edges and corners rounded by
    ``radius`` [m] (default 0: sharp).

    Parameters
    ----------
    body : Body
        The body it is fixed to.
    size : array_like
        Edge lengths along the body's axes [m] (two in a planar model, three in space).
    point : array_like, optional
        Its centre in the body frame [m].
    at : array_like, optional
        Its centre in global coordinates of the drawing [m], instead of ``point``.
    radius : float
        Rounding of the edges and corners [m], >= 0.
    """

    body: Body
    size: Any
    point: Any = None
    at: Any = None
    radius: float = 0.0


@dataclass(frozen=True)
class Hole:
    """A round hole through ``body`` (planar model: a circle; spatial: a cylinder without
    ends) of ``radius`` [m] about the axis through ``point`` (body frame) or ``at``
    (drawing), default the body's reference point, along ``axis`` (body frame) or ``axis_at``
    (the drawing's axes; spatial models only). A sphere or a capsule of another body moves
    inside it and is pushed back from its wall: a pin in a hole with clearance (a revolute
    clearance joint), a ball in a tube, a shaft in a bearing.

    Parameters
    ----------
    body : Body
        The body it is fixed to.
    radius : float
        [m], positive.
    point : array_like, optional
        A point of its axis in the body frame [m].
    at : array_like, optional
        A point of its axis in global coordinates of the drawing [m], instead of ``point``.
    axis : array_like, optional
        Its axis in the body frame (spatial models).
    axis_at : array_like, optional
        Its axis in the drawing's axes, instead of ``axis`` (spatial models).
    """

    body: Body
    radius: float
    point: Any = None
    at: Any = None
    axis: Any = None
    axis_at: Any = None


@dataclass(frozen=True)
class Cam:
    """A disc cam fixed to ``body`` (planar models): the region inside the closed curve
    ``profile`` (a :class:`~mbd3d.joints.CamProfile`, polar about the cam's centre in the
    body's axes), centred at ``point`` (body frame) or ``at`` (drawing), default the body's
    reference point. The curve is the cam's surface; from the pitch curve of a roller of
    radius ``d``, ``pitch.surface(d)``, from a flat-faced follower's support function ``h``,
    ``h.envelope()``. A sphere (circle) touches it from outside, a roller follower (a knife
    edge: a small radius), or a plane (line), a flat face, whose gap is measured to the cam's
    point farthest towards it (a convex cam's support point); either may leave the cam and
    land on it again.

    Parameters
    ----------
    body : Body
        The body it is fixed to.
    profile : CamProfile
        The cam's surface, polar about its centre in the body's axes [m].
    point : array_like, optional
        Its centre in the body frame [m].
    at : array_like, optional
        Its centre in global coordinates of the drawing [m], instead of ``point``.
    """

    body: Body
    profile: Any
    point: Any = None
    at: Any = None


@dataclass(frozen=True)
class PairRows:
    """A pair of shapes as rows of the compiled core: the body points ``points (r, 4, dim)``
    and ``(kind, r_i, r_j)`` per row, with the shapes' radius of curvature at the touch (for
    Hertz's law), a label per row, and ``swapped`` where the core's body i is the second
    shape's (the pair was given the other way round); a cam's curve as the core reads it
    (:mod:`mbd3d.numerics.compiled.curves`), else None."""

    points: np.ndarray
    kinds: list
    radius: float
    labels: list
    swapped: bool | np.ndarray  # or per row
    curve: np.ndarray | None = None


#: the pairs the core evaluates, first shape (its body i) then second
_PAIRS = {(Sphere, Plane), (Sphere, Sphere), (Capsule, Plane), (Capsule, Sphere),
          (Capsule, Capsule), (Box, Plane), (Box, Sphere), (Box, Capsule), (Box, Box),
          (Sphere, Hole), (Capsule, Hole), (Cam, Sphere), (Cam, Plane)}


def pair_order(first: Any, second: Any, what: str) -> bool:
    """Whether the pair ``(first, second)`` is evaluated the other way round (the core's body
    i is the second shape's); a pair the core has no contact for is refused."""
    kinds = (type(first), type(second))
    if kinds in _PAIRS:
        return False
    if kinds[::-1] in _PAIRS:
        return True
    names = ", ".join(sorted(f"{a.__name__}-{b.__name__}" for a, b in _PAIRS))
    raise ModelError(f"{what}: no contact between a {kinds[0].__name__} and a "
                     f"{kinds[1].__name__}; the pairs are {names}, in either order")


def pair_rows(ctx: "BuildContext", first: Any, second: Any, what: str) -> PairRows:
    """The rows of the contact between ``first`` and ``second`` (either order of a supported
    pair), checked, with every message naming ``what``."""
    if pair_order(first, second, what):
        return _rows(ctx, second, first, what, swapped=True)
    return _rows(ctx, first, second, what, swapped=False)


def _rows(ctx, first, second, what, swapped) -> PairRows:
    if first.body is second.body:
        raise ModelError(f"{what}: both shapes are on body '{first.body.name}'")
    if isinstance(first, Cam):
        return _on_cam(ctx, first, second, what, swapped)
    r_i, core_i = _core(ctx, first, what)
    if isinstance(second, Plane):
        P = resolve_point(ctx, second.body, second.point, second.at, f"{what}: plane point")
        m = _plane_normal(ctx, second, what)
        rows = [np.stack([c, P, m, np.zeros(ctx.dim)]) for c in core_i]
        labels = ([""] if len(core_i) == 1 else _labels(first, ctx.dim))
        return PairRows(np.stack(rows), [(kernel.SPHERE_PLANE, r_i, 0.0)] * len(rows),
                        r_i, labels, swapped)
    if isinstance(second, Hole):
        return _in_hole(ctx, first, second, r_i, core_i, what, swapped)
    if isinstance(second, Box):
        return _box_on_box(ctx, first, second, what)
    r_j, core_j = _core(ctx, second, what)
    kind = {Sphere: kernel.SPHERE_SPHERE, Capsule: kernel.SEGMENT_SPHERE,
            Box: kernel.BOX_SPHERE}[type(first)]
    if isinstance(second, Capsule):
        kind = kernel.BOX_SEGMENT if isinstance(first, Box) else kernel.SEGMENT_SEGMENT
    cores = list(core_i) + list(core_j)
    if isinstance(first, Box):  # the centre and half sizes, not the corners
        cores = list(_box(ctx, first, what)[1:]) + list(core_j)
    points = np.zeros((1, kernel.POINTS, ctx.dim))
    points[0, :len(cores)] = cores
    radius = r_i * r_j / (r_i + r_j) if r_i + r_j > 0 else 0.0
    return PairRows(points, [(kind, r_i, r_j)], radius, [""], swapped)


def _box_on_box(ctx, first: Box, second: Box, what: str) -> PairRows:
    """Two boxes: each corner of either against the other box, a row each (the core's box is
    body i: the rows of the first box's corners are the pair the other way round). Faces and
    corners meet this way; two edges that cross with no corner inside the other box do not."""
    r_a, centre_a, half_a = _box(ctx, first, what)
    r_b, centre_b, half_b = _box(ctx, second, what)
    corners_a, corners_b = _core(ctx, first, what)[1], _core(ctx, second, what)[1]
    zero = np.zeros(ctx.dim)
    points = ([np.stack([centre_b, half_b, c, zero]) for c in corners_a]
              + [np.stack([centre_a, half_a, c, zero]) for c in corners_b])
    kinds = ([(kernel.BOX_SPHERE, r_b, r_a)] * len(corners_a)
             + [(kernel.BOX_SPHERE, r_a, r_b)] * len(corners_b))
    labels = ([f"first {label}" for label in _labels(first, ctx.dim)]
              + [f"second {label}" for label in _labels(second, ctx.dim)])
    swapped = np.arange(len(points)) < len(corners_a)
    radius = r_a * r_b / (r_a + r_b) if r_a + r_b > 0 else 0.0
    return PairRows(np.stack(points), kinds, radius, labels, swapped)


def _in_hole(ctx, pin, hole: Hole, r_i: float, core_i: np.ndarray, what: str,
             swapped: bool) -> PairRows:
    """A pin (a sphere, or a capsule's two ends) in a hole: a row per pin point."""
    r_j = finite_scalar(hole.radius, f"{what}: radius of the hole", positive=True)
    if not r_i < r_j:
        raise ModelError(f"{what}: the pin must be narrower than the hole, got a radius of "
                         f"{r_i:g} m in a hole of {r_j:g} m")
    centre, axis = _hole_axis(ctx, hole, what)
    rows = np.stack([np.stack([c, centre, axis, np.zeros(ctx.dim)]) for c in core_i])
    labels = [""] if len(core_i) == 1 else _labels(pin, ctx.dim)
    # Hertz's radius of a convex pin in a concave hole
    return PairRows(rows, [(kernel.PIN_IN_HOLE, r_i, r_j)] * len(rows), r_i * r_j / (r_j - r_i),
                    labels, swapped)


def _on_cam(ctx, cam: Cam, other: Any, what: str, swapped: bool) -> PairRows:
    """A sphere (a roller, a knife edge) or a plane (a flat face) on a cam: one row, the
    curve's offset and interval count filled in by the contacts' table
    (:class:`mbd3d.model.contacts._Contacts`)."""
    centre, profile = _cam(ctx, cam, what)
    points = np.zeros((1, kernel.POINTS, ctx.dim))
    points[0, 0] = centre
    # Hertz's radius with the cam's base circle (its smallest radius), where a follower rests
    base = float(np.min(profile(np.linspace(0.0, 2 * np.pi, 720, endpoint=False))))
    if isinstance(other, Plane):
        points[0, 1] = resolve_point(ctx, other.body, other.point, other.at,
                                     f"{what}: plane point")
        points[0, 2] = _plane_normal(ctx, other, what)
        return PairRows(points, [(kernel.CAM_PLANE, 0.0, 0.0)], base, [""], swapped,
                        profile.table())
    r_j, core_j = _core(ctx, other, what)
    points[0, 1] = core_j[0]
    return PairRows(points, [(kernel.CAM_SPHERE, 0.0, r_j)], r_j * base / (r_j + base), [""],
                    swapped, profile.table())


def _cam(ctx, cam: Cam, what: str) -> tuple[np.ndarray, CamProfile]:
    """A cam's centre in its body frame and its profile, checked."""
    if ctx.dim != 2:
        raise ModelError(f"{what}: cams are available for planar models only (dim=2) so far")
    if not isinstance(cam.profile, CamProfile):
        raise ModelError(f"{what}: the cam's profile must be a CamProfile (angles and radii, "
                         f"or CamProfile.sampled(function)), got a "
                         f"{type(cam.profile).__name__}")
    return resolve_point(ctx, cam.body, cam.point, cam.at, f"{what}: cam centre"), cam.profile


@dataclass(frozen=True)
class Outline:
    """A shape resolved in its body's frame, for drawing: ``kind`` its class name; ``radius``
    [m] (a sphere's, capsule's, hole's or a box's rounding; 0 for a plane or a cam);
    ``points`` (p, dim) [m]: a sphere's centre, a capsule's two ends, a box's centre and half
    sizes, a plane's point and unit normal, a hole's centre and unit axis (planar: zero), a
    cam's surface (closed: the last point is the first)."""

    body: Body
    kind: str
    radius: float
    points: np.ndarray


def outline(ctx: "BuildContext", shape: Any, what: str) -> Outline:
    """``shape`` in its body's frame (see :class:`Outline`), checked as its contact was."""
    kind = type(shape).__name__
    if isinstance(shape, Plane):
        point = resolve_point(ctx, shape.body, shape.point, shape.at, f"{what}: plane point")
        return Outline(shape.body, kind, 0.0, np.stack([point, _plane_normal(ctx, shape, what)]))
    if isinstance(shape, Hole):
        radius = finite_scalar(shape.radius, f"{what}: radius of the hole", positive=True)
        return Outline(shape.body, kind, radius, np.stack(_hole_axis(ctx, shape, what)))
    if isinstance(shape, Box):
        radius, centre, half = _box(ctx, shape, what)
        return Outline(shape.body, kind, radius, np.stack([centre, half]))
    if isinstance(shape, Cam):
        centre, profile = _cam(ctx, shape, what)
        phi = np.linspace(0.0, 2 * np.pi, 361)
        return Outline(shape.body, kind, 0.0, centre + profile.offset(phi, 0.0))
    radius, core = _core(ctx, shape, what)
    return Outline(shape.body, kind, radius, core)


def shape_core(ctx: "BuildContext", shape: Any, what: str) -> tuple[int, float, np.ndarray]:
    """``(kind, radius, points)`` of a sphere, a capsule, a box or a plane of a contact group
    in its body frame (see :mod:`mbd3d.numerics.compiled.contact_grid`; a plane's radius
    infinite, a box's its rounding)."""
    if isinstance(shape, Plane):
        P = resolve_point(ctx, shape.body, shape.point, shape.at, f"{what}: plane point")
        return grid.PLANE, math.inf, np.stack([P, _plane_normal(ctx, shape, what)])
    if isinstance(shape, Box):
        radius, centre, half = _box(ctx, shape, what)
        return grid.BOX, radius, np.stack([centre, half])
    radius, core = _core(ctx, shape, what)
    return (grid.SPHERE if isinstance(shape, Sphere) else grid.CAPSULE), radius, core


def _hole_axis(ctx, hole: Hole, what: str) -> tuple[np.ndarray, np.ndarray]:
    """A hole's centre and unit axis in its body frame (planar: the axis is zero)."""
    centre = resolve_point(ctx, hole.body, hole.point, hole.at, f"{what}: hole centre")
    if ctx.dim == 2:
        if hole.axis is not None or hole.axis_at is not None:
            raise ModelError(f"{what}: the hole's axis is the plane's normal in a planar model; "
                             "leave axis and axis_at out")
        axis = np.zeros(2)
    elif (hole.axis is None) == (hole.axis_at is None):
        raise ModelError(f"{what}: give the hole's axis in the body frame (axis) or in the "
                         "drawing (axis_at), one of them")
    elif hole.axis is not None:
        axis = ctx.direction(hole.axis, f"{what}: the hole's axis")
    else:
        axis = ctx.to_local_vector(hole.body, ctx.direction(hole.axis_at,
                                                            f"{what}: the hole's axis"))
    return centre, axis


def _core(ctx, shape, what) -> tuple[float, np.ndarray]:
    """``(radius, core points (c, dim))`` of a shape in its body frame: a sphere's centre, a
    capsule's two ends, a box's corners."""
    name = type(shape).__name__.lower()
    if isinstance(shape, Box):
        radius, centre, half = _box(ctx, shape, what)
        signs = np.array(list(itertools.product((-1.0, 1.0), repeat=ctx.dim)))
        return radius, centre + signs * half
    radius = finite_scalar(shape.radius, f"{what}: radius of the {name}", positive=True)
    if isinstance(shape, Sphere):
        centre = resolve_point(ctx, shape.body, shape.point, shape.at, f"{what}: sphere centre")
        return radius, centre[None]
    if (shape.ends is None) == (shape.ends_at is None):
        raise ModelError(f"{what}: give the capsule's two ends in the body frame (ends) or in "
                         "the drawing (ends_at), one of them")
    given = shape.ends if shape.ends is not None else shape.ends_at
    if np.shape(given)[:1] != (2,):
        raise ModelError(f"{what}: the capsule's ends are two points, got {given!r}")
    in_body = shape.ends is not None
    ends = np.stack([resolve_point(ctx, shape.body, e if in_body else None,
                                   None if in_body else e, f"{what}: capsule end")
                     for e in given])
    if not np.linalg.norm(ends[1] - ends[0]) > 0.0:
        raise ModelError(f"{what}: the capsule's two ends coincide; give a Sphere instead")
    return radius, ends


def _box(ctx, box: Box, what: str) -> tuple[float, np.ndarray, np.ndarray]:
    """``(rounding radius, centre, half sizes)`` of a box in its body frame, checked."""
    radius = finite_scalar(box.radius, f"{what}: radius of the box")
    if radius < 0.0:
        raise ModelError(f"{what}: the box's radius must be >= 0, got {box.radius!r}")
    size = ctx.vector(box.size, f"{what}: box size")
    if not np.all(size > 0.0):
        raise ModelError(f"{what}: the box's edge lengths must be > 0, got {box.size!r}")
    centre = resolve_point(ctx, box.body, box.point, box.at, f"{what}: box centre")
    return radius, centre, 0.5 * size


def _labels(shape, dim: int) -> list:
    """Names of a shape's touching points: a capsule's ends a and b, a box's corners by the
    signs of their body coordinates."""
    if isinstance(shape, Capsule):
        return ["end a", "end b"]
    return ["corner " + "".join("-+"[s > 0] for s in signs)
            for signs in itertools.product((-1.0, 1.0), repeat=dim)]


def _plane_normal(ctx: "BuildContext", plane: Plane, what: str) -> np.ndarray:
    if (plane.normal is None) == (plane.normal_at is None):
        raise ModelError(f"{what}: give the plane's normal in the body frame (normal) or in "
                         "the drawing (normal_at), one of them")
    if plane.normal is not None:
        return ctx.direction(plane.normal, f"{what}: plane normal")
    return ctx.to_local_vector(plane.body, ctx.direction(plane.normal_at, f"{what}: plane normal"))
