"""Work-precision study of every integrator on the free slider-crank, and Exudyn at equal accuracy.

The model is ``mbd3d.mechanisms.slider_crank(crank_speed=None)`` (Nikravesh's data, no
driver) under gravity, started at a crank angle of 65 degrees turning at 30 rad/s: in 2 s the
crank makes about 14 turns. The reported quantity is the crank angle at t = 2 s; its
reference comes from DOP853 at rtol 1e-13 (and the study shows every integrator converging to
it). For each integrator and setting the script prints the error and the wall time (median of
3 runs). With --peers (``pip install -e ".[peers]"``) it finds the cheapest Exudyn step
(its generalized-alpha, steps halved from 1e-4 s) and the cheapest mbd3d setting (DOP853,
tolerances halved from 1e-6: the same search for both) that get the angle to 1e-6 rad, times
the two in turn (3 rounds, so that a drift in the machine's speed hits both alike) and prints
the ratio of their median wall times (target: mbd3d / Exudyn <= 0.01). It also runs both
engines' generalized-alpha at the same steps (``SAME_STEPS``), where they reach the same
accuracy, and prints their errors, times and ratio (issue #34's target: at most 0.5 x
Exudyn's time at h = 1e-3).

Run: python benchmarks/slider_crank.py [--peers] [--quick]
"""

from __future__ import annotations

import argparse
import math
import pathlib
import sys

import timeit

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

import mbd3d as mb  # noqa: E402
import peers  # noqa: E402
from mbd3d.mechanisms import slider_crank  # noqa: E402
from measure import cheapest, interleaved_medians, machine  # noqa: E402

#: crank rate at t = 0 [rad/s], duration [s], and the accuracy of the comparison [rad]
CRANK_RATE, DURATION, TOLERANCE = 30.0, 2.0, 1e-6

#: the steps at which both engines' generalized-alpha are timed [s]
SAME_STEPS = (1e-3, 2.5e-4, 6.25e-5)

#: the settings of the study, cheapest first
STUDY = {
    "RK45": [{"rtol": r} for r in (1e-5, 1e-7, 1e-9)],
    "DOP853": [{"rtol": r} for r in (1e-5, 1e-7, 1e-9, 1e-11)],
    "RK23": [{"rtol": r} for r in (1e-5, 1e-7)],
    "generalized-alpha": [{"step": h} for h in (1e-3, 2.5e-4, 6.25e-5)],
}


def initial_state(model) -> tuple[np.ndarray, np.ndarray]:
    """Assembled positions at 65 degrees and the rates with the crank at ``CRANK_RATE``."""
    q = mb.solve_position(model)
    guess = np.zeros(model.n_coordinates)
    guess[model.coordinate_index("crank.theta")] = CRANK_RATE
    return q, mb.solve_velocity(model, q, qd_guess=guess, hold=["crank.theta"])


def run(model, q0, qd0, method: str, options: dict) -> tuple[float, float]:
    """Crank angle at ``DURATION`` [rad] and the wall time [s] of one integration."""
    tolerances = {"rtol": options["rtol"], "atol": options["rtol"] * 1e-2} if "rtol" in options \
        else {"step": options["step"]}
    res = mb.forward_dynamics(model, [0.0, DURATION], q0=q0, qd0=qd0, method=method,
                              **tolerances)
    return float(res.body("crank").angle[-1]), res.stats["wall_time"]


def main(compare: bool = False, quick: bool = False, repeat: int = 3) -> list[dict]:
    model = slider_crank(crank_speed=None)
    q0, qd0 = initial_state(model)
    reference = run(model, q0, qd0, "DOP853", {"rtol": 1e-13})[0]
    print(f"free slider-crank, crank angle at t = {DURATION:g} s (reference {reference:.12f} rad"
          f" from DOP853 at rtol 1e-13); {machine()}")
    study = {m: s[:1] for m, s in STUDY.items()} if quick else STUDY
    rows = []
    for method, settings in study.items():
        for options in settings:
            walls, angle = [], None
            setting = ", ".join(f"{k} {v:g}" for k, v in options.items())
            try:
                for _ in range(repeat):
                    angle, wall = run(model, q0, qd0, method, options)
                    walls.append(wall)
            except mb.MBDError as exc:  # reported, as a user would meet it
                print(f"{method}, {setting}: failed: {exc}")
                continue
            rows.append({"method": method, "setting": setting,
                         "error": abs(angle - reference), "wall": float(np.median(walls))})
    print(mb.format_table({"integrator": [r["method"] for r in rows],
                           "setting": [r["setting"] for r in rows],
                           "angle error [rad]": [r["error"] for r in rows],
                           "wall [s]": [r["wall"] for r in rows]}, precision=3))
    print(f"(medians of {repeat} runs; explicit methods at atol = rtol / 100)")
    right_hand_sides(model, q0, qd0, quick)
    if compare:
        compare_with_exudyn(model, q0, qd0, reference)
        same_steps_as_exudyn(model, q0, qd0, reference)
    return rows


def right_hand_sides(model, q0, qd0, quick: bool = False) -> dict:
    """The cost of one ``forward_accelerations`` call (median of 7 rounds of 2000 calls) and
    of a whole DOP853 run per right-hand side, against it (targets: 5 us, and the whole run
    at most 1.5 x the right-hand sides times the cost of one)."""
    calls = 200 if quick else 2000
    mb.forward_accelerations(model, 0.0, q0, qd0)
    times = timeit.repeat(lambda: mb.forward_accelerations(model, 0.0, q0, qd0), number=calls,
                          repeat=7)
    one = float(np.median(times)) / calls
    res = mb.forward_dynamics(model, [0.0, DURATION], q0=q0, qd0=qd0, method="DOP853",
                              rtol=7.8e-9, atol=7.8e-11)
    walls = [res.stats["wall_time"]] + [
        mb.forward_dynamics(model, [0.0, DURATION], q0=q0, qd0=qd0, method="DOP853",
                            rtol=7.8e-9, atol=7.8e-11).stats["wall_time"]
        for _ in range(0 if quick else 4)]
    wall = float(np.median(walls))
    evaluations = res.stats["rhs_evaluations"]
    ratio = wall / (evaluations * one)
    print(f"forward_accelerations: {1e6 * one:.2f} us (target <= 5 us: "
          f"{'met' if one <= 5e-6 else 'missed'}); a DOP853 run at rtol 7.8e-9: "
          f"{evaluations} right-hand sides in {wall:.4f} s, {1e6 * wall / evaluations:.2f} us "
          f"each all-in, {ratio:.2f} x the cost of one call (target <= 1.5: "
          f"{'met' if ratio <= 1.5 else 'missed'})")
    return {"forward_accelerations": one, "run": wall, "rhs_evaluations": evaluations}


def compare_with_exudyn(model, q0, qd0, reference: float, repeat: int = 3) -> None:
    """Cheapest mbd3d and Exudyn settings within ``TOLERANCE`` of the reference angle."""
    if not peers.available("exudyn"):
        print("Exudyn is not installed: pip install -e '.[peers]'")
        return
    ours = [(f"DOP853 rtol {r:.2g}", lambda r=r: run(model, q0, qd0, "DOP853", {"rtol": r}))
            for r in 1e-6 * 0.5 ** np.arange(23)]
    theirs = [(f"h {h:.3g}", lambda h=h: peers.exudyn_slider_crank(
        h, qd0, DURATION, math.radians(65.0))) for h in 1e-4 * 2.0 ** -np.arange(0, 7)]

    def error(angle):
        return abs(angle - reference)

    found = {"mbd3d": cheapest(ours, error, TOLERANCE),
             "Exudyn generalized-alpha": cheapest(theirs, error, TOLERANCE)}
    for engine, result in found.items():
        if result is None:
            print(f"{engine}: no setting tried reaches the accuracy")
    if not all(found.values()):
        return
    walls = dict(zip(found, interleaved_medians([run for _, _, run in found.values()], repeat)))
    for engine, (label, err, _) in found.items():
        print(f"{engine}: {label}: error {err:.2e} rad, {walls[engine]:.3g} s")
    ratio = walls["mbd3d"] / walls["Exudyn generalized-alpha"]
    print(f"mbd3d / Exudyn at {TOLERANCE:g} rad: {ratio:.3f} (target <= 0.01: "
          f"{'met' if ratio <= 0.01 else 'missed'}; medians of {repeat} rounds in which the "
          "engines ran in turn)")


def same_steps_as_exudyn(model, q0, qd0, reference: float, repeat: int = 5) -> list[dict]:
    """mbd3d's and Exudyn's generalized-alpha at the same steps (``SAME_STEPS``): the crank
    angle's error at ``DURATION`` and the median wall time of ``repeat`` rounds in which the
    two ran in turn."""
    if not peers.available("exudyn"):
        return []
    rows = []
    for h in SAME_STEPS:
        runs = [lambda h=h: run(model, q0, qd0, "generalized-alpha", {"step": h}),
                lambda h=h: peers.exudyn_slider_crank(h, qd0, DURATION, math.radians(65.0))]
        errors = [abs(engine()[0] - reference) for engine in runs]
        walls = interleaved_medians(runs, repeat)
        rows.append({"step": h, "errors": errors, "walls": walls, "ratio": walls[0] / walls[1]})
    print(mb.format_table({
        "step [s]": [r["step"] for r in rows],
        "mbd3d error [rad]": [r["errors"][0] for r in rows],
        "Exudyn error [rad]": [r["errors"][1] for r in rows],
        "mbd3d [s]": [r["walls"][0] for r in rows],
        "Exudyn [s]": [r["walls"][1] for r in rows],
        "mbd3d / Exudyn": [r["ratio"] for r in rows]}, precision=3))
    ratio = rows[0]["ratio"]
    print(f"generalized-alpha at the same step h = {SAME_STEPS[0]:g} s: {ratio:.2f} x Exudyn's "
          f"time (target <= 0.5: {'met' if ratio <= 0.5 else 'missed'}; medians of {repeat} "
          "rounds in which the engines ran in turn)")
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--peers", action="store_true", help="compare with Exudyn")
    parser.add_argument("--quick", action="store_true", help="one setting per integrator")
    args = parser.parse_args()
    main(args.peers, args.quick)
