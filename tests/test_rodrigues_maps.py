"""The spatial bodies' velocity maps and chart resets (``numerics/compiled/bodies.py``) against
rotation matrices built by SciPy's Rotation, differenced in time: an independent statement of
``A(g)``, of ``omega_bar = A^T A_dot`` and of its rate, at random states in random charts.

Fast on purpose: these maps sit under every spatial integration, and a mutant of them should be
judged here in a second, not by an integration that runs to a time limit."""

from __future__ import annotations

import numpy as np
import pytest
import quaternion
from scipy.spatial.transform import Rotation

from mbd3d.numerics.compiled.bodies import (spatial_rates, spatial_reset_charts,
                                            spatial_velocities, spatial_velocity_derivative)

rng = np.random.default_rng(2026)
N_BODIES = 4


def _matrix(g: np.ndarray) -> np.ndarray:
    """``A(g)`` through SciPy: the rotation by ``2 atan|g|`` about ``g``."""
    size = np.linalg.norm(g)
    return Rotation.from_rotvec(2.0 * np.arctan(size) * g / size).as_matrix()


def _omega_bar(g_of_t, t: float, h: float = 1e-4) -> np.ndarray:
    """Angular velocity in body axes, ``(A^T A_dot)^vee``, by a 4th-order central difference
    (about 4e-12 off for the rates of these tests; differenced again, about 3e-9)."""
    A_dot = (-_matrix(g_of_t(t + 2 * h)) + 8 * _matrix(g_of_t(t + h))
             - 8 * _matrix(g_of_t(t - h)) + _matrix(g_of_t(t - 2 * h))) / (12 * h)
    W = _matrix(g_of_t(t)).T @ A_dot
    return np.array([W[2, 1], W[0, 2], W[1, 0]])


def _random_state():
    """Positions, rates and accelerations of ``N_BODIES`` bodies; ``g`` up to a 2.4 rad turn."""
    q = rng.normal(size=6 * N_BODIES)
    qd = rng.normal(size=6 * N_BODIES)
    qdd = rng.normal(size=6 * N_BODIES)
    return q, qd, qdd


def test_angular_velocities_are_those_of_the_rotation_matrices():
    q, qd, _ = _random_state()
    v = spatial_velocities(q, qd)
    for b in range(N_BODIES):
        o = 6 * b
        expected = _omega_bar(lambda t: q[o + 3:o + 6] + t * qd[o + 3:o + 6], 0.0)
        np.testing.assert_allclose(v[o + 3:o + 6], expected, rtol=0, atol=1e-10)
        np.testing.assert_array_equal(v[o:o + 3], qd[o:o + 3])


def test_rates_from_angular_velocities_invert_the_rotation_matrices():
    q, _, _ = _random_state()
    v = rng.normal(size=6 * N_BODIES)
    qd = spatial_rates(q, v)
    np.testing.assert_array_equal(qd.reshape(-1, 6)[:, :3], v.reshape(-1, 6)[:, :3])
    for b in range(N_BODIES):
        o = 6 * b
        # g moving at the rates found turns the body at the angular velocity given
        omega = _omega_bar(lambda t: q[o + 3:o + 6] + t * qd[o + 3:o + 6], 0.0)
        np.testing.assert_allclose(omega, v[o + 3:o + 6], rtol=0, atol=1e-10)


def test_velocity_derivative_is_the_rate_of_the_angular_velocity():
    q, qd, qdd = _random_state()
    a = spatial_velocity_derivative(q, qd, qdd)
    np.testing.assert_array_equal(a.reshape(-1, 6)[:, :3], qdd.reshape(-1, 6)[:, :3])
    h = 1e-3
    for b in range(N_BODIES):
        o = 6 * b
        g0, g1, g2 = q[o + 3:o + 6], qd[o + 3:o + 6], qdd[o + 3:o + 6]

        def path(t):
            return g0 + t * g1 + 0.5 * t * t * g2

        alpha = (-_omega_bar(path, 2 * h) + 8 * _omega_bar(path, h)
                 - 8 * _omega_bar(path, -h) + _omega_bar(path, -2 * h)) / (12 * h)
        np.testing.assert_allclose(a[o + 3:o + 6], alpha, rtol=0, atol=1e-8)


@pytest.mark.parametrize("with_rates", [True, False])
def test_chart_reset_keeps_orientation_angular_velocity_and_quaternion(with_rates):
    limit = 1.3
    # body 0 over the limit (by all three of its parameters), body 1 past half of it, bodies 2
    # and 3 below half: 0 and 1 move
    g = np.array([[0.8, -0.8, 0.8], [0.3, 0.5, -0.3], [0.3, -0.3, 0.3], [0.05, 0.0, 0.1]])
    q = rng.normal(size=6 * N_BODIES)
    q.reshape(-1, 6)[:, 3:] = g
    qd = rng.normal(size=6 * N_BODIES)
    charts = Rotation.random(N_BODIES, random_state=3).as_matrix()
    turns = np.zeros((N_BODIES + 1, 4))
    turns[:N_BODIES] = Rotation.from_matrix(charts).as_quat(scalar_first=True)
    turns[:N_BODIES] *= -1.0       # the other sign of each: a reset must keep it, not flip it
    turns_in = turns.copy()
    before = charts @ np.array([_matrix(row) for row in g])
    omega = spatial_velocities(q, qd).reshape(-1, 6)[:, 3:].copy()
    positions, q_in, qd_in = q.reshape(-1, 6)[:, :3].copy(), q.copy(), qd.copy()
    rates = qd if with_rates else np.zeros(0)

    assert spatial_reset_charts(q, rates, charts, limit, turns)

    moved = [0, 1]
    np.testing.assert_array_equal(q.reshape(-1, 6)[moved, 3:], 0.0)
    np.testing.assert_array_equal(q.reshape(-1, 6)[2:, 3:], g[2:])
    np.testing.assert_array_equal(q.reshape(-1, 6)[:, :3], positions)
    after = charts @ np.array([_matrix(row) if row.any() else np.eye(3)
                               for row in q.reshape(-1, 6)[:, 3:]])
    np.testing.assert_allclose(after, before, rtol=0, atol=1e-14)
    for b in range(N_BODIES):
        # a Hamilton product by numpy-quaternion, from the sign given at the start
        expected = quaternion.from_float_array(turns_in[b])
        if b in moved:
            expected *= quaternion.from_float_array(np.r_[1.0, g[b]] / np.sqrt(1 + g[b] @ g[b]))
        np.testing.assert_allclose(turns[b], quaternion.as_float_array(expected),
                                   rtol=0, atol=1e-14)
        # and it is the quaternion of the chart
        np.testing.assert_allclose(quaternion.as_rotation_matrix(
            quaternion.from_float_array(turns[b])), charts[b], rtol=0, atol=1e-14)
    np.testing.assert_array_equal(turns[N_BODIES], 0.0)
    if with_rates:
        np.testing.assert_allclose(spatial_velocities(q, qd).reshape(-1, 6)[:, 3:], omega,
                                   rtol=0, atol=1e-14)
        np.testing.assert_array_equal(qd.reshape(-1, 6)[2:], qd_in.reshape(-1, 6)[2:])
    # nothing over the limit: nothing moves, and the answer says so
    q_small = q_in.copy()
    q_small.reshape(-1, 6)[:, 3:] *= 0.8      # |g| of body 0 at 0.85 of the limit
    kept = charts.copy()
    assert not spatial_reset_charts(q_small, np.zeros(0), charts, limit, np.zeros((0, 4)))
    np.testing.assert_array_equal(charts, kept)


def test_the_error_of_rodrigues_parameters_is_measured_as_the_turn_it_stands_for():
    """The explicit loop's error scale: a position or rate component's is ``atol + rtol
    max(|y|, |y_new|)``; a Rodrigues parameter's the orientation error its change stands
    for, measured as a unit quaternion's components (``atol + rtol`` for components of size
    one), times the most a change of g outgrows the quaternion's it causes, found here with
    SciPy's quaternions: ``|dg| / |dq|`` is largest along g, where it is ``1 + g.g``."""
    from mbd3d.numerics.compiled.integration import error_scale

    def quaternion_of(g):
        size = np.linalg.norm(g)
        return Rotation.from_rotvec(2.0 * np.arctan(size) * g / size).as_quat()

    def growth(g, direction, h=1e-7):
        dq = quaternion_of(g + h * direction) - quaternion_of(g)
        return h / np.linalg.norm(dq)

    n = 6 * N_BODIES
    y, y_new = rng.normal(size=2 * n), rng.normal(size=2 * n)
    atol, rtol = rng.uniform(1e-9, 1e-6, 2 * n), 1e-5
    scale = error_scale(True, n, y, y_new, atol, rtol)
    for i in range(2 * n):
        body, k = divmod(i, 6)
        if i < n and k >= 3:
            gs = [state[6 * body + 3:6 * body + 6] for state in (y, y_new)]
            most = max(growth(g, g / np.linalg.norm(g)) for g in gs)
            others = [growth(g, d / np.linalg.norm(d)) for g in gs
                      for d in rng.normal(size=(5, 3))]
            assert max(others) < most
            assert scale[i] == pytest.approx((atol[i] + rtol) * most, rel=1e-6)
        else:
            assert scale[i] == atol[i] + rtol * max(abs(y[i]), abs(y_new[i]))
    planar = error_scale(False, n, y, y_new, atol, rtol)
    np.testing.assert_array_equal(planar, atol + rtol * np.maximum(abs(y), abs(y_new)))
