"""Drivers: constraints that prescribe a coordinate or a relative motion as a function of time.

Each driver is one constraint row ``c(q) - f(t) = 0``. Its **effort**
(``results.driver(name).effort``) is the generalized force the actuator applies in the direction
of increasing ``c``: a torque [N m] for a rotation driver, a force [N] for a translation driver.
"""

from __future__ import annotations

import numpy as np

from mbd3d.model.body import Body
from mbd3d.model.element import ConstraintElement, PrimitiveSpec
from mbd3d.errors import ModelError
from mbd3d.model.builder import BuildContext
from mbd3d.model.motion import Constant, Motion, as_motion
from mbd3d.numerics.checks import finite_scalar

from mbd3d.joints.prismatic import Prismatic
from mbd3d.joints.revolute import Revolute


class CoordinateDriver(ConstraintElement):
    """Prescribes one absolute coordinate of a body: ``q[coordinate] = f(t)``.

    Parameters
    ----------
    name : str
    body : Body
    coordinate : str or int
        Which coordinate: planar "x", "y" [m] or "theta" [rad]; spatial "x", "y", "z" [m].
    motion : Motion or float
        ``f(t)``; a number is a constant.
    """

    is_driver = True

    def __init__(self, name: str, body: Body, coordinate: str | int, motion: Motion | float):
        self.name = name
        self.body_i = None  # the ground, filled in when the model is built
        self.body_j = body
        self.coordinate = coordinate
        self.motion = as_motion(motion, f"driver '{name}': motion")

    @property
    def effort_unit(self) -> str:
        """Unit of the effort: a torque [N m] on an angle, a force [N] on a position."""
        return "N m" if self.coordinate in ("theta", 2) else "N"

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        names = ctx.body_type.coordinate_names
        c = self.coordinate
        if isinstance(c, str):
            if c not in names:
                raise ModelError(f"driver '{self.name}': coordinate must be one of {names}, "
                                 f"got {c!r}")
            index, label = names.index(c), c
        elif isinstance(c, (int, np.integer)) and 0 <= c < len(names):
            index, label = int(c), names[int(c)]
        else:
            raise ModelError(f"driver '{self.name}': coordinate must be one of {names} or an "
                             f"index 0..{len(names) - 1}, got {c!r}")
        if self.body_j.is_ground:
            raise ModelError(f"driver '{self.name}': the ground has no coordinates to drive")
        if ctx.dim == 3 and index >= 3:
            raise ModelError(f"driver '{self.name}': the orientation coordinates {names[3:]} are "
                             "relative to a chart that moves during a run; drive rotations with "
                             "RotationDriver across a Revolute")
        return [PrimitiveSpec("coordinate", self.body_i, self.body_j, {"coordinate": index},
                              (label,), motion=self.motion)]


class RotationDriver(ConstraintElement):
    """Prescribes the rotation of body j relative to body i: ``theta_j - theta_i = f(t)``.

    The angle is measured from body i's x axis to body j's x axis, counter-clockwise [rad]; for a
    crank driven from the ground it is the crank's absolute angle. In space the rotation is about
    the revolute's axis and the x axes are projected on the plane normal to it (a body whose x
    axis lies along the hinge uses its y axis); any number of turns is allowed. The effort is the
    motor torque on body j about the axis [N m] (the reaction torque on body i is opposite).

    Parameters
    ----------
    name : str
    joint : Revolute or Body
        The revolute across which the rotation is driven (its bodies are used), or body i (2D).
    body_j : Body, optional
        Body j, when ``joint`` is body i.
    motion : Motion or float
        ``f(t)`` [rad].
    offset : float
        The angle at which the driven coordinate is zero [rad]: the angle is ``offset + f(t)``
        (a URDF joint's coordinate, whose zero is where the URDF draws it).
    """

    is_driver = True
    #: the effort is the torque about the hinge
    effort_unit = "N m"

    def __init__(self, name: str, joint: Revolute | Body, body_j: Body | None = None, *,
                 motion: Motion | float, offset: float = 0.0):
        self.name = name
        self.joint = joint if isinstance(joint, Revolute) else None
        if self.joint is not None:
            if body_j is not None:
                raise ModelError(f"driver '{name}': give a Revolute or two bodies, not both")
            self.body_i, self.body_j = joint.body_i, joint.body_j
        else:
            if body_j is None:
                raise ModelError(f"driver '{name}': give the Revolute to drive, or body_i and "
                                 "body_j")
            self.body_i, self.body_j = joint, body_j
        self.motion = as_motion(motion, f"driver '{name}': motion")
        self.offset = finite_scalar(offset, f"driver '{name}': offset")

    def driven_motion(self) -> Motion:
        """What the row prescribes: ``f(t)`` plus the offset."""
        return self.motion + Constant(self.offset) if self.offset else self.motion

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        if ctx.dim == 2:
            return [PrimitiveSpec("angle", self.body_i, self.body_j, {}, ("angle",),
                                  motion=self.driven_motion())]
        if self.joint is None:
            raise ModelError(f"driver '{self.name}': in space, give the Revolute whose rotation "
                             "is driven (its axis defines the angle)")
        f_i, g_i, f_j = self.joint.hinge_directions(ctx, f"driver '{self.name}'")
        return [PrimitiveSpec("rotation", self.body_i, self.body_j,
                              {"f_i": f_i, "g_i": g_i, "f_j": f_j}, ("angle",),
                              motion=self.driven_motion())]

    def reaction_frame(self, ctx: BuildContext):
        if self.joint is not None:
            return self.joint.reaction_frame(ctx)
        return super().reaction_frame(ctx)


class TranslationDriver(ConstraintElement):
    """Prescribes the sliding of a prismatic joint: ``dot(h_i, r_Pj - r_Pi) = f(t)`` [m].

    ``f`` is the position [m] of the prismatic's point on body j along the axis, measured from its
    point on body i (zero in the drawing when the joint was given with ``at``), less ``offset``
    [m] (the position at which the driven coordinate is zero: a URDF joint's). The effort is
    the force on body j along the axis [N].

    Parameters
    ----------
    name : str
        The driver's name (``results.driver(name)``).
    joint : Prismatic
        The slider whose travel is driven (its bodies, points and axis are used).
    motion : Motion or float
        ``f(t)`` [m].
    offset : float
        The travel at which the driven coordinate is zero [m]: the travel is ``offset +
        f(t)``.
    """

    is_driver = True
    #: the effort is the force along the slider
    effort_unit = "N"

    def __init__(self, name: str, joint: Prismatic, *, motion: Motion | float,
                 offset: float = 0.0):
        if not isinstance(joint, Prismatic):
            raise ModelError(f"driver '{name}': joint must be a Prismatic, got {joint!r}")
        self.name = name
        self.joint = joint
        self.body_i, self.body_j = joint.body_i, joint.body_j
        self.motion = as_motion(motion, f"driver '{name}': motion")
        self.offset = finite_scalar(offset, f"driver '{name}': offset")

    def driven_motion(self) -> Motion:
        """What the row prescribes: ``f(t)`` plus the offset."""
        return self.motion + Constant(self.offset) if self.offset else self.motion

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        u_i, u_j, h_i, _ = self.joint.geometry(ctx)
        return [PrimitiveSpec("dot2", self.body_i, self.body_j,
                              {"v_i": h_i, "u_i": u_i, "u_j": u_j}, ("translation",),
                              motion=self.driven_motion())]

    def reaction_frame(self, ctx: BuildContext):
        return self.joint.reaction_frame(ctx)
