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

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.model.body import Body
from mbd3d.model.contact_groups import ContactGroup
from mbd3d.model.contact_laws import ContactLaw, pair_mass
from mbd3d.model.contact_rows import _Contacts
from mbd3d.model.forces import ForceElement, _CompiledForces
from mbd3d.model.joint_limits import JointLimit
from mbd3d.model.shapes import (Box, Cam, Capsule, Hole, Plane, Sphere, outline, pair_order,
                                pair_rows)
from mbd3d.numerics.checks import finite_scalar
from mbd3d.numerics.compiled import contacts as kernel

if TYPE_CHECKING:
    from mbd3d.model.builder import BuildContext, Model

__all__ = ["Sphere", "Plane", "Capsule", "Box", "Hole", "Cam", "Contact", "ContactGroup",
           "JointLimit", "ContactStates", "contact_states"]


class Contact(ForceElement):
    """A compliant contact between shapes on two bodies: a sphere, a capsule or a box against
    a plane; a sphere or a capsule against a sphere or a capsule, or inside a hole (a pin with
    clearance); a box against a sphere, a capsule or a box; a sphere (a roller) or a plane
    (a flat face) on a planar disc cam; in either order.

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
        calibration then holds for one of them touching alone. A capsule touches a box at
        its core's point nearest the box (or deepest in it), one row; lying flat on a face,
        at the middle of what lies on it (as two parallel capsules touch).
    law : ContactLaw
        :class:`~mbd3d.LinearContact`, :class:`~mbd3d.HertzContact`,
        :class:`~mbd3d.HuntCrossley` or :class:`~mbd3d.ImpactFunction`; or
        :class:`~mbd3d.RigidImpact`, which makes the contact
        rigid: no force, every touch an impact (forward dynamics; with Coulomb's friction
        where it has ``friction``), and where it comes to rest it is held closed, sticking or
        sliding with Coulomb's friction (the explicit methods; see ``friction``). Laws
        calibrated to a restitution use the pair's effective
        mass ``m* = m_i m_j / (m_i + m_j)`` (``m`` of the ground infinite): the masses of the
        free bodies, not the inertia the pair has through joints (give ``effective_mass``).
        Hertz's stiffness from the material uses the radii ``r_i r_j / (r_i + r_j)`` (a
        sphere's or a capsule's, a box's rounding, a plane's infinite; a hole's negative; a
        cam's smallest radius, its base circle, where a follower dwells).
    friction : float
        Coulomb coefficient ``mu`` >= 0. At a rigid contact held at rest it is exact: the
        contact sticks (no slip) while its friction stays within ``mu F_n``, and slides with
        ``mu F_n`` against the slip beyond; each switch is an event of the run
        (:mod:`mbd3d.analyses.sticking`). At a rigid impact the same law holds for the
        impulses: the slip after it stops where ``mu`` times the normal impulse can stop it,
        else the contact slides with that much against the slip it leaves with.
    slip_velocity : float
        [m/s] > 0, the slip below which friction falls off smoothly to zero (compliant laws;
        a rigid contact's friction does not fall off).
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

    #: contacts, contact groups and joint limits are one group of the compiled core
    group_key = "contacts"
    #: a pair of shapes (not a group), and what its warning says where they overlap
    is_group, overlap_words = False, "the shapes overlap by"

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

    def outlines(self, ctx: "BuildContext") -> list:
        """The two shapes in their bodies' frames, for drawing.

        Parameters
        ----------
        ctx : BuildContext
            The model being built (its drawing, and the checks that name what is wrong).
        """
        return [outline(ctx, shape, self.what) for shape in (self.first, self.second)]

    def arrays(self, ctx: "BuildContext") -> tuple:
        """``(points (r, 4, dim), values (r, 10), labels, swapped, effective mass, curve)``:
        the rows of the compiled core (see :mod:`mbd3d.numerics.compiled.contacts` and
        :func:`shapes.pair_rows`), checked, the mass the law is calibrated with, and a cam's
        curve table (else None).

        Parameters
        ----------
        ctx : BuildContext
            The model being built (its drawing, and the checks that name what is wrong).
        """
        what = f"contact '{self.name}'"
        rows = pair_rows(ctx, self.first, self.second, what)
        mu = finite_scalar(self.friction, f"{what}: friction")
        slip = finite_scalar(self.slip_velocity, f"{what}: slip_velocity", positive=True)
        if mu < 0.0:
            raise ModelError(f"{what}: friction must be >= 0, got {self.friction!r}")
        mass = self._effective_mass(what)
        K, n, D, p = self.law.constants(mass, rows.radius, what)
        d = self.law.damping_ramp(what)
        values = np.array([[kind, r_i, r_j, K, n, D, p, mu, slip, d]
                           for kind, r_i, r_j in rows.kinds], dtype=float)
        return rows.points, values, rows.labels, rows.swapped, mass, rows.curve

    def _effective_mass(self, what: str) -> float:
        if self.effective_mass is not None:
            return finite_scalar(self.effective_mass, f"{what}: effective_mass", positive=True)
        return pair_mass([b.mass for b in (self.body_i, self.body_j) if not b.is_ground])


@dataclass(frozen=True)
class ContactStates:
    """The contacts and joint stops of a model at one state, one row per contact in the
    order they were added (a capsule or a box against a plane a row per end or corner, a
    stop's row after the contacts added before it, a :class:`~mbd3d.ContactGroup` one row:
    its pair deepest in contact, with the energies of all its pairs); over a run
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
    slip_velocity : ndarray (k, 3)
        Of the second shape's material point at the contact point relative to the first's,
        its part in the tangent plane [m/s], global axes (what friction opposes; zero at a
        joint stop).
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
    slip_velocity: np.ndarray
    dissipated_energy: np.ndarray | None = None


def contact_group(model: "Model", required: bool = True) -> _Contacts | None:
    """The compiled contacts and joint stops of ``model``; a model without any is refused
    (``required``) or gives None."""
    found = [g for g in model.force_groups if isinstance(g, _Contacts)]
    if not found and required:
        raise ModelError(f"model '{model.name}' has no contacts or joint limits")
    return found[0] if found else None


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
                         potential_energy=r[..., c.POTENTIAL].copy(),
                         slip_velocity=r[..., c.SLIP:c.SLIP + 3].copy())


def contact_states(model: "Model", q: np.ndarray, qd: np.ndarray | None = None,
                   charts: np.ndarray | None = None) -> ContactStates:
    """The state of every contact of ``model`` at ``(q, qd)`` (``qd`` default zero); over a
    run, :meth:`mbd3d.Results.contacts`.

    Parameters
    ----------
    model : Model
    q : (n,) array_like
        Positions (in ``charts`` for a spatial model).
    qd : (n,) array_like, optional
        Velocities (default zero).
    charts : ndarray, optional
        Spatial models: the bodies' reference rotations ``q`` is given in (default the model's).
    """
    from mbd3d.model.constraints import frames  # noqa: PLC0415

    q = np.asarray(q, dtype=float)
    fr = frames(model, q, np.zeros_like(q) if qd is None else np.asarray(qd, dtype=float), charts)
    group = contact_group(model)
    return states_of(group, group.states(model, fr))
