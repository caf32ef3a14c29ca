"""Disc cams against the follower law they were cut for: a cycloidal rise-dwell-return-dwell
law (written out below with its derivatives) comes back from kinematic analysis to the
spline's accuracy, converging at the spline's orders; the contact force balances the
follower's spring, weight and inertia through the pressure angle of the law; a free cam and
follower conserve energy; flat-faced followers read the support function.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.joints import (CamFollower, CamProfile, FlatFaceFollower, Prismatic, Revolute,
                          RotationDriver)

G = 9.81
BASE, ROLLER, LIFT, BETA = 0.04, 0.01, 0.02, math.radians(120.0)
SPEED = 2 * math.pi  # rad/s, one turn a second


def law(theta: np.ndarray, derivative: int = 0) -> np.ndarray:
    """The lift s(theta) [m] (or its derivatives in theta): cycloidal rise over BETA from 0,
    dwell to pi, cycloidal return over BETA, dwell."""
    th = np.mod(theta, 2 * math.pi)
    out = np.zeros_like(th)
    if derivative == 0:
        out[(th >= BETA) & (th < math.pi)] = LIFT
    for start, sign in ((0.0, 1.0), (math.pi, -1.0)):
        inside = (th >= start) & (th < start + BETA)
        x = (th[inside] - start) / BETA
        if derivative == 0:
            rise = LIFT * (x - np.sin(2 * math.pi * x) / (2 * math.pi))
            out[inside] = rise if sign > 0 else LIFT - rise
        elif derivative == 1:
            out[inside] = sign * LIFT / BETA * (1 - np.cos(2 * math.pi * x))
        else:
            out[inside] = sign * LIFT / BETA ** 2 * 2 * math.pi * np.sin(2 * math.pi * x)
    return out


def cam_and_follower(points: int = 1440, flat: bool = False, spring: float = 0.0,
                     driven: bool = True, speed: float = SPEED) -> mb.Model:
    """A cam turning counter-clockwise about the origin lifts a follower sliding on the y
    axis above it: roller centre at radius BASE + ROLLER + s, or a flat face at BASE + s.
    The follower's point sits at the polar angle pi/2 - theta in the cam's frame."""
    offset = 0.0 if flat else ROLLER
    profile = CamProfile.sampled(lambda phi: BASE + offset + law(math.pi / 2 - phi),
                                 points=points)
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G), name="cam")
    cam = b.add_body("cam", mass=2.0, inertia=2e-3, position=(0.0, 0.0))
    follower = b.add_body("follower", mass=0.5, inertia=1e-3, position=(0.0, BASE + offset))
    shaft = b.add(Revolute("shaft", b.ground, cam, at=(0.0, 0.0)))
    b.add(Prismatic("guide", b.ground, follower, axis=(0.0, 1.0)))
    if flat:
        b.add(FlatFaceFollower("contact", cam, follower, profile=profile, normal=(0.0, -1.0)))
    else:
        b.add(CamFollower("contact", cam, follower, profile=profile, roller_radius=ROLLER))
    if spring:
        # a return spring from 0.2 m above, compressed: free length 0.25 m
        b.add(mb.SpringDamper("return", b.ground, follower, at_i=(0.0, 0.2),
                              at_j=(0.0, BASE + offset), stiffness=spring, free_length=0.25))
    if driven:
        b.add(RotationDriver("motor", shaft, motion=mb.Ramp(0.0, speed)))
    return b.build()


def errors(res: mb.Results, offset: float) -> tuple[float, float, float]:
    theta = SPEED * res.t
    f = res.body("follower")
    return (np.max(np.abs(f.position[:, 1] - BASE - offset - law(theta))),
            np.max(np.abs(f.velocity[:, 1] - SPEED * law(theta, 1))),
            np.max(np.abs(f.acceleration[:, 1] - SPEED ** 2 * law(theta, 2))))


@pytest.mark.parametrize("flat", [False, True], ids=["roller", "flat face"])
def test_follower_reproduces_the_law_at_the_splines_orders(flat):
    t = np.linspace(0.0, 1.0, 997)  # not on the spline's knots
    coarse, fine = (errors(mb.kinematic_analysis(cam_and_follower(n, flat), t),
                           0.0 if flat else ROLLER) for n in (720, 1440))
    # a cubic spline's value, slope and curvature errors fall as h^4, h^3, h^2
    peak = SPEED ** 2 * LIFT / BETA ** 2 * 2 * math.pi  # the law's largest acceleration
    assert fine[0] < 1e-12 and fine[1] < 5e-9 and fine[2] < 5e-5 * peak
    for ratio, order in zip(np.divide(coarse, fine), (4, 3, 2)):
        assert 2 ** order * 0.75 < ratio < 2 ** order * 1.25, (coarse, fine)


def test_contact_force_balances_spring_weight_and_inertia():
    k = 400.0
    t = np.linspace(0.0, 1.0, 181)
    res = mb.inverse_dynamics(cam_and_follower(spring=k), t)
    theta = SPEED * t
    s, slope, accel = law(theta), law(theta, 1), SPEED ** 2 * law(theta, 2)
    # along the guide: N cos(a) = m y'' + m g + k (0.25 - (0.2 - y)), the spring 0.2 - y
    # long pushing down; a, the pressure angle: tan a = s' / (r_b + rho + s)
    y = BASE + ROLLER + s
    along = 0.5 * accel + 0.5 * G + k * (0.25 - (0.2 - y))
    pressure = np.arctan2(slope, BASE + ROLLER + s)
    expected = along / np.cos(pressure)
    np.testing.assert_allclose(res.joint("contact").contact_force, expected, rtol=2e-5)
    assert len(res.joint("contact").lift_off) == 0


def test_contact_points_lie_on_roller_and_face():
    """The roller touches the cam a roller radius from its centre; a flat face touches it
    s'(theta) off the follower's axis (the classical result for translating flat faces)."""
    t = np.linspace(0.0, 1.0, 37)
    theta = SPEED * t
    roller = mb.inverse_dynamics(cam_and_follower(spring=300.0), t)
    point, normal = roller.joint("contact").contact()
    centre = roller.body("follower").position
    np.testing.assert_allclose(np.linalg.norm(centre - point, axis=1), ROLLER, rtol=1e-12)
    np.testing.assert_allclose(np.einsum("ki,ki->k", normal, (centre - point) / ROLLER), 1.0)
    flat = mb.inverse_dynamics(cam_and_follower(flat=True, spring=300.0), t)
    point, normal = flat.joint("contact").contact()
    face = flat.body("follower").position
    np.testing.assert_allclose(point[:, 1], face[:, 1], rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.abs(point[:, 0]), np.abs(law(theta, 1)), rtol=0, atol=1e-7)
    np.testing.assert_allclose(normal, np.tile([0.0, 1.0], (len(t), 1)), rtol=0, atol=1e-15)


def test_lift_off_is_reported_where_the_contact_would_pull():
    speed = 4 * SPEED  # four turns a second: the return decelerates faster than g
    t = np.linspace(0.0, 0.25, 91)
    with pytest.warns(mb.LiftOffWarning, match="cam 'contact' would have to pull"):
        fast = mb.inverse_dynamics(cam_and_follower(spring=0.0, speed=speed), t)  # weight only
    force = fast.joint("contact").contact_force
    assert np.any(force < 0) and np.any(force > 0)
    np.testing.assert_array_equal(fast.joint("contact").lift_off, t[force < 0])
    # by hand: only the weight holds the follower on, so it would leave where the law pulls
    # it down faster than g
    pulling = speed ** 2 * law(speed * t, 2) < -G
    np.testing.assert_array_equal(force < 0, pulling)


@pytest.mark.parametrize("analysis", ["inverse dynamics", "forward dynamics"])
def test_lift_off_is_warned_at_the_first_time_the_contact_would_pull(analysis):
    speed = 4 * SPEED
    t = np.linspace(0.0, 0.25, 91)
    model = cam_and_follower(spring=0.0, speed=speed)
    # by hand, as above: the weight alone holds the follower on
    first = t[np.argmax(speed ** 2 * law(speed * t, 2) < -G)]
    run = mb.inverse_dynamics if analysis == "inverse dynamics" else mb.forward_dynamics
    with pytest.warns(mb.LiftOffWarning) as caught:
        run(model, t)
    (warning,) = [w for w in caught if w.category is mb.LiftOffWarning]
    assert f"{analysis} of 'cam': cam 'contact'" in str(warning.message)
    assert f"at t = {first:.6g} s" in str(warning.message)
    assert warning.filename == __file__  # points at the caller's line, not into mbd3d
    # held on by a spring strong enough, it never has to pull: no warning
    with warnings.catch_warnings():
        warnings.simplefilter("error", mb.LiftOffWarning)
        run(cam_and_follower(spring=2000.0, speed=speed), t)


@pytest.mark.parametrize("flat", [False, True], ids=["roller", "flat face"])
def test_free_cam_and_sprung_follower_conserve_energy(flat):
    """No motor: the spinning cam lifts the follower against its spring and gets the energy
    back; the total stays put (the rows' velocity terms are right)."""
    # a coarser spline: DOP853's steps are bounded by the knots (its curvature is piecewise
    # linear), not by stiffness: far below the spring's stability limit, so no crawling
    # warning (it once blamed the 300 N/m spring)
    model = cam_and_follower(points=360, flat=flat, spring=300.0, driven=False)
    t = np.linspace(0.0, 0.5, 11)
    with warnings.catch_warnings():
        warnings.simplefilter("error", mb.StiffnessWarning)
        res = mb.forward_dynamics(model, t, initial_rates={"shaft": 40.0}, method="DOP853",
                                  rtol=1e-11, atol=1e-12)
    assert res.stats["steps"] > 200  # the stiffness check ran
    energy = res.kinetic_energy + res.potential_energy
    exchanged = np.ptp(res.potential_energy)
    assert exchanged > 0.1 * res.kinetic_energy[0]
    assert np.ptp(energy) < 1e-9 * exchanged
    assert res.body("cam").angle[-1] > 2 * math.pi  # several rises and returns


def test_bad_cams_are_named():
    profile = CamProfile.sampled(lambda phi: 0.05 + 0.0 * phi, points=8)
    b = mb.ModelBuilder(dim=2, name="bad cam")
    cam = b.add_body("cam", mass=1.0, inertia=1e-3, position=(0.0, 0.0))
    follower = b.add_body("follower", mass=1.0, inertia=1e-3, position=(0.0, 0.06))
    b.add(CamFollower("contact", cam, follower, profile=profile))
    with pytest.raises(mb.ModelError, match="'contact'.*0.01 m off the pitch curve"):
        b.build()
    with pytest.raises(mb.ModelError, match="angles must increase"):
        CamProfile([0.0, 1.0, 0.5, 2.0], [1.0, 1.0, 1.0, 1.0])
    with pytest.raises(mb.ModelError, match="radii must be positive"):
        CamProfile([0.0, 1.0, 2.0, 3.0], [1.0, -1.0, 1.0, 1.0])
    b = mb.ModelBuilder(dim=3, name="spatial cam")
    cam = b.add_body("cam", mass=1.0, inertia=np.eye(3) * 1e-3, position=(0.0, 0.0, 0.0))
    follower = b.add_body("follower", mass=1.0, inertia=np.eye(3) * 1e-3,
                          position=(0.0, 0.05, 0.0))
    b.add(CamFollower("contact", cam, follower, profile=profile))
    with pytest.raises(mb.ModelError, match="'contact'.*planar models only"):
        b.build()


def test_undercut_and_concave_cams_are_refused():
    """A roller larger than the pitch curve's radius of curvature, or a flat face on a cam
    that is not convex, cannot follow the law."""
    b = mb.ModelBuilder(dim=2, name="sharp cam")
    # a 20 mm nose over a tenth of a radian: it bends far tighter than a 10 mm roller
    profile = CamProfile.sampled(lambda phi: 0.03 + 0.02 * np.exp(-((phi - math.pi) / 0.15) ** 2))
    cam = b.add_body("cam", mass=1.0, inertia=1e-3, position=(0.0, 0.0))
    follower = b.add_body("follower", mass=1.0, inertia=1e-3, position=(0.0, 0.03))
    b.add(CamFollower("contact", cam, follower, profile=profile, roller_radius=ROLLER))
    with pytest.raises(mb.ModelError, match="'contact'.*undercut"):
        b.build()
    b = mb.ModelBuilder(dim=2, name="concave cam")
    profile = CamProfile.sampled(lambda phi: 0.005 + law(math.pi / 2 - phi))
    cam = b.add_body("cam", mass=1.0, inertia=1e-3, position=(0.0, 0.0))
    follower = b.add_body("follower", mass=1.0, inertia=1e-3, position=(0.0, 0.005))
    b.add(FlatFaceFollower("contact", cam, follower, profile=profile, normal=(0.0, -1.0)))
    with pytest.raises(mb.ModelError, match="'contact'.*not convex"):
        b.build()



def test_the_compiled_curve_evaluates_the_profile_s_spline_anywhere_on_any_turn():
    """The compiled evaluation of a cam's profile (the wrap to one turn, the search for the
    interval, the cubic and its derivatives) against SciPy's evaluation of the same periodic
    spline, for a profile whose first angle is not zero, at angles in every interval, on the
    knots, in the last interval and turns away on both sides."""
    from mbd3d.numerics.compiled.curves import periodic_curve
    rng = np.random.default_rng(4)
    angles = 0.4 + np.sort(rng.uniform(0.0, 2 * math.pi - 0.1, 9))
    profile = CamProfile(angles, 0.05 + 0.01 * rng.uniform(size=9))
    curves, count = profile.table(), len(angles)
    last = angles[-1] + 0.5 * (angles[0] + 2 * math.pi - angles[-1])
    x = np.concatenate([angles, [last, last - 2 * math.pi, last + 6 * math.pi],
                        rng.uniform(-20.0, 20.0, 200)])
    ours = np.array([periodic_curve(curves, 0, count, float(v)) for v in x])
    scipy_says = np.stack([profile(x, derivative) for derivative in (0, 1, 2)], axis=1)
    np.testing.assert_allclose(ours, scipy_says, rtol=1e-12, atol=1e-12)
