"""Simple and double pendulum against their minimal-coordinate equations; a pendulum at rest.

The minimal equations are derived by hand in each test (Lagrange's equations in the absolute
link angles) and integrated with SciPy at tight tolerance; nothing of mbd3d is used for them.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mbd3d as mb
from mbd3d.mechanisms import pendulum_chain

G = 9.81


def test_simple_pendulum_matches_minimal_equation():
    L, m = 1.0, 1.0
    J, c = m * L * L / 12, L / 2
    model = pendulum_chain(1, link_length=L, link_mass=m, angle=0.0)
    t = np.linspace(0.0, 3.0, 61)
    res = mb.forward_dynamics(model, t, method="DOP853", rtol=1e-11, atol=1e-12)

    # (J + m c^2) theta'' = -m g c cos(theta), theta from the x axis
    sol = solve_ivp(lambda _, y: [y[1], -m * G * c * math.cos(y[0]) / (J + m * c * c)],
                    (0, 3), [0.0, 0.0], t_eval=t, method="DOP853", rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res.body("link1").angle, sol.y[0], rtol=0, atol=1e-8)
    np.testing.assert_allclose(res.body("link1").angular_velocity, sol.y[1], rtol=0, atol=1e-7)
    energy = res.kinetic_energy + res.potential_energy
    np.testing.assert_allclose(energy, energy[0], rtol=0, atol=1e-9)


def test_double_pendulum_matches_minimal_equations():
    L1, L2, m1, m2 = 1.0, 0.7, 1.5, 0.8
    I1, I2 = m1 * L1**2 / 12, m2 * L2**2 / 12
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    from mbd3d.joints import Revolute
    th1, th2 = 0.3, -0.4
    p1 = 0.5 * L1 * np.array([math.cos(th1), math.sin(th1)])
    a = 2 * p1
    p2 = a + 0.5 * L2 * np.array([math.cos(th2), math.sin(th2)])
    link1 = b.add_body("link1", mass=m1, inertia=I1, position=p1, angle=th1)
    link2 = b.add_body("link2", mass=m2, inertia=I2, position=p2, angle=th2,
                       angular_velocity=1.5)
    b.add(Revolute("O", b.ground, link1, at=(0.0, 0.0)))
    b.add(Revolute("A", link1, link2, at=a))
    model = b.build()
    t = np.linspace(0.0, 2.0, 41)
    # the guessed rates of link2 are not consistent; hold its angular velocity while projecting
    res = mb.forward_dynamics(model, t, method="DOP853", rtol=1e-11, atol=1e-12,
                              hold=["link1.theta", "link2.theta"])

    # Lagrange in the absolute angles, k = m2 L1 L2 / 2:
    # M11 th1'' + k cos(d) th2'' + k sin(d) th2'^2 + (m1 L1/2 + m2 L1) g cos th1 = 0
    # k cos(d) th1'' + M22 th2'' - k sin(d) th1'^2 + m2 L2/2 g cos th2 = 0,  d = th1 - th2
    M11 = I1 + m1 * (L1 / 2) ** 2 + m2 * L1**2
    M22 = I2 + m2 * (L2 / 2) ** 2
    k = m2 * L1 * L2 / 2

    def rhs(_, y):
        q1, q2, w1, w2 = y
        d = q1 - q2
        M = np.array([[M11, k * math.cos(d)], [k * math.cos(d), M22]])
        f = np.array([-k * math.sin(d) * w2 * w2 - (m1 * L1 / 2 + m2 * L1) * G * math.cos(q1),
                      k * math.sin(d) * w1 * w1 - m2 * L2 / 2 * G * math.cos(q2)])
        return [w1, w2, *np.linalg.solve(M, f)]

    w0 = res.qd[0, [2, 5]]
    assert w0[1] == pytest.approx(1.5)  # the held rate was kept
    sol = solve_ivp(rhs, (0, 2), [th1, th2, *w0], t_eval=t, method="DOP853", rtol=1e-12,
                    atol=1e-12)
    np.testing.assert_allclose(res.body("link1").angle, sol.y[0], rtol=0, atol=1e-7)
    np.testing.assert_allclose(res.body("link2").angle, sol.y[1], rtol=0, atol=1e-7)
    energy = res.kinetic_energy + res.potential_energy
    np.testing.assert_allclose(energy, energy[0], rtol=0, atol=1e-8)


def _wobbling_body(torque: float, position=(0.3, -0.2), angle=0.4, velocity=(0.5, 0.1),
                   angular_velocity=2.0, gravity=(0.0, -9.81), spring=True):
    """A free body on a spring under a torque varying in time, and its equations as SciPy's
    solve_ivp takes them (no constraints: the same ODE in the same coordinates)."""
    b = mb.ModelBuilder(dim=2, gravity=gravity)
    body = b.add_body("b", mass=1.3, inertia=0.05, position=position, angle=angle,
                      velocity=velocity, angular_velocity=angular_velocity)
    if spring:
        b.add(mb.SpringDamper("s", b.ground, body, point_i=(0.0, 0.0), point_j=(0.1, 0.05),
                              stiffness=200.0, free_length=0.2))
    if torque:
        b.add(mb.Torque("wobble", body, mb.Harmonic(torque, 9.0)))
    model = b.build()

    def f(t, y):
        return np.concatenate([y[3:], mb.forward_accelerations(model, t, y[:3], y[3:])[0]])

    return model, f, np.concatenate([model.q0, model.qd0])


def test_dop853_s_dense_output_between_steps_under_a_torque_varying_in_time():
    """DOP853's interpolant takes three more stages at their own times within the step: the
    outputs between its steps of a body under a torque varying in time agree with SciPy's
    DOP853 on the same equations (a tight run: their difference is the pair's accuracy)."""
    model, f, y0 = _wobbling_body(3.0)
    t = np.linspace(0.0, 2.0, 401)
    res = mb.forward_dynamics(model, t, method="DOP853", rtol=1e-10, atol=1e-12)
    assert res.stats["steps"] < len(t) / 2  # most outputs lie between steps
    sol = solve_ivp(f, (0.0, 2.0), y0, method="DOP853", rtol=1e-13, atol=1e-14, t_eval=t)
    np.testing.assert_allclose(res.q, sol.y[:3].T, rtol=0, atol=1e-8)


def test_hanging_pendulum_at_rest_carries_its_weight():
    m = 2.5
    model = pendulum_chain(1, link_mass=m, angle=-math.pi / 2)
    res = mb.forward_dynamics(model, np.linspace(0.0, 1.0, 11))
    np.testing.assert_allclose(res.body("link1").angle, -math.pi / 2, rtol=0, atol=1e-12)
    pin = res.joint("pin1")
    np.testing.assert_allclose(pin.reaction(on="link1").force, [[0.0, m * G]] * 11,
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(pin.reaction(on="ground").force, [[0.0, -m * G]] * 11,
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(pin.reaction(on="link1").moment, 0.0, rtol=0, atol=1e-12)


@pytest.mark.parametrize("method", ["RK23", "RK45", "DOP853"])
def test_the_explicit_pairs_step_as_scipys_solve_ivp_does(method):
    """A free body on a spring under a torque varying in time (no constraints: the same ODE in
    the same coordinates) through SciPy's solve_ivp with the same pair and tolerances: the
    compiled loop's step-size control (its error norm, safety factor and limits) and its
    stages' times take the steps SciPy's does, within a few (the first step's guess differs
    slightly), with as many evaluations, and land on the same state."""
    # a torque that varies in time: the stages must be evaluated at their own times
    model, f, y0 = _wobbling_body(0.3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mb.StiffnessWarning)
        res = mb.forward_dynamics(model, [0.0, 2.0], method=method, rtol=1e-8, atol=1e-10)

    sol = solve_ivp(f, (0.0, 2.0), y0, method=method, rtol=1e-8, atol=1e-10)
    steps = len(sol.t) - 1
    assert abs(res.stats["steps"] - steps) <= 0.05 * steps, (res.stats["steps"], steps)
    # and evaluates the right-hand side as often (the stages of accepted and rejected steps)
    assert abs(res.stats["rhs_evaluations"] - sol.nfev) <= 0.05 * sol.nfev, (
        res.stats["rhs_evaluations"], sol.nfev)
    # each tried step evaluates the pair's new stages once (after the first evaluation and
    # the first step's guess, as SciPy counts), DOP853 its interpolant's three more at the
    # output: so as many steps are rejected as SciPy's evaluations say it rejected
    stages = {"RK23": 3, "RK45": 6, "DOP853": 12}[method]
    tried = res.stats["steps"] + res.stats["rejected_steps"]
    assert res.stats["rhs_evaluations"] == 2 + stages * tried + 3 * (method == "DOP853")
    rejected = (sol.nfev - 2) // stages - steps
    assert abs(res.stats["rejected_steps"] - rejected) <= 0.05 * steps, (
        res.stats["rejected_steps"], rejected)
    np.testing.assert_allclose(res.q[-1], sol.y[:3, -1], rtol=0, atol=1e-6)


_FIRST_STEP_CASES = {
    # the general rule: the step from the sizes of y, f and a difference of f
    "moving": (dict(torque=0.3), (0.5, 2.0)),
    # the same, capped at a short interval
    "short interval": (dict(torque=0.3), (0.5, 0.5002)),
    # y = 0: the trial step is 1e-6 s, and the guess at most 100 times that
    "at the origin": (dict(torque=0.3, position=(0.0, 0.0), angle=0.0, velocity=(0.0, 0.0),
                           angular_velocity=0.0, spring=False), (0.0, 2.0)),
    # f = 0 and f does not change: the guess of last resort
    "at rest, no forces": (dict(torque=0.0, velocity=(0.0, 0.0), angular_velocity=0.0,
                                gravity=(0.0, 0.0), spring=False), (0.0, 2.0)),
}


@pytest.mark.parametrize("case", _FIRST_STEP_CASES)
@pytest.mark.parametrize("method", ["RK23", "RK45", "DOP853"])
def test_the_first_step_is_scipys_guess(method, case):
    """The explicit methods' first step is guessed as SciPy's solve_ivp guesses it (Hairer,
    Norsett and Wanner, II.4), with the same tolerances per coordinate (atol in the model's
    units): the same step to rounding, in each of the rule's branches."""
    import scipy.integrate

    options, (t0, t1) = _FIRST_STEP_CASES[case]
    model, f, y0 = _wobbling_body(**options)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mb.StiffnessWarning)
        res = mb.forward_dynamics(model, [t0, t1], method=method, rtol=1e-8, atol=1e-10)
    atol = 1e-10 * np.tile(model.coordinate_scale, 2)
    solver = getattr(scipy.integrate, method)(f, t0, y0, t1, rtol=1e-8, atol=atol)
    solver.step()
    stages = {"RK23": 3, "RK45": 6, "DOP853": 12}[method]
    assert solver.nfev == 2 + stages  # SciPy's first step was accepted: it is its guess
    np.testing.assert_allclose(res.stats["initial_step"], solver.step_size, rtol=1e-12)


def test_a_drifted_state_is_projected_mass_weighted_from_one_factorization():
    """After a step drifts, the explicit methods project the state from one factorization of
    [M Cq^T; Cq 0] (simplified Newton). On a chain whose first pin is driven (Ct != 0), a
    drift of 1e-6 m and 1e-5 m/s comes back onto the position and velocity rows, and by the
    mass-weighted rule: the correction's momentum M dq has no part along the free motions
    (the null space of Cq), for positions to first order in the drift, for rates likewise."""
    import scipy.linalg as la
    from mbd3d.analyses.explicit import _project_with_one_factorization
    from mbd3d.joints import Revolute, RotationDriver
    from mbd3d.model import constraints
    from mbd3d.model.equations import mass_matrix

    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    previous, top = b.ground, np.zeros(2)
    for k, angle in enumerate((-1.0, -0.3, 0.4)):
        direction = np.array([math.cos(angle), math.sin(angle)])
        bar = b.add_body(f"bar{k}", mass=1.0 + k, inertia=0.1 + 0.05 * k,
                         position=top + 0.4 * direction, angle=angle)
        pin = b.add(Revolute(f"pin{k}", previous, bar, at=top))
        if k == 0:
            b.add(RotationDriver("motor", pin, motion=mb.Ramp(angle, 3.0)))
        previous, top = bar, top + 0.8 * direction
    model = b.build()
    t = 0.0
    q = model.q0
    qd = mb.solve_velocity(model, q, t)
    rng = np.random.default_rng(7)
    q_drift = q + 1e-6 * rng.standard_normal(q.size)
    qd_drift = qd + 1e-5 * rng.standard_normal(q.size)
    projected = _project_with_one_factorization(model, t, q_drift, qd_drift, 1e-12, None)
    assert projected is not None
    q_p, qd_p = projected
    frames = constraints.frames(model, q_p, qd_p)
    C, _, _, nu = constraints.evaluate(model, t, frames, rate=True)
    Cq = constraints.jacobian(model, t, q_p, frames, sparse=False)
    assert np.max(np.abs(C)) < 1e-13
    np.testing.assert_allclose(Cq @ qd_p, nu, rtol=0, atol=1e-12 * np.abs(nu).max())
    M, free = mass_matrix(model, frames, sparse=False), la.null_space(Cq)
    assert free.shape[1] == 2
    for moved in (q_p - q_drift, qd_p - qd_drift):
        momentum = M @ moved
        assert np.abs(free.T @ momentum).max() < 1e-4 * np.abs(momentum).max()
