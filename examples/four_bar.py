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

import numpy as np

import mbd3d as mb
from mbd3d.mechanisms import four_bar
from mbd3d.viewer import check_recording_first, record, run_script


def build() -> mb.Model:
    """The crank-rocker at 2 pi rad/s (examples/models/four_bar.yaml as a file)."""
    return four_bar(crank_speed=2 * np.pi)


@check_recording_first
def main(n_points: int = 241, rrd: str | None = None, show: bool = False) -> mb.Results:
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
    run_script(main, __doc__, "four_bar.rrd")
