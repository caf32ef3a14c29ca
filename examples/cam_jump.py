"""A follower that jumps: a roller held on an eccentric cam by a spring, the cam turned faster
than the follower can follow.

The cam is a disc of radius 50 mm turning about a shaft 12 mm off its centre (so the lift is
nearly harmonic); a 0.5 kg follower with a 10 mm roller slides on a vertical guide above it,
pushed down by a 200 N/m spring and its weight. The cam is a contact, not a joint: a stiff,
damped linear law (1e8 N/m, restitution 0.5) pushes the roller out of the cam, so the roller
can leave it. Above the speed where the cam's lift decelerates faster than spring and weight
can pull the follower down, it does: it flies on its spring, lands on the cam, rebounds and
settles again. Worked out by hand and printed beside the run: the lift-off speed, the angle
where the follower leaves, and where its free flight (a harmonic motion on the spring) meets
the cam again. The contact lets go 0.1 degree after the angle by hand: its damper holds the
last of the force for about c/K = 30 us. Recorded to cam_jump.rrd: rerun cam_jump.rrd

Run: python examples/cam_jump.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import math
import warnings

import numpy as np
from scipy.optimize import brentq

import mbd3d as mb
from mbd3d.joints import CamProfile, Prismatic, Revolute, RotationDriver
from mbd3d.viewer import check_recording_first, record, run_script

RADIUS, ECCENTRICITY, ROLLER = 0.050, 0.012, 0.010
MASS, STIFFNESS, PLATE, FREE_LENGTH, G = 0.5, 200.0, 0.2, 0.15, 9.81
CONTACT_STIFFNESS = 1e8


def lift(theta: float, derivative: int = 0) -> float:
    """The roller centre's height [m] on the cam turned by ``theta`` [rad] (the eccentric
    points up at pi/2), ``e sin + sqrt(a^2 - e^2 cos^2)`` with ``a`` the cam's radius plus the
    roller's, or its first or second derivative in ``theta``."""
    e, c, s = ECCENTRICITY, math.cos(theta), math.sin(theta)
    root = math.sqrt((RADIUS + ROLLER) ** 2 - (e * c) ** 2)
    return (e * s + root, e * c + e * e * c * s / root,
            -e * s + e * e * (c * c - s * s) / root - e ** 4 * c * c * s * s / root ** 3
            )[derivative]


def free_acceleration(y: float) -> float:
    """The follower's acceleration [m/s2] off the cam at height ``y``: spring and weight."""
    return STIFFNESS * (PLATE - FREE_LENGTH - y) / MASS - G


def lift_off_speed() -> float:
    """The cam speed [rad/s] above which the follower leaves, by hand: the contact force
    ``m (w^2 y'' - free acceleration)`` must stay positive where the lift curves down."""
    theta = np.linspace(0.0, 2 * math.pi, 20001)
    curving = np.array([lift(th, 2) for th in theta])
    held = np.array([free_acceleration(lift(th)) for th in theta])
    return math.sqrt(np.min(held[curving < 0] / curving[curving < 0]))


def build(speed: float | None = None) -> mb.Model:
    """The cam turning at ``speed`` [rad/s] (default 1.3 times the lift-off speed) from its
    lowest point (its eccentric pointing down), the follower resting on it there
    (examples/models/cam_jump.yaml as a file)."""
    speed = 1.3 * lift_off_speed() if speed is None else speed
    surface = CamProfile.sampled(lambda phi: ECCENTRICITY * np.cos(phi) + np.sqrt(
        RADIUS ** 2 - (ECCENTRICITY * np.sin(phi)) ** 2), 1440)
    start = -math.pi / 2
    # the contact's force there carries the follower up at the cam's acceleration; the
    # roller starts pressed into the cam by that force over the contact's stiffness
    force = MASS * (speed ** 2 * lift(start, 2) - free_acceleration(lift(start)))
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G), name="eccentric cam, jumping follower")
    cam = b.add_body("cam", mass=2.0, inertia=2e-3, position=(0.0, 0.0), angle=start)
    follower = b.add_body("follower", mass=MASS, inertia=1e-4,
                          position=(0.0, lift(start) - force / CONTACT_STIFFNESS))
    shaft = b.add(Revolute("shaft", b.ground, cam, at=(0.0, 0.0)))
    b.add(Prismatic("guide", b.ground, follower, axis=(0.0, 1.0)))
    b.add(RotationDriver("motor", shaft, motion=mb.Ramp(start, speed)))
    b.add(mb.SpringDamper("spring", b.ground, follower, at_i=(0.0, PLATE),
                          at_j=(0.0, lift(start)), stiffness=STIFFNESS,
                          free_length=FREE_LENGTH))
    # the law calibrated on the follower's mass: the cam is driven, its inertia does not count
    b.add(mb.Contact("roller", mb.Cam(cam, surface), mb.Sphere(follower, ROLLER),
                     law=mb.LinearContact(stiffness=CONTACT_STIFFNESS, restitution=0.5),
                     effective_mass=MASS))
    with warnings.catch_warnings():  # pressed into the cam on purpose
        warnings.simplefilter("ignore", mb.ContactWarning)
        return b.build()


def jump(speed: float) -> tuple[float, float]:
    """By hand at ``speed``: the cam angles [rad] where the follower leaves (the contact
    force crossing zero on the way up) and where its free flight from there, a harmonic
    motion on the spring, meets the cam again."""
    leaves = brentq(lambda th: speed ** 2 * lift(th, 2) - free_acceleration(lift(th)),
                    0.0, math.pi / 2, xtol=1e-14)
    y0, v0 = lift(leaves), speed * lift(leaves, 1)
    omega = math.sqrt(STIFFNESS / MASS)
    hang = PLATE - FREE_LENGTH - MASS * G / STIFFNESS

    def above(th: float) -> float:  # the flight's height above the cam, at cam angle th
        tau = (th - leaves) / speed
        flight = hang + (y0 - hang) * math.cos(omega * tau) + v0 / omega * math.sin(omega * tau)
        return flight - lift(th)
    angles = leaves + np.linspace(1e-3, 4 * math.pi, 40001)
    k = int(np.flatnonzero(np.array([above(th) for th in angles]) < 0.0)[0])
    return leaves, brentq(above, angles[k - 1], angles[k], xtol=1e-14)


@check_recording_first
def main(n_points: int = 401, rrd: str | None = None, show: bool = False) -> mb.Results:
    critical = lift_off_speed()
    speed = 1.3 * critical
    leaves, lands = jump(speed)
    model = build(speed)
    # the contact's gap as events: the times the roller leaves the cam and lands on it. It
    # leaves where the two move alike, the gap growing with the cube of the time, and dithers
    # about zero by its rounding (1e-17 m) for a while: a crossing counts once the gap has
    # been a picometre from zero since the last
    gap = lambda t, q, qd: mb.contact_states(model, q, qd).gap[0]  # noqa: E731
    events = [mb.Event("leaves", gap, direction=1, tolerance=1e-12),
              mb.Event("lands", gap, direction=-1, tolerance=1e-12)]
    res = mb.forward_dynamics(model, np.linspace(0.0, 4 * math.pi / speed, n_points),
                              method="DOP853", rtol=1e-9, atol=1e-11, events=events)
    times = {name: [e["time"] for e in res.stats["events"] if e["name"] == name]
             for name in ("leaves", "lands")}
    angle = lambda t: math.degrees(speed * t - math.pi / 2)  # noqa: E731  the cam's angle
    print(f"lift-off speed by hand: {critical:.3f} rad/s; the cam turns at {speed:.3f} rad/s")
    print(f"the follower leaves the cam at {angle(times['leaves'][0]):.3f} deg (by hand "
          f"{math.degrees(leaves):.3f}) and lands at {angle(times['lands'][0]):.3f} deg (its "
          f"free flight by hand: {math.degrees(lands):.3f})")
    print(f"in two turns it leaves the cam {len(times['leaves'])} times and lands "
          f"{len(times['lands'])} times")
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res


if __name__ == "__main__":
    run_script(main, __doc__, "cam_jump.rrd")
