"""Constraint primitives, each evaluated for all its instances at once.

Every constraint row of a model has the form ``C = c(q) - c0 - f(t)``: ``c`` one of the primitive
functions below, ``c0`` a constant of the row (a distance, a relative angle of the drawing) and
``f`` an optional prescribed motion (drivers). The primitives are written against
:class:`mbd3d.body.BodyType` only, so the same code serves planar and spatial bodies.

Conventions (Haug, *Computer-Aided Kinematics and Dynamics of Mechanical Systems*, 1989; verified
in Rodrigues coordinates in ``shared/rodrigues.md`` section 4): bodies ``i`` and ``j``,
``d = r_j - r_i``, ``a = A v`` body vectors, and ``gamma = -(Cq qd)_q qd`` is the
velocity-dependent right-hand side of the acceleration equation (drivers add ``f''`` separately).

Each primitive class provides, for ``k`` instances with body indices ``bi``, ``bj`` (k,) and
stacked parameters ``p`` (a dict of arrays with leading dimension k):

- ``rows(dim)``: rows per instance;
- ``evaluate(bt, fr, bi, bj, p, value, jacobian, gamma)`` returning the requested parts
  ``(c (k, r), dc/dq (k, r, 2, n_coords), gamma (k, r))``, ``None`` for the others. The Jacobian
  holds the derivatives with respect to body i (``[:, :, 0]``) and body j (``[:, :, 1]``);
  ``gamma`` needs velocities in ``fr``.

Rotated vectors ``s = A v`` are computed once per call and shared by the three parts.
"""

from __future__ import annotations

import numpy as np

__all__ = ["PRIMITIVES", "PointCoincidence", "Dot1", "Dot2", "Distance", "Coordinate",
           "RelativeAngle", "Rotation"]


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("kd,kd->k", a, b)


def _relative_velocity(bt, fr, bi, bj, si: np.ndarray, sj: np.ndarray) -> np.ndarray:
    """Time derivative of ``d = r_j - r_i`` for body points with rotated offsets ``si``, ``sj``."""
    return fr.Rd[bj] + bt.velocity_of(fr, bj, sj) - fr.Rd[bi] - bt.velocity_of(fr, bi, si)


def _pair(Ji: np.ndarray, Jj: np.ndarray) -> np.ndarray:
    """Jacobians of one row with respect to bodies i and j, (k, n) each -> (k, 1, 2, n)."""
    J = np.empty((Ji.shape[0], 1, 2, Ji.shape[1]))
    J[:, 0, 0] = Ji
    J[:, 0, 1] = Jj
    return J


def _aJ(a: np.ndarray, J: np.ndarray) -> np.ndarray:
    """``a^T J`` per instance: (k, d) with (k, d, n) -> (k, n)."""
    return np.matmul(a[:, None, :], J)[:, 0, :]


class PointCoincidence:
    """``c = r_i - r_j``: point ``u_i`` of body i coincides with point ``u_j`` of body j.

    A planar revolute joint; the point part of a spatial spherical/revolute/universal joint.
    Reaction: the force ``-lam`` acts on body i at its point and ``+lam`` on body j.
    """

    kind = "point"
    params = ("u_i", "u_j")

    @staticmethod
    def rows(dim: int) -> int:
        return dim

    @staticmethod
    def evaluate(bt, fr, bi, bj, p, value=True, jacobian=True, gamma=False):
        si, sj = bt.rotate(fr, bi, p["u_i"]), bt.rotate(fr, bj, p["u_j"])
        c = J = g = None
        if value:
            c = fr.R[bi] + si - fr.R[bj] - sj
        if jacobian:
            J = np.empty((len(bi), si.shape[1], 2, bt.n_coords))
            J[:, :, 0] = bt.jacobian_of(fr, bi, si, True)
            J[:, :, 1] = bt.jacobian_of(fr, bj, sj, True)
            J[:, :, 1] *= -1.0
        if gamma:
            g = bt.acceleration_term_of(fr, bj, sj) - bt.acceleration_term_of(fr, bi, si)
        return c, J, g


class Dot1:
    """``c = a_i . a_j``: body vectors kept perpendicular (Haug's dot-1).

    Axis alignment is written as perpendicularity, whose gradient does not vanish at the
    solution.
    """

    kind = "dot1"
    params = ("v_i", "v_j")

    @staticmethod
    def rows(dim: int) -> int:
        return 1

    @staticmethod
    def evaluate(bt, fr, bi, bj, p, value=True, jacobian=True, gamma=False):
        ai, aj = bt.rotate(fr, bi, p["v_i"]), bt.rotate(fr, bj, p["v_j"])
        c = J = g = None
        if value:
            c = _dot(ai, aj)[:, None]
        if jacobian:
            J = _pair(_aJ(aj, bt.jacobian_of(fr, bi, ai, False)),
                      _aJ(ai, bt.jacobian_of(fr, bj, aj, False)))
        if gamma:
            g = -(_dot(aj, bt.acceleration_term_of(fr, bi, ai))
                  + _dot(ai, bt.acceleration_term_of(fr, bj, aj))
                  + 2.0 * _dot(bt.velocity_of(fr, bi, ai), bt.velocity_of(fr, bj, aj)))[:, None]
        return c, J, g


class Dot2:
    """``c = a_i . (r_j - r_i)``: point j stays on a plane (3D) or line (2D) of body i.

    With a motion ``f(t)`` it is a translation driver along ``a_i``.
    """

    kind = "dot2"
    params = ("v_i", "u_i", "u_j")

    @staticmethod
    def rows(dim: int) -> int:
        return 1

    @staticmethod
    def evaluate(bt, fr, bi, bj, p, value=True, jacobian=True, gamma=False):
        ai = bt.rotate(fr, bi, p["v_i"])
        si, sj = bt.rotate(fr, bi, p["u_i"]), bt.rotate(fr, bj, p["u_j"])
        d = fr.R[bj] + sj - fr.R[bi] - si
        c = J = g = None
        if value:
            c = _dot(ai, d)[:, None]
        if jacobian:
            Ji = _aJ(d, bt.jacobian_of(fr, bi, ai, False)) - _aJ(ai, bt.jacobian_of(fr, bi, si, True))
            Jj = _aJ(ai, bt.jacobian_of(fr, bj, sj, True))
            J = _pair(Ji, Jj)
        if gamma:
            d_dot = _relative_velocity(bt, fr, bi, bj, si, sj)
            g = -(_dot(d, bt.acceleration_term_of(fr, bi, ai))
                  + 2.0 * _dot(bt.velocity_of(fr, bi, ai), d_dot)
                  + _dot(ai, bt.acceleration_term_of(fr, bj, sj)
                         - bt.acceleration_term_of(fr, bi, si)))[:, None]
        return c, J, g


class Distance:
    """``c = |r_j - r_i|``: with ``c0 = L`` a massless rigid link of length L.

    ``lam`` is then the compressive force in the link [N] (positive pushes the points apart).
    """

    kind = "distance"
    params = ("u_i", "u_j")

    @staticmethod
    def rows(dim: int) -> int:
        return 1

    @staticmethod
    def evaluate(bt, fr, bi, bj, p, value=True, jacobian=True, gamma=False):
        si, sj = bt.rotate(fr, bi, p["u_i"]), bt.rotate(fr, bj, p["u_j"])
        d = fr.R[bj] + sj - fr.R[bi] - si
        # a zero length is refused when the model is built; the floor only avoids 0/0 in an
        # iterate that passes through coincidence
        length = np.maximum(np.sqrt(_dot(d, d)), 1e-300)
        e = d / length[:, None]
        c = J = g = None
        if value:
            c = length[:, None]
        if jacobian:
            J = _pair(-_aJ(e, bt.jacobian_of(fr, bi, si, True)),
                      _aJ(e, bt.jacobian_of(fr, bj, sj, True)))
        if gamma:
            d_dot = _relative_velocity(bt, fr, bi, bj, si, sj)
            e_dd = _dot(e, d_dot)
            g = -(_dot(e, bt.acceleration_term_of(fr, bj, sj) - bt.acceleration_term_of(fr, bi, si))
                  + (_dot(d_dot, d_dot) - e_dd * e_dd) / length)[:, None]
        return c, J, g


class Coordinate:
    """``c = q_j[coordinate]``: one coordinate of body j (body i is the ground)."""

    kind = "coordinate"
    params = ("coordinate",)

    @staticmethod
    def rows(dim: int) -> int:
        return 1

    @staticmethod
    def evaluate(bt, fr, bi, bj, p, value=True, jacobian=True, gamma=False):
        k = len(bj)
        c = J = g = None
        if value:
            c = fr.Q[bj, p["coordinate"]][:, None]
        if jacobian:
            J = np.zeros((k, 1, 2, bt.n_coords))
            J[np.arange(k), 0, 1, p["coordinate"]] = 1.0
        if gamma:
            g = np.zeros((k, 1))
        return c, J, g


class RelativeAngle:
    """``c = theta_j - theta_i``: rotation of body j relative to body i about the plane normal."""

    kind = "angle"
    params = ()

    @staticmethod
    def rows(dim: int) -> int:
        return 1

    @staticmethod
    def evaluate(bt, fr, bi, bj, p, value=True, jacobian=True, gamma=False):
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
    + (f_j . u) phi'^2 + (f_j . w) phi''``.
    """

    kind = "rotation"
    params = ("f_i", "g_i", "f_j")
    time_dependent = True

    @staticmethod
    def rows(dim: int) -> int:
        return 1

    @staticmethod
    def _vectors(p):
        c, s = np.cos(p["phi"][:, 0]), np.sin(p["phi"][:, 0])
        u_bar = p["g_i"] * c[:, None] - p["f_i"] * s[:, None]
        w_bar = p["f_i"] * c[:, None] + p["g_i"] * s[:, None]
        return u_bar, w_bar

    @staticmethod
    def evaluate(bt, fr, bi, bj, p, value=True, jacobian=True, gamma=False):
        u_bar, w_bar = Rotation._vectors(p)
        c, J, g = Dot1.evaluate(bt, fr, bi, bj, {"v_i": u_bar, "v_j": p["f_j"]}, value,
                                jacobian, gamma)
        if gamma:
            rate, accel = p["phi"][:, 1], p["phi"][:, 2]
            u = bt.rotate(fr, bi, u_bar)
            w = bt.rotate(fr, bi, w_bar)
            f_j = bt.rotate(fr, bj, p["f_j"])
            mixed = _dot(f_j, bt.velocity_of(fr, bi, w)) + _dot(w, bt.velocity_of(fr, bj, f_j))
            g = g + (2.0 * rate * mixed + _dot(f_j, u) * rate * rate
                     + _dot(f_j, w) * accel)[:, None]
        return c, J, g

    @staticmethod
    def rate(bt, fr, bi, bj, p) -> np.ndarray:
        """``-C_t``, shape (k, 1)."""
        _, w_bar = Rotation._vectors(p)
        w = bt.rotate(fr, bi, w_bar)
        return (_dot(bt.rotate(fr, bj, p["f_j"]), w) * p["phi"][:, 1])[:, None]


PRIMITIVES = {cls.kind: cls for cls in
              (PointCoincidence, Dot1, Dot2, Distance, Coordinate, RelativeAngle, Rotation)}
