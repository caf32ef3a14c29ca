"""Cold and warm start of examples/slider_crank.py: the first run compiles mbd3d's compiled
core (Numba) and caches it, later runs load it from the cache.

A fresh cache directory (``NUMBA_CACHE_DIR``) stands for a fresh install; each run is a new
process, timed from its start to its end, the recordings written to a temporary folder.
Targets (issue #23): the first run within 30 s, later runs within 2 s.

    python benchmarks/cold_start.py [--warm-runs 3]
"""

from __future__ import annotations

import argparse
import os
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

EXAMPLE = pathlib.Path(__file__).resolve().parent.parent / "examples" / "slider_crank.py"


def timed_run(cache: str, folder: str) -> float:
    """Wall time [s] of one run of the example in a new process."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache)
    env.pop("NUMBA_DISABLE_JIT", None)
    start = time.perf_counter()
    subprocess.run([sys.executable, str(EXAMPLE)], cwd=folder, env=env, check=True,
                   stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def main(warm_runs: int = 3) -> dict:
    with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as folder:
        cold = timed_run(cache, folder)
        warm = [timed_run(cache, folder) for _ in range(warm_runs)]
    warm_median = float(np.median(warm)) if warm else float("nan")
    print(f"examples/slider_crank.py: first run (compiling) {cold:.1f} s (target <= 30 s: "
          f"{'met' if cold <= 30 else 'missed'}); later runs {warm_median:.2f} s, median of "
          f"{warm_runs} (target <= 2 s: {'met' if warm_median <= 2 else 'missed'})")
    return {"cold": cold, "warm": warm_median}


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--warm-runs", type=int, default=3)
    main(parser.parse_args().warm_runs)
