"""Coulomb friction at rigid contacts held at rest: the forces of one state, sticking or sliding.

A held row (:mod:`mbd3d.analyses.resting`) with a friction coefficient ``mu`` either *sticks*,
its slip velocity ``v = T qd`` (the tangential part of the second shape's material point's
velocity relative to the first's, :class:`~mbd3d.ContactStates`) held at zero by a tangential
force ``s`` of free sign, which must stay within the cone ``|s| <= mu f``; or *slides* along a
direction ``u``, the friction ``-mu f e`` opposing ``e``, the slip's direction (``u`` where the
slip vanishes: at the start of a slide; :func:`direction`). With ``[X; Y]`` the augmented
system's response to a unit generalized force along each column (the joints holding) and
``f`` the normal forces::

    qdd = qdd0 + X z,   z = (f, s),   columns  G_k^T - mu_k T_k^T e_k  (sliding),
                                               G_k^T, (B_k T_k)^T (sticking, B_k its tangents)
    0 <= f  _|_  G qdd + g >= 0,     B T qdd + t = 0 (the sticking rows)

with ``g`` and ``t`` the gaps' and the slips' convective terms (``(dG/dq qd) qd``): a mixed
complementarity problem (:func:`mixed_complementarity`), not symmetric where rows
slide. Where sticking rows depend on each other (a box's corners flat on a floor: their slips
are one) the split of their tangential forces is not determined by the motion; it is taken in
proportion to each row's ``mu f`` (:func:`share_by_capacity`), so that they reach their cones
together and the face slips as one, as a rigid body's does.
"""

from __future__ import annotations

import numpy as np

from mbd3d.errors import ModelError

__all__ = ["direction", "tangents", "mixed_complementarity", "share_by_capacity"]


def direction(slip: np.ndarray, along: np.ndarray, blend: float) -> np.ndarray:
    """The direction (unit, global) in which a sliding row slips: its slip velocity's
    ``v / |v|`` where the slip is beyond the small speed ``blend`` [m/s]; below, turning
    smoothly (with a continuous slope) into ``u``, the direction it slides along, as
    ``(v + w u) / |v + w u|``, ``w = (b - |v|)^2 / b``: ``u`` where the slip vanishes, at the
    start of a slide and at the stop where the row sticks. The slip's direction alone would
    follow the rounding of a vanishing slip, sideways in space, and the steps would
    collapse on its noise (Coulomb's friction turns a slow slip stiffly)."""
    speed = float(np.linalg.norm(slip))
    if speed >= blend:
        return slip / speed
    blended = slip + (blend - speed) ** 2 / blend * along
    size = float(np.linalg.norm(blended))
    return blended / size if size > 0.0 else along


def tangents(normal: np.ndarray, planar: bool) -> np.ndarray:
    """Unit tangents (d, 3) at a contact of unit ``normal``: one in the plane of a planar
    model, two orthogonal ones in space."""
    if planar:
        return np.array([[-normal[1], normal[0], 0.0]])
    axis = np.eye(3)[0] if abs(normal[0]) < 0.9 else np.eye(3)[1]
    t1 = axis - (axis @ normal) * normal
    t1 /= np.linalg.norm(t1)
    return np.array([t1, np.cross(normal, t1)])


def _solve_part(A: np.ndarray, c: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """``z`` zero off ``rows`` with ``(A z + c)[rows] = 0``: where those rows depend on each
    other, the least-norm such ``z`` (the even share; a compliance added instead, as the
    impacts add one, would leave its own size in the rows' accelerations: a held block
    creeping by 1e-12 m in a second)."""
    z = np.zeros(len(c))
    if not len(rows):
        return z
    Ar = A[np.ix_(rows, rows)]
    if np.linalg.cond(Ar) > 1e10:
        z[rows] = np.linalg.lstsq(Ar, -c[rows], rcond=1e-10)[0]
    else:
        z[rows] = np.linalg.solve(Ar, -c[rows])
    return z


def mixed_complementarity(A: np.ndarray, c: np.ndarray, a: int) -> np.ndarray:
    """``z`` with ``0 <= z_k _|_ (A z + c)_k >= 0`` for ``k < a`` and ``(A z + c)_k = 0``
    beyond, by Murty's least-index principal pivoting: starting from every ``k < a`` pressing,
    the first row whose force pulls or whose rate sinks is switched, until none is. It ends
    for a P-matrix ``A``; where it does not (sliding friction that presses a contact closed
    the harder it presses: Painleve's paradox), the run is refused, saying so."""
    m = len(c)
    size = max(float(np.max(np.abs(c), initial=0.0)), np.finfo(float).tiny)
    pressing = np.ones(a, dtype=bool)
    for _ in range(8 * a + 8):
        z = _solve_part(A, c, np.concatenate([np.flatnonzero(pressing), np.arange(a, m)]))
        y = A @ z + c
        tol = 1e-10 * max(size, float(np.max(np.abs(A @ z), initial=0.0)))
        wrong = np.flatnonzero((pressing & (z[:a] < -tol)) | (~pressing & (y[:a] < -tol)))
        if not len(wrong):
            z[:a][~pressing] = 0.0
            return z
        pressing[wrong[0]] = not pressing[wrong[0]]
    raise ModelError("the forces of the rigid contacts held at rest were not found: sliding "
                     "friction there would press a contact closed harder the harder it "
                     "presses (Painleve's paradox); lower the friction coefficient or give "
                     "the contacts compliant laws")


def share_by_capacity(A: np.ndarray, s: np.ndarray, capacity: np.ndarray) -> np.ndarray:
    """The sticking rows' tangential forces ``s`` shared in proportion to ``capacity`` (each
    row's ``mu f``, repeated per tangent) where ``A`` (their response to one another) leaves
    the split free: the forces with the same ``A s`` of least ``sum s^2 / capacity``, i.e.
    ``D A (A D A)^+ A s``; ``s`` itself where ``A`` is regular."""
    if len(s) < 2 or np.linalg.cond(A) <= 1e10:
        return s
    D = np.maximum(capacity, np.finfo(float).tiny)
    target = A @ s
    y = np.linalg.lstsq((A * D) @ A, target, rcond=1e-10)[0]
    return D * (A @ y)
