"""Joint stops: a joint coordinate kept in ``[lower, upper]`` by a contact law, evaluated with
the contacts (:mod:`mbd3d.model.contacts`) in the compiled core's one loop
(:mod:`mbd3d.numerics.compiled.joint_stops`)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.model.body import Body
from mbd3d.model.contact_laws import ContactLaw, pair_mass
from mbd3d.model.contact_rows import _Contacts
from mbd3d.model.forces import ForceElement, _CompiledForces
from mbd3d.numerics.checks import finite_scalar
from mbd3d.numerics.compiled import contact_table as kernel

if TYPE_CHECKING:
    from mbd3d.model.builder import BuildContext

__all__ = ["JointLimit"]


class JointLimit(ForceElement):
    """A stop at each end of a joint's travel: the joint coordinate stays in ``[lower,
    upper]`` up to the compliance of ``law``, which pushes it back when it passes an end.

    The coordinates are those results report for the joint (``results.joint(name).angle``,
    ``.displacement``):

    - ``"angle"`` of a revolute or a cylindrical joint [rad]: body j about the hinge (planar
      ``theta_j - theta_i``; spatial, in (-pi, pi], from body i's reference direction to body
      j's, each the body's x axis projected on the plane square to the hinge, or its y axis
      where x lies along the hinge: not zero in the drawing unless those coincide there, as
      ``results.joint(name).angle`` at the start shows);
    - ``"displacement"`` of a prismatic or a cylindrical joint [m]: body j's point along the
      axis;
    - ``"angle"``, ``"plane_position[0]"`` and ``"plane_position[1]"`` of a planar joint
      (spatial): the turn about its normal as a hinge's, and body j's point along either of
      the plane's two axes [m] (``results.joint(name).plane_position``);
    - ``"cone"`` of a spherical joint [rad]: the angle between ``axis`` as carried by body i
      and as carried by body j (0 in the drawing), kept below ``upper``, the cone's half
      angle: a ball joint's range of swing in every direction.

    Parameters
    ----------
    name : str
    joint : Revolute, Prismatic, Cylindrical, Planar or Spherical
        A joint of the model.
    lower, upper : float, optional
        The ends [rad or m] (either may be left out: no stop there; a cone has ``upper``
        only).
    law : ContactLaw
        As for :class:`~mbd3d.Contact`; a law calibrated to a restitution uses ``effective_mass``:
        default the pair's effective mass (a slide) or moment of inertia about the hinge
        (about the axes square to a cone's) [kg m^2], ``m_i m_j / (m_i + m_j)``, of the free
        bodies.
    coordinate : str, optional
        ``"angle"``, ``"displacement"``, ``"plane_position[0]"``, ``"plane_position[1]"`` or
        ``"cone"``; default the joint's only one (a cylindrical joint has two, a planar one
        three: name it, and stop the others with limits of their own).
    axis : array_like, optional
        The cone's axis, a direction of the drawing (global axes); a cone only.
    effective_mass : float, optional
        [kg or kg m^2].

    Examples
    --------
    >>> import mbd3d as mb
    >>> from mbd3d.joints import Revolute
    >>> b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    >>> arm = b.add_body("arm", mass=1.0, inertia=0.08, position=(0.5, 0.0))
    >>> pin = b.add(Revolute("pin", b.ground, arm, at=(0.0, 0.0)))
    >>> _ = b.add(mb.JointLimit("pin stop", pin, lower=-1.0, upper=1.0,
    ...                         law=mb.LinearContact(stiffness=1e4, restitution=0.5)))
    """

    group_key = "contacts"
    is_group, overlap_words = False, "the joint is past its limit by"

    def __init__(self, name: str, joint: Any, *, lower: float | None = None,
                 upper: float | None = None, law: ContactLaw, coordinate: str | None = None,
                 axis: Any = None, effective_mass: float | None = None):
        what = f"joint limit '{name}'"
        choices = getattr(joint, "limit_coordinates", None)
        if not choices or not hasattr(joint, "reaction_frame"):
            raise ModelError(f"{what}: give a Revolute, Prismatic, Cylindrical, Planar or "
                             f"Spherical joint, got {joint!r}")
        if coordinate is None and len(choices) > 1:
            raise ModelError(f"{what}: a {type(joint).__name__} joint has {len(choices)} "
                             f"coordinates; name the one stopped: coordinate= "
                             f"{' or '.join(repr(c) for c in choices)}")
        coordinate = choices[0] if coordinate is None else coordinate
        if coordinate not in choices:
            raise ModelError(f"{what}: a {type(joint).__name__} joint's coordinates are "
                             f"{', '.join(repr(c) for c in choices)}; got {coordinate!r}")
        if (coordinate == "cone") != (axis is not None):
            raise ModelError(f"{what}: " + ("a cone needs its axis= (a direction of the "
                                            "drawing)" if axis is None else
                                            "axis= is a cone's; a hinge or a slide has the "
                                            "joint's own"))
        if not isinstance(law, ContactLaw):
            raise ModelError(f"{what}: law must be a LinearContact, HertzContact, HuntCrossley, "
                             f"ImpactFunction or RigidImpact, got {law!r}")
        self.name, self.joint, self.law = name, joint, law
        self.lower, self.upper, self.effective_mass = lower, upper, effective_mass
        self.coordinate, self.axis = coordinate, axis
        self.body_i, self.body_j = joint.body_i, joint.body_j
        self.what = what
        self.units = ("rad", "N m") if coordinate in ("angle", "cone") else ("m", "N")

    def bodies(self) -> list[tuple[str, Body]]:
        return [("body_i", self.body_i), ("body_j", self.body_j)]

    @classmethod
    def compile(cls, elements: list, ctx: "BuildContext") -> "_CompiledForces":
        return _Contacts(elements, ctx)

    def outlines(self, ctx: "BuildContext") -> list:
        """None: a stop has no shapes to draw.

        Parameters
        ----------
        ctx : BuildContext
            The model being built (its drawing, and the checks that name what is wrong).
        """
        return []

    def arrays(self, ctx: "BuildContext") -> tuple:
        """``(points (1, 4, dim), values (1, 10), labels, swapped, effective mass, None)`` of
        the compiled core, checked (see :meth:`mbd3d.Contact.arrays`).

        Parameters
        ----------
        ctx : BuildContext
            The model being built (its drawing, and the checks that name what is wrong).
        """
        what = self.what
        lower, upper = self._ends(ctx)
        u_i, u_j, axes = self.joint.reaction_frame(ctx)
        points = np.zeros((kernel.POINTS, ctx.dim))
        if self.coordinate == "cone":
            kind = kernel.CONE_STOP
            direction = ctx.direction(self.axis, f"{what}: axis")
            points[:2] = (ctx.to_local_vector(self.body_i, direction),
                          ctx.to_local_vector(self.body_j, direction))
            spin = [ctx.rotation(self.body_i) @ v for v in _across(points[0])]
        elif self.coordinate == "angle":
            kind = kernel.HINGE_STOP
            spin = [np.array([0.0, 0.0, 1.0])]
            if ctx.dim == 3:
                points[:3] = self.joint.hinge_directions(ctx, what)
                spin = [ctx.rotation(self.body_i) @ np.cross(points[0], points[1])]
        else:  # a slide: along the axis, or one of a planar joint's in-plane axes
            kind, spin = kernel.SLIDE_STOP, None
            column = {"plane_position[0]": 1, "plane_position[1]": 2}.get(self.coordinate, 0)
            points[:3] = u_i, u_j, axes[:, column]
        mass = self._effective_mass(ctx, u_i, u_j, spin, what)
        K, n, D, p = self.law.constants(mass, math.inf, what)
        values = [kind, lower, upper, K, n, D, p, 0.0, 1.0, self.law.damping_ramp(what)]
        return points[None], np.array([values]), [""], False, mass, None

    def _ends(self, ctx) -> tuple[float, float]:
        what = self.what
        lower = -math.inf if self.lower is None else finite_scalar(self.lower, f"{what}: lower")
        upper = math.inf if self.upper is None else finite_scalar(self.upper, f"{what}: upper")
        if not lower < upper:
            raise ModelError(f"{what}: lower must be below upper, got {self.lower!r} and "
                             f"{self.upper!r}")
        if self.coordinate == "cone" and not (self.lower is None and 0.0 < upper < math.pi):
            raise ModelError(f"{what}: a cone has an upper end only, its half angle in (0, pi) "
                             f"[rad], got lower={self.lower!r}, upper={self.upper!r}")
        inside = ((-math.pi < lower or self.lower is None)
                  and (upper < math.pi or self.upper is None))
        if self.coordinate == "angle" and ctx.dim == 3 and not inside:
            raise ModelError(f"{what}: a spatial hinge's angle is measured in (-pi, pi]; "
                             f"give limits inside it, got {self.lower!r}, {self.upper!r}")
        return lower, upper

    def _effective_mass(self, ctx, u_i, u_j, spin, what) -> float:
        """The pair's mass along a slide (``spin`` None), or its mean moment of inertia
        about the global axes ``spin`` through the joint (a hinge's, a cone's two across)."""
        if self.effective_mass is not None:
            return finite_scalar(self.effective_mass, f"{what}: effective_mass", positive=True)
        if spin is None:
            return pair_mass([b.mass for b in (self.body_i, self.body_j) if not b.is_ground])
        return float(np.mean([pair_mass([_moment(ctx, body, u, h) for body, u in
                                          ((self.body_i, u_i), (self.body_j, u_j))
                                          if not body.is_ground]) for h in spin]))


def _across(a: np.ndarray) -> list[np.ndarray]:
    """Two unit vectors square to ``a`` (3,) and to each other."""
    e = np.eye(3)[int(np.argmin(np.abs(a)))]
    first = np.cross(a, e)
    first /= np.linalg.norm(first)
    return [first, np.cross(a / np.linalg.norm(a), first)]


def _moment(ctx, body, u, h) -> float:
    """Moment of inertia [kg m^2] of ``body`` about the global axis ``h`` (3D; planar: the
    normal) through its body point ``u``."""
    if ctx.dim == 2:
        return float(body.inertia) + body.mass * float(u @ u)
    axis = ctx.rotation(body).T @ h
    arm = u - (u @ axis) * axis
    return float(axis @ np.asarray(body.inertia) @ axis) + body.mass * float(arm @ arm)
