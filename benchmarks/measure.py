"""What the benchmark scripts share: timing, the fitted cost exponent, the machine line, and the
search for the cheapest setting of an integrator that reaches a given accuracy."""

from __future__ import annotations

import os
import platform
import time
from typing import Callable, Iterable

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


def fitted_exponent(sizes: Iterable[float], costs: Iterable[float]) -> float:
    """Slope ``p`` of the least-squares line ``log cost = p log N + c`` (cost ~ N^p)."""
    x, y = np.log(np.asarray(list(sizes), float)), np.log(np.asarray(list(costs), float))
    return float(np.polyfit(x, y, 1)[0])


def machine() -> str:
    """One line naming the machine and the numerical stack."""
    return (f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
            f"NumPy {np.__version__}, SciPy {scipy.__version__}, mbd3d {mb.__version__}")


def cheapest(settings: Iterable[tuple[str, Callable[[], tuple[object, float]]]],
             error: Callable[[object], float], tolerance: float, repeat: int = 3
             ) -> tuple[str, float, float] | None:
    """The first of ``settings`` (ordered cheapest first) whose answer is within ``tolerance``.

    Each setting is ``(label, run)``, ``run()`` returning ``(answer, wall time [s])``; the one
    found is run ``repeat`` times more and its median wall time reported.

    Returns
    -------
    (label, error, median wall time [s]), or None when no setting is accurate enough.
    """
    for label, run in settings:
        answer, _ = run()
        err = error(answer)
        if err <= tolerance:
            walls = [run()[1] for _ in range(repeat)]
            return label, err, float(np.median(walls))
    return None
