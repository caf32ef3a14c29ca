"""The implicit index-3 generalized-alpha integrator (mbd3d.implicit), against references
independent of it: minimal-coordinate equations solved by SciPy, closed-form oscillators,
the explicit integrators on the same model, and its own order of convergence."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mbd3d as mb
from joints import Prismatic, Revolute
from mbd3d.mechanisms import pendulum_chain, spatial_chain

G = 9.81


def pendulum_reference(t: np.ndarray) -> np.ndarray:
    """Angle of a uniform 1 m, 1 kg bar pinned at one end, released horizontal:
    (J + m c^2) theta'' = -m g c cos(theta)."""
    J, c = 1.0 / 12.0, 0.5
    sol = solve_ivp(lambda _, y: [y[1], -G * c * math.cos(y[0]) / (J + c * c)],
                    (t[0], t[-1]), [0.0, 0.0], t_eval=t, method="DOP853", rtol=1e-12,
                    atol=1e-12)
    return sol.y[0]


def test_pendulum_converges_at_second_order_to_the_minimal_equation():
    model = pendulum_chain(1, angle=0.0)
    t = np.linspace(0.0, 2.0, 21)
    reference = pendulum_reference(t)
    errors = []
    for step in (1e-3, 5e-4, 2.5e-4):
        res = mb.forward_dynamics(model, t, method="generalized-alpha", step=step)
        errors.append(np.max(np.abs(res.body("link1").angle - reference)))
        # index 3: positions on the constraints to the Newton tolerance at every output
        assert res.position_residual.max() < 1e-10 and res.velocity_residual.max() < 1e-8
    assert errors[-1] < 2e-6
    # second order: halving the step divides the error by about four (first order would
    # give two, third order eight; the coarsest step is not yet fully asymptotic)
    for coarse, fine in zip(errors, errors[1:]):
        assert 3.5 < coarse / fine < 6.0


def test_spatial_chain_agrees_with_dop853_through_chart_resets():
    """A spatial double pendulum of ball joints, swinging out of its plane: the Rodrigues
    charts are re-referenced during the run, and both integrators must give one motion."""
    model = spatial_chain(2)
    t = np.linspace(0.0, 1.5, 16)
    qd0 = np.zeros(model.n_coordinates)
    qd0[1] = 1.0  # the first link's centre moves sideways
    explicit = mb.forward_dynamics(model, t, qd0=qd0, method="DOP853", rtol=1e-11, atol=1e-12)
    tips = []
    for step in (1e-3, 5e-4):
        res = mb.forward_dynamics(model, t, qd0=qd0, method="generalized-alpha", step=step)
        assert res.stats["chart_resets"] > 0
        tips.append(res.point("link2", (0.5, 0.0, 0.0)).position)
    reference = explicit.point("link2", (0.5, 0.0, 0.0)).position
    errors = [np.max(np.abs(tip - reference)) for tip in tips]
    assert errors[1] < 1e-4
    assert 3.0 < errors[0] / errors[1] < 5.0
    energy = res.kinetic_energy + res.potential_energy
    assert np.max(np.abs(energy - energy[0])) < 1e-3 * np.max(np.abs(res.kinetic_energy))


def stiff_oscillator(stiffness: float, damping: float) -> mb.Model:
    """A 2 kg slider on a rail along x, held by a spring-damper to a ground point 1 m away."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0))
    block = b.add_body("block", mass=2.0, inertia=0.1, position=(1.01, 0.0))
    b.add(Prismatic("rail", b.ground, block, axis=(1.0, 0.0), point_i=(0.0, 0.0),
                    point_j=(0.0, 0.0)))
    b.add(mb.SpringDamper("spring", b.ground, block, point_i=(0.0, 0.0), point_j=(0.0, 0.0),
                          stiffness=stiffness, damping=damping, free_length=1.0))
    return b.build()


def test_stiff_spring_damper_matches_the_closed_form():
    """x'' + 2 zeta w x' + w^2 x = 0 from x = 1 cm at rest, w = 500 rad/s: the applied-force
    tangent enters the Newton matrix, so steps of a tenth of the period converge."""
    m, k, c = 2.0, 5e5, 200.0
    model = stiff_oscillator(k, c)
    w, zeta = math.sqrt(k / m), c / (2 * math.sqrt(k * m))
    wd = w * math.sqrt(1 - zeta**2)
    t = np.linspace(0.0, 0.05, 51)
    exact = 0.01 * np.exp(-zeta * w * t) * (np.cos(wd * t) + zeta * w / wd * np.sin(wd * t))
    res = mb.forward_dynamics(model, t, method="generalized-alpha", step=2e-5, rho_inf=1.0)
    np.testing.assert_allclose(res.body("block").position[:, 0] - 1.0, exact, atol=2e-6)
    # Newton converges in a few iterations per step: the force tangent is in the matrix
    assert res.stats["newton_iterations"] <= 3 * res.stats["steps"]


def test_bad_integrator_options_are_named():
    model = pendulum_chain(1)
    t = [0.0, 0.1]
    with pytest.raises(mb.ModelError, match="needs a fixed step"):
        mb.forward_dynamics(model, t, method="generalized-alpha")
    with pytest.raises(mb.ModelError, match="step must be a positive"):
        mb.forward_dynamics(model, t, method="generalized-alpha", step=-1e-3)
    with pytest.raises(mb.ModelError, match="rho_inf must be between 0 and 1"):
        mb.forward_dynamics(model, t, method="generalized-alpha", step=1e-3, rho_inf=1.5)
    with pytest.raises(mb.ModelError, match="step applies to method='generalized-alpha'"):
        mb.forward_dynamics(model, t, method="RK45", step=1e-3)
    with pytest.raises(mb.ModelError, match="generalized-alpha"):
        mb.forward_dynamics(model, t, method="Euler")
