"""Spatial four-bar: why an all-revolute one locks, and an RSUR linkage that moves.

The crank turns about z, the rocker about y: their axes are skew. Built with four revolutes the
loop is rigid (a spatial four-bar of revolutes moves only under Bennett's conditions); the
mobility report says so and names the dependent rows. With a ball joint and a universal joint
on the coupler the same loop has one degree of freedom, and the crank drives the rocker.

The RSUR linkage is recorded to spatial_four_bar.rrd: rerun spatial_four_bar.rrd

Run: python examples/spatial_four_bar.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import numpy as np

import mbd3d as mb
from mbd3d.mechanisms import spatial_four_bar
from mbd3d.viewer import check_recording_first, record, run_script


def build() -> mb.Model:
    """The RSUR four-bar driven at 2 pi rad/s (examples/models/spatial_four_bar.yaml)."""
    return spatial_four_bar(crank_speed=2 * np.pi)


@check_recording_first
def main(n_points: int = 201, rrd: str | None = None, show: bool = False) -> mb.Results:
    print(mb.mobility(spatial_four_bar(all_revolute=True, crank_speed=None)), "\n")
    model = build()
    print(mb.mobility(model), "\n")
    t = np.linspace(0.0, 1.0, n_points)
    res = mb.inverse_dynamics(model, t)
    rocker = res.body("rocker").rotation[:, :, 0]  # the rocker's own axis, O4 -> B
    print(mb.format_table({
        "t [s]": t,
        "crank [deg]": np.degrees(2 * np.pi * t),
        "rocker [deg]": np.degrees(np.arctan2(rocker[:, 2], rocker[:, 0])),
        "torque [N m]": res.driver("motor").effort,
        "|force at O4| [N]": np.linalg.norm(res.joint("O4").reaction(on="rocker").force, axis=1),
    }, rows=9))
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res


if __name__ == "__main__":
    run_script(main, __doc__, "spatial_four_bar.rrd")
