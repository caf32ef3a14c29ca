"""Gear pairs and rack and pinion: higher pairs whose pitch curves roll without slip."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.model.body import Body
from mbd3d.model.builder import BuildContext
from mbd3d.model.element import ConstraintElement, PrimitiveSpec

from mbd3d.joints.base import perpendicular

#: relative mismatch allowed between the drawing's centre distance and the pitch radii
_CENTRE_TOLERANCE = 1e-6


class _Mesh(ConstraintElement):
    """What gear meshes share: checks of pitch radii, centres and the pressure angle.

    Subclasses give ``mesh_radius``: body j's pitch radius, about whose centre the mesh force
    is reported.
    """

    #: what the error messages call it
    kind = "gear pair"

    def _radius(self, ctx: BuildContext, value: Any, what: str) -> float:
        return ctx.scalar(value, f"{self.kind} '{self.name}': {what}", positive=True)

    def _pressure_angle(self, ctx: BuildContext) -> float:
        alpha = ctx.scalar(self.pressure_angle, f"{self.kind} '{self.name}': pressure_angle")
        if not 0.0 <= alpha < math.radians(45.0):
            raise ModelError(f"{self.kind} '{self.name}': pressure_angle must be in [0, 45) "
                             f"degrees, given in radians; got {alpha!r} rad "
                             "(20 degrees is math.radians(20))")
        return alpha

    def _centre(self, ctx: BuildContext, body: Body, value: Any, what: str) -> np.ndarray:
        """A gear centre in body frame: given in the drawing, or the body's centre of mass."""
        if value is None:
            if body.is_ground:
                raise ModelError(f"{self.kind} '{self.name}': the ground has no centre of mass; "
                                 f"give {what}= (the gear centre in the drawing, global axes)")
            return np.zeros(ctx.dim)
        return ctx.to_local_point(body, ctx.vector(value, f"{self.kind} '{self.name}': {what}"))


class GearPair(_Mesh):
    """Two planar gears in mesh: their pitch circles roll on each other without slip.

    Whatever carries the gear centres (the ground, or an arm that turns as in a planetary
    train), the gears' angles ``theta_i``, ``theta_j`` [rad] and the angle ``phi`` of the line
    from centre i to centre j satisfy ``rho_i (theta_i - phi) + sigma rho_j (theta_j - phi) =
    const`` (``sigma = +1`` external mesh, ``-1`` internal); with the centres fixed, ``omega_j /
    omega_i = -sigma rho_i / rho_j``. The centre distance must be held by other joints (each
    gear's revolute to a common carrier); this constraint adds the one row of the mesh (see
    :class:`mbd3d.model.primitives.Gear`).

    The teeth push along the line of action, inclined by the pressure angle to the common
    tangent: ``results.joint(name).mesh_force`` gives the tangential force, the tooth force and
    its separating component. The model is of rigid, backlash-free gears with their pitch
    circles exactly touching: the separating component is not part of the joints' reactions,
    the bearings carry it in addition.

    Parameters
    ----------
    name : str
    body_i, body_j : Body
        The gears (either may be the ground: a fixed gear). With ``internal=True``, body j is
        the ring (the internal gear) and body i the pinion inside it.
    radius_i, radius_j : float
        Pitch radii [m] (module times teeth over two).
    internal : bool
        Internal mesh: the pinion rolls inside the ring, both turning the same way.
    center_i, center_j : array_like, optional
        The gear centres in the drawing (global coordinates) [m]; default each gear's centre
        of mass. Their distance must be ``radius_i + radius_j`` (internal:
        ``radius_j - radius_i``).
    pressure_angle : float
        Angle of the line of action to the common tangent [rad]; default 20 degrees.

    Examples
    --------
    >>> import math
    >>> import mbd3d as mb
    >>> from mbd3d.joints import GearPair, Revolute
    >>> b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0))
    >>> pinion = b.add_body("pinion", mass=1.0, inertia=1e-3, position=(0.0, 0.0))
    >>> wheel = b.add_body("wheel", mass=4.0, inertia=2e-2, position=(0.15, 0.0))
    >>> _ = b.add(Revolute("A", b.ground, pinion, at=(0.0, 0.0)))
    >>> _ = b.add(Revolute("B", b.ground, wheel, at=(0.15, 0.0)))
    >>> mesh = b.add(GearPair("mesh", pinion, wheel, radius_i=0.05, radius_j=0.10))
    """

    def __init__(self, name: str, body_i: Body, body_j: Body, *, radius_i: float,
                 radius_j: float, internal: bool = False, center_i: Any = None,
                 center_j: Any = None, pressure_angle: float = math.radians(20.0)):
        self.name = name
        self.body_i = body_i
        self.body_j = body_j
        self.radius_i = radius_i
        self.radius_j = radius_j
        self.internal = internal
        self.center_i = center_i
        self.center_j = center_j
        self.pressure_angle = pressure_angle

    def geometry(self, ctx: BuildContext) -> tuple[np.ndarray, np.ndarray, float, float]:
        """``(u_i, u_j, rho_i, sigma rho_j)``: centres in body frames and signed radii [m]."""
        if ctx.dim != 2:
            raise ModelError(f"gear pair '{self.name}': gears are available for planar models "
                             "only (dim=2) so far")
        if not isinstance(self.internal, (bool, np.bool_)):
            raise ModelError(f"gear pair '{self.name}': internal must be True or False, got "
                             f"{self.internal!r}")
        rho_i = self._radius(ctx, self.radius_i, "radius_i")
        rho_j = self._radius(ctx, self.radius_j, "radius_j")
        self._pressure_angle(ctx)
        if self.internal and not rho_j > rho_i:
            raise ModelError(f"gear pair '{self.name}': with internal=True body j "
                             f"('{self.body_j.name}') is the ring, so radius_j must be larger "
                             f"than radius_i; got {rho_j!r} <= {rho_i!r} m")
        u_i = self._centre(ctx, self.body_i, self.center_i, "center_i")
        u_j = self._centre(ctx, self.body_j, self.center_j, "center_j")
        distance = float(np.linalg.norm(ctx.to_global_point(self.body_j, u_j)
                                        - ctx.to_global_point(self.body_i, u_i)))
        expected = rho_j - rho_i if self.internal else rho_i + rho_j
        if abs(distance - expected) > _CENTRE_TOLERANCE * expected:
            raise ModelError(
                f"gear pair '{self.name}': the gear centres are {distance:.9g} m apart in the "
                f"drawing, but pitch radii {rho_i:g} and {rho_j:g} m "
                f"{'in internal mesh' if self.internal else 'in mesh'} need {expected:.9g} m; "
                "place the gears (or center_i/center_j) so that the pitch circles touch")
        return u_i, u_j, rho_i, -rho_j if self.internal else rho_j

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        u_i, u_j, rho_i, signed_j = self.geometry(ctx)
        d = ctx.to_global_point(self.body_j, u_j) - ctx.to_global_point(self.body_i, u_i)
        phi = math.atan2(d[1], d[0])
        theta_i = ctx.initial_coordinate(self.body_i, 2)
        theta_j = ctx.initial_coordinate(self.body_j, 2)
        total = rho_i + signed_j
        constant = rho_i * theta_i + signed_j * theta_j - total * phi
        real = (rho_i / total, signed_j / total, constant / total, math.copysign(1.0, total))
        return [PrimitiveSpec("gear", self.body_i, self.body_j,
                              {"u_i": u_i, "u_j": u_j, "real": real}, ("mesh",))]

    def reaction_frame(self, ctx: BuildContext):
        u_i, u_j, _, _ = self.geometry(ctx)
        return u_i, u_j, np.eye(2)

    @property
    def mesh_radius(self) -> float:
        """Pitch radius of body j [m], about whose centre the mesh force is reported."""
        return float(self.radius_j)


class RackPinion(_Mesh):
    """A planar rack and pinion: the pinion's pitch circle rolls without slip on the rack's
    pitch line.

    Body i is the rack, body j the pinion. The rack's pitch line runs along ``axis`` at
    ``radius`` to the right of the pinion's centre (looking along ``axis``; reverse ``axis``
    for a rack above the pinion): when the pinion centre advances by ``s`` along the rack,
    relative to it, the pinion turns by ``-s / radius`` relative to the rack (clockwise for a
    rack below). The distance of the centre from the line must be held by other joints
    (typically the rack's prismatic joint and the pinion's revolute). Row:
    :class:`mbd3d.model.primitives.Rack`.

    Parameters
    ----------
    name : str
    body_i : Body
        The rack (may be the ground: the pinion then rolls along a fixed rack).
    body_j : Body
        The pinion.
    radius : float
        The pinion's pitch radius [m].
    axis : array_like
        Direction of the rack in the drawing (global axes).
    center : array_like, optional
        The pinion centre in the drawing [m]; default the pinion's centre of mass.
    pressure_angle : float
        Angle of the line of action to the pitch line [rad]; default 20 degrees.
    """

    #: what the error messages call it
    kind = "rack and pinion"

    def __init__(self, name: str, body_i: Body, body_j: Body, *, radius: float, axis: Any,
                 center: Any = None, pressure_angle: float = math.radians(20.0)):
        self.name = name
        self.body_i = body_i
        self.body_j = body_j
        self.radius = radius
        self.axis = axis
        self.center = center
        self.pressure_angle = pressure_angle

    def geometry(self, ctx: BuildContext) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        """``(u_i, u_j, a_i, rho)``: the pinion centre in the frames of the rack and the pinion,
        the rack's unit direction in its frame, the pitch radius [m]."""
        if ctx.dim != 2:
            raise ModelError(f"{self.kind} '{self.name}': available for planar models only "
                             "(dim=2) so far")
        rho = self._radius(ctx, self.radius, "radius")
        self._pressure_angle(ctx)
        u_j = self._centre(ctx, self.body_j, self.center, "center")
        u_i = ctx.to_local_point(self.body_i, ctx.to_global_point(self.body_j, u_j))
        axis = ctx.direction(self.axis, f"{self.kind} '{self.name}': axis")
        return u_i, u_j, ctx.to_local_vector(self.body_i, axis), rho

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        u_i, u_j, a_i, rho = self.geometry(ctx)
        turn = ctx.initial_coordinate(self.body_j, 2) - ctx.initial_coordinate(self.body_i, 2)
        return [PrimitiveSpec("rack", self.body_i, self.body_j,
                              {"v_i": a_i, "u_i": u_i, "u_j": u_j, "real": (rho,)}, ("mesh",),
                              c0=rho * turn)]

    def reaction_frame(self, ctx: BuildContext):
        u_i, u_j, a_i, _ = self.geometry(ctx)
        return u_i, u_j, np.column_stack([a_i, perpendicular(a_i)])

    @property
    def mesh_radius(self) -> float:
        """The pinion's pitch radius [m]: the mesh force is reported about its centre."""
        return float(self.radius)
