"""The spatial rigid body: ``q = (R, g)``, ``R`` the centre of mass, ``g`` Rodrigues parameters.

Formulas after Shabana, *Dynamics of Multibody Systems*, ch. 2 (Rodrigues parameters); the
numbers in brackets are those of the developers' formula sheet, where each was verified
numerically (the tests check them against finite differences and conservation laws). Each
body keeps a reference rotation ``A0`` (its *chart*, part of the state, not of
the body): ``A = A0 A(g)`` [5.1]. With ``s = A v`` a body vector in global components:

- ``d(A v)/dg = -s~ A G_bar`` [2.9, 4.1], ``d(R + s)/dq = [I3, -s~ A G_bar]``;
- ``ds/dt = omega x s``; velocity-dependent part of ``d2s/dt2``:
  ``omega x (omega x s) - kappa omega x s``, ``kappa = 2 g.g_dot / (1 + g.g)`` [2.7, 4.3];
- ``M = blockdiag(m I3, G_bar^T J G_bar)``,
  ``Qv = [0; -G_bar^T (w x J w) + kappa G_bar^T J w]`` with ``w = G_bar g_dot`` [3.1, 3.2];
- torque ``n``: ``Q_g = (A G_bar)^T n`` [3.4].

``g`` is infinite at a half turn from the chart, so :meth:`SpatialBody.reset_charts` moves the
chart to the current orientation when ``|g|`` passes 1 (90 degrees) [5.2-5.4]: ``A0 <- A0 A(g)``,
``g <- 0``, ``g_dot <- G_bar(g) g_dot / 2``, keeping orientation and angular velocity.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mbd3d.numerics import rotations as rot
from mbd3d.model.body import BodyType, Frames
from mbd3d.numerics.compiled.bodies import (spatial_frames, spatial_mass_blocks,
                                            spatial_quadratic_velocity, spatial_rates,
                                            spatial_reset_charts, spatial_velocities,
                                            spatial_velocity_derivative)
from mbd3d.numerics.checks import finite_vector
from mbd3d.errors import ModelError

#: ``|g|`` above which a body's chart is moved (90 degrees from the reference orientation)
CHART_LIMIT = 1.0


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


class SpatialBody(BodyType):
    """Kinematics of spatial rigid bodies in Rodrigues parameters, batched over bodies."""

    dim = 3
    n_coords = 6
    coordinate_names = ("x", "y", "z", "g1", "g2", "g3")
    name = "spatial"

    def check_inertia(self, inertia: Any, body: str) -> np.ndarray:
        what = f"body '{body}': inertia"
        arr = np.asarray(inertia, dtype=float) if not isinstance(inertia, str) else None
        if arr is not None and arr.shape == (3,):
            arr = np.diag(arr)
        if arr is None or arr.shape != (3, 3):
            raise ModelError(f"{what} must be a 3x3 centroidal inertia tensor [kg m^2] in body "
                             f"axes, or its 3 principal values, got {inertia!r}")
        if not np.all(np.isfinite(arr)):
            raise ModelError(f"{what} must be finite, got {inertia!r}")
        # relative to the tensor's size: a tensor of a 1 mm body is 1e-12 of one of 1 m
        if np.max(np.abs(arr - arr.T)) > 1e-12 * np.max(np.abs(arr)):
            raise ModelError(f"{what} must be symmetric, got {inertia!r}")
        principal = np.linalg.eigvalsh(arr)
        if principal[0] <= 0.0:
            raise ModelError(f"{what} must be positive definite; its principal moments are "
                             f"{principal}")
        # a real mass distribution has J1 + J2 >= J3 for its principal moments
        if principal[0] + principal[1] < principal[2] * (1.0 - 1e-9):
            raise ModelError(f"{what}: principal moments {principal} violate J1 + J2 >= J3, so "
                             "no real body has them; check the values and their axes")
        return 0.5 * (arr + arr.T)

    def initial_state(self, body: str, position: Any, orientation: Any
                      ) -> tuple[np.ndarray, np.ndarray]:
        pos = finite_vector(position, 3, f"body '{body}': position")
        A = rot.as_rotation_matrix(orientation, f"body '{body}': orientation")
        chart, g = rot.initial_chart(A)
        return np.concatenate([pos, g]), chart

    def initial_rates(self, body: str, velocity: Any, angular_velocity: Any, q0: np.ndarray,
                      chart: np.ndarray | None) -> np.ndarray:
        vel = finite_vector((0, 0, 0) if velocity is None else velocity, 3,
                            f"body '{body}': velocity")
        omega = finite_vector((0, 0, 0) if angular_velocity is None else angular_velocity, 3,
                              f"body '{body}': angular_velocity (global axes)")
        g = q0[3:]
        A = chart @ rot.from_rodrigues(g)
        return np.concatenate([vel, rot.g_bar_inverse(g) @ (A.T @ omega)])

    def frames(self, Q: np.ndarray, Qd: np.ndarray | None = None,
               charts: np.ndarray | None = None) -> Frames:
        velocities = Qd is not None
        # C-contiguous writable arrays: the kernel is compiled for those, and a view or a
        # read-only array would each be compiled again
        Q = np.require(Q, float, ("C", "W"))
        Qd = np.require(Qd, float, ("C", "W")) if velocities else Q
        charts = (np.tile(np.eye(3), (len(Q), 1, 1)) if charts is None
                  else np.require(charts, float, ("C", "W")))
        A, AG, omega, kappa, Gb, omega_bar = spatial_frames(Q, Qd, charts, velocities)
        fr = Frames(Q=Q, A=A, R=Q[:, :3], g=Q[:, 3:6], Gbar=Gb, AG=AG, axes=AG, omega3=omega,
                    kappa=kappa, charts=charts)
        if velocities:
            fr.Qd, fr.Rd, fr.omega, fr.omega_bar = Qd, Qd[:, :3], omega, omega_bar
        return fr

    def cross(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return _cross(a, b)

    def mass_blocks(self, fr: Frames, mass: np.ndarray, inertia: np.ndarray) -> np.ndarray:
        return spatial_mass_blocks(fr.Gbar, mass, inertia)

    def quadratic_velocity(self, fr: Frames, mass: np.ndarray, inertia: np.ndarray) -> np.ndarray:
        return spatial_quadratic_velocity(fr.Gbar, fr.omega_bar, fr.kappa, inertia)

    def torque_generalized(self, fr: Frames, idx: np.ndarray, torque: np.ndarray) -> np.ndarray:
        out = np.zeros((len(idx), 6))
        out[:, 3:] = np.matmul(np.swapaxes(fr.AG[idx], 1, 2), torque[:, :, None])[:, :, 0]
        return out

    def wrench(self, fr: Frames, idx: np.ndarray, generalized: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
        # Q_g = (A G_bar)^T n  =>  n = A G_bar^-T Q_g
        inverse_t = np.swapaxes(rot.g_bar_inverse(fr.g[idx]), 1, 2)
        n_bar = np.matmul(inverse_t, generalized[:, 3:, None])
        return generalized[:, :3].copy(), np.matmul(fr.A[idx], n_bar)[:, :, 0]

    def angular_velocity(self, fr: Frames, idx: np.ndarray) -> np.ndarray:
        return fr.omega[idx]

    def angular_acceleration(self, fr: Frames, idx: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        # d omega_bar/dt of the bodies' own coordinates, turned to global axes
        k = len(idx)
        alpha_bar = spatial_velocity_derivative(
            np.ravel(fr.Q[idx]), np.ravel(fr.Qd[idx]), np.ravel(qdd)).reshape(k, 6)[:, 3:]
        return np.matvec(fr.A[idx], alpha_bar)

    def velocities(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """``(R_dot, omega_bar)`` per body, ``omega_bar = G_bar(g) g_dot`` [2.5]."""
        return spatial_velocities(np.asarray(q, dtype=float), np.asarray(qd, dtype=float))

    def rates(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``g_dot = G_bar(g)^-1 omega_bar`` [2.4] per body."""
        return spatial_rates(np.asarray(q, dtype=float), np.asarray(v, dtype=float))

    def velocity_derivative(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """``d omega_bar/dt = G_bar g_ddot - kappa omega_bar`` [2.8] per body."""
        return spatial_velocity_derivative(np.asarray(q, dtype=float),
                                           np.asarray(qd, dtype=float),
                                           np.asarray(qdd, dtype=float))

    def reset_charts(self, q: np.ndarray, qd: np.ndarray | None, charts: np.ndarray,
                     limit: float = CHART_LIMIT, turns: np.ndarray | None = None):
        """Move the chart of every body with ``|g| > limit`` (and, to restart the integrator
        less often, of every body past half of it when one does) to its current orientation.

        Returns ``(q, qd, charts, changed)``; the inputs are not modified, except ``turns``
        (the charts' quaternions, whose signs follow the motion), updated in place when given
        (the formulas are :func:`mbd3d.numerics.compiled.bodies.spatial_reset_charts`).
        """
        q = np.array(q, dtype=float)
        qd = None if qd is None else np.array(qd, dtype=float)
        charts = np.array(charts, dtype=float)
        if not spatial_reset_charts(q, np.zeros(0) if qd is None else qd, charts, limit,
                                    np.zeros((0, 4)) if turns is None else turns):
            return q, qd, charts, False
        return q, qd, charts, True
