"""Spheres in a box (``mbd3d.mechanisms.spheres_in_box``): how the cost of a step grows with
the number of spheres in one contact group, issue #32's "1000 spheres in a box, cost per step
at most like N log N".

Each model is a lattice of N spheres pressed together (``spacing`` below two radii, so that
every sphere touches its lattice neighbours and the bottom layer the floor) in an open box of
ground planes; RK45 follows it for ``DURATION`` as the pile springs apart, at a tolerance that
keeps the steps alike across N. The figure is the wall time per step, and per step and
sphere: with the grid's broad phase a step costs in proportion to the spheres and to the
pairs in touch (a bounded number per sphere), so the last column, the cost per step over ``N
log N`` relative to the smallest N, should not grow. Each N is timed ``--repeat`` times, in
turn with the others, and the median taken.

Run: python benchmarks/spheres_in_box.py [--sizes 250 500 1000 2000 4000] [--repeat 3] [--dim 3]
"""

from __future__ import annotations

import argparse
import math
import pathlib
import sys
import warnings

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

import mbd3d as mb  # noqa: E402
from mbd3d.errors import ContactWarning  # noqa: E402
from mbd3d.mechanisms import spheres_in_box  # noqa: E402
from measure import machine  # noqa: E402

#: the spheres' lattice spacing [radii], the time followed [s] and the tolerance
SPACING, DURATION, RTOL = 1.99, 5e-4, 1e-5


def build(n: int, dim: int) -> mb.Model:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ContactWarning)  # pressed together on purpose
        return spheres_in_box(n, dim=dim, spacing=SPACING, speed=0.0)


def run(model: mb.Model) -> tuple[float, int]:
    """``(wall time [s], steps)`` of one run."""
    res = mb.forward_dynamics(model, [0.0, DURATION], rtol=RTOL, atol=1e-3 * RTOL)
    return res.stats["wall_time"], res.stats["steps"]


def near_pair_count(model: mb.Model) -> int:
    """How many pairs of shapes the broad phase finds near each other at the start."""
    from mbd3d.model.contacts import contact_group  # noqa: PLC0415
    from mbd3d.model import constraints  # noqa: PLC0415
    from mbd3d.numerics.compiled.contact_grid import near_pairs  # noqa: PLC0415

    group = contact_group(model)
    fr = constraints.frames(model, model.q0, np.zeros_like(model.q0))
    bodies, points, values, _ = group._tables(model)[1]
    return len(near_pairs(fr.A, fr.Q, bodies, points, values, 0, len(bodies)))


def measure(sizes: list[int], repeat: int, dim: int) -> list[dict]:
    """Per N, the median wall time per step [s], the steps and the near pairs at the start;
    printed as a table with the cost over ``N log N`` relative to the smallest N."""
    models = {n: build(n, dim) for n in sizes}
    run(build(8, dim))  # compile before timing
    times, steps = {n: [] for n in sizes}, {}
    for _ in range(repeat):
        for n, model in models.items():
            wall, steps[n] = run(model)
            times[n].append(wall / steps[n])
    rows = [{"n": n, "near": near_pair_count(models[n]), "steps": steps[n],
             "per_step": float(np.median(times[n]))} for n in sizes]
    base = rows[0]["per_step"] / (sizes[0] * math.log(sizes[0]))
    print(f"{'N':>6} {'near pairs':>10} {'steps':>6} {'ms/step':>9} {'us/step/N':>10} "
          f"{'/(N log N), rel.':>17}")
    for r in rows:
        n = r["n"]
        print(f"{n:6d} {r['near']:10d} {r['steps']:6d} {1e3 * r['per_step']:9.3f} "
              f"{1e6 * r['per_step'] / n:10.3f} {r['per_step'] / (n * math.log(n)) / base:17.3f}")
    if len(sizes) > 1:
        exponent = np.polyfit(np.log(sizes), np.log([r["per_step"] for r in rows]), 1)[0]
        print(f"cost per step ~ N^{exponent:.3f} over N = {sizes[0]} ... {sizes[-1]}")
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[250, 500, 1000, 2000, 4000])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--dim", type=int, default=3, choices=(2, 3))
    args = parser.parse_args()
    print(machine())
    measure(sorted(args.sizes), args.repeat, args.dim)


if __name__ == "__main__":
    main()
