"""Spatial bodies in motion, against oracles independent of mbd3d: an integration of Euler's
equations in quaternions (numpy-quaternion), closed forms (steady precession), conservation
laws, and the planar models for mechanisms whose spatial model is restricted to the plane."""

from __future__ import annotations

import math

import numpy as np
import quaternion
import pytest
import quaternion as npq
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

import mbd3d as mb
from mbd3d.model import constraints
from mbd3d.model.equations import generalized_forces, mass_matrix
from mbd3d.mechanisms import pendulum_chain, slider_crank, slider_crank_positions, spatial_four_bar
from mbd3d.joints import Prismatic, Revolute, Spherical, Universal

G = 9.81


def euler_quaternion_reference(J, omega_bar0, A0, t, rtol=1e-13, atol=1e-13):
    """Orientation and body angular velocity of a torque-free body: Euler's equations and
    q' = q (0, omega_bar) / 2, integrated by SciPy; rotations through numpy-quaternion."""
    J_inv = np.linalg.inv(J)

    def rhs(_, y):
        q = npq.from_float_array(y[:4])
        w = y[4:]
        q_dot = 0.5 * q * npq.quaternion(0.0, *w)
        return np.concatenate([npq.as_float_array(q_dot), J_inv @ -np.cross(w, J @ w)])

    q0 = npq.as_float_array(npq.from_rotation_matrix(A0))
    sol = solve_ivp(rhs, (t[0], t[-1]), np.concatenate([q0, omega_bar0]), t_eval=t,
                    method="DOP853", rtol=rtol, atol=atol)
    quats = npq.from_float_array(sol.y[:4].T)
    return npq.as_rotation_matrix(quats), sol.y[4:].T


def test_dzhanibekov_flip_across_many_half_turns():
    """Intermediate-axis spin (the Dzhanibekov flip): I = (1, 2, 3), omega_bar(0) =
    (1e-3, 1, 0); omega_2 flips sign at T/4 = 14.3657 s."""
    J = np.diag([1.0, 2.0, 3.0])
    omega_bar0 = np.array([1e-3, 1.0, 0.0])
    A0 = Rotation.from_rotvec([2.5, -0.4, 1.1]).as_matrix()  # starts beyond 90 degrees
    b = mb.ModelBuilder(dim=3)
    b.add_body("body", mass=2.0, inertia=J, position=(0.0, 0.0, 0.0), orientation=A0,
               velocity=(0.1, 0.0, -0.2), angular_velocity=A0 @ omega_bar0)
    t = np.linspace(0.0, 30.0, 61)
    res = mb.forward_dynamics(b.build(), t, method="DOP853", rtol=1e-12, atol=1e-12)
    body = res.body("body")
    A_ref, w_ref = euler_quaternion_reference(J, omega_bar0, A0, t)
    np.testing.assert_allclose(body.rotation, A_ref, rtol=0, atol=1e-8)
    omega_bar = np.einsum("kji,kj->ki", body.rotation, body.angular_velocity)
    np.testing.assert_allclose(omega_bar, w_ref, rtol=0, atol=1e-8)
    assert omega_bar[t == 10.0, 1] > 0.9 and omega_bar[t == 20.0, 1] < -0.9  # the flip
    energy = 0.5 * np.einsum("ki,ij,kj->k", omega_bar, J, omega_bar)
    momentum = np.einsum("kij,jl,kl->ki", body.rotation, J, omega_bar)
    assert np.max(np.abs(energy / energy[0] - 1)) < 1e-9
    assert np.max(np.linalg.norm(momentum - momentum[0], axis=1)) < 1e-9 * np.linalg.norm(momentum[0])
    np.testing.assert_allclose(body.position, np.outer(t, (0.1, 0.0, -0.2)), rtol=0, atol=1e-10)
    assert res.stats["chart_resets"] >= 10  # the half-turn singularity was passed many times
    # the quaternion is reported continuously through every chart reset
    quat = body.quaternion
    assert np.min(np.einsum("ki,ki->k", quat[1:], quat[:-1])) > 0.5
    # as numpy-quaternion objects: the rotation from the start to each time, by quaternion
    # algebra, is the matrix product of the reference's rotations
    relative = body.orientation[0].conj() * body.orientation
    np.testing.assert_allclose(quaternion.as_rotation_matrix(relative),
                               np.einsum("ji,kjl->kil", A_ref[0], A_ref), rtol=0, atol=1e-8)


def test_a_tolerance_buys_the_same_accuracy_as_a_quaternion_integration():
    """A body tumbling through the intermediate-axis flip (I = 1, 2, 3; omega_bar(0) =
    (0.01, 3, 0)) for 20 s, a chart reset at every step. The integrator carries the body's
    angular velocity, not the rates of its Rodrigues parameters, and measures the error of g
    as the orientation error it is: at rtol 1e-10 the rotation is as accurate as Euler's
    equations with a quaternion integrated by the same method at that rtol (carrying the
    rates of g it was 6e-6 rad, 2400 times worse), and over a range of tolerances."""
    J = np.diag([1.0, 2.0, 3.0])
    omega_bar0 = np.array([0.01, 3.0, 0.0])
    b = mb.ModelBuilder(dim=3)
    b.add_body("body", mass=1.0, inertia=J, position=(0.0, 0.0, 0.0),
               angular_velocity=omega_bar0)
    model = b.build()
    t = np.linspace(0.0, 20.0, 41)
    A_ref, _ = euler_quaternion_reference(J, omega_bar0, np.eye(3), t)

    def largest_angle(A):
        return np.max(Rotation.from_matrix(np.einsum("kji,kjl->kil", A_ref, A)).magnitude())

    for rtol in (1e-6, 1e-8, 1e-10):
        res = mb.forward_dynamics(model, t, method="DOP853", rtol=rtol, atol=rtol)
        A_quaternion, _ = euler_quaternion_reference(J, omega_bar0, np.eye(3), t, rtol, rtol)
        assert res.stats["chart_resets"] > 20
        assert largest_angle(res.body("body").rotation) < 1.5 * largest_angle(A_quaternion)


def test_heavy_top_steady_precession():
    """Cone of Kinon-Betsch: the symmetry axis keeps its nutation
    angle and precesses at omega_p when spun at omega_s = m g l/(C omega_p) + (A - C)/C
    omega_p cos(alpha0)."""
    m, J1, J3, l = 0.706858347, 5.30143760e-4, 5.30143760e-4, 0.075
    alpha0, omega_p = math.pi / 3, 10.0
    A, C = J1 + m * l * l, J3
    omega_s = m * G * l / (C * omega_p) + (A - C) / C * omega_p * math.cos(alpha0)
    tilt = Rotation.from_rotvec([0.0, alpha0, 0.0]).as_matrix()
    d3 = tilt[:, 2]
    omega = omega_p * np.array([0.0, 0.0, 1.0]) + omega_s * d3
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G))
    top = b.add_body("top", mass=m, inertia=np.diag([J1, J1, J3]), position=l * d3,
                     orientation=tilt, velocity=np.cross(omega, l * d3), angular_velocity=omega)
    b.add(Spherical("tip", b.ground, top, at=(0.0, 0.0, 0.0)))
    t = np.linspace(0.0, 1.0, 21)
    res = mb.forward_dynamics(b.build(), t, method="DOP853", rtol=1e-12, atol=1e-12)
    axis = res.body("top").rotation[:, :, 2]
    np.testing.assert_allclose(np.arccos(axis[:, 2]), alpha0, rtol=0, atol=1e-8)
    azimuth = np.unwrap(np.arctan2(axis[:, 1], axis[:, 0]))
    np.testing.assert_allclose(azimuth, omega_p * t, rtol=0, atol=1e-8)
    # the tip carries the weight plus the centripetal force of the precessing centre of mass
    radius = l * math.sin(alpha0)
    force = res.joint("tip").reaction(on="top").force
    np.testing.assert_allclose(force[:, 2], m * G, rtol=0, atol=1e-7)
    np.testing.assert_allclose(np.linalg.norm(force[:, :2], axis=1), m * omega_p**2 * radius,
                               rtol=1e-7)


def test_spherical_pendulum_conserves_energy_and_vertical_momentum():
    m, L = 1.3, 0.9
    J = np.diag([0.01, 0.02, 0.015])
    start = np.array([L * math.sin(1.0), 0.0, -L * math.cos(1.0)])
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G))
    bob = b.add_body("bob", mass=m, inertia=J, position=start, velocity=(0.0, 2.5, 0.0),
                     angular_velocity=(0.3, -0.2, 1.0))
    b.add(Spherical("pivot", b.ground, bob, point_i=(0.0, 0.0, 0.0), point_j=-start))
    t = np.linspace(0.0, 3.0, 31)
    res = mb.forward_dynamics(b.build(), t, method="DOP853", rtol=1e-12, atol=1e-12)
    h = res.body("bob")
    energy = res.kinetic_energy + res.potential_energy
    assert np.max(np.abs(energy - energy[0])) < 1e-9 * np.max(np.abs(res.kinetic_energy))
    spin = np.einsum("kij,jl,kml,km->ki", h.rotation, J, h.rotation, h.angular_velocity)
    vertical = m * np.cross(h.position, h.velocity)[:, 2] + spin[:, 2]
    np.testing.assert_allclose(vertical, vertical[0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(h.position, axis=1), L, rtol=0, atol=1e-9)


def spatial_double_pendulum():
    b = mb.ModelBuilder(dim=3, gravity=(0.0, -G, 0.0))
    previous = b.ground
    for k in range(2):
        body = b.add_body(f"link{k + 1}", mass=1.0, inertia=np.diag([0.01, 1 / 12, 1 / 12]),
                          position=(k + 0.5, 0.0, 0.0))
        b.add(Revolute(f"pin{k + 1}", previous, body, axis=(0.0, 0.0, 1.0),
                       point_i=(0.0, 0.0, 0.0) if k == 0 else (0.5, 0.0, 0.0),
                       point_j=(-0.5, 0.0, 0.0)))
        previous = body
    return b.build()


def test_planar_restricted_double_pendulum_reproduces_the_planar_model():
    t = np.linspace(0.0, 2.0, 41)
    planar = mb.forward_dynamics(pendulum_chain(2), t, method="DOP853", rtol=1e-12, atol=1e-12)
    spatial = mb.forward_dynamics(spatial_double_pendulum(), t, method="DOP853", rtol=1e-12,
                                  atol=1e-12)
    assert spatial.stats["chart_resets"] > 0
    for name in ("link1", "link2"):
        p, s = planar.body(name), spatial.body(name)
        angle = np.unwrap(np.arctan2(s.rotation[:, 1, 0], s.rotation[:, 0, 0]))
        np.testing.assert_allclose(angle, p.angle, rtol=0, atol=1e-8)
        np.testing.assert_allclose(s.position[:, :2], p.position, rtol=0, atol=1e-8)
        np.testing.assert_allclose(s.position[:, 2], 0.0, rtol=0, atol=1e-12)
        np.testing.assert_allclose(s.angular_velocity[:, 2], p.angular_velocity, rtol=0, atol=1e-7)
    for pin in ("pin1", "pin2"):
        fp = planar.joint(pin).reaction(on="link1" if pin == "pin1" else "link2").force
        fs = spatial.joint(pin).reaction(on="link1" if pin == "pin1" else "link2").force
        np.testing.assert_allclose(fs[:, :2], fp, rtol=0, atol=1e-6)
        np.testing.assert_allclose(fs[:, 2], 0.0, rtol=0, atol=1e-9)
        np.testing.assert_allclose(spatial.joint(pin).lam[:, :2], planar.joint(pin).lam,
                                   rtol=0, atol=1e-6)


def test_planar_restricted_slider_crank_reproduces_the_planar_model():
    phi0, L1, L2 = math.radians(65.0), 0.12, 0.26
    a, psi, b_point = slider_crank_positions(phi0, L1, L2)
    b = mb.ModelBuilder(dim=3, gravity=(0.0, -G, 0.0))
    rz = lambda angle: Rotation.from_rotvec([0.0, 0.0, angle]).as_matrix()  # noqa: E731
    flat = lambda inertia: np.diag([inertia, inertia, inertia])  # noqa: E731
    crank = b.add_body("crank", mass=1.0, inertia=flat(0.001), position=(*a / 2, 0.0),
                       orientation=rz(phi0))
    rod = b.add_body("rod", mass=2.0, inertia=flat(0.01), position=(*(a + b_point) / 2, 0.0),
                     orientation=rz(psi))
    slider = b.add_body("slider", mass=4.0, inertia=flat(0.02), position=(*b_point, 0.0))
    z = (0.0, 0.0, 1.0)
    b.add(Revolute("O", b.ground, crank, at=(0.0, 0.0, 0.0), axis=z))
    # a planar loop of spatial revolutes would be overconstrained: a universal and a ball
    # joint close it with exactly one degree of freedom
    b.add(Universal("A", crank, rod, at=(*a, 0.0), axis_i=z,
                    axis_j=(-math.sin(psi), math.cos(psi), 0.0)))
    b.add(Spherical("B", rod, slider, at=(*b_point, 0.0)))
    b.add(Prismatic("rail", b.ground, slider, axis=(1.0, 0.0, 0.0)))
    b.add(mb.Torque("torque", crank, (0.0, 0.0, 2.0)))
    model = b.build()
    report = mb.mobility(model)
    assert (report.dof, report.redundant) == (1, 0)
    t = np.linspace(0.0, 1.0, 21)
    spatial = mb.forward_dynamics(model, t, method="DOP853", rtol=1e-12, atol=1e-12)
    planar = mb.forward_dynamics(slider_crank(crank_speed=None, crank_torque=2.0), t,
                                 method="DOP853", rtol=1e-12, atol=1e-12)
    crank_s = spatial.body("crank")
    angle = np.unwrap(np.arctan2(crank_s.rotation[:, 1, 0], crank_s.rotation[:, 0, 0]))
    np.testing.assert_allclose(angle, planar.body("crank").angle, rtol=0, atol=1e-8)
    np.testing.assert_allclose(spatial.body("slider").position[:, 0],
                               planar.body("slider").position[:, 0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(spatial.joint("O").reaction(on="crank").force[:, :2],
                               planar.joint("O").reaction(on="crank").force, rtol=0, atol=1e-6)


def test_spatial_torsion_spring_about_a_skew_axis():
    J_axis, k, w0 = 0.05, 3.0, 2.0
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    frame = Rotation.align_vectors([axis], [[0.0, 0.0, 1.0]])[0].as_matrix()  # body z = axis
    b = mb.ModelBuilder(dim=3)
    disc = b.add_body("disc", mass=1.0, inertia=(0.03, 0.04, J_axis), position=(0, 0, 0),
                      orientation=frame, angular_velocity=w0 * axis)
    hinge = b.add(Revolute("axle", b.ground, disc, at=(0.0, 0.0, 0.0), axis=axis))
    b.add(mb.RotationalSpringDamper("torsion", joint=hinge, stiffness=k))
    t = np.linspace(0.0, 1.0, 21)
    # few, long steps: the integrator tolerance must be below the 1e-9 checked
    res = mb.forward_dynamics(b.build(), t, method="DOP853", rtol=1e-12, atol=1e-13)
    wn = math.sqrt(k / J_axis)
    np.testing.assert_allclose(res.body("disc").angular_velocity @ axis, w0 * np.cos(wn * t),
                               rtol=0, atol=1e-8)
    energy = res.kinetic_energy + res.potential_energy
    np.testing.assert_allclose(energy, 0.5 * J_axis * w0**2, rtol=1e-9)


def test_torque_in_body_axes_turns_with_the_body():
    J3, T = 0.2, 0.7
    A0 = Rotation.from_rotvec([0.4, -1.0, 0.3]).as_matrix()
    b = mb.ModelBuilder(dim=3)
    body = b.add_body("rotor", mass=1.0, inertia=(0.1, 0.1, J3), position=(0, 0, 0),
                      orientation=A0)
    b.add(mb.Torque("motor", body, (0.0, 0.0, T), frame="body"))
    t = np.linspace(0.0, 2.0, 11)
    res = mb.forward_dynamics(b.build(), t, method="DOP853", rtol=1e-11, atol=1e-12)
    rotor = res.body("rotor")
    np.testing.assert_allclose(rotor.angular_velocity, np.outer(T / J3 * t, A0[:, 2]),
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(rotor.rotation[:, :, 2], np.tile(A0[:, 2], (11, 1)),
                               rtol=0, atol=1e-9)


def spatial_four_bar_in_plane(planar: mb.Results, driven: bool, torque: float = 0.0,
                              revolutes_only: bool = False) -> mb.Model:
    """The four-bar of mbd3d.mechanisms.four_bar rebuilt with spatial bodies, hinges along z and
    a universal and a ball joint on the coupler, or (``revolutes_only``) four revolutes: then
    3 of the 21 equations are redundant. The drawing is read from the planar results at t = 0."""
    from mbd3d.joints import RotationDriver
    planar_model = planar.model
    o2, o4 = np.zeros(2), np.array([0.30, 0.0])
    a = planar.point("crank", (0.05, 0.0)).position[0]
    b_point = planar.point("rocker", (0.15, 0.0)).position[0]
    z = (0.0, 0.0, 1.0)
    b = mb.ModelBuilder(dim=3, gravity=(0.0, -G, 0.0))
    bodies = {}
    for body in planar_model.bodies:
        bodies[body.name] = b.add_body(
            body.name, mass=body.mass, inertia=(body.inertia,) * 3,
            position=(*planar.body(body.name).position[0], 0.0),
            orientation=Rotation.from_rotvec([0.0, 0.0, planar.body(body.name).angle[0]]).as_matrix())
    coupler_dir = np.r_[(b_point - a) / np.linalg.norm(b_point - a), 0.0]
    o2_pin = b.add(Revolute("O2", b.ground, bodies["crank"], at=(*o2, 0.0), axis=z))
    if revolutes_only:
        b.add(Revolute("A", bodies["crank"], bodies["coupler"], at=(*a, 0.0), axis=z))
        b.add(Revolute("B", bodies["coupler"], bodies["rocker"], at=(*b_point, 0.0), axis=z))
    else:
        b.add(Universal("A", bodies["crank"], bodies["coupler"], at=(*a, 0.0), axis_i=z,
                        axis_j=np.cross(coupler_dir, z)))
        b.add(Spherical("B", bodies["coupler"], bodies["rocker"], at=(*b_point, 0.0)))
    b.add(Revolute("O4", b.ground, bodies["rocker"], at=(*o4, 0.0), axis=z))
    if driven:
        b.add(RotationDriver("motor", o2_pin, motion=mb.Ramp(math.radians(60.0), 2 * math.pi)))
    else:
        b.add(mb.Torque("torque", bodies["crank"], (0.0, 0.0, torque)))
    return b.build()


def test_planar_restricted_four_bar_reproduces_the_planar_model():
    from mbd3d.mechanisms import four_bar
    planar = mb.inverse_dynamics(four_bar(crank_speed=2 * math.pi), np.linspace(0.0, 1.0, 25))
    spatial = mb.inverse_dynamics(spatial_four_bar_in_plane(planar, driven=True), planar.t)
    for name in ("crank", "coupler", "rocker"):
        rot = spatial.body(name).rotation
        angle = np.unwrap(np.arctan2(rot[:, 1, 0], rot[:, 0, 0]))
        np.testing.assert_allclose(angle, planar.body(name).angle, rtol=0, atol=1e-10)
        np.testing.assert_allclose(spatial.body(name).position[:, :2], planar.body(name).position,
                                   rtol=0, atol=1e-12)
    np.testing.assert_allclose(spatial.driver("motor").effort, planar.driver("motor").effort,
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(spatial.joint("O4").reaction(on="rocker").force[:, :2],
                               planar.joint("O4").reaction(on="rocker").force, rtol=0, atol=1e-9)


def test_four_revolute_four_bar_is_redundant_and_still_analysed():
    """A planar four-bar of four spatial revolutes: Gruebler -2 (21 equations, 18 coordinates)
    but one driven degree of freedom. Kinematics and inverse dynamics run on the redundant
    rows and reproduce the planar model; the in-plane reactions and the motor torque are
    unique and equal the planar ones, the out-of-plane ones are the minimum-norm share."""
    from mbd3d.mechanisms import four_bar
    planar = mb.inverse_dynamics(four_bar(crank_speed=2 * math.pi), np.linspace(0.0, 1.0, 25))
    model = spatial_four_bar_in_plane(planar, driven=True, revolutes_only=True)
    report = mb.mobility(model)
    assert (report.gruebler, report.rank, report.dof, report.redundant) == (-3, 18, 0, 3)
    spatial = mb.inverse_dynamics(model, planar.t)
    assert not spatial.reactions_unique and spatial.status == "complete"
    for name in ("crank", "coupler", "rocker"):
        rot = spatial.body(name).rotation
        np.testing.assert_allclose(np.unwrap(np.arctan2(rot[:, 1, 0], rot[:, 0, 0])),
                                   planar.body(name).angle, rtol=0, atol=1e-10)
        np.testing.assert_allclose(spatial.body(name).position[:, :2],
                                   planar.body(name).position, rtol=0, atol=1e-12)
        np.testing.assert_allclose(spatial.body(name).angular_velocity[:, 2],
                                   planar.body(name).angular_velocity, rtol=0, atol=1e-9)
        np.testing.assert_allclose(spatial.body(name).acceleration[:, :2],
                                   planar.body(name).acceleration, rtol=0, atol=1e-8)
    np.testing.assert_allclose(spatial.driver("motor").effort, planar.driver("motor").effort,
                               rtol=0, atol=1e-8)
    for joint in ("O2", "A", "B", "O4"):
        np.testing.assert_allclose(spatial.joint(joint).reaction(on=joint_body(joint)).force[:, :2],
                                   planar.joint(joint).reaction(on=joint_body(joint)).force,
                                   rtol=0, atol=1e-8)
    # the multipliers balance the equations of motion and carry nothing along the three left
    # null vectors of Cq (the statically indeterminate out-of-plane share)
    for k in (0, 7, 19):
        q, qd = spatial.q[k], spatial.qd[k]
        fr = constraints.frames(model, q, qd, spatial.charts[k])
        Cq = constraints.jacobian(model, spatial.t[k], q, fr, sparse=False)
        residual = (mass_matrix(model, fr) @ spatial.qdd[k] + Cq.T @ spatial.lam[k]
                    - generalized_forces(model, spatial.t[k], fr))
        assert np.max(np.abs(residual)) < 1e-8
        U, singular, _ = np.linalg.svd(Cq)
        null = U[:, np.sum(singular > 1e-9 * singular[0]):]
        assert null.shape[1] == 3
        assert np.max(np.abs(null.T @ spatial.lam[k])) < 1e-8 * np.max(np.abs(spatial.lam[k]))


def test_four_revolute_loop_with_skew_axes_is_not_driven_by_one_motor():
    """Four revolutes with skew crank and rocker hinges (not a Bennett linkage): the joints
    alone make the loop rigid, so a motor on it conflicts with them, and kinematic analysis
    says so instead of failing at the velocity solve."""
    model = spatial_four_bar(all_revolute=True, crank_speed=2 * math.pi)
    with pytest.raises(mb.OverDrivenError, match="over-driven.*joints alone leave 0 degree"):
        mb.kinematic_analysis(model, [0.0, 0.1])


def joint_body(joint: str) -> str:
    return {"O2": "crank", "A": "coupler", "B": "rocker", "O4": "rocker"}[joint]


def test_planar_restricted_four_bar_forward_dynamics():
    from mbd3d.mechanisms import four_bar
    drawing = mb.inverse_dynamics(four_bar(crank_speed=0.0), [0.0])
    t = np.linspace(0.0, 1.0, 21)
    planar = mb.forward_dynamics(four_bar(crank_speed=None, crank_torque=0.5), t,
                                 method="DOP853", rtol=1e-12, atol=1e-12)
    spatial = mb.forward_dynamics(spatial_four_bar_in_plane(drawing, driven=False, torque=0.5), t,
                                  method="DOP853", rtol=1e-12, atol=1e-12)
    for name in ("crank", "rocker"):
        rot = spatial.body(name).rotation
        # the crank speeds up to about pi per output interval: compare angles modulo a turn
        difference = np.arctan2(rot[:, 1, 0], rot[:, 0, 0]) - planar.body(name).angle
        np.testing.assert_allclose(np.angle(np.exp(1j * difference)), 0.0, rtol=0, atol=1e-8)
    np.testing.assert_allclose(spatial.joint("O2").reaction(on="crank").force[:, :2],
                               planar.joint("O2").reaction(on="crank").force, rtol=0, atol=1e-6)
