"""IFToMM benchmark A04: Bricard's mechanism, an overconstrained spatial loop that moves.

Five 1 m rods (1 kg, 0.1 m square section) and the ground close a loop through six revolutes
along the edges of a unit cube, each hinge axis turned 90 degrees from the last. Gruebler's
count gives 30 coordinates - 30 equations = 0 degrees of freedom, yet the loop moves with one:
one constraint is redundant. The mobility report finds it with a rank-revealing factorisation
and names the joints whose rows depend on each other; forward dynamics then runs from rest
under gravity (9.81 m/s^2 along -y) with the implicit generalized-alpha method, whose Newton
matrix stays regular with dependent rows. The reactions are one of many that balance the
loop (the minimum-norm one): Results flags them as not unique.

No reference series exists; the check is conservation of mechanical energy (Exudyn and
MBS-BOS do the same), printed with the constraint residuals.

Source: IFToMM / MBS benchmark library, problem A04 (M. Gonzalez et al., Univ. of A Coruna);
geometry as in MBS-BOS (the benchmarks in OpenSim, RehabEngGroup/MBSbenchmarksInOpenSim) and
Exudyn's test model bricardMechanism.py.

Recorded to bricard.rrd: rerun bricard.rrd

Run: python examples/bricard.py [--duration 10] [--rrd FILE] [--show]
"""

from __future__ import annotations

import numpy as np

import mbd3d as mb
from mbd3d.joints import Revolute
from mbd3d.mechanisms import frame_along
from mbd3d.viewer import check_recording_first, record, run_script

#: the loop's corners P1..P6 and hinge axes; rod k joins P_k and P_(k+1), the ground P6 and P1
CORNERS = np.array([[0, 0, 0], [1, 0, 0], [1, -1, 0], [1, -1, 1], [0, -1, 1], [0, 0, 1]], float)
AXES = np.array([[0, 1, 0], [0, 0, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 0]], float)


def build() -> mb.Model:
    """Bricard's mechanism at rest in its cube-edge position."""
    b = mb.ModelBuilder(dim=3, gravity=(0.0, -9.81, 0.0), name="Bricard mechanism")
    # a 1 kg bar 1 x 0.1 x 0.1 m, its own x axis along the bar
    inertia = np.array([0.1**2 + 0.1**2, 1.0 + 0.1**2, 1.0 + 0.1**2]) / 12.0
    rods = [b.add_body(f"rod{k + 1}", mass=1.0, inertia=inertia,
                       position=(CORNERS[k] + CORNERS[k + 1]) / 2,
                       orientation=frame_along(CORNERS[k + 1] - CORNERS[k]))
            for k in range(5)]
    chain = [b.ground, *rods, b.ground]
    for k in range(6):
        b.add(Revolute(f"P{k + 1}", chain[k], chain[k + 1], at=CORNERS[k], axis=AXES[k]))
    return b.build()


@check_recording_first
def main(duration: float = 10.0, n_points: int = 1001, step: float = 1e-3,
         rrd: str | None = None, show: bool = False) -> mb.Results:
    model = build()
    print(mb.mobility(model), "\n")
    times = np.linspace(0.0, duration, n_points)
    res = mb.forward_dynamics(model, times, method="generalized-alpha", step=step)
    energy = res.kinetic_energy + res.potential_energy
    p3 = res.point("rod2", (0.5, 0.0, 0.0)).position  # the end of rod 2, P3
    print(mb.format_table({"t [s]": res.t, "x P3 [m]": p3[:, 0], "y P3 [m]": p3[:, 1],
                           "z P3 [m]": p3[:, 2], "energy [J]": energy}, rows=9))
    print(f"\n{res.stats['steps']} steps of {step:g} s, {res.stats['wall_time']:.1f} s of wall "
          f"time; energy drift {np.max(np.abs(energy - energy[0])):.2e} J; largest |C| "
          f"{res.position_residual.max():.1e} m; reactions unique: {res.reactions_unique}")
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res


if __name__ == "__main__":
    run_script(lambda duration, **kw: main(duration, n_points=int(duration * 100) + 1, **kw),
               __doc__, "bricard.rrd",
               {"--duration": {"type": float, "default": 10.0, "help": "simulated time [s]"}})
