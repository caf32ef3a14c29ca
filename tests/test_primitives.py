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
from mbd3d.joints import Distance, Fixed, PointOnLine, Prismatic, Revolute, RotationDriver


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


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_jacobian_equals_central_differences(seed):
    model, q, _ = random_model(seed)
    Cq = constraints.jacobian(model, 0.0, q, sparse=False)
    h = 1e-6
    fd = np.empty_like(Cq)
    for j in range(model.n_coordinates):
        e = np.zeros_like(q)
        e[j] = h
        fd[:, j] = (constraints.residual(model, 0.0, q + e)
                    - constraints.residual(model, 0.0, q - e)) / (2 * h)
    np.testing.assert_allclose(Cq, fd, atol=1e-8)


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
    np.testing.assert_allclose(gamma, -second, atol=1e-7)


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
