"""Fixed joint (weld)."""

from __future__ import annotations

import numpy as np

from mbd3d.model.element import PrimitiveSpec
from mbd3d.model.builder import BuildContext

from mbd3d.joints.base import Axes, Joint, perpendicular_rows, point_parameters


@point_parameters
class Fixed(Joint):
    """Welds body j to body i (or to the ground) as they are in the drawing.

    Planar form: point coincidence (rows ``x``, ``y``) and constant relative angle (row
    ``angle``). Spatial form: point coincidence and three dot-1 rows locking the relative
    orientation (``axis_f``, ``axis_g``, ``twist``). The relative orientation is that of the
    bodies' initial guesses. Reaction on body j: force [N] and moment [N m] about the weld point
    (default body j's centre of mass).

    Parameters
    ----------
    {point_parameters}
    """

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        u_i, u_j = self.points(ctx)
        bi, bj = self.body_i, self.body_j
        point = PrimitiveSpec("point", bi, bj, {"u_i": u_i, "u_j": u_j}, ("x", "y", "z")[:ctx.dim])
        if ctx.dim == 2:
            angle = ctx.initial_coordinate(bj, 2) - ctx.initial_coordinate(bi, 2)
            return [point, PrimitiveSpec("angle", bi, bj, {}, ("angle",), c0=angle)]
        axes = Axes(ctx, self, np.array([0.0, 0.0, 1.0]))
        return [point, *perpendicular_rows(self, axes),
                PrimitiveSpec("dot1", bi, bj, {"v_i": axes.i[0], "v_j": axes.j[1]}, ("twist",))]
