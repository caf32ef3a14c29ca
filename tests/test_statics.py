"""Static equilibrium against closed forms, virtual work, an energy minimum found separately,
and a damped forward-dynamics run left to settle."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq, minimize

import mbd3d as mb
from mbd3d.joints import Prismatic, Revolute, RotationDriver, Spherical

G = 9.81


def sprung_pendulum(m=2.0, L=0.8, k=5.0, c=0.0, driven=False):
    """A bar pinned at one end (horizontal at the start), a torsion spring to the ground
    (free at the horizontal), gravity along -y; optionally a motor on the pin."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    bar = b.add_body("bar", mass=m, inertia=m * L * L / 12, position=(L / 2, 0.0))
    pin = b.add(Revolute("O", b.ground, bar, at=(0.0, 0.0)))
    if k or c:
        b.add(mb.RotationalSpringDamper("spring", body_i=b.ground, body_j=bar, stiffness=k,
                                        damping=c))
    if driven:
        b.add(RotationDriver("motor", pin, motion=mb.Ramp(-1.0, 1.0)))
    return b.build()


@pytest.mark.parametrize("k", [5.0, 40.0])
def test_sprung_pendulum_rests_where_spring_and_gravity_balance(k):
    """k theta = -m g (L/2) cos theta, solved separately; the pin carries the weight."""
    m, L = 2.0, 0.8
    res = mb.static_equilibrium(sprung_pendulum(m, L, k))
    exact = brentq(lambda th: k * th + m * G * L / 2 * math.cos(th), -math.pi / 2, 0.0)
    assert res.body("bar").angle[0] == pytest.approx(exact, abs=1e-11)
    np.testing.assert_allclose(res.joint("O").reaction(on="bar").force[0], [0.0, m * G],
                               rtol=0, atol=1e-9)
    # the second derivative of the potential, k - m g L/2 sin(theta), is positive
    assert res.stats["stability"] == ["stable"]


def test_a_block_hanging_on_a_spring_rests_at_its_stretch_in_a_few_iterations():
    """A 2 kg block on a vertical rail under a 100 N/m spring of free length 0.5 m rests at
    y = -(0.5 + m g / k). The balance is linear: Newton's method takes a few iterations (one
    with an exact stiffness; this one is differenced), and says how many."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    block = b.add_body("block", mass=2.0, inertia=0.1, position=(0.0, -1.0))
    b.add(Prismatic("rail", b.ground, block, axis=(0.0, 1.0), point_i=(0.0, 0.0),
                    point_j=(0.0, 0.0)))
    b.add(mb.SpringDamper("spring", b.ground, block, point_i=(0.0, 0.0), point_j=(0.0, 0.0),
                          stiffness=100.0, free_length=0.5))
    res = mb.static_equilibrium(b.build())
    assert res.body("block").position[0, 1] == pytest.approx(-(0.5 + 2.0 * G / 100.0),
                                                             rel=1e-10)
    assert 1 <= res.stats["newton_iterations"] <= 4


def test_the_inverted_pendulum_is_found_unstable_and_the_hanging_one_stable():
    """Without a spring the bar rests straight up or straight down; V'' = -m g L/2 sin(theta)
    is negative up and positive down. Newton's method finds the one nearest the guess."""
    model = sprung_pendulum(k=0.0)
    for angle, rest, stability in ((math.pi / 2 + 0.2, math.pi / 2, "unstable"),
                                   (-math.pi / 2 + 0.2, -math.pi / 2, "stable")):
        guess = model.q0.copy()
        guess[:2] = 0.4 * np.array([math.cos(angle), math.sin(angle)])
        guess[2] = angle
        res = mb.static_equilibrium(model, q_guess=guess)
        assert res.body("bar").angle[0] == pytest.approx(rest, abs=1e-10)
        assert res.stats["stability"] == [stability]


def test_a_released_motor_lets_the_pendulum_settle_and_a_held_one_carries_gravity():
    m, L = 2.0, 0.8
    model = sprung_pendulum(m, L, k=0.0, driven=True)
    times = np.linspace(0.0, 2.0, 9)
    held = mb.static_equilibrium(model, times)
    angle = -1.0 + times  # the ramp
    np.testing.assert_allclose(held.body("bar").angle, angle, rtol=0, atol=1e-12)
    # the motor balances gravity's moment about the pin: |effort| = m g L/2 |cos(angle)|
    np.testing.assert_allclose(np.abs(held.driver("motor").effort),
                               m * G * L / 2 * np.abs(np.cos(angle)), rtol=0, atol=1e-9)
    assert held.stats["stability"] == ["fully constrained"] * len(times)
    # released where the motor held it at t = 0 (angle -1 rad): it settles hanging
    released = mb.static_equilibrium(model, q_guess=held.q[0], release=["motor"])
    assert released.body("bar").angle[0] == pytest.approx(-math.pi / 2, abs=1e-10)
    assert released.driver("motor").effort[0] == 0.0
    assert released.stats["stability"] == ["stable"]
    with pytest.raises(mb.ModelError, match="'pump' is none"):
        mb.static_equilibrium(model, release=["pump"])


def test_a_torque_that_grows_in_time_is_balanced_where_it_is_at_each_time():
    """A pinned bar with a torque tau(t) = 2 + 3 t [N m] on it rests where gravity's moment
    about the pin balances it: m g L/2 cos(theta) = tau(t), on the branch below the pin."""
    m, L = 2.0, 0.8
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    bar = b.add_body("bar", mass=m, inertia=m * L * L / 12, position=(L / 2, 0.0))
    b.add(Revolute("O", b.ground, bar, at=(0.0, 0.0)))
    b.add(mb.Torque("push", bar, mb.Ramp(2.0, 3.0)))
    model = b.build()
    times = np.array([0.0, 0.5, 1.0])
    rest = mb.static_equilibrium(model, times, q_guess=[0.3, -0.2, -0.8])
    expected = -np.arccos((2.0 + 3.0 * times) / (m * G * L / 2))
    np.testing.assert_allclose(rest.body("bar").angle, expected, rtol=0, atol=1e-10)
    assert rest.stats["stability"] == ["stable"] * 3


def test_four_bar_motor_effort_by_virtual_work():
    """A four-bar with a spring from the coupler to the ground, held by its crank motor over a
    turn: the static effort equals dV/dphi, the slope of the potential energy (gravity and
    spring) along the motion, from positions alone (no multipliers)."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    A, B, C, D = (np.array(p) for p in ((0.0, 0.0), (0.1, 0.0), (0.35, 0.25), (0.3, 0.0)))

    def bar(name, p, q, mass):
        d = q - p
        return b.add_body(name, mass=mass, inertia=mass * float(d @ d) / 12,
                          position=(p + q) / 2, angle=math.atan2(d[1], d[0]))

    crank, coupler = bar("crank", A, B, 0.2), bar("coupler", B, C, 0.7)
    rocker = bar("rocker", D, C, 0.6)
    pin = b.add(Revolute("A", b.ground, crank, at=A))
    b.add(Revolute("B", crank, coupler, at=B))
    b.add(Revolute("C", coupler, rocker, at=C))
    b.add(Revolute("D", rocker, b.ground, at=D))
    b.add(mb.SpringDamper("spring", b.ground, coupler, at_i=(0.1, 0.4), at_j=(B + C) / 2,
                          stiffness=300.0, free_length=0.1))
    b.add(RotationDriver("motor", pin, motion=mb.Ramp(0.0, 2 * math.pi)))
    model = b.build()
    t = np.linspace(0.0, 0.95, 20)
    res = mb.static_equilibrium(model, t)
    h = 1e-5
    kin = mb.kinematic_analysis(model, np.sort(np.concatenate([t - h, t + h])))
    V = np.array([mb.potential_energy(model, q, c) for q, c in zip(kin.q, kin.charts)]) \
        if kin.charts is not None else np.array([mb.potential_energy(model, q) for q in kin.q])
    slope = (V[1::2] - V[0::2]) / (2 * math.pi * 2 * h)  # dV/dphi, phi = 2 pi t
    effort = res.driver("motor").effort
    np.testing.assert_allclose(np.abs(effort), np.abs(slope), rtol=1e-5,
                               atol=1e-6 * np.abs(slope).max())
    assert np.all(np.sign(effort) == np.sign(effort[0] * slope / slope[0]))


def test_settles_where_a_damped_run_comes_to_rest():
    model = sprung_pendulum(k=5.0, c=0.8)
    rest = mb.static_equilibrium(model)
    run = mb.forward_dynamics(model, np.linspace(0.0, 30.0, 301), method="DOP853", rtol=1e-10,
                              atol=1e-12)
    assert run.body("bar").angle[-1] == pytest.approx(rest.body("bar").angle[0], abs=1e-6)


def test_spatial_bar_on_a_ball_joint_pulled_by_a_spring_minimises_its_energy():
    """A bar hanging from a ball joint, pulled aside by a spring: its equilibrium is the
    minimum of gravity's and the spring's energy over the bar's direction, found here by
    scipy over two angles."""
    m, L, k, l0 = 1.5, 1.0, 60.0, 0.3
    anchor = np.array([0.8, 0.3, -0.2])
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G))
    bar = b.add_body("bar", mass=m, inertia=m * L * L * np.array([1e-2, 1 / 12, 1 / 12]),
                     position=(L / 2, 0.0, 0.0))
    b.add(Spherical("ball", b.ground, bar, at=(0.0, 0.0, 0.0)))
    b.add(mb.SpringDamper("spring", b.ground, bar, at_i=anchor, at_j=(L, 0.0, 0.0),
                          stiffness=k, free_length=l0))
    res = mb.static_equilibrium(b.build())
    tip = res.point("bar", (L / 2, 0.0, 0.0)).position[0]

    def energy(angles):
        a, e = angles
        u = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
        stretch = np.linalg.norm(L * u - anchor) - l0
        return m * G * (L / 2) * u[2] + 0.5 * k * stretch ** 2

    best = minimize(energy, [0.0, -0.5], method="Nelder-Mead",
                    options={"xatol": 1e-12, "fatol": 1e-14, "maxiter": 20000})
    a, e = best.x
    expected = L * np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    np.testing.assert_allclose(tip, expected, rtol=0, atol=1e-6)
    # the bar may still spin about its own axis, which passes through the spring's point:
    # one free motion without stiffness (neutral), the two swings stiff
    assert res.stats["stability"] == ["neutral"]
    eigenvalues = np.sort(res.stats["stiffness_eigenvalues"][0])
    assert abs(eigenvalues[0]) < 1e-6 * eigenvalues[-1] and np.all(eigenvalues[1:] > 0)


@pytest.mark.parametrize("angle", [0.3, 1.0, 2.5])
def test_a_relaxed_torsion_spring_without_gravity_is_found_from_far_away(angle):
    """No gravity: the bar rests where its spring is free (angle 0), where the applied forces
    vanish, so the force balance cannot be judged relative to them; the reduced stiffness in
    an orthonormal basis of the pin's free motion (-L/2 sin, L/2 cos, 1) / norm is
    k / (1 + (L/2)^2)."""
    L, k = 0.8, 5.0
    b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0))
    bar = b.add_body("bar", mass=2.0, inertia=0.1, angle=angle,
                     position=(L / 2 * math.cos(angle), L / 2 * math.sin(angle)))
    b.add(Revolute("O", b.ground, bar, at=(0.0, 0.0)))
    b.add(mb.RotationalSpringDamper("spring", body_i=b.ground, body_j=bar, stiffness=k,
                                    free_angle=0.0))
    res = mb.static_equilibrium(b.build())
    assert abs(res.body("bar").angle[0]) < 1e-12
    np.testing.assert_allclose(res.q[0], [L / 2, 0.0, 0.0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(res.lam[0], 0.0, rtol=0, atol=1e-12)
    assert res.stats["stability"] == ["stable"]
    np.testing.assert_allclose(res.stats["stiffness_eigenvalues"][0], [k / (1 + L * L / 4)],
                               rtol=1e-6, atol=0)


def test_a_spatial_bar_comes_to_rest_where_its_spring_is_free():
    """No gravity, a spring from a fixed point to the tip of a bar on a ball joint: every
    direction that puts the tip at the spring's free length from the anchor is an equilibrium
    (a circle of them, plus the spin about the bar), so the stiffness is singular along two
    free motions; the one found must have the spring relaxed."""
    L, l0 = 1.0, 0.3
    anchor = np.array([0.8, 0.3, -0.2])
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, 0.0))
    bar = b.add_body("bar", mass=1.5, inertia=1.5 * np.array([1e-2, 1 / 12, 1 / 12]),
                     position=(L / 2, 0.0, 0.0))
    b.add(Spherical("ball", b.ground, bar, at=(0.0, 0.0, 0.0)))
    b.add(mb.SpringDamper("spring", b.ground, bar, at_i=anchor, at_j=(L, 0.0, 0.0),
                          stiffness=60.0, free_length=l0))
    res = mb.static_equilibrium(b.build())
    tip = res.point("bar", (L / 2, 0.0, 0.0)).position[0]
    assert np.linalg.norm(tip - anchor) == pytest.approx(l0, abs=1e-10)
    assert np.linalg.norm(tip) == pytest.approx(L, abs=1e-12)
    np.testing.assert_allclose(res.lam[0], 0.0, rtol=0, atol=1e-9)
    assert res.stats["stability"] == ["neutral"]


def test_a_bar_guessed_at_the_horizontal_follows_gravity_down():
    """At the horizontal the pendulum's potential is flat to second order (V'' = 0), so the
    differenced stiffness there has no meaningful sign; the solve follows the weight down to
    the hanging rest, not up to the inverted one."""
    res = mb.static_equilibrium(sprung_pendulum(k=0.0))
    assert res.body("bar").angle[0] == pytest.approx(-math.pi / 2, abs=1e-10)
    assert res.stats["stability"] == ["stable"]
