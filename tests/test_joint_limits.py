"""Joint limits beyond the revolute and the prismatic: a spherical joint's cone and both
coordinates of a cylindrical joint, against models whose stops are already checked (a swing in
a plane against a hinge stop, a cylindrical joint's decoupled slide and turn against a
prismatic and a revolute) and against differences of the cone's potential written here with
SciPy's rotations."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import mbd3d as mb
from mbd3d.joints import Cylindrical, Prismatic, Revolute, Spherical
from mbd3d.model import constraints
from mbd3d.model.equations import generalized_forces

G = 9.81
M, L = 2.0, 0.8
#: a uniform bar's inertia about its centre, its own axis along x (a thin rod with some girth)
INERTIA = np.diag([0.004, M * L * L / 12, M * L * L / 12])


def _rotation(chart: np.ndarray, g: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(g)
    rotvec = np.zeros(3) if norm == 0 else 2.0 * math.atan(norm) * g / norm
    return chart @ Rotation.from_rotvec(rotvec).as_matrix()


def _hanging_bar(joint: str, law, cone=0.6, speed=3.0):
    """A bar hanging from a joint at the origin along -z, set swinging in the x-z plane at
    ``speed`` rad/s: on a ball joint whose cone about -z has half angle ``cone``, or on a
    hinge about y stopped at +-``cone`` about the bar's drawn angle."""
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G))
    rotation = Rotation.from_rotvec([0.0, math.pi / 2, 0.0]).as_matrix()  # body x along -z
    bar = b.add_body("bar", mass=M, inertia=INERTIA, position=(0.0, 0.0, -L / 2),
                     orientation=rotation, velocity=(-speed * L / 2, 0.0, 0.0),
                     angular_velocity=(0.0, speed, 0.0))
    if joint == "ball":
        ball = b.add(Spherical("ball", b.ground, bar, at=(0.0, 0.0, 0.0)))
        b.add(mb.JointLimit("cone", ball, upper=cone, axis=(0.0, 0.0, -1.0), law=law))
    else:
        hinge = b.add(Revolute("hinge", b.ground, bar, at=(0.0, 0.0, 0.0), axis=(0.0, 1.0, 0.0)))
        # the hinge's angle runs from the ground's x to the bar's own x (along -z): pi / 2
        b.add(mb.JointLimit("stop", hinge, lower=math.pi / 2 - cone, upper=math.pi / 2 + cone,
                            law=law))
    return b.build()


def test_a_ball_joints_cone_stops_a_swing_in_a_plane_as_a_hinge_stop_does():
    """In the plane of the swing the cone's angle is the hinge's |angle|, its axis the
    hinge's, and the calibration's moment of inertia the same (the bar is symmetric about its
    own axis), so the two models move alike through several strikes on both sides."""
    law = mb.HuntCrossley(stiffness=2e4, restitution=0.6, impact_speed=2.0)
    t = np.linspace(0.0, 3.0, 301)
    runs = [mb.forward_dynamics(_hanging_bar(joint, law), t, method="DOP853", rtol=1e-11,
                                atol=1e-12) for joint in ("ball", "hinge")]
    tips = [run.point("bar", (L / 2, 0.0, 0.0)).position for run in runs]
    np.testing.assert_allclose(tips[0], tips[1], rtol=0, atol=1e-8)
    angle = np.arctan2(tips[1][:, 0], -tips[1][:, 2])
    assert angle.max() > 0.55 and angle.min() < -0.55  # it reached both sides
    assert np.abs(tips[0][:, 1]).max() < 1e-12  # and stayed in its plane


def test_the_cone_torque_is_minus_the_gradient_of_its_potential():
    """Two free bodies in random charts, their axes 0.55 rad apart against a cone of 0.5 rad:
    Q = -dV/dq with V = K delta^(5/2) / (5/2), delta the angle between the axes (from SciPy's
    rotations) past the cone."""
    rng = np.random.default_rng(2)
    b = mb.ModelBuilder(dim=3)
    one = b.add_body("one", mass=2.0, inertia=np.diag([0.1, 0.2, 0.3]), position=(0, 0, 0))
    two = b.add_body("two", mass=3.0, inertia=np.diag([0.3, 0.2, 0.4]), position=(0, 0, 1.0))
    ball = b.add(Spherical("ball", one, two, at=(0.0, 0.0, 0.5)))
    axis, K, cone = np.array([0.3, -0.5, 0.8]), 3e3, 0.5
    b.add(mb.JointLimit("cone", ball, upper=cone, axis=axis, law=mb.HertzContact(stiffness=K)))
    model = b.build()
    charts = np.tile(np.eye(3), (3, 1, 1))
    charts[:2] = Rotation.random(2, random_state=5).as_matrix()
    n = axis / np.linalg.norm(axis)  # in both bodies' frames (the drawing is unturned)
    q = np.zeros(12)
    q[3:6] = rng.normal(size=3) * 0.4
    # body two turned from body one's attitude by 0.55 rad about an axis square to the cone's
    across = np.cross(n, rng.normal(size=3))
    turn = Rotation.from_rotvec(0.55 * across / np.linalg.norm(across)).as_matrix()
    A2 = _rotation(charts[0], q[3:6]) @ turn
    rotvec = Rotation.from_matrix(charts[1].T @ A2).as_rotvec()
    q[9:12] = math.tan(np.linalg.norm(rotvec) / 2) * rotvec / np.linalg.norm(rotvec)
    q[6:9] = (0.0, 0.0, 1.0)

    def V(x):
        angle = math.acos(np.clip((_rotation(charts[0], x[3:6]) @ n)
                                  @ (_rotation(charts[1], x[9:12]) @ n), -1, 1))
        return K * max(angle - cone, 0.0) ** 2.5 / 2.5

    h = 1e-7
    expected = np.array([-(V(q + h * e) - V(q - h * e)) / (2 * h) for e in np.eye(12)])
    Q = generalized_forces(model, 0.0, constraints.frames(model, q, np.zeros(12), charts))
    np.testing.assert_allclose(Q, expected, rtol=0, atol=1e-6 * np.abs(expected).max())
    assert np.abs(expected).max() > 1.0
    states = mb.contact_states(model, q, charts=charts)
    assert states.gap[0] == pytest.approx(-0.05, abs=1e-12)


def _on_an_axis(joint: str, law, lower=-0.2, upper=0.3, turns=(-0.5, 0.4)):
    """A spinning slider on a vertical axis (its centre of mass and a principal axis on it,
    so slide and turn do not couple), moving up at 1 m/s and turning at 2 rad/s: on a
    cylindrical joint stopped in both coordinates, or on a prismatic or a revolute alone."""
    b = mb.ModelBuilder(dim=3)
    body = b.add_body("slider", mass=1.5, inertia=np.diag([0.02, 0.02, 0.03]),
                      position=(0.0, 0.0, 0.0),
                      velocity=(0.0, 0.0, 0.0 if joint == "revolute" else 1.0),
                      angular_velocity=(0.0, 0.0, 0.0 if joint == "prismatic" else 2.0))
    axis = (0.0, 0.0, 1.0)
    if joint == "cylindrical":
        slide = b.add(Cylindrical("slide", b.ground, body, at=(0, 0, 0), axis=axis))
        b.add(mb.JointLimit("ends", slide, lower=lower, upper=upper, law=law,
                            coordinate="displacement"))
        b.add(mb.JointLimit("turns", slide, lower=turns[0], upper=turns[1], law=law,
                            coordinate="angle"))
    elif joint == "prismatic":
        # the prismatic joint holds the turn: the slide alone, its inertia along z the same
        slide = b.add(Prismatic("slide", b.ground, body, at=(0, 0, 0), axis=axis))
        b.add(mb.JointLimit("ends", slide, lower=lower, upper=upper, law=law))
    else:
        hinge = b.add(Revolute("slide", b.ground, body, at=(0, 0, 0), axis=axis))
        b.add(mb.JointLimit("turns", hinge, lower=turns[0], upper=turns[1], law=law))
    return b.build()


def test_a_cylindrical_joint_stops_its_slide_and_its_turn_as_the_single_joints_do():
    law = mb.LinearContact(frequency=60.0, restitution=0.7)
    t = np.linspace(0.0, 2.0, 201)
    run = {joint: mb.forward_dynamics(_on_an_axis(joint, law), t, method="DOP853",
                                      rtol=1e-11, atol=1e-12)
           for joint in ("cylindrical", "prismatic", "revolute")}
    both = run["cylindrical"].joint("slide")
    np.testing.assert_allclose(both.displacement, run["prismatic"].joint("slide").displacement,
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(both.angle, run["revolute"].joint("slide").angle, rtol=0,
                               atol=1e-9)
    # it reached both ends of both (the samples catch a stop only near it)
    assert both.displacement.max() > 0.29 and both.displacement.min() < -0.19
    assert both.angle.max() > 0.39 and both.angle.min() < -0.49


def test_bad_cone_and_cylindrical_limits_are_named():
    b = mb.ModelBuilder(dim=3)
    body = b.add_body("body", mass=1.0, inertia=np.eye(3), position=(0.0, 0.0, 0.0))
    ball = Spherical("ball", b.ground, body, at=(0, 0, 0))
    tube = Cylindrical("tube", b.ground, body, at=(0, 0, 0), axis=(0, 0, 1))
    hinge = Revolute("hinge", b.ground, body, at=(0, 0, 0), axis=(0, 0, 1))
    law = mb.LinearContact(stiffness=1e4, damping=1.0)
    for joint, kwargs, words in [
            (tube, dict(upper=1.0), "a Cylindrical joint has 2 coordinates; name the one "
                                    "stopped: coordinate= 'angle' or 'displacement'"),
            (hinge, dict(upper=1.0, coordinate="displacement"),
             "a Revolute joint's coordinates are 'angle'; got 'displacement'"),
            (ball, dict(upper=1.0), "a cone needs its axis="),
            (hinge, dict(upper=1.0, axis=(1, 0, 0)), "axis= is a cone's")]:
        with pytest.raises(mb.ModelError, match=f"joint limit 'stop': {words}"):
            mb.JointLimit("stop", joint, law=law, **kwargs)
    for kwargs in (dict(upper=3.2), dict(upper=0.0), dict(lower=0.1, upper=0.5)):
        builder = mb.ModelBuilder(dim=3)
        body = builder.add_body("body", mass=1.0, inertia=np.eye(3), position=(0.0, 0.0, 0.0))
        ball = builder.add(Spherical("ball", builder.ground, body, at=(0, 0, 0)))
        builder.add(mb.JointLimit("stop", ball, law=law, axis=(0, 0, 1), **kwargs))
        with pytest.raises(mb.ModelError, match="joint limit 'stop': a cone has an upper end "
                                                "only, its half angle in"):
            builder.build()


def test_cone_and_cylindrical_limits_round_trip_through_a_model_file(tmp_path):
    law = mb.LinearContact(frequency=60.0, restitution=0.7)
    for model in (_hanging_bar("ball", law), _on_an_axis("cylindrical", law)):
        again = mb.load(mb.save(model, tmp_path / "limits.yaml", overwrite=True))
        t = np.linspace(0.0, 0.5, 6)
        first, second = (mb.forward_dynamics(m, t, method="DOP853") for m in (model, again))
        np.testing.assert_array_equal(second.q, first.q)


@pytest.mark.filterwarnings("ignore::mbd3d.ContactWarning")  # past the stop in the drawing
@pytest.mark.parametrize("stop", ["slide", "hinge", "cone"])
def test_a_stops_rate_is_the_rate_of_its_coordinate_with_both_bodies_moving(stop):
    """The rate a stop damps with, against central differences of its own coordinate along
    the velocities, with both bodies moving and turning in random charts: the slide's
    ``h . (P_j - P_i)`` turns with body i, the cone's angle with both (any state), the hinge's
    angle about an axis both bodies share."""
    rng = np.random.default_rng({"slide": 1, "hinge": 2, "cone": 3}[stop])
    b = mb.ModelBuilder(dim=3)
    one = b.add_body("one", mass=2.0, inertia=np.diag([0.1, 0.2, 0.3]), position=(0, 0, 0))
    two = b.add_body("two", mass=3.0, inertia=np.diag([0.3, 0.2, 0.4]), position=(0.2, 0, 0.5))
    law = mb.LinearContact(stiffness=1e4, damping=50.0)
    if stop == "slide":
        joint = b.add(Prismatic("joint", one, two, at=(0.1, 0.0, 0.4), axis=(0.3, 0.4, 1.0)))
        b.add(mb.JointLimit("stop", joint, upper=-0.1, law=law))
    elif stop == "hinge":
        joint = b.add(Revolute("joint", one, two, at=(0.1, 0.0, 0.4), axis=(0.3, 0.4, 1.0)))
        b.add(mb.JointLimit("stop", joint, upper=-0.1, law=law))
    else:
        joint = b.add(Spherical("joint", one, two, at=(0.1, 0.0, 0.4)))
        b.add(mb.JointLimit("stop", joint, upper=0.1, axis=(0.3, 0.4, 1.0), law=law))
    model = b.build()
    charts = np.tile(np.eye(3), (3, 1, 1))
    charts[:2] = Rotation.random(2, random_state=int(rng.integers(100))).as_matrix()
    q = np.zeros(12)
    q[0:3], q[6:9] = rng.normal(size=3) * 0.1, rng.normal(size=3) * 0.1 + (0.2, 0, 0.5)
    q[3:6], q[9:12] = rng.normal(size=3) * 0.3, rng.normal(size=3) * 0.3
    qd = rng.normal(size=12)
    if stop == "hinge":  # body two turned from body one's attitude about the shared axis only
        axis = np.array([0.3, 0.4, 1.0]) / np.linalg.norm([0.3, 0.4, 1.0])
        A2 = _rotation(charts[0], q[3:6]) @ Rotation.from_rotvec(0.7 * axis).as_matrix()
        rotvec = Rotation.from_matrix(charts[1].T @ A2).as_rotvec()
        q[9:12] = math.tan(np.linalg.norm(rotvec) / 2) * rotvec / np.linalg.norm(rotvec)
        # and turning relative to it about that axis (body one's rates, plus a spin about it)
        omega = rng.normal(size=3)
        frames = constraints.frames(model, q, np.zeros(12), charts)
        G = [np.linalg.lstsq(frames.axes[k], np.eye(3), rcond=None)[0] for k in (0, 1)]
        h = _rotation(charts[0], q[3:6]) @ axis
        qd[3:6] = G[0] @ omega
        qd[9:12] = G[1] @ (omega + 1.3 * h)

    def coordinate(x):
        return mb.contact_states(model, x, charts=charts).gap[0]

    step = 1e-6
    expected = (coordinate(q + step * qd) - coordinate(q - step * qd)) / (2 * step)
    states = mb.contact_states(model, q, qd, charts)
    assert states.gap_rate[0] == pytest.approx(expected, rel=1e-7, abs=1e-9)
    assert abs(expected) > 0.1
    # what the stop reports: the direction it pushes body two, back from its upper end
    # (against the slide's axis, or the turn about the hinge's or about the cone's tilt),
    # and the point it pushes: the slide's the joint's point of body two, a turn's body two's
    # centre of mass (a torque has no point of its own)
    a = np.array([0.3, 0.4, 1.0]) / np.linalg.norm([0.3, 0.4, 1.0])
    R1, R2 = _rotation(charts[0], q[3:6]), _rotation(charts[1], q[9:12])
    h = np.cross(R1 @ a, R2 @ a) if stop == "cone" else R1 @ a
    np.testing.assert_allclose(states.normal[0], -h / np.linalg.norm(h), rtol=0, atol=1e-12)
    point = q[6:9] + R2 @ [-0.1, 0.0, -0.1] if stop == "slide" else q[6:9]
    np.testing.assert_allclose(states.point[0], point, rtol=0, atol=1e-12)


def test_a_planar_joint_stops_each_coordinate_with_its_restitution():
    """A puck sliding and turning on a tilted plane (no gravity) strikes a stop along the
    plane's first axis and one on its turn: a slide stop pushes at the joint's point (the
    centre) and a turn stop is a pure torque, so each rebounds its own coordinate with its
    restitution (linear laws calibrated to the puck's mass and its moment about the normal)
    and leaves the others' rates as they were."""
    from mbd3d.joints import Planar

    normal = np.array([0.3, -0.4, 0.85]) / np.linalg.norm([0.3, -0.4, 0.85])
    first = np.eye(3)[0] - normal[0] * normal
    first /= np.linalg.norm(first)
    attitude = np.column_stack([first, np.cross(normal, first), normal])  # body z the normal
    m, inertia = 1.5, np.diag([0.01, 0.012, 0.02])
    speed, across, spin = 0.8, 0.3, 2.0

    def build(velocity):
        b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, 0.0))
        puck = b.add_body("puck", mass=m, inertia=inertia, position=(0.1, 0.2, 0.3),
                          orientation=attitude, velocity=velocity,
                          angular_velocity=spin * normal)
        plane = b.add(Planar("plane", b.ground, puck, axis=normal, at=(0.1, 0.2, 0.3)))
        b.add(mb.JointLimit("edge", plane, coordinate="plane_position[0]", lower=-0.3,
                            upper=0.1, law=mb.LinearContact(stiffness=1e5, restitution=0.6)))
        b.add(mb.JointLimit("turn", plane, coordinate="angle", upper=0.5,
                            law=mb.LinearContact(stiffness=1e3, restitution=0.4)))
        return b.build()

    axes = build(np.zeros(3)).reaction_frame("plane")[2]  # the normal, the plane's two axes
    np.testing.assert_allclose(axes[:, 0], normal, rtol=0, atol=1e-15)
    model = build(speed * axes[:, 1] + across * axes[:, 2])
    res = mb.forward_dynamics(model, np.linspace(0.0, 0.5, 101), method="DOP853",
                              rtol=1e-11, atol=1e-12, strict=True)
    joint = res.joint("plane")
    np.testing.assert_allclose(joint.plane_velocity[0], [speed, across], rtol=1e-12)
    assert joint.angle[0] == pytest.approx(0.0, abs=1e-14)
    assert joint.angle_rate[0] == pytest.approx(spin, rel=1e-12)
    # both struck (at 0.125 s and 0.25 s) and left
    assert np.max(joint.plane_position[:, 0]) > 0.1 and np.max(joint.angle) > 0.5
    np.testing.assert_allclose(joint.plane_velocity[-1], [-0.6 * speed, across], rtol=1e-7)
    assert joint.angle_rate[-1] == pytest.approx(-0.4 * spin, rel=1e-7)
    states = res.contacts()
    assert states.names == ["edge", "turn"]
    assert np.all(states.normal_force[-1] == 0.0)
