"""Prescribed motions: functions of time with exact first and second derivatives.

Drivers and actuators take a :class:`Motion`. The kinematic solvers need ``f``, ``f'`` and ``f''``
exactly (``Cq qd = f'`` and ``Cq qdd = Qd + f''``), so every motion supplies all three analytically;
none is obtained by finite differences.

Units are those of the driven quantity: rad for angles, m for translations, per second and per
second squared for the derivatives.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import Callable, Sequence

import numpy as np

from mbd3d.checks import finite_scalar
from mbd3d.errors import ModelError

__all__ = [
    "Motion",
    "Constant",
    "Ramp",
    "Harmonic",
    "Polynomial",
    "SmoothStep",
    "Function",
    "as_motion",
]


class Motion(ABC):
    """A scalar function of time ``f(t)`` with its exact derivatives.

    Motions can be added: ``Ramp(0, 2) + Harmonic(0.1, 5)`` is a motion too.
    """

    @abstractmethod
    def evaluate(self, t: float) -> tuple[float, float, float]:
        """Return ``(f(t), f'(t), f''(t))``."""

    def __call__(self, t: float) -> float:
        return self.evaluate(t)[0]

    def __add__(self, other: "Motion | float") -> "Motion":
        return _Sum(self, as_motion(other, "motion"))

    __radd__ = __add__


class _Sum(Motion):
    def __init__(self, first: Motion, second: Motion):
        self.parts = (first, second)

    def evaluate(self, t: float) -> tuple[float, float, float]:
        a, b = (p.evaluate(t) for p in self.parts)
        return a[0] + b[0], a[1] + b[1], a[2] + b[2]

    def __repr__(self) -> str:
        return f"{self.parts[0]!r} + {self.parts[1]!r}"


class Constant(Motion):
    """``f(t) = value``."""

    def __init__(self, value: float):
        self.value = finite_scalar(value, "Constant value")

    def evaluate(self, t: float) -> tuple[float, float, float]:
        return self.value, 0.0, 0.0

    def __repr__(self) -> str:
        return f"Constant({self.value})"


class Ramp(Motion):
    """``f(t) = initial + rate * t``: constant speed, e.g. a crank turning at ``rate`` rad/s."""

    def __init__(self, initial: float, rate: float):
        self.initial = finite_scalar(initial, "Ramp initial")
        self.rate = finite_scalar(rate, "Ramp rate")

    def evaluate(self, t: float) -> tuple[float, float, float]:
        return self.initial + self.rate * t, self.rate, 0.0

    def __repr__(self) -> str:
        return f"Ramp(initial={self.initial}, rate={self.rate})"


class Harmonic(Motion):
    """``f(t) = offset + amplitude * sin(frequency * t + phase)``, frequency in rad/s."""

    def __init__(self, amplitude: float, frequency: float, phase: float = 0.0, offset: float = 0.0):
        self.amplitude = finite_scalar(amplitude, "Harmonic amplitude")
        self.frequency = finite_scalar(frequency, "Harmonic frequency")
        self.phase = finite_scalar(phase, "Harmonic phase")
        self.offset = finite_scalar(offset, "Harmonic offset")

    def evaluate(self, t: float) -> tuple[float, float, float]:
        arg = self.frequency * t + self.phase
        s, c = math.sin(arg), math.cos(arg)
        a, w = self.amplitude, self.frequency
        return self.offset + a * s, a * w * c, -a * w * w * s

    def __repr__(self) -> str:
        return (f"Harmonic(amplitude={self.amplitude}, frequency={self.frequency}, "
                f"phase={self.phase}, offset={self.offset})")


class Polynomial(Motion):
    """``f(t) = c0 + c1 t + c2 t^2 + ...`` with coefficients in ascending powers."""

    def __init__(self, coefficients: Sequence[float]):
        coefficients = [finite_scalar(c, "Polynomial coefficient") for c in coefficients]
        if not coefficients:
            raise ModelError("Polynomial needs at least one coefficient")
        self.poly = np.polynomial.Polynomial(coefficients)
        self._d1 = self.poly.deriv(1)
        self._d2 = self.poly.deriv(2)

    def evaluate(self, t: float) -> tuple[float, float, float]:
        return float(self.poly(t)), float(self._d1(t)), float(self._d2(t))

    def __repr__(self) -> str:
        return f"Polynomial({list(self.poly.coef)})"


class SmoothStep(Motion):
    """Quintic step from ``start`` (for ``t <= t0``) to ``end`` (for ``t >= t1``).

    Velocity and acceleration are zero at both ends, so a driver using it starts and stops
    without a jump in the driving effort.
    """

    def __init__(self, t0: float, t1: float, start: float, end: float):
        self.t0 = finite_scalar(t0, "SmoothStep t0")
        self.t1 = finite_scalar(t1, "SmoothStep t1")
        if not self.t1 > self.t0:
            raise ModelError(f"SmoothStep needs t1 > t0, got t0={self.t0}, t1={self.t1}")
        self.start = finite_scalar(start, "SmoothStep start")
        self.end = finite_scalar(end, "SmoothStep end")

    def evaluate(self, t: float) -> tuple[float, float, float]:
        span = self.t1 - self.t0
        if t <= self.t0:
            return self.start, 0.0, 0.0
        if t >= self.t1:
            return self.end, 0.0, 0.0
        s = (t - self.t0) / span
        height = self.end - self.start
        # 10 s^3 - 15 s^4 + 6 s^5: the lowest-order step with zero slope and curvature at both ends
        shape = s**3 * (10.0 - 15.0 * s + 6.0 * s * s)
        d_shape = 30.0 * s * s * (1.0 - s) ** 2
        dd_shape = 60.0 * s * (1.0 - s) * (1.0 - 2.0 * s)
        return (self.start + height * shape, height * d_shape / span,
                height * dd_shape / span**2)

    def __repr__(self) -> str:
        return f"SmoothStep(t0={self.t0}, t1={self.t1}, start={self.start}, end={self.end})"


class Function(Motion):
    """A user motion given by three callables ``f(t)``, ``df(t)`` and ``d2f(t)``.

    The derivatives must be exact; they are not checked against ``f``.
    """

    def __init__(self, f: Callable[[float], float], df: Callable[[float], float],
                 d2f: Callable[[float], float]):
        for label, fn in (("f", f), ("df", df), ("d2f", d2f)):
            if not callable(fn):
                raise ModelError(f"Function: {label} must be callable, got {fn!r}")
        self.f, self.df, self.d2f = f, df, d2f

    def evaluate(self, t: float) -> tuple[float, float, float]:
        return float(self.f(t)), float(self.df(t)), float(self.d2f(t))

    def __repr__(self) -> str:
        return f"Function({getattr(self.f, '__name__', 'f')})"


def as_motion(value: "Motion | float", what: str) -> Motion:
    """Return ``value`` as a :class:`Motion` (a number becomes a :class:`Constant`).

    Raises
    ------
    ModelError
        If ``value`` is neither a motion nor a finite number; ``what`` names it in the message.
    """
    if isinstance(value, Motion):
        return value
    if callable(value):
        raise ModelError(
            f"{what}: a plain callable has no exact derivatives; wrap it as "
            f"mbd3d.Function(f, df, d2f) or use Constant, Ramp, Harmonic, Polynomial, SmoothStep")
    return Constant(finite_scalar(value, what))
