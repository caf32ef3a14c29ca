"""The points of a parameter study: every combination of given values (:func:`grid`) or
random samples from distributions (:func:`monte_carlo`), as the dicts :func:`mbd3d.sweeps.sweep`
takes, their values plain Python numbers (so that they serialise to JSON and key the runs).
"""

from __future__ import annotations

import itertools
import math
from typing import Any, Iterable

import numpy as np

from mbd3d.errors import MBDError

__all__ = ["grid", "monte_carlo"]


def grid(**axes: Iterable) -> list[dict]:
    """Every combination of the values given per parameter (the last one varies fastest).

    Floats are kept to 15 significant digits, so that ``np.linspace(0.1, 0.5, 9)`` gives
    0.15, as written, where its binary value prints as 0.15000000000000002.

    Parameters
    ----------
    **axes
        Parameter name -> its values (any iterable).

    Examples
    --------
    >>> grid(speed=[1.0, 2.0], rod=[0.3, 0.4])
    [{'speed': 1.0, 'rod': 0.3}, {'speed': 1.0, 'rod': 0.4}, {'speed': 2.0, 'rod': 0.3}, {'speed': 2.0, 'rod': 0.4}]
    >>> grid(speed=np.array([1.0, 2.0]), mode="fast")
    [{'speed': 1.0, 'mode': 'fast'}, {'speed': 2.0, 'mode': 'fast'}]
    >>> grid(rod=np.linspace(0.1, 0.2, 3))
    [{'rod': 0.1}, {'rod': 0.15}, {'rod': 0.2}]
    """
    names = list(axes)
    values = []
    for name in names:
        given = axes[name]
        if isinstance(given, (str, bytes)) or np.ndim(given) == 0:
            given = [given]  # one value: the parameter is held fixed
        axis = [_as_given(v) for v in given]
        if not axis:
            raise MBDError(f"grid: parameter '{name}' needs a non-empty sequence of values, got "
                           f"{axes[name]!r}")
        values.append(axis)
    return [dict(zip(names, combination)) for combination in itertools.product(*values)]


def monte_carlo(n: int, seed: int, **distributions: Any) -> list[dict]:
    """``n`` random samples of the parameters, reproducible from ``seed``.

    Each parameter is a ``(low, high)`` pair (uniform), a SciPy frozen distribution
    (``scipy.stats.norm(0.26, 0.001)``), or a function of a ``numpy.random.Generator``
    returning one value. Parameters are drawn in the order given, sample after sample.

    Parameters
    ----------
    n : int
        The number of samples, positive.
    seed : int
        Of the random generator.
    **distributions
        Parameter name -> its distribution (see above).

    Examples
    --------
    >>> samples = monte_carlo(3, seed=1, rod=(0.25, 0.27))
    >>> len(samples), all(0.25 <= s["rod"] <= 0.27 for s in samples)
    (3, True)
    """
    if not (isinstance(n, (int, np.integer)) and n > 0):
        raise MBDError(f"monte_carlo: n must be a positive number of samples, got {n!r}")
    rng = np.random.default_rng(seed)
    draws = {}
    for name, spec in distributions.items():
        if hasattr(spec, "rvs"):
            draws[name] = lambda spec=spec: float(spec.rvs(random_state=rng))
        elif callable(spec):
            draws[name] = lambda spec=spec: spec(rng)
        elif (isinstance(spec, (tuple, list)) and len(spec) == 2
              and all(np.isfinite(float(v)) for v in spec) and spec[0] < spec[1]):
            draws[name] = lambda spec=spec: float(rng.uniform(spec[0], spec[1]))
        else:
            raise MBDError(f"monte_carlo: parameter '{name}' must be a (low, high) pair with "
                           "low < high, a scipy.stats frozen distribution or a function of a "
                           f"numpy Generator, got {spec!r}")
    samples = []
    for _ in range(n):
        samples.append({name: _plain(draw()) for name, draw in draws.items()})
    return samples


def _plain(value: Any) -> Any:
    """NumPy scalars and arrays as Python numbers and lists, so values serialize to JSON."""
    if isinstance(value, np.generic) or (isinstance(value, np.ndarray) and value.ndim == 0):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    return value


def _as_given(value: Any) -> Any:
    """A grid value as the user means it: floats rounded to 15 significant digits, which
    drops the representation error of ``linspace`` and ``arange`` (0.15000000000000002 is
    0.15) and never changes a number written with 15 digits or fewer."""
    value = _plain(value)
    if isinstance(value, float) and math.isfinite(value):
        return float(f"{value:.15g}")
    return value
