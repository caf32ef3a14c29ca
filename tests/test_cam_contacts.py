"""A roller on a disc cam as a contact (``mb.Cam`` against ``mb.Sphere``): the follower may
leave the cam and land on it again. The cam is an eccentric circle, whose polar equation and
whose follower's lift are closed forms, so that every figure here is derived from the geometry,
the follower's free flight (a mass on a spring: a harmonic motion) and Newton's law of
restitution alone."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.optimize import brentq

import mbd3d as mb
from mbd3d.errors import ModelError
from mbd3d.joints import CamFollower, CamProfile, Prismatic, Revolute, RotationDriver

#: the cam's surface, a circle of radius R about a point E at ECC from the shaft (along the
#: cam's x axis); the roller's radius; the follower's mass, spring and the plate the spring
#: is compressed against; the cam's speed, above the speed at which the follower leaves it
R, ECC, ROLLER = 0.05, 0.012, 0.01
MASS, STIFFNESS, PLATE, FREE_LENGTH, G = 0.5, 200.0, 0.2, 0.15, 9.81
SPEED = 50.0
OMEGA = math.sqrt(STIFFNESS / MASS)
#: where the follower would hang on its spring alone
HANG = PLATE - FREE_LENGTH - MASS * G / STIFFNESS
TIGHT = dict(method="DOP853", rtol=1e-11, atol=1e-12)


def surface() -> CamProfile:
    """The eccentric circle in polar form about the shaft: ``r = e cos phi + sqrt(R^2 - e^2
    sin^2 phi)``."""
    return CamProfile.sampled(
        lambda phi: ECC * np.cos(phi) + np.sqrt(R ** 2 - (ECC * np.sin(phi)) ** 2), 1440)


def lift(theta: float, derivative: int = 0, face: bool = False) -> float:
    """The height [m] of the roller's centre on the cam turned by ``theta`` (the follower on
    the vertical through the shaft), ``y = e sin + sqrt(a^2 - e^2 cos^2)`` with ``a = R +
    roller``, or its first or second derivative in ``theta``; of a flat face below the
    follower (``face``), the cam's top, ``e sin + R``."""
    c, s = math.cos(theta), math.sin(theta)
    if face:
        return (ECC * s + R, ECC * c, -ECC * s)[derivative]
    root = math.sqrt((R + ROLLER) ** 2 - (ECC * c) ** 2)
    return (ECC * s + root, ECC * c + ECC ** 2 * c * s / root,
            -ECC * s + ECC ** 2 * (c * c - s * s) / root
            - ECC ** 4 * c * c * s * s / root ** 3)[derivative]


def free_acceleration(y: float) -> float:
    """The follower's acceleration [m/s2] off the cam: spring and weight."""
    return STIFFNESS * (PLATE - FREE_LENGTH - y) / MASS - G


def lift_off_angle(face: bool = False) -> float:
    """The cam angle at which the cam's lift decelerates faster than spring and weight can
    follow (the contact would have to pull), on the way up to the top."""
    def pressing(th):
        return SPEED ** 2 * lift(th, 2, face) - free_acceleration(lift(th, 0, face))
    return brentq(pressing, 0.0, math.pi / 2, xtol=1e-15)


def build(theta0: float, law: mb.ContactLaw | None, face: bool = False) -> mb.Model:
    """The cam turned to ``theta0`` at ``t = 0`` and driven at ``SPEED``, the follower
    touching it there with the cam's lift rate: a contact of ``law`` with its roller or its
    flat face (``face``), or with ``None`` the bilateral ``CamFollower`` on the pitch
    circle."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G), name="eccentric cam, roller on a spring")
    cam = b.add_body("cam", mass=2.0, inertia=2e-3, position=(0.0, 0.0), angle=theta0)
    y0 = lift(theta0, 0, face)
    follower = b.add_body("follower", mass=MASS, inertia=1e-4, position=(0.0, y0),
                          velocity=(0.0, SPEED * lift(theta0, 1, face)))
    shaft = b.add(Revolute("shaft", b.ground, cam, at=(0.0, 0.0)))
    b.add(Prismatic("guide", b.ground, follower, axis=(0.0, 1.0)))
    b.add(RotationDriver("motor", shaft, motion=mb.Ramp(theta0, SPEED)))
    b.add(mb.SpringDamper("spring", b.ground, follower, at_i=(0.0, PLATE), at_j=(0.0, y0),
                          stiffness=STIFFNESS, free_length=FREE_LENGTH))
    if face:
        b.add(mb.Contact("face", mb.Cam(cam, surface()),
                         mb.Plane(follower, normal=(0.0, -1.0)), law=law))
    elif law is None:
        pitch = CamProfile.sampled(lambda phi: ECC * np.cos(phi) + np.sqrt(
            (R + ROLLER) ** 2 - (ECC * np.sin(phi)) ** 2), 1440)
        b.add(CamFollower("roller", cam, follower, profile=pitch, roller_radius=ROLLER))
    else:
        b.add(mb.Contact("roller", mb.Cam(cam, surface()), mb.Sphere(follower, ROLLER),
                         law=law))
    with warnings.catch_warnings():  # set on the cam to the spline's rounding, 1e-14 m
        warnings.simplefilter("ignore", mb.ContactWarning)
        return b.build()


def landing(t0: float, theta0: float, y0: float, v0: float,
            face: bool = False) -> tuple[float, float, float]:
    """``(time, follower's speed, cam's lift rate)`` where the follower, flying freely from
    height ``y0`` at speed ``v0`` at ``t0`` (the cam then at ``theta0``), meets the cam."""
    def above(t):
        tau = t - t0
        y = HANG + (y0 - HANG) * math.cos(OMEGA * tau) + v0 / OMEGA * math.sin(OMEGA * tau)
        return y - lift(theta0 + SPEED * tau, 0, face)
    grid = t0 + np.linspace(1e-6, 0.5, 100001)
    heights = np.array([above(t) for t in grid])
    k = int(np.flatnonzero(heights < 0.0)[0])
    t = brentq(above, grid[k - 1], grid[k], xtol=1e-15)
    tau = t - t0
    v = -(y0 - HANG) * OMEGA * math.sin(OMEGA * tau) + v0 * math.cos(OMEGA * tau)
    return t, v, SPEED * lift(theta0 + SPEED * tau, 1, face)


def turn(angle: float) -> np.ndarray:
    """The planar rotation by ``angle`` [rad]."""
    return np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])


def random_states(seed: int, count: int = 300):
    """``count`` random ``(q, qd)`` of a cam near the origin, turned anyhow, and another
    body anywhere within 0.09 m of it."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        yield (np.concatenate([rng.normal(0.0, 0.01, 2), rng.uniform(-4, 4, 1),
                               rng.uniform(-0.09, 0.09, 2), rng.uniform(-4, 4, 1)]),
               rng.normal(0.0, 1.0, 6))


def assert_rate_is_the_gaps_derivative(model: mb.Model, q: np.ndarray, qd: np.ndarray):
    """The reported gap rate against central differences of the gap along the motion."""
    h = 1e-7
    ahead = mb.contact_states(model, q + h * qd).gap[0]
    behind = mb.contact_states(model, q - h * qd).gap[0]
    assert mb.contact_states(model, q, qd).gap_rate[0] == pytest.approx(
        (ahead - behind) / (2 * h), abs=1e-7)


def test_the_gap_is_the_distance_to_an_off_centre_circle():
    """The surface is a spline through the circle's polar equation; the gap of a roller
    anywhere about it, turned anyhow, is its distance to the circle less the radii."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0))
    cam = b.add_body("cam", mass=1.0, inertia=1e-3, position=(0.0, 0.0))
    roller = b.add_body("roller", mass=0.5, inertia=1e-4, position=(0.0, 0.2))
    b.add(mb.Contact("c", mb.Cam(cam, surface(), point=(0.001, -0.002)),
                     mb.Sphere(roller, ROLLER, point=(0.003, 0.0)),
                     law=mb.LinearContact(stiffness=1e6, damping=10.0)))
    model = b.build()
    for q, qd in random_states(7):
        centre = q[:2] + turn(q[2]) @ np.array([0.001 + ECC, -0.002])
        pin = q[3:5] + turn(q[5]) @ np.array([0.003, 0.0])
        if np.linalg.norm(pin - centre) < 0.6 * R:  # deep inside: no closest point of use
            continue
        state = mb.contact_states(model, q, qd)
        expected = np.linalg.norm(pin - centre) - R - ROLLER
        assert state.gap[0] == pytest.approx(expected, abs=1e-11)
        normal = (pin - centre) / np.linalg.norm(pin - centre)
        np.testing.assert_allclose(state.normal[0, :2], normal, atol=1e-9)
        # the point midway between the circle's surface and the roller's
        middle = (centre + R * normal + pin - ROLLER * normal) / 2
        np.testing.assert_allclose(state.point[0, :2], middle, atol=1e-11)
        assert_rate_is_the_gaps_derivative(model, q, qd)


@pytest.mark.parametrize("face", [False, True])
def test_a_follower_leaves_the_cam_and_lands_by_the_law_of_restitution(face):
    """Set on the cam just past the angle where it would have to be pulled, the follower (a
    roller, or a flat face) flies free (a harmonic motion on its spring) and strikes the cam
    where that flight meets the lift; it leaves the strike at ``-e`` times its speed
    relative to the cam's lift, and so on for every landing."""
    e = 0.5
    theta0 = lift_off_angle(face) + 0.02
    res = mb.forward_dynamics(build(theta0, mb.RigidImpact(restitution=e), face),
                              np.linspace(0.0, 0.6, 301), **TIGHT)
    impacts = res.stats["impacts"]
    assert len(impacts) >= 3
    t, y, v = 0.0, lift(theta0, 0, face), SPEED * lift(theta0, 1, face)
    for impact in impacts[:3]:
        t_hit, v_hit, v_cam = landing(t, theta0 + SPEED * t, y, v, face)
        assert impact["time"] == pytest.approx(t_hit, abs=1e-9)
        t, y, v = t_hit, lift(theta0 + SPEED * t_hit, 0, face), v_cam - e * (v_hit - v_cam)
        assert impact["rate_after"] == pytest.approx(-e * impact["rate_before"], rel=1e-9)
        after = mb.forward_dynamics(build(theta0, mb.RigidImpact(restitution=e), face),
                                    [0.0, t_hit + 1e-7], **TIGHT)
        rates = after.body("follower").velocity[-1, 1]
        # 0.1 us after the strike: the flight's acceleration moves the speed 1e-6 m/s
        assert rates == pytest.approx(v, abs=5e-6)


def test_a_flat_face_touches_the_cam_at_its_support_point():
    """A line against the eccentric circle, turned anyhow: the gap is the circle centre's
    height above the line less the radius, the normal the line's, and the surface from the
    circle's support function ``e cos + R`` is the circle again."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0))
    cam = b.add_body("cam", mass=1.0, inertia=1e-3, position=(0.0, 0.0))
    plate = b.add_body("plate", mass=0.5, inertia=1e-4, position=(0.0, 0.2))
    normal = np.array([0.6, -0.8])
    b.add(mb.Contact("c", mb.Cam(cam, surface()),
                     mb.Plane(plate, normal=normal, point=(0.01, -0.003)),
                     law=mb.LinearContact(stiffness=1e6, damping=10.0)))
    model = b.build()
    for q, qd in random_states(5):
        centre = q[:2] + turn(q[2]) @ np.array([ECC, 0.0])
        point, m = q[3:5] + turn(q[5]) @ np.array([0.01, -0.003]), turn(q[5]) @ normal
        state = mb.contact_states(model, q, qd)
        assert state.gap[0] == pytest.approx(m @ (centre - point) - R, abs=1e-11)
        np.testing.assert_allclose(state.normal[0, :2], -m, atol=1e-15)
        # midway between the circle's point nearest the line and the line
        lowest = centre - R * m
        np.testing.assert_allclose(state.point[0, :2], lowest - state.gap[0] / 2 * m,
                                   atol=1e-11)
        assert_rate_is_the_gaps_derivative(model, q, qd)
    support = CamProfile.sampled(lambda psi: ECC * np.cos(psi) + R, 1440)
    phi = np.linspace(0.0, 2 * math.pi, 1001)
    np.testing.assert_allclose(support.envelope(1440)(phi), surface()(phi), rtol=0, atol=1e-10)


def test_a_stiff_compliant_cam_contact_leaves_where_the_bilateral_cam_would_pull():
    """A stiff linear contact, damped about critically, carries the follower along the lift,
    the force it reports agreeing with the reaction of the bilateral ``CamFollower`` on the
    pitch circle, and lets go where that reaction crosses zero."""
    theta0 = 0.0
    law = mb.LinearContact(stiffness=1e9, damping=2 * math.sqrt(1e9 * MASS))
    t = np.linspace(0.0, 0.03, 61)
    res = mb.forward_dynamics(build(theta0, law), t, **dict(TIGHT, rtol=1e-9, atol=1e-11))
    force = res.contacts().normal_force[:, 0]
    with warnings.catch_warnings():  # it would pull after t_off: reported, and expected
        warnings.simplefilter("ignore", mb.LiftOffWarning)
        bilateral = mb.inverse_dynamics(build(theta0, None), t).joint("roller").contact_force
    t_off = (lift_off_angle() - theta0) / SPEED
    # after the first millisecond (the contact starts undeflected: a damped ring of 0.1 ms)
    before = (t > 1e-3) & (t < t_off - 1e-3)
    np.testing.assert_allclose(force[before], bilateral[before], rtol=0,
                               atol=1e-5 * np.max(bilateral))
    assert np.all(force[t > t_off + 1e-3][:5] == 0.0)


def test_cams_are_checked():
    b = mb.ModelBuilder(dim=2)
    cam = b.add_body("cam", mass=1.0, inertia=1e-3, position=(0.0, 0.0))
    roller = b.add_body("roller", mass=0.5, inertia=1e-4, position=(0.0, 0.2))
    with pytest.raises(ModelError, match="contact 'c'.*CamProfile"):
        b.add(mb.Contact("c", mb.Cam(cam, [1.0, 2.0]), mb.Sphere(roller, ROLLER),
                         law=mb.RigidImpact(0.5)))
        b.build()
    with pytest.raises(ModelError, match="no contact between a Cam and a Capsule"):
        mb.Contact("d", mb.Cam(cam, surface()), mb.Capsule(roller, 0.01, ends=[(0, 0), (1, 0)]),
                   law=mb.RigidImpact(0.5))
    s = mb.ModelBuilder(dim=3)
    body = s.add_body("cam", mass=1.0, inertia=np.eye(3), position=(0.0, 0.0, 0.0))
    other = s.add_body("ball", mass=1.0, inertia=np.eye(3), position=(0.0, 1.0, 0.0))
    s.add(mb.Contact("c", mb.Cam(body, surface()), mb.Sphere(other, 0.1),
                     law=mb.RigidImpact(0.5)))
    with pytest.raises(ModelError, match="contact 'c': cams are available for planar models"):
        s.build()
    with pytest.raises(ModelError, match="undercut"):
        CamProfile.sampled(lambda phi: 0.05 + 0.02 * np.cos(5 * phi)).surface(0.03)
    with pytest.raises(ModelError, match="not the support function of a convex cam"):
        CamProfile.sampled(lambda phi: 0.05 + 0.02 * np.cos(5 * phi)).envelope()


def test_the_viewer_draws_the_cam_as_its_surface():
    from mbd3d.viewer.shapes import contact_parts

    model = build(0.3, mb.RigidImpact(0.5))
    plate, = contact_parts(model, model.body("cam"), 0.1)
    rim = plate.vertices[1:, :2]  # the first vertex is the fan's centre
    np.testing.assert_allclose(np.linalg.norm(rim - [ECC, 0.0], axis=1), R, rtol=1e-9)
    assert np.all(plate.vertices[:, 2] == 0.0)


def test_the_iteration_matrix_takes_the_cam_contacts_velocity_slopes():
    """Generalized-alpha's tangent of a cam contact pressed in and slipping with friction: its
    velocity part (damping and friction) against central differences of the forces."""
    from test_generalized_alpha import _contact_tangent, _differenced_tangent

    b = mb.ModelBuilder(dim=2)
    cam = b.add_body("cam", mass=2.0, inertia=2e-3, position=(0.01, -0.02), angle=0.4)
    roller = b.add_body("roller", mass=0.5, inertia=1e-4, position=(0.0, 0.0))
    b.add(mb.Contact("c", mb.Cam(cam, surface()), mb.Sphere(roller, ROLLER),
                     law=mb.HuntCrossley(stiffness=3e6, restitution=0.6, impact_speed=1.0,
                                         exponent=1.5),
                     friction=0.4, slip_velocity=0.05))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mb.ContactWarning)
        model = b.build()
    q = model.q0.copy()
    # the roller 1 mm into the cam's surface, 60 degrees round from its eccentric
    angle = 0.4 + math.radians(60.0)
    centre = q[:2] + ECC * np.array([math.cos(0.4), math.sin(0.4)])
    q[3:5] = centre + (R + ROLLER - 1e-3) * np.array([math.cos(angle), math.sin(angle)])
    qd = np.random.default_rng(3).normal(size=6) * 0.05
    assert mb.contact_states(model, q, qd).gap[0] == pytest.approx(-1e-3, abs=1e-10)
    weight = 1e3
    _, _, D = _differenced_tangent(model, q, qd, model.charts0, weight)
    velocity_part = (_contact_tangent(model, q, qd, model.charts0, weight)
                     - _contact_tangent(model, q, qd, model.charts0, 0.0)) / weight
    assert np.abs(D).max() > 10.0
    np.testing.assert_allclose(velocity_part, D, rtol=0, atol=1e-6 * np.abs(D).max())


def test_generalized_alpha_carries_the_follower_on_a_stiff_cam_contact():
    """Generalized-alpha with the cam contact's stiffness in its iteration matrix: the
    follower carried along the lift as with DOP853 (the contact force to 1e-4 of it at 0.1 ms
    steps, a second-order method: measured 2.4e-5), and let go at the same angle."""
    law = mb.LinearContact(stiffness=1e8, damping=2 * math.sqrt(1e8 * MASS))
    t = np.linspace(0.0, 0.03, 31)
    runs = [mb.forward_dynamics(build(0.0, law), t, **options)
            for options in (dict(TIGHT, rtol=1e-9, atol=1e-11),
                            dict(method="generalized-alpha", step=1e-4))]
    force = [res.contacts().normal_force[:, 0] for res in runs]
    t_off = lift_off_angle() / SPEED
    riding = (t > 1e-3) & (t < t_off - 1e-3)
    np.testing.assert_allclose(force[1][riding], force[0][riding], rtol=0,
                               atol=1e-4 * np.max(force[0]))
    assert np.all(force[1][t > t_off + 1e-3][:5] == 0.0)
