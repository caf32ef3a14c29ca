"""Quaternions keep their sign along the motion whatever output grid is asked for: the
charts' quaternions are carried through every chart reset of the integration, so outputs
seconds apart, with many turns between them, give the same quaternion as the dense path."""

from __future__ import annotations

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.joints import Revolute, RotationDriver


def tumbler() -> mb.Model:
    """A free brick spinning about its middle axis (it flips every few seconds)."""
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, 0.0), name="tumbler")
    b.add_body("brick", mass=1.0, inertia=np.diag([1.0, 2.0, 3.0]), position=(0.0, 0.0, 0.0),
               angular_velocity=(0.02, 3.0, 0.01))
    return b.build()


def assert_same_path(sparse: np.ndarray, dense: np.ndarray, atol: float) -> None:
    """Equal with their signs: a sign error would be a distance of about 2."""
    np.testing.assert_allclose(sparse, dense, rtol=0, atol=atol)


@pytest.mark.parametrize("options, atol", [
    (dict(method="DOP853", rtol=1e-10, atol=1e-12), 1e-6),
    (dict(method="generalized-alpha", step=2e-3), 0.05),
], ids=["DOP853", "generalized-alpha"])
def test_sparse_outputs_of_a_tumbling_body_follow_the_dense_path(options, atol):
    dense_t = np.linspace(0.0, 20.0, 4001)
    dense = mb.forward_dynamics(tumbler(), dense_t, **options).body("brick").quaternion
    # the dense path is continuous: no step between neighbours near a sign flip
    assert np.all(np.einsum("ki,ki->k", dense[1:], dense[:-1]) > 0.9)
    sparse_t = np.array([0.0, 5.0, 10.0, 20.0])
    sparse = mb.forward_dynamics(tumbler(), sparse_t, **options).body("brick").quaternion
    assert_same_path(sparse, dense[np.searchsorted(dense_t, sparse_t)], atol)


def test_kinematics_of_a_fast_hinge_keeps_the_quaternion_path():
    """A wheel at 10 turns a second sampled every 0.037 s: kinematic analysis sees only its
    samples, so it follows the turn between them the short way (less than half a turn)."""
    b = mb.ModelBuilder(dim=3, name="wheel")
    wheel = b.add_body("wheel", mass=1.0, inertia=np.eye(3) * 0.1, position=(0.0, 0.0, 0.0))
    hinge = b.add(Revolute("hinge", b.ground, wheel, at=(0.0, 0.0, 0.0), axis=(1.0, 1.0, 0.0)))
    b.add(RotationDriver("motor", hinge, motion=mb.Ramp(0.0, 20 * np.pi)))
    model = b.build()
    t = np.arange(0, 40) * 0.037
    q = mb.kinematic_analysis(model, t).body("wheel").quaternion
    # by hand: a turn of phi about the unit axis n is (cos(phi/2), sin(phi/2) n), continuous
    phi = 20 * np.pi * t
    n = np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0)
    expected = np.column_stack([np.cos(phi / 2), np.sin(phi / 2)[:, None] * n])
    np.testing.assert_allclose(q, expected, rtol=0, atol=1e-9)
