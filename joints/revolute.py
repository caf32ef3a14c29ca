"""Revolute joint (pin / hinge)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.model.body import Body
from mbd3d.model.element import PrimitiveSpec
from mbd3d.model.builder import BuildContext

from mbd3d.joints.base import Axes, Joint, perpendicular_rows


class Revolute(Joint):
    """A pin or hinge: a point of body i and a point of body j coincide; rotation about the axis
    is free.

    Planar form: ``r_i + A_i u_i - r_j - A_j u_j = 0`` (rows ``x``, ``y``; the original
    program's eqs. 4-6). Spatial form (Haug): the same point coincidence (rows ``x``, ``y``,
    ``z``) and two dot-1 rows keeping the hinge axes aligned (``axis_f``, ``axis_g``).

    Reaction on body j (``results.joint(name).reaction()``): the pin force [N] and, in 3D, the
    moment [N m] about the pin, which is perpendicular to the axis. Joint axes: z along the
    hinge axis.

    Parameters
    ----------
    name : str
    body_i, body_j : Body
        The connected bodies (either may be ``builder.ground``).
    at : array_like, optional
        The pin in global coordinates of the drawing [m].
    point_i, point_j : array_like, optional
        The pin in the frames of body i and body j [m] (see :class:`joints.base.Joint`).
    axis : (3,) array_like
        Spatial models: the hinge axis in the drawing (global axes). Ignored in 2D.
    drawn_angle : float, optional
        Spatial models: the angle the hinge reads in the drawing [rad] (its
        ``results.joint(name).angle``, what a RotationDriver, a JointLimit and a
        RotationalSpringDamper across it take as its angle): body j's reference direction
        is the one at this angle from body i's in the drawing. Default: the angle from
        body i's to body j's x axis, projected on the plane normal to the axis (see
        :func:`reference_direction`). Robot files' importers give it their joint
        coordinate, so that the angle reads as the file's. Refused in 2D, where the angle
        is ``theta_j - theta_i`` of the bodies' own angles.

    Examples
    --------
    >>> import mbd3d as mb
    >>> from mbd3d.joints import Revolute
    >>> b = mb.ModelBuilder(dim=2)
    >>> crank = b.add_body("crank", mass=1.0, inertia=0.01, position=(0.05, 0.0))
    >>> pin = b.add(Revolute("O", b.ground, crank, at=(0.0, 0.0)))
    """

    friction_kind = "revolute"
    #: the coordinates a :class:`~mbd3d.JointLimit` may stop
    limit_coordinates = ("angle",)

    def __init__(self, name: str, body_i: Body, body_j: Body, *, at: Any = None,
                 point_i: Any = None, point_j: Any = None, axis: Any = None,
                 drawn_angle: float | None = None):
        super().__init__(name, body_i, body_j, at=at, point_i=point_i, point_j=point_j)
        self.axis = axis
        self.drawn_angle = drawn_angle

    def hinge_directions(self, ctx: BuildContext, what: str
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return hinge_directions(ctx, self)

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        u_i, u_j = self.points(ctx)
        point = PrimitiveSpec("point", self.body_i, self.body_j, {"u_i": u_i, "u_j": u_j},
                              ("x", "y", "z")[:ctx.dim])
        if ctx.dim == 2:
            planar_angle(ctx, self)
            return [point]
        return [point, *perpendicular_rows(self, Axes(ctx, self, self.axis))]

    def reaction_frame(self, ctx: BuildContext):
        u_i, u_j = self.points(ctx)
        if ctx.dim == 2:
            return super().reaction_frame(ctx)
        return u_i, u_j, Axes(ctx, self, self.axis).reaction_axes(along_x=False)


def hinge_directions(ctx: BuildContext, joint: Joint
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(f_i, g_i, f_j)``: the directions a spatial hinge's angle about ``joint.axis`` is
    measured from, in body i's frame (``g_i = h x f_i``), and body j's reference direction in
    its own frame: :func:`reference_direction`, or where the joint's ``drawn_angle`` is
    given, the direction at that angle from ``f_i`` in the drawing."""
    axes = Axes(ctx, joint, joint.axis)
    h_i, h_j = axes.i[2], axes.j[2]
    f_i = reference_direction(h_i)
    g_i = np.cross(h_i, f_i)
    if joint.drawn_angle is None:
        return f_i, g_i, reference_direction(h_j)
    angle = ctx.scalar(joint.drawn_angle, f"joint '{joint.name}': drawn_angle")
    drawn = ctx.rotation(joint.body_i) @ (math.cos(angle) * f_i + math.sin(angle) * g_i)
    return f_i, g_i, ctx.to_local_vector(joint.body_j, drawn)


def planar_angle(ctx: BuildContext, joint: Joint) -> None:
    """Refuse a hinge's ``drawn_angle`` in a planar model, naming the joint."""
    if joint.drawn_angle is not None:
        raise ModelError(f"joint '{joint.name}': drawn_angle is for spatial hinges; in a plane "
                         "a hinge's angle is theta_j - theta_i of the bodies' own angles (give "
                         "the bodies' angles, or a RotationDriver's offset)")


def reference_direction(h: np.ndarray) -> np.ndarray:
    """The body's x axis projected on the plane normal to ``h`` (body frame), or its y axis
    when x lies along ``h`` (both cannot): where a rotation about ``h`` is measured from."""
    x, y = np.eye(3)[0], np.eye(3)[1]
    v = x - (x @ h) * h
    if np.linalg.norm(v) < 1e-6:
        v = y - (y @ h) * h
    return v / np.linalg.norm(v)
