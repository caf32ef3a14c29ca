"""Compliant contacts against what is derived apart from the code: the contact's generalized
forces against differences of a potential and a gap written here, restitution against the
single impact's phase plane (Chrono's restitution test; what the published Hunt-Crossley
calibrations really give),
a bouncing ball against e^(2n) h0 as the contact stiffens, energy over many elastic impacts,
and a sliding ball that ends rolling at 5/7 of its speed (angular momentum about the contact
point)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

import mbd3d as mb
from mbd3d.joints import Prismatic, Revolute, Universal
from mbd3d.model import constraints
from mbd3d.model.equations import generalized_forces

G = 9.81


def _rotation(chart: np.ndarray, g: np.ndarray) -> np.ndarray:
    """``A = A0 A(g)``, ``g = tan(phi / 2) axis``, through SciPy's rotation vectors."""
    norm = np.linalg.norm(g)
    rotvec = np.zeros(3) if norm == 0 else 2.0 * math.atan(norm) * g / norm
    return chart @ Rotation.from_rotvec(rotvec).as_matrix()


def _spatial_pair(second: str, law, friction=0.0, seed=0):
    """Two free spatial bodies in random charts carrying a sphere and a plane or a sphere,
    placed so that they overlap; returns the model, its charts and the shapes' data."""
    rng = np.random.default_rng(seed)
    b = mb.ModelBuilder(dim=3)
    one = b.add_body("one", mass=2.0, inertia=np.diag([0.1, 0.2, 0.3]), position=(0, 0, 0))
    two = b.add_body("two", mass=3.0, inertia=np.diag([0.3, 0.2, 0.4]), position=(0, 0, 2.0))
    centre, r_i = rng.normal(size=3) * 0.2, 0.3
    point, normal, r_j = rng.normal(size=3) * 0.2, rng.normal(size=3), 0.25
    normal[2] = -abs(normal[2]) - 0.5  # in the drawing, facing body one from above it
    normal /= np.linalg.norm(normal)
    shape = (mb.Plane(two, normal=normal, point=point) if second == "plane"
             else mb.Sphere(two, radius=r_j, point=point))
    b.add(mb.Contact("touch", mb.Sphere(one, radius=r_i, point=centre), shape, law=law,
                     friction=friction, slip_velocity=0.05))
    model = b.build()
    charts = np.tile(np.eye(3), (3, 1, 1))
    charts[:2] = Rotation.random(2, random_state=seed + 7).as_matrix()
    return model, charts, (centre, r_i, point, normal, r_j)


def _overlapping_state(model, charts, data, second, rng):
    """Random rotations, then body two moved so that the shapes overlap by 1 to 3 mm."""
    centre, r_i, point, normal, r_j = data
    q = np.zeros(12)
    q[3:6], q[9:12] = rng.normal(size=3) * 0.6, rng.normal(size=3) * 0.6
    q[0:3] = rng.normal(size=3) * 0.1
    c = q[0:3] + _rotation(charts[0], q[3:6]) @ centre
    A2 = _rotation(charts[1], q[9:12])
    depth = rng.uniform(1e-3, 3e-3)
    if second == "plane":  # the plane through c - (r_i - depth) m
        m = A2 @ normal
        q[6:9] = c - (r_i - depth) * m - A2 @ point
    else:
        d = rng.normal(size=3)
        q[6:9] = c + (r_i + r_j - depth) * d / np.linalg.norm(d) - A2 @ point
    return q


def _gap(q, charts, data, second):
    """The gap written from the shapes' definitions."""
    centre, r_i, point, normal, r_j = data
    c = q[0:3] + _rotation(charts[0], q[3:6]) @ centre
    A2 = _rotation(charts[1], q[9:12])
    p = q[6:9] + A2 @ point
    if second == "plane":
        return float((A2 @ normal) @ (c - p) - r_i)
    return float(np.linalg.norm(p - c) - r_i - r_j)


@pytest.mark.parametrize("second", ["plane", "sphere"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_contact_force_is_minus_the_gradient_of_the_hertz_potential(second, seed):
    # at rest the force is conservative: Q = -dV/dq, V = K delta^(5/2) / (5/2), delta = -gap
    K = 4e6
    model, charts, data = _spatial_pair(second, mb.HertzContact(stiffness=K), seed=seed)
    q = _overlapping_state(model, charts, data, second, np.random.default_rng(seed + 3))
    V = lambda x: K * max(-_gap(x, charts, data, second), 0.0) ** 2.5 / 2.5  # noqa: E731
    h = 1e-7
    expected = np.array([-(V(q + h * e) - V(q - h * e)) / (2 * h) for e in np.eye(12)])
    Q = generalized_forces(model, 0.0, constraints.frames(model, q, np.zeros(12), charts))
    np.testing.assert_allclose(Q, expected, rtol=1e-6, atol=1e-6 * np.abs(expected).max())
    states = mb.contact_states(model, q, charts=charts)
    np.testing.assert_allclose(states.gap, [_gap(q, charts, data, second)], rtol=0, atol=1e-15)
    # the gap's rounding (1e-16 m of a 1e-3 m depth) raised to the power 5/2
    np.testing.assert_allclose(states.potential_energy, [V(q)], rtol=1e-12, atol=0)


def _material_point_jacobian(q, charts, body, x, h=1e-7):
    """d/dq of the global position of the material point of ``body`` (0 or 1) at ``x``."""
    A = _rotation(charts[body], q[6 * body + 3:6 * body + 6])
    u = A.T @ (x - q[6 * body:6 * body + 3])
    J = np.zeros((3, 12))
    for k in range(6 * body, 6 * body + 6):
        e = np.zeros(12)
        e[k] = h
        plus, minus = ((x[6 * body:6 * body + 3]
                        + _rotation(charts[body], x[6 * body + 3:6 * body + 6]) @ u)
                       for x in (q + e, q - e))
        J[:, k] = (plus - minus) / (2 * h)
    return J


@pytest.mark.parametrize("second", ["plane", "sphere"])
def test_damped_normal_force_and_friction_act_at_the_contact_point(second):
    # the Hunt-Crossley force with the gap's rate from differences along qd, friction against
    # the slip of the material points there, and Q = J_j^T F - J_i^T F with J from differences
    K, e, v0, mu, v_slip = 4e6, 0.6, 1.5, 0.4, 0.05
    law = mb.HuntCrossley(stiffness=K, restitution=e, impact_speed=v0, exponent=1.4)
    model, charts, data = _spatial_pair(second, law, friction=mu, seed=5)
    rng = np.random.default_rng(11)
    q = _overlapping_state(model, charts, data, second, rng)
    qd = rng.normal(size=12)
    h = 1e-7
    gap = _gap(q, charts, data, second)
    rate = (_gap(q + h * qd, charts, data, second)
            - _gap(q - h * qd, charts, data, second)) / (2 * h)
    chi = law.constants(1.0, 1.0, "law")[2] * v0 / K
    # the exact calibration: chi (1 + e) = ln((1 + chi) / (1 - chi e)) (_hunt_crossley_restitution)
    assert chi * (1 + e) == pytest.approx(math.log((1 + chi) / (1 - chi * e)), rel=1e-12)
    force = K * (-gap) ** 1.4 * (1 + chi * (-rate) / v0)
    states = mb.contact_states(model, q, qd, charts)
    np.testing.assert_allclose(states.gap_rate, [rate], rtol=1e-7, atol=0)
    np.testing.assert_allclose(states.normal_force, [force], rtol=1e-7, atol=0)
    x, n = states.point[0], states.normal[0]
    J_i, J_j = (_material_point_jacobian(q, charts, body, x) for body in (0, 1))
    slip = (J_j - J_i) @ qd
    slip -= (slip @ n) * n
    speed = np.linalg.norm(slip)
    friction = -mu * force * math.tanh(speed / v_slip) * slip / speed
    np.testing.assert_allclose(states.friction_force[0], friction, rtol=1e-7, atol=0)
    F = force * n + friction
    Q = np.zeros((3, 6))  # the contact's own, without the quadratic velocity forces
    model.force_groups[0].apply(model, 0.0, constraints.frames(model, q, qd, charts), Q)
    Q = Q[:2].ravel()
    np.testing.assert_allclose(Q, J_j.T @ F - J_i.T @ F, rtol=1e-6, atol=1e-7 * abs(force))


def _two_spheres(law, closing=2.0):
    """Chrono's restitution test (utest_SMC_cor_normal): spheres of 1 kg and radius 0.5 m,
    centres 1.25 m apart, closing at 2 m/s, no gravity; the measured restitution."""
    b = mb.ModelBuilder(dim=3)
    inertia = np.eye(3) * 0.1
    left = b.add_body("left", mass=1.0, inertia=inertia, position=(-0.625, 0, 0),
                      velocity=(closing / 2, 0, 0))
    right = b.add_body("right", mass=1.0, inertia=inertia, position=(0.625, 0, 0),
                       velocity=(-closing / 2, 0, 0))
    b.add(mb.Contact("pair", mb.Sphere(left, 0.5), mb.Sphere(right, 0.5), law=law))
    res = mb.forward_dynamics(b.build(), [0.0, 0.3], method="DOP853", rtol=1e-11, atol=1e-13)
    return (res.qd[-1, 6] - res.qd[-1, 0]) / closing


@pytest.mark.parametrize("e", [0.25, 0.5, 0.75, 1.0])
def test_chrono_restitution_test_rebounds_with_the_restitution_asked_for(e):
    # Chrono asserts 1e-3 for its Hertz law; the calibrated laws here are exact
    laws = [mb.HertzContact(young_modulus=2e5, poisson_ratio=0.3, restitution=e),
            mb.LinearContact(stiffness=1e5, restitution=e),
            mb.HuntCrossley(stiffness=73260.07, restitution=e, impact_speed=2.0)]
    for law in laws:
        assert _two_spheres(law) == pytest.approx(e, abs=1e-8), law


def _hunt_crossley_restitution(chi: float) -> float:
    """The restitution of ``F = K d^n (1 + chi d' / v0)`` in a free impact at ``v0``: its
    phase plane ``m v dv = -K d^n (1 + chi v / v0) dd`` integrated over the compression
    (``v0`` to 0) and the restitution (0 to ``-e v0``), whose energy integrals cancel:
    ``int_{-e}^{1} u / (1 + chi u) du = 0``, i.e. ``chi (1 + e) = ln((1 + chi) / (1 - chi
    e))``, whatever ``K``, ``n``, ``m`` and ``v0``."""
    f = lambda e: chi * (1 + e) - math.log((1 + chi) / (1 - chi * e))  # noqa: E731
    return brentq(f, 1e-9, min(1.0, (1 - 1e-12) / chi))


def _clipped_linear_restitution(zeta: float) -> float:
    """The restitution of ``m x'' = -k x - c x'`` (``zeta = c / (2 sqrt(k m))``) whose force
    may not pull: the speed where ``k x + c x'`` falls to zero, by SciPy."""
    def parted(_t, y):
        return y[0] + 2 * zeta * y[1] if y[1] < 0 else 1.0
    parted.terminal, parted.direction = True, -1
    solution = solve_ivp(lambda _t, y: [y[1], -y[0] - 2 * zeta * y[1]], (0.0, 10.0),
                         [0.0, 1.0], rtol=1e-12, atol=1e-14, events=parted)
    return -float(solution.y_events[0][0][1])


def test_published_hunt_crossley_calibrations_give_other_restitutions():
    # what each published chi, asked for e = 0.5, really gives (the phase plane above), and
    # the linear law with the damping ratio of the unclipped oscillator's e = 0.5 clipped
    published = {"hunt-crossley": 1.5 * 0.5, "lankarani-nikravesh": 0.75 * (1 - 0.25),
                 "flores": 1.6 * 0.5 / 0.5, "gonthier": (1 - 0.25) / 0.5}
    for calibration, chi in published.items():
        law = mb.HuntCrossley(stiffness=73260.07, restitution=0.5, impact_speed=2.0,
                              calibration=calibration)
        expected = _hunt_crossley_restitution(chi)
        assert abs(expected - 0.5) > 0.01  # none is exact
        assert _two_spheres(law) == pytest.approx(expected, abs=1e-8), calibration
    zeta = -math.log(0.5) / math.hypot(math.pi, math.log(0.5))
    m_star, k = 0.5, 1e5
    law = mb.LinearContact(stiffness=k, damping=2 * zeta * math.sqrt(k * m_star))
    expected = _clipped_linear_restitution(zeta)
    assert expected == pytest.approx(0.550, abs=5e-4)
    assert _two_spheres(law) == pytest.approx(expected, abs=1e-8)
    # a Hunt-Crossley law rebounds more from a slower impact
    slow = _two_spheres(mb.HuntCrossley(stiffness=73260.07, restitution=0.5, impact_speed=2.0),
                        closing=1.0)
    assert slow > 0.6


def _adams_step(x, x0, h0, x1, h1):
    """Adams' STEP function: h0 before x0, h1 after x1, the cubic h0 + (h1 - h0) a^2 (3 - 2 a)
    with a = (x - x0) / (x1 - x0) between (MSC Adams Solver function reference)."""
    a = min(max((x - x0) / (x1 - x0), 0.0), 1.0)
    return h0 + (h1 - h0) * a * a * (3.0 - 2.0 * a)


def _adams_impact(x, xd, x1, k, e, cmax, d):
    """Adams' IMPACT(x, x', x1, k, e, cmax, d) = max(0, k (x1 - x)^e - STEP(x, x1 - d, cmax,
    x1, 0) x') while x < x1, else 0."""
    if x >= x1:
        return 0.0
    return max(0.0, k * (x1 - x) ** e - _adams_step(x, x1 - d, cmax, x1, 0.0) * xd)


def _piecewise_reference(rhs, y0, t_end, kinks) -> tuple:
    """SciPy's DOP853 on ``rhs`` restarted at each zero of the functions ``kinks`` (where the
    right-hand side has a kink), so that no step straddles one: ``(solution of t, the time
    the first kink function crosses upwards, the state then)``. DOP853 across the kinks
    wanders by 1e-11 m at rtol 1e-12 and by 1e-3 in the rebound at 1e-13."""
    t0, y, pieces, parted = 0.0, np.asarray(y0, dtype=float), [], None
    events = [lambda t, y, f=f: f(y) for f in kinks]
    for event in events:
        event.terminal = True
    while t0 < t_end:
        piece = solve_ivp(rhs, (t0, t_end), y, method="DOP853", rtol=1e-13, atol=1e-16,
                          events=events, dense_output=True)
        pieces.append((t0, piece.t[-1], piece.sol))
        t0, y = piece.t[-1], piece.y[:, -1]
        if piece.status == 0:
            break
        if len(piece.t_events[0]) and parted is None and t0 > 0.0:  # not the start's zero
            parted = (t0, y)
        # step off the zero, so that the same event does not end the next piece at once
        t_next = min(t0 + 1e-12, t_end)
        y = y + (t_next - t0) * np.asarray(rhs(t0, y))
        t0 = t_next

    def solution(times):
        return np.array([next(sol for a, b, sol in pieces if a <= t <= b)(t) for t in times]).T
    return solution, parted


@pytest.mark.parametrize("depth", [2e-3, 1e-2])
def test_the_impact_function_is_adams_impact(depth):
    # a 1 kg ball touching a floor at 1 m/s, no gravity, against SciPy integrating m x'' =
    # IMPACT(x, x', r, ...) of its height x: the ramp ends inside the impact (2 mm of 4.4) or
    # never (10 mm); the height inside the impact and the speed it leaves with
    K, n, cmax, r, v0 = 1e6, 1.5, 200.0, 0.1, 1.0

    def rhs(_t, y):
        return [y[1], _adams_impact(y[0], y[1], r, K, n, cmax, depth)]

    def unclipped(y):  # the force before it is clipped at zero
        if y[0] >= r:
            return 1.0
        return K * (r - y[0]) ** n - _adams_step(y[0], r - depth, cmax, r, 0.0) * y[1]

    t_end = 0.02
    # the kinks: leaving the floor, the ramp's end, the force clipped at zero
    solution, (t_off, leaving) = _piecewise_reference(
        rhs, [r, -v0], t_end, [lambda y: y[0] - r, lambda y: y[0] - (r - depth), unclipped])

    b = mb.ModelBuilder(dim=2)
    ball = b.add_body("ball", mass=1.0, inertia=0.004, position=(0.0, r), velocity=(0.0, -v0))
    b.add(mb.Contact("floor", mb.Sphere(ball, r), mb.Plane(b.ground, normal=(0.0, 1.0)),
                     law=mb.ImpactFunction(stiffness=K, damping=cmax, penetration=depth,
                                           exponent=n)))
    t = np.concatenate([np.linspace(0.0, t_off, 9)[1:-1], [t_end]])
    res = mb.forward_dynamics(b.build(), np.concatenate([[0.0], t]), method="DOP853",
                              rtol=1e-12, atol=1e-15)
    height = solution(t[:-1])[0]
    assert (r - height).max() > min(depth, 3e-3)  # deeper than the ramp, or most of it
    np.testing.assert_allclose(res.q[1:-1, 1], height, rtol=0, atol=1e-12)
    rebound = leaving[1]
    assert 0.2 < rebound < 0.95
    assert res.qd[-1, 1] == pytest.approx(rebound, rel=1e-9)


def _bouncing_ball(stiffness, e=0.8, h0=1.0, dim=2, t=None, rtol=1e-10, law=None,
                   max_step=1e-3):
    b = mb.ModelBuilder(dim=dim, gravity=(0.0, -G) if dim == 2 else (0.0, 0.0, -G))
    r = 0.1
    inertia = 0.4 * r * r if dim == 2 else np.eye(3) * 0.4 * r * r
    ball = b.add_body("ball", mass=1.0, inertia=inertia,
                      position=(0.0, h0 + r) if dim == 2 else (0.0, 0.0, h0 + r))
    up = (0.0, 1.0) if dim == 2 else (0.0, 0.0, 1.0)
    law = law or mb.HertzContact(stiffness=stiffness, restitution=e)
    b.add(mb.Contact("floor", mb.Sphere(ball, r), mb.Plane(b.ground, normal=up), law=law))
    model = b.build()
    res = mb.forward_dynamics(model, t, method="DOP853", rtol=rtol, atol=rtol * 1e-2,
                              max_step=max_step)
    return model, res, res.q[:, dim - 1] - r


def test_bouncing_ball_converges_to_the_rigid_apex_heights_as_the_contact_stiffens():
    # a rigid bounce with restitution e reaches e^(2n) h0; a compliant one
    # loses a little to gravity during the contact, in proportion to its depth ~ K^(-2/5)
    e, h0 = 0.8, 1.0
    n = np.arange(1, 4)
    # half-way through the rigid ball's n-th flight, where the apex is y + vy^2 / (2 g)
    t1 = math.sqrt(2 * h0 / G)
    t = np.concatenate([[0.0], t1 * (1 + 2 * e * (1 - e ** (n - 1)) / (1 - e)) + e ** n * t1])
    errors = []
    for stiffness in (1e7, 1e9):
        _, res, height = _bouncing_ball(stiffness, e, h0, t=t)
        apexes = height[1:] + res.qd[1:, 1] ** 2 / (2 * G)
        assert np.all(height[1:] > 0.1)  # in flight
        errors.append(np.abs(apexes - e ** (2 * n) * h0).max())
    assert errors[1] < 4e-4
    assert errors[0] / errors[1] == pytest.approx(100 ** 0.4, rel=0.05)


@pytest.mark.parametrize("dim", [2, 3])
def test_elastic_bounces_conserve_energy(dim):
    # the explicit integrators end their steps at each touch and release, so the energy's
    # error is the integrator's own: some 100 rtol over the 3000 steps
    t = np.linspace(0.0, 2.5, 501)
    model, res, height = _bouncing_ball(1e8, e=1.0, dim=dim, t=t, rtol=1e-12)
    assert np.sum(np.diff(np.sign(np.diff(height))) < 0) >= 2  # two bounces at least
    energy = _energy(model, res)
    np.testing.assert_allclose(energy, energy[0], rtol=0, atol=1e-9 * energy[0])


def _energy(model, res) -> np.ndarray:
    charts = [None] * len(res.t) if res.charts is None else res.charts
    return np.array([mb.kinetic_energy(model, q, qd, c) + mb.potential_energy(model, q, c)
                     for q, qd, c in zip(res.q, res.qd, charts)])


@pytest.mark.parametrize("dim", [2, 3])
def test_steps_end_just_past_each_touch_and_release_so_the_energy_keeps_to_rtol(dim):
    """A linear elastic floor's force has a kink at the touch and the release, which a step
    across it hides from the error estimate: steps are shortened to end just past each
    switch, and two bounces then keep the energy to the tolerance asked (measured: at most
    0.8 rtol; ended wherever the error control puts them, 10 to 40 rtol)."""
    t1 = math.sqrt(2 * 1.0 / G)  # the touch-down of a drop from 1 m
    t = [0.0, 2.5 * t1, 4.5 * t1]  # in flight after the first and the second bounce
    for rtol in (1e-5, 1e-7, 1e-9):
        model, res, height = _bouncing_ball(None, dim=dim, t=t, rtol=rtol, max_step=np.inf,
                                            law=mb.LinearContact(stiffness=1e6, damping=0.0))
        assert np.all(height[1:] > 0.3)
        energy = _energy(model, res)
        np.testing.assert_allclose(energy, energy[0], rtol=0, atol=2 * rtol * energy[0])
        # the steps shortened at a switch count as rejected: each tried step evaluates
        # DOP853's 12 stages, each output after the start 3 more (as the ODE test counts)
        tried = res.stats["steps"] + res.stats["rejected_steps"]
        assert res.stats["rhs_evaluations"] == 2 + 12 * tried + 3 * 2


@pytest.mark.parametrize("dim", [2, 3])
def test_a_sliding_ball_ends_rolling_at_five_sevenths_of_its_speed(dim):
    # friction acts at the contact point, gravity and the normal force through it: the
    # angular momentum about it is kept, m v0 rho = m v rho + I v / rho, so v = 5/7 v0 for
    # I = 2/5 m r^2 and rho = r, reached after 2 v0 / (7 mu g). The contact point is midway
    # through the Hertz penetration delta = (m g / K)^(2/3): rho = r - delta / 2
    r, m, v0, mu, K = 0.1, 1.0, 2.0, 0.3, 1e7
    b = mb.ModelBuilder(dim=dim, gravity=(0.0, -G) if dim == 2 else (0.0, 0.0, -G))
    inertia = 0.4 * m * r * r
    delta = (m * G / K) ** (2 / 3)  # placed at rest in its static penetration
    position, velocity = (((0.0, r - delta), (v0, 0.0)) if dim == 2
                          else ((0.0, 0.0, r - delta), (v0, 0.0, 0.0)))
    ball = b.add_body("ball", mass=m, inertia=inertia if dim == 2 else np.eye(3) * inertia,
                      position=position, velocity=velocity)
    up = (0.0, 1.0) if dim == 2 else (0.0, 0.0, 1.0)
    b.add(mb.Contact("floor", mb.Sphere(ball, r), mb.Plane(b.ground, normal=up),
                     law=mb.HertzContact(stiffness=K, restitution=0.3), friction=mu,
                     slip_velocity=1e-4))
    with pytest.warns(mb.ContactWarning, match="overlap"):
        model = b.build()
    t_roll = 2 * v0 / (7 * mu * G)
    res = mb.forward_dynamics(model, [0.0, 0.5 * t_roll, 2 * t_roll], method="DOP853", rtol=1e-9,
                              atol=1e-11)
    rho = r - delta / 2
    v = v0 * rho ** 2 / (rho ** 2 + inertia / m)
    assert v == pytest.approx(5 / 7 * v0, rel=3e-4)
    assert res.qd[-1, 0] == pytest.approx(v, rel=1e-7)
    # half-way: still slipping, decelerated by mu g (the normal force has settled to m g)
    assert res.qd[1, 0] == pytest.approx(v0 - mu * G * 0.5 * t_roll, rel=2e-3)
    spin = res.qd[-1, 2] if dim == 2 else res.body("ball").angular_velocity[-1][1]
    assert spin == pytest.approx((-1 if dim == 2 else 1) * v / rho, rel=1e-7)


def test_bad_contacts_are_named():
    b = mb.ModelBuilder(dim=2)
    ball = b.add_body("ball", mass=1.0, inertia=0.004, position=(0.0, 0.05))
    floor = mb.Plane(b.ground, normal=(0.0, 1.0))

    def build(law=None, shape=None, **kw):
        builder = mb.ModelBuilder(dim=2)
        body = builder.add_body("ball", mass=1.0, inertia=0.004, position=(0.0, 0.2))
        builder.add(mb.Contact("bounce", shape or mb.Sphere(body, 0.1),
                               mb.Plane(builder.ground, normal=(0.0, 1.0)),
                               law=law or mb.LinearContact(stiffness=1e5, damping=1.0), **kw))
        return builder.build()

    cases = [
        (dict(law=mb.HertzContact(stiffness=1e6, restitution=1.5)), "restitution must lie in"),
        (dict(law=mb.HertzContact(stiffness=1e6, restitution=0.0)), "restitution 0"),
        (dict(law=mb.LinearContact(stiffness=-1.0, damping=0.0)), "stiffness must be > 0"),
        (dict(law=mb.LinearContact(stiffness=1.0)), "damping or the restitution"),
        (dict(law=mb.HertzContact(restitution=0.5)), "young_modulus"),
        (dict(law=mb.HuntCrossley(1e6, 0.5, 1.0, calibration="guess")), "calibration must"),
        (dict(law=mb.ImpactFunction(1e6, 10.0, penetration=0.0)), "penetration must be > 0"),
        (dict(law=mb.ImpactFunction(1e6, -1.0, penetration=1e-3)), "damping must be >= 0"),
        (dict(friction=-0.1), "friction must be >= 0"),
        (dict(slip_velocity=0.0), "slip_velocity"),
    ]
    for kwargs, words in cases:
        with pytest.raises(mb.ModelError, match=words) as info:
            build(**kwargs)
        assert "contact 'bounce'" in str(info.value)
    b.add(mb.Contact("bounce", mb.Sphere(ball, 0.1), floor,
                     law=mb.LinearContact(stiffness=1e5, damping=1.0)))
    with pytest.warns(mb.ContactWarning,
                      match=r"contact 'bounce': the shapes overlap by 0\.05 m .* force of 5000 N;"):
        b.build()
    with pytest.raises(mb.ModelError, match="contact 'bad': no contact between a Plane and a "
                       "Plane; the pairs are Box-Box, Box-Capsule, Box-Plane"):
        mb.Contact("bad", floor, floor, law=mb.LinearContact(stiffness=1.0, damping=0.0))


def _slider(dim, law, v=1.5):
    """A block on a prismatic joint along x, sent at ``v`` towards the upper stop."""
    b = mb.ModelBuilder(dim=dim)
    inertia = 0.01 if dim == 2 else np.eye(3) * 0.01
    block = b.add_body("block", mass=2.0, inertia=inertia, position=(0.0,) * dim,
                       velocity=(v,) + (0.0,) * (dim - 1))
    slide = b.add(Prismatic("slide", b.ground, block, axis=(1.0,) + (0.0,) * (dim - 1)))
    b.add(mb.JointLimit("ends", slide, lower=-0.3, upper=0.2, law=law))
    return b.build()


@pytest.mark.parametrize("dim", [2, 3])
def test_a_slider_rebounds_from_both_stops_with_the_restitution(dim):
    # a free mass on a fixed stop: the calibration's own impact, exact
    e, v = 0.6, 1.5
    for law in (mb.LinearContact(stiffness=1e6, restitution=e),
                mb.HertzContact(stiffness=1e8, restitution=e)):
        model = _slider(dim, law, v)
        res = mb.forward_dynamics(model, [0.0, 0.4, 1.2], method="DOP853", rtol=1e-11,
                                  atol=1e-13)
        np.testing.assert_allclose(res.qd[1:, 0], [-e * v, e * e * v], rtol=1e-8, atol=0)
        slide = res.joint("slide").displacement
        assert -0.3 < slide[1] < 0.2


def _pendulum(dim, law, lower):
    """A rod of 1 m pinned at its end, released horizontal, with a stop at ``lower``."""
    m, L = 1.5, 1.0
    b = mb.ModelBuilder(dim=dim, gravity=(0.0, -G) if dim == 2 else (0.0, -G, 0.0))
    inertia = m * L * L / 12
    rod = b.add_body("rod", mass=m,
                     inertia=inertia if dim == 2 else np.diag([1e-4, inertia, inertia]),
                     position=(L / 2, 0.0) if dim == 2 else (L / 2, 0.0, 0.0))
    pin = b.add(Revolute("pin", b.ground, rod, at=(0.0,) * dim,
                         axis=None if dim == 2 else (0.0, 0.0, 1.0)))
    b.add(mb.JointLimit("stop", pin, lower=lower, law=law))
    return b.build(), m * L * L / 3, m * G * L / 2


@pytest.mark.parametrize("dim", [2, 3])
def test_a_pendulum_rebounds_from_its_stop(dim):
    # hanging straight down at the stop, gravity has no moment there: the rate after the
    # bounce is e times the rate before, sqrt(2 m g (L/2) / I_O); after it the rod swings
    # freely, so omega^2 + 2 m g (L/2) (1 + sin theta) / I_O keeps its value
    e = 0.7
    law = mb.HertzContact(stiffness=1e7, restitution=e)
    model, I_O, moment = _pendulum(dim, law, -math.pi / 2)
    res = mb.forward_dynamics(model, np.linspace(0.0, 1.0, 11), method="DOP853", rtol=1e-11,
                              atol=1e-13)
    pin = res.joint("pin")
    before = math.sqrt(2 * moment / I_O)
    after = np.sqrt(pin.angle_rate ** 2 + 2 * moment * (1 + np.sin(pin.angle)) / I_O)
    rebounded = (res.t > 0.75) & (pin.angle > -math.pi / 2 + 1e-3)
    assert rebounded.sum() >= 2
    np.testing.assert_allclose(after[rebounded], e * before, rtol=1e-5, atol=0)
    np.testing.assert_allclose(after[res.t < 0.5], before, rtol=1e-9, atol=0)


def test_a_spatial_pendulum_in_the_plane_bounces_as_the_planar_one():
    law = mb.LinearContact(stiffness=1e5, restitution=0.5)
    t = np.linspace(0.0, 2.0, 21)
    angles = []
    for dim in (2, 3):
        model, _, _ = _pendulum(dim, law, -1.2)
        res = mb.forward_dynamics(model, t, method="DOP853", rtol=1e-11, atol=1e-13)
        angles.append(res.joint("pin").angle)
    np.testing.assert_allclose(angles[1], angles[0], rtol=0, atol=1e-8)
    assert angles[0].min() < -1.2  # it reached the stop


@pytest.mark.parametrize("dim", [2, 3])
def test_elastic_stops_keep_the_energy(dim):
    model, _, moment = _pendulum(dim, mb.HertzContact(stiffness=1e6), -1.0)
    res = mb.forward_dynamics(model, np.linspace(0.0, 3.0, 61), method="DOP853", rtol=1e-12,
                              atol=1e-14)
    charts = [None] * len(res.t) if res.charts is None else res.charts
    energy = np.array([mb.kinetic_energy(model, q, qd, c) + mb.potential_energy(model, q, c)
                       for q, qd, c in zip(res.q, res.qd, charts)])
    np.testing.assert_allclose(energy, energy[0], rtol=0, atol=1e-9 * moment)
    assert res.joint("pin").angle.min() < -1.0


def test_bad_joint_limits_are_named():
    b = mb.ModelBuilder(dim=3)
    body = b.add_body("body", mass=1.0, inertia=np.eye(3), position=(0.0, 0.0, 0.0))
    hinge = Revolute("hinge", b.ground, body, at=(0, 0, 0), axis=(0, 0, 1))
    law = mb.LinearContact(stiffness=1e4, damping=1.0)
    with pytest.raises(mb.ModelError, match="joint limit 'stop': give a Revolute, Prismatic, "
                       "Cylindrical, Planar or Spherical joint"):
        mb.JointLimit("stop", Universal("cross", b.ground, body, at=(0, 0, 0), axis_i=(1, 0, 0),
                                        axis_j=(0, 1, 0)), upper=1.0, law=law)
    for kwargs, words in [(dict(lower=1.0, upper=0.5), "lower must be below upper"),
                          (dict(lower=-4.0), r"inside it")]:
        builder = mb.ModelBuilder(dim=3)
        body = builder.add_body("body", mass=1.0, inertia=np.eye(3), position=(0.0, 0.0, 0.0))
        hinge = builder.add(Revolute("hinge", builder.ground, body, at=(0, 0, 0), axis=(0, 0, 1)))
        builder.add(mb.JointLimit("stop", hinge, law=law, **kwargs))
        with pytest.raises(mb.ModelError, match=f"joint limit 'stop': .*{words}"):
            builder.build()


def test_contacts_and_limits_round_trip_through_a_model_file(tmp_path):
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G), name="bounce and stop")
    ball = b.add_body("ball", mass=1.0, inertia=0.004, position=(0.3, 1.0),
                      velocity=(0.5, 0.0))
    b.add(mb.Contact("floor", mb.Sphere(ball, 0.1), mb.Plane(b.ground, normal=(0.1, 1.0)),
                     law=mb.HuntCrossley(1e7, 0.8, 2.0, calibration="flores"), friction=0.3))
    slider = b.add_body("slider", mass=2.0, inertia=0.01, position=(0.0, 2.0),
                        velocity=(1.0, 0.0))
    slide = b.add(Prismatic("slide", b.ground, slider, axis=(1.0, 0.0)))
    b.add(mb.JointLimit("ends", slide, upper=0.1, law=mb.LinearContact(frequency=50.0,
                                                                       restitution=0.5)))
    drop = b.add_body("drop", mass=1.0, inertia=0.004, position=(2.0, 0.3))
    b.add(mb.Contact("pad", mb.Sphere(drop, 0.1), mb.Plane(b.ground, normal=(0.0, 1.0)),
                     law=mb.ImpactFunction(1e6, 50.0, penetration=1e-3)))
    model = b.build()
    again = mb.load(mb.save(model, tmp_path / "contacts.yaml"))
    t = np.linspace(0.0, 0.6, 7)
    first, second = (mb.forward_dynamics(m, t, method="DOP853") for m in (model, again))
    np.testing.assert_array_equal(second.q, first.q)
    assert first.qd[-1, 3] < 0.0  # the slider came back from its stop
    text = (tmp_path / "contacts.yaml").read_text()
    assert "type: HuntCrossley" in text and "body: ball" in text
    assert "type: ImpactFunction" in text and first.q[-1, 7] > 0.1  # bounced off the pad


def _two_bars(dim, R=np.eye(3)):
    """No ground: a bar spinning at 3 rad/s carries a second one turning 6 rad/s faster on a
    hinge at their ends, limited to +-0.5 rad; in space the whole of it turned by ``R``. The
    hinge's angle (from the joint's own coordinates) and the first bar's angle."""
    b = mb.ModelBuilder(dim=dim)
    turn = (lambda v: tuple(v[:2])) if dim == 2 else (lambda v: tuple(R @ np.asarray(v)))
    inertia = 0.1 if dim == 2 else np.diag([0.01, 0.1, 0.1])
    extra = {} if dim == 2 else {"orientation": R}

    def spin(rate):
        return rate if dim == 2 else turn((0.0, 0.0, rate))

    first = b.add_body("first", mass=1.0, inertia=inertia, position=turn((0.5, 0.0, 0.0)),
                       angular_velocity=spin(3.0), **extra)
    # the hinge point moves at 3 x 0.5 = 1.5 m/s; the second bar turns at 9 rad/s about it
    second = b.add_body("second", mass=1.0, inertia=inertia, position=turn((1.5, 0.0, 0.0)),
                        velocity=turn((0.0, 1.5 + 9.0 * 0.5, 0.0)), angular_velocity=spin(9.0),
                        **extra)
    hinge = b.add(Revolute("hinge", first, second, at=turn((1.0, 0.0, 0.0)),
                           axis=None if dim == 2 else turn((0.0, 0.0, 1.0))))
    # damped, so that the stop's rate counts too
    b.add(mb.JointLimit("stop", hinge, lower=-0.5, upper=0.5,
                        law=mb.LinearContact(stiffness=1e5, restitution=0.8)))
    t = np.linspace(0.0, 1.0, 2001)
    res = mb.forward_dynamics(b.build(), t, method="DOP853", rtol=1e-11, atol=1e-13,
                              strict=True)
    return res.joint("hinge").angle, res.body("first").angle if dim == 2 else None


def test_a_hinge_stop_between_two_spinning_bodies_acts_at_their_relative_angle():
    angle, turned = _two_bars(2)
    assert angle.max() > 0.5 and angle.min() < -0.5  # both stops reached
    # the stiff stop lets the hinge past by at most its elastic dent, ~ rate sqrt(I/k)
    assert angle.max() < 0.52 and angle.min() > -0.52
    assert np.ptp(turned) > 1.0  # while the first bar turned a lot
    # the same in space, turned to a skew hinge axis, as the plane's
    skew, _ = _two_bars(3, Rotation.from_rotvec([0.4, -0.9, 0.6]).as_matrix())
    np.testing.assert_allclose(skew, angle, rtol=0, atol=1e-7)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_slide_stop_on_a_spinning_body_acts_at_the_relative_slide(dim):
    # no ground: a block slides on a turning bar (2 rad/s), thrown out at 1 m/s towards the
    # stop 0.3 m along it; the slide the joint reports turns back there, and with an elastic
    # stop the energy stays
    b = mb.ModelBuilder(dim=dim)
    pad = (0.0,) * (dim - 2)
    inertia = 0.2 if dim == 2 else np.diag([0.2, 0.2, 0.2])

    def spin(rate):
        return rate if dim == 2 else (0.0, 0.0, rate)

    bar = b.add_body("bar", mass=3.0, inertia=inertia, position=(0.0, 0.0) + pad,
                     angular_velocity=spin(2.0))
    block = b.add_body("block", mass=1.0, inertia=inertia, position=(0.4, 0.0) + pad,
                       velocity=(1.0, 2.0 * 0.4) + pad, angular_velocity=spin(2.0))
    slide = b.add(Prismatic("slide", bar, block, axis=(1.0, 0.0) + pad))
    b.add(mb.JointLimit("ends", slide, lower=-0.2, upper=0.3,
                        law=mb.LinearContact(stiffness=1e5, restitution=1.0)))
    model = b.build()
    res = mb.forward_dynamics(model, np.linspace(0.0, 1.5, 1501), method="DOP853", rtol=1e-11,
                              atol=1e-13, strict=True)
    s = res.joint("slide").displacement
    assert 0.3 < s.max() < 0.31  # reached the stop, let past by its elastic dent only
    charts = [None] * len(res.t) if res.charts is None else res.charts
    energy = np.array([mb.kinetic_energy(model, q, qd, c) + mb.potential_energy(model, q, c)
                       for q, qd, c in zip(res.q[::50], res.qd[::50], charts[::50])])
    np.testing.assert_allclose(energy, energy[0], rtol=0, atol=1e-8 * energy[0])
    R = res.body("bar").rotation  # the bar turned by more than a radian meanwhile
    assert math.acos((np.trace(R[0].T @ R[-1]) - (1 if dim == 3 else 0)) / 2) > 1.0


@pytest.mark.parametrize("lower, upper", [(0.4, 1.2), (-1.2, -0.4)])
def test_stops_both_on_one_side_of_zero_hold_at_both_ends(lower, upper):
    # a pendulum drawn half-way between its stops, thrown up at 4 rad/s: it meets the upper
    # stop, falls back onto the lower one and bounces between them (elastic stops); which
    # end is nearer must be judged from the ends themselves, not from zero
    middle, L, m = 0.5 * (lower + upper), 1.0, 1.5
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    rod = b.add_body("rod", mass=m, inertia=m * L * L / 12, angle=middle,
                     position=(L / 2 * math.cos(middle), L / 2 * math.sin(middle)))
    pin = b.add(Revolute("pin", b.ground, rod, at=(0.0, 0.0)))
    b.add(mb.JointLimit("stops", pin, lower=lower, upper=upper,
                        law=mb.LinearContact(stiffness=1e4, restitution=1.0)))
    res = mb.forward_dynamics(b.build(), np.linspace(0.0, 2.0, 2001),
                              initial_rates={"pin": 4.0}, method="DOP853", rtol=1e-10,
                              atol=1e-12)
    angle = res.joint("pin").angle
    assert angle.max() > upper and angle.min() < lower  # both ends met
    assert angle.max() < upper + 0.05 and angle.min() > lower - 0.05  # and held


def test_the_switch_is_positive_exactly_while_the_law_pushes():
    """A ball over a floor with a damped linear law (K = 1e5 N/m, c = 50 N s/m): its
    switching function is minus the gap while apart, the dent while pressed in and going in,
    and the dent times the force over the spring's and the damper's sizes, ``delta (K delta -
    c v) / (K delta + c v)`` (negative), while pressed in but leaving at ``v`` faster than the
    spring pushes, so that a step ends where the clipped force sets in, before the gap
    closes."""
    from mbd3d.model import constraints

    b = mb.ModelBuilder(dim=2)
    ball = b.add_body("ball", mass=1.0, inertia=1e-3, position=(0.0, 0.2))
    b.add(mb.Contact("floor", mb.Sphere(ball, radius=0.1), mb.Plane(b.ground, normal=(0, 1)),
                     law=mb.LinearContact(stiffness=1e5, damping=50.0)))
    model = b.build()
    group = next(g for g in model.force_groups if hasattr(g, "switches"))
    for height, speed, expected in ((0.11, 0.0, -0.01),            # apart by 1 cm
                                    (0.099, -0.1, 1e-3),           # pressed 1 mm, going in
                                    # leaving fast
                                    (0.099, 5.0, 1e-3 * (100 - 250) / (100 + 250))):
        q, qd = np.array([0.0, height, 0.0]), np.array([0.0, speed, 0.0])
        value = group.switches(model, constraints.frames(model, q, qd))[0]
        assert value == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("restitution", [1.0, 0.5])
def test_the_switch_of_a_hertz_contact_has_a_slope_where_it_opens(restitution):
    """Hertz's law (K = 1e8 N/m^1.5) on a ball of 1 kg over a floor: pressed in by ``delta``
    and leaving at ``v``, Tsuji's force ``K delta^(3/2) + alpha sqrt(m K) delta^(1/4) delta'``
    (``alpha`` calibrated for the restitution by SciPy on a free impact). The switching
    function has the force's sign, and is the dent itself, of slope one in it, where the
    undamped contact opens: ``F / K = delta^(3/2)`` has no slope at zero, and a secant on it
    never reaches the release."""
    from mbd3d.model import constraints

    K, m = 1e8, 1.0
    b = mb.ModelBuilder(dim=2)
    ball = b.add_body("ball", mass=m, inertia=1e-3, position=(0.0, 0.2))
    b.add(mb.Contact("floor", mb.Sphere(ball, radius=0.1), mb.Plane(b.ground, normal=(0, 1)),
                     law=mb.HertzContact(stiffness=K, restitution=restitution)))
    model = b.build()
    group = next(g for g in model.force_groups if hasattr(g, "switches"))
    alpha = 0.0 if restitution == 1.0 else _tsuji_alpha(restitution)
    for delta in (1e-9, 1e-6, 1e-4):
        for speed in (0.0, 0.3, 3.0):  # leaving the floor
            q, qd = np.array([0.0, 0.1 - delta, 0.0]), np.array([0.0, speed, 0.0])
            value = group.switches(model, constraints.frames(model, q, qd))[0]
            force = K * delta ** 1.5 - alpha * math.sqrt(m * K) * delta ** 0.25 * speed
            assert np.sign(value) == np.sign(force)
            if alpha == 0.0:
                assert value == pytest.approx(delta, rel=1e-9)


def _tsuji_alpha(e: float) -> float:
    """The damping factor ``alpha`` of Tsuji's Hertz law for which a free impact of unit mass
    and stiffness at unit speed rebounds with restitution ``e`` (the law is scale-free)."""
    def rebound(alpha: float) -> float:
        def rhs(_, y):
            d, v = y
            return [v, -max(0.0, max(d, 0.0) ** 1.5 + alpha * max(d, 0.0) ** 0.25 * v)]
        out = solve_ivp(rhs, (0.0, 20.0), [0.0, 1.0], rtol=1e-10, atol=1e-12,
                        events=_leaves, dense_output=False)
        return -out.y_events[0][0][1] - e
    return brentq(rebound, 0.0, 5.0)


def _leaves(_, y):
    return y[0] if y[1] < 0 else 1.0


_leaves.terminal, _leaves.direction = True, -1


def test_the_first_switch_is_where_the_earliest_sign_change_interpolates_to_zero():
    # the explicit loop's secant on the switching functions: the fraction of a step where the
    # first one crosses zero, by linear interpolation between the step's ends
    from mbd3d.numerics.compiled.integration import first_switch
    rng = np.random.default_rng(8)
    for _ in range(20):
        before, after = rng.normal(size=6), rng.normal(size=6)
        crossing = (before > 0) != (after > 0)
        expected = min((brentq(lambda s: b + s * (a - b), 0.0, 1.0)
                        for b, a in zip(before[crossing], after[crossing])), default=None)
        found = first_switch(before, after, 0.0)
        if expected is None:
            assert found > 1.0  # none: past the step's end
        else:
            assert found == pytest.approx(expected, rel=1e-12, abs=1e-15)
    assert first_switch(np.array([0.5, -1.0]), np.array([0.25, -2.0]), 0.0) > 1.0
    # a sign change within the noise is none (a corner skimming the floor: 1e-17 m)
    assert first_switch(np.array([-4e-18, 0.5]), np.array([1.3e-16, 0.25]), 1e-14) > 1.0
    assert first_switch(np.array([-4e-18, 0.5]), np.array([1.3e-16, -0.25]), 1e-14) == \
        pytest.approx(2 / 3)
