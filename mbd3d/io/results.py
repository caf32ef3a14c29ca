"""One results object for every analysis: time histories, named access, reactions, export.

``Results`` holds ``t``, ``q``, ``qd``, ``qdd`` and, after inverse or forward dynamics, the
multipliers ``lam``. Everything else (body poses, point trajectories, joint reactions, driver
efforts, energies, residuals) is derived from them on request, through the same body kinematics
and constraint primitives the solvers use.

Sign conventions. With ``M qdd + Cq^T lam = Qe`` the constraint forces are ``-Cq^T lam``. The
reaction of a joint *on a body* is the force [N] and moment [N m] the joint exerts on that body,
the moment taken about the joint's point on that body. A driver's effort is the generalized force
it applies in the direction of its coordinate: ``-lam`` (a torque [N m] for a rotation driver, a
force [N] for a translation driver).
"""

from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass
from typing import Any, BinaryIO, Callable, Sequence

import numpy as np

from mbd3d.model import constraints

from mbd3d.io import files, history
from mbd3d.model.body import Body
from mbd3d.errors import MBDError, ModelError
from mbd3d.model.primitives import evaluate_rows
from mbd3d.numerics.rotations import continuous_quaternions, to_quaternion

__all__ = ["Results", "ResultsBuffer", "BodyHistory", "PointHistory", "Reaction", "JointHistory",
           "format_table"]


@dataclass(frozen=True)
class BodyHistory:
    """Motion of a body over time (global axes).

    Attributes
    ----------
    position, velocity, acceleration : ndarray (k, dim)
        Centre of mass [m], [m/s], [m/s^2].
    rotation : ndarray (k, dim, dim)
        Orientation: the body axes as columns, in global components.
    angular_velocity, angular_acceleration : ndarray
        [rad/s], [rad/s^2]: (k,) about the normal for planar bodies, (k, 3) global for spatial.
    angle : ndarray (k,) or None
        Planar bodies: body angle [rad], unwrapped (it keeps counting turns).
    turning : ndarray (k, 4) or None
        Spatial bodies: quaternions whose signs follow the motion between the outputs (from
        the analysis's charts), which :attr:`quaternion` takes its signs from.

    ``angular_velocity_body`` and ``angular_acceleration_body`` give them in the body's axes.
    """

    name: str
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    rotation: np.ndarray
    angular_velocity: np.ndarray
    angular_acceleration: np.ndarray
    angle: np.ndarray | None = None
    turning: np.ndarray | None = None

    @property
    def angular_velocity_body(self) -> np.ndarray:
        """Angular velocity in the body's own axes [rad/s]: (k, 3) ``A^T omega`` for spatial
        bodies (what a gyro on the body reads), (k,) for planar ones (the same scalar)."""
        if self.angular_velocity.ndim == 1:
            return self.angular_velocity
        return np.einsum("kba,kb->ka", self.rotation, self.angular_velocity)

    @property
    def angular_acceleration_body(self) -> np.ndarray:
        """Angular acceleration in the body's own axes [rad/s^2]: ``A^T alpha`` (the rate of
        :attr:`angular_velocity_body`: ``d(A^T omega)/dt = A^T alpha`` since ``A' = omega~ A``)."""
        if self.angular_acceleration.ndim == 1:
            return self.angular_acceleration
        return np.einsum("kba,kb->ka", self.rotation, self.angular_acceleration)

    @property
    def quaternion(self) -> np.ndarray:
        """Spatial bodies: unit quaternions (k, 4), ``(w, x, y, z)``, their signs continuous
        along the motion. Forward dynamics carries them through every step, so they follow
        the motion however far apart the outputs; kinematic analysis and inverse dynamics see
        only their time points and take the turn between them the short way (less than half
        a turn)."""
        if self.rotation.shape[-1] != 3:
            raise ModelError(f"body '{self.name}' is planar: use .angle")
        q = to_quaternion(self.rotation)
        if self.turning is None:
            return continuous_quaternions(q)
        return np.where(np.einsum("ki,ki->k", q, self.turning)[:, None] < 0, -q, q)

    @property
    def orientation(self):
        """Spatial bodies: the orientations as a numpy-quaternion array (k,) of
        ``np.quaternion``, the same rotations as :attr:`quaternion`, for quaternion algebra:
        ``a.conj() * b`` is the rotation from ``a`` to ``b``, ``quaternion.slerp`` and
        ``quaternion.squad`` interpolate between output times, and
        ``quaternion.as_rotation_vector`` gives rotation vectors [rad]."""
        import quaternion  # noqa: PLC0415  (numpy-quaternion; imported when asked for)

        return quaternion.from_float_array(self.quaternion)

    @property
    def pose(self) -> np.ndarray:
        """(k, 3) ``(x, y, angle)`` for planar bodies; (k, 7) ``(x, y, z, w, qx, qy, qz)``
        for spatial ones."""
        if self.angle is not None:
            return np.column_stack([self.position, self.angle])
        return np.column_stack([self.position, self.quaternion])


@dataclass(frozen=True)
class PointHistory:
    """Trajectory of a body point in global axes: ``position`` [m], ``velocity`` [m/s] and
    ``acceleration`` [m/s^2], each (k, dim).

    Indexing and NumPy see the positions, the common use: ``p[:, 0]`` is the x coordinate
    over time and ``np.asarray(p)`` the (k, dim) positions.

    >>> import numpy as np, mbd3d as mb
    >>> from mbd3d.mechanisms import slider_crank
    >>> res = mb.kinematic_analysis(slider_crank(crank_speed=1.0), np.linspace(0.0, 1.0, 3))
    >>> tip = res.point("crank", (0.06, 0.0))
    >>> np.array_equal(tip[:, 1], tip.position[:, 1]), len(tip), np.asarray(tip).shape
    (True, 3, (3, 2))
    """

    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray

    def __getitem__(self, index):
        return self.position[index]

    def __len__(self) -> int:
        return len(self.position)

    def __array__(self, dtype=None, copy=None):
        return np.asarray(self.position, dtype=dtype)


@dataclass(frozen=True)
class Reaction:
    """Force [N] (k, dim) and moment [N m] ((k,) planar) of a joint on a body, about the joint's
    point on that body, in the axes named by ``frame`` ("global" or "joint")."""

    body: str
    frame: str
    force: np.ndarray
    moment: np.ndarray


@dataclass(frozen=True)
class MeshForce:
    """Force of a gear mesh on body j (:class:`~mbd3d.joints.GearPair`,
    :class:`~mbd3d.joints.RackPinion`), each (k,) [N].

    Attributes
    ----------
    tangential : ndarray
        Along the pitch circles' common tangent: the torque of the mesh on body j about its
        centre (spatial: about its axis) over its pitch radius, positive when it turns body j
        counter-clockwise (about its axis, which for a bevel pair points away from the apex).
    tooth : ndarray
        Magnitude of the tooth force along the line of action, ``|tangential| / cos(alpha)``.
    separating : ndarray
        Its component pushing the centres apart, ``|tangential| tan(alpha)``, carried by the
        bearings in addition to the joints' reactions (rigid gears touching at their pitch
        circles have no separating force of their own).
    point : ndarray (k, dim)
        The pitch point, where the pitch curves touch, global [m]; of a spatial pair, in the
        plane of gear j's centre (spur) or at the radii given (bevel).
    force : ndarray (k, dim)
        The tooth force on body j at the pitch point, along the line of action, global [N]. A
        bevel pair's separating part is normal to the pitch cone: ``|tangential| tan(alpha)
        cos(delta_j)`` towards gear j's axis and ``... sin(delta_j)`` along it away from the
        apex, ``delta_j`` its pitch-cone angle.
    """

    tangential: np.ndarray
    tooth: np.ndarray
    separating: np.ndarray
    point: np.ndarray
    force: np.ndarray


class JointHistory:
    """Multipliers, reactions and (for drivers) efforts of one joint or driver."""

    def __init__(self, results: "Results", name: str):
        self._results = results
        self.name = name
        self.element = results.model.joint(name)
        self.rows = results.model.rows_of(name)

    @property
    def lam(self) -> np.ndarray:
        """Lagrange multipliers of the joint's rows, (k, rows)."""
        return self._results._require_lam()[:, self.rows]

    @property
    def effort(self) -> np.ndarray:
        """Driver effort ``-lam``, (k,): the torque [N m] or force [N] the actuator must
        supply in the direction of its coordinate (``element.effort_unit``)."""
        if not self.element.is_driver:
            raise ModelError(f"'{self.name}' is a joint, not a driver; it has reactions, not an "
                             "effort (use .reaction(on=...))")
        return -self.lam[:, 0]

    # -- joint coordinates (mbd3d.io.joint_coordinates) -------------------------------------
    def _coordinates(self, kind: str):
        """The hinge, slide or ball coordinates of this joint (a driver: of its joint)."""
        from mbd3d.io import joint_coordinates as jc  # noqa: PLC0415
        from mbd3d.joints import (Cylindrical, Planar, Prismatic,  # noqa: PLC0415
                                  Revolute, Spherical, Universal)

        cache = self.__dict__.setdefault("_cache", {})
        if kind in cache:
            return cache[kind]
        model, element = self._results.model, self.element
        joint = getattr(element, "joint", None) if element.is_driver else element
        source = joint if joint is not None else element
        u_i, u_j, axes = model.reaction_frame(source.name)
        planar = model.dim == 2
        if kind == "hinge" and (isinstance(source, (Revolute, Cylindrical, Planar)) or (
                planar and element.is_driver and joint is None)):
            axis = axes[:, 0] if isinstance(source, (Cylindrical, Planar)) else (
                np.array([0.0, 0.0, 1.0]) if planar else axes[:, 2])
            value = jc.hinge(self._results, source.body_i, source.body_j, axis)
        elif kind == "slide" and isinstance(source, (Prismatic, Cylindrical)):
            value = jc.slide(self._results, source.body_i, source.body_j, axes[:, 0], u_i, u_j)
        elif kind == "plane" and isinstance(source, Planar):
            along = [jc.slide(self._results, source.body_i, source.body_j, axes[:, c], u_i, u_j)
                     for c in (1, 2)]
            value = tuple(np.column_stack([a[part] for a in along]) for part in range(3))
        elif kind == "ball" and isinstance(source, Spherical):
            value = jc.ball(self._results, source.body_i, source.body_j)
        elif kind == "cardan" and isinstance(source, Universal):
            value = jc.cardan(self._results, source.body_i, source.body_j, source.axis_i,
                              source.axis_j)
        else:
            what = {"hinge": "angle", "slide": "displacement", "ball": "ball rotation",
                    "cardan": "cross angles", "plane": "position in a plane"}
            raise ModelError(
                f"'{self.name}' ({type(element).__name__}) has no {what[kind]}: revolute and "
                "cylindrical (and planar) joints have angles, prismatic and cylindrical ones "
                "displacements, planar ones positions in the plane, spherical ones rotations, "
                "universal ones cross angles (and drivers those of their joint)")
        cache[kind] = value
        return value

    @property
    def angle(self) -> np.ndarray:
        """Revolute, cylindrical or planar joint (or its rotation driver): rotation of body j
        relative to body i about the axis (a planar joint's normal) [rad], (k,), continuous
        over any number of turns: the angle a RotationDriver on it reads (planar models:
        ``theta_j - theta_i``)."""
        return self._coordinates("hinge")[0]

    @property
    def angle_rate(self) -> np.ndarray:
        """Rate of :attr:`angle` [rad/s], (k,)."""
        return self._coordinates("hinge")[1]

    @property
    def angle_acceleration(self) -> np.ndarray:
        """Second derivative of :attr:`angle` [rad/s^2], (k,)."""
        return self._coordinates("hinge")[2]

    @property
    def displacement(self) -> np.ndarray:
        """Prismatic or cylindrical joint (or its translation driver): position of body j's
        point along the axis from body i's [m], (k,); what a TranslationDriver reads."""
        return self._coordinates("slide")[0]

    @property
    def displacement_rate(self) -> np.ndarray:
        """Rate of :attr:`displacement` [m/s], (k,)."""
        return self._coordinates("slide")[1]

    @property
    def displacement_acceleration(self) -> np.ndarray:
        """Second derivative of :attr:`displacement` [m/s^2], (k,)."""
        return self._coordinates("slide")[2]

    @property
    def plane_position(self) -> np.ndarray:
        """Planar joint: body j's point in the plane from body i's, along the joint's two
        in-plane axes (columns 1 and 2 of ``model.reaction_frame(name)[2]``, in body i's
        frame) [m], (k, 2); its turn about the normal is :attr:`angle`."""
        return self._coordinates("plane")[0]

    @property
    def plane_velocity(self) -> np.ndarray:
        """Rate of :attr:`plane_position` [m/s], (k, 2)."""
        return self._coordinates("plane")[1]

    @property
    def plane_acceleration(self) -> np.ndarray:
        """Second derivative of :attr:`plane_position` [m/s^2], (k, 2)."""
        return self._coordinates("plane")[2]

    @property
    def cross_angles(self) -> np.ndarray:
        """Universal joint: ``(alpha, beta)`` [rad], (k, 2): the cross's rotation about
        ``axis_i`` relative to body i, and body j's about ``axis_j`` relative to the cross,
        from the drawing, continuous over turns."""
        return self._coordinates("cardan")[0]

    @property
    def cross_angle_rates(self) -> np.ndarray:
        """Rates of :attr:`cross_angles` [rad/s], (k, 2)."""
        return self._coordinates("cardan")[1]

    @property
    def cross_angle_accelerations(self) -> np.ndarray:
        """Second derivatives of :attr:`cross_angles` [rad/s^2], (k, 2)."""
        return self._coordinates("cardan")[2]

    @property
    def relative_rotation(self) -> np.ndarray:
        """Spherical joint: rotation of body j relative to body i since the drawing, in body
        i's axes, (k, 3, 3)."""
        return self._coordinates("ball")[0]

    @property
    def relative_quaternion(self) -> np.ndarray:
        """:attr:`relative_rotation` as unit quaternions ``(w, x, y, z)``, continuous, (k, 4)."""
        return self._coordinates("ball")[1]

    @property
    def rotation_vector(self) -> np.ndarray:
        """:attr:`relative_rotation` as a rotation vector (axis times angle [rad]), (k, 3)."""
        return self._coordinates("ball")[2]

    @property
    def relative_angular_velocity(self) -> np.ndarray:
        """Spherical joint: angular velocity of body j relative to body i, in body i's axes
        [rad/s], (k, 3)."""
        return self._coordinates("ball")[3]

    def _row_vectors(self) -> np.ndarray:
        """The body-frame vectors of the joint's first primitive row, in its class's order
        (see :attr:`mbd3d.model.primitives.RowTable.slots`)."""
        table = self._results.model.row_table
        slots = table.slots[self._results.model._instances_of[self.name][0]]
        return table.vector_local[slots[slots >= 0]]

    @property
    def mesh_force(self) -> MeshForce:
        """Gear pair or rack and pinion: the force of the mesh on body j (see
        :class:`MeshForce`), from the multiplier of the mesh row."""
        from mbd3d.joints.gears import GearPair, RackPinion  # noqa: PLC0415
        from mbd3d.joints.rolling import RollingDisc  # noqa: PLC0415

        element = self.element
        if isinstance(element, RollingDisc):
            raise ModelError(f"'{self.name}' is a rolling disc: its forces are contact_force "
                             "(normal) and traction (tangential)")
        if not isinstance(element, (GearPair, RackPinion)):
            raise ModelError(f"'{self.name}' ({type(element).__name__}) is not a gear mesh; "
                             "mesh_force is reported by GearPair and RackPinion")
        if isinstance(element, GearPair) and self._results.model.dim == 3:
            return self._spatial_mesh_force(element)
        torque = self.reaction(on=element.body_j).moment
        tangential = torque / element.mesh_radius
        alpha = float(element.pressure_angle)
        separating = np.abs(tangential) * math.tan(alpha)
        # r: the unit vector from body j's centre to the pitch point
        u_i, u_j, axes = self._results.model.reaction_frame(self.name)
        centre_j = self._results._global_point(element.body_j, u_j)
        if isinstance(element, GearPair):
            line = centre_j - self._results._global_point(element.body_i, u_i)
            r = -line / np.linalg.norm(line, axis=1)[:, None]
            # the teeth push gear j away from gear i; a ring's away from the pinion inside it
            away = r if element.internal else -r
        else:
            along = self._results._global_point(element.body_i, axes[:, 0], vector=True)
            r = np.column_stack([along[:, 1], -along[:, 0]])  # to the right of the rack
            away = -r
        point = centre_j + element.mesh_radius * r
        turning = np.column_stack([-r[:, 1], r[:, 0]])  # counter-clockwise about j's centre
        force = tangential[:, None] * turning + separating[:, None] * away
        return MeshForce(tangential, np.abs(tangential) / math.cos(alpha), separating, point,
                         force)

    def _spatial_mesh_force(self, element) -> MeshForce:
        """:attr:`mesh_force` of a spatial spur or bevel pair: the tooth force at the pitch
        point, where the pitch circles (cones, at the radii given) touch."""
        results = self._results
        u_i, u_j, _ = results.model.reaction_frame(self.name)
        # each gear's axis, f x g of the row's vectors on it (slots 0, 1 on i; 2, 3 on j)
        local = self._row_vectors()
        h_i, h_j = (results._global_point(body, np.cross(local[k], local[k + 1]), vector=True)
                    for body, k in ((element.body_i, 0), (element.body_j, 2)))
        centre_i = results._global_point(element.body_i, u_i)
        centre_j = results._global_point(element.body_j, u_j)
        radius_i, radius_j = float(element.radius_i), float(element.radius_j)
        tangential = np.einsum("ki,ki->k", self.reaction(on=element.body_j).moment, h_j) / radius_j
        alpha = float(element.pressure_angle)
        separating = np.abs(tangential) * math.tan(alpha)
        cosine = np.einsum("ki,ki->k", h_i, h_j)
        if np.all(np.abs(cosine) > 1.0 - 1e-12):  # parallel axes: a spur pair
            line = centre_i - centre_j
            across = line - np.einsum("ki,ki->k", line, h_j)[:, None] * h_j
            e_j = across / np.linalg.norm(across, axis=1)[:, None]  # from axis j towards i
            point = centre_j + radius_j * e_j
            # the teeth push gear j away from gear i; a ring's away from the pinion inside it
            away = e_j if element.internal else -e_j
        else:
            # the apex, where the axes meet, and the pitch cone of gear j (angle delta_j)
            # touching gear i's along the line from the apex through the pitch point
            e_j = h_i - cosine[:, None] * h_j
            e_j /= np.linalg.norm(e_j, axis=1)[:, None]
            shaft = np.arccos(np.clip(cosine, -1.0, 1.0))
            delta = np.arctan2(np.sin(shaft), radius_i / radius_j + np.cos(shaft))
            # apex = centre_j + b h_j on both axes: b from the component across h_i
            line = centre_i - centre_j
            across_i = h_j - cosine[:, None] * h_i
            b = (np.einsum("ki,ki->k", line, across_i)
                 / np.einsum("ki,ki->k", h_j, across_i))
            apex = centre_j + b[:, None] * h_j
            distance = radius_j / np.sin(delta)
            point = apex + distance[:, None] * (np.cos(delta)[:, None] * h_j
                                                + np.sin(delta)[:, None] * e_j)
            # normal to the pitch cone, into gear j: radial inwards, axial away from the apex
            away = np.sin(delta)[:, None] * h_j - np.cos(delta)[:, None] * e_j
        force = (tangential[:, None] * np.cross(h_j, e_j) + separating[:, None] * away)
        return MeshForce(tangential, np.abs(tangential) / math.cos(alpha), separating, point,
                         force)

    @property
    def contact_force(self) -> np.ndarray:
        """Cam and follower, or rolling disc: the normal force between the two bodies [N],
        (k,), positive while they press on each other (from the multipliers of the contact
        rows; see :attr:`lift_off`)."""
        force = self.reaction(on=self.element.body_j).force  # on the follower or disc
        return np.einsum("ki,ki->k", force, self.contact()[1])

    @property
    def traction(self) -> np.ndarray:
        """Rolling disc: the tangential force the track exerts on the disc along the track's
        axis [N], (k,): the friction rolling without slip needs. On a plane
        (:class:`~mbd3d.joints.RollingDiscOnPlane`): the in-plane force, global, (k, 3)."""
        from mbd3d.joints.rolling import RollingDisc, RollingDiscOnPlane  # noqa: PLC0415

        if isinstance(self.element, RollingDiscOnPlane):
            force = self.reaction(on=self.element.body_j).force
            normal = self.contact()[1]
            return force - np.einsum("ki,ki->k", force, normal)[:, None] * normal
        if not isinstance(self.element, RollingDisc):
            raise ModelError(f"'{self.name}' ({type(self.element).__name__}) is not a rolling "
                             "disc; traction is reported by RollingDisc and "
                             "RollingDiscOnPlane")
        force = self.reaction(on=self.element.body_j).force
        normal = self.contact()[1]
        return normal[:, 1] * force[:, 0] - normal[:, 0] * force[:, 1]

    def contact(self) -> tuple[np.ndarray, np.ndarray]:
        """Cam and follower, or rolling disc: the contact point on the cam's surface (the
        track, the plane), global [m], and the unit normal there towards the follower (disc),
        each (k, dim)."""
        from mbd3d.joints.cams import CamFollower, FlatFaceFollower  # noqa: PLC0415
        from mbd3d.joints.rolling import RollingDisc, RollingDiscOnPlane  # noqa: PLC0415

        element = self.element
        if not isinstance(element, (CamFollower, FlatFaceFollower, RollingDisc,
                                    RollingDiscOnPlane)):
            raise ModelError(f"'{self.name}' ({type(element).__name__}) is not a cam or a "
                             "rolling disc; contacts are reported by CamFollower, "
                             "FlatFaceFollower, RollingDisc and RollingDiscOnPlane")
        results = self._results
        u_i, u_j, axes = results.model.reaction_frame(self.name)
        if isinstance(element, RollingDiscOnPlane):
            # the lowest rim point, r (a_k a - k) / |a x k| from the centre
            normal = np.tile(axes[:, 2], (len(results.t), 1))
            a = results._global_point(element.body_j, self._row_vectors()[2], vector=True)
            along = np.einsum("ki,ki->k", a, normal)
            down = (along[:, None] * a - normal) / np.sqrt(1.0 - along ** 2)[:, None]
            return (results._global_point(element.body_j, u_j)
                    + float(element.radius) * down, normal)
        if isinstance(element, RollingDisc):
            # the track's normal (to the left of its axis), the contact a radius below
            normal = results._global_point(element.body_i, axes[:, 1], vector=True)
            return (results._global_point(element.body_j, u_j)
                    - float(element.radius) * normal, normal)
        centre = results._global_point(element.body_i, u_i)
        cam_angle = (np.zeros(len(results.t)) if element.body_i.is_ground
                     else results.body(element.body_i.name).angle)
        if isinstance(element, CamFollower):
            point = results._global_point(element.body_j, u_j)
            d = point - centre
            distance = np.linalg.norm(d, axis=1)
            u = d / distance[:, None]
            slope = element.profile(np.arctan2(d[:, 1], d[:, 0]) - cam_angle, 1)
            # the pitch curve's outward normal, u - r' w / |d|; the surface a roller in
            normal = u + slope[:, None] * np.column_stack([u[:, 1], -u[:, 0]]) / distance[:, None]
            normal /= np.linalg.norm(normal, axis=1)[:, None]
            return point - float(element.roller_radius) * normal, normal
        # the face's normal (towards the cam) is the row's first body vector, on body j
        v_j = self._row_vectors()[0]
        normal = -results._global_point(element.body_j, v_j, vector=True)
        psi = np.arctan2(normal[:, 1], normal[:, 0]) - cam_angle
        # the support function's envelope: h e + h' e_perp
        across = np.column_stack([-normal[:, 1], normal[:, 0]])
        return (centre + element.profile(psi)[:, None] * normal
                + element.profile(psi, 1)[:, None] * across, normal)

    @property
    def lift_off(self) -> np.ndarray:
        """Cam and follower: the times [s] at which the contact would have to pull, (j,):
        there a real follower leaves the cam (a stronger return spring, or a lower speed, keeps
        it on)."""
        return self._results.t[self.contact_force < 0.0]

    def reaction(self, on: str | Body | None = None, frame: str = "global") -> Reaction:
        """Force and moment this joint exerts on body ``on`` (default: its second body, j).

        Parameters
        ----------
        on : str or Body, optional
            ``body_i`` or ``body_j`` of the joint (the ground is allowed).
        frame : {"global", "joint"}
            Axes of the components; "joint" are the joint's axes attached to body i.
        """
        return self._results._reaction(self.name, on, frame)


class Results:
    """Time histories of one analysis.

    Attributes
    ----------
    model : Model
    analysis : str
        "kinematic analysis", "inverse dynamics" or "forward dynamics".
    t : ndarray (k,)
        Times [s].
    q, qd, qdd : ndarray (k, n)
        Coordinates and their first and second time derivatives.
    lam : ndarray (k, m) or None
        Lagrange multipliers (dynamics only).
    status : str
        "complete", "failed" or "interrupted"; ``message`` says why when not complete.
    stats : dict
        Solver statistics (steps, right-hand side evaluations, projections, wall time [s]).
    charts : ndarray (k, n_bodies + 1, 3, 3) or None
        Spatial models: the reference rotations the coordinates of each time point are relative
        to. Use ``body(name).rotation`` or ``.quaternion`` for orientations, never raw ``q``.
    model_t : ndarray (k,)
        Times [s] at which the model's drivers and forces are evaluated for derived quantities
        (residuals, reactions): ``t``, except in a vibration mode's animation, whose time axis
        is the vibration's while the mechanism stays at the equilibrium's time.
    """

    def __init__(self, model, analysis: str, t: np.ndarray, q: np.ndarray, qd: np.ndarray,
                 qdd: np.ndarray, lam: np.ndarray | None = None, *, status: str = "complete",
                 message: str = "", stats: dict | None = None, charts: np.ndarray | None = None,
                 turns: np.ndarray | None = None,
                 model_t: np.ndarray | None = None):
        self.model = model
        self.analysis = analysis
        self.t = np.asarray(t, dtype=float)
        self.model_t = self.t if model_t is None else np.asarray(model_t, dtype=float)
        self.q, self.qd, self.qdd = (np.asarray(a, dtype=float) for a in (q, qd, qdd))
        self.lam = None if lam is None else np.asarray(lam, dtype=float)
        self.status = status
        self.message = message
        self.stats = dict(stats or {})
        self.charts = charts
        #: spatial models: the charts as quaternions with signs that follow the motion, (k,
        #: n_bodies + 1, 4), where the analysis tracked them (else None)
        self.turns = turns
        self._residuals: tuple[np.ndarray, np.ndarray] | None = None
        self._energies: tuple[np.ndarray, np.ndarray] | None = None

    def __len__(self) -> int:
        return len(self.t)

    def __repr__(self) -> str:
        span = f"t = {self.t[0]:g}..{self.t[-1]:g} s" if len(self.t) else "no time points"
        return (f"Results({self.analysis} of '{self.model.name}': {len(self.t)} time points, "
                f"{span}, {self.status})")

    def subset(self, start: int, stop: int | None = None) -> "Results":
        """The time points ``start <= k < stop`` as results of their own (views, not copies)."""
        sl = slice(start, stop)
        return Results(self.model, self.analysis, self.t[sl], self.q[sl], self.qd[sl],
                       self.qdd[sl], None if self.lam is None else self.lam[sl],
                       status=self.status, message=self.message, stats=self.stats,
                       charts=None if self.charts is None else self.charts[sl],
                       turns=None if self.turns is None else self.turns[sl],
                       model_t=self.model_t[sl])

    # -- named access ----------------------------------------------------------------------------
    def _require_lam(self) -> np.ndarray:
        if self.lam is None:
            raise MBDError(f"{self.analysis} results carry no multipliers; run "
                           "mbd3d.inverse_dynamics or mbd3d.forward_dynamics for reactions and "
                           "driver efforts")
        return self.lam

    def _state(self, k: int) -> tuple[np.ndarray, np.ndarray | None]:
        """Coordinates of time point ``k`` and the charts they are relative to."""
        return self.q[k], None if self.charts is None else self.charts[k]

    def _body_charts(self, body: Body) -> np.ndarray | None:
        """The reference rotations of one body over all times (k, 3, 3), or None."""
        if self.charts is None:
            return None
        return self.charts[:, self.model.padded_index(body)]

    def _body_frames(self, body: Body):
        """Frames of one body over all times (k rows) and the matching coordinate arrays."""
        model = self.model
        sl = model.coordinates_of(body)
        fr = model.body_type.frames(self.q[:, sl], self.qd[:, sl], self._body_charts(body))
        return fr, self.qdd[:, sl]

    def _body(self, body: str | Body) -> Body:
        if isinstance(body, Body):
            return body
        if body == "ground":
            return self.model.ground
        return self.model.body(body)

    def body(self, name: str) -> BodyHistory:
        """Motion of body ``name``: centre of mass, orientation, angular velocity and
        acceleration."""
        b = self.model.body(name)
        bt = self.model.body_type
        fr, qdd = self._body_frames(b)
        idx = np.arange(len(self.t))
        d = self.model.dim
        sl = self.model.coordinates_of(b)
        turning = None
        if self.turns is not None:
            # the chart's tracked quaternion times that of g, (1, g) / sqrt(1 + g.g)
            g = self.q[:, sl.start + 3:sl.start + 6]
            local = (np.column_stack([np.ones(len(g)), g])
                     / np.sqrt(1.0 + np.sum(g * g, axis=1))[:, None])
            import quaternion  # noqa: PLC0415  (numpy-quaternion; imported when asked for)
            turning = quaternion.as_float_array(
                quaternion.as_quat_array(self.turns[:, self.model.padded_index(b)])
                * quaternion.as_quat_array(local))
        return BodyHistory(name, fr.R.copy(), fr.Rd.copy(), qdd[:, :d].copy(), fr.A,
                           bt.angular_velocity(fr, idx).copy(),
                           bt.angular_acceleration(fr, idx, qdd),
                           self.q[:, sl.start + 2].copy() if d == 2 else None, turning)

    def poses(self) -> tuple[np.ndarray, np.ndarray]:
        """Every body's pose at every time, as a 3D pose (what a viewer draws).

        Returns
        -------
        position : ndarray (k, n_bodies, 3)
            Centres of mass [m], global axes; planar bodies lie in the plane z = 0.
        quaternion : ndarray (k, n_bodies, 4)
            Orientations as unit quaternions ``(w, x, y, z)``; planar bodies turn about z.
        """
        model = self.model
        k, nb, nc, d = len(self.t), model.n_bodies, model.n_coords_per_body, model.dim
        Q = self.q.reshape(k, nb, nc)
        position = np.zeros((k, nb, 3))
        position[:, :, :d] = Q[:, :, :d]
        if d == 2:
            half = 0.5 * Q[:, :, 2]
            quaternion = np.zeros((k, nb, 4))
            quaternion[:, :, 0], quaternion[:, :, 3] = np.cos(half), np.sin(half)
            return position, quaternion
        charts = None if self.charts is None else self.charts[:, :nb].reshape(k * nb, 3, 3)
        A = model.body_type.frames(Q.reshape(k * nb, nc), None, charts).A
        return position, to_quaternion(A).reshape(k, nb, 4)

    def _global_point(self, body: Body, u: np.ndarray, vector: bool = False) -> np.ndarray:
        """(k, dim) global positions [m] of the body-frame point ``u`` of ``body`` (the
        ground's are global), or of the body vector ``u`` with ``vector``."""
        u = np.asarray(u, dtype=float)
        if body.is_ground:
            return np.tile(u, (len(self.t), 1))
        history = self.body(body.name)
        turned = np.einsum("kab,b->ka", history.rotation, u)
        return turned if vector else history.position + turned

    def point(self, body: str, point: Sequence[float]) -> PointHistory:
        """Trajectory of the point ``point`` [m] (body frame) of body ``body``: its global
        ``.position`` [m], ``.velocity`` [m/s] and ``.acceleration`` [m/s^2]; indexing the
        history indexes the positions."""
        b = self.model.body(body)
        u = np.asarray(point, dtype=float).reshape(-1)
        if u.size != self.model.dim or not np.all(np.isfinite(u)):
            raise ModelError(f"point of body '{body}' must be {self.model.dim} finite numbers, "
                             f"got {point!r}")
        bt = self.model.body_type
        fr, qdd = self._body_frames(b)
        k = len(self.t)
        idx = np.arange(k)
        U = np.broadcast_to(u, (k, u.size))
        acc = (np.einsum("kdn,kn->kd", bt.point_jacobian(fr, idx, U), qdd)
               + bt.point_acceleration_term(fr, idx, U))
        return PointHistory(bt.point(fr, idx, U), bt.point_velocity(fr, idx, U), acc)

    def joint(self, name: str) -> JointHistory:
        """Multipliers, reactions and efforts of joint or driver ``name``."""
        return JointHistory(self, name)

    driver = joint

    @property
    def efforts(self) -> dict[str, np.ndarray]:
        """Effort of every driver, by name."""
        return {e.name: self.joint(e.name).effort for e in self.model.joints if e.is_driver}

    def friction(self, name: str) -> np.ndarray:
        """Friction of :class:`~mbd3d.JointFriction` ``name`` on its joint's body j, (k,): a
        torque [N m] about a revolute's axis, a force [N] along a prismatic joint's axis (the
        opposite acts on body i), from the results' multipliers."""
        group = self.model.friction
        if group is None or name not in group.names:
            known = group.names if group is not None else []
            raise ModelError(f"'{name}' is not a joint friction of '{self.model.name}' "
                             f"(its frictions: {known or 'none'})")
        lam = self._require_lam()
        index = group.names.index(name)
        Q = np.zeros((self.model.n_bodies + 1, self.model.n_coords_per_body))
        out = np.empty(len(self.t))
        for k in range(len(self.t)):
            q, chart = self._state(k)
            fr = constraints.frames(self.model, q, self.qd[k], chart)
            out[k] = group.apply(self.model, fr, lam[k], Q)[index]
        return out

    def _reaction(self, name: str, on: Any, frame: str) -> Reaction:
        model = self.model
        element = model.joint(name)
        lam = self._require_lam()
        body = element.body_j if on is None else self._body(on)
        if body is not element.body_i and body is not element.body_j:
            raise ModelError(f"joint '{name}' connects '{element.body_i.name}' and "
                             f"'{element.body_j.name}'; it exerts no reaction on '{body.name}'")
        if frame not in ("global", "joint"):
            raise ModelError(f"frame must be 'global' or 'joint', got {frame!r}")
        bt, nc, k = model.body_type, model.n_coords_per_body, len(self.t)
        # Evaluate the joint's primitives for all times at once: rows 2t and 2t+1 of a stacked
        # coordinate array hold bodies i and j at time t (zeros for the ground).
        Q = np.zeros((2 * k, nc))
        charts = None if self.charts is None else np.tile(np.eye(3), (2 * k, 1, 1))
        for side, b in enumerate((element.body_i, element.body_j)):
            if not b.is_ground:
                Q[side::2] = self.q[:, model.coordinates_of(b)]
                if charts is not None:
                    charts[side::2] = self._body_charts(b)
        fr = bt.frames(Q, charts=charts)
        # the joint's rows read body i from row 2t and body j from row 2t + 1 at time t
        body_map = np.full(model.n_bodies + 1, -1, dtype=np.int64)
        body_map[model.padded_index(element.body_i)] = 0
        body_map[model.padded_index(element.body_j)] = 1
        n_motions = len(model.rotation_motions)
        table = (model.row_table.subset(np.array(model._instances_of[name]))
                 .on_bodies(body_map).repeated(k, 2, n_motions))
        phi = (np.concatenate([constraints.motion_phases(model, tk) for tk in self.model_t])
               if n_motions else np.zeros((0, 3)))
        J = evaluate_rows(table, fr, phi, value=False)[1]  # (k * r, 2, nc)
        rows = model.rows_of(name)
        # constraint force on this body, -Cq^T lam, from the side of each row that is this
        # body (a primitive may take the joint's bodies in either order)
        target = body_map[model.padded_index(body)]
        bi, bj = table.row_bodies()
        J_body = (J[:, 0] * (bi % 2 == target)[:, None] + J[:, 1] * (bj % 2 == target)[:, None])
        generalized = -np.einsum("krn,kr->kn", J_body.reshape(k, len(rows), nc), lam[:, rows])
        side = 0 if body is element.body_i else 1
        idx = np.arange(k) * 2 + side
        force, moment_cm = bt.wrench(fr, idx, generalized)
        point_i, point_j, axes = model.reaction_frame(name)
        u = np.broadcast_to(point_i if side == 0 else point_j, (k, model.dim))
        arm = bt.point(fr, idx, u) - fr.Q[idx, :model.dim]
        moment = moment_cm - bt.cross(arm, force)
        if frame == "joint":
            A_axes = np.einsum("kab,bc->kac", fr.A[np.arange(k) * 2], axes)
            force = np.einsum("kab,ka->kb", A_axes, force)
            if model.dim == 3:
                moment = np.einsum("kab,ka->kb", A_axes, moment)
        return Reaction(body.name, frame, force, moment)

    # -- checks ----------------------------------------------------------------------------------
    def _compute_residuals(self) -> tuple[np.ndarray, np.ndarray]:
        if self._residuals is None:
            self._residuals = history.residuals(self.model, self.model_t, self.q, self.qd,
                                                 self.charts)
        return self._residuals

    def _compute_energies(self) -> tuple[np.ndarray, np.ndarray]:
        if self._energies is None:
            self._energies = history.energies(self.model, self.q, self.qd, self.charts)
        return self._energies

    @property
    def position_residual(self) -> np.ndarray:
        """``max |C|`` at every time point [m or rad]."""
        return self._compute_residuals()[0]

    @property
    def velocity_residual(self) -> np.ndarray:
        """``max |Cq qd + Ct|`` at every time point [m/s or rad/s]."""
        return self._compute_residuals()[1]

    @property
    def reactions_unique(self) -> bool:
        """False when the constraint rows were dependent at some time point (redundant
        constraints, a singular position): the multipliers there, hence the reactions and
        efforts, are one of many that balance the mechanism (the minimum-norm one).
        ``stats["singular_outputs"]`` lists those times [s]."""
        return not self.stats.get("singular_outputs")

    @property
    def singular_passages(self) -> list:
        """Singular positions the motion passed (generalized-alpha only; the explicit methods
        stop at one): a list of :class:`mbd3d.analyses.passages.SingularPassage`, each with the
        ``time`` [s] and the ``joints`` whose rows (nearly) depend on each other there."""
        return list(self.stats.get("singular_passages", []))

    @property
    def kinetic_energy(self) -> np.ndarray:
        """Kinetic energy [J] at every time point."""
        return self._compute_energies()[0]

    @property
    def potential_energy(self) -> np.ndarray:
        """Potential energy of gravity (zero at the global origin) and springs [J]."""
        return self._compute_energies()[1]

    # -- export ----------------------------------------------------------------------------------
    def _export_columns(self) -> list[tuple[str, str, np.ndarray]]:
        """``(name, unit, values)`` of every exported time history (see :meth:`columns`)."""
        out: list[tuple[str, str, np.ndarray]] = []
        planar = self.model.dim == 2
        axes = "xy" if planar else "xyz"
        for b in self.model.bodies:
            h = self.body(b.name)
            for label, unit, arr in (("", "m", h.position), ("v", "m/s", h.velocity),
                                     ("a", "m/s^2", h.acceleration)):
                out += [(f"{b.name}.{label}{c}", unit, arr[:, k]) for k, c in enumerate(axes)]
            if planar:
                out += [(f"{b.name}.angle", "rad", h.angle),
                        (f"{b.name}.omega", "rad/s", h.angular_velocity),
                        (f"{b.name}.alpha", "rad/s^2", h.angular_acceleration)]
            else:
                quaternion = h.quaternion  # computed per call: once
                out += [(f"{b.name}.q{c}", "-", quaternion[:, k]) for k, c in enumerate("wxyz")]
                out += [(f"{b.name}.omega_{c}", "rad/s", h.angular_velocity[:, k])
                        for k, c in enumerate(axes)]
                out += [(f"{b.name}.alpha_{c}", "rad/s^2", h.angular_acceleration[:, k])
                        for k, c in enumerate(axes)]
        if self.lam is None:
            return out
        for element in self.model.joints:
            if element.is_driver:
                out.append((f"{element.name}.effort", element.effort_unit, self.joint(
                    element.name).effort))
                continue
            on = element.body_i if element.body_j.is_ground else element.body_j
            r = self.joint(element.name).reaction(on=on)
            out += [(f"{element.name}.F{c} on {on.name}", "N", r.force[:, k])
                    for k, c in enumerate(axes)]
            if planar:
                out.append((f"{element.name}.M on {on.name}", "N m", r.moment))
            else:
                out += [(f"{element.name}.M{c} on {on.name}", "N m", r.moment[:, k])
                        for k, c in enumerate(axes)]
        return out

    def columns(self) -> dict[str, np.ndarray]:
        """All time histories as named columns with their units, the layout of :meth:`to_csv`
        and :meth:`to_pandas`.

        ``t [s]``; for every body, the centre of mass ``body.x [m]``, its velocity
        ``body.vx [m/s]`` and acceleration ``body.ax [m/s^2]`` (global axes), and the
        orientation: planar ``body.angle [rad]``, ``body.omega [rad/s]``, ``body.alpha
        [rad/s^2]``; spatial the unit quaternion ``body.qw`` ... ``body.qz`` (sign kept
        continuous) and the angular velocity and acceleration in global axes. With multipliers
        (dynamics), every driver's ``effort`` [N m or N] and every joint's reaction as the
        printed tables show it: the force ``joint.Fx on body [N]`` and the moment ``joint.M on
        body [N m]`` (about the joint's point) that the joint exerts on its moving body, global
        axes. The raw coordinates and multipliers are in :meth:`to_npz`.

        Examples
        --------
        >>> import numpy as np, mbd3d as mb
        >>> from mbd3d.mechanisms import slider_crank
        >>> res = mb.inverse_dynamics(slider_crank(crank_speed=1.0), np.linspace(0.0, 0.1, 3))
        >>> [c for c in res.columns() if c.startswith(("slider.x", "O.F", "motor"))]
        ['slider.x [m]', 'O.Fx on crank [N]', 'O.Fy on crank [N]', 'motor.effort [N m]']
        """
        cols: dict[str, np.ndarray] = {"t [s]": self.t}
        for name, unit, values in self._export_columns():
            cols[f"{name} [{unit}]"] = values
        return cols

    def to_csv(self, path: str | os.PathLike, overwrite: bool = True) -> str:
        """Write :meth:`columns` to a CSV file: a header of names with units, then one row per
        time point, every number to full double precision.

        Names are quoted by the csv module where they hold commas, quotes or line breaks, so
        any body or joint name reads back. The file is checked before it is written and written
        atomically (see :mod:`mbd3d.io.files`). Returns the absolute path written.
        """
        cols = self.columns()
        data = np.column_stack(list(cols.values())) if len(self.t) else np.zeros((0, len(cols)))

        def write(f):
            writer = csv.writer(f, lineterminator="\n")
            writer.writerow(cols)
            writer.writerows([repr(float(x)) for x in row] for row in data)
        return files.atomic_write(path, write, text=True, overwrite=overwrite,
                                  what="the CSV file")

    def to_pandas(self):
        """The :meth:`columns` as a ``pandas.DataFrame`` indexed by time ``t [s]``.

        Column names carry their units, as in the CSV; ``df.attrs["units"]`` maps each column
        to its unit alone. Needs pandas (``pip install "mbd3d[pandas]"``).
        """
        pd = _import_pandas()
        cols = self.columns()
        t = cols.pop("t [s]")
        df = pd.DataFrame(cols, index=pd.Index(t, name="t [s]"))
        df.attrs["units"] = {label: label[label.rindex("[") + 1:-1] for label in df.columns}
        df.attrs["analysis"], df.attrs["model"] = self.analysis, self.model.name
        return df

    def to_npz(self, path: str | os.PathLike | BinaryIO, overwrite: bool = True) -> str | None:
        """Write the raw arrays (``t``, ``q``, ``qd``, ``qdd``, ``lam``, ``charts``,
        ``chart_quaternions``) and their labels to a compressed NumPy ``.npz`` file: a path
        (checked, then written atomically; its absolute path is returned) or an open binary
        file."""
        arrays = dict(t=self.t, q=self.q, qd=self.qd, qdd=self.qdd,
                      coordinate_labels=np.array(self.model.coordinate_labels),
                      row_labels=np.array(self.model.row_labels),
                      analysis=np.array(self.analysis), status=np.array(self.status),
                      message=np.array(self.message), model=np.array(self.model.name))
        if self.lam is not None:
            arrays["lam"] = self.lam
        if self.charts is not None:
            arrays["charts"] = self.charts
        if self.turns is not None:
            arrays["chart_quaternions"] = self.turns

        def write(f):
            np.savez_compressed(f, **arrays)
        if hasattr(path, "write"):
            write(path)
            return None
        return files.atomic_write(path, write, text=False, overwrite=overwrite,
                                  what="the NPZ file")


def _import_pandas():
    """pandas, or an error that says how to get it (it is an optional extra)."""
    try:
        import pandas  # noqa: PLC0415  (optional)
    except ImportError:
        raise MBDError('to_pandas needs pandas: pip install "mbd3d[pandas]" (or pip install '
                       'pandas)') from None
    return pandas


class ResultsBuffer:
    """Histories an analysis fills time point by time point, preallocated for all ``t``.

    :meth:`partial` builds the :class:`Results` of the points stored so far, as the analysis
    hands them to observers while it runs and keeps them when it fails.
    """

    def __init__(self, model, analysis: str, t: np.ndarray, stats: dict,
                 with_lam: bool = True):
        import time
        self._clock = time.perf_counter
        self._start = self._clock()
        self.model, self.analysis, self.t, self.stats = model, analysis, t, stats
        k, n = len(t), model.n_coordinates
        self.q, self.qd, self.qdd = (np.empty((k, n)) for _ in range(3))
        self.lam = np.empty((k, model.n_constraints)) if with_lam else None
        self.charts = None if model.charts0 is None else np.empty((k,) + model.charts0.shape)
        self.turns = None
        self.done = 0

    def store(self, q, qd, qdd, lam=None, chart=None, turns=None) -> None:
        """The next time point's state (``chart``: its reference rotations, spatial models;
        ``turns``: the charts' quaternions whose signs follow the motion, where tracked)."""
        k = self.done
        self.q[k], self.qd[k], self.qdd[k] = q, qd, qdd
        if self.lam is not None:
            self.lam[k] = lam
        if self.charts is not None:
            self.charts[k] = chart
        if turns is not None:
            if self.turns is None:
                self.turns = np.empty((len(self.t),) + np.shape(turns))
            self.turns[k] = turns
        self.done = k + 1

    def partial(self, status: str, message: str) -> Results:
        self.stats["wall_time"] = self._clock() - self._start
        k = self.done
        return Results(self.model, self.analysis, self.t[:k], self.q[:k], self.qd[:k],
                       self.qdd[:k], None if self.lam is None else self.lam[:k], status=status,
                       message=message, stats=self.stats,
                       charts=None if self.charts is None else self.charts[:k],
                       turns=None if self.turns is None else self.turns[:k])


def run_keeping_results(loop: Callable[[], None], partial: Callable[[str, str], "Results"],
                        watch: Any = None) -> "Results":
    """Run an analysis ``loop`` so that no computed time point is lost.

    ``partial(status, message)`` builds the results of the time points done so far. On an error
    they are attached to it (``error.results``) before it propagates; on Ctrl-C they are
    returned with status "interrupted". ``watch`` (:class:`mbd3d.io.observers.Watch`) is started
    before the loop and handed the final results however the loop ends, so a recording of a
    failing run keeps everything up to the failure.
    """
    if watch is not None:
        watch.start()
    try:
        loop()
    except KeyboardInterrupt:
        results = partial("interrupted", "interrupted by the user; the results end at the last "
                                         "completed time point")
    except Exception as exc:
        results = partial("failed", str(exc))
        try:
            exc.results = results  # type: ignore[attr-defined]
        except AttributeError:  # exception types with __slots__
            pass
        if watch is not None:
            watch.finish(results, failing=True)
        raise
    else:
        results = partial("complete", "")
    if watch is not None:
        watch.finish(results, failing=False)
    return results


def format_table(columns: dict[str, Sequence[float]], precision: int = 5,
                 rows: int | None = None) -> str:
    """A plain-text table of equally long columns (numbers or text), for printing in a terminal.

    ``rows`` limits a long table to that many rows, evenly spaced, first and last included.

    >>> print(format_table({"t [s]": [0.0, 0.5], "x [m]": [1.0, -0.25]}, precision=3))
      t [s]  x [m]
          0      1
        0.5  -0.25
    >>> print(format_table({"k": range(11)}, rows=3))
       k
       0
       5
      10
    """
    names = list(columns)
    length = len(columns[names[0]]) if names else 0
    shown = range(length)
    if rows is not None and length > rows:
        shown = np.unique(np.round(np.linspace(0, length - 1, max(rows, 2))).astype(int))
    # adding 0.0 turns -0.0 into 0.0, which reads better in a table
    cells = [[v if isinstance(v, str) else f"{float(v) + 0.0:.{precision}g}"
              for v in (columns[name][k] for k in shown)] for name in names]
    widths = [max([len(name)] + [len(c) for c in col]) + 1 for name, col in zip(names, cells)]
    lines = ["".join(name.rjust(w + 1) for name, w in zip(names, widths))]
    for row in zip(*cells):
        lines.append("".join(c.rjust(w + 1) for c, w in zip(row, widths)))
    return "\n".join(line.rstrip() for line in lines)
