"""Shared machinery of the joints: bodies, attachment points, axes."""

from __future__ import annotations

from typing import Any

import numpy as np

from mbd3d.model.body import Body
from mbd3d.model.element import ConstraintElement
from mbd3d.errors import ModelError
from mbd3d.model.builder import BuildContext
from mbd3d.model.element import PrimitiveSpec


#: the arguments of a joint at a point, as its docstring's Parameters section gives them:
#: :func:`point_parameters` puts them where the docstring says ``{point_parameters}``
POINT_PARAMETERS = """name : str
    The joint's name (``results.joint(name)``).
body_i, body_j : Body
    The connected bodies (either may be ``builder.ground``).
at : array_like, optional
    The joint's point in global coordinates of the drawing [m].
point_i, point_j : array_like, optional
    The point in the frames of body i and body j [m] (see :class:`mbd3d.joints.base.Joint`;
    default body j's centre of mass)."""


def point_parameters(cls: type) -> type:
    """Class decorator: the line ``{point_parameters}`` of the class's docstring becomes
    :data:`POINT_PARAMETERS`, at that line's indentation (one text for every joint's).

    Parameters
    ----------
    cls : type
        A joint class.
    """
    if cls.__doc__ is None:  # python -OO: no docstrings
        return cls
    lines = []
    for line in cls.__doc__.split("\n"):
        if line.strip() != "{point_parameters}":
            lines.append(line)
            continue
        indent = line[:len(line) - len(line.lstrip())]
        lines += [indent + part if part else part for part in POINT_PARAMETERS.split("\n")]
    cls.__doc__ = "\n".join(lines)
    return cls


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


#: how much more aligned with a joint's axis than the least aligned global axis another may be
#: and still be taken as the start of its triad (a fraction of the unit axis)
_TIE = 0.01


def triad(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit vectors ``(f, g, h)``, right-handed and orthonormal, with ``h`` along ``axis``."""
    h = axis / np.linalg.norm(axis)
    # start from a global axis little aligned with h: well conditioned for any h. Among those
    # within _TIE of the least aligned, the first: an axis drawn along a global one has two
    # least aligned (zero components), and a choice that jumped between them as the axis
    # changes a little would turn f and g by a right angle (sensitivities difference it)
    size = np.abs(h)
    e = np.eye(3)[int(np.flatnonzero(size <= size.min() + _TIE)[0])]
    f = np.cross(e, h)
    f /= np.linalg.norm(f)
    return f, np.cross(h, f), h


class Axes:
    """A joint's triad ``(f, g, h)`` of the drawing in the frames of bodies i and j."""

    def __init__(self, ctx: BuildContext, joint: ConstraintElement, axis: Any):
        if axis is None:
            raise ModelError(f"joint '{joint.name}': a spatial {type(joint).__name__} needs its "
                             "axis= (a direction of the drawing, global axes)")
        f, g, h = triad(ctx.direction(axis, f"joint '{joint.name}': axis"))
        self.i = [ctx.to_local_vector(joint.body_i, v) for v in (f, g, h)]
        self.j = [ctx.to_local_vector(joint.body_j, v) for v in (f, g, h)]

    def reaction_axes(self, along_x: bool) -> np.ndarray:
        """Joint axes as columns in body i's frame: the axis as z (revolute-like) or x."""
        f, g, h = self.i
        return np.column_stack([h, f, g] if along_x else [f, g, h])


def require_spatial(ctx: BuildContext, element: str) -> None:
    if ctx.dim != 3:
        raise ModelError(f"'{element}': this joint is available for spatial models only (dim=3)")


def perpendicular_rows(joint: ConstraintElement, axes: Axes) -> list[PrimitiveSpec]:
    """Two dot-1 rows keeping body j's copy of the axis h perpendicular to f and g of body i:
    the axes stay aligned (Haug's revolute/cylindrical pair)."""
    f, g, _ = axes.i
    h_j = axes.j[2]
    return [PrimitiveSpec("dot1", joint.body_i, joint.body_j, {"v_i": f, "v_j": h_j}, ("axis_f",)),
            PrimitiveSpec("dot1", joint.body_i, joint.body_j, {"v_i": g, "v_j": h_j}, ("axis_g",))]
