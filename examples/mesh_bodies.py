"""Bodies made from meshes: a steel pendulum whose mass properties come from its geometry.

A steel arm (a 40 x 4 x 2 cm box) hangs from a hinge at its top end; a steel disc (16 cm
across, 2 cm thick, a 64-sided trimesh cylinder) is welded to its lower end. Each body is given
as a trimesh mesh and a density: mbd3d computes its mass, centre of mass and inertia from the
mesh, puts the body frame at the centre of mass, and the viewer draws the mesh.

The script prints those mass properties next to the textbook formulas for a box and a disc,
then lets the pendulum swing from 5 degrees and compares its period with the compound-pendulum
formula T = 2 pi sqrt(I_O / (m g d)) (1 + theta0^2 / 16).

Recorded to mesh_bodies.rrd: rerun mesh_bodies.rrd

Run: python examples/mesh_bodies.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import math

import numpy as np
import trimesh

import mbd3d as mb
from mbd3d.joints import Fixed, Revolute
from mbd3d.viewer import check_recording_first, record, run_script

STEEL = 7850.0  # kg/m^3


LENGTH, RADIUS, THETA0 = 0.40, 0.08, math.radians(5.0)


def build() -> mb.Model:
    """The pendulum, released 5 degrees from hanging (examples/models/mesh_bodies.yaml, with
    the meshes beside it)."""
    arm_mesh = trimesh.creation.box(extents=(0.04, LENGTH, 0.02))      # along y, centred
    disc_mesh = trimesh.creation.cylinder(radius=RADIUS, height=0.02, sections=64)  # axis z
    swing = mb.rotations.axis_angle((0.0, 0.0, 1.0), THETA0)  # the drawing, turned by theta0
    b = mb.ModelBuilder(dim=3, gravity=(0.0, -9.81, 0.0), name="mesh pendulum")
    arm = b.add_body("arm", shape=arm_mesh, density=STEEL, orientation=swing,
                     position=swing @ (0.0, -LENGTH / 2, 0.0))
    disc = b.add_body("disc", shape=disc_mesh, density=STEEL, orientation=swing,
                      position=swing @ (0.0, -LENGTH, 0.0))
    b.add(Revolute("hinge", b.ground, arm, at=(0.0, 0.0, 0.0), axis=(0.0, 0.0, 1.0)))
    b.add(Fixed("weld", arm, disc, at=swing @ (0.0, -LENGTH, 0.0)))
    return b.build()


@check_recording_first
def main(periods: float = 3.0, n_points: int = 301, rrd: str | None = None,
         show: bool = False) -> mb.Results:
    length, radius = LENGTH, RADIUS
    model = build()
    arm, disc = model.body("arm"), model.body("disc")

    # what the meshes gave, against the closed forms of a box and of a circular disc
    m_arm = STEEL * 0.04 * length * 0.02
    m_disc = STEEL * math.pi * radius**2 * 0.02
    print(mb.format_table({
        "body": ["arm", "disc"],
        "mass [kg]": [arm.mass, disc.mass],
        "closed form [kg]": [m_arm, m_disc],
        "I_zz [kg m2]": [arm.inertia[2, 2], disc.inertia[2, 2]],
        "closed form [kg m2]": [m_arm * (0.04**2 + length**2) / 12, m_disc * radius**2 / 2],
    }, precision=6))
    print("(the disc is a 64-sided prism: 0.16 % less area than the circle)\n")

    # the compound pendulum about the hinge, from the mesh properties
    mass = arm.mass + disc.mass
    d = (arm.mass * length / 2 + disc.mass * length) / mass
    inertia_o = (arm.inertia[2, 2] + arm.mass * (length / 2) ** 2
                 + disc.inertia[2, 2] + disc.mass * length**2)
    period = 2 * math.pi * math.sqrt(inertia_o / (mass * 9.81 * d)) * (1 + THETA0**2 / 16)

    t = np.linspace(0.0, periods * period, n_points)
    res = mb.forward_dynamics(model, t, method="DOP853", rtol=1e-10, atol=1e-12)
    x_axis = res.body("arm").rotation[:, :, 0]
    angle = np.arctan2(x_axis[:, 1], x_axis[:, 0])
    # downward zero crossings of the angle, interpolated: one per period
    k = np.flatnonzero((angle[:-1] > 0) & (angle[1:] <= 0))
    crossings = t[k] + (t[k + 1] - t[k]) * angle[k] / (angle[k] - angle[k + 1])
    energy = res.kinetic_energy + res.potential_energy
    print(f"period: simulated {np.mean(np.diff(crossings)):.6f} s, "
          f"formula {period:.6f} s")
    print(f"energy change over the run: {np.ptp(energy):.2e} J "
          f"(of {energy[0] - (-mass * 9.81 * d):.4f} J of swing)")
    if rrd is not None:
        record(res, rrd, overwrite=True, points={"disc rim": ("disc", (radius, 0.0, 0.0))},
               show=show)
    return res


if __name__ == "__main__":
    run_script(main, __doc__, "mesh_bodies.rrd")
