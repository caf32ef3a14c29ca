"""Events of forward dynamics: zero crossings located on the dense output, and the run stopped
or restarted there, checked against closed forms (a pendulum's quarter period from the complete
elliptic integral, the impact times of a ball bouncing with restitution)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import ellipk

import mbd3d as mb
from mbd3d.mechanisms import pendulum_chain

G = 9.81
METHODS = [("DOP853", {"rtol": 1e-11, "atol": 1e-12}),
           ("generalized-alpha", {"step": 2e-4})]
#: event-time accuracy each method is held to: DOP853's tolerance; generalized-alpha's
#: second-order phase error at its step, which grows with time (measured 6.6e-8 s at the
#: first crossing and 2.0e-7 s at the second at step 2e-4 s, a quarter of that at 1e-4 s)
TIME_TOL = {"DOP853": 1e-9, "generalized-alpha": 5e-7}


def quarter_period(length: float) -> float:
    """Time from rest at the horizontal to the bottom of a uniform rod pivoted at one end:
    I_O phi'' = -m g c sin(phi), amplitude pi/2, T/4 = sqrt(I_O / (m g c)) K(sin^2(pi/4))."""
    inertia_o, c = length**2 / 3, length / 2  # per unit mass
    return math.sqrt(inertia_o / (G * c)) * ellipk(math.sin(math.pi / 4) ** 2)


def pendulum():
    model = pendulum_chain(1, link_length=1.0, link_mass=1.0, angle=0.0)
    return model, model.coordinate_index("link1.theta")


@pytest.mark.parametrize("method,options", METHODS, ids=[m for m, _ in METHODS])
def test_recorded_crossings_of_the_bottom_are_the_odd_quarter_periods(method, options):
    model, k = pendulum()
    bottom = mb.Event("bottom", lambda t, q, qd: q[k] + math.pi / 2)
    res = mb.forward_dynamics(model, np.linspace(0.0, 1.5, 7), method=method, events=[bottom],
                              **options)
    assert res.status == "complete"
    quarter = quarter_period(1.0)
    times = [e["time"] for e in res.stats["events"]]
    expected = [quarter * (2 * j + 1) for j in range(len(times))]
    assert len(times) == int((1.5 / quarter + 1) // 2) == 2
    np.testing.assert_allclose(times, expected, rtol=0, atol=TIME_TOL[method])


def test_a_height_passed_up_and_down_within_one_step_is_recorded_twice():
    """A ball thrown up at 10 m/s from the floor passes 5 m, 10 cm below its apex, at the
    roots of 5 = 10 t - g t^2 / 2, 0.28 s apart. Its flight is a parabola, which DOP853
    integrates exactly, so its steps grow long: both passages lie inside one of them (the
    first once hid the second), and each is recorded."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    b.add_body("ball", mass=0.2, inertia=1e-4, position=(0.0, 0.0), velocity=(0.0, 10.0))
    model = b.build()
    k = model.coordinate_index("ball.y")
    height = mb.Event("5 m", lambda t, q, qd: q[k] - 5.0)
    res = mb.forward_dynamics(model, [0.0, 2.0], method="DOP853", events=[height])
    roots = np.sort(np.roots([-G / 2, 10.0, -5.0]))
    np.testing.assert_allclose([e["time"] for e in res.stats["events"]], roots, rtol=0,
                               atol=1e-12)


@pytest.mark.parametrize("method,options", METHODS, ids=[m for m, _ in METHODS])
def test_a_stopping_event_ends_the_run_at_the_crossing_in_its_direction(method, options):
    model, k = pendulum()
    # rising through the bottom: the swing back, not the first fall
    back = mb.Event("back through the bottom", lambda t, q, qd: q[k] + math.pi / 2,
                    direction=1, action="stop")
    t = np.linspace(0.0, 1.6, 33)
    res = mb.forward_dynamics(model, t, method=method, events=[back], **options)
    te = 3 * quarter_period(1.0)
    assert res.status == "stopped" and "back through the bottom" in res.message
    (event,) = res.stats["events"]
    assert abs(event["time"] - te) <= TIME_TOL[method]
    np.testing.assert_array_equal(res.t, t[t <= te])


def free_ball():
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    b.add_body("ball", mass=0.2, inertia=1e-4, position=(0.0, 1.0))
    model = b.build()
    return model, model.coordinate_index("ball.y")


@pytest.mark.parametrize("method,options", METHODS, ids=[m for m, _ in METHODS])
def test_a_ball_bouncing_with_restitution_lands_at_the_closed_form_times(method, options):
    model, k = free_ball()
    e = 0.8

    def bounce(t, q, qd):
        qd[k] = -e * qd[k]
        return q, qd

    floor = mb.Event("floor", lambda t, q, qd: q[k], direction=-1, action=bounce)
    t = np.linspace(0.0, 2.0, 201)
    res = mb.forward_dynamics(model, t, method=method, events=[floor], **options)
    assert res.status == "complete"
    # free fall from 1 m: lands at sqrt(2 h / g) with speed g t1, then flights of 2 e^j v1 / g
    t1 = math.sqrt(2.0 / G)
    v1 = G * t1
    landings = t1 + np.concatenate([[0.0], np.cumsum([2 * e**j * v1 / G for j in range(1, 6)])])
    landings = landings[landings <= 2.0]
    times = [ev["time"] for ev in res.stats["events"]]
    # a parabola is integrated exactly by DOP853 (one step spans a whole flight) and by
    # generalized-alpha up to its Newton tolerance
    np.testing.assert_allclose(times, landings, rtol=0, atol=1e-9)
    # the height between the landings is the parabola after the last one
    j = np.searchsorted(landings, t, side="right") - 1
    after = j >= 0
    speed = np.where(after, e ** (j + 1) * v1, 0.0)
    tau = np.where(after, t - landings[np.maximum(j, 0)], t)
    height = np.where(after, speed * tau - 0.5 * G * tau**2, 1.0 - 0.5 * G * t**2)
    np.testing.assert_allclose(res.q[:, k], height, rtol=0, atol=1e-9)


def test_forty_crossings_of_an_oscillator_are_each_found_once_at_their_times():
    """A 2 kg block on a 200 N/m spring along a rail, released 1 cm from rest: x = 0.01
    cos(w t), w = 10 rad/s, through its rest point at (2k + 1) pi / (2 w). Over twenty periods
    the crossings fall anywhere in the steps (also in the last of the samples each step is
    searched at), and every one is found once, at its time."""
    from mbd3d.joints import Prismatic

    b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0))
    block = b.add_body("block", mass=2.0, inertia=0.1, position=(1.01, 0.0))
    b.add(Prismatic("rail", b.ground, block, axis=(1.0, 0.0), point_i=(0.0, 0.0),
                    point_j=(0.0, 0.0)))
    b.add(mb.SpringDamper("spring", b.ground, block, point_i=(0.0, 0.0), point_j=(0.0, 0.0),
                          stiffness=200.0, free_length=1.0))
    model = b.build()
    k = model.coordinate_index("block.x")
    rest = mb.Event("rest", lambda t, q, qd: q[k] - 1.0)
    w = 10.0
    res = mb.forward_dynamics(model, np.linspace(0.0, 40 * math.pi / w, 161), method="DOP853",
                              rtol=1e-11, atol=1e-13, events=[rest])
    times = [e["time"] for e in res.stats["events"]]
    assert len(times) == 40
    np.testing.assert_allclose(times, (2 * np.arange(40) + 1) * math.pi / (2 * w), rtol=0,
                               atol=1e-9)


def test_bad_events_are_refused_by_name():
    model, k = pendulum()
    with pytest.raises(mb.ModelError, match="direction"):
        mb.Event("e", lambda t, q, qd: q[k], direction=2)
    with pytest.raises(mb.ModelError, match="action"):
        mb.Event("e", lambda t, q, qd: q[k], action="bounce")
    with pytest.raises(mb.ModelError, match="event 'e': rate must be callable"):
        mb.Event("e", lambda t, q, qd: q[k], rate=1.0)
    with pytest.raises(mb.ModelError, match="event 'e': tolerance must be a number >= 0"):
        mb.Event("e", lambda t, q, qd: q[k], tolerance=-1e-9)
    wild = mb.Event("wild", lambda t, q, qd: q[k], rate=lambda t, q, qd: None)
    with pytest.raises(mb.ModelError, match=r"event 'wild': rate\(t, q, qd\) must return a "
                                            "finite number, returned None"):
        mb.forward_dynamics(model, [0.0, 0.1], events=[wild])
    with pytest.raises(mb.ModelError, match="events must be mbd3d.Event"):
        mb.forward_dynamics(model, [0.0, 0.1], events=[lambda t, q, qd: q[k]])
    nan = mb.Event("broken", lambda t, q, qd: float("nan"))
    with pytest.raises(mb.ModelError, match="event 'broken'.*finite number"):
        mb.forward_dynamics(model, [0.0, 0.1], events=[nan])
    careless = mb.Event("bottom", lambda t, q, qd: q[k] + math.pi / 2, action=lambda t, q, qd: qd)
    with pytest.raises(mb.ModelError, match=r"event 'bottom' at t = 0.48333\d* s: its action "
                                            r"must return \(q, qd\), two arrays of 3 finite"):
        mb.forward_dynamics(model, [0.0, 1.0], events=[careless])


@pytest.mark.parametrize("with_rate", [True, False])
def test_a_crossing_and_return_between_samples_is_found_from_the_rate(with_rate):
    """Thrown up at 5 m/s, the ball stays above 99.99 % of its apex height for only 10 ms
    around the apex: the long exact steps of its flight sample it too sparsely, and miss it.
    Given its rate, the event is evaluated where that turns (the apex) too, and the passage
    up is found at the root of y = 0.9999 h, h = v^2 / (2 g)."""
    v = 5.0
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    b.add_body("ball", mass=0.2, inertia=1e-4, position=(0.0, 0.0), velocity=(0.0, v))
    model = b.build()
    k = model.coordinate_index("ball.y")
    h = v * v / (2 * G)
    near = mb.Event("near the apex", lambda t, q, qd: q[k] - 0.9999 * h, direction=1,
                    rate=(lambda t, q, qd: qd[k]) if with_rate else None)
    res = mb.forward_dynamics(model, [0.0, 2.5], method="DOP853", events=[near],
                              rtol=1e-11, atol=1e-12)
    times = [e["time"] for e in res.stats["events"]]
    if not with_rate:  # the steps are as long as the test says: the crossing is unseen
        assert times == []
        return
    up = (v - math.sqrt(v * v - 2 * G * 0.9999 * h)) / G
    assert len(times) == 1
    np.testing.assert_allclose(times[0], up, rtol=0, atol=1e-9)


@pytest.mark.compiled_only  # 10,000 steps
def test_a_function_dithering_about_zero_crosses_once_within_its_tolerance():
    """(t - 1)^3 with a ripple of 1e-8 and a period of 20 us: near t = 1 the ripple crosses
    zero dozens of times before the cube outgrows it. Each of those is a sign change; with a
    tolerance above the ripple only the first counts, up and down alike."""
    model, _ = pendulum()

    def dithering(t, q, qd):
        return (t - 1.0) ** 3 - 1e-8 * math.sin(2 * math.pi * t / 2e-5)

    def times(tolerance):
        events = [mb.Event(name, dithering, direction=d, tolerance=tolerance)
                  for name, d in (("up", 1), ("down", -1))]
        res = mb.forward_dynamics(model, [0.99, 1.01], events=events, max_step=2e-6)
        return {name: [e["time"] for e in res.stats["events"] if e["name"] == name]
                for name in ("up", "down")}

    every = times(0.0)
    assert len(every["up"]) > 10 and len(every["down"]) > 10
    assert abs(every["up"][0] - 1.0) < 3e-3
    once = times(1e-7)
    assert once["up"] == every["up"][:1] and once["down"] == []

