"""Vibration modes along a motion: a four-bar driven through an elastic shaft.

The crank-rocker of examples/four_bar.py lies in a horizontal plane; its motor turns a shaft
that drives the crank through a torsionally elastic coupling of 50 N m/rad. Held at each
position of the motor's turn, the linkage can vibrate in one mode, the crank twisting against
the coupling while the coupler and rocker follow. Its natural frequency changes with the crank
angle because the inertia the coupling carries does: a designer reads off the speeds to avoid.

The check, printed beside it: sqrt(k / I(theta)) / 2 pi, with I(theta) = 2 T / w^2 the
inertia the crank carries, from the kinetic energy T of the rigid linkage's kinematic analysis
at crank speed w (no eigenvalues involved).

Recorded: four_bar_modes.rrd (the linkage through its positions, the frequency as a time
series and against the crank angle) and four_bar_mode.rrd (the mode animated where its
frequency is lowest): rerun four_bar_modes.rrd

Run: python examples/four_bar_modes.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import pathlib

import numpy as np

import mbd3d as mb
from mbd3d.mechanisms import four_bar
from mbd3d.viewer import check_recording_first, record, record_modes, run_script

STIFFNESS = 50.0  # [N m/rad] of the coupling between shaft and crank


def build() -> mb.Model:
    """The linkage on its elastic shaft (examples/models/four_bar_modes.yaml)."""
    return four_bar(shaft_stiffness=STIFFNESS, gravity=0.0)


@check_recording_first
def main(n_points: int = 37, rrd: str | None = None, show: bool = False) -> mb.ModesAlong:
    t = np.linspace(0.0, 1.0, n_points)  # the motor turns once a second
    model = build()
    along = mb.vibration_modes_along(model, t)
    frequency = along.frequencies[:, 0]

    rigid = mb.kinematic_analysis(four_bar(gravity=0.0), t)  # crank at 2 pi rad/s
    inertia = 2 * rigid.kinetic_energy / (2 * np.pi) ** 2
    check = np.sqrt(STIFFNESS / inertia) / (2 * np.pi)
    crank = np.degrees(along.equilibrium.body("crank").angle)
    print(mb.format_table({"crank [deg]": crank, "frequency [Hz]": frequency,
                           "check [Hz]": check, "inertia [kg m^2]": inertia,
                           "speed to avoid [rpm]": 60 * frequency}, rows=13))
    lowest = int(np.argmin(frequency))
    print(f"\nlowest: {frequency[lowest]:.4f} Hz at a crank angle of {crank[lowest]:.1f} deg; "
          f"largest difference from the check {np.max(np.abs(frequency - check)):.1e} Hz")
    if rrd is not None:
        record_modes(along, rrd, against="crank.theta", overwrite=True, show=show)
        animation = pathlib.Path(rrd).with_name(pathlib.Path(rrd).stem + "_mode.rrd")
        record(along.at(lowest).animation(), animation, overwrite=True)
    return along


if __name__ == "__main__":
    run_script(main, __doc__, "four_bar_modes.rrd")
