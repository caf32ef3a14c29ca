"""Dense LU with partial pivoting, the augmented solve of a small model in one call, and the
penalty that weighs constraints like masses in augmented-Lagrangian matrices.

For the matrices of a mechanism of a few bodies (tens of unknowns) a plain compiled LU costs
less than the calls into LAPACK around it. The pivot test is that of :mod:`mbd3d.numerics.linalg`: a
matrix is singular when its smallest pivot falls below ``pivot_tolerance`` times the largest
(or a pivot is not finite).
"""

from __future__ import annotations

import numpy as np

from mbd3d.numerics.compiled import jit


@jit
def pivots_regular(sizes: np.ndarray, pivot_tolerance: float) -> bool:
    """Whether the pivots' sizes ``|U_kk|`` make a regular matrix: all finite and the
    smallest above ``pivot_tolerance`` times the largest."""
    smallest = np.inf
    largest = 0.0
    for size in sizes:
        if not size < np.inf:  # inf or NaN
            return False
        smallest = min(smallest, size)
        largest = max(largest, size)
    return sizes.shape[0] == 0 or smallest > pivot_tolerance * largest


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
    sizes = np.empty(n)
    for k in range(n):
        sizes[k] = abs(A[k, k])
    return piv, pivots_regular(sizes, pivot_tolerance)


@jit
def lu_solve_into(LU: np.ndarray, piv: np.ndarray, x: np.ndarray) -> None:
    """Overwrite ``x`` (holding ``b``) with the solution of ``A x = b`` from the factors of
    :func:`lu_factor`."""
    n = LU.shape[0]
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


@jit
def lu_solve_transpose_into(LU: np.ndarray, piv: np.ndarray, x: np.ndarray) -> None:
    """Overwrite ``x`` (holding ``b``) with the solution of ``A^T x = b`` from the factors of
    :func:`lu_factor`: ``U^T L^T P x = b``, the interchanges undone last, in reverse."""
    _triangular_solves(LU, x, True)
    for k in range(LU.shape[0] - 1, -1, -1):
        p = piv[k]
        if p != k:
            x[k], x[p] = x[p], x[k]


@jit
def _triangular_solves(LU: np.ndarray, x: np.ndarray, transpose: bool) -> None:
    """``x <- U^-1 L^-1 x``, or with ``transpose`` ``x <- L^-T U^-T x`` (``L`` with a unit
    diagonal; no row interchanges)."""
    n = LU.shape[0]
    if not transpose:
        for i in range(n):
            for j in range(i):
                x[i] -= LU[i, j] * x[j]
        for i in range(n - 1, -1, -1):
            for j in range(i + 1, n):
                x[i] -= LU[i, j] * x[j]
            x[i] /= LU[i, i]
        return
    # by rows of the factors (each x[i] done is taken out of the ones after it): the
    # storage's order
    for i in range(n):
        x[i] /= LU[i, i]
        for j in range(i + 1, n):
            x[j] -= LU[i, j] * x[i]
    for i in range(n - 1, -1, -1):
        for j in range(i):
            x[j] -= LU[i, j] * x[i]


@jit
def _signs_into(x: np.ndarray, signs: np.ndarray) -> bool:
    """``x <- sign(x)`` (+1 for zero), the old signs in ``signs``; returns whether they are
    unchanged."""
    same = True
    for i in range(x.shape[0]):
        sign = 1.0 if x[i] >= 0.0 else -1.0
        same = same and sign == signs[i]
        signs[i] = sign
        x[i] = sign
    return same


@jit
def _absolute_sum(x: np.ndarray) -> float:
    total = 0.0
    for value in x:
        total += abs(value)
    return total


@jit
def _largest_entry(x: np.ndarray) -> int:
    j = 0
    for i in range(x.shape[0]):
        if abs(x[i]) > abs(x[j]):
            j = i
    return j


@jit
def _inverse_into(LU: np.ndarray, ab: np.ndarray, kl: int, ku: int, piv: np.ndarray,
                  x: np.ndarray, transpose: bool) -> None:
    """``x <- U^-1 L^-1 x`` (``transpose``: ``x <- L^-T U^-T x``) from dense factors ``LU``
    without their interchanges (as ``gecon`` applies them), or, where ``ab`` is not empty,
    from band factors with theirs, which interleave with ``L`` (as ``gbcon``)."""
    if ab.shape[0] == 0:
        _triangular_solves(LU, x, transpose)
    elif transpose:
        band_solve_transpose_into(ab, x.shape[0], kl, ku, piv, x)
    else:
        band_solve_into(ab, x.shape[0], kl, ku, piv, x)


@jit
def _inverse_norm(LU: np.ndarray, ab: np.ndarray, kl: int, ku: int, piv: np.ndarray,
                  n: int) -> float:
    """Hager's and Higham's estimate of ``|A^-1|_1`` from the factors of :func:`_inverse_into`
    (Higham, ACM TOMS 14, 1988, Algorithm 4.1): LAPACK's ``lacn2`` with the same start and
    stopping rules."""
    x = np.full(n, 1.0 / n)
    _inverse_into(LU, ab, kl, ku, piv, x, False)
    estimate = _absolute_sum(x)
    if n == 1:
        return estimate
    signs = np.zeros(n)
    _signs_into(x, signs)
    _inverse_into(LU, ab, kl, ku, piv, x, True)
    j = _largest_entry(x)
    for iteration in range(2, 6):
        x[:] = 0.0
        x[j] = 1.0
        _inverse_into(LU, ab, kl, ku, piv, x, False)
        last = estimate
        estimate = _absolute_sum(x)
        # a repeated sign vector, or no growth: converged
        if _signs_into(x, signs) or estimate <= last:
            break
        _inverse_into(LU, ab, kl, ku, piv, x, True)
        j_last, j = j, _largest_entry(x)
        if x[j_last] == abs(x[j]) or iteration == 5:
            break
    # an alternating vector catches what the power iteration misses
    sign = 1.0
    for i in range(n):
        x[i] = sign * (1.0 + i / (n - 1))
        sign = -sign
    _inverse_into(LU, ab, kl, ku, piv, x, False)
    return max(estimate, 2.0 * _absolute_sum(x) / (3.0 * n))


@jit
def reciprocal_condition(LU: np.ndarray, norm: float) -> float:
    """Estimate of ``1 / (|A|_1 |A^-1|_1)`` from the factors of :func:`lu_factor` of ``A``,
    whose 1-norm is ``norm``: the algorithm of LAPACK's ``gecon``, so that it agrees with the
    estimate of the dense Factorization (SciPy's LAPACK) in :mod:`mbd3d.numerics.linalg`.
    ``|A^-1|_1`` is that of ``U^-1 L^-1``: the interchanges permute its columns only."""
    n = LU.shape[0]
    if norm == 0.0 or n == 0:
        return 0.0
    estimate = _inverse_norm(LU, np.empty(0), 0, 0, np.empty(0, dtype=np.int64), n)
    if not estimate > 0.0:
        return 0.0
    return (1.0 / estimate) / norm


@jit
def band_reciprocal_condition(ab: np.ndarray, n: int, kl: int, ku: int, piv: np.ndarray,
                              norm: float) -> float:
    """As :func:`reciprocal_condition` from the factors of :func:`band_factor`: the algorithm
    of LAPACK's ``gbcon``."""
    if norm == 0.0 or n == 0:
        return 0.0
    estimate = _inverse_norm(np.empty((0, 0)), ab, kl, ku, piv, n)
    if not estimate > 0.0:
        return 0.0
    return (1.0 / estimate) / norm


@jit
def solve_pattern_into(rows, cols, entry_scale, scale, values, b, pivot_tolerance, matrix, x):
    """Solve ``A x = b`` for the matrix with ``values`` at ``(rows, cols)``, factored as
    ``D A D`` with ``D = diag(scale)`` (the model's units; see :mod:`mbd3d.numerics.linalg`), in the
    scratch ``matrix`` (n, n); returns whether the matrix is regular."""
    n = scale.shape[0]
    matrix[:, :] = 0.0
    for p in range(rows.shape[0]):
        matrix[rows[p], cols[p]] = values[p] * entry_scale[p]
    piv, regular = lu_factor(matrix, pivot_tolerance)
    if not regular:
        x[:] = 0.0
        return False
    for i in range(n):
        x[i] = scale[i] * b[i]
    lu_solve_into(matrix, piv, x)
    for i in range(n):
        x[i] *= scale[i]
    return True


@jit
def solve_pattern(rows: np.ndarray, cols: np.ndarray, entry_scale: np.ndarray,
                  scale: np.ndarray, values: np.ndarray, b: np.ndarray,
                  pivot_tolerance: float):
    """``(x, regular)`` of :func:`solve_pattern_into`."""
    n = scale.shape[0]
    x = np.empty(n)
    regular = solve_pattern_into(rows, cols, entry_scale, scale, values, b, pivot_tolerance,
                                 np.empty((n, n)), x)
    return x, regular


@jit
def band_factor(ab: np.ndarray, n: int, kl: int, ku: int, pivot_tolerance: float):
    """Factor in place a matrix in LAPACK's band storage ``ab`` (flat, column-major, ``2 kl +
    ku + 1`` rows: ``A[i, j]`` at row ``kl + ku + i - j`` of column ``j``, the first ``kl``
    rows room for fill-in) by LU with partial pivoting (the algorithm of LAPACK's ``gbtf2``).
    Returns ``(piv, regular)``."""
    rows = 2 * kl + ku + 1
    kv = kl + ku
    piv = np.empty(n, dtype=np.int64)
    last = 0  # last column touched by the row interchanges so far
    for j in range(n):
        below = min(kl, n - 1 - j)
        column = j * rows
        p = 0
        big = abs(ab[column + kv])
        for i in range(1, below + 1):
            if abs(ab[column + kv + i]) > big:
                big = abs(ab[column + kv + i])
                p = i
        piv[j] = j + p
        if ab[column + kv + p] == 0.0:
            continue
        last = max(last, min(j + ku + p, n - 1))
        if p != 0:
            for c in range(j, last + 1):
                a = c * rows + kv + j - c
                b = a + p
                ab[a], ab[b] = ab[b], ab[a]
        pivot = ab[column + kv]
        for i in range(1, below + 1):
            ab[column + kv + i] /= pivot
        for c in range(j + 1, last + 1):
            top = c * rows + kv + j - c
            value = ab[top]
            if value != 0.0:
                for i in range(1, below + 1):
                    ab[top + i] -= ab[column + kv + i] * value
    sizes = np.empty(n)
    for j in range(n):
        sizes[j] = abs(ab[j * rows + kv])
    return piv, pivots_regular(sizes, pivot_tolerance)


@jit
def band_solve_into(ab: np.ndarray, n: int, kl: int, ku: int, piv: np.ndarray,
                    x: np.ndarray) -> None:
    """Overwrite ``x`` (holding ``b``) with the solution of ``A x = b`` from the factors of
    :func:`band_factor` (LAPACK's ``gbtrs``)."""
    rows = 2 * kl + ku + 1
    kv = kl + ku
    for j in range(n - 1):
        p = piv[j]
        if p != j:
            x[p], x[j] = x[j], x[p]
        below = min(kl, n - 1 - j)
        for i in range(1, below + 1):
            x[j + i] -= ab[j * rows + kv + i] * x[j]
    for j in range(n - 1, -1, -1):
        x[j] /= ab[j * rows + kv]
        for i in range(max(0, j - kv), j):
            x[i] -= ab[j * rows + kv + i - j] * x[j]


@jit
def band_solve_transpose_into(ab: np.ndarray, n: int, kl: int, ku: int, piv: np.ndarray,
                              x: np.ndarray) -> None:
    """Overwrite ``x`` (holding ``b``) with the solution of ``A^T x = b`` from the factors of
    :func:`band_factor` (LAPACK's ``gbtrs`` with ``trans``): ``U^T``, then ``L^T`` with the
    interchanges undone in reverse."""
    rows = 2 * kl + ku + 1
    kv = kl + ku
    for j in range(n):
        total = x[j]
        for i in range(max(0, j - kv), j):
            total -= ab[j * rows + kv + i - j] * x[i]
        x[j] = total / ab[j * rows + kv]
    for j in range(n - 2, -1, -1):
        total = x[j]
        for i in range(1, min(kl, n - 1 - j) + 1):
            total -= ab[j * rows + kv + i] * x[j + i]
        x[j] = total
        p = piv[j]
        if p != j:
            x[p], x[j] = x[j], x[p]


@jit
def solve_banded_pattern_into(flat, kl, ku, perm, entry_scale, scale, values, b,
                              pivot_tolerance, ab, permuted, x):
    """As :func:`solve_pattern_into` for a pattern permuted to a small bandwidth: the entries
    go to the band storage ``ab`` at ``flat`` and the unknowns are taken in the order
    ``perm`` (``permuted``: scratch of the size of ``x``)."""
    n = scale.shape[0]
    ab[:] = 0.0
    for p in range(flat.shape[0]):
        ab[flat[p]] = values[p] * entry_scale[p]
    piv, regular = band_factor(ab, n, kl, ku, pivot_tolerance)
    if not regular:
        x[:] = 0.0
        return False
    for i in range(n):
        permuted[i] = scale[perm[i]] * b[perm[i]]
    band_solve_into(ab, n, kl, ku, piv, permuted)
    for i in range(n):
        x[perm[i]] = scale[perm[i]] * permuted[i]
    return True


@jit
def solve_banded_pattern(flat: np.ndarray, kl: int, ku: int, perm: np.ndarray,
                         entry_scale: np.ndarray, scale: np.ndarray, values: np.ndarray,
                         b: np.ndarray, pivot_tolerance: float):
    """``(x, regular)`` of :func:`solve_banded_pattern_into`."""
    n = scale.shape[0]
    x = np.empty(n)
    regular = solve_banded_pattern_into(flat, kl, ku, perm, entry_scale, scale, values, b,
                                        pivot_tolerance, np.empty((2 * kl + ku + 1) * n),
                                        np.empty(n), x)
    return x, regular


@jit
def penalty_scale(mass_diagonal: np.ndarray, row_squared_norms: np.ndarray) -> float:
    """Penalty [units of the mass matrix per squared unit of ``Cq``] that weighs the
    constraints like the masses: mean ``|M_ii|`` over the mean squared row norm of ``Cq``
    (rows without entries left out; 1 when no row has any)."""
    total, count = 0.0, 0
    for norm in row_squared_norms:
        if norm > 0.0:
            total += norm
            count += 1
    if count == 0:
        return 1.0
    diagonal = 0.0
    for value in mass_diagonal:
        diagonal += abs(value)
    return (diagonal / max(mass_diagonal.shape[0], 1)) / (total / count)
