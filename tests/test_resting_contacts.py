"""Rigid contacts at rest (:mod:`mbd3d.analyses.resting`): a rigid contact that comes to rest is
held closed by the force it needs, through the joints, until that force would pull; then it lets
go. Checked against closed forms derived here from Newton's second law alone: a ball on a table
shaken up and down (the table's push, where it lets go and where it lands again), a ball
resting under a ball dropped on it, a box settling flat on its four corners, a rod resting on
its hinge's stop (generalized-alpha holding them as the explicit methods do); and a ball on a
carriage sliding on a rail with friction, whose force (resting) and impulses (bouncing) the
rail's friction takes, by Coulomb's law alone."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

import mbd3d as mb
from mbd3d.joints import Prismatic, Revolute, TranslationDriver

G = 9.81
TIGHT = dict(method="DOP853", rtol=1e-11, atol=1e-12)
GA = dict(method="generalized-alpha", step=5e-4)
#: the shaken table: amplitude [m], frequency [rad/s], masses [kg], ball radius [m]
A, W, M_TABLE, M_BALL, R = 0.01, 40.0, 3.0, 0.5, 0.05


def shaken_table(e: float) -> mb.Model:
    """A ball resting on a table that a driver moves as y = A (1 - cos W t) (A W^2 > g)."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G), name="shaken table")
    table = b.add_body("table", mass=M_TABLE, inertia=0.1, position=(0.0, 0.0))
    slide = b.add(Prismatic("slide", b.ground, table, axis=(0.0, 1.0), at=(0.0, 0.0)))
    b.add(TranslationDriver("shake", slide, motion=mb.Harmonic(A, W, -math.pi / 2, A)))
    ball = b.add_body("ball", mass=M_BALL, inertia=2e-4, position=(0.0, R))
    b.add(mb.Contact("top", mb.Sphere(ball, R), mb.Plane(table, normal=(0.0, 1.0)),
                     law=mb.RigidImpact(restitution=e)))
    return b.build()


def table(t):
    """The table's height, speed and acceleration at ``t``."""
    return (A * (1 - np.cos(W * t)), A * W * np.sin(W * t), A * W * W * np.cos(W * t))


@pytest.mark.parametrize("method", [TIGHT, GA], ids=["DOP853", "generalized-alpha"])
def test_a_ball_on_a_shaken_table_is_pushed_then_lets_go_and_lands_where_newton_says(method):
    """Held from the start, the ball moves with the table, pushed by N = m (g + y''), until
    the table falls faster than gravity: cos(W t) = -g / (A W^2), where N reaches zero. Then it
    flies freely until the table meets it again, at the closed-form speed difference.
    Generalized-alpha holds it as the explicit methods do (the held row's force taken at each
    Newton iterate's state, its drift projected away), to the same figures: the force and
    release depend on the driven table alone, and the method is exact on the free flight's
    parabola."""
    e = 0.5
    t = np.linspace(0.0, 0.16, 321)
    res = mb.forward_dynamics(shaken_table(e), t, **method)
    assert res.status == "complete"
    rests, impacts = res.stats["rests"], res.stats["impacts"]
    assert rests[0] == {"time": 0.0, "event": "rest", "contacts": ["top"], "energy_lost": 0.0}
    release = math.acos(-G / (A * W * W)) / W
    assert rests[1]["event"] == "release"
    np.testing.assert_allclose(rests[1]["time"], release, rtol=0, atol=1e-9)
    # pushed up to there: the table's force on the ball, and the driver's on the table and ball
    pushed = res.t < release
    y, v, a = table(res.t[pushed])
    np.testing.assert_allclose(res.contacts().normal_force[pushed, 0], M_BALL * (G + a),
                               rtol=1e-9, atol=1e-9 * M_BALL * G)
    np.testing.assert_allclose(res.body("ball").position[pushed, 1], y + R, rtol=0,
                               atol=1e-11)
    effort = res.efforts["shake"][pushed]
    np.testing.assert_allclose(np.abs(effort), (M_TABLE + M_BALL) * (G + a), rtol=1e-9)
    # free flight from there to the first impact
    y0, v0, _ = table(release)

    def gap(tt):
        s = tt - release
        return y0 + v0 * s - 0.5 * G * s * s - table(tt)[0]
    grid = np.linspace(release + 1e-4, 0.16, 2000)
    k = np.flatnonzero(np.diff(np.sign(gap(grid))))[0]
    land = brentq(gap, grid[k], grid[k + 1], xtol=1e-15)
    np.testing.assert_allclose(impacts[0]["time"], land, rtol=0, atol=1e-9)
    closing = (v0 - G * (land - release)) - table(land)[1]
    np.testing.assert_allclose(impacts[0]["rate_before"], closing, rtol=1e-7)
    np.testing.assert_allclose(impacts[0]["rate_after"], -e * closing, rtol=1e-7)
    flying = (res.t > release) & (res.t < land)
    assert np.all(res.contacts().normal_force[flying, 0] == 0.0)


def test_a_ball_dropped_on_a_resting_ball_bounces_off_it_as_off_the_floor():
    """A ball resting on the floor (e = 0 there) is struck from above (e between the balls):
    the floor takes the impulse through it, so the lower ball stays and the upper one leaves
    at -e times its closing speed, as from the floor itself. Until the strike, the floor
    carries the lower ball's weight; after the upper one has come to rest, both weights."""
    e = 0.6
    b = mb.ModelBuilder(dim=3, gravity=(0.0, -G, 0.0))
    lower = b.add_body("lower", mass=2.0, inertia=0.01 * np.eye(3), position=(0.0, R, 0.0))
    upper = b.add_body("upper", mass=0.5, inertia=0.002 * np.eye(3),
                       position=(0.0, 3 * R + 0.2, 0.0))
    b.add(mb.Contact("floor", mb.Sphere(lower, R), mb.Plane(b.ground, normal=(0.0, 1.0, 0.0)),
                     law=mb.RigidImpact(restitution=0.0)))
    b.add(mb.Contact("balls", mb.Sphere(upper, R), mb.Sphere(lower, R),
                     law=mb.RigidImpact(restitution=e, rest_speed=0.05)))
    res = mb.forward_dynamics(b.build(), np.linspace(0.0, 2.0, 401), **TIGHT)
    assert res.status == "complete"
    strike = math.sqrt(2 * 0.2 / G)
    struck = [i for i in res.stats["impacts"] if i["contact"] == "balls"]
    taken = [i for i in res.stats["impacts"] if i["contact"] == "floor"]
    first = struck[0]
    # the floor takes the same impulse at the same instant, its ball not moving
    assert [i["time"] for i in taken] == [i["time"] for i in struck]
    np.testing.assert_allclose([i["impulse"] for i in taken], [i["impulse"] for i in struck],
                               rtol=1e-12)
    np.testing.assert_allclose(first["time"], strike, rtol=0, atol=1e-9)
    np.testing.assert_allclose(first["rate_after"], -e * first["rate_before"], rtol=1e-9)
    np.testing.assert_allclose(-first["rate_before"], G * strike, rtol=1e-9)
    np.testing.assert_allclose(res.body("lower").position[:, 1], R, rtol=0, atol=1e-11)
    force = res.contacts().normal_force
    names = res.contacts().names
    floor, balls = names.index("floor"), names.index("balls")
    before = res.t < strike
    np.testing.assert_allclose(force[before, floor], 2.0 * G, rtol=1e-9)
    settled = res.stats["rests"][-1]
    assert settled["event"] == "rest" and settled["contacts"] == ["balls"]
    after = res.t > settled["time"]
    np.testing.assert_allclose(force[after, floor], 2.5 * G, rtol=1e-9)
    np.testing.assert_allclose(force[after, balls], 0.5 * G, rtol=1e-9)
    # the upper ball's bounces: each flight 2 v / g, v falling by e at each
    times = [i["time"] for i in struck]
    speeds = G * strike * e ** np.arange(1, len(times))
    np.testing.assert_allclose(np.diff(times), 2 * speeds / G, rtol=0, atol=2e-9)


def carriage_under_a_ball(dim: int, mu: float, drop: float = 0.0, restitution: float = 0.0,
                          speed: float = 1.0) -> mb.Model:
    """A carriage (2 kg) sliding at ``speed`` along a level rail with Coulomb friction ``mu``,
    a 1 kg ball (frictionless) resting on its top or dropped from ``drop`` above it."""
    b = mb.ModelBuilder(dim=dim, gravity=(0.0, -G) + (0.0,) * (dim - 2), name="carriage")
    zero = (0.0,) * (dim - 2)
    inertia = 0.1 if dim == 2 else 0.1 * np.eye(3)
    carriage = b.add_body("carriage", mass=2.0, inertia=inertia, position=(0.0, 0.0) + zero,
                          velocity=(speed, 0.0) + zero)
    rail = b.add(Prismatic("rail", b.ground, carriage, axis=(1.0, 0.0) + zero,
                           at=(0.0, 0.0) + zero))
    b.add(mb.JointFriction("friction", rail, mu))
    ball = b.add_body("ball", mass=1.0, inertia=0.004 if dim == 2 else 0.004 * np.eye(3),
                      position=(0.3, R + drop) + zero)
    b.add(mb.Contact("top", mb.Sphere(ball, R), mb.Plane(carriage, normal=(0.0, 1.0) + zero),
                     law=mb.RigidImpact(restitution=restitution, rest_speed=0.05)))
    return b.build()


@pytest.mark.parametrize("method", [TIGHT, GA], ids=["DOP853", "generalized-alpha"])
@pytest.mark.parametrize("dim", [2, 3])
def test_a_ball_resting_on_a_sliding_carriage_loads_its_rail_friction(method, dim):
    """The ball, held on the carriage from the start, presses the carriage onto its rail with
    its weight: the rail's friction is mu (M + m) g, so the carriage slows at
    mu (M + m) g / M (not mu g, what the carriage alone would), while the frictionless ball
    stays where it is, carried by its weight m g. The joint's friction and the held
    contact's force are solved together (either changes the other's reaction)."""
    mu, M, m = 0.3, 2.0, 1.0
    t = np.linspace(0.0, 0.2, 41)  # it stops at 1 / a = 0.227 s
    res = mb.forward_dynamics(carriage_under_a_ball(dim, mu), t, **method)
    assert res.status == "complete"
    assert res.stats["rests"] == [{"time": 0.0, "event": "rest", "contacts": ["top"],
                                   "energy_lost": 0.0}]
    a = mu * (M + m) * G / M
    np.testing.assert_allclose(res.body("carriage").position[:, 0], t - a * t * t / 2,
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.contacts().normal_force[:, 0], m * G, rtol=1e-9)
    np.testing.assert_allclose(res.body("ball").position[:, :2] - [0.3, R], 0.0, rtol=0,
                               atol=1e-9)
    np.testing.assert_allclose(res.friction("friction"), -mu * (M + m) * G, rtol=1e-9)


@pytest.mark.parametrize("method", [TIGHT, GA], ids=["DOP853", "generalized-alpha"])
def test_a_ball_dropped_on_a_sliding_carriage_bounces_to_rest_and_loads_its_friction(method):
    """Dropped onto the sliding carriage, the ball bounces to rest on it (its flights and
    impacts as on a floor: the impulses are normal to the rail). The rail carries each
    impulse P and, sliding, its friction takes mu P from the carriage's momentum at once (as
    a stiff contact's force would over its short duration), and mu m v for the last bounce,
    of speed v, that coming to rest takes away; from the rest on the ball's weight loads the
    friction too: the carriage slows at mu g until then, at mu (M + m) g / M after."""
    mu, M, m, e, drop = 0.1, 2.0, 1.0, 0.5, 0.05
    t = np.linspace(0.0, 0.5, 101)
    res = mb.forward_dynamics(carriage_under_a_ball(2, mu, drop, e), t, **method)
    assert res.status == "complete"
    # the ball's impacts: falling from drop, rebounding at e times its speed until below
    # its rest speed (0.05 m/s: the fifth impact)
    speeds = math.sqrt(2 * G * drop) * e ** np.arange(5)
    times = math.sqrt(2 * drop / G) + np.concatenate([[0.0], np.cumsum(2 * e * speeds[:-1] / G)])
    impacts = res.stats["impacts"]
    np.testing.assert_allclose([i["time"] for i in impacts], times, rtol=0, atol=1e-9)
    np.testing.assert_allclose([i["impulse"] for i in impacts], m * (1 + e) * speeds,
                               rtol=1e-9)
    rest = res.stats["rests"][-1]
    assert rest["event"] == "rest" and rest["contacts"] == ["top"]
    np.testing.assert_allclose(rest["time"], times[-1], rtol=0, atol=1e-9)
    # the carriage's speed drops by mu P / M at each impact, by mu m e v / M at the rest
    drops = mu * m * (1 + e) * speeds / M
    drops[-1] += mu * m * e * speeds[-1] / M
    held = np.maximum(t - rest["time"], 0.0)
    x = t - mu * G * t ** 2 / 2 - mu * m * G / M * held ** 2 / 2
    x -= np.sum(drops * np.maximum(t[:, None] - times, 0.0), axis=1)
    np.testing.assert_allclose(res.body("carriage").position[:, 0], x, rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.friction("friction")[t > rest["time"]],
                               -mu * (M + m) * G, rtol=1e-9)


def test_a_strike_whose_rail_friction_outweighs_the_carriages_momentum_stops_it():
    """A carriage slowing on its rail is struck from above: the friction mu P that the
    strike's impulse P allows exceeds what stops it (M v), so the rail sticks (its friction
    impulse M v, within the cone) and the carriage stays where it was struck, the ball
    bouncing on it as on a floor."""
    mu, M, e, drop, v0 = 0.3, 2.0, 0.5, 0.05, 0.4
    t = np.linspace(0.0, 0.3, 61)
    res = mb.forward_dynamics(carriage_under_a_ball(2, mu, drop, e, v0), t, **TIGHT)
    assert res.status == "complete"
    strike = res.stats["impacts"][0]["time"]
    v = v0 - mu * G * strike  # sliding until then against mu M g
    assert 0.0 < M * v < mu * res.stats["impacts"][0]["impulse"]
    x = v0 * strike - mu * G * strike ** 2 / 2
    struck = res.t >= strike
    np.testing.assert_allclose(res.body("carriage").position[struck, 0], x, rtol=0,
                               atol=1e-9)
    np.testing.assert_allclose(res.body("carriage").velocity[struck, 0], 0.0, rtol=0,
                               atol=1e-9)


@pytest.mark.parametrize("method", [
    dict(method="DOP853", rtol=1e-10, atol=1e-12),
    pytest.param(dict(method="generalized-alpha", step=1e-3), marks=pytest.mark.compiled_only)],
    ids=["DOP853", "generalized-alpha"])
def test_a_tumbling_box_settles_flat_its_weight_shared_by_the_four_corners(method):
    """A box dropped tilted rocks from corner to corner until it lies flat. Its four lower
    corners then depend on each other (a rigid body leaves their shares open): the least-norm
    share, a quarter of the weight each, holds all four, and it rests at half its height
    (generalized-alpha too: its rows held through chart resets)."""
    from scipy.spatial.transform import Rotation

    size, m = np.array([0.4, 0.2, 0.3]), 3.0
    inertia = m / 12 * np.diag([size[1] ** 2 + size[2] ** 2, size[0] ** 2 + size[2] ** 2,
                                size[0] ** 2 + size[1] ** 2])
    b = mb.ModelBuilder(dim=3, gravity=(0.0, -G, 0.0))
    box = b.add_body("box", mass=m, inertia=inertia, position=(0.0, 0.35, 0.0),
                     orientation=Rotation.from_euler("xz", [0.15, 0.25]).as_matrix())
    b.add(mb.Contact("floor", mb.Box(box, size), mb.Plane(b.ground, normal=(0.0, 1.0, 0.0)),
                     law=mb.RigidImpact(restitution=0.3, rest_speed=0.05)))
    res = mb.forward_dynamics(b.build(), np.linspace(0.0, 0.8, 81), **method)
    assert res.status == "complete"
    contacts = res.contacts()
    # "floor[corner x y z]" by the signs of the corner's coordinates: y = -size / 2 below
    lower = [k for k, name in enumerate(contacts.names) if name[-3] == "-"]
    assert len(lower) == 4
    np.testing.assert_allclose(contacts.normal_force[-1, lower], m * G / 4, rtol=1e-9)
    assert np.all(np.delete(contacts.normal_force[-1], lower) == 0.0)
    np.testing.assert_allclose(res.body("box").position[-1], [0.0, size[1] / 2, 0.0],
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.body("box").velocity[-1], 0.0, rtol=0, atol=1e-10)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_rod_falls_onto_its_hinge_stop_and_rests_there_held_by_gravitys_moment(dim):
    """Pinned at one end and released level, the rod swings down onto a stop at -60 degrees
    and bounces to rest on it. Resting, the stop takes gravity's moment about the pin,
    m g (L/2) cos 60, and the pin the whole weight (the multipliers with the stop's force),
    planar and spatial alike."""
    L, m = 0.8, 2.0
    b = mb.ModelBuilder(dim=dim, gravity=(0.0, -G) + (0.0,) * (dim - 2))
    inertia = m * L * L / 12 if dim == 2 else np.diag([1e-3, m * L * L / 12, m * L * L / 12])
    rod = b.add_body("rod", mass=m, inertia=inertia, position=(L / 2, 0.0) + (0.0,) * (dim - 2))
    pin = b.add(Revolute("pin", b.ground, rod, at=(0.0,) * dim,
                         **({} if dim == 2 else {"axis": (0.0, 0.0, 1.0)})))
    b.add(mb.JointLimit("stop", pin, lower=-math.radians(60.0),
                        law=mb.RigidImpact(restitution=0.5, rest_speed=0.05)))
    res = mb.forward_dynamics(b.build(), np.linspace(0.0, 3.0, 301), **TIGHT)
    assert res.status == "complete" and res.stats["rests"][-1]["contacts"] == ["stop"]
    after = res.t > res.stats["rests"][-1]["time"]
    np.testing.assert_allclose(res.contacts().normal_force[after, 0],
                               m * G * L / 2 * math.cos(math.radians(60.0)), rtol=1e-9)
    force = res.joint("pin").reaction().force[after]
    np.testing.assert_allclose(force[:, 1], m * G, rtol=1e-9)
    np.testing.assert_allclose(np.delete(force, 1, axis=1), 0.0, rtol=0, atol=1e-9 * m * G)


def test_rests_and_releases_are_recorded_on_the_time_line(tmp_path):
    from mbd3d.viewer import read_component, record

    res = mb.forward_dynamics(shaken_table(0.5), np.linspace(0.0, 0.2, 41), **TIGHT)
    path = tmp_path / "table.rrd"
    record(res, path)
    times, text = read_component(path, "/impacts/rests", "TextLog:text", timeline="sim_time")
    rests = res.stats["rests"]
    np.testing.assert_allclose(times.astype(np.int64) * 1e-9, [r["time"] for r in rests],
                               atol=1e-9)
    assert [str(row[0]).split(" ")[1] for row in text] == [
        {"rest": "comes", "release": "lets"}[r["event"]] for r in rests]
    assert str(text[0][0]) == "top comes to rest (its bounces took 0 J)"
