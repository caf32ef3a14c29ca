"""Cost of the planar solvers on an N-link pendulum chain.

For N = 10, 100, 1000 links (horizontal at rest, falling under gravity) it prints medians over
repeated runs of: one constraint Jacobian evaluation, one augmented solve (accelerations and
multipliers from [M Cq^T; Cq 0], including the evaluation of everything in it), and one
simulated second with RK45 at rtol 1e-6, as totals, per integrator step and per body.

Run: python benchmarks/planar_chain.py [--sizes 10 100 1000] [--crossover]
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

import mbd3d as mb
from mbd3d import constraints
from mbd3d.mechanisms import pendulum_chain


def median_time(fn, repeat: int) -> float:
    """Median wall time of ``fn()`` over ``repeat`` runs [s]."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def measure(n_links: int, simulate: bool = True, sparse: bool | None = None,
            factory=pendulum_chain) -> dict:
    model = factory(n_links, sparse=sparse)
    q, qd = model.q0.copy(), np.zeros(model.n_coordinates)
    repeat = 30 if n_links <= 100 else 10
    row = {
        "N": n_links,
        "solver": "sparse" if model.sparse else "dense",
        "jacobian_ms": 1e3 * median_time(lambda: constraints.jacobian(model, 0.0, q), repeat),
        "solve_ms": 1e3 * median_time(lambda: mb.forward_accelerations(model, 0.0, q, qd), repeat),
    }
    if simulate:
        runs = [mb.forward_dynamics(model, [0.0, 1.0], rtol=1e-6, atol=1e-8) for _ in range(3)]
        wall = float(np.median([r.stats["wall_time"] for r in runs]))
        steps = runs[0].stats["steps"]
        row.update(second_s=wall, steps=steps, step_ms=1e3 * wall / steps,
                   step_us_per_body=1e6 * wall / steps / n_links)
    return row


def report(title: str, factory, sizes, simulate: bool) -> list[dict]:
    """Measure chains of the given sizes built by ``factory`` and print the table."""
    print(f"{title}, {platform.processor() or platform.machine()}, "
          f"Python {platform.python_version()}, NumPy {np.__version__}")
    rows = [measure(n, simulate, factory=factory) for n in sizes]
    print(mb.format_table({
        "N": [r["N"] for r in rows],
        "Jacobian [ms]": [r["jacobian_ms"] for r in rows],
        "augmented solve [ms]": [r["solve_ms"] for r in rows],
        "solve per body [us]": [1e3 * r["solve_ms"] / r["N"] for r in rows],
        **({"1 s simulated [s]": [r["second_s"] for r in rows],
            "steps": [r["steps"] for r in rows],
            "per step [ms]": [r["step_ms"] for r in rows],
            "per step per body [us]": [r["step_us_per_body"] for r in rows]} if simulate else {}),
    }, precision=4))
    print("(medians; 'augmented solve' includes evaluating M, Cq, Qe and Qd; solver: "
          + ", ".join(f"N={r['N']} {r['solver']}" for r in rows) + ")")
    return rows


def main(sizes=(10, 100, 1000), simulate: bool = True) -> list[dict]:
    return report("planar N-link chain", pendulum_chain, sizes, simulate)


def crossover(sizes=(5, 10, 20, 30, 40, 60)) -> None:
    """Dense vs sparse augmented solve around the threshold (mbd3d.model.SPARSE_THRESHOLD)."""
    dense = [measure(n, False, sparse=False)["solve_ms"] for n in sizes]
    sparse = [measure(n, False, sparse=True)["solve_ms"] for n in sizes]
    print(mb.format_table({"N": sizes, "unknowns n+m": [5 * n for n in sizes],
                           "dense [ms]": dense, "sparse [ms]": sparse, "sparse/dense": np.divide(sparse, dense)}))


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[10, 100, 1000])
    parser.add_argument("--no-simulation", action="store_true")
    parser.add_argument("--crossover", action="store_true",
                        help="compare dense and sparse solves around the size threshold")
    args = parser.parse_args()
    if args.crossover:
        crossover()
    else:
        main(tuple(args.sizes), not args.no_simulation)
