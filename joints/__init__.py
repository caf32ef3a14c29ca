"""The joint and driver library of mbd3d.

Every joint is a composition of the constraint primitives of :mod:`mbd3d.model.primitives`, written
against the body kinematics, so the same classes serve every body type that supports them.

- :class:`Revolute`: pin (point coincidence).
- :class:`Prismatic`: slider along an axis.
- :class:`Fixed`: weld (also to the ground).
- :class:`Distance`: massless rigid link between two points.
- :class:`PointOnLine`: a point on a line (spatial), the pin in a slot (planar).
- Spatial only: :class:`Spherical`, :class:`Universal`, :class:`Cylindrical`, :class:`Planar`,
  :class:`PointOnPlane`.
- Higher pairs: :class:`GearPair` (planar external and internal; spatial spur and bevel),
  and, planar, :class:`RackPinion`, :class:`CamFollower` (point or roller on a
  :class:`CamProfile`), :class:`FlatFaceFollower`, :class:`RollingDisc` (on a straight
  track); spatial, :class:`RollingDiscOnPlane` (nonholonomic).
- Drivers: :class:`CoordinateDriver`, :class:`RotationDriver`, :class:`TranslationDriver`.

What belongs here: constraint elements a user adds to a model, each a composition of
primitives; a new kind of constraint row belongs in :mod:`mbd3d.model.primitives` and
:mod:`mbd3d.numerics.compiled.rows`, and the joint that uses it here.
"""

from mbd3d.joints.cams import CamFollower, CamProfile, FlatFaceFollower
from mbd3d.joints.distance import Distance
from mbd3d.joints.drivers import CoordinateDriver, RotationDriver, TranslationDriver
from mbd3d.joints.fixed import Fixed
from mbd3d.joints.gears import GearPair, RackPinion
from mbd3d.joints.prismatic import Prismatic
from mbd3d.joints.revolute import Revolute
from mbd3d.joints.rolling import RollingDisc, RollingDiscOnPlane
from mbd3d.joints.spatial_joints import (Cylindrical, Planar, PointOnLine, PointOnPlane, Spherical,
                                         Universal)

__all__ = ["Revolute", "Prismatic", "Fixed", "Distance", "CoordinateDriver", "RotationDriver",
           "TranslationDriver", "Spherical", "Universal", "Cylindrical", "Planar", "PointOnLine",
           "PointOnPlane", "GearPair", "RackPinion", "CamFollower", "FlatFaceFollower",
           "CamProfile", "RollingDisc", "RollingDiscOnPlane"]
