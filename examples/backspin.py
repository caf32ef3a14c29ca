"""Backspin: a ball thrown sliding with backspin stops slipping, then rolls on or comes back.

A ball (r = 0.1 m, 2 kg) is thrown along the floor at v0 = 2 m/s spinning backwards at
omega0 (about y; rolling forward would be +v0 / r). Its contact with the floor is rigid with
Coulomb's friction mu = 0.2 (mb.RigidImpact and friction=0.2): while the contact point slips
at s = v - r omega, friction mu m g slows the ball and spins it forward, so the slip runs out
at (7/2) mu g, and where it reaches zero the contact sticks and the ball rolls, at
t* = 2 s0 / (7 mu g) with v* = (5 v0 + 2 r omega0) / 7: on, slower, or back towards the
thrower where the backspin is strong enough (2 r |omega0| > 5 v0). Each throw's stick is an
event of the run, set beside the closed form. The last throw is recorded to backspin.rrd:
rerun backspin.rrd

Run: python examples/backspin.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import numpy as np

import mbd3d as mb
from mbd3d.viewer import check_recording_first, record, run_script

G, RADIUS, MASS, MU, V0 = 9.81, 0.1, 2.0, 0.2, 2.0


def build(omega0: float) -> mb.Model:
    """The ball on the floor z = 0, thrown at V0 along x spinning at ``omega0`` [rad/s] about
    y."""
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G), name="backspin")
    ball = b.add_body("ball", mass=MASS, inertia=0.4 * MASS * RADIUS ** 2 * np.ones(3),
                      position=(0.0, 0.0, RADIUS), velocity=(V0, 0.0, 0.0),
                      angular_velocity=(0.0, omega0, 0.0))
    b.add(mb.Contact("floor", mb.Sphere(ball, RADIUS), mb.Plane(b.ground, normal=(0, 0, 1)),
                     law=mb.RigidImpact(restitution=0.0), friction=MU))
    return b.build()


@check_recording_first
def main(n_points: int = 201, rrd: str | None = None, show: bool = False) -> list:
    t = np.linspace(0.0, 2.0, n_points)
    spins = [0.0, -V0 / RADIUS, -4 * V0 / RADIUS]
    runs = [mb.forward_dynamics(build(omega0), t, method="DOP853", rtol=1e-10, atol=1e-12)
            for omega0 in spins]
    sticks = [next(r["time"] for r in res.stats["rests"] if r["event"] == "stick")
              for res in runs]
    slips = [V0 - RADIUS * omega0 for omega0 in spins]
    print(mb.format_table({
        "omega0 [rad/s]": spins,
        "sticks at [s]": sticks,
        "by hand [s]": [2 * s0 / (7 * MU * G) for s0 in slips],
        "rolls at [m/s]": [res.body("ball").velocity[-1, 0] for res in runs],
        "by hand [m/s]": [(5 * V0 + 2 * RADIUS * omega0) / 7 for omega0 in spins],
    }, precision=9))
    back = runs[-1].body("ball").position[:, 0]
    print(f"\nthe last ball goes out to {back.max():.6f} m and is back at {back[-1]:.6f} m "
          f"after {t[-1]:g} s")
    if rrd is not None:
        record(runs[-1], rrd, overwrite=True, show=show)
    return runs


if __name__ == "__main__":
    run_script(main, __doc__, "backspin.rrd")
