"""Planar rigid bodies: coordinates ``(Rx, Ry, theta)`` of the centre of mass and the body angle.

What belongs here: the planar body type, which hands the rest of mbd3d its rotation matrices,
axes and angular velocities; the spatial one is :mod:`mbd3d.model.spatial`. Whatever is the same
physics in the plane and in space is written once elsewhere, against that interface.
"""

from mbd3d.planar.body import PlanarBody

__all__ = ["PlanarBody"]
