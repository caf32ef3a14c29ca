"""Four-bar linkage: kinematics of a crank-rocker, a coupler point's path, the motor torque.

Ground pivots O2 = (0, 0) and O4 = (0.3, 0) m; crank 0.10 m, coupler 0.35 m, rocker 0.30 m
(Grashof crank-rocker), slender steel-like bars of 2 kg/m; the crank turns at 2 pi rad/s.
The table shows the rocker swing, the transmission angle (between coupler and rocker; a
linkage runs badly when it nears 0 or 180 degrees), the path of the coupler's midpoint and the
motor torque.

Recorded to four_bar.rrd with the coupler midpoint's path: rerun four_bar.rrd

Run: python examples/four_bar.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import argparse

import numpy as np

import mbd3d as mb
from mbd3d.mechanisms import four_bar
from mbd3d.viewer import check_destination, record


def build() -> mb.Model:
    """The crank-rocker at 2 pi rad/s (examples/models/four_bar.yaml as a file)."""
    return four_bar(crank_speed=2 * np.pi)


def main(n_points: int = 241, rrd: str | None = None, show: bool = False) -> mb.Results:
    # a bad path, or --show without a display, fails now, not after the computing
    if rrd is not None:
        check_destination(rrd, show=show)
    model = build()
    print(mb.mobility(model), "\n")
    t = np.linspace(0.0, 1.0, n_points)
    res = mb.inverse_dynamics(model, t)
    coupler, rocker = res.body("coupler"), res.body("rocker")
    transmission = np.degrees(np.abs(np.angle(np.exp(1j * (coupler.angle - rocker.angle)))))
    midpoint = res.point("coupler", (0.0, 0.0)).position
    print(mb.format_table({
        "t [s]": t,
        "crank [deg]": np.degrees(res.body("crank").angle),
        "rocker [deg]": np.degrees(rocker.angle),
        "transmission [deg]": transmission,
        "coupler mid x [m]": midpoint[:, 0],
        "coupler mid y [m]": midpoint[:, 1],
        "torque [N m]": res.driver("motor").effort,
    }, rows=13))
    swing = np.degrees(rocker.angle.max() - rocker.angle.min())
    print(f"\nrocker swing over the sampled cycle: {swing:.2f} deg")
    if rrd is not None:
        record(res, rrd, overwrite=True, points={"coupler middle": ("coupler", (0.0, 0.0))},
               show=show)
    return res


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rrd", default="four_bar.rrd", help="the Rerun recording to write")
    parser.add_argument("--show", action="store_true", help="open it in the Rerun viewer")
    args = parser.parse_args()
    try:
        main(rrd=args.rrd, show=args.show)
    except mb.MBDError as error:  # a bad path, no display, ...: the message says what to do
        raise SystemExit(f"error: {error}")
