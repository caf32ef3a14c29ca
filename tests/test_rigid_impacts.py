"""Rigid contacts (``mb.RigidImpact``): every touch an impact by Newton's law of restitution on
the whole mechanism, the joints holding. Checked against closed forms derived here from
momentum, angular momentum and the restitution alone: a bouncing ball's impact times and
flight (and its coming to rest), a rod landing flat on two supports at once and on one end,
a pinned bar striking the floor, two balls of unequal mass head-on, a hinge's stop, Newton's
cradle of touching balls, and energy over many elastic bounces."""

from __future__ import annotations

import math

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.analyses.impacts import impulses
from mbd3d.errors import ModelError
from mbd3d.joints import Prismatic, Revolute, RotationDriver
from mbd3d.viewer import read_component, record

G, H0, RADIUS = 9.81, 1.0, 0.1
TIGHT = dict(method="DOP853", rtol=1e-11, atol=1e-12)


def falling_ball(dim: int, e: float, rest_speed: float = 1e-3, height: float = H0,
                 others: int = 0) -> mb.Model:
    """A ball whose lowest point is ``height`` above the floor (normal along y), at rest;
    ``others``: bodies added before it, falling beside it (its coordinates come after
    theirs)."""
    b = mb.ModelBuilder(dim=dim, gravity=(0.0, -G) + (0.0,) * (dim - 2))
    inertia = 0.004 if dim == 2 else 0.004 * np.eye(3)
    for k in range(others):
        b.add_body(f"other{k}", mass=1.0, inertia=inertia,
                   position=(1.0 + k, 2.0) + (0.0,) * (dim - 2))
    ball = b.add_body("ball", mass=2.0, inertia=inertia,
                      position=(0.0, height + RADIUS) + (0.0,) * (dim - 2))
    b.add(mb.Contact("floor", mb.Sphere(ball, RADIUS),
                     mb.Plane(b.ground, normal=(0.0, 1.0) + (0.0,) * (dim - 2)),
                     law=mb.RigidImpact(restitution=e, rest_speed=rest_speed)))
    return b.build()


def bounce_times(e: float, n: int) -> np.ndarray:
    """The first ``n`` impact times of a ball dropped from ``H0`` with restitution ``e``:
    the first after ``t1 = sqrt(2 H0 / g)``, each flight ``2 e^k g t1 / g`` long."""
    t1 = math.sqrt(2 * H0 / G)
    return t1 + np.concatenate([[0.0], np.cumsum([2 * e ** k * t1 for k in range(1, n)])])


def heights(t: np.ndarray, e: float, times: np.ndarray) -> np.ndarray:
    """The height of the ball's lowest point at ``t`` in flight, from the impact times: it
    falls from ``H0``, then leaves the k-th impact at ``e^k`` times the first impact's speed."""
    v1 = G * times[0]
    k = np.searchsorted(times, t)  # impacts before t
    since = np.where(k == 0, t, t - times[np.maximum(k - 1, 0)])
    up = np.where(k == 0, 0.0, e ** k * v1)
    return np.where(k == 0, H0, 0.0) + up * since - 0.5 * G * since ** 2


@pytest.mark.parametrize("dim", [2, 3])
def test_a_ball_bounces_at_the_closed_form_times_and_comes_to_rest_on_the_floor(dim):
    e, rest = 0.8, 0.05
    res = mb.forward_dynamics(falling_ball(dim, e, rest, others=2), np.linspace(0.0, 5.0, 1001),
                              **TIGHT)
    impacts = res.stats["impacts"]
    v1 = G * math.sqrt(2 * H0 / G)
    # it comes to rest at the first impact that leaves it slower than the rest speed
    count = math.ceil(math.log(rest / v1) / math.log(e))
    assert len(impacts) == count
    expected = bounce_times(e, count)
    np.testing.assert_allclose([i["time"] for i in impacts], expected, rtol=0, atol=1e-9)
    before = np.array([i["rate_before"] for i in impacts])
    np.testing.assert_allclose(before, -v1 * e ** np.arange(count), rtol=0, atol=1e-9 * v1)
    np.testing.assert_allclose([i["rate_after"] for i in impacts], -e * before, rtol=1e-12)
    # the impulse turns the ball's momentum, the energy lost is its kinetic energy's change
    np.testing.assert_allclose([i["impulse"] for i in impacts], -2.0 * (1 + e) * before,
                               rtol=1e-12)
    np.testing.assert_allclose([i["energy_lost"] for i in impacts],
                               0.5 * 2.0 * (1 - e * e) * before ** 2, rtol=1e-12)
    # the flight between impacts, at every output time
    y = res.body("ball").position[:, 1] - RADIUS
    flying = res.t < expected[-1]
    np.testing.assert_allclose(y[flying], heights(res.t[flying], e, expected), rtol=0,
                               atol=1e-9)
    # it rests from that impact on, the floor carrying its weight: the rest of the run
    rests = res.stats["rests"]
    assert [(r["event"], r["contacts"]) for r in rests] == [("rest", ["floor"])]
    assert rests[0]["time"] == impacts[-1]["time"] and res.status == "complete"
    # the bounce it no longer makes: its kinetic energy leaving the last impact
    np.testing.assert_allclose(rests[0]["energy_lost"],
                               0.5 * 2.0 * impacts[-1]["rate_after"] ** 2, rtol=1e-9)
    # ... which would have ended at the closed-form time to rest, sqrt(2 h0 / g)(1+e)/(1-e),
    # after its remaining flights, 2 v / g each, v falling by e at each
    t_rest = math.sqrt(2 * H0 / G) * (1 + e) / (1 - e)
    np.testing.assert_allclose(t_rest - rests[0]["time"],
                               2 * impacts[-1]["rate_after"] / (G * (1 - e)), rtol=0,
                               atol=1e-9)  # as the impacts' times
    after = res.t > rests[0]["time"]
    np.testing.assert_allclose(y[after], 0.0, rtol=0, atol=1e-10)
    np.testing.assert_allclose(res.body("ball").velocity[after], 0.0, rtol=0, atol=1e-10)
    np.testing.assert_allclose(res.contacts().normal_force[after, 0], 2.0 * G, rtol=1e-10)
    np.testing.assert_allclose(res.contacts().normal_force[~after, 0], 0.0, rtol=0, atol=0)
    # each impact is an event on the recording's time line, where the ball touched the floor
    np.testing.assert_allclose([i["point"] for i in impacts],
                               np.column_stack([np.zeros(count), np.zeros(count),
                                                np.zeros(count)]), atol=1e-9)


def test_impacts_are_recorded_on_the_time_line(tmp_path):
    res = mb.forward_dynamics(falling_ball(3, 0.5, 0.5), np.linspace(0.0, 2.0, 201), **TIGHT)
    impacts = res.stats["impacts"]
    path = tmp_path / "ball.rrd"
    record(res, path)
    times, text = read_component(path, "/impacts", "TextLog:text", timeline="sim_time")
    np.testing.assert_allclose(times.astype(np.int64) * 1e-9, [i["time"] for i in impacts],
                               atol=1e-9)
    assert all(str(row[0]).startswith("impact at floor: closing at") for row in text)
    times, points = read_component(path, "/world/impacts", "Points3D:positions",
                                   timeline="sim_time")
    assert len(times) == len(impacts) and np.allclose(points[:, 0], 0.0, atol=1e-6)


def test_generalized_alpha_bounces_the_ball_at_the_same_times():
    """The touches are located on its interpolant (exact on a free flight's parabola), the
    impacts are the same driver's: 1 ms steps give the closed-form times."""
    e = 0.8
    res = mb.forward_dynamics(falling_ball(3, e), np.linspace(0.0, 2.0, 201),
                              method="generalized-alpha", step=1e-3)
    times = [i["time"] for i in res.stats["impacts"]]
    expected = bounce_times(e, 10)
    np.testing.assert_allclose(times, expected[expected < 2.0], rtol=0, atol=1e-9)
    assert len(times) == 3 and res.status == "complete"


def test_an_elastic_ball_keeps_its_energy_over_many_bounces():
    t = np.linspace(0.0, 30.0, 3001)
    model = falling_ball(2, 1.0)
    res = mb.forward_dynamics(model, t, **TIGHT)
    total = res.kinetic_energy + res.potential_energy
    np.testing.assert_allclose(total, total[0], rtol=0, atol=1e-9 * abs(total[0]))
    impacts = res.stats["impacts"]
    period = 2 * math.sqrt(2 * H0 / G)
    assert len(impacts) == int((30.0 - period / 2) / period) + 1
    np.testing.assert_allclose([i["time"] for i in impacts],
                               period / 2 + period * np.arange(len(impacts)), rtol=0,
                               atol=1e-9)
    assert res.status == "complete" and sum(i["energy_lost"] for i in impacts) == 0.0


def rod(angle: float, pinned: bool = False, e: float = 0.5) -> tuple[mb.Model, float, float]:
    """A rod (length 2 a, planar) its centre 0.5 m up, tilted ``angle``, with a small circle at
    each end over the floor; ``pinned``: its left end on a pin instead. Returns the model and
    the rod's half length and moment of inertia about its centre."""
    a, m = 0.4, 3.0
    inertia = m * (2 * a) ** 2 / 12
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    centre = np.array([0.0, 0.5])
    axis = np.array([math.cos(angle), math.sin(angle)])
    body = b.add_body("rod", mass=m, inertia=inertia, position=centre, angle=angle)
    law = mb.RigidImpact(restitution=e)
    floor = mb.Plane(b.ground, point=(0.0, 0.0), normal=(0.0, 1.0))
    for label, side in (("left", -1.0), ("right", 1.0)):
        if pinned and side < 0:
            b.add(Revolute("pin", b.ground, body, at=centre + side * a * axis))
            continue
        b.add(mb.Contact(label, mb.Sphere(body, 1e-3, point=(side * a, 0.0)), floor,
                         law=law))
    return b.build(), a, inertia


def test_a_rod_landing_flat_on_both_ends_takes_half_the_impulse_on_each():
    e, m = 0.5, 3.0
    model, _, _ = rod(0.0, e=e)
    res = mb.forward_dynamics(model, np.linspace(0.0, 0.4, 41), **TIGHT)
    impacts = res.stats["impacts"]
    v = G * math.sqrt(2 * (0.5 - 1e-3) / G)  # the ends fall 0.499 m
    assert sorted(i["contact"] for i in impacts) == ["left", "right"]
    assert impacts[0]["time"] == impacts[1]["time"]
    # simultaneous: the two rows share the impulse m (1 + e) v equally, and the rod does not
    # turn (one at a time, the first end would start it turning)
    np.testing.assert_allclose([i["impulse"] for i in impacts], m * (1 + e) * v / 2,
                               rtol=1e-9)
    after = impacts[0]["time"] + 0.01
    k = np.searchsorted(res.t, after)
    np.testing.assert_allclose(res.body("rod").angular_velocity[k:], 0.0, atol=1e-9)
    np.testing.assert_allclose(res.body("rod").velocity[k, 1],
                               e * v - G * (res.t[k] - impacts[0]["time"]), rtol=1e-9)


def test_a_rod_landing_on_one_end_and_a_pinned_bar_striking_the_floor():
    """One end of a free rod: the impulse P on the end changes the centre's speed by P / m and
    the turn by P a cos(angle) / I; Newton's law on the end's speed gives P. Pinned at the other
    end, the pin's impulse takes part and the bar's rate simply turns over by -e."""
    e, m, angle = 0.5, 3.0, math.radians(30.0)
    model, a, inertia = rod(angle, e=e)
    res = mb.forward_dynamics(model, np.linspace(0.0, 0.3, 31), **TIGHT)
    first = res.stats["impacts"][0]
    assert first["contact"] == "left"
    v = -first["rate_before"]
    arm = a * math.cos(angle)  # the end's lever about the centre, across the normal
    impulse = (1 + e) * v / (1 / m + arm ** 2 / inertia)
    np.testing.assert_allclose(first["impulse"], impulse, rtol=1e-9)
    np.testing.assert_allclose(first["rate_after"], e * v, rtol=1e-9)
    # pinned at its left end: the bar turns about the pin until its right end's circle
    # (radius 1e-3) touches, at the angle phi below the horizontal
    model, a, inertia = rod(angle, pinned=True, e=e)
    res = mb.forward_dynamics(model, np.linspace(0.0, 0.5, 51), **TIGHT)
    first = res.stats["impacts"][0]
    assert first["contact"] == "right"
    pin_y = 0.5 - a * math.sin(angle)
    phi = math.asin((1e-3 - pin_y) / (2 * a))
    pin_inertia = inertia + m * a ** 2
    w = math.sqrt(2 * m * G * a * (math.sin(angle) - math.sin(phi)) / pin_inertia)
    tip = 2 * a * w * math.cos(phi)
    np.testing.assert_allclose(first["rate_before"], -tip, rtol=1e-9)
    np.testing.assert_allclose(first["rate_after"], e * tip, rtol=1e-9)
    # the pin holds: the floor's impulse is the angular impulse about the pin over the arm,
    # not the free rod's, and the bar's rate turns over by -e
    np.testing.assert_allclose(first["impulse"], pin_inertia * (1 + e) * w
                               / (2 * a * math.cos(phi)), rtol=1e-9)
    np.testing.assert_allclose(first["energy_lost"], 0.5 * pin_inertia * w ** 2 * (1 - e * e),
                               rtol=1e-9)


def two_balls(m1: float, m2: float, v1: float, v2: float, e: float, dim: int = 2):
    b = mb.ModelBuilder(dim=dim, gravity=(0.0,) * dim)
    pad = (0.0,) * (dim - 1)
    inertia = (lambda m: 0.4 * m * RADIUS ** 2 * (1.0 if dim == 2 else np.eye(3)))
    first = b.add_body("first", mass=m1, inertia=inertia(m1), position=(0.0,) + pad,
                       velocity=(v1,) + pad)
    second = b.add_body("second", mass=m2, inertia=inertia(m2), position=(0.5,) + pad,
                        velocity=(v2,) + pad)
    b.add(mb.Contact("touch", mb.Sphere(first, RADIUS), mb.Sphere(second, RADIUS),
                     law=mb.RigidImpact(restitution=e)))
    return b.build()


@pytest.mark.parametrize("dim", [2, 3])
def test_two_balls_head_on_leave_by_momentum_and_restitution(dim):
    m1, m2, v1, v2, e = 1.0, 3.0, 2.0, -0.5, 0.7
    res = mb.forward_dynamics(two_balls(m1, m2, v1, v2, e, dim), [0.0, 0.5], **TIGHT)
    # closing from 0.3 m apart at 2.5 m/s (the event fires 1e-10 of the model's length past
    # the touch)
    np.testing.assert_allclose(res.stats["impacts"][0]["time"], 0.3 / 2.5, rtol=0, atol=1e-10)
    p = m1 * v1 + m2 * v2
    after1 = (p - m2 * e * (v1 - v2)) / (m1 + m2)
    after2 = (p + m1 * e * (v1 - v2)) / (m1 + m2)
    np.testing.assert_allclose(res.body("first").velocity[-1][0], after1, rtol=1e-12)
    np.testing.assert_allclose(res.body("second").velocity[-1][0], after2, rtol=1e-12)
    reduced = m1 * m2 / (m1 + m2)
    np.testing.assert_allclose(res.stats["impacts"][0]["energy_lost"],
                               0.5 * reduced * (1 - e * e) * (v1 - v2) ** 2, rtol=1e-12)


def test_a_cradle_of_touching_balls_passes_the_strikers_momentum_to_the_last():
    """Five balls on strings, touching in a row, the first released from 20 degrees: the
    impacts at the bottom pass ball to ball within one instant, and the last ball alone
    swings out to the height the first fell from."""
    n, length, mass = 5, 0.3, 0.1
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    law = mb.RigidImpact(restitution=1.0)
    balls, release = [], math.radians(20.0)
    for k in range(n):
        pivot = np.array([2 * RADIUS * k, length])
        angle = -release if k == 0 else 0.0
        centre = pivot + length * np.array([math.sin(angle), -math.cos(angle)])
        ball = b.add_body(f"ball{k}", mass=mass, inertia=0.4 * mass * RADIUS ** 2,
                          position=centre, angle=angle)
        b.add(Revolute(f"string{k}", b.ground, ball, at=pivot))
        if balls:
            b.add(mb.Contact(f"touch{k}", mb.Sphere(balls[-1], RADIUS),
                             mb.Sphere(ball, RADIUS), law=law))
        balls.append(ball)
    model = b.build()
    res = mb.forward_dynamics(model, np.linspace(0.0, 0.6, 601), **TIGHT)
    impacts = res.stats["impacts"]
    assert [i["contact"] for i in impacts[:n - 1]] == [f"touch{k}" for k in range(1, n)]
    assert len({i["time"] for i in impacts[:n - 1]}) == 1
    # the striker's rate at the bottom, a ball turning about its string's pin
    pin_inertia = mass * length ** 2 + 0.4 * mass * RADIUS ** 2
    rate = math.sqrt(2 * mass * G * length * (1 - math.cos(release)) / pin_inertia)
    after = res.t > impacts[0]["time"]
    k = np.flatnonzero(after)[0]
    swings = np.array([res.body(f"ball{j}").angular_velocity[k] for j in range(n)])
    # each ball's turn rate at the first output after the impact (gravity acts for < 1 ms)
    np.testing.assert_allclose(swings[:-1], 0.0, atol=1e-9)
    # the last ball leaves at the striker's rate, slowed by gravity over < 1 ms since
    np.testing.assert_allclose(swings[-1], rate, rtol=1e-4)
    # from then on the last ball swings with the energy the striker fell with
    last = res.body(f"ball{n - 1}")
    swing = (0.5 * pin_inertia * last.angular_velocity ** 2
             + mass * G * length * (1 - np.cos(last.angle)))
    fell = mass * G * length * (1 - math.cos(release))
    np.testing.assert_allclose(swing[after], fell, rtol=1e-9)
    total = res.kinetic_energy + res.potential_energy
    np.testing.assert_allclose(total, total[0], rtol=0, atol=1e-9 * mass * G * length)


def test_a_hinge_stop_turns_the_pendulum_back_at_its_restitution():
    e, length, mass = 0.6, 0.5, 1.0
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    bar = b.add_body("bar", mass=mass, inertia=mass * length ** 2 / 12,
                     position=(length / 2, 0.0))
    pin = b.add(Revolute("pin", b.ground, bar, at=(0.0, 0.0)))
    b.add(mb.JointLimit("stop", pin, lower=-math.pi / 2,
                        law=mb.RigidImpact(restitution=e)))
    res = mb.forward_dynamics(b.build(), np.linspace(0.0, 1.0, 101), **TIGHT)
    first = res.stats["impacts"][0]
    # the bar falls from horizontal to hanging: I_pin w^2 / 2 = m g L / 2
    w = math.sqrt(mass * G * length / (mass * length ** 2 / 3))
    np.testing.assert_allclose(first["rate_before"], -w, rtol=1e-9)
    np.testing.assert_allclose(first["rate_after"], e * w, rtol=1e-9)
    # the angular impulse I_pin (1 + e) w, and the bar then rises to e^2 of its fall
    np.testing.assert_allclose(first["impulse"], mass * length ** 2 / 3 * (1 + e) * w,
                               rtol=1e-9)
    angle = res.joint("pin").angle
    later = res.t > first["time"]
    rise = np.max(angle[later] + math.pi / 2)
    np.testing.assert_allclose(1 - math.cos(rise), e * e, rtol=1e-3)


def test_a_slide_stop_with_generalized_alpha():
    """A block on a slide hits its rigid end at 1 m/s and leaves at e times that; the
    implicit method takes the impact at the located touch as the explicit one does."""
    e = 0.5
    b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0))
    block = b.add_body("block", mass=2.0, inertia=0.01, position=(0.0, 0.0),
                       velocity=(1.0, 0.0))
    slide = b.add(Prismatic("slide", b.ground, block, at=(0.0, 0.0), axis=(1.0, 0.0)))
    b.add(mb.JointLimit("end", slide, upper=0.25, law=mb.RigidImpact(restitution=e)))
    res = mb.forward_dynamics(b.build(), np.linspace(0.0, 1.0, 11), method="generalized-alpha",
                              step=1e-3)
    first = res.stats["impacts"][0]
    np.testing.assert_allclose(first["time"], 0.25, rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.body("block").velocity[-1], [-e, 0.0], atol=1e-9)
    np.testing.assert_allclose(res.body("block").position[-1, 0], 0.25 - e * 0.75, atol=1e-9)


def test_the_impulses_solve_newtons_law_on_every_row():
    """The active set against the closed form of rows that all push (``W lam = -b``), and on
    random problems (up to twelve rows, many with dependent rows, as four corners of a face)
    against the minimum found by trying every set of pushing rows."""
    rng = np.random.default_rng(3)
    A = rng.normal(size=(4, 6))
    W = A @ A.T
    lam = impulses(W, -W @ np.array([1.0, 2.0, 0.5, 3.0]))
    np.testing.assert_allclose(lam, [1.0, 2.0, 0.5, 3.0], rtol=1e-10)
    stepped_back = 0
    for trial in range(300):
        a = int(rng.integers(2, 13))
        A = rng.normal(size=(a, int(rng.integers(max(2, a - 3), a + 3))))
        # closing rates b = G qd (in the range of W = G S G^T, here A A^T), some raised (a
        # restitution above another's)
        W = A @ A.T
        b = A @ rng.normal(size=A.shape[1]) + np.where(rng.random(a) < 0.3,
                                                       np.abs(rng.normal(size=a)), 0.0)
        lam = impulses(W, b)
        w = W @ lam + b
        scale = np.max(np.abs(b)) * max(1.0, np.max(np.abs(lam)))
        assert np.all(lam >= 0.0) and np.all(w >= -1e-9 * scale), trial
        assert abs(lam @ w) < 1e-9 * scale * max(1.0, np.max(np.abs(lam))), trial
        if a <= 8:
            best = min(_objective(W, b, x) for x in _supported(W, b))
            assert _objective(W, b, lam) == pytest.approx(best, rel=1e-9, abs=1e-12), trial
        # whether the greedy choice had to be undone: a row freed first ends without impulse
        first = int(np.argmin(b))
        stepped_back += bool(b[first] < 0 and lam[first] == 0.0)
    assert stepped_back > 5  # the step back is exercised


def _objective(W, b, x) -> float:
    return float(0.5 * x @ W @ x + b @ x)


def _supported(W, b) -> list:
    """The nonnegative minimizers on every support (the least-squares one where the rows of
    a support depend on each other)."""
    a, out = len(b), []
    for mask in range(2 ** a):
        free = np.array([(mask >> i) & 1 for i in range(a)], dtype=bool)
        x = np.zeros(a)
        if free.any():
            x[free] = np.linalg.lstsq(W[np.ix_(free, free)], -b[free], rcond=None)[0]
        if np.all(x >= -1e-12):
            out.append(np.maximum(x, 0.0))
    return out


def test_rigid_contacts_refuse_bad_input():
    with pytest.raises(ModelError, match="restitution must lie in"):
        falling_ball(2, 1.5)
    with pytest.raises(ModelError, match="rest_speed must be > 0"):
        falling_ball(2, 0.5, rest_speed=0.0)
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    ball = b.add_body("ball", mass=1.0, inertia=0.004, position=(0.0, 0.05))
    b.add(mb.Contact("floor", mb.Sphere(ball, RADIUS), mb.Plane(b.ground, normal=(0, 1)),
                     law=mb.RigidImpact(restitution=0.5)))
    with pytest.warns(mb.ContactWarning, match="rigid contact"):
        model = b.build()
    with pytest.raises(ModelError, match=r"'floor' starts 0.05 m inside"):
        mb.forward_dynamics(model, [0.0, 1.0])


def test_a_rigid_contact_in_a_model_file(tmp_path):
    """Written and read back, the law keeps its restitution and rest speed: the same
    bounces."""
    model = falling_ball(3, 0.6, rest_speed=0.2)
    path = tmp_path / "ball.yaml"
    mb.save(model, path)
    assert "RigidImpact" in path.read_text()
    t = np.linspace(0.0, 3.0, 301)
    ran = [mb.forward_dynamics(m, t, **TIGHT) for m in (model, mb.load(path))]
    times = [[i["time"] for i in res.stats["impacts"]] for res in ran]
    assert times[0] == times[1] and len(times[0]) == math.ceil(
        math.log(0.2 / math.sqrt(2 * G * H0)) / math.log(0.6))


@pytest.mark.parametrize("overlap", [1e-13, 1e-10])
def test_a_rigid_contact_may_start_touching_to_rounding_but_not_inside(overlap):
    """On a bead of a millimetre (the model's length scale 0.6 mm) touching is within 1e-9 of
    that length: 1e-13 m is touching, 1e-10 m inside."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    bead = b.add_body("bead", mass=1e-6, inertia=4e-13, position=(0.0, 1e-3 - overlap),
                      velocity=(0.0, 0.1))
    b.add(mb.Contact("floor", mb.Sphere(bead, 1e-3), mb.Plane(b.ground, normal=(0, 1)),
                     law=mb.RigidImpact(restitution=0.5)))
    if overlap < 1e-12:
        res = mb.forward_dynamics(b.build(), [0.0, 0.01], **TIGHT)
        assert res.status == "complete" and not res.stats["impacts"]
        return
    with pytest.warns(mb.ContactWarning, match="overlap by 1e-10 m"):
        model = b.build()
    with pytest.raises(ModelError, match=r"'floor' starts 1e-10 m inside"):
        mb.forward_dynamics(model, [0.0, 0.01])


def test_a_bead_flung_along_a_spinning_rod_strikes_its_end_and_rests_there():
    """A bead slides freely along a rod turned at a constant rate w (no gravity): along the
    rod s'' = w^2 s, so s = s0 cosh(w t) + (v0 / w) sinh(w t) until it strikes the rod's end
    (e = 0). There it stays, pressed out by the turning alone (the gap's rate is zero, its
    acceleration w^2 s from how the rod's direction turns): the stop holds it there."""
    w, s0, v0, end = 3.0, 0.1, 0.2, 0.3
    b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0))
    rod_ = b.add_body("rod", mass=5.0, inertia=1.0, position=(0.0, 0.0))  # centred on the pin
    pin = b.add(Revolute("pin", b.ground, rod_, at=(0.0, 0.0)))
    b.add(RotationDriver("spin", pin, motion=mb.Ramp(0.0, w)))
    bead = b.add_body("bead", mass=0.1, inertia=1e-5, position=(s0, 0.0),
                      velocity=(v0, s0 * w), angular_velocity=w)
    slide = b.add(Prismatic("slide", rod_, bead, at=(s0, 0.0), axis=(1.0, 0.0)))
    b.add(mb.JointLimit("end", slide, upper=end - s0, law=mb.RigidImpact(restitution=0.0)))
    res = mb.forward_dynamics(b.build(), np.linspace(0.0, 1.0, 101), **TIGHT)
    impacts = res.stats["impacts"]
    # s = R cosh(w t + phi), R = sqrt(s0^2 - (v0/w)^2), tanh(phi) = v0 / (w s0)
    R, phi = math.sqrt(s0 ** 2 - (v0 / w) ** 2), math.atanh(v0 / (w * s0))
    strike = (math.acosh(end / R) - phi) / w
    assert len(impacts) == 1
    np.testing.assert_allclose(impacts[0]["time"], strike, rtol=0, atol=1e-9)
    np.testing.assert_allclose(-impacts[0]["rate_before"], w * R * math.sinh(w * strike + phi),
                               rtol=1e-8)
    # at the strike itself: the turning presses the bead out at once (no second touch
    # needed); the stop holds it there, pushing it round with the rod: m w^2 s
    rests = res.stats["rests"]
    assert len(rests) == 1 and rests[0]["contacts"] == ["end"] and res.status == "complete"
    np.testing.assert_allclose(rests[0]["time"], strike, rtol=0, atol=1e-9)
    after = res.t > strike
    np.testing.assert_allclose(res.contacts().normal_force[after, 0], 0.1 * w * w * end,
                               rtol=1e-9)
    # held like a joint: to the outputs' projection, 1e-3 constraint_tol of the model's size
    np.testing.assert_allclose(res.contacts().gap[after, 0], 0.0, rtol=0,
                               atol=1e-11 * res.model.length_scale)
