"""Validation of user numbers, with messages that name what is wrong (``what``)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from mbd3d.errors import ModelError

__all__ = ["finite_scalar", "finite_vector", "is_finite_vector"]


def finite_scalar(value: Any, what: str, positive: bool = False) -> float:
    """``value`` as a finite float (positive if asked), else a :class:`ModelError` naming ``what``."""
    if isinstance(value, (bool, np.bool_)):  # float(True) is 1.0: a flag is not a quantity
        raise ModelError(f"{what} must be a number, got {value!r}")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ModelError(f"{what} must be a real number, got {value!r}") from None
    if not math.isfinite(number):
        raise ModelError(f"{what} must be finite, got {value!r}")
    if positive and not number > 0.0:
        raise ModelError(f"{what} must be positive, got {number}")
    return number


def finite_vector(value: Any, size: int, what: str) -> np.ndarray:
    """``value`` as a finite float array of ``size`` components, else a :class:`ModelError`."""
    if np.asarray(value).dtype == bool:
        raise ModelError(f"{what} must be {size} numbers, got {value!r}")
    try:
        arr = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ModelError(f"{what} must be {size} numbers, got {value!r}") from None
    if arr.size != size:
        raise ModelError(f"{what} must have {size} components, got {arr.size}: {value!r}")
    if not all(map(math.isfinite, arr.tolist())):  # a tenth of np.all's time on 3 numbers
        raise ModelError(f"{what} must be finite, got {value!r}")
    return arr


def is_finite_vector(value: Any, size: int) -> bool:
    """Whether ``value`` is ``size`` finite numbers (a test; :func:`finite_vector` says what is
    wrong)."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return False
    return arr.shape == (size,) and bool(np.all(np.isfinite(arr)))
