"""Andrews' squeezing mechanism: a published stiff-in-time benchmark, 7 bodies and 10 revolutes.

The planar mechanism of Hairer & Wanner (Solving ODEs II, sect. VII.7) and of the Bari Test Set
for IVP solvers: a crank driven by a constant 0.033 N m turns about 2.5 revolutions in 0.03 s
against a spring, through a linkage with three closed loops. The Test Set integrates it in 7
relative angles; here it is built as a user would, from 7 rigid bodies, 10 revolute joints, a
spring to the ground and a torque, and the angles at t = 0.03 s are compared with the published
reference (PSIDE at tolerance 1e-14).

Data: E. Hairer, G. Wanner, *Solving Ordinary Differential Equations II*, 2nd ed., Springer
1996, section VII.7, and the Test Set for IVP Solvers (University of Bari), problem "andrews":
parameters, joint points, consistent initial values and the reference solution at 0.03 s.

Recorded to andrews_squeezer.rrd: rerun andrews_squeezer.rrd

Run: python examples/andrews_squeezer.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import numpy as np

import mbd3d as mb
from mbd3d.joints import Revolute
from mbd3d.viewer import check_recording_first, record, run_script

#: Test Set reference at t = 0.03 s: beta, Theta, gamma, Phi, delta, Omega, epsilon [rad]
REFERENCE = np.array([0.1581077119629904e+2, -0.1575637105984298e+2, 0.4082224013073101e-1,
                      -0.5347301163226948e+0, 0.5244099658805304e+0, 0.5347301163226948e+0,
                      0.1048080741042263e+1])
NAMES = ("beta", "Theta", "gamma", "Phi", "delta", "Omega", "epsilon")
A, B, C = (-0.06934, -0.00227), (-0.03635, 0.03273), (0.014, 0.072)  # ground points [m]


def build() -> mb.Model:
    """The squeezer at t = 0 (assembled, at rest), bodies 1-7 in the Test Set's order."""
    b = mb.ModelBuilder(dim=2, name="Andrews' squeezer")  # no gravity
    # mass [kg], inertia [kg m^2], centre of mass [m] and angle [rad] at t = 0
    data = [(0.04325, 2.194e-6, (0.000918248598031, -0.000056740745629), -0.061713890014276),
            (0.00365, 4.410e-7, (-0.004491433359933, 0.000277536255794), -0.061713890014276),
            (0.02373, 5.255e-6, (-0.018742186670315, 0.020485106789074), 0.455279819163070),
            (0.00706, 5.667e-7, (-0.030222939830159, 0.012071182356664), 0.710033369709728),
            (0.07050, 1.169e-5, (-0.053236828155704, 0.016631847966616), 0.487364979543843),
            (0.00706, 5.667e-7, (-0.028543268536784, -0.010722254707252), 1.007879054383935),
            (0.05498, 1.912e-5, (-0.059262402801792, -0.010600698332713), 1.230547444549821)]
    k1, k2, k3, k4, k5, k6, k7 = (
        b.add_body(f"body{n + 1}", mass=m, inertia=inertia, position=s, angle=phi)
        for n, (m, inertia, s, phi) in enumerate(data))
    ground = b.ground
    # joint points in the body frames (centre of mass, x axis at the body angle)
    b.add(Revolute("O", ground, k1, point_i=(0.0, 0.0), point_j=(-0.00092, 0.0)))
    b.add(Revolute("F", k1, k2, point_i=(0.00608, 0.0), point_j=(0.0115, 0.0)))
    b.add(Revolute("E23", k2, k3, point_i=(-0.0165, 0.0), point_j=(-0.01043, -0.01626)))
    b.add(Revolute("E24", k2, k4, point_i=(-0.0165, 0.0), point_j=(0.0, -0.01421)))
    b.add(Revolute("E26", k2, k6, point_i=(-0.0165, 0.0), point_j=(0.01421, 0.0)))
    b.add(Revolute("B", ground, k3, point_i=B, point_j=(-0.01043, 0.01874)))
    b.add(Revolute("G", k4, k5, point_i=(0.0, 0.00579), point_j=(0.01692, -0.00916)))
    b.add(Revolute("A5", ground, k5, point_i=A, point_j=(-0.02308, -0.00916)))
    b.add(Revolute("A7", ground, k7, point_i=A, point_j=(0.00449, 0.01228)))
    b.add(Revolute("H", k6, k7, point_i=(-0.00579, 0.0), point_j=(0.00449, -0.02772)))
    b.add(mb.SpringDamper("spring", ground, k3, point_i=C, point_j=(0.00957, 0.00074),
                          stiffness=4530.0, free_length=0.07785))
    b.add(mb.Torque("motor", k1, 0.033))
    return b.build()


def test_set_angles(res: mb.Results) -> np.ndarray:
    """The Test Set's 7 angles (k, 7) from the absolute body angles."""
    phi = np.column_stack([res.body(f"body{n}").angle for n in range(1, 8)])
    return np.column_stack([phi[:, 0], phi[:, 1] - phi[:, 0], phi[:, 2], phi[:, 3] - phi[:, 4],
                            phi[:, 4], phi[:, 5] - phi[:, 6], phi[:, 6]])


@check_recording_first
def main(n_points: int = 301, rtol: float = 1e-11, rrd: str | None = None,
         show: bool = False) -> mb.Results:
    model = build()
    print(mb.mobility(model), "\n")
    t = np.linspace(0.0, 0.03, n_points)
    res = mb.forward_dynamics(model, t, method="DOP853", rtol=rtol, atol=1e-14,
                              constraint_tol=1e-12)
    angles = test_set_angles(res)[-1]
    print(mb.format_table({
        "angle": list(NAMES),
        "t = 0.03 s [rad]": angles,
        "Test Set [rad]": REFERENCE,
        "relative error": np.abs(angles - REFERENCE) / np.abs(REFERENCE),
    }, precision=13))
    energy = res.kinetic_energy + res.potential_energy
    work = 0.033 * (res.body("body1").angle - res.body("body1").angle[0])
    print(f"\nenergy balance: T + V - E0 - work of the motor = "
          f"{np.max(np.abs(energy - energy[0] - work)):.2e} J (of {work[-1]:.4f} J of work)")
    print(f"{res.stats['steps']} steps, {res.stats['wall_time']:.1f} s of wall time")
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res


if __name__ == "__main__":
    run_script(main, __doc__, "andrews_squeezer.rrd")
