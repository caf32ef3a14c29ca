"""Joint friction against what Coulomb friction must do: a block on an incline (sliding at
g (sin a - mu cos a), creeping at the regularised law's speed below the friction angle), a
pendulum with pin friction against its one-degree-of-freedom equation (derived by hand below,
the pin force depending on the acceleration it limits) with the energy lost equal to the
friction's work, the same pendulum built in space, and a slider-crank at constant speed whose
motor torque is computed by hand with the friction that its own normal forces cause.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mbd3d as mb
from mbd3d.joints import Distance, Prismatic, Revolute, RotationDriver, Spherical

G = 9.81
INTEGRATORS = [dict(method="DOP853", rtol=1e-11, atol=1e-12),
               dict(method="generalized-alpha", step=1e-3)]


def incline(slope: float, mu: float, speed: float = 0.0, stiction: float = 1e-3):
    """A 2 kg block on a prismatic joint down a slope, ``speed`` [m/s] down it at the start."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G), name="incline")
    down = np.array([math.cos(slope), -math.sin(slope)])
    block = b.add_body("block", mass=2.0, inertia=0.1, position=(0.0, 0.0), angle=-slope,
                       velocity=speed * down)
    slide = b.add(Prismatic("slide", b.ground, block, axis=down))
    b.add(mb.JointFriction("friction", slide, mu, stiction_velocity=stiction))
    return b.build(), down


@pytest.mark.parametrize("options", INTEGRATORS, ids=["DOP853", "generalized-alpha"])
@pytest.mark.parametrize("speed", [1.0, -1.0], ids=["down", "up"])
def test_sliding_block_accelerates_at_the_coulomb_rate(options, speed):
    slope, mu = 0.5, 0.2
    model, down = incline(slope, mu, speed)
    # moving down, friction holds it back; moving up, friction and gravity both slow it
    accel = G * (math.sin(slope) - math.copysign(mu, speed) * math.cos(slope))
    t = np.linspace(0.0, 0.1, 6)  # the block going up does not stop before 0.1 s
    res = mb.forward_dynamics(model, t, **options)
    travel = (res.body("block").position - res.body("block").position[0]) @ down
    np.testing.assert_allclose(travel, speed * t + 0.5 * accel * t * t, rtol=0, atol=1e-11)
    np.testing.assert_allclose(res.friction("friction"), -math.copysign(
        mu * 2.0 * G * math.cos(slope), speed), rtol=1e-11)


@pytest.mark.parametrize("options", INTEGRATORS, ids=["DOP853", "generalized-alpha"])
def test_block_below_the_friction_angle_creeps_at_the_regularised_speed(options):
    slope, mu, stiction = 0.2, 0.3, 1e-3
    assert math.tan(slope) < mu
    model, down = incline(slope, mu, stiction=stiction)
    t = np.array([0.0, 0.2, 0.3])
    res = mb.forward_dynamics(model, t, **options)
    creep = stiction * math.atanh(math.tan(slope) / mu)
    speed = res.body("block").velocity @ down
    pull = 2.0 * G * math.sin(slope)
    if options["method"] == "DOP853":
        np.testing.assert_allclose(speed[1:], creep, rtol=1e-7)
        np.testing.assert_allclose(res.friction("friction")[1:], -pull, rtol=1e-7)
    else:
        # generalized-alpha's Newton tolerance on positions (1e-10 of the model's scale)
        # leaves velocity errors up to gamma' 1e-10 m, about 2e-7 m/s at h = 1e-3
        np.testing.assert_allclose(speed[1:], creep, rtol=0, atol=2e-8)
        np.testing.assert_allclose(res.friction("friction")[1:], -pull, rtol=1e-5)


PIN = dict(L=0.8, m=1.5, mu=0.3, r=0.02, v_s=1e-3)


def pendulum(spatial: bool = False) -> mb.Model:
    """A bar hinged at the origin with pin friction, released 30 degrees above horizontal."""
    p = PIN
    theta0 = math.radians(30.0)
    c = p["L"] / 2
    centre = c * np.array([math.cos(theta0), math.sin(theta0)])
    inertia = p["m"] * p["L"] ** 2 / 12
    if spatial:
        b = mb.ModelBuilder(dim=3, gravity=(0.0, -G, 0.0), name="friction pendulum 3D")
        bar = b.add_body("bar", mass=p["m"], inertia=np.diag([1e-3, inertia, inertia]),
                         position=(*centre, 0.0),
                         orientation=mb.rotations.frame_along((math.cos(theta0),
                                                               math.sin(theta0), 0.0)))
        pin = b.add(Revolute("O", b.ground, bar, at=(0.0, 0.0, 0.0), axis=(0.0, 0.0, 1.0)))
    else:
        b = mb.ModelBuilder(dim=2, gravity=(0.0, -G), name="friction pendulum")
        bar = b.add_body("bar", mass=p["m"], inertia=inertia, position=centre, angle=theta0)
        pin = b.add(Revolute("O", b.ground, bar, at=(0.0, 0.0)))
    b.add(mb.JointFriction("pin friction", pin, p["mu"], pin_radius=p["r"],
                           stiction_velocity=p["v_s"]))
    return b.build()


def pendulum_by_hand(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """theta, theta' and the friction's work from the bar's own equations: J theta'' =
    -m g c cos(theta) + T, T = -mu r |F| tanh(r theta' / v_s), with the pin force
    F = m a_c - m g depending on theta'' (solved by iterating: mu r m c / J is small)."""
    p = PIN
    m, c, mu, r = p["m"], p["L"] / 2, p["mu"], p["r"]
    J = m * p["L"] ** 2 / 12 + m * c * c

    def rhs(_, y):
        theta, rate, _work = y
        accel = -m * G * c * math.cos(theta) / J
        for _ in range(60):
            radial = -c * rate * rate  # along the bar, from the pin
            tangential = c * accel
            # F = m a_c - m g, in the bar's axes (g = -G y)
            force = np.array([m * radial + m * G * math.sin(theta),
                              m * tangential + m * G * math.cos(theta)])
            torque = -mu * r * np.linalg.norm(force) * math.tanh(r * rate / p["v_s"])
            accel = (-m * G * c * math.cos(theta) + torque) / J
        return [rate, accel, torque * rate]

    sol = solve_ivp(rhs, (t[0], t[-1]), [math.radians(30.0), 0.0, 0.0], t_eval=t,
                    method="DOP853", rtol=1e-12, atol=1e-12)
    return sol.y


def test_pendulum_with_pin_friction_matches_its_equation_and_loses_the_friction_work():
    t = np.linspace(0.0, 1.5, 16)
    res = mb.forward_dynamics(pendulum(), t, **INTEGRATORS[0])
    theta, rate, work = pendulum_by_hand(t)
    np.testing.assert_allclose(res.body("bar").angle, theta, rtol=0, atol=1e-8)
    energy = res.kinetic_energy + res.potential_energy
    np.testing.assert_allclose(energy - energy[0], work, rtol=0, atol=1e-8)
    assert work[-1] < -0.05 * (energy[0] - energy.min())  # friction took a visible share
    # the reported friction torque is mu r |pin force| against the turning
    force = res.joint("O").reaction(on="bar").force
    np.testing.assert_allclose(res.friction("pin friction"), -PIN["mu"] * PIN["r"]
                               * np.linalg.norm(force, axis=1)
                               * np.tanh(PIN["r"] * rate / PIN["v_s"]), rtol=1e-6, atol=1e-12)


def test_generalized_alpha_with_pin_friction_converges_at_second_order():
    """Its error against the pendulum's equation is the method's own: a quarter for half the
    step."""
    t = np.linspace(0.0, 1.5, 16)
    theta = pendulum_by_hand(t)[0]
    errors = [np.max(np.abs(mb.forward_dynamics(pendulum(), t, method="generalized-alpha",
                                                step=h).body("bar").angle - theta))
              for h in (2e-3, 1e-3)]
    assert errors[1] < 1e-4 and 3.0 < errors[0] / errors[1] < 5.0, errors


def test_spatial_pendulum_in_the_plane_reproduces_the_planar_one():
    t = np.linspace(0.0, 1.0, 11)
    options = INTEGRATORS[0]
    planar = mb.forward_dynamics(pendulum(), t, **options)
    spatial = mb.forward_dynamics(pendulum(spatial=True), t, **options)
    np.testing.assert_allclose(spatial.body("bar").position[:, :2],
                               planar.body("bar").position, rtol=0, atol=1e-9)
    np.testing.assert_allclose(spatial.friction("pin friction"), planar.friction("pin friction"),
                               rtol=1e-7, atol=1e-10)


def slider_crank(mu_slider: float, mu_pin: float) -> mb.Model:
    """A crank (centre of mass on its axle) at 10 rad/s pushes a 2 kg slider through a massless
    link (a Distance joint), no gravity; friction in the slider's guide and the crank's axle."""
    r, link = 0.1, 0.3
    b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0), name="slider-crank with friction")
    phi0 = 0.4
    a = r * np.array([math.cos(phi0), math.sin(phi0)])
    crank = b.add_body("crank", mass=1.0, inertia=0.01, position=(0.0, 0.0), angle=phi0)
    x0 = a[0] + math.sqrt(link ** 2 - a[1] ** 2)
    slider = b.add_body("slider", mass=2.0, inertia=0.01, position=(x0, 0.0))
    axle = b.add(Revolute("O", b.ground, crank, at=(0.0, 0.0)))
    guide = b.add(Prismatic("guide", b.ground, slider, axis=(1.0, 0.0)))
    b.add(Distance("link", crank, slider, point_i=(r, 0.0), point_j=(0.0, 0.0)))
    b.add(RotationDriver("motor", axle, motion=mb.Ramp(phi0, 10.0)))
    if mu_slider:
        b.add(mb.JointFriction("guide friction", guide, mu_slider))
    if mu_pin:
        b.add(mb.JointFriction("axle friction", axle, mu_pin, pin_radius=0.015))
    return b.build()


def test_slider_crank_motor_torque_rises_by_the_friction_computed_by_hand():
    r, link, omega, m = 0.1, 0.3, 10.0, 2.0
    mu_s, mu_o, r_o = 0.25, 0.2, 0.015
    t = np.linspace(0.0, 0.6, 25)
    res = mb.inverse_dynamics(slider_crank(mu_s, mu_o), t)
    phi = 0.4 + omega * t
    s, c = np.sin(phi), np.cos(phi)
    root = np.sqrt(link ** 2 - r ** 2 * s ** 2)
    x = r * c + root
    x_rate = -r * s * omega - r * r * s * c * omega / root
    x_accel = (-r * c * omega ** 2 - r * r * omega ** 2 * (c * c - s * s) / root
               - (r * r * s * c * omega) ** 2 / root ** 3)
    # the link's compression P along e (from the crank pin A to the slider): on the slider
    # m x'' = P e_x + f, the guide holding N = -P e_y, f = -mu |N| s_v with the law's
    # s_v = tanh(x' / v_s) (the slider passes its dead centres at a few v_s); so
    # P (e_x - mu s_v sign(P) |e_y|) = m x'', the sign of P found by trying both
    A = r * np.column_stack([c, s])
    e = (np.column_stack([x, np.zeros_like(x)]) - A) / link
    sv = np.tanh(x_rate / 1e-3)
    P = np.empty_like(x)
    for k in range(len(t)):
        for sign in (1.0, -1.0):
            candidate = m * x_accel[k] / (e[k, 0] - mu_s * sv[k] * sign * abs(e[k, 1]))
            if np.sign(candidate) == sign:
                P[k] = candidate
    # the crank (centre on its axle, at constant speed): the axle carries P e, the motor
    # balances the link's moment and the axle's friction
    torque = A[:, 0] * P * e[:, 1] - A[:, 1] * P * e[:, 0] + mu_o * r_o * np.abs(P)
    np.testing.assert_allclose(res.driver("motor").effort, torque, rtol=1e-10)
    np.testing.assert_allclose(res.friction("guide friction"),
                               -mu_s * np.abs(P * e[:, 1]) * sv, rtol=1e-10)
    # without friction the motor only moves the slider's inertia: friction adds a tenth
    plain = mb.inverse_dynamics(slider_crank(0.0, 0.0), t).driver("motor").effort
    added = res.driver("motor").effort - plain
    assert np.max(np.abs(added)) > 0.05 * np.max(np.abs(plain))


@pytest.mark.parametrize("make, words", [
    (lambda b, j, s: mb.JointFriction("f", s, 0.2), ["'f'", "Revolute and Prismatic"]),
    (lambda b, j, s: mb.JointFriction("f", j, 0.2), ["'f'", "pin_radius="]),
    (lambda b, j, s: mb.JointFriction("f", j, -0.2, pin_radius=0.01), ["'f'", "coefficient"]),
    (lambda b, j, s: mb.JointFriction("f", j, 0.2, pin_radius=0.01, stiction_velocity=0.0),
     ["'f'", "stiction_velocity", "positive"]),
    (lambda b, j, s: mb.JointFriction("f", Revolute("loose", b.ground, b.ground), 0.1,
                                      pin_radius=0.01), ["'f'", "'loose' is not part"]),
])
def test_bad_joint_friction_is_named(make, words):
    b = mb.ModelBuilder(dim=3, name="bad friction")
    bar = b.add_body("bar", mass=1.0, inertia=np.eye(3) * 1e-2, position=(0.5, 0.0, 0.0))
    bob = b.add_body("bob", mass=1.0, inertia=np.eye(3) * 1e-2, position=(1.0, 0.0, 0.0))
    hinge = b.add(Revolute("hinge", b.ground, bar, at=(0.0, 0.0, 0.0), axis=(0.0, 0.0, 1.0)))
    ball = b.add(Spherical("ball", bar, bob, at=(1.0, 0.0, 0.0)))
    b.add(make(b, hinge, ball))
    with pytest.raises(mb.ModelError) as info:
        b.build()
    for word in words:
        assert word in str(info.value), str(info.value)


def test_friction_with_redundant_constraints_is_refused():
    """Redundant constraints leave the reactions, so the friction, undetermined."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G), name="double pin")
    bar = b.add_body("bar", mass=1.0, inertia=0.05, position=(0.5, 0.0))
    pin = b.add(Revolute("pin", b.ground, bar, at=(0.0, 0.0)))
    b.add(Revolute("same pin", b.ground, bar, at=(0.0, 0.0)))
    b.add(mb.JointFriction("f", pin, 0.2, pin_radius=0.01))
    with pytest.raises(mb.AnalysisError, match="'f'.*not unique"):
        mb.forward_dynamics(b.build(), [0.0, 0.1])


def test_tilted_rotor_spins_down_by_its_pin_and_thrust_friction():
    """A rotor spinning on a hinge tilted by beta from the vertical, centre of mass on the
    pin: the pin carries m g, m g sin(beta) across the axis (at the pin radius) and
    m g cos(beta) along it (at the thrust face's arm), so the spin falls at
    mu m g (r sin(beta) + a cos(beta)) / J_axis."""
    m, j_axis, j_across, beta, mu, r, arm = 3.0, 0.05, 0.03, 0.6, 0.3, 0.01, 0.03
    axis = np.array([math.sin(beta), 0.0, math.cos(beta)])
    turned = np.array([[math.cos(beta), 0.0, math.sin(beta)], [0.0, 1.0, 0.0],
                       [-math.sin(beta), 0.0, math.cos(beta)]])  # body z along the hinge
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G))
    rotor = b.add_body("rotor", mass=m, inertia=[j_across, j_across, j_axis],
                       position=(0.2, -0.1, 0.5), orientation=turned,
                       angular_velocity=20.0 * axis)
    hinge = b.add(Revolute("hinge", b.ground, rotor, at=(0.2, -0.1, 0.5), axis=axis))
    b.add(mb.JointFriction("friction", hinge, mu, pin_radius=r, axial_arm=arm))
    t = np.linspace(0.0, 0.5, 6)
    res = mb.forward_dynamics(b.build(), t, **INTEGRATORS[0])
    torque = mu * m * G * (r * math.sin(beta) + arm * math.cos(beta))
    np.testing.assert_allclose(res.body("rotor").angular_velocity @ axis,
                               20.0 - torque / j_axis * t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.friction("friction"), -torque, rtol=1e-10)


def test_spatial_block_slides_against_the_friction_of_its_whole_normal_force():
    """A block on a spatial prismatic joint along x, gravity with components along both
    normals (y and z, unequal): the normal force is m (g_y^2 + g_z^2)^(1/2), the block
    accelerates at g_x - mu (g_y^2 + g_z^2)^(1/2)."""
    gravity, mu, m = np.array([2.0, -3.0, -9.81]), 0.1, 2.0
    b = mb.ModelBuilder(dim=3, gravity=gravity)
    block = b.add_body("block", mass=m, inertia=[0.02, 0.03, 0.04], position=(0.1, 0.2, 0.3),
                       velocity=(1.0, 0.0, 0.0))
    slide = b.add(Prismatic("slide", b.ground, block, axis=(1.0, 0.0, 0.0)))
    b.add(mb.JointFriction("friction", slide, mu))
    t = np.linspace(0.0, 0.5, 6)
    res = mb.forward_dynamics(b.build(), t, **INTEGRATORS[0])
    normal = math.hypot(gravity[1], gravity[2])
    accel = gravity[0] - mu * normal
    np.testing.assert_allclose(res.body("block").position[:, 0], 0.1 + t + 0.5 * accel * t * t,
                               rtol=0, atol=1e-10)
    np.testing.assert_allclose(res.friction("friction"), -mu * m * normal, rtol=1e-10)


@pytest.mark.parametrize("kind", ["revolute", "prismatic"])
def test_friction_between_two_free_bodies_keeps_their_momentum(kind):
    """A spinning pair of free bodies joined by a pin or a slot with friction, no gravity:
    the friction is internal, so linear and angular momentum stay what they were while the
    sliding loses energy (every joint test above has the ground as one side)."""
    b = mb.ModelBuilder(dim=2, gravity=None)
    a = b.add_body("a", mass=2.0, inertia=0.1, position=(0.0, 0.0), velocity=(0.3, -0.2),
                   angular_velocity=3.0)
    c = b.add_body("c", mass=1.0, inertia=0.05, position=(0.5, 0.0), velocity=(0.1, 1.2),
                   angular_velocity=-2.0)
    if kind == "revolute":
        joint = b.add(Revolute("pin", a, c, at=(0.25, 0.0)))
        b.add(mb.JointFriction("friction", joint, 0.3, pin_radius=0.02))
    else:
        joint = b.add(Prismatic("slot", a, c, axis=(1.0, 0.0)))
        b.add(mb.JointFriction("friction", joint, 0.3))
    t = np.linspace(0.0, 1.0, 11)
    with pytest.warns(mb.InitialStateWarning):  # the given rates break the joint: projected
        res = mb.forward_dynamics(b.build(), t, **INTEGRATORS[0])
    masses = {"a": 2.0, "c": 1.0}
    inertias = {"a": 0.1, "c": 0.05}
    momentum = sum(m * res.body(n).velocity for n, m in masses.items())
    def moment(n):  # about the origin: m (x vy - y vx) + I omega
        (x, y), (vx, vy) = res.body(n).position.T, res.body(n).velocity.T
        return masses[n] * (x * vy - y * vx) + inertias[n] * res.body(n).angular_velocity

    angular = sum(moment(n) for n in masses)
    np.testing.assert_allclose(momentum, np.broadcast_to(momentum[0], momentum.shape), rtol=0,
                               atol=1e-9)
    np.testing.assert_allclose(angular, angular[0], rtol=0, atol=1e-9)
    assert np.max(np.abs(res.friction("friction"))) > 1e-2  # it acts
    energy = res.kinetic_energy
    assert energy[-1] < energy[0] - 1e-3
