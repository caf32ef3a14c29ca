"""Spheres dropped into a box: 27 rubber balls in one contact group.

Twenty-seven balls of 10 mm (rubber-like: E = 10 MPa, density 1000 kg/m^3) start on a lattice
above the floor of an open box, each thrown a little in a random direction, and fall into a
pile. Every two balls and each ball and the box's floor and walls touch by Hertz's law damped
to a restitution of 0.5, with Coulomb friction 0.3: one `mb.ContactGroup`, whose pairs near
each other are found at each evaluation on a grid, so that the cost grows with the balls, not
with their 351 pairs. The energy balance closes: what the balls lose, the contacts'
dampers and friction dissipate. Recorded to spheres_in_box.rrd: rerun spheres_in_box.rrd

Run: python examples/spheres_in_box.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import numpy as np

import mbd3d as mb
from mbd3d.mechanisms import spheres_in_box
from mbd3d.viewer import check_recording_first, record, run_script

BALLS, RADIUS = 27, 0.01


def build() -> mb.Model:
    """The balls and the box; see :func:`mbd3d.mechanisms.spheres_in_box`."""
    return spheres_in_box(BALLS, radius=RADIUS, density=1000.0, young_modulus=1e7,
                          restitution=0.5, friction=0.3, speed=0.3, seed=1)


@check_recording_first
def main(n_points: int = 61, rrd: str | None = None, show: bool = False) -> mb.Results:
    model = build()
    t = np.linspace(0.0, 0.3, n_points)
    res = mb.forward_dynamics(model, t, rtol=1e-5, atol=1e-8)
    balance = res.energy_balance()
    every = max(1, (n_points - 1) // 6)
    heights = res.q.reshape(len(t), BALLS, -1)[:, :, 2]
    print(mb.format_table({"t [s]": t[::every],
                           "kinetic [J]": balance["kinetic"][::every],
                           "potential [J]": balance["potential"][::every],
                           "dissipated [J]": balance["dissipated"][::every],
                           "total [J]": balance["total"][::every],
                           "lowest ball [mm]": 1e3 * heights.min(axis=1)[::every]},
                          precision=6))
    print(f"\n{res.stats['steps']} steps; the pile's deepest pair is pressed in "
          f"{-1e6 * res.contacts().gap[-1, 0]:.1f} um at the end")
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res


if __name__ == "__main__":
    run_script(main, __doc__, "spheres_in_box.rrd")
