"""Linear solves of the solvers, with diagnostics that name joints when a matrix is singular.

Dense LAPACK (``getrf``) for small systems, SuperLU for large sparse ones; the choice is the
model's (``model.sparse``). A matrix is treated as singular when a pivot of its LU factors falls
below ``PIVOT_TOLERANCE`` times the largest one: the solution would then be dominated by rounding.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.sparse.csgraph import reverse_cuthill_mckee

__all__ = ["SingularMatrix", "Factorization", "dependent_rows", "augmented_matrix",
           "solve_augmented", "solve_model_augmented",
           "AugmentedPattern"]

#: relative size of the smallest LU pivot below which a matrix counts as singular
PIVOT_TOLERANCE = 1e-12


class SingularMatrix(Exception):
    """Internal: raised by :class:`Factorization`; the solvers turn it into a named error."""


class Factorization:
    """LU factors of a square matrix, dense or sparse, reusable for several right-hand sides.

    ``ordering`` is SuperLU's column ordering for sparse matrices: its default "COLAMD", or
    "NATURAL" for a matrix already permuted to a small bandwidth.
    """

    def __init__(self, A, ordering: str = "COLAMD"):
        self.sparse = sp.issparse(A)
        if self.sparse:
            try:
                self._lu = spla.splu(sp.csc_matrix(A), permc_spec=ordering)
            except RuntimeError as exc:  # SuperLU: "Factor is exactly singular"
                raise SingularMatrix(str(exc)) from None
            pivots = np.abs(self._lu.U.diagonal())
        else:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", la.LinAlgWarning)
                self._lu = la.lu_factor(A, check_finite=False)
            pivots = np.abs(np.diag(self._lu[0]))
        if pivots.size and (not np.all(np.isfinite(pivots))
                            or pivots.min() <= PIVOT_TOLERANCE * pivots.max()):
            raise SingularMatrix("smallest pivot below tolerance")

    def solve(self, b: np.ndarray, transpose: bool = False) -> np.ndarray:
        if self.sparse:
            return self._lu.solve(b, trans="T" if transpose else "N")
        return la.lu_solve(self._lu, b, trans=1 if transpose else 0, check_finite=False)


def dependent_rows(Cq, relative_tolerance: float = 1e-9) -> tuple[int, list[np.ndarray]]:
    """Numerical rank of ``Cq`` and the groups of rows that depend on each other.

    Uses the SVD: each left singular vector whose singular value is below
    ``relative_tolerance`` times the largest is a combination of rows that vanishes; the rows
    with a significant weight in it are reported together. When ``Cq`` has full rank by that
    tolerance, the rows of its smallest singular value are reported (nearly dependent).

    Returns
    -------
    rank : int
    groups : list of ndarray of int
        Row indices, one array per dependency.
    """
    A = Cq.toarray() if sp.issparse(Cq) else np.asarray(Cq)
    m = A.shape[0]
    if m == 0 or not np.all(np.isfinite(A)):
        return 0, []
    U, s, _ = la.svd(A, full_matrices=True)
    s_full = np.zeros(m)
    s_full[:len(s)] = s
    top = s_full.max() if s_full.size else 0.0
    small = np.flatnonzero(s_full <= relative_tolerance * top)
    rank = m - len(small)
    if len(small) == 0:
        small = [int(np.argmin(s_full))]
    groups = []
    for k in small:
        u = np.abs(U[:, k])
        groups.append(np.flatnonzero(u > 0.05 * u.max()))
    return rank, groups


def augmented_matrix(M, Cq):
    """``[[M, Cq^T], [Cq, 0]]``, dense or sparse like its blocks."""
    if sp.issparse(M) or sp.issparse(Cq):
        return sp.bmat([[sp.csr_matrix(M), sp.csr_matrix(Cq).T], [Cq, None]], format="csc")
    m = Cq.shape[0]
    return np.block([[M, Cq.T], [Cq, np.zeros((m, m))]])


class AugmentedPattern:
    """Where the mass blocks and the Jacobian values go in ``[M Cq^T; Cq 0]``, fixed per model."""

    def __init__(self, model):
        nb, nc, n, m = model.n_bodies, model.n_coords_per_body, model.n_coordinates, model.n_constraints
        base = np.arange(nb)[:, None, None] * nc
        block_rows = np.broadcast_to(base + np.arange(nc)[None, :, None], (nb, nc, nc)).ravel()
        block_cols = np.broadcast_to(base + np.arange(nc)[None, None, :], (nb, nc, nc)).ravel()
        jr, jc = model._jac_rows, model._jac_cols
        self.rows = np.concatenate([block_rows, n + jr, jc])
        self.cols = np.concatenate([block_cols, jc, n + jr])
        self.size = n + m
        self.sparse = model.sparse
        if self.sparse:
            # A symmetric reverse Cuthill-McKee permutation, computed once: the matrix is then
            # assembled already permuted to a small bandwidth (a chain's is banded) and SuperLU
            # factors it in natural order, instead of recomputing a column ordering per solve.
            structure = sp.csr_matrix((np.ones(len(self.rows)), (self.rows, self.cols)),
                                      shape=(self.size, self.size))
            self.perm = reverse_cuthill_mckee(structure, symmetric_mode=True)
            inverse = np.empty_like(self.perm)
            inverse[self.perm] = np.arange(self.size)
            prow, pcol = inverse[self.rows], inverse[self.cols]
            self.order = np.lexsort((prow, pcol))  # column-major for CSC
            self.indices = prow[self.order]
            counts = np.bincount(pcol, minlength=self.size)
            self.indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.intp)


def solve_model_augmented(model, blocks: np.ndarray, jac_data: np.ndarray, rhs: np.ndarray
                          ) -> np.ndarray:
    """Solve ``[M Cq^T; Cq 0] x = rhs`` from per-body mass blocks and Jacobian values.

    The matrix is filled into the pattern fixed at build: dense below the model's size
    threshold, otherwise sparse, permuted to a small bandwidth and factored by SuperLU.

    Raises
    ------
    SingularMatrix
    """
    pattern = model._augmented_pattern
    values = np.concatenate([blocks.ravel(), jac_data, jac_data])
    if pattern.sparse:
        K = sp.csc_matrix((values[pattern.order], pattern.indices, pattern.indptr),
                          shape=(pattern.size, pattern.size))
        x = np.empty(pattern.size)
        x[pattern.perm] = Factorization(K, ordering="NATURAL").solve(rhs[pattern.perm])
        return x
    K = np.zeros((pattern.size, pattern.size))
    K[pattern.rows, pattern.cols] = values
    return Factorization(K).solve(rhs)


def solve_augmented(M, Cq, top: np.ndarray, bottom: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Solve ``[M Cq^T; Cq 0] [x; lam] = [top; bottom]``.

    Raises
    ------
    SingularMatrix
        If the augmented matrix is singular (dependent constraint rows).
    """
    n = M.shape[0]
    K = augmented_matrix(M, Cq)
    sol = Factorization(K).solve(np.concatenate([top, bottom]))
    return sol[:n], sol[n:]
