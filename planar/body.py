"""The planar rigid body: ``q = (Rx, Ry, theta)``, ``A(theta)`` the 2x2 rotation.

Formulas (Nikravesh, *Planar Multibody Dynamics*; Shabana, *Computational Dynamics*, planar
kinematics): with ``s = A v`` and ``s_perp = (-s_y, s_x) = dA/dtheta v``,

- point ``r = R + s``: ``dr/dq = [I2, s_perp]``, ``rdot = Rdot + thetadot s_perp``;
- velocity-dependent part of the acceleration of ``s``: ``-thetadot^2 s``;
- a body vector ``a = A v`` behaves the same without ``R``.

The mass matrix is ``diag(m, m, J)`` and constant; there is no quadratic velocity vector.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mbd3d.model.body import BodyType, Frames
from mbd3d.numerics.compiled.bodies import planar_frames, planar_mass_blocks
from mbd3d.numerics.checks import finite_scalar, finite_vector
from mbd3d.errors import ModelError


def inertia_tensors(inertia: np.ndarray) -> np.ndarray:
    """Planar inertias about the normal (b,) as the tensors ``diag(0, 0, J)`` (b, 3, 3) the
    compiled core takes."""
    tensors = np.zeros((len(inertia), 3, 3))
    tensors[:, 2, 2] = inertia
    return tensors


class PlanarBody(BodyType):
    """Kinematics of planar rigid bodies, batched over bodies (see :class:`mbd3d.model.body.BodyType`)."""

    dim = 2
    n_coords = 3
    coordinate_names = ("x", "y", "theta")
    name = "planar"
    constant_mass = True

    def check_inertia(self, inertia: Any, body: str) -> float:
        value = finite_scalar(inertia, f"body '{body}': inertia")
        if not value > 0.0:
            raise ModelError(f"body '{body}': inertia must be positive [kg m^2], got {value}; "
                             "a planar body needs its centroidal moment of inertia about the normal")
        return value

    def initial_state(self, body: str, position: Any, orientation: Any
                      ) -> tuple[np.ndarray, None]:
        pos = finite_vector(position, 2, f"body '{body}': position")
        angle = finite_scalar(0.0 if orientation is None else orientation, f"body '{body}': angle")
        return np.array([pos[0], pos[1], angle]), None

    def initial_rates(self, body: str, velocity: Any, angular_velocity: Any, q0: np.ndarray,
                      chart: None) -> np.ndarray:
        vel = finite_vector((0.0, 0.0) if velocity is None else velocity, 2,
                             f"body '{body}': velocity")
        omega = finite_scalar(0.0 if angular_velocity is None else angular_velocity,
                               f"body '{body}': angular_velocity")
        return np.array([vel[0], vel[1], omega])

    def frames(self, Q: np.ndarray, Qd: np.ndarray | None = None,
               charts: np.ndarray | None = None) -> Frames:
        velocities = Qd is not None
        # C-contiguous writable arrays: the kernel is compiled for those, and a view or a
        # read-only array would each be compiled again
        Q = np.require(Q, float, ("C", "W"))
        Qd = np.require(Qd, float, ("C", "W")) if velocities else Q
        A, axes, omega3, kappa = planar_frames(Q, Qd, velocities)
        fr = Frames(Q=Q, A=A, R=Q[:, :2], axes=axes, omega3=omega3, kappa=kappa)
        if velocities:
            fr.Qd, fr.Rd, fr.omega = Qd, Qd[:, :2], Qd[:, 2]
        return fr

    def cross(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]

    def mass_blocks(self, fr: Frames, mass: np.ndarray, inertia: np.ndarray) -> np.ndarray:
        return planar_mass_blocks(mass, inertia_tensors(inertia))

    def quadratic_velocity(self, fr: Frames, mass: np.ndarray, inertia: np.ndarray) -> np.ndarray:
        return np.zeros((len(mass), 3))

    def torque_generalized(self, fr: Frames, idx: np.ndarray, torque: np.ndarray) -> np.ndarray:
        out = np.zeros((len(idx), 3))
        out[:, 2] = torque
        return out

    def wrench(self, fr: Frames, idx: np.ndarray, generalized: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
        return generalized[:, :2].copy(), generalized[:, 2].copy()

    def angular_velocity(self, fr: Frames, idx: np.ndarray) -> np.ndarray:
        return fr.omega[idx]

    def angular_acceleration(self, fr: Frames, idx: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        return qdd[:, 2]

