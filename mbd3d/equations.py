"""Terms of the equations of motion ``M qdd + Cq^T lam = Qe + Qv``: mass matrix, applied and
quadratic velocity forces, energies."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from mbd3d.body import Frames, rotate_rows
from mbd3d.compiled import accelerations as kernel
from mbd3d.constraints import driver_values, frames, motion_phases
from mbd3d.linalg import SingularMatrix

__all__ = ["mass_matrix", "mass_times", "generalized_forces", "kinetic_energy",
           "potential_energy", "augmented_accelerations"]


def mass_matrix(model, fr: Frames, sparse: bool | None = None):
    """Mass matrix ``M`` (n, n): block diagonal, one block per body. CSR when sparse."""
    blocks = model.body_type.mass_blocks(fr, model.mass, model.inertia)
    nb, nc = blocks.shape[0], blocks.shape[1]
    if model.sparse if sparse is None else sparse:
        return sp.bsr_matrix((blocks, np.arange(nb), np.arange(nb + 1)),
                             shape=(nb * nc, nb * nc)).tocsr()
    M = np.zeros((nb * nc, nb * nc))
    idx = np.arange(nb)[:, None] * nc + np.arange(nc)[None, :]
    M[idx[:, :, None], idx[:, None, :]] = blocks
    return M


def mass_times(blocks: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``M x`` (n,) from the per-body mass blocks (n_bodies, n_coords, n_coords), without
    assembling ``M``."""
    return rotate_rows(blocks, x.reshape(blocks.shape[:2])).ravel()


def generalized_forces(model, t: float, fr: Frames) -> np.ndarray:
    """``Qe + Qv``: gravity, force elements and the quadratic velocity vector, shape (n,)."""
    nb = model.n_bodies
    Q = model._weight.copy()
    if not model.body_type.constant_mass:
        Q[:nb] += model.body_type.quadratic_velocity(fr, model.mass, model.inertia)
    for group in model.force_groups:
        group.apply(model, t, fr, Q)
    return Q[:nb].ravel()


def kinetic_energy(model, q: np.ndarray, qd: np.ndarray, charts: np.ndarray | None = None
                   ) -> float:
    """``T = 1/2 qd^T M qd`` [J] (``charts``: see :func:`mbd3d.constraints.frames`)."""
    fr = frames(model, q, qd, charts)
    blocks = model.body_type.mass_blocks(fr, model.mass, model.inertia)
    v = np.reshape(qd, blocks.shape[:2])
    return float(0.5 * np.einsum("ki,kij,kj->", v, blocks, v))


def potential_energy(model, q: np.ndarray, charts: np.ndarray | None = None) -> float:
    """Potential energy of gravity (zero at the global origin) and of springs [J]."""
    nb = model.n_bodies
    R = np.reshape(q, (nb, model.n_coords_per_body))[:, :model.dim]
    V = -float(np.sum(model.mass * (R @ model.gravity)))
    fr = None
    for group in model.force_groups:
        if fr is None:
            fr = frames(model, q, np.zeros_like(q), charts)
        V += group.potential(model, fr)
    return V


class _Core:
    """A model's arrays in the form the compiled augmented solve takes them, fixed at build."""

    def __init__(self, model):
        table, pattern = model.row_table, model._augmented_pattern
        nb = model.n_bodies
        self.spatial = model.dim == 3
        self.layout = {"dense": kernel.DENSE, "banded": kernel.BANDED,
                       "sparse": kernel.SPARSE}[pattern.layout]
        banded = pattern.layout == "banded"
        self.no_forces = np.zeros(model.n_coordinates)
        self.no_drivers = np.zeros(0)
        # writable contiguous copies: the compiled functions are typed (and cached) for those
        inertia = np.array(model.inertia)
        if not self.spatial:
            from mbd3d.planar.body import inertia_tensors
            inertia = inertia_tensors(inertia)
        self.before = (np.array(model.mass), inertia,
                       np.array(model._weight[:nb].ravel()), table.code, table.bi, table.bj,
                       table.first_row, table.slots, table.coordinate, table.motion,
                       table.vector_bodies, np.ascontiguousarray(table.vector_local),
                       table.n_rows)
        self.driver_rows = np.array(model.driver_rows, dtype=np.int64)
        self.after = (model._jac_destination, len(model._jac_take), self.layout,
                      np.array(pattern.rows, dtype=np.int64),
                      np.array(pattern.cols, dtype=np.int64),
                      np.array(pattern.flat if banded else [], dtype=np.int64),
                      pattern.kl if banded else 0, pattern.ku if banded else 0,
                      np.array(pattern.perm if banded else [], dtype=np.int64),
                      np.array(pattern.entry_scale), np.array(pattern.scale),
                      float(pattern.pivot_tolerance))
        self._model = model

    def system(self, redundant: bool) -> tuple:
        """The model as the compiled integrator loop takes it (see
        :mod:`mbd3d.compiled.integration`); ``redundant``: accelerations from Python's
        augmented-Lagrangian solve."""
        model = self._model
        python_parts = bool(model.force_groups or len(model.driver_rows)
                            or model.rotation_motions)
        return (model.dim == 3, model.n_coordinates, bool(redundant), python_parts,
                self.layout != kernel.SPARSE,
                self.before, self.driver_rows, self.after, np.array(model.c0),
                np.array(model.row_scale, dtype=float),
                np.array(model._jac_rows, dtype=np.int64),
                np.array(model._jac_cols, dtype=np.int64), self.no_forces, np.zeros((3, 0)),
                np.zeros((0, 3)))


def augmented_accelerations(model, t: float, q: np.ndarray, qd: np.ndarray,
                            charts: np.ndarray | None = None) -> np.ndarray | None:
    """``(qdd, lam)`` stacked (n + m,) from the augmented equations at ``(t, q, qd)``, or None
    when the state is not finite.

    Everything but the force elements, the drivers' motions (Python objects) and the SuperLU
    solve of a large model with a wide band is one compiled call (:mod:`mbd3d.compiled.accelerations`): the
    one place this system is assembled and solved.

    Raises
    ------
    SingularMatrix
        When the matrix is singular (dependent constraint rows).
    """
    core = model._core
    extra = core.no_forces
    if model.force_groups:
        fr = frames(model, q, qd, charts)
        Q = np.zeros((model.n_bodies + 1, model.n_coords_per_body))
        for group in model.force_groups:
            group.apply(model, t, fr, Q)
        extra = Q[:model.n_bodies].ravel()
    phi = motion_phases(model, t)
    f2 = (np.ascontiguousarray(driver_values(model, t)[2]) if len(core.driver_rows)
          else core.no_drivers)
    q = np.asarray(q, dtype=float)
    qd = np.asarray(qd, dtype=float)
    if core.spatial:
        x, status, values, rhs = kernel.spatial_accelerations(
            q, qd, model.charts0 if charts is None else charts, extra, *core.before, phi,
            core.driver_rows, f2, *core.after)
    else:
        x, status, values, rhs = kernel.planar_accelerations(
            q, qd, extra, *core.before, phi, core.driver_rows, f2, *core.after)
    if status == kernel.NOT_FINITE:
        return None
    if status == kernel.SINGULAR:
        raise SingularMatrix("smallest pivot below tolerance")
    return x if core.layout != kernel.SPARSE else model._augmented_pattern.solve(values, rhs)
