"""Planar rigid bodies: coordinates ``(Rx, Ry, theta)`` of the centre of mass and the body angle."""

from planar.body import PlanarBody

__all__ = ["PlanarBody"]
