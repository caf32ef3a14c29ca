"""Spatial slider-crank: the slider runs on a line out of the crank's plane.

The crank (0.10 m) turns about the global z axis at 2 pi rad/s; the slider runs parallel to x at
y = 0.04 m, z = 0.06 m; the rod (0.30 m) has a universal joint at the crank and a ball joint at
the slider. The table compares the slider position with its closed form
x = r cos(phi) + sqrt(l^2 - e^2 - (d - r sin(phi))^2) and shows the motor torque and the moment
the universal joint transmits.

Recorded to spatial_slider_crank.rrd: rerun spatial_slider_crank.rrd

Run: python examples/spatial_slider_crank.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import numpy as np

import mbd3d as mb
from mbd3d.mechanisms import spatial_slider_crank
from mbd3d.viewer import check_recording_first, record, run_script


def build() -> mb.Model:
    """The spatial slider-crank at 2 pi rad/s (examples/models/spatial_slider_crank.yaml)."""
    return spatial_slider_crank(crank_speed=2 * np.pi)


@check_recording_first
def main(n_points: int = 201, rrd: str | None = None, show: bool = False) -> mb.Results:
    model = build()
    print(mb.mobility(model), "\n")
    t = np.linspace(0.0, 1.0, n_points)
    res = mb.inverse_dynamics(model, t)
    phi = 2 * np.pi * t
    closed_form = 0.1 * np.cos(phi) + np.sqrt(0.09 - 0.06**2 - (0.04 - 0.1 * np.sin(phi)) ** 2)
    slider = res.body("slider")
    joint_a = res.joint("A").reaction(on="rod")
    print(mb.format_table({
        "t [s]": t,
        "crank [deg]": np.degrees(phi),
        "x_slider [m]": slider.position[:, 0],
        "closed form [m]": closed_form,
        "v_slider [m/s]": slider.velocity[:, 0],
        "torque [N m]": res.driver("motor").effort,
        "|moment at A| [N m]": np.linalg.norm(joint_a.moment, axis=1),
    }, rows=9))
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res


if __name__ == "__main__":
    run_script(main, __doc__, "spatial_slider_crank.rrd")
