"""Prescribed motions: functions of time with exact first and second derivatives.

Drivers and actuators take a :class:`Motion`. The kinematic solvers need ``f``, ``f'`` and ``f''``
exactly (``Cq qd = f'`` and ``Cq qdd = Qd + f''``), so every motion supplies all three analytically;
none is obtained by finite differences.

Units are those of the driven quantity: rad for angles, m for translations, per second and per
second squared for the derivatives.

The built-in motions are sums of terms whose formulas are compiled
(:mod:`mbd3d.numerics.compiled.motions`), so that the compiled core evaluates drivers without calling
Python; :class:`Function` is evaluated by Python.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Callable, Sequence

import numpy as np

from mbd3d.numerics.checks import finite_scalar
from mbd3d.numerics.compiled import motions as compiled
from mbd3d.errors import ModelError
from mbd3d.model.arguments import RecordsArguments

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


class Motion(RecordsArguments, ABC):
    """A scalar function of time ``f(t)`` with its exact derivatives.

    Motions can be added: ``Ramp(0, 2) + Harmonic(0.1, 5)`` is a motion too.
    """

    @abstractmethod
    def evaluate(self, t: float) -> tuple[float, float, float]:
        """Return ``(f(t), f'(t), f''(t))``.

        Parameters
        ----------
        t : float
            Time [s].
        """

    def terms(self) -> list[tuple[int, np.ndarray]] | None:
        """The motion as a sum of terms ``(kind, parameters)`` of
        :mod:`mbd3d.numerics.compiled.motions`, which the compiled core evaluates without calling
        Python; None for a motion only Python can evaluate (:class:`Function`)."""
        return None

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

    def terms(self) -> list[tuple[int, np.ndarray]] | None:
        first, second = (p.terms() for p in self.parts)
        return None if first is None or second is None else first + second

    def __repr__(self) -> str:
        return f"{self.parts[0]!r} + {self.parts[1]!r}"


class _Term(Motion):
    """A motion of one compiled term (:mod:`mbd3d.numerics.compiled.motions`)."""

    _kind: int
    _params: np.ndarray

    def evaluate(self, t: float) -> tuple[float, float, float]:
        f, f1, f2 = compiled.term_values(self._kind, self._params, float(t))
        return float(f), float(f1), float(f2)

    def terms(self) -> list[tuple[int, np.ndarray]]:
        return [(self._kind, self._params)]


class Constant(_Term):
    """``f(t) = value``.

    Parameters
    ----------
    value : float
        The value [rad or m, as the driver it drives].
    """

    _kind = compiled.CONSTANT

    def __init__(self, value: float):
        self.value = finite_scalar(value, "Constant value")
        self._params = np.array([self.value])

    def __repr__(self) -> str:
        return f"Constant({self.value})"


class Ramp(_Term):
    """``f(t) = initial + rate * t``: constant speed, e.g. a crank turning at ``rate`` rad/s.

    Parameters
    ----------
    initial : float
        The value at t = 0 [rad or m].
    rate : float
        Its rate [rad/s or m/s].
    """

    _kind = compiled.RAMP

    def __init__(self, initial: float, rate: float):
        self.initial = finite_scalar(initial, "Ramp initial")
        self.rate = finite_scalar(rate, "Ramp rate")
        self._params = np.array([self.initial, self.rate])

    def __repr__(self) -> str:
        return f"Ramp(initial={self.initial}, rate={self.rate})"


class Harmonic(_Term):
    """``f(t) = offset + amplitude * sin(frequency * t + phase)``, frequency in rad/s.

    Parameters
    ----------
    amplitude : float
        [rad or m].
    frequency : float
        Angular frequency [rad/s].
    phase : float
        [rad].
    offset : float
        The mean value [rad or m].
    """

    _kind = compiled.HARMONIC

    def __init__(self, amplitude: float, frequency: float, phase: float = 0.0, offset: float = 0.0):
        self.amplitude = finite_scalar(amplitude, "Harmonic amplitude")
        self.frequency = finite_scalar(frequency, "Harmonic frequency")
        self.phase = finite_scalar(phase, "Harmonic phase")
        self.offset = finite_scalar(offset, "Harmonic offset")
        self._params = np.array([self.amplitude, self.frequency, self.phase, self.offset])

    def __repr__(self) -> str:
        return (f"Harmonic(amplitude={self.amplitude}, frequency={self.frequency}, "
                f"phase={self.phase}, offset={self.offset})")


class Polynomial(_Term):
    """``f(t) = c0 + c1 t + c2 t^2 + ...`` with coefficients in ascending powers.

    Parameters
    ----------
    coefficients : sequence of float
        ``c0, c1, ...`` [rad or m, per second to the power].
    """

    def __init__(self, coefficients: Sequence[float]):
        coefficients = [finite_scalar(c, "Polynomial coefficient") for c in coefficients]
        if not coefficients:
            raise ModelError("Polynomial needs at least one coefficient")
        self._params = np.array(coefficients)

    _kind = compiled.POLYNOMIAL

    def __repr__(self) -> str:
        return f"Polynomial({self._params.tolist()})"


class SmoothStep(_Term):
    """Quintic step from ``start`` (for ``t <= t0``) to ``end`` (for ``t >= t1``).

    Velocity and acceleration are zero at both ends, so a driver using it starts and stops
    without a jump in the driving effort.

    Parameters
    ----------
    t0, t1 : float
        Where the step starts and ends [s], ``t1 > t0``.
    start, end : float
        The values before and after it [rad or m].
    """

    _kind = compiled.SMOOTH_STEP

    def __init__(self, t0: float, t1: float, start: float, end: float):
        self.t0 = finite_scalar(t0, "SmoothStep t0")
        self.t1 = finite_scalar(t1, "SmoothStep t1")
        if not self.t1 > self.t0:
            raise ModelError(f"SmoothStep needs t1 > t0, got t0={self.t0}, t1={self.t1}")
        self.start = finite_scalar(start, "SmoothStep start")
        self.end = finite_scalar(end, "SmoothStep end")
        self._params = np.array([self.t0, self.t1, self.start, self.end])

    def __repr__(self) -> str:
        return f"SmoothStep(t0={self.t0}, t1={self.t1}, start={self.start}, end={self.end})"


class Function(Motion):
    """A user motion given by three callables ``f(t)``, ``df(t)`` and ``d2f(t)``.

    The derivatives must be exact; they are not checked against ``f``.

    Parameters
    ----------
    f, df, d2f : callable
        ``f(t)`` [rad or m] and its first and second derivatives, each of the time [s].
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
