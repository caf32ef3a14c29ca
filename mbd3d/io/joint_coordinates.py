"""Joint coordinates from the bodies' motion: what a joint's own axes see.

Every quantity is computed from the results' body histories (orientations, angular velocities
and accelerations, point trajectories), planar bodies lifted to 3D (the plane's normal is z), so
one formula serves both:

- a hinge (revolute, cylindrical) turns body j about the axis ``h = A_i h_i`` by the angle from
  body i's reference direction ``f_i`` to body j's ``f_j`` (their x axes projected on the plane
  normal to ``h``, y where x lies along it; or, where the joint has a ``drawn_angle``, ``f_j``
  the direction at that angle from ``f_i`` in the drawing: what a
  :class:`~mbd3d.joints.RotationDriver` reads, :meth:`mbd3d.Model.hinge_directions`),
  ``theta = atan2(h . (f_i x f_j), f_i . f_j)``, kept continuous over any number of
  turns; its rate is ``h . (omega_j - omega_i)`` and its acceleration ``h . (alpha_j -
  alpha_i)`` (exact: the relative angular velocity of a hinge lies along ``h``, which turns with
  body i). Planar revolutes give ``theta_j - theta_i`` of the bodies' own angles.
- a slide (prismatic, cylindrical) moves body j's point ``P_j`` along ``h`` from body i's
  ``P_i``: ``s = h . d`` with ``d = r_Pj - r_Pi`` (what a
  :class:`~mbd3d.joints.TranslationDriver` reads), ``s' = h . d' + (omega_i x h) . d`` and
  ``s'' = h . d'' + 2 (omega_i x h) . d' + (alpha_i x h + omega_i x (omega_i x h)) . d``.
- a ball (spherical) turns body j relative to body i by ``A_i^T A_j`` from its value in the
  drawing, in body i's axes, with relative angular velocity ``A_i^T (omega_j - omega_i)``.
- a Cardan (universal) joint turns its cross by ``alpha`` about ``a_i`` (fixed in body i)
  relative to body i, and body j by ``beta`` about ``a_j`` (fixed in body j) relative to the
  cross, both from the drawing; the relative angular velocity is ``alpha' a_i + beta' a_j``
  with ``a_i`` and ``a_j`` perpendicular, so ``alpha' = a_i . (omega_j - omega_i)``,
  ``beta' = a_j . (omega_j - omega_i)``, ``alpha'' = a_i . (alpha_j - alpha_i) + (omega_i x
  a_i) . (omega_j - omega_i)`` and likewise ``beta''`` with ``omega_j x a_j``.
"""

from __future__ import annotations

import numpy as np

from mbd3d.numerics.rotations import continuous_quaternions, from_rodrigues, to_quaternion

__all__ = ["BodyMotion", "hinge", "slide", "ball", "cardan"]


class BodyMotion:
    """A body's (or the ground's) motion over the results' times, lifted to 3D."""

    def __init__(self, results, body):
        k = len(results.t)
        self.body = body
        planar = results.model.dim == 2
        if body.is_ground:
            self.rotation = np.broadcast_to(np.eye(3), (k, 3, 3))
            self.omega = np.zeros((k, 3))
            self.alpha = np.zeros((k, 3))
            self.angle = np.zeros(k)
        else:
            history = results.body(body.name)
            self.rotation = _lift_rotation(history.rotation) if planar else history.rotation
            self.omega = _lift_scalar(history.angular_velocity) if planar else \
                history.angular_velocity
            self.alpha = _lift_scalar(history.angular_acceleration) if planar else \
                history.angular_acceleration
            self.angle = history.angle
        self.results = results

    def point(self, u: np.ndarray):
        """``(position, velocity, acceleration)`` (k, 3) of the body-frame point ``u``."""
        k = len(self.results.t)
        if self.body.is_ground:
            position = np.broadcast_to(_lift_vector(u), (k, 3))
            return position, np.zeros((k, 3)), np.zeros((k, 3))
        history = self.results.point(self.body.name, u)
        return (_lift_points(history.position), _lift_points(history.velocity),
                _lift_points(history.acceleration))


def hinge(results, body_i, body_j, axis_i: np.ndarray, directions=None):
    """``(angle [rad], rate [rad/s], acceleration [rad/s^2])`` (k,) of a hinge whose axis is
    ``axis_i`` in body i's frame, measured in space from ``directions`` (``(f_i, g_i, f_j)``
    of :meth:`mbd3d.Model.hinge_directions`; see the module doc)."""
    i, j = BodyMotion(results, body_i), BodyMotion(results, body_j)
    h = np.einsum("kab,b->ka", i.rotation, _lift_vector(axis_i))
    rate = np.einsum("ka,ka->k", h, j.omega - i.omega)
    acceleration = np.einsum("ka,ka->k", h, j.alpha - i.alpha)
    if results.model.dim == 2:
        return j.angle - i.angle, rate, acceleration
    f_i = np.einsum("kab,b->ka", i.rotation, directions[0])
    f_j = np.einsum("kab,b->ka", j.rotation, directions[2])
    wrapped = np.arctan2(np.einsum("ka,ka->k", h, np.cross(f_i, f_j)),
                         np.einsum("ka,ka->k", f_i, f_j))
    return _unwrap(wrapped, results.t, rate, acceleration), rate, acceleration


def slide(results, body_i, body_j, axis_i: np.ndarray, u_i: np.ndarray, u_j: np.ndarray):
    """``(displacement [m], rate [m/s], acceleration [m/s^2])`` (k,) of body j's point along
    the axis ``axis_i`` of body i from body i's point (see the module doc)."""
    i, j = BodyMotion(results, body_i), BodyMotion(results, body_j)
    h = np.einsum("kab,b->ka", i.rotation, _lift_vector(axis_i))
    p_i, v_i, a_i = i.point(u_i)
    p_j, v_j, a_j = j.point(u_j)
    d, d_rate, d_acc = p_j - p_i, v_j - v_i, a_j - a_i
    h_rate = np.cross(i.omega, h)
    h_acc = np.cross(i.alpha, h) + np.cross(i.omega, h_rate)
    dot = lambda a, b: np.einsum("ka,ka->k", a, b)  # noqa: E731
    return (dot(h, d), dot(h, d_rate) + dot(h_rate, d),
            dot(h, d_acc) + 2 * dot(h_rate, d_rate) + dot(h_acc, d))


def ball(results, body_i, body_j):
    """``(rotation (k, 3, 3), quaternion (k, 4), rotation vector (k, 3) [rad], relative angular
    velocity (k, 3) [rad/s])`` of body j relative to body i from the drawing, in body i's
    axes."""
    i, j = BodyMotion(results, body_i), BodyMotion(results, body_j)
    drawing = _drawing_rotation(results.model, body_i).T @ _drawing_rotation(results.model,
                                                                              body_j)
    rotation = np.einsum("kba,kbc,dc->kad", i.rotation, j.rotation, drawing)
    quaternion = continuous_quaternions(to_quaternion(rotation))
    w = np.clip(quaternion[:, 0], -1.0, 1.0)
    sine = np.linalg.norm(quaternion[:, 1:], axis=1)
    angle = 2 * np.arctan2(sine, w)
    scale = np.where(sine > 1e-12, angle / np.where(sine > 1e-12, sine, 1.0), 2.0)
    velocity = np.einsum("kba,kb->ka", i.rotation, j.omega - i.omega)
    return rotation, quaternion, quaternion[:, 1:] * scale[:, None], velocity


def cardan(results, body_i, body_j, axis_i: np.ndarray, axis_j: np.ndarray):
    """``(angles, rates, accelerations)``, each (k, 2): ``alpha`` of the cross about
    ``axis_i`` relative to body i and ``beta`` of body j about ``axis_j`` relative to the cross
    [rad, rad/s, rad/s^2], from the drawing; the axes are directions of the drawing."""
    model = results.model
    i, j = BodyMotion(results, body_i), BodyMotion(results, body_j)
    R_i0, R_j0 = _drawing_rotation(model, body_i), _drawing_rotation(model, body_j)
    a_i_drawn = np.asarray(axis_i, float) / np.linalg.norm(axis_i)
    a_j_drawn = np.asarray(axis_j, float) / np.linalg.norm(axis_j)
    a_i_local, a_j_local = R_i0.T @ a_i_drawn, R_j0.T @ a_j_drawn
    a_i = np.einsum("kab,b->ka", i.rotation, a_i_local)
    a_j = np.einsum("kab,b->ka", j.rotation, a_j_local)
    relative = j.omega - i.omega
    dot = lambda a, b: np.einsum("ka,ka->k", a, b)  # noqa: E731
    rates = np.column_stack([dot(a_i, relative), dot(a_j, relative)])
    accelerations = np.column_stack([
        dot(a_i, j.alpha - i.alpha) + dot(np.cross(i.omega, a_i), relative),
        dot(a_j, j.alpha - i.alpha) + dot(np.cross(j.omega, a_j), relative)])
    # a_j seen from body i turns by alpha about a_i; a_i seen from body j by -beta about a_j
    seen_from_i = np.einsum("kba,kb->ka", i.rotation, a_j)
    seen_from_j = np.einsum("kba,kb->ka", j.rotation, a_i)
    b0, c0 = R_i0.T @ a_j_drawn, R_j0.T @ a_i_drawn
    alpha = np.arctan2(np.cross(b0, seen_from_i) @ a_i_local, seen_from_i @ b0)
    beta = -np.arctan2(np.cross(c0, seen_from_j) @ a_j_local, seen_from_j @ c0)
    angles = np.column_stack([_unwrap(alpha, results.t, rates[:, 0], accelerations[:, 0]),
                              _unwrap(beta, results.t, rates[:, 1], accelerations[:, 1])])
    return angles, rates, accelerations


def _drawing_rotation(model, body) -> np.ndarray:
    if body.is_ground:
        return np.eye(3)
    if model.dim == 2:
        return _lift_rotation(np.array([[[np.cos(body.q0[2]), -np.sin(body.q0[2])],
                                         [np.sin(body.q0[2]), np.cos(body.q0[2])]]]))[0]
    return body.chart @ from_rodrigues(body.q0[3:])


def _unwrap(wrapped: np.ndarray, t: np.ndarray, rate: np.ndarray,
            acceleration: np.ndarray) -> np.ndarray:
    """A continuous angle through any number of turns between outputs: at each time the turn
    nearest the angle predicted from the previous one by the rates and accelerations
    (Hermite's cubic rule, exact for a cubic angle), so coarse outputs do not lose turns."""
    angle = np.array(wrapped, dtype=float)
    for k in range(1, len(angle)):
        dt = t[k] - t[k - 1]
        predicted = (angle[k - 1] + 0.5 * dt * (rate[k - 1] + rate[k])
                     + dt * dt * (acceleration[k - 1] - acceleration[k]) / 12.0)
        angle[k] += 2 * np.pi * np.round((predicted - angle[k]) / (2 * np.pi))
    return angle


def _lift_vector(v: np.ndarray) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    return v if v.size == 3 else np.array([v[0], v[1], 0.0])


def _lift_points(p: np.ndarray) -> np.ndarray:
    if p.shape[-1] == 3:
        return p
    return np.concatenate([p, np.zeros(p.shape[:-1] + (1,))], axis=-1)


def _lift_scalar(w: np.ndarray) -> np.ndarray:
    out = np.zeros((len(w), 3))
    out[:, 2] = w
    return out


def _lift_rotation(R: np.ndarray) -> np.ndarray:
    out = np.zeros((len(R), 3, 3))
    out[:, :2, :2] = R
    out[:, 2, 2] = 1.0
    return out
