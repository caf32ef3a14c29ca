"""Cost of the spatial solvers on an N-link chain of bars joined by ball joints.

The spatial analogue of planar_chain.py (same figures): for N = 10, 100, 1000 links, laid along x
and falling under gravity, medians of one constraint Jacobian evaluation, one augmented solve
(including the evaluation of M, Cq, Qe, Qd) and one simulated second with RK45 at rtol 1e-6,
as totals, per integrator step and per body.

Run: python benchmarks/spatial_chain.py [--sizes 10 100 1000] [--no-simulation]
"""

from __future__ import annotations

import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

from planar_chain import report  # noqa: E402  (the shared measuring and printing)

from mbd3d.mechanisms import spatial_chain  # noqa: E402


def main(sizes=(10, 100, 1000), simulate: bool = True) -> list[dict]:
    return report("spatial N-link chain (ball joints)", spatial_chain, sizes, simulate)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[10, 100, 1000])
    parser.add_argument("--no-simulation", action="store_true")
    args = parser.parse_args()
    main(tuple(args.sizes), not args.no_simulation)
