"""A steel ball bouncing on a steel plate: a compliant contact with Hertz's law.

A ball of radius 20 mm dropped from 1 m (its lowest point) onto a plate, both steel (E = 210
GPa, nu = 0.3), with a restitution of 0.8 and friction 0.2; it also moves sideways at 0.5 m/s.
Hertz's stiffness follows from the materials, K = (4/3) E* sqrt(r) (E* = E / (2 (1 - nu^2))
for two bodies of one material), and the law's damping is calibrated to the restitution. A
rigid ball would rebound to e^(2n) h0 after its n-th bounce; the compliant one loses a
little to gravity while it is in contact (a tenth of a millisecond, 0.15 mm deep). At the
first bounce its bottom slides on the plate: friction spins it up until it rolls, and as
friction acts at the contact point the angular momentum about that point is kept,
m v r = m v' r + (2/5) m r^2 v' / r: it goes on at 5/7 of its sideways speed (a little less:
the dent brings the contact point nearer the centre, so the spin takes a larger share).
Recorded to bouncing_ball.rrd: rerun bouncing_ball.rrd

Run: python examples/bouncing_ball.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import math

import numpy as np

import mbd3d as mb
from mbd3d.viewer import check_recording_first, record, run_script

G, RADIUS, DENSITY, HEIGHT, RESTITUTION = 9.81, 0.02, 7850.0, 1.0, 0.8


def build() -> mb.Model:
    """The ball above the plate z = 0 (examples/models/bouncing_ball.yaml)."""
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G), name="bouncing ball")
    ball = b.add_body("ball", shape={"sphere": RADIUS}, density=DENSITY,
                      position=(0.0, 0.0, HEIGHT + RADIUS), velocity=(0.5, 0.0, 0.0))
    law = mb.HertzContact(young_modulus=210e9, poisson_ratio=0.3, restitution=RESTITUTION)
    b.add(mb.Contact("plate", mb.Sphere(ball, RADIUS), mb.Plane(b.ground, normal=(0, 0, 1)),
                     law=law, friction=0.2))
    return b.build()


@check_recording_first
def main(n_points: int = 1001, rrd: str | None = None, show: bool = False) -> mb.Results:
    model = build()
    t = np.linspace(0.0, 2.5, n_points)
    res = mb.forward_dynamics(model, t, method="DOP853", rtol=1e-10, atol=1e-12)
    height = res.body("ball").position[:, 2] - RADIUS
    rising = res.body("ball").velocity[:, 2]
    apex = height + np.maximum(rising, 0.0) ** 2 / (2 * G)  # where a free flight tops out
    # the first output after each bounce: rising again, off the plate
    flights = np.flatnonzero((height[1:] > 0) & (rising[1:] > 0) & (rising[:-1] <= 0)) + 1
    bounces = np.arange(1, len(flights) + 1)
    print(mb.format_table({
        "bounce": bounces,
        "t [s]": t[flights],
        "apex [m]": apex[flights],
        "rigid e^(2n) h0 [m]": RESTITUTION ** (2 * bounces) * HEIGHT,
    }, precision=8))
    # Hertz's impact (Johnson, Contact Mechanics, 11.4): the deepest dent
    # (5 m v^2 / (4 K))^(2/5) and the time in contact 2.943 dent / v
    mass, speed = model.mass[0], math.sqrt(2 * G * HEIGHT)
    K = 4 / 3 * 210e9 / (2 * (1 - 0.3 ** 2)) * math.sqrt(RADIUS)
    dent = (5 * mass * speed ** 2 / (4 * K)) ** 0.4
    print(f"\nfirst impact at {speed:.4f} m/s: dent {dent * 1e6:.2f} um, in contact "
          f"{2.943275 * dent / speed * 1e6:.1f} us (undamped Hertz)")
    print(f"sideways speed after the first bounce: {res.body('ball').velocity[-1, 0]:.6f} m/s, "
          f"a rigid ball's 5/7 of 0.5 = {2.5 / 7:.6f} m/s")
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res


if __name__ == "__main__":
    run_script(main, __doc__, "bouncing_ball.rrd")
