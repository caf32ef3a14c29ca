"""Matrices whose sparsity is fixed when a model is built: the augmented matrix
(:class:`AugmentedPattern`, dense, banded or SuperLU, or the range-space solve of
:class:`RangeSpacePattern` for chains) and generalized-alpha's iteration matrix
(:class:`PenaltyPattern`). Each lays its entries out once and is refilled and factored at every
evaluation by the compiled kernels of :mod:`mbd3d.numerics.compiled.dense` and
:mod:`mbd3d.numerics.compiled.range_space`; the scaling and singularity rules are those of
:mod:`mbd3d.numerics.linalg`.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import reverse_cuthill_mckee

from mbd3d.numerics.compiled.dense import penalty_scale, solve_banded_pattern, solve_pattern
from mbd3d.numerics.compiled.range_space import range_space_factor, range_space_solve_factored
from mbd3d.numerics.linalg import (PIVOT_TOLERANCE, BandedFactorization, Factorization,
                                   SingularMatrix, _power_of_two, augmented_scaling)

__all__ = ["AugmentedPattern", "RangeSpacePattern", "RangeSpaceFactorization", "PenaltyPattern",
           "penalty_scale", "jacobian_layout", "BANDED_WORK_LIMIT", "RANGE_SPACE_WORK_LIMIT"]


#: banded LU is used for a sparse pattern when ``kl (kl + ku)``, its work per unknown, is at
#: most this: a chain's augmented matrix has ``kl, ku`` of 5 to 12 whatever its length, where
#: SuperLU's ordering and bookkeeping per call cost several times the arithmetic
BANDED_WORK_LIMIT = 4096
#: the range-space solve (:class:`RangeSpacePattern`) is used for a banded pattern when
#: ``k^2``, its work per constraint row for ``S``'s half-bandwidth ``k``, is at most this
RANGE_SPACE_WORK_LIMIT = 1024


def jacobian_layout(rows: np.ndarray, cols: np.ndarray, n: int
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """How the square Jacobian (n, n) with entries at ``(rows, cols)`` is factored by the
    compiled kinematics (:mod:`mbd3d.numerics.compiled.kinematics`): ``(row_at, col_at, flat,
    (kl, ku))``, each row's and column's place, each entry's place in LAPACK's band storage
    and the bandwidths; ``kl`` is -1 where the matrix is best factored dense.

    The columns are tried in their own order, in reverse Cuthill-McKee order of the columns
    that share a row, and each reversed; the rows are then sorted by the last and first
    places of their columns, which puts a chain's joint rows beside the columns of the
    bodies they join. The order whose band LU costs least, ``kl (kl + ku)`` a column, is
    taken where that is below a twelfth of the dense LU's ``n^2 / 3`` (and within
    :data:`BANDED_WORK_LIMIT`)."""
    rows, cols = np.asarray(rows, dtype=np.int64), np.asarray(cols, dtype=np.int64)
    shared = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    shared = (shared.T @ shared).tocsr()
    ordering = np.asarray(reverse_cuthill_mckee(shared, symmetric_mode=True), dtype=np.int64)
    best = None
    for order in (np.arange(n), ordering, np.arange(n)[::-1], ordering[::-1]):
        col_at = np.empty(n, dtype=np.int64)
        col_at[order] = np.arange(n)
        last, first = np.full(n, -1), np.full(n, n)
        np.maximum.at(last, rows, col_at[cols])
        np.minimum.at(first, rows, col_at[cols])
        row_at = np.empty(n, dtype=np.int64)
        row_at[np.lexsort((first, last))] = np.arange(n)
        reach = row_at[rows] - col_at[cols]
        kl, ku = int(max(reach.max(initial=0), 0)), int(max(-reach.min(initial=0), 0))
        if best is None or kl * (kl + ku) < best[2] * (best[2] + best[3]):
            best = (row_at, col_at, kl, ku)
    row_at, col_at, kl, ku = best
    if n == 0 or 12 * kl * (kl + ku) > n * n or kl * (kl + ku) > BANDED_WORK_LIMIT:
        return (np.arange(n, dtype=np.int64), np.arange(n, dtype=np.int64),
                np.zeros(0, dtype=np.int64), np.array([-1, -1], dtype=np.int64))
    flat = (kl + ku + row_at[rows] - col_at[cols]) + col_at[cols] * (2 * kl + ku + 1)
    return row_at, col_at, flat.astype(np.int64), np.array([kl, ku], dtype=np.int64)


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
                 scale: np.ndarray, coupled: tuple | None = None) -> None:
        """Choose the layout of the entries ``(rows, cols)``; ``coupled``: more ``(rows,
        cols)`` whose values are not among them but added to the matrix later (the applied
        forces' tangent), which the ordering and the band take in."""
        self.rows, self.cols, self.size = rows.astype(np.int64), cols.astype(np.int64), size
        # the matrix is factored as D A D with the model's fixed powers of two D = diag(scale)
        # (see the module doc); entry_scale multiplies the values in the pattern's order
        self.scale = _power_of_two(scale)
        self.entry_scale = self.scale[rows] * self.scale[cols]
        if not sparse:
            self.layout = "dense"
            self.flat = rows + cols * size  # Fortran order, as LAPACK takes it
            return
        every_row, every_col = rows, cols
        if coupled is not None:
            every_row = np.concatenate([rows, coupled[0]])
            every_col = np.concatenate([cols, coupled[1]])
        structure = sp.csr_matrix((np.ones(len(every_row)), (every_row, every_col)),
                                  shape=(size, size))
        self.perm = reverse_cuthill_mckee(structure, symmetric_mode=True).astype(np.int64)
        inverse = np.empty_like(self.perm)
        inverse[self.perm] = np.arange(size)
        self.inverse = inverse
        prow, pcol = inverse[rows], inverse[cols]
        reach = inverse[every_row] - inverse[every_col]  # the band holds the coupled too
        # CSC structure of the permuted matrix: SuperLU's input, also for a banded pattern
        # whose matrix gets entries outside the band (see factor)
        self.order = np.lexsort((prow, pcol))
        self.indices = prow[self.order].astype(np.int32)
        counts = np.bincount(pcol, minlength=size)
        self.indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
        kl = int(np.max(reach, initial=0))
        ku = int(np.max(-reach, initial=0))
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


def force_couplings(model) -> tuple[np.ndarray, np.ndarray]:
    """The coordinates ``(rows, cols)`` that the force elements of ``model`` couple across
    bodies (a spring, a contact, a stop between two bodies: every coordinate of each with
    every one of the other), where their tangent enters generalized-alpha's iteration
    matrix. A contact group's pairs change as its bodies move: it couples none here (its
    tangent takes a dense matrix)."""
    nc, pairs = model.n_coords_per_body, set()
    for element in model.forces:
        if getattr(element, "is_group", False):
            continue
        bodies = sorted({body.index for _, body in element.bodies() if not body.is_ground})
        pairs.update((a, b) for a in bodies for b in bodies if a != b)
    if not pairs:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    a, b = np.array(sorted(pairs)).T
    block = np.arange(nc)
    shape = (len(a), nc, nc)
    rows = np.broadcast_to(a[:, None, None] * nc + block[None, :, None], shape)
    cols = np.broadcast_to(b[:, None, None] * nc + block[None, None, :], shape)
    return rows.ravel().astype(np.int64), cols.ravel().astype(np.int64)


class PenaltyPattern(_FixedPattern):
    """Where the mass blocks and the products of Jacobian values go in ``a M + p Cq^T Cq``,
    fixed per model, so that the iteration matrix of the implicit integrator is filled by one
    pass over them (:func:`mbd3d.numerics.compiled.generalized_alpha.iteration_values_into`)
    instead of sparse matrix products.

    ``Cq^T Cq`` couples the coordinates of every pair of Jacobian entries in one row: with the
    entries sorted by row (CSR order) those pairs are enumerated once, here.

    The matrix is symmetric positive definite (positive masses), and its pivots span the
    penalty ratio times the spread of the bodies' masses and inertias by design: only pivots
    at the rounding level mean singular, and the compiled factorization tests each against
    its own column (:func:`mbd3d.numerics.compiled.generalized_alpha.factor_into`).
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
                      augmented_scaling(model)[:n], force_couplings(model))
