"""What the benchmark scripts share: timing, the fitted cost exponent, the machine line, the
search for the cheapest setting of an integrator that reaches a given accuracy, and the
interleaved timing of the settings found for several engines."""

from __future__ import annotations

import os
import platform
import time
import warnings
from typing import Callable, Iterable, Sequence

import numpy as np
import scipy

import mbd3d as mb


def median_time(fn: Callable[[], object], repeat: int) -> float:
    """Median wall time of ``fn()`` over ``repeat`` runs [s]."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def cost_with_and_without(build: Callable[[bool], mb.Model], t: np.ndarray, repeat: int,
                          ignored: tuple = ()) -> list[dict]:
    """A free slider-crank's run from 30 rad/s on its crank's pin ``O``, ``build(False)``
    and ``build(True)`` (without and with what is measured), by DOP853 at rtol 1e-8 and
    generalized-alpha at h = 1e-3: per run, the median wall time ``wall`` [s] of ``repeat``
    after a first one (which compiles), the right-hand sides or steps ``count`` and the time
    ``per`` one [s] (and generalized-alpha's Newton ``iterations``). ``ignored``: warning
    classes the runs may give."""
    rows = []
    for method, options in (("DOP853", dict(rtol=1e-8)),
                            ("generalized-alpha", dict(step=1e-3))):
        for variant in (False, True):
            model = build(variant)

            def run():
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", (mb.InitialStateWarning, *ignored))
                    return mb.forward_dynamics(model, t, initial_rates={"O": 30.0},
                                               method=method, **options)
            res = run()  # compiled and cached before the timing
            wall = median_time(run, repeat)
            count = res.stats["rhs_evaluations" if method == "DOP853" else "steps"]
            rows.append({"method": method, "variant": variant, "count": count,
                         "per": wall / count, "wall": wall,
                         "iterations": res.stats.get("newton_iterations", 0),
                         "unit": "right-hand side" if method == "DOP853" else "step"})
    return rows


def fitted_exponent(sizes: Iterable[float], costs: Iterable[float]) -> float:
    """Slope ``p`` of the least-squares line ``log cost = p log N + c`` (cost ~ N^p)."""
    x, y = np.log(np.asarray(list(sizes), float)), np.log(np.asarray(list(costs), float))
    return float(np.polyfit(x, y, 1)[0])


def machine() -> str:
    """One line naming the machine and the numerical stack."""
    return (f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
            f"NumPy {np.__version__}, SciPy {scipy.__version__}, mbd3d {mb.__version__}")


def cheapest(settings: Iterable[tuple[str, Callable[[], tuple[object, float]]]],
             error: Callable[[object], float], tolerance: float
             ) -> tuple[str, float, Callable[[], tuple[object, float]]] | None:
    """The first of ``settings`` (ordered cheapest first) whose answer is within ``tolerance``.

    Each setting is ``(label, run)``, ``run()`` returning ``(answer, wall time [s])``.

    Returns
    -------
    (label, error, run) of the setting found, or None when none is accurate enough. Time the
    settings found for several engines with :func:`interleaved_medians`.
    """
    for label, run in settings:
        answer, _ = run()
        err = error(answer)
        if err <= tolerance:
            return label, err, run
    return None


def interleaved_medians(runs: Sequence[Callable[[], tuple[object, float]]], repeat: int = 3
                        ) -> list[float]:
    """Median wall time [s] of each of ``runs`` over ``repeat`` rounds that run them in turn.

    The wall times of this machine drift by tens of per cent within minutes (other tenants);
    taking the engines in turn, round after round, exposes each to the same drift, so that
    their ratio holds where separately measured times would not.
    """
    walls = [[] for _ in runs]
    for _ in range(repeat):
        for k, run in enumerate(runs):
            walls[k].append(run()[1])
    return [float(np.median(w)) for w in walls]


def compare_at_equal_accuracy(engines: dict, tolerance: float, unit: str, quantity: str,
                              repeat: int = 3) -> list[dict]:
    """Each engine's cheapest setting within ``tolerance``, timed in turn with the others.

    ``engines`` maps a name to ``(settings, error)``: the settings as for :func:`cheapest`
    (cheapest first), ``error(answer)`` in ``unit``. Prints the table (``quantity`` names the
    error's column) and returns its rows: ``engine``, ``setting``, ``error``, ``wall`` [s]
    (:func:`interleaved_medians` of ``repeat`` rounds) and ``ratio``, the best mbd3d engine's
    wall time over this one's.
    """
    rows, runs = [], []
    for engine, (settings, error) in engines.items():
        found = cheapest(settings, error, tolerance)
        if found is None:
            print(f"{engine}: no setting tried reaches {tolerance:g} {unit}")
            continue
        label, err, run = found
        rows.append({"engine": engine, "setting": label, "error": err})
        runs.append(run)
    for row, wall in zip(rows, interleaved_medians(runs, repeat)):
        row["wall"] = wall
    best = min((r["wall"] for r in rows if r["engine"].startswith("mbd3d")), default=np.nan)
    for row in rows:
        row["ratio"] = best / row["wall"]
    print(mb.format_table({
        "engine": [r["engine"] for r in rows],
        "cheapest setting": [r["setting"] for r in rows],
        f"{quantity} error [{unit}]": [r["error"] for r in rows],
        "wall [s]": [r["wall"] for r in rows],
        "mbd3d best / this": [r["ratio"] for r in rows],
    }, precision=3))
    return rows
