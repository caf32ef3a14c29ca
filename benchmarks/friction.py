"""What joint friction costs: a free slider-crank under a crank torque, with and without
friction in its three pins and its rail, per right-hand side (DOP853) and per step
(generalized-alpha), medians of a few runs in one process.

With friction every evaluation solves the frictions and the reactions together
(mbd3d.model.friction): one augmented solve without friction, one per friction element for
its response, and Newton's method in the frictions, in Python around the compiled solves.

Run: python benchmarks/friction.py [--repeat N]
"""

from __future__ import annotations

import argparse
import math

import numpy as np

import mbd3d as mb
from mbd3d.joints import Prismatic, Revolute
from mbd3d.mechanisms import slider_crank_positions
from measure import cost_with_and_without, machine


def build(friction: bool, torque: float = 2.0) -> mb.Model:
    """The slider-crank of examples/slider_crank_friction.py, free, with a torque on the
    crank and a start at 30 rad/s."""
    crank_angle = math.radians(65.0)
    a, rod_angle, pin_b = slider_crank_positions(crank_angle, 0.12, 0.26)
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81), name="free slider-crank")
    crank = b.add_body("crank", mass=1.0, inertia=0.001, position=a / 2, angle=crank_angle)
    rod = b.add_body("rod", mass=2.0, inertia=0.01, position=(a + pin_b) / 2, angle=rod_angle)
    slider = b.add_body("slider", mass=4.0, inertia=0.02, position=pin_b)
    pins = [b.add(Revolute("O", b.ground, crank, at=(0.0, 0.0))),
            b.add(Revolute("A", crank, rod, at=a)), b.add(Revolute("B", rod, slider, at=pin_b))]
    rail = b.add(Prismatic("rail", b.ground, slider, axis=(1.0, 0.0)))
    b.add(mb.Torque("motor", crank, torque))
    if friction:
        for pin in pins:
            b.add(mb.JointFriction(f"{pin.name} friction", pin, 0.1, pin_radius=0.01))
        b.add(mb.JointFriction("rail friction", rail, 0.15))
    return b.build()


def main(repeat: int = 3, duration: float = 0.5) -> list[dict]:
    print(machine())
    t = np.linspace(0.0, duration, 51)
    rows = cost_with_and_without(build, t, repeat)
    print(f"{'method':18s} {'friction':8s} {'run [s]':>9s} {'count':>7s} {'per item':>12s}")
    for r in rows:
        print(f"{r['method']:18s} {str(r['variant']):8s} {r['wall']:9.4f} {r['count']:7d} "
              f"{r['per'] * 1e6:9.1f} us per {r['unit']}")
    for method in ("DOP853", "generalized-alpha"):
        plain, rubbing = (r for r in rows if r["method"] == method)
        print(f"{method}: friction costs {rubbing['per'] / plain['per']:.1f} x per "
              f"{plain['unit']}")
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, help="runs per median")
    main(repeat=parser.parse_args().repeat)
