"""The spatial rotation driver: its time terms against finite differences in (q, t), and the
planar-restricted slider-crank in kinematic and inverse dynamics against the planar model."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import mbd3d as mb
from mbd3d.analyses import kinematics
from mbd3d.model import constraints
from mbd3d.mechanisms import slider_crank, slider_crank_positions
from mbd3d.joints import CoordinateDriver, Prismatic, Revolute, RotationDriver, Spherical, Universal


def driven_pair(seed: int):
    rng = np.random.default_rng(seed)
    b = mb.ModelBuilder(dim=3)
    A = Rotation.random(2, random_state=seed).as_matrix()
    arm = b.add_body("arm", mass=1.0, inertia=(0.1, 0.2, 0.25), position=rng.normal(size=3),
                     orientation=A[0])
    tip = b.add_body("tip", mass=2.0, inertia=(0.3, 0.2, 0.4), position=rng.normal(size=3),
                     orientation=A[1])
    hinge = b.add(Revolute("hinge", arm, tip, point_i=rng.normal(size=3),
                           point_j=rng.normal(size=3), axis=rng.normal(size=3)))
    b.add(RotationDriver("motor", hinge, motion=mb.Harmonic(0.8, 3.0, phase=0.4, offset=0.3)))
    model = b.build()
    q = model.q0 + 0.2 * rng.normal(size=model.n_coordinates)
    qd = rng.normal(size=model.n_coordinates)
    charts = np.tile(np.eye(3), (3, 1, 1))
    charts[:2] = Rotation.random(2, random_state=seed + 50).as_matrix()
    return model, q, qd, charts


@pytest.mark.parametrize("seed", [0, 1])
def test_rotation_driver_time_terms_match_finite_differences(seed):
    model, q, qd, charts = driven_pair(seed)
    t, h = 0.37, 1e-3
    C = lambda x, tt: constraints.residual(model, tt, x, constraints.frames(model, x, charts=charts))  # noqa: E731
    fr = constraints.frames(model, q, qd, charts)
    # -C_t
    nu = constraints.velocity_rhs(model, t, fr)
    ct = (C(q, t + 2 * h) * -1 + 8 * C(q, t + h) - 8 * C(q, t - h) + C(q, t - 2 * h)) / (12 * h)
    np.testing.assert_allclose(nu, -ct, rtol=0, atol=1e-9)
    # Qd = -d2/de2 C(q + e qd, t + e)
    path = lambda e: C(q + e * qd, t + e)  # noqa: E731
    second = (-path(2 * h) + 16 * path(h) - 30 * path(0) + 16 * path(-h) - path(-2 * h)) / (12 * h * h)
    np.testing.assert_allclose(constraints.acceleration_rhs(model, t, q, qd, fr), -second,
                               rtol=0, atol=1e-6)


def spatial_slider_crank(speed: float | None):
    phi0, L1, L2 = math.radians(65.0), 0.12, 0.26
    a, psi, b_point = slider_crank_positions(phi0, L1, L2)
    b = mb.ModelBuilder(dim=3, gravity=(0.0, -9.81, 0.0))
    rz = lambda angle: Rotation.from_rotvec([0.0, 0.0, angle]).as_matrix()  # noqa: E731
    crank = b.add_body("crank", mass=1.0, inertia=(0.0005, 0.001, 0.001), position=(*a / 2, 0.0),
                       orientation=rz(phi0))
    rod = b.add_body("rod", mass=2.0, inertia=(0.002, 0.01, 0.01),
                     position=(*(a + b_point) / 2, 0.0), orientation=rz(psi))
    slider = b.add_body("slider", mass=4.0, inertia=(0.02, 0.02, 0.02), position=(*b_point, 0.0))
    z = (0.0, 0.0, 1.0)
    pin = b.add(Revolute("O", b.ground, crank, at=(0.0, 0.0, 0.0), axis=z))
    b.add(Universal("A", crank, rod, at=(*a, 0.0), axis_i=z,
                    axis_j=(-math.sin(psi), math.cos(psi), 0.0)))
    b.add(Spherical("B", rod, slider, at=(*b_point, 0.0)))
    b.add(Prismatic("rail", b.ground, slider, axis=(1.0, 0.0, 0.0)))
    if speed is not None:
        b.add(RotationDriver("motor", pin, motion=mb.Ramp(phi0, speed)))
    return b.build()


def test_planar_restricted_slider_crank_inverse_dynamics_equals_planar():
    # the planar model with the in-plane inertias of the spatial one (J about z)
    planar_model = slider_crank(crank_inertia=0.001, rod_inertia=0.01, slider_inertia=0.02)
    t = np.linspace(0.0, 2.0, 49)  # two crank turns: the crank's chart is reset on the way
    planar = mb.inverse_dynamics(planar_model, t)
    spatial = mb.inverse_dynamics(spatial_slider_crank(2 * math.pi), t)
    assert mb.mobility(spatial.model).fully_driven
    crank = spatial.body("crank")
    angle = np.unwrap(np.arctan2(crank.rotation[:, 1, 0], crank.rotation[:, 0, 0]))
    np.testing.assert_allclose(angle, planar.body("crank").angle, rtol=0, atol=1e-10)
    for name in ("crank", "rod", "slider"):
        np.testing.assert_allclose(spatial.body(name).position[:, :2],
                                   planar.body(name).position, rtol=0, atol=1e-12)
        np.testing.assert_allclose(spatial.body(name).acceleration[:, :2],
                                   planar.body(name).acceleration, rtol=0, atol=1e-9)
    np.testing.assert_allclose(spatial.driver("motor").effort, planar.driver("motor").effort,
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(spatial.joint("O").reaction(on="crank").force[:, :2],
                               planar.joint("O").reaction(on="crank").force, rtol=0, atol=1e-9)
    # the out-of-plane reactions carry nothing
    np.testing.assert_allclose(spatial.joint("O").reaction(on="crank").force[:, 2], 0.0,
                               rtol=0, atol=1e-9)


def test_coordinate_driver_refuses_orientation_coordinates():
    b = mb.ModelBuilder(dim=3)
    body = b.add_body("b", mass=1.0, inertia=(1, 1, 1), position=(0, 0, 0))
    b.add(CoordinateDriver("spin", body, "g3", 0.0))
    with pytest.raises(mb.ModelError, match="driver 'spin'.*RotationDriver"):
        b.build()


def test_joints_of_the_wrong_dimension_are_refused():
    b3 = mb.ModelBuilder(dim=3)
    body = b3.add_body("b", mass=1.0, inertia=(1, 1, 1), position=(0, 0, 0))
    b3.add(Revolute("hinge", b3.ground, body, at=(0, 0, 0)))
    with pytest.raises(mb.ModelError, match="joint 'hinge'.*needs its axis="):
        b3.build()
    b2 = mb.ModelBuilder(dim=2)
    flat = b2.add_body("f", mass=1.0, inertia=1.0, position=(0, 0))
    b2.add(Spherical("ball", b2.ground, flat, at=(0, 0)))
    with pytest.raises(mb.ModelError, match="'ball'.*spatial models only"):
        b2.build()
    with pytest.raises(mb.ModelError, match="spatial body takes orientation="):
        b3.add_body("c", mass=1.0, inertia=(1, 1, 1), position=(0, 0, 0), angle=0.3)
    with pytest.raises(mb.ModelError, match="J1 \\+ J2 >= J3"):
        b3.add_body("d", mass=1.0, inertia=(1.0, 1.0, 3.0), position=(0, 0, 0))
    with pytest.raises(mb.ModelError, match="axis must be a non-zero"):
        b4 = mb.ModelBuilder(dim=3)
        c = b4.add_body("c", mass=1.0, inertia=(1, 1, 1), position=(0, 0, 0))
        b4.add(Revolute("h", b4.ground, c, at=(0, 0, 0), axis=(0, 0, 0)))
        b4.build()


def test_spatial_slider_crank_matches_its_closed_form():
    from mbd3d.mechanisms import spatial_slider_crank
    r, l, d, e, w = 0.10, 0.30, 0.04, 0.06, 2 * math.pi
    res = mb.inverse_dynamics(spatial_slider_crank(crank_length=r, rod_length=l, offset_y=d,
                                                   offset_z=e, crank_speed=w),
                              np.linspace(0.0, 2.0, 73))  # two turns, 10 degree steps

    def x(phi):  # complex-safe closed form of the slider position
        return r * np.cos(phi) + np.sqrt(l * l - e * e - (d - r * np.sin(phi)) ** 2)

    def dx(phi):
        return np.imag(x(phi + 1e-30j)) / 1e-30

    def dx_hand(phi):  # derivative written out, to check the complex step
        S = np.sqrt(l * l - e * e - (d - r * np.sin(phi)) ** 2)
        return -r * np.sin(phi) + (d - r * np.sin(phi)) * r * np.cos(phi) / S

    phi = w * res.t
    np.testing.assert_allclose(dx(phi), dx_hand(phi), rtol=1e-14)
    h = 1e-4
    d2x = (dx_hand(phi + h) - dx_hand(phi - h)) / (2 * h)
    slider = res.body("slider")
    np.testing.assert_allclose(slider.position[:, 0], x(phi), rtol=0, atol=1e-12)
    np.testing.assert_allclose(slider.position[:, 1:], np.tile((d, e), (len(phi), 1)),
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(slider.velocity[:, 0], w * dx(phi), rtol=0, atol=1e-10)
    np.testing.assert_allclose(slider.acceleration[:, 0], w * w * d2x, rtol=0, atol=1e-6)
    # the rod keeps its length and the crank end its circle
    a = res.point("crank", (r / 2, 0.0, 0.0)).position
    np.testing.assert_allclose(a, r * np.column_stack([np.cos(phi), np.sin(phi), 0 * phi]),
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(slider.position - a, axis=1), l, rtol=0, atol=1e-12)
    # power balance: motor power = rate of kinetic + potential energy (gravity along -z)
    rate = np.zeros(len(phi))
    for body in res.model.bodies:
        hist = res.body(body.name)
        J_global = np.einsum("kij,jl,kml->kim", hist.rotation, body.inertia, hist.rotation)
        spin = np.einsum("kij,kj->ki", J_global, hist.angular_velocity)
        rate += body.mass * np.einsum("kd,kd->k", hist.velocity, hist.acceleration + (0, 0, 9.81))
        rate += np.einsum("ki,ki->k", spin, hist.angular_acceleration)
    np.testing.assert_allclose(res.driver("motor").effort * w, rate, rtol=0, atol=1e-9)


def test_all_revolute_spatial_four_bar_reports_its_redundancy():
    from mbd3d.mechanisms import spatial_four_bar
    # a generic spatial 4R is rigid: 20 rows of rank 18, no mobility and 2 dependent rows
    report = mb.mobility(spatial_four_bar(all_revolute=True, crank_speed=None))
    assert (report.n_constraints, report.gruebler, report.rank) == (20, -2, 18)
    assert (report.dof, report.redundant) == (0, 2)
    involved = {label.split(".")[0] for group in report.dependent for label in group}
    assert involved <= {"O2", "A", "B", "O4"}
    fine = mb.mobility(spatial_four_bar(crank_speed=None))
    assert (fine.gruebler, fine.dof, fine.redundant) == (1, 1, 0)


def test_translation_driver_and_joint_axes_reactions_in_space():
    from mbd3d.joints import TranslationDriver
    m, g = 3.0, np.array([0.0, 0.0, -9.81])
    axis = np.array([2.0, -1.0, 2.0]) / 3.0
    b = mb.ModelBuilder(dim=3, gravity=g)
    block = b.add_body("block", mass=m, inertia=(0.1, 0.1, 0.1), position=(0.2, 0.1, 0.3),
                       orientation=Rotation.from_rotvec([0.3, 0.2, -0.5]).as_matrix())
    rail = b.add(Prismatic("rail", b.ground, block, axis=axis))
    b.add(TranslationDriver("push", rail, motion=mb.Ramp(0.0, 0.4)))
    res = mb.inverse_dynamics(b.build(), np.linspace(0.0, 1.0, 6))
    np.testing.assert_allclose(res.body("block").position,
                               (0.2, 0.1, 0.3) + np.outer(0.4 * res.t, axis), rtol=0, atol=1e-12)
    # constant speed: the actuator holds the weight's component along the rail
    np.testing.assert_allclose(res.driver("push").effort, -m * g @ axis, rtol=0, atol=1e-10)
    reaction = res.joint("rail").reaction(on="block", frame="joint")
    np.testing.assert_allclose(reaction.force[:, 0], 0.0, rtol=0, atol=1e-10)  # frictionless slide
    weight_normal = m * (g - (g @ axis) * axis)
    np.testing.assert_allclose(np.linalg.norm(reaction.force, axis=1),
                               np.linalg.norm(weight_normal), rtol=0, atol=1e-10)
    np.testing.assert_allclose(reaction.moment, 0.0,
                               rtol=0, atol=1e-10)  # centre of mass on the line
    np.testing.assert_allclose(res.joint("rail").reaction(on="block").force, -weight_normal[None]
                               * np.ones((6, 1)), rtol=0, atol=1e-10)


@pytest.mark.parametrize("compiled", [False, True], ids=["Python", "compiled"])
@pytest.mark.parametrize("target", [math.pi - 0.1, -math.pi + 0.2, 3.0, 2.5 + 4 * math.pi])
def test_a_rotation_driver_far_from_the_drawing_reaches_its_angle_not_the_half_turn(
        target, compiled, monkeypatch):
    """The driver's row sin(theta - f) also vanishes half a turn from f; drawn at 0 and
    driven to beyond a quarter turn, the position must still be f (mod a turn), and the joint
    angle reads it: in Python and in the compiled time points
    (:mod:`mbd3d.numerics.compiled.kinematics`), which then leave no point to Python."""
    monkeypatch.setattr(kinematics, "COMPILED_POINTS", compiled)
    if compiled:
        monkeypatch.setattr(kinematics, "solve_position", None)
    from mbd3d.mechanisms import frame_along
    axis = np.array([0.0, 0.6, 0.8])
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -9.81))
    arm = b.add_body("arm", mass=1.0, inertia=(0.01, 0.02, 0.02), position=(0.3, 0.0, 0.0),
                     orientation=frame_along(np.array([1.0, 0.0, 0.0]), axis))
    pin = b.add(Revolute("pin", b.ground, arm, at=(0.0, 0.0, 0.0), axis=axis))
    b.add(RotationDriver("motor", pin, motion=mb.Constant(target)))
    res = mb.kinematic_analysis(b.build(), [0.0])
    turn = 2 * math.pi
    assert (res.joint("pin").angle[0] - target + math.pi) % turn - math.pi == pytest.approx(
        0.0, abs=1e-10)
