"""How the disturbances of a linearisation are measured (see :mod:`.linearization`): the
physical displacements ``dx`` (per body: the centre's ``dR`` [m] and a small rotation
``theta`` [rad]) and velocities ``w`` (``R_dot`` and an angular velocity), from which the
state's independent components are chosen.

- :class:`BodyAxes` (the default): rotations and angular velocities in each body's own axes,
  which turn with the reference motion (co-moving): ``A = A_ref exp(theta~)``, ``w = (R_dot,
  omega_bar)``, and ``theta' = d omega_bar - omega_bar_ref x theta``. The matrices are
  constant about a motion steady in the bodies' axes (and forces steady there).
- :class:`TurningFrame`: every vector in the axes of a frame turning at ``Omega`` (global
  axes, aligned with them at the reference): ``A = exp(theta~) A_ref``, ``w = (R_dot,
  omega)`` in global axes, ``theta' = d omega + omega_ref x theta``, and each vector's rate in
  the frame is its global rate less ``Omega x`` itself. The matrices are constant about a
  motion steady in that frame (a symmetric top spinning about its axis while it precesses at
  ``Omega``; a disc rolling straight on, ``Omega = 0``), which the bodies' own axes, turning
  with the spin, are not.

Planar models measure angles as they are (the frame does not matter).
"""

from __future__ import annotations

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.model import constraints

__all__ = ["BodyAxes", "TurningFrame", "measure"]


def _skew(x: np.ndarray) -> np.ndarray:
    """``x~`` (3, 3), with ``x~ y = x cross y``."""
    return np.array([[0.0, -x[2], x[1]], [x[2], 0.0, -x[0]], [-x[1], x[0], 0.0]])


class BodyAxes:
    """Co-moving measures (see the module); planar: the coordinates themselves."""

    def __init__(self, model, q: np.ndarray, qd: np.ndarray):
        self.model = model
        n = model.n_coordinates
        # a rotation about a body axis is 2 g at g = 0 (the reference's chart)
        unit = np.ones(n)
        if model.dim == 3:
            unit.reshape(-1, 6)[:, 3:] = 2.0
        #: dq = P dx, and dx = P_inv (q - q0) to first order
        self.P, self.P_inv = np.diag(1.0 / unit), np.diag(unit)
        self.w0, _ = self.rates(q, qd, np.zeros(n))

    def velocity_map(self, q: np.ndarray) -> np.ndarray:
        """``E`` (n, n) with ``w = E qd`` at ``q``."""
        body_type = self.model.body_type
        return np.column_stack([body_type.velocities(q, e)
                                for e in np.eye(self.model.n_coordinates)])

    def rates(self, q, qd, qdd) -> tuple[np.ndarray, np.ndarray]:
        """``(w, w_dot)`` at a state."""
        body_type = self.model.body_type
        return body_type.velocities(q, qd), body_type.velocity_derivative(q, qd, qdd)

    def position_rate(self, w: np.ndarray, dx: np.ndarray) -> np.ndarray:
        """``dx'`` at a state of velocities ``w`` displaced ``dx`` from the reference."""
        rate = w - self.w0
        if self.model.dim == 3:
            rotation = rate.reshape(-1, 6)[:, 3:]
            rotation -= np.cross(self.w0.reshape(-1, 6)[:, 3:], dx.reshape(-1, 6)[:, 3:])
        return rate

    def turning(self, basis: np.ndarray) -> np.ndarray | None:
        """What the frame's own turning adds to the rates of the measures ``basis`` (n, k)
        describes; None: nothing."""
        return None


class TurningFrame(BodyAxes):
    """Measures in a frame turning at ``rate`` [rad/s, global axes] (see the module)."""

    def __init__(self, model, q: np.ndarray, qd: np.ndarray, charts, rate: np.ndarray):
        self.rate = rate
        self._A = lambda q_: constraints.frames(model, q_, None, charts).A[:model.n_bodies]
        super().__init__(model, q, qd)
        nb = model.n_bodies
        P = np.zeros((nb, 6, 6))
        P[:, :3, :3] = np.eye(3)
        P[:, 3:, 3:] = 0.5 * np.swapaxes(charts[:nb], 1, 2)  # g = A_ref^T theta / 2
        self.P = _blocks(P)
        self.P_inv = np.linalg.inv(self.P)

    def velocity_map(self, q: np.ndarray) -> np.ndarray:
        return self._global(self._A(q), super().velocity_map(q))

    def rates(self, q, qd, qdd) -> tuple[np.ndarray, np.ndarray]:
        w, w_dot = super().rates(q, qd, qdd)
        A = self._A(q)
        # omega = A omega_bar, and its rate A omega_bar_dot (omega_bar x omega_bar = 0)
        return self._global(A, w[:, None])[:, 0], self._global(A, w_dot[:, None])[:, 0]

    def position_rate(self, w: np.ndarray, dx: np.ndarray) -> np.ndarray:
        rate = w - self.w0
        rotation = rate.reshape(-1, 6)[:, 3:]
        rotation += np.cross(self.w0.reshape(-1, 6)[:, 3:], dx.reshape(-1, 6)[:, 3:])
        return rate

    def turning(self, basis: np.ndarray) -> np.ndarray:
        K = np.zeros((self.model.n_bodies, 6, 6))
        K[:, :3, :3] = K[:, 3:, 3:] = -_skew(self.rate)
        return _blocks(K) @ basis

    def _global(self, A: np.ndarray, body: np.ndarray) -> np.ndarray:
        """Rows of body-axes angular velocities (every body's rows 3:6) turned to global
        axes by the bodies' attitudes ``A``; (n, m)."""
        out = body.reshape(self.model.n_bodies, 6, -1).copy()
        out[:, 3:] = np.einsum("bij,bjm->bim", A, out[:, 3:])
        return out.reshape(body.shape)


def _blocks(blocks: np.ndarray) -> np.ndarray:
    """The block-diagonal matrix of ``blocks`` (b, 6, 6)."""
    b = blocks.shape[0]
    out = np.zeros((6 * b, 6 * b))
    for k in range(b):
        out[6 * k:6 * k + 6, 6 * k:6 * k + 6] = blocks[k]
    return out


def measure(model, q, qd, charts, frame_rate, what: str) -> BodyAxes:
    """The measures of a linearisation: co-moving, or in the frame turning at
    ``frame_rate`` (spatial models)."""
    if frame_rate is None:
        return BodyAxes(model, q, qd)
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
    return TurningFrame(model, q, qd, charts, rate)
