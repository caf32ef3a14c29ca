"""Distance constraint: a massless rigid link between two body points."""

from __future__ import annotations

from typing import Any

import numpy as np

from mbd3d.model.body import Body
from mbd3d.model.element import PrimitiveSpec
from mbd3d.errors import ModelError
from mbd3d.model.forces import resolve_point
from mbd3d.model.builder import BuildContext

from mbd3d.joints.base import Joint


class Distance(Joint):
    """Keeps point P_i of body i and point P_j of body j at a fixed distance (a massless link).

    ``|r_Pj - r_Pi| - length = 0`` (row ``length``). Its multiplier is the compressive force in
    the link [N]; ``results.joint(name).reaction()`` gives the force on body j.

    Parameters
    ----------
    name : str
    body_i, body_j : Body
    point_i, point_j : (dim,) array_like, optional
        Link ends in the body frames [m]; default the centres of mass.
    at_i, at_j : (dim,) array_like, optional
        Link ends in global coordinates of the drawing [m], instead of ``point_i``,
        ``point_j``.
    length : float, optional
        [m], positive; default the distance of the two points in the drawing.
    """

    def __init__(self, name: str, body_i: Body, body_j: Body, *, point_i: Any = None,
                 point_j: Any = None, at_i: Any = None, at_j: Any = None,
                 length: float | None = None):
        super().__init__(name, body_i, body_j)
        self.link_points = (point_i, point_j, at_i, at_j)
        self.length = length

    def points(self, ctx: BuildContext) -> tuple[np.ndarray, np.ndarray]:
        point_i, point_j, at_i, at_j = self.link_points
        what = f"joint '{self.name}'"
        return (resolve_point(ctx, self.body_i, point_i, at_i, f"{what}: point_i"),
                resolve_point(ctx, self.body_j, point_j, at_j, f"{what}: point_j"))

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        u_i, u_j = self.points(ctx)
        if self.length is None:
            length = float(np.linalg.norm(ctx.to_global_point(self.body_j, u_j)
                                          - ctx.to_global_point(self.body_i, u_i)))
        else:
            length = ctx.scalar(self.length, f"joint '{self.name}': length")
        if not length > 1e-12:
            raise ModelError(f"joint '{self.name}': the link length must be positive, got {length} "
                             "(for coincident points use a Revolute)")
        return [PrimitiveSpec("distance", self.body_i, self.body_j, {"u_i": u_i, "u_j": u_j},
                              ("length",), c0=length)]
