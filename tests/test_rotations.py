"""Rotation utilities: every representation round-tripped, checked against numpy-quaternion and
SciPy's Rotation (independent implementations)."""

from __future__ import annotations

import numpy as np
import pytest
import quaternion as npq
from scipy.spatial.transform import Rotation

import mbd3d as mb
from mbd3d.numerics import rotations as rot

rng = np.random.default_rng(42)
RANDOM = Rotation.random(50, random_state=7)


def test_rodrigues_matrix_matches_independent_implementations():
    g = rng.normal(size=(50, 3))
    q = np.column_stack([np.ones(50), g]) / np.sqrt(1 + np.sum(g * g, axis=1))[:, None]
    expected = npq.as_rotation_matrix(npq.from_float_array(q))
    np.testing.assert_allclose(rot.from_rodrigues(g), expected, rtol=0, atol=1e-14)
    np.testing.assert_allclose(rot.from_rodrigues(g),
                               Rotation.from_quat(q[:, [1, 2, 3, 0]]).as_matrix(),
                               rtol=0, atol=1e-14)


def test_quaternion_round_trip_including_near_half_turns():
    A = RANDOM.as_matrix()
    np.testing.assert_allclose(rot.from_quaternion(rot.to_quaternion(A)), A, rtol=0, atol=1e-14)
    # near and at a half turn, where the trace formula of g loses accuracy
    for angle in (np.pi - 1e-6, np.pi):
        A = rot.axis_angle((1.0, -2.0, 0.5), angle)
        np.testing.assert_allclose(rot.from_quaternion(rot.to_quaternion(A)), A,
                                   rtol=0, atol=1e-14)
    q = rot.to_quaternion(A)
    assert q[0] >= 0 and np.linalg.norm(q) == pytest.approx(1.0)


def test_axis_angle_and_rodrigues_agree():
    axis = np.array([0.3, -0.2, 0.9])
    angle = 2.1
    g = np.tan(angle / 2) * axis / np.linalg.norm(axis)
    np.testing.assert_allclose(rot.axis_angle(axis, angle), rot.from_rodrigues(g),
                               rtol=0, atol=1e-14)
    np.testing.assert_allclose(rot.to_rodrigues(rot.from_rodrigues(g)), g, rtol=1e-13)
    np.testing.assert_allclose(Rotation.from_rotvec(angle * axis / np.linalg.norm(axis)).as_matrix(),
                               rot.axis_angle(axis, angle), rtol=0, atol=1e-14)


def test_g_bar_maps_rates_to_body_angular_velocity():
    # omega_bar = vex(A^T dA/dt), A(g(t)) differentiated by central differences
    g, g_dot, h = rng.normal(size=3), rng.normal(size=3), 1e-6
    A = rot.from_rodrigues(g)
    dA = (rot.from_rodrigues(g + h * g_dot) - rot.from_rodrigues(g - h * g_dot)) / (2 * h)
    W = A.T @ dA
    omega_bar = np.array([W[2, 1], W[0, 2], W[1, 0]])
    np.testing.assert_allclose(rot.g_bar(g) @ g_dot, omega_bar, rtol=0, atol=1e-8)
    np.testing.assert_allclose(rot.g_bar_inverse(g) @ rot.g_bar(g), np.eye(3), rtol=0, atol=1e-14)


def test_composition_and_initial_chart():
    ga, gb = rng.normal(size=3) * 0.4, rng.normal(size=3) * 0.4
    np.testing.assert_allclose(rot.from_rodrigues(ga) @ rot.from_rodrigues(gb),
                               rot.from_rodrigues(rot.compose_rodrigues(ga, gb)),
                               rtol=0, atol=1e-14)
    for A in RANDOM.as_matrix():
        A0, g = rot.initial_chart(A)
        assert np.linalg.norm(g) <= 1.0 + 1e-12
        np.testing.assert_allclose(A0 @ rot.from_rodrigues(g), A, rtol=0, atol=1e-14)


def test_user_orientations_are_checked():
    with pytest.raises(mb.ModelError, match="quaternion.*unit norm"):
        rot.as_rotation_matrix((1.0, 0.1, 0.0, 0.0), "body 'b': orientation")
    with pytest.raises(mb.ModelError, match="not a rotation matrix"):
        rot.as_rotation_matrix(np.diag([1.0, 1.0, -1.0]), "body 'b': orientation")
    with pytest.raises(mb.ModelError, match="not a rotation matrix"):
        rot.as_rotation_matrix(np.eye(3) * 1.01, "body 'b': orientation")
    with pytest.raises(mb.ModelError, match="ambiguous"):
        rot.as_rotation_matrix((0.1, 0.2, 0.3), "body 'b': orientation")
    with pytest.raises(mb.ModelError, match="non-zero"):
        rot.axis_angle((0.0, 0.0, 0.0), 1.0)
    q = np.array([0.5, 0.5, 0.5, 0.5])
    np.testing.assert_allclose(rot.as_rotation_matrix(q, "q"), rot.from_quaternion(q))
