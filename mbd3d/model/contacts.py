"""Contacts between shapes attached to bodies (:mod:`mbd3d.model.shapes`: spheres, capsules,
boxes, planes and holes; circles, stadiums, rectangles, lines, holes and disc cams in the
plane), pushed apart by a normal force law (:mod:`mbd3d.model.contact_laws`) and dragged by
regularised Coulomb friction; and joint stops, by the same laws.

A contact is a force element: it acts only while the shapes overlap, and the compiled core
evaluates all contacts of a model in one loop (:mod:`mbd3d.numerics.compiled.contacts`), in
the planar and the spatial model alike. :func:`contact_states` reports each contact's gap,
forces, point and normal at a state.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from mbd3d.errors import ContactWarning, ModelError, user_stacklevel
from mbd3d.model.body import Body
from mbd3d.model.contact_laws import ContactLaw
from mbd3d.model.forces import ForceElement, _CompiledForces
from mbd3d.model.shapes import (Box, Cam, Capsule, Hole, Plane, Sphere, outline, pair_order,
                                pair_rows)
from mbd3d.numerics.checks import finite_scalar
from mbd3d.numerics.compiled import contacts as kernel

if TYPE_CHECKING:
    from mbd3d.model.builder import BuildContext, Model

__all__ = ["Sphere", "Plane", "Capsule", "Box", "Hole", "Cam", "Contact", "JointLimit",
           "ContactStates", "contact_states"]


class Contact(ForceElement):
    """A compliant contact between shapes on two bodies: a sphere, a capsule or a box against
    a plane; a sphere or a capsule against a sphere or a capsule, or inside a hole (a pin with
    clearance); a box against a sphere or a box; a sphere (a roller) or a plane (a flat
    face) on a planar disc cam; in either order.

    The normal force ``F_n`` [N] of ``law`` pushes the shapes apart while they overlap; the
    friction force ``-friction F_n tanh(|v_t| / slip_velocity) v_t / |v_t|`` opposes the slip
    ``v_t`` of the second shape on the first at the contact point (regularised Coulomb: the
    full ``friction F_n`` beyond a few ``slip_velocity``).

    Parameters
    ----------
    name : str
    first, second : Sphere, Capsule, Box, Plane, Hole or Cam
        The shapes (see :mod:`mbd3d.model.shapes`). A capsule touches a plane or a hole's
        wall at its two ends and a box touches a plane at its corners, each end or corner a
        contact of its own (a row of :func:`contact_states`, named ``"name[end a]"``,
        ``"name[corner -+-]"``); of two boxes each corner of either touches the other box
        (``"name[first corner -+-]"``, ``"name[second corner +--]"``: faces and corners
        meet, two edges that cross with no corner inside the other box do not). A law's
        calibration then holds for one of them touching alone.
    law : ContactLaw
        :class:`~mbd3d.LinearContact`, :class:`~mbd3d.HertzContact`,
        :class:`~mbd3d.HuntCrossley` or :class:`~mbd3d.ImpactFunction`; or
        :class:`~mbd3d.RigidImpact`, which makes the contact
        rigid: no force, every touch an impact (forward dynamics, without friction). Laws
        calibrated to a restitution use the pair's effective
        mass ``m* = m_i m_j / (m_i + m_j)`` (``m`` of the ground infinite): the masses of the
        free bodies, not the inertia the pair has through joints (give ``effective_mass``).
        Hertz's stiffness from the material uses the radii ``r_i r_j / (r_i + r_j)`` (a
        sphere's or a capsule's, a box's rounding, a plane's infinite; a hole's negative; a
        cam's smallest radius, its base circle, where a follower dwells).
    friction : float
        Coulomb coefficient ``mu`` >= 0.
    slip_velocity : float
        [m/s] > 0, the slip below which friction falls off smoothly to zero.
    effective_mass : float, optional
        [kg], overrides ``m*`` in the laws' calibration.

    Examples
    --------
    >>> import mbd3d as mb
    >>> b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    >>> ball = b.add_body("ball", mass=1.0, inertia=0.004, position=(0.0, 1.0))
    >>> _ = b.add(mb.Contact("bounce", mb.Sphere(ball, radius=0.1),
    ...                      mb.Plane(b.ground, normal=(0.0, 1.0)),
    ...                      law=mb.HertzContact(stiffness=1e7, restitution=0.8)))
    """

    #: contacts and joint limits are one group of the compiled core
    group_key = "contacts"

    def __init__(self, name: str, first: Any, second: Any, *, law: ContactLaw,
                 friction: float = 0.0, slip_velocity: float = 1e-3,
                 effective_mass: float | None = None):
        shapes = (Sphere, Capsule, Box, Plane, Hole, Cam)
        if not isinstance(first, shapes) or not isinstance(second, shapes):
            raise ModelError(f"contact '{name}': give two shapes (Sphere, Capsule, Box, Plane, "
                             f"Hole or Cam), got {type(first).__name__} and "
                             f"{type(second).__name__}")
        pair_order(first, second, f"contact '{name}'")
        if not isinstance(law, ContactLaw):
            raise ModelError(f"contact '{name}': law must be a LinearContact, HertzContact, "
                             f"HuntCrossley, ImpactFunction or RigidImpact, got {law!r}")
        self.name, self.first, self.second, self.law = name, first, second, law
        self.friction, self.slip_velocity = friction, slip_velocity
        self.effective_mass = effective_mass
        self.body_i, self.body_j = first.body, second.body
        self.what, self.units = f"contact '{name}'", ("m", "N")

    def bodies(self) -> list[tuple[str, Body]]:
        return [("first", self.body_i), ("second", self.body_j)]

    @classmethod
    def compile(cls, elements: list, ctx: "BuildContext") -> "_CompiledForces":
        return _Contacts(elements, ctx)

    def arrays(self, ctx: "BuildContext") -> tuple:
        """``(points (r, 4, dim), values (r, 10), labels, swapped, effective mass, curve)``:
        the rows of the compiled core (see :mod:`mbd3d.numerics.compiled.contacts` and
        :func:`shapes.pair_rows`), checked, the mass the law is calibrated with, and a cam's
        curve table (else None)."""
        what = f"contact '{self.name}'"
        rows = pair_rows(ctx, self.first, self.second, what)
        mu = finite_scalar(self.friction, f"{what}: friction")
        slip = finite_scalar(self.slip_velocity, f"{what}: slip_velocity", positive=True)
        if mu < 0.0:
            raise ModelError(f"{what}: friction must be >= 0, got {self.friction!r}")
        if mu > 0.0 and self.law.rigid:
            raise ModelError(f"{what}: friction at a rigid contact (stick and slip) is not "
                             "modelled yet; give friction=0, or a compliant law (HertzContact, "
                             "LinearContact) with friction")
        mass = self._effective_mass(what)
        K, n, D, p = self.law.constants(mass, rows.radius, what)
        d = self.law.damping_ramp(what)
        values = np.array([[kind, r_i, r_j, K, n, D, p, mu, slip, d]
                           for kind, r_i, r_j in rows.kinds], dtype=float)
        return rows.points, values, rows.labels, rows.swapped, mass, rows.curve

    def _effective_mass(self, what: str) -> float:
        if self.effective_mass is not None:
            return finite_scalar(self.effective_mass, f"{what}: effective_mass", positive=True)
        return _pair_mass([b.mass for b in (self.body_i, self.body_j) if not b.is_ground])


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
        As for :class:`Contact`; a law calibrated to a restitution uses ``effective_mass``:
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

    def arrays(self, ctx: "BuildContext") -> tuple:
        """``(points (1, 4, dim), values (1, 10), labels, swapped, effective mass, None)`` of
        the compiled core, checked (see :meth:`Contact.arrays`)."""
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
            return _pair_mass([b.mass for b in (self.body_i, self.body_j) if not b.is_ground])
        return float(np.mean([_pair_mass([_moment(ctx, body, u, h) for body, u in
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


def _curve_table(points: np.ndarray, curves: list) -> np.ndarray:
    """The cams' curves one after another (:mod:`mbd3d.numerics.compiled.curves`), each row's
    offset and interval count written into its ``points[r, 3]`` (see
    :mod:`mbd3d.numerics.compiled.contacts`)."""
    tables, offset = [], 0
    for r, curve in enumerate(curves):
        if curve is not None:
            points[r, 3, :2] = offset, (len(curve) - 1) // 5  # count + 1 knots, 4 count
            tables.append(curve)
            offset += len(curve)
    return np.ascontiguousarray(np.concatenate(tables) if tables else np.zeros(0))


def _pair_mass(masses: list) -> float:
    """``1 / sum(1 / m)`` of the moving bodies' masses or moments (inf: none moves)."""
    inverse = sum(1.0 / m for m in masses)
    return 1.0 / inverse if inverse > 0.0 else math.inf


class _Contacts(_CompiledForces):
    """The contacts and joint stops of a model as rows of the compiled core: ``owners[r]``
    is the element of row ``r``; where a pair was given the other way round (``swapped``)
    the core's body i is the element's second body, and its reports are turned back."""

    def __init__(self, elements: list, ctx: "BuildContext"):
        self.elements = elements
        arrays = [e.arrays(ctx) for e in elements]
        self._points = np.ascontiguousarray(np.concatenate([a[0] for a in arrays]))
        self._curves = _curve_table(self._points, [a[5] for a in arrays for _ in a[2]])
        self._values = np.ascontiguousarray(np.concatenate([a[1] for a in arrays]))
        self.owners = [e for e, a in zip(elements, arrays) for _ in a[2]]
        self.names = [f"{e.name}[{label}]" if label else e.name
                      for e, a in zip(elements, arrays) for label in a[2]]
        self._swapped = np.concatenate([np.broadcast_to(np.asarray(a[3], dtype=bool), len(a[2]))
                                        for a in arrays])
        #: per row, the mass (a stop: the moment of inertia) its law is calibrated with
        self.masses = np.array([a[4] for a in arrays for _ in a[2]], dtype=float)
        #: per row, whether it is rigid (:class:`~mbd3d.RigidImpact`: no force, impacts),
        #: and its law's restitution and rest speed (rigid rows only, else nan)
        laws = [e.law for e in self.owners]
        self.rigid = np.array([law.rigid for law in laws], dtype=bool)
        self.restitution = np.array([law.restitution if law.rigid else np.nan for law in laws])
        self.rest_speed = np.array([law.rest_speed if law.rigid else np.nan for law in laws])
        #: the contacts' shapes in their bodies' frames, for drawing
        self.outlines = [outline(ctx, shape, e.what) for e in elements if isinstance(e, Contact)
                         for shape in (e.first, e.second)]
        self._rows = None
        self._check_apart(ctx)

    def _pairs(self, row) -> np.ndarray:
        """The core's ``(i, j)`` body indices per row, from ``row(body)``."""
        pairs = np.array([[row(e.body_i), row(e.body_j)] for e in self.owners], dtype=np.int64)
        pairs[self._swapped] = pairs[self._swapped, ::-1]
        return pairs

    def _check_apart(self, ctx: "BuildContext") -> None:
        """Shapes that overlap in the drawing are reported with the depth (a
        :class:`~mbd3d.errors.ContactWarning`): an integration starts with that force."""
        fr = ctx.body_type.frames(ctx.frames.Q, np.zeros_like(ctx.frames.Q), charts=ctx.charts)
        report = self._report(fr, self._pairs(ctx.row))
        # rigid shapes drawn touching overlap by the rounding of their positions
        rounding = 1e-12 * (1.0 + float(np.max(np.abs(ctx.frames.Q), initial=0.0)))
        overlap = report[:, kernel.GAP] < np.where(self.rigid, -rounding, 0.0)
        for k in np.flatnonzero(overlap):
            e = self.owners[k]
            depth, force = -report[k, kernel.GAP], report[k, kernel.NORMAL_FORCE]
            where = ("the shapes overlap by" if isinstance(e, Contact)
                     else "the joint is past its limit by")
            what = e.what.replace(f"'{e.name}'", f"'{self.names[k]}'")  # with the corner
            force = ("a rigid contact, which forward dynamics refuses to start inside"
                     if self.rigid[k] else f"with a force of {force:.6g} {e.units[1]}")
            warnings.warn(f"{what}: {where} {depth:.6g} {e.units[0]} in the drawing, "
                          f"{force}; place the bodies apart (or at the limit) unless that is "
                          "their static penetration", ContactWarning,
                          stacklevel=user_stacklevel())

    def _report(self, fr, bodies: np.ndarray, k: int = 1) -> np.ndarray:
        """A row of the core's report per contact row, normals and friction turned back to
        the element's order of shapes; of ``k`` states stacked time-major in ``fr`` (rows ``t *
        (n_bodies + 1) + b``), the rows of state ``t`` at ``t * r ... (t + 1) * r``."""
        r, rows = len(self.owners), len(fr.Q) // k
        if k > 1:
            bodies = (bodies[None] + rows * np.arange(k)[:, None, None]).reshape(k * r, 2)
        out = np.zeros_like(fr.Q)
        report = np.zeros((k * r, kernel.REPORT_COLUMNS))
        failed = kernel.contact_forces_into(fr.A, fr.axes, fr.omega3, fr.Q, fr.Qd, bodies,
                                            np.tile(self._points, (k, 1, 1)),
                                            np.tile(self._values, (k, 1)), self._curves, out,
                                            report, np.zeros(0))
        if failed >= 0:
            raise ModelError(f"{self.owners[failed % r].what}: the shapes' cores meet; the "
                             "contact normal is undefined")
        swapped = np.tile(self._swapped, k)
        for columns in (slice(kernel.FRICTION, kernel.FRICTION + 3),
                        slice(kernel.NORMAL, kernel.NORMAL + 3)):
            report[swapped, columns] *= -1.0
        return report

    def _bodies(self, model) -> np.ndarray:
        if self._rows is None:
            self._rows = self._pairs(model.padded_index)
        return self._rows

    def apply(self, model, t, fr, Q):
        failed = kernel.contact_forces_into(fr.A, fr.axes, fr.omega3, fr.Q, fr.Qd,
                                            self._bodies(model), self._points, self._values,
                                            self._curves, Q,
                                            np.zeros((0, kernel.REPORT_COLUMNS)), np.zeros(0))
        if failed >= 0:
            raise ModelError(f"{self.owners[failed].what}: the shapes' cores meet at t = {t:g} "
                             "s; the contact normal is undefined")

    analytic_tangent = True

    def tangent(self, model, t, fr, velocity_weight):
        """The laws' slopes through each pair's velocity Jacobian (see
        :func:`~mbd3d.numerics.compiled.contacts.contact_tangents_into`), as COO triplets over
        the padded coordinates; rows that do not push add zeros."""
        bodies, nc = self._bodies(model), model.n_coords_per_body
        blocks = np.empty((len(bodies), 2 * nc, 2 * nc))
        kernel.contact_tangents_into(fr.A, fr.axes, fr.omega3, fr.Q, fr.Qd, bodies,
                                     self._points, self._values, self._curves, velocity_weight,
                                     blocks)
        index = (bodies[:, :, None] * nc + np.arange(nc)).reshape(len(bodies), 2 * nc)
        rows = np.broadcast_to(index[:, :, None], blocks.shape)
        cols = np.broadcast_to(index[:, None, :], blocks.shape)
        return rows.ravel(), cols.ravel(), blocks.ravel()

    def switches(self, model, fr) -> np.ndarray:
        """Each row's switching function at the state of ``fr``: positive exactly while its law
        pushes (see :func:`~mbd3d.numerics.compiled.contacts.switches_into`)."""
        out = np.empty(len(self.owners))
        kernel.switches_into(fr.A, fr.omega3, fr.Q, fr.Qd, self._bodies(model), self._points,
                             self._values, self._curves, out)
        return out

    def impact_periods(self, gap: np.ndarray, gap_rate: np.ndarray) -> np.ndarray:
        """Per row, the period [s] of the law's oscillation ``2 pi sqrt(m* / k)`` at its
        stiffest in the impact at ``(gap, gap_rate)``: ``k = n K delta^(n - 1)`` at the
        deeper of the penetration now and the one the closing speed reaches against the
        law's spring, ``((n + 1) m* v^2 / (2 K))^(1 / (n + 1))`` (damping only shortens it)."""
        K, n, m = self._values[:, 3], self._values[:, 4], self.masses
        # a rigid row (K = 0) has no oscillation: its impact takes no time
        K = np.where(self.rigid, np.inf, K)
        closing = np.maximum(-gap_rate, 0.0)
        deepest = ((n + 1.0) * m * closing ** 2 / (2.0 * K)) ** (1.0 / (n + 1.0))
        delta = np.maximum(np.maximum(-gap, deepest), 1e-300)
        return np.where(self.rigid, np.inf,
                        2.0 * math.pi * np.sqrt(m / (n * K * delta ** (n - 1.0))))

    def table(self, model):
        return {"contact_bodies": self._bodies(model), "contact_points": self._points,
                "contact_values": self._values, "contact_curves": self._curves}

    def potential(self, model, fr) -> float:
        return float(np.sum(self._report(fr, self._bodies(model))[:, kernel.POTENTIAL]))

    def states(self, model, fr, k: int = 1) -> np.ndarray:
        """The report of ``k`` states stacked in ``fr`` (see :meth:`_report`), (k * r, c)."""
        return self._report(fr, self._bodies(model), k)


@dataclass(frozen=True)
class ContactStates:
    """The contacts and joint stops of a model at one state, one row per contact in the
    order they were added (a capsule or a box against a plane a row per end or corner, a
    stop's row after the contacts added before it); over a run
    (:meth:`mbd3d.Results.contacts`) every array has a leading time axis ``k``.

    Attributes
    ----------
    names : list of str
        The contacts' names, an end's or a corner's label in brackets.
    gap : ndarray (k,)
        Distance between the surfaces [m]; negative: the penetration. A stop's: how far its
        joint coordinate is inside its limits [rad or m], negative past one.
    gap_rate : ndarray (k,)
        [m/s or rad/s], positive while they separate.
    normal_force : ndarray (k,)
        [N], >= 0; a hinge's or a cone's stop: a torque [N m]. A rigid contact's is 0: its
        impacts are impulses, listed in ``results.stats["impacts"]``.
    friction_force : ndarray (k, 3)
        On the second shape [N], global axes (the opposite acts on the first).
    point : ndarray (k, 3)
        Midway between the surfaces [m], global; a stop's: its joint's point on body j.
    normal : ndarray (k, 3)
        Unit normal from the first shape to the second, global; a stop's: the direction of
        its force or torque on body j.
    potential_energy : ndarray (k,)
        Of the law's spring part [J].
    dissipated_energy : ndarray (k,) or None
        Over a forward dynamics run (:meth:`mbd3d.Results.contacts`): the energy [J] the
        row's damper and friction have dissipated since the start; else None.
    """

    names: list
    gap: np.ndarray
    gap_rate: np.ndarray
    normal_force: np.ndarray
    friction_force: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    potential_energy: np.ndarray
    dissipated_energy: np.ndarray | None = None


def contact_group(model: "Model", required: bool = True) -> _Contacts | None:
    """The compiled contacts and joint stops of ``model``; a model without any is refused
    (``required``) or gives None."""
    groups = [g for g in model.force_groups if isinstance(g, _Contacts)]
    if not groups and required:
        raise ModelError(f"model '{model.name}' has no contacts or joint limits")
    return groups[0] if groups else None


def states_of(group: _Contacts, report: np.ndarray, k: int | None = None) -> ContactStates:
    """The core's ``report`` as :class:`ContactStates`: of one state (``k`` None), or of
    ``k`` states (every array with a leading axis ``k``)."""
    r = report if k is None else report.reshape(k, len(group.names), -1)
    c = kernel
    return ContactStates(names=list(group.names), gap=r[..., c.GAP].copy(),
                         gap_rate=r[..., c.GAP_RATE].copy(),
                         normal_force=r[..., c.NORMAL_FORCE].copy(),
                         friction_force=r[..., c.FRICTION:c.FRICTION + 3].copy(),
                         point=r[..., c.POINT:c.POINT + 3].copy(),
                         normal=r[..., c.NORMAL:c.NORMAL + 3].copy(),
                         potential_energy=r[..., c.POTENTIAL].copy())


def contact_states(model: "Model", q: np.ndarray, qd: np.ndarray | None = None,
                   charts: np.ndarray | None = None) -> ContactStates:
    """The state of every contact of ``model`` at ``(q, qd)`` (``qd`` default zero); over a
    run, :meth:`mbd3d.Results.contacts`."""
    from mbd3d.model.constraints import frames  # noqa: PLC0415

    q = np.asarray(q, dtype=float)
    fr = frames(model, q, np.zeros_like(q) if qd is None else np.asarray(qd, dtype=float), charts)
    group = contact_group(model)
    return states_of(group, group.states(model, fr))
