"""Coulomb's friction in rigid impacts (:func:`mbd3d.analyses.sticking.impact_with_friction`):
Newton's restitution on the normal rate, Coulomb's law on the slip after the impact (it sticks
within ``mu P_n``, else slides with ``mu P_n`` against its slip). Checked against what is
derived here from momentum alone: a spinning ball bouncing to rest while it slides, whose
slip falls with the normal impulse however that impulse is split into impacts; a tilted rod
striking a floor, by the impulse-momentum equations of one free body; a pendulum's tip
striking a floor, by its angular momentum about the pivot; and the two impacts the law
cannot make (energy gained, Kane's paradox; an impact that jams, Painleve's) refused."""

from __future__ import annotations

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.errors import ModelError
from mbd3d.joints import Revolute

G = 9.81
TIGHT = dict(method="DOP853", rtol=1e-10, atol=1e-12)
#: the rods: length [m], mass [kg], the radius of the circle at their end [m]
ROD, ROD_MASS, END = 1.0, 2.0, 0.01
#: the radius of the pendulum's pin [m] (the friction in its hinge)
PIN = 0.1
#: the spatial rod's inertia about every axis [kg m^2]
SPATIAL_INERTIA = 0.3


def spinning_ball(dim: int, mu: float, e: float, v0, omega0, height: float,
                  radius: float = 0.1, mass: float = 2.0) -> mb.Model:
    """A disc (planar) or a ball (spatial) released ``height`` above a rigid floor moving at
    ``v0`` and spinning at ``omega0``."""
    b = mb.ModelBuilder(dim=dim, gravity=(0.0, -G) if dim == 2 else (0.0, 0.0, -G))
    up = np.eye(dim)[dim - 1]
    inertia = 0.5 * mass * radius ** 2 if dim == 2 else 0.4 * mass * radius ** 2 * np.ones(3)
    ball = b.add_body("ball", mass=mass, inertia=inertia, position=tuple((radius + height) * up),
                      velocity=tuple(v0), angular_velocity=omega0)
    b.add(mb.Contact("floor", mb.Sphere(ball, radius), mb.Plane(b.ground, normal=tuple(up)),
                     law=mb.RigidImpact(restitution=e), friction=mu))
    return b.build()


@pytest.mark.parametrize("dim", [2, 3])
def test_a_spinning_ball_bounces_to_rest_sliding_as_its_normal_impulse_says(dim):
    """Its slip u = v + omega x r (the contact point's velocity) never turns on a ball, and
    while it slides each impulse's friction is mu times its normal impulse: the slip falls
    by k mu / m of the normal impulse (k = 1 + m r^2 / I: 3 for a disc, 7/2 for a ball),
    which momentum gives at any time t after the first impact t1 as
    m (vz(t) + vn + g (t - t1)), whether it came in impacts or while the ball rests. So
    it sticks at t* = t1 + (u0 / (k mu) - vn) / g, rolling on at v0 - u0 / k, and the
    centre has moved sideways by v0 t - mu (z(t) - r + vn s + g s^2 / 2) u0 / |u0|,
    s = t - t1: across twelve impacts, the rest and the slide that follows."""
    mu, e, height, radius, mass = 0.1, 0.5, 0.5, 0.1, 2.0
    if dim == 2:
        v0, omega0, k = np.array([1.0, 0.0]), 30.0, 3.0
        u0 = np.array([v0[0] + omega0 * radius])
    else:
        v0, omega0, k = np.array([1.0, -0.5, 0.0]), np.array([-10.0, -25.0, 4.0]), 3.5
        u0 = (v0 + np.cross(omega0, [0.0, 0.0, -radius]))[:2]
    model = spinning_ball(dim, mu, e, v0, omega0, height, radius, mass)
    t = np.linspace(0.0, 2.0, 81)
    res = mb.forward_dynamics(model, t, **TIGHT)
    assert res.status == "complete"
    speed, along = float(np.linalg.norm(u0)), u0 / np.linalg.norm(u0)
    vn, t1 = np.sqrt(2 * G * height), np.sqrt(2 * height / G)
    t_stick = t1 + (speed / (k * mu) - vn) / G
    impacts, rests = res.stats["impacts"], res.stats["rests"]
    assert len(impacts) > 5 and [r["event"] for r in rests] == ["rest", "stick"]
    np.testing.assert_allclose(rests[1]["time"], t_stick, rtol=0, atol=1e-9)
    # each impact's friction (on the floor) mu times its normal impulse, along the slip
    for impact in impacts:
        np.testing.assert_allclose(impact["friction_impulse"][:dim - 1],
                                   mu * impact["impulse"] * along, rtol=1e-9)
    ball = res.body("ball")
    s = np.clip(t - t1, 0.0, None)
    height_now = ball.position[:, dim - 1] - radius
    sideways = v0[:dim - 1] * t[:, None] - mu * np.where(
        t > t1, height_now + vn * s + 0.5 * G * s ** 2, 0.0)[:, None] * along
    sliding = t < t_stick
    np.testing.assert_allclose(ball.position[sliding, :dim - 1], sideways[sliding], rtol=0,
                               atol=1e-9)
    np.testing.assert_allclose(ball.velocity[-1, :dim - 1], v0[:dim - 1] - speed / k * along,
                               rtol=0, atol=1e-9)
    energy = res.energy_balance()
    np.testing.assert_allclose(energy["total"], energy["total"][0], rtol=1e-9)


def tilted_rod(angle: float, v, omega: float, mu: float, e: float,
               static: float | None = None) -> mb.Model:
    """A free rod (1 m, 2 kg) without gravity, its lower end (a 1 cm circle) 5 cm above a rigid
    floor, tilted by ``angle`` from it, moving at ``v`` and turning at ``omega``; friction
    ``mu``, and ``static`` above it."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0))
    rod = b.add_body("rod", mass=ROD_MASS, inertia=ROD_MASS * ROD ** 2 / 12,
                     position=(0.0, 0.05 + END + ROD / 2 * np.sin(angle)), angle=angle,
                     velocity=tuple(v), angular_velocity=omega)
    b.add(mb.Contact("end", mb.Sphere(rod, END, point=(-ROD / 2, 0.0)),
                     mb.Plane(b.ground, normal=(0.0, 1.0)),
                     law=mb.RigidImpact(e, static_friction=static), friction=mu))
    return b.build()


def rod_impacts_by_hand(angle: float, v: np.ndarray, omega: float, mu: float, e: float,
                        static: float | None = None) -> list:
    """Every way the rod can leave the floor after its end strikes it, from the
    impulse-momentum equations of one body: ``m dv = P``, ``I domega = r x P`` with ``r`` from
    the centre to the contact point; Newton's law on the point's normal velocity and
    Coulomb's on its slip after the impact: sticking within ``static P_n`` (default ``mu``),
    or sliding along +x or -x against a slip that goes that way, with ``mu P_n``.
    ``[(v+, omega+, P)]``, ``P`` on the rod."""
    inertia = ROD_MASS * ROD ** 2 / 12
    r = np.array([-ROD / 2 * np.cos(angle), -ROD / 2 * np.sin(angle) - END])

    def after(P):
        return v + P / ROD_MASS, omega + (r[0] * P[1] - r[1] * P[0]) / inertia

    def point(vel, om):
        return np.array([vel[0] - om * r[1], vel[1] + om * r[0]])

    before = point(v, omega)
    A = np.column_stack([point(*after(p)) - before for p in np.eye(2)])  # dP -> d(point)
    found = []
    P = np.linalg.solve(A, np.array([0.0, -e * before[1]]) - before)
    if abs(P[0]) <= (mu if static is None else static) * P[1]:
        found.append((*after(P), P))
    for sign in (1.0, -1.0):
        d = np.array([-mu * sign, 1.0])
        P = (-(1.0 + e) * before[1]) / (A[1] @ d) * d
        if P[1] >= 0.0 and (before + A @ P)[0] * sign > 0.0:
            found.append((*after(P), P))
    return found


def touching(angle: float, v, omega: float) -> float:
    """When the flying rod's end first touches the floor [s], to 1e-12 s (bisection on the
    lowest point's height, 0.05 + L/2 (sin(angle) - sin(angle + omega t)) + v_y t)."""
    def low(t):
        return 0.05 + ROD / 2 * (np.sin(angle) - np.sin(angle + omega * t)) + v[1] * t
    times = np.linspace(0.0, 1.0, 10001)
    k = int(np.argmax(low(times) <= 0.0))
    a, b = times[k - 1], times[k]
    while b - a > 1e-12:
        a, b = (a, 0.5 * (a + b)) if low(0.5 * (a + b)) <= 0.0 else (0.5 * (a + b), b)
    return b


@pytest.mark.parametrize("angle, v, omega, mu, e, static", [
    (0.6, (0.3, -1.5), 0.5, 0.8, 0.5, None),    # sticks
    (0.6, (0.3, -1.5), 0.5, 0.3, 0.5, 0.8),     # sticks by its static coefficient
    (0.6, (1.5, -1.5), 0.5, 0.2, 0.5, 0.5),     # sticks by it (sliding with 0.2 would too)
    (0.6, (1.5, -1.5), 0.5, 0.2, 0.5, None),    # slides on
    (0.6, (1.5, -1.5), 0.5, 0.2, 0.5, 0.25),    # slides, with the kinetic coefficient
    (1.2, (-0.4, -2.0), -2.0, 0.3, 0.0, None),  # slides
    (0.3, (0.5, -1.0), 2.0, 0.25, 0.9, None),
])
def test_a_tilted_rod_striking_a_floor_as_its_momentum_says(angle, v, omega, mu, e, static):
    """Without gravity the rod flies straight at constant rates, so at the impact's time
    (the end's circle touching the floor, checked) its state is known; after it the rod
    flies on at the rates derived by hand, and each impact's energy is what the motion
    lost. Its friction turns its normal rate (the rod's rows are coupled): the case
    where Newton's law and Coulomb's are not independent."""
    model = tilted_rod(angle, v, omega, mu, e, static)
    res = mb.forward_dynamics(model, np.linspace(0.0, 0.5, 3), **TIGHT)
    assert res.status == "complete"
    (impact,) = res.stats["impacts"]
    ti = touching(angle, v, omega)
    np.testing.assert_allclose(impact["time"], ti, rtol=0, atol=1e-10)
    found = rod_impacts_by_hand(angle + omega * ti, np.array(v, float), omega, mu, e, static)
    # one way out with one coefficient; with a static one above it, a slide with the kinetic
    # one is consistent too where sticking is: the contact sticks where it can (its slip is
    # arrested in the impact), the first found
    assert len(found) == 1 or static is not None
    v_after, omega_after, P = found[0]
    rod = res.body("rod")
    np.testing.assert_allclose(rod.velocity[-1], v_after, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.ravel(rod.angular_velocity[-1])[-1], omega_after, rtol=0,
                               atol=1e-9)
    np.testing.assert_allclose(impact["impulse"], P[1], rtol=1e-9)
    np.testing.assert_allclose(impact["friction_impulse"][0], -P[0], rtol=0, atol=1e-9)
    inertia = ROD_MASS * ROD ** 2 / 12
    lost = 0.5 * ROD_MASS * (np.dot(v, v) - v_after @ v_after) + 0.5 * inertia * (
        omega ** 2 - omega_after ** 2)
    np.testing.assert_allclose(impact["energy_lost"], lost, rtol=1e-9)


def test_an_impact_that_would_give_energy_is_refused_naming_it():
    """Newton's law and Coulomb's are not dissipative at every impact of coupled rows:
    the rod below, derived by hand, would leave faster than it came (Kane and Levinson's
    paradox). The run is refused at the impact, naming it, rather than gaining energy."""
    angle, v, omega, mu, e = 0.65, np.array([0.83, -2.15]), 1.94, 0.31, 0.94
    ti = touching(angle, v, omega)
    (by_hand,) = rod_impacts_by_hand(angle + omega * ti, v, omega, mu, e)
    v_after, omega_after, _ = by_hand
    inertia = ROD_MASS * ROD ** 2 / 12
    gained = 0.5 * ROD_MASS * (v_after @ v_after - v @ v) + 0.5 * inertia * (
        omega_after ** 2 - omega ** 2)
    assert gained > 0.1
    model = tilted_rod(angle, v, omega, mu, e)
    with pytest.raises(ModelError, match=r"impact at t = .* on 'end' would give the motion "
                                         r".* J.*Kane's paradox"):
        mb.forward_dynamics(model, np.linspace(0.0, 0.5, 3), **TIGHT)


def pendulum_striking_floor(phi: float, omega: float, mu: float, e: float,
                            hinge_friction: float = 0.0) -> mb.Model:
    """A rod (1 m, 2 kg) hinged at the origin, swinging down at ``omega`` [rad/s] without
    gravity 0.2 rad before its tip (a 1 mm circle) strikes a floor at ``phi`` below the
    hinge's horizontal; with ``hinge_friction``, the hinge's Coulomb coefficient on a pin
    of radius :data:`PIN`."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0))
    a = phi - 0.2
    centre = np.array([np.cos(a), -np.sin(a)]) * ROD / 2
    rod = b.add_body("rod", mass=ROD_MASS, inertia=ROD_MASS * ROD ** 2 / 12,
                     position=tuple(centre), angle=-a, angular_velocity=omega,
                     velocity=(-omega * centre[1], omega * centre[0]))
    hinge = b.add(Revolute("hinge", b.ground, rod, at=(0.0, 0.0)))
    if hinge_friction:
        b.add(mb.JointFriction("rub", hinge, hinge_friction, pin_radius=PIN))
    b.add(mb.Contact("tip", mb.Sphere(rod, 1e-3, point=(ROD / 2, 0.0)),
                     mb.Plane(b.ground, normal=(0.0, 1.0), point=(0.0, -ROD * np.sin(phi) - 1e-3)),
                     law=mb.RigidImpact(e), friction=mu))
    return b.build()


@pytest.mark.parametrize("phi, mu", [(0.5, 0.3), (0.05, 0.3), (0.5, 0.9)])
def test_a_pendulum_striking_a_floor_as_its_angular_momentum_says(phi, mu):
    """The hinge holds through the impact: Newton's law turns the swing back at -e omega,
    which leaves the tip slipping (its velocity is across the rod), so it cannot stick and
    slides, and the angular momentum about the hinge, I dw = x P_n + y P_t with the tip's
    contact point (x, -y) = (L cos phi, -(L sin phi + rho)), gives
    P_n = I (1 + e) |omega| / (x - mu y)."""
    omega, e = -2.0, 0.5
    res = mb.forward_dynamics(pendulum_striking_floor(phi, omega, mu, e),
                              np.linspace(0.0, 0.2, 3), **TIGHT)
    (impact,) = res.stats["impacts"]
    np.testing.assert_allclose(impact["time"], 0.2 / abs(omega), rtol=1e-9)
    np.testing.assert_allclose(np.ravel(res.body("rod").angular_velocity[-1])[-1], -e * omega,
                               rtol=1e-9)
    x, y = ROD * np.cos(phi), ROD * np.sin(phi) + 1e-3
    hinged = ROD_MASS * ROD ** 2 / 3
    normal = hinged * (1.0 + e) * abs(omega) / (x - mu * y)
    np.testing.assert_allclose(impact["impulse"], normal, rtol=1e-9)
    np.testing.assert_allclose(impact["friction_impulse"], [mu * normal, 0.0, 0.0], rtol=1e-9)


@pytest.mark.parametrize("phi, e", [(0.5, 0.5), (0.0, 0.0), (1.2, 1.0)])
def test_a_pendulum_striking_a_floor_takes_its_hinges_friction_impulse(phi, e):
    """With Coulomb friction in the hinge (mu_j on a pin of radius r) and none at the tip,
    the impact's impulses load the pin, whose friction impulse mu_j r |R| opposes the swing
    while the tip closes (compression: dw = |omega| about the hinge) and the swing back
    while it opens again (restitution: dw = e |omega|, Newton's law at the tip). In each
    phase about the hinge I dw = x P -+ mu_j r |R|, x = L cos phi the tip's arm, omega the
    swing at the strike (the pin's friction has slowed it from its start) and the pin's
    impulse R = m dv_G - (0, P), the centre's velocity change dv_G = dw (L/2)(sin phi,
    cos phi). The pin's impulse depends on the friction's: each phase solved here by SciPy's
    brentq, the impulse their sum."""
    from scipy.optimize import brentq

    omega, mu_j = -2.0, 0.5
    res = mb.forward_dynamics(pendulum_striking_floor(phi, omega, 0.0, e, mu_j),
                              np.linspace(0.0, 0.2, 3), **TIGHT)
    (impact,) = res.stats["impacts"]
    x, hinged = ROD * np.cos(phi), ROD_MASS * ROD ** 2 / 3
    swing = -impact["rate_before"] / x

    def phase(dw: float, sense: float) -> float:
        def balance(P: float) -> float:
            pin = ROD_MASS * dw * ROD / 2 * np.array([np.sin(phi), np.cos(phi)]) - [0.0, P]
            return x * P + sense * mu_j * PIN * np.linalg.norm(pin) - hinged * dw
        return brentq(balance, 0.0, 2 * hinged * dw / x + 1.0, xtol=1e-15, rtol=1e-15)

    normal = phase(swing, 1.0) + (phase(e * swing, -1.0) if e else 0.0)
    frictionless = hinged * (1 + e) * swing / x
    assert abs(normal / frictionless - 1.0) > 0.01  # the friction takes a visible part
    np.testing.assert_allclose(impact["impulse"], normal, rtol=1e-9)
    np.testing.assert_allclose(impact["rate_after"], -e * impact["rate_before"], rtol=0,
                               atol=1e-12)


def test_a_pendulum_that_would_jam_is_refused():
    """Where mu y > x no impulse stops the tip: friction would press it into the floor the
    harder the harder it pressed (an impact that jams, Painleve's paradox), refused."""
    with pytest.raises(ModelError, match=r"at the impact at t = 0\.1 s on 'tip', the "
                                         r"impulses of an impact with friction were not "
                                         r"found.*Painleve"):
        mb.forward_dynamics(pendulum_striking_floor(1.2, -2.0, 0.5, 0.5),
                            np.linspace(0.0, 0.2, 3), **TIGHT)


def spatial_rod(tilt, v, omega, mu: float, e: float) -> tuple[mb.Model, np.ndarray]:
    """A free body (2 kg, inertia 0.3 kg m^2 about every axis, so that it turns at a constant
    rate in flight) whose end, a 1 cm ball at -0.5 m along its x axis, flies 5 cm above a
    rigid floor; its orientation ``tilt``; ``(model, centre)``."""
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, 0.0))
    centre = np.array([0.0, 0.0, 0.05 + END]) - tilt @ np.array([-ROD / 2, 0.0, 0.0])
    rod = b.add_body("rod", mass=ROD_MASS, inertia=SPATIAL_INERTIA * np.ones(3),
                     position=tuple(centre), orientation=tilt, velocity=tuple(v),
                     angular_velocity=tuple(omega))
    b.add(mb.Contact("end", mb.Sphere(rod, END, point=(-ROD / 2, 0.0, 0.0)),
                     mb.Plane(b.ground, normal=(0.0, 0.0, 1.0)), law=mb.RigidImpact(e),
                     friction=mu))
    return b.build(), centre


def spatial_impacts_by_hand(r: np.ndarray, v: np.ndarray, omega: np.ndarray, mu: float,
                            e: float) -> list:
    """Every impulse ``P`` (on the body) with which the spatial rod can leave the floor, its
    contact point at ``r`` from the centre: the momentum equations ``m dv = P``,
    ``I domega = r x P``; sticking (the point's slip stopped, its normal velocity
    ``-e`` times the one before) within the cone, or sliding, ``P = P_n (z - mu u)``, along
    the direction ``u = (cos a, sin a, 0)`` of the slip it leaves with: two equations in
    ``(P_n, a)``, solved by SciPy's fsolve from twelve directions."""
    from scipy.optimize import fsolve

    def point(P):
        return v + P / ROD_MASS + np.cross(omega + np.cross(r, P) / SPATIAL_INERTIA, r)

    before = point(np.zeros(3))
    A = np.column_stack([point(p) - before for p in np.eye(3)])
    found = []
    P = np.linalg.solve(A, np.array([0.0, 0.0, -e * before[2]]) - before)
    if np.linalg.norm(P[:2]) <= mu * P[2]:
        found.append(P)

    def sliding(x):
        u = np.array([np.cos(x[1]), np.sin(x[1]), 0.0])
        return x[0] * (np.array([0.0, 0.0, 1.0]) - mu * u), u

    def mismatch(x):
        P, u = sliding(x)
        c = point(P)
        return [c[2] + e * before[2], u[0] * c[1] - u[1] * c[0]]

    for start in np.linspace(0.0, 2 * np.pi, 12, endpoint=False):
        x = fsolve(mismatch, [1.0, start], xtol=1e-14, full_output=True)[0]
        P, u = sliding(x)
        if (np.max(np.abs(mismatch(x))) <= 1e-12 and x[0] > 0.0 and point(P) @ u > 0.0
                and not any(np.allclose(P, f, rtol=0, atol=1e-9) for f in found)):
            found.append(P)
    return found


@pytest.mark.parametrize("v, omega, mu, e, turn, yaw", [
    ((0.3, 0.8, -1.5), (0.5, -1.0, 0.3), 0.9, 0.5, None, 0.0),  # sticks
    ((1.5, 0.6, -1.5), (2.0, -1.0, 0.3), 0.3, 0.5, 1.8, 0.0),
    ((0.2, 1.6, -1.0), (2.5, -1.5, 1.0), 0.4, 0.2, 12.9, 0.0),  # from 67 to 80 degrees
    ((0.2, 1.6, -1.0), (2.5, -1.5, 1.0), 0.4, 0.2, 12.9, 106.4),  # across 180 degrees
])
def test_a_spatial_rod_striking_a_floor_slides_the_way_its_slip_leaves(v, omega, mu, e, turn,
                                                                       yaw):
    """In space the friction of a body struck off its centre turns the slip it rubs against:
    the direction it slides in is the one its slip comes out along, found by hand from the
    momentum equations by another method (SciPy's root finder from twelve starts, which
    finds no other way out). The whole throw is turned by ``yaw`` [deg] about the vertical,
    once so that the slip turns through the x axis's back (the angles' cut)."""
    from scipy.spatial.transform import Rotation

    turned_by = Rotation.from_euler("z", yaw, degrees=True).as_matrix()
    tilt = turned_by @ Rotation.from_euler("zy", [0.4, -0.7]).as_matrix()
    v, omega = turned_by @ np.array(v), turned_by @ np.array(omega)
    model, centre = spatial_rod(tilt, v, omega, mu, e)
    res = mb.forward_dynamics(model, np.linspace(0.0, 0.5, 3), **TIGHT)
    (impact,) = res.stats["impacts"]
    # flying straight, turning at omega: where the end's ball touches the floor is the impact
    ti = impact["time"]
    end = Rotation.from_rotvec(omega * ti).as_matrix() @ tilt @ np.array([-ROD / 2, 0.0, 0.0])
    np.testing.assert_allclose(centre[2] + v[2] * ti + end[2] - END, 0.0, rtol=0, atol=1e-10)
    r = end - np.array([0.0, 0.0, END])
    (P,) = spatial_impacts_by_hand(r, v, omega, mu, e)
    rod = res.body("rod")
    np.testing.assert_allclose(rod.velocity[-1], v + P / ROD_MASS, rtol=0, atol=1e-9)
    np.testing.assert_allclose(rod.angular_velocity[-1],
                               omega + np.cross(r, P) / SPATIAL_INERTIA, rtol=0, atol=1e-9)
    np.testing.assert_allclose(impact["impulse"], P[2], rtol=1e-9)
    np.testing.assert_allclose(impact["friction_impulse"], -P * [1.0, 1.0, 0.0], rtol=0,
                               atol=1e-9)
    if turn is None:  # sticking, inside the cone
        assert np.linalg.norm(P[:2]) < mu * P[2]
        return
    # sliding: the friction against the slip it leaves with, turned from the one it came with
    np.testing.assert_allclose(np.linalg.norm(P[:2]), mu * P[2], rtol=1e-12)
    slip_before = (v + np.cross(omega, r))[:2]
    turned = np.degrees(np.arccos(-P[:2] @ slip_before / np.linalg.norm(P[:2])
                                  / np.linalg.norm(slip_before)))
    np.testing.assert_allclose(turned, turn, atol=0.05)


def test_the_friction_impulses_are_kept_in_a_results_file_and_on_the_time_line(tmp_path):
    """Written and read back, a run keeps each impact's friction impulse; the recording's
    time line gives its size beside the normal impulse."""
    from mbd3d.viewer import read_component, record

    model = tilted_rod(0.6, (1.5, -1.5), 0.5, 0.2, 0.5)
    res = mb.forward_dynamics(model, np.linspace(0.0, 0.2, 5), **TIGHT)
    (impact,) = res.stats["impacts"]
    path = tmp_path / "rod.npz"
    res.to_npz(path)
    (back,) = mb.read_results(path, model).stats["impacts"]
    assert back["friction_impulse"] == impact["friction_impulse"]
    record(res, tmp_path / "rod.rrd")
    _, text = read_component(tmp_path / "rod.rrd", "/impacts", "TextLog:text",
                             timeline="sim_time")
    size = np.linalg.norm(impact["friction_impulse"])
    assert f"friction impulse {size:.6g}," in str(text[0][0])
    np.testing.assert_allclose(size, 0.2 * impact["impulse"], rtol=1e-12)
