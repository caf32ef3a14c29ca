"""Joints of spatial models: spherical, universal, cylindrical, planar, point-on-line (also the
planar pin in a slot), point-on-plane. Each is a composition of the same primitives as the
planar joints."""

from __future__ import annotations

from typing import Any

import numpy as np

from mbd3d.model.body import Body
from mbd3d.model.element import PrimitiveSpec
from mbd3d.errors import ModelError
from mbd3d.model.builder import BuildContext

from mbd3d.joints.base import (Axes, Joint, perpendicular, perpendicular_rows, point_parameters,
                               require_spatial)
from mbd3d.joints.revolute import hinge_directions


@point_parameters
class Spherical(Joint):
    """Ball joint: a point of body i and a point of body j coincide (rows ``x``, ``y``, ``z``).

    Reaction on body j: the force [N]; no moment about the ball. A
    :class:`~mbd3d.JointLimit` stops it at a cone (``coordinate="cone"``).

    Parameters
    ----------
    {point_parameters}
    """

    #: the coordinates a :class:`~mbd3d.JointLimit` may stop
    limit_coordinates = ("cone",)

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        require_spatial(ctx, self.name)
        u_i, u_j = self.points(ctx)
        return [PrimitiveSpec("point", self.body_i, self.body_j, {"u_i": u_i, "u_j": u_j},
                              ("x", "y", "z"))]


@point_parameters
class Universal(Joint):
    """Cardan joint: coincident points, and the cross's two axes ``axis_i`` (fixed in body i)
    and ``axis_j`` (fixed in body j) kept perpendicular (rows ``x``, ``y``, ``z``, ``cross``).

    ``axis_i`` and ``axis_j`` are directions of the drawing and must be perpendicular there.

    Parameters
    ----------
    {point_parameters}
    axis_i, axis_j : (3,) array_like
        The cross's axis fixed in body i and the one fixed in body j, in the drawing (global
        axes).
    """

    def __init__(self, name: str, body_i: Body, body_j: Body, *, axis_i: Any, axis_j: Any,
                 at: Any = None, point_i: Any = None, point_j: Any = None):
        super().__init__(name, body_i, body_j, at=at, point_i=point_i, point_j=point_j)
        self.axis_i, self.axis_j = axis_i, axis_j

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        require_spatial(ctx, self.name)
        u_i, u_j = self.points(ctx)
        a_i = ctx.direction(self.axis_i, f"joint '{self.name}': axis_i")
        a_j = ctx.direction(self.axis_j, f"joint '{self.name}': axis_j")
        if abs(a_i @ a_j) > 1e-9:
            raise ModelError(f"joint '{self.name}': axis_i and axis_j must be perpendicular in "
                             f"the drawing (cosine {a_i @ a_j:.3g})")
        return [PrimitiveSpec("point", self.body_i, self.body_j, {"u_i": u_i, "u_j": u_j},
                              ("x", "y", "z")),
                PrimitiveSpec("dot1", self.body_i, self.body_j,
                              {"v_i": ctx.to_local_vector(self.body_i, a_i),
                               "v_j": ctx.to_local_vector(self.body_j, a_j)}, ("cross",))]


class _AxisJoint(Joint):
    def __init__(self, name: str, body_i: Body, body_j: Body, *, axis: Any, at: Any = None,
                 point_i: Any = None, point_j: Any = None):
        super().__init__(name, body_i, body_j, at=at, point_i=point_i, point_j=point_j)
        self.axis = axis

    def reaction_frame(self, ctx: BuildContext):
        u_i, u_j = self.points(ctx)
        return u_i, u_j, Axes(ctx, self, self.axis).reaction_axes(along_x=True)


class _Hinge(_AxisJoint):
    """An axis joint that turns about its axis, from the angle ``drawn_angle`` [rad] it reads
    in the drawing (see :class:`~mbd3d.joints.Revolute`)."""

    def __init__(self, name: str, body_i: Body, body_j: Body, *, axis: Any, at: Any = None,
                 point_i: Any = None, point_j: Any = None, drawn_angle: float | None = None):
        super().__init__(name, body_i, body_j, axis=axis, at=at, point_i=point_i,
                         point_j=point_j)
        self.drawn_angle = drawn_angle

    def hinge_directions(self, ctx: BuildContext, what: str
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return hinge_directions(ctx, self)


@point_parameters
class Cylindrical(_Hinge):
    """Body j slides along and turns about an axis of body i: axes aligned (``axis_f``,
    ``axis_g``) and the point of j on the line (``normal_f``, ``normal_g``); 4 rows.


    Parameters
    ----------
    {point_parameters}
    axis : (3,) array_like
        The axis it slides along and turns about, in the drawing (global axes).
    drawn_angle : float, optional
        The angle it reads in the drawing [rad] (see :class:`~mbd3d.joints.Revolute`).
    """

    #: the coordinates a :class:`~mbd3d.JointLimit` may stop
    limit_coordinates = ("angle", "displacement")

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        require_spatial(ctx, self.name)
        u_i, u_j = self.points(ctx)
        axes = Axes(ctx, self, self.axis)
        f, g, _ = axes.i
        bi, bj = self.body_i, self.body_j
        return [*perpendicular_rows(self, axes),
                PrimitiveSpec("dot2", bi, bj, {"v_i": f, "u_i": u_i, "u_j": u_j}, ("normal_f",)),
                PrimitiveSpec("dot2", bi, bj, {"v_i": g, "u_i": u_i, "u_j": u_j}, ("normal_g",))]


@point_parameters
class Planar(_Hinge):
    """Body j slides on a plane of body i and turns about its normal ``axis``: normals aligned
    (``axis_f``, ``axis_g``) and the point of j in the plane (``plane``); 3 rows.


    Parameters
    ----------
    {point_parameters}
    axis : (3,) array_like
        The plane's normal, which it turns about, in the drawing (global axes).
    drawn_angle : float, optional
        The angle it reads in the drawing [rad] (see :class:`~mbd3d.joints.Revolute`).
    """

    #: the coordinates a :class:`~mbd3d.JointLimit` may stop: the turn about the normal and
    #: the two components of ``results.joint(name).plane_position``
    limit_coordinates = ("angle", "plane_position[0]", "plane_position[1]")

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        require_spatial(ctx, self.name)
        u_i, u_j = self.points(ctx)
        axes = Axes(ctx, self, self.axis)
        return [*perpendicular_rows(self, axes),
                PrimitiveSpec("dot2", self.body_i, self.body_j,
                              {"v_i": axes.i[2], "u_i": u_i, "u_j": u_j}, ("plane",))]


@point_parameters
class PointOnLine(_AxisJoint):
    """The point of body j stays on the line of body i through its point along ``axis``;
    rotations are free. Spatial: rows ``normal_f``, ``normal_g`` (2 rows). Planar: the pin in a
    slot, row ``normal`` (1 row; body j also slides along and turns freely).

    Reaction on body j: force [N] normal to the line, in joint axes (x along the line).

    Parameters
    ----------
    {point_parameters}
    axis : array_like
        The line's direction in the drawing (global axes).
    """

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        u_i, u_j = self.points(ctx)
        if ctx.dim == 2:
            h_i = ctx.to_local_vector(self.body_i,
                                      ctx.direction(self.axis, f"joint '{self.name}': axis"))
            return [PrimitiveSpec("dot2", self.body_i, self.body_j,
                                  {"v_i": perpendicular(h_i), "u_i": u_i, "u_j": u_j},
                                  ("normal",))]
        f, g, _ = Axes(ctx, self, self.axis).i
        return [PrimitiveSpec("dot2", self.body_i, self.body_j, {"v_i": v, "u_i": u_i, "u_j": u_j},
                              (label,)) for v, label in ((f, "normal_f"), (g, "normal_g"))]

    def reaction_frame(self, ctx: BuildContext):
        if ctx.dim == 3:
            return super().reaction_frame(ctx)
        u_i, u_j = self.points(ctx)
        h_i = ctx.to_local_vector(self.body_i, ctx.direction(self.axis, f"joint '{self.name}': axis"))
        return u_i, u_j, np.column_stack([h_i, perpendicular(h_i)])


@point_parameters
class PointOnPlane(_AxisJoint):
    """The point of body j stays in the plane of body i through its point with normal ``axis``
    (row ``plane``); everything else is free. 1 row.

    Parameters
    ----------
    {point_parameters}
    axis : (3,) array_like
        The plane's normal, in the drawing (global axes).
    """

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        require_spatial(ctx, self.name)
        u_i, u_j = self.points(ctx)
        h = Axes(ctx, self, self.axis).i[2]
        return [PrimitiveSpec("dot2", self.body_i, self.body_j, {"v_i": h, "u_i": u_i, "u_j": u_j},
                              ("plane",))]


__all__ = ["Spherical", "Universal", "Cylindrical", "Planar", "PointOnLine", "PointOnPlane"]

