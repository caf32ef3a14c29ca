"""Speed-up of a parameter sweep with 1 and 2 Dask worker processes on this machine.

The sweep is the slider-crank map of examples/sweep_slider_crank.py (inverse dynamics of one
crank turn per point). Each configuration runs ``repeat`` times into a fresh folder; the
printed times are medians and include starting the local cluster, as a user meets them.

Run: python benchmarks/sweep_speedup.py [--points N] [--repeat R]
"""

from __future__ import annotations

import argparse
import math
import pathlib
import statistics
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent / "examples"))

from measure import machine  # noqa: E402
from sweep_slider_crank import build, peak_slider_speed, peak_torque  # noqa: E402
from mbd3d.sweeps import Analysis, grid, sweep  # noqa: E402


def main(points: int = 40, repeat: int = 3, n_points: int = 181) -> dict[str, float]:
    side = max(1, int(round(math.sqrt(points))))
    grid_points = grid(crank_speed=np.linspace(5.0, 50.0, side),
                       rod_length=np.linspace(0.2, 0.5, max(1, points // side)))
    analysis = Analysis("inverse dynamics", np.linspace(0.0, 2 * math.pi / 5.0, n_points))
    metrics = {"peak_speed": peak_slider_speed, "peak_torque": peak_torque}
    print(f"sweep of {len(grid_points)} slider-crank points ({n_points} time points each); "
          f"{machine()}")
    medians = {}
    for label, options in (("serial", {"backend": "serial"}), ("1 worker", {"workers": 1}),
                           ("2 workers", {"workers": 2})):
        walls = []
        for _ in range(repeat):
            with tempfile.TemporaryDirectory() as folder:
                start = time.perf_counter()
                table = sweep(build, grid_points, analysis, metrics, folder, progress=False,
                              **options)
                walls.append(time.perf_counter() - start)
            assert not table.failed, table.failed[0]["error"]
        medians[label] = statistics.median(walls)
        print(f"  {label:>9}: {medians[label]:6.2f} s (median of {repeat})")
    print(f"speed-up 2 workers / 1 worker: {medians['1 worker'] / medians['2 workers']:.2f}; "
          f"2 workers / serial: {medians['serial'] / medians['2 workers']:.2f}")
    return medians


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=40)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    main(points=args.points, repeat=args.repeat)
