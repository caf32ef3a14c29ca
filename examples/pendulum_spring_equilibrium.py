"""Static equilibrium: a bar on a pin with a torsion spring, under gravity.

A 2 kg bar, 0.8 m long, pinned at one end; a torsion spring at the pin is relaxed with the bar
horizontal. Where does the bar rest, is that rest stable, and what holds it? For three spring
stiffnesses the table shows the resting angle, the pin's reaction and the stability (from the
reduced stiffness on the motion the pin allows), and checks the angle against the balance of
moments k theta = -m g (L/2) cos(theta). Then a motor on the pin holds the bar still at angles
along a quarter turn: the static torque it needs at each.

Recorded to pendulum_spring_equilibrium.rrd (the bar held along the quarter turn, with the
motor's torque): rerun pendulum_spring_equilibrium.rrd

Run: python examples/pendulum_spring_equilibrium.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import math

import numpy as np

import mbd3d as mb
from mbd3d.joints import Revolute, RotationDriver
from mbd3d.viewer import check_recording_first, record, run_script

MASS, LENGTH, GRAVITY = 2.0, 0.8, 9.81


def pendulum(stiffness: float, motor: bool = False) -> mb.Model:
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -GRAVITY),
                        name=f"bar on a spring of {stiffness} N m/rad")
    bar = b.add_body("bar", mass=MASS, inertia=MASS * LENGTH**2 / 12, position=(LENGTH / 2, 0.0))
    pin = b.add(Revolute("O", b.ground, bar, at=(0.0, 0.0)))
    b.add(mb.RotationalSpringDamper("spring", body_i=b.ground, body_j=bar, stiffness=stiffness))
    if motor:  # from 0 to -90 degrees in one second
        b.add(RotationDriver("motor", pin, motion=mb.Ramp(0.0, -math.pi / 2)))
    return b.build()


@check_recording_first
def main(n_points: int = 7, rrd: str | None = None, show: bool = False) -> list[mb.Results]:
    rests = []
    for k in (2.0, 10.0, 50.0):
        res = mb.static_equilibrium(pendulum(k))
        theta = res.body("bar").angle[0]
        balance = k * theta + MASS * GRAVITY * LENGTH / 2 * math.cos(theta)
        force = res.joint("O").reaction(on="bar").force[0]
        print(f"k = {k:5.1f} N m/rad: rests at {math.degrees(theta):8.3f} deg "
              f"({res.stats['stability'][0]}), pin force on the bar ({force[0]:.3f}, "
              f"{force[1]:.3f}) N, moment balance {balance:.1e} N m")
        rests.append(res)
    held = mb.static_equilibrium(pendulum(10.0, motor=True), np.linspace(0.0, 1.0, n_points))
    print("\nHeld still by a motor on the pin (spring of 10 N m/rad):")
    print(mb.format_table({"angle [deg]": np.degrees(held.body("bar").angle),
                           "motor torque [N m]": held.driver("motor").effort}))
    if rrd is not None:
        record(held, rrd, overwrite=True, show=show)
    return rests + [held]


if __name__ == "__main__":
    run_script(main, __doc__, "pendulum_spring_equilibrium.rrd")
