"""A cam's closed curve in polar form about its centre (:class:`CamProfile`): the pitch curve
of a roller follower, the support function of a flat-faced one, or the surface of a
:class:`~mbd3d.Cam` shape that contacts touch."""

from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.model.arguments import RecordsArguments

__all__ = ["CamProfile"]


class CamProfile(RecordsArguments):
    """A closed curve about a cam's centre, in polar form: ``r(phi)`` [m] for ``phi`` [rad] in
    the cam's frame, one turn, as a periodic cubic spline through the given points (so the
    radius, slope and curvature are continuous all round).

    For a point or roller follower it is the pitch curve (the path of the roller's centre on
    the cam: the cam's surface offset by the roller radius); for a flat-faced follower, the
    cam's support function (the distance from the centre to the tangent whose outward normal
    points at ``phi``), which for a follower translating along its face's normal is the base
    radius plus the lift; for a :class:`~mbd3d.Cam` shape, the cam's surface (from a pitch
    curve: :meth:`surface`).

    Parameters
    ----------
    angles : array_like
        Strictly increasing, within one turn (the last less than the first plus 2 pi) [rad].
    radii : array_like
        Positive [m], one per angle.
    """

    def __init__(self, angles: Any, radii: Any):
        self.angles = angles
        self.radii = radii
        try:
            phi = np.asarray(angles, dtype=float)
            r = np.asarray(radii, dtype=float)
        except (TypeError, ValueError):
            raise ModelError(f"cam profile: angles and radii must be numbers, got {angles!r} "
                             f"and {radii!r}") from None
        if phi.ndim != 1 or r.shape != phi.shape or len(phi) < 4:
            raise ModelError(f"cam profile: give at least 4 angles and as many radii, got "
                             f"shapes {phi.shape} and {r.shape}")
        if not (np.all(np.isfinite(phi)) and np.all(np.isfinite(r))):
            raise ModelError("cam profile: angles and radii must be finite")
        if not (np.all(np.diff(phi) > 0) and phi[-1] < phi[0] + 2 * math.pi):
            raise ModelError("cam profile: angles must increase strictly and span less than one "
                             "turn (the curve closes itself)")
        if not np.all(r > 0):
            raise ModelError(f"cam profile: radii must be positive, the smallest is {r.min()!r}")
        # imported here: SciPy's interpolation takes a third of mbd3d's import time, and
        # only cam profiles use it
        from scipy.interpolate import CubicSpline

        self._spline = CubicSpline(np.append(phi, phi[0] + 2 * math.pi), np.append(r, r[0]),
                                   bc_type="periodic")

    @classmethod
    def sampled(cls, function: Callable[[np.ndarray], np.ndarray], points: int = 720
                ) -> "CamProfile":
        """The profile through ``points`` samples, evenly spaced over a turn from 0, of
        ``function(phi)`` [m] (vectorised over an array of angles).

        Parameters
        ----------
        function : callable
            ``r(phi)`` [m] of the angle [rad], vectorised.
        points : int
            The number of samples over a turn.
        """
        phi = np.linspace(0.0, 2 * math.pi, int(points), endpoint=False)
        return cls(phi, np.asarray(function(phi), dtype=float))

    def __call__(self, phi: Any, derivative: int = 0) -> np.ndarray:
        """``r`` [m] (or its ``derivative``-th derivative) at the angles ``phi`` [rad]."""
        return self._spline(np.asarray(phi, dtype=float), derivative, extrapolate="periodic")

    def table(self) -> np.ndarray:
        """The curve as the compiled rows read it (:mod:`mbd3d.numerics.compiled.curves`):
        the knots, then the coefficients of each interval in ascending powers."""
        return np.concatenate([self._spline.x, self._spline.c[::-1].T.ravel()])

    def offset(self, phi: Any, distance: float) -> np.ndarray:
        """The points ``(m, 2)`` [m] of the curve at the angles ``phi`` [rad] moved by
        ``distance`` [m] along its outward normal ``(r e - r' e_perp) / sqrt(r^2 + r'^2)``
        (``e`` the radial unit vector, ``e_perp`` it turned by 90 degrees): with ``-d``, the
        surface of a cam whose pitch curve this is for a roller of radius ``d``.

        Parameters
        ----------
        phi : array_like
            Angles [rad].
        distance : float
            Along the outward normal [m].
        """
        phi = np.asarray(phi, dtype=float)
        r, slope = self(phi), self(phi, 1)
        e = np.column_stack([np.cos(phi), np.sin(phi)])
        across = np.column_stack([-e[:, 1], e[:, 0]])
        normal = r[:, None] * e - slope[:, None] * across
        normal /= np.linalg.norm(normal, axis=1)[:, None]
        return r[:, None] * e + float(distance) * normal

    def surface(self, roller_radius: float, points: int = 720) -> "CamProfile":
        """The cam's surface for a roller of ``roller_radius`` [m] whose centre runs on this
        pitch curve: the curve moved inwards by the radius, sampled at ``points`` angles
        evenly spaced from 0 and interpolated again in polar form (the shape a
        :class:`~mbd3d.Cam` contact touches).

        Parameters
        ----------
        roller_radius : float
            [m], >= 0.
        points : int
            The number of samples over a turn.
        """
        rho = float(roller_radius)
        if not (math.isfinite(rho) and rho >= 0.0):
            raise ModelError(f"cam profile: roller_radius must be finite and >= 0, got "
                             f"{roller_radius!r}")
        phi = np.linspace(0.0, 2 * math.pi, int(points), endpoint=False)
        return _polar(self.offset(phi, -rho), f"a roller of {rho:g} m on this pitch curve")

    def envelope(self, points: int = 720) -> "CamProfile":
        """The cam's surface whose support function this is (a flat-faced follower's
        profile): the envelope ``h e + h' e_perp`` of the tangent lines, sampled at ``points``
        angles evenly spaced from 0 and interpolated again in polar form.

        Parameters
        ----------
        points : int
            The number of samples over a turn.
        """
        phi = np.linspace(0.0, 2 * math.pi, int(points), endpoint=False)
        # only a convex cam has a support function: its radius of curvature h + h'' > 0
        curvature_radius = self(phi) + self(phi, 2)
        if curvature_radius.min() <= 0.0:
            k = int(np.argmin(curvature_radius))
            raise ModelError(f"cam profile: h + h'' = {curvature_radius[k]:.4g} m at "
                             f"{math.degrees(phi[k]):.4g} deg: not the support function of a "
                             "convex cam, whose envelope a flat face touches")
        return _polar(self.envelope_points(phi), "this support function's envelope")

    def envelope_points(self, phi: Any) -> np.ndarray:
        """The points ``(m, 2)`` [m] where the tangent lines with outward normals at the
        angles ``phi`` [rad] touch the cam whose support function ``h`` this is: ``h e + h'
        e_perp``.

        Parameters
        ----------
        phi : array_like
            The tangent lines' outward normals' angles [rad].
        """
        phi = np.asarray(phi, dtype=float)
        e = np.column_stack([np.cos(phi), np.sin(phi)])
        across = np.column_stack([-e[:, 1], e[:, 0]])
        return self(phi)[:, None] * e + self(phi, 1)[:, None] * across


def _polar(xy: np.ndarray, what: str) -> CamProfile:
    """The closed curve through the points ``xy`` (m, 2), in order round the centre, as a
    profile in polar form; refused where it is not one (undercut)."""
    angles = np.unwrap(np.arctan2(xy[:, 1], xy[:, 0]))
    radii = np.hypot(xy[:, 0], xy[:, 1])
    if not (np.all(np.diff(angles) > 0) and angles[-1] < angles[0] + 2 * math.pi
            and np.all(radii > 0)):
        raise ModelError(f"cam profile: {what} is not a curve in polar form about the "
                         "centre (an undercut cam, or a roller larger than the cam)")
    return CamProfile(angles, radii)
