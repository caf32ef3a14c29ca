"""IFToMM benchmark A05, the flyball governor: a spinning shaft, two flyball arms and a sleeve
held by very stiff, heavily damped springs.

A vertical shaft turns freely in a bearing at the ground. Two arms (1 m rods with 5 kg balls at
their ends) hang from hinges at the top of the shaft; the coupler rods to the sleeve that slides
on the shaft are spring-dampers of k = 8e5 N/m and c = 4e4 N s/m. Spun at 2 pi rad/s and let
go, the arms fly out and pull the sleeve up, the shaft slows as they do (its angular momentum is
conserved) and they swing back: a steady oscillation between spin and swing, which the dampers
hardly touch because the stiff springs barely stretch. The springs make the model stiff (the
damper alone relaxes in m / c ~ 1e-4 s): the implicit generalized-alpha integrator takes it
at h = 1e-3 s.

No reference series is published. What the physics guarantees, and the example prints: the
angular momentum about the shaft is conserved (nothing exerts a moment about it), the energy
is conserved but for the millijoules the dampers take, and the governor moves as the same
governor with rigid couplers (Distance links instead of the springs, integrated by DOP853)
does, to the springs' compliance.

Data: IFToMM / MBS benchmark library, problem A05, as built in MBS-BOS (the benchmarks in
OpenSim, RehabEngGroup/MBSbenchmarksInOpenSim, A05_FlyballGovernor); the free-shaft variant.

Recorded to flyball_governor.rrd: rerun flyball_governor.rrd

Run: python examples/flyball_governor.py [--duration S] [--rrd FILE] [--show]
"""

from __future__ import annotations

import numpy as np

import mbd3d as mb
from mbd3d.joints import Distance, Prismatic, Revolute
from mbd3d.viewer import check_recording_first, record, run_script

SPIN = 2 * np.pi                 # initial speed of the shaft [rad/s]
ALPHA = np.radians(30.0)         # arms below the horizontal at t = 0
STIFFNESS, DAMPING, FREE_LENGTH = 8e5, 4e4, 0.5
ROD, BALL = 0.3, 5.0             # masses of an arm's rod and of its ball [kg]
ARM_CENTRE = (ROD * 0.5 + BALL * 1.0) / (ROD + BALL)  # arm's centre of mass from the hinge [m]


def prism(mass: float, length: float, side: float) -> np.ndarray:
    """Principal inertia [kg m^2] of a square prism along its x axis."""
    return mass / 12 * np.array([2 * side**2, length**2 + side**2, length**2 + side**2])


def build(rigid_couplers: bool = False) -> mb.Model:
    """The governor at t = 0: springs at their free length, everything spinning with the shaft.
    ``rigid_couplers``: massless rigid links of the springs' free length instead."""
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -9.81), name="flyball governor")
    spin = (0.0, 0.0, SPIN)

    def spinning(name, mass, inertia, position, orientation):
        # a point of the governor turning rigidly about the z axis at the initial speed
        return b.add_body(name, mass=mass, inertia=inertia, position=position,
                          orientation=orientation, velocity=np.cross(spin, position),
                          angular_velocity=spin)

    # shaft: 1 m x 1 cm x 1 cm, 3000 kg/m^3, along z (body x axis turned onto z)
    along_z = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
    shaft = spinning("shaft", 0.3, prism(0.3, 1.0, 0.01), (0.0, 0.0, 0.5), along_z)
    b.add(Revolute("bearing", b.ground, shaft, at=(0.0, 0.0, 0.0), axis=(0.0, 0.0, 1.0)))
    sleeve = spinning("sleeve", 3.0, np.full(3, 3.0 * 0.1**2 / 6), (0.0, 0.0, 0.5), np.eye(3))
    b.add(Prismatic("sleeve guide", shaft, sleeve, axis=(0.0, 0.0, 1.0)))
    # each arm: the rod (0.3 kg) and its ball (a 5 kg point mass at the rod's end) as one body,
    # its centre of mass and inertia by the parallel-axis theorem (body x axis along the rod)
    mass, centre = ROD + BALL, ARM_CENTRE
    inertia = prism(ROD, 1.0, 0.01) + np.array(
        [0.0, 1.0, 1.0] * np.array(ROD * (0.5 - centre)**2 + BALL * (1.0 - centre)**2))
    for side, sign in (("right", 1.0), ("left", -1.0)):
        hinge = np.array([0.05 * sign, 0.0, 1.0])
        direction = np.array([np.cos(ALPHA) * sign, 0.0, -np.sin(ALPHA)])
        x = direction
        y = np.array([0.0, sign, 0.0])  # hinge axis, right-handed frame (x, y, x cross y)
        arm = spinning(f"arm {side}", mass, inertia, hinge + centre * direction,
                       np.column_stack([x, y, np.cross(x, y)]))
        b.add(Revolute(f"hinge {side}", shaft, arm, at=hinge, axis=(0.0, 1.0, 0.0)))
        point_i, point_j = spring_points(sign)
        if rigid_couplers:
            b.add(Distance(f"coupler {side}", sleeve, arm, point_i=point_i, point_j=point_j,
                           length=FREE_LENGTH))
            continue
        b.add(mb.SpringDamper(f"spring {side}", sleeve, arm, point_i=point_i, point_j=point_j,
                              stiffness=STIFFNESS, damping=DAMPING, free_length=FREE_LENGTH))
    return b.build()


def spring_points(sign: float) -> tuple[np.ndarray, np.ndarray]:
    """A spring's ends in the frames of the sleeve and of its arm (the rod's mid-point) [m]."""
    return np.array([0.05 * sign, 0.0, 0.0]), np.array([0.5 - ARM_CENTRE, 0.0, 0.0])


def angular_momentum_z(res: mb.Results) -> np.ndarray:
    """Angular momentum about the global z axis [kg m^2/s] at every time point."""
    total = np.zeros(len(res.t))
    for body in res.model.bodies:
        motion = res.body(body.name)
        inertia = motion.rotation @ body.inertia @ np.swapaxes(motion.rotation, 1, 2)
        spin = np.einsum("kij,kj->ki", inertia, motion.angular_velocity)
        total += spin[:, 2] + body.mass * np.cross(motion.position, motion.velocity)[:, 2]
    return total


@check_recording_first
def main(duration: float = 5.0, step: float = 1e-3, rrd: str | None = None,
         show: bool = False) -> mb.Results:
    model = build()
    print(mb.mobility(model), "\n")
    t = np.linspace(0.0, duration, int(round(duration / 0.01)) + 1)
    res = mb.forward_dynamics(model, t, method="generalized-alpha", step=step)
    sleeve = res.body("sleeve").position[:, 2]
    shaft_speed = res.body("shaft").angular_velocity[:, 2]
    momentum = angular_momentum_z(res)
    energy = res.kinetic_energy + res.potential_energy
    print(mb.format_table({"t [s]": t, "sleeve height [m]": sleeve,
                           "shaft speed [rad/s]": shaft_speed, "energy [J]": energy}, rows=11))
    drift = np.max(np.abs(momentum - momentum[0]))
    print(f"\nangular momentum about the shaft: {momentum[0]:.6f} kg m^2/s, drift "
          f"{drift:.1e} kg m^2/s ({drift / abs(momentum[0]):.1e} of it)")
    print(f"energy: largest change {np.max(np.abs(energy - energy[0])):.1e} J of "
          f"{energy[0]:.2f} J")
    rigid = mb.forward_dynamics(build(rigid_couplers=True), t, method="DOP853", rtol=1e-10,
                                atol=1e-12)
    print(f"sleeve height against the governor with rigid couplers: largest difference "
          f"{np.max(np.abs(sleeve - rigid.body('sleeve').position[:, 2])):.1e} m")
    print(f"{res.stats['steps']} steps of {step:g} s, {res.stats['wall_time']:.1f} s of wall time")
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res


if __name__ == "__main__":
    run_script(main, __doc__, "flyball_governor.rrd",
               {"--duration": {"type": float, "default": 5.0, "help": "simulated time [s]"}})
