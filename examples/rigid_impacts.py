"""Rigid impacts: a rod dropped tilted onto a floor, every touch an impulse.

A rod 0.8 m long (3 kg) falls from 0.5 m, tilted 30 degrees, onto a rigid floor with a
restitution of 0.5; a small circle at each end is its contact (mb.RigidImpact). Each touch is
an impact solved by Newton's law on the whole rod at once: the end's closing speed turns
into half of it opening, and the impulse P follows from the rod's mass and inertia alone,
P = (1 + e) v / (1/m + (a cos(angle))^2 / I) for an end at lever a cos(angle) from the centre.
The rod rocks from end to end, ever lower. Where an end opens slower than its rest speed while
gravity presses it down, it has come to rest: it is held on the floor (the rod pivots about it)
until the other end's impact lifts it again. At last both ends rest, each carrying half the
rod's weight. Recorded to rigid_impacts.rrd: rerun rigid_impacts.rrd

Run: python examples/rigid_impacts.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import math

import numpy as np

import mbd3d as mb
from mbd3d.viewer import check_recording_first, record, run_script

G, HALF, MASS, TILT, RESTITUTION = 9.81, 0.4, 3.0, math.radians(30.0), 0.5
INERTIA = MASS * (2 * HALF) ** 2 / 12


def build() -> mb.Model:
    """The rod's centre 0.5 m above the floor y = 0, its left end lowest."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G), name="rod drop")
    rod = b.add_body("rod", mass=MASS, inertia=INERTIA, position=(0.0, 0.5), angle=TILT)
    floor = mb.Plane(b.ground, normal=(0.0, 1.0))
    for name, side in (("left end", -1.0), ("right end", 1.0)):
        b.add(mb.Contact(name, mb.Sphere(rod, 1e-3, point=(side * HALF, 0.0)), floor,
                         law=mb.RigidImpact(restitution=RESTITUTION, rest_speed=0.01)))
    return b.build()


@check_recording_first
def main(n_points: int = 401, rrd: str | None = None, show: bool = False) -> mb.Results:
    res = mb.forward_dynamics(build(), np.linspace(0.0, 2.0, n_points), method="DOP853",
                              rtol=1e-10, atol=1e-12)
    impacts = res.stats["impacts"]
    print(mb.format_table({
        "t [s]": [i["time"] for i in impacts],
        "end": [i["contact"] for i in impacts],
        "closing [m/s]": [-i["rate_before"] for i in impacts],
        "opening [m/s]": [i["rate_after"] for i in impacts],
        "impulse [N s]": [i["impulse"] for i in impacts],
        "energy lost [J]": [i["energy_lost"] for i in impacts],
    }, precision=6))
    first = impacts[0]
    lever = HALF * math.cos(TILT)  # the right end is higher: it tilts back at the first touch
    closed_form = (1 + RESTITUTION) * -first["rate_before"] / (1 / MASS + lever ** 2 / INERTIA)
    print(f"\nfirst impulse {first['impulse']:.9f} N s, closed form {closed_form:.9f} N s")
    events = {"rest": "comes to rest", "release": "lets go"}
    for rest in res.stats["rests"]:
        print(f"{rest['time']:.6f} s: {', '.join(rest['contacts'])} {events[rest['event']]}")
    forces = res.contacts().normal_force[-1]
    print(f"at {res.t[-1]:g} s the ends carry {forces[0]:.9f} N and {forces[1]:.9f} N, "
          f"half the weight {MASS * G / 2:.9f} N")
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res


if __name__ == "__main__":
    run_script(main, __doc__, "rigid_impacts.rrd")
