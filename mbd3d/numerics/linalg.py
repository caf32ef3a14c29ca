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
from scipy.sparse.csgraph import reverse_cuthill_mckee

from mbd3d.numerics.compiled.dense import (penalty_scale, pivots_regular, solve_banded_pattern,
                                           solve_pattern)
from mbd3d.numerics.compiled.range_space import range_space_factor, range_space_solve_factored

__all__ = ["SingularMatrix", "Factorization", "BandedFactorization", "dependent_rows",
           "jacobian_scaling", "augmented_scaling",
           "ranked_rows", "summarize", "augmented_matrix", "solve_augmented", "solve_model_augmented",
           "factor_model_augmented", "AugmentedPattern", "RangeSpacePattern",
           "RangeSpaceFactorization", "PenaltyPattern", "penalty_scale",
           "penalty_matrix", "solve_augmented_lagrangian"]

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


def dependent_rows(Cq, relative_tolerance: float = 1e-9, scaling: tuple | None = None
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


#: banded LU is used for a sparse pattern when ``kl (kl + ku)``, its work per unknown, is at
#: most this: a chain's augmented matrix has ``kl, ku`` of 5 to 12 whatever its length, where
#: SuperLU's ordering and bookkeeping per call cost several times the arithmetic
BANDED_WORK_LIMIT = 4096
#: the range-space solve (:class:`RangeSpacePattern`) is used for a banded pattern when
#: ``k^2``, its work per constraint row for ``S``'s half-bandwidth ``k``, is at most this
RANGE_SPACE_WORK_LIMIT = 1024


class _FixedPattern:
    """Entries of a matrix whose sparsity is fixed when the model is built.

    Three layouts, chosen once per model:

    - dense (``model.sparse`` False): LAPACK ``getrf`` on the full matrix;
    - banded: the rows and columns are permuted once by a symmetric reverse Cuthill-McKee
      ordering, and when that leaves a small bandwidth (a chain, a mechanism with a few
      loops) the entries are scattered straight into LAPACK's band storage and factored by
      ``gbtrf``, at a cost linear in the size with no symbolic analysis per call;
    - sparse: otherwise, the permuted matrix in CSC form factored by SuperLU in natural order.
    """

    #: smallest pivot, relative to the largest, of a regular matrix of this pattern
    pivot_tolerance = PIVOT_TOLERANCE

    rows: np.ndarray
    cols: np.ndarray

    @staticmethod
    def mass_block_entries(model) -> tuple[np.ndarray, np.ndarray]:
        """Row and column indices of the per-body mass blocks, in ``blocks.ravel()`` order."""
        nb, nc = model.n_bodies, model.n_coords_per_body
        base = np.arange(nb)[:, None, None] * nc
        return (np.broadcast_to(base + np.arange(nc)[None, :, None], (nb, nc, nc)).ravel(),
                np.broadcast_to(base + np.arange(nc)[None, None, :], (nb, nc, nc)).ravel())

    def _lay_out(self, rows: np.ndarray, cols: np.ndarray, size: int, sparse: bool,
                 scale: np.ndarray) -> None:
        self.rows, self.cols, self.size = rows.astype(np.int64), cols.astype(np.int64), size
        # the matrix is factored as D A D with the model's fixed powers of two D = diag(scale)
        # (see the module doc); entry_scale multiplies the values in the pattern's order
        self.scale = _power_of_two(scale)
        self.entry_scale = self.scale[rows] * self.scale[cols]
        if not sparse:
            self.layout = "dense"
            self.flat = rows + cols * size  # Fortran order, as LAPACK takes it
            return
        structure = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(size, size))
        self.perm = reverse_cuthill_mckee(structure, symmetric_mode=True).astype(np.int64)
        inverse = np.empty_like(self.perm)
        inverse[self.perm] = np.arange(size)
        self.inverse = inverse
        prow, pcol = inverse[rows], inverse[cols]
        # CSC structure of the permuted matrix: SuperLU's input, also for a banded pattern
        # whose matrix gets entries outside the band (see factor)
        self.order = np.lexsort((prow, pcol))
        self.indices = prow[self.order].astype(np.int32)
        counts = np.bincount(pcol, minlength=size)
        self.indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
        kl = int(np.max(prow - pcol, initial=0))
        ku = int(np.max(pcol - prow, initial=0))
        if kl * (kl + ku) > BANDED_WORK_LIMIT:
            self.layout = "sparse"
            return
        self.layout = "banded"
        self.kl, self.ku = kl, ku
        self.band_rows = 2 * kl + ku + 1
        self.flat = ((kl + ku + prow - pcol) + pcol * self.band_rows).astype(np.int64)

    def _permuted_csc(self, values: np.ndarray, extra=None) -> sp.csc_matrix:
        """The permuted matrix in CSC form, plus ``extra`` (n, n) in the original order."""
        A = sp.csc_matrix((values[self.order], self.indices, self.indptr),
                          shape=(self.size, self.size))
        if extra is not None:
            A = sp.csc_matrix(A + sp.csr_matrix(extra)[self.perm][:, self.perm])
        return A

    def factor(self, values: np.ndarray, extra=None):
        """LU factors of the matrix with entries ``values`` (in the pattern's order) plus
        ``extra`` ((n, n), dense or sparse, in the original order; entries outside the band
        send the matrix to SuperLU).

        Returns
        -------
        Factorization or BandedFactorization, wrapped to solve in the original order.

        Raises
        ------
        SingularMatrix
        """
        values = values * self.entry_scale
        if extra is not None:
            d = self.scale
            extra = (sp.diags(d) @ sp.csr_matrix(extra) @ sp.diags(d) if sp.issparse(extra)
                     else d[:, None] * extra * d[None, :])
        if self.layout == "dense":
            A = self._scatter(values, self.size)
            if extra is not None:
                A += extra.toarray() if sp.issparse(extra) else extra
            return _Scaled(self.scale, Factorization(A, pivot_tolerance=self.pivot_tolerance,
                                                     overwrite=True))
        if self.layout in ("banded", "range"):  # "range" here: with ``extra``
            ab = self._scatter(values, self.band_rows)
            if extra is None or self._add_to_band(ab, extra):
                return _Scaled(self.scale, _Permuted(self, BandedFactorization(
                    ab, self.kl, self.ku, self.pivot_tolerance)))
        return _Scaled(self.scale, _Permuted(self, Factorization(
            self._permuted_csc(values, extra), "NATURAL", self.pivot_tolerance)))

    def solve(self, values: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Solve ``A x = b`` once for the matrix with entries ``values``: what :meth:`factor`
        then ``solve`` give, in one call (the compiled LU of :mod:`mbd3d.numerics.compiled.dense`,
        dense or in band storage).

        Raises
        ------
        SingularMatrix
        """
        d = self.scale
        if self.layout == "dense":
            x, regular = solve_pattern(self.rows, self.cols, self.entry_scale, d, values, b,
                                       self.pivot_tolerance)
            if not regular:
                raise SingularMatrix("smallest pivot below tolerance")
            return x
        if self.layout == "banded":
            x, regular = solve_banded_pattern(self.flat, self.kl, self.ku, self.perm,
                                              self.entry_scale, d, values, b,
                                              self.pivot_tolerance)
            if not regular:
                raise SingularMatrix("smallest pivot below tolerance")
            return x
        return self.factor(values).solve(b)

    def _scatter(self, values: np.ndarray, n_rows: int) -> np.ndarray:
        """(n_rows, size) array in Fortran order (as LAPACK takes it) holding ``values`` at
        the pattern's flat positions, zero elsewhere."""
        buffer = np.zeros(n_rows * self.size)
        buffer[self.flat] = values
        return buffer.reshape((n_rows, self.size), order="F")

    def _add_to_band(self, ab: np.ndarray, extra) -> bool:
        """Add ``extra`` into band storage; False (nothing added) if it reaches outside."""
        extra = sp.coo_matrix(extra)
        prow, pcol = self.inverse[extra.row], self.inverse[extra.col]
        offset = prow - pcol
        if np.any(offset > self.kl) or np.any(-offset > self.ku):
            return False
        np.add.at(ab, (self.kl + self.ku + offset, pcol), extra.data)
        return True


class _Scaled:
    """Factors of ``D A D`` (``D = diag(scale)``), solving with ``A``."""

    def __init__(self, scale: np.ndarray, lu):
        self.scale, self.lu = scale, lu

    @property
    def log_abs_determinant(self) -> float:
        return self.lu.log_abs_determinant - 2.0 * float(np.sum(np.log(self.scale)))

    def solve(self, b: np.ndarray, transpose: bool = False) -> np.ndarray:
        # D A D is symmetric in its scaling: A x = b is (D A D)(D^-1 x) = D b, either way round
        return self.scale * self.lu.solve(self.scale * b, transpose)


class _Permuted:
    """Factors of a permuted matrix, solving in the original order."""

    def __init__(self, pattern: _FixedPattern, lu):
        self.perm, self.lu = pattern.perm, lu

    @property
    def log_abs_determinant(self) -> float:
        return self.lu.log_abs_determinant

    def solve(self, b: np.ndarray, transpose: bool = False) -> np.ndarray:
        x = np.empty_like(b)
        x[self.perm] = self.lu.solve(b[self.perm], transpose)
        return x


class AugmentedPattern(_FixedPattern):
    """Where the mass blocks and the Jacobian values go in ``[M Cq^T; Cq 0]``, fixed per model.

    A fourth layout, "range", is that of a banded model whose constraint rows, ordered by
    reverse Cuthill-McKee, make ``Cq M^-1 Cq^T`` a narrow band (:class:`RangeSpacePattern`):
    :meth:`factor`, :meth:`solve` and the compiled core then solve through it
    (:class:`RangeSpaceFactorization`).
    """

    def __init__(self, model):
        n, m = model.n_coordinates, model.n_constraints
        block_rows, block_cols = self.mass_block_entries(model)
        jr, jc = model._jac_rows, model._jac_cols
        self._lay_out(np.concatenate([block_rows, n + jr, jc]),
                      np.concatenate([block_cols, jc, n + jr]), n + m, model.sparse,
                      augmented_scaling(model))
        self.range_space = None
        if self.layout == "banded" and m:
            pattern = RangeSpacePattern(model.n_bodies, model.n_coords_per_body, m, jr, jc)
            if pattern.bandwidth ** 2 <= RANGE_SPACE_WORK_LIMIT:
                self.range_space = pattern
                self.layout = "range"
                self.blocks_size = model.n_bodies * model.n_coords_per_body ** 2
                self.block_shape = (model.n_bodies, model.n_coords_per_body,
                                    model.n_coords_per_body)

    def factor(self, values: np.ndarray, extra=None):
        if self.layout != "range" or extra is not None:
            return super().factor(values, extra)
        return RangeSpaceFactorization(self.range_space, values[:self.blocks_size].reshape(
            self.block_shape), values[self.blocks_size:self.blocks_size + self.range_space.nnz],
            self.pivot_tolerance)

    def solve(self, values: np.ndarray, b: np.ndarray) -> np.ndarray:
        if self.layout != "range":
            return super().solve(values, b)
        return self.factor(values).solve(b)


class RangeSpaceFactorization:
    """Factors of ``[M Cq^T; Cq 0]`` through ``S = Cq M^-1 Cq^T`` (see
    :mod:`mbd3d.numerics.compiled.range_space`), reusable for several right-hand sides.

    Raises
    ------
    SingularMatrix
        When a pivot of ``S`` falls below ``pivot_tolerance`` times its diagonal entry.
    """

    sparse = False

    def __init__(self, pattern: "RangeSpacePattern", blocks: np.ndarray, jac_data: np.ndarray,
                 pivot_tolerance: float = PIVOT_TOLERANCE):
        self.pattern = pattern
        self.nc = blocks.shape[1]
        m = len(pattern.row_position)
        self.blocks = np.array(blocks, dtype=float)  # becomes the factors
        self.jacobian = np.empty(pattern.body_start[-1] * self.nc)
        self.band = np.empty((pattern.bandwidth + 1) * m)
        if not range_space_factor(self.nc, self.blocks, np.ascontiguousarray(jac_data,
                                                                             dtype=float),
                                  pattern.slot, pattern.body_start, pattern.positions,
                                  pattern.bandwidth, pivot_tolerance, self.jacobian, self.band,
                                  np.empty(m)):
            raise SingularMatrix("a pivot of Cq M^-1 Cq^T below tolerance")

    def solve(self, b: np.ndarray, transpose: bool = False) -> np.ndarray:
        """The solution of ``A x = b`` (``A`` is symmetric: ``transpose`` changes nothing)."""
        pattern = self.pattern
        x = np.empty(len(b))
        range_space_solve_factored(self.nc, self.blocks, pattern.body_start, pattern.positions,
                                   pattern.row_position, pattern.bandwidth,
                                   np.ascontiguousarray(b, dtype=float), self.jacobian,
                                   self.band, np.empty(len(pattern.row_position)),
                                   np.empty(self.blocks.shape[0] * self.nc), x)
        return x


class RangeSpacePattern:
    """The structure of ``S = Cq M^-1 Cq^T`` for :mod:`mbd3d.numerics.compiled.range_space`.

    Two constraint rows are coupled in ``S`` when they act on a common body. The rows are
    ordered by reverse Cuthill-McKee on that coupling, which makes ``S`` of a chain a band of
    half-width ``bandwidth`` (2 to 5 rows for a chain of revolutes or ball joints) whatever
    its length.

    Attributes
    ----------
    rows, cols : ndarray of int
        The Jacobian's entries (the model's CSR order).
    slot : ndarray of int
        Where each entry goes in the per-body copies of the rows: body ``b``'s rows are rows
        ``body_start[b]`` to ``body_start[b + 1]`` of an array of ``n_coords_per_body``
        columns (flattened).
    positions : ndarray of int
        The position in ``S``'s ordering of each of those rows, increasing within a body.
    row_position : ndarray of int
        The position of each constraint row.
    """

    def __init__(self, n_bodies: int, n_coords_per_body: int, n_rows: int, rows: np.ndarray,
                 cols: np.ndarray):
        nc = n_coords_per_body
        self.rows = np.ascontiguousarray(rows, dtype=np.int64)
        self.cols = np.ascontiguousarray(cols, dtype=np.int64)
        self.nnz = len(rows)
        body = self.cols // nc
        # one (body, row) pair per row acting on a body, sorted by body then row
        pairs, pair_of_entry = np.unique(body * n_rows + self.rows, return_inverse=True)
        pair_body, pair_row = pairs // n_rows, pairs % n_rows
        self.body_start = np.searchsorted(pair_body, np.arange(n_bodies + 1)).astype(np.int64)
        # rows coupled through a body: every pair of rows of one body
        counts = np.diff(self.body_start)
        sizes = counts * counts
        start = np.repeat(self.body_start[:-1], sizes)
        offset = np.arange(int(sizes.sum())) - np.repeat(np.cumsum(sizes) - sizes, sizes)
        width = np.repeat(counts, sizes)
        first, second = start + offset // width, start + offset % width
        coupling = sp.csr_matrix((np.ones(len(first)), (pair_row[first], pair_row[second])),
                                 shape=(n_rows, n_rows))
        order = reverse_cuthill_mckee(coupling, symmetric_mode=True).astype(np.int64)
        self.row_position = np.empty(n_rows, dtype=np.int64)
        self.row_position[order] = np.arange(n_rows)
        position = self.row_position[pair_row]
        offsets = position[first] - position[second]
        self.bandwidth = int(np.max(np.abs(offsets), initial=0))
        # each body's rows in the order of S: the compiled loops then visit S's lower
        # triangle without tests
        order = np.lexsort((position, pair_body))
        rank = np.empty_like(order)
        rank[order] = np.arange(len(order))
        self.positions = position[order]
        self.slot = (rank[pair_of_entry.ravel()] * nc + self.cols % nc).astype(np.int64)


class PenaltyPattern(_FixedPattern):
    """Where the mass blocks and the products of Jacobian values go in ``a M + p Cq^T Cq``,
    fixed per model, so that the iteration matrix of the implicit integrator is filled by one
    pass over them (:func:`mbd3d.numerics.compiled.generalized_alpha.iteration_values_into`)
    instead of sparse matrix products.

    ``Cq^T Cq`` couples the coordinates of every pair of Jacobian entries in one row: with the
    entries sorted by row (CSR order) those pairs are enumerated once, here.

    The matrix is symmetric positive definite (positive masses), and its pivots span the
    penalty ratio times the spread of the bodies' masses and inertias by design: only pivots
    at the rounding level mean singular.
    """

    pivot_tolerance = 64 * np.finfo(float).eps

    def __init__(self, model):
        n = model.n_coordinates
        block_rows, block_cols = self.mass_block_entries(model)
        rows, cols, indptr = model._jac_rows, model._jac_cols, model._jac_indptr
        per_row = np.diff(indptr)[rows]  # entries in the row of each entry
        self.first = np.repeat(np.arange(len(rows)), per_row)
        start = np.repeat(np.cumsum(per_row) - per_row, per_row)
        self.second = indptr[rows[self.first]] + np.arange(len(self.first)) - start
        self.first_rows = rows[self.first]  # the constraint row of each product
        all_rows = np.concatenate([block_rows, cols[self.first]])
        all_cols = np.concatenate([block_cols, cols[self.second]])
        linear, self.target = np.unique(all_rows * n + all_cols, return_inverse=True)
        self._lay_out(linear // n, linear % n, n, model.sparse,
                      augmented_scaling(model)[:n])


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
    """The entries of ``[M Cq^T; Cq 0]`` in the order of :class:`AugmentedPattern`."""
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
