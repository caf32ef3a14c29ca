"""A car's bevel-gear differential in a turn: the speeds split, the torque does not.

The differential's cage turns on the axle at 20 rad/s, driven by the engine. It carries a
spider gear on a pin across the axle, meshing with the left and right side gears (16 and 10
teeth of module 4 mm, straight bevel gears at right angles). In a left turn the road makes
the inner (left) wheel turn at 18 rad/s; the right wheel then turns at 2 x 20 - 18 = 22 rad/s
and the spider spins on its pin. The right wheel's road resistance is 4 N m. An open
differential splits the torque equally whatever the speeds, so the spider pushes both side
gears with the same torque, the left road must hold the left wheel with 4 N m too, and the
engine gives 8 N m: its power goes to the wheels, 72 W and 88 W, as the speeds split.
(Real differentials have two or more spiders; one gives the same motion and torques without
redundant meshes. Gravity is left out: the spider's weight turning with the cage would add a
torque of its own.)

Recorded to differential.rrd (pitch circles and tooth forces drawn): rerun differential.rrd

Run: python examples/differential.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import math

import numpy as np

import mbd3d as mb
from mbd3d.joints import GearPair, Revolute, RotationDriver
from mbd3d.viewer import check_recording_first, record, run_script

MODULE = 0.004  # m
R_SIDE, R_SPIDER = MODULE * 16 / 2, MODULE * 10 / 2  # pitch radii at the same cone distance
CAGE_SPEED, LEFT_SPEED = 20.0, 18.0  # rad/s
ROAD = 4.0  # N m, the right road's resistance
AXLE, PIN = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])


def disc(mass: float, radius: float) -> np.ndarray:
    """Centroidal inertia [kg m^2] of a thin disc whose axis is the body x axis."""
    return mass * radius ** 2 * np.diag([0.5, 0.25, 0.25])


def build() -> mb.Model:
    """Cage, side gears and spider, apex at the origin (examples/models/differential.yaml)."""
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, 0.0), name="differential")
    # the side gears' pitch circles are centred a spider radius from the apex, the spider's a
    # side-gear radius: the pitch cones meet there
    sides = {"left": -R_SPIDER * AXLE, "right": R_SPIDER * AXLE}
    cage = b.add_body("cage", mass=2.0, inertia=np.diag([4e-3, 3e-3, 3e-3]),
                      position=(0.0, 0.0, 0.0))
    gears = {side: b.add_body(side, mass=0.6, inertia=disc(0.6, R_SIDE), position=centre)
             for side, centre in sides.items()}
    spider = b.add_body("spider", mass=0.2, inertia=disc(0.2, R_SPIDER),
                        position=R_SIDE * PIN, orientation=mb.rotations.frame_along(PIN))
    engine = b.add(Revolute("cage bearing", b.ground, cage, at=(0.0, 0.0, 0.0), axis=AXLE))
    axles = {side: b.add(Revolute(f"{side} axle", b.ground, gears[side], at=centre, axis=AXLE))
             for side, centre in sides.items()}
    b.add(Revolute("spider pin", cage, spider, at=R_SIDE * PIN, axis=PIN))
    for side in sides:
        b.add(GearPair(f"{side} mesh", gears[side], spider, radius_i=R_SIDE, radius_j=R_SPIDER,
                       axis_i=AXLE, axis_j=PIN))
    b.add(RotationDriver("engine", engine, motion=mb.Polynomial([0.0, CAGE_SPEED])))
    b.add(RotationDriver("left road", axles["left"], motion=mb.Polynomial([0.0, LEFT_SPEED])))
    b.add(mb.Torque("right road", gears["right"], -ROAD * AXLE))
    return b.build()


@check_recording_first
def main(n_points: int = 9, rrd: str | None = None, show: bool = False) -> mb.Results:
    model = build()
    print(mb.mobility(model), "\n")
    res = mb.inverse_dynamics(model, np.linspace(0.0, 0.5, n_points))
    speed = {name: res.body(name).angular_velocity @ AXLE for name in ("cage", "left", "right")}
    # the torque each mesh puts on its side gear about the axle
    split = {side: res.joint(f"{side} mesh").reaction(on=side).moment @ AXLE
             for side in ("left", "right")}
    engine = res.driver("engine").effort
    left_road = res.driver("left road").effort
    tooth = res.joint("left mesh").mesh_force
    print(mb.format_table({
        "t [s]": res.t,
        "right [rad/s]": speed["right"],
        "spider spin [rad/s]": res.joint("spider pin").angle_rate,
        "left mesh [N m]": split["left"],
        "right mesh [N m]": split["right"],
        "engine [N m]": engine,
        "tooth force [N]": tooth.tooth,
    }))
    print(f"\nright wheel {speed['right'].min():.12f} .. {speed['right'].max():.12f} rad/s; "
          f"2 x cage - left = {2 * CAGE_SPEED - LEFT_SPEED:.12f} rad/s")
    print(f"spider on its pin: {res.joint('spider pin').angle_rate[0]:.12f} rad/s; "
          f"(left - cage) r_side/r_spider = {(LEFT_SPEED - CAGE_SPEED) * R_SIDE / R_SPIDER:.12f}")
    unequal = np.max(np.abs(split["left"] - split["right"]))
    print(f"torque split: the two meshes differ by {unequal:.1e} N m at most; the left road "
          f"holds {-left_road[0]:.12f} N m against the right's {ROAD}")
    power = engine * speed["cage"] + left_road * speed["left"] - ROAD * speed["right"]
    print(f"power: engine {engine[0] * CAGE_SPEED:.9f} W = left {-left_road[0] * LEFT_SPEED:.9f} "
          f"W + right {ROAD * speed['right'][0]:.9f} W, mismatch {np.max(np.abs(power)):.1e} W")
    thrust = -res.joint("left mesh").mesh_force.force @ AXLE  # on the left gear, along the axle
    delta = math.atan2(R_SIDE, R_SPIDER)  # the side gear's pitch-cone angle
    print(f"left side gear's thrust {np.abs(thrust).max():.9f} N along the axle = F_t tan(20 deg)"
          f" sin(delta) = {abs(tooth.tangential[0]) * math.tan(math.radians(20)) * math.sin(delta):.9f}"
          " N (Shigley)")
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res


if __name__ == "__main__":
    run_script(main, __doc__, "differential.rrd")
