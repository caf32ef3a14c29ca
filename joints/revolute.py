"""Revolute joint (pin)."""

from __future__ import annotations

from mbd3d.element import PrimitiveSpec
from mbd3d.model import BuildContext

from joints.base import Joint, require_planar


class Revolute(Joint):
    """A pin: a point of body i and a point of body j coincide; relative rotation is free.

    Planar form: ``r_i + A_i u_i - r_j - A_j u_j = 0`` (2 equations; the original program's
    eqs. 4-6, Nikravesh's revolute). Rows ``x``, ``y``.

    Reaction on body j (``results.joint(name).reaction()``): the pin force [N]; the moment about
    the pin is zero.

    Parameters
    ----------
    name : str
    body_i, body_j : Body
        The connected bodies (either may be ``builder.ground``).
    at : (2,) array_like, optional
        The pin in global coordinates of the drawing [m].
    point_i, point_j : (2,) array_like, optional
        The pin in the frames of body i and body j [m] (see :class:`joints.base.Joint`).

    Examples
    --------
    >>> import mbd3d as mb
    >>> from joints import Revolute
    >>> b = mb.ModelBuilder(dim=2)
    >>> crank = b.add_body("crank", mass=1.0, inertia=0.01, position=(0.05, 0.0))
    >>> pin = b.add(Revolute("O", b.ground, crank, at=(0.0, 0.0)))
    """

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        require_planar(ctx, self.name)
        u_i, u_j = self.points(ctx)
        return [PrimitiveSpec("point", self.body_i, self.body_j, {"u_i": u_i, "u_j": u_j},
                              ("x", "y"))]
