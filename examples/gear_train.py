"""Planetary gear train: speed ratio by Willis's formula, motor torque by the power balance.

A sun gear (pitch radius 40 mm) is driven by a motor that runs up from 0 to 100 rad/s in
0.5 s; a planet (25 mm) on a carrier rolls inside a fixed ring (90 mm), and the carrier, the
output, drives a load of 5 N m. Willis's formula gives the reduction with the ring held:
omega_carrier / omega_sun = r_sun / (r_sun + r_ring). The motor's power must equal the load's
plus the rate of the kinetic energy, summed over the bodies from their own velocities and
accelerations. The meshes' tangential and tooth forces (20 degree pressure angle) are printed
too. Recorded to gear_train.rrd: rerun gear_train.rrd

Run: python examples/gear_train.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import numpy as np

import mbd3d as mb
from mbd3d.joints import GearPair, Revolute, RotationDriver
from mbd3d.viewer import check_recording_first, record, run_script

R_SUN, R_PLANET = 0.040, 0.025
R_RING = R_SUN + 2 * R_PLANET
LOAD = 5.0  # N m, against the carrier's turning


def build() -> mb.Model:
    """Sun, one planet and its carrier; the ring is the ground (examples/models/gear_train.yaml
    as a file)."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0), name="planetary gear train")
    sun = b.add_body("sun", mass=0.4, inertia=0.4 * R_SUN ** 2 / 2, position=(0.0, 0.0))
    carrier = b.add_body("carrier", mass=0.6, inertia=1.5e-3, position=(0.0, 0.0))
    centre = (R_SUN + R_PLANET, 0.0)
    planet = b.add_body("planet", mass=0.15, inertia=0.15 * R_PLANET ** 2 / 2, position=centre)
    shaft = b.add(Revolute("sun shaft", b.ground, sun, at=(0.0, 0.0)))
    b.add(Revolute("output shaft", b.ground, carrier, at=(0.0, 0.0)))
    b.add(Revolute("planet pin", carrier, planet, at=centre))
    b.add(GearPair("sun-planet", sun, planet, radius_i=R_SUN, radius_j=R_PLANET))
    b.add(GearPair("planet-ring", planet, b.ground, radius_i=R_PLANET, radius_j=R_RING,
                   internal=True, center_j=(0.0, 0.0)))
    # the sun's angle: 0 -> 100 rad/s in 0.5 s at constant acceleration, then steady
    b.add(RotationDriver("motor", shaft, motion=mb.Polynomial([0.0, 0.0, 100.0])))
    b.add(mb.Torque("load", carrier, -LOAD))
    return b.build()


def kinetic_energy_rate(res: mb.Results) -> np.ndarray:
    """d/dt of the kinetic energy [W], from every body's velocities and accelerations."""
    total = np.zeros(len(res))
    for body in res.model.bodies:
        h = res.body(body.name)
        total += body.mass * np.einsum("ki,ki->k", h.velocity, h.acceleration)
        total += body.inertia * h.angular_velocity * h.angular_acceleration
    return total


@check_recording_first
def main(n_points: int = 11, rrd: str | None = None, show: bool = False) -> mb.Results:
    model = build()
    print(mb.mobility(model), "\n")
    res = mb.inverse_dynamics(model, np.linspace(0.0, 0.5, n_points))
    sun, carrier = res.body("sun").angular_velocity, res.body("carrier").angular_velocity
    torque = res.driver("motor").effort
    willis = R_SUN / (R_SUN + R_RING)
    power_out = LOAD * carrier + kinetic_energy_rate(res)
    inner, outer = res.joint("sun-planet").mesh_force, res.joint("planet-ring").mesh_force
    print(mb.format_table({
        "t [s]": res.t,
        "sun [rad/s]": sun,
        "carrier [rad/s]": carrier,
        "motor [N m]": torque,
        "motor power [W]": torque * sun,
        "load + dT/dt [W]": power_out,
        "sun mesh Ft [N]": inner.tangential,
        "ring mesh tooth [N]": outer.tooth,
    }))
    moving = sun > 0
    ratio = carrier[moving] / sun[moving]
    print(f"\nspeed ratio carrier/sun: {ratio.min():.15f} .. {ratio.max():.15f}; "
          f"Willis r_sun/(r_sun + r_ring) = {willis:.15f}")
    mismatch = np.max(np.abs(torque * sun - power_out)) / np.max(np.abs(power_out))
    print(f"power balance: largest mismatch {mismatch:.1e} of the largest power")
    print(f"motor torque {torque[-1]:.6f} N m = load x ratio {LOAD * willis:.6f} N m "
          f"+ {torque[-1] - LOAD * willis:.6f} N m accelerating the train")
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res


if __name__ == "__main__":
    run_script(main, __doc__, "gear_train.rrd")
