"""Generalized-alpha's step rules at compliant contacts (mbd3d.numerics.compiled.contact_steps)
against the closed-form period of the impact they resolve: a hundred steps per period of the
law's oscillation, at its stiffest, from the closing speed (the bounces themselves are checked
against DOP853 in test_generalized_alpha.py)."""

from __future__ import annotations

import math

import pytest

import mbd3d as mb
from mbd3d.analyses.contact_steps import ContactSteps
from mbd3d.numerics.compiled import contact_steps as rules
from test_generalized_alpha import ball_over_floor

SPEED = 2.0  # m/s, the 1 kg ball's closing speed as it touches


def linear_period() -> float:
    """A 1 kg mass on a 1e6 N/m spring: 2 pi sqrt(m / k) [s]."""
    return 2.0 * math.pi * math.sqrt(1.0 / 1e6)


def hertz_period() -> float:
    """Hertz's law F = K delta^1.5 (K = 1e8) met at SPEED: the energy m v^2 / 2 = K
    delta^2.5 / 2.5 stored at the deepest point, where the stiffness dF/ddelta = 1.5 K
    delta^0.5 is greatest; the period of that stiffness [s]."""
    deepest = (2.5 * SPEED ** 2 / (2.0 * 1e8)) ** 0.4
    return 2.0 * math.pi * math.sqrt(1.0 / (1.5 * 1e8 * deepest ** 0.5))


LAWS = [(mb.LinearContact(stiffness=1e6, restitution=1.0), linear_period),
        (mb.HertzContact(stiffness=1e8, restitution=1.0), hertz_period)]


@pytest.mark.parametrize("law, period", LAWS, ids=["linear", "Hertz"])
def test_a_ball_touching_the_floor_limits_the_step_to_just_past_the_touch(law, period):
    """The ball's surface on the floor (gap 0), closing at SPEED: the touch is now, so the
    step may reach just past it, by BAND of an impact step T / PER_PERIOD."""
    model = ball_over_floor(law, 0.1, speed=SPEED)
    steps = ContactSteps(model, model._core.workspace())
    steps.start(0.0, model.q0, model.qd0, None)
    expected = 0.5 * rules.BAND * period() / rules.PER_PERIOD
    assert steps.limit(0.0) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("law, period", LAWS, ids=["linear", "Hertz"])
def test_an_impact_is_stepped_a_hundred_times_a_period(law, period):
    """From the touch, through 0.45 of the impact's period (the contact lasts about half of
    it), the 10 ms step is cut to T / 100: one step to the touch, then 45."""
    model = ball_over_floor(law, 0.1, speed=SPEED)
    res = mb.forward_dynamics(model, [0.0, 0.45 * period()], method="generalized-alpha",
                              step=1e-2)
    assert res.stats["steps"] == 1 + 45
    assert res.stats["contact_retries"] == 0
    assert res.q[-1, 1] < 0.1  # still pressed in
