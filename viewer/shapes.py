"""What each body looks like in the viewer: its own mesh, or one drawn from where it is joined.

A body given a ``shape`` (see ``ModelBuilder.add_body``) is drawn with it. Otherwise the shape
comes from the model, the way a mechanism is sketched on paper: a link is a bar (a capsule)
between its joint points, a ternary link the outline through its points, a slider a block along
its sliding axis, and a body joined at one point or none (a top, a free body) the box with the
same mass and principal inertia. Gears add their pitch circle (a thin ring with a spoke, so
that the turning shows), racks their pitch line, cams their surface (a plate) and rollers
their circle. The shapes of contacts (spheres, capsules, boxes, planes, holes) are drawn as
they are, in place of the inertia box of a body that has no joints. All shapes are trimesh
meshes in the body frame [m].
"""

from __future__ import annotations

from typing import Any

import numpy as np
import trimesh

from mbd3d.joints import CamFollower, FlatFaceFollower, GearPair, Prismatic, RackPinion
from mbd3d.joints.base import triad
from mbd3d.model.body import Body
from mbd3d.model.springs import SpringDamper
from mbd3d.model.builder import Model
from mbd3d.model.contacts import contact_group
from mbd3d.model.shapes import Outline

__all__ = ["attachment_points", "body_shape", "contact_parts", "model_size", "initial_frames", "initial_points",
           "pitch_curves", "cam_outlines", "color_of", "GROUND_COLOR"]

#: body colours, cycled (RGBA, 0-255): distinguishable and readable on the dark background
PALETTE = np.array([[76, 144, 226, 255], [240, 140, 50, 255], [90, 190, 110, 255],
                    [220, 80, 90, 255], [160, 110, 210, 255], [200, 180, 60, 255],
                    [70, 190, 200, 255], [230, 120, 180, 255]], dtype=np.uint8)
GROUND_COLOR = np.array([150, 150, 150, 255], dtype=np.uint8)


def color_of(body: Body) -> np.ndarray:
    """The RGBA colour (uint8) of a body."""
    return PALETTE[body.index % len(PALETTE)]


def _lift(u: np.ndarray) -> np.ndarray:
    """A body-frame point as 3 components (planar points lie in z = 0)."""
    out = np.zeros(3)
    out[:len(u)] = u
    return out


def attachment_points(model: Model) -> dict[str, list[tuple[str, np.ndarray]]]:
    """Where each body (and the ground) is joined: ``{body: [(element, point)]}``, body frame
    [m], 3 components. Joints and the ends of spring-dampers count; drivers act at the points of
    their joints and add none, gear meshes are drawn by their pitch curves."""
    points: dict[str, list[tuple[str, np.ndarray]]] = {b.name: [] for b in model.bodies}
    points["ground"] = []
    for element in model.joints:
        # gear meshes and cams are drawn by their curves (see pitch_curves, cam_outlines)
        if element.is_driver or isinstance(element, (GearPair, RackPinion, CamFollower,
                                                     FlatFaceFollower)):
            continue
        u_i, u_j, _ = model.reaction_frame(element.name)
        points[element.body_i.name].append((element.name, _lift(u_i)))
        points[element.body_j.name].append((element.name, _lift(u_j)))
    for group in model.force_groups:
        if not hasattr(group, "u_i"):
            continue
        for n, element in enumerate(group.elements):
            if isinstance(element, SpringDamper):
                points[element.body_i.name].append((element.name, _lift(group.u_i[n])))
                points[element.body_j.name].append((element.name, _lift(group.u_j[n])))
    return points


def pitch_curves(model: Model) -> dict[str, list[tuple[np.ndarray, float | np.ndarray,
                                                     np.ndarray | None]]]:
    """The gear meshes' pitch curves by body (the ground included): ``(centre, radius,
    axis)`` of a pitch circle (about the centre the mesh was given), or ``(point, direction,
    None)`` of a rack's pitch line through the contact, body frame [m], 3 components."""
    curves: dict[str, list] = {b.name: [] for b in model.bodies}
    curves["ground"] = []
    normal = np.array([0.0, 0.0, 1.0])
    for element in model.joints:
        u_i, u_j, axes = model.reaction_frame(element.name) if isinstance(
            element, (GearPair, RackPinion, CamFollower)) else (None, None, None)
        if isinstance(element, GearPair):
            axis_i = axis_j = normal
            if model.dim == 3:
                # each gear's axis in its frame: f x g of the mesh row's vectors on it
                table = model.row_table
                local = table.vector_local[table.slots[model._instances_of[element.name][0]]]
                axis_i, axis_j = np.cross(local[0], local[1]), np.cross(local[2], local[3])
            curves[element.body_i.name].append((_lift(u_i), float(element.radius_i), axis_i))
            curves[element.body_j.name].append((_lift(u_j), float(element.radius_j), axis_j))
        elif isinstance(element, RackPinion):
            # the pitch line lies to the right of the rack's direction, a radius from the centre
            along, across = axes[:, 0], axes[:, 1]
            rho = float(element.radius)
            curves[element.body_i.name].append((_lift(u_i - rho * across), _lift(along), None))
            curves[element.body_j.name].append((_lift(u_j), rho, normal))
        elif isinstance(element, CamFollower) and element.roller_radius > 0:
            curves[element.body_j.name].append((_lift(u_j), float(element.roller_radius), normal))
    return curves


def cam_outlines(model: Model) -> dict[str, list[np.ndarray]]:
    """The cams' surfaces by body (the ground included): closed polylines (m, 3) in the cam's
    frame [m], from the pitch curve less the roller radius, or from a flat-faced follower's
    support function ``h``, whose envelope is ``h e + h' e_perp``."""
    outlines: dict[str, list] = {b.name: [] for b in model.bodies}
    outlines["ground"] = []
    angle = np.linspace(0.0, 2 * np.pi, 361)
    for element in model.joints:
        if isinstance(element, CamFollower):
            surface = element.profile.offset(angle, -float(element.roller_radius))
        elif isinstance(element, FlatFaceFollower):
            surface = element.profile.envelope_points(angle)
        else:
            continue
        centre = model.reaction_frame(element.name)[0]
        points = centre + surface
        outlines[element.body_i.name].append(np.column_stack([points,
                                                              np.zeros(len(points))]))
    return outlines


def _plate(outline: np.ndarray) -> trimesh.Trimesh:
    """A flat plate (a triangle fan from the centroid) bounded by a closed polyline that is
    star-shaped about it, both faces drawn."""
    centre = outline[:-1].mean(axis=0)
    vertices = np.vstack([centre, outline])
    k = np.arange(1, len(outline))
    faces = np.column_stack([np.zeros_like(k), k, k + 1])
    return trimesh.Trimesh(vertices, np.vstack([faces, faces[:, ::-1]]), process=False)


def curve_polyline(curve: tuple, size: float) -> np.ndarray:
    """Points along a pitch circle (closed) or a rack's pitch line (``size`` each way)."""
    start, shape, axis = curve
    if np.ndim(shape) == 0:
        angle = np.linspace(0.0, 2 * np.pi, 97)
        f, g, _ = _circle_axes(axis)
        return start + float(shape) * (np.cos(angle)[:, None] * f + np.sin(angle)[:, None] * g)
    return np.array([start - size * shape, start + size * shape])


def _circle_axes(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """In-plane axes and normal of a circle about ``axis``: the body's own x, y about z."""
    if np.allclose(axis, (0.0, 0.0, 1.0)):
        return np.eye(3)[0], np.eye(3)[1], np.eye(3)[2]
    return triad(np.asarray(axis, dtype=float))


def _pitch_parts(curves: list, radius: float, size: float) -> list[trimesh.Trimesh]:
    """A thin ring and a spoke for each pitch circle, a bar along each pitch line."""
    parts = []
    for start, shape, axis in curves:
        if np.ndim(shape) == 0:
            rho = float(shape)
            ring = trimesh.creation.annulus(r_min=max(rho - radius, 0.5 * rho), r_max=rho,
                                            height=radius)
            # the annulus lies about z: turn z onto the gear's axis
            placed = np.eye(4)
            placed[:3, :3] = np.column_stack(_circle_axes(axis))
            placed[:3, 3] = start
            ring.apply_transform(placed)
            # the spoke's rounded end reaches the pitch circle, not beyond
            spoke = start + max(rho - 0.5 * radius, 0.0) * placed[:3, 0]
            parts += [ring, _capsule(start, spoke, 0.5 * radius)]
        else:
            line = curve_polyline((start, shape, None), size)
            parts.append(_capsule(line[0], line[1], 0.5 * radius))
    return parts


def initial_frames(model: Model) -> tuple[np.ndarray, np.ndarray]:
    """Positions (n_bodies + 1, 3) [m] and rotations (n_bodies + 1, 3, 3) of the bodies at
    their initial guesses, the ground last (the drawing the model was built from)."""
    bt, nb = model.body_type, model.n_bodies
    Q = np.zeros((nb + 1, model.n_coords_per_body))
    Q[:nb] = model.q0.reshape(nb, -1)
    fr = bt.frames(Q, charts=model.charts0)
    position = np.zeros((nb + 1, 3))
    position[:, :model.dim] = fr.Q[:, :model.dim]
    rotation = np.tile(np.eye(3), (nb + 1, 1, 1))
    rotation[:, :model.dim, :model.dim] = fr.A
    return position, rotation


def initial_points(model: Model, points: dict[str, list[tuple[str, np.ndarray]]],
                   meshes: dict[str, Any] | None = None) -> np.ndarray:
    """Global positions [m], (p, 3), at the bodies' initial guesses of the centres of mass, of
    the attachment points ``points`` and of the bounding-box corners of the ``meshes`` given
    for some bodies (body frames)."""
    position, rotation = initial_frames(model)
    cloud = [position[:model.n_bodies]]
    local = {name: [u for _, u in joined] for name, joined in points.items()}
    for name, mesh in (meshes or {}).items():
        lo, hi = mesh.bounds
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                            for z in (lo[2], hi[2])])
        local[name] = local.get(name, []) + list(corners)
    for name, us in local.items():
        if us:
            row = model.n_bodies if name == "ground" else model.body(name).index
            cloud.append(position[row] + np.asarray(us) @ rotation[row].T)
    return np.vstack(cloud)


def model_size(model: Model, points: dict[str, list[tuple[str, np.ndarray]]],
               meshes: dict[str, Any] | None = None) -> float:
    """A length [m] that sizes the default shapes, arrows and the camera: the extent of the
    mechanism (centres of mass, joint points, given meshes) in its initial configuration
    (1 m if that is a single point)."""
    cloud = initial_points(model, points, meshes)
    extent = float(np.max(np.ptp(cloud, axis=0))) if len(cloud) > 1 else 0.0
    return extent if extent > 1e-9 else 1.0


def _capsule(a: np.ndarray, b: np.ndarray, radius: float) -> trimesh.Trimesh:
    """A capsule of ``radius`` whose axis runs from ``a`` to ``b``."""
    axis = b - a
    length = float(np.linalg.norm(axis))
    mesh = trimesh.creation.capsule(height=max(length, 1e-12), radius=radius, count=[16, 16])
    if length > 1e-12:
        mesh.apply_transform(trimesh.geometry.align_vectors([0.0, 0.0, 1.0], axis / length))
    mesh.apply_translation(0.5 * (a + b))
    return mesh


def _inertia_box(body: Body, dim: int, size: float) -> trimesh.Trimesh:
    """The uniform box with the body's mass and centroidal inertia (a flat square plate of the
    same polar moment for a planar body), so that a heavier-looking body is heavier."""
    if dim == 2:
        side = np.sqrt(6.0 * float(body.inertia) / body.mass)  # I = m s^2 / 6
        side = float(np.clip(side, 0.05 * size, 0.5 * size))
        return trimesh.creation.box(extents=(side, side, 0.2 * side))
    principal, axes = np.linalg.eigh(np.asarray(body.inertia, dtype=float))
    if np.linalg.det(axes) < 0:
        axes[:, 2] = -axes[:, 2]
    # edge a_k of a box: I_k = m (a_l^2 + a_m^2) / 12, so a_k^2 = 6 (I_l + I_m - I_k) / m
    squares = 6.0 * (principal.sum() - 2.0 * principal) / body.mass
    extents = np.sqrt(np.clip(squares, (0.02 * size) ** 2, None))
    extents = np.minimum(extents, size)
    transform = np.eye(4)
    transform[:3, :3] = axes
    return trimesh.creation.box(extents=extents, transform=transform)


def _distinct(points: list[np.ndarray], tolerance: float) -> list[np.ndarray]:
    out: list[np.ndarray] = []
    for p in points:
        if all(np.linalg.norm(p - o) > tolerance for o in out):
            out.append(p)
    return out


def _outline(points: list[np.ndarray]) -> list[np.ndarray]:
    """Points of a planar link in order around their convex hull (all of them if collinear)."""
    xy = np.array(points)[:, :2]
    centre = xy.mean(axis=0)
    order = np.argsort(np.arctan2(xy[:, 1] - centre[1], xy[:, 0] - centre[0]))
    return [points[k] for k in order]


def _slider_axis(model: Model, body: Body) -> np.ndarray | None:
    """The sliding direction of ``body`` in its own frame, if it is the moving side of a
    prismatic joint."""
    for element in model.joints:
        if isinstance(element, Prismatic) and body in (element.body_i, element.body_j):
            axis_i = _lift(model.reaction_frame(element.name)[2][:, 0])
            if element.body_i is body:
                return axis_i
            # the axis is stored in body i's frame; the drawing turns it into body j's
            _, rotation = initial_frames(model)
            rows = [model.padded_index(element.body_i), model.padded_index(body)]
            return rotation[rows[1]].T @ rotation[rows[0]] @ axis_i
    return None


def body_shape(model: Model, body: Body, joined: list[tuple[str, np.ndarray]],
               size: float) -> trimesh.Trimesh:
    """The default mesh drawn for ``body`` (body frame, [m]); see the module docstring."""
    radius = 0.02 * size
    points = _distinct([p for _, p in joined], 0.5 * radius)
    parts: list[trimesh.Trimesh] = _pitch_parts(pitch_curves(model)[body.name], radius, size)
    parts += [_plate(outline) for outline in cam_outlines(model)[body.name]]
    axis = _slider_axis(model, body)
    if axis is not None:
        block = np.array([0.16, 0.08, 0.08]) * size
        transform = np.eye(4)
        transform[:3, :3] = trimesh.geometry.align_vectors([1.0, 0.0, 0.0], axis)[:3, :3]
        parts.append(trimesh.creation.box(extents=block, transform=transform))
        points = [p for p in points if np.linalg.norm(p) > 0.1 * size]
        parts += [_capsule(np.zeros(3), p, radius) for p in points]
    elif len(points) == 2:
        parts.append(_capsule(points[0], points[1], radius))
    elif len(points) >= 3 and model.dim == 2:
        ring = _outline(points)
        parts += [_capsule(a, b, radius) for a, b in zip(ring, ring[1:] + ring[:1])]
    elif len(points) >= 3:
        parts += [_capsule(np.zeros(3), p, radius) for p in points]
    contacts = contact_parts(model, body, size)
    if not parts and not contacts:
        parts.append(_inertia_box(body, model.dim, size))
    if len(points) < 2 and axis is None:
        parts += [_capsule(np.zeros(3), p, radius) for p in points]
    return trimesh.util.concatenate(parts + contacts)


def contact_parts(model: Model, body: Body, size: float) -> list[trimesh.Trimesh]:
    """The shapes of the contacts fixed to ``body`` (or the ground), body frame [m]: planes
    as squares (planar: strips) ``2 size`` wide, holes as rings, planar shapes and cams as
    plates."""
    group = contact_group(model, required=False)
    if group is None:
        return []
    return [_contact_part(o, size) for o in group.outlines if o.body.name == body.name]


def _contact_part(shape: Outline, size: float) -> trimesh.Trimesh:
    """One contact shape as a mesh in its body's frame."""
    planar = len(shape.points[0]) == 2
    p, r = [_lift(x) for x in shape.points], shape.radius
    thin = 0.01 * size
    if shape.kind == "Sphere":
        return trimesh.creation.icosphere(subdivisions=2, radius=r).apply_translation(p[0])
    if shape.kind == "Capsule":
        return _capsule(p[0], p[1], r)
    if shape.kind == "Cam":
        return _plate(np.array(p))
    if shape.kind == "Box":
        extents = 2.0 * (p[1] + r)
        if planar:
            extents[2] = 2.0 * thin
        return trimesh.creation.box(extents=extents).apply_translation(p[0])
    frame = np.eye(4)
    if shape.kind == "Plane":
        normal = p[1]
        if planar:  # a strip along the line, its face in the drawing's plane
            frame[:3, :3] = np.column_stack([np.cross(normal, [0.0, 0.0, 1.0]), normal,
                                             [0.0, 0.0, 1.0]])
            extents = [4.0 * size, thin, 2.0 * thin]
        else:
            frame[:3, :3] = trimesh.geometry.align_vectors([0.0, 0.0, 1.0], normal)[:3, :3]
            extents = [4.0 * size, 4.0 * size, thin]
        frame[:3, 3] = p[0] - 0.5 * thin * normal  # its top face on the plane
        return trimesh.creation.box(extents=extents, transform=frame)
    axis = np.array([0.0, 0.0, 1.0]) if planar else p[1]  # a hole
    frame[:3, :3] = trimesh.geometry.align_vectors([0.0, 0.0, 1.0], axis)[:3, :3]
    frame[:3, 3] = p[0]
    return trimesh.creation.annulus(r_min=r, r_max=r + 2.0 * thin, height=0.2 * size,
                                    transform=frame)
