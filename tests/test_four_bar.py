"""Four-bar kinematics against Freudenstein's equation; motor torque against the power balance."""

from __future__ import annotations

import math

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.mechanisms import four_bar

a, b, c, d = 0.10, 0.35, 0.30, 0.30  # crank, coupler, rocker, ground
OMEGA = 2 * math.pi


def freudenstein(theta2: np.ndarray, branch: int) -> np.ndarray:
    """Rocker angle theta4 (Norton, Design of Machinery, eq. 4.10): A t^2 + B t + C = 0 in
    t = tan(theta4 / 2)."""
    K1, K2, K3 = d / a, d / c, (a * a - b * b + c * c + d * d) / (2 * a * c)
    A = np.cos(theta2) - K1 - K2 * np.cos(theta2) + K3
    B = -2 * np.sin(theta2)
    C = K1 - (K2 + 1) * np.cos(theta2) + K3
    return 2 * np.arctan2(-B + branch * np.sqrt(B * B - 4 * A * C), 2 * A)


@pytest.fixture(scope="module")
def result():
    model = four_bar(crank_length=a, coupler_length=b, rocker_length=c, ground_length=d,
                     crank_angle=math.radians(60.0), crank_speed=OMEGA)
    return mb.inverse_dynamics(model, np.linspace(0.0, 1.0, 121))


def test_rocker_angle_matches_freudenstein_on_one_branch(result):
    theta2 = math.radians(60.0) + OMEGA * result.t
    rocker = np.angle(np.exp(1j * result.body("rocker").angle))
    branches = [np.angle(np.exp(1j * freudenstein(theta2, s))) for s in (-1, 1)]
    errors = [np.max(np.abs(np.angle(np.exp(1j * (rocker - br))))) for br in branches]
    # the whole cycle stays on the branch it was assembled on
    assert min(errors) < 1e-10


def test_angular_velocities_match_loop_closure(result):
    theta2 = math.radians(60.0) + OMEGA * result.t
    theta3 = result.body("coupler").angle
    theta4 = result.body("rocker").angle
    # Norton eq. 6.18: omega3 = a w2 sin(t4 - t2) / (b sin(t3 - t4)),
    #                  omega4 = a w2 sin(t2 - t3) / (c sin(t4 - t3))
    w3 = a * OMEGA * np.sin(theta4 - theta2) / (b * np.sin(theta3 - theta4))
    w4 = a * OMEGA * np.sin(theta2 - theta3) / (c * np.sin(theta4 - theta3))
    np.testing.assert_allclose(result.body("coupler").angular_velocity, w3, rtol=0, atol=1e-10)
    np.testing.assert_allclose(result.body("rocker").angular_velocity, w4, rtol=0, atol=1e-10)


def test_motor_power_equals_rate_of_energy(result):
    model = result.model
    power = result.driver("motor").effort * OMEGA
    rate = np.zeros(len(result.t))
    for body in model.bodies:
        h = result.body(body.name)
        rate += body.mass * np.einsum("kd,kd->k", h.velocity, h.acceleration)
        rate += body.inertia * h.angular_velocity * h.angular_acceleration
        rate += body.mass * 9.81 * h.velocity[:, 1]  # d/dt of the potential energy
    np.testing.assert_allclose(power, rate, rtol=0, atol=1e-10)
