"""Newton's cradle of ten steel balls (``mbd3d.mechanisms.newtons_cradle``): mbd3d against
Exudyn and MuJoCo at equal accuracy, issue #32's shared contact scenario.

Ten balls of 15 mm on strings of 100 mm, 0.2 mm apart; the first, released from 30 degrees,
strikes the row after a quarter swing, the impulse runs down it in nine undamped Hertz
impacts of about 90 us each, and the last ball swings out. The stated quantity is the balls'
centres at 0.25 s, when the last ball is half-way up its swing; an engine's answer is
accurate when no centre is more than ``TOLERANCE`` from its converged answer. For mbd3d and
Exudyn (the same law) that is the mbd3d run at rtol 1e-12, which Exudyn's shortest step
approaches; MuJoCo's linear law (see ``peers.py``) gives answers of its own, compared with
its run at its shortest step.

For each engine, the cheapest setting that reaches the accuracy (tolerances from loose to
tight, steps from long to short) is found, then the settings found are timed in turn, round
after round (``measure.interleaved_medians``), so that the machine's drift hits all alike.
``--soft`` runs the same cradle with balls a thousand times softer (E = 210 MPa, impacts of
about 1.5 ms, several balls in contact at once).

Run: python benchmarks/cradle.py [--soft] [--repeat N]   (peers: pip install -e ".[peers]")
"""

from __future__ import annotations

import argparse
import math
import pathlib
import sys
import warnings

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

import mbd3d as mb  # noqa: E402
import peers  # noqa: E402
from mbd3d.mechanisms import newtons_cradle  # noqa: E402
from mbd3d.model.contact_laws import hertz_stiffness  # noqa: E402
from measure import compare_at_equal_accuracy, machine  # noqa: E402

#: the cradle (mbd3d.mechanisms.newtons_cradle's arguments), its duration [s] and the
#: accuracy of the balls' centres at which the engines are compared [m]
CRADLE = dict(n_balls=10, radius=0.015, string_length=0.1, gap=0.2e-3, density=7850.0,
              poisson_ratio=0.3, release=math.radians(30.0))
DURATION, TOLERANCE = 0.25, 1e-5


def derived(cradle: dict, young_modulus: float) -> dict:
    """The peers' description of the cradle: ``cradle`` with the balls' mass [kg], Hertz's
    stiffness of a pair [N/m^1.5] and the duration [s] of the first impact."""
    r = cradle["radius"]
    mass = cradle["density"] * 4.0 / 3.0 * math.pi * r ** 3
    K = hertz_stiffness(young_modulus, cradle["poisson_ratio"], r / 2, "cradle")
    # the striker's speed at the bottom: its fall feeds the pendulum's turning, ball included
    L = cradle["string_length"]
    speed = L * math.sqrt(2 * 9.81 * L * (1 - math.cos(cradle["release"]))
                          / (L * L + 0.4 * r * r))
    return dict(cradle, mass=mass, stiffness=K,
                impact_duration=hertz_impact_duration(mass / 2, K, speed))


def hertz_impact_duration(m: float, K: float, speed: float) -> float:
    """How long [s] a mass ``m`` [kg] meeting ``K delta^1.5`` at ``speed`` [m/s] stays in
    contact (SciPy; the closed form is ``2.94 delta_max / speed``)."""
    def parted(_, y):
        return y[0]
    parted.terminal, parted.direction = True, -1
    scale = (m * m * speed ** 3 / (K * K)) ** 0.2  # the contact's time and length scales
    out = solve_ivp(lambda _, y: [y[1], -K / m * max(y[0], 0.0) ** 1.5], (0.0, 100 * scale),
                    [0.0, speed], events=parted, rtol=1e-12, atol=1e-15 * scale,
                    first_step=1e-3 * scale)
    return float(out.t_events[0][0]) if out.t_events[0].size else math.nan


def centres(res: mb.Results, n: int) -> np.ndarray:
    return np.array([res.body(f"ball{k + 1}").position[-1] for k in range(n)])


def ours(model, method: str, rtol: float):
    def run():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", mb.InitialStateWarning)
            res = mb.forward_dynamics(model, [0.0, DURATION], method=method, rtol=rtol,
                                      atol=rtol * 1e-2)
        return centres(res, CRADLE["n_balls"]), res.stats["wall_time"]
    return run


def ours_alpha(model, step: float):
    """mbd3d's generalized-alpha at ``step`` [s] (shortened into each impact by the contact
    rules, as Exudyn's is not)."""
    def run():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", mb.InitialStateWarning)
            res = mb.forward_dynamics(model, [0.0, DURATION], method="generalized-alpha",
                                      step=step)
        return centres(res, CRADLE["n_balls"]), res.stats["wall_time"]
    return run


def compare(young_modulus: float, repeat: int) -> list[dict]:
    model = newtons_cradle(young_modulus=young_modulus, **CRADLE)
    cradle = derived(CRADLE, young_modulus)
    ours(model, "DOP853", 1e-6)()  # compiled before any timing
    reference = ours(model, "DOP853", 1e-12)()[0]

    def error_from(answer):
        return lambda x: float(np.max(np.abs(np.asarray(x) - answer)))

    error = error_from(reference)
    engines = {f"mbd3d {m}": ([(f"rtol {rtol:.1g}", ours(model, m, rtol))
                               for rtol in 10.0 ** -np.arange(3.0, 12.5, 0.5)], error)
               for m in ("DOP853", "RK45")}
    ours_alpha(model, 1e-3)()  # compiled before any timing
    engines["mbd3d generalized-alpha"] = ([(f"h {h:.3g}", ours_alpha(model, h))
                                           for h in 1e-3 * 0.5 ** np.arange(0, 8)], error)
    steps = 1e-4 * 0.5 ** np.arange(0, 10)
    if peers.available("exudyn"):
        engines["Exudyn generalized-alpha"] = ([
            (f"h {h:.3g}", lambda h=h: peers.exudyn_cradle(cradle, h, DURATION))
            for h in steps], error)
        tightest = peers.exudyn_cradle(cradle, steps[-1], DURATION)[0]
        print(f"check: Exudyn at its shortest step (h {steps[-1]:.3g}) differs from the mbd3d "
              f"reference by {error(tightest):.1e} m")
    if peers.available("mujoco"):
        T = cradle["impact_duration"]
        def mujoco(h, integrator="RK4"):
            return lambda: peers.mujoco_cradle(cradle, h, DURATION, T, integrator)
        own = mujoco(steps[-1] / 4)()[0]
        print(f"MuJoCo's linear law (impacts of {T * 1e6:.0f} us) differs from the Hertz law by "
              f"{error(own):.1e} m: it is compared with its own run (RK4) at "
              f"h {steps[-1] / 4:.3g}")
        # each of its integrators, so that the ratio published is against its best
        for integrator in ("RK4", "Euler", "implicitfast"):
            engines[f"MuJoCo {integrator}"] = ([(f"h {h:.3g}", mujoco(h, integrator))
                                                for h in steps], error_from(own))
    if len(engines) == 3:
        print("no peers installed: pip install -e '.[peers]' for Exudyn and MuJoCo")
    rows = compare_at_equal_accuracy(engines, TOLERANCE, "m", "centres'", repeat)
    print(f"({CRADLE['n_balls']} balls, E = {young_modulus:.3g} Pa, impacts of "
          f"{cradle['impact_duration'] * 1e6:.0f} us; centres at t = {DURATION} s to "
          f"{TOLERANCE:g} m; medians of {repeat} rounds in which the engines ran in turn)")
    for r in rows:
        if r["engine"].startswith("Exudyn"):
            print(f"mbd3d / {r['engine']}: {r['ratio']:.3f} (issue #32's target <= 1: "
                  f"{'met' if r['ratio'] <= 1.0 else 'missed'})")
    return rows


def main(soft: bool = False, repeat: int = 3) -> None:
    print(machine())
    compare(210e6 if soft else 210e9, repeat)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--soft", action="store_true", help="balls of E = 210 MPa")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    main(args.soft, args.repeat)
