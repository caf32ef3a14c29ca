"""Linearisation against equations derived by hand (the inverted pendulum on a cart, simple
and double pendulums about the hanging position, a spatial pendulum), and against the
nonlinear equations themselves: a small disturbance of a swinging double pendulum, followed by
two forward-dynamics runs, grows as the linear time-varying equations predict."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg as la

import mbd3d as mb
from mbd3d.joints import Prismatic, Revolute, Spherical
from test_modes import hanging_bars

G = 9.81


def cart_pole(cart_mass=1.5, pole_mass=0.5, length=0.8, gravity=G):
    """A cart on a horizontal rail with a uniform pole pinned on it, upright; a force on the
    cart (zero: it is the input)."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -gravity))
    cart = b.add_body("cart", mass=cart_mass, inertia=0.1, position=(0.0, 0.0))
    pole = b.add_body("pole", mass=pole_mass, inertia=pole_mass * length ** 2 / 12,
                      position=(0.0, length / 2), angle=math.pi / 2)
    b.add(Prismatic("rail", b.ground, cart, axis=(1.0, 0.0)))
    b.add(Revolute("hinge", cart, pole, at=(0.0, 0.0)))
    b.add(mb.PointForce("push", cart, force=(0.0, 0.0)))
    return b.build()


def test_cart_pole_against_its_lagrangian():
    """With phi the pole's tilt from upright: M = [[Mc + m, -m l], [-m l, I + m l^2]],
    K = diag(0, -m g l), input (1, 0), l = L/2; the hinge pushes the pole with
    Fx = m (x'' - l phi'')."""
    Mc, m, L = 1.5, 0.5, 0.8
    l, inertia = L / 2, m * L * L / 12
    lin = mb.linearize(cart_pole(Mc, m, L), cart_pole(Mc, m, L).q0,
                       coordinates=["cart.x", "pole.theta"], inputs=["push.x"],
                       outputs={"x": "cart.x", "tilt rate": "pole.theta_dot",
                                "Fx": lambda r: r.joint("hinge").reaction().force[0, 0]})
    M = np.array([[Mc + m, -m * l], [-m * l, inertia + m * l * l]])
    K = np.diag([0.0, -m * G * l])
    np.testing.assert_allclose(lin.mass, M, rtol=1e-12)
    np.testing.assert_allclose(lin.stiffness, K, rtol=0, atol=1e-7 * m * G * l)
    np.testing.assert_allclose(lin.damping, 0.0, rtol=0, atol=1e-7)
    expected_A = np.block([[np.zeros((2, 2)), np.eye(2)], [-la.solve(M, K), np.zeros((2, 2))]])
    np.testing.assert_allclose(lin.A, expected_A, rtol=0, atol=1e-7)
    np.testing.assert_allclose(lin.B[:, 0], np.r_[0.0, 0.0, la.solve(M, [1.0, 0.0])],
                               rtol=1e-12, atol=1e-14)
    assert lin.states == ["cart.x", "pole.theta", "cart.x_dot", "pole.theta_dot"]
    # outputs: two picks of the state, and the reaction by Newton's law on the pole
    np.testing.assert_allclose(lin.C[:2], np.eye(4)[[0, 3]], rtol=0, atol=1e-9)
    np.testing.assert_allclose(lin.D[:2], 0.0, rtol=0, atol=1e-9)
    np.testing.assert_allclose(lin.C[2], m * (expected_A[2] - l * expected_A[3]),
                               rtol=0, atol=1e-6)
    np.testing.assert_allclose(lin.D[2], m * (lin.B[2] - l * lin.B[3]), rtol=1e-7)
    # upright is unstable at the rate of lambda^2 = (Mc + m) m g l / det M
    rate = math.sqrt((Mc + m) * m * G * l / la.det(M))
    assert lin.eigenvalues[0].real == pytest.approx(rate, rel=1e-8)


def test_a_falling_cart_pole_takes_the_push_through_its_tilted_mass_matrix():
    """Tilted phi = 30 degrees and at rest, the pole falls (qdd != 0): the push still acts
    through M(phi) = [[Mc + m, -m l cos phi], [-m l cos phi, I + m l^2]], B = M^-1 (1, 0), and
    an output read from the accelerations (the cart's) responds with B's first rate row and
    follows the state as A's."""
    Mc, m, L, phi = 1.5, 0.5, 0.8, math.radians(30)
    l, inertia = L / 2, m * L * L / 12
    model = cart_pole(Mc, m, L)
    q = model.q0.copy()
    q[model.coordinate_index("pole.x")] = -l * math.sin(phi)
    q[model.coordinate_index("pole.y")] = l * math.cos(phi)
    q[model.coordinate_index("pole.theta")] = math.pi / 2 + phi
    cart_x = model.coordinate_index("cart.x")
    lin = mb.linearize(model, q, coordinates=["cart.x", "pole.theta"], inputs=["push.x"],
                       outputs={"cart acceleration": lambda r: r.qdd[0, cart_x]})
    M = np.array([[Mc + m, -m * l * math.cos(phi)], [-m * l * math.cos(phi), inertia + m * l * l]])
    assert la.solve(M, [0.0, m * G * l * math.sin(phi)])[1] > 1.0  # falling
    np.testing.assert_allclose(lin.B[:, 0], np.r_[0.0, 0.0, la.solve(M, [1.0, 0.0])],
                               rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(lin.D[0], lin.B[2], rtol=1e-7)
    np.testing.assert_allclose(lin.C[0], lin.A[2], rtol=1e-6, atol=1e-7 * np.abs(lin.A).max())


def test_cart_pole_drawn_in_millimetres_linearises_as_in_metres():
    """Lengths in mm and g = 9810 mm/s^2, with the cart's and the pole's centre's x as
    coordinates: every state is a length or its rate, so A is the same in mm as in m. The
    differencing steps follow the model's size (steps of 1e-8 mm lose the forces' digits to
    rounding), and so does the check that the state is on the constraints: 1e-10 of the size
    off is rounding, 1e-7 is another state."""
    scale = 1000.0
    metres, millimetres = cart_pole(), cart_pole(length=0.8 * scale, gravity=G * scale)
    coordinates = ["cart.x", "pole.x"]
    A_m = mb.linearize(metres, metres.q0, coordinates=coordinates).A
    q = millimetres.q0.copy()
    pole_y = millimetres.coordinate_index("pole.y")
    q[pole_y] += 0.8 * scale * 1e-10
    lin = mb.linearize(millimetres, q, coordinates=coordinates)
    np.testing.assert_allclose(lin.A, A_m, rtol=1e-7, atol=1e-9 * np.abs(A_m).max())
    assert np.abs(A_m[2:, :2]).min() > 1.0  # every displacement pushes: no column is idle
    q[pole_y] += 0.8 * scale * 1e-7
    with pytest.raises(mb.ModelError, match="position"):
        mb.linearize(millimetres, q, coordinates=coordinates)


@pytest.mark.parametrize("coordinates", [None, ["bar1.x"], ["bar1.theta"]])
def test_pendulum_about_hanging_whatever_the_coordinate(coordinates):
    """I_O theta'' + m g L/2 theta = 0: eigenvalues +-i sqrt(3 g / 2 L) in any independent
    coordinate (the horizontal position of the centre too, at the hanging position)."""
    L, m = 0.7, 1.3
    model = hanging_bars([L], [m])
    lin = mb.linearize(model, model.q0, coordinates=coordinates)
    omega = math.sqrt(3 * G / (2 * L))
    np.testing.assert_allclose(np.sort(lin.eigenvalues.imag), [-omega, omega], rtol=1e-8)
    np.testing.assert_allclose(lin.eigenvalues.real, 0.0, rtol=0, atol=1e-7 * omega)
    if coordinates == ["bar1.theta"]:
        assert lin.mass[0, 0] == pytest.approx(m * L * L / 3, rel=1e-12)
        assert lin.stiffness[0, 0] == pytest.approx(m * G * L / 2, rel=1e-8)


def test_spatial_double_pendulum_swings_as_the_planar_one():
    """Two bars hanging on hinges about y, drawn in space: the six bodies' coordinates less
    ten hinge rows leave the planar double pendulum's two modes, omega^2 the eigenvalues of
    K and M of the test below, whatever the independent coordinates picked."""
    from mbd3d.mechanisms import frame_along
    (L1, L2), (m1, m2) = (0.6, 0.9), (1.5, 2.5)
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G))
    previous, top = b.ground, 0.0
    for k, (L, m) in enumerate(((L1, m1), (L2, m2))):
        bar = b.add_body(f"bar{k + 1}", mass=m, inertia=m * L * L * np.array([1e-2, 1, 1]) / 12,
                         position=(0.0, 0.0, top - L / 2),
                         orientation=frame_along(np.array([0.0, 0.0, -1.0])))
        b.add(Revolute(f"pin{k + 1}", previous, bar, at=(0.0, 0.0, top), axis=(0.0, 1.0, 0.0)))
        previous, top = bar, top - L
    model = b.build()
    M = np.array([[(m1 / 3 + m2) * L1 * L1, m2 * L1 * L2 / 2],
                  [m2 * L1 * L2 / 2, m2 * L2 * L2 / 3]])
    K = np.diag([(m1 / 2 + m2) * G * L1, m2 * G * L2 / 2])
    omega = np.sqrt(la.eigvalsh(K, M))
    # in the bodies' axes, and in a frame that does not turn (the global axes)
    for frame_rate in (None, (0.0, 0.0, 0.0)):
        values = mb.linearize(model, model.q0, frame_rate=frame_rate).eigenvalues
        assert len(values) == 4
        np.testing.assert_allclose(np.sort(np.abs(values.imag)), np.repeat(omega, 2),
                                   rtol=1e-8)
        np.testing.assert_allclose(values.real, 0.0, rtol=0, atol=1e-7 * omega[0])


def test_double_pendulum_mass_and_stiffness_in_its_angles():
    """Absolute angles: the 2 x 2 Lagrangian of test_modes, exactly (not only its
    eigenvalues)."""
    (L1, L2), (m1, m2), (k, c) = (0.6, 0.9), (1.5, 2.5), (4.0, 0.7)
    model = hanging_bars([L1, L2], [m1, m2], spring=k, damper=c)
    lin = mb.linearize(model, model.q0, coordinates=["bar1.theta", "bar2.theta"])
    M = np.array([[(m1 / 3 + m2) * L1 * L1, m2 * L1 * L2 / 2],
                  [m2 * L1 * L2 / 2, m2 * L2 * L2 / 3]])
    # the torsion spring-damper at the top pin turns with bar 1's angle alone
    K = np.diag([(m1 / 2 + m2) * G * L1 + k, m2 * G * L2 / 2])
    np.testing.assert_allclose(lin.mass, M, rtol=1e-12)
    np.testing.assert_allclose(lin.stiffness, K, rtol=1e-7, atol=1e-8 * K.max())
    np.testing.assert_allclose(lin.damping, np.diag([c, 0.0]), rtol=1e-7, atol=1e-8 * c)
    np.testing.assert_allclose(lin.A[2:], -la.solve(M, np.hstack([K, np.diag([c, 0.0])])),
                               rtol=1e-7, atol=1e-8)
    # without outputs named, the outputs are the states
    assert lin.outputs == lin.states
    np.testing.assert_array_equal(lin.C, np.eye(4))
    np.testing.assert_array_equal(lin.D, np.zeros((4, 0)))
    # the dependent coordinates follow the angles: bar 2's centre moves with both
    basis = lin.basis[model.coordinate_index("bar2.x")]
    np.testing.assert_allclose(basis, [L1, L2 / 2], rtol=1e-12)


def test_spatial_pendulum_swings_as_the_planar_one():
    """A bar on a ball joint: two swings at sqrt(3 g / 2 L) and a free spin (two zero
    eigenvalues), from a hanging state given in a chart far from the body's attitude."""
    m, L = 1.5, 1.2
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G))
    from mbd3d.mechanisms import frame_along
    bar = b.add_body("bar", mass=m, inertia=m * L * L * np.array([1e-2, 1 / 12, 1 / 12]),
                     position=(0.0, 0.0, -L / 2), orientation=frame_along(np.array([0, 0, -1.0])))
    b.add(Spherical("ball", b.ground, bar, at=(0.0, 0.0, 0.0)))
    model = b.build()
    # the same state relative to a chart turned 80 degrees away
    turn = mb.rotations.from_rodrigues(math.tan(math.radians(40)) * np.array([0.0, 0.6, 0.8]))
    charts = model.charts0.copy()
    charts[0] = charts[0] @ turn
    q = model.q0.copy()
    q[3:6] = mb.rotations.to_rodrigues(turn.T)
    lin = mb.linearize(model, q, charts=charts)
    omega = math.sqrt(3 * G / (2 * L))
    values = lin.eigenvalues
    np.testing.assert_allclose(np.sort(np.abs(values.imag)), [0, 0, omega, omega, omega, omega],
                               atol=1e-7 * omega, rtol=1e-8)
    np.testing.assert_allclose(values.real, 0.0, rtol=0, atol=1e-6 * omega)
    assert lin.q[3:6] == pytest.approx(np.zeros(3), abs=1e-15)  # re-charted at the attitude


def test_small_disturbance_of_a_swinging_double_pendulum_follows_the_linear_equations():
    """Along a large swing (a moving state), dx' = A(t) dx integrated by RK4 on the
    reference's grid predicts the difference of two nonlinear runs, one disturbed by eps, to
    O(eps^2)."""
    model = hanging_bars([0.6, 0.9], [1.5, 2.5], angle=-math.pi / 2 + 1.0)
    coordinates = ["bar1.theta", "bar2.theta"]
    h, steps = 0.01, 40
    grid = np.linspace(0.0, h * steps, 2 * steps + 1)
    reference = mb.forward_dynamics(model, grid, method="DOP853", rtol=1e-12, atol=1e-13)

    def A(k):
        return mb.linearize(model, reference.q[k], reference.qd[k], grid[k],
                            coordinates=coordinates).A

    eps = 1e-6
    dx0 = eps * np.array([1.0, -0.5, 0.3, 2.0])
    dx = dx0.copy()
    for step in range(steps):  # RK4 on the grid's half steps
        A0, A1, A2 = A(2 * step), A(2 * step + 1), A(2 * step + 2)
        k1 = A0 @ dx
        k2 = A1 @ (dx + h / 2 * k1)
        k3 = A1 @ (dx + h / 2 * k2)
        k4 = A2 @ (dx + h * k3)
        dx = dx + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)

    index = [model.coordinate_index(c) for c in coordinates]
    q0, qd0 = reference.q[0].copy(), reference.qd[0].copy()
    q0[index] += dx0[:2]
    qd0[index] += dx0[2:]
    # the other coordinates follow the held angles: the constraints change them, and say so
    with pytest.warns(mb.InitialStateWarning, match="bar2"):
        disturbed = mb.forward_dynamics(model, grid, q0, qd0, method="DOP853", rtol=1e-12,
                                        atol=1e-13, hold=coordinates)
    difference = np.concatenate([disturbed.q[-1, index] - reference.q[-1, index],
                                 disturbed.qd[-1, index] - reference.qd[-1, index]])
    # the disturbance has grown and turned; the linear prediction holds to O(eps^2) and RK4
    assert np.linalg.norm(difference - dx0) > np.linalg.norm(dx0)
    np.testing.assert_allclose(dx, difference, rtol=0, atol=2e-5 * np.linalg.norm(difference))


def test_bad_linearisation_requests_are_named():
    model = cart_pole()
    q = model.q0.copy()
    q[4] += 0.01  # the pole's centre off its hinge
    with pytest.raises(mb.ModelError, match="violates the position constraints.*hinge"):
        mb.linearize(model, q)
    with pytest.raises(mb.ModelError, match="push.x"):
        mb.linearize(model, model.q0, inputs=["push"])
    with pytest.raises(mb.ModelError, match="PointForce or Torque.*push"):
        mb.linearize(model, model.q0, inputs=["shove.x"])
    with pytest.raises(mb.ModelError, match="2 degrees of freedom"):
        mb.linearize(model, model.q0, coordinates=["cart.x"])
    with pytest.raises(mb.ModelError, match="not independent"):
        mb.linearize(model, model.q0, coordinates=["cart.y", "pole.theta"])
    with pytest.raises(mb.ModelError, match="output 'pole.spin'"):
        mb.linearize(model, model.q0, outputs=["pole.spin"])
    with pytest.raises(mb.ModelError, match="frame_rate is for spatial models"):
        mb.linearize(model, model.q0, frame_rate=(0.0, 0.0, 1.0))


def test_heavy_top_in_steady_precession_nutates_at_the_closed_form_frequency():
    """A disc on a short stalk pivoted at its tip, turning at Omega about the vertical with
    its axis tilted theta0 and no spin of its own: steady when m g l = Omega^2 cos theta0
    (I3 - I1) (I1 about the pivot). Small nutation about it has
    omega_n^2 = Omega^2 sin^2 theta0 + (I3 w3 - 2 I1 Omega cos theta0)^2 / I1^2,
    w3 = Omega cos theta0 (Routh reduction of the Euler-angle Lagrangian); the precession and
    the spin are free (zero eigenvalues)."""
    m, radius, l, theta0 = 1.0, 0.1, 0.02, math.radians(30)
    I3, transverse = m * radius ** 2 / 2, m * radius ** 2 / 4
    I1 = transverse + m * l * l
    c, s = math.cos(theta0), math.sin(theta0)
    Omega = math.sqrt(m * G * l / (c * (I3 - I1)))
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G))
    attitude = mb.rotations.axis_angle((1.0, 0.0, 0.0), theta0)
    axis, omega = attitude[:, 2], np.array([0.0, 0.0, Omega])
    top = b.add_body("top", mass=m, inertia=(transverse, transverse, I3), position=l * axis,
                     orientation=attitude, velocity=np.cross(omega, l * axis),
                     angular_velocity=omega)
    b.add(Spherical("tip", b.ground, top, at=(0.0, 0.0, 0.0)))
    model = b.build()
    # the motion is steady: the tilt holds over a precession period
    run = mb.forward_dynamics(model, np.linspace(0.0, 2 * math.pi / Omega, 9), rtol=1e-10,
                              atol=1e-12)
    tilt = np.arccos(run.body("top").rotation[:, 2, 2])
    np.testing.assert_allclose(tilt, theta0, rtol=0, atol=1e-8)

    lin = mb.linearize(model, run.q[4], run.qd[4], run.t[4], charts=run.charts[4])
    nutation = math.sqrt(Omega ** 2 * s * s + (I3 * Omega * c - 2 * I1 * Omega * c) ** 2 / I1 ** 2)
    values = lin.eigenvalues
    oscillating = values[np.argsort(-np.abs(values))[:2]]
    np.testing.assert_allclose(np.sort(oscillating.imag), [-nutation, nutation], rtol=1e-8)
    np.testing.assert_allclose(oscillating.real, 0.0, rtol=0, atol=1e-7 * nutation)
    assert np.sort(np.abs(values))[3] < 1e-4 * Omega
    assert lin.states == ["top.rx", "top.ry", "top.rz", "top.wx", "top.wy", "top.wz"]


def test_a_motor_released_as_the_input_about_the_position_it_holds():
    """A bar held by a motor at 30 degrees above the horizontal: released, with its effort as
    the input about the holding torque m g L/2 cos 30, I_O theta'' = u + m g L/2 sin 30 theta
    (gravity's moment falls as the bar rises: a negative stiffness)."""
    from mbd3d.joints import RotationDriver
    m, L, angle = 2.0, 0.8, math.radians(30)
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    bar = b.add_body("bar", mass=m, inertia=m * L * L / 12,
                     position=(L / 2 * math.cos(angle), L / 2 * math.sin(angle)), angle=angle)
    pin = b.add(Revolute("O", b.ground, bar, at=(0.0, 0.0)))
    b.add(RotationDriver("motor", pin, motion=mb.Ramp(angle, 0.0)))
    b.add(mb.Torque("kick", bar, torque=0.0))
    model = b.build()
    rest = mb.static_equilibrium(model)
    assert rest.driver("motor").effort[0] == pytest.approx(m * G * L / 2 * math.cos(angle))
    lin = mb.linearize(model, rest.q[0], inputs=["motor", "kick"], coordinates=["bar.theta"],
                       outputs={"effort": lambda r: r.driver("motor").effort[0],
                                "pin y": lambda r: r.joint("O").reaction().force[0, 1],
                                "effort^2": lambda r: r.driver("motor").effort[0] ** 2})
    inertia = m * L * L / 3
    np.testing.assert_allclose(lin.A, [[0, 1], [m * G * L / 2 * math.sin(angle) / inertia, 0]],
                               rtol=1e-7, atol=1e-9)
    # the motor's effort and a torque applied to the bar turn it alike
    np.testing.assert_allclose(lin.B, [[0.0, 0.0], [1.0 / inertia, 1.0 / inertia]], rtol=1e-12)
    # the effort output is the input itself; the pin's vertical force carries the weight less
    # m times the centre's vertical acceleration, (L/2) cos(angle) theta''
    np.testing.assert_allclose(lin.D[0], [1.0, 0.0], rtol=1e-7, atol=1e-9)
    # an output not linear in the effort: d(tau^2) = 2 tau0 du, tau0 the holding torque
    np.testing.assert_allclose(lin.D[2], [2 * m * G * L / 2 * math.cos(angle), 0.0], rtol=1e-7,
                               atol=1e-7)
    np.testing.assert_allclose(lin.C[0], 0.0, rtol=0, atol=1e-7)
    np.testing.assert_allclose(lin.D[1], np.full(2, m * L / 2 * math.cos(angle) / inertia),
                               rtol=1e-6)
    # about the held position theta'' = 0: the pin force varies with the angle only through
    # (L/2) cos(angle) theta'' (were the reference effort the holding torque's opposite, the
    # bar would accelerate there and -(L/2) sin(angle) theta''_0 would add)
    np.testing.assert_allclose(lin.C[1], [m * L / 2 * math.cos(angle) * lin.A[1, 0], 0.0],
                               rtol=1e-6, atol=1e-7)
    with pytest.raises(mb.ModelError, match="0 degrees of freedom.*release"):
        mb.linearize(model, rest.q[0], coordinates=["bar.theta"])


def test_a_pendulum_under_a_cart_driven_at_constant_speed_swings_as_under_a_fixed_one():
    """The cart's driver keeps its speed v: the pole hangs in a frame moving uniformly, so
    I_O theta'' = -m g L/2 theta about hanging. A state whose rates break the driver's row (the
    pole left behind, or the cart still) is another motion and is refused, naming the rows."""
    from mbd3d.joints import TranslationDriver
    m, L, v = 0.7, 0.6, 1.5
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    cart = b.add_body("cart", mass=2.0, inertia=0.1, position=(0.0, 0.0))
    pole = b.add_body("pole", mass=m, inertia=m * L * L / 12, position=(0.0, -L / 2),
                      angle=-math.pi / 2)
    rail = b.add(Prismatic("rail", b.ground, cart, axis=(1.0, 0.0)))
    b.add(TranslationDriver("drive", rail, motion=mb.Ramp(0.0, v)))
    b.add(Revolute("hinge", cart, pole, at=(0.0, 0.0)))
    model = b.build()
    qd = np.zeros(model.n_coordinates)
    qd[[model.coordinate_index("cart.x"), model.coordinate_index("pole.x")]] = v
    lin = mb.linearize(model, model.q0, qd, coordinates=["pole.theta"])
    np.testing.assert_allclose(lin.A, [[0.0, 1.0], [-m * G * L / 2 / (m * L * L / 3), 0.0]],
                               rtol=1e-7, atol=1e-9)
    left_behind = qd.copy()
    left_behind[model.coordinate_index("pole.x")] = 0.0
    still = np.zeros(model.n_coordinates)
    for rates, row in ((left_behind, "hinge"), (still, "drive")):
        with pytest.raises(mb.ModelError, match=f"velocity.*{row}"):
            mb.linearize(model, model.q0, rates, coordinates=["pole.theta"])


def test_a_singular_position_is_reported_as_the_linearisation_s():
    from mbd3d.mechanisms import four_bar
    # a parallelogram four-bar lying flat: every body on one line, the Jacobian singular
    flat = four_bar(ground_length=0.3, crank_length=0.1, coupler_length=0.3, rocker_length=0.1,
                    crank_angle=0.0, crank_speed=None)
    with pytest.raises(mb.SingularJacobianError,
                       match=r"^linearisation of 'four-bar': the constraint Jacobian is singular"):
        mb.linearize(flat, mb.solve_position(flat))


@pytest.mark.parametrize("root", [-1.0, 1.0])
def test_a_spinning_top_nutates_at_rouths_frequency_in_the_precessing_frame(root):
    """A top spinning at w3 about its axis tilted theta0 precesses steadily at either root of
    I1 cos(theta0) Omega^2 - I3 w3 Omega + m g l = 0 (slow and fast precession). In the bodies'
    axes the motion is not steady (the spin turns them), but in a frame turning at Omega about
    the vertical it is: there the small nutation has Routh's frequency, the second
    derivative of the effective potential (p_phi - p_psi cos theta)^2 / (2 I1 sin^2 theta) +
    m g l cos theta over I1, the same at any time of the motion. The world is drawn tilted
    (the vertical along no axis), so every component of the frame's rate counts."""
    m, radius, l, theta0, w3 = 1.0, 0.1, 0.05, math.radians(40), 60.0
    I3, transverse = m * radius ** 2 / 2, m * radius ** 2 / 4
    I1 = transverse + m * l * l
    c, s = math.cos(theta0), math.sin(theta0)
    Omega = (I3 * w3 + root * math.sqrt((I3 * w3) ** 2 - 4 * I1 * m * G * l * c)) / (2 * I1 * c)
    p_psi = I3 * w3
    p_phi = I1 * Omega * s * s + p_psi * c

    def effective(theta):
        return ((p_phi - p_psi * np.cos(theta)) ** 2 / (2 * I1 * np.sin(theta) ** 2)
                + m * G * l * np.cos(theta))

    h = 1e-4
    routh = math.sqrt((effective(theta0 + h) - 2 * effective(theta0) + effective(theta0 - h))
                      / (h * h) / I1)
    closed = math.sqrt(Omega ** 2 * s * s + (I3 * w3 - 2 * I1 * Omega * c) ** 2 / I1 ** 2)
    assert routh == pytest.approx(closed, rel=1e-6)  # the differences' own accuracy

    world = mb.rotations.axis_angle(np.array([1.0, 2.0, 3.0]) / math.sqrt(14.0), 0.7)
    vertical = world[:, 2]
    b = mb.ModelBuilder(dim=3, gravity=-G * vertical)
    attitude = world @ mb.rotations.axis_angle((1.0, 0.0, 0.0), theta0)
    axis = attitude[:, 2]
    omega = Omega * vertical + (w3 - Omega * c) * axis
    top = b.add_body("top", mass=m, inertia=(transverse, transverse, I3), position=l * axis,
                     orientation=attitude, velocity=np.cross(omega, l * axis),
                     angular_velocity=omega)
    b.add(Spherical("tip", b.ground, top, at=(0.0, 0.0, 0.0)))
    model = b.build()
    period = 2 * math.pi / Omega
    run = mb.forward_dynamics(model, np.linspace(0.0, period, 7), method="DOP853", rtol=1e-11,
                              atol=1e-12)
    np.testing.assert_allclose(np.arccos(run.body("top").rotation[:, :, 2] @ vertical), theta0,
                               rtol=0, atol=1e-8)
    for k in (0, 2, 5):  # anywhere along the steady motion
        lin = mb.linearize(model, run.q[k], run.qd[k], run.t[k], charts=run.charts[k],
                           frame_rate=Omega * vertical)
        values = lin.eigenvalues
        oscillating = values[np.argsort(-np.abs(values))[:2]]
        np.testing.assert_allclose(np.sort(oscillating.imag), [-closed, closed], rtol=1e-7)
        np.testing.assert_allclose(oscillating.real, 0.0, rtol=0, atol=1e-7 * closed)
        # the precession and the spin are free
        assert np.sort(np.abs(values))[3] < 1e-4 * Omega
    with pytest.raises(mb.ModelError, match="frame_rate must be 3 finite numbers"):
        mb.linearize(model, model.q0, model.qd0, frame_rate=(0.0, Omega))
