"""What the results say of one body or one body point over time: :class:`BodyHistory` (pose,
velocity and acceleration of its centre of mass, its orientation) and :class:`PointHistory`
(a point fixed in the body), in global axes. Made by :meth:`Results.body` and
:meth:`Results.point`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.numerics.rotations import continuous_quaternions, to_quaternion

__all__ = ["BodyHistory", "PointHistory"]


@dataclass(frozen=True)
class BodyHistory:
    """Motion of a body over time (global axes).

    Attributes
    ----------
    position, velocity, acceleration : ndarray (k, dim)
        Centre of mass [m], [m/s], [m/s^2].
    rotation : ndarray (k, dim, dim)
        Orientation: the body axes as columns, in global components.
    angular_velocity, angular_acceleration : ndarray
        [rad/s], [rad/s^2]: (k,) about the normal for planar bodies, (k, 3) global for spatial.
    angle : ndarray (k,) or None
        Planar bodies: body angle [rad], unwrapped (it keeps counting turns).
    turning : ndarray (k, 4) or None
        Spatial bodies: quaternions whose signs follow the motion between the outputs (from
        the analysis's charts), which :attr:`quaternion` takes its signs from.

    ``angular_velocity_body`` and ``angular_acceleration_body`` give them in the body's axes.
    """

    name: str
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    rotation: np.ndarray
    angular_velocity: np.ndarray
    angular_acceleration: np.ndarray
    angle: np.ndarray | None = None
    turning: np.ndarray | None = None

    @property
    def angular_velocity_body(self) -> np.ndarray:
        """Angular velocity in the body's own axes [rad/s]: (k, 3) ``A^T omega`` for spatial
        bodies (what a gyro on the body reads), (k,) for planar ones (the same scalar)."""
        if self.angular_velocity.ndim == 1:
            return self.angular_velocity
        return np.einsum("kba,kb->ka", self.rotation, self.angular_velocity)

    @property
    def angular_acceleration_body(self) -> np.ndarray:
        """Angular acceleration in the body's own axes [rad/s^2]: ``A^T alpha`` (the rate of
        :attr:`angular_velocity_body`: ``d(A^T omega)/dt = A^T alpha`` since ``A' = omega~ A``)."""
        if self.angular_acceleration.ndim == 1:
            return self.angular_acceleration
        return np.einsum("kba,kb->ka", self.rotation, self.angular_acceleration)

    @property
    def quaternion(self) -> np.ndarray:
        """Spatial bodies: unit quaternions (k, 4), ``(w, x, y, z)``, their signs continuous
        along the motion. Forward dynamics carries them through every step, so they follow
        the motion however far apart the outputs; kinematic analysis and inverse dynamics see
        only their time points and take the turn between them the short way (less than half
        a turn)."""
        if self.rotation.shape[-1] != 3:
            raise ModelError(f"body '{self.name}' is planar: use .angle")
        q = to_quaternion(self.rotation)
        if self.turning is None:
            return continuous_quaternions(q)
        return np.where(np.einsum("ki,ki->k", q, self.turning)[:, None] < 0, -q, q)

    @property
    def orientation(self):
        """Spatial bodies: the orientations as a numpy-quaternion array (k,) of
        ``np.quaternion``, the same rotations as :attr:`quaternion`, for quaternion algebra:
        ``a.conj() * b`` is the rotation from ``a`` to ``b``, ``quaternion.slerp`` and
        ``quaternion.squad`` interpolate between output times, and
        ``quaternion.as_rotation_vector`` gives rotation vectors [rad]."""
        import quaternion  # noqa: PLC0415  (numpy-quaternion; imported when asked for)

        return quaternion.from_float_array(self.quaternion)

    @property
    def pose(self) -> np.ndarray:
        """(k, 3) ``(x, y, angle)`` for planar bodies; (k, 7) ``(x, y, z, w, qx, qy, qz)``
        for spatial ones."""
        if self.angle is not None:
            return np.column_stack([self.position, self.angle])
        return np.column_stack([self.position, self.quaternion])


@dataclass(frozen=True)
class PointHistory:
    """Trajectory of a body point in global axes: ``position`` [m], ``velocity`` [m/s] and
    ``acceleration`` [m/s^2], each (k, dim).

    Indexing and NumPy see the positions, the common use: ``p[:, 0]`` is the x coordinate
    over time and ``np.asarray(p)`` the (k, dim) positions.

    >>> import numpy as np, mbd3d as mb
    >>> from mbd3d.mechanisms import slider_crank
    >>> res = mb.kinematic_analysis(slider_crank(crank_speed=1.0), np.linspace(0.0, 1.0, 3))
    >>> tip = res.point("crank", (0.06, 0.0))
    >>> np.array_equal(tip[:, 1], tip.position[:, 1]), len(tip), np.asarray(tip).shape
    (True, 3, (3, 2))
    """

    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray

    def __getitem__(self, index):
        return self.position[index]

    def __len__(self) -> int:
        return len(self.position)

    def __array__(self, dtype=None, copy=None):
        return np.asarray(self.position, dtype=dtype)
