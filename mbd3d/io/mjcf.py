"""MJCF import: mechanisms described in MuJoCo's format, read by MuJoCo's own compiler.

MuJoCo (``pip install "mbd3d[mjcf]"``) parses the file, applies its defaults, ``<include>``s
and compiler options (angles in degrees or radians, Euler sequences, inertias computed from
geoms) and places every body; this module only reads the compiled model, so that an MJCF
means here what it means in MuJoCo. In the drawing at ``joint_positions`` (default the
``keyframe``'s pose, else each joint's ``ref``: MuJoCo's ``qpos0``):

- each body that a joint carries, together with the bodies welded to it (nested without a
  joint), becomes one spatial body named after it: their summed mass and inertia at their
  common centre of mass, with the body's axes; bodies welded to the world are the ground;
- ``hinge``, ``slide`` and ``ball`` joints are a :class:`~mbd3d.joints.Revolute` about the
  axis through the anchor, a :class:`~mbd3d.joints.Prismatic` (both read MuJoCo's ``qpos``,
  drawn at it) and a :class:`~mbd3d.joints.Spherical`; a ``free`` joint leaves its body free;
- a limited hinge's or slide's ``range`` becomes a :class:`~mbd3d.JointLimit` (as URDF's
  ``<limit>``: ``joint_limits``);
- ``drive={"joint": motion}`` adds a driver named ``"<joint>_drive"`` whose coordinate is
  MuJoCo's ``qpos`` of that joint [rad or m], so its effort is the joint's generalised force;
- geoms are the bodies' shapes for the viewer (spheres, capsules, cylinders, boxes,
  ellipsoids and meshes; planes and height fields are not drawn).

Two hinges of one body through one point about perpendicular axes are a
:class:`~mbd3d.joints.Universal` joint, three about independent axes a
:class:`~mbd3d.joints.Spherical` one, a hinge and two independent slides normal to it (a
planar robot's root) a :class:`~mbd3d.joints.Planar` one (named after their joints joined by
``+``; the same motion, but those joints cannot be driven and their ranges are not stops);
other bodies with more than one joint are refused, naming them.

A hinge's ``stiffness`` and ``damping`` (a body's only joint) are a
:class:`~mbd3d.RotationalSpringDamper` named ``"<joint>_spring"``, at rest at the joint's
``springref``; an active ``connect`` equality is a :class:`~mbd3d.joints.Spherical` joint
between its two points (closing a loop exactly, where MuJoCo's is soft), and an active
``weld`` a :class:`~mbd3d.joints.Fixed` joint at its anchor, holding the bodies as drawn (a
drawing off the weld's relative pose is refused). What the file holds that the model leaves
out is said in a :class:`MjcfWarning`: actuators, tendons, other equality constraints, the
springs and damping of other joints, armature and dry friction, fluid forces, gravity
compensation, contacts between geoms, a ball joint's range.
"""

from __future__ import annotations

import os
import pathlib
import warnings
from typing import Any, Mapping

import numpy as np

from mbd3d.errors import ModelError, user_stacklevel
from mbd3d.io.robot_parts import add_driver, add_limit, composite, joint_names, limit_law, physical
from mbd3d.model.motion import Motion, as_motion

__all__ = ["mjcf_builder", "load_mjcf", "MjcfWarning"]

#: MuJoCo's joint types (mjtJoint)
_FREE, _BALL, _SLIDE, _HINGE = 0, 1, 2, 3
_KINDS = {_FREE: "free", _BALL: "ball", _SLIDE: "slide", _HINGE: "hinge"}
#: the largest MJCF file read [bytes]: MuJoCo parses the whole file in memory
MAX_FILE_BYTES = 64 * 2**20


class MjcfWarning(UserWarning):
    """What an MJCF file holds that the model leaves out (actuators, tendons, equality
    constraints, joint springs and damping, contacts between geoms), or what loading it
    mended (renamed joints, repaired inertias)."""


def load_mjcf(path: str | os.PathLike, **options: Any):
    """The model of an MJCF file: :func:`mjcf_builder` built. Returns a :class:`Model`.

    Parameters
    ----------
    path : str or path-like
        The MJCF file.
    **options
        As for :func:`mjcf_builder`.
    """
    return mjcf_builder(path, **options).build()


def mjcf_builder(path: str | os.PathLike, *, joint_positions: Mapping[str, float] | None = None,
                 drive: Mapping[str, Motion | float] | None = None, keyframe: str | None = None,
                 name: str | None = None, joint_limits: Any = "stop", builder=None,
                 files_read: list[str] | None = None):
    """A :class:`ModelBuilder` holding the mechanism of an MJCF file, to extend before
    building (drivers, loop-closing joints, forces, contacts).

    Parameters
    ----------
    path : str or path
        The MJCF file (its includes and meshes are found as MuJoCo finds them).
    joint_positions : mapping, optional
        Hinge or slide joint name -> its ``qpos`` [rad or m] in the drawing the bodies start
        from (default: a driven joint's motion at t = 0, else the keyframe's, else the
        joint's ``ref``).
    drive : mapping, optional
        Hinge or slide joint name -> motion (a Motion or a constant) of its ``qpos``.
    keyframe : str, optional
        The ``<key>`` whose ``qpos`` is the drawing (free and ball joints too) and whose
        ``qvel`` the bodies' initial velocities (for forward dynamics).
    name : str, optional
        The model's name (default the file's ``<mujoco model>``).
    joint_limits : "stop", "ignore" or ContactLaw
        What a limited hinge's or slide's ``range`` becomes, as for
        :func:`mbd3d.load_urdf`: a :class:`~mbd3d.JointLimit` named ``"<joint>_limit"``.
    builder : ModelBuilder, optional
        Add the mechanism to this spatial builder (its body names must be free) instead of a
        new one; its gravity is kept (a warning says so where the file's differs).
    files_read : list, optional
        Appended with the path of every file read: the MJCF file, the files it includes and
        its asset files (meshes, height fields, textures), e.g. to tell when a result made
        from it is stale.

    Returns
    -------
    ModelBuilder
        Spatial; a new one has the file's gravity (``<option gravity>``, default 9.81 m/s^2
        down z).

    Raises
    ------
    ModelError
        MuJoCo missing, a file MuJoCo refuses (its message, with the line), a body with
        joints mbd3d cannot read as one, a moving body without mass, an unknown or unfit joint in
        ``joint_positions`` or ``drive``.
    """
    mujoco = _mujoco()
    path = pathlib.Path(path)
    what = f"MJCF '{path}'"
    m = _compiled(mujoco, path, what)
    if files_read is not None:
        files_read.extend(_files_read(m, path))
    joints = {_name(mujoco, m, "joint", j): j for j in range(m.njnt)}
    drive = {key: as_motion(value, f"{what}: drive of '{key}'")
             for key, value in (drive or {}).items()}
    positions = dict(joint_positions or {})
    for key, motion in drive.items():
        positions.setdefault(key, motion.evaluate(0.0)[0])
    d = _drawing(mujoco, m, joints, positions, _key(mujoco, m, keyframe, what), what)
    # everything that can be refused is checked before the builder (maybe the caller's) is
    # touched, so that a refusal leaves no part of the mechanism in it
    law = limit_law(joint_limits, what)
    _check_welds(mujoco, m, d, what)
    sets = _joint_sets(mujoco, m)
    for label, (_, js) in sets.items():
        for hinge in sorted(set(label.split("+")) & set(drive) if len(js) > 1 else ()):
            raise ModelError(f"{what}: joint '{hinge}' is one of the joints mbd3d models as "
                             f"the {_joint_set_kind(m, js)} joint '{label}'; it cannot be "
                             "driven (drive a joint that is its body's only one)")

    b = _builder(builder, m, name or m.names[:m.names.index(b"\0")].decode() or path.stem,
                 what)
    owner, bodies = _add_bodies(mujoco, m, d, b, what)
    taken = {body.name for body in bodies.values()} | {b.ground.name}
    joining = _Joints(mujoco, m, d, b, drive, law, what)
    equalities = {}  # by a name apart from the joints' (MuJoCo keeps the two apart)
    for (kind, label), k in _equalities(mujoco, m).items():
        while label in sets or label in equalities:
            label += f"_{kind}"
        equalities[label] = kind, k
    for label, name in joint_names(list(sets) + list(equalities), taken, what,
                                   MjcfWarning).items():
        if label in equalities:
            kind, k = equalities[label]
            if kind == "connect":
                joining.connect(name, k, bodies, owner)
            elif owner[int(m.eq_obj1id[k])] != owner[int(m.eq_obj2id[k])]:  # else one body
                joining.weld(name, k, bodies, owner)
            continue
        body, js = sets[label]
        parent, child = bodies[owner[int(m.body_parentid[body])]], bodies[body]
        if len(js) > 1:
            joining.several(label, name, parent, child, js)
        else:
            joining.one(label, name, parent, child, js[0])
    left_out = (_not_modelled(mujoco, m, owner, joining.sprung, len(equalities))
                + joining.left_out)
    if left_out:
        warnings.warn(f"{what}: not modelled: {'; '.join(left_out)}", MjcfWarning,
                      stacklevel=user_stacklevel())
    return b


class _Joints:
    """Adds the file's joints to the builder ``b``, noting what of them is left out."""

    def __init__(self, mujoco, m, d, b, drive: Mapping[str, Motion], law, what: str):
        self.mujoco, self.m, self.d, self.b = mujoco, m, d, b
        self.drive, self.law, self.what = drive, law, what
        self.left_out: list[str] = []
        self.sprung: set[int] = set()  # the joints whose stiffness and damping are modelled

    def one(self, label: str, name: str, parent, child, j: int) -> None:
        """Joint ``j`` (hinge, slide or ball), its range, drive and spring-damper."""
        m, d, kind = self.m, self.d, int(self.m.jnt_type[j])
        qpos = float(d.qpos[m.jnt_qposadr[j]])
        element = _add_joint(self.b, kind, name, parent, child, d.xanchor[j].copy(),
                             d.xaxis[j].copy(), qpos)
        if m.jnt_limited[j] and kind == _BALL:
            self.left_out.append(f"the range of ball joint '{label}'")
        elif m.jnt_limited[j] and not add_limit(self.b, kind == _SLIDE, name, element,
                                                tuple(m.jnt_range[j]), self.law):
            lower, upper = m.jnt_range[j]
            unit = "m" if kind == _SLIDE else "rad"
            self.left_out.append(f"the range [{lower:.6g}, {upper:.6g}] {unit} of joint "
                                 f"'{label}'")
        if label in self.drive:
            add_driver(self.b, kind == _SLIDE, name, element, self.drive[label])
        stiffness, damping = float(m.jnt_stiffness[j]), float(m.dof_damping[m.jnt_dofadr[j]])
        if kind == _HINGE and (stiffness or damping):
            from mbd3d.model.springs import RotationalSpringDamper  # noqa: PLC0415
            # MuJoCo's spring is at rest at qpos_spring; the hinge reads qpos (drawn_angle)
            self.b.add(RotationalSpringDamper(
                f"{name}_spring", joint=element, stiffness=stiffness, damping=damping,
                free_angle=float(m.qpos_spring[m.jnt_qposadr[j]])))
            self.sprung.add(j)

    def connect(self, name: str, k: int, bodies: dict, owner: dict) -> None:
        """Equality constraint ``k``, a ``connect``: a ball joint between the points of its
        two bodies (anchors, or sites) that MuJoCo holds together."""
        from mbd3d.joints import Spherical  # noqa: PLC0415

        m, d = self.m, self.d
        one, two = int(m.eq_obj1id[k]), int(m.eq_obj2id[k])
        if m.eq_objtype[k] == self.mujoco.mjtObj.mjOBJ_SITE:
            ends = [(int(m.site_bodyid[s]), d.site_xpos[s]) for s in (one, two)]
        else:
            ends = [(b, d.xpos[b] + d.xmat[b].reshape(3, 3) @ m.eq_data[k, 3 * i:3 * i + 3])
                    for i, b in enumerate((one, two))]
        (b_i, p_i), (b_j, p_j) = [(bodies[owner[b]], p) for b, p in ends]
        self.b.add(Spherical(name, b_i, b_j, point_i=_local(b_i, p_i),
                             point_j=_local(b_j, p_j)))

    def weld(self, name: str, k: int, bodies: dict, owner: dict) -> None:
        """Equality constraint ``k``, a ``weld``: a :class:`~mbd3d.joints.Fixed` joint at its
        anchor, holding the bodies as drawn (which :func:`_check_welds` found to be the weld's
        relative pose)."""
        from mbd3d.joints import Fixed  # noqa: PLC0415

        one, two = int(self.m.eq_obj1id[k]), int(self.m.eq_obj2id[k])
        anchor = self.d.xpos[one] + self.d.xmat[one].reshape(3, 3) @ self.m.eq_data[k, :3]
        self.b.add(Fixed(name, bodies[owner[one]], bodies[owner[two]], at=anchor))

    def several(self, label: str, name: str, parent, child, js: list) -> None:
        """The joints ``js`` of one body as one joint of mbd3d's (not driven: refused
        before)."""
        kind = _add_joint_set(self.b, self.m, name, parent, child, self.d, js)
        hinges = [_name(self.mujoco, self.m, "joint", j) for j in js]
        limited = [hinge for hinge, j in zip(hinges, js) if self.m.jnt_limited[j]]
        if limited:
            self.left_out.append(f"the ranges of joints {', '.join(limited)} (the {kind} joint "
                                 f"'{name}')")


def _builder(builder, m, name: str, what: str):
    """A new spatial builder with the file's gravity, or ``builder`` (spatial), warned where
    its gravity is not the file's."""
    from mbd3d.model.builder import ModelBuilder  # noqa: PLC0415

    gravity = np.array(m.opt.gravity, dtype=float)
    if builder is None:
        return ModelBuilder(dim=3, gravity=tuple(gravity), name=name)
    if builder.dim != 3:
        raise ModelError(f"{what}: an MJCF mechanism is spatial; the builder is planar")
    if not np.allclose(builder.gravity, gravity, rtol=1e-12, atol=0.0):
        warnings.warn(f"{what}: the model's gravity {tuple(builder.gravity)} is kept, not the "
                      f"file's {tuple(gravity)} [m/s^2]", MjcfWarning,
                      stacklevel=user_stacklevel())
    return builder


def _mujoco():
    try:
        import mujoco  # noqa: PLC0415
    except ImportError:
        raise ModelError('MJCF import needs MuJoCo: pip install "mbd3d[mjcf]"') from None
    return mujoco


def _compiled(mujoco, path: pathlib.Path, what: str):
    """MuJoCo's compiled model of the file, its refusal as a ModelError."""
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise ModelError(f"{what} cannot be read: {exc.strerror}") from None
    if size > MAX_FILE_BYTES:
        raise ModelError(f"{what} is {size / 2**20:.0f} MiB; an MJCF file of more than "
                         f"{MAX_FILE_BYTES / 2**20:.0f} MiB is refused (is it one?)")
    try:
        return mujoco.MjModel.from_xml_path(str(path))
    except ValueError as exc:  # MuJoCo's parse and compile errors, with the element and line
        raise ModelError(f"{what}: MuJoCo refuses it: {' '.join(str(exc).split())}") from None


def _files_read(m, path: pathlib.Path) -> list[str]:
    """The MJCF file, those it includes (relative to its folder, as MuJoCo finds them) and
    the asset files MuJoCo read (relative to the compiler's ``meshdir``, ``texturedir`` or
    ``assetdir``), those found."""
    from xml.etree import ElementTree  # noqa: PLC0415 (files MuJoCo has already parsed)

    folder, found, queue = path.resolve().parent, [], [path.resolve()]
    folders = {"mesh": "", "texture": ""}
    while queue:
        file = queue.pop()
        if str(file) in found or not file.is_file():
            continue
        found.append(str(file))
        for element in ElementTree.parse(file).iter():
            if element.tag == "include" and element.get("file"):
                queue.append(folder / element.get("file"))
            elif element.tag == "compiler":
                for kind in folders:
                    folders[kind] = element.get(f"{kind}dir", element.get("assetdir",
                                                                          folders[kind]))
    ends = np.flatnonzero(np.frombuffer(m.paths, dtype=np.uint8) == 0)
    starts = {"mesh": m.mesh_pathadr, "hfield": m.hfield_pathadr, "skin": m.skin_pathadr,
              "texture": m.tex_pathadr}
    for kind, addresses in starts.items():
        for start in addresses[addresses >= 0]:
            name = m.paths[start:ends[np.searchsorted(ends, start)]].decode()
            asset = folder / folders["texture" if kind == "texture" else "mesh"] / name
            if name and asset.is_file() and str(asset.resolve()) not in found:
                found.append(str(asset.resolve()))
    return found


def _name(mujoco, m, kind: str, index: int) -> str:
    """The element's name in the file, or ``"<kind><index>"`` for an unnamed one."""
    objects = {"body": mujoco.mjtObj.mjOBJ_BODY, "joint": mujoco.mjtObj.mjOBJ_JOINT}
    return mujoco.mj_id2name(m, objects[kind], index) or f"{kind}{index}"


def _key(mujoco, m, keyframe: str | None, what: str) -> int | None:
    """The index of the keyframe named ``keyframe``, or None."""
    if keyframe is None:
        return None
    k = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, str(keyframe))
    if k < 0:
        keys = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_KEY, i) for i in range(m.nkey)]
        raise ModelError(f"{what}: no keyframe '{keyframe}' (named keyframes: "
                         f"{', '.join(key for key in keys if key) or 'none'})")
    return k


def _drawing(mujoco, m, joints: dict, positions: Mapping[str, float], key: int | None,
             what: str):
    """MuJoCo's kinematics and velocities at ``qpos0`` (the keyframe ``key``'s ``qpos`` and
    ``qvel``) with the given hinge and slide coordinates."""
    d = mujoco.MjData(m)
    d.qpos[:] = m.qpos0 if key is None else m.key_qpos[key]
    if key is not None:
        d.qvel[:] = m.key_qvel[key]
    for joint, value in positions.items():
        if joint not in joints:
            raise ModelError(f"{what}: no joint '{joint}' (joints: "
                             f"{', '.join(sorted(joints))})")
        j = joints[joint]
        if m.jnt_type[j] not in (_HINGE, _SLIDE):
            raise ModelError(f"{what}: joint '{joint}' is a {_KINDS[int(m.jnt_type[j])]} "
                             "joint; only hinge and slide joints take a coordinate or a drive")
        d.qpos[m.jnt_qposadr[j]] = float(value)
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    mujoco.mj_comVel(m, d)
    return d


def _add_bodies(mujoco, m, d, b, what: str) -> tuple[dict, dict]:
    """A body per group of welded MuJoCo bodies (the world's group is the ground). Returns
    each MuJoCo body's group (its first body's index) and the model's body of each group."""
    owner, members = {0: 0}, {0: [0]}
    for k in range(1, m.nbody):  # parents before children
        count = int(m.body_jntnum[k])
        if count > 1:
            _check_joint_set(mujoco, m, k, what)
        owner[k] = k if count else owner[int(m.body_parentid[k])]
        members.setdefault(owner[k], []).append(k)
    bodies = {0: b.ground}
    for first, group in members.items():
        if first == 0:
            continue
        mass, centre, inertia = composite(
            (float(m.body_mass[k]), d.xipos[k],
             d.ximat[k].reshape(3, 3) @ np.diag(m.body_inertia[k]) @ d.ximat[k].reshape(3, 3).T)
            for k in group)
        body = _name(mujoco, m, "body", first)
        if body == b.ground.name:
            warnings.warn(f"{what}: body '{body}' is the body '{body}_body' (the model's "
                          f"ground is '{body}')", MjcfWarning, stacklevel=user_stacklevel())
            body = f"{body}_body"
        if not mass > 0:
            raise ModelError(f"{what}: body '{body}' moves on its joint but has no mass (nor "
                             "have the bodies welded to it); give it an <inertial> or geoms")
        frame = d.xmat[first].reshape(3, 3)
        welded = ", ".join(_name(mujoco, m, "body", k) for k in group)
        inertia = physical(frame.T @ inertia @ frame, f"body '{body}'",
                           f" (with the bodies welded to it: {welded})", "<inertial>", what,
                           MjcfWarning)
        to_body = np.eye(4)
        to_body[:3, :3], to_body[:3, 3] = frame.T, -frame.T @ centre
        velocity = np.zeros(6)  # angular, then linear at its centre of mass (global axes)
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, first, velocity, 0)
        omega = velocity[:3].copy()
        bodies[first] = b.add_body(
            body, mass=mass, inertia=inertia, position=centre, orientation=frame,
            velocity=velocity[3:] + np.cross(omega, centre - d.xipos[first]),
            angular_velocity=omega, shape=_shape(mujoco, m, d, group, to_body))
    return owner, bodies


def _joint_sets(mujoco, m) -> dict[str, tuple[int, list[int]]]:
    """Each moving body's joints (free ones aside) by their name in the file (several hinges'
    joined by '+'): the body and the joints' indices."""
    sets = {}
    for k in range(1, m.nbody):
        first, count = int(m.body_jntadr[k]), int(m.body_jntnum[k])
        if count and m.jnt_type[first] != _FREE:
            js = list(range(first, first + count))
            sets["+".join(_name(mujoco, m, "joint", j) for j in js)] = (k, js)
    return sets


def _joint_set_kind(m, js: list) -> str | None:
    """Which one joint of mbd3d the joints ``js`` of one body make: two hinges about
    perpendicular axes through one point a universal joint, three about independent axes a
    ball joint, a hinge and two independent slides normal to it a planar joint; else None."""
    axes = np.array([m.jnt_axis[j] / np.linalg.norm(m.jnt_axis[j]) for j in js])
    types = sorted(int(m.jnt_type[j]) for j in js)
    one_point = all(np.allclose(m.jnt_pos[j], m.jnt_pos[js[0]], rtol=0, atol=1e-12)
                    for j in js)
    if types == [_HINGE, _HINGE] and one_point and abs(axes[0] @ axes[1]) <= 1e-9:
        return "universal"
    if types == [_HINGE] * 3 and one_point and abs(np.linalg.det(axes)) > 1e-6:
        return "ball"
    if types == [_SLIDE, _SLIDE, _HINGE]:
        normal = axes[[m.jnt_type[j] == _HINGE for j in js]][0]
        slides = axes[[m.jnt_type[j] == _SLIDE for j in js]]
        if (np.all(np.abs(slides @ normal) <= 1e-9)
                and np.linalg.norm(np.cross(*slides)) > 1e-6):
            return "planar"
    return None


def _check_joint_set(mujoco, m, k: int, what: str) -> None:
    """Refuse body ``k``'s several joints unless they make one joint of mbd3d's."""
    first, count = int(m.body_jntadr[k]), int(m.body_jntnum[k])
    js = list(range(first, first + count))
    if _joint_set_kind(m, js) is None:
        listed = ", ".join(f"{_name(mujoco, m, 'joint', j)} ({_KINDS[int(m.jnt_type[j])]})"
                           for j in js)
        raise ModelError(
            f"{what}: body '{_name(mujoco, m, 'body', k)}' has {count} joints ({listed}); "
            "mbd3d joins two bodies by one joint, and reads several only as two hinges about "
            "perpendicular axes or three about independent axes, all through one point (a "
            "universal or a ball joint), or a hinge and two slides normal to it (a planar "
            "joint): nest a body, with mass, per joint")


def _add_joint_set(b, m, name: str, parent, child, d, js: list) -> str:
    """The one joint of mbd3d's that the joints ``js`` of a body make (see
    :func:`_joint_set_kind`; a universal joint's first axis fixed in the parent, the second
    in the child, as MuJoCo turns them in turn); returns which."""
    from mbd3d.joints import Planar, Spherical, Universal  # noqa: PLC0415

    kind = _joint_set_kind(m, js)
    if kind == "universal":
        b.add(Universal(name, parent, child, axis_i=d.xaxis[js[0]].copy(),
                        axis_j=d.xaxis[js[1]].copy(), at=d.xanchor[js[0]].copy()))
    elif kind == "ball":
        b.add(Spherical(name, parent, child, at=d.xanchor[js[0]].copy()))
    else:
        hinge = next(j for j in js if m.jnt_type[j] == _HINGE)
        b.add(Planar(name, parent, child, axis=d.xaxis[hinge].copy(),
                     at=d.xanchor[hinge].copy()))
    return kind


def _add_joint(b, kind: int, name: str, parent, child, anchor: np.ndarray, axis, qpos: float):
    """The hinge, slide or ball joint ``name`` at ``anchor`` (global) along ``axis``, drawn at
    ``qpos`` (a hinge reads its angle as MuJoCo's ``qpos``)."""
    from mbd3d.joints import Prismatic, Revolute, Spherical  # noqa: PLC0415

    if kind == _BALL:
        return b.add(Spherical(name, parent, child, at=anchor))
    return b.add(Prismatic(name, parent, child, at=anchor, axis=axis, drawn_displacement=qpos)
                 if kind == _SLIDE else
                 Revolute(name, parent, child, at=anchor, axis=axis, drawn_angle=qpos))


def _equalities(mujoco, m) -> dict[tuple[str, str], int]:
    """The active ``connect`` and ``weld`` equality constraints, by kind and name
    (``"connect<k>"``, ``"weld<k>"`` unnamed)."""
    kinds = {int(mujoco.mjtEq.mjEQ_CONNECT): "connect", int(mujoco.mjtEq.mjEQ_WELD): "weld"}
    found = {}
    for k in range(m.neq):
        kind = kinds.get(int(m.eq_type[k]))
        if kind is not None and m.eq_active0[k]:
            found[kind, mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_EQUALITY, k) or f"{kind}{k}"] = k
    return found


def _check_welds(mujoco, m, d, what: str) -> None:
    """Refuse a weld whose relative pose (``relpose``, by default the one at ``qpos0``) is
    not the drawing's: mbd3d welds the bodies as drawn."""
    for (kind, label), k in _equalities(mujoco, m).items():
        if kind != "weld":
            continue
        one, two = int(m.eq_obj1id[k]), int(m.eq_obj2id[k])
        R1, R2 = d.xmat[one].reshape(3, 3), d.xmat[two].reshape(3, 3)
        drawn = np.concatenate([R1.T @ (d.xpos[two] - d.xpos[one]), np.zeros(4)])
        mujoco.mju_mat2Quat(drawn[3:], (R1.T @ R2).ravel())
        held = np.array(m.eq_data[k, 3:10], dtype=float)
        if held[3:] @ drawn[3:] < 0.0:  # q and -q are one turn
            held[3:] *= -1.0
        scale = 1.0 + float(np.max(np.abs(d.xpos)))
        if np.max(np.abs(drawn - held) * ([1.0 / scale] * 3 + [1.0] * 4)) > 1e-9:
            raise ModelError(f"{what}: weld '{label}' holds body2 at {_pose(held)} in body1's "
                             f"frame, the drawing (qpos0, the keyframe or joint_positions) at "
                             f"{_pose(drawn)}; mbd3d welds the bodies as drawn: draw them "
                             "at the weld's pose")


def _pose(pose: np.ndarray) -> str:
    return (f"position {np.array2string(pose[:3], precision=6)} m, quaternion "
            f"{np.array2string(pose[3:], precision=6)}")


def _local(body, p: np.ndarray) -> np.ndarray:
    """The global point ``p`` (drawing) in ``body``'s frame."""
    from mbd3d.numerics.rotations import from_rodrigues  # noqa: PLC0415

    if body.is_ground:
        return np.array(p, dtype=float)
    R = body.chart @ from_rodrigues(np.asarray(body.q0[3:], dtype=float))
    return R.T @ (np.asarray(p, dtype=float) - body.q0[:3])


def _not_modelled(mujoco, m, owner: dict, sprung: set, equalities: int) -> list[str]:
    """What of the file the model leaves out, each said once (the stiffness and damping of
    the joints ``sprung`` and ``equalities`` active connect and weld constraints are
    modelled)."""
    out = []
    for count, label in ((m.nu, "actuators"), (m.ntendon, "tendons"),
                         (m.neq - equalities, "equality constraints (other than connect and "
                                              "weld)")):
        if count:
            out.append(f"{count} {label}")
    dof = {"damping": m.dof_damping, "armature": m.dof_armature,
           "frictionloss": m.dof_frictionloss}
    for label, values in [("stiffness", m.jnt_stiffness)] + list(dof.items()):
        found = {int(m.dof_jntid[k]) if label in dof else int(k)
                 for k in np.flatnonzero(values)}
        if label in ("stiffness", "damping"):
            found -= sprung
        joints = sorted(_name(mujoco, m, "joint", j) for j in found)
        if joints:
            out.append(f"joint {label} ({', '.join(joints)})")
    if m.opt.density > 0 or m.opt.viscosity > 0:
        out.append(f"fluid forces (density {m.opt.density:g}, viscosity {m.opt.viscosity:g})")
    if np.any(m.body_gravcomp):
        out.append("gravity compensation")
    collide = {owner[int(m.geom_bodyid[g])] for g in range(m.ngeom)
               if m.geom_contype[g] or m.geom_conaffinity[g]}
    if len(collide) > 1 and not m.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT:
        out.append("contacts between geoms (add mb.Contact between shapes)")
    return out


def _shape(mujoco, m, d, group: list, to_body: np.ndarray):
    """The geoms of the welded bodies ``group`` as one mesh in their body's frame
    (``to_body``: global to body, 4x4), or None."""
    import trimesh  # noqa: PLC0415

    types = mujoco.mjtGeom
    parts = []
    for g in np.flatnonzero(np.isin(m.geom_bodyid, group)):
        kind, size = int(m.geom_type[g]), m.geom_size[g]
        if kind == types.mjGEOM_SPHERE:
            mesh = trimesh.creation.icosphere(radius=size[0], subdivisions=2)
        elif kind == types.mjGEOM_ELLIPSOID:
            mesh = trimesh.creation.icosphere(radius=1.0, subdivisions=2)
            mesh.apply_scale(size)
        elif kind == types.mjGEOM_CAPSULE:
            mesh = trimesh.creation.capsule(height=2 * size[1], radius=size[0])
        elif kind == types.mjGEOM_CYLINDER:
            mesh = trimesh.creation.cylinder(radius=size[0], height=2 * size[1], sections=32)
        elif kind == types.mjGEOM_BOX:
            mesh = trimesh.creation.box(extents=2 * size)
        elif kind == types.mjGEOM_MESH:
            k = int(m.geom_dataid[g])
            vertices = m.mesh_vert[m.mesh_vertadr[k]:m.mesh_vertadr[k] + m.mesh_vertnum[k]]
            faces = m.mesh_face[m.mesh_faceadr[k]:m.mesh_faceadr[k] + m.mesh_facenum[k]]
            mesh = trimesh.Trimesh(vertices.copy(), faces.copy(), process=False)
        else:
            continue  # planes and height fields: no body of finite size
        pose = np.eye(4)
        pose[:3, :3], pose[:3, 3] = d.geom_xmat[g].reshape(3, 3), d.geom_xpos[g]
        mesh.apply_transform(to_body @ pose)
        parts.append(mesh)
    return trimesh.util.concatenate(parts) if parts else None
