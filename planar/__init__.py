"""Planar rigid bodies: coordinates ``(Rx, Ry, theta)`` of the centre of mass and the body angle."""

from mbd3d.planar.body import PlanarBody

__all__ = ["PlanarBody"]
