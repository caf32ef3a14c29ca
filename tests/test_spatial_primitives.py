"""Spatial bodies: every joint's Jacobian and gamma (gear meshes' included) against finite
differences of C, with the bodies in random charts (reference rotations), and the mass matrix
and quadratic velocity vector against the kinetic energy."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import mbd3d as mb
from mbd3d.model import constraints
from mbd3d.model.equations import generalized_forces, kinetic_energy
from mbd3d.joints import (Cylindrical, Distance, Fixed, GearPair, Planar, PointOnLine,
                          PointOnPlane, Prismatic, Revolute, RotationDriver, Spherical,
                          Universal)


def random_spatial_model(seed: int):
    rng = np.random.default_rng(seed)
    b = mb.ModelBuilder(dim=3)
    orientations = Rotation.random(4, random_state=seed).as_matrix()
    bodies = [b.add_body(f"b{k}", mass=1.0 + k, inertia=np.diag([0.2, 0.3, 0.4]) + 0.01 * k,
                         position=rng.normal(size=3), orientation=orientations[k])
              for k in range(4)]
    b0, b1, b2, b3 = bodies
    p = lambda: rng.normal(size=3)  # noqa: E731
    b.add(Spherical("ball", b0, b1, point_i=p(), point_j=p()))
    hinge = b.add(Revolute("hinge", b.ground, b0, point_i=p(), point_j=p(), axis=p()))
    # rotation drivers turning it and a hinge between two moving bodies to and fro: their rows
    # depend on time too
    elbow = b.add(Revolute("elbow", b2, b3, point_i=p(), point_j=p(), axis=p()))
    b.add(RotationDriver("turn", hinge, motion=mb.Harmonic(0.7, 2.3, phase=0.4, offset=0.2)))
    b.add(RotationDriver("bend", elbow, motion=mb.Harmonic(0.5, 1.9, phase=1.1, offset=-0.3)))
    b.add(Prismatic("slide", b1, b2, axis=p(), point_i=p(), point_j=p()))
    b.add(Universal("cardan", b2, b3, axis_i=(1, 0, 0), axis_j=(0, 1, 0), point_i=p(),
                    point_j=p()))
    b.add(Cylindrical("cyl", b0, b3, axis=p(), point_i=p(), point_j=p()))
    b.add(Distance("link", b1, b3, point_i=p(), point_j=p(), length=1.7))
    b.add(Planar("plane", b.ground, b2, axis=p(), point_i=p(), point_j=p()))
    b.add(PointOnLine("line", b0, b2, axis=p(), point_i=p(), point_j=p()))
    b.add(PointOnPlane("surface", b3, b1, axis=p(), point_i=p(), point_j=p()))
    b.add(Fixed("weld", b1, b3, point_i=p(), point_j=p()))
    # a spur pair (parallel axes, centres the pitch radii apart across them) and a bevel pair
    # (axes meeting at an apex)
    axis, centre = p(), p()
    across = np.cross(axis, p())
    b.add(GearPair("spur", b0, b2, radius_i=0.5, radius_j=0.3, axis_i=axis, center_i=centre,
                   center_j=centre + 0.8 * across / np.linalg.norm(across)))
    apex, h_i, h_j = p(), p(), p()
    b.add(GearPair("bevel", b1, b3, radius_i=0.4, radius_j=0.6, axis_i=h_i, axis_j=h_j,
                   center_i=apex + 0.7 * h_i, center_j=apex - 0.5 * h_j))
    model = b.build()
    q = model.q0 + 0.3 * rng.normal(size=model.n_coordinates)
    qd = rng.normal(size=model.n_coordinates)
    charts = np.tile(np.eye(3), (model.n_bodies + 1, 1, 1))
    charts[:-1] = Rotation.random(model.n_bodies, random_state=seed + 100).as_matrix()
    return model, q, qd, charts


#: the time at which the rows are evaluated: the driver's motion, its rate and its
#: acceleration are all non-zero there
T0 = 0.37


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_spatial_jacobian_equals_central_differences(seed):
    model, q, _, charts = random_spatial_model(seed)
    C = lambda x: constraints.residual(model, T0, x, constraints.frames(model, x, charts=charts))  # noqa: E731
    Cq = constraints.jacobian(model, T0, q, constraints.frames(model, q, charts=charts), sparse=False)
    h = 1e-6
    fd = np.column_stack([(C(q + h * e) - C(q - h * e)) / (2 * h) for e in np.eye(len(q))])
    np.testing.assert_allclose(Cq, fd, rtol=0, atol=2e-8)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_spatial_gamma_equals_second_directional_derivative(seed):
    """Along ``(q + s qd, T0 + s)`` the accelerations are zero, so ``d2C/ds2 = -gamma``,
    the time-dependent terms of the driver's row included."""
    model, q, qd, charts = random_spatial_model(seed)

    def C(s: float) -> np.ndarray:
        x = q + s * qd
        return constraints.residual(model, T0 + s, x, constraints.frames(model, x, charts=charts))

    gamma = constraints.acceleration_rhs(model, T0, q, qd,
                                         constraints.frames(model, q, qd, charts=charts))
    h = 1e-3
    second = (-C(2 * h) + 16 * C(h) - 30 * C(0.0) + 16 * C(-h) - C(-2 * h)) / (12 * h * h)
    np.testing.assert_allclose(gamma, -second, rtol=0, atol=1e-6)


def test_mass_matrix_and_quadratic_velocity_follow_from_kinetic_energy():
    # Lagrange: for a free body, M qdd = Qv + Q with Qv = dT/dq - Mdot qd; check both sides
    # along a path q + e qd with derivatives of T by central differences
    model, q, qd, charts = random_spatial_model(3)
    T = lambda x, v: kinetic_energy(model, x, v, charts=charts)  # noqa: E731
    fr = constraints.frames(model, q, qd, charts=charts)
    blocks = model.body_type.mass_blocks(fr, model.mass, model.inertia)
    M = np.zeros((len(q), len(q)))
    for k in range(model.n_bodies):
        M[6 * k:6 * k + 6, 6 * k:6 * k + 6] = blocks[k]
    assert T(q, qd) == pytest.approx(0.5 * qd @ M @ qd, rel=1e-13)
    h = 1e-6
    dT_dq = np.array([(T(q + h * e, qd) - T(q - h * e, qd)) / (2 * h) for e in np.eye(len(q))])
    fr_plus = constraints.frames(model, q + h * qd, charts=charts)
    fr_minus = constraints.frames(model, q - h * qd, charts=charts)
    M_dot_blocks = (model.body_type.mass_blocks(fr_plus, model.mass, model.inertia)
                    - model.body_type.mass_blocks(fr_minus, model.mass, model.inertia)) / (2 * h)
    M_dot_qd = np.concatenate([M_dot_blocks[k] @ qd[6 * k:6 * k + 6]
                               for k in range(model.n_bodies)])
    Qv = model.body_type.quadratic_velocity(fr, model.mass, model.inertia).ravel()
    np.testing.assert_allclose(Qv, dT_dq - M_dot_qd, rtol=0, atol=1e-7)
    # gravity-free model without force elements: the generalized forces are Qv alone
    np.testing.assert_allclose(generalized_forces(model, 0.0, fr), Qv, rtol=0, atol=1e-15)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_gear_meshes_are_in_mesh_as_drawn(seed):
    """The drawing is in mesh: each gear row vanishes there, whatever the bodies' poses (the
    rest of the random model's joints are not assembled)."""
    model = random_spatial_model(seed)[0]
    C = constraints.residual(model, T0, model.q0, constraints.frames(model, model.q0,
                                                                     charts=model.charts0))
    for mesh in ("spur", "bevel"):
        np.testing.assert_allclose(C[model.rows_of(mesh)], 0.0, rtol=0, atol=1e-14)
