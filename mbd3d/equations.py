"""Terms of the equations of motion ``M qdd + Cq^T lam = Qe + Qv``: mass matrix, applied and
quadratic velocity forces, energies."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from mbd3d.body import Frames, rotate_rows
from mbd3d.constraints import frames

__all__ = ["mass_matrix", "mass_times", "generalized_forces", "kinetic_energy",
           "potential_energy"]


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
