"""Rotations: Rodrigues parameters, rotation matrices, unit quaternions, axis-angle.

All rotation maths of mbd3d is here (Shabana, *Dynamics of Multibody Systems*, ch. 2;
each formula is checked against finite differences and conservation laws by the tests). Conventions:

- ``u = A u_bar``: ``A`` maps body components to global components (active rotation, right-hand
  rule); its columns are the body axes in global components.
- Rodrigues parameters ``g = tan(angle / 2) * axis`` (the Gibbs vector), ``s = g . g``.
- Quaternions are scalar first, ``(w, x, y, z) = (cos(angle / 2), sin(angle / 2) * axis)``
  (scipy's ``Rotation.from_quat`` is scalar last).

Functions accept leading batch dimensions: ``g`` of shape (..., 3) gives ``A`` of shape
(..., 3, 3).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mbd3d.numerics.compiled import rotations as compiled
from mbd3d.numerics.checks import finite_scalar, finite_vector
from mbd3d.errors import ModelError

__all__ = ["skew", "from_rodrigues", "to_rodrigues", "from_quaternion", "to_quaternion",
           "axis_angle", "frame_along", "g_bar", "g_bar_inverse", "initial_chart",
           "as_rotation_matrix",
           "compose_rodrigues", "continuous_quaternions"]


def skew(a: np.ndarray) -> np.ndarray:
    """``skew(a) b = a x b``; (..., 3) -> (..., 3, 3)."""
    a = np.asarray(a, dtype=float)
    out = np.zeros(a.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -a[..., 2], a[..., 1]
    out[..., 1, 0], out[..., 1, 2] = a[..., 2], -a[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -a[..., 1], a[..., 0]
    return out


def _batched(kind: int, g: np.ndarray) -> np.ndarray:
    """The compiled per-row matrices ``kind`` of ``g`` (..., 3), giving (..., 3, 3)."""
    g = np.asarray(g, dtype=float)
    return compiled.matrices(kind, np.ascontiguousarray(g.reshape(-1, 3))).reshape(
        g.shape[:-1] + (3, 3))


def from_rodrigues(g: np.ndarray) -> np.ndarray:
    """``A(g) = I + 2 / (1 + s) (g~ + g~^2)`` ([1.1] of the formula sheet), ``s = g.g``
    (evaluated as ``((1 - s) I + 2 (g g^T + g~)) / (1 + s)``, :mod:`mbd3d.numerics.compiled.rotations`).
    """
    return _batched(compiled.RODRIGUES, g)


def to_quaternion(A: np.ndarray) -> np.ndarray:
    """Unit quaternion ``(w, x, y, z)`` with ``w >= 0`` of rotation matrices (Shepperd's method:
    the largest of ``tr A, A11, A22, A33`` chooses the stable formula; [1.8] of the formula
    sheet)."""
    A = np.asarray(A, dtype=float)
    M = A.reshape(-1, 3, 3)
    tr = np.trace(M, axis1=1, axis2=2)
    diag = np.diagonal(M, axis1=1, axis2=2)
    choice = np.argmax(np.column_stack([tr, diag]), axis=1)
    # K = 4 q q^T, q = (w, x, y, z): every entry is a sum of entries of A, so all four rows are
    # known; the row of the largest diagonal entry divides by the largest component (stable)
    skew = np.stack([M[:, 2, 1] - M[:, 1, 2], M[:, 0, 2] - M[:, 2, 0],
                     M[:, 1, 0] - M[:, 0, 1]], axis=1)
    K = np.empty((len(M), 4, 4))
    K[:, 0, 0] = 1.0 + tr
    K[:, 0, 1:] = K[:, 1:, 0] = skew
    K[:, 1:, 1:] = M + np.swapaxes(M, 1, 2)
    for i in range(3):
        K[:, 1 + i, 1 + i] = 1.0 + 2.0 * diag[:, i] - tr
    rows = K[np.arange(len(M)), choice]           # 4 q_c q, with q_c the largest component
    q = rows / (2.0 * np.sqrt(rows[np.arange(len(M)), choice]))[:, None]
    q[q[:, 0] < 0] *= -1.0
    return q.reshape(A.shape[:-2] + (4,))


def continuous_quaternions(q: np.ndarray) -> np.ndarray:
    """The path of unit quaternions ``q`` (k, 4) with signs flipped so that consecutive ones
    are in the same hemisphere: ``q`` and ``-q`` are the same rotation, and a path without
    jumps is what interpolation and plots need.

    >>> continuous_quaternions(np.array([[1.0, 0, 0, 0], [-0.6, 0.8, 0, 0], [0.6, -0.8, 0, 0]]))
    array([[ 1. ,  0. ,  0. ,  0. ],
           [ 0.6, -0.8, -0. , -0. ],
           [ 0.6, -0.8,  0. ,  0. ]])
    """
    q = np.array(q, dtype=float)
    if len(q) > 1:
        # flipping q[k] flips its product with q[k+1] too: the signs accumulate
        flips = np.sign(np.einsum("ki,ki->k", q[1:], q[:-1]))
        flips[flips == 0] = 1.0
        q[1:] *= np.cumprod(flips)[:, None]
    return q


def from_quaternion(q: np.ndarray) -> np.ndarray:
    """Rotation matrices of unit quaternions ``(w, x, y, z)`` (..., 4) -> (..., 3, 3)."""
    q = np.asarray(q, dtype=float)
    w, x, y, z = (q[..., k] for k in range(4))
    A = np.empty(q.shape[:-1] + (3, 3))
    A[..., 0, 0] = 1 - 2 * (y * y + z * z)
    A[..., 0, 1] = 2 * (x * y - w * z)
    A[..., 0, 2] = 2 * (x * z + w * y)
    A[..., 1, 0] = 2 * (x * y + w * z)
    A[..., 1, 1] = 1 - 2 * (x * x + z * z)
    A[..., 1, 2] = 2 * (y * z - w * x)
    A[..., 2, 0] = 2 * (x * z - w * y)
    A[..., 2, 1] = 2 * (y * z + w * x)
    A[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return A


def to_rodrigues(A: np.ndarray) -> np.ndarray:
    """Rodrigues parameters ``g = (x, y, z) / w`` of rotation matrices (via Shepperd's quaternion).

    Infinite at a half turn (``w = 0``): keep charts so that this is never needed there.
    """
    q = to_quaternion(A)
    with np.errstate(divide="ignore", invalid="ignore"):
        return q[..., 1:] / q[..., :1]


def axis_angle(axis: Any, angle: float) -> np.ndarray:
    """Rotation matrix of ``angle`` [rad] about ``axis`` (any non-zero length)."""
    axis = finite_vector(axis, 3, "rotation axis")
    norm = float(np.linalg.norm(axis))
    if norm < 1e-12:
        raise ModelError(f"rotation axis must be a non-zero vector, got {axis!r}")
    half = 0.5 * finite_scalar(angle, "rotation angle")
    return from_quaternion(np.concatenate([[np.cos(half)], np.sin(half) * axis / norm]))


def frame_along(direction: Any, hint: Any = (0.0, 0.0, 1.0)) -> np.ndarray:
    """A body frame from the drawing: the rotation matrix (body axes as columns) whose x axis
    is ``direction`` and whose z axis is as close to ``hint`` as that allows (y axis instead
    of ``hint`` when the two are parallel). For a bar along ``direction``, a hinge's yoke, a
    body whose axis the drawing gives but whose roll it does not.

    Parameters
    ----------
    direction : (3,) array_like
        The body's x axis in the drawing.
    hint : (3,) array_like
        Where its z axis should point as nearly as it can.
    """
    x = finite_vector(direction, 3, "frame direction")
    if np.linalg.norm(x) < 1e-12:
        raise ModelError(f"frame direction must be a non-zero vector, got {direction!r}")
    x = x / np.linalg.norm(x)
    y = np.cross(finite_vector(hint, 3, "frame hint"), x)
    if np.linalg.norm(y) < 1e-9:
        y = np.cross(np.array([0.0, 1.0, 0.0]), x)
    y /= np.linalg.norm(y)
    return np.column_stack([x, y, np.cross(x, y)])


def g_bar(g: np.ndarray) -> np.ndarray:
    """``G_bar(g) = 2 / (1 + s) (I - g~)``: body angular velocity ``omega_bar = G_bar g_dot``."""
    return _batched(compiled.G_BAR, g)


def g_bar_inverse(g: np.ndarray) -> np.ndarray:
    """``G_bar^-1 = (I + g~ + g g^T) / 2`` ([2.4] of the formula sheet)."""
    return _batched(compiled.G_BAR_INVERSE, g)


def compose_rodrigues(ga: np.ndarray, gb: np.ndarray) -> np.ndarray:
    """``g_ab`` with ``A(ga) A(gb) = A(g_ab)`` ([1.6] of the formula sheet; undefined at a
    half turn)."""
    return (ga + gb + np.cross(ga, gb)) / (1.0 - np.vecdot(ga, gb))[..., None]


def as_rotation_matrix(orientation: Any, what: str) -> np.ndarray:
    """A user's orientation as a rotation matrix.

    Accepted: ``None`` (identity), a 3x3 rotation matrix (orthonormal with determinant +1 to
    1e-9; it is re-orthonormalized), or a unit quaternion ``(w, x, y, z)`` (norm within 1e-6 of
    1; it is normalized). For axis-angle or Rodrigues parameters use :func:`axis_angle` or
    :func:`from_rodrigues`.

    Raises
    ------
    ModelError
        For anything else, naming ``what``.
    """
    if orientation is None:
        return np.eye(3)
    try:
        arr = np.asarray(orientation, dtype=float)
    except (TypeError, ValueError):
        raise ModelError(f"{what} must be a 3x3 rotation matrix or a quaternion (w, x, y, z), "
                         f"got {orientation!r}") from None
    if not np.all(np.isfinite(arr)):
        raise ModelError(f"{what} must be finite, got {orientation!r}")
    if arr.shape == (4,):
        norm = float(np.linalg.norm(arr))
        if abs(norm - 1.0) > 1e-6:
            raise ModelError(f"{what}: quaternion (w, x, y, z) must have unit norm, got norm "
                             f"{norm:.9g}; normalize it first if that is what you meant")
        return from_quaternion(arr / norm)
    if arr.shape == (3, 3):
        error = float(np.max(np.abs(arr.T @ arr - np.eye(3))))
        if error > 1e-9 or np.linalg.det(arr) < 0:
            raise ModelError(f"{what}: not a rotation matrix (|A^T A - I| = {error:.2e}, "
                             f"det = {np.linalg.det(arr):.6g}); it must be orthonormal with "
                             "determinant +1")
        return from_quaternion(to_quaternion(arr))  # rounding-level re-orthonormalization
    if arr.shape == (3,):
        raise ModelError(f"{what}: a 3-vector is ambiguous (Rodrigues parameters? rotation "
                         "vector?); pass mbd3d.numerics.rotations.axis_angle(axis, angle) or "
                         "mbd3d.numerics.rotations.from_rodrigues(g)")
    raise ModelError(f"{what} must be a 3x3 rotation matrix or a quaternion (w, x, y, z), got "
                     f"an array of shape {arr.shape}")


def initial_chart(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Reference rotation ``A0`` and parameters ``g`` with ``A0 A(g) = A`` and ``|g| <= 1``:
    the global chart when ``A`` is within 90 degrees of the identity, else ``A0 = A, g = 0``
    (section 1 of the formula sheet)."""
    q = to_quaternion(A)
    if q[0] >= np.sqrt(0.5):  # |g| = tan(angle / 2) <= 1
        return np.eye(3), q[1:] / q[0]
    return A.copy(), np.zeros(3)
