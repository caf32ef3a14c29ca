"""The energy balance of runs with contacts: kinetic and potential energy (the contacts'
springs included) from the states, the energy the contacts dissipated integrated from their
power, and the rigid impacts' losses, add up to the start's energy to the integrator's
tolerance; a ball that slides into rolling loses to friction what the closed form says."""

from __future__ import annotations

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.joints import Prismatic

G = 9.81


def _ball(dim: int, law, friction: float = 0.0, height: float = 0.3, speed: float = 0.5,
          rigid_ball: bool = False, python_force: bool = False) -> mb.Model:
    """A ball of radius 0.1 m thrown sideways at ``speed`` from ``height`` above a floor; with
    ``rigid_ball``, a second ball beside it bouncing to rest on the floor rigidly; with
    ``python_force``, a force element given as a Python function that pushes with nothing."""
    up = (0.0, 1.0) + (0.0,) * (dim - 2)
    b = mb.ModelBuilder(dim=dim, gravity=tuple(-G * np.array(up)))
    inertia = 0.004 if dim == 2 else np.eye(3) * 0.004
    ball = b.add_body("ball", mass=1.0, inertia=inertia, position=(0.0, height + 0.1)
                      + (0.0,) * (dim - 2), velocity=(speed, 0.0) + (0.0,) * (dim - 2))
    floor = mb.Plane(b.ground, normal=up)
    b.add(mb.Contact("floor", mb.Sphere(ball, 0.1), floor, law=law, friction=friction,
                     slip_velocity=1e-3))
    if python_force:
        b.add(mb.PointForce("nothing", ball, force=lambda t: (0.0,) * dim))
    if rigid_ball:
        other = b.add_body("other", mass=2.0, inertia=inertia, position=(3.0, 0.25)
                           + (0.0,) * (dim - 2))
        b.add(mb.Contact("rigid", mb.Sphere(other, 0.1), floor,
                         law=mb.RigidImpact(restitution=0.5, rest_speed=0.05)))
    return b.build()


@pytest.mark.parametrize("dim, method", [(2, "DOP853"), (3, "DOP853"), (2, "RK45")])
def test_bounces_with_damping_and_friction_keep_the_balance_to_the_tolerance(dim, method):
    """Hertz's damped law and friction: 97 % of the energy the ball can lose dissipated over
    1.5 s of bounces (it is left rolling slowly), the balance kept to 2e-9 of the whole at
    every output (measured: 0.9e-10 with DOP853, 5e-10 with RK45, at rtol 1e-10), in flight
    and inside the contacts, where the law's force is clipped at zero while its spring
    unloads: a power the motion does not feel, so the steps are controlled on the energy too
    and end where the unloading does."""
    model = _ball(dim, mb.HertzContact(stiffness=1e7, restitution=0.5), friction=0.3)
    res = mb.forward_dynamics(model, np.linspace(0.0, 1.5, 1501), method=method, rtol=1e-10,
                              atol=1e-12)
    balance = res.energy_balance()
    start = balance["total"][0]
    inside = res.contacts().gap[:, 0] < 0.0
    resting = G * 0.1  # the potential energy of the ball lying on the floor
    assert inside.sum() > 20
    assert balance["dissipated"][-1] > 0.95 * (start - resting)
    np.testing.assert_allclose(balance["total"], start, rtol=0, atol=2e-9 * start)
    assert np.all(np.diff(balance["dissipated"]) >= -2e-9 * start)  # never negative power
    np.testing.assert_array_equal(res.columns()["floor.dissipated [J]"],
                                  res.contact_dissipation[:, 0])


def test_a_model_with_a_force_given_as_a_function_keeps_the_balance():
    """A force element given as a Python function is evaluated in Python at every stage; the
    contacts stay in the compiled loop, which integrates their dissipation and ends steps
    at their switches as without it: the balance closes to the same 2e-9."""
    model = _ball(2, mb.HertzContact(stiffness=1e7, restitution=0.5), friction=0.3,
                  python_force=True)
    assert model._core.python_parts
    res = mb.forward_dynamics(model, np.linspace(0.0, 0.6, 61), method="DOP853", rtol=1e-10,
                              atol=1e-12)
    balance = res.energy_balance()
    start = balance["total"][0]
    assert balance["dissipated"][-1] > 0.5 * (start - G * 0.1)
    np.testing.assert_allclose(balance["total"], start, rtol=0, atol=2e-9 * start)


def test_an_elastic_frictionless_bounce_dissipates_nothing():
    model = _ball(2, mb.HertzContact(stiffness=1e7, restitution=1.0))
    res = mb.forward_dynamics(model, np.linspace(0.0, 1.0, 101), method="DOP853")
    assert np.all(res.contact_dissipation == 0.0)
    assert np.all(res.contacts().dissipated_energy == 0.0)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_sliding_ball_loses_two_sevenths_of_its_energy_to_friction(dim):
    """Set down sliding at v0 (no spin) in its static penetration, it ends rolling at 5/7 v0:
    its kinetic energy falls from m v0^2 / 2 to (m + I / r^2) (5 v0 / 7)^2 / 2 = 5/7 of it
    (I = 2/5 m r^2), the rest dissipated by friction. Its contact point is midway through
    the penetration, where the rolling radius is rho = r - delta / 2: exactly, the speed and
    the loss with rho."""
    m, r, v0, K = 1.0, 0.1, 2.0, 1e7
    delta = (m * G / K) ** (2 / 3)
    rho = r - delta / 2
    b = mb.ModelBuilder(dim=dim, gravity=(0.0, -G) + (0.0,) * (dim - 2))
    inertia = 0.4 * m * r * r
    ball = b.add_body("ball", mass=m, inertia=inertia if dim == 2 else np.eye(3) * inertia,
                      position=(0.0, r - delta) + (0.0,) * (dim - 2),
                      velocity=(v0, 0.0) + (0.0,) * (dim - 2))
    b.add(mb.Contact("floor", mb.Sphere(ball, r), mb.Plane(b.ground, normal=(0.0, 1.0)
                                                               + (0.0,) * (dim - 2)),
                     law=mb.HertzContact(stiffness=K, restitution=0.5), friction=0.3,
                     slip_velocity=1e-4))
    with pytest.warns(mb.ContactWarning, match="static penetration"):
        model = b.build()  # placed in it
    res = mb.forward_dynamics(model, [0.0, 2 * v0 / (7 * 0.3 * G) + 0.3],
                              method="DOP853", rtol=1e-10, atol=1e-12)
    # the angular momentum about the contact point is kept: m v0 rho = m v rho + I v / rho
    v = v0 * rho * rho / (rho * rho + 0.4 * r * r)
    rolling = 0.5 * m * v * v + 0.5 * inertia * (v / rho) ** 2
    lost = 0.5 * m * v0 * v0 - rolling
    assert lost == pytest.approx(m * v0 * v0 / 7, rel=1e-3)
    assert res.contact_dissipation[-1, 0] == pytest.approx(lost, rel=1e-6)


@pytest.mark.parametrize("python_force", [False, True])
def test_generalized_alpha_keeps_the_balance_to_its_second_order(python_force):
    """The trapezoidal rule on its steps' ends: halving the step quarters the balance's
    error (the method's own numerical damping off, rho_inf = 1); so too beside a force
    element given as a Python function."""
    model = _ball(2, mb.LinearContact(stiffness=1e5, restitution=0.5), friction=0.3,
                  python_force=python_force)
    errors = []
    for h in (1e-4, 5e-5):
        res = mb.forward_dynamics(model, np.linspace(0.0, 0.6, 61), method="generalized-alpha",
                                  step=h, rho_inf=1.0)
        balance = res.energy_balance()
        assert balance["dissipated"][-1] > 1.0
        errors.append(np.abs(balance["total"] - balance["total"][0]).max())
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=0.1)


def test_the_balance_holds_with_rigid_impacts_and_rests_beside():
    """A compliant ball beside a rigid one that bounces to rest: the impacts' losses and the
    bounces no longer made (``stats``) close the balance with the compliant contact's
    dissipation, while the held rest switches the run to its Python right-hand side."""
    model = _ball(2, mb.HertzContact(stiffness=1e7, restitution=0.5), friction=0.3,
                  rigid_ball=True)
    res = mb.forward_dynamics(model, np.linspace(0.0, 1.5, 301), method="DOP853", rtol=1e-10,
                              atol=1e-12)
    assert res.stats["rests"] and res.stats["impacts"]
    balance = res.energy_balance()
    assert balance["lost_in_impacts"][-1] > 0.5 and balance["dissipated"][-1] > 1.0
    start = balance["total"][0]
    np.testing.assert_allclose(balance["total"], start, rtol=0, atol=2e-9 * start)


def _slider_between_stops(dim: int, law) -> mb.Model:
    """A 2 kg slider on a level rail, thrown at 1 m/s from the middle of its 0.2 m travel
    between two stops of ``law``; gravity square to the rail."""
    b = mb.ModelBuilder(dim=dim, gravity=(0.0, -G) + (0.0,) * (dim - 2))
    inertia = 0.01 if dim == 2 else np.eye(3) * 0.01
    slider = b.add_body("slider", mass=2.0, inertia=inertia, position=(0.0,) * dim,
                        velocity=(1.0,) + (0.0,) * (dim - 1))
    rail = b.add(Prismatic("rail", b.ground, slider, axis=(1.0,) + (0.0,) * (dim - 1)))
    b.add(mb.JointLimit("stops", rail, lower=-0.1, upper=0.1, law=law))
    return b.build()


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("law", [mb.HertzContact(stiffness=1e8, restitution=0.6),
                                 mb.ImpactFunction(stiffness=1e8, damping=2e3,
                                                   penetration=1e-4)],
                         ids=["Hertz", "IMPACT"])
def test_joint_stops_keep_the_balance(dim, law):
    """The stops' laws dissipate through the contacts' code: the total stays at its start to
    2e-9 of it over three strikes (measured: 1.3e-10 at most), and Hertz's law, calibrated to
    e = 0.6 on the slider's mass, leaves it e^3 of its speed, so that the stops dissipated
    ``(1 - e^6)`` of its kinetic energy (strikes at 0.1, 0.43 and 0.99 s; 1.2 s run;
    measured to 1.2e-10)."""
    res = mb.forward_dynamics(_slider_between_stops(dim, law), np.linspace(0.0, 1.2, 121),
                              method="DOP853", rtol=1e-10, atol=1e-12)
    balance = res.energy_balance()
    start = balance["total"][0]
    assert balance["dissipated"][-1] > 0.5 * start
    np.testing.assert_allclose(balance["total"], start, rtol=0, atol=2e-9 * start)
    if isinstance(law, mb.HertzContact):
        assert balance["dissipated"][-1] == pytest.approx(start * (1 - 0.6 ** 6), rel=1e-8)


def test_the_energy_between_step_ends_is_the_cubic_through_their_energies_and_powers():
    """Generalized-alpha's energies between its steps' ends (``dissipation.hermite``): any
    cubic in time is reproduced exactly from its values and slopes at the ends, of two
    contacts at once, anywhere inside the step (and held at the ends outside it)."""
    from mbd3d.analyses.dissipation import hermite

    c = np.array([[0.3, -1.0, 2.0, 0.5], [1.0, 0.25, -0.5, 3.0]])  # two cubics' coefficients

    def energy(t):
        return c[:, 0] + c[:, 1] * t + c[:, 2] * t ** 2 + c[:, 3] * t ** 3

    def power(t):
        return c[:, 1] + 2 * c[:, 2] * t + 3 * c[:, 3] * t ** 2

    t_old, step = 1.2, 0.35
    z = np.array([energy(t_old + step), energy(t_old), power(t_old + step), power(t_old)])
    for t in np.linspace(t_old, t_old + step, 7):
        np.testing.assert_allclose(hermite(t, t_old, step, z), energy(t), rtol=1e-13, atol=0)
    np.testing.assert_allclose(hermite(t_old + 2 * step, t_old, step, z), energy(t_old + step))
