"""What a time point of inverse dynamics costs (positions by Newton-Raphson from the last point,
velocities, accelerations, multipliers), solved in one compiled call, through LAPACK with the
Jacobian factored densely, and through SuperLU with it sparse; and that cost against one
``mb.forward_accelerations`` call at the model's initial state (issue #34's target for the
1000-link chain: at most 10 times).

Models: the PUMA 560 of tests/data driven by a harmonic motion at each joint (36 coordinates),
and planar chains driven at every pin (60 to 3000 coordinates). Medians of a few runs of 201
points in one process. The compiled call is what the library uses where the model allows
(mbd3d.analyses.kinematics.COMPILED_POINTS), with the Jacobian dense or, ordered along the
chain, banded (mbd3d.numerics.patterns.jacobian_layout); otherwise it factors densely up to
mbd3d.model.constraints.KINEMATIC_DENSE_LIMIT coordinates and sparse above. The dense column
is left out above 600 coordinates.

Run: python benchmarks/kinematics.py [--repeat N]
"""

from __future__ import annotations

import argparse
import math
import pathlib
import warnings

import numpy as np

import mbd3d as mb
from mbd3d.analyses import kinematics
from mbd3d.mechanisms import driven_chain
from mbd3d.model import constraints
from measure import machine, median_time

ROOT = pathlib.Path(__file__).resolve().parents[1]


def puma() -> mb.Model:
    """The PUMA 560, each joint on a harmonic motion about its odd pose."""
    amplitude = [0.8, 0.6, -0.7, 1.2, 0.9, -1.5]
    rate = [1.3, 2.1, 1.7, 3.0, 2.6, 3.4]
    start = [0.3, -0.7, 1.1, 0.4, -0.9, 0.6]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mb.UrdfWarning)
        return mb.load_urdf(ROOT / "tests" / "data" / "puma560.urdf", drive={
            f"joint{i + 1}": mb.Harmonic(amplitude[i], rate[i], 0.0, start[i]) for i in range(6)})


def per_point(model: mb.Model, path: str, repeat: int, points: int = 201) -> float:
    """Median cost of one time point [s] by ``path``: "compiled", "dense" (LAPACK) or
    "sparse" (SuperLU)."""
    limit, compiled = constraints.KINEMATIC_DENSE_LIMIT, kinematics.COMPILED_POINTS
    constraints.KINEMATIC_DENSE_LIMIT = -1 if path == "sparse" else 10 ** 9
    kinematics.COMPILED_POINTS = path == "compiled"
    try:
        t = np.linspace(0.0, 1.0, points)
        mb.inverse_dynamics(model, t[:3])  # compiles
        return median_time(lambda: mb.inverse_dynamics(model, t), repeat) / points
    finally:
        constraints.KINEMATIC_DENSE_LIMIT, kinematics.COMPILED_POINTS = limit, compiled


def accelerations_call(model: mb.Model, repeat: int) -> float:
    """Median cost [s] of one ``mb.forward_accelerations`` call at the initial state."""
    q, qd = model.q0, np.zeros(model.n_coordinates)
    mb.forward_accelerations(model, 0.0, q, qd)  # compiles
    calls = 200
    return median_time(lambda: [mb.forward_accelerations(model, 0.0, q, qd)
                                for _ in range(calls)], repeat) / calls


def main(repeat: int = 3, links: tuple = (20, 33, 50, 100, 200, 1000), points: int = 201
         ) -> list[dict]:
    print(machine())
    rows = []
    for label, build in [("PUMA 560", puma)] + [
            (f"{n}-link chain", lambda n=n: driven_chain(n)) for n in links]:
        model = build()
        row = {"model": label, "n": model.n_coordinates,
               "compiled": per_point(model, "compiled", repeat, points),
               "dense": (per_point(model, "dense", repeat, points)
                         if model.n_coordinates <= 600 else math.nan),
               "sparse": per_point(model, "sparse", repeat, points),
               "accelerations": accelerations_call(model, repeat)}
        rows.append(row)
    print(mb.format_table({
        "model": [r["model"] for r in rows],
        "coordinates": [r["n"] for r in rows],
        "compiled [us/point]": [r["compiled"] * 1e6 for r in rows],
        "dense [us/point]": [r["dense"] * 1e6 for r in rows],
        "sparse [us/point]": [r["sparse"] * 1e6 for r in rows],
        "dense / compiled": [r["dense"] / r["compiled"] for r in rows],
        "sparse / dense": [r["sparse"] / r["dense"] for r in rows],
        "forward_accelerations [us]": [r["accelerations"] * 1e6 for r in rows],
        "compiled / forward_accelerations": [r["compiled"] / r["accelerations"] for r in rows],
    }, precision=4))
    print("the compiled call factors the Jacobian in a band where an ordering makes it narrow; "
          f"the library factors densely up to {constraints.KINEMATIC_DENSE_LIMIT} coordinates "
          "where the compiled call does not apply")
    print("issue #34's target: a time point of the 1000-link chain at most 10 times one "
          "forward_accelerations call, its cost linear in the size")
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    main(repeat=parser.parse_args().repeat)
