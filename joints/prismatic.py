"""Prismatic joint (slider)."""

from __future__ import annotations

from typing import Any

import numpy as np

from mbd3d.model.body import Body
from mbd3d.model.element import PrimitiveSpec
from mbd3d.model.builder import BuildContext

from mbd3d.joints.base import Axes, Joint, perpendicular, perpendicular_rows


class Prismatic(Joint):
    """A slider: body j translates along an axis of body i, without relative rotation.

    Planar form (Haug's and Nikravesh's translational joint): the relative angle stays that of
    the drawing, ``theta_j - theta_i = theta_j0 - theta_i0`` (row ``rotation``: linear in q, so
    its Jacobian row is constant and it adds nothing to ``Qd``), and with ``n`` the normal of the
    axis on body i, ``n_i . (r_Pj - r_Pi) = 0`` (row ``normal``: point P of body j stays on the
    line of body i). Spatial form: the axes stay aligned (``axis_f``,
    ``axis_g``), P stays on the line (``normal_f``, ``normal_g``, dot-2) and body j does not turn
    about the axis (``twist``): 5 rows.

    Reaction on body j: force [N] and moment [N m] about its point P; in joint axes the first
    component is along the sliding axis.

    Parameters
    ----------
    name : str
    body_i, body_j : Body
    axis : array_like
        Direction of sliding in the drawing (global axes).
    at, point_i, point_j : optional
        A point on the sliding line (see :class:`joints.base.Joint`); default body j's centre of
        mass.
    drawn_displacement : float, optional
        The displacement it reads in the drawing [m] (``results.joint(name).displacement``,
        what a TranslationDriver and a JointLimit take): body i's point is taken that far back
        along the axis. Default zero, the points' own separation along it. Robot files'
        importers give it their joint coordinate, so that it reads as the file's.
    """

    friction_kind = "prismatic"
    #: the coordinates a :class:`~mbd3d.JointLimit` may stop
    limit_coordinates = ("displacement",)

    def __init__(self, name: str, body_i: Body, body_j: Body, *, axis: Any, at: Any = None,
                 point_i: Any = None, point_j: Any = None,
                 drawn_displacement: float | None = None):
        super().__init__(name, body_i, body_j, at=at, point_i=point_i, point_j=point_j)
        self.axis = axis
        self.drawn_displacement = drawn_displacement

    def geometry(self, ctx: BuildContext) -> tuple[np.ndarray, ...]:
        """``(u_i, u_j, h_i, h_j)``: points and unit axis in the frames of bodies i and j.

        Parameters
        ----------
        ctx : BuildContext
            The model being built (its drawing, and the checks that name what is wrong).
        """
        u_i, u_j = self.points(ctx)
        h = ctx.direction(self.axis, f"joint '{self.name}': axis")
        h_i = ctx.to_local_vector(self.body_i, h)
        if self.drawn_displacement is not None:
            # along the axis: the rows across it do not see it, the displacement does
            u_i = u_i - ctx.scalar(self.drawn_displacement,
                                   f"joint '{self.name}': drawn_displacement") * h_i
        return u_i, u_j, h_i, ctx.to_local_vector(self.body_j, h)

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        u_i, u_j, h_i, h_j = self.geometry(ctx)
        bi, bj = self.body_i, self.body_j
        if ctx.dim == 2:
            angle = ctx.initial_coordinate(bj, 2) - ctx.initial_coordinate(bi, 2)
            return [PrimitiveSpec("angle", bi, bj, {}, ("rotation",), c0=angle),
                    PrimitiveSpec("dot2", bi, bj, {"v_i": perpendicular(h_i), "u_i": u_i,
                                                   "u_j": u_j}, ("normal",))]
        axes = Axes(ctx, self, self.axis)
        f, g, _ = axes.i
        return [*perpendicular_rows(self, axes),
                PrimitiveSpec("dot2", bi, bj, {"v_i": f, "u_i": u_i, "u_j": u_j}, ("normal_f",)),
                PrimitiveSpec("dot2", bi, bj, {"v_i": g, "u_i": u_i, "u_j": u_j}, ("normal_g",)),
                PrimitiveSpec("dot1", bi, bj, {"v_i": f, "v_j": axes.j[1]}, ("twist",))]

    def reaction_frame(self, ctx: BuildContext):
        u_i, u_j, h_i, _ = self.geometry(ctx)
        if ctx.dim == 2:
            return u_i, u_j, np.column_stack([h_i, perpendicular(h_i)])
        return u_i, u_j, Axes(ctx, self, self.axis).reaction_axes(along_x=True)
