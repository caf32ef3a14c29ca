"""Synthesis: a four-bar whose coupler point passes through eight given points at given crank
angles (path generation with prescribed timing).

The crank turns at one turn a second; at t = 0, 0.1, ..., 0.7 s the point of the coupler 0.1 m
off its centre line must be at the eight target points. The unknowns are the four link lengths,
set by where the joints sit on the links and the ground, and the crank's starting angle, five
numbers named as the model names them (mb.parameters). Starting from a linkage whose coupler
point misses the targets by centimetres, SciPy's least_squares moves the five numbers until it
passes through them, with the exact Jacobian of the coupler point's path from mb.sensitivities
(one kinematic analysis and its sensitivities per iteration: no differences of runs).

The targets were traced by a four-bar of the same family, so a linkage through all eight
exists: the fit finds it to the last digits.

Recorded: the synthesised linkage turning, four_bar_synthesis.rrd:
rerun four_bar_synthesis.rrd

Run: python examples/four_bar_synthesis.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import math

import numpy as np
import scipy.optimize

import mbd3d as mb
from mbd3d.mechanisms import four_bar
from mbd3d.viewer import check_recording_first, record, run_script

#: the unknowns, by their names in the model: the ground pivot O4's distance from O2, the crank
#: pin A on the crank, the pin B on the coupler and on the rocker, the crank's starting angle
PARAMETERS = ["joints.O4.point_i[0]", "joints.A.point_i[0]", "joints.B.point_i[0]",
              "joints.B.point_j[0]", "joints.motor.motion.initial"]
#: the linkage that traced the targets [m, m, m, m, rad]
TRACED = [0.33, 0.06, 0.19, 0.17, math.radians(70.0)]
COUPLER_POINT = (0.0, 0.1)  # on the coupler, from its centre [m]
TIMES = np.linspace(0.0, 0.7, 8)  # [s]


def build() -> mb.Model:
    """The starting linkage: ground 0.30 m, crank 0.10 m, coupler and rocker 0.35 and 0.30 m,
    the crank at 60 degrees and turning at 2 pi rad/s; no gravity (kinematics only)."""
    return four_bar(crank_speed=2 * math.pi, gravity=0.0)


def path(model: mb.Model) -> tuple[mb.Results, np.ndarray]:
    """The kinematic analysis at ``TIMES`` and the coupler point's positions (8, 2) [m]."""
    res = mb.kinematic_analysis(model, TIMES)
    return res, res.point("coupler", COUPLER_POINT).position


@check_recording_first
def main(rrd: str | None = None, show: bool = False) -> dict:
    start = build()
    targets = path(mb.with_parameters(start, dict(zip(PARAMETERS, TRACED))))[1]
    x0 = [mb.parameters(start)[name] for name in PARAMETERS]

    def residuals(x: np.ndarray) -> np.ndarray:
        return (path(mb.with_parameters(start, dict(zip(PARAMETERS, x))))[1]
                - targets).ravel()

    def jacobian(x: np.ndarray) -> np.ndarray:
        res = path(mb.with_parameters(start, dict(zip(PARAMETERS, x))))[0]
        sens = mb.sensitivities(res, PARAMETERS)
        # d(coupler point)/d(each parameter), (8, 2, 5): the points' rows, one column each
        moved = sens.derivative(lambda r: r.point("coupler", COUPLER_POINT).position)
        return moved.reshape(-1, len(PARAMETERS))

    fit = scipy.optimize.least_squares(residuals, x0, jac=jacobian, xtol=1e-14, ftol=1e-14)
    synthesised = mb.with_parameters(start, dict(zip(PARAMETERS, fit.x)))
    points = path(synthesised)[1]
    misses = np.linalg.norm(points - targets, axis=1)
    print(mb.format_table({"parameter": PARAMETERS, "start": x0, "synthesised": fit.x,
                           "traced by": TRACED}, precision=9))
    print(f"\nthe coupler point misses the targets by {np.max(misses):.1e} m at most "
          f"(at the start: {np.max(np.linalg.norm(path(start)[1] - targets, axis=1)):.3f} m); "
          f"{fit.nfev} evaluations, {fit.njev} Jacobians")
    if rrd is not None:  # a whole turn of the synthesised linkage
        record(mb.kinematic_analysis(synthesised, np.linspace(0.0, 1.0, 101)), rrd,
               overwrite=True, show=show)
    return {"fit": fit, "misses": misses, "model": synthesised}


if __name__ == "__main__":
    run_script(main, __doc__, "four_bar_synthesis.rrd")
