"""Disc cam with a roller follower: the follower law back from the cam, the contact force, and
the speed at which the follower would leave the cam.

The cam is cut for a cycloidal rise of 20 mm over 120 degrees, a dwell, a cycloidal return
over 120 degrees and a dwell (base circle 40 mm, roller 10 mm); its pitch curve is a periodic
spline through 720 samples of that law. A 0.5 kg follower slides on a vertical guide above
it, held down by a 400 N/m spring. Kinematic analysis gives the lift, velocity and
acceleration back against the law; inverse dynamics gives the contact force and the motor
torque. Above a certain speed the return decelerates the follower faster than the spring and
weight can: the contact would have to pull, and mbd3d reports where (lift-off). That speed,
worked out by hand from the law, is checked just below and just above. Recorded to
cam_follower.rrd with the cam's surface and the contact force: rerun cam_follower.rrd

Run: python examples/cam_follower.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import math
import warnings

import numpy as np

import mbd3d as mb
from mbd3d.joints import CamFollower, CamProfile, Prismatic, Revolute, RotationDriver
from mbd3d.viewer import check_recording_first, record, run_script

BASE, ROLLER, LIFT, BETA = 0.040, 0.010, 0.020, math.radians(120.0)
MASS, STIFFNESS, G = 0.5, 400.0, 9.81


def lift(theta: np.ndarray, derivative: int = 0) -> np.ndarray:
    """The follower law s(theta) [m] and its first two derivatives in the cam angle."""
    th = np.mod(theta, 2 * math.pi)
    s = np.where((th >= BETA) & (th < math.pi), LIFT, 0.0) if derivative == 0 else 0.0 * th
    for start, sign in ((0.0, 1.0), (math.pi, -1.0)):
        inside = (th >= start) & (th < start + BETA)
        x = (th - start) / BETA
        terms = (LIFT * (x - np.sin(2 * math.pi * x) / (2 * math.pi)),
                 LIFT / BETA * (1 - np.cos(2 * math.pi * x)),
                 LIFT / BETA ** 2 * 2 * math.pi * np.sin(2 * math.pi * x))
        value = terms[derivative] if sign > 0 or derivative else LIFT - terms[0]
        s = np.where(inside, value * (sign if derivative else 1.0), s)
    return s


def build(speed: float = 2 * math.pi) -> mb.Model:
    """The cam turning at ``speed`` [rad/s] (examples/models/cam_follower.yaml as a file)."""
    # the roller's centre sits at the polar angle pi/2 - theta in the cam's frame
    profile = CamProfile.sampled(lambda phi: BASE + ROLLER + lift(math.pi / 2 - phi), 720)
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G), name="cam and roller follower")
    cam = b.add_body("cam", mass=2.0, inertia=2e-3, position=(0.0, 0.0))
    follower = b.add_body("follower", mass=MASS, inertia=1e-3, position=(0.0, BASE + ROLLER))
    shaft = b.add(Revolute("shaft", b.ground, cam, at=(0.0, 0.0)))
    b.add(Prismatic("guide", b.ground, follower, axis=(0.0, 1.0)))
    b.add(CamFollower("contact", cam, follower, profile=profile, roller_radius=ROLLER))
    # compressed between the follower and a plate 0.2 m up: it pushes down with
    # STIFFNESS (0.05 m + the follower's height)
    b.add(mb.SpringDamper("spring", b.ground, follower, at_i=(0.0, 0.2),
                          at_j=(0.0, BASE + ROLLER), stiffness=STIFFNESS, free_length=0.25))
    b.add(RotationDriver("motor", shaft, motion=mb.Ramp(0.0, speed)))
    return b.build()


def lift_off_speed() -> float:
    """The cam speed [rad/s] above which the follower leaves the cam, by hand: the contact
    pushes while m w^2 s''(theta) + m g + k (0.05 + y) > 0 at every angle."""
    theta = np.linspace(0.0, 2 * math.pi, 200001)
    pulling = lift(theta, 2) < 0
    held = MASS * G + STIFFNESS * (0.05 + BASE + ROLLER + lift(theta))
    return float(np.sqrt(np.min(held[pulling] / (-MASS * lift(theta[pulling], 2)))))


@check_recording_first
def main(n_points: int = 25, rrd: str | None = None, show: bool = False) -> mb.Results:
    speed = 2 * math.pi
    t = np.linspace(0.0, 1.0, n_points)  # one turn
    res = mb.inverse_dynamics(build(speed), t)
    theta = speed * t
    follower = res.body("follower")
    errors = (follower.position[:, 1] - BASE - ROLLER - lift(theta),
              follower.velocity[:, 1] - speed * lift(theta, 1),
              follower.acceleration[:, 1] - speed ** 2 * lift(theta, 2))
    print(mb.format_table({
        "cam [deg]": np.degrees(theta),
        "lift [mm]": 1e3 * (follower.position[:, 1] - BASE - ROLLER),
        "law [mm]": 1e3 * lift(theta),
        "acceleration [m/s2]": follower.acceleration[:, 1],
        "contact force [N]": res.joint("contact").contact_force,
        "motor torque [N m]": res.driver("motor").effort,
    }))
    print(f"\nagainst the law: lift {np.max(np.abs(errors[0])):.1e} m, velocity "
          f"{np.max(np.abs(errors[1])):.1e} m/s, acceleration {np.max(np.abs(errors[2])):.1e} "
          "m/s2 (the spline's interpolation error)")
    print(f"smallest contact force at {speed:.3g} rad/s: "
          f"{res.joint('contact').contact_force.min():.2f} N; lift-off at "
          f"{len(res.joint('contact').lift_off)} of {n_points} times")
    critical = lift_off_speed()
    print(f"lift-off speed by hand: {critical:.4f} rad/s ({critical * 30 / math.pi:.0f} rpm)")
    for factor in (0.97, 1.03):
        angles = np.linspace(0.0, 2 * math.pi, 4 * n_points)
        with warnings.catch_warnings():  # above the lift-off speed on purpose: no warning
            warnings.simplefilter("ignore", mb.LiftOffWarning)
            fast = mb.inverse_dynamics(build(factor * critical), angles / (factor * critical))
        off = fast.joint("contact").contact_force < 0
        # the stretches of the turn where the contact would pull
        edges = np.flatnonzero(np.diff(np.concatenate([[0], off.astype(int), [0]])))
        spans = [f"{np.degrees(angles[a]):.0f}-{np.degrees(angles[b - 1]):.0f}"
                 for a, b in zip(edges[::2], edges[1::2])]
        where = f"lifts off at {', '.join(spans)} deg" if spans else "stays on the cam"
        print(f"  at {factor:.2f} times that speed the follower {where}")
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res


if __name__ == "__main__":
    run_script(lambda **kw: main(n_points=71, **kw), __doc__, "cam_follower.rrd")
