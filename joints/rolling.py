"""Discs rolling without slipping: on a line (planar), on a plane (spatial, nonholonomic)."""

from __future__ import annotations

from typing import Any

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.model.body import Body
from mbd3d.model.builder import BuildContext
from mbd3d.model.element import ConstraintElement, PrimitiveSpec

from mbd3d.joints.base import perpendicular, triad
from mbd3d.joints.gears import RackPinion


class RollingDisc(RackPinion):
    """A planar disc (body j) rolling without slipping on a straight track (body i, or the
    ground), touching it all the time.

    The track's line runs along ``axis`` at ``radius`` to the right of the disc's centre
    (looking along ``axis``; reverse it for a disc under a track). Two rows: the centre stays
    at ``radius`` from the line (``contact``: a dot-2 row, like a pin in a slot), and the disc
    turns by ``-s / radius`` relative to the track as its centre advances by ``s`` along it
    (``rolling``: the rack and pinion's row, :class:`mbd3d.model.primitives.Rack`). In space
    a disc rolls on a plane: :class:`RollingDiscOnPlane`.

    ``results.joint(name).contact_force`` is the normal force pressing disc and track
    together [N] and ``.traction`` the tangential force the track exerts on the disc along
    ``axis`` [N]: the friction that rolling needs, to compare with ``mu`` times the normal
    force.

    Parameters
    ----------
    name : str
    body_i : Body
        The track (may be the ground).
    body_j : Body
        The disc.
    radius : float
        The disc's rolling radius [m].
    axis : array_like
        Direction of the track in the drawing (global axes).
    center : array_like, optional
        The disc's centre in the drawing [m]; default its centre of mass.
    """

    kind = "rolling disc"

    def __init__(self, name: str, body_i: Body, body_j: Body, *, radius: float, axis: Any,
                 center: Any = None):
        super().__init__(name, body_i, body_j, radius=radius, axis=axis, center=center,
                         pressure_angle=0.0)

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        u_i, u_j, a_i, _ = self.geometry(ctx)
        rolling = super().primitives(ctx)[0]
        rolling.labels = ("rolling",)
        contact = PrimitiveSpec("dot2", self.body_i, self.body_j,
                                {"v_i": perpendicular(a_i), "u_i": u_i, "u_j": u_j},
                                ("contact",))
        return [contact, rolling]

    def reaction_frame(self, ctx: BuildContext):
        u_i, u_j, a_i, _ = self.geometry(ctx)
        return u_i, u_j, np.column_stack([a_i, perpendicular(a_i)])


class RollingDiscOnPlane(ConstraintElement):
    """A thin disc (body j) rolling without slipping on a fixed plane (the ground): the
    classical rolling disc, a nonholonomic joint.

    The disc's lowest rim point stays on the plane (one holonomic row) and the disc's
    material point there has no velocity along the plane (two velocity-level rows): the disc
    can roll to any position and heading, so the configurations it can reach are five
    dimensional while its velocities are three (:class:`mbd3d.model.primitives.DiscOnPlane`).
    Forward dynamics with the explicit integrators (DOP853, RK45, ...), static equilibrium
    (balanced in the motions the rows leave), vibration modes and linearisation
    (:func:`mbd3d.linearize`, with fewer independent velocities than displacements) handle
    such rows; kinematic analysis, inverse dynamics and generalized-alpha need positions that
    follow from the constraints and refuse them.

    ``results.joint(name).contact_force`` is the normal force the plane exerts on the disc
    [N] and ``.traction`` the in-plane force (global, (k, 3)) [N]: the friction rolling needs,
    to compare with ``mu`` times the normal force; ``.contact()`` the contact point and the
    plane's normal.

    Parameters
    ----------
    name : str
    body_i : Body
        The ground (moving planes are not supported).
    body_j : Body
        The disc; its centre is its centre of mass.
    radius : float
        The disc's rolling radius [m].
    axis : array_like
        The disc's axis in the drawing (global axes); not along ``normal``.
    normal : array_like
        The plane's normal in the drawing, towards the disc; default ``(0, 0, 1)``.
    point : array_like, optional
        A point of the plane in the drawing [m]; default the disc's lowest point in the
        drawing (the plane placed under it).
    """

    kind = "rolling disc"

    def __init__(self, name: str, body_i: Body, body_j: Body, *, radius: float, axis: Any,
                 normal: Any = (0.0, 0.0, 1.0), point: Any = None):
        self.name = name
        self.body_i = body_i
        self.body_j = body_j
        self.radius = radius
        self.axis = axis
        self.normal = normal
        self.point = point

    def geometry(self, ctx: BuildContext):
        """``(k, t_1, a_j, r, offset)``: the plane's normal and an in-plane axis (global), the
        disc's axis in its frame, the radius [m] and the plane's offset ``k . P0`` [m].

        Parameters
        ----------
        ctx : BuildContext
            The model being built (its drawing, and the checks that name what is wrong).
        """
        what = f"rolling disc '{self.name}'"
        if ctx.dim != 3:
            raise ModelError(f"{what}: RollingDiscOnPlane is spatial (dim=3); a planar disc on "
                             "a line is RollingDisc")
        if not self.body_i.is_ground:
            raise ModelError(f"{what}: body_i must be the ground (the plane is fixed); moving "
                             f"planes such as '{self.body_i.name}' are not supported")
        radius = ctx.scalar(self.radius, f"{what}: radius", positive=True)
        k = ctx.direction(self.normal, f"{what}: normal")
        axis = ctx.direction(self.axis, f"{what}: axis")
        across = float(np.linalg.norm(np.cross(axis, k)))
        if across < 1e-6:
            raise ModelError(f"{what}: the disc's axis is along the plane's normal (the disc "
                             "lies flat), where its contact point is undefined; give the axis "
                             "of a disc standing on its rim")
        centre = ctx.to_global_point(self.body_j, np.zeros(3))
        if self.point is None:
            # the lowest rim point: from the centre, r (a_k a - k) / |a x k|
            lowest = centre + radius * ((axis @ k) * axis - k) / across
            offset = float(k @ lowest)
        else:
            offset = float(k @ ctx.vector(self.point, f"{what}: point"))
        f, _, _ = triad(k)
        return k, f, ctx.to_local_vector(self.body_j, axis), radius, offset

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        k, t_1, a_j, radius, offset = self.geometry(ctx)
        x, y, z = np.eye(3)  # the disc's body axes, in its own frame
        return [PrimitiveSpec("disc_on_plane", self.body_i, self.body_j,
                              {"k_i": k, "t_i": t_1, "a_j": a_j, "x_j": x, "y_j": y, "z_j": z,
                               "real": (radius,)},
                              ("contact", "rolling_1", "rolling_2"), c0=offset)]

    def reaction_frame(self, ctx: BuildContext):
        k, t_1, _, _, _ = self.geometry(ctx)
        return np.zeros(3), np.zeros(3), np.column_stack([t_1, np.cross(k, t_1), k])
