"""Shared machinery of the joints: bodies, attachment points, axes."""

from __future__ import annotations

from typing import Any

import numpy as np

from mbd3d.body import Body
from mbd3d.element import ConstraintElement
from mbd3d.errors import ModelError
from mbd3d.model import BuildContext


def perpendicular(v: np.ndarray) -> np.ndarray:
    """A 2D vector turned by +90 degrees."""
    return np.array([-v[1], v[0]])


class Joint(ConstraintElement):
    """A constraint between two bodies at a point.

    The point can be given once, in global coordinates of the drawing (``at``; converted to the
    body frames with the bodies' initial guesses, so the guesses must be the assembled drawing),
    or in each body's frame (``point_i``, ``point_j``; the way to go when the guesses are rough).
    When only one of ``point_i``, ``point_j`` is given the other is the same point of the drawing.
    With none, the point is body j's centre of mass in the drawing.
    """

    def __init__(self, name: str, body_i: Body, body_j: Body, *, at: Any = None,
                 point_i: Any = None, point_j: Any = None):
        self.name = name
        self.body_i = body_i
        self.body_j = body_j
        self.at = at
        self.point_i = point_i
        self.point_j = point_j

    def points(self, ctx: BuildContext) -> tuple[np.ndarray, np.ndarray]:
        """Attachment points ``(u_i, u_j)`` in the frames of body i and body j [m]."""
        what = f"joint '{self.name}'"
        if self.at is not None:
            if self.point_i is not None or self.point_j is not None:
                raise ModelError(f"{what}: give either at= (drawing) or point_i/point_j "
                                 "(body frames), not both")
            p = ctx.vector(self.at, f"{what}: at")
            return ctx.to_local_point(self.body_i, p), ctx.to_local_point(self.body_j, p)
        if self.point_i is not None and self.point_j is not None:
            return (ctx.vector(self.point_i, f"{what}: point_i"),
                    ctx.vector(self.point_j, f"{what}: point_j"))
        if self.point_i is not None:
            u_i = ctx.vector(self.point_i, f"{what}: point_i")
            return u_i, ctx.to_local_point(self.body_j, ctx.to_global_point(self.body_i, u_i))
        if self.point_j is not None:
            u_j = ctx.vector(self.point_j, f"{what}: point_j")
            return ctx.to_local_point(self.body_i, ctx.to_global_point(self.body_j, u_j)), u_j
        u_j = np.zeros(ctx.dim)
        return ctx.to_local_point(self.body_i, ctx.to_global_point(self.body_j, u_j)), u_j

    def reaction_frame(self, ctx: BuildContext):
        u_i, u_j = self.points(ctx)
        return u_i, u_j, np.eye(ctx.dim)


def require_planar(ctx: BuildContext, element: str) -> None:
    if ctx.dim != 2:
        raise ModelError(f"'{element}': this joint is available for planar models only (dim=2)")
