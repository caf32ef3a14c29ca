"""The same mechanism at any size: lengths from 1e-6 to 1e3 m, masses from 1e-9 to 1e6 kg.

Scaling lengths by ``a`` and masses by ``b`` with time unchanged (gravity by ``a``, torques
by ``b a^2``) leaves the equations of motion the same in the units ``a`` and ``b``: angles,
positions over ``a``, forces over ``b a`` and torques over ``b a^2`` must come out the same.
Every tolerance of mbd3d (Newton, pivots, ranks, drift, the integrators' atol) is relative to
the model's length and mass, so they do, to rounding for kinematics and inverse dynamics and
to the integrators' tolerance for forward dynamics; before, a 10 um four-bar was refused as
singular and a micrometre slider-crank converged to 1e-6 of its size.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.joints import Prismatic, Revolute, RotationDriver, Spherical, Universal
from mbd3d.mechanisms import frame_along, slider_crank_positions

LENGTHS = (1e-6, 1e-3, 1e3)
MASSES = (1e-9, 1e6)
T = np.linspace(0.0, 0.5, 11)


def planar_slider_crank(a: float, b: float, driven: bool) -> mb.Model:
    """Crank 0.12 a, rod 0.26 a, Nikravesh's masses times b; motor at 2 pi rad/s or a moment
    of 2 b a^2 N m on the crank."""
    r, l, phi = 0.12 * a, 0.26 * a, math.radians(65.0)
    pin_a, rod_angle, b_point = slider_crank_positions(phi, r, l)
    m = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81 * a), name="scaled slider-crank")
    crank = m.add_body("crank", mass=1.0 * b, inertia=1e-3 * b * a * a, position=pin_a / 2,
                       angle=phi)
    rod = m.add_body("rod", mass=2.0 * b, inertia=1e-2 * b * a * a,
                     position=(pin_a + b_point) / 2, angle=rod_angle)
    slider = m.add_body("slider", mass=4.0 * b, inertia=2e-2 * b * a * a, position=b_point)
    pin = m.add(Revolute("O", m.ground, crank, point_i=(0.0, 0.0), point_j=(-r / 2, 0.0)))
    m.add(Revolute("A", crank, rod, point_i=(r / 2, 0.0), point_j=(-l / 2, 0.0)))
    m.add(Revolute("B", rod, slider, point_i=(l / 2, 0.0), point_j=(0.0, 0.0)))
    m.add(Prismatic("rail", m.ground, slider, axis=(1.0, 0.0)))
    if driven:
        m.add(RotationDriver("motor", pin, motion=mb.Ramp(phi, 2 * math.pi)))
    else:
        m.add(mb.Torque("moment", crank, 2.0 * b * a * a))
    return m.build()


def spatial_slider_crank(a: float, b: float, driven: bool) -> mb.Model:
    """The spatial slider-crank of mbd3d.mechanisms (rod out of the crank's plane) scaled."""
    r, l, d, e = 0.10 * a, 0.30 * a, 0.04 * a, 0.06 * a
    pin_a = np.array([r, 0.0, 0.0])
    b_point = np.array([r + math.sqrt(l * l - e * e - d * d), d, e])
    rod_dir = (b_point - pin_a) / l
    z = np.array([0.0, 0.0, 1.0])
    m = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -9.81 * a), name="scaled spatial slider-crank")

    def bar(length: float, mass: float) -> np.ndarray:
        return mass * np.array([1e-2 * length**2, length**2 / 12, length**2 / 12])

    crank = m.add_body("crank", mass=0.5 * b, inertia=bar(r, 0.5 * b), position=pin_a / 2,
                       orientation=frame_along(pin_a))
    rod = m.add_body("rod", mass=1.0 * b, inertia=bar(l, 1.0 * b), position=(pin_a + b_point) / 2,
                     orientation=frame_along(rod_dir))
    slider = m.add_body("slider", mass=2.0 * b, inertia=np.full(3, 0.002 * b * a * a),
                        position=b_point)
    pin = m.add(Revolute("O", m.ground, crank, at=(0.0, 0.0, 0.0), axis=z))
    side = np.cross(rod_dir, z)
    m.add(Universal("A", crank, rod, at=pin_a, axis_i=z, axis_j=side / np.linalg.norm(side)))
    m.add(Spherical("B", rod, slider, at=b_point))
    m.add(Prismatic("rail", m.ground, slider, axis=(1.0, 0.0, 0.0)))
    if driven:
        m.add(RotationDriver("motor", pin, motion=mb.Ramp(0.0, 2 * math.pi)))
    else:
        m.add(mb.Torque("moment", crank, (0.0, 0.0, 0.05 * b * a * a)))
    return m.build()


def dimensionless(res: mb.Results, a: float, b: float) -> dict[str, np.ndarray]:
    """The slider's position, velocity and acceleration over ``a``, the crank's angular
    velocity, and with multipliers the rail's force on the slider over ``b a`` and the motor's
    torque over ``b a^2``."""
    slider, crank = res.body("slider"), res.body("crank")
    out = {"position": slider.position / a, "velocity": slider.velocity / a,
           "acceleration": slider.acceleration / a, "crank speed": crank.angular_velocity}
    if res.lam is not None:
        out["rail force"] = res.joint("rail").reaction(on="slider").force / (b * a)
        if "motor" in res.efforts:
            out["motor torque"] = res.driver("motor").effort / (b * a * a)
    return out


@pytest.mark.parametrize("build", [planar_slider_crank, spatial_slider_crank],
                         ids=["planar", "spatial"])
def test_the_same_mechanism_at_any_size_moves_the_same(build):
    analyses = {
        "kinematic": lambda a, b: mb.kinematic_analysis(build(a, b, True), T),
        "inverse": lambda a, b: mb.inverse_dynamics(build(a, b, True), T),
        "forward": lambda a, b: mb.forward_dynamics(build(a, b, False), T),
        "generalized-alpha": lambda a, b: mb.forward_dynamics(
            build(a, b, False), T, method="generalized-alpha", step=1e-3),
    }
    for name, run in analyses.items():
        reference = dimensionless(run(1.0, 1.0), 1.0, 1.0)
        # rounding for the exact analyses; the integrators' tolerances for forward dynamics
        tol = {"forward": 1e-7, "generalized-alpha": 1e-8}.get(name, 1e-10)
        for a in LENGTHS:
            for b in MASSES:
                res = run(a, b)
                assert res.status == "complete", (name, a, b)
                for quantity, values in dimensionless(res, a, b).items():
                    expected = reference[quantity]
                    error = np.max(np.abs(values - expected)) / np.max(np.abs(expected))
                    assert error <= tol, (name, quantity, a, b, error)


def test_a_four_bar_of_ten_micrometres_is_analysed_like_one_of_ten_centimetres():
    """The issue's case: refused at t = 0 as 'singular (numerical rank 2 of 2 rows)'."""
    from mbd3d.mechanisms import four_bar

    reference = mb.inverse_dynamics(four_bar(), T)
    for a, b in ((1e-4, 1e-9), (1e-4, 1.0), (1e-3, 1e-9)):
        # bars of 10 to 35 um (a = 1e-4), masses times b, gravity times a: the same motion
        small = four_bar(ground_length=0.30 * a, crank_length=0.10 * a,
                         coupler_length=0.35 * a, rocker_length=0.30 * a,
                         mass_per_length=2.0 * b / a, gravity=9.81 * a)
        res = mb.inverse_dynamics(small, T)
        np.testing.assert_allclose(res.body("rocker").angle, reference.body("rocker").angle,
                                   rtol=0, atol=1e-12)
        np.testing.assert_allclose(res.driver("motor").effort / (b * a * a),
                                   reference.driver("motor").effort,
                                   rtol=1e-9, atol=1e-12 * np.abs(reference.lam).max())


@pytest.mark.parametrize("far", [0.0, 1e6])
def test_a_slider_crank_far_from_the_origin_moves_as_one_at_it(far):
    """Drawn 1000 km along x, a 0.29 m slider-crank's coordinates carry 1e6 m, whose rounding
    (1e-10 m) is far above the 1e-12 of its length the tolerance asks: Newton-Raphson stops at
    the rounding its coordinates allow (100 eps (L + max |R|), 2e-8 m) instead of failing,
    and the slider follows the closed form to that (times its sensitivity)."""
    r, l = 0.12, 0.26
    a0, rod0, b0 = slider_crank_positions(math.radians(65.0), r, l)
    origin = np.array([far, 0.0])
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    crank = b.add_body("crank", mass=1.0, inertia=1e-3, position=origin + a0 / 2,
                       angle=math.radians(65.0))
    rod = b.add_body("rod", mass=2.0, inertia=1e-2, position=origin + (a0 + b0) / 2,
                     angle=rod0)
    slider = b.add_body("slider", mass=4.0, inertia=2e-2, position=origin + b0)
    pin = b.add(Revolute("O", b.ground, crank, at=origin))
    b.add(Revolute("A", crank, rod, at=origin + a0))
    b.add(Revolute("B", rod, slider, at=origin + b0))
    b.add(Prismatic("rail", b.ground, slider, axis=(1.0, 0.0), at=origin))
    b.add(RotationDriver("motor", pin, motion=mb.Ramp(math.radians(65.0), 2 * math.pi)))
    t = np.linspace(0.0, 1.0, 9)
    res = mb.kinematic_analysis(b.build(), t)
    expected = [slider_crank_positions(math.radians(65.0) + 2 * math.pi * tk, r, l)[2][0]
                for tk in t]
    # residuals to the floor, 100 eps (L + max |R|) [m], times the slider's sensitivity to
    # them (a few)
    floor = 100 * np.finfo(float).eps * (0.29 + far)
    np.testing.assert_allclose(res.body("slider").position[:, 0] - far, expected, rtol=0,
                               atol=max(5 * floor, 1e-12))


def test_a_crank_a_million_radians_round_moves_as_in_its_first_turn():
    """A crank angle of 1e6 rad (160,000 turns) carries a rounding of 1e-10 rad, which moves
    its pin by 1e-11 m, above the 1e-12 of the length the tolerance asks: Newton-Raphson
    stops at the rounding the angles allow (100 eps (1 + max |angle|) of the length, for the
    points too) instead of failing as stuck at a singular position, and the slider follows
    the closed form to it."""
    from mbd3d.mechanisms import slider_crank

    # the drawn 65 degrees plus 159,155 turns: the drawing is the start's position
    start = math.radians(65.0) + 2 * math.pi * round(1e6 / (2 * math.pi))
    model = slider_crank(crank_motion=mb.Ramp(start, 2 * math.pi))
    t = np.linspace(0.0, 1.0, 9)
    res = mb.kinematic_analysis(model, t)
    expected = [slider_crank_positions(start + 2 * math.pi * tk, 0.12, 0.26)[2][0] for tk in t]
    # residuals to the floor, 100 eps (1 + max |angle|) of the 0.29 m length, times the
    # slider's sensitivity to them (a few)
    floor = 100 * np.finfo(float).eps * (1.0 + start)
    np.testing.assert_allclose(res.body("slider").position[:, 0], expected, rtol=0,
                               atol=5 * floor * 0.29)


def test_velocities_off_their_rows_are_judged_alike_at_any_size():
    """The last guard of a kinematic time point: velocities whose rows miss by more than
    1e-10 of the terms they sum are refused, with the relative residual named. The slider's
    speed off by 1e-12 of itself passes; off by 1e-9 and 1e-8 it is refused, at the same
    relative residual (in proportion) whether the mechanism measures millimetres or
    kilometres."""
    import re

    from mbd3d.analyses.kinematics import _check_velocities
    from mbd3d.mechanisms import slider_crank
    from mbd3d.model import constraints

    printed = {}
    for size in (1e-3, 1.0, 1e3):
        model = slider_crank(crank_length=0.12 * size, rod_length=0.26 * size,
                             crank_inertia=1e-3 * size ** 2, rod_inertia=1e-2 * size ** 2,
                             slider_inertia=2e-2 * size ** 2)
        q = mb.solve_position(model)
        fr = constraints.frames(model, q)
        Cq = constraints.jacobian(model, 0.0, q, fr, sparse=False)
        nu = constraints.velocity_rhs(model, 0.0, fr)
        qd = np.linalg.solve(Cq, nu)
        k = model.coordinate_index("slider.x")
        for off in (1e-12, 1e-9, 1e-8):
            wrong = qd.copy()
            wrong[k] *= 1.0 + off
            if off == 1e-12:
                _check_velocities(model, Cq, wrong, nu, 0.0, "a test")
                continue
            with pytest.raises(mb.AnalysisError, match="do not satisfy the constraints") as info:
                _check_velocities(model, Cq, wrong, nu, 0.0, "a test")
            printed[size, off] = float(re.search(r"relative residual (\S+)\)", str(info.value))[1])
    for off in (1e-9, 1e-8):  # printed to two digits
        assert printed[1e-3, off] == pytest.approx(printed[1.0, off], rel=0.05)
        assert printed[1e3, off] == pytest.approx(printed[1.0, off], rel=0.05)
    assert printed[1.0, 1e-8] == pytest.approx(10 * printed[1.0, 1e-9], rel=0.05)
