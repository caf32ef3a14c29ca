"""What a contact costs against the joint it stands in for: the free slider-crank of
friction.py with its rod-slider pin an ideal revolute, or a journal in a bearing 10 um larger
(a compliant contact that stays closed under the pin's load), per right-hand side (DOP853)
and per step (generalized-alpha), medians of a few runs in one process.

The contact is a force element evaluated in the compiled loop with the others; it replaces
two constraint rows by one force row. The runs' lengths differ (a stiff contact needs short
explicit steps, and generalized-alpha shortens its step into impacts): the cost per
evaluation is what the contact adds to the loop.

Run: python benchmarks/contacts.py [--repeat N]
"""

from __future__ import annotations

import argparse
import math

import numpy as np

import mbd3d as mb
from mbd3d.joints import Prismatic, Revolute
from mbd3d.mechanisms import slider_crank_positions
from measure import cost_with_and_without, machine

PIN, CLEARANCE = 0.01, 1e-5  # m


def build(contact: bool, torque: float = 2.0) -> mb.Model:
    """The free slider-crank under a crank torque, its rod-slider pin a revolute or a pin in
    a hole (steel, Hertz's law, restitution 0.9)."""
    crank_angle = math.radians(65.0)
    a, rod_angle, pin_b = slider_crank_positions(crank_angle, 0.12, 0.26)
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81), name="free slider-crank")
    crank = b.add_body("crank", mass=1.0, inertia=0.001, position=a / 2, angle=crank_angle)
    rod = b.add_body("rod", mass=2.0, inertia=0.01, position=(a + pin_b) / 2, angle=rod_angle)
    slider = b.add_body("slider", mass=4.0, inertia=0.02, position=pin_b)
    b.add(Revolute("O", b.ground, crank, at=(0.0, 0.0)))
    b.add(Revolute("A", crank, rod, at=a))
    b.add(Prismatic("rail", b.ground, slider, axis=(1.0, 0.0)))
    if contact:
        law = mb.HertzContact(young_modulus=207e9, poisson_ratio=0.3, restitution=0.9)
        b.add(mb.Contact("B", mb.Sphere(rod, PIN, at=pin_b),
                         mb.Hole(slider, PIN + CLEARANCE, at=pin_b), law=law))
    else:
        b.add(Revolute("B", rod, slider, at=pin_b))
    b.add(mb.Torque("motor", crank, torque))
    return b.build()


def main(repeat: int = 3, duration: float = 0.5) -> list[dict]:
    print(machine())
    t = np.linspace(0.0, duration, 51)
    rows = cost_with_and_without(build, t, repeat, ignored=(mb.StiffnessWarning,))
    print(mb.format_table({
        "method": [r["method"] for r in rows],
        "pin B": ["pin in a hole" if r["variant"] else "revolute" for r in rows],
        "evaluations or steps": [r["count"] for r in rows],
        "per one [us]": [r["per"] * 1e6 for r in rows],
        "run [s]": [r["wall"] for r in rows],
    }, precision=4))
    for method in ("DOP853", "generalized-alpha"):
        plain, contact = (r["per"] for r in rows if r["method"] == method)
        print(f"{method}: the contact costs {contact / plain:.2f} x the joint per "
              f"{'right-hand side' if method == 'DOP853' else 'step'}")
    # the revolute's run is 500 steps, the contact's twenty times more: its fixed costs
    # (start, outputs) weigh more per step; per Newton iteration they weigh alike
    plain, contact = (r["wall"] / r["iterations"] for r in rows
                      if r["method"] == "generalized-alpha")
    print(f"generalized-alpha: {contact * 1e6:.3g} against {plain * 1e6:.3g} us per Newton "
          f"iteration, {contact / plain:.2f} x")
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    main(repeat=parser.parse_args().repeat)
