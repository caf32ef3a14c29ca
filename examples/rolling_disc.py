"""A disc rolling in a circle on a table: the classical rolling disc, a nonholonomic joint.

A thin uniform disc (radius 0.1 m, 2 kg) leans 10 degrees into a turn, its contact point on a
circle of radius 0.5 m. Euler's equations about the contact point give the turning rate at
which it rolls round steadily (Greenwood, Advanced Dynamics, sec. 8.5):

    Omega^2 = 4 g tan(lean) / (6 R - 5 r sin(lean)) = (1.541134 rad/s)^2

Started at that rate, the disc goes once round the circle with its lean and its centre's
radius unchanged; the table presses it with its weight and the friction rolling needs holds
its centre on the circle, m Omega^2 R_G. Started 5 % slower, it does not stay upright at the
same lean. Recorded to rolling_disc.rrd (with the path of a point on the rim):
rerun rolling_disc.rrd

Run: python examples/rolling_disc.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import math

import numpy as np

import mbd3d as mb
from mbd3d.joints import RollingDiscOnPlane
from mbd3d.viewer import check_recording_first, record, run_script

G, MASS, RADIUS, THICKNESS = 9.81, 2.0, 0.1, 0.01
LEAN, PATH = math.radians(10.0), 0.5  # towards the turn's centre; the contact's circle [m]
STEADY = math.sqrt(4 * G * math.tan(LEAN) / (6 * PATH - 5 * RADIUS * math.sin(LEAN)))
UP = np.array([0.0, 0.0, 1.0])


def build(turning: float = STEADY) -> mb.Model:
    """The disc on the table z = 0, its contact at (PATH, 0, 0), rolling towards +y round
    the origin at ``turning`` rad/s (examples/models/rolling_disc.yaml)."""
    inwards = np.array([-math.sin(LEAN), 0.0, math.cos(LEAN)])  # from the contact to the centre
    centre = np.array([PATH, 0.0, 0.0]) + RADIUS * inwards
    axis = np.array([math.cos(LEAN), 0.0, math.sin(LEAN)])
    velocity = turning * np.cross(UP, centre)
    # spin about the axis so that the rim point on the table stands still
    contact = -RADIUS * inwards
    spin = -(velocity + np.cross(turning * UP, contact))[1] / np.cross(axis, contact)[1]
    # body z along the disc's axis (the viewer's cylinder's and the inertia's symmetry axis):
    # frame_along's axes turned cyclically
    along, across, third = mb.rotations.frame_along(axis).T
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G), name="rolling disc")
    disc = b.add_body("disc", mass=MASS, inertia=MASS * RADIUS ** 2 * np.diag([0.25, 0.25, 0.5]),
                      position=centre, orientation=np.column_stack([across, third, along]),
                      velocity=velocity, angular_velocity=spin * axis + turning * UP,
                      shape={"cylinder": [RADIUS, THICKNESS]})
    b.add(RollingDiscOnPlane("table", b.ground, disc, radius=RADIUS, axis=axis))
    return b.build()


def lean_of(res: mb.Results) -> np.ndarray:
    """The disc's lean from the vertical [deg]: its axis's rise."""
    return np.degrees(np.arcsin(res.body("disc").rotation[:, 2, 2]))


@check_recording_first
def main(n_points: int = 41, rrd: str | None = None, show: bool = False) -> mb.Results:
    model = build()
    print(mb.mobility(model), "\n")
    t = np.linspace(0.0, 2 * math.pi / STEADY, n_points)  # once round the circle
    res = mb.forward_dynamics(model, t, method="DOP853", rtol=1e-11, atol=1e-12)
    centre = res.body("disc").position
    table = res.joint("table")
    path_of_centre = PATH - RADIUS * math.sin(LEAN)
    print(mb.format_table({
        "t [s]": t,
        "lean [deg]": lean_of(res),
        "centre radius [m]": np.hypot(centre[:, 0], centre[:, 1]),
        "heading [rad]": np.unwrap(np.arctan2(centre[:, 1], centre[:, 0])),
        "normal [N]": table.contact_force,
        "friction [N]": np.linalg.norm(table.traction, axis=1),
    }, precision=10, rows=9))
    print(f"\nturning rate by the closed form: {STEADY:.9f} rad/s, one turn in "
          f"{2 * math.pi / STEADY:.6f} s")
    print(f"lean stays within {np.max(np.abs(lean_of(res) - 10.0)):.1e} deg of 10; the centre's "
          f"radius within "
          f"{np.max(np.abs(np.hypot(centre[:, 0], centre[:, 1]) - path_of_centre)):.1e} m of "
          f"R - r sin(lean) = {path_of_centre:.9f} m")
    print(f"back at the start after one turn: {np.linalg.norm(centre[-1] - centre[0]):.1e} m")
    print(f"normal force {table.contact_force[0]:.9f} N = m g = {MASS * G:.9f} N; friction "
          f"{np.linalg.norm(table.traction[0]):.9f} N = m Omega^2 R_G = "
          f"{MASS * STEADY ** 2 * path_of_centre:.9f} N")
    energy = res.kinetic_energy + res.potential_energy
    print(f"energy: changes by {np.ptp(energy):.1e} J of {energy[0]:.6f} J")
    slower = mb.forward_dynamics(build(0.95 * STEADY), np.linspace(0.0, 1.0, 11),
                                 method="DOP853", rtol=1e-10, atol=1e-12)
    print(f"turning 5 % slower: the lean drifts by {np.ptp(lean_of(slower)):.2f} deg in 1 s")
    if rrd is not None:
        record(res, rrd, overwrite=True, points={"rim": ("disc", (RADIUS, 0.0, 0.0))},
               show=show)
    return res


if __name__ == "__main__":
    run_script(main, __doc__, "rolling_disc.rrd")
