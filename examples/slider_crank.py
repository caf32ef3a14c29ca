"""Slider-crank: kinematic analysis, inverse dynamics and forward dynamics.

The acceptance case of the original program: a crank pinned to the ground, a connecting rod and
a piston sliding on a ground line (crank 0.12 m, rod 0.26 m, Nikravesh's masses; gravity -y).

1. Kinematic screen: the crank turns at a constant 2 pi rad/s; slider position, velocity and
   acceleration, rod angle.
2. Force screen (inverse dynamics): the motor torque and the pin reactions that motion needs.
3. Forward dynamics: the motor is replaced by a known constant moment on the crank, starting
   from rest; the crank angle and speed, and the energy balance (work of the moment =
   change of kinetic + potential energy).

The inverse-dynamics run (both screens) is recorded to slider_crank.rrd and the forward run
to slider_crank_forward.rrd, for the Rerun viewer: rerun slider_crank.rrd

Run: python examples/slider_crank.py [--rrd FILE] [--show] [--csv FOLDER]
"""

from __future__ import annotations

import math
import os

import numpy as np

import mbd3d as mb
from mbd3d.io.files import check_output_folder
from mbd3d.mechanisms import slider_crank
from mbd3d.viewer import check_recording_first, record, run_script


def build() -> mb.Model:
    """The slider-crank of the kinematic and force analyses: crank at 2 pi rad/s from 65
    degrees (examples/models/slider_crank.yaml is the same model as a file)."""
    return slider_crank(crank_angle=math.radians(65.0), crank_speed=2 * math.pi)


@check_recording_first
def main(n_points: int = 201, duration: float = 1.0, moment: float = 2.0,
         csv_folder: str | None = None, rrd: str | None = None,
         show: bool = False) -> dict[str, mb.Results]:
    if csv_folder is not None:
        check_output_folder(csv_folder, "the CSV files")
    # 1. kinematics: crank at constant speed from 65 degrees
    model = build()
    print(mb.mobility(model), "\n")
    t = np.linspace(0.0, duration, n_points)
    kin = mb.inverse_dynamics(model, t)
    slider, rod = kin.body("slider"), kin.body("rod")
    print("Kinematic analysis (crank at 2 pi rad/s)")
    print(mb.format_table({
        "t [s]": t,
        "crank [deg]": np.degrees(kin.body("crank").angle),
        "rod [deg]": np.degrees(rod.angle),
        "x_slider [m]": slider.position[:, 0],
        "v_slider [m/s]": slider.velocity[:, 0],
        "a_slider [m/s2]": slider.acceleration[:, 0],
    }, rows=9))

    # 2. forces: what the motor must supply and what the pins carry
    pin_o = kin.joint("O").reaction(on="crank")
    pin_b = kin.joint("B").reaction(on="slider")
    rail = kin.joint("rail").reaction(on="slider", frame="joint")
    print("\nForce analysis (inverse dynamics); reactions on the named body, global axes")
    print(mb.format_table({
        "t [s]": t,
        "torque [N m]": kin.driver("motor").effort,
        "O_x on crank [N]": pin_o.force[:, 0],
        "O_y on crank [N]": pin_o.force[:, 1],
        "B_x on slider [N]": pin_b.force[:, 0],
        "rail normal [N]": rail.force[:, 1],
    }, rows=9))

    # 3. forward dynamics: a known moment on the crank instead of the motor
    free = slider_crank(crank_angle=math.radians(65.0), crank_speed=None, crank_torque=moment)
    dyn = mb.forward_dynamics(free, t, method="DOP853", rtol=1e-10, atol=1e-12)
    crank = dyn.body("crank")
    energy = dyn.kinetic_energy + dyn.potential_energy
    work = moment * (crank.angle - crank.angle[0])
    print(f"\nForward dynamics: constant moment {moment} N m on the crank, from rest")
    print(mb.format_table({
        "t [s]": t,
        "crank [deg]": np.degrees(crank.angle),
        "crank speed [rad/s]": crank.angular_velocity,
        "x_slider [m]": dyn.body("slider").position[:, 0],
        "work - dE [J]": work - (energy - energy[0]),
        "|C| [m]": dyn.position_residual,
    }, rows=9))
    print(f"  {dyn.stats['steps']} steps, {dyn.stats['projections']} projections, "
          f"{dyn.stats['wall_time']:.2f} s")

    if csv_folder is not None:
        for name, res in (("slider_crank_inverse_dynamics", kin), ("slider_crank_forward", dyn)):
            path = os.path.join(csv_folder, f"{name}.csv")
            res.to_csv(path)
            print(f"wrote {path}")
    if rrd is not None:
        # a path with the coupler's midpoint traced; prints where the file went
        record(kin, rrd, overwrite=True, points={"rod middle": ("rod", (0.0, 0.0))}, show=show)
        stem, ext = os.path.splitext(rrd)
        record(dyn, f"{stem}_forward{ext or '.rrd'}", overwrite=True)
    return {"inverse": kin, "forward": dyn}


if __name__ == "__main__":
    run_script(main, __doc__, "slider_crank.rrd",
               {"--csv": {"dest": "csv_folder", "metavar": "FOLDER",
                          "help": "also write the results as CSV files"}})
