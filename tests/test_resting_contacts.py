"""Rigid contacts at rest (:mod:`mbd3d.analyses.resting`): a rigid contact that comes to rest is
held closed by the force it needs, through the joints, until that force would pull; then it lets
go. Checked against closed forms derived here from Newton's second law alone: a ball on a table
shaken up and down (the table's push, where it lets go and where it lands again), a ball
resting under a ball dropped on it, a box settling flat on its four corners, a rod resting on
its hinge's stop (generalized-alpha holding them as the explicit methods do); and the stop
of joint friction, which does not see a held contact's force."""

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


def test_a_block_sliding_onto_a_rigid_stop_with_joint_friction_stops_the_run_there():
    """Joint friction would not see a held contact's force: the run ends where the block comes
    to rest against the stop, naming why, with the results up to there."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G), name="incline")
    down = np.array([math.cos(0.5), -math.sin(0.5)])
    block = b.add_body("block", mass=2.0, inertia=0.1, position=(0.0, 0.0), angle=-0.5,
                       velocity=0.5 * down)
    slide = b.add(Prismatic("slide", b.ground, block, axis=down))
    b.add(mb.JointFriction("friction", slide, 0.2))
    b.add(mb.JointLimit("stop", slide, upper=0.1, law=mb.RigidImpact(restitution=0.0)))
    res = mb.forward_dynamics(b.build(), np.linspace(0.0, 1.0, 101), **TIGHT)
    assert res.status == "stopped" and "'stop' came to rest" in res.message
    assert "not held with joint friction" in res.message
    # it slid 0.1 m from 0.5 m/s at g (sin a - mu cos a)
    a = G * (math.sin(0.5) - 0.2 * math.cos(0.5))
    slid = (math.sqrt(0.25 + 2 * a * 0.1) - 0.5) / a
    np.testing.assert_allclose(res.stats["impacts"][0]["time"], slid, rtol=1e-6)


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
