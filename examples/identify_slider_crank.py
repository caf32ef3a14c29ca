"""Identification: a slider-crank's rod and slider masses and its slider's damper, from its
measured motor torque.

A motor turns the crank at 2 turns a second; a viscous damper (a dashpot along the rail)
brakes the slider. The "measured" torque is the inverse dynamics of the true model with
noise of 0.05 N m added. Starting from masses and damping that are all wrong, SciPy's
least_squares fits the model's torque to the measurement, with the exact Jacobian of the
torque with respect to the three parameters from mb.sensitivities (one inverse-dynamics run
and its sensitivities per iteration: no differences of runs).

Printed: the true, starting and identified values with their standard errors (from the
Jacobian at the fit and the residuals' spread), and how far each identified value lies from
the truth in standard errors (a fit is sound when these are a few at most).

Recorded: the identified model's motion and torque, identify_slider_crank.rrd:
rerun identify_slider_crank.rrd

Run: python examples/identify_slider_crank.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import numpy as np
import scipy.optimize

import mbd3d as mb
from mbd3d.joints import Prismatic, Revolute, RotationDriver
from mbd3d.viewer import check_recording_first, record, run_script

#: the parameters identified, by their names in the model (mb.parameters)
PARAMETERS = ["bodies.rod.mass", "bodies.slider.mass", "forces.dashpot.damping"]
TRUE = [2.0, 4.0, 30.0]  # [kg, kg, N s/m]
START = [1.0, 1.0, 1.0]
NOISE = 0.05  # [N m], standard deviation of the measured torque's noise


def build(rod_mass: float = 1.0, slider_mass: float = 1.0, damping: float = 1.0) -> mb.Model:
    """The slider-crank (crank 0.12 m, rod 0.26 m) with a dashpot on its slider."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81), name="slider-crank with a dashpot")
    crank = b.add_body("crank", mass=1.0, inertia=0.001, position=(0.06, 0.0))
    rod = b.add_body("rod", mass=rod_mass, inertia=0.01, position=(0.25, 0.0))
    slider = b.add_body("slider", mass=slider_mass, inertia=0.02, position=(0.38, 0.0))
    pin = b.add(Revolute("O", b.ground, crank, point_i=(0.0, 0.0), point_j=(-0.06, 0.0)))
    b.add(Revolute("A", crank, rod, point_i=(0.06, 0.0), point_j=(-0.13, 0.0)))
    b.add(Revolute("B", rod, slider, point_i=(0.13, 0.0), point_j=(0.0, 0.0)))
    b.add(Prismatic("rail", b.ground, slider, axis=(1.0, 0.0), point_i=(0.0, 0.0),
                    point_j=(0.0, 0.0)))
    b.add(RotationDriver("motor", pin, motion=mb.Ramp(0.0, 4 * np.pi)))
    # the dashpot's line lies along the rail, so its length changes at the slider's speed
    b.add(mb.SpringDamper("dashpot", b.ground, slider, point_i=(-1.0, 0.0),
                          point_j=(0.0, 0.0), stiffness=0.0, damping=damping,
                          free_length=1.38))
    return b.build()


def torque(model: mb.Model, t: np.ndarray) -> tuple[mb.Results, np.ndarray]:
    """The inverse dynamics over ``t`` and the motor's torque [N m]."""
    res = mb.inverse_dynamics(model, t)
    return res, res.joint("motor").effort


@check_recording_first
def main(n_points: int = 201, rrd: str | None = None, show: bool = False) -> dict:
    t = np.linspace(0.0, 0.5, n_points)  # one turn of the crank
    rng = np.random.default_rng(1)
    measured = torque(build(*TRUE), t)[1] + NOISE * rng.standard_normal(n_points)
    start = build(*START)

    def residuals(x: np.ndarray) -> np.ndarray:
        return torque(mb.with_parameters(start, dict(zip(PARAMETERS, x))), t)[1] - measured

    def jacobian(x: np.ndarray) -> np.ndarray:
        res = torque(mb.with_parameters(start, dict(zip(PARAMETERS, x))), t)[0]
        sens = mb.sensitivities(res, PARAMETERS)
        return np.column_stack([sens.effort("motor", name) for name in PARAMETERS])

    fit = scipy.optimize.least_squares(residuals, START, jac=jacobian)
    # standard errors: the residuals' variance times the diagonal of (J^T J)^-1
    variance = 2 * fit.cost / (n_points - len(PARAMETERS))
    errors = np.sqrt(variance * np.diag(np.linalg.inv(fit.jac.T @ fit.jac)))
    print(mb.format_table({"parameter": PARAMETERS, "true": TRUE, "start": START,
                           "identified": fit.x, "standard error": errors,
                           "off by [errors]": (fit.x - TRUE) / errors}))
    print(f"\n{fit.nfev} evaluations, {fit.njev} Jacobians; residual torque "
          f"{np.sqrt(variance):.4f} N m (the noise: {NOISE} N m)")
    identified = mb.with_parameters(start, dict(zip(PARAMETERS, fit.x)))
    if rrd is not None:
        record(torque(identified, t)[0], rrd, overwrite=True, show=show)
    return {"fit": fit, "errors": errors, "model": identified}


if __name__ == "__main__":
    run_script(main, __doc__, "identify_slider_crank.rrd")
