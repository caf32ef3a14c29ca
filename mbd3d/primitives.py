"""Constraint primitives, each evaluated for all its instances at once.

Every constraint row of a model has the form ``C = c(q) - c0 - f(t)``: ``c`` one of the primitive
functions below, ``c0`` a constant of the row (a distance, a relative angle of the drawing) and
``f`` an optional prescribed motion (drivers). The primitives are written against
:class:`mbd3d.body.BodyType` only, so the same code serves planar and spatial bodies.

Conventions (Haug, *Computer-Aided Kinematics and Dynamics of Mechanical Systems*, 1989; verified
in Rodrigues coordinates by ``tests/test_spatial_primitives.py``): bodies ``i`` and ``j``,
``d = r_j - r_i``, ``a = A v`` body vectors, and ``gamma = -(Cq qd)_q qd`` is the
velocity-dependent right-hand side of the acceleration equation (drivers add ``f''`` separately).

Each primitive class says whether its rows are lengths (``length_rows``), so that residuals
are judged relative to the model's length scale; and it provides, for ``k`` instances with body indices ``bi``, ``bj`` (k,) and
stacked parameters ``p`` (a dict of arrays with leading dimension k):

- ``rows(dim)``: rows per instance;
- ``vectors``: the body-frame vectors it needs, as ``(name, body "i" or "j", parameter)``;
- ``evaluate(bt, fr, bi, bj, p, value, jacobian, gamma, vectors)`` returning the requested parts
  ``(c (k, r), dc/dq (k, r, 2, n_coords), gamma (k, r))``, ``None`` for the others. The Jacobian
  holds the derivatives with respect to body i (``[:, :, 0]``) and body j (``[:, :, 1]``);
  ``gamma`` needs velocities in ``fr``.

``vectors`` maps each name to a :class:`mbd3d.body.Vectors` (``s = A v``, its Jacobian,
velocity and acceleration term). A model evaluates the vectors of all its primitives in one
batched call per state and hands each group its rows, so that the NumPy calls per evaluation
do not grow with the number of primitive types; called without them, a primitive evaluates
its own.
"""

from __future__ import annotations

import numpy as np

from mbd3d.body import Vectors

__all__ = ["PRIMITIVES", "PointCoincidence", "Dot1", "Dot2", "Distance", "Coordinate",
           "RelativeAngle", "Rotation", "own_vectors", "stack_vectors"]

_dot = np.vecdot


def stack_vectors(cls, bi: np.ndarray, bj: np.ndarray, p: dict, dim: int
                  ) -> tuple[np.ndarray, np.ndarray, dict[str, slice]]:
    """The body-frame vectors of ``cls.vectors`` for ``k`` instances, stacked one vector name
    after the other: body indices (k * n_vectors,), vectors (k * n_vectors, dim), and the rows
    of each name."""
    k = len(bi)
    if not cls.vectors:
        return np.zeros(0, dtype=np.intp), np.zeros((0, dim)), {}
    idx = np.concatenate([bi if side == "i" else bj for _, side, _ in cls.vectors])
    local = np.concatenate([np.broadcast_to(p[key], (k, dim)) for _, _, key in cls.vectors])
    rows = {name: slice(n * k, (n + 1) * k) for n, (name, _, _) in enumerate(cls.vectors)}
    return idx, local, rows


def own_vectors(cls, bt, fr, bi: np.ndarray, bj: np.ndarray, p: dict, velocities: bool
                ) -> dict[str, Vectors]:
    """The vectors of ``cls.vectors`` for these instances, in one batched evaluation (what a
    model does for all its primitives at once)."""
    if not cls.vectors:
        return {}
    idx, local, rows = stack_vectors(cls, bi, bj, p, bt.dim)
    table = bt.vectors(fr, idx, local, velocities)
    return {name: table.part(r) for name, r in rows.items()}


def _jacobian(k: int, rows: int, bt) -> np.ndarray:
    return np.zeros((k, rows, 2, bt.n_coords))


def _relative_velocity(fr, bi, bj, si: Vectors, sj: Vectors) -> np.ndarray:
    """Time derivative of ``d = r_j - r_i`` between body points ``si``, ``sj``."""
    return (fr.Rd.take(bj, axis=0) - fr.Rd.take(bi, axis=0)) + (sj.v - si.v)


def _relative_position(fr, bi, bj, si: Vectors, sj: Vectors) -> np.ndarray:
    """``d = r_j - r_i`` between body points ``si``, ``sj``."""
    return (fr.R.take(bj, axis=0) - fr.R.take(bi, axis=0)) + (sj.s - si.s)


class PointCoincidence:
    """``c = r_i - r_j``: point ``u_i`` of body i coincides with point ``u_j`` of body j.

    A planar revolute joint; the point part of a spatial spherical/revolute/universal joint.
    Reaction: the force ``-lam`` acts on body i at its point and ``+lam`` on body j.
    """

    kind = "point"
    #: whether the rows are lengths [m] (else dimensionless: cosines, angles [rad])
    length_rows = True
    params = ("u_i", "u_j")
    vectors = (("si", "i", "u_i"), ("sj", "j", "u_j"))

    @staticmethod
    def rows(dim: int) -> int:
        return dim

    @staticmethod
    def evaluate(bt, fr, bi, bj, p, value=True, jacobian=True, gamma=False, vectors=None):
        vec = vectors or own_vectors(PointCoincidence, bt, fr, bi, bj, p, gamma)
        si, sj = vec["si"], vec["sj"]
        dim = bt.dim
        c = J = g = None
        if value:
            c = -_relative_position(fr, bi, bj, si, sj)
        if jacobian:
            J = _jacobian(len(bi), dim, bt)
            J[:, :, 0, :dim] = _EYE[dim]
            J[:, :, 1, :dim] = _MINUS_EYE[dim]
            J[:, :, 0, dim:] = si.J
            np.negative(sj.J, out=J[:, :, 1, dim:])
        if gamma:
            g = sj.a - si.a
        return c, J, g


class Dot1:
    """``c = a_i . a_j``: body vectors kept perpendicular (Haug's dot-1).

    Axis alignment is written as perpendicularity, whose gradient does not vanish at the
    solution.
    """

    kind = "dot1"
    #: whether the rows are lengths [m] (else dimensionless: cosines, angles [rad])
    length_rows = False
    params = ("v_i", "v_j")
    vectors = (("ai", "i", "v_i"), ("aj", "j", "v_j"))

    @staticmethod
    def rows(dim: int) -> int:
        return 1

    @staticmethod
    def evaluate(bt, fr, bi, bj, p, value=True, jacobian=True, gamma=False, vectors=None):
        vec = vectors or own_vectors(Dot1, bt, fr, bi, bj, p, gamma)
        return _dot1(bt, vec["ai"], vec["aj"], value, jacobian, gamma)


def _dot1(bt, ai: Vectors, aj: Vectors, value: bool, jacobian: bool, gamma: bool):
    """``a_i . a_j``, its Jacobian and ``gamma`` for vectors of bodies i and j."""
    c = J = g = None
    if value:
        c = _dot(ai.s, aj.s)[:, None]
    if jacobian:
        dim = bt.dim
        J = _jacobian(len(ai.s), 1, bt)
        np.vecmat(aj.s, ai.J, out=J[:, 0, 0, dim:])
        np.vecmat(ai.s, aj.J, out=J[:, 0, 1, dim:])
    if gamma:
        g = -(_dot(aj.s, ai.a) + _dot(ai.s, aj.a) + 2.0 * _dot(ai.v, aj.v))[:, None]
    return c, J, g


class Dot2:
    """``c = a_i . (r_j - r_i)``: point j stays on a plane (3D) or line (2D) of body i.

    With a motion ``f(t)`` it is a translation driver along ``a_i``.
    """

    kind = "dot2"
    #: whether the rows are lengths [m] (else dimensionless: cosines, angles [rad])
    length_rows = True
    params = ("v_i", "u_i", "u_j")
    vectors = (("ai", "i", "v_i"), ("si", "i", "u_i"), ("sj", "j", "u_j"))

    @staticmethod
    def rows(dim: int) -> int:
        return 1

    @staticmethod
    def evaluate(bt, fr, bi, bj, p, value=True, jacobian=True, gamma=False, vectors=None):
        vec = vectors or own_vectors(Dot2, bt, fr, bi, bj, p, gamma)
        ai, si, sj = vec["ai"], vec["si"], vec["sj"]
        d = _relative_position(fr, bi, bj, si, sj)
        c = J = g = None
        if value:
            c = _dot(ai.s, d)[:, None]
        if jacobian:
            dim = bt.dim
            J = _jacobian(len(bi), 1, bt)
            np.negative(ai.s, out=J[:, 0, 0, :dim])
            np.subtract(np.vecmat(d, ai.J), np.vecmat(ai.s, si.J), out=J[:, 0, 0, dim:])
            J[:, 0, 1, :dim] = ai.s
            np.vecmat(ai.s, sj.J, out=J[:, 0, 1, dim:])
        if gamma:
            d_dot = _relative_velocity(fr, bi, bj, si, sj)
            g = -(_dot(d, ai.a) + 2.0 * _dot(ai.v, d_dot) + _dot(ai.s, sj.a - si.a))[:, None]
        return c, J, g


class Distance:
    """``c = |r_j - r_i|``: with ``c0 = L`` a massless rigid link of length L.

    ``lam`` is then the compressive force in the link [N] (positive pushes the points apart).
    """

    kind = "distance"
    #: whether the rows are lengths [m] (else dimensionless: cosines, angles [rad])
    length_rows = True
    params = ("u_i", "u_j")
    vectors = (("si", "i", "u_i"), ("sj", "j", "u_j"))

    @staticmethod
    def rows(dim: int) -> int:
        return 1

    @staticmethod
    def evaluate(bt, fr, bi, bj, p, value=True, jacobian=True, gamma=False, vectors=None):
        vec = vectors or own_vectors(Distance, bt, fr, bi, bj, p, gamma)
        si, sj = vec["si"], vec["sj"]
        d = _relative_position(fr, bi, bj, si, sj)
        # a zero length is refused when the model is built; the floor only avoids 0/0 in an
        # iterate that passes through coincidence
        length = np.maximum(np.sqrt(_dot(d, d)), 1e-300)
        e = d / length[:, None]
        c = J = g = None
        if value:
            c = length[:, None]
        if jacobian:
            dim = bt.dim
            J = _jacobian(len(bi), 1, bt)
            np.negative(e, out=J[:, 0, 0, :dim])
            np.negative(np.vecmat(e, si.J), out=J[:, 0, 0, dim:])
            J[:, 0, 1, :dim] = e
            np.vecmat(e, sj.J, out=J[:, 0, 1, dim:])
        if gamma:
            d_dot = _relative_velocity(fr, bi, bj, si, sj)
            e_dd = _dot(e, d_dot)
            g = -(_dot(e, sj.a - si.a) + (_dot(d_dot, d_dot) - e_dd * e_dd) / length)[:, None]
        return c, J, g


class Coordinate:
    """``c = q_j[coordinate]``: one coordinate of body j (body i is the ground)."""

    kind = "coordinate"
    #: translation coordinates are lengths, a planar angle is not (see :meth:`row_is_length`)
    length_rows = None

    @staticmethod
    def row_is_length(params: dict, dim: int) -> bool:
        return int(params["coordinate"]) < dim
    params = ("coordinate",)
    vectors = ()

    @staticmethod
    def rows(dim: int) -> int:
        return 1

    @staticmethod
    def evaluate(bt, fr, bi, bj, p, value=True, jacobian=True, gamma=False, vectors=None):
        k = len(bj)
        c = J = g = None
        if value:
            c = fr.Q[bj, p["coordinate"]][:, None]
        if jacobian:
            J = _jacobian(k, 1, bt)
            J[np.arange(k), 0, 1, p["coordinate"]] = 1.0
        if gamma:
            g = np.zeros((k, 1))
        return c, J, g


class RelativeAngle:
    """``c = theta_j - theta_i``: rotation of body j relative to body i about the plane normal."""

    kind = "angle"
    #: whether the rows are lengths [m] (else dimensionless: cosines, angles [rad])
    length_rows = False
    params = ()
    vectors = ()

    @staticmethod
    def rows(dim: int) -> int:
        return 1

    @staticmethod
    def evaluate(bt, fr, bi, bj, p, value=True, jacobian=True, gamma=False, vectors=None):
        c = J = g = None
        if value:
            c = bt.relative_angle(fr, bi, bj)[:, None]
        if jacobian:
            J = bt.relative_angle(fr, bi, bj, jacobian=True)[:, None]
        if gamma:
            # theta_j - theta_i is linear in q for planar bodies: no velocity-dependent term
            g = np.zeros((len(bi), 1))
        return c, J, g


class Rotation:
    """Spatial rotation driver across a hinge: ``C = f_j . (g_i cos(phi) - f_i sin(phi))``,
    ``phi = f(t)``.

    ``f_i, g_i`` span body i's plane normal to the hinge, ``f_j`` is body j's reference
    direction in that plane; with ``theta`` the angle from ``f_i`` to ``f_j`` about the hinge,
    ``C = sin(theta - phi)``: no turn counting, any number of revolutions, and ``lam`` is minus
    the driving torque about the hinge. The time dependence sits inside the row, so this class
    supplies its own ``-C_t`` (``rate``) and time terms of ``Qd``; ``p["phi"]`` holds
    ``(f, f', f'')`` per instance. With ``u = A_i (g cos(phi) - f sin(phi))`` and
    ``w = A_i (f cos(phi) + g sin(phi))``: ``-C_t = (f_j . w) phi'`` and
    ``Qd = gamma_dot1(u, f_j) + 2 phi' (f_j . (omega_i x w) + w . (omega_j x f_j))
    + (f_j . u) phi'^2 + (f_j . w) phi''``. ``u`` and ``w`` and everything derived from them
    are linear in ``f_i`` and ``g_i``, so they are combined from those two vectors' parts.
    """

    kind = "rotation"
    #: whether the rows are lengths [m] (else dimensionless: cosines, angles [rad])
    length_rows = False
    params = ("f_i", "g_i", "f_j")
    vectors = (("fi", "i", "f_i"), ("gi", "i", "g_i"), ("fj", "j", "f_j"))
    time_dependent = True

    @staticmethod
    def rows(dim: int) -> int:
        return 1

    @staticmethod
    def _turned(p, vec) -> tuple[Vectors, Vectors]:
        """``u`` and ``w`` of the class docstring, from the parts of ``f_i`` and ``g_i``."""
        c, s = np.cos(p["phi"][:, 0]), np.sin(p["phi"][:, 0])
        fi, gi = vec["fi"], vec["gi"]
        return gi.combine(c, fi, -s), fi.combine(c, gi, s)

    @staticmethod
    def evaluate(bt, fr, bi, bj, p, value=True, jacobian=True, gamma=False, vectors=None):
        vec = vectors or own_vectors(Rotation, bt, fr, bi, bj, p, gamma)
        u, w = Rotation._turned(p, vec)
        f_j = vec["fj"]
        c, J, g = _dot1(bt, u, f_j, value, jacobian, gamma)
        if gamma:
            rate, accel = p["phi"][:, 1], p["phi"][:, 2]
            mixed = _dot(f_j.s, w.v) + _dot(w.s, f_j.v)
            g = g + (2.0 * rate * mixed + _dot(f_j.s, u.s) * rate * rate
                     + _dot(f_j.s, w.s) * accel)[:, None]
        return c, J, g

    @staticmethod
    def rate(bt, fr, bi, bj, p) -> np.ndarray:
        """``-C_t``, shape (k, 1)."""
        vec = own_vectors(Rotation, bt, fr, bi, bj, p, False)
        _, w = Rotation._turned(p, vec)
        return (_dot(vec["fj"].s, w.s) * p["phi"][:, 1])[:, None]


#: translation part of a point's Jacobian, by dimension
_EYE = {2: np.eye(2), 3: np.eye(3)}
_MINUS_EYE = {dim: -eye for dim, eye in _EYE.items()}

PRIMITIVES = {cls.kind: cls for cls in
              (PointCoincidence, Dot1, Dot2, Distance, Coordinate, RelativeAngle, Rotation)}
