"""A disc rolling without slipping on a line (planar)."""

from __future__ import annotations

from typing import Any

import numpy as np

from mbd3d.model.body import Body
from mbd3d.model.builder import BuildContext
from mbd3d.model.element import PrimitiveSpec

from mbd3d.joints.base import perpendicular
from mbd3d.joints.gears import RackPinion


class RollingDisc(RackPinion):
    """A planar disc (body j) rolling without slipping on a straight track (body i, or the
    ground), touching it all the time.

    The track's line runs along ``axis`` at ``radius`` to the right of the disc's centre
    (looking along ``axis``; reverse it for a disc under a track). Two rows: the centre stays
    at ``radius`` from the line (``contact``: a dot-2 row, like a pin in a slot), and the disc
    turns by ``-s / radius`` relative to the track as its centre advances by ``s`` along it
    (``rolling``: the rack and pinion's row, :class:`mbd3d.model.primitives.Rack`). In space
    the rolling disc is nonholonomic, which mbd3d does not model yet.

    ``results.joint(name).contact_force`` is the normal force pressing disc and track
    together [N] and ``.traction`` the tangential force the track exerts on the disc along
    ``axis`` [N]: the friction that rolling needs, to compare with ``mu`` times the normal
    force.

    Parameters
    ----------
    name : str
    body_i : Body
        The track (may be the ground).
    body_j : Body
        The disc.
    radius : float
        The disc's rolling radius [m].
    axis : array_like
        Direction of the track in the drawing (global axes).
    center : array_like, optional
        The disc's centre in the drawing [m]; default its centre of mass.
    """

    kind = "rolling disc"

    def __init__(self, name: str, body_i: Body, body_j: Body, *, radius: float, axis: Any,
                 center: Any = None):
        super().__init__(name, body_i, body_j, radius=radius, axis=axis, center=center,
                         pressure_angle=0.0)

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        u_i, u_j, a_i, _ = self.geometry(ctx)
        rolling = super().primitives(ctx)[0]
        rolling.labels = ("rolling",)
        contact = PrimitiveSpec("dot2", self.body_i, self.body_j,
                                {"v_i": perpendicular(a_i), "u_i": u_i, "u_j": u_j},
                                ("contact",))
        return [contact, rolling]

    def reaction_frame(self, ctx: BuildContext):
        u_i, u_j, a_i, _ = self.geometry(ctx)
        return u_i, u_j, np.column_stack([a_i, perpendicular(a_i)])
