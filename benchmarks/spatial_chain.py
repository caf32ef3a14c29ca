"""Cost of the spatial solvers on an N-link chain of bars joined by ball joints, and the same chain
in Exudyn and MuJoCo.

The spatial analogue of planar_chain.py (same figures): the bars laid along x, gravity along
-z, and the whole chain turning at 1 rad/s about the vertical at t = 0, so that it swings out
in three dimensions as it falls (Rodrigues charts are re-referenced as the links turn).

Run: python benchmarks/spatial_chain.py [--sizes 1 10 100 1000 10000] [--peers] [--peer-links 100]
"""

from __future__ import annotations

import argparse
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

from planar_chain import compare_with_peers, report  # noqa: E402  (shared measuring)

from mbd3d.mechanisms import spatial_chain  # noqa: E402

#: rate of the initial rigid rotation about z [rad/s]
SPIN = 1.0


def spinning(model) -> np.ndarray:
    """Rates of the chain turning rigidly at ``SPIN`` about z: ``v = w x R`` for the centres,
    and Rodrigues rates ``g' = w / 2`` (the links start unrotated, ``g = 0``)."""
    qd = np.zeros((model.n_bodies, 6))
    centres = model.q0.reshape(model.n_bodies, 6)[:, :3]
    omega = np.array([0.0, 0.0, SPIN])
    qd[:, :3] = np.cross(omega, centres)
    qd[:, 3:] = omega / 2
    return qd.ravel()


def main(sizes=(1, 10, 100, 1000, 10000), simulate: bool = True, compare: bool = False,
         peer_links: int = 100, method: str = "DOP853") -> list[dict]:
    # 0.02 s above 1000 links: the spinning 10 km chain's tip moves at 10 km/s and takes
    # about 6000 steps per simulated second
    rows = report("spatial N-link chain (ball joints, spinning)", spatial_chain, sizes,
                  simulate, spinning, method, long_span=0.02)
    if compare:
        compare_with_peers(peer_links, spatial_chain, spatial=True, spin=SPIN, rates=spinning)
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1, 10, 100, 1000, 10000])
    parser.add_argument("--no-simulation", action="store_true")
    parser.add_argument("--peers", action="store_true",
                        help="compare with Exudyn and MuJoCo at equal accuracy")
    parser.add_argument("--peer-links", type=int, default=100)
    parser.add_argument("--method", default="DOP853", help="integrator of the simulated runs")
    args = parser.parse_args()
    main(tuple(args.sizes), not args.no_simulation, args.peers, args.peer_links, args.method)
