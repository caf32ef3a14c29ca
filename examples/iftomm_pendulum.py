"""IFToMM benchmark A01: a simple pendulum over 2000 s against the library's reference series.

A 1 kg point mass on a massless 1 m link, pinned at the origin, released from rest with the
link horizontal (x = -1 m, as the reference file starts), gravity 9.81 m/s^2 along -y. The
benchmark asks for the mass's x and y every 0.5 s for 2000 s (about 845 swings) within 1e-3 m
("high precision"); its reference series is in examples/data/. The script prints the
largest error against it and the drift of the total energy (zero at the start).

Built as a user would: the mass is a body whose inertia does not matter (the link holds it by
its centre, so nothing turns it) and the link a Distance joint.

Source: IFToMM / MBS benchmark library, problem A01 (M. Gonzalez et al., Univ. of A Coruna);
the reference series and its source: examples/data/README.md.

Recorded to iftomm_pendulum.rrd: rerun iftomm_pendulum.rrd

Run: python examples/iftomm_pendulum.py [--duration 2000] [--rtol 1e-12] [--rrd FILE] [--show]
(a few minutes)
"""

from __future__ import annotations

import pathlib

import numpy as np

import mbd3d as mb
from mbd3d.joints import Distance
from mbd3d.viewer import check_recording_first, record, run_script

#: the benchmark\'s reference series, with its source in data/README.md
REFERENCE = pathlib.Path(__file__).resolve().parent / "data" / "iftomm_A01_simple_pendulum_P1.txt"


def build() -> mb.Model:
    """A point mass of 1 kg on a massless 1 m link, released horizontally
    (examples/models/iftomm_pendulum.yaml)."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81), name="IFToMM A01 pendulum")
    mass = b.add_body("P1", mass=1.0, inertia=1e-3, position=(-1.0, 0.0))
    b.add(Distance("link", b.ground, mass, point_i=(0.0, 0.0), point_j=(0.0, 0.0)))
    return b.build()


@check_recording_first
def main(duration: float = 2000.0, rtol: float = 1e-12, rrd: str | None = None,
         show: bool = False) -> mb.Results:
    reference = np.loadtxt(REFERENCE, skiprows=1)
    reference = reference[reference[:, 0] <= duration + 1e-9]
    res = mb.forward_dynamics(build(), reference[:, 0], method="DOP853", rtol=rtol,
                              atol=1e-12)
    error = np.abs(res.body("P1").position - reference[:, 1:])
    energy = res.kinetic_energy + res.potential_energy
    print(f"{duration:g} s, {len(res)} output points, {res.stats['steps']} steps, "
          f"{res.stats['wall_time']:.1f} s of wall time")
    print(f"largest error against the reference: x {error[:, 0].max():.2e} m, "
          f"y {error[:, 1].max():.2e} m (criterion 1e-3 m; the file has 6 digits)")
    print(f"energy drift: {np.max(np.abs(energy - energy[0])):.2e} J; "
          f"largest |C|: {res.position_residual.max():.1e} m")
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res


if __name__ == "__main__":
    run_script(main, __doc__, "iftomm_pendulum.rrd",
               {"--duration": {"type": float, "default": 2000.0, "help": "simulated time [s]"},
                "--rtol": {"type": float, "default": 1e-12,
                           "help": "DOP853 relative tolerance (the phase error accumulates "
                                   "over the 845 swings)"}})
