"""The rigid contacts' events as a recording shows them on the simulated time line: each
impact as the point struck (until the next) and a line of text under "Impacts and rests" with
the contact, its gap's rates, the impulse and the energy lost; each rest and release (a
contact held closed at rest, :mod:`mbd3d.analyses.resting`) as a line under it.
"""

from __future__ import annotations

import numpy as np

from mbd3d.io.results import Results
from mbd3d.viewer.timeline import _rerun, sim_time_column

__all__ = ["log_contact_events"]


def log_contact_events(stream, results: Results, size: float) -> None:
    """Send ``results.stats["impacts"]`` and ``["rests"]`` to ``stream`` (entities
    ``world/impacts``, ``impacts`` and ``impacts/rests``); ``size``: the model's size [m],
    which the struck points' radii follow."""
    rr = _rerun()
    impacts = results.stats.get("impacts") or []
    if impacts:
        times = [sim_time_column(np.array([i["time"] for i in impacts]))]
        stream.send_columns("world/impacts", indexes=times, columns=rr.Points3D.columns(
            positions=np.array([i["point"] for i in impacts]),
            radii=np.full(len(impacts), 0.03 * size), labels=[i["contact"] for i in impacts]))
        text = [f"impact at {i['contact']}: closing at {-i['rate_before']:.6g}, opening at "
                f"{i['rate_after']:.6g}, impulse {i['impulse']:.6g}" + _rubbed(i)
                + f", energy lost {i['energy_lost']:.6g} J" for i in impacts]
        stream.send_columns("impacts", indexes=times, columns=rr.TextLog.columns(
            text=text, level=["INFO"] * len(impacts)))
    rests = results.stats.get("rests") or []
    if rests:
        said = {"rest": "comes to rest (its bounces took {:.6g} J)", "release": "lets go",
                "stick": "sticks (its slip took {:.6g} J)", "slip": "slips"}
        text = [f"{', '.join(r['contacts'])} " + said[r["event"]].format(r["energy_lost"])
                for r in rests]
        stream.send_columns("impacts/rests",
                            indexes=[sim_time_column(np.array([r["time"] for r in rests]))],
                            columns=rr.TextLog.columns(text=text, level=["INFO"] * len(rests)))


def _rubbed(impact: dict) -> str:
    """The friction impulse's size in an impact's text, where it has one (files written
    before impacts had friction have none)."""
    size = float(np.linalg.norm(impact.get("friction_impulse", [0.0, 0.0, 0.0])))
    return f", friction impulse {size:.6g}" if size > 0.0 else ""
