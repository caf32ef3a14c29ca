"""The joints' own coordinates as plots: a hinge's angle, a slide's displacement, one line
per joint coordinate (a robot's six angles, not its bodies' eighteen positions), in the
recording's ``plots/joints`` panel.
"""

from __future__ import annotations

import math

import numpy as np

from mbd3d.joints import Cylindrical, Planar, Prismatic, Revolute
from mbd3d.model.builder import Model

__all__ = ["JointPlots"]

#: the coordinates each joint type is plotted with, and their units
_COORDINATES = ((Cylindrical, (("angle", "rad"), ("displacement", "m"))),
                (Planar, (("angle", "rad"),)),
                (Revolute, (("angle", "rad"),)),
                (Prismatic, (("displacement", "m"),)))


class JointPlots:
    """The coordinates of the first ``limit`` joints that have them, sent block by block;
    an angle stays continuous from one block to the next (each block's own history starts
    within half a turn of zero)."""

    def __init__(self, model: Model, limit: int):
        self.items = []
        for element in model.joints:
            if element.is_driver:
                continue
            for kind, coordinates in _COORDINATES:
                if isinstance(element, kind):
                    self.items += [(element.name, q, unit) for q, unit in coordinates]
                    break
        self.items = self.items[:limit]
        self._last: dict[tuple[str, str], float] = {}

    def log_styles(self, stream, rr, part) -> None:
        for name, quantity, unit in self.items:
            stream.log(f"plots/joints/{part(name)}/{quantity}",
                       rr.SeriesLines(names=f"{name} {quantity} [{unit}]"), static=True)

    def send(self, stream, rr, part, block, times: list) -> None:
        for name, quantity, _ in self.items:
            values = np.array(getattr(block.joint(name), quantity), dtype=float)
            key = (name, quantity)
            if quantity == "angle" and key in self._last and len(values):
                # whole turns between the blocks' starts
                turns = round((self._last[key] - values[0]) / (2.0 * math.pi))
                values += 2.0 * math.pi * turns
            if len(values):
                self._last[key] = float(values[-1])
            stream.send_columns(f"plots/joints/{part(name)}/{quantity}", indexes=times,
                                columns=rr.Scalars.columns(scalars=values))
