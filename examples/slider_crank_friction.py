"""Slider-crank with friction in its pins and its rail: how much more the motor must give.

Nikravesh's slider-crank (crank 0.12 m, rod 0.26 m, slider 4 kg) driven at a constant
300 rpm, with Coulomb friction (mu = 0.1) in its three pins (10 mm journals) and in the rail
(mu = 0.15). Friction depends on the joints' reactions, which depend on the friction: mbd3d
solves the two together at every time point. The table shows the motor torque with and
without friction, and the check: the motor's power must equal the rate of the mechanism's
energy plus the power the frictions take, each from its joint's own rate. Recorded to
slider_crank_friction.rrd: rerun slider_crank_friction.rrd

Run: python examples/slider_crank_friction.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import math

import numpy as np

import mbd3d as mb
from mbd3d.joints import Prismatic, Revolute, RotationDriver
from mbd3d.mechanisms import slider_crank_positions
from mbd3d.viewer import check_recording_first, record, run_script

SPEED = 300 * 2 * math.pi / 60  # rad/s
PIN_RADIUS = 0.010  # m
PINS, RAIL = 0.10, 0.15  # friction coefficients


def build(friction: bool = True) -> mb.Model:
    """The slider-crank at 300 rpm, with or without friction (examples/models/
    slider_crank_friction.yaml as a file)."""
    crank_angle = math.radians(65.0)
    a, rod_angle, pin_b = slider_crank_positions(crank_angle, 0.12, 0.26)
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81),
                        name="slider-crank with friction" if friction else "slider-crank")
    crank = b.add_body("crank", mass=1.0, inertia=0.001, position=a / 2, angle=crank_angle)
    rod = b.add_body("rod", mass=2.0, inertia=0.01, position=(a + pin_b) / 2, angle=rod_angle)
    slider = b.add_body("slider", mass=4.0, inertia=0.02, position=pin_b)
    pins = [b.add(Revolute("O", b.ground, crank, at=(0.0, 0.0))),
            b.add(Revolute("A", crank, rod, at=a)),
            b.add(Revolute("B", rod, slider, at=pin_b))]
    rail = b.add(Prismatic("rail", b.ground, slider, axis=(1.0, 0.0)))
    b.add(RotationDriver("motor", pins[0], motion=mb.Ramp(crank_angle, SPEED)))
    if friction:
        for pin in pins:
            b.add(mb.JointFriction(f"{pin.name} friction", pin, PINS, pin_radius=PIN_RADIUS))
        b.add(mb.JointFriction("rail friction", rail, RAIL))
    return b.build()


def energy_rate(res: mb.Results) -> np.ndarray:
    """d/dt of kinetic plus potential energy [W], from the bodies' motion."""
    total = np.zeros(len(res))
    for body in res.model.bodies:
        h = res.body(body.name)
        total += body.mass * np.einsum("ki,ki->k", h.velocity,
                                       h.acceleration - res.model.gravity)
        total += body.inertia * h.angular_velocity * h.angular_acceleration
    return total


def friction_power(res: mb.Results) -> np.ndarray:
    """Power the frictions take from the motion [W]: each torque or force times its joint's
    relative rate (negative: friction opposes the motion)."""
    power = res.friction("rail friction") * res.joint("rail").displacement_rate
    for pin in "OAB":
        power += res.friction(f"{pin} friction") * res.joint(pin).angle_rate
    return power


@check_recording_first
def main(n_points: int = 13, rrd: str | None = None, show: bool = False) -> mb.Results:
    t = np.linspace(0.0, 2 * math.pi / SPEED, n_points)  # one revolution
    res = mb.inverse_dynamics(build(), t)
    plain = mb.inverse_dynamics(build(friction=False), t)
    torque = res.driver("motor").effort
    balance = torque * SPEED - energy_rate(res) + friction_power(res)
    print(mb.format_table({
        "crank [deg]": np.degrees(res.body("crank").angle) % 360,
        "torque, no friction [N m]": plain.driver("motor").effort,
        "torque [N m]": torque,
        "O friction [N m]": res.friction("O friction"),
        "rail friction [N]": res.friction("rail friction"),
        "friction power [W]": friction_power(res),
        "balance [W]": balance,
    }))
    lost = -np.trapezoid(friction_power(res), t)
    print(f"\npower balance (motor - energy rate - friction): largest "
          f"{np.max(np.abs(balance)):.1e} W of {np.max(np.abs(torque * SPEED)):.3g} W")
    print(f"energy lost to friction per revolution: {lost:.4f} J (trapezoid over "
          f"{n_points} points)")
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res


if __name__ == "__main__":
    run_script(lambda **kw: main(n_points=73, **kw), __doc__, "slider_crank_friction.rrd")
