"""Prescribed motions: the exact derivatives they supply against finite differences of f."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import mbd3d as mb

MOTIONS = [
    mb.Constant(0.7),
    mb.Ramp(0.2, -1.5),
    mb.Harmonic(0.3, 4.0, phase=0.5, offset=1.0),
    mb.Polynomial([1.0, -2.0, 0.5, 0.25]),
    mb.SmoothStep(0.2, 0.9, -1.0, 2.0),
    mb.Function(math.exp, math.exp, math.exp),
    mb.Ramp(0.0, 1.0) + mb.Harmonic(0.1, 10.0),
]


@pytest.mark.parametrize("motion", MOTIONS, ids=repr)
def test_derivatives_match_finite_differences(motion):
    h = 1e-4
    for t in np.linspace(0.05, 1.1, 23):
        f, df, d2f = motion.evaluate(t)
        fd1 = (motion(t + h) - motion(t - h)) / (2 * h)
        fd2 = (motion(t + h) - 2 * f + motion(t - h)) / (h * h)
        assert df == pytest.approx(fd1, abs=1e-6)
        assert d2f == pytest.approx(fd2, abs=1e-4)


def test_smooth_step_starts_and_stops_at_rest():
    step = mb.SmoothStep(1.0, 3.0, 5.0, 7.0)
    assert step.evaluate(0.0) == (5.0, 0.0, 0.0)
    assert step.evaluate(4.0) == (7.0, 0.0, 0.0)
    for t in (1.0, 3.0):
        f, df, d2f = step.evaluate(t)
        assert df == pytest.approx(0.0, abs=1e-15) and d2f == pytest.approx(0.0, abs=1e-15)
    assert step(2.0) == pytest.approx(6.0)


def test_bad_motion_parameters():
    with pytest.raises(mb.ModelError, match="SmoothStep needs t1 > t0"):
        mb.SmoothStep(1.0, 1.0, 0.0, 1.0)
    with pytest.raises(mb.ModelError, match="Ramp rate must be finite"):
        mb.Ramp(0.0, math.inf)
    with pytest.raises(mb.ModelError, match="Function: df must be callable"):
        mb.Function(math.sin, 1.0, math.sin)


def test_spring_actuator_adds_tension():
    # an actuator force equal to the weight holds the mass where the spring is slack
    m = 2.0
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    mass = b.add_body("mass", mass=m, inertia=0.1, position=(0.0, -1.0))
    from mbd3d.joints import Prismatic
    b.add(Prismatic("guide", b.ground, mass, axis=(0.0, 1.0)))
    b.add(mb.SpringDamper("jack", b.ground, mass, at_i=(0.0, 0.0), stiffness=100.0,
                          damping=1.0, actuator=lambda t: m * 9.81))
    res = mb.forward_dynamics(b.build(), np.linspace(0.0, 1.0, 5))
    np.testing.assert_allclose(res.body("mass").position[:, 1], -1.0, rtol=0, atol=1e-10)


def test_polynomial_values_equal_numpys():
    coefficients = [1.0, -2.0, 0.5, 0.25, -0.125]
    motion = mb.Polynomial(coefficients)
    p = np.polynomial.Polynomial(coefficients)
    for t in (-1.3, 0.0, 0.7, 2.5):
        np.testing.assert_allclose(motion.evaluate(t), (p(t), p.deriv(1)(t), p.deriv(2)(t)),
                                   rtol=1e-14, atol=1e-14)


def test_compiled_and_python_motions_drive_the_same_motion():
    # the same crank motion as a Harmonic (evaluated in the compiled core) and as a Function
    # of math.sin and math.cos (evaluated by Python at every right-hand side)
    from mbd3d.mechanisms import slider_crank

    a, w, phase = 0.4, 3.0, 0.2
    function = mb.Function(lambda t: a * math.sin(w * t + phase),
                           lambda t: a * w * math.cos(w * t + phase),
                           lambda t: -a * w * w * math.sin(w * t + phase))
    t = np.linspace(0.0, 1.0, 11)
    runs = [mb.forward_dynamics(slider_crank(crank_motion=motion), t, rtol=1e-10, atol=1e-12)
            for motion in (mb.Harmonic(a, w, phase=phase), function)]
    assert runs[0].model._core.python_parts is False and runs[1].model._core.python_parts
    np.testing.assert_allclose(runs[0].q, runs[1].q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(runs[0].lam, runs[1].lam, rtol=1e-9, atol=1e-9)


def test_every_motion_and_a_sum_of_them_through_the_compiled_table_equal_their_formulas():
    """The motions' values as the compiled loop evaluates them (the table of terms the
    model's drivers and actuators become) against the formulas written here, with offsets,
    initial values and phases that are not zero."""
    from mbd3d.numerics.compiled.motions import motion_values_into, table
    ramp, wave = mb.Ramp(0.7, -2.0), mb.Harmonic(0.3, 5.0, phase=0.2, offset=-0.4)
    step = mb.SmoothStep(0.2, 1.1, start=0.5, end=-1.5)
    motions = [mb.Constant(1.25), ramp, wave, step, ramp + wave + mb.Constant(1.25)]
    first, kinds, starts, params = table([m.terms() for m in motions])
    for t in (0.0, 0.35, 0.9, 1.7):
        out = np.empty((len(motions), 3))
        motion_values_into(first, kinds, starts, params, t, out)
        a = 5.0 * t + 0.2
        s = min(max((t - 0.2) / 0.9, 0.0), 1.0)
        expected = [
            (1.25, 0.0, 0.0),
            (0.7 - 2.0 * t, -2.0, 0.0),
            (-0.4 + 0.3 * np.sin(a), 1.5 * np.cos(a), -7.5 * np.sin(a)),
            (0.5 - 2.0 * (10 * s**3 - 15 * s**4 + 6 * s**5),
             -2.0 * 30 * s**2 * (1 - s) ** 2 / 0.9,
             -2.0 * 60 * s * (1 - s) * (1 - 2 * s) / 0.9**2),
        ]
        expected.append(tuple(np.sum([expected[0], expected[1], expected[2]], axis=0)))
        np.testing.assert_allclose(out, expected, rtol=0, atol=1e-13)


def test_forward_dynamics_follows_a_driver_s_acceleration():
    """A slider whose slide is driven by a harmonic motion, integrated by forward dynamics
    (the compiled loop's accelerations: the driver's second derivative enters the rows'
    right-hand side): the slider accelerates as the motion's second derivative and the
    driver pushes m times that (Newton along a level rail), to the integrator's accuracy."""
    from mbd3d.joints import Prismatic, TranslationDriver
    m = 2.5
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    slider = b.add_body("slider", mass=m, inertia=0.01, position=(0.0, 0.0))
    rail = b.add(Prismatic("rail", b.ground, slider, axis=(1.0, 0.0)))
    motion = mb.Harmonic(0.1, 2.0, phase=0.3)
    b.add(TranslationDriver("push", rail, motion=motion))
    t = np.linspace(0.0, 1.0, 11)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mb.InitialStateWarning)  # rates set by the driver
        res = mb.forward_dynamics(b.build(), t, method="DOP853", rtol=1e-10, atol=1e-12)
    wanted = np.array([motion.evaluate(tk)[2] for tk in t])
    assert np.max(np.abs(wanted)) > 0.1
    np.testing.assert_allclose(res.body("slider").acceleration[:, 0], wanted, rtol=0,
                               atol=1e-7)
    np.testing.assert_allclose(res.driver("push").effort, m * wanted, rtol=0, atol=1e-6)
