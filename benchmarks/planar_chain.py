"""Cost of the solvers on an N-link planar pendulum chain, and the same chain in Exudyn and MuJoCo.

For N = 1, 10, 100, 1000, 10000 links (1 m, 1 kg bars pinned end to end, horizontal at rest,
falling under gravity) it prints medians of one constraint Jacobian evaluation, one augmented
solve (accelerations and multipliers from [M Cq^T; Cq 0], including the evaluation of
everything in it), and a forward-dynamics run at rtol 1e-6 with DOP853 (``--method``
to pick another; one simulated second up to 1000 links, 0.1 s above): its wall time and
steps, the cost of a step (that of the run's second half, free of the setup), per step and
body, and the fitted exponent of the costs in N from 100 links up.

With --peers (needs ``pip install -e ".[peers]"``) it then finds, for each engine, the
cheapest setting that gets the tip of the last link at t = 1 s right to 1e-6 m (against
DOP853 at rtol 1e-12, itself checked against MuJoCo's finest run) and prints the wall times
and the ratios mbd3d / peer. The search is the same for every engine: mbd3d's tolerance is
halved from 1e-3, the peers' step from a coarse one, until the answer is accurate enough. The
settings found are then timed in turn, 3 rounds, and the medians compared.

Run: python benchmarks/planar_chain.py [--sizes 1 10 100 1000 10000] [--peers] [--peer-links 100]
"""

from __future__ import annotations

import argparse
import pathlib
import sys
from typing import Callable

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

import mbd3d as mb  # noqa: E402
import peers  # noqa: E402
from mbd3d.model import constraints  # noqa: E402
from mbd3d.mechanisms import pendulum_chain  # noqa: E402
from measure import (compare_at_equal_accuracy, fitted_exponent, machine, median_time)  # noqa: E402,E501

#: accuracy of the tip position at which the engines are compared [m]
TOLERANCE = 1e-6


def no_initial_rates(model) -> None:
    """The planar chain starts at rest."""
    return None


def measure(n_links: int, factory=pendulum_chain, rates: Callable = no_initial_rates,
            simulate: bool = True, sparse: bool | None = None, method: str = "DOP853",
            long_span: float = 0.1) -> dict:
    """Costs of one chain size (see the module docstring)."""
    model = factory(n_links, sparse=sparse)
    q = model.q0.copy()
    qd = np.zeros(model.n_coordinates) if rates(model) is None else rates(model)
    repeat = 30 if n_links <= 100 else 10 if n_links <= 1000 else 3
    row = {
        "N": n_links,
        "solver": model._augmented_pattern.layout,
        "jacobian_ms": 1e3 * median_time(lambda: constraints.jacobian(model, 0.0, q), repeat),
        "solve_ms": 1e3 * median_time(lambda: mb.forward_accelerations(model, 0.0, q, qd),
                                      repeat),
    }
    if simulate:
        span = 1.0 if n_links <= 1000 else long_span

        def run(until: float) -> tuple[float, int]:
            runs = [mb.forward_dynamics(model, [0.0, until], qd0=rates(model), method=method,
                                        rtol=1e-6, atol=1e-8)
                    for _ in range(3 if n_links <= 1000 else 1)]
            return (float(np.median([r.stats["wall_time"] for r in runs])),
                    runs[0].stats["steps"])

        wall, steps = run(span)
        # the cost of a step is that of the second half of the run: the first half also pays
        # for the setup (the initial position and velocity solves, the first step's choice),
        # which would weigh on a run of a few steps and bend the fitted exponent
        half_wall, half_steps = run(span / 2)
        step_s = (wall - half_wall) / max(steps - half_steps, 1)
        row.update(span=span, run_s=wall, steps=steps, step_ms=1e3 * step_s,
                   step_us_per_body=1e6 * step_s / n_links)
    return row


def report(title: str, factory, sizes, simulate: bool,
           rates: Callable = no_initial_rates, method: str = "DOP853",
           long_span: float = 0.1) -> list[dict]:
    """Measure chains of the given sizes built by ``factory`` and print the table
    (``long_span``: the simulated time above 1000 links)."""
    print(f"{title}; {machine()}")
    rows = [measure(n, factory, rates, simulate, method=method, long_span=long_span)
            for n in sizes]
    table = {
        "N": [r["N"] for r in rows],
        "Jacobian [ms]": [r["jacobian_ms"] for r in rows],
        "augmented solve [ms]": [r["solve_ms"] for r in rows],
        "solve per body [us]": [1e3 * r["solve_ms"] / r["N"] for r in rows],
    }
    if simulate:
        table.update({"simulated [s]": [r["span"] for r in rows],
                      "wall [s]": [r["run_s"] for r in rows],
                      "steps": [r["steps"] for r in rows],
                      "per step [ms]": [r["step_ms"] for r in rows],
                      "per step per body [us]": [r["step_us_per_body"] for r in rows]})
    print(mb.format_table(table, precision=4))
    print("(medians; 'augmented solve' includes evaluating M, Cq, Qe and Qd; "
          f"{method} at rtol 1e-6; "
          "linear algebra: " + ", ".join(f"N={r['N']} {r['solver']}" for r in rows) + ")")
    large = [r for r in rows if r["N"] >= 100]
    if len(large) >= 2:
        sizes_large = [r["N"] for r in large]
        exponents = {"augmented solve": fitted_exponent(sizes_large, [r["solve_ms"] for r in large])}
        if simulate:
            exponents["integrator step"] = fitted_exponent(sizes_large,
                                                           [r["step_ms"] for r in large])
        print(f"cost ~ N^p from N = {sizes_large[0]} to {sizes_large[-1]}: " + ", ".join(
            f"{name} p = {p:.2f}" for name, p in exponents.items()))
    return rows


def compare_with_peers(n_links: int, factory=pendulum_chain, spatial: bool = False,
                       spin: float = 0.0, rates: Callable = no_initial_rates) -> list[dict]:
    """Wall time of each engine's cheapest setting that gets the tip at t = 1 s to
    ``TOLERANCE`` (see the module docstring); prints the table and returns its rows."""
    model = factory(n_links)
    tip_point = (0.5, 0.0, 0.0) if spatial else (0.5, 0.0)

    def ours(method: str, rtol: float):
        def run():
            res = mb.forward_dynamics(model, [0.0, 1.0], qd0=rates(model), method=method,
                                      rtol=rtol, atol=rtol * 1e-2)
            return res.point(f"link{n_links}", tip_point).position[-1], res.stats["wall_time"]
        return run

    reference = ours("DOP853", 1e-12)()[0]

    def error(tip):
        return float(np.max(np.abs(np.asarray(tip) - reference)))

    engines = {f"mbd3d {method}": [(f"rtol {rtol:.2g}", ours(method, rtol))
                                    for rtol in 1e-3 * 0.5 ** np.arange(27)]
               for method in ("DOP853", "RK45")}
    steps = 2.0 ** -np.arange(0, 10)
    if peers.available("exudyn"):
        engines["Exudyn generalized-alpha"] = [
            (f"h {h:g}", lambda h=h: peers.exudyn_chain(n_links, h, 1.0, spatial, spin))
            for h in 4e-3 * steps]
    if peers.available("mujoco"):
        engines["MuJoCo RK4"] = [
            (f"h {h:g}", lambda h=h: peers.mujoco_chain(n_links, h, 1.0, spatial, spin))
            for h in 2e-2 * steps]
        check = error(peers.mujoco_chain(n_links, 1e-4, 1.0, spatial, spin)[0])
        print(f"reference check: MuJoCo (RK4, h = 1e-4) differs from the mbd3d reference "
              f"(DOP853, rtol 1e-12) by {check:.1e} m at the tip")
    if len(engines) == 2:
        print("no peers installed: pip install -e '.[peers]' for Exudyn and MuJoCo")
    rows = compare_at_equal_accuracy({name: (settings, error)
                                      for name, settings in engines.items()},
                                     TOLERANCE, "m", "tip")
    # issue #23's targets: half MuJoCo's time in the plane, 0.3 of it in space, and ahead of
    # Exudyn's generalized-alpha
    targets = {"MuJoCo RK4": 0.3 if spatial else 0.5}
    print(f"({n_links} links, tip at t = 1 s to {TOLERANCE:g} m; medians of 3 rounds in which "
          "the engines ran in turn)")
    for r in rows:
        if not r["engine"].startswith("mbd3d"):
            target = targets.get(r["engine"], 1.0)
            print(f"mbd3d / {r['engine']}: {r['ratio']:.2f} (target <= {target}: "
                  f"{'met' if r['ratio'] <= target else 'missed'})")
    return rows


def crossover(sizes=(2, 4, 8, 12, 16, 24)) -> None:
    """Dense vs banded augmented solve around the threshold (mbd3d.model.builder.SPARSE_THRESHOLD)."""
    dense = [measure(n, simulate=False, sparse=False)["solve_ms"] for n in sizes]
    banded = [measure(n, simulate=False, sparse=True)["solve_ms"] for n in sizes]
    print(mb.format_table({"N": list(sizes), "unknowns n+m": [5 * n for n in sizes],
                           "dense [ms]": dense, "banded [ms]": banded,
                           "banded/dense": [s / d for s, d in zip(banded, dense)]}, precision=5))


def main(sizes=(1, 10, 100, 1000, 10000), simulate: bool = True, compare: bool = False,
         peer_links: int = 100, method: str = "DOP853") -> list[dict]:
    rows = report("planar N-link chain", pendulum_chain, sizes, simulate, method=method)
    if compare:
        compare_with_peers(peer_links)
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1, 10, 100, 1000, 10000])
    parser.add_argument("--no-simulation", action="store_true")
    parser.add_argument("--peers", action="store_true",
                        help="compare with Exudyn and MuJoCo at equal accuracy")
    parser.add_argument("--peer-links", type=int, default=100)
    parser.add_argument("--method", default="DOP853", help="integrator of the simulated runs")
    parser.add_argument("--crossover", action="store_true",
                        help="compare dense and banded solves around the size threshold")
    args = parser.parse_args()
    if args.crossover:
        crossover()
    else:
        main(tuple(args.sizes), not args.no_simulation, args.peers, args.peer_links, args.method)
