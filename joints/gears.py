"""Gear pairs and rack and pinion: higher pairs whose pitch curves roll without slip."""

from __future__ import annotations

import math
from fractions import Fraction
from typing import Any

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.model.body import Body
from mbd3d.model.builder import BuildContext
from mbd3d.model.element import ConstraintElement, PrimitiveSpec

from mbd3d.numerics.compiled.rows import mesh_phase

from mbd3d.joints.base import perpendicular, triad

#: relative mismatch allowed between the drawing's centre distance and the pitch radii
_CENTRE_TOLERANCE = 1e-6
#: the largest tooth count a spatial gear pair's ratio is read as
_MAX_TEETH = 1000


class _Mesh(ConstraintElement):
    """What gear meshes share: checks of pitch radii, centres and the pressure angle.

    Subclasses give ``mesh_radius``: body j's pitch radius, about whose centre the mesh force
    is reported.
    """

    #: what the error messages call it
    kind = "gear pair"

    def _radius(self, ctx: BuildContext, value: Any, what: str) -> float:
        return ctx.scalar(value, f"{self.kind} '{self.name}': {what}", positive=True)

    def _pressure_angle(self, ctx: BuildContext) -> float:
        alpha = ctx.scalar(self.pressure_angle, f"{self.kind} '{self.name}': pressure_angle")
        if not 0.0 <= alpha < math.radians(45.0):
            raise ModelError(f"{self.kind} '{self.name}': pressure_angle must be in [0, 45) "
                             f"degrees, given in radians; got {alpha!r} rad "
                             "(20 degrees is math.radians(20))")
        return alpha

    def _centre(self, ctx: BuildContext, body: Body, value: Any, what: str) -> np.ndarray:
        """A gear centre in body frame: given in the drawing, or the body's centre of mass."""
        if value is None:
            if body.is_ground:
                raise ModelError(f"{self.kind} '{self.name}': the ground has no centre of mass; "
                                 f"give {what}= (the gear centre in the drawing, global axes)")
            return np.zeros(ctx.dim)
        return ctx.to_local_point(body, ctx.vector(value, f"{self.kind} '{self.name}': {what}"))


class GearPair(_Mesh):
    """Two gears in mesh: their pitch circles (planar, spatial spur) or pitch cones (spatial
    bevel) roll on each other without slip.

    Planar: whatever carries the gear centres (the ground, or an arm that turns as in a
    planetary train), the gears' angles ``theta_i``, ``theta_j`` [rad] and the angle ``phi`` of
    the line from centre i to centre j satisfy ``rho_i (theta_i - phi) + sigma rho_j (theta_j -
    phi) = const`` (``sigma = +1`` external mesh, ``-1`` internal); with the centres fixed,
    ``omega_j / omega_i = -sigma rho_i / rho_j``. The centre distance must be held by other
    joints (each gear's revolute to a common carrier); this constraint adds the one row of the
    mesh (see :class:`mbd3d.model.primitives.Gear`).

    Spatial: each gear turns on a hinge about ``axis_i`` or ``axis_j`` (directions of the
    drawing, through the gear centres). Parallel axes make a spur pair (external or internal,
    as in the plane); intersecting axes a bevel pair, any shaft angle, whose pitch cones share
    their apex where the axes meet; the radii are the pitch radii at a common distance from
    the apex, so that ``rho_i / rho_j = sin(delta_i) / sin(delta_j)`` (``delta``: pitch-cone
    angles). Relative to the carrier of both hinges, gear j turns ``-sigma rho_i / rho_j``
    times gear i's angle, about its axis pointing the same way as gear i's (spur) or away
    from the apex (bevel). The angles are known modulo a turn, so the row is written in the
    mesh's phase (:class:`mbd3d.model.primitives.GearMesh`), which needs
    ``radius_i / radius_j`` to be a ratio of tooth counts: whole numbers up to 1000, as every
    real gear pair's is.

    The teeth push along the line of action, inclined by the pressure angle to the common
    tangent: ``results.joint(name).mesh_force`` gives the tangential force, the tooth force and
    its separating component. The model is of rigid, backlash-free gears with their pitch
    circles exactly touching: the separating component is not part of the joints' reactions,
    the bearings carry it in addition.

    Parameters
    ----------
    name : str
    body_i, body_j : Body
        The gears (either may be the ground: a fixed gear). With ``internal=True``, body j is
        the ring (the internal gear) and body i the pinion inside it.
    radius_i, radius_j : float
        Pitch radii [m] (module times teeth over two).
    internal : bool
        Internal mesh: the pinion rolls inside the ring, both turning the same way.
    center_i, center_j : array_like, optional
        The gear centres in the drawing (global coordinates) [m]; default each gear's centre
        of mass. Planar and spatial spur: their distance across the axes must be
        ``radius_i + radius_j`` (internal: ``radius_j - radius_i``). Bevel: any point of each
        axis but the apex.
    pressure_angle : float
        Angle of the line of action to the common tangent [rad]; default 20 degrees.
    axis_i, axis_j : array_like, optional
        Spatial models: the gears' axes of rotation in the drawing (global axes); ``axis_j``
        defaults to ``axis_i`` (a spur pair). Planar gears turn about the plane's normal and
        take neither.

    Examples
    --------
    >>> import math
    >>> import mbd3d as mb
    >>> from mbd3d.joints import GearPair, Revolute
    >>> b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0))
    >>> pinion = b.add_body("pinion", mass=1.0, inertia=1e-3, position=(0.0, 0.0))
    >>> wheel = b.add_body("wheel", mass=4.0, inertia=2e-2, position=(0.15, 0.0))
    >>> _ = b.add(Revolute("A", b.ground, pinion, at=(0.0, 0.0)))
    >>> _ = b.add(Revolute("B", b.ground, wheel, at=(0.15, 0.0)))
    >>> mesh = b.add(GearPair("mesh", pinion, wheel, radius_i=0.05, radius_j=0.10))
    """

    def __init__(self, name: str, body_i: Body, body_j: Body, *, radius_i: float,
                 radius_j: float, internal: bool = False, center_i: Any = None,
                 center_j: Any = None, pressure_angle: float = math.radians(20.0),
                 axis_i: Any = None, axis_j: Any = None):
        self.name = name
        self.body_i = body_i
        self.body_j = body_j
        self.radius_i = radius_i
        self.radius_j = radius_j
        self.internal = internal
        self.center_i = center_i
        self.center_j = center_j
        self.pressure_angle = pressure_angle
        self.axis_i = axis_i
        self.axis_j = axis_j

    def _radii(self, ctx: BuildContext) -> tuple[float, float]:
        if not isinstance(self.internal, (bool, np.bool_)):
            raise ModelError(f"gear pair '{self.name}': internal must be True or False, got "
                             f"{self.internal!r}")
        rho_i = self._radius(ctx, self.radius_i, "radius_i")
        rho_j = self._radius(ctx, self.radius_j, "radius_j")
        self._pressure_angle(ctx)
        if self.internal and not rho_j > rho_i:
            raise ModelError(f"gear pair '{self.name}': with internal=True body j "
                             f"('{self.body_j.name}') is the ring, so radius_j must be larger "
                             f"than radius_i; got {rho_j!r} <= {rho_i!r} m")
        return rho_i, rho_j

    def _check_centre_distance(self, distance: float, rho_i: float, rho_j: float) -> None:
        expected = rho_j - rho_i if self.internal else rho_i + rho_j
        if abs(distance - expected) > _CENTRE_TOLERANCE * expected:
            raise ModelError(
                f"gear pair '{self.name}': the gear centres are {distance:.9g} m apart in the "
                f"drawing{' across the axes' if self.axis_i is not None else ''}, but pitch "
                f"radii {rho_i:g} and {rho_j:g} m "
                f"{'in internal mesh' if self.internal else 'in mesh'} need {expected:.9g} m; "
                "place the gears (or center_i/center_j) so that the pitch circles touch")

    def geometry(self, ctx: BuildContext) -> tuple[np.ndarray, np.ndarray, float, float]:
        """Planar: ``(u_i, u_j, rho_i, sigma rho_j)``: centres in body frames and signed radii
        [m].

        Parameters
        ----------
        ctx : BuildContext
            The model being built (its drawing, and the checks that name what is wrong).
        """
        if ctx.dim != 2:
            return self.spatial_geometry(ctx)[:4]
        if self.axis_i is not None or self.axis_j is not None:
            raise ModelError(f"gear pair '{self.name}': planar gears turn about the plane's "
                             "normal; leave out axis_i and axis_j")
        rho_i, rho_j = self._radii(ctx)
        u_i = self._centre(ctx, self.body_i, self.center_i, "center_i")
        u_j = self._centre(ctx, self.body_j, self.center_j, "center_j")
        self._check_centre_distance(float(np.linalg.norm(
            ctx.to_global_point(self.body_j, u_j) - ctx.to_global_point(self.body_i, u_i))),
            rho_i, rho_j)
        return u_i, u_j, rho_i, -rho_j if self.internal else rho_j

    def spatial_geometry(self, ctx: BuildContext):
        """Spatial: ``(u_i, u_j, rho_i, sigma rho_j, h_i, h_j)``: centres in body frames,
        signed radii [m] and the axes in the drawing, gear j's the same way as gear i's
        (spur) or both away from the apex (bevel).

        Parameters
        ----------
        ctx : BuildContext
            The model being built (its drawing, and the checks that name what is wrong).
        """
        rho_i, rho_j = self._radii(ctx)
        what = f"gear pair '{self.name}'"
        if self.axis_i is None:
            raise ModelError(f"{what}: spatial gears need axis_i= (gear i's axis of rotation "
                             "in the drawing, global axes), and axis_j= for a bevel pair")
        h_i = ctx.direction(self.axis_i, f"{what}: axis_i")
        h_j = h_i if self.axis_j is None else ctx.direction(self.axis_j, f"{what}: axis_j")
        u_i = self._centre(ctx, self.body_i, self.center_i, "center_i")
        u_j = self._centre(ctx, self.body_j, self.center_j, "center_j")
        o_i = ctx.to_global_point(self.body_i, u_i)
        o_j = ctx.to_global_point(self.body_j, u_j)
        d = o_j - o_i
        normal = np.cross(h_i, h_j)
        sine = float(np.linalg.norm(normal))
        if sine < 1e-9:  # parallel axes: a spur pair
            h_j = h_i
            self._check_centre_distance(float(np.linalg.norm(d - (d @ h_i) * h_i)), rho_i, rho_j)
            return u_i, u_j, rho_i, -rho_j if self.internal else rho_j, h_i, h_j
        if self.internal:
            raise ModelError(f"{what}: internal=True is for parallel axes (a ring gear); the "
                             "axes given intersect at an angle (a bevel pair)")
        skew = abs(float(d @ normal)) / sine
        scale = max(rho_i, rho_j, float(np.linalg.norm(d)))
        if skew > _CENTRE_TOLERANCE * scale:
            raise ModelError(f"{what}: the axes through center_i and center_j pass "
                             f"{skew:.6g} m apart; a bevel pair's axes must intersect (skew "
                             "axes, as of hypoid or worm gears, are not supported)")
        # the apex: where the axes meet, from o_i + a h_i = o_j + b h_j in least squares
        a, b = np.linalg.lstsq(np.column_stack([h_i, -h_j]), d, rcond=None)[0]
        oriented = []
        for h, along, key in ((h_i, a, "center_i"), (h_j, b, "center_j")):
            if abs(along) < _CENTRE_TOLERANCE * scale:
                raise ModelError(f"{what}: {key} is the apex, where the axes meet; give a "
                                 "point of the gear's axis away from it (the centre of its "
                                 "pitch circle)")
            oriented.append(-h if along > 0 else h)  # away from the apex
        return u_i, u_j, rho_i, rho_j, oriented[0], oriented[1]

    def teeth(self, ctx: BuildContext) -> tuple[int, int]:
        """The smallest tooth counts ``(z_i, z_j)`` in the ratio of the pitch radii.

        Parameters
        ----------
        ctx : BuildContext
            The model being built (its drawing, and the checks that name what is wrong).
        """
        rho_i, rho_j = self._radii(ctx)
        ratio = Fraction(rho_i / rho_j).limit_denominator(_MAX_TEETH)
        z_i, z_j = ratio.numerator, ratio.denominator
        if abs(z_i / z_j - rho_i / rho_j) > 1e-9 * rho_i / rho_j or max(z_i, z_j) > _MAX_TEETH:
            raise ModelError(
                f"gear pair '{self.name}': radius_i / radius_j = {rho_i / rho_j!r} is not a "
                f"ratio of tooth counts up to {_MAX_TEETH} (nearest {z_i}/{z_j}); spatial "
                "gears keep their teeth in phase through the ratio, so give radii in the "
                "exact ratio of the teeth, e.g. module * teeth / 2")
        return z_i, z_j

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        if ctx.dim == 3:
            return [self._spatial_primitive(ctx)]
        u_i, u_j, rho_i, signed_j = self.geometry(ctx)
        d = ctx.to_global_point(self.body_j, u_j) - ctx.to_global_point(self.body_i, u_i)
        phi = math.atan2(d[1], d[0])
        theta_i = ctx.initial_coordinate(self.body_i, 2)
        theta_j = ctx.initial_coordinate(self.body_j, 2)
        total = rho_i + signed_j
        constant = rho_i * theta_i + signed_j * theta_j - total * phi
        real = (rho_i / total, signed_j / total, constant / total, math.copysign(1.0, total))
        return [PrimitiveSpec("gear", self.body_i, self.body_j,
                              {"u_i": u_i, "u_j": u_j, "real": real}, ("mesh",))]

    def _spatial_primitive(self, ctx: BuildContext) -> PrimitiveSpec:
        u_i, u_j, rho_i, signed_j, h_i, h_j = self.spatial_geometry(ctx)
        z_i, z_j = self.teeth(ctx)
        z_j_signed = math.copysign(z_j, signed_j)
        d = ctx.to_global_point(self.body_j, u_j) - ctx.to_global_point(self.body_i, u_i)
        f_i, g_i, _ = triad(h_i)
        f_j, g_j, _ = triad(h_j)
        # the phase constant: the drawing is in mesh
        phase = float(mesh_phase(d @ f_i, d @ g_i, d @ f_j, d @ g_j, z_i, z_j_signed, 0.0))
        params = {"f_i": ctx.to_local_vector(self.body_i, f_i),
                  "g_i": ctx.to_local_vector(self.body_i, g_i),
                  "f_j": ctx.to_local_vector(self.body_j, f_j),
                  "g_j": ctx.to_local_vector(self.body_j, g_j),
                  "u_i": u_i, "u_j": u_j, "real": (z_i, z_j_signed, phase, rho_i / z_i)}
        return PrimitiveSpec("gear_mesh", self.body_i, self.body_j, params, ("mesh",))

    def reaction_frame(self, ctx: BuildContext):
        if ctx.dim == 3:
            u_i, u_j, _, _, h_i, _ = self.spatial_geometry(ctx)
            f, g, h = triad(h_i)
            return u_i, u_j, np.column_stack([ctx.to_local_vector(self.body_i, v)
                                              for v in (f, g, h)])
        u_i, u_j, _, _ = self.geometry(ctx)
        return u_i, u_j, np.eye(2)

    @property
    def mesh_radius(self) -> float:
        """Pitch radius of body j [m], about whose centre the mesh force is reported."""
        return float(self.radius_j)


class RackPinion(_Mesh):
    """A planar rack and pinion: the pinion's pitch circle rolls without slip on the rack's
    pitch line.

    Body i is the rack, body j the pinion. The rack's pitch line runs along ``axis`` at
    ``radius`` to the right of the pinion's centre (looking along ``axis``; reverse ``axis``
    for a rack above the pinion): when the pinion centre advances by ``s`` along the rack,
    relative to it, the pinion turns by ``-s / radius`` relative to the rack (clockwise for a
    rack below). The distance of the centre from the line must be held by other joints
    (typically the rack's prismatic joint and the pinion's revolute). Row:
    :class:`mbd3d.model.primitives.Rack`.

    Parameters
    ----------
    name : str
    body_i : Body
        The rack (may be the ground: the pinion then rolls along a fixed rack).
    body_j : Body
        The pinion.
    radius : float
        The pinion's pitch radius [m].
    axis : array_like
        Direction of the rack in the drawing (global axes).
    center : array_like, optional
        The pinion centre in the drawing [m]; default the pinion's centre of mass.
    pressure_angle : float
        Angle of the line of action to the pitch line [rad]; default 20 degrees.
    """

    #: what the error messages call it
    kind = "rack and pinion"

    def __init__(self, name: str, body_i: Body, body_j: Body, *, radius: float, axis: Any,
                 center: Any = None, pressure_angle: float = math.radians(20.0)):
        self.name = name
        self.body_i = body_i
        self.body_j = body_j
        self.radius = radius
        self.axis = axis
        self.center = center
        self.pressure_angle = pressure_angle

    def geometry(self, ctx: BuildContext) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        """``(u_i, u_j, a_i, rho)``: the pinion centre in the frames of the rack and the pinion,
        the rack's unit direction in its frame, the pitch radius [m].

        Parameters
        ----------
        ctx : BuildContext
            The model being built (its drawing, and the checks that name what is wrong).
        """
        if ctx.dim != 2:
            raise ModelError(f"{self.kind} '{self.name}': available for planar models only "
                             "(dim=2) so far")
        rho = self._radius(ctx, self.radius, "radius")
        self._pressure_angle(ctx)
        u_j = self._centre(ctx, self.body_j, self.center, "center")
        u_i = ctx.to_local_point(self.body_i, ctx.to_global_point(self.body_j, u_j))
        axis = ctx.direction(self.axis, f"{self.kind} '{self.name}': axis")
        return u_i, u_j, ctx.to_local_vector(self.body_i, axis), rho

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        u_i, u_j, a_i, rho = self.geometry(ctx)
        turn = ctx.initial_coordinate(self.body_j, 2) - ctx.initial_coordinate(self.body_i, 2)
        return [PrimitiveSpec("rack", self.body_i, self.body_j,
                              {"v_i": a_i, "u_i": u_i, "u_j": u_j, "real": (rho,)}, ("mesh",),
                              c0=rho * turn)]

    def reaction_frame(self, ctx: BuildContext):
        u_i, u_j, a_i, _ = self.geometry(ctx)
        return u_i, u_j, np.column_stack([a_i, perpendicular(a_i)])

    @property
    def mesh_radius(self) -> float:
        """The pinion's pitch radius [m]: the mesh force is reported about its centre."""
        return float(self.radius)
