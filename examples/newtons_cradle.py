"""Newton's cradle: five steel balls on strings, the first released from 30 degrees.

Each ball (radius 15 mm, steel) hangs on a rigid string of 100 mm from a pin above it; at
rest they stand 0.2 mm apart. The contacts are Hertz's law from the material (E = 210 GPa,
nu = 0.3) without damping (restitution 1), so each impact, about 90 microseconds long while
the struck ball moves some 40 micrometres, is a collision of two equal pendulums that
conservation alone settles: the striker stops and the struck ball takes its swing. The
impulse runs down the row and the last ball swings out nearly to the height the first fell
from. Nearly: the balls stand apart, so the striker meets the next ball 0.2 mm before the
bottom of its swing and stops there, a tenth of a degree up, and so on down the row; those
small swings keep the little energy the last ball lacks (the whole is kept to the
integrator's tolerance). Recorded to newtons_cradle.rrd: rerun newtons_cradle.rrd

Run: python examples/newtons_cradle.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import math

import numpy as np

import mbd3d as mb
from mbd3d.mechanisms import newtons_cradle
from mbd3d.viewer import check_recording_first, record, run_script

G, BALLS, RADIUS, STRING, GAP, DENSITY = 9.81, 5, 0.015, 0.1, 0.2e-3, 7850.0
RELEASE = math.radians(30.0)


def build() -> mb.Model:
    """The balls hanging in a row along x, the first turned back by ``RELEASE``; see
    :func:`mbd3d.mechanisms.newtons_cradle` for how the pins and contacts are added."""
    return newtons_cradle(BALLS, radius=RADIUS, string_length=STRING, gap=GAP,
                          density=DENSITY, young_modulus=210e9, poisson_ratio=0.3,
                          restitution=1.0, release=RELEASE, gravity=G)


def swing(res: mb.Results, k: int) -> np.ndarray:
    """Ball ``k``'s (from 1) angle about its pin [rad], positive to the right."""
    return res.body(f"ball{k}").angle


@check_recording_first
def main(n_points: int = 701, rrd: str | None = None, show: bool = False) -> mb.Results:
    model = build()
    # the striker falls for a quarter swing (about 0.16 s), the last ball rises for another
    t = np.linspace(0.0, 0.35, n_points)
    res = mb.forward_dynamics(model, t, method="DOP853", rtol=1e-10, atol=1e-12)
    rates = np.column_stack([res.body(f"ball{k}").angular_velocity for k in
                             range(1, BALLS + 1)])
    before = np.max(np.abs(rates[:, 0]))  # the striker at the bottom
    print(mb.format_table({
        "ball": np.arange(1, BALLS + 1),
        "largest swing [deg]": np.degrees([np.max(np.abs(swing(res, k)))
                                           for k in range(1, BALLS + 1)]),
        "turning at the end [rad/s]": rates[-1],
    }, precision=6))
    print(f"\nthe striker reached {before:.6f} rad/s at the bottom; the last ball left at "
          f"{np.max(rates[:, -1]):.6f} rad/s and swung out to "
          f"{math.degrees(np.max(swing(res, BALLS))):.4f} degrees "
          f"(released from {math.degrees(RELEASE):g})")
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res


if __name__ == "__main__":
    run_script(main, __doc__, "newtons_cradle.rrd")
