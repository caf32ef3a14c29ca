"""A heavy spinning top in steady precession.

A solid cone (0.1 m high, 0.05 m base radius, 2700 kg/m^3) stands on its tip, tilted 60 degrees
from the vertical. Spun at omega_s = m g l / (C omega_p) + (A - C)/C omega_p cos(alpha) about
its axis, it precesses at exactly omega_p = 10 rad/s without nodding. The table shows the
nutation angle staying at 60 degrees, the azimuth advancing 10 rad/s, and the tip reaction.

Recorded to spinning_top.rrd (drawn as the cone, with the path of a point on its rim):
rerun spinning_top.rrd

Run: python examples/spinning_top.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import math

import numpy as np
import trimesh

import mbd3d as mb
from mbd3d.numerics import rotations
from mbd3d.joints import Spherical
from mbd3d.viewer import check_recording_first, record, run_script


M, J1, J3, L = 0.706858347, 5.30143760e-4, 5.30143760e-4, 0.075  # cone, about its centre
ALPHA, OMEGA_P = math.radians(60.0), 10.0  # nutation angle, precession rate [rad/s]
# the spin that makes the precession steady: m g l = omega_p (C omega_3 - A omega_p cos alpha)
OMEGA_S = (M * 9.81 * L / (J3 * OMEGA_P)
           + (J1 + M * L * L - J3) / J3 * OMEGA_P * math.cos(ALPHA))


def build() -> mb.Model:
    """The top, started in steady precession (examples/models/spinning_top.yaml)."""
    tilt = rotations.axis_angle((0.0, 1.0, 0.0), ALPHA)
    axis = tilt[:, 2]
    omega = OMEGA_P * np.array([0.0, 0.0, 1.0]) + OMEGA_S * axis
    # drawn as the cone, apex down at the tip; its centre of mass is a quarter height up
    cone = trimesh.creation.cone(radius=0.05, height=0.1, sections=64)
    cone.apply_transform(trimesh.transformations.rotation_matrix(math.pi, (1, 0, 0)))
    cone.apply_translation((0.0, 0.0, 0.025))
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -9.81), name="spinning top")
    top = b.add_body("top", mass=M, inertia=(J1, J1, J3), position=L * axis, orientation=tilt,
                     velocity=np.cross(omega, L * axis), angular_velocity=omega, shape=cone)
    b.add(Spherical("tip", b.ground, top, at=(0.0, 0.0, 0.0)))
    return b.build()


@check_recording_first
def main(duration: float = 1.0, n_points: int = 201, rrd: str | None = None,
         show: bool = False) -> mb.Results:
    omega_s, omega_p = OMEGA_S, OMEGA_P
    t = np.linspace(0.0, duration, n_points)
    res = mb.forward_dynamics(build(), t, method="DOP853", rtol=1e-11, atol=1e-12)

    symmetry_axis = res.body("top").rotation[:, :, 2]
    nutation = np.degrees(np.arccos(symmetry_axis[:, 2]))
    azimuth = np.unwrap(np.arctan2(symmetry_axis[:, 1], symmetry_axis[:, 0]))
    tip_z = res.joint("tip").reaction(on="top").force[:, 2]
    print(f"spin {omega_s:.2f} rad/s about the axis, precession {omega_p} rad/s\n")
    print(mb.format_table({"t [s]": t, "nutation [deg]": nutation, "azimuth [rad]": azimuth,
                           "tip force z [N]": tip_z}, precision=8, rows=11))
    # steady precession by hand: the nutation stays at alpha, the azimuth is omega_p t, and the
    # centre of mass circles at a constant height, so the tip carries the weight m g
    print(f"\nlargest departures from steady precession: nutation "
          f"{np.max(np.abs(nutation - math.degrees(ALPHA))):.1e} deg, azimuth "
          f"{np.max(np.abs(azimuth - omega_p * t)):.1e} rad, tip force "
          f"{np.max(np.abs(tip_z - M * 9.81)):.1e} N (m g = {M * 9.81:.4f} N)")
    print(f"\n{res.stats['steps']} steps, {res.stats['chart_resets']} chart resets "
          f"(the top turns {omega_s * duration / (2 * math.pi):.0f} times about its axis)")
    if rrd is not None:
        record(res, rrd, overwrite=True, points={"rim": ("top", (0.05, 0.0, 0.025))}, show=show)
    return res


if __name__ == "__main__":
    run_script(main, __doc__, "spinning_top.rrd")
