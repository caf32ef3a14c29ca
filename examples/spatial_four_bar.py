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


def rocker_by_hand(theta: np.ndarray) -> np.ndarray:
    """The rocker's angle from x in the xz-plane for crank angles ``theta`` [rad]: the coupler
    keeps its length c, |O4 + r (cos phi, 0, sin phi) - A(theta)| = c, that is
    d_x cos phi + d_z sin phi = (c^2 - |d|^2 - r^2) / (2 r) with d = O4 - A; the branch of the
    drawing (phi = 90 degrees at theta = 0)."""
    o4, r, crank = np.array([0.25, 0.0, 0.1]), 0.2, 0.08  # spatial_four_bar's drawing
    c = np.linalg.norm(o4 + [0.0, 0.0, r] - [crank, 0.0, 0.0])
    d = o4[None, :] - crank * np.stack([np.cos(theta), np.sin(theta), 0 * theta], axis=1)
    k = (c**2 - np.sum(d**2, axis=1) - r**2) / (2 * r)
    return np.arctan2(d[:, 2], d[:, 0]) + np.arccos(k / np.hypot(d[:, 0], d[:, 2]))


@check_recording_first
def main(n_points: int = 201, rrd: str | None = None, show: bool = False) -> mb.Results:
    print(mb.mobility(spatial_four_bar(all_revolute=True, crank_speed=None)), "\n")
    model = build()
    print(mb.mobility(model), "\n")
    t = np.linspace(0.0, 1.0, n_points)
    res = mb.inverse_dynamics(model, t)
    rocker = res.body("rocker").rotation[:, :, 0]  # the rocker's own axis, O4 -> B
    angle = np.arctan2(rocker[:, 2], rocker[:, 0])
    print(mb.format_table({
        "t [s]": t,
        "crank [deg]": np.degrees(2 * np.pi * t),
        "rocker [deg]": np.degrees(angle),
        "torque [N m]": res.driver("motor").effort,
        "|force at O4| [N]": np.linalg.norm(res.joint("O4").reaction(on="rocker").force, axis=1),
    }, rows=9))
    print(f"\nrocker angle against the loop closure solved by hand: largest difference "
          f"{np.max(np.abs(angle - rocker_by_hand(2 * np.pi * t))):.1e} rad")
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res


if __name__ == "__main__":
    run_script(main, __doc__, "spatial_four_bar.rrd")
