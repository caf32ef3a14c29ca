"""Cost of recording analyses for the Rerun viewer.

1. Recording finished results: 10,000 time points of a 10-link pendulum chain (planar and
   spatial) to an .rrd file, with everything the viewer shows (poses, shapes, reaction and
   effort arrows, plots of positions, velocities, accelerations, reactions, energies and
   residuals). Median of 3 recordings.
2. Live streaming: the same forward-dynamics run with and without a live Recorder writing the
   file as it goes; the ratio of the median wall times of 3 runs each is the slow-down.

Run: python benchmarks/viewer_logging.py [--points 10000] [--links 10]
"""

from __future__ import annotations

import argparse
import os
import pathlib
import platform
import sys
import tempfile

import numpy as np

import mbd3d as mb
from mbd3d.mechanisms import pendulum_chain, spatial_chain
from mbd3d.viewer import Recorder, record

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from measure import median_time  # noqa: E402  (the shared timer)


def main(points: int = 10_000, links: int = 10, repeat: int = 3) -> list[dict]:
    print(f"Recording for Rerun, {platform.processor() or platform.machine()}, "
          f"Python {platform.python_version()}; {links} links, {points} time points, "
          f"medians of {repeat} runs")
    with tempfile.TemporaryDirectory(prefix="mbd3d-viewer-bench-") as folder:
        rows = [measure(kind, factory, points, links, repeat, folder)
                for kind, factory in (("planar", pendulum_chain), ("spatial", spatial_chain))]
    print(mb.format_table({
        "model": [r["model"] for r in rows],
        "record [s]": [r["record_s"] for r in rows],
        "file [MB]": [r["file_mb"] for r in rows],
        "simulate [s]": [r["simulate_s"] for r in rows],
        "with live recording [s]": [r["live_s"] for r in rows],
        "slow-down": [r["slowdown"] for r in rows],
    }, precision=3))
    return rows


def measure(kind: str, factory, points: int, links: int, repeat: int, folder: str) -> dict:
    """Recording and live-streaming figures of one chain model; files go to ``folder``."""
    t = np.linspace(0.0, points * 1e-3, points)
    model = factory(links)
    res = mb.forward_dynamics(model, t, rtol=1e-6, atol=1e-8)
    counter = iter(range(10**6))

    def record_once():
        record(res, os.path.join(folder, f"{kind}-{next(counter)}.rrd"), announce=False)
    recording = median_time(record_once, repeat)
    size = os.path.getsize(os.path.join(folder, f"{kind}-0.rrd"))

    def simulate(live: bool):
        observers = ([Recorder(os.path.join(folder, f"{kind}-live-{next(counter)}.rrd"),
                               announce=False)] if live else [])
        return mb.forward_dynamics(model, t, rtol=1e-6, atol=1e-8, observers=observers,
                                   progress=False)
    # alternate the two so that machine noise hits both alike
    plain, live = [], []
    for _ in range(repeat):
        plain.append(median_time(lambda: simulate(False), 1))
        live.append(median_time(lambda: simulate(True), 1))
    row = {"model": kind, "record_s": recording, "file_mb": size / 1e6,
           "simulate_s": float(np.median(plain)), "live_s": float(np.median(live))}
    row["slowdown"] = row["live_s"] / row["simulate_s"]
    return row


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=10_000)
    parser.add_argument("--links", type=int, default=10)
    args = parser.parse_args()
    main(args.points, args.links)
