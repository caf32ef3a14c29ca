"""Dense LU with partial pivoting, and the augmented solve of a small model in one call.

For the matrices of a mechanism of a few bodies (tens of unknowns) a plain compiled LU costs
less than the calls into LAPACK around it. The pivot test is that of :mod:`mbd3d.linalg`: a
matrix is singular when its smallest pivot falls below ``pivot_tolerance`` times the largest
(or a pivot is not finite).
"""

from __future__ import annotations

import numpy as np

from mbd3d.compiled import jit


@jit
def lu_factor(A: np.ndarray, pivot_tolerance: float):
    """Factor ``A`` (n, n) in place into ``L U`` (row interchanges ``piv``); returns
    ``(piv, regular)``."""
    n = A.shape[0]
    piv = np.empty(n, dtype=np.int64)
    for k in range(n):
        p = k
        big = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > big:
                big = abs(A[i, k])
                p = i
        piv[k] = p
        if p != k:
            for j in range(n):
                A[k, j], A[p, j] = A[p, j], A[k, j]
        pivot = A[k, k]
        if pivot != 0.0:
            for i in range(k + 1, n):
                factor = A[i, k] / pivot
                A[i, k] = factor
                if factor != 0.0:
                    for j in range(k + 1, n):
                        A[i, j] -= factor * A[k, j]
    smallest = np.inf
    largest = 0.0
    regular = True
    for k in range(n):
        size = abs(A[k, k])
        if not size < np.inf:  # inf or NaN
            regular = False
        smallest = min(smallest, size)
        largest = max(largest, size)
    if n and not smallest > pivot_tolerance * largest:
        regular = False
    return piv, regular


@jit
def lu_solve(LU: np.ndarray, piv: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``x`` with ``A x = b`` from the factors of :func:`lu_factor`."""
    n = LU.shape[0]
    x = b.copy()
    for k in range(n):
        p = piv[k]
        if p != k:
            x[k], x[p] = x[p], x[k]
    for i in range(n):
        total = x[i]
        for j in range(i):
            total -= LU[i, j] * x[j]
        x[i] = total
    for i in range(n - 1, -1, -1):
        total = x[i]
        for j in range(i + 1, n):
            total -= LU[i, j] * x[j]
        x[i] = total / LU[i, i]
    return x


@jit
def solve_pattern(rows: np.ndarray, cols: np.ndarray, entry_scale: np.ndarray,
                  scale: np.ndarray, values: np.ndarray, b: np.ndarray,
                  pivot_tolerance: float):
    """Solve ``A x = b`` for the matrix with ``values`` at ``(rows, cols)``, factored as
    ``D A D`` with ``D = diag(scale)`` (the model's units; see :mod:`mbd3d.linalg`).
    Returns ``(x, regular)``."""
    n = scale.shape[0]
    A = np.zeros((n, n))
    for p in range(rows.shape[0]):
        A[rows[p], cols[p]] = values[p] * entry_scale[p]
    piv, regular = lu_factor(A, pivot_tolerance)
    if not regular:
        return np.zeros(n), False
    x = lu_solve(A, piv, scale * b)
    return scale * x, True
