"""Joint coordinates against closed forms: the four-bar's joint angles, rates and accelerations
from its loop equations solved by hand (Freudenstein's positions), the slider-crank's slider
travel, a spatial hinge through many turns between coarse outputs (and from its drawn
angle), planar == spatial in the plane, a spherical joint's rotation against its own angular velocity, and body-axes angular
velocities against Euler's torque-free solution."""

from __future__ import annotations

import math

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.joints import Cylindrical, Revolute, RotationDriver, Spherical
from mbd3d.mechanisms import four_bar, slider_crank
from four_bar_loop import four_bar_by_hand
from test_spatial_dynamics import spatial_four_bar_in_plane

def test_four_bar_joint_angles_rates_and_accelerations():
    w2 = 2 * math.pi
    res = mb.inverse_dynamics(four_bar(crank_speed=w2), np.linspace(0.0, 1.0, 13))
    theta2 = math.radians(60.0) + w2 * res.t
    hand = [four_bar_by_hand(angle, w2) for angle in theta2]
    t3 = np.array([h[0][0] for h in hand])
    t4 = np.array([h[0][1] for h in hand])
    w3 = np.array([h[1][0] for h in hand])
    w4 = np.array([h[1][1] for h in hand])
    a3 = np.array([h[2][0] for h in hand])
    a4 = np.array([h[2][1] for h in hand])
    wrap = lambda x: np.angle(np.exp(1j * x))  # noqa: E731 (angles compared modulo turns)
    np.testing.assert_allclose(res.joint("O2").angle, theta2, rtol=0, atol=1e-12)  # counts turns
    np.testing.assert_allclose(res.joint("motor").angle, theta2, rtol=0, atol=1e-12)
    np.testing.assert_allclose(wrap(res.joint("A").angle - (t3 - theta2)), 0.0, rtol=0, atol=1e-10)
    np.testing.assert_allclose(wrap(res.joint("B").angle - (t4 - t3)), 0.0, rtol=0, atol=1e-10)
    np.testing.assert_allclose(wrap(res.joint("O4").angle - t4), 0.0, rtol=0, atol=1e-10)
    np.testing.assert_allclose(res.joint("A").angle_rate, w3 - w2, rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.joint("B").angle_rate, w4 - w3, rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.joint("O4").angle_rate, w4, rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.joint("B").angle_acceleration, a4 - a3, rtol=0, atol=1e-7)
    np.testing.assert_allclose(res.joint("O4").angle_acceleration, a4, rtol=0, atol=1e-7)


def test_slider_travel_rate_and_acceleration():
    """x = r cos(phi) + sqrt(l^2 - r^2 sin^2(phi)) and its derivatives at constant speed."""
    r, l, w = 0.12, 0.26, 2 * math.pi
    res = mb.kinematic_analysis(slider_crank(crank_angle=math.radians(65.0), crank_speed=w),
                                np.linspace(0.0, 1.0, 11))
    phi = math.radians(65.0) + w * res.t
    root = np.sqrt(l * l - (r * np.sin(phi)) ** 2)
    x = r * np.cos(phi) + root
    dx = -r * np.sin(phi) - r * r * np.sin(phi) * np.cos(phi) / root
    ddx = (-r * np.cos(phi) - r * r * np.cos(2 * phi) / root
           - (r * r * np.sin(phi) * np.cos(phi)) ** 2 / root ** 3)
    rail = res.joint("rail")
    np.testing.assert_allclose(rail.displacement, x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(rail.displacement_rate, w * dx, rtol=0, atol=1e-10)
    np.testing.assert_allclose(rail.displacement_acceleration, w * w * ddx, rtol=0, atol=1e-8)
    with pytest.raises(mb.ModelError, match=r"'rail' \(Prismatic\) has no angle: revolute"):
        rail.angle  # noqa: B018


def test_spatial_four_bar_in_the_plane_reads_the_planar_joint_coordinates():
    planar = mb.inverse_dynamics(four_bar(crank_speed=2 * math.pi), np.linspace(0.0, 1.0, 9))
    spatial = mb.inverse_dynamics(spatial_four_bar_in_plane(planar, driven=True), planar.t)
    for joint in ("O2", "O4", "motor"):
        np.testing.assert_allclose(spatial.joint(joint).angle - spatial.joint(joint).angle[0],
                                   planar.joint(joint).angle - planar.joint(joint).angle[0],
                                   rtol=0, atol=1e-10)
        np.testing.assert_allclose(spatial.joint(joint).angle_rate,
                                   planar.joint(joint).angle_rate, rtol=0, atol=1e-9)
        np.testing.assert_allclose(spatial.joint(joint).angle_acceleration,
                                   planar.joint(joint).angle_acceleration, rtol=0, atol=1e-7)


def test_a_spatial_hinge_keeps_count_of_turns_between_coarse_outputs():
    """Ten turns a second on a skew axis, outputs 0.085 s apart (0.85 turn): the angle is the
    driver's motion, turn for turn."""
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -9.81))
    from mbd3d.mechanisms import frame_along
    wheel = b.add_body("wheel", mass=2.0, inertia=(0.02, 0.02, 0.03), position=0.1 * axis,
                       orientation=frame_along(axis))
    pin = b.add(Revolute("axle", b.ground, wheel, at=(0.0, 0.0, 0.0), axis=axis))
    motion = mb.Ramp(0.3, 20 * math.pi) + mb.Harmonic(0.5, 3.0)
    b.add(RotationDriver("motor", pin, motion=motion))
    res = mb.kinematic_analysis(b.build(), np.arange(0.0, 2.0, 0.085))
    expected = np.array([motion.evaluate(t) for t in res.t])
    np.testing.assert_allclose(res.joint("axle").angle, expected[:, 0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.joint("axle").angle_rate, expected[:, 1], rtol=0, atol=1e-8)
    np.testing.assert_allclose(res.joint("axle").angle_acceleration, expected[:, 2],
                               rtol=0, atol=1e-6)


def test_a_hinge_given_its_drawn_angle_reads_it_and_turns_from_it(tmp_path):
    """A wheel on a skew axis drawn at 0.9 rad (its x axis leaning on the axis): it reads
    0.9 + what it turned, a driver of that angle turns it by the motion less 0.9 about the
    axis from the drawing (Rodrigues' rotation composed by SciPy), and a model file keeps it.
    Planar models refuse it (their angle is theta_j - theta_i), naming the joint."""
    from scipy.spatial.transform import Rotation

    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    drawing = Rotation.from_euler("xyz", [0.3, -0.5, 1.1])
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, 0.0))
    wheel = b.add_body("wheel", mass=2.0, inertia=(0.02, 0.03, 0.04), position=0.1 * axis,
                       orientation=drawing.as_matrix())
    pin = b.add(Revolute("axle", b.ground, wheel, at=(0.0, 0.0, 0.0), axis=axis,
                         drawn_angle=0.9))
    motion = mb.Ramp(0.9, 7.0) + mb.Harmonic(0.5, 3.0)
    b.add(RotationDriver("motor", pin, motion=motion))
    model = b.build()
    mb.save(model, tmp_path / "wheel.yaml")
    for built in (model, mb.load(tmp_path / "wheel.yaml")):
        res = mb.kinematic_analysis(built, np.linspace(0.0, 1.5, 7))
        angle = np.array([motion.evaluate(t)[0] for t in res.t])
        np.testing.assert_allclose(res.joint("axle").angle, angle, rtol=0, atol=1e-10)
        turned = [(Rotation.from_rotvec((a - 0.9) * axis) * drawing).as_matrix() for a in angle]
        np.testing.assert_allclose(res.body("wheel").rotation, turned, rtol=0, atol=1e-10)
    with pytest.raises(mb.ModelError, match="'motor' of model .* is not a spatial hinge"):
        model.hinge_directions("motor")
    # a cylindrical joint reads it too
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, 0.0))
    wheel = b.add_body("wheel", mass=2.0, inertia=(0.02, 0.03, 0.04), position=0.1 * axis,
                       orientation=drawing.as_matrix())
    b.add(Cylindrical("axle", b.ground, wheel, at=(0.0, 0.0, 0.0), axis=axis, drawn_angle=-2.5))
    res = mb.forward_dynamics(b.build(), [0.0, 1.0], initial_rates={"axle.angle": 0.5},
                              method="DOP853", rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res.joint("axle").angle, [-2.5, -2.0], rtol=0, atol=1e-9)
    flat = mb.ModelBuilder(dim=2)
    crank = flat.add_body("crank", mass=1.0, inertia=0.01, position=(0.1, 0.0))
    flat.add(Revolute("O", flat.ground, crank, at=(0.0, 0.0), drawn_angle=0.9))
    with pytest.raises(mb.ModelError, match="joint 'O': drawn_angle is for spatial hinges"):
        flat.build()


def test_a_ball_joints_rotation_follows_its_relative_angular_velocity():
    """dR/dt = w~ R (w the relative angular velocity in body i's axes), by central differences
    of the reported rotations; and the rotation vector's length is the rotation's angle."""
    planar = mb.inverse_dynamics(four_bar(crank_speed=2 * math.pi), np.linspace(0.0, 1.0, 3))
    model = spatial_four_bar_in_plane(planar, driven=True)
    h = 1e-5
    t = np.array([0.3 - h, 0.3, 0.3 + h, 0.71 - h, 0.71, 0.71 + h])
    res = mb.kinematic_analysis(model, t)
    joint = res.joint("B")  # a ball between coupler and rocker
    R, w = joint.relative_rotation, joint.relative_angular_velocity
    for k in (1, 4):
        rate = (R[k + 1] - R[k - 1]) / (2 * h)
        skew = np.array([[0, -w[k, 2], w[k, 1]], [w[k, 2], 0, -w[k, 0]],
                         [-w[k, 1], w[k, 0], 0]])
        np.testing.assert_allclose(rate, skew @ R[k], rtol=0, atol=1e-7)
    angle = np.arccos(np.clip((np.trace(R, axis1=1, axis2=2) - 1) / 2, -1, 1))
    np.testing.assert_allclose(np.linalg.norm(joint.rotation_vector, axis=1), angle,
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(joint.relative_quaternion, axis=1), 1.0)


def test_body_axes_angular_velocity_of_a_free_symmetric_body():
    """Torque-free, I1 = I2: omega_bar_3 stays, (omega_bar_1, omega_bar_2) turns at
    lambda = (I3 - I1) / I1 omega_bar_3 (Euler's equations solved by hand)."""
    I1, I3 = 0.02, 0.035
    w0 = np.array([1.5, 0.0, 7.0])  # global = body axes at t = 0 (aligned)
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, 0.0))
    b.add_body("disc", mass=1.0, inertia=(I1, I1, I3), position=(0.0, 0.0, 0.0),
               angular_velocity=w0)
    res = mb.forward_dynamics(b.build(), np.linspace(0.0, 3.0, 31), method="DOP853",
                              rtol=1e-12, atol=1e-12)
    body = res.body("disc")
    lam = (I3 - I1) / I1 * w0[2]
    expected = np.column_stack([w0[0] * np.cos(lam * res.t), w0[0] * np.sin(lam * res.t),
                                np.full(len(res.t), w0[2])])
    np.testing.assert_allclose(body.angular_velocity_body, expected, rtol=0, atol=1e-8)
    rate = np.column_stack([-lam * expected[:, 1], lam * expected[:, 0], 0 * res.t])
    np.testing.assert_allclose(body.angular_acceleration_body, rate, rtol=0, atol=1e-7)
    # in global axes the angular momentum is constant instead
    momentum = np.einsum("kab,b,kb->ka", body.rotation, np.array([I1, I1, I3]),
                         body.angular_velocity_body)
    np.testing.assert_allclose(momentum, np.broadcast_to(momentum[0], momentum.shape),
                               rtol=0, atol=1e-9)


def test_a_spherical_pendulums_rotation_is_its_bodys():
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -9.81))
    bob = b.add_body("bob", mass=1.0, inertia=(0.01, 0.01, 0.01), position=(0.5, 0.0, 0.0),
                     velocity=(0.0, 1.0, 0.0), angular_velocity=(0.0, 0.0, 2.0))
    b.add(Spherical("ball", b.ground, bob, at=(0.0, 0.0, 0.0)))
    res = mb.forward_dynamics(b.build(), np.linspace(0.0, 1.0, 11), method="DOP853",
                              rtol=1e-10, atol=1e-12)
    joint, body = res.joint("ball"), res.body("bob")
    np.testing.assert_allclose(joint.relative_rotation, body.rotation, rtol=0, atol=1e-12)
    np.testing.assert_allclose(joint.relative_angular_velocity, body.angular_velocity,
                               rtol=0, atol=1e-12)


def test_a_cardan_shafts_cross_angles_and_its_output_shaft():
    """Input shaft along x turning at w, output shaft bent by b in the x-z plane, a universal
    joint between them. By hand: the cross carries a_i = R_x(theta1) e_y and a_j, normal to a_i
    and to the output axis d, so a_j is along a_i x d; the output shaft turns by theta2 about d
    with tan(theta2) = tan(theta1) cos(b): the classic Cardan relation, for the input yoke
    normal to the plane of the shafts at theta1 = 0 (tan(theta2) = tan(theta1) / cos(b) counts
    both angles from the yoke in that plane, a quarter turn on)."""
    from mbd3d.joints import PointOnLine, Universal
    bend, w = math.radians(30.0), 2 * math.pi
    d = np.array([math.cos(bend), 0.0, math.sin(bend)])
    e_y = np.array([0.0, 1.0, 0.0])
    a_j0 = np.cross(e_y, d)
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, 0.0))
    shaft_in = b.add_body("in", mass=1.0, inertia=(0.001, 0.01, 0.01), position=(-0.2, 0, 0))
    out_frame = mb.rotations.frame_along(d)
    shaft_out = b.add_body("out", mass=1.0, inertia=(0.001, 0.01, 0.01), position=0.2 * d,
                           orientation=out_frame)
    bearing = b.add(Revolute("bearing", b.ground, shaft_in, at=(-0.2, 0.0, 0.0),
                             axis=(1.0, 0.0, 0.0)))
    b.add(Universal("cross", shaft_in, shaft_out, at=(0.0, 0.0, 0.0), axis_i=e_y, axis_j=a_j0))
    b.add(PointOnLine("sleeve", b.ground, shaft_out, at=0.4 * d, axis=d))
    b.add(RotationDriver("motor", bearing, motion=mb.Ramp(0.0, w)))
    res = mb.kinematic_analysis(b.build(), np.linspace(0.0, 1.0, 17))
    joint = res.joint("cross")

    theta1 = w * res.t
    expected_alpha, expected_theta2 = [], []
    previous = a_j0
    for angle in theta1:
        c, s = math.cos(angle), math.sin(angle)
        a_i = np.array([0.0, c, s])
        a_j = np.cross(a_i, d)
        a_j /= np.linalg.norm(a_j)
        a_j = a_j if a_j @ previous >= 0 else -a_j  # the cross turns continuously
        previous = a_j
        R1 = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
        seen = R1.T @ a_j  # a_j in the input shaft's axes turns about e_y by alpha
        expected_alpha.append(math.atan2(np.cross(a_j0, seen) @ e_y, seen @ a_j0))
        expected_theta2.append(math.atan2(np.cross(a_j0, a_j) @ d, a_j @ a_j0))
    wrap = lambda x: np.angle(np.exp(1j * np.asarray(x)))  # noqa: E731
    np.testing.assert_allclose(wrap(joint.cross_angles[:, 0] - expected_alpha), 0.0,
                               rtol=0, atol=1e-10)
    # the output shaft's turn, from its rotation, against the Cardan relation
    R_out = res.body("out").rotation
    turned = np.einsum("kab,cb->kac", R_out, out_frame)  # Rot(d, theta2)
    theta2 = np.arctan2(np.einsum("a,kab,b->k", np.cross(d, a_j0) / np.linalg.norm(a_j0),
                                  turned, a_j0), np.einsum("a,kab,b->k", a_j0, turned, a_j0))
    np.testing.assert_allclose(wrap(theta2 - np.array(expected_theta2)), 0.0, rtol=0, atol=1e-10)
    np.testing.assert_allclose(np.tan(theta2[[1, 2, 5]]),
                               np.tan(theta1[[1, 2, 5]]) * math.cos(bend), rtol=1e-9)
    # beta: body j (the output shaft) turns about a_j relative to the cross; with the input
    # turning and the output following, the two cross angles and the shafts' turns close up
    rates = joint.cross_angle_rates
    relative = res.body("out").angular_velocity - res.body("in").angular_velocity
    a_i_now = np.einsum("kab,b->ka", res.body("in").rotation, e_y)
    a_j_now = np.einsum("kab,b->ka", R_out, out_frame.T @ a_j0)
    np.testing.assert_allclose(rates[:, :1] * a_i_now + rates[:, 1:] * a_j_now, relative,
                               rtol=0, atol=1e-9)
    # rates and accelerations are the angles' derivatives (central differences, h = 1e-5)
    h = 1e-5
    fine = mb.kinematic_analysis(b.build(), [0.3 - h, 0.3, 0.3 + h]).joint("cross")
    np.testing.assert_allclose((fine.cross_angles[2] - fine.cross_angles[0]) / (2 * h),
                               fine.cross_angle_rates[1], rtol=1e-7)
    np.testing.assert_allclose((fine.cross_angle_rates[2] - fine.cross_angle_rates[0]) / (2 * h),
                               fine.cross_angle_accelerations[1], rtol=1e-6)


def test_a_puck_on_a_tilted_plane_moves_uniformly_in_the_planes_coordinates():
    """No gravity, a Planar joint on a plane of normal n through the origin: the puck glides at
    its initial in-plane velocity and spins at its initial rate (Newton's first law), so its
    plane coordinates are s0 + (e . v) t along the joint's in-plane axes e, and its angle
    w t."""
    from mbd3d.joints import Planar
    n = np.array([0.0, 0.6, 0.8])
    in_plane = np.array([1.0, 0.0, 0.0])
    v = 0.3 * in_plane + 0.2 * np.cross(n, in_plane)
    spin = 1.7
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, 0.0))
    puck = b.add_body("puck", mass=0.5, inertia=(0.002, 0.002, 0.003), position=(0.0, 0, 0),
                      orientation=mb.rotations.frame_along(in_plane, hint=n), velocity=v,
                      angular_velocity=spin * n)
    b.add(Planar("table", b.ground, puck, at=(0.0, 0.0, 0.0), axis=n))
    model = b.build()
    res = mb.forward_dynamics(model, np.linspace(0.0, 2.0, 9), method="DOP853", rtol=1e-11,
                              atol=1e-12, strict=True)
    joint = res.joint("table")
    axes = model.reaction_frame("table")[2]  # body i is the ground: these are global
    e = axes[:, 1:].T  # the joint's point on the puck is its centre (drawn at the origin)
    np.testing.assert_allclose(joint.plane_position, np.outer(res.t, e @ v), rtol=0, atol=1e-9)
    np.testing.assert_allclose(joint.plane_velocity, np.broadcast_to(e @ v, (9, 2)),
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(joint.plane_acceleration, 0.0, rtol=0, atol=1e-8)
    np.testing.assert_allclose(joint.angle - joint.angle[0], spin * res.t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(joint.angle_rate, spin, rtol=0, atol=1e-9)
