"""Gear pairs and rack and pinion against what gears must do: speed ratios from the pitch radii,
torque ratios by the power balance, Willis's formula for a planetary train, a geared pendulum
against its one-degree-of-freedom equation (derived by hand below, integrated by SciPy), and
a rack driven by its pinion.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mbd3d as mb
from mbd3d.joints import (GearPair, PointOnLine, Prismatic, RackPinion, Revolute,
                          RotationDriver)

G = 9.81
R1, R2, R3 = 0.05, 0.03, 0.08
INERTIA = (1.2e-3, 4e-4, 6e-3)
CRANK = mb.Polynomial([0.3, 10.0, 3.0])  # theta_1(t) = 0.3 + 10 t + 3 t^2 [rad]


def gear_train(load: float = 0.0) -> mb.Model:
    """Three gears on fixed axles, 1 -> idler 2 -> 3, the centre line bent at 2 (gravity in
    the plane, a load torque on gear 3)."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G), name="gear train")
    c2 = np.array([R1 + R2, 0.0])
    c3 = c2 + (R2 + R3) * np.array([math.cos(0.7), math.sin(0.7)])
    gears = [b.add_body(f"g{k + 1}", mass=m, inertia=inertia, position=c, angle=a)
             for k, (m, inertia, c, a) in enumerate(zip(
                 (1.0, 0.4, 2.5), INERTIA, ((0.0, 0.0), c2, c3), (0.3, -0.2, 1.0)))]
    axles = [b.add(Revolute(n, b.ground, g, at=g.q0[:2])) for n, g in zip("ABC", gears)]
    b.add(GearPair("m12", gears[0], gears[1], radius_i=R1, radius_j=R2))
    b.add(GearPair("m23", gears[1], gears[2], radius_i=R2, radius_j=R3))
    b.add(RotationDriver("motor", axles[0], motion=CRANK))
    if load:
        b.add(mb.Torque("load", gears[2], load))
    return b.build()


def test_gear_train_speed_ratio_at_every_level():
    t = np.linspace(0.0, 1.5, 31)
    res = mb.kinematic_analysis(gear_train(), t)
    theta = [res.body(f"g{k}").angle for k in (1, 2, 3)]
    turn = [th - th[0] for th in theta]
    # the idler turns the other way, the output with ratio R1/R3 through it
    np.testing.assert_allclose(turn[1], -R1 / R2 * turn[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(turn[2], R1 / R3 * turn[0], rtol=0, atol=1e-12)
    omega_1, alpha_1 = 10.0 + 6.0 * t, 6.0
    np.testing.assert_allclose(res.body("g3").angular_velocity, R1 / R3 * omega_1, rtol=1e-12)
    np.testing.assert_allclose(res.body("g2").angular_acceleration, -R1 / R2 * alpha_1,
                               rtol=1e-11)
    assert np.max(res.position_residual) < 1e-12


def test_gear_train_torques_by_the_power_balance():
    load = -3.0  # N m on gear 3, against its turning
    t = np.linspace(0.0, 1.0, 21)
    res = mb.inverse_dynamics(gear_train(load), t)
    ratios = np.array([1.0, -R1 / R2, R1 / R3])
    # power: effort omega_1 + load omega_3 = d/dt sum(I omega^2 / 2); centres fixed, so
    # gravity does no work
    inertia_1 = float(np.sum(np.array(INERTIA) * ratios ** 2))
    expected = inertia_1 * 6.0 - load * R1 / R3
    np.testing.assert_allclose(res.driver("motor").effort, expected, rtol=1e-11)
    # gear 3 alone: I_3 alpha_3 = load + torque of the mesh on it
    tangential = res.joint("m23").mesh_force.tangential
    np.testing.assert_allclose(tangential * R3, INERTIA[2] * R1 / R3 * 6.0 - load, rtol=1e-11)
    # its axle carries the tooth force, perpendicular to the centre line, and the weight
    force = res.joint("m23").reaction(on="g3").force
    line = res.body("g3").position - res.body("g2").position
    np.testing.assert_allclose(np.einsum("ki,ki->k", force, line), 0.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(force, axis=1), np.abs(tangential), rtol=1e-12)
    axle = res.joint("C").reaction(on="g3").force
    np.testing.assert_allclose(axle + force + [0.0, -2.5 * G], 0.0, rtol=0, atol=1e-11)
    tooth = res.joint("m23").mesh_force
    np.testing.assert_allclose(tooth.tooth, np.abs(tangential) / math.cos(math.radians(20)))
    np.testing.assert_allclose(tooth.separating, np.abs(tangential) * math.tan(math.radians(20)))
    check_tooth_force(tooth, res.body("g3").position, res.body("g2").position, R3, away=1.0)


def check_tooth_force(mesh, centre, other, radius, away):
    """The tooth force at the pitch point on the line of centres: its moment about the centre
    is the tangential force times the radius, it leans by the pressure angle, and it pushes
    the gear ``away`` (+1) from the other centre or towards it (-1, a ring)."""
    arm = mesh.point - centre
    np.testing.assert_allclose(np.linalg.norm(arm, axis=1), radius, rtol=1e-12)
    line = other - centre
    np.testing.assert_allclose(arm[:, 0] * line[:, 1] - arm[:, 1] * line[:, 0], 0.0,
                               rtol=0, atol=1e-14)
    np.testing.assert_allclose(arm[:, 0] * mesh.force[:, 1] - arm[:, 1] * mesh.force[:, 0],
                               mesh.tangential * radius, rtol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(mesh.force, axis=1), mesh.tooth, rtol=1e-12)
    radial = -np.einsum("ki,ki->k", mesh.force, arm) / radius
    np.testing.assert_allclose(radial * away, mesh.separating, rtol=1e-12)


def planetary(carrier_load: float = 0.0) -> mb.Model:
    """Sun driven, ring fixed (the ground), one planet on a carrier: an internal mesh."""
    rs, rp = 0.04, 0.025
    b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0), name="planetary")
    sun = b.add_body("sun", mass=0.5, inertia=4e-4, position=(0.0, 0.0))
    arm = b.add_body("carrier", mass=0.8, inertia=2e-3, position=(0.0, 0.0))
    centre = (rs + rp) * np.array([math.cos(2.0), math.sin(2.0)])
    planet = b.add_body("planet", mass=0.3, inertia=9e-5, position=centre, angle=0.4)
    shaft = b.add(Revolute("sun shaft", b.ground, sun, at=(0.0, 0.0)))
    b.add(Revolute("carrier shaft", b.ground, arm, at=(0.0, 0.0)))
    b.add(Revolute("planet pin", arm, planet, at=centre))
    b.add(GearPair("sun-planet", sun, planet, radius_i=rs, radius_j=rp))
    b.add(GearPair("planet-ring", planet, b.ground, radius_i=rp, radius_j=rs + 2 * rp,
                   internal=True, center_j=(0.0, 0.0)))
    b.add(RotationDriver("motor", shaft, motion=CRANK))
    if carrier_load:
        b.add(mb.Torque("load", arm, carrier_load))
    return b.build()


def test_planetary_train_follows_willis():
    rs, rp = 0.04, 0.025
    rr = rs + 2 * rp
    t = np.linspace(0.0, 2.0, 41)
    res = mb.kinematic_analysis(planetary(), t)
    w_sun = res.body("sun").angular_velocity
    w_carrier = res.body("carrier").angular_velocity
    w_planet = res.body("planet").angular_velocity
    # ring fixed: omega_carrier = omega_sun rs / (rs + rr); relative to the carrier, the
    # planet turns against the sun by rs / rp
    np.testing.assert_allclose(w_carrier, w_sun * rs / (rs + rr), rtol=1e-12)
    np.testing.assert_allclose(w_planet - w_carrier, -(w_sun - w_carrier) * rs / rp, rtol=1e-12)
    np.testing.assert_allclose(res.body("planet").angular_acceleration,
                               6.0 * (rs / (rs + rr) - (1 - rs / (rs + rr)) * rs / rp),
                               rtol=1e-11)
    # the carrier turns more than a full turn: the mesh row has no turn count to lose
    assert res.body("carrier").angle[-1] - res.body("carrier").angle[0] > 2 * math.pi
    sun_turn = res.body("sun").angle - res.body("sun").angle[0]
    carrier_turn = res.body("carrier").angle - res.body("carrier").angle[0]
    np.testing.assert_allclose(carrier_turn, sun_turn * rs / (rs + rr), rtol=0, atol=1e-12)


def test_planetary_torque_ratio_and_internal_mesh_force():
    rs, rp = 0.04, 0.025
    rr = rs + 2 * rp
    load = -5.0
    t = np.linspace(0.0, 1.0, 11)
    res = mb.inverse_dynamics(planetary(load), t)
    ratio = rs / (rs + rr)  # carrier per sun
    planet_ratio = ratio - (1 - ratio) * rs / rp
    # planet centre on a circle of radius rs + rp: its kinetic energy adds m v^2 / 2
    inertia = 4e-4 + 2e-3 * ratio ** 2 + 9e-5 * planet_ratio ** 2 + 0.3 * ((rs + rp) * ratio) ** 2
    np.testing.assert_allclose(res.driver("motor").effort, inertia * 6.0 - load * ratio,
                               rtol=1e-11)
    # the ring (the ground, body j of the internal mesh) takes the torque about O that the
    # motor and the load put in and the moving gears' angular momentum about O does not keep:
    # H_O = (I_s + I_c k + I_p k_p + m_p (rs + rp)^2 k) omega_sun
    momentum_rate = (4e-4 + 2e-3 * ratio + 9e-5 * planet_ratio
                     + 0.3 * (rs + rp) ** 2 * ratio) * 6.0
    ring_torque = res.joint("planet-ring").mesh_force.tangential * rr
    origin = np.zeros((len(t), 2))
    check_tooth_force(res.joint("planet-ring").mesh_force, origin, res.body("planet").position,
                      rr, away=-1.0)
    check_tooth_force(res.joint("sun-planet").mesh_force, res.body("planet").position, origin,
                      rp, away=1.0)
    np.testing.assert_allclose(ring_torque, res.driver("motor").effort + load - momentum_rate,
                               rtol=1e-11)


def test_geared_pendulum_matches_its_one_degree_of_freedom_equation():
    """An arm hinged at O carries a planet gear rolling round a sun gear fixed at O."""
    rs, rp = 0.06, 0.04
    L = rs + rp
    ma, ia, mp, ip = 0.6, 0.6 * L * L / 12, 0.9, 0.9 * rp * rp / 2
    phi0 = 1.2  # from hanging
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G), name="geared pendulum")
    down = np.array([math.sin(phi0), -math.cos(phi0)])
    arm = b.add_body("arm", mass=ma, inertia=ia, position=L / 2 * down, angle=phi0 - math.pi / 2)
    planet = b.add_body("planet", mass=mp, inertia=ip, position=L * down, angle=0.5)
    b.add(Revolute("O", b.ground, arm, at=(0.0, 0.0)))
    b.add(Revolute("P", arm, planet, at=L * down))
    b.add(GearPair("mesh", b.ground, planet, radius_i=rs, radius_j=rp, center_i=(0.0, 0.0)))
    model = b.build()
    t = np.linspace(0.0, 2.0, 41)
    res = mb.forward_dynamics(model, t, method="DOP853", rtol=1e-11, atol=1e-12)

    # T = J phi'^2 / 2, the planet turning at (1 + rs/rp) phi'; V = -(ma L/2 + mp L) g cos phi
    J = ia + ma * (L / 2) ** 2 + mp * L * L + ip * (1 + rs / rp) ** 2
    torque = (ma * L / 2 + mp * L) * G
    sol = solve_ivp(lambda _, y: [y[1], -torque / J * math.sin(y[0])], (0.0, 2.0), [phi0, 0.0],
                    t_eval=t, method="DOP853", rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res.body("arm").angle + math.pi / 2, sol.y[0], rtol=0, atol=1e-8)
    planet_turn = res.body("planet").angle - 0.5
    np.testing.assert_allclose(planet_turn, (1 + rs / rp) * (sol.y[0] - phi0), rtol=0, atol=1e-8)
    energy = res.kinetic_energy + res.potential_energy
    assert np.ptp(energy) < 1e-9 * torque


def rack_and_pinion(force: float = 0.0, angle: float = 0.25) -> mb.Model:
    """A pinion on a fixed axle drives a rack sliding below it along a tilted guide."""
    rho = 0.04
    axis = np.array([math.cos(angle), math.sin(angle)])
    below = np.array([axis[1], -axis[0]])  # to the right of the axis
    b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0), name="rack and pinion")
    pinion = b.add_body("pinion", mass=0.4, inertia=3e-4, position=(0.0, 0.0), angle=0.7)
    rack = b.add_body("rack", mass=1.5, inertia=0.02, position=(rho + 0.01) * below, angle=angle)
    axle = b.add(Revolute("axle", b.ground, pinion, at=(0.0, 0.0)))
    b.add(Prismatic("guide", b.ground, rack, axis=axis))
    b.add(RackPinion("mesh", rack, pinion, radius=rho, axis=axis))
    b.add(RotationDriver("motor", axle, motion=CRANK))
    if force:
        b.add(mb.PointForce("push", rack, force * axis))
    return b.build()


def test_rack_advances_one_pitch_radius_per_radian():
    rho, angle = 0.04, 0.25
    axis = np.array([math.cos(angle), math.sin(angle)])
    t = np.linspace(0.0, 1.0, 21)
    res = mb.inverse_dynamics(rack_and_pinion(force=-20.0), t)
    turn = res.body("pinion").angle - res.body("pinion").angle[0]
    travel = (res.body("rack").position - res.body("rack").position[0]) @ axis
    # a counter-clockwise pinion moves a rack below it forwards
    np.testing.assert_allclose(travel, rho * turn, rtol=0, atol=1e-13)
    np.testing.assert_allclose(res.body("rack").velocity @ axis,
                               rho * res.body("pinion").angular_velocity, rtol=1e-12)
    # power: effort omega = (I + m rho^2) omega alpha + 20 N * rho omega
    np.testing.assert_allclose(res.driver("motor").effort, (3e-4 + 1.5 * rho ** 2) * 6.0
                               + 20.0 * rho, rtol=1e-11)
    # the mesh turns the pinion back: the rack's inertia and push, over the radius
    np.testing.assert_allclose(res.joint("mesh").mesh_force.tangential,
                               -(1.5 * rho * 6.0 + 20.0), rtol=1e-11)
    below = np.array([axis[1], -axis[0]])
    check_tooth_force(res.joint("mesh").mesh_force, res.body("pinion").position,
                      res.body("pinion").position + below, rho, away=1.0)


def test_pinion_rolls_along_a_fixed_rack():
    """A wheel (pinion) on a fixed rack: its centre advances -rho per radian, and it falls
    down an incline as a rolling disc, a = g sin(b) / (1 + I / (m rho^2))."""
    rho, slope = 0.05, 0.3
    axis = np.array([math.cos(slope), -math.sin(slope)])  # downhill
    up = np.array([math.sin(slope), math.cos(slope)])
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G), name="wheel on a rack")
    wheel = b.add_body("wheel", mass=2.0, inertia=2.0 * rho * rho / 2, position=rho * up)
    # the rack's line lies below the centre: to the right of the downhill direction
    b.add(PointOnLine("track", b.ground, wheel, axis=axis, at=rho * up))
    b.add(RackPinion("teeth", b.ground, wheel, radius=rho, axis=axis))
    model = b.build()
    t = np.linspace(0.0, 1.0, 11)
    res = mb.forward_dynamics(model, t, method="DOP853", rtol=1e-11, atol=1e-12)
    along = (res.body("wheel").position - rho * up) @ axis
    np.testing.assert_allclose(along, 0.5 * G * math.sin(slope) / 1.5 * t ** 2, rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.body("wheel").angle, -along / rho, rtol=0, atol=1e-9)


def test_position_analysis_keeps_the_mesh_off_the_half_turn():
    """The mesh row also vanishes where the centre line points against where rolling puts
    it; a guess nearer that root than a quarter turn still assembles the right way."""
    model = gear_train()
    index = model.coordinate_index
    q = model.q0.copy()
    # the mesh row's angle is R2 / (R1 + R2) of the idler's turn: 5 rad put it at 1.9 rad,
    # nearer the half turn (pi) than the root
    q[index("g2.theta")] += 5.0
    solved = mb.solve_position(model, q, 0.0)
    turns = solved - model.q0
    assert abs(R1 * turns[index("g1.theta")] + R2 * turns[index("g2.theta")]) < 1e-12
    assert abs(R2 * turns[index("g2.theta")] + R3 * turns[index("g3.theta")]) < 1e-12


@pytest.mark.parametrize("change, words", [
    (dict(radius_j=0.031), ["'m12'", "0.08 m apart", "need 0.081"]),
    (dict(internal=True), ["'m12'", "ring", "radius_j must be larger"]),
    (dict(radius_i=-0.05), ["'m12'", "radius_i"]),
    (dict(pressure_angle=20.0), ["'m12'", "pressure_angle", "math.radians(20)"]),
])
def test_bad_gear_pairs_are_named(change, words):
    b = mb.ModelBuilder(dim=2, name="bad gears")
    g1 = b.add_body("g1", mass=1.0, inertia=1e-3, position=(0.0, 0.0))
    g2 = b.add_body("g2", mass=1.0, inertia=1e-3, position=(0.08, 0.0))
    b.add(Revolute("A", b.ground, g1, at=(0.0, 0.0)))
    b.add(Revolute("B", b.ground, g2, at=(0.08, 0.0)))
    b.add(GearPair("m12", g1, g2, **{"radius_i": 0.05, "radius_j": 0.03, **change}))
    with pytest.raises(mb.ModelError) as info:
        b.build()
    for word in words:
        assert word in str(info.value), str(info.value)


def test_racks_refuse_spatial_models_and_gears_a_centreless_ground():
    b = mb.ModelBuilder(dim=3, name="spatial rack")
    g1 = b.add_body("g1", mass=1.0, inertia=np.eye(3) * 1e-3, position=(0.0, 0.0, 0.0))
    b.add(RackPinion("m", b.ground, g1, radius=0.05, axis=(1.0, 0.0, 0.0)))
    with pytest.raises(mb.ModelError, match="'m'.*planar models only"):
        b.build()
    b = mb.ModelBuilder(dim=2, name="no centre")
    g1 = b.add_body("g1", mass=1.0, inertia=1e-3, position=(0.1, 0.0))
    b.add(GearPair("m", b.ground, g1, radius_i=0.05, radius_j=0.05))
    with pytest.raises(mb.ModelError, match="'m'.*center_i="):
        b.build()
