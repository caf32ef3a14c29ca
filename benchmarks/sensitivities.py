"""What the sensitivities of an analysis cost against the analysis itself: inverse dynamics of
the slider-crank and of a hanging planar chain driven at every pin, then ``mb.sensitivities``
of its results with respect to p of the model's numbers (masses and joint points); and
forward dynamics of the slider-crank turned by a torque and of a falling 100-link chain
against ``mb.forward_sensitivities`` of the same run with p masses (then inertias). Medians of
a few runs in one process.

Each parameter costs its four variants of the model (built once) and, per time point, one
solve for the positions with the exact rows, and eight evaluations of the rows and four of
the dynamic equations along the parameter: the ratio per parameter is what to expect of a
study of p parameters, p times it.

Forward sensitivities take, at every stage of every step, the stage's accelerations and
multipliers solved once, then per parameter the change of the right-hand side and of the
equations' residual with them held, from four evaluations of the model's variants (at a
shorter step where the state's sensitivities are large: interpolated from the first variants'
compiled arrays where the parameter enters them affinely, built otherwise), and one solve with
the stage's matrix; all stages of a step in one compiled call. Four residuals per stage and
parameter, plus building the four variants through the model's file, is still several
analyses per parameter, not the issue's target of half of one, which needs the residual's own
tangent compiled (one evaluation instead of four, and no variants to build).

Run: python benchmarks/sensitivities.py [--repeat N]
"""

from __future__ import annotations

import argparse

import numpy as np

import mbd3d as mb
from mbd3d.io.parameters import parameter_tangent
from mbd3d.mechanisms import pendulum_chain, slider_crank
from kinematics import driven_chain
from measure import machine, median_time


def main(points: int = 101, links: int = 10, counts: tuple = (1, 4), repeat: int = 3
         ) -> list[dict]:
    """Per model and number of parameters: the analysis' time, the sensitivities' time and
    their ratio per parameter (printed as a table)."""
    t = np.linspace(0.0, 1.0, points)
    rows = []
    for model in (slider_crank(), driven_chain(links)):
        names = [n for n in mb.parameters(model)
                 if n.endswith(".mass") or ".point_" in n or ".at[" in n]
        mb.sensitivities(mb.inverse_dynamics(model, t[:3]), names[:1])  # compiles
        plain = median_time(lambda: mb.inverse_dynamics(model, t), repeat)
        res = mb.inverse_dynamics(model, t)
        for p in counts:
            cost = median_time(lambda: mb.sensitivities(res, names[:p]), repeat)
            rows.append({"model": model.name, "coordinates": model.n_coordinates, "p": p,
                         "analysis [s]": plain, "sensitivities [s]": cost,
                         "per parameter [x analysis]": cost / plain / p})
    print(machine())
    print(f"inverse dynamics over {points} time points, then mb.sensitivities of its results "
          f"to p parameters (medians of {repeat})\n")
    print(mb.format_table({key: [r[key] for r in rows] for key in rows[0]}))
    return rows


def forward(counts: tuple = (1, 4), repeat: int = 3, links: int = 100, duration: float = 1.0
            ) -> list[dict]:
    """Per model and number of parameters: forward dynamics' time, forward sensitivities'
    time, their ratio and the issue's target ``1 + 0.5 p`` (printed as a table); the chain
    falls for half of ``duration`` [s]."""
    rows = []
    cases = ((slider_crank(crank_angle=1.134, crank_speed=None, crank_torque=2.0), duration),
             (pendulum_chain(links), duration / 2))
    for model, duration in cases:
        t = np.linspace(0.0, duration, 11)
        # the bodies' masses, then their inertias (the slider-crank has three masses)
        names = [n for suffix in (".mass", ".inertia") for n in mb.parameters(model)
                 if n.endswith(suffix)]
        options = dict(method="DOP853", rtol=1e-8, atol=1e-10)
        mb.forward_sensitivities(model, t[:2] * 0.01, names[:1], **options)  # compiles
        plain = median_time(lambda: mb.forward_dynamics(model, t, **options), repeat)
        for p in counts:
            assert len(names) >= p, f"{model.name} has {len(names)} masses and inertias"
            cost = median_time(lambda: mb.forward_sensitivities(model, t, names[:p],
                                                                **options), repeat)
            # of which: building the model's variants (four models per parameter)
            built = median_time(lambda: [parameter_tangent(model, name, "")
                                         for name in names[:p]], repeat)
            rows.append({"model": model.name, "coordinates": model.n_coordinates, "p": p,
                         "forward dynamics [s]": plain, "with sensitivities [s]": cost,
                         "of which variants [s]": built, "ratio": cost / plain,
                         "target 1 + 0.5 p": 1 + 0.5 * p})
    print(f"\nforward dynamics (DOP853, rtol 1e-8) against mb.forward_sensitivities of the "
          f"same run to p masses and inertias (medians of {repeat})\n")
    print(mb.format_table({key: [r[key] for r in rows] for key in rows[0]}))
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    arguments = parser.parse_args()
    main(repeat=arguments.repeat)
    forward(repeat=arguments.repeat)
