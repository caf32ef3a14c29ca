"""Linear solves of the solvers, with diagnostics that name joints when a matrix is singular.

Dense LAPACK (``getrf``) for small systems; for large ones (``model.sparse``) banded LAPACK
(``gbtrf``) after a bandwidth-reducing permutation, or SuperLU when the bandwidth is large.
A matrix is treated as singular when a pivot of its LU factors falls below
``PIVOT_TOLERANCE`` times the largest one: the solution would then be dominated by rounding.

Every matrix of a model is scaled before it is factored or its rank is taken, so that these
tests mean the same whatever the units: a mechanism of micrometres and micrograms has Jacobian
and mass entries that differ from a metre-sized one's by powers of ten, by column (positions
against angles) and by row (length rows against angle rows). The factors come from the
model's length and mass scales (``Model.row_scale``, ``Model.coordinate_scale``), rounded to
powers of two so that scaling is exact. They are physical units, never the entries' own sizes:
scaling a column by its largest entry would blow up a column that is small because the
mechanism is at a singular position, and hide the singularity.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import scipy.linalg as la
from scipy.linalg.lapack import dgbtrf as _gbtrf, dgbtrs as _gbtrs, \
    dgecon as _gecon, dgetrf as _getrf, dgetrs as _getrs
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from mbd3d.numerics.compiled.dense import penalty_scale, pivots_regular

__all__ = ["SingularMatrix", "Factorization", "BandedFactorization", "dependent_rows",
           "RANK_TOLERANCE",
           "jacobian_scaling", "jacobian_factors", "augmented_scaling",
           "ranked_rows", "summarize", "augmented_matrix", "solve_augmented", "solve_model_augmented",
           "factor_model_augmented", "penalty_matrix", "solve_augmented_lagrangian"]

#: relative size of the smallest LU pivot below which a matrix counts as singular
PIVOT_TOLERANCE = 1e-12
#: relative constraint violation accepted when the augmented-Lagrangian iteration stalls
STALL_TOLERANCE = 1e-10


class SingularMatrix(Exception):
    """Internal: raised by :class:`Factorization`; the solvers turn it into a named error."""


def _power_of_two(x: np.ndarray) -> np.ndarray:
    """The powers of two nearest to ``x`` (> 0): scaling by them is exact."""
    return np.exp2(np.round(np.log2(x)))


class Factorization:
    """LU factors of a square matrix, dense or sparse, reusable for several right-hand sides.

    ``ordering`` is SuperLU's column ordering for sparse matrices: its default "COLAMD", or
    "NATURAL" for a matrix already permuted to a small bandwidth. Dense matrices go straight
    to LAPACK's ``getrf``/``getrs`` (the wrappers' input checks cost more than the solve at the
    sizes of a mechanism). With ``overwrite`` a dense ``A`` that is already a Fortran-ordered
    float array is factored in place (the caller's buffer becomes the factors).

    ``scaling``: ``(r, c)``, factors of the rows and columns (see :func:`jacobian_scaling`),
    rounded to powers of two; ``diag(r) A diag(c)`` is factored, so that the pivot test does
    not depend on the units of the rows and columns. Solves and the determinant are those of
    ``A``.
    """

    def __init__(self, A, ordering: str = "COLAMD", pivot_tolerance: float = PIVOT_TOLERANCE,
                 overwrite: bool = False, scaling: tuple | None = None):
        self.sparse = sp.issparse(A)
        self._r = self._c = None
        if scaling is not None:
            self._r, self._c = (_power_of_two(np.asarray(f, dtype=float)) for f in scaling)
            if self.sparse:
                A = sp.diags(self._r) @ sp.csc_matrix(A) @ sp.diags(self._c)
            else:
                A = np.asfortranarray(self._r[:, None] * np.asarray(A, dtype=float)
                                      * self._c[None, :])
                overwrite = True
        self._norm = (float(abs(sp.csc_matrix(A)).sum(axis=0).max()) if self.sparse
                      else float(np.abs(A).sum(axis=0).max(initial=0.0)))  # 1-norm
        if self.sparse:
            try:
                self._lu = spla.splu(sp.csc_matrix(A), permc_spec=ordering)
            except RuntimeError as exc:  # SuperLU: "Factor is exactly singular"
                raise SingularMatrix(str(exc)) from None
            pivots = np.abs(self._lu.U.diagonal())
        else:
            # ``overwrite``: A is a Fortran-ordered float buffer the caller gives up
            A = A if overwrite else np.array(A, dtype=float, order="F")
            self._lu, self._piv, _ = _getrf(A, overwrite_a=1)
            pivots = np.abs(self._lu.diagonal())
        self._pivots = _check_pivots(pivots, pivot_tolerance)

    @property
    def log_abs_determinant(self) -> float:
        """``log |det A|`` from the pivots (the factor L has a unit diagonal)."""
        log_det = float(np.sum(np.log(self._pivots)))
        if self._r is not None:
            log_det -= float(np.sum(np.log(self._r)) + np.sum(np.log(self._c)))
        return log_det

    def solve(self, b: np.ndarray, transpose: bool = False) -> np.ndarray:
        if self._r is not None:
            # A = R^-1 S C^-1 with S = R A C factored: A x = b is S (C^-1 x) = R b, and
            # A^T y = b is S^T (R^-1 y) = C b
            inner, outer = (self._c, self._r) if transpose else (self._r, self._c)
            return outer * self._solve_scaled(inner * b, transpose)
        return self._solve_scaled(b, transpose)

    def reciprocal_condition(self) -> float:
        """Estimate of ``1 / (|A|_1 |A^-1|_1)`` of the factored (scaled) matrix: 1 for an
        orthogonal matrix, about the rounding error for a singular one (LAPACK ``gecon``;
        Higham's estimator for sparse factors)."""
        if self._norm == 0.0:
            return 0.0
        if self.sparse:
            n = self._lu.shape[0]
            inverse = spla.LinearOperator(
                (n, n), matvec=lambda x: self._lu.solve(np.asarray(x, dtype=float).ravel()),
                rmatvec=lambda x: self._lu.solve(np.asarray(x, dtype=float).ravel(), trans="T"),
                dtype=float)
            return 1.0 / (self._norm * spla.onenormest(inverse))
        return float(_gecon(self._lu, self._norm, norm="1")[0])

    def _solve_scaled(self, b: np.ndarray, transpose: bool) -> np.ndarray:
        if self.sparse:
            return self._lu.solve(b, trans="T" if transpose else "N")
        return _getrs(self._lu, self._piv, b, trans=1 if transpose else 0)[0]


class BandedFactorization:
    """LU factors (LAPACK ``gbtrf``, partial pivoting) of a matrix stored in LAPACK's band
    layout: ``ab[kl + ku + i - j, j] = A[i, j]`` with ``kl`` rows of room for fill-in on top.

    The cost is ``O(size kl (kl + ku))``: linear in the size for a matrix whose bandwidth
    does not grow with it (a chain ordered by reverse Cuthill-McKee).
    """

    sparse = False
    _r = _c = None  # never scaled here: the pattern scales the matrix (see _Scaled)

    def __init__(self, ab: np.ndarray, kl: int, ku: int,
                 pivot_tolerance: float = PIVOT_TOLERANCE):
        self.kl, self.ku = kl, ku
        self._lu, self._piv, info = _gbtrf(ab, kl, ku, overwrite_ab=1)
        if info < 0:
            raise ValueError(f"gbtrf: argument {-info} is invalid")
        self._pivots = _check_pivots(np.abs(self._lu[kl + ku]), pivot_tolerance)

    log_abs_determinant = Factorization.log_abs_determinant

    def solve(self, b: np.ndarray, transpose: bool = False) -> np.ndarray:
        return _gbtrs(self._lu, self.kl, self.ku, b, self._piv, trans=1 if transpose else 0)[0]


def _check_pivots(pivots: np.ndarray, pivot_tolerance: float) -> np.ndarray:
    """``pivots`` (their sizes) if they make a regular matrix by the compiled core's test
    (:func:`mbd3d.numerics.compiled.dense.pivots_regular`), else raise :class:`SingularMatrix`."""
    if not pivots_regular(np.ascontiguousarray(pivots, dtype=float), pivot_tolerance):
        raise SingularMatrix("smallest pivot below tolerance")
    return pivots


def jacobian_scaling(model, held: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Row and column factors that make a model's constraint Jacobian dimensionless: rows by
    one over their scale (lengths by the model's length, angles by one), columns by the
    coordinates' scale. ``held``: coordinates appended as rows ``q[k] = const``."""
    rows = 1.0 / model.row_scale
    if held is not None and len(held):
        rows = np.concatenate([rows, 1.0 / model.coordinate_scale[held]])
    return rows, model.coordinate_scale


def jacobian_factors(model) -> tuple[np.ndarray, np.ndarray]:
    """The factors of :func:`jacobian_scaling` as :class:`Factorization` applies them:
    rounded to powers of two, so that scaling is exact."""
    return tuple(_power_of_two(np.asarray(f, dtype=float)) for f in jacobian_scaling(model))


def augmented_scaling(model, held: np.ndarray | None = None) -> np.ndarray:
    """Symmetric factors for ``[M Cq^T; Cq 0]``: coordinates by ``s / (sqrt(m) L)``,
    multipliers by ``sqrt(m) L / r`` (``s``, ``r`` the coordinate and row scales, ``m``, ``L``
    the model's mass and length): every block of the scaled matrix is then of order one.
    ``held``: coordinates appended as rows ``q[k] = const`` (see :func:`jacobian_scaling`)."""
    size = np.sqrt(model.mass_scale) * model.length_scale
    rows = model.row_scale
    if held is not None and len(held):
        rows = np.concatenate([rows, model.coordinate_scale[held]])
    return np.concatenate([model.coordinate_scale / size, size / rows])


#: singular values at most this fraction of the largest count as zero in a Jacobian's rank
RANK_TOLERANCE = 1e-9


def dependent_rows(Cq, relative_tolerance: float = RANK_TOLERANCE, scaling: tuple | None = None
                   ) -> tuple[int, list[np.ndarray]]:
    """Numerical rank of ``Cq`` and, for each redundant equation, a smallest set of rows that
    depend on each other, most involved first.

    The rank comes from the SVD of ``diag(r) Cq diag(c)``, ``scaling = (r, c)`` (see
    :func:`jacobian_scaling`): singular values below ``relative_tolerance`` times the largest
    count as zero. A column-pivoted QR of ``Cq^T`` then picks ``rank`` independent
    rows; every other row is a combination of those, and the rows of that combination with
    it form its dependent set: a minimal one (no proper subset of it is dependent), so that a
    closed loop reports the rows that close it, not every row a singular vector touches.
    Rows are ordered by their weight in the combination. When ``Cq`` has full rank by that
    tolerance, the rows of its smallest singular value are reported (nearly dependent, as at
    a singular position), ordered by their weight in its left singular vector.

    Returns
    -------
    rank : int
    groups : list of ndarray of int
        Row indices, one array per dependency (per redundant equation when rank < rows).
    """
    A = Cq.toarray() if sp.issparse(Cq) else np.asarray(Cq)
    m = A.shape[0]
    if m == 0 or not np.all(np.isfinite(A)):
        return 0, []
    if scaling is not None:  # the rank must not depend on the units of rows and columns
        r, c = scaling
        A = np.asarray(r)[:, None] * A * np.asarray(c)[None, :]
    U, s, _ = la.svd(A, full_matrices=True)
    s_full = np.zeros(m)
    s_full[:len(s)] = s
    top = s_full.max() if s_full.size else 0.0
    rank = m - int(np.count_nonzero(s_full <= relative_tolerance * top))
    if rank == m:
        u = np.abs(U[:, int(np.argmin(s_full))])
        rows = np.flatnonzero(u > 0.05 * u.max())
        return rank, [rows[np.argsort(-u[rows], kind="stable")]]
    _, _, order = la.qr(A.T, mode="economic", pivoting=True)
    basis, others = order[:rank], order[rank:]
    coefficients = la.lstsq(A[basis].T, A[others].T)[0]  # (rank, redundant)
    groups = []
    for k, row in enumerate(others):
        c = np.abs(coefficients[:, k])
        used = np.flatnonzero(c > 1e-8 * max(1.0, c.max()))
        weights = np.concatenate([[1.0], c[used]])
        rows = np.concatenate([[row], basis[used]])
        groups.append(rows[np.argsort(-weights, kind="stable")])
    return rank, groups


def ranked_rows(groups, n_rows: int) -> np.ndarray:
    """The rows of all ``groups`` below ``n_rows``, once each, in the groups' order (each
    group lists its rows most involved first)."""
    seen: dict[int, None] = {}
    for group in groups:
        for r in group:
            if r < n_rows:
                seen[int(r)] = None
    return np.array(list(seen), dtype=int)


def summarize(names: Sequence[str], limit: int = 6) -> str:
    """``names`` for a message: the first ``limit`` and how many more."""
    names = list(names)
    if len(names) <= limit:
        return ", ".join(names)
    return f"{', '.join(names[:limit])} and {len(names) - limit} more"


def augmented_matrix(M, Cq):
    """``[[M, Cq^T], [Cq, 0]]``, dense or sparse like its blocks."""
    if sp.issparse(M) or sp.issparse(Cq):
        return sp.bmat([[sp.csr_matrix(M), sp.csr_matrix(Cq).T], [Cq, None]], format="csc")
    m = Cq.shape[0]
    return np.block([[M, Cq.T], [Cq, np.zeros((m, m))]])


def solve_model_augmented(model, blocks: np.ndarray, jac_data: np.ndarray, rhs: np.ndarray
                          ) -> np.ndarray:
    """Solve ``[M Cq^T; Cq 0] x = rhs`` from per-body mass blocks and Jacobian values.

    The matrix is filled into the pattern fixed at build (see :class:`_FixedPattern`): dense
    below the model's size threshold, otherwise permuted to a small bandwidth and factored in
    band storage by LAPACK, or by SuperLU when the bandwidth is large.

    Raises
    ------
    SingularMatrix
    """
    return model._augmented_pattern.solve(_augmented_values(blocks, jac_data), rhs)


def factor_model_augmented(model, blocks: np.ndarray, jac_data: np.ndarray):
    """Factors of ``[M Cq^T; Cq 0]`` from per-body mass blocks and Jacobian values, to solve
    several right-hand sides (see :func:`solve_model_augmented`).

    Raises
    ------
    SingularMatrix
    """
    return model._augmented_pattern.factor(_augmented_values(blocks, jac_data))


def _augmented_values(blocks: np.ndarray, jac_data: np.ndarray) -> np.ndarray:
    """The entries of ``[M Cq^T; Cq 0]`` in the order of :class:`mbd3d.numerics.patterns.AugmentedPattern`."""
    return np.concatenate([blocks.ravel(), jac_data, jac_data])


def solve_augmented(M, Cq, top: np.ndarray, bottom: np.ndarray,
                    scaling: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Solve ``[M Cq^T; Cq 0] [x; lam] = [top; bottom]`` (``scaling``: symmetric factors of
    the matrix, :func:`augmented_scaling`, for a pivot test independent of units).

    Raises
    ------
    SingularMatrix
        If the augmented matrix is singular (dependent constraint rows).
    """
    n = M.shape[0]
    K = augmented_matrix(M, Cq)
    sol = Factorization(K, scaling=None if scaling is None else (scaling, scaling)).solve(
        np.concatenate([top, bottom]))
    return sol[:n], sol[n:]


def penalty_matrix(A, Cq, penalty: float):
    """``A + penalty Cq^T Cq``, sparse (CSC) when either block is sparse."""
    if sp.issparse(A) or sp.issparse(Cq):
        Cq = sp.csr_matrix(Cq)
        return sp.csc_matrix(sp.csr_matrix(A) + penalty * (Cq.T @ Cq))
    return A + penalty * (Cq.T @ Cq)


def solve_augmented_lagrangian(A, Cq, b: np.ndarray, c: np.ndarray, *, relative_penalty: float = 1e6,
                               lam: np.ndarray | None = None, tol: float = 1e-13,
                               max_iterations: int = 50, scaling: np.ndarray | None = None
                               ) -> tuple[np.ndarray, np.ndarray, int]:
    """Solve ``[A Cq^T; Cq 0] [x; lam] = [b; c]`` by the augmented-Lagrangian iteration.

    ``(A + p Cq^T Cq) x_k = b - Cq^T lam_k + p Cq^T c``, ``lam_{k+1} = lam_k + p (Cq x_k - c)``,
    with ``p = relative_penalty * penalty_scale(A, Cq)``. Unlike the LU of the augmented matrix
    it needs ``A`` positive definite only on the null space of ``Cq`` and never divides by a
    vanishing pivot of ``Cq``: with dependent rows (redundant constraints) or at a singular
    configuration of the mechanism it converges to the solution ``x`` of the consistent part
    and to multipliers without a component in the null space of ``Cq^T`` (the minimum-norm
    ones when started from ``lam = 0``). Each iteration cuts the constraint error in a
    direction of singular value ``s`` by ``a / (a + p s^2)``.

    Returns
    -------
    x, lam : ndarray
    iterations : int
        Iterations used; ``max_iterations`` when ``|Cq x - c|`` did not reach ``tol`` relative
        to the size of its terms (the best iterate is returned).

    ``scaling``: symmetric factors of the augmented matrix (:func:`augmented_scaling`). The
    iteration then runs on the scaled, dimensionless system, so that its penalty, tolerances
    and minimum norm do not depend on units (the multipliers are then the minimum-norm ones
    in that scaling).

    Raises
    ------
    SingularMatrix
        If ``A + p Cq^T Cq`` is singular (``A`` is not positive definite on the null space of
        ``Cq``: a body without mass that nothing constrains).
    """
    if scaling is not None:
        n = A.shape[0]
        dx, dl = scaling[:n], scaling[n:]
        if sp.issparse(A) or sp.issparse(Cq):
            A_s = sp.diags(dx) @ sp.csr_matrix(A) @ sp.diags(dx)
            Cq_s = sp.csr_matrix(sp.diags(dl) @ sp.csr_matrix(Cq) @ sp.diags(dx))
        else:
            A_s = dx[:, None] * A * dx[None, :]
            Cq_s = dl[:, None] * Cq * dx[None, :]
        x, lam_s, used = solve_augmented_lagrangian(
            A_s, Cq_s, dx * b, dl * c, relative_penalty=relative_penalty,
            lam=None if lam is None else np.asarray(lam) / dl, tol=tol,
            max_iterations=max_iterations)
        return dx * x, dl * lam_s, used
    rows = (np.asarray(Cq.multiply(Cq).sum(axis=1)).ravel() if sp.issparse(Cq)
            else np.einsum("ij,ij->i", Cq, Cq))
    p = relative_penalty * penalty_scale(
        np.ascontiguousarray(A.diagonal() if sp.issparse(A) else np.diag(A), dtype=float),
        np.ascontiguousarray(rows, dtype=float))
    lu = Factorization(penalty_matrix(A, Cq, p))
    lam = np.zeros(Cq.shape[0]) if lam is None else np.array(lam, dtype=float)
    CqT = Cq.T
    abs_Cq = abs(Cq) if sp.issparse(Cq) else np.abs(Cq)
    rhs0 = b + p * (CqT @ c)
    best = None
    for iteration in range(1, max_iterations + 1):
        x = lu.solve(rhs0 - CqT @ lam)
        violation = Cq @ x - c
        lam = lam + p * violation
        size = float(np.max(np.abs(violation), initial=0.0))
        # rounding in Cq x - c is relative to the terms summed, not to the (small) result
        scale = float(np.max(np.abs(c), initial=0.0)) + float(
            np.max(abs_Cq @ np.abs(x), initial=0.0))
        stalled = best is not None and size > 0.5 * best[0]
        if best is None or size < best[0]:
            best = (size, x, lam)
        if size <= tol * max(scale, 1e-300):
            return x, lam, iteration
        if stalled and best[0] <= STALL_TOLERANCE * max(scale, 1e-300):
            # rows dependent only up to rounding (a configuration assembled to 1e-12 leaves
            # a singular value of that size): the violation stops at that level, far below
            # anything an inconsistent (locked) system would leave
            return best[1], best[2], iteration
    return best[1], best[2], max_iterations
