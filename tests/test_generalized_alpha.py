"""The implicit index-3 generalized-alpha integrator (mbd3d.analyses.implicit), against references
independent of it: minimal-coordinate equations solved by SciPy, closed-form oscillators,
the explicit integrators on the same model, and its own order of convergence."""

from __future__ import annotations

import math
import re
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mbd3d as mb
from mbd3d.joints import Prismatic, Revolute
from mbd3d.mechanisms import pendulum_chain, slider_crank, spatial_chain
from mbd3d.analyses.implicit import GeneralizedAlphaIntegrator
from test_examples import load
from test_published_problems import four_bar_oscillator

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
    assert res.singular_passages == []  # a regular motion, through the resets
    # outputs between the step ends: interpolated in each step's chart, as accurate
    between = np.r_[0.0, t[1:-1] + 3.7e-4, t[-1]]
    explicit = mb.forward_dynamics(model, between, qd0=qd0, method="DOP853", rtol=1e-11,
                                   atol=1e-12)
    res = mb.forward_dynamics(model, between, qd0=qd0, method="generalized-alpha", step=5e-4)
    tip = res.point("link2", (0.5, 0.0, 0.0)).position
    assert np.max(np.abs(tip - explicit.point("link2", (0.5, 0.0, 0.0)).position)) < 1e-4
    assert np.max(np.abs(res.position_residual)) < 1e-10


def test_steps_shortened_at_a_stop_pass_no_singular_position():
    """The indicator of singular positions, log|det S| - n log beta' - log det M, is free of
    the step: a slider-crank falling from level whose slider strikes a stop has its steps
    cut a hundredfold while each strike lasts (beta' 1e4 times larger: n log 1e4 = 83 for
    the nine coordinates, far more than the dip that marks a passage), and, regular all
    along, reports no passage."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    crank = b.add_body("crank", mass=1.0, inertia=1e-3, position=(0.05, 0.0))
    rod = b.add_body("rod", mass=1.5, inertia=0.01, position=(0.25, 0.0))
    slider = b.add_body("slider", mass=0.5, inertia=1e-3, position=(0.4, 0.0))
    b.add(Revolute("O", b.ground, crank, at=(0.0, 0.0)))
    b.add(Revolute("A", crank, rod, at=(0.1, 0.0)))
    b.add(Revolute("B", rod, slider, at=(0.4, 0.0)))
    rail = b.add(Prismatic("rail", b.ground, slider, at=(0.4, 0.0), axis=(1.0, 0.0)))
    b.add(mb.JointLimit("stop", rail, lower=-0.03,
                        law=mb.LinearContact(stiffness=1e6, restitution=0.5)))
    res = mb.forward_dynamics(b.build(), np.linspace(0.0, 1.0, 101),
                              method="generalized-alpha", step=1e-3)
    assert np.any(res.contacts().normal_force[:, 0] > 0)  # it struck
    assert res.stats["steps"] > 1100  # steps cut while it did
    assert res.singular_passages == []


@pytest.mark.parametrize("build", [lambda: pendulum_chain(1, angle=0.0),
                                   lambda: pendulum_chain(12, link_mass=2.7, link_length=0.8),
                                   lambda: slider_crank(crank_speed=None),
                                   lambda: spatial_chain(2)],
                         ids=["pendulum", "banded chain", "closed loop", "spatial"])
def test_newton_converges_in_two_iterations_a_step(build):
    """The iteration matrix ``beta' M + p Cq^T Cq`` is the residual's exact derivative (less
    the velocity terms', of the step's order), so Newton converges quadratically from the
    predictor: at steps of 1 ms the first iteration corrects it and the second confirms (one
    suffices where the predictor is already right). A matrix off in a term converges linearly
    and takes more."""
    model = build()
    res = mb.forward_dynamics(model, np.linspace(0.0, 0.5, 6), method="generalized-alpha",
                              step=1e-3)
    assert res.stats["steps"] == 500
    assert res.stats["newton_iterations"] <= 2 * res.stats["steps"]
    # and each iteration factors its matrix once
    assert res.stats["factorizations"] == res.stats["newton_iterations"]


def test_newton_closes_the_constraints_of_a_whipping_crank_in_two_iterations_a_step():
    """The free slider-crank turning at 30 to 80 rad/s: at 1e-3 s the predictor misses by up
    to 1e-3 of the crank, and the first Newton step leaves the constraints open by its square
    (1e-10 of the rod). The multipliers' own Newton step (``lam += p (C + Cq dq)``) lets the
    second step close them to rounding, and the test at the iterate it reaches saves the
    third factorization: about 2.1 iterations a step. Updated with ``C`` at the new iterate,
    the multipliers flipped the constraints' sign instead (3.7 a step, and a step at
    t = 0.11 s rejected); tested before the step rather than after, 2.9."""
    model = slider_crank(crank_speed=None)
    guess = np.zeros(model.n_coordinates)
    guess[model.coordinate_index("crank.theta")] = 30.0
    qd0 = mb.solve_velocity(model, model.q0, qd_guess=guess, hold=["crank.theta"])
    res = mb.forward_dynamics(model, np.linspace(0.0, 0.5, 501), qd0=qd0,
                              method="generalized-alpha", step=1e-3)
    assert (res.stats["steps"], res.stats["rejected_steps"]) == (500, 0)
    assert res.stats["newton_iterations"] <= 2.3 * res.stats["steps"]
    assert np.max(np.abs(res.body("crank").angular_velocity)) > 70.0  # it whipped


def test_a_fully_driven_mechanism_moves_and_pushes_as_its_inverse_dynamics_say():
    """A crank driven harmonically, a Distance rod (its row's constant is the length) to a
    slider turned 0.4 rad on its rail (a constant kept by the rail's rotation row): fully
    driven, so generalized-alpha must reproduce the kinematic inverse dynamics, the positions
    to the Newton tolerance, the rates it reports and the motor's effort with them (the
    drivers' motions and the rows' constants enter its residual as they enter the position
    analysis)."""
    from test_slider_crank import _offset_slider_crank

    model = _offset_slider_crank(1.0)
    assert np.any(model.c0 != 0.0)
    t = np.linspace(0.0, 1.0, 11)
    res = mb.forward_dynamics(model, t, method="generalized-alpha", step=1e-3)
    reference = mb.inverse_dynamics(model, t)
    np.testing.assert_allclose(res.q, reference.q, rtol=0, atol=1e-10)
    # the reported rates are projected onto Cq qd = -Ct, the driver's rate included
    np.testing.assert_allclose(res.qd, reference.qd, rtol=0,
                               atol=1e-8 * np.max(np.abs(reference.qd)))
    effort = reference.joint("motor").effort
    np.testing.assert_allclose(res.joint("motor").effort, effort, rtol=0,
                               atol=1e-8 * np.max(np.abs(effort)))


def stiff_oscillator(stiffness: float, damping: float) -> mb.Model:
    """A 2 kg slider on a rail along x, held by a spring-damper to a ground point 1 m away."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0))
    block = b.add_body("block", mass=2.0, inertia=0.1, position=(1.01, 0.0))
    b.add(Prismatic("rail", b.ground, block, axis=(1.0, 0.0), point_i=(0.0, 0.0),
                    point_j=(0.0, 0.0)))
    b.add(mb.SpringDamper("spring", b.ground, block, point_i=(0.0, 0.0), point_j=(0.0, 0.0),
                          stiffness=stiffness, damping=damping, free_length=1.0))
    return b.build()


def test_feedback_forces_enter_newton_through_every_coordinate_they_depend_on():
    """A free 2 kg body (the model's second) held by a feedback force on its centre,
    -k (r - r0) - c r', and a feedback torque, -kt theta - ct theta' (Python functions of the
    state: their tangent is differenced over the body's three coordinates), all three at
    500 rad/s: steps of a tenth of the period converge in two Newton iterations (a coordinate
    left out of the differences converges by a tenth a step), and fine steps follow the three
    damped oscillations."""
    m, inertia, w, zeta = 2.0, 0.1, 500.0, 0.02
    k, kt = m * w * w, inertia * w * w
    c, ct = 2 * zeta * w * m, 2 * zeta * w * inertia
    b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0))
    b.add_body("idle", mass=1.0, inertia=1.0, position=(0.0, 0.0))  # body 0: no force on it
    body = b.add_body("body", mass=m, inertia=inertia, position=(1.01, -0.01), angle=0.02)
    b.add(mb.PointForce("tether", body, force=lambda t, s: -k * (s.position - (1.0, 0.0))
                        - c * s.velocity))
    b.add(mb.Torque("twist", body, torque=lambda t, s: -kt * s.angle - ct * s.angular_velocity))
    model = b.build()
    period = 2 * math.pi / w
    coarse = mb.forward_dynamics(model, np.linspace(0.0, 10 * period, 11),
                                 method="generalized-alpha", step=0.1 * period, rho_inf=1.0)
    assert coarse.stats["newton_iterations"] <= 2 * coarse.stats["steps"]
    t = np.linspace(0.0, 2 * period, 21)
    h = period / 1000
    fine = mb.forward_dynamics(model, t, method="generalized-alpha", step=h, rho_inf=1.0)
    wd = w * math.sqrt(1 - zeta ** 2)
    decay = np.exp(-zeta * w * t) * (np.cos(wd * t) + zeta * w / wd * np.sin(wd * t))
    # the method's phase error, (h w)^2 / 12 of a radian per radian, over the 4 pi swung
    phase = (h * w) ** 2 / 12 * w * t[-1]
    np.testing.assert_allclose(fine.q[:, 3:], np.outer(decay, [0.01, -0.01, 0.02])
                               + [1.0, 0.0, 0.0], rtol=0, atol=2 * phase * 0.02)
    np.testing.assert_array_equal(fine.q[:, :3], 0.0)


def test_free_slider_crank_recovers_from_rejected_steps_without_diverging(monkeypatch):
    """The free slider-crank started at 30 rad/s whips its light crank up to 80 rad/s near
    t = 0.11 s, where a step of 1e-3 s needs more Newton iterations than elsewhere: with
    Newton held to 4 of them that step is rejected (with the default 30, Newton converges
    there since its multipliers take their own Newton step). Returning to the nominal step
    at once after each recovery made the recursion diverge there (IntegrationError at
    t = 0.113 s); now the run goes on, the step growing back by doubling (held by the count
    of steps), and the finer step converges to the DOP853 reference."""
    monkeypatch.setattr(GeneralizedAlphaIntegrator, "max_newton_iterations", 4)
    model = slider_crank(crank_speed=None)
    q0 = mb.solve_position(model)
    guess = np.zeros(model.n_coordinates)
    guess[model.coordinate_index("crank.theta")] = 30.0
    qd0 = mb.solve_velocity(model, q0, qd_guess=guess, hold=["crank.theta"])
    t = [0.0, 0.25]
    reference = mb.forward_dynamics(model, t, q0=q0, qd0=qd0, method="DOP853", rtol=1e-12,
                                    atol=1e-14).body("crank").angle[-1]
    errors, runs = [], []
    for step in (1e-3, 5e-4):
        runs.append(mb.forward_dynamics(model, t, q0=q0, qd0=qd0, method="generalized-alpha",
                                        step=step))
        errors.append(abs(runs[-1].body("crank").angle[-1] - reference))
    # at 1e-3 one step is rejected and the step grows back by doubling: h/4, h/2, then h,
    # which leaves h/4 of the last nominal step to a step of its own: 250 + 2 steps (going
    # straight back to h from h/4 would take 250 + 1)
    coarse = runs[0].stats
    assert (coarse["rejected_steps"], coarse["steps"]) == (1, 252)
    assert coarse["smallest_step"] == pytest.approx(0.25e-3, rel=1e-9)
    assert runs[1].stats["rejected_steps"] == 0
    # 0.029 and 0.0032 rad measured: at 1e-3 the step is too long for the whip (about
    # 0.08 rad of crank per step), not unstable
    assert errors[0] < 0.15 and errors[1] < 0.01


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
    np.testing.assert_allclose(res.body("block").position[:, 0] - 1.0, exact, rtol=0, atol=2e-6)
    # at a tenth of the period the spring's stiffness is a tenth of the mass term beta' M:
    # Newton still converges in two iterations a step because the force tangent is in the
    # matrix (without it, or with its sign turned, it converges linearly, by a tenth a step)
    coarse = mb.forward_dynamics(model, t, method="generalized-alpha",
                                 step=0.1 * 2 * math.pi / w, rho_inf=1.0)
    assert coarse.stats["newton_iterations"] <= 2 * coarse.stats["steps"]


def test_bad_integrator_options_are_named():
    model = pendulum_chain(1)
    t = [0.0, 0.1]
    with pytest.raises(mb.ModelError, match="needs a fixed step"):
        mb.forward_dynamics(model, t, method="generalized-alpha")
    with pytest.raises(mb.ModelError, match=r"step \(the fixed time step .*must be positive"):
        mb.forward_dynamics(model, t, method="generalized-alpha", step=-1e-3)
    with pytest.raises(mb.ModelError, match="rho_inf must be between 0 and 1"):
        mb.forward_dynamics(model, t, method="generalized-alpha", step=1e-3, rho_inf=1.5)
    with pytest.raises(mb.ModelError, match="step applies to method='generalized-alpha'"):
        mb.forward_dynamics(model, t, method="RK45", step=1e-3)
    with pytest.raises(mb.ModelError, match="generalized-alpha"):
        mb.forward_dynamics(model, t, method="Euler")
    for multistep in ("BDF", "LSODA"):
        with pytest.raises(mb.ModelError, match=f"{multistep} is a multistep method.*restart"):
            mb.forward_dynamics(model, t, method=multistep)
    with pytest.raises(mb.ModelError, match="Radau is no longer offered.*generalized-alpha"):
        mb.forward_dynamics(model, t, method="Radau")


def crossing_times(t: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Times where ``values`` changes sign, by linear interpolation."""
    k = np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:]))
    return t[k] - values[k] * (t[k + 1] - t[k]) / (values[k + 1] - values[k])


def test_singular_passages_of_the_four_bars_are_reported_at_the_flat_positions():
    """IFToMM A02, N = 2: every time the cranks lie flat (sin phi = 0 in the separately
    derived one-DOF equation) the integration reports a passage, within a step, naming the
    joints of the chain."""
    t = np.linspace(0.0, 6.0, 61)
    res = mb.forward_dynamics(load("iftomm_four_bar").build(2), t, method="generalized-alpha",
                              step=1e-3)
    fine = np.linspace(0.0, 6.0, 60001)
    flat = crossing_times(fine, four_bar_oscillator(2, fine)[:, 1])
    passages = res.singular_passages
    assert len(flat) >= 6 and len(passages) == len(flat)
    np.testing.assert_allclose([p.time for p in passages], flat, rtol=0, atol=1.5e-3)
    assert all({"O0", "B0"} <= set(p.joints) and p.depth > 15 for p in passages)
    assert "t = " in str(passages[0])
    # the explicit methods report none: they stop at the first one
    assert mb.forward_dynamics(load("iftomm_four_bar").build(2), t[:5]).singular_passages == []


def isosceles_slider_crank() -> tuple[mb.Model, np.ndarray]:
    """Crank and rod of equal length, turning freely at 2 pi rad/s without gravity: where the
    crank is vertical the slider reaches the pivot and the rod folds onto the crank, a
    bifurcation of the constraint manifold."""
    model = slider_crank(crank_length=0.2, rod_length=0.2, crank_angle=0.3, crank_speed=None,
                         gravity=0.0)
    guess = np.zeros(model.n_coordinates)
    guess[model.coordinate_index("crank.theta")] = 2 * math.pi
    return model, mb.solve_velocity(model, model.q0, 0.0, qd_guess=guess, hold=["crank.theta"])


def test_isosceles_slider_crank_passes_its_bifurcation_conserving_energy():
    """No force does work, so the kinetic energy is constant; through two passages of the
    singular position its error falls at second order with the step, and the passages are
    reported where the slider crosses the pivot."""
    model, qd0 = isosceles_slider_crank()
    t = np.linspace(0.0, 1.6, 801)
    errors = []
    for step in (1e-3, 5e-4):
        res = mb.forward_dynamics(model, t, qd0=qd0, method="generalized-alpha", step=step)
        energy = res.kinetic_energy
        errors.append(np.max(np.abs(energy - energy[0])) / energy[0])
    assert errors[1] < 2e-4 and 3.5 < errors[0] / errors[1] < 4.5
    assert np.max(res.position_residual) < 1e-10
    slider_x = res.body("slider").position[:, 0]
    crossings = crossing_times(res.t, slider_x)
    assert len(crossings) == 2
    np.testing.assert_allclose([p.time for p in res.singular_passages], crossings,
                               rtol=0, atol=1e-3)
    assert all(set(p.joints) == {"O", "A", "B", "rail"} for p in res.singular_passages)


@pytest.mark.parametrize("dim", [2, 3])
def test_spring_damper_tangent_equals_finite_differences_at_free_length(dim):
    """The iteration matrix's analytic spring-damper tangent against central differences of
    the generalized forces, for turned bodies at rest with the spring at its free length (where
    the terms the tangent leaves out vanish); the damper part is exact at any state."""
    from mbd3d.model import constraints
    from mbd3d.model.equations import generalized_forces
    from mbd3d.analyses.alpha_step import force_tangent
    from mbd3d.numerics.rotations import axis_angle
    rng = np.random.default_rng(7)
    b = mb.ModelBuilder(dim=dim)
    pose = {"angle": 0.7} if dim == 2 else {"orientation": axis_angle(rng.normal(size=3), 0.9)}
    other = {"angle": -0.4} if dim == 2 else {"orientation": axis_angle(rng.normal(size=3), 1.3)}
    one = b.add_body("one", mass=1.0, inertia=0.1 if dim == 2 else (0.1, 0.2, 0.3),
                     position=rng.normal(size=dim), **pose)
    two = b.add_body("two", mass=2.0, inertia=0.2 if dim == 2 else (0.3, 0.2, 0.1),
                     position=rng.normal(size=dim), **other)
    b.add(mb.SpringDamper("spring", one, two, point_i=rng.normal(size=dim),
                          point_j=rng.normal(size=dim), stiffness=300.0, damping=7.0))
    b.add(mb.SpringDamper("anchor", b.ground, two, point_i=rng.normal(size=dim),
                          point_j=rng.normal(size=dim), stiffness=50.0, damping=2.0))
    model = b.build()
    q, qd = model.q0, np.zeros(model.n_coordinates)
    weight = 40.0
    analytic = force_tangent(model, 0.0, q, qd, model.charts0, weight)
    analytic = analytic.toarray() if hasattr(analytic, "toarray") else analytic
    numeric = np.empty_like(analytic)
    for j in range(model.n_coordinates):
        e = np.zeros_like(q)
        e[j] = 1e-6
        Q = [generalized_forces(model, 0.0, constraints.frames(model, *state, model.charts0))
             for state in ((q + e, qd), (q - e, qd), (q, qd + e), (q, qd - e))]
        numeric[:, j] = -(Q[0] - Q[1]) / 2e-6 - weight * (Q[2] - Q[3]) / 2e-6
    np.testing.assert_allclose(analytic, numeric, rtol=0, atol=1e-6 * np.max(np.abs(numeric)))


def _differenced_tangent(model, q, qd, charts, weight, h=1e-7):
    """``-dQ/dq - weight dQ/dqd`` of the force elements (not the bodies' quadratic velocity
    terms, which the iteration matrix leaves out) by central differences, and the two parts
    apart."""
    from mbd3d.model import constraints

    def Q(x, xd):
        out = np.zeros((model.n_bodies + 1, model.n_coords_per_body))
        for group in model.force_groups:
            group.apply(model, 0.0, constraints.frames(model, x, xd, charts), out)
        return out[:-1].ravel()
    eye = np.eye(len(q)) * h
    K = -np.column_stack([(Q(q + e, qd) - Q(q - e, qd)) / (2 * h) for e in eye])
    D = -np.column_stack([(Q(q, qd + e) - Q(q, qd - e)) / (2 * h) for e in eye])
    return K + weight * D, K, D


def _contact_tangent(model, q, qd, charts, weight):
    from mbd3d.analyses.alpha_step import force_tangent
    T = force_tangent(model, 0.0, q, qd, charts, weight)
    return T.toarray() if hasattr(T, "toarray") else T


@pytest.mark.parametrize("dim", [2, 3])
def test_contact_tangent_equals_finite_differences_where_nothing_is_left_out(dim):
    """The iteration matrix's analytic contact tangent against central differences of the
    generalized forces: whole for a frictionless ball pressed into the floor while it slides
    and spins (the normal is fixed and the force passes through the centre, so the terms the
    tangent leaves out vanish), and its velocity part, exact at any state, with friction, a
    damped Hertz law and a sphere against a sphere on two turned, moving bodies."""
    from test_contacts import _overlapping_state, _spatial_pair
    rng = np.random.default_rng(11)
    weight = 1e3
    # Hunt-Crossley; Adams' IMPACT with its damping ramp two thirds of the way in at 2 mm
    for law in (mb.HuntCrossley(stiffness=3e6, restitution=0.6, impact_speed=1.0, exponent=1.5),
                mb.ImpactFunction(stiffness=3e6, damping=300.0, penetration=3e-3)):
        b = mb.ModelBuilder(dim=dim)
        ball = b.add_body("ball", mass=1.3, inertia=0.02 if dim == 2 else (0.02, 0.03, 0.025),
                          position=(0.3, 0.5) if dim == 2 else (0.3, 0.5, 0.4))
        up = (0.6, 0.8) if dim == 2 else (0.0, 0.6, 0.8)
        b.add(mb.Contact("floor", mb.Sphere(ball, 0.1), mb.Plane(b.ground, normal=up), law=law))
        model = b.build()
        q = model.q0.copy()
        q[:dim] += (0.098 - np.asarray(up) @ q[:dim]) * np.asarray(up)  # 2 mm into the floor
        qd = rng.normal(size=model.n_coordinates)
        qd[:dim] -= (np.asarray(up) @ qd[:dim] + 0.3) * np.asarray(up)  # closing at 0.3 m/s
        numeric, _, _ = _differenced_tangent(model, q, qd, model.charts0, weight)
        analytic = _contact_tangent(model, q, qd, model.charts0, weight)
        assert np.abs(numeric).max() > 1e5  # pressed: the law's stiffness at 2 mm
        np.testing.assert_allclose(analytic, numeric, rtol=0,
                                   atol=1e-6 * np.abs(numeric).max())
    if dim == 2:
        return
    for second in ("plane", "sphere"):
        pair, charts, data = _spatial_pair(second, mb.HertzContact(stiffness=4e6, restitution=0.5),
                                           friction=0.4)
        q = _overlapping_state(pair, charts, data, second, rng)
        # slipping at about the slip velocity, 0.05 m/s; then at rest (no slip: friction's
        # slope there is its steepest, mu F_n / v_slip, the same every way in the plane)
        for qd in (rng.normal(size=12) * 0.03, np.zeros(12)):
            _, _, D = _differenced_tangent(pair, q, qd, charts, weight)
            velocity_part = (_contact_tangent(pair, q, qd, charts, weight)
                             - _contact_tangent(pair, q, qd, charts, 0.0)) / weight
            assert np.abs(D).max() > 10.0
            np.testing.assert_allclose(velocity_part, D, rtol=0, atol=1e-6 * np.abs(D).max())


@pytest.mark.parametrize("hole, dim", [(False, 3), (True, 2), (True, 3)])
def test_contact_tangent_turns_the_normal_between_centres(hole, dim):
    """Two spheres pressed together (spatial, turned bodies) and a pin pressed into the wall of
    its hole, each shape centred on its body, away from the origin: the normal turns as the
    centres move, a stiffness of the force over the centres' distance, negative between
    spheres, positive in the hole (none along a spatial hole's axis); the whole tangent
    against central differences, the relative velocity along the normal (so that the
    damper's rate does not turn with it). In a spatial hole the axis turns with the hole, a
    term the tangent leaves out: there the translations' block."""
    law = mb.HuntCrossley(stiffness=3e6, restitution=0.6, impact_speed=1.0, exponent=1.5)
    b = mb.ModelBuilder(dim=dim)
    centre = np.array([0.3, -0.2, 0.5])[:dim]
    one = b.add_body("one", mass=1.0, inertia=0.01 if dim == 2 else (0.01, 0.02, 0.03),
                     position=centre)
    d = np.array([0.6, 0.8]) if dim == 2 else np.array([0.48, 0.6, 0.64])  # unit
    if hole and dim == 3:
        d = np.array([0.6, 0.8, 0.0])  # square to the hole's axis, z
    gap = 0.002
    two = b.add_body("two", mass=2.0, inertia=0.03 if dim == 2 else (0.03, 0.02, 0.01),
                     position=centre + d * ((0.1 - gap) if not hole else 0.003 + gap))
    if hole:  # pin radius 0.05 in a hole 0.053: the pin 3 mm + 2 mm off the hole's centre
        axis = {} if dim == 2 else {"axis": (0.0, 0.0, 1.0)}
        b.add(mb.Contact("pin", mb.Sphere(one, 0.05), mb.Hole(two, 0.053, **axis), law=law))
    else:
        b.add(mb.Contact("pair", mb.Sphere(one, 0.04), mb.Sphere(two, 0.06), law=law))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mb.ContactWarning)  # they overlap in the drawing
        model = b.build()
    q, qd = model.q0.copy(), np.zeros(model.n_coordinates)
    if not hole:
        q[3:6], q[9:12] = (0.3, -0.2, 0.5), (-0.4, 0.1, 0.2)
    nc = model.n_coords_per_body
    qd[nc:nc + dim] = (-0.2 if not hole else 0.2) * d   # closing
    weight = 500.0
    numeric, K, _ = _differenced_tangent(model, q, qd, model.charts0, weight)
    analytic = _contact_tangent(model, q, qd, model.charts0, weight)
    assert np.abs(K).max() > 1e4
    if hole and dim == 3:
        moves = np.r_[0:3, 6:9]
        numeric, analytic = numeric[np.ix_(moves, moves)], analytic[np.ix_(moves, moves)]
        assert abs(numeric[2, 2]) < 1e-6 * np.abs(numeric).max()  # along the axis: none
    np.testing.assert_allclose(analytic, numeric, rtol=0, atol=1e-6 * np.abs(numeric).max())


def _hinged_bars(dim: int, law) -> mb.Model:
    """Two free bars hinged at their ends (axis z), the hinge limited to +-0.5 rad."""
    b = mb.ModelBuilder(dim=dim)
    inertia = 0.1 if dim == 2 else np.diag([0.01, 0.1, 0.1])
    first = b.add_body("first", mass=1.0, inertia=inertia, position=(0.5,) + (0.0,) * (dim - 1))
    second = b.add_body("second", mass=1.5, inertia=inertia,
                        position=(1.5,) + (0.0,) * (dim - 1))
    hinge = b.add(Revolute("hinge", first, second, at=(1.0,) + (0.0,) * (dim - 1),
                           axis=None if dim == 2 else (0.0, 0.0, 1.0)))
    b.add(mb.JointLimit("stop", hinge, lower=-0.5, upper=0.5, law=law))
    return b.build()


@pytest.mark.parametrize("dim", [2, 3])
def test_stop_tangent_equals_finite_differences(dim):
    """A slider past its upper stop (the force along a fixed axis through the block's centre)
    and, in the plane, a pendulum past its hinge stop and two free bars past theirs (the angle
    linear in both bodies' coordinates): the whole tangent exact; in space the hinges'
    velocity part (their axes turn with the bodies, which the tangent leaves out)."""
    from test_contacts import _pendulum, _slider
    law = mb.HuntCrossley(stiffness=2e5, restitution=0.7, impact_speed=0.5, exponent=1.0)
    slider = _slider(dim, law)
    pendulum, _, _ = _pendulum(dim, law, lower=-0.5)
    bars = _hinged_bars(dim, law)
    rng = np.random.default_rng(5)
    for model in (slider, pendulum, bars):
        q, qd = model.q0.copy(), rng.normal(size=model.n_coordinates)
        if model is slider:  # the block 3 mm past the stop, moving on into it
            q[0], qd[0] = 0.203, 0.2
        elif model is pendulum and dim == 2:  # 0.01 rad past its stop at -0.5, turning on
            q[:3], qd[2] = (0.5 * np.cos(-0.51), 0.5 * np.sin(-0.51), -0.51), -0.3
        elif model is pendulum:
            q[:3], q[5], qd[5] = (0.5 * np.cos(-0.51), 0.5 * np.sin(-0.51), 0.0), \
                math.tan(-0.51 / 2), -0.15
        elif dim == 2:  # the second bar turned 0.51 rad from the first, and turning on
            q[2], q[5], qd[2], qd[5] = 0.2, 0.71, -0.4, 0.3
        else:
            q[5], q[11], qd[5], qd[11] = math.tan(0.1), math.tan(0.355), -0.2, 0.15
        weight = 300.0
        numeric, _, D = _differenced_tangent(model, q, qd, model.charts0, weight)
        analytic = _contact_tangent(model, q, qd, model.charts0, weight)
        assert np.abs(numeric).max() > 1e3
        if dim == 3 and model is not slider:
            analytic = (analytic - _contact_tangent(model, q, qd, model.charts0, 0.0)) / weight
            numeric = D
        np.testing.assert_allclose(analytic, numeric, rtol=0,
                                   atol=1e-6 * np.abs(numeric).max())


def test_a_step_far_too_long_for_the_swing_is_warned_and_a_fitting_one_is_not():
    # the pendulum released from the horizontal swings through the bottom at about 5.4 rad/s
    # (energy: omega^2 = 3 g / L for a uniform rod): a step of 10 s (landing on t = 1 s) takes
    # it a radian and more per step, a wrong swing (-4.13 rad at t = 1 s, against -3.13)
    model = pendulum_chain(1, link_length=1.0, link_mass=1.0, angle=0.0)
    with pytest.warns(mb.AccuracyWarning, match="body 'link1' turned by .* rad in the step") \
            as caught:
        mb.forward_dynamics(model, [0.0, 1.0], method="generalized-alpha", step=10.0)
    # the step it advises is a tenth of a radian per step at the swing's fastest (sqrt(3 g /
    # L), within the quarter its long steps misjudge the rate by), and is not warned of
    advised = float(re.search(r"Use step <= (\S+) s", str(caught[0].message))[1])
    assert advised * math.sqrt(3 * G / 1.0) == pytest.approx(0.1, rel=0.25)
    with warnings.catch_warnings():
        warnings.simplefilter("error", mb.AccuracyWarning)
        mb.forward_dynamics(model, [0.0, 1.0], method="generalized-alpha", step=advised)
    # 0.11 rad per step at the bottom: no warning, and the swing within 1e-3 rad of DOP853's;
    # nor at 0.8 rad per step, below the documented radian (a phase error of 5 % a step)
    with warnings.catch_warnings():
        warnings.simplefilter("error", mb.AccuracyWarning)
        mb.forward_dynamics(model, [0.0, 1.0], method="generalized-alpha", step=0.15)
        res = mb.forward_dynamics(model, [0.0, 1.0], method="generalized-alpha", step=0.02)
    exact = mb.forward_dynamics(model, [0.0, 1.0], method="DOP853", rtol=1e-10)
    assert abs(res.body("link1").angle[-1] - exact.body("link1").angle[-1]) < 1e-3
    # the same bar on a ball joint: its turn is read from the Rodrigues parameters, which
    # change by about half the angle; steps of 0.2 s turn it by about a radian at the bottom
    # (5.4 rad/s), steps of 0.1 s by half of one
    spatial = spatial_chain(1)
    with pytest.warns(mb.AccuracyWarning, match="body 'link1' turned by .* rad in the step"):
        mb.forward_dynamics(spatial, [0.0, 1.0], method="generalized-alpha", step=0.2)
    with warnings.catch_warnings():
        warnings.simplefilter("error", mb.AccuracyWarning)
        mb.forward_dynamics(spatial, [0.0, 1.0], method="generalized-alpha", step=0.1)


def test_an_iterate_thrown_half_a_turn_is_a_rejected_step_not_a_singular_model():
    """A bar on a ball joint released level and stepped 1 s at once: Newton's first iterates
    turn it by nearly half a turn, where the Rodrigues parameters run to 1e4 and the
    iteration matrix is singular at the iterate. That is a step too long, not a model without
    inertia: the step is shortened (it was refused, blaming light bodies) and the too-long
    step is warned of."""
    with pytest.warns(mb.AccuracyWarning, match="body 'link1' turned by"):
        res = mb.forward_dynamics(spatial_chain(1), [0.0, 1.0], method="generalized-alpha",
                                  step=1.0)
    assert res.status == "complete" and res.stats["rejected_steps"] > 0


def _index3_generalized_alpha(h: float, rho_inf: float, steps: int):
    """An independent index-3 generalized-alpha (Arnold and Bruls 2007, eqs. 9-12) on a
    uniform 1 m, 1 kg bar pinned at one end, released level, in absolute coordinates
    (x, y, theta) with a full Newton iteration on (qdd, lam) and a finite-difference
    Jacobian: the positions after each step, or None once Newton fails (50 iterations)."""
    L, J = 1.0, 1.0 / 12.0
    M, Q = np.diag([1.0, 1.0, J]), np.array([0.0, -G, 0.0])
    am, af = (2 * rho_inf - 1) / (rho_inf + 1), rho_inf / (rho_inf + 1)
    gam = 0.5 + af - am
    beta = 0.25 * (gam + 0.5) ** 2

    def rows(q):
        c, s = math.cos(q[2]), math.sin(q[2])
        return np.array([q[0] - L / 2 * c, q[1] - L / 2 * s]), np.array(
            [[1.0, 0.0, L / 2 * s], [0.0, 1.0, -L / 2 * c]])

    q, qd = np.array([L / 2, 0.0, 0.0]), np.zeros(3)
    Cq = rows(q)[1]  # at rest: Cq qdd = 0
    x = np.linalg.solve(np.block([[M, Cq.T], [Cq, np.zeros((2, 2))]]), np.r_[Q, 0.0, 0.0])
    qdd, a, path = x[:3], x[:3].copy(), []

    def residual(x):
        a1 = ((1 - af) * x[:3] + af * qdd - am * a) / (1 - am)
        q1 = q + h * qd + h * h * (0.5 - beta) * a + h * h * beta * a1
        C, Cq1 = rows(q1)
        return np.r_[M @ x[:3] + Cq1.T @ x[3:] - Q, C / (beta * h * h)], q1, a1

    for _ in range(steps):
        for _ in range(50):
            r = residual(x)[0]
            if np.linalg.norm(r) < 1e-10:
                break
            dx = 1e-7 * np.maximum(1.0, np.abs(x))
            jac = np.column_stack([(residual(x + dx[k] * np.eye(5)[k])[0] - r) / dx[k]
                                   for k in range(5)])
            x = x - np.linalg.solve(jac, r)
        else:
            return None
        _, q1, a1 = residual(x)
        qd = qd + h * (1 - gam) * a + h * gam * a1
        q, qdd, a = q1, x[:3], a1
        path.append(q)
    return np.array(path)


def test_twenty_steps_a_swing_as_an_independent_index3_generalized_alpha_takes_them():
    """A bar released level at 0.1 s steps (20 a swing, a third of a radian per step at the
    bottom): mbd3d's positions are those of generalized-alpha written independently in this
    test, to 1e-8 over 50 steps, with rho_inf = 0.5. With rho_inf = 0.9 both lose the swing:
    the velocities alternate from step to step and grow until Newton fails (the method's
    property on this motion, not the code's), and mbd3d says so naming the remedies."""
    model = pendulum_chain(1, link_length=1.0, link_mass=1.0, angle=0.0)
    t = np.arange(1, 51) * 0.1
    res = mb.forward_dynamics(model, np.r_[0.0, t], method="generalized-alpha", step=0.1,
                              rho_inf=0.5)
    np.testing.assert_allclose(res.q[1:], _index3_generalized_alpha(0.1, 0.5, 50),
                               rtol=0, atol=1e-8)
    assert res.stats["rejected_steps"] == 0
    assert _index3_generalized_alpha(0.1, 0.9, 50) is None
    with pytest.raises(mb.IntegrationError, match=r"(?s)not converge at t = .* not even with "
                       r"the step shortened from 0.1 s.*unstable.*rho_inf below 0.9, e\.g\. "
                       "0.45"):
        mb.forward_dynamics(model, np.r_[0.0, t], method="generalized-alpha", step=0.1)


def test_outputs_between_steps_are_interpolated_without_changing_the_steps():
    """Outputs every 1.1 steps of a bar released level (500 steps a swing): the steps stay
    10 ms (cut to land on the outputs, 10 ms then 1 ms, they disturbed the recursion until
    Newton failed at t = 0.7 s), the states at the step ends are those of a run with an
    output at every step, and between them the interpolated states are on the constraints
    and as close to the minimal equation's solution as the step ends are."""
    model = pendulum_chain(1, link_length=1.0, link_mass=1.0, angle=0.0)
    every = mb.forward_dynamics(model, np.linspace(0.0, 4.95, 496),
                                method="generalized-alpha", step=0.01)
    t = np.linspace(0.0, 4.95, 451)  # 11 ms apart
    res = mb.forward_dynamics(model, t, method="generalized-alpha", step=0.01)
    assert res.stats["steps"] == every.stats["steps"] == 495
    np.testing.assert_allclose(res.q[::10], every.q[::11], rtol=0, atol=1e-12)
    assert np.max(np.abs(res.position_residual)) < 1e-10
    k = 1.5 * G  # theta'' = -(3 g / 2 L) cos(theta)
    exact = solve_ivp(lambda _, y: [y[1], -k * math.cos(y[0])], (0.0, 4.95), [0.0, 0.0],
                      t_eval=t, rtol=1e-12, atol=1e-12).y
    at_ends = solve_ivp(lambda _, y: [y[1], -k * math.cos(y[0])], (0.0, 4.95), [0.0, 0.0],
                        t_eval=every.t, rtol=1e-12, atol=1e-12).y
    error_at_ends = np.max(np.abs(every.body("link1").angle - at_ends[0]))
    assert 1e-3 < error_at_ends < 1e-2  # the method's error at 500 steps a swing
    assert np.max(np.abs(res.body("link1").angle - exact[0])) < 1.05 * error_at_ends
    assert np.max(np.abs(res.body("link1").angular_velocity - exact[1])) < 1.05 * np.max(
        np.abs(every.body("link1").angular_velocity - at_ends[1]))


@pytest.mark.parametrize("past, steps, smallest", [
    (0.3, 51, 0.3),  # 50 steps of 10 ms, then the 3 ms left
    (0.04, 51, 0.52),  # 49 steps, then two of 5.2 ms: not a sliver of 0.4 ms
    (1e-11, 50, 1.0)])  # the end within rounding of a step's: no step of 1e-13 s
def test_the_run_s_end_is_landed_on_without_a_sliver_of_a_step(past, steps, smallest):
    """A run that ends ``past`` steps after its 50th step of 10 ms: generalized-alpha lands
    on the end exactly; a remainder shorter than a twentieth of a step is not taken as a
    sliver (a step far shorter than the others disturbs the method's recursion, and its
    iteration matrix scales with 1 / h^2) but shared with the step before it, two even steps;
    ``stats["smallest_step"]`` reports the shortest step taken."""
    h = 0.01
    model = pendulum_chain(1, link_length=1.0, link_mass=1.0, angle=0.0)
    end = (50 + past) * h
    res = mb.forward_dynamics(model, [0.0, end], method="generalized-alpha", step=h)
    assert res.t[-1] == end
    assert res.stats["steps"] == steps
    assert res.stats["smallest_step"] == pytest.approx(smallest * h, rel=1e-9)


def ball_over_floor(law, height: float, speed: float = 0.0) -> mb.Model:
    """A 1 kg ball of radius 0.1 m, its centre ``height`` [m] above a floor of ``law``,
    falling at ``speed`` [m/s]."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    ball = b.add_body("ball", mass=1.0, inertia=0.004, position=(0.0, height),
                      velocity=(0.0, -speed))
    b.add(mb.Contact("floor", mb.Sphere(ball, radius=0.1), mb.Plane(b.ground, normal=(0, 1)),
                     law=law))
    return b.build()


def bounce_energy_error(model, t: np.ndarray, after: float, in_flight: int
                        ) -> tuple[float, mb.Results]:
    """Largest difference [J/kg] between the ball's energy under generalized-alpha (10 ms
    steps) and DOP853 at the output times past ``after`` where both are in flight (at least
    ``in_flight`` of them), and the generalized-alpha run."""
    reference = mb.forward_dynamics(model, t, method="DOP853", rtol=1e-11, atol=1e-12)
    res = mb.forward_dynamics(model, t, method="generalized-alpha", step=1e-2)
    energy = [0.5 * r.qd[:, 1] ** 2 + G * r.q[:, 1] for r in (res, reference)]
    flying = (t > after) & (reference.q[:, 1] > 0.1) & (res.q[:, 1] > 0.1)
    assert np.sum(flying) >= in_flight
    return float(np.max(np.abs(energy[0] - energy[1])[flying])), res


@pytest.mark.parametrize("law", [mb.LinearContact(stiffness=1e6, restitution=1.0),
                                 mb.HertzContact(stiffness=1e8, restitution=0.5)],
                         ids=["linear elastic", "Hertz"])
def test_a_falling_ball_s_step_lands_just_past_the_touch(law):
    """A ball falling 0.4 m onto a floor whose force starts from zero: the steps of 10 ms
    reach t = 0.2856 s in 28, and the 29th, aimed by the gap's closing at its rate and
    acceleration (gap + v s + a s^2 / 2 = 0, exact in free fall), ends just past the touch:
    no step is retried, none added. (A linear law with damping pushes at once at the touch,
    c v: its landing step is retried; not this test.)"""
    model = ball_over_floor(law, 0.5)
    touch = math.sqrt(2 * 0.4 / G)
    # an output a nanosecond past the touch: the 29th step reaches it
    through = mb.forward_dynamics(model, [0.0, touch + 1e-9], method="generalized-alpha",
                                  step=1e-2)
    assert through.stats["steps"] == 29
    # on into the impact: the landing step is not retried for ending too far past the touch
    after = mb.forward_dynamics(model, [0.0, touch + 1e-3], method="generalized-alpha",
                                step=1e-2)
    assert after.stats["contact_retries"] == 0 and after.stats["rejected_steps"] == 0


@pytest.mark.parametrize("law", [mb.LinearContact(stiffness=1e6, restitution=1.0),
                                 mb.LinearContact(stiffness=1e5, restitution=0.8)],
                         ids=["elastic", "restitution 0.8"])
def test_a_first_step_across_the_touch_is_retried_to_end_at_it(law):
    """A ball 1 mm above the floor falling at 0.1 m/s touches at the root of
    1e-3 = 0.1 s + g s^2 / 2, 7.4 ms. The first step knows no acceleration yet and aims at
    10 ms (gap / speed): it crosses the touch by 2.6 ms, so it is retried at half, and the
    next one ends at the touch. The bounce then keeps DOP853's energy to 2e-3 of the drop's
    (a first step left across the touch loses 60 % of it)."""
    error, res = bounce_energy_error(ball_over_floor(law, 0.101, speed=0.1),
                                     np.linspace(0.0, 0.1, 11), after=0.02, in_flight=2)
    assert res.stats["contact_retries"] == 1
    assert error < 2e-3 * (0.5 * 0.1 ** 2 + G * 1e-3)


@pytest.mark.parametrize("drop", [0.0, G / 1e5], ids=["pressed in", "set down"])
def test_a_ball_resting_on_the_floor_is_stepped_at_the_nominal_step(drop):
    """A 1 kg ball on a 1e5 N/m floor (restitution 0.2: the contact's oscillation has a
    period of 20 ms), pressed in to its static depth m g / k (closed from the start: no
    impact), or set down on it at zero speed (an impact that dies out within its three
    periods of short steps): after that, generalized-alpha takes its own 10 ms step, and the
    ball rests m g / k deep."""
    depth = G / 1e5
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mb.ContactWarning)  # pressed in: as intended
        model = ball_over_floor(mb.LinearContact(stiffness=1e5, restitution=0.2),
                                0.1 - depth + drop)
    res = mb.forward_dynamics(model, np.linspace(0.0, 2.0, 5), method="generalized-alpha",
                              step=1e-2)
    impact_steps = 3 * 100 if drop else 0  # three periods at a hundred steps each
    assert res.stats["steps"] <= 200 + impact_steps + 20
    np.testing.assert_allclose(res.q[-1, 1], 0.1 - depth, rtol=0, atol=1e-9)


@pytest.mark.parametrize("law", [mb.LinearContact(stiffness=1e8, restitution=0.8),
                                 mb.LinearContact(stiffness=1e6, restitution=1.0),
                                 mb.HertzContact(stiffness=1e8, restitution=0.5),
                                 mb.HertzContact(stiffness=1e6, restitution=0.8)],
                         ids=["linear 1e8", "linear 1e6 elastic", "hertz 1e8", "hertz 1e6"])
def test_a_long_step_resolves_an_impact_on_a_stiff_floor(law):
    """A ball dropped 0.4 m onto a floor whose contact lasts 0.3 to 5 ms, with a step of
    10 ms: the step shortens into the impact (ending at the touch, a hundred steps per period
    of the contact's oscillation while it lasts) and comes back in flight, so the energy after
    the bounce matches DOP853's to 0.25 % of the drop's (the method's own error at that
    resolution: 0.2 % at most over linear and Hertz laws of 1e5 to 1e8 and restitutions 0.5
    to 1, falling as the square of the steps per period). A fixed step left this ball 2.8 m
    high, moving up at 7 m/s."""
    error, res = bounce_energy_error(ball_over_floor(law, 0.5), np.linspace(0.0, 0.6, 13),
                                     after=0.3, in_flight=3)
    assert error < 2.5e-3 * G * 0.4
    # in flight the nominal step: a few hundred steps for the impact, not 0.6 s of them
    assert res.stats["steps"] < 400


@pytest.mark.parametrize("layout", ["dense", "banded"])
@pytest.mark.filterwarnings("ignore::mbd3d.ContactWarning")
def test_the_compiled_contact_tangent_storage_is_the_sparse_one(layout):
    """The contacts' and joint stops' tangent, compiled into the iteration matrix's storage,
    against the same tangent as a sparse matrix placed by the pattern's own SciPy code:
    dense, spheres pressed together in a box (a contact group: its pairs found at the state)
    beside a fixed contact; banded, a chain whose pins are pressed into their stops. A
    contact group in a banded model is left to the sparse path (its pairs move)."""
    from mbd3d.analyses.alpha_step import _tangent_storage, force_tangent
    from mbd3d.joints import Revolute
    from mbd3d.mechanisms import spheres_in_box
    from mbd3d.numerics.compiled import force_tangents
    rng = np.random.default_rng(5)
    law = mb.HertzContact(young_modulus=1e7, poisson_ratio=0.3, restitution=0.5)
    if layout == "dense":
        model = spheres_in_box(8, dim=2, spacing=1.95, friction=0.3)
        q = model.q0 + 1e-4 * rng.normal(size=model.n_coordinates)
    else:
        b = mb.ModelBuilder(dim=2)
        links = [b.ground]
        for k in range(12):
            links.append(b.add_body(f"link{k}", mass=1.0, inertia=1 / 12,
                                    position=(k + 0.5, 0.0)))
            pin = b.add(Revolute(f"pin{k}", links[-2], links[-1], at=(float(k), 0.0)))
            b.add(mb.JointLimit(f"stop{k}", pin, lower=-0.1, upper=0.1,
                                law=mb.LinearContact(stiffness=1e4, restitution=0.5)))
        b.add(mb.Contact("floor", mb.Sphere(links[-1], 0.05, point=(0.5, 0.0)),
                         mb.Plane(b.ground, normal=(0.0, 1.0), at=(0.0, 0.01)), law=law,
                         friction=0.2))
        model = b.build()
        q = model.q0.copy()
        for k in range(12):  # every pin 0.02 rad past a stop, alternately
            q[3 * k + 2:model.n_coordinates:3] += 0.12 * (-1) ** k
    assert model._penalty_pattern.layout == layout
    qd = rng.normal(size=model.n_coordinates)
    arrays, work = model._core.penalty_arrays(model), model._core.workspace()
    expected, python_factor = _tangent_storage(
        model, force_tangent(model, 0.1, q, qd, model.charts0, 30.0))
    assert not python_factor and force_tangents.tangent_fits(arrays, work)
    extra = np.zeros(len(expected))
    force_tangents.force_tangent_into(work, arrays, 0.1, q, qd, None, 30.0, extra)
    assert np.abs(expected).max() > 0
    np.testing.assert_allclose(extra, expected, rtol=1e-13, atol=1e-13 * np.abs(expected).max())
    if layout == "banded":
        grouped = spheres_in_box(40, dim=2)
        assert grouped._penalty_pattern.layout == "banded"
        assert not force_tangents.tangent_fits(grouped._core.penalty_arrays(grouped),
                                               grouped._core.workspace())
