"""Observers see an analysis grow and always see how it ended; the progress bar."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.mechanisms import pendulum_chain, slider_crank


class Log(mb.Observer):
    interval = 0.0  # every step: the test sees each update

    def __init__(self):
        self.calls = []

    def start(self, model, times, analysis):
        self.calls.append(("start", analysis, len(times)))

    def update(self, results, time, steps):
        self.calls.append(("update", len(results), time, results.status))

    def finish(self, results):
        self.calls.append(("finish", len(results), results.status))
        self.final = results


@pytest.mark.parametrize("analysis", ["kinematic", "forward"])
def test_observer_sees_growing_results_and_the_end(analysis):
    log = Log()
    times = np.linspace(0.0, 0.2, 11)
    if analysis == "kinematic":
        res = mb.kinematic_analysis(slider_crank(crank_speed=2 * math.pi), times, observers=[log])
    else:
        res = mb.forward_dynamics(pendulum_chain(2), times, observers=[log])
    assert log.calls[0][0] == "start" and log.calls[0][2] == 11
    assert log.calls[-1] == ("finish", 11, "complete")
    updates = [c for c in log.calls if c[0] == "update"]
    assert updates and all(c[3] == "running" for c in updates)
    sizes = [c[1] for c in updates]
    assert sizes == sorted(sizes) and sizes[0] >= 1
    np.testing.assert_array_equal(log.final.q, res.q)


def test_failing_force_keeps_results_and_tells_observers():
    """A user's force function raising mid-run: the error propagates with the results so far,
    and the observers were handed them (a recording would be complete up to the failure)."""
    log = Log()
    model_b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    bar = model_b.add_body("bar", mass=1.0, inertia=0.1, position=(0.5, 0.0))
    from mbd3d.joints import Revolute
    model_b.add(Revolute("pin", model_b.ground, bar, at=(0.0, 0.0)))

    def push(t):
        if t > 0.5:
            raise ValueError("sensor table ends at 0.5 s")
        return (0.0, 1.0)

    model_b.add(mb.PointForce("push", bar, push, point=(0.5, 0.0)))
    with pytest.raises(ValueError, match="sensor table") as info:
        mb.forward_dynamics(model_b.build(), np.linspace(0.0, 1.0, 21), observers=[log])
    partial = info.value.results
    assert partial.status == "failed" and 9 <= len(partial) <= 11
    assert partial.t[-1] <= 0.5
    assert log.calls[-1] == ("finish", len(partial), "failed")


def test_progress_bar_draws_time_rate_and_eta():
    out = io.StringIO()
    bar = mb.ProgressBar(stream=out, delay=0.0)
    bar.interval = 0.0
    mb.forward_dynamics(pendulum_chain(3), np.linspace(0.0, 0.5, 6), observers=[bar])
    text = out.getvalue()
    last = text.split("\r")[-1]
    assert "forward dynamics of" in last and "100%" in last and "steps/s" in last
    assert last.endswith("complete\n")
    assert "t = 0.5/0.5 s" in last


def test_progress_is_silent_when_not_a_terminal(capsys):
    mb.forward_dynamics(pendulum_chain(2), np.linspace(0.0, 0.1, 3))
    assert capsys.readouterr().err == ""


def test_bad_observer_is_named():
    with pytest.raises(mb.ModelError, match="observers must have start"):
        mb.kinematic_analysis(slider_crank(crank_speed=1.0), [0.0, 0.1], observers=[print])
