"""Disc cams and their followers (planar): a point or roller on the cam's pitch curve, and a
flat face tangent to the cam."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.model.body import Body
from mbd3d.model.cam_profile import CamProfile
from mbd3d.model.builder import BuildContext
from mbd3d.model.element import ConstraintElement, PrimitiveSpec

#: how far (relative to the curve's size) the drawing may put the follower off the curve: the
#: position analysis at the start closes small gaps (a profile interpolated between samples
#: of the law the drawing was made from), not a forgotten roller radius
_ON_CURVE = 1e-3


#: angles at which a profile's curvature is checked
_CHECKED = np.linspace(0.0, 2 * math.pi, 3600, endpoint=False)


def _profile(element: ConstraintElement, profile: Any) -> CamProfile:
    if not isinstance(profile, CamProfile):
        raise ModelError(f"cam '{element.name}': profile must be a CamProfile (angles and radii, "
                         f"or CamProfile.sampled(function)), got {profile!r}")
    return profile


def _cam_centre(ctx: BuildContext, element: ConstraintElement, centre: Any) -> np.ndarray:
    if centre is None:
        if element.body_i.is_ground:
            raise ModelError(f"cam '{element.name}': the ground has no centre of mass; give "
                             "center= (the cam's centre in the drawing)")
        return np.zeros(2)
    return ctx.to_local_point(element.body_i, ctx.vector(centre, f"cam '{element.name}': center"))


def _require_planar(ctx: BuildContext, element: ConstraintElement) -> None:
    if ctx.dim != 2:
        raise ModelError(f"cam '{element.name}': cams are available for planar models only "
                         "(dim=2) so far")


class CamFollower(ConstraintElement):
    """A point or roller follower on a planar disc cam: the follower's point (a knife edge, or
    a roller's centre) stays on the cam's pitch curve.

    The cam (body i) turns about its centre however it is driven; the follower (body j) is
    guided by its own joints (a prismatic joint for a translating follower, a revolute for a
    rocker). Row: :class:`mbd3d.model.primitives.CamPoint`. ``results.joint(name)
    .contact_force`` is the normal force between them, positive while they press on each
    other; where it would pull, the follower lifts off in reality, and ``.lift_off`` lists
    those times.

    Parameters
    ----------
    name : str
    body_i : Body
        The cam (may be the ground: a fixed track).
    body_j : Body
        The follower.
    profile : CamProfile
        The pitch curve, polar about the cam's centre in the cam's frame.
    center : array_like, optional
        The cam's centre in the drawing (global) [m]; default the cam's centre of mass.
    point : array_like, optional
        The follower's point (roller centre) in the drawing [m], on the pitch curve; default
        the follower's centre of mass.
    roller_radius : float
        The roller's radius [m] (0: a knife edge), for drawing the cam's surface and placing
        the contact point.
    """

    def __init__(self, name: str, body_i: Body, body_j: Body, *, profile: CamProfile,
                 center: Any = None, point: Any = None, roller_radius: float = 0.0):
        self.name = name
        self.body_i = body_i
        self.body_j = body_j
        self.profile = profile
        self.center = center
        self.point = point
        self.roller_radius = roller_radius

    def geometry(self, ctx: BuildContext) -> tuple[np.ndarray, np.ndarray]:
        """``(u_i, u_j)``: the cam's centre in its frame and the follower's point in its own.

        Parameters
        ----------
        ctx : BuildContext
            The model being built (its drawing, and the checks that name what is wrong).
        """
        _require_planar(ctx, self)
        profile = _profile(self, self.profile)
        rho = ctx.scalar(self.roller_radius, f"cam '{self.name}': roller_radius")
        if rho < 0:
            raise ModelError(f"cam '{self.name}': roller_radius must be >= 0, got {rho!r}")
        r, r1, r2 = (profile(_CHECKED, k) for k in range(3))
        # the pitch curve's radius of curvature where it is convex: a roller larger than it
        # would need the cam's surface to cross itself (undercutting)
        bend = r * r + 2 * r1 * r1 - r * r2
        curvature_radius = (r * r + r1 * r1) ** 1.5 / np.where(bend > 0, bend, np.nan)
        if rho > 0 and np.nanmin(curvature_radius, initial=np.inf) < rho:
            k = int(np.nanargmin(curvature_radius))
            raise ModelError(f"cam '{self.name}': the pitch curve bends tighter than the roller "
                             f"({curvature_radius[k]:.4g} m against a {rho:g} m roller at "
                             f"{math.degrees(_CHECKED[k]):.4g} deg in the cam's frame): the cam "
                             "would be undercut; use a smaller roller, a larger base circle "
                             "or a gentler law")
        u_i = _cam_centre(ctx, self, self.center)
        u_j = (np.zeros(2) if self.point is None else ctx.to_local_point(
            self.body_j, ctx.vector(self.point, f"cam '{self.name}': point")))
        d = ctx.to_global_point(self.body_j, u_j) - ctx.to_global_point(self.body_i, u_i)
        phi = math.atan2(d[1], d[0]) - ctx.initial_coordinate(self.body_i, 2)
        r = float(profile(phi))
        off = float(np.linalg.norm(d)) - r
        if abs(off) > _ON_CURVE * r:
            raise ModelError(f"cam '{self.name}': the follower's point is {off:.6g} m off the "
                             f"pitch curve in the drawing (radius {r:.6g} m at "
                             f"{math.degrees(phi):.4g} deg in the cam's frame); put it on the "
                             "curve, or turn the cam to match")
        return u_i, u_j

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        u_i, u_j = self.geometry(ctx)
        return [PrimitiveSpec("cam", self.body_i, self.body_j,
                              {"u_i": u_i, "u_j": u_j, "curve": self.profile.table()},
                              ("contact",))]

    def reaction_frame(self, ctx: BuildContext):
        u_i, u_j = self.geometry(ctx)
        return u_i, u_j, np.eye(2)


class FlatFaceFollower(ConstraintElement):
    """A flat-faced follower on a planar disc cam: the face stays tangent to the cam.

    Row: :class:`mbd3d.model.primitives.CamFace`. The cam is given by its support function
    (see :class:`CamProfile`), which must describe a convex cam. ``contact_force`` and
    ``lift_off`` as for :class:`CamFollower`.

    Parameters
    ----------
    name : str
    body_i : Body
        The cam.
    body_j : Body
        The follower.
    profile : CamProfile
        The cam's support function about its centre, in the cam's frame.
    normal : array_like
        The face's normal in the drawing, pointing from the face towards the cam.
    center : array_like, optional
        The cam's centre in the drawing [m]; default the cam's centre of mass.
    at : array_like, optional
        A point of the face in the drawing [m]; default the follower's centre of mass.
    """

    def __init__(self, name: str, body_i: Body, body_j: Body, *, profile: CamProfile,
                 normal: Any, center: Any = None, at: Any = None):
        self.name = name
        self.body_i = body_i
        self.body_j = body_j
        self.profile = profile
        self.normal = normal
        self.center = center
        self.at = at

    def geometry(self, ctx: BuildContext) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        """``(u_i, u_j, v_j, psi_0)``: the cam's centre, the face's point and normal in the
        follower's frame, and the angle of ``-v_j`` there.

        Parameters
        ----------
        ctx : BuildContext
            The model being built (its drawing, and the checks that name what is wrong).
        """
        _require_planar(ctx, self)
        profile = _profile(self, self.profile)
        # a flat face follows only a convex cam: the support function's radius of curvature,
        # h + h'', must stay positive
        curvature_radius = profile(_CHECKED) + profile(_CHECKED, 2)
        if curvature_radius.min() <= 0:
            k = int(np.argmin(curvature_radius))
            raise ModelError(f"cam '{self.name}': the cam is not convex at "
                             f"{math.degrees(_CHECKED[k]):.4g} deg in its frame (h + h'' = "
                             f"{curvature_radius[k]:.4g} m): a flat face cannot follow it; use "
                             "a larger base circle or a gentler law")
        u_i = _cam_centre(ctx, self, self.center)
        n = ctx.direction(self.normal, f"cam '{self.name}': normal")
        u_j = (np.zeros(2) if self.at is None else ctx.to_local_point(
            self.body_j, ctx.vector(self.at, f"cam '{self.name}': at")))
        v_j = ctx.to_local_vector(self.body_j, n)
        psi_0 = math.atan2(-v_j[1], -v_j[0])
        gap = (ctx.to_global_point(self.body_i, u_i) - ctx.to_global_point(self.body_j, u_j)) @ n
        psi = (ctx.initial_coordinate(self.body_j, 2) - ctx.initial_coordinate(self.body_i, 2)
               + psi_0)
        h = float(profile(psi))
        if abs(gap - h) > _ON_CURVE * h:
            raise ModelError(f"cam '{self.name}': the face is {gap:.6g} m from the cam's centre "
                             f"in the drawing, but the cam reaches {h:.6g} m in its direction; "
                             "place the face on the cam")
        return u_i, u_j, v_j, psi_0

    def primitives(self, ctx: BuildContext) -> list[PrimitiveSpec]:
        u_i, u_j, v_j, psi_0 = self.geometry(ctx)
        return [PrimitiveSpec("cam_face", self.body_i, self.body_j,
                              {"v_j": v_j, "u_j": u_j, "u_i": u_i,
                               "curve": self.profile.table(), "real": (0.0, 0.0, psi_0)},
                              ("contact",))]

    def reaction_frame(self, ctx: BuildContext):
        u_i, u_j, _, _ = self.geometry(ctx)
        return u_i, u_j, np.eye(2)
