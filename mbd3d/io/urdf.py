"""URDF import: robots described in URDF as spatial mechanisms.

The file is parsed by yourdfpy (``pip install "mbd3d[urdf]"``). Each link with mass becomes a
spatial body: its frame at the link's centre of mass with the link's axes (so a joint's angle is
measured between link axes, as in the URDF), its inertia tensor turned from the inertial frame
into the link's axes. Joints become constraints between those bodies, given in the drawing of
the robot at ``joint_positions`` (default all zero):

- ``revolute`` and ``continuous``: :class:`~mbd3d.joints.Revolute` about the joint axis;
- ``prismatic``: :class:`~mbd3d.joints.Prismatic` along it;
- ``fixed``: :class:`~mbd3d.joints.Fixed`, or nothing when the child link has no mass (a tool
  frame, a sensor mount: its children hang on the parent);
- ``floating`` and ``planar``: refused, naming the joint.

The root link is welded to the ground (``fixed_base=True``, it becomes the ground) or left
free. A revolute or prismatic joint's ``<limit>`` becomes a :class:`~mbd3d.JointLimit` at its
lower and upper ends (``joint_limits``: the contact law, or ``"ignore"``); mimic joints are not
coupled, which a :class:`UrdfWarning` reports. Visual geometry (collision geometry where a
link has none) becomes the body's shape for the viewer: meshes (paths relative to the URDF,
``package://`` resolved from the URDF's folder upwards), boxes, cylinders and spheres.

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
from mbd3d.model.motion import Constant, Motion, as_motion

__all__ = ["urdf_builder", "load_urdf", "UrdfWarning"]


class UrdfWarning(UserWarning):
    """A URDF feature mbd3d reads but does not model (joint limits, mimic joints)."""


def load_urdf(path: str | os.PathLike, **options: Any):
    """The model of a URDF robot: :func:`urdf_builder` built. Returns a :class:`Model`."""
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
                 files_read: list[str] | None = None, joint_limits: Any = "stop"):
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
    from mbd3d.joints import Fixed, Prismatic, Revolute
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

    frames, order = _drawing_frames(links, joints, roots[0], positions, what)

    b = builder if builder is not None else ModelBuilder(
        dim=3, gravity=gravity, name=name or robot.robot.name or path.stem)
    if b.dim != 3:
        raise ModelError(f"{what}: a URDF robot is spatial; the builder is planar")
    bodies: dict[str, Any] = {}
    root = links[roots[0]]
    if fixed_base:
        bodies[root.name] = b.ground
    else:
        bodies[root.name] = _add_link(b, root, frames[root.name], path, what, files_read)
    limit_law = _limit_law(joint_limits, what)
    limited, mimic = [], []
    for joint in order:
        child = links[joint.child]
        parent_body = bodies[joint.parent]
        frame = frames[joint.child]
        point = frame[:3, 3]
        axis = frame[:3, :3] @ _axis(joint, what)
        massive = _mass(child, what) > 0
        if not massive:
            if joint.type != "fixed":
                raise ModelError(f"{what}: link '{child.name}' has no mass but moves on "
                                 f"{joint.type} joint '{joint.name}'; give it an <inertial>")
            bodies[child.name] = parent_body  # hangs on its parent
            continue
        body = _add_link(b, child, frame, path, what, files_read)
        bodies[child.name] = body
        if joint.type in ("revolute", "continuous"):
            element = b.add(Revolute(joint.name, parent_body, body, at=point, axis=axis))
        elif joint.type == "prismatic":
            element = b.add(Prismatic(joint.name, parent_body, body, at=point, axis=axis))
        else:
            element = b.add(Fixed(joint.name, parent_body, body, at=point))
        if joint.limit is not None and joint.type in ("revolute", "prismatic") and (
                joint.limit.lower is not None or joint.limit.upper is not None):
            q0 = float(positions.get(joint.name, 0.0))
            if not _add_limit(b, joint, element, axis, q0, limit_law):
                limited.append(f"{joint.name} [{joint.limit.lower}, {joint.limit.upper}]")
        if joint.mimic is not None:
            mimic.append(f"{joint.name} = {joint.mimic.multiplier or 1.0} x "
                         f"{joint.mimic.joint} + {joint.mimic.offset or 0.0}")
        if joint.name in drive:
            _add_driver(b, joint, element, axis, drive[joint.name],
                        float(positions.get(joint.name, 0.0)), what)
    if limited:
        why = ("joint_limits='ignore'" if limit_law is None
               else "a spatial hinge's angle is measured within half a turn of the drawing")
        warnings.warn(f"{what}: joint limits are not enforced ({why}): {', '.join(limited)}",
                      UrdfWarning, stacklevel=user_stacklevel())
    if mimic:
        warnings.warn(f"{what}: mimic joints are not coupled (each moves freely): "
                      f"{', '.join(mimic)}", UrdfWarning, stacklevel=user_stacklevel())
    return b


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
    elif joint.type != "fixed":
        raise ModelError(f"{what}: joint '{joint.name}' is {joint.type}; mbd3d models revolute, "
                         "continuous, prismatic and fixed joints (leave the base free with "
                         "fixed_base=False instead of a floating joint)")
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


def _add_link(b, link, frame: np.ndarray, path: pathlib.Path, what: str, files_read: list):
    """A body for a link: frame at its centre of mass, axes the link's."""
    inertial = link.inertial
    if not _mass(link, what) > 0:
        raise ModelError(f"{what}: link '{link.name}' has no mass; give it an <inertial> or "
                         "weld it to the ground (fixed_base=True)")
    T_inertial = _origin(inertial.origin)
    R = T_inertial[:3, :3]
    inertia = R @ np.asarray(inertial.inertia, dtype=float) @ R.T  # in the link's axes
    centre_in_link = T_inertial[:3, 3]
    position = frame[:3, :3] @ centre_in_link + frame[:3, 3]
    return b.add_body(link.name, mass=float(inertial.mass), inertia=inertia, position=position,
                      orientation=frame[:3, :3],
                      shape=_shape(link, centre_in_link, path, what, files_read))


def _add_driver(b, joint, element, axis: np.ndarray, motion: Motion, q0: float,
                what: str) -> None:
    """Drive the URDF joint's coordinate (``q0`` in the drawing) by ``motion``."""
    from mbd3d.joints import RotationDriver, TranslationDriver  # noqa: PLC0415

    if joint.type == "prismatic":
        b.add(TranslationDriver(f"{joint.name}_drive", element, motion=motion + Constant(-q0)))
    elif joint.type in ("revolute", "continuous"):
        offset = _drive_offset(element.body_i, element.body_j, axis) - q0
        b.add(RotationDriver(f"{joint.name}_drive", element,
                             motion=motion + Constant(offset) if offset else motion))
    else:
        raise ModelError(f"{what}: joint '{joint.name}' is fixed; it cannot be driven")


def _add_limit(b, joint, element, axis: np.ndarray, q0: float, law) -> bool:
    """Add the URDF joint's ``<limit>`` as a JointLimit on ``element`` (its ends moved from
    the URDF coordinate, ``q0`` in the drawing, to the angle or slide mbd3d measures); False
    when it is not added (no law, or a hinge's ends beyond half a turn of the drawing)."""
    from mbd3d.model.contacts import JointLimit  # noqa: PLC0415

    offset = -q0
    if joint.type == "revolute":
        offset += _drive_offset(element.body_i, element.body_j, axis)
    ends = [None if end is None else float(end) + offset
            for end in (joint.limit.lower, joint.limit.upper)]
    if law is None or (joint.type == "revolute" and any(
            end is not None and not -np.pi < end < np.pi for end in ends)):
        return False
    b.add(JointLimit(f"{joint.name}_limit", element, lower=ends[0], upper=ends[1], law=law))
    return True


def _limit_law(joint_limits: Any, what: str):
    """The contact law of the URDF's joint limits, or None (``"ignore"``)."""
    from mbd3d.model.contact_laws import ContactLaw, LinearContact  # noqa: PLC0415

    if isinstance(joint_limits, ContactLaw):
        return joint_limits
    if joint_limits == "stop":
        return LinearContact(frequency=100.0, restitution=0.5)
    if joint_limits == "ignore":
        return None
    raise ModelError(f"{what}: joint_limits must be 'stop', 'ignore' or a contact law "
                     f"(mbd3d.LinearContact, ...), got {joint_limits!r}")


def _drive_offset(body_i, body_j, axis: np.ndarray) -> float:
    """The angle a RotationDriver reads in the drawing: from body i's to body j's x axis (y
    where x lies along the axis), projected on the plane normal to the axis."""
    def reference(body) -> np.ndarray:
        R = np.eye(3) if body.is_ground else body.chart @ _rodrigues_matrix(body.q0[3:])
        for column in (0, 1):
            v = R[:, column] - (R[:, column] @ axis) * axis
            if np.linalg.norm(v) >= 1e-6:
                return v / np.linalg.norm(v)
        raise AssertionError("a body's x and y axes cannot both lie along one axis")

    f_i, f_j = reference(body_i), reference(body_j)
    return float(np.arctan2(np.cross(f_i, f_j) @ axis, f_i @ f_j))


def _rodrigues_matrix(g: np.ndarray) -> np.ndarray:
    from mbd3d.numerics.rotations import from_rodrigues  # noqa: PLC0415
    return from_rodrigues(np.asarray(g, dtype=float))


def _shape(link, centre: np.ndarray, path: pathlib.Path, what: str, files_read: list):
    """The link's visual (else collision) geometry as one mesh in the body frame (link axes,
    origin at the centre of mass), or None."""
    import trimesh  # noqa: PLC0415

    parts = []
    for item in (link.visuals or link.collisions or []):
        geometry = item.geometry
        if geometry is None:
            continue
        if geometry.mesh is not None:
            file = _mesh_file(geometry.mesh.filename, path, what)
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
    mesh.apply_translation(-centre)
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
