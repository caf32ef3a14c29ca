"""Rodrigues parameters ``g = tan(angle / 2) axis``: the rotation matrix and the matrices that
map ``g_dot`` to the angular velocity in body axes, one body per row.

Formulas of :mod:`mbd3d.numerics.rotations` (Shabana, *Dynamics of Multibody Systems*, ch. 2), with
``s = g . g`` and ``g~`` the cross-product matrix of ``g``:

- ``A(g) = ((1 - s) I + 2 (g g^T + g~)) / (1 + s)``;
- ``G_bar(g) = 2 (I - g~) / (1 + s)``, ``omega_bar = G_bar g_dot``;
- ``G_bar^-1 = (I + g~ + g g^T) / 2``.
"""

from __future__ import annotations

import numpy as np

from mbd3d.numerics.compiled import jit


@jit
def rodrigues_matrix(g: np.ndarray, A: np.ndarray) -> None:
    """Write ``A(g)`` (3, 3) for one ``g`` (3,)."""
    x, y, z = g[0], g[1], g[2]
    s = x * x + y * y + z * z
    f = 1.0 / (1.0 + s)
    A[0, 0] = (1.0 - s + 2.0 * x * x) * f
    A[0, 1] = 2.0 * (x * y - z) * f
    A[0, 2] = 2.0 * (x * z + y) * f
    A[1, 0] = 2.0 * (y * x + z) * f
    A[1, 1] = (1.0 - s + 2.0 * y * y) * f
    A[1, 2] = 2.0 * (y * z - x) * f
    A[2, 0] = 2.0 * (z * x - y) * f
    A[2, 1] = 2.0 * (z * y + x) * f
    A[2, 2] = (1.0 - s + 2.0 * z * z) * f


@jit
def g_bar_matrix(g: np.ndarray, G: np.ndarray) -> None:
    """Write ``G_bar(g)`` (3, 3) for one ``g`` (3,)."""
    x, y, z = g[0], g[1], g[2]
    f = 2.0 / (1.0 + x * x + y * y + z * z)
    G[0, 0] = f
    G[0, 1] = z * f
    G[0, 2] = -y * f
    G[1, 0] = -z * f
    G[1, 1] = f
    G[1, 2] = x * f
    G[2, 0] = y * f
    G[2, 1] = -x * f
    G[2, 2] = f


@jit
def g_bar_inverse_matrix(g: np.ndarray, G: np.ndarray) -> None:
    """Write ``G_bar(g)^-1`` (3, 3) for one ``g`` (3,)."""
    x, y, z = g[0], g[1], g[2]
    G[0, 0] = 0.5 * (1.0 + x * x)
    G[0, 1] = 0.5 * (x * y - z)
    G[0, 2] = 0.5 * (x * z + y)
    G[1, 0] = 0.5 * (y * x + z)
    G[1, 1] = 0.5 * (1.0 + y * y)
    G[1, 2] = 0.5 * (y * z - x)
    G[2, 0] = 0.5 * (z * x - y)
    G[2, 1] = 0.5 * (z * y + x)
    G[2, 2] = 0.5 * (1.0 + z * z)


#: the per-row matrices of :func:`matrices`
RODRIGUES, G_BAR, G_BAR_INVERSE = 0, 1, 2


@jit
def matrices(kind: int, g: np.ndarray) -> np.ndarray:
    """``A(g)``, ``G_bar(g)`` or ``G_bar(g)^-1`` (``kind``) of every row of ``g`` (k, 3):
    (k, 3, 3)."""
    out = np.empty((g.shape[0], 3, 3))
    for k in range(g.shape[0]):
        if kind == RODRIGUES:
            rodrigues_matrix(g[k], out[k])
        elif kind == G_BAR:
            g_bar_matrix(g[k], out[k])
        else:
            g_bar_inverse_matrix(g[k], out[k])
    return out
