"""What force elements cost generalized-alpha: their steps in the compiled loop against the same
steps taken from Python.

Since the applied forces' tangent is compiled (``mbd3d/numerics/compiled/force_tangents.py``),
a model whose force elements are all compiled (spring-dampers, rotational ones, point forces
and torques given as constants or built-in motions) takes its steps in the compiled loop
(``alpha_loop.py``) like a model without forces; before, the tangent was built in Python at
every step and the whole step loop ran there. The same steps either way (the suite checks
them bit for bit: ``tests/test_alpha_loop.py``); this script times them, generalized-alpha at
h = 1e-3, with ``mbd3d.analyses.implicit.COMPILED_STEPS`` on and off, the two taken in turn
(medians of ``--repeat`` rounds), and prints the time per step and the ratio:

- Haug's slider-crank (SUNDIALS' idasSlCrank): a spring-damper and a force at a point, 10 s;
- the four-bar driven through a torsion spring (``four_bar(shaft_stiffness=50)``), 2 s;
- a 100-link planar chain with a torsion spring-damper at every pin (banded), 0.5 s;
- two spatial bodies on skew hinges with a torsion spring, a spring-damper, a torque in body
  axes and a force at a point (chart resets), 2 s.

Run: python benchmarks/force_elements.py [--repeat 5]
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))

import mbd3d as mb  # noqa: E402
from mbd3d.analyses import implicit  # noqa: E402
from mbd3d.joints import Revolute  # noqa: E402
from mbd3d.mechanisms import four_bar  # noqa: E402
from measure import interleaved_medians, machine  # noqa: E402


def haug() -> tuple[mb.Model, float]:
    import haug_slider_crank
    return haug_slider_crank.build(), 10.0


def driven_four_bar() -> tuple[mb.Model, float]:
    return four_bar(shaft_stiffness=50.0), 2.0


def sprung_chain(n_links: int = 100) -> tuple[mb.Model, float]:
    b = mb.ModelBuilder(dim=2, name=f"{n_links}-link sprung chain")
    previous = b.ground
    for k in range(n_links):
        body = b.add_body(f"link{k}", mass=1.0, inertia=1 / 12, position=(k + 0.5, 0.0))
        b.add(Revolute(f"pin{k}", previous, body, at=(float(k), 0.0)))
        b.add(mb.RotationalSpringDamper(f"torsion{k}", previous, body, stiffness=200.0,
                                        damping=0.5))
        previous = body
    return b.build(), 0.5


def spatial_pair() -> tuple[mb.Model, float]:
    b = mb.ModelBuilder(dim=3, name="sprung spatial pair")
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    spin = 5.0 * axis
    one = b.add_body("one", mass=1.0, inertia=(0.03, 0.04, 0.05), position=(0.3, 0.0, 0.0),
                     angular_velocity=spin, velocity=np.cross(spin, (0.3, 0.0, 0.0)))
    two = b.add_body("two", mass=0.5, inertia=(0.02, 0.01, 0.02), position=(0.6, 0.2, 0.0),
                     angular_velocity=spin, velocity=np.cross(spin, (0.6, 0.2, 0.0)))
    hinge = b.add(Revolute("first", b.ground, one, at=(0.0, 0.0, 0.0), axis=axis))
    b.add(Revolute("second", one, two, at=(0.6, 0.0, 0.0), axis=(0.0, 0.0, 1.0)))
    b.add(mb.RotationalSpringDamper("torsion", joint=hinge, stiffness=0.05, damping=0.01))
    b.add(mb.SpringDamper("spring", b.ground, two, at_i=(0.5, 0.5, 0.5),
                          point_j=(0.1, 0.0, 0.0), stiffness=40.0, damping=0.2,
                          free_length=0.3))
    b.add(mb.Torque("motor", one, (0.0, 0.0, 0.3), frame="body"))
    b.add(mb.PointForce("push", two, (0.5, 0.0, -1.0), point=(0.1, 0.05, 0.0)))
    return b.build(), 2.0


def timed(model: mb.Model, duration: float, compiled: bool):
    """A run of generalized-alpha at h = 1e-3 with the compiled loop on or off: (results,
    wall time [s])."""
    implicit.COMPILED_STEPS = compiled
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mb.InitialStateWarning)
        res = mb.forward_dynamics(model, np.linspace(0.0, duration, 11),
                                  method="generalized-alpha", step=1e-3)
    return res, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    print(machine())
    rows = {"model": [], "steps": [], "Newton its/step": [], "Python loop [us/step]": [],
            "compiled loop [us/step]": [], "compiled / Python": []}
    for case in (haug, driven_four_bar, sprung_chain, spatial_pair):
        model, duration = case()
        runs = [lambda c=c: timed(model, duration, c) for c in (False, True)]
        (python, _), (compiled, _) = runs[0](), runs[1]()  # compiles and caches
        same = all(np.array_equal(getattr(python, f), getattr(compiled, f))
                   for f in ("q", "qd", "lam"))
        if not same:
            raise SystemExit(f"{model.name}: the two loops' results differ")
        walls = interleaved_medians(runs, args.repeat)
        steps = compiled.stats["steps"]
        rows["model"].append(model.name)
        rows["steps"].append(str(steps))
        rows["Newton its/step"].append(compiled.stats["newton_iterations"] / steps)
        rows["Python loop [us/step]"].append(1e6 * walls[0] / steps)
        rows["compiled loop [us/step]"].append(1e6 * walls[1] / steps)
        rows["compiled / Python"].append(walls[1] / walls[0])
    implicit.COMPILED_STEPS = True
    print(mb.format_table(rows, precision=3))


if __name__ == "__main__":
    main()
