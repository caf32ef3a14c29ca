"""The augmented equations of a large model solved through the constraint forces alone.

``[M Cq^T; Cq 0] [qdd; lam] = [Q; gamma]`` with ``M`` block diagonal (one positive definite
block per body) is, eliminating ``qdd = M^-1 (Q - Cq^T lam)``::

    S lam = Cq M^-1 Q - gamma,    S = Cq M^-1 Cq^T

``S`` couples two constraint rows only when they act on a common body: for a chain it is
block tridiagonal, and after a reverse Cuthill-McKee ordering of the rows
(:class:`mbd3d.numerics.patterns.RangeSpacePattern`) it is a narrow band whatever the chain's length.
Each body contributes ``Y_b^T Y_b`` with ``Y_b = L_b^-1 Cq_b^T`` (``M_b = L_b L_b^T``), and
``S`` is factored by a banded Cholesky. On a chain that takes several times fewer operations
than the LU of the augmented matrix, whose band is twice as wide and indefinite.

Accuracy is that of the augmented LU: both matrices have condition numbers growing as the
inverse square of ``Cq``'s smallest singular value near a singular position (the augmented
matrix's small eigenvalues are ``-sigma^2`` for ``M = I``). The pivot test is local: a
constraint row is dependent when its Cholesky pivot falls below ``pivot_tolerance`` times its
own diagonal entry of ``S``, i.e. when the squared sine of its angle (in the metric of
``M^-1``) to the span of the rows before it does. It does not depend on units (``S`` scales
with its rows, and is unchanged by a change of the coordinates' units) nor on the size of the
model, where a test against the largest pivot of the whole matrix is not.
"""

from __future__ import annotations

import math

import numpy as np

from mbd3d.numerics.compiled import jit


@jit
def _cholesky_in_place(nc: int, blocks: np.ndarray, k: int) -> bool:
    """Lower Cholesky factor ``L`` of ``blocks[k]`` (nc, nc) in its lower triangle, with the
    reciprocals ``1 / L_ii`` on the diagonal (the solves then multiply instead of dividing);
    False unless positive definite (a mass block always is: masses and inertias are
    positive)."""
    for j in range(nc):
        d = blocks[k, j, j]
        for p in range(j):
            d -= blocks[k, j, p] * blocks[k, j, p]
        if not d > 0.0:
            return False
        reciprocal = 1.0 / math.sqrt(d)
        blocks[k, j, j] = reciprocal
        for i in range(j + 1, nc):
            total = blocks[k, i, j]
            for p in range(j):
                total -= blocks[k, i, p] * blocks[k, j, p]
            blocks[k, i, j] = total * reciprocal
    return True


@jit
def _forward(nc: int, blocks: np.ndarray, k: int, x: np.ndarray, start: int) -> None:
    """``x[start:start + nc] = L^-1 x[start:start + nc]`` for the factor ``L`` of
    ``blocks[k]`` (:func:`_cholesky_in_place`)."""
    for i in range(nc):
        total = x[start + i]
        for p in range(i):
            total -= blocks[k, i, p] * x[start + p]
        x[start + i] = total * blocks[k, i, i]


@jit
def _backward(nc: int, blocks: np.ndarray, k: int, x: np.ndarray, start: int) -> None:
    """``x[start:start + nc] = L^-T x[start:start + nc]`` for the factor ``L`` of
    ``blocks[k]`` (:func:`_cholesky_in_place`)."""
    for i in range(nc - 1, -1, -1):
        total = x[start + i]
        for p in range(i + 1, nc):
            total -= blocks[k, p, i] * x[start + p]
        x[start + i] = total * blocks[k, i, i]


@jit
def band_cholesky(band: np.ndarray, m: int, k: int, diagonal: np.ndarray,
                  pivot_tolerance: float) -> bool:
    """Factor in place ``S = L L^T`` held in lower band storage (``S[i, j]``, ``i >= j``, at
    ``band[j (k + 1) + i - j]``); ``diagonal``: ``S``'s diagonal before factoring. Returns
    whether every pivot is above ``pivot_tolerance`` times its diagonal entry (and finite)."""
    width = k + 1
    for j in range(m):
        column = j * width
        d = band[column]
        if not (d > pivot_tolerance * diagonal[j] and d < np.inf):
            return False
        d = math.sqrt(d)
        band[column] = d
        below = min(k, m - 1 - j)
        for i in range(1, below + 1):
            band[column + i] /= d
        for c in range(1, below + 1):
            value = band[column + c]
            if value != 0.0:
                target = (j + c) * width - c
                for i in range(c, below + 1):
                    band[target + i] -= band[column + i] * value
    return True


@jit
def band_cholesky_solve(band: np.ndarray, m: int, k: int, x: np.ndarray) -> None:
    """Overwrite ``x`` (holding ``b``) with the solution of ``L L^T x = b``
    (:func:`band_cholesky`'s factor)."""
    width = k + 1
    for j in range(m):
        column = j * width
        x[j] /= band[column]
        value = x[j]
        for i in range(1, min(k, m - 1 - j) + 1):
            x[j + i] -= band[column + i] * value
    for j in range(m - 1, -1, -1):
        column = j * width
        total = x[j]
        for i in range(1, min(k, m - 1 - j) + 1):
            total -= band[column + i] * x[j + i]
        x[j] = total / band[column]


@jit
def range_space_factor(nc, blocks, data, slot, body_start, positions, k, pivot_tolerance,
                       jacobian, band, diagonal) -> bool:
    """Factor ``[M Cq^T; Cq 0]`` for :func:`range_space_solve_factored`: ``M_b = L_b L_b^T``,
    ``Y_b = L_b^-1 Cq_b^T`` and ``S = Cq M^-1 Cq^T = sum_b Y_b^T Y_b`` in band storage,
    factored by :func:`band_cholesky`. Returns whether ``S`` is regular.

    ``nc``: coordinates per body, a constant where the body type is (the loops over a body's
    coordinates are then unrolled). ``blocks`` (bodies, nc, nc): the mass blocks, overwritten
    by their factors. ``data`` (nnz,): the Jacobian's entries in the model's order. The
    pattern (:class:`mbd3d.numerics.patterns.RangeSpacePattern`): entry ``p`` goes to
    ``jacobian[slot[p]]``; body ``b``'s rows ``Cq_b`` are rows ``body_start[b]`` to
    ``body_start[b + 1]`` of ``jacobian`` (nc values each; overwritten by ``Y_b^T``) and the
    rows at positions ``positions[...]`` (increasing) of the ordering of ``S``, of
    half-bandwidth ``k``. ``band`` ((k + 1) m,): ``S``'s factor; ``diagonal`` (m,): scratch.
    """
    n_bodies = blocks.shape[0]
    m = diagonal.shape[0]
    width = k + 1
    jacobian[:] = 0.0
    for p in range(data.shape[0]):
        jacobian[slot[p]] = data[p]
    band[:] = 0.0
    for body in range(n_bodies):
        if not _cholesky_in_place(nc, blocks, body):
            return False
        first, last = body_start[body], body_start[body + 1]
        for r in range(first, last):
            _forward(nc, blocks, body, jacobian, r * nc)
        for r in range(first, last):
            pr = positions[r]
            for s in range(first, r + 1):  # positions increase within a body
                total = 0.0
                for c in range(nc):
                    total += jacobian[r * nc + c] * jacobian[s * nc + c]
                band[positions[s] * width + pr - positions[s]] += total
    for j in range(m):
        diagonal[j] = band[j * width]
    return band_cholesky(band, m, k, diagonal, pivot_tolerance)


@jit
def range_space_solve_factored(nc, blocks, body_start, positions, row_position, k, b,
                               jacobian, band, vector, forces, x) -> None:
    """Solve ``[M Cq^T; Cq 0] x = b`` from the factors of :func:`range_space_factor`
    (same arguments): ``S lam = Cq M^-1 Q - gamma``, then ``qdd = M^-1 (Q - Cq^T lam)``.
    ``vector`` (m,) and ``forces`` (n,): scratch; ``b`` and ``x`` may be the same array."""
    n_bodies = blocks.shape[0]
    n = n_bodies * nc
    m = row_position.shape[0]
    vector[:] = 0.0
    for i in range(m):
        vector[row_position[i]] = -b[n + i]
    for body in range(n_bodies):
        base = body * nc
        for c in range(nc):
            forces[base + c] = b[base + c]
        _forward(nc, blocks, body, forces, base)  # u_b = L_b^-1 Q_b
        for r in range(body_start[body], body_start[body + 1]):
            total = 0.0
            for c in range(nc):
                total += jacobian[r * nc + c] * forces[base + c]
            vector[positions[r]] += total  # (Cq M^-1 Q) at row r
    band_cholesky_solve(band, m, k, vector)
    for i in range(m):
        x[n + i] = vector[row_position[i]]
    # qdd_b = M_b^-1 (Q_b - Cq_b^T lam) = L_b^-T (u_b - Y_b lam)
    for body in range(n_bodies):
        base = body * nc
        for c in range(nc):
            x[base + c] = forces[base + c]
        for r in range(body_start[body], body_start[body + 1]):
            lam = vector[positions[r]]
            for c in range(nc):
                x[base + c] -= jacobian[r * nc + c] * lam
        _backward(nc, blocks, body, x, base)


@jit
def range_space_solve_into(nc, blocks, data, slot, body_start, positions, row_position, k,
                           pivot_tolerance, b, jacobian, band, diagonal, vector, forces,
                           x) -> bool:
    """:func:`range_space_factor` then :func:`range_space_solve_factored` (the arguments of
    both); returns whether the matrix is regular (else ``x`` is zero)."""
    if not range_space_factor(nc, blocks, data, slot, body_start, positions, k,
                              pivot_tolerance, jacobian, band, diagonal):
        x[:] = 0.0
        return False
    range_space_solve_factored(nc, blocks, body_start, positions, row_position, k, b,
                               jacobian, band, vector, forces, x)
    return True
