"""A slider-crank whose rod-slider pin has a clearance: the pin flies in its hole and strikes.

The setup of Flores, Ambrosio, Claro and Lankarani (Proc. IMechE K 2004, "Dynamic behaviour
of planar rigid multi-body systems including revolute joints with clearance"): crank 0.05 m,
rod 0.12 m, masses 0.30, 0.21 and 0.14 kg, the crank driven at 5000 rpm; the joint between
the rod and the slider has a journal of 10 mm radius in a bearing 0.5 mm larger, both steel
(E = 207 GPa, nu = 0.3), with Hertz's contact law calibrated to a restitution of 0.9 (a
compliant contact of a pin in a hole, mbd3d.Hole). The table compares the slider's
acceleration with the ideal joint's: the pin loses contact, strikes and rebounds, and the
acceleration spikes several times above the ideal one, as in the paper's figures, while
between strikes the slider coasts (no force, no acceleration). Its position stays in the band
the clearance leaves about the ideal one: the pin within the clearance plus the dent of the
bearing, the rod turned accordingly, |x - x_ideal| <= (c + dent)(1 + tan(rod angle)).
Recorded to slider_crank_clearance.rrd: rerun slider_crank_clearance.rrd

Run: python examples/slider_crank_clearance.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import math
import warnings

import numpy as np

import mbd3d as mb
from mbd3d.joints import Prismatic, Revolute, RotationDriver
from mbd3d.mechanisms import slider_crank_positions
from mbd3d.viewer import check_recording_first, record, run_script

CRANK, ROD, SPEED = 0.05, 0.12, 5000 * 2 * math.pi / 60  # m, m, rad/s
JOURNAL, CLEARANCE = 0.010, 0.5e-3  # m


def build(clearance: float | None = CLEARANCE) -> mb.Model:
    """The slider-crank, its rod-slider pin a journal in a bearing ``clearance`` [m] larger
    (None: an ideal revolute), the pin in the middle of its hole at the start."""
    a, rod_angle, pin = slider_crank_positions(0.0, CRANK, ROD)
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81),
                        name="slider-crank" + ("" if clearance is None else " with clearance"))
    crank = b.add_body("crank", mass=0.30, inertia=0.0001, position=a / 2, angle=0.0)
    rod = b.add_body("rod", mass=0.21, inertia=0.00025, position=(a + pin) / 2,
                     angle=rod_angle)
    slider = b.add_body("slider", mass=0.14, inertia=0.0001, position=pin)
    motor = b.add(Revolute("O", b.ground, crank, at=(0.0, 0.0)))
    b.add(Revolute("A", crank, rod, at=a))
    b.add(Prismatic("rail", b.ground, slider, axis=(1.0, 0.0)))
    b.add(RotationDriver("motor", motor, motion=mb.Ramp(0.0, SPEED)))
    if clearance is None:
        b.add(Revolute("B", rod, slider, at=pin))
    else:
        law = mb.HertzContact(young_modulus=207e9, poisson_ratio=0.3, restitution=0.9)
        b.add(mb.Contact("B", mb.Sphere(rod, JOURNAL, at=pin),
                         mb.Hole(slider, JOURNAL + clearance, at=pin), law=law))
    return b.build()


def band(res: mb.Results, clearance: float = CLEARANCE) -> float:
    """How far [m] the slider may be from the ideal one: the pin anywhere within the
    clearance plus the deepest dent of the run from the bearing's centre, the rod (at most
    asin(crank / rod) from the rail) turned by the pin's offset across the rail."""
    dent = max(0.0, -float(np.min(res.contacts().gap[:, 0])))
    return (clearance + dent) * (1.0 + math.tan(math.asin(CRANK / ROD)))


@check_recording_first
def main(n_points: int = 401, turns: float = 2.0, rrd: str | None = None,
         show: bool = False) -> tuple[mb.Results, mb.Results]:
    t = np.linspace(0.0, turns * 2 * math.pi / SPEED, n_points)
    ideal = mb.inverse_dynamics(build(None), t)
    with warnings.catch_warnings():
        # the explicit method's steps are as short as the impacts need: expected here
        warnings.simplefilter("ignore", mb.StiffnessWarning)
        res = mb.forward_dynamics(build(), t, method="DOP853", rtol=1e-8, atol=1e-10)
    force = res.contacts().normal_force[:, 0]
    rows = np.unique(np.linspace(0, n_points - 1, 13).astype(int))
    print(mb.format_table({
        "crank [deg]": np.degrees(res.body("crank").angle[rows]) % 360,
        "slider a, ideal [m/s^2]": ideal.body("slider").acceleration[rows, 0],
        "with clearance [m/s^2]": res.body("slider").acceleration[rows, 0],
        "pin force [N]": force[rows],
    }, precision=5))
    a, a_ideal = res.body("slider").acceleration[:, 0], ideal.body("slider").acceleration[:, 0]
    ideal_force = np.linalg.norm(ideal.joint("B").reaction(on="slider").force, axis=1)
    print(f"\npeak slider acceleration {np.max(np.abs(a)):.0f} m/s^2, ideal "
          f"{np.max(np.abs(a_ideal)):.0f} m/s^2; the pin is off its bearing at "
          f"{np.mean(force == 0):.0%} of the outputs; its largest force {np.max(force):.0f} N, "
          f"the ideal pin's {np.max(ideal_force):.0f} N")
    off = np.max(np.abs(res.body("slider").position[:, 0] - ideal.body("slider").position[:, 0]))
    print(f"the slider is at most {off * 1e3:.3f} mm off the ideal one, within the band of "
          f"{band(res) * 1e3:.3f} mm the clearance leaves; {res.stats['steps']} steps")
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res, ideal


if __name__ == "__main__":
    run_script(main, __doc__, "slider_crank_clearance.rrd")
