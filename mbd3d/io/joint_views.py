"""What the results say of one joint, driver or higher pair over time: :class:`JointHistory`
(multipliers, efforts, joint coordinates, reactions, mesh and contact forces), with
:class:`Reaction` and :class:`MeshForce`. Made by :meth:`Results.joint`; sign conventions as
in :mod:`mbd3d.io.results`."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mbd3d.model.body import Body
from mbd3d.errors import ModelError

if TYPE_CHECKING:
    from mbd3d.io.results import Results

__all__ = ["Reaction", "MeshForce", "JointHistory"]


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
            value = jc.hinge(self._results, source.body_i, source.body_j, axis,
                             None if planar else model.hinge_directions(source.name))
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
        (see ``RowTable.slots``, :class:`mbd3d.model.primitives.RowTable`)."""
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
