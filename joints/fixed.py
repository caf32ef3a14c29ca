"""Fixed joint (weld)."""

from __future__ import annotations

from mbd3d.element import PrimitiveSpec
from mbd3d.model import BuildContext

from joints.base import Joint, require_planar


class Fixed(Joint):
    """Welds body j to body i (or to the ground) as they are in the drawing.

    Planar form: point coincidence (rows ``x``, ``y``) and constant relative angle (row
    ``angle``), the angle taken from the bodies' initial guesses. Reaction on body j: force [N]
    and moment [N m] about the weld point (default body j's centre of mass).
    """

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        require_planar(ctx, self.name)
        u_i, u_j = self.points(ctx)
        angle = ctx.initial_coordinate(self.body_j, 2) - ctx.initial_coordinate(self.body_i, 2)
        return [PrimitiveSpec("point", self.body_i, self.body_j, {"u_i": u_i, "u_j": u_j},
                              ("x", "y")),
                PrimitiveSpec("angle", self.body_i, self.body_j, {}, ("angle",), c0=angle)]
