"""Contact groups: many spheres, capsules and boxes (planar: circles, stadiums and
rectangles), and the planes (lines) that bound them, of which every pair on two bodies may
touch, by one law.

A group is found pair by pair at each evaluation by a broad phase on a uniform grid
(:mod:`mbd3d.numerics.compiled.contact_grid`), so that its cost grows with the shapes and the
pairs near each other, not with all pairs; each pair near enough is then the contact
:class:`~mbd3d.Contact` would be between the two shapes (:mod:`mbd3d.numerics.compiled.contact_groups`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.model.body import Body
from mbd3d.model.contact_laws import ContactLaw, pair_mass
from mbd3d.model.contact_rows import _Contacts
from mbd3d.model.forces import ForceElement, _CompiledForces
from mbd3d.model.shapes import Box, Capsule, Plane, Sphere, outline, shape_core
from mbd3d.numerics.checks import finite_scalar
from mbd3d.numerics.compiled import contact_grid as grid
from mbd3d.numerics.compiled.contact_table import GROUP, POINTS

if TYPE_CHECKING:
    from mbd3d.model.builder import BuildContext

__all__ = ["ContactGroup"]

#: the most classes of shapes alike (radius, mass, plane or not) a group may have: their
#: pairs' laws are a table of classes^2 rows
MAX_CLASSES = 256


class ContactGroup(ForceElement):
    """Compliant contacts between every two of many shapes on different bodies: spheres,
    capsules and boxes (planar: circles, stadiums and rectangles) against each other and
    against planes (lines), by one law and one friction coefficient, as
    :class:`~mbd3d.Contact` would give each pair on its own (a box against a plane or a box
    at its corners); the pairs near each other are found at each evaluation, in a time that grows
    with the number of shapes (a uniform grid), not with the number of pairs.

    The group is one row of :func:`~mbd3d.contact_states` and of the results' contacts,
    named ``name``: the pair deepest in contact (its gap, an infinite one when no pair is
    near, its rate, normal force, friction, point and normal), and the potential energy and
    the dissipated power of all pairs. The integrators do not end steps at the group's
    touches and releases as they do at a :class:`~mbd3d.Contact`'s: an explicit method's
    error control sets its steps, and generalized-alpha's step must be short against an
    impact's duration (about ``T / 100``, ``T = 2 pi sqrt(m* / k)``).

    Parameters
    ----------
    name : str
    shapes : sequence of Sphere, Capsule, Box or Plane
        At least two, on at least two bodies; two planes never touch each other, nor do two
        shapes of one body.
    law : ContactLaw
        A compliant law (not :class:`~mbd3d.RigidImpact`); where it depends on the pair's
        effective mass and radius (a restitution, Hertz's stiffness from the material), each
        pair gets its own, from the free bodies' masses as for :class:`~mbd3d.Contact`.
    friction : float
        Coulomb coefficient ``mu`` >= 0.
    slip_velocity : float
        [m/s] > 0, below which friction falls off smoothly to zero.

    Examples
    --------
    >>> import mbd3d as mb
    >>> b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    >>> balls = [b.add_body(f"ball{k}", mass=1.0, inertia=0.004, position=(0.25 * k, 1.0))
    ...          for k in range(3)]
    >>> shapes = [mb.Sphere(ball, radius=0.1) for ball in balls]
    >>> shapes.append(mb.Plane(b.ground, normal=(0.0, 1.0)))
    >>> _ = b.add(mb.ContactGroup("pile", shapes,
    ...                           law=mb.HertzContact(stiffness=1e7, restitution=0.8)))
    """

    group_key = "contacts"
    is_group, overlap_words = True, "two of its shapes overlap by (the deepest pair)"

    def __init__(self, name: str, shapes: Any, *, law: ContactLaw, friction: float = 0.0,
                 slip_velocity: float = 1e-3):
        what = f"contact group '{name}'"
        shapes = list(shapes)
        for k, shape in enumerate(shapes):
            if not isinstance(shape, (Sphere, Capsule, Box, Plane)):
                raise ModelError(f"{what}: shape {k} is a {type(shape).__name__}; a group holds "
                                 "Spheres, Capsules, Boxes and Planes (add a Contact for a "
                                 "hole or a cam)")
        if len({id(s.body) for s in shapes}) < 2:
            raise ModelError(f"{what}: give shapes on at least two bodies, got {len(shapes)} "
                             "shape(s)")
        if not isinstance(law, ContactLaw) or law.rigid:
            raise ModelError(f"{what}: law must be a compliant law (LinearContact, "
                             f"HertzContact, HuntCrossley or ImpactFunction), got {law!r}")
        self.name, self.shapes, self.law = name, shapes, law
        self.friction, self.slip_velocity = friction, slip_velocity
        self.what, self.units = what, ("m", "N")

    def bodies(self) -> list[tuple[str, Body]]:
        return [(f"shape {k}", s.body) for k, s in enumerate(self.shapes)]

    @classmethod
    def compile(cls, elements: list, ctx: "BuildContext") -> "_CompiledForces":
        return _Contacts(elements, ctx)

    def arrays(self, ctx: "BuildContext") -> tuple:
        """As :meth:`mbd3d.Contact.arrays`, the group's one row: ``points[0, 3, :2]`` the
        first and the number of its shapes and ``points[0, 2, :2]`` the offset and number of
        classes of its law table, both from zero (:class:`~mbd3d.model.contact_rows._Contacts`
        moves them to the model's tables); the mass is the smallest pair's.

        Parameters
        ----------
        ctx : BuildContext
            The model being built (its drawing, and the checks that name what is wrong).
        """
        shape_points, shape_values, laws, masses = self.tables(ctx)
        points = np.zeros((1, POINTS, ctx.dim))
        points[0, 3, :2] = 0, len(self.shapes)
        points[0, 2, :2] = 0, math.isqrt(len(laws))
        values = laws[:1].copy()
        values[0, :3] = GROUP, 0.0, 0.0
        return points, values, [""], False, float(np.min(masses)), None

    def tables(self, ctx: "BuildContext") -> tuple:
        """``(points (s, 2, dim), values (s, 3), laws (c * c, 10), pair masses)`` of the
        shapes (see :mod:`mbd3d.numerics.compiled.contact_grid`) and of the classes' laws.

        Parameters
        ----------
        ctx : BuildContext
            The model being built (its drawing, and the checks that name what is wrong).
        """
        what = self.what
        mu = finite_scalar(self.friction, f"{what}: friction")
        slip = finite_scalar(self.slip_velocity, f"{what}: slip_velocity", positive=True)
        if mu < 0.0:
            raise ModelError(f"{what}: friction must be >= 0, got {self.friction!r}")
        points, values, classes = np.zeros((len(self.shapes), 2, ctx.dim)), [], {}
        for k, shape in enumerate(self.shapes):
            kind, radius, core = shape_core(ctx, shape, f"{what}: shape {k}")
            points[k, :len(core)] = core
            mass = math.inf if shape.body.is_ground else float(shape.body.mass)
            key = (kind, radius, mass)
            values.append((kind, radius, classes.setdefault(key, len(classes))))
        if len(classes) > MAX_CLASSES:
            raise ModelError(f"{what}: its shapes have {len(classes)} different radii and "
                             f"masses, more than {MAX_CLASSES}; split the group or round them")
        laws, masses = np.zeros((len(classes) ** 2, 10)), []
        ramp = self.law.damping_ramp(what)
        for (kind_a, r_a, m_a), a in classes.items():
            for (kind_b, r_b, m_b), b in classes.items():
                mass = pair_mass([m_a, m_b])
                radius = (r_a if kind_b == grid.PLANE else r_b if kind_a == grid.PLANE
                          else r_a * r_b / (r_a + r_b) if r_a + r_b > 0.0 else 0.0)
                K, n, D, p = ((0.0, 1.0, 0.0, 0.0) if kind_a == kind_b == grid.PLANE
                              or not math.isfinite(mass)
                              else self.law.constants(mass, radius, what))
                laws[a * len(classes) + b] = (0, 0, 0, K, n, D, p, mu, slip, ramp)
                if math.isfinite(mass):
                    masses.append(mass)
        return points, np.array(values, dtype=float), laws, np.array(masses or [math.inf])

    def outlines(self, ctx: "BuildContext") -> list:
        """The group's shapes as the viewer draws them, one outline per shape.

        Parameters
        ----------
        ctx : BuildContext
            The model being built (its drawing, and the checks that name what is wrong).
        """
        return [outline(ctx, shape, f"{self.what}: shape {k}")
                for k, shape in enumerate(self.shapes)]

