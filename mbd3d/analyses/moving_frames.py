"""How the disturbances of a linearisation are measured in space (see
:mod:`.linearization`): a body's small rotation in its own axes, which turn with the
reference motion (co-moving), or in a frame that turns at a constant rate.

Both enter the state matrix as ``x_F = T(t) x`` with ``T(0) = I`` at the reference, adding
``dT/dt`` to ``A``; ``basis`` (n, k) maps the state's displacements to every coordinate's
(rotations [rad]) and ``independent`` selects the state's coordinates.
"""

from __future__ import annotations

import numpy as np

from mbd3d.errors import ModelError

__all__ = ["co_moving_turning", "frame_turning"]


def co_moving_turning(model, v0: np.ndarray, basis: np.ndarray, independent: np.ndarray
                      ) -> np.ndarray:
    """``W`` (k, k) with ``theta' = d omega_bar - W theta``: a rotation in body axes, which
    turn at the reference's ``omega_bar`` (``v0``'s rotation rates), changes by
    ``-omega_bar x theta`` even while the body's angular velocity does not."""
    k = basis.shape[1]
    rotations = basis.reshape(model.n_bodies, 6, k)[:, 3:]  # d theta / d p
    omega = v0.reshape(-1, 6)[:, 3:, None]
    turning = np.zeros((model.n_bodies, 6, k))
    turning[:, 3:] = np.cross(omega, rotations, axisa=1, axisb=1, axisc=1)
    return turning.reshape(-1, k)[independent]


def frame_turning(model, frame_rate, charts: np.ndarray, v0: np.ndarray, basis: np.ndarray,
                  independent: np.ndarray, what: str) -> np.ndarray:
    """``W`` (k, k): how disturbances measured in a frame turning at ``frame_rate`` (global
    axes, aligned with each body's reference axes at the reference) change against
    co-moving ones: ``x_F = T(t) x`` with ``T(0) = I``, so ``A_F = A + diag(W, W)``.

    A body's position and velocity disturbances are global vectors, which the frame turns
    back: ``-Omega~``. Its rotation and angular velocity disturbances are in its own axes
    ``A_b``, which turn at ``omega_bar`` while the frame turns at ``Omega_bar = A_b^T
    Omega``: ``(omega_bar - Omega_bar)~`` (``d/dt (A_b^T A_F) = (Omega_bar - omega_bar)~``
    at the reference, transposed). The matrices are constant along a motion that is steady
    in the frame: every body's attitude turns at ``Omega`` about axes of symmetry of its
    inertia and of the applied forces (a symmetric top spinning about its axis while it
    precesses at ``Omega`` under gravity along ``Omega``). ``basis`` maps the state's
    displacements to every coordinate's (rotations [rad])."""
    if model.dim != 3:
        raise ModelError(f"{what}: frame_rate is for spatial models (a planar model's angles "
                         "do not depend on the frame)")
    try:
        rate = np.asarray(frame_rate, dtype=float).reshape(3)
    except (TypeError, ValueError):
        rate = np.full(3, np.nan)
    if not np.all(np.isfinite(rate)):
        raise ModelError(f"{what}: frame_rate must be 3 finite numbers [rad/s], global axes, "
                         f"got {frame_rate!r}")
    nb = model.n_bodies
    bar = np.einsum("bji,j->bi", charts[:nb], rate)  # Omega in each body's axes
    K = np.zeros((nb, 6, 6))
    K[:, :3, :3] = -_skew(rate)
    K[:, 3:, 3:] = _skew(v0.reshape(nb, 6)[:, 3:] - bar)
    return (K @ basis.reshape(nb, 6, -1)).reshape(6 * nb, -1)[independent]


def _skew(x: np.ndarray) -> np.ndarray:
    """``x~`` (..., 3, 3), with ``x~ y = x cross y``."""
    out = np.zeros(np.shape(x)[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2], out[..., 1, 2] = -x[..., 2], x[..., 1], -x[..., 0]
    return out - np.swapaxes(out, -1, -2)
