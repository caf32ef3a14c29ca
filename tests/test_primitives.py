"""Every constraint primitive against finite differences of its own constraint function.

The Jacobian must equal the central difference of ``C`` with respect to each coordinate, and
``gamma`` must equal ``-d2/de2 C(q + e qd)`` at ``e = 0`` (for constraints without explicit time
dependence, ``(Cq qd)_q qd`` is the second directional derivative of ``C`` along ``qd``). Both
oracles use only the values of ``C``, not the analytic derivatives under test.
"""

from __future__ import annotations

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.model import constraints
from mbd3d.joints import (CamFollower, CamProfile, Distance, FlatFaceFollower, Fixed, GearPair,
                          PointOnLine, Prismatic, RackPinion, Revolute, RotationDriver)


def random_model(seed: int):
    """Three bodies at random poses with one of each joint type, not assembled."""
    rng = np.random.default_rng(seed)
    b = mb.ModelBuilder(dim=2)
    bodies = [b.add_body(f"b{k}", mass=1.0 + k, inertia=0.1 + 0.05 * k,
                         position=rng.normal(size=2), angle=rng.uniform(-3, 3)) for k in range(3)]
    b0, b1, b2 = bodies
    b.add(Revolute("rev", b0, b1, point_i=rng.normal(size=2), point_j=rng.normal(size=2)))
    b.add(Revolute("rev_ground", b.ground, b2, point_i=rng.normal(size=2),
                   point_j=rng.normal(size=2)))
    b.add(Prismatic("pri", b1, b2, axis=rng.normal(size=2), point_i=rng.normal(size=2),
                    point_j=rng.normal(size=2)))
    b.add(Distance("dist", b0, b2, point_i=rng.normal(size=2), point_j=rng.normal(size=2),
                   length=1.3))
    b.add(Fixed("weld", b.ground, b0, point_i=rng.normal(size=2), point_j=rng.normal(size=2)))
    b.add(RotationDriver("drive", b0, b1, motion=mb.Constant(0.4)))
    b.add(PointOnLine("slot", b1, b0, axis=rng.normal(size=2), point_i=rng.normal(size=2),
                      point_j=rng.normal(size=2)))
    model = b.build()
    q = model.q0 + 0.3 * rng.normal(size=model.n_coordinates)
    qd = rng.normal(size=model.n_coordinates)
    return model, q, qd


def unit(rng) -> np.ndarray:
    v = rng.normal(size=2)
    return v / np.linalg.norm(v)


def random_higher_pairs(seed: int):
    """The planar higher pairs between free bodies at random poses, not assembled: an external
    and an internal gear pair, a rack and pinion, a roller and a flat-faced follower on one
    cam. Every centre and point is off its body's centre of mass and every body turns, so no
    term of their rows vanishes (a flat face's normal turns with its rocking follower)."""
    rng = np.random.default_rng(seed)
    b = mb.ModelBuilder(dim=2)
    names = ("pinion", "wheel", "ring", "rack", "spur", "cam", "roller", "face")
    angles = dict(zip(names, rng.uniform(-3, 3, size=len(names))))
    bodies = {name: b.add_body(name, mass=1.0, inertia=0.1, position=rng.normal(size=2),
                               angle=angles[name]) for name in names}
    centre = rng.normal(size=2)
    b.add(GearPair("external", bodies["pinion"], bodies["wheel"], radius_i=0.3, radius_j=0.5,
                   center_i=centre, center_j=centre + 0.8 * unit(rng)))
    b.add(GearPair("internal", bodies["pinion"], bodies["ring"], radius_i=0.3, radius_j=0.9,
                   internal=True, center_i=centre, center_j=centre + 0.6 * unit(rng)))
    b.add(RackPinion("rack_mesh", bodies["rack"], bodies["spur"], radius=0.2, axis=unit(rng),
                     center=rng.normal(size=2)))
    # one cam, off-centre, with a smooth pitch curve and support function
    profile = CamProfile.sampled(lambda phi: 0.5 + 0.08 * np.cos(phi) + 0.03 * np.sin(2 * phi))
    cam, theta = rng.normal(size=2), angles["cam"]
    towards = unit(rng)
    polar = np.arctan2(towards[1], towards[0]) - theta
    b.add(CamFollower("roller_contact", bodies["cam"], bodies["roller"], profile=profile,
                      center=cam, point=cam + float(profile(polar)) * towards))
    normal = unit(rng)  # from the face towards the cam: the cam's outward normal is -normal
    psi = np.arctan2(-normal[1], -normal[0]) - theta
    along = np.array([-normal[1], normal[0]])
    at = cam - float(profile(psi)) * normal + 0.2 * rng.normal() * along
    b.add(FlatFaceFollower("face_contact", bodies["cam"], bodies["face"], profile=profile,
                           normal=normal, center=cam, at=at))
    model = b.build()
    q = model.q0 + 0.3 * rng.normal(size=model.n_coordinates)
    qd = rng.normal(size=model.n_coordinates)
    return model, q, qd


MODELS = [(random_model, seed) for seed in range(4)] + [(random_higher_pairs, seed)
                                                        for seed in range(4)]


@pytest.mark.parametrize("build, seed", MODELS)
def test_jacobian_equals_central_differences(build, seed):
    model, q, _ = build(seed)
    Cq = constraints.jacobian(model, 0.0, q, sparse=False)
    h = 1e-6
    fd = np.empty_like(Cq)
    for j in range(model.n_coordinates):
        e = np.zeros_like(q)
        e[j] = h
        fd[:, j] = (constraints.residual(model, 0.0, q + e)
                    - constraints.residual(model, 0.0, q - e)) / (2 * h)
    np.testing.assert_allclose(Cq, fd, rtol=0, atol=1e-8)


@pytest.mark.parametrize("build, seed", MODELS)
def test_gamma_equals_the_jacobians_rate_along_qd(build, seed):
    """``gamma = -d/de (Cq(q + e qd) qd)`` at ``e = 0``, by a central first difference of the
    Jacobian (itself checked against ``C`` above). A first difference needs only the second
    derivative of a cam's spline to be continuous; the second difference of ``C`` below also
    sees the jumps of its third derivative at the knots (about 1e-6 here), and serves the
    rows without splines."""
    model, q, qd = build(seed)
    gamma = constraints.acceleration_rhs(model, 0.0, q, qd)
    h = 1e-6
    rate = (constraints.jacobian(model, 0.0, q + h * qd, sparse=False) @ qd
            - constraints.jacobian(model, 0.0, q - h * qd, sparse=False) @ qd) / (2 * h)
    np.testing.assert_allclose(gamma, -rate, rtol=0, atol=1e-8)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_gamma_equals_second_directional_derivative(seed):
    model, q, qd = random_model(seed)
    gamma = constraints.acceleration_rhs(model, 0.0, q, qd)
    # rounding of the stencil is ~eps |C| / h^2, truncation ~h^4: h = 1e-3 balances them
    h = 1e-3
    C = lambda x: constraints.residual(model, 0.0, x)  # noqa: E731
    # fourth-order central second difference: error O(h^4)
    second = (-C(q + 2 * h * qd) + 16 * C(q + h * qd) - 30 * C(q) + 16 * C(q - h * qd)
              - C(q - 2 * h * qd)) / (12 * h * h)
    np.testing.assert_allclose(gamma, -second, rtol=0, atol=1e-7)


def test_sparse_and_dense_jacobians_agree():
    model, q, _ = random_model(5)
    dense = constraints.jacobian(model, 0.0, q, sparse=False)
    sparse = constraints.jacobian(model, 0.0, q, sparse=True).toarray()
    np.testing.assert_array_equal(dense, sparse)


def test_driver_rows_carry_exact_time_derivatives():
    # C = theta_j - theta_i - f(t): velocity rhs f', acceleration rhs gets f''
    b = mb.ModelBuilder(dim=2)
    body = b.add_body("b", mass=1.0, inertia=1.0, position=(0, 0))
    b.add(Revolute("pin", b.ground, body, at=(0, 0)))
    motion = mb.Harmonic(0.5, 3.0, phase=0.2)
    b.add(RotationDriver("drive", b.ground, body, motion=motion))
    model = b.build()
    t = 0.37
    f, df, d2f = motion.evaluate(t)
    row = model.rows_of("drive")[0]
    assert constraints.velocity_rhs(model, t)[row] == pytest.approx(df, rel=1e-15)
    q = model.q0
    assert constraints.acceleration_rhs(model, t, q, np.zeros(3))[row] == pytest.approx(d2f)
    assert constraints.residual(model, t, q)[row] == pytest.approx(-f)
