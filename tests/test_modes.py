"""Vibration modes about an equilibrium against the small-motion equations derived by hand:
a sprung and damped pendulum, a double pendulum (its 2 x 2 Lagrangian), a spatial pendulum
on a ball joint, and an inverted pendulum's growth rate."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg as la

import mbd3d as mb
from mbd3d.joints import Revolute, Spherical
from four_bar_loop import COUPLER, CRANK, ROCKER, four_bar_by_hand, perp

G = 9.81


def hanging_bars(lengths, masses, spring=0.0, damper=0.0, angle=-math.pi / 2):
    """Uniform bars pinned end to end from the origin, hanging straight down (or at
    ``angle``); a torsion spring-damper at the top pin, relaxed there."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    previous, top = b.ground, np.zeros(2)
    direction = np.array([math.cos(angle), math.sin(angle)])
    for k, (L, m) in enumerate(zip(lengths, masses)):
        body = b.add_body(f"bar{k + 1}", mass=m, inertia=m * L * L / 12,
                          position=top + direction * L / 2, angle=angle)
        b.add(Revolute(f"pin{k + 1}", previous, body, at=top))
        if k == 0 and (spring or damper):
            b.add(mb.RotationalSpringDamper("torsion", body_i=b.ground, body_j=body,
                                            stiffness=spring, damping=damper))
        previous, top = body, top + direction * L
    return b.build()


def test_sprung_damped_pendulum_frequency_and_damping_ratio():
    """I_O theta'' + c theta' + (k + m g L/2) theta = 0, I_O = m L^2 / 3."""
    m, L, k, c = 2.0, 0.8, 6.0, 0.9
    modes = mb.vibration_modes(hanging_bars([L], [m], spring=k, damper=c))
    inertia, stiffness = m * L * L / 3, k + m * G * L / 2
    omega = math.sqrt(stiffness / inertia)
    assert modes.frequencies == pytest.approx([omega / (2 * math.pi)], rel=1e-7)
    assert modes.damping_ratios == pytest.approx([c / (2 * math.sqrt(stiffness * inertia))],
                                                 rel=1e-6)
    # the shape: the bar's centre moves L/2 per radian, sideways
    shape = modes.shapes[0].real
    assert shape[0] == pytest.approx(L / 2 * shape[2], rel=1e-8)
    assert modes.equilibrium.stats["stability"] == ["stable"]


def test_double_pendulum_against_its_lagrangian():
    """Two uniform bars, angles from the vertical: M = [[(m1/3 + m2) L1^2, m2 L1 L2 / 2],
    [m2 L1 L2 / 2, m2 L2^2 / 3]], K = diag((m1/2 + m2) g L1, m2 g L2 / 2)."""
    (L1, L2), (m1, m2) = (0.6, 0.9), (1.5, 2.5)
    modes = mb.vibration_modes(hanging_bars([L1, L2], [m1, m2]))
    M = np.array([[(m1 / 3 + m2) * L1 * L1, m2 * L1 * L2 / 2],
                  [m2 * L1 * L2 / 2, m2 * L2 * L2 / 3]])
    K = np.diag([(m1 / 2 + m2) * G * L1, m2 * G * L2 / 2])
    expected = np.sqrt(la.eigh(K, M, eigvals_only=True)) / (2 * math.pi)
    np.testing.assert_allclose(modes.frequencies, expected, rtol=1e-7)
    np.testing.assert_allclose(modes.damping_ratios, 0.0, rtol=0, atol=1e-9)


def test_spatial_pendulum_swings_alike_both_ways_and_spins_freely():
    """A bar on a ball joint: two swings at sqrt(3 g / 2 L) and a spin about its own axis
    without stiffness (a zero frequency, twice: the two real roots of a free motion)."""
    m, L = 1.5, 1.2
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G))
    from mbd3d.mechanisms import frame_along
    bar = b.add_body("bar", mass=m, inertia=m * L * L * np.array([1e-2, 1 / 12, 1 / 12]),
                     position=(0.0, 0.0, -L / 2), orientation=frame_along(np.array([0, 0, -1.0])))
    b.add(Spherical("ball", b.ground, bar, at=(0.0, 0.0, 0.0)))
    modes = mb.vibration_modes(b.build())
    swing = math.sqrt(3 * G / (2 * L)) / (2 * math.pi)
    np.testing.assert_allclose(modes.frequencies, [0.0, 0.0, swing, swing], atol=1e-7 * swing,
                               rtol=1e-7)
    assert modes.equilibrium.stats["stability"] == ["neutral"]


def test_mode_animations_swing_in_the_phases_of_their_shapes():
    """With the damper at one pin only, a double pendulum's modes are complex (its parts do
    not swing in phase): the animation is q0 + a Re(shape e^(i w t)) to first order in a,
    each coordinate at its own phase. A spatial mode's animation carries the charts."""
    modes = mb.vibration_modes(hanging_bars([0.6, 0.9], [1.5, 2.5], damper=0.8))
    q0 = modes.equilibrium.q[0]
    for mode in (0, 1):
        shape, w = modes.shapes[mode], 2 * math.pi * modes.frequencies[mode]
        assert np.max(np.abs(shape.imag)) > 0.02
        swing = modes.animation(mode, amplitude=1e-3, frames=16, cycles=1)
        turning = shape[None, :] * np.exp(1j * w * swing.t)[:, None]
        np.testing.assert_allclose(swing.q, q0 + 1e-3 * turning.real, rtol=0, atol=1e-6)
        # the rates and accelerations of that first-order motion, its derivatives
        np.testing.assert_allclose(swing.qd, 1e-3 * (1j * w * turning).real, rtol=0,
                                   atol=1e-15 * w)
        np.testing.assert_allclose(swing.qdd, -1e-3 * w * w * turning.real, rtol=0,
                                   atol=1e-15 * w * w)
        assert f"mode {mode + 1} of 2" in swing.message

    m, L = 1.5, 1.2
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G))
    bar = b.add_body("bar", mass=m, inertia=m * L * L * np.array([1 / 12, 1 / 12, 1e-2]),
                     position=(0.0, 0.0, -L / 2))
    b.add(Spherical("ball", b.ground, bar, at=(0.0, 0.0, 0.0)))
    model = b.build()
    swing = mb.vibration_modes(model).animation(2, amplitude=0.01, frames=8, cycles=1)
    assert swing.charts.shape == (9,) + model.charts0.shape
    assert swing.position_residual.max() < 1e-12
    # the shape is led by the centre's sideways motion, 0.01 m; the lower end, twice as far
    # from the ball joint, swings twice as far
    end = swing.point("bar", (0.0, 0.0, -L / 2)).position
    assert np.max(np.hypot(end[:, 0], end[:, 1])) == pytest.approx(0.02, rel=1e-3)
    # the spin about the bar's axis does not oscillate: drawn as a swing of 1 s
    assert mb.vibration_modes(model).animation(0, frames=4, cycles=2).t[-1] == 2.0
    # by default a shape led by a position swings by a tenth of the model's length
    default = mb.vibration_modes(model).animation(2, frames=4, cycles=1)
    centre = default.body("bar").position
    assert np.max(np.hypot(centre[:, 0], centre[:, 1])) == pytest.approx(
        0.1 * model.length_scale, rel=1e-2)
    assert model.length_scale != pytest.approx(1.0, rel=0.1)

    # a mode damped at 0.7 of critical still oscillates: drawn over its own period
    inertia, stiffness = 2.0 * 0.8 ** 2 / 3, 2.0 * G * 0.8 / 2
    damped = mb.vibration_modes(hanging_bars([0.8], [2.0], damper=1.4 * math.sqrt(
        stiffness * inertia)))
    assert damped.damping_ratios[0] == pytest.approx(0.7, rel=1e-6)
    swing = damped.animation(0, frames=4, cycles=1)
    assert swing.t[-1] == pytest.approx(1.0 / damped.frequencies[0])


def test_an_inverted_pendulum_grows_at_the_rate_of_its_equation():
    """Upright, I_O theta'' = m g L/2 theta: a real root sqrt(3 g / 2 L) (damping ratio -1)."""
    L = 0.8
    modes = mb.vibration_modes(hanging_bars([L], [2.0], angle=math.pi / 2))
    rate = math.sqrt(3 * G / (2 * L))
    assert sorted(modes.damping_ratios) == pytest.approx([-1.0, 1.0])
    np.testing.assert_allclose(modes.frequencies * 2 * math.pi, [rate, rate], rtol=1e-7)
    assert modes.equilibrium.stats["stability"] == ["unstable"]


def _inertia_by_hand(theta2, rho=2.0):
    """The inertia the crank carries, I = sum m v^2 + J w^2 at unit crank rate, and the
    rocker's rate per unit crank rate, from the loop solved by hand."""
    (theta3, _), (w3, w4), _ = four_bar_by_hand(theta2)
    v_coupler = CRANK * perp(theta2) + COUPLER / 2 * w3 * perp(theta3)
    inertia = 0.0
    for length, speed, rate in ((CRANK, CRANK / 2, 1.0), (COUPLER, np.linalg.norm(v_coupler), w3),
                                (ROCKER, ROCKER / 2 * abs(w4), w4)):
        m = rho * length
        inertia += m * speed ** 2 + m * length ** 2 / 12 * rate ** 2
    return inertia, w4


def test_four_bar_on_an_elastic_shaft_along_its_turn():
    """Each position's one frequency is sqrt(k / I(theta)) / 2 pi, I from the loop's velocity
    equations by hand; the mode shape moves the rocker by the loop's velocity ratio; the
    animation of the mode stays assembled and swings at the mode's frequency."""
    from mbd3d.mechanisms import four_bar
    k = 50.0
    model = four_bar(shaft_stiffness=k, gravity=0.0)
    along = mb.vibration_modes_along(model, np.linspace(0.0, 1.0, 7))
    crank = along.equilibrium.body("crank").angle
    np.testing.assert_allclose(crank, math.radians(60) + 2 * math.pi * along.t, rtol=0, atol=1e-12)
    by_hand = [_inertia_by_hand(angle) for angle in crank]
    expected = [math.sqrt(k / inertia) / (2 * math.pi) for inertia, _ in by_hand]
    np.testing.assert_allclose(along.frequencies[:, 0], expected, rtol=1e-7)
    np.testing.assert_allclose(along.damping_ratios, 0.0, rtol=0, atol=1e-9)
    i_crank, i_rocker = (model.coordinate_index(c) for c in ("crank.theta", "rocker.theta"))
    ratios = along.shapes[:, 0, i_rocker] / along.shapes[:, 0, i_crank]
    np.testing.assert_allclose(ratios.real, [w4 for _, w4 in by_hand], rtol=1e-7)
    np.testing.assert_allclose(ratios.imag, 0.0, rtol=0, atol=1e-9)

    modes = along.at(2)
    swing = modes.animation(frames=16, cycles=1, amplitude=0.05)
    assert swing.position_residual.max() < 1e-12
    twist = swing.body("crank").angle - crank[2]
    period = 1.0 / modes.frequencies[0]
    assert swing.t[-1] == pytest.approx(period)
    # to first order in the amplitude (putting the positions back on the constraints moves
    # them by its square)
    w, shape = 2 * math.pi / period, modes.shapes[0, i_crank].real
    np.testing.assert_allclose(twist, 0.05 * np.cos(w * swing.t) * shape, rtol=0,
                               atol=0.5 * 0.05 ** 2)
    # one point per frame and the period's end; the rates and accelerations those of the
    # first-order motion, its derivatives
    assert len(swing.t) == 17 and "mode 1 of 1" in swing.message
    np.testing.assert_allclose(swing.qd[:, i_crank], -0.05 * w * np.sin(w * swing.t) * shape,
                               rtol=0, atol=1e-12 * w)
    np.testing.assert_allclose(swing.qdd[:, i_crank], -0.05 * w * w * np.cos(w * swing.t)
                               * shape, rtol=0, atol=1e-12 * w * w)
    # by default the coordinate leading the shape swings by a tenth of a radian, or of the
    # model's length
    lead = int(np.argmax(np.abs(modes.shapes[0])))
    unit = model.length_scale if model.position_coordinates[lead] else 1.0
    default = modes.animation(frames=4, cycles=3)
    assert len(default.t) == 13 and default.t[-1] == pytest.approx(3 * period)
    np.testing.assert_allclose(np.max(np.abs(default.qd[:, lead])), 0.1 * unit * w, rtol=1e-12)
    with pytest.raises(mb.ModelError, match=r"1 modes here \(0 to 0\)"):
        modes.animation(3)


def test_a_rigid_driven_mechanism_has_no_modes():
    from mbd3d.mechanisms import four_bar
    along = mb.vibration_modes_along(four_bar(gravity=0.0), [0.0, 0.5])
    assert along.frequencies.shape == (2, 0)


def test_a_bar_sprung_to_a_driven_crank_without_gravity_along_the_turn():
    """No gravity: a driven crank carries a bar on a pin; a spring of free length h joins the
    crank's point (r + a, h) to the bar's point at a from the pin, so it is relaxed when the
    bar lies along the crank. At rest the applied forces vanish at every crank angle (the
    solve must judge convergence without them), and a swing phi of the bar stretches the
    spring by a phi with no tension to stiffen it geometrically: the bar swings about the pin
    at sqrt(k a^2 / I_pin) / 2 pi, I_pin = I + m (L/2)^2, wherever the crank stands."""
    from mbd3d.joints import RotationDriver
    r, L, m, k, a, h = 0.3, 0.8, 2.0, 7.0, 0.6, 0.25
    inertia = m * L * L / 12
    b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0))
    crank = b.add_body("crank", mass=1.0, inertia=0.01, position=(r / 2, 0.0))
    bar = b.add_body("bar", mass=m, inertia=inertia, position=(r + L / 2, 0.0))
    hub = b.add(Revolute("hub", b.ground, crank, at=(0.0, 0.0)))
    b.add(Revolute("pin", crank, bar, at=(r, 0.0)))
    b.add(mb.SpringDamper("spring", crank, bar, at_i=(r + a, h), at_j=(r + a, 0.0),
                          stiffness=k))
    b.add(RotationDriver("motor", hub, motion=mb.Ramp(0.0, 2.0)))
    along = mb.vibration_modes_along(b.build(), np.linspace(0.0, 3.0, 7))
    expected = math.sqrt(k * a * a / (inertia + m * L * L / 4)) / (2 * math.pi)
    np.testing.assert_allclose(along.frequencies, expected, rtol=1e-6, atol=0)
    rest = along.equilibrium
    np.testing.assert_allclose(rest.body("bar").angle, rest.body("crank").angle, rtol=0,
                               atol=1e-10)
    np.testing.assert_allclose(rest.body("crank").angle, 2.0 * along.t, rtol=0, atol=1e-10)
