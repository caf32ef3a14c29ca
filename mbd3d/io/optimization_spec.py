"""A model file's ``optimize:`` section: what ``mbd3d optimize`` varies, within which bounds,
and what it minimises (:mod:`mbd3d.optimization`)::

    optimize:
      vary:                              # parameters (mbd3d.parameters names) and bounds
        bodies.rod.mass: [0.5, 5.0]
        bodies.slider.mass: [0.5, 10.0]
      fit: torque.csv                    # measurements, relative to this file ...
      # minimize: peak:motor.effort      # ... or a statistic of a results column
      starts: 4                          # optional: how many starts (default 4)
      seed: 0                            # optional: of the starts spread over the bounds

The command line's ``--vary``, ``--fit``/``--minimize``, ``--starts`` and ``--seed`` replace the
section's. Mistakes are reported with the file, the line and the field.
"""

from __future__ import annotations

import math
import os
import pathlib
from dataclasses import dataclass
from typing import Any

__all__ = ["OptimizationSpec", "read_optimization"]

_FIELDS = ("vary", "fit", "minimize", "starts", "seed")


@dataclass(frozen=True)
class OptimizationSpec:
    """A file's optimisation: ``vary`` (name -> (lower, upper)), ``fit`` (the measurements'
    absolute path) or ``minimize`` ("STATISTIC:COLUMN"), ``starts`` and ``seed``."""

    vary: dict
    fit: str | None = None
    minimize: str | None = None
    starts: int = 4
    seed: int = 0

    def entry(self, folder: str | os.PathLike) -> dict:
        """The section as a file in ``folder`` writes it (``fit`` relative to it)."""
        entry: dict = {"vary": {name: list(pair) for name, pair in self.vary.items()}}
        if self.fit is not None:
            entry["fit"] = pathlib.Path(os.path.relpath(self.fit, folder)).as_posix()
        else:
            entry["minimize"] = self.minimize
        return {**entry, "starts": self.starts, "seed": self.seed}


def read_optimization(reader: Any, entry: Any) -> OptimizationSpec:
    """The ``optimize`` section ``entry`` of the file ``reader`` reads (its ``error(where,
    message)`` names the file and the line, its ``folder`` resolves ``fit``)."""
    where = ("optimize",)
    if not isinstance(entry, dict):
        raise reader.error(where, f"must be a mapping (vary, fit or minimize, starts, seed), "
                                  f"got {entry!r}")
    for key in entry:
        if key not in _FIELDS:
            raise reader.error(where + (key,), f"unknown field (fields: {', '.join(_FIELDS)})")
    vary = entry.get("vary")
    if not isinstance(vary, dict) or not vary:
        raise reader.error(where + ("vary",), "give the parameters to vary and their bounds, "
                                              "e.g. 'bodies.rod.mass: [0.5, 5.0]'")
    bounds = {}
    for name, pair in vary.items():
        if not (isinstance(pair, list) and len(pair) == 2 and all(
                _is_number(v) for v in pair) and pair[0] < pair[1]):
            raise reader.error(where + ("vary", name), f"bounds must be [lower, upper], two "
                                                       f"finite numbers, got {pair!r}")
        bounds[str(name)] = (float(pair[0]), float(pair[1]))
    if ("fit" in entry) == ("minimize" in entry):
        raise reader.error(where, "give either fit (a CSV file of measurements) or minimize "
                                  "(STATISTIC:COLUMN, e.g. peak:motor.effort)")
    for key in ("fit", "minimize"):
        if key in entry and not isinstance(entry[key], str):
            raise reader.error(where + (key,), f"must be text, got {entry[key]!r}")
    counts = {}
    for key, least in (("starts", 1), ("seed", 0)):
        value = entry.get(key, OptimizationSpec.__dataclass_fields__[key].default)
        if type(value) is not int or value < least:
            raise reader.error(where + (key,), f"must be a whole number >= {least}, got "
                                               f"{value!r}")
        counts[key] = value
    fit = os.path.normpath(reader.folder / entry["fit"]) if "fit" in entry else None
    return OptimizationSpec(bounds, fit, entry.get("minimize"), **counts)


def _is_number(value: Any) -> bool:
    return (isinstance(value, (int, float)) and not isinstance(value, bool)
            and math.isfinite(value))
