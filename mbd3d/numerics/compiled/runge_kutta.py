"""Explicit Runge-Kutta pairs with error control and dense output, compiled.

The methods are the published pairs: Bogacki-Shampine 3(2) ("RK23"), Dormand-Prince 5(4)
("RK45", MATLAB's ode45) and Hairer's DOP853 8(5,3) with its 7th-order interpolant. Their
tableaus are taken from SciPy's classes (the numbers of the papers, already checked there)
and turned into one layout (:class:`Tableau`), so that one compiled step, one error norm and
one interpolation serve the three. The step-size control is the standard one (Hairer,
Norsett and Wanner, *Solving Ordinary Differential Equations I*, II.4): the error is measured
in the RMS norm against ``atol + rtol max(|y|, |y_new|)``, and the step is multiplied by
``0.9 err^(-1 / (q + 1))`` within [0.2, 10] (no growth right after a rejection), ``q`` the
order of the error estimator.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.integrate as si

from mbd3d.numerics.compiled import jit

#: dense output: a polynomial in the step fraction (``K^T P``), or DOP853's interpolant
POLYNOMIAL, DOP853_INTERPOLANT = 0, 1
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0


class Tableau:
    """One explicit pair in the layout of the compiled step.

    Attributes
    ----------
    A : (s, s), C : (s,), B : (s,)
        The Butcher tableau of the ``s`` stages; stage ``s + 1`` is ``f(t + h, y_new)``
        (first same as last).
    E, E_low : (s + 1,)
        Error weights: ``E`` the main estimate; DOP853 also ``E_low`` (its 3rd-order one),
        zero for the others.
    dense_kind : int
        ``POLYNOMIAL`` (``P`` (s + 1, p)) or ``DOP853_INTERPOLANT`` (``A_extra`` (3, 16),
        ``C_extra`` (3,), ``D`` (4, 16)).
    error_order : int
        Order of the error estimator.
    """

    def __init__(self, cls):
        self.name = cls.__name__
        self.A, self.B, self.C = (np.ascontiguousarray(getattr(cls, k), dtype=float)
                                  for k in ("A", "B", "C"))
        s = len(self.B)
        self.error_order = int(cls.error_estimator_order)
        if hasattr(cls, "E5"):
            self.E, self.E_low = np.array(cls.E5, dtype=float), np.array(cls.E3, dtype=float)
            self.dense_kind = DOP853_INTERPOLANT
            self.P = np.zeros((s + 1, 0))
            self.A_extra = np.ascontiguousarray(cls.A_EXTRA, dtype=float)
            self.C_extra = np.ascontiguousarray(cls.C_EXTRA, dtype=float)
            self.D = np.ascontiguousarray(cls.D, dtype=float)
        else:
            self.E, self.E_low = np.array(cls.E, dtype=float), np.zeros(s + 1)
            self.dense_kind = POLYNOMIAL
            self.P = np.ascontiguousarray(cls.P, dtype=float)
            self.A_extra = np.zeros((0, s + 1))
            self.C_extra = np.zeros(0)
            self.D = np.zeros((0, s + 1))
        # stages of the step plus DOP853's three extra ones for its interpolant
        self.n_stored = s + 1 + len(self.C_extra)
        #: rows of the dense-output coefficients
        self.dense_rows = 3 + len(self.D) if hasattr(cls, "E5") else self.P.shape[1]

    def arrays(self) -> tuple:
        """The tableau as the compiled functions take it."""
        return (self.A, self.B, self.C, self.E, self.E_low, self.P, self.A_extra,
                self.C_extra, self.D, self.dense_kind, self.error_order)


#: the pairs by the names forward_dynamics takes
TABLEAUS = {name: Tableau(cls) for name, cls in
            (("RK23", si.RK23), ("RK45", si.RK45), ("DOP853", si.DOP853))}


@jit
def rms(x: np.ndarray, scale: np.ndarray) -> float:
    """``sqrt(mean((x / scale)^2))``."""
    total = 0.0
    for i in range(x.shape[0]):
        r = x[i] / scale[i]
        total += r * r
    return math.sqrt(total / max(x.shape[0], 1))


@jit
def stage_state(y: np.ndarray, K: np.ndarray, a: np.ndarray, stages: int, h: float,
                out: np.ndarray) -> np.ndarray:
    """``out = y + h sum_j a_j K_j`` over the first ``stages`` stages; returns ``out``."""
    out[:] = y
    for j in range(stages):
        c = h * a[j]
        if c != 0.0:
            for i in range(y.shape[0]):
                out[i] += c * K[j, i]
    return out


@jit
def error_norm(K: np.ndarray, E: np.ndarray, E_low: np.ndarray, scale: np.ndarray, h: float,
               dense_kind: int) -> float:
    """The step's error relative to ``scale`` (RMS): ``h |K^T E|``; for DOP853 Hairer's
    combination of its 5th- and 3rd-order estimates."""
    n = scale.shape[0]
    stages = E.shape[0]
    main = 0.0
    low = 0.0
    for i in range(n):
        e5 = 0.0
        e3 = 0.0
        for j in range(stages):
            e5 += K[j, i] * E[j]
            e3 += K[j, i] * E_low[j]
        e5 /= scale[i]
        e3 /= scale[i]
        main += e5 * e5
        low += e3 * e3
    if dense_kind != DOP853_INTERPOLANT:
        return abs(h) * math.sqrt(main / max(n, 1))
    if main == 0.0 and low == 0.0:
        return 0.0
    return abs(h) * main / math.sqrt((main + 0.01 * low) * n)


@jit
def step_factor(error: float, error_order: int) -> float:
    """How much to lengthen (or shorten) the step after an error ``error`` (1 = tolerance)."""
    if error == 0.0:
        return MAX_FACTOR
    return min(MAX_FACTOR, max(MIN_FACTOR, SAFETY * error ** (-1.0 / (error_order + 1))))


@jit
def polynomial_coefficients(K: np.ndarray, P: np.ndarray, stages: int) -> np.ndarray:
    """``(K^T P)^T`` (p, n): the dense output ``y_old + h sum_k Q_k x^(k + 1)``."""
    p = P.shape[1]
    n = K.shape[1]
    Q = np.zeros((p, n))
    for k in range(p):
        for j in range(stages):
            c = P[j, k]
            if c != 0.0:
                for i in range(n):
                    Q[k, i] += K[j, i] * c
    return Q


@jit
def dop853_coefficients(K: np.ndarray, D: np.ndarray, y_old: np.ndarray, y: np.ndarray,
                        f_old: np.ndarray, f: np.ndarray, h: float) -> np.ndarray:
    """The seven rows ``F`` of DOP853's interpolant from all 16 stages ``K``."""
    n = y.shape[0]
    F = np.zeros((3 + D.shape[0], n))
    for i in range(n):
        delta = y[i] - y_old[i]
        F[0, i] = delta
        F[1, i] = h * f_old[i] - delta
        F[2, i] = 2.0 * delta - h * (f[i] + f_old[i])
    for r in range(D.shape[0]):
        for j in range(D.shape[1]):
            c = h * D[r, j]
            if c != 0.0:
                for i in range(n):
                    F[3 + r, i] += c * K[j, i]
    return F


@jit
def interpolate(dense_kind: int, coefficients: np.ndarray, y_old: np.ndarray, t_old: float,
                h: float, t: float) -> np.ndarray:
    """The state at ``t`` in the step ``[t_old, t_old + h]`` from its dense-output
    ``coefficients``."""
    x = (t - t_old) / h
    n = y_old.shape[0]
    y = np.zeros(n)
    if dense_kind == POLYNOMIAL:
        power = 1.0
        for k in range(coefficients.shape[0]):
            power *= x
            for i in range(n):
                y[i] += coefficients[k, i] * power
        for i in range(n):
            y[i] = y_old[i] + h * y[i]
        return y
    rows = coefficients.shape[0]
    for r in range(rows):
        row = rows - 1 - r
        for i in range(n):
            y[i] += coefficients[row, i]
        factor = x if r % 2 == 0 else 1.0 - x
        for i in range(n):
            y[i] *= factor
    for i in range(n):
        y[i] += y_old[i]
    return y
