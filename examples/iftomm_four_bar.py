"""IFToMM benchmark A02: N four-bars in a row, through the singular flat positions.

N parallelogram four-bars share their cranks: N + 1 vertical cranks (1 m, 1 kg, pinned at
(k, 0)) and N horizontal couplers (1 m, 1 kg) joined at the cranks' tops. Released with the
first crank's top B0 moving at 1 m/s along +x, gravity 9.81 m/s^2 along -y. Every time the
cranks lie flat all bodies are on one line: the constraint Jacobian loses N ranks and the
mechanism could leave its parallelogram branch. The benchmark asks for B0 over 20 s within
1e-3 m of its ADAMS reference series (N = 40, in examples/data/).

Integrated by the implicit index-3 generalized-alpha method (``method="generalized-alpha"``),
whose Newton iteration matrix stays regular where the Jacobian loses rank; the explicit
index-1 methods stop at the first flat position with a SingularJacobianError naming the joints.

Source: IFToMM / MBS benchmark library, problem A02 (M. Gonzalez et al., Univ. of A Coruna);
the reference series and its source: examples/data/README.md.

Recorded to iftomm_four_bar.rrd: rerun iftomm_four_bar.rrd

Run: python examples/iftomm_four_bar.py [--bars 40] [--duration 20] [--rrd FILE] [--show]
(about ten seconds)
"""

from __future__ import annotations

import pathlib

import numpy as np

import mbd3d as mb
from mbd3d.joints import Revolute
from mbd3d.viewer import check_recording_first, record, run_script

#: the benchmark\'s reference series, with its source in data/README.md
REFERENCE = pathlib.Path(__file__).resolve().parent / "data" / "iftomm_A02_n_four_bar_B0.txt"


def build(bars: int) -> mb.Model:
    """The A02 mechanism with ``bars`` four-bars, in its initial (upright) position."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81), name=f"IFToMM A02 {bars} four-bars")
    rod = {"mass": 1.0, "inertia": 1.0 / 12.0}  # uniform 1 m rods: m L^2 / 12
    cranks = [b.add_body(f"crank{k}", position=(k, 0.5), angle=np.pi / 2, velocity=(0.5, 0.0),
                         angular_velocity=-1.0, **rod) for k in range(bars + 1)]
    couplers = [b.add_body(f"coupler{k}", position=(k + 0.5, 1.0), velocity=(1.0, 0.0), **rod)
                for k in range(bars)]
    for k, crank in enumerate(cranks):
        b.add(Revolute(f"O{k}", b.ground, crank, at=(k, 0.0)))
    for k, coupler in enumerate(couplers):
        b.add(Revolute(f"B{k}", cranks[k], coupler, at=(k, 1.0)))
        b.add(Revolute(f"C{k}", coupler, cranks[k + 1], at=(k + 1, 1.0)))
    return b.build()


@check_recording_first
def main(bars: int = 40, duration: float = 20.0, step: float = 1e-3, rrd: str | None = None,
         show: bool = False) -> mb.Results:
    times = np.linspace(0.0, duration, int(round(duration / 0.05)) + 1)  # every 0.05 s
    res = mb.forward_dynamics(build(bars), times, method="generalized-alpha", step=step)
    b0 = res.point("crank0", (0.5, 0.0)).position  # the top of the first crank
    energy = res.kinetic_energy + res.potential_energy
    print(f"{bars} four-bars, {duration:g} s: {res.stats['steps']} steps of {step:g} s, "
          f"{res.stats['wall_time']:.1f} s of wall time")
    print(f"B0 at {duration:g} s: ({b0[-1, 0]:.6f}, {b0[-1, 1]:.6f}) m; energy drift "
          f"{np.max(np.abs(energy - energy[0])):.2e} J; largest |C| "
          f"{res.position_residual.max():.1e} m")
    passages = res.singular_passages
    print(f"{len(passages)} singular positions passed, e.g. "
          + "; ".join(str(p) for p in passages[:2]))
    if bars == 40:
        reference = np.loadtxt(REFERENCE, comments="#")
        reference = reference[reference[:, 0] <= duration + 1e-9]
        error = np.abs(b0[:len(reference)] - reference[:, 1:]).max()
        print(f"largest error against the ADAMS reference: {error:.2e} m (criterion 1e-3 m)")
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res


if __name__ == "__main__":
    run_script(main, __doc__, "iftomm_four_bar.rrd",
               {"--bars": {"type": int, "default": 40, "help": "number of four-bars N"},
                "--duration": {"type": float, "default": 20.0, "help": "simulated time [s]"}})
