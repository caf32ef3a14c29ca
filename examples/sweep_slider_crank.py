"""Slider-crank design map: peak slider speed and peak driving torque over crank speeds and
rod lengths, run as a parameter sweep on a Dask cluster of local worker processes.

Each point of the grid is one inverse-dynamics run of a slider-crank (crank 0.12 m,
Nikravesh's masses) whose crank turns once at constant speed. Rods shorter than the crank
cannot reach the slider line all the way round: those runs fail, are recorded with their
error, and leave a gap in the map. Every finished run is stored in the results folder at
once, so stopping the script (Ctrl-C) and starting it again finishes only the missing points.

The two maps are drawn with their axes and colour bars to sweep_slider_crank.png (with
matplotlib, pip install "mbd3d[plots]") and written to a Rerun recording, the picture and the
raw tensors (speed x rod): rerun sweep_slider_crank.rrd

Run: python examples/sweep_slider_crank.py [--folder FOLDER] [--rrd FILE] [--workers N]
     (pip install "mbd3d[distributed]" for the cluster; without Dask it runs serially)
"""

from __future__ import annotations

import argparse
import math
import os
import uuid

import numpy as np
import rerun as rr

import mbd3d as mb
from mbd3d.mechanisms import slider_crank
from mbd3d.sweeps import Analysis, SweepTable, grid, sweep
from mbd3d.viewer import check_destination

CRANK_LENGTH = 0.12  # [m]


def build(crank_speed: float, rod_length: float) -> mb.Model:
    """The model of one grid point: crank speed [rad/s], rod length [m]."""
    return slider_crank(crank_length=CRANK_LENGTH, rod_length=rod_length,
                        crank_speed=crank_speed, crank_angle=0.0)


def peak_slider_speed(results: mb.Results) -> float:
    """[m/s]"""
    return float(np.max(np.abs(results.body("slider").velocity[:, 0])))


def peak_torque(results: mb.Results) -> float:
    """Largest motor torque over the turn [N m]."""
    return float(np.max(np.abs(results.driver("motor").effort)))


def draw_maps(speeds, rods, speed_map, torque_map, path: str) -> str | None:
    """Both maps as a PNG image with axes and colour bars (failed runs in grey), or None
    without matplotlib (pip install "mbd3d[plots]")."""
    try:
        import matplotlib
        matplotlib.use("Agg")  # a file, never a window
        import matplotlib.pyplot as plt
        from matplotlib.patches import Patch
    except ImportError:
        print('no matplotlib: the maps are in the recording as raw tensors only '
              '(pip install "mbd3d[plots]" to draw them)')
        return None
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), constrained_layout=True)
    for ax, values, title, unit in ((axes[0], speed_map, "peak slider speed", "m/s"),
                                    (axes[1], torque_map, "peak motor torque", "N m")):
        ax.set_facecolor("0.85")  # what shows through where a run failed
        mesh = ax.pcolormesh(speeds, rods, np.ma.masked_invalid(values.T), shading="nearest")
        fig.colorbar(mesh, ax=ax, label=f"{title} [{unit}]")
        ax.set(xlabel="crank speed [rad/s]", ylabel="rod length [m]", title=title)
        if np.any(~np.isfinite(values)):
            ax.legend(handles=[Patch(facecolor="0.85", edgecolor="0.5",
                                     label="failed: the rod cannot reach")],
                      loc="upper right", fontsize="small")
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def main(speeds=np.linspace(5.0, 50.0, 10), rods=np.linspace(0.10, 0.50, 9),
         n_points: int | None = None, folder: str = "sweep_slider_crank", rrd: str | None = None,
         workers: int | None = None, backend: str = "auto") -> SweepTable:
    if rrd is not None:  # a bad path fails now, not after the sweep
        check_destination(rrd)
    points = grid(crank_speed=speeds, rod_length=rods)

    # one analysis for all points: over one turn of the slowest crank, so that every crank
    # passes through every angle (the faster ones turn more than once)
    one_turn = 2 * math.pi / float(np.min(speeds))
    if n_points is None:  # 2 degrees a sample for the fastest crank, so no peak is missed
        n_points = int(180 * np.max(speeds) / np.min(speeds)) + 1
    analysis = Analysis("inverse dynamics", np.linspace(0.0, one_turn, n_points))
    table = sweep(build, points, analysis,
                  {"peak slider speed [m/s]": peak_slider_speed,
                   "peak torque [N m]": peak_torque},
                  folder, workers=workers, backend=backend)
    print(table)
    for row in table.failed[:3]:
        print(f"failed: speed {row['crank_speed']:g} rad/s, rod {row['rod_length']:g} m: "
              f"{row['error']}")

    shape = (len(speeds), len(rods))
    speed_map = table.column("peak slider speed [m/s]").reshape(shape)
    torque_map = table.column("peak torque [N m]").reshape(shape)
    best = np.unravel_index(np.nanargmax(speed_map), shape)
    print(f"fastest slider: {speed_map[best]:.3f} m/s at {speeds[best[0]]:g} rad/s with a "
          f"{rods[best[1]]:g} m rod, needing {torque_map[best]:.3f} N m")

    if rrd is not None:
        recording = rr.RecordingStream("mbd3d sweep_slider_crank", recording_id=uuid.uuid4())
        recording.save(rrd)
        png = draw_maps(speeds, rods, speed_map, torque_map, os.path.splitext(rrd)[0] + ".png")
        if png is not None:  # the maps with their axes and colour bars, as an image
            recording.log("maps/figure", rr.EncodedImage(path=png), static=True)
            print(f"maps drawn to {png}")
        for name, values in (("peak_slider_speed", speed_map), ("peak_torque", torque_map)):
            # the raw values, coloured over their own range (failed points are drawn at it)
            finite = values[np.isfinite(values)]
            low, high = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
            recording.log(f"maps/{name}", rr.Tensor(np.where(np.isfinite(values), values, low),
                                                    dim_names=("crank_speed", "rod_length"),
                                                    value_range=(low, high)), static=True)
        recording.log("maps/axes", rr.TextDocument(
            f"crank speeds [rad/s]: {np.round(speeds, 4).tolist()}\n\n"
            f"rod lengths [m]: {np.round(rods, 4).tolist()}"), static=True)
        recording.disconnect()
        print(f"maps written; view them with: rerun {rrd}")
    return table


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    parser.add_argument("--folder", default="sweep_slider_crank",
                        help="results folder (runs found there are not run again)")
    parser.add_argument("--rrd", default="sweep_slider_crank.rrd", help="recording of the maps")
    parser.add_argument("--workers", type=int, default=None, help="worker processes")
    args = parser.parse_args()
    try:
        main(folder=args.folder, rrd=args.rrd, workers=args.workers)
    except mb.MBDError as error:  # a bad path, no display, ...: the message says what to do
        raise SystemExit(f"error: {error}")
