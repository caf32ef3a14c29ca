"""The classical rolling disc, a nonholonomic joint: its rows against finite differences and
the contact's velocity computed apart, steady circular rolling at the closed-form speed-radius
relation (Omega^2 = 4 g tan(phi) / (6 R - 5 r sin(phi)) for a thin uniform disc, derived from
Euler's equations about the contact; Greenwood, *Advanced Dynamics*, 2003, sec. 8.5) and its
negative control, a disc rolling down an inclined plane at g sin(b) / (1 + J / (m r^2)),
energy conserved in a wobbling run; its linearisation about upright rolling against the lean
dynamics' closed form (stable above v^2 = g r / 3), its rest on a slope and its fall-over
rate; and the analyses that cannot take velocity-level rows refusing them by name."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import mbd3d as mb
from mbd3d.joints import RollingDiscOnPlane
from mbd3d.joints.base import triad
from mbd3d.model import constraints

G = 9.81
M, RADIUS = 2.0, 0.1
#: a thin uniform disc about its axis (the body x axis) and a diameter
THIN_DISC = np.diag([0.5, 0.25, 0.25]) * M * RADIUS ** 2
UP = np.array([0.0, 0.0, 1.0])


# planes whose normals are least aligned with x, y and z in turn: the in-plane axes the joint
# takes from the normal then have their zero component on each axis once, so every product
# of the second in-plane axis is non-zero in one of them
@pytest.mark.parametrize("normal", [(0.2, 0.6, -0.77), (-0.6, 0.2, 0.77), (0.6, 0.77, 0.2)])
def test_rows_against_finite_differences_and_the_contact_velocity(normal):
    """In random charts, off the constraint: the holonomic row's Jacobian and gamma by central
    differences of C; the velocity rows' ``B qd`` equal the in-plane velocity of the disc's
    material point at the contact (angular velocity from the rotation's time difference), and
    their gamma equals ``-(d/dt B) qd`` by differences along ``q + s qd``."""
    rng = np.random.default_rng(1)
    b = mb.ModelBuilder(dim=3)
    disc = b.add_body("disc", mass=M, inertia=THIN_DISC, position=(0.3, 0.2, 0.5),
                      orientation=Rotation.random(random_state=4).as_matrix())
    normal = np.array(normal) / np.linalg.norm(normal)
    b.add(RollingDiscOnPlane("roll", b.ground, disc, radius=0.4, axis=rng.normal(size=3),
                             normal=normal, point=(0.0, 0.0, -0.2)))
    model = b.build()
    assert list(model.velocity_rows) == [1, 2]
    q = model.q0 + 0.3 * rng.normal(size=6)
    qd = rng.normal(size=6)
    charts = np.tile(np.eye(3), (2, 1, 1))
    charts[0] = Rotation.random(random_state=9).as_matrix()
    frames = lambda x, v=None: constraints.frames(model, x, v, charts)  # noqa: E731
    C = lambda x: constraints.residual(model, 0.0, x, frames(x))  # noqa: E731
    Cq = lambda x: constraints.jacobian(model, 0.0, x, frames(x), sparse=False)  # noqa: E731
    h = 1e-6
    fd = np.column_stack([(C(q + h * e) - C(q - h * e)) / (2 * h) for e in np.eye(6)])
    np.testing.assert_allclose(Cq(q)[0], fd[0], rtol=0, atol=1e-9)
    assert np.all(C(q)[1:] == 0.0)  # velocity rows have no value
    gamma = constraints.acceleration_rhs(model, 0.0, q, qd, frames(q, qd))
    s = 1e-5
    second = (C(q + s * qd) - 2 * C(q) + C(q - s * qd)) / s ** 2
    assert gamma[0] == pytest.approx(-second[0], abs=1e-5)
    rate = (Cq(q + s * qd) @ qd - Cq(q - s * qd) @ qd) / (2 * s)
    np.testing.assert_allclose(gamma[1:], -rate[1:], rtol=0, atol=1e-8)

    rotation = lambda x: charts[0] @ mb.rotations.from_rodrigues(x[3:])  # noqa: E731
    spin = (rotation(q + h * qd) - rotation(q - h * qd)) / (2 * h) @ rotation(q).T
    omega = np.array([spin[2, 1], spin[0, 2], spin[1, 0]])
    axis = rotation(q) @ model.groups[0].params["a_j"][0]
    along = axis @ normal
    contact = 0.4 * (along * axis - normal) / math.sqrt(1 - along ** 2)
    velocity = qd[:3] + np.cross(omega, contact)
    t_1 = triad(normal)[0]
    np.testing.assert_allclose(Cq(q)[1:] @ qd, [t_1 @ velocity, np.cross(normal, t_1) @ velocity],
                               rtol=1e-8)


def steady_disc(lean: float, path_radius: float, turning: float) -> mb.Model:
    """A thin disc started rolling on a circle of ``path_radius`` (the contact's), leaning
    ``lean`` towards the centre (the origin), turning at ``turning`` rad/s about the vertical,
    its spin set by rolling."""
    inwards = np.array([-math.sin(lean), 0.0, math.cos(lean)])  # contact to centre
    centre = np.array([path_radius, 0.0, 0.0]) + RADIUS * inwards
    axis = np.array([math.cos(lean), 0.0, math.sin(lean)])
    velocity = turning * np.array([0.0, centre[0], 0.0])
    # omega = s axis + turning z with the contact at rest: s from the heading's component
    contact = -RADIUS * inwards
    spin = -(velocity[1] + np.cross(turning * UP, contact)[1]) / np.cross(axis, contact)[1]
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G), name="rolling disc")
    disc = b.add_body("disc", mass=M, inertia=THIN_DISC, position=centre,
                      orientation=mb.rotations.frame_along(axis), velocity=velocity,
                      angular_velocity=spin * axis + turning * UP)
    b.add(RollingDiscOnPlane("roll", b.ground, disc, radius=RADIUS, axis=axis))
    return b.build()


def steady_turning(lean: float, path_radius: float) -> float:
    """The closed form's turning rate of steady circular rolling [rad/s]."""
    return math.sqrt(4 * G * math.tan(lean) / (6 * path_radius - 5 * RADIUS * math.sin(lean)))


def test_steady_circular_rolling_at_the_closed_form_speed():
    lean, path_radius = math.radians(10.0), 0.5
    turning = steady_turning(lean, path_radius)
    assert turning == pytest.approx(1.541134, abs=5e-7)  # the formula sheet's number
    model = steady_disc(lean, path_radius, turning)
    report = mb.mobility(model)
    assert (report.dof, report.configuration_dof, report.velocity_rows) == (3, 5, 2)
    t = np.linspace(0.0, 2 * math.pi / turning, 41)  # one turn round the circle
    res = mb.forward_dynamics(model, t, method="DOP853", rtol=1e-11, atol=1e-12)
    assert res.stats["initial_state"] == {"positions": {}, "velocities": {}}
    disc = res.body("disc")
    centre_path = path_radius - RADIUS * math.sin(lean)
    np.testing.assert_allclose(np.hypot(disc.position[:, 0], disc.position[:, 1]), centre_path,
                               rtol=0, atol=1e-10)
    axis = np.einsum("kab,b->ka", disc.rotation, [1.0, 0.0, 0.0])
    np.testing.assert_allclose(axis[:, 2], math.sin(lean), rtol=0, atol=1e-10)
    # heading: the centre goes round once, back where it started
    heading = np.unwrap(np.arctan2(disc.position[:, 1], disc.position[:, 0]))
    np.testing.assert_allclose(heading, turning * t, rtol=0, atol=1e-9)
    joint = res.joint("roll")
    np.testing.assert_allclose(joint.contact_force, M * G, rtol=1e-10)
    # the friction holds the centre on its circle: m Omega^2 R_G towards the turn's centre
    point, normal = joint.contact()
    inwards = -point / np.linalg.norm(point, axis=1)[:, None]
    np.testing.assert_allclose(joint.traction, M * turning ** 2 * centre_path * inwards,
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(point[:, :2], axis=1), path_radius,
                               rtol=0, atol=1e-10)
    assert np.max(np.abs(point[:, 2])) < 1e-12 and np.all(normal == UP)
    energy = res.kinetic_energy + res.potential_energy
    assert np.ptp(energy) < 1e-10 * res.kinetic_energy[0]


def test_off_the_closed_form_the_disc_does_not_roll_steadily():
    """Negative control: turning 5 % slower than the closed form, the lean changes by degrees
    within a second."""
    lean, path_radius = math.radians(10.0), 0.5
    model = steady_disc(lean, path_radius, 0.95 * steady_turning(lean, path_radius))
    res = mb.forward_dynamics(model, np.linspace(0.0, 1.0, 11), method="DOP853", rtol=1e-10,
                              atol=1e-12)
    axis = np.einsum("kab,b->ka", res.body("disc").rotation, [1.0, 0.0, 0.0])
    assert np.ptp(np.degrees(np.arcsin(axis[:, 2]))) > 1.0


@pytest.mark.parametrize("method", ["DOP853", "RK45"])
def test_disc_rolls_straight_down_an_inclined_plane(method):
    """Upright on a plane tilted by b about x, its axis horizontal: it rolls straight down the
    slope at g sin(b) / (1 + J / (m r^2)) = 2/3 g sin(b), held by a friction of a third of the
    slope's pull, pressing m g cos(b)."""
    slope = 0.3
    normal = np.array([0.0, -math.sin(slope), math.cos(slope)])
    down = np.array([0.0, -math.cos(slope), -math.sin(slope)])
    axis = np.array([1.0, 0.0, 0.0])
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G), name="disc on a slope")
    disc = b.add_body("disc", mass=M, inertia=THIN_DISC, position=RADIUS * normal)
    b.add(RollingDiscOnPlane("roll", b.ground, disc, radius=RADIUS, axis=axis, normal=normal,
                             point=(0.0, 0.0, 0.0)))
    t = np.linspace(0.0, 1.0, 11)
    options = dict(rtol=1e-11, atol=1e-12) if method == "DOP853" else dict(rtol=1e-9)
    res = mb.forward_dynamics(b.build(), t, method=method, **options)
    accel = G * math.sin(slope) / 1.5
    travel = res.body("disc").position - RADIUS * normal
    tolerance = 1e-10 if method == "DOP853" else 1e-6
    np.testing.assert_allclose(travel, 0.5 * accel * np.outer(t * t, down), rtol=0,
                               atol=tolerance)
    # turning about its axis at the speed over the radius: x (axis) cross the normal is
    # down the slope, so rolling down is turning about +x
    np.testing.assert_allclose(res.body("disc").angular_velocity,
                               np.outer(accel * t / RADIUS, axis), rtol=0, atol=tolerance * 10)
    joint = res.joint("roll")
    np.testing.assert_allclose(joint.contact_force, M * G * math.cos(slope), rtol=1e-9)
    np.testing.assert_allclose(joint.traction, np.outer(np.full(len(t), -M * accel / 2), down),
                               rtol=0, atol=1e-8)


def test_a_wobbling_disc_keeps_its_energy_and_its_contact_still():
    """Started leaning and turning off any steady motion, with rates that break rolling (the
    start is projected onto the rolling velocities, and the change reported): energy stays
    constant, the contact on the plane, and the disc's material point there at rest."""
    lean = math.radians(25.0)
    axis = np.array([math.cos(lean), 0.0, math.sin(lean)])
    centre = RADIUS * np.array([-math.sin(lean), 0.0, math.cos(lean)])
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G), name="wobbling disc")
    disc = b.add_body("disc", mass=M, inertia=THIN_DISC, position=centre,
                      orientation=mb.rotations.frame_along(axis),
                      velocity=(0.1, 0.8, 0.0), angular_velocity=(0.5, 0.3, 2.0))
    b.add(RollingDiscOnPlane("roll", b.ground, disc, radius=RADIUS, axis=axis))
    t = np.linspace(0.0, 2.0, 81)
    with pytest.warns(mb.InitialStateWarning, match="disc"):
        res = mb.forward_dynamics(b.build(), t, method="DOP853", rtol=1e-11, atol=1e-12)
    h = res.body("disc")
    energy = res.kinetic_energy + res.potential_energy
    assert np.ptp(energy) < 1e-9 * np.max(res.kinetic_energy)
    point, _ = res.joint("roll").contact()
    assert np.max(np.abs(point[:, 2])) < 1e-11
    material = h.velocity + np.cross(h.angular_velocity, point - h.position)
    assert np.max(np.abs(material)) < 1e-9
    # it does wobble: the lean changes by degrees, the heading turns
    tilt = np.degrees(np.arcsin(np.einsum("kab,b->ka", h.rotation, [1.0, 0.0, 0.0])[:, 2]))
    assert np.ptp(tilt) > 5.0


def test_analyses_that_need_positions_from_the_constraints_refuse_it():
    model = steady_disc(math.radians(10.0), 0.5, 1.5)
    t = np.linspace(0.0, 0.1, 3)
    for run in (lambda: mb.kinematic_analysis(model, t),
                lambda: mb.inverse_dynamics(model, t),
                lambda: mb.forward_dynamics(model, t, method="generalized-alpha", step=1e-3)):
        with pytest.raises(mb.ModelError, match="'roll' constrains velocities only.*DOP853"):
            run()


def _upright(speed: float) -> mb.Model:
    """A thin disc standing upright with its axis along x, rolling along y at ``speed``."""
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G), name="upright disc")
    axis = np.array([1.0, 0.0, 0.0])
    disc = b.add_body("disc", mass=M, inertia=THIN_DISC, position=(0.0, 0.0, RADIUS),
                      orientation=mb.rotations.frame_along(axis), velocity=(0.0, speed, 0.0),
                      angular_velocity=-speed / RADIUS * axis)
    b.add(RollingDiscOnPlane("roll", b.ground, disc, radius=RADIUS, axis=axis))
    return b.build()


@pytest.mark.parametrize("speed", [0.0, 0.3, 0.8, 1.5])
def test_upright_rolling_linearises_to_the_closed_form_lean_dynamics(speed):
    """About upright straight rolling at spin w, the lean phi and the heading psi obey
    (A + m r^2) phi'' + (C + m r^2) w psi' - m g r phi = 0 and A psi'' = C w phi' (A about a
    diameter, C about the axis; with the heading's equation integrated the lean's stiffness
    is (C + m r^2) C w^2 / A - m g r): a thin disc is stable above w^2 = g / (3 r), where the
    lean's pair of roots turns from real to imaginary (the closed form's period is a nudged
    disc's, next test). The disc's own axes turn with its spin, a frame that does not
    turn (frame_rate 0) sees a steady motion. The rolling rows leave 5 displacements and 3
    velocities; the other roots are zero (place, heading, spin angle and rate are free)."""
    model = _upright(speed)
    lin = mb.linearize(model, model.q0, model.qd0, frame_rate=(0.0, 0.0, 0.0))
    assert lin.A.shape == (8, 8) and len(lin.states) == 8
    assert lin.basis.shape == (6, 5) and lin.rate_basis.shape == (6, 3)
    A_, C_ = THIN_DISC[1, 1], THIN_DISC[0, 0]
    w = speed / RADIUS
    stiffness = (C_ + M * RADIUS ** 2) * C_ * w ** 2 / A_ - M * G * RADIUS
    root = np.sqrt(complex(-stiffness / (A_ + M * RADIUS ** 2)))
    values = lin.eigenvalues
    pair = values[np.argsort(-np.abs(values))[:2]]
    np.testing.assert_allclose(np.sort_complex(pair), np.sort_complex([root, -root]),
                               rtol=1e-6, atol=1e-9 * abs(root))
    assert np.sort(np.abs(values))[5] < 1e-5 * abs(root)
    # stable exactly above the critical speed sqrt(g r / 3)
    assert (speed > math.sqrt(G * RADIUS / 3.0)) == (np.max(values.real) < 1e-5 * abs(root))


def test_the_lean_closed_form_is_the_nonlinear_disc_s_wobble():
    """The closed form the linearisation is checked against, checked in turn: a disc rolling
    upright at 1.5 m/s, nudged with a lean rate of 0.01 rad/s, wobbles at its period."""
    speed, nudge = 1.5, 0.01
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G), name="nudged disc")
    axis = np.array([1.0, 0.0, 0.0])
    # the lean turns the disc about the rolling direction, its contact at rest
    disc = b.add_body("disc", mass=M, inertia=THIN_DISC, position=(0.0, 0.0, RADIUS),
                      orientation=mb.rotations.frame_along(axis),
                      velocity=(nudge * RADIUS, speed, 0.0),
                      angular_velocity=-speed / RADIUS * axis + nudge * np.eye(3)[1])
    b.add(RollingDiscOnPlane("roll", b.ground, disc, radius=RADIUS, axis=axis))
    t = np.linspace(0.0, 1.5, 3001)
    res = mb.forward_dynamics(b.build(), t, method="DOP853", rtol=1e-11, atol=1e-13)
    lean = np.arcsin(res.body("disc").rotation[:, 2, 0])
    assert np.max(np.abs(lean)) < 1e-3  # small: the linear regime
    # its zero crossings, located between outputs
    k = np.flatnonzero(np.sign(lean[1:]) != np.sign(lean[:-1]))[1:]
    crossings = t[k] - lean[k] * (t[k + 1] - t[k]) / (lean[k + 1] - lean[k])
    period = 2.0 * np.mean(np.diff(crossings))
    A_, C_ = THIN_DISC[1, 1], THIN_DISC[0, 0]
    w = speed / RADIUS
    stiffness = (C_ + M * RADIUS ** 2) * C_ * w ** 2 / A_ - M * G * RADIUS
    assert period == pytest.approx(2 * math.pi * math.sqrt((A_ + M * RADIUS ** 2) / stiffness),
                                   rel=1e-4)


def test_a_disc_at_rest_on_a_slope_leans_until_its_centre_is_above_the_contact():
    """Standing square to a plane tilted 20 degrees, rolling direction along the level line,
    the disc can rest only leaning so that gravity passes through the contact (it cannot roll
    down: the rolling rows hold it sideways): there the plane pushes m g cos(b) along its
    normal and the rolling rows m g sin(b) up the slope, and the rest is unstable (it falls
    over); static equilibrium finds it from the square stance. Its fall-over on a level
    plane is the root sqrt(m g r / (A + m r^2)) of the upright disc at rest."""
    beta = math.radians(20.0)
    normal = np.array([0.0, -math.sin(beta), math.cos(beta)])
    axis = np.cross(normal, [1.0, 0.0, 0.0])  # square to the plane, along its fall line
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G), name="disc on a slope")
    disc = b.add_body("disc", mass=M, inertia=THIN_DISC, position=RADIUS * normal,
                      orientation=mb.rotations.frame_along(axis))
    b.add(RollingDiscOnPlane("roll", b.ground, disc, radius=RADIUS, axis=axis, normal=normal,
                             point=(0.0, 0.0, 0.0)))
    rest = mb.static_equilibrium(b.build())
    assert rest.stats["stability"] == ["unstable"]
    point, _ = rest.joint("roll").contact()
    np.testing.assert_allclose(rest.body("disc").position[0, :2], point[0, :2], rtol=0,
                               atol=1e-12)
    np.testing.assert_allclose(rest.joint("roll").contact_force, M * G * math.cos(beta),
                               rtol=1e-12)
    np.testing.assert_allclose(rest.joint("roll").traction[0],
                               M * G * math.sin(beta) * np.cross(normal, [1.0, 0.0, 0.0]),
                               rtol=0, atol=1e-12 * M * G)
    modes = mb.vibration_modes(_upright(0.0))
    fall = math.sqrt(M * G * RADIUS / (THIN_DISC[1, 1] + M * RADIUS ** 2))
    np.testing.assert_allclose(2 * math.pi * modes.frequencies[-2:], fall, rtol=1e-7)
    np.testing.assert_array_equal(np.sort(modes.damping_ratios[-2:]), [-1.0, 1.0])
    np.testing.assert_allclose(modes.frequencies[:-2], 0.0, rtol=0, atol=1e-7 * fall)


@pytest.mark.parametrize("change, words", [
    (dict(axis=(0.0, 0.0, 1.0)), ["'roll'", "lies flat"]),
    (dict(radius=0.0), ["'roll'", "radius"]),
    (dict(body_i="arm"), ["'roll'", "ground", "'arm'"]),
])
def test_bad_rolling_discs_are_named(change, words):
    b = mb.ModelBuilder(dim=3, name="bad disc")
    disc = b.add_body("disc", mass=M, inertia=THIN_DISC, position=(0.0, 0.0, RADIUS))
    arm = b.add_body("arm", mass=M, inertia=THIN_DISC, position=(1.0, 0.0, 0.0))
    options = {"radius": RADIUS, "axis": (1.0, 0.0, 0.0), **change}
    body_i = arm if options.pop("body_i", None) == "arm" else b.ground
    b.add(RollingDiscOnPlane("roll", body_i, disc, **options))
    with pytest.raises(mb.ModelError) as info:
        b.build()
    for word in words:
        assert word in str(info.value), str(info.value)


def test_planar_models_take_the_planar_disc():
    b = mb.ModelBuilder(dim=2, name="planar")
    disc = b.add_body("disc", mass=M, inertia=0.01, position=(0.0, RADIUS))
    b.add(RollingDiscOnPlane("roll", b.ground, disc, radius=RADIUS, axis=(1.0, 0.0)))
    with pytest.raises(mb.ModelError, match="'roll'.*RollingDisc"):
        b.build()
