"""The acceptance case: the slider-crank in kinematic, inverse and forward dynamic analysis.

Oracles: the closed-form slider motion, a separately derived one-degree-of-freedom Lagrange
equation (tests/slider_crank_oracle.py), the crank's Newton-Euler equations, energy, and the
published Nikravesh-style example (Nikravesh, *Computer-Aided Analysis of Mechanical Systems*).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.mechanisms import slider_crank, slider_crank_positions
from mbd3d.joints import Prismatic, Revolute, RotationDriver

from slider_crank_oracle import SliderCrankOracle

OMEGA = 2 * math.pi
PHI0 = math.radians(65.0)


@pytest.fixture(scope="module")
def inverse():
    model = slider_crank(crank_angle=PHI0, crank_speed=OMEGA)
    t = np.linspace(0.0, 1.0, 73)  # 5 degree steps over a full turn
    return model, mb.inverse_dynamics(model, t)


def test_kinematics_match_closed_form(inverse):
    _, res = inverse
    oracle = SliderCrankOracle()
    phi = PHI0 + OMEGA * res.t
    d1, d2 = oracle.slider_x_derivatives(phi)
    slider = res.body("slider")
    np.testing.assert_allclose(slider.position[:, 0], oracle.slider_x(phi), rtol=0, atol=1e-12)
    np.testing.assert_allclose(slider.velocity[:, 0], OMEGA * d1, rtol=0, atol=1e-11)
    np.testing.assert_allclose(slider.acceleration[:, 0], OMEGA**2 * d2, rtol=0, atol=1e-10)
    np.testing.assert_allclose(res.body("rod").angle, oracle.rod_angle(phi), rtol=0, atol=1e-12)
    np.testing.assert_allclose(res.body("crank").angle, phi, rtol=0, atol=1e-12)
    # the slider never leaves the rail, the crank end follows its circle
    np.testing.assert_allclose(slider.position[:, 1], 0.0, rtol=0, atol=1e-12)
    tip = res.point("crank", (0.06, 0.0)).position
    np.testing.assert_allclose(tip, 0.12 * np.column_stack([np.cos(phi), np.sin(phi)]),
                               rtol=0, atol=1e-12)


def test_driving_torque_equals_power_balance(inverse):
    _, res = inverse
    oracle = SliderCrankOracle()
    phi = PHI0 + OMEGA * res.t
    expected = np.array([oracle.driving_torque(p, OMEGA) for p in phi])
    np.testing.assert_allclose(res.driver("motor").effort, expected, rtol=1e-9, atol=1e-9)


def test_ground_pin_reaction_satisfies_newton_euler_of_crank(inverse):
    model, res = inverse
    phi = PHI0 + OMEGA * res.t
    r, m1 = 0.12, 1.0
    e = np.column_stack([np.cos(phi), np.sin(phi)])
    a_centre = -OMEGA**2 * 0.5 * r * e  # closed form: uniform circular motion of the centre
    f_o = res.joint("O").reaction(on="crank").force
    f_a = res.joint("A").reaction(on="crank").force
    weight = m1 * np.array([0.0, -9.81])
    np.testing.assert_allclose(f_o + f_a + weight, m1 * a_centre, rtol=0, atol=1e-9)
    # moments about the centre of mass: motor + pin forces = J alpha = 0
    cross = lambda a, b: a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]  # noqa: E731
    moment = (res.driver("motor").effort + cross(-0.5 * r * e, f_o) + cross(0.5 * r * e, f_a))
    np.testing.assert_allclose(moment, 0.0, rtol=0, atol=1e-9)
    # a pin carries no moment about its own point, and A acts equally and oppositely
    np.testing.assert_allclose(res.joint("O").reaction(on="crank").moment, 0.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(res.joint("A").reaction(on="rod").force, -f_a, rtol=0, atol=1e-12)


def test_published_nikravesh_example():
    """Nikravesh-style slider-crank: theta1 = 65 deg,
    1.6 rad/s, horizontal force 50 N on the slider; reference torque 7.3809866111 N m (confirmed
    there two ways) and the reaction forces of the example's script."""
    a, psi, b_point = slider_crank_positions(PHI0, 0.12, 0.26)
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    crank = b.add_body("crank", mass=1.0, inertia=0.001, position=a / 2, angle=PHI0)
    rod = b.add_body("rod", mass=2.0, inertia=0.01, position=(a + b_point) / 2, angle=psi)
    slider = b.add_body("slider", mass=4.0, inertia=0.02, position=b_point)
    pin_o = b.add(Revolute("O", b.ground, crank, at=(0.0, 0.0)))
    b.add(Revolute("A", crank, rod, at=a))
    b.add(Revolute("B", rod, slider, at=b_point))
    b.add(Prismatic("rail", b.ground, slider, axis=(1.0, 0.0)))
    b.add(RotationDriver("motor", pin_o, motion=mb.Ramp(PHI0, 1.6)))
    b.add(mb.PointForce("load", slider, (50.0, 0.0)))
    res = mb.inverse_dynamics(b.build(), [0.0])
    assert res.body("rod").angle[0] == pytest.approx(-0.431568389770, abs=1e-11)
    assert res.body("slider").position[0, 0] == pytest.approx(0.286875003590, abs=1e-11)
    assert res.body("rod").angular_velocity[0] == pytest.approx(-0.343590901067, abs=1e-11)
    assert res.body("slider").velocity[0, 0] == pytest.approx(-0.211378988214, abs=1e-11)
    assert res.body("rod").angular_acceleration[0] == pytest.approx(1.124566271864, abs=1e-11)
    assert res.body("slider").acceleration[0, 0] == pytest.approx(-0.035403845256, abs=1e-11)
    assert res.driver("motor").effort[0] == pytest.approx(7.3809866111, abs=1e-9)
    np.testing.assert_allclose(res.joint("O").reaction(on="crank").force[0],
                               (-50.371761721, 42.423260094), rtol=0, atol=1e-8)
    np.testing.assert_allclose(res.joint("A").reaction(on="rod").force[0],
                               (-50.306847556, 32.752468970), rtol=0, atol=1e-8)
    # the script's f_B is the force of the rod on the slider: ours on the rod is its opposite
    np.testing.assert_allclose(res.joint("B").reaction(on="rod").force[0],
                               (50.141615381, -13.410886722), rtol=0, atol=1e-8)
    rail = res.joint("rail").reaction(on="slider", frame="joint").force[0]
    assert rail[1] == pytest.approx(25.829113278, abs=1e-8)
    assert rail[0] == pytest.approx(0.0, abs=1e-12)


def test_assembles_from_a_guess_tens_of_degrees_off():
    model = slider_crank(crank_angle=PHI0, crank_speed=OMEGA)
    guess = model.q0.copy()
    crank, rod, slider = (model.coordinates_of(n) for n in ("crank", "rod", "slider"))
    guess[rod.start + 2] += math.radians(35.0)
    guess[rod.start:rod.start + 2] += (0.04, -0.03)
    guess[slider.start] += 0.08
    guess[slider.start + 2] += math.radians(-20.0)
    guess[crank.start + 2] += math.radians(25.0)
    res = mb.kinematic_analysis(model, [0.0, 0.1], q_guess=guess)
    exact = mb.kinematic_analysis(model, [0.0, 0.1])
    np.testing.assert_allclose(res.q, exact.q, rtol=0, atol=1e-12)
    assert res.body("rod").angle[0] == pytest.approx(SliderCrankOracle().rod_angle(PHI0), abs=1e-12)


def test_velocities_with_the_crank_s_rate_held_are_the_closed_form_ones():
    """The free slider-crank with its crank's rate held at 30 rad/s: the rest follows from
    the rows, the slider at the closed-form speed dx/dphi * 30."""
    model = slider_crank(crank_angle=PHI0, crank_speed=None)
    q = mb.solve_position(model)
    guess = np.zeros(model.n_coordinates)
    k = model.coordinate_index("crank.theta")
    guess[k] = 30.0
    qd = mb.solve_velocity(model, q, qd_guess=guess, hold=["crank.theta"])
    assert qd[k] == 30.0
    r, l, phi = 0.12, 0.26, PHI0
    dx = -r * math.sin(phi) - r * r * math.sin(phi) * math.cos(phi) / math.sqrt(
        l * l - (r * math.sin(phi)) ** 2)
    assert qd[model.coordinate_index("slider.x")] == pytest.approx(30.0 * dx, rel=1e-12)


def test_forward_dynamics_energy_balance_and_lagrange_equation():
    torque = 2.0
    model = slider_crank(crank_angle=PHI0, crank_speed=None, crank_torque=torque)
    assert mb.mobility(model).dof == 1
    t = np.linspace(0.0, 2.0, 41)
    res = mb.forward_dynamics(model, t, method="DOP853", rtol=1e-11, atol=1e-12)
    assert res.status == "complete"
    crank = res.body("crank")
    energy = res.kinetic_energy + res.potential_energy
    work = torque * (crank.angle - crank.angle[0])
    # work of the moment = change of kinetic + potential energy
    assert np.max(np.abs(work - (energy - energy[0]))) < 1e-6 * np.max(np.abs(work))
    phi, phi_dot = SliderCrankOracle().simulate(torque, PHI0, t)
    np.testing.assert_allclose(crank.angle, phi, rtol=1e-8, atol=1e-8)
    np.testing.assert_allclose(crank.angular_velocity, phi_dot, rtol=1e-7, atol=1e-7)
    assert np.max(res.position_residual) <= 1e-8
    assert np.max(res.velocity_residual) <= 1e-8


def test_rk45_default_keeps_constraint_residuals_below_tolerance():
    model = slider_crank(crank_angle=PHI0, crank_speed=None, crank_torque=1.0)
    res = mb.forward_dynamics(model, np.linspace(0.0, 3.0, 31), constraint_tol=1e-9)
    assert res.stats["method"] == "RK45"
    assert np.max(res.position_residual) <= 1e-9
    assert np.max(res.velocity_residual) <= 1e-9
    assert res.stats["max_drift"] > 0.0  # drift was measured, and kept in check


def test_drift_is_measured_row_by_row_in_the_model_s_own_length():
    """The compiled loop's drift check (what triggers a projection): a driven slider-crank of
    0.12 mm and 0.26 mm links keeps its rows (the driver's too, with its offset) to 1e-12 of
    its size at rtol 1e-11, so no step is projected; at rtol 1e-4 it drifts to 3e-7 of its size
    and steps are projected. A driver's offset or motion left out of the measure, or
    the length scale applied the wrong way, turns one into the other."""
    model = slider_crank(crank_length=0.12e-3, rod_length=0.26e-3, crank_angle=PHI0)
    tight = mb.forward_dynamics(model, np.linspace(0.0, 0.5, 11), method="DOP853",
                                rtol=1e-11, constraint_tol=1e-8)
    assert tight.stats["projections"] == 0
    assert 0.0 < tight.stats["max_drift"] < 1e-8
    loose = mb.forward_dynamics(model, np.linspace(0.0, 0.5, 11), method="RK45", rtol=1e-4,
                                constraint_tol=1e-8)
    assert loose.stats["projections"] > 0
    assert loose.stats["max_drift"] > 1e-8


def _offset_slider_crank(size: float = 1e-3) -> mb.Model:
    """A crank driven harmonically, a massless rod (a Distance joint: its row's constant is
    the length) to a slider drawn turned by 0.4 rad on a rail along x (the rail's rotation row
    keeps that angle as its constant), all of ``size``."""
    from mbd3d.joints import Distance
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    r, L, phi = 0.4 * size, size, 0.7
    a = np.array([r * math.cos(phi), r * math.sin(phi)])
    x_b = a[0] + math.sqrt(L * L - a[1] ** 2)
    crank = b.add_body("crank", mass=0.1, inertia=0.1 * r * r / 3, position=a / 2, angle=phi)
    slider = b.add_body("slider", mass=0.2, inertia=0.2 * (size / 4) ** 2,
                        position=(x_b, 0.0), angle=0.4)
    pin = b.add(Revolute("O", b.ground, crank, at=(0.0, 0.0)))
    b.add(Distance("rod", crank, slider, at_i=a, at_j=(x_b, 0.0)))
    b.add(Prismatic("rail", b.ground, slider, axis=(1.0, 0.0)))
    b.add(RotationDriver("motor", pin, motion=mb.Harmonic(0.3, 5.0, offset=phi)))
    return b.build()


def test_the_compiled_drift_measure_is_the_rows_residuals_in_the_model_s_units():
    """The explicit loop's drift (what triggers a projection) against the constraint rows
    evaluated in Python: the largest position residual ``C = c(q) - c0 - f(t)`` and velocity
    residual ``Cq qd - f'(t)`` of each row over its scale (lengths over the model's), at
    states off the constraints, one where the positions are furthest off, one the rates."""
    from mbd3d.model import constraints
    from mbd3d.numerics.compiled.integration import drift
    from mbd3d.numerics.compiled.structures import workspace
    model = _offset_slider_crank()
    assert np.any(model.c0 != 0.0) and model.length_scale < 1e-2
    arrays = model._core.arrays(python_accelerations=False)
    work = workspace(False, arrays)
    rng = np.random.default_rng(2)
    n = model.n_coordinates
    # where the motor stands still (f' = 0), at rest, the positions 1e-7 m (rad) off; then
    # where it turns, positions solved and the rates 1e-6 off: the rows' residuals are then
    # as small as the errors, so that a constant, a driver's value or rate, or a scale
    # misplaced is the largest
    t_still, t_turning = math.pi / 10, 0.37
    still = mb.solve_position(model, model.q0, t_still)
    turning = mb.solve_position(model, model.q0, t_turning)
    rates = mb.solve_velocity(model, turning, t_turning)
    for t, q, qd in ((t_still, still + 1e-7 * rng.normal(size=n), np.zeros(n)),
                     (t_turning, turning, rates + 1e-6 * rng.normal(size=n))):
        fr = constraints.frames(model, q)
        position = constraints.largest_relative(model, constraints.residual(model, t, q, fr))
        velocity = constraints.largest_relative(
            model, constraints.jacobian(model, t, q, fr, sparse=False) @ qd
            - constraints.velocity_rhs(model, t, fr))
        expected = max(position, velocity)
        assert expected > 10 * min(position, velocity)  # each part the larger in turn
        found = drift(arrays, 0, t, np.concatenate([q, qd]), None, work)
        assert found == pytest.approx(expected, rel=1e-10)
