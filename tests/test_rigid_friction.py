"""Coulomb friction at rigid contacts held at rest (:mod:`mbd3d.analyses.sticking`): a held
contact sticks while its friction stays within ``mu N`` and slides with ``mu N`` against the
slip beyond, each switch located as an event. Checked against closed forms derived here from
Newton's laws alone: a ball (a disc in the plane) thrown sliding, which rolls from where its
slip has run out; a block on an incline that holds, that slides, that is pushed up and stops
(to stay, or to slide back); a block under a push growing in time, which holds until the push
reaches ``mu m g``; and the energy balance, in which friction takes what the motion loses."""

from __future__ import annotations

import math

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.errors import ModelError
from mbd3d.joints import Prismatic, TranslationDriver

G = 9.81
TIGHT = dict(method="DOP853", rtol=1e-10, atol=1e-12)
#: the block: edge lengths along the slope, across it (spatial) and up from it [m], mass [kg]
LENGTH, WIDTH, HEIGHT, MASS = 0.4, 0.3, 0.2, 3.0
#: where the slider pulling the block starts, along x [m]
PULLER = 0.5


def ball_on_floor(dim: int, mu: float, radius: float = 0.1, mass: float = 2.0) -> mb.Model:
    """A disc (planar) or a ball (spatial) touching a rigid floor with friction ``mu``."""
    b = mb.ModelBuilder(dim=dim, gravity=(0.0, -G) if dim == 2 else (0.0, 0.0, -G))
    if dim == 2:
        ball = b.add_body("ball", mass=mass, inertia=0.5 * mass * radius ** 2,
                          position=(0.0, radius))
        floor = mb.Plane(b.ground, normal=(0.0, 1.0))
    else:
        ball = b.add_body("ball", mass=mass, inertia=0.4 * mass * radius ** 2 * np.ones(3),
                          position=(0.0, 0.0, radius))
        floor = mb.Plane(b.ground, normal=(0.0, 0.0, 1.0))
    b.add(mb.Contact("floor", mb.Sphere(ball, radius), floor,
                     law=mb.RigidImpact(restitution=0.0), friction=mu))
    return b.build()


def thrown_ball(dim: int, mu: float, radius: float, mass: float) -> tuple:
    """``(model, k, v0, qd0)``: the ball of :func:`ball_on_floor` thrown along the floor at
    ``v0`` without spin (slanted in space), ``k = 1 + m r^2 / I``."""
    model = ball_on_floor(dim, mu, radius, mass)
    v0 = np.array([1.5, 0.0]) if dim == 2 else np.array([1.2, -0.9, 0.0])
    qd0 = np.zeros(model.n_coordinates)
    qd0[:dim] = v0
    return model, 3.0 if dim == 2 else 3.5, v0, qd0


@pytest.mark.parametrize("dim", [2, 3])
def test_a_ball_thrown_sliding_rolls_from_where_its_slip_runs_out(dim):
    """Thrown at v0 without spin, the contact slips at s = v0 - mu g k t (friction mu m g
    slows the centre and spins the ball up, k = 1 + m r^2 / I: 3 for a disc, 7/2 for a
    ball), so it sticks at t* = v0 / (mu g k) and rolls on at v0 - mu g t*, having lost
    m v0^2 / (2 k) to friction. In space the throw is slanted and the ball spins about
    the vertical too: the slip stays along the throw, the spin (no drilling friction at a
    point) stays as it is."""
    mu, radius, mass = 0.3, 0.1, 2.0
    model, k, v0, qd0 = thrown_ball(dim, mu, radius, mass)
    if dim == 3:
        qd0[5] = 3.0 / 2  # the Rodrigues rate of a spin of 3 rad/s about z, from g = 0
    t = np.linspace(0.0, 0.5, 51)
    res = mb.forward_dynamics(model, t, qd0=qd0, **TIGHT)
    assert res.status == "complete"
    speed = float(np.linalg.norm(v0))
    along = v0 / speed
    t_stick = speed / (mu * G * k)
    sticks = [r for r in res.stats["rests"] if r["event"] == "stick"]
    assert len(sticks) == 1 and sticks[0]["contacts"] == ["floor"]
    np.testing.assert_allclose(sticks[0]["time"], t_stick, rtol=0, atol=1e-9)
    v_end = (speed - mu * G * t_stick) * along
    ball = res.body("ball")
    np.testing.assert_allclose(ball.velocity[-1, :dim], v_end, rtol=0, atol=1e-9)
    reach = speed * t_stick - 0.5 * mu * G * t_stick ** 2 + float(
        np.linalg.norm(v_end)) * (t[-1] - t_stick)
    np.testing.assert_allclose(ball.position[-1, :dim] - ball.position[0, :dim],
                               reach * along, rtol=0, atol=1e-9)
    # rolling: the contact point at rest, v = omega x r
    omega = ball.angular_velocity[-1]
    if dim == 2:
        np.testing.assert_allclose(-float(np.ravel(omega)[-1]) * radius, v_end[0], rtol=1e-9)
    else:
        np.testing.assert_allclose(np.cross(omega, [0.0, 0.0, radius]), v_end, rtol=0,
                                   atol=1e-9)
        np.testing.assert_allclose(omega[2], 3.0, rtol=1e-9)
    # the friction on the floor: mu m g along the slip while it slides, none once it rolls
    contacts = res.contacts()
    sliding, rolling = t < t_stick - 1e-6, t > t_stick + 1e-6
    F = contacts.friction_force[sliding, 0, :dim]
    size = np.linalg.norm(F, axis=1)
    np.testing.assert_allclose(size, mu * mass * G, rtol=1e-9)
    # its direction, the slip's, to the integration's error in a slip that runs out
    slip = speed - mu * G * k * t[sliding]
    assert np.all(np.linalg.norm(F / size[:, None] - along, axis=1) <= 1e-9 * speed / slip)
    # (to the convective terms' differences, 1e-10 of the turning's accelerations)
    np.testing.assert_allclose(contacts.friction_force[rolling, 0], 0.0, rtol=0,
                               atol=1e-9 * mass * G)
    np.testing.assert_allclose(contacts.normal_force[:, 0], mass * G, rtol=1e-9)
    energy = res.energy_balance()
    lost = 0.5 * mass * speed ** 2 / k
    np.testing.assert_allclose(energy["dissipated"][-1], lost, rtol=1e-8)
    np.testing.assert_allclose(energy["total"], energy["total"][0], rtol=1e-9)


@pytest.mark.parametrize("dim", [2, pytest.param(3, marks=pytest.mark.compiled_only)])
def test_generalized_alpha_holds_a_sliding_ball_until_it_rolls_as_the_closed_form_says(dim):
    """The throw of the test above with generalized-alpha, which holds a rigid contact and
    its friction as the explicit methods do (the held row's forces at each Newton
    iterate's state). A disc's forces are constant while it slides and zero once it rolls,
    on which the method is exact: the stick at v0 / (mu g k), the rolling speed and the
    energy friction takes to 1e-9. A ball's turning makes the method's O(h^2) error: the
    stick time and rolling speed converge to the closed form at second order, a quarter of
    the error for half the step."""
    mu, radius, mass = 0.3, 0.1, 2.0
    model, k, v0, qd0 = thrown_ball(dim, mu, radius, mass)
    speed = float(np.linalg.norm(v0))
    t_stick = speed / (mu * G * k)
    v_end = (speed - mu * G * t_stick) * v0 / speed
    errors = []
    for h in (1e-3,) if dim == 2 else (1e-3, 5e-4):
        res = mb.forward_dynamics(model, np.linspace(0.0, 0.2, 21), qd0=qd0,
                                  method="generalized-alpha", step=h)
        assert res.status == "complete"
        sticks = [r["time"] for r in res.stats["rests"] if r["event"] == "stick"]
        assert len(sticks) == 1
        errors.append(np.array([abs(sticks[0] - t_stick), np.max(np.abs(
            res.body("ball").velocity[-1, :dim] - v_end))]))
        energy = res.energy_balance()
    if dim == 2:
        assert np.all(errors[0] <= 1e-9)
        np.testing.assert_allclose(energy["dissipated"][-1], 0.5 * mass * speed ** 2 / k,
                                   rtol=1e-9)
        np.testing.assert_allclose(energy["total"], energy["total"][0], rtol=1e-9)
    else:  # 1.5e-6 s and 5.3e-6 m/s at 1 ms
        ratio = errors[0] / errors[1]
        assert np.all((ratio >= 3.5) & (ratio <= 4.5)) and np.all(errors[0] <= 1e-4)


def block_on_slope(dim: int, mu: float, alpha: float, pull: tuple | None = None,
                   static: float | None = None) -> mb.Model:
    """A block lying flat on a rigid floor with friction ``mu``, gravity tilted by ``alpha``
    down the +x axis (an incline), its corners the contacts; ``pull = (k, v)``: a spring of
    stiffness k [N/m] from its centre of mass, slack at the start, along x to a slider driven
    away at v [m/s]; ``static``: a static coefficient above ``mu`` (the kinetic one)."""
    down = (math.sin(alpha), -math.cos(alpha))
    if dim == 2:
        b = mb.ModelBuilder(dim=2, gravity=(G * down[0], G * down[1]))
        block = b.add_body("block", mass=MASS, inertia=MASS * (LENGTH ** 2 + HEIGHT ** 2) / 12,
                           position=(0.0, HEIGHT / 2))
        size, floor = (LENGTH, HEIGHT), mb.Plane(b.ground, normal=(0.0, 1.0))
    else:
        b = mb.ModelBuilder(dim=3, gravity=(G * down[0], 0.0, G * down[1]))
        inertia = MASS / 12 * np.array([WIDTH ** 2 + HEIGHT ** 2, LENGTH ** 2 + HEIGHT ** 2,
                                        LENGTH ** 2 + WIDTH ** 2])
        block = b.add_body("block", mass=MASS, inertia=inertia, position=(0.0, 0.0, HEIGHT / 2))
        size, floor = (LENGTH, WIDTH, HEIGHT), mb.Plane(b.ground, normal=(0.0, 0.0, 1.0))
    b.add(mb.Contact("floor", mb.Box(block, size), floor,
                     law=mb.RigidImpact(restitution=0.0, static_friction=static), friction=mu))
    if pull is not None:
        end = (PULLER,) + (0.0,) * (dim - 2) + (HEIGHT / 2,)
        puller = b.add_body("puller", mass=1.0, inertia=0.01 if dim == 2 else (0.01,) * 3,
                            position=end)
        rail = b.add(Prismatic("rail", b.ground, puller, axis=(1.0,) + (0.0,) * (dim - 1),
                               at=end))
        b.add(TranslationDriver("pull", rail, motion=mb.Ramp(0.0, pull[1])))
        b.add(mb.SpringDamper("spring", block, puller, stiffness=pull[0]))
    return b.build()


def lower_corners(names: list[str], dim: int) -> tuple[list[int], list[int]]:
    """The indices of the block's lower corners at its back (-x) and at its front (+x)."""
    signs = [name[name.index("corner ") + 7:-1] for name in names]
    lower = [k for k, s in enumerate(signs) if s[dim - 1] == "-"]
    return [k for k in lower if signs[k][0] == "-"], [k for k in lower if signs[k][0] == "+"]


def slope_loads(friction: float, alpha: float) -> tuple[float, float]:
    """The normal forces [N] on the block's back and front edges when the floor's friction
    on it is ``friction`` [N] up the slope: the weight's part square to the slope, shared
    so that the moments about the centre of mass balance, the friction's (at the floor,
    ``HEIGHT / 2`` below it) leaning the block onto its front:
    ``N_front - N_back = friction HEIGHT / LENGTH``."""
    square = MASS * G * math.cos(alpha)
    lean = friction * HEIGHT / LENGTH
    return 0.5 * (square - lean), 0.5 * (square + lean)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_block_on_an_incline_holds_where_mu_exceeds_the_slope_and_slides_where_not(dim):
    """Held (tan alpha < mu): it stays, its friction m g sin(alpha) shared so that every
    corner is equally near its cone (|F_t| / N = tan alpha at each); the edges carry the
    moment balance's normal forces. Sliding (mu < tan alpha): it moves down by
    g (sin(alpha) - mu cos(alpha)) t^2 / 2 with mu N at every corner."""
    alpha, t = 0.5, np.linspace(0.0, 0.8, 41)
    held = mb.forward_dynamics(block_on_slope(dim, 0.8, alpha), t, **TIGHT)
    assert held.status == "complete"
    np.testing.assert_allclose(held.body("block").position[:, 0], 0.0, rtol=0, atol=1e-12)
    contacts = held.contacts()
    back, front = lower_corners(contacts.names, dim)
    assert len(back) == len(front) == dim - 1
    N, F = contacts.normal_force, np.linalg.norm(contacts.friction_force, axis=2)
    np.testing.assert_allclose(F[:, back + front] / N[:, back + front], math.tan(alpha),
                               rtol=1e-9)
    loads = slope_loads(MASS * G * math.sin(alpha), alpha)
    np.testing.assert_allclose(N[:, back].sum(axis=1), loads[0], rtol=1e-9)
    np.testing.assert_allclose(N[:, front].sum(axis=1), loads[1], rtol=1e-9)

    mu = 0.3
    sliding = mb.forward_dynamics(block_on_slope(dim, mu, alpha), t, **TIGHT)
    assert sliding.status == "complete"
    assert [r["event"] for r in sliding.stats["rests"]] == ["rest"]  # it never sticks
    a = G * (math.sin(alpha) - mu * math.cos(alpha))
    np.testing.assert_allclose(sliding.body("block").position[:, 0], 0.5 * a * t ** 2,
                               rtol=0, atol=1e-9)
    contacts = sliding.contacts()
    N, F = contacts.normal_force, np.linalg.norm(contacts.friction_force, axis=2)
    np.testing.assert_allclose(F[:, back + front], mu * N[:, back + front], rtol=1e-9)
    loads = slope_loads(mu * MASS * G * math.cos(alpha), alpha)
    np.testing.assert_allclose(N[:, back].sum(axis=1), loads[0], rtol=1e-9)
    np.testing.assert_allclose(N[:, front].sum(axis=1), loads[1], rtol=1e-9)


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("mu", [0.8, 0.3])
def test_a_block_pushed_up_an_incline_stops_then_stays_or_slides_back(dim, mu):
    """Thrown up the slope at v0, it slows at g (sin(alpha) + mu cos(alpha)) and stops at
    t_s. Where mu > tan(alpha) it sticks there for good; else it slides back down at
    g (sin(alpha) - mu cos(alpha)), the friction turned round."""
    alpha, v0 = 0.5, 1.2
    model = block_on_slope(dim, mu, alpha)
    qd0 = np.zeros(model.n_coordinates)
    qd0[0] = -v0
    t = np.linspace(0.0, 0.6, 61)
    res = mb.forward_dynamics(model, t, qd0=qd0, **TIGHT)
    assert res.status == "complete"
    up = G * (math.sin(alpha) + mu * math.cos(alpha))
    t_stop = v0 / up
    x_stop = -0.5 * v0 * t_stop
    x = res.body("block").position[:, 0]
    before, after = t <= t_stop, t > t_stop
    np.testing.assert_allclose(x[before], -v0 * t[before] + 0.5 * up * t[before] ** 2,
                               rtol=0, atol=1e-9)
    events = [r for r in res.stats["rests"] if r["event"] in ("stick", "slip")]
    if mu > math.tan(alpha):
        assert [r["event"] for r in events] == ["stick"]
        np.testing.assert_allclose(events[0]["time"], t_stop, rtol=0, atol=1e-9)
        np.testing.assert_allclose(x[after], x_stop, rtol=0, atol=1e-9)
    else:
        assert events == []  # the stick it tried would not hold: it slides on, turned round
        down = G * (math.sin(alpha) - mu * math.cos(alpha))
        np.testing.assert_allclose(x[after], x_stop + 0.5 * down * (t[after] - t_stop) ** 2,
                                   rtol=0, atol=1e-9)


@pytest.mark.parametrize("phi0", [math.pi / 2, 3 * math.pi / 4])
def test_a_block_thrown_across_an_incline_turns_downhill_as_a_particle_does(phi0):
    """With mu = tan(alpha), a block thrown across the slope (phi0 = 90 degrees from the
    downhill direction) or across and up (135) turns downhill: along its path friction
    cancels gravity's part but for g sin(alpha) (cos(phi) - 1), across it gravity turns it,
    v dphi/dt = -g sin(alpha) sin(phi), so that v (1 + cos(phi)) = C = v0 (1 + cos(phi0))
    and, with u = tan(phi / 2), ln(u) / 2 + u^2 / 4 falls at g sin(alpha) / C. The block
    slides as a particle: the friction's moment about the normal is zero, its centre of
    pressure lying on its path. In space only: the slip's direction turns (by more than a
    right angle from 135 degrees, where a slide watched along its first direction would
    seem to stop)."""
    from scipy.optimize import brentq

    alpha, v0 = 0.5, 1.0
    model = block_on_slope(3, math.tan(alpha), alpha)
    qd0 = np.zeros(model.n_coordinates)
    qd0[:2] = v0 * math.cos(phi0), v0 * math.sin(phi0)
    t = np.linspace(0.0, 0.5, 26)
    res = mb.forward_dynamics(model, t, qd0=qd0, **TIGHT)
    assert res.status == "complete"
    assert [r["event"] for r in res.stats["rests"]] == ["rest"]
    block = res.body("block")
    v = block.velocity[:, :2]
    speed, phi = np.linalg.norm(v, axis=1), np.arctan2(v[:, 1], v[:, 0])
    C = v0 * (1.0 + math.cos(phi0))
    np.testing.assert_allclose(speed * (1.0 + np.cos(phi)), C, rtol=1e-9)
    u0, rate = math.tan(phi0 / 2), G * math.sin(alpha) / C

    def falls(u: float, tk: float) -> float:
        return 0.5 * math.log(u / u0) + 0.25 * (u * u - u0 * u0) + rate * tk
    u = [brentq(falls, 1e-12, u0, args=(tk,), xtol=1e-15) for tk in t[1:]]
    np.testing.assert_allclose(phi[1:], 2.0 * np.arctan(u), rtol=0, atol=1e-9)
    assert phi[-1] < phi0 - math.pi / 2 if phi0 > math.pi / 2 else True
    np.testing.assert_allclose(block.angular_velocity, 0.0, rtol=0, atol=1e-9)


@pytest.mark.compiled_only
def test_generalized_alpha_turns_a_block_thrown_across_an_incline_at_second_order():
    """The throw across and up the incline of the test above (135 degrees) with
    generalized-alpha holding the block's four corners and their friction: ``v (1 +
    cos(phi))`` and the angle's closed form (brentq) converge at second order (errors of
    4.9e-5 and 2.2e-5 rad at 1 ms, a quarter of that at half the step), and the block
    does not turn about the normal."""
    from scipy.optimize import brentq

    alpha, v0, phi0 = 0.5, 1.0, 3 * math.pi / 4
    model = block_on_slope(3, math.tan(alpha), alpha)
    qd0 = np.zeros(model.n_coordinates)
    qd0[:2] = v0 * math.cos(phi0), v0 * math.sin(phi0)
    t = np.linspace(0.0, 0.25, 26)
    C = v0 * (1.0 + math.cos(phi0))
    u0, rate = math.tan(phi0 / 2), G * math.sin(alpha) / C

    def falls(u: float, tk: float) -> float:
        return 0.5 * math.log(u / u0) + 0.25 * (u * u - u0 * u0) + rate * tk
    exact = 2.0 * np.arctan([brentq(falls, 1e-12, u0, args=(tk,), xtol=1e-15)
                             for tk in t[1:]])
    errors = []
    for h in (1e-3, 5e-4):
        res = mb.forward_dynamics(model, t, qd0=qd0, method="generalized-alpha", step=h)
        assert res.status == "complete"
        assert [r["event"] for r in res.stats["rests"]] == ["rest"]
        block = res.body("block")
        v = block.velocity[:, :2]
        speed, phi = np.linalg.norm(v, axis=1), np.arctan2(v[:, 1], v[:, 0])
        errors.append(np.array([np.max(np.abs(speed * (1.0 + np.cos(phi)) / C - 1.0)),
                                np.max(np.abs(phi[1:] - exact))]))
        np.testing.assert_allclose(block.angular_velocity, 0.0, rtol=0, atol=1e-9)
    ratio = errors[0] / errors[1]
    assert np.all((ratio >= 3.5) & (ratio <= 4.5)) and np.all(errors[0] <= 1e-4)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_block_pulled_by_a_spring_holds_until_the_pull_reaches_mu_m_g(dim):
    """A spring (k) whose far end moves away at v pulls the block with k v t while it holds,
    until k v t_1 = mu m g; from there m x'' = k (v t - x) - mu m g, whose solution from
    rest is x = v (tau - sin(w tau) / w), tau = t - t_1, w^2 = k / m (checked here for half a
    swing: at w tau = 2 pi its slip would come back to zero just at its cone). The energy
    friction takes is mu m g x."""
    mu, k, v = 0.4, 200.0, 0.15
    t = np.linspace(0.0, 0.7, 71)
    res = mb.forward_dynamics(block_on_slope(dim, mu, 0.0, pull=(k, v)), t, **TIGHT)
    assert res.status == "complete"
    t1, w = mu * MASS * G / (k * v), math.sqrt(k / MASS)
    assert t[-1] - t1 < math.pi / w
    slips = [r for r in res.stats["rests"] if r["event"] == "slip"]
    assert len(slips) == 1 and len(slips[0]["contacts"]) == 2 * (dim - 1)  # all at once
    np.testing.assert_allclose(slips[0]["time"], t1, rtol=0, atol=1e-9)
    assert [r["event"] for r in res.stats["rests"]].count("stick") == 1  # at the start only
    x = res.body("block").position[:, 0]
    np.testing.assert_allclose(x[t <= t1], 0.0, rtol=0, atol=1e-12)
    tau = t[t > t1] - t1
    np.testing.assert_allclose(x[t > t1], v * (tau - np.sin(w * tau) / w), rtol=0, atol=1e-9)
    contacts = res.contacts()
    F = np.linalg.norm(contacts.friction_force, axis=2).sum(axis=1)
    np.testing.assert_allclose(F[t <= t1], k * v * t[t <= t1], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(F[t > t1], mu * MASS * G, rtol=1e-9)
    np.testing.assert_allclose(res.energy_balance()["dissipated"], mu * MASS * G * x,
                               rtol=1e-8, atol=1e-12)


def test_the_friction_of_a_held_contact_is_kept_in_a_results_file_and_on_the_time_line(
        tmp_path):
    """Written and read back, a run keeps its held contacts' friction forces; the recording
    says where the ball starts to roll."""
    from mbd3d.viewer import read_component, record

    model = ball_on_floor(2, 0.3)
    qd0 = np.zeros(model.n_coordinates)
    qd0[0] = 1.0
    res = mb.forward_dynamics(model, np.linspace(0.0, 0.2, 11), qd0=qd0, **TIGHT)
    path = tmp_path / "ball.npz"
    res.to_npz(path)
    back = mb.read_results(path, model)
    np.testing.assert_array_equal(back.contacts().friction_force, res.contacts().friction_force)
    assert np.any(back.contacts().friction_force != 0.0)
    record(res, tmp_path / "ball.rrd")
    times, text = read_component(tmp_path / "ball.rrd", "/impacts/rests", "TextLog:text",
                                 timeline="sim_time")
    assert [str(row[0]) for row in text][1].startswith("floor sticks (its slip took")
    stick = res.stats["rests"][1]["time"]
    np.testing.assert_allclose(times[1].astype(np.int64) * 1e-9, stick, atol=1e-9)


@pytest.mark.parametrize("dim", [2, pytest.param(3, marks=pytest.mark.compiled_only)])
def test_a_block_pulled_through_a_spring_sticks_and_slips_in_a_limit_cycle(dim):
    """With a static coefficient mu_s above the kinetic mu_k (``RigidImpact(static_friction)``)
    the pulled block of the test above sticks and slips for ever: it holds until the spring's
    k e = mu_s m g, then slides with y = e - mu_k m g / k swinging as
    y = D cos(w tau) + (v / w) sin(w tau) from y = D = (mu_s - mu_k) m g / k, until its
    speed v - y' is zero again at w tau = pi + 2 phi, tan(phi) = v / (w D), where y = -D:
    the spring then pulls with (2 mu_k - mu_s) m g, inside the cone, and it sticks until
    y is back at D, 2 D / v later. Every slip and stick at its closed-form time (1e-9 s), the
    block where y puts it (1e-9 m), friction mu_k m g while it slides and the spring's pull
    while it sticks, and mu_k m g times the way slid dissipated."""
    # mu_s > 3 mu_k: where it sticks, the spring pushes it back harder than mu_k m g
    mu_k, mu_s, k, v = 0.15, 0.5, 200.0, 0.15
    D, w = (mu_s - mu_k) * MASS * G / k, math.sqrt(k / MASS)
    phi = math.atan2(v / w, D)
    t1, slide, stick = mu_s * MASS * G / (k * v), (math.pi + 2 * phi) / w, 2 * D / v
    period = slide + stick
    t = np.linspace(0.0, t1 + 2 * period + 0.5 * slide, 121)
    res = mb.forward_dynamics(block_on_slope(dim, mu_k, 0.0, pull=(k, v), static=mu_s), t,
                              **TIGHT)
    assert res.status == "complete"
    switches = [(r["time"], r["event"]) for r in res.stats["rests"]
                if r["event"] in ("stick", "slip") and r["time"] > 0.0]
    expected = [(t1 + n * period + shift, event) for n in range(3)
                for shift, event in ((0.0, "slip"), (slide, "stick"))][:5]
    assert [e for _, e in switches] == [e for _, e in expected]
    np.testing.assert_allclose([s for s, _ in switches], [s for s, _ in expected], rtol=0,
                               atol=1e-9)
    # y over time: D cos + (v / w) sin while sliding (from each slip), rising at v while stuck
    cycle = np.mod(t - t1, period)
    y = np.where(cycle < slide, D * np.cos(w * cycle) + v / w * np.sin(w * cycle),
                 -D + v * (cycle - slide))
    y = np.where(t < t1, v * t - mu_k * MASS * G / k, y)
    x = res.body("block").position[:, 0]
    np.testing.assert_allclose(x, v * t - y - mu_k * MASS * G / k, rtol=0, atol=1e-9)
    F = np.linalg.norm(res.contacts().friction_force, axis=2).sum(axis=1)
    sliding = (t > t1) & (cycle > 1e-6) & (cycle < slide - 1e-6)
    np.testing.assert_allclose(F[sliding], mu_k * MASS * G, rtol=1e-9)
    np.testing.assert_allclose(F[~sliding], k * np.abs(v * t - x)[~sliding], rtol=1e-9,
                               atol=1e-9)
    np.testing.assert_allclose(res.energy_balance()["dissipated"], mu_k * MASS * G * x,
                               rtol=1e-8, atol=1e-12)


def test_a_static_coefficient_below_the_kinetic_one_is_refused_naming_the_contact():
    """Sticking must hold at least what sliding rubs: mu_s >= mu_k, else refused by name."""
    with pytest.raises(ModelError, match=r"contact 'floor'.*static_friction 0\.2 is below its "
                                         r"friction 0\.3"):
        block_on_slope(2, 0.3, 0.0, static=0.2)


def test_a_static_coefficient_is_kept_in_a_model_file(tmp_path):
    """Saved and loaded, the block still holds until the spring pulls with mu_s m g (the
    kinetic coefficient would let it go at a third of that time), and names its parameter."""
    mu_k, mu_s, k, v = 0.15, 0.5, 200.0, 0.15
    path = tmp_path / "stick_slip.yaml"
    mb.save(block_on_slope(2, mu_k, 0.0, pull=(k, v), static=mu_s), path)
    model = mb.load(path)
    assert "forces.floor.law.static_friction" in mb.parameters(model)
    res = mb.forward_dynamics(model, np.linspace(0.0, 0.6, 7), **TIGHT)
    slips = [r["time"] for r in res.stats["rests"] if r["event"] == "slip"]
    np.testing.assert_allclose(slips[0], mu_s * MASS * G / (k * v), rtol=0, atol=1e-9)


def test_a_rod_whose_sliding_end_would_jam_is_refused_naming_it():
    """Painleve's rod: a rod at 45 degrees (1 m, 1 kg) whose lower end slides on the floor
    towards its foot with friction mu = 2. The end's normal acceleration per unit normal
    force is (1 + 3 cos^2 - 3 mu sin cos) / m = -0.5 / m: friction would press the end down
    the harder, the harder the floor pushed (no force holds it, none lets it go), so the
    run is refused where it starts, naming the contact and the time, with the results so
    far attached."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    theta = math.pi / 4
    rod = b.add_body("rod", mass=1.0, inertia=1.0 / 12,
                     position=(0.5 * math.cos(theta), 0.5 * math.sin(theta)), angle=theta,
                     velocity=(-1.0, 0.0))
    b.add(mb.Contact("end", mb.Sphere(rod, 1e-3, point=(-0.5, 0.0)),
                     mb.Plane(b.ground, normal=(0.0, 1.0), point=(0.0, -1e-3)),
                     law=mb.RigidImpact(restitution=0.0), friction=2.0))
    with pytest.raises(ModelError, match=r"held at rest \('end'\) at t = 0 s.*Painleve") as error:
        mb.forward_dynamics(b.build(), np.linspace(0.0, 0.2, 3), **TIGHT)
    assert error.value.results.status == "failed"
