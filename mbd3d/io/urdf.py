"""URDF import: robots described in URDF as spatial mechanisms.

The file is parsed by yourdfpy (``pip install "mbd3d[urdf]"``). Each link that a moving joint
carries, together with the links fixed joints weld to it (a tool flange, a sensor, a
massless frame), becomes one spatial body named after that link: its mass the sum of theirs,
its frame at their common centre of mass with the link's axes, its inertia theirs about that
centre (each turned from its inertial frame, by the parallel-axis theorem), its shape theirs
joined.
Joints become constraints between those bodies, given in the drawing of the robot at
``joint_positions`` (default all zero):

- ``revolute`` and ``continuous``: :class:`~mbd3d.joints.Revolute` about the joint axis,
  whose ``drawn_angle`` is the joint's position, so that ``results.joint(name).angle``,
  ``initial_positions``, drivers and stops are in the file's joint coordinate [rad];
- ``prismatic``: :class:`~mbd3d.joints.Prismatic` along it, its ``drawn_displacement`` the
  joint's position (so it reads the file's joint coordinate [m] too);
- ``fixed``: nothing (its child is part of its parent's body; its axis is not read);
- ``floating``: nothing either, its child is free (a floating base);
- ``planar``: :class:`~mbd3d.joints.Planar`, its axis the plane's normal.

URDF keeps the names of links and of joints apart, a model does not: a joint named as a link
is renamed ``"<name>_joint"`` (a :class:`UrdfWarning` lists them).

The root link is welded to the ground (``fixed_base=True``, it becomes the ground) or left
free. A revolute or prismatic joint's ``<limit>`` becomes a :class:`~mbd3d.JointLimit` at its
lower and upper ends (``joint_limits``: the contact law, or ``"ignore"``; equal ends are no
range); mimic joints are not coupled, which a :class:`UrdfWarning` reports. Joints that move
no mass (no link below them has an ``<inertial>``: a camera frame on a hinge, fingers drawn
without inertias) are left out with their links, and principal moments of inertia that break
``J1 + J2 >= J3`` by rounding (:data:`INERTIA_ROUNDING`) are repaired, both said in a
warning; beyond that the robot is refused, naming the link. Visual geometry (collision
geometry where a link has none) becomes the body's shape for the viewer: meshes (paths
relative to the URDF, ``package://`` resolved from the URDF's folder upwards; a missing one
is a warning unless ``meshes="require"``), boxes, cylinders and spheres.

``drive={"joint": motion}`` adds a :class:`~mbd3d.joints.RotationDriver` (or
:class:`~mbd3d.joints.TranslationDriver`) named ``"<joint>_drive"`` whose motion is the URDF
joint coordinate [rad or m]: its effort is the joint torque or force.
"""

from __future__ import annotations

import os
import pathlib
import warnings
from typing import Any, Mapping

import numpy as np

from mbd3d.errors import ModelError, did_you_mean, user_stacklevel
from mbd3d.io.robot_parts import (INERTIA_ROUNDING, add_driver, add_limit, composite,
                                   joint_names, limit_law, physical)
from mbd3d.model.motion import Motion, as_motion

__all__ = ["urdf_builder", "load_urdf", "UrdfWarning", "INERTIA_ROUNDING"]


class UrdfWarning(UserWarning):
    """A URDF feature mbd3d reads but does not model (joint limits, mimic joints), or what
    loading the file mended (renamed joints, repaired inertias, missing meshes, joints that
    move no mass)."""


def load_urdf(path: str | os.PathLike, **options: Any):
    """The model of a URDF robot: :func:`urdf_builder` built. Returns a :class:`Model`.

    Parameters
    ----------
    path : str or path-like
        The URDF file.
    **options
        As for :func:`urdf_builder` (``joint_positions``, ``drive``, ``fixed_base``,
        ``joint_limits``, ``meshes``, ...).
    """
    return urdf_builder(path, **options).build()


def _check_xml(path: pathlib.Path, what: str) -> None:
    """Refuse a file that is not XML, or XML whose root is not a named ``<robot>``, before the
    URDF parser sees it (its own messages name neither)."""
    from lxml import etree  # noqa: PLC0415 (yourdfpy's own XML library)

    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False)
    try:
        root = etree.parse(str(path), parser).getroot()
    except OSError as exc:
        raise ModelError(f"{what} cannot be read: {exc}") from None
    except etree.XMLSyntaxError as exc:
        raise ModelError(f"{what} is not well-formed XML ({exc.msg}); a URDF is an XML file whose root "
                         "element is <robot name=\"...\">") from None
    if root.tag != "robot":
        raise ModelError(f"{what}: the root element is <{root.tag}>; a URDF's is "
                         "<robot name=\"...\">")
    if not root.get("name"):
        raise ModelError(f"{what}: <robot> has no name attribute; give it one")


def _read_robot(yourdfpy, path: pathlib.Path, what: str) -> tuple:
    """The URDF's robot, its links by name, its joints and its root link (in a list of one),
    refused unless it is one tree."""
    _check_xml(path, what)
    try:
        robot = yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False,
                                   load_collision_meshes=False)
    except Exception as exc:  # noqa: BLE001 (lxml and yourdfpy raise many kinds)
        raise ModelError(f"{what} cannot be read: {exc}") from None
    links = {link.name: link for link in robot.robot.links}
    joints = list(robot.robot.joints)
    _check_tree(joints, links, what)
    children = {joint.child for joint in joints}
    roots = [name for name in links if name not in children]
    if len(roots) != 1:
        raise ModelError(f"{what}: a robot is a tree with one root link; found roots "
                         f"{', '.join(roots) or 'none'}")
    return robot, links, joints, roots


def _drawing_frames(links: dict, joints: list, root: str, positions: Mapping[str, float],
                    what: str) -> tuple[dict, list]:
    """Every link's frame in the drawing (4x4, in the root's frame), from the root down, at
    the given joint coordinates; and the joints in that order."""
    frames = {root: np.eye(4)}
    by_parent: dict[str, list] = {}
    for joint in joints:
        by_parent.setdefault(joint.parent, []).append(joint)
    order = []
    stack = [root]
    while stack:
        parent = stack.pop()
        for joint in by_parent.get(parent, []):
            frames[joint.child] = frames[parent] @ _origin(joint.origin) @ _motion(
                joint, float(positions.get(joint.name, 0.0)), what)
            order.append(joint)
            stack.append(joint.child)

    unreached = [name for name in links if name not in frames]
    if unreached:  # a cycle of joints hanging from no link of the tree
        raise ModelError(f"{what}: link(s) {', '.join(unreached)} cannot be reached from the "
                         f"root link '{root}' through the joints; a URDF robot is one tree")

    return frames, order


def urdf_builder(path: str | os.PathLike, *, joint_positions: Mapping[str, float] | None = None,
                 fixed_base: bool = True, drive: Mapping[str, Motion | float] | None = None,
                 gravity=(0.0, 0.0, -9.81), name: str | None = None, builder=None,
                 files_read: list[str] | None = None, joint_limits: Any = "stop",
                 meshes: str = "load"):
    """A :class:`ModelBuilder` holding the robot of a URDF file, to extend before building
    (drivers on its joints, loop-closing joints, forces).

    Parameters
    ----------
    path : str or path
        The URDF file.
    joint_positions : mapping, optional
        Joint name -> coordinate [rad or m] of the drawing: the assembled pose the bodies start
        from (default: a driven joint's motion at t = 0, else 0).
    fixed_base : bool
        Weld the root link to the ground (True) or leave the robot free.
    drive : mapping, optional
        Joint name -> motion (a Motion or a constant) of its URDF coordinate.
    gravity : (3,) sequence
        [m/s^2]; URDF has none.
    name : str, optional
        The model's name (default the robot's).
    builder : ModelBuilder, optional
        Add the robot to this spatial builder (its link names must be free) instead of a new one.
    files_read : list, optional
        Appended with the path of every file read (the URDF and its meshes), e.g. to tell
        when a result made from the robot is stale.
    joint_limits : "stop", "ignore" or ContactLaw
        What a joint's ``<limit lower upper>`` becomes: a :class:`~mbd3d.JointLimit` named
        ``"<joint>_limit"`` with the given law, or by default (``"stop"``) a
        :class:`~mbd3d.LinearContact` of natural frequency 100 Hz with the link's inertia
        about the joint and restitution 0.5; ``"ignore"``: none (reported in a warning).
    meshes : "load", "require" or "skip"
        The visual meshes the bodies are drawn with: loaded, a missing one reported in a
        :class:`UrdfWarning` (the robot still loads: meshes do not enter the dynamics);
        loaded, a missing one refused; or not read at all (faster; primitives still drawn).

    Raises
    ------
    ModelError
        A file that cannot be read, a joint type not modelled, a moving link without mass, an
        unknown joint in ``joint_positions`` or ``drive``.
    """
    try:
        import yourdfpy  # noqa: PLC0415
    except ImportError:
        raise ModelError('URDF import needs yourdfpy: pip install "mbd3d[urdf]"') from None
    from mbd3d.model.builder import ModelBuilder  # noqa: PLC0415

    path = pathlib.Path(path)
    what = f"URDF '{path}'"
    files_read = files_read if files_read is not None else []
    files_read.append(str(path.resolve()))
    robot, links, joints, roots = _read_robot(yourdfpy, path, what)
    positions = dict(joint_positions or {})
    names = {joint.name for joint in joints}
    for key in list(positions) + list(drive or {}):
        if key not in names:
            raise ModelError(f"{what}: no joint '{key}' (joints: {', '.join(sorted(names))})")
    # a driven joint is drawn where its motion starts: a rotation driver's row, sin(theta -
    # f), vanishes half a turn away too, so the drawing must choose the branch
    drive = {key: as_motion(value, f"{what}: drive of '{key}'")
             for key, value in (drive or {}).items()}
    for key, motion in drive.items():
        positions.setdefault(key, motion.evaluate(0.0)[0])

    if meshes not in ("load", "require", "skip"):
        raise ModelError(f"{what}: meshes must be 'load', 'require' or 'skip', got {meshes!r}")
    for joint in joints:
        if joint.type in ("fixed", "floating", "planar") and joint.name in drive:
            raise ModelError(f"{what}: joint '{joint.name}' is {joint.type}; it cannot be "
                             "driven (drive a revolute, continuous or prismatic joint)")
    frames, order = _drawing_frames(links, joints, roots[0], positions, what)
    order = _without_massless_branches(order, links, drive, what)
    law = limit_law(joint_limits, what)  # refused before a builder given is touched

    b = builder if builder is not None else ModelBuilder(
        dim=3, gravity=gravity, name=name or robot.robot.name or path.stem)
    if b.dim != 3:
        raise ModelError(f"{what}: a URDF robot is spatial; the builder is planar")
    owner = _welded_groups(order, roots[0])
    bodies = _add_bodies(b, links, order, owner, frames, roots[0] if fixed_base else None,
                         (path, what, files_read, meshes))
    names = joint_names([joint.name for joint in order if joint.type != "fixed"],
                        set(bodies) | {b.ground.name}, what, UrdfWarning)
    limited, mimic = [], []
    for joint in order:
        if joint.type == "fixed":
            continue  # its child is part of its parent's body
        q0 = float(positions.get(joint.name, 0.0))
        element = _add_joint(b, joint, names[joint.name], bodies[owner[joint.parent]],
                             bodies[joint.child], frames[joint.child], q0, what)
        if element is None:
            continue  # floating: its child is free
        if joint.limit is not None and joint.type in ("revolute", "prismatic") and (
                joint.limit.lower is not None or joint.limit.upper is not None):
            if not add_limit(b, joint.type == "prismatic", names[joint.name], element,
                             (joint.limit.lower, joint.limit.upper), law):
                limited.append(f"{joint.name} [{joint.limit.lower}, {joint.limit.upper}]")
        if joint.mimic is not None:
            mimic.append(f"{joint.name} = {joint.mimic.multiplier or 1.0} x "
                         f"{joint.mimic.joint} + {joint.mimic.offset or 0.0}")
        if joint.name in drive:
            add_driver(b, joint.type == "prismatic", names[joint.name], element,
                       drive[joint.name])
    if limited:
        why = ("joint_limits='ignore'" if law is None
               else "a spatial hinge's angle is measured within half a turn of the drawing, "
                    "and equal ends are no range")
        warnings.warn(f"{what}: joint limits are not enforced ({why}): {', '.join(limited)}",
                      UrdfWarning, stacklevel=user_stacklevel())
    if mimic:
        warnings.warn(f"{what}: mimic joints are not coupled (each moves freely): "
                      f"{', '.join(mimic)}", UrdfWarning, stacklevel=user_stacklevel())
    return b


def _welded_groups(order: list, root: str) -> dict:
    """Each link's body: the link itself when a moving joint (or nothing, the root) carries
    it, else its parent's (a fixed joint welds a link to its parent's body)."""
    owner = {root: root}
    for joint in order:  # parents before children
        owner[joint.child] = owner[joint.parent] if joint.type == "fixed" else joint.child
    return owner


def _add_bodies(b, links: dict, order: list, owner: dict, frames: dict, welded: str | None,
                source: tuple) -> dict:
    """A body per group of welded links, named after its first link: their masses, centres
    and inertias summed (the parallel-axis theorem), their shapes joined; the group of the
    link ``welded`` (the root, with a fixed base) is the ground. ``source``: the URDF's path,
    its description, the files read and the ``meshes`` option. Returns the body of each
    group's first link."""
    what = source[1]
    members: dict[str, list] = {}
    for link, first in owner.items():
        members.setdefault(first, []).append(links[link])
    bodies = {}
    for first, group in members.items():
        if first == welded:
            bodies[first] = b.ground
            continue
        mass, centre, inertia = _composite(group, frames, what)
        if not mass > 0:  # the free base (a moving link's massless branch is dropped)
            raise ModelError(f"{what}: the root link '{first}' (with the links welded to it: "
                             f"{', '.join(link.name for link in group)}) has no mass but is "
                             "the free base; give it an <inertial>, or weld it: "
                             "fixed_base=True")
        frame = frames[first][:3, :3]
        links = ", ".join(link.name for link in group)
        inertia = physical(frame.T @ inertia @ frame, f"link '{first}'",
                           f" (with the links welded to it: {links})", "<inertia>", what,
                           UrdfWarning)
        body_frame = np.eye(4)
        body_frame[:3, :3], body_frame[:3, 3] = frame, centre
        shapes = [_shape(link, np.linalg.inv(body_frame) @ frames[link.name], source)
                  for link in group]
        shapes = [mesh for mesh in shapes if mesh is not None]
        name = first if first != b.ground.name else f"{first}_link"  # the model's ground
        if name != first:
            warnings.warn(f"{what}: link '{first}' is the body '{name}' (the model's ground "
                          f"is '{first}')", UrdfWarning, stacklevel=user_stacklevel())
        bodies[first] = b.add_body(name, mass=mass, inertia=inertia, position=centre,
                                   orientation=frame, shape=_joined(shapes))
    return bodies


def _without_massless_branches(order: list, links: dict, drive: Mapping, what: str) -> list:
    """The joints less those whose child and everything below it have no mass (a finger
    drawn without <inertial>s, a camera frame on a hinge): nothing the joint moves has
    inertia, so they are dropped with their links, a warning naming them."""
    below: dict[str, float] = {}
    for joint in reversed(order):  # children before parents
        below[joint.child] = below.get(joint.child, 0.0) + _mass(links[joint.child], what)
        below[joint.parent] = below.get(joint.parent, 0.0) + below[joint.child]
    dropped = {joint.child for joint in order
               if joint.type != "fixed" and not below[joint.child] > 0}
    kept, lost = [], []
    for joint in order:  # parents first: a dropped link's children are dropped with it
        if joint.parent in dropped or joint.child in dropped:
            dropped.add(joint.child)
            lost.append(joint)
            continue
        kept.append(joint)
    driven = [joint.name for joint in lost if joint.name in drive]
    if driven:
        raise ModelError(f"{what}: joint(s) {', '.join(driven)} move no mass (no link below "
                         "has an <inertial>); they cannot be driven")
    if lost:
        warnings.warn(f"{what}: joints that move no mass (no link below them has an "
                      f"<inertial>) are left out with their links: "
                      f"{', '.join(joint.name for joint in lost if joint.type != 'fixed')}",
                      UrdfWarning, stacklevel=user_stacklevel())
    return kept


def _composite(group: list, frames: dict, what: str) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass [kg], centre [m] and centroidal inertia [kg m^2] (drawing axes) of links welded
    together, each from its <inertial> in its frame of the drawing."""
    parts = []
    for link in group:
        m = _mass(link, what)
        if m > 0:
            T = frames[link.name] @ _origin(link.inertial.origin)
            R = T[:3, :3]
            parts.append((m, T[:3, 3], R @ np.asarray(link.inertial.inertia, float) @ R.T))
    return composite(parts)


def _joined(shapes: list):
    import trimesh  # noqa: PLC0415
    return trimesh.util.concatenate(shapes) if shapes else None


def _add_joint(b, joint, name: str, parent, child, frame: np.ndarray, q0: float, what: str):
    """The moving joint ``joint`` between two bodies, at its child's frame ``frame`` of the
    drawing, where its coordinate is ``q0`` (a hinge reads its angle as the file's); None for
    a floating joint (nothing joins its child to its parent)."""
    from mbd3d.joints import Planar, Prismatic, Revolute  # noqa: PLC0415

    point, axis = frame[:3, 3], frame[:3, :3] @ _axis(joint, what)
    if joint.type == "floating":
        return None
    if joint.type == "prismatic":
        return b.add(Prismatic(name, parent, child, at=point, axis=axis, drawn_displacement=q0))
    if joint.type == "planar":  # its axis is the normal of the plane its child moves in
        return b.add(Planar(name, parent, child, at=point, axis=axis))
    return b.add(Revolute(name, parent, child, at=point, axis=axis, drawn_angle=q0))


def _check_tree(joints: list, links: dict, what: str) -> None:
    """Refuse a robot whose joints name links it does not have, or give a link two parents:
    loaded anyway, the links below such a joint would silently go missing."""
    parents: dict[str, str] = {}
    for joint in joints:
        for role in ("parent", "child"):
            link = getattr(joint, role)
            if link not in links:
                raise ModelError(
                    f"{what}: joint '{joint.name}' names {role} link '{link}', which the file "
                    f"does not have{did_you_mean(link, links)}; the links below it would be "
                    "lost (links: " + ", ".join(sorted(links)) + ")")
        if joint.child in parents:
            raise ModelError(f"{what}: link '{joint.child}' is the child of joints "
                             f"'{parents[joint.child]}' and '{joint.name}'; a URDF robot is a "
                             "tree (close loops in a model file instead)")
        parents[joint.child] = joint.name


def _origin(origin) -> np.ndarray:
    return np.eye(4) if origin is None else np.asarray(origin, dtype=float)


def _axis(joint, what: str = "URDF") -> np.ndarray:
    axis = np.array([1.0, 0.0, 0.0] if joint.axis is None else joint.axis, dtype=float)
    length = float(np.linalg.norm(axis))
    if not (np.isfinite(length) and length > 1e-12):
        raise ModelError(f"{what}: joint '{joint.name}': <axis xyz> {axis.tolist()} is not a "
                         "direction; give a nonzero axis, e.g. xyz=\"0 0 1\"")
    return axis / length


def _motion(joint, q: float, what: str) -> np.ndarray:
    """The joint's own motion at coordinate ``q``, in the child frame."""
    T = np.eye(4)
    if joint.type in ("revolute", "continuous"):
        from mbd3d.numerics.rotations import axis_angle  # noqa: PLC0415
        T[:3, :3] = axis_angle(_axis(joint, what), q)
    elif joint.type == "prismatic":
        T[:3, 3] = q * _axis(joint)
    elif joint.type in ("floating", "planar"):
        if q != 0.0:
            raise ModelError(f"{what}: joint '{joint.name}' is {joint.type}; its child is drawn "
                             "where the URDF puts it (a joint_positions value is for a "
                             "revolute, continuous or prismatic joint)")
    elif joint.type != "fixed":
        raise ModelError(f"{what}: joint '{joint.name}' is {joint.type}; mbd3d models revolute, "
                         "continuous, prismatic, fixed, floating and planar joints")
    return T


def _mass(link, what: str) -> float:
    """The link's mass [kg], 0 without an <inertial>; refused unless finite and >= 0."""
    if link.inertial is None:
        return 0.0
    mass = link.inertial.mass
    if not (np.isfinite(mass) and mass >= 0):
        raise ModelError(f"{what}: link '{link.name}': <mass value> must be a finite number "
                         f">= 0 [kg], got {mass}")
    return float(mass)


def _shape(link, to_body: np.ndarray, source: tuple):
    """The link's visual (else collision) geometry as one mesh in its body's frame
    (``to_body``: the link's frame in the body's, 4x4), or None; ``source`` as for
    :func:`_add_bodies`."""
    import trimesh  # noqa: PLC0415

    parts = []
    for item in (link.visuals or link.collisions or []):
        geometry = item.geometry
        if geometry is None:
            continue
        if geometry.mesh is not None:
            path, what, files_read, meshes = source
            if meshes == "skip":
                continue
            try:
                file = _mesh_file(geometry.mesh.filename, path, what)
            except ModelError as exc:
                if meshes == "require":
                    raise
                warnings.warn(f"{exc}; link '{link.name}' is drawn without it (meshes="
                              "'require' refuses this)", UrdfWarning,
                              stacklevel=user_stacklevel())
                continue
            files_read.append(str(pathlib.Path(file).resolve()))
            mesh = trimesh.load(str(file), force="mesh")
            if geometry.mesh.scale is not None:
                mesh.apply_scale(np.broadcast_to(np.asarray(geometry.mesh.scale, float), 3))
        elif geometry.box is not None:
            mesh = trimesh.creation.box(extents=geometry.box.size)
        elif geometry.cylinder is not None:
            mesh = trimesh.creation.cylinder(radius=geometry.cylinder.radius,
                                             height=geometry.cylinder.length, sections=32)
        elif geometry.sphere is not None:
            mesh = trimesh.creation.icosphere(radius=geometry.sphere.radius, subdivisions=2)
        else:
            continue
        mesh.apply_transform(_origin(item.origin))
        parts.append(mesh)
    if not parts:
        return None
    mesh = trimesh.util.concatenate(parts)
    mesh.apply_transform(to_body)
    return mesh


def _mesh_file(filename: str, path: pathlib.Path, what: str) -> pathlib.Path:
    """A mesh's file: relative to the URDF, or package://name/rest found from the URDF's
    folder upwards (the package's folder, or a folder holding it)."""
    if filename.startswith("package://"):
        package, _, rest = filename[len("package://"):].partition("/")
        for folder in [path.resolve().parent, *path.resolve().parents]:
            candidates = [folder / package / rest]
            if folder.name == package:
                candidates.append(folder / rest)
            for candidate in candidates:
                if candidate.is_file():
                    return candidate
        raise ModelError(f"{what}: mesh '{filename}' not found in the URDF's folder or above")
    if filename.startswith("file://"):
        filename = filename[len("file://"):]
    file = pathlib.Path(filename)
    file = file if file.is_absolute() else path.resolve().parent / file
    if not file.is_file():
        raise ModelError(f"{what}: mesh '{filename}' not found ({file})")
    return file
