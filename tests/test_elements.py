"""Joints, drivers and force elements against closed forms and minimal equations."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

import mbd3d as mb
from mbd3d.joints import CoordinateDriver, Distance, Fixed, Prismatic, Revolute, TranslationDriver
from mbd3d.mechanisms import slider_crank

G = 9.81


def test_spring_damper_on_a_slider_is_a_damped_oscillator():
    m, k, c, l0 = 2.0, 800.0, 8.0, 1.0
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    mass = b.add_body("mass", mass=m, inertia=0.1, position=(0.0, -l0))
    b.add(Prismatic("guide", b.ground, mass, axis=(0.0, 1.0)))
    b.add(mb.SpringDamper("spring", b.ground, mass, at_i=(0.0, 0.0), stiffness=k, damping=c))
    t = np.linspace(0.0, 1.0, 51)
    res = mb.forward_dynamics(b.build(), t, method="DOP853", rtol=1e-11, atol=1e-12)
    # z = y + l0 + m g / k obeys m z'' + c z' + k z = 0, z(0) = m g / k, z'(0) = 0
    wn = math.sqrt(k / m)
    zeta = c / (2 * math.sqrt(k * m))
    wd = wn * math.sqrt(1 - zeta**2)
    z0 = m * G / k
    z = np.exp(-zeta * wn * t) * (z0 * np.cos(wd * t) + zeta * wn * z0 / wd * np.sin(wd * t))
    np.testing.assert_allclose(res.body("mass").position[:, 1], z - l0 - m * G / k,
                               rtol=0, atol=1e-10)
    # the guide carries no vertical force, no moment on a centred mass
    guide = res.joint("guide").reaction(on="mass", frame="joint")
    np.testing.assert_allclose(guide.force[:, 0], 0.0, rtol=0, atol=1e-9)


def test_rotational_spring_is_a_torsional_oscillator():
    J, k, w0 = 0.05, 3.0, 2.0
    b = mb.ModelBuilder(dim=2)
    disc = b.add_body("disc", mass=1.0, inertia=J, position=(0.0, 0.0), angle=0.3,
                      angular_velocity=w0)
    b.add(Revolute("axle", b.ground, disc, at=(0.0, 0.0)))
    b.add(mb.RotationalSpringDamper("torsion", b.ground, disc, stiffness=k))
    t = np.linspace(0.0, 2.0, 41)
    res = mb.forward_dynamics(b.build(), t, method="DOP853", rtol=1e-11, atol=1e-12)
    wn = math.sqrt(k / J)
    np.testing.assert_allclose(res.body("disc").angle, 0.3 + w0 / wn * np.sin(wn * t),
                               rtol=0, atol=1e-9)
    energy = res.kinetic_energy + res.potential_energy
    np.testing.assert_allclose(energy, 0.5 * J * w0**2, rtol=1e-9)


def test_free_body_with_feedback_drag_and_torque():
    m, c, J, T = 3.0, 1.5, 0.2, 0.7
    b = mb.ModelBuilder(dim=2)
    body = b.add_body("puck", mass=m, inertia=J, position=(0.0, 0.0), velocity=(1.0, 2.0))
    b.add(mb.PointForce("drag", body, lambda t, state: -c * state.velocity))
    b.add(mb.Torque("spin", body, lambda t: T))
    model = b.build()
    assert model.n_constraints == 0
    t = np.linspace(0.0, 2.0, 21)
    res = mb.forward_dynamics(model, t, method="DOP853", rtol=1e-11, atol=1e-12)
    decay = np.exp(-c * t / m)
    np.testing.assert_allclose(res.body("puck").velocity, np.outer(decay, (1.0, 2.0)),
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.body("puck").position,
                               np.outer(m / c * (1 - decay), (1.0, 2.0)), rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.body("puck").angle, 0.5 * T / J * t**2, rtol=0, atol=1e-9)


def test_welded_bodies_swing_as_one_compound_pendulum():
    mA, L, mB, JB = 1.0, 1.0, 0.5, 0.02
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    bar = b.add_body("bar", mass=mA, inertia=mA * L * L / 12, position=(L / 2, 0.0))
    bob = b.add_body("bob", mass=mB, inertia=JB, position=(L, 0.0), angle=0.4)
    b.add(Revolute("pivot", b.ground, bar, at=(0.0, 0.0)))
    b.add(Fixed("weld", bar, bob))
    t = np.linspace(0.0, 1.5, 31)
    res = mb.forward_dynamics(b.build(), t, method="DOP853", rtol=1e-11, atol=1e-12)
    I_o = mA * L * L / 3 + JB + mB * L * L
    sol = solve_ivp(lambda _, y: [y[1], -G * (mA * L / 2 + mB * L) * math.cos(y[0]) / I_o],
                    (0, 1.5), [0.0, 0.0], t_eval=t, method="DOP853", rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res.body("bar").angle, sol.y[0], rtol=0, atol=1e-8)
    np.testing.assert_allclose(res.body("bob").angle - res.body("bar").angle, 0.4,
                               rtol=0, atol=1e-12)
    # Newton-Euler of the bob: the weld supplies m a - m g and the moment J alpha
    bob_h = res.body("bob")
    weld = res.joint("weld").reaction(on="bob")
    np.testing.assert_allclose(weld.force, mB * (bob_h.acceleration - [0.0, -G]),
                               rtol=0, atol=1e-8)
    np.testing.assert_allclose(weld.moment, JB * bob_h.angular_acceleration, rtol=0, atol=1e-8)


def test_distance_joint_is_a_massless_rod():
    m, L = 1.2, 0.8
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G))
    bob = b.add_body("bob", mass=m, inertia=0.01, position=(L, 0.0), angular_velocity=3.0)
    b.add(Distance("rod", b.ground, bob, at_i=(0.0, 0.0)))
    t = np.linspace(0.0, 1.0, 21)
    res = mb.forward_dynamics(b.build(), t, method="DOP853", rtol=1e-11, atol=1e-12)
    # the rod leaves the bob's rotation free; its centre is a simple pendulum
    np.testing.assert_allclose(res.body("bob").angular_velocity, 3.0, rtol=0, atol=1e-9)
    sol = solve_ivp(lambda _, y: [y[1], -G / L * math.cos(y[0])], (0, 1), [0.0, 0.0],
                    t_eval=t, method="DOP853", rtol=1e-12, atol=1e-12)
    phi, phi_dot = sol.y
    pos = res.body("bob").position
    np.testing.assert_allclose(np.arctan2(pos[:, 1], pos[:, 0]), phi, rtol=0, atol=1e-8)
    tension = m * L * phi_dot**2 - m * G * np.sin(phi)
    e = np.column_stack([np.cos(phi), np.sin(phi)])
    np.testing.assert_allclose(res.joint("rod").reaction(on="bob").force, -tension[:, None] * e,
                               rtol=0, atol=1e-7)


@pytest.mark.parametrize("driver", ["translation", "coordinate"])
def test_slider_driven_crank_follows_the_law_of_cosines(driver):
    r, l = 0.12, 0.26
    model = slider_crank(crank_speed=None)
    x0 = model.body("slider").q0[0]
    b = mb.ModelBuilder(dim=2)
    # rebuild the same mechanism with the slider driven instead of the crank
    bodies = {body.name: b.add_body(body.name, mass=body.mass, inertia=body.inertia,
                                    position=body.q0[:2], angle=body.q0[2])
              for body in model.bodies}
    crank, rod, slider = bodies["crank"], bodies["rod"], bodies["slider"]
    b.add(Revolute("O", b.ground, crank, point_i=(0, 0), point_j=(-r / 2, 0)))
    b.add(Revolute("A", crank, rod, point_i=(r / 2, 0), point_j=(-l / 2, 0)))
    b.add(Revolute("B", rod, slider, point_i=(l / 2, 0), point_j=(0, 0)))
    rail = b.add(Prismatic("rail", b.ground, slider, axis=(1, 0)))
    speed = -0.05
    if driver == "translation":
        b.add(TranslationDriver("piston", rail, motion=mb.Ramp(0.0, speed)))
    else:
        b.add(CoordinateDriver("piston", slider, "x", mb.Ramp(x0, speed)))
    t = np.linspace(0.0, 1.0, 11)
    res = mb.kinematic_analysis(b.build(), t)
    x = x0 + speed * t
    phi = np.arccos((r * r + x * x - l * l) / (2 * r * x))
    np.testing.assert_allclose(res.body("crank").angle, phi, rtol=0, atol=1e-12)
    np.testing.assert_allclose(res.body("slider").position[:, 0], x, rtol=0, atol=1e-13)


@pytest.mark.parametrize("dim", [2, 3])
def test_forces_in_the_compiled_core_equal_forces_written_here(dim):
    """Every kind of force element, with constant values and a built-in motion as actuator
    (all evaluated inside the compiled loop), against a second model where the spring and
    the torsion spring are point forces and torques whose values this test computes itself
    from the state, in Python (a second implementation of their formulas), and the body-frame
    force and the torque are Python functions of time (values handed into the loop)."""
    from mbd3d.mechanisms import frame_along

    # the spring acts at a point off the tip's centre, so that the point's velocity has its
    # rotation part (omega x s) and the damper sees it
    offset = np.array([0.2, 0.1, 0.05])[:dim]
    anchor = np.array([0.0, 1.0, 0.0])[:dim]
    free_length = float(np.linalg.norm(np.array([1.5, 0.0, 0.0])[:dim] + offset - anchor))

    def spring_on_tip(t, state):
        # tension k (l - l0) + c dl/dt + 2 sin(3 t) pulls the tip towards the anchor
        d = state.position - anchor
        length = np.linalg.norm(d)
        tension = (40.0 * (length - free_length) + 0.5 * (d @ state.velocity) / length
                   + 2.0 * math.sin(3.0 * t))
        return -tension * d / length

    def torsion_on_arm(t, state):
        # the arm turns about the hinge at the origin, its centre of mass on its x axis
        angle = math.atan2(state.position[1], state.position[0])
        rate = state.angular_velocity if dim == 2 else state.angular_velocity[2]
        torque = -3.0 * angle - 0.1 * rate + 0.4
        return torque if dim == 2 else np.array([0.0, 0.0, torque])

    def build(python: bool):
        value = (lambda v: (lambda t: v)) if python else (lambda v: v)
        b = mb.ModelBuilder(dim=dim, gravity=(0.0, -9.81) if dim == 2 else (0.0, -9.81, 0.0))
        kw = {} if dim == 2 else {"orientation": frame_along(np.array([1.0, 0.0, 0.0]))}
        pos = (lambda *x: x[:dim])
        arm = b.add_body("arm", mass=1.0, inertia=0.1 if dim == 2 else (0.05, 0.1, 0.1),
                         position=pos(0.5, 0.0, 0.0), **kw)
        tip = b.add_body("tip", mass=0.5, inertia=0.02 if dim == 2 else (0.01, 0.02, 0.02),
                         position=pos(1.5, 0.0, 0.0), **kw)
        axis = {} if dim == 2 else {"axis": (0.0, 0.0, 1.0)}
        hinge = b.add(Revolute("hinge", b.ground, arm, at=pos(0.0, 0.0, 0.0), **axis))
        b.add(Revolute("elbow", arm, tip, at=pos(1.0, 0.0, 0.0), **axis))
        if python:
            b.add(mb.PointForce("spring", tip, spring_on_tip, point=tuple(offset)))
            b.add(mb.Torque("torsion", arm, torsion_on_arm))
        else:
            b.add(mb.SpringDamper("spring", b.ground, tip, at_i=tuple(anchor),
                                  at_j=tuple(np.array(pos(1.5, 0.0, 0.0)) + offset),
                                  stiffness=40.0, damping=0.5,
                                  actuator=mb.Harmonic(2.0, 3.0)))
            joint = {"joint": hinge} if dim == 3 else {"body_i": b.ground, "body_j": arm}
            b.add(mb.RotationalSpringDamper("torsion", stiffness=3.0, damping=0.1,
                                            actuator=0.4, **joint))
        b.add(mb.PointForce("push", tip, value(np.array(pos(0.0, 5.0, 1.0))),
                            point=pos(0.2, 0.0, 0.0), frame="body"))
        b.add(mb.Torque("twist", arm, value(0.7 if dim == 2 else np.array([0.1, 0.2, 0.7]))))
        return b.build()

    t = np.linspace(0.0, 1.0, 11)
    runs = [mb.forward_dynamics(build(python), t, rtol=1e-11, atol=1e-13)
            for python in (False, True)]
    assert not runs[0].model._core.python_parts and runs[1].model._core.python_parts
    # poses, not coordinates: the two runs' steps differ, and with them where a spatial
    # body's Rodrigues chart is re-referenced
    for body in ("arm", "tip"):
        poses = [res.body(body) for res in runs]
        np.testing.assert_allclose(poses[0].position, poses[1].position, rtol=0, atol=1e-11)
        if dim == 3:
            np.testing.assert_allclose(poses[0].rotation, poses[1].rotation, rtol=0, atol=1e-11)
    arm = runs[0].body("arm").position
    assert np.ptp(np.arctan2(arm[:, 1], arm[:, 0])) > 0.3  # the spring and torsion do work
    np.testing.assert_allclose(runs[0].lam, runs[1].lam, rtol=1e-8, atol=1e-8)


@pytest.mark.parametrize("moving", [False, True])
def test_a_spring_between_two_free_bodies_rests_as_drawn_and_keeps_its_energy(moving):
    """An undamped spring between off-centre points of two free spatial bodies, no gravity:
    drawn at rest it stays so (its free length is the drawing's); set moving, kinetic plus
    the spring's potential energy stays what it was."""
    from scipy.spatial.transform import Rotation
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, 0.0))
    turns = Rotation.random(2, random_state=3).as_matrix()
    kw = [dict(velocity=(0.3, -0.2, 0.1), angular_velocity=(1.0, 0.5, -2.0)),
          dict(velocity=(-0.1, 0.4, 0.2), angular_velocity=(-0.7, 1.5, 0.4))] if moving else [
          {}, {}]
    a = b.add_body("a", mass=2.0, inertia=(0.02, 0.03, 0.04), position=(0.0, 0.0, 0.0),
                   orientation=turns[0], **kw[0])
    c = b.add_body("c", mass=1.0, inertia=(0.01, 0.02, 0.025), position=(0.6, 0.2, -0.1),
                   orientation=turns[1], **kw[1])
    b.add(mb.SpringDamper("spring", a, c, at_i=(0.1, 0.05, 0.0), at_j=(0.5, 0.1, -0.2),
                          stiffness=80.0))
    model = b.build()
    res = mb.forward_dynamics(model, np.linspace(0.0, 2.0, 21), method="DOP853", rtol=1e-12,
                              atol=1e-13)
    energy = res.kinetic_energy + res.potential_energy
    if not moving:
        np.testing.assert_array_equal(res.body("c").position,
                                      np.broadcast_to(res.body("c").position[0], (21, 3)))
        assert np.all(energy == 0.0)
        return
    assert np.ptp(res.potential_energy) > 0.1 * energy[0]  # the spring is worked hard
    np.testing.assert_allclose(energy, energy[0], rtol=1e-10)


def dissipated_energy(power: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The integral of ``power`` from ``t[0]`` to every second time (Simpson's rule on pairs
    of equal intervals: error of order h^4)."""
    h = np.diff(t)[::2]
    pieces = h / 3.0 * (power[:-2:2] + 4.0 * power[1:-1:2] + power[2::2])
    return np.concatenate([[0.0], np.cumsum(pieces)])


def test_a_damper_between_two_turning_bodies_dissipates_c_times_its_rate_squared():
    """A spring-damper between off-centre points of two tumbling free bodies: the energy
    falls at c (dl/dt)^2, dl/dt from the points' velocities written here (v = v_c + omega x
    (A s), global axes), so every term of the points' velocities inside the kernel counts."""
    from scipy.spatial.transform import Rotation
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, 0.0))
    turns = Rotation.random(2, random_state=5).as_matrix()
    a = b.add_body("a", mass=2.0, inertia=(0.02, 0.03, 0.04), position=(0.0, 0.0, 0.0),
                   orientation=turns[0], velocity=(0.3, -0.2, 0.1),
                   angular_velocity=(3.0, 1.5, -4.0))
    c = b.add_body("c", mass=1.0, inertia=(0.01, 0.02, 0.025), position=(0.6, 0.2, -0.1),
                   orientation=turns[1], velocity=(-0.1, 0.4, 0.2),
                   angular_velocity=(-2.7, 3.5, 1.4))
    at_i, at_j = np.array([0.1, 0.05, 0.0]), np.array([0.5, 0.1, -0.2])
    b.add(mb.SpringDamper("spring", a, c, at_i=tuple(at_i), at_j=tuple(at_j), stiffness=80.0,
                          damping=0.7))
    t = np.linspace(0.0, 1.0, 4001)
    res = mb.forward_dynamics(b.build(), t, method="DOP853", rtol=1e-12, atol=1e-13)

    def point(name, drawn):
        body = res.body(name)
        s = body.rotation @ (body.rotation[0].T @ (drawn - body.position[0]))  # A s, global
        return body.position + s, body.velocity + np.cross(body.angular_velocity, s)

    (p_i, v_i), (p_j, v_j) = point("a", at_i), point("c", at_j)
    d = p_j - p_i
    rate = np.einsum("ka,ka->k", d, v_j - v_i) / np.linalg.norm(d, axis=1)
    energy = res.kinetic_energy + res.potential_energy
    dissipated = dissipated_energy(0.7 * rate ** 2, t)
    assert dissipated[-1] > 0.1 * energy[0]  # the damper works
    np.testing.assert_allclose(energy[0] - energy[::2], dissipated, rtol=0,
                               atol=1e-9 * dissipated[-1])


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("moving", [False, True])
def test_a_torsion_spring_between_two_moving_bodies_rests_as_drawn_and_keeps_energy(moving,
                                                                                   dim):
    """Two free bars pinned together at angles 0.3 and 1.1 rad with a torsion spring across
    the pin, no gravity: drawn at rest they stay so (the spring's free angle is the drawn
    relative angle, not either bar's); spun, the energy stays, the spring's included."""
    b = mb.ModelBuilder(dim=dim, gravity=None)
    z = np.array([0.0, 0.0, 1.0])

    def placed(angle, position):
        if dim == 2:
            return {"angle": angle, "position": position}
        return {"orientation": mb.rotations.axis_angle(z, angle),
                "position": tuple(position) + (0.0,)}

    spin = ({"angular_velocity": 2.0 if dim == 2 else 2.0 * z} if moving else {})
    inertia = (lambda j: j if dim == 2 else (j, j, j))
    a = b.add_body("a", mass=1.0, inertia=inertia(0.05), **placed(0.3, (0.0, 0.0)), **spin)
    c = b.add_body("c", mass=0.5, inertia=inertia(0.02), **placed(1.1, (0.6, 0.3)))
    pin = b.add(Revolute("pin", a, c, at=(0.3, 0.15) + (() if dim == 2 else (0.0,)),
                         **({} if dim == 2 else {"axis": tuple(z)})))
    b.add(mb.RotationalSpringDamper("torsion", stiffness=4.0,
                                    **({"body_i": a, "body_j": c} if dim == 2 else
                                       {"joint": pin})))
    t = np.linspace(0.0, 2.0, 21)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mb.InitialStateWarning)  # the spin is projected
        res = mb.forward_dynamics(b.build(), t, method="DOP853", rtol=1e-12, atol=1e-13)
    energy = res.kinetic_energy + res.potential_energy
    if not moving:
        np.testing.assert_allclose(res.body("c").position, np.broadcast_to(
            res.body("c").position[0], res.body("c").position.shape), rtol=0, atol=1e-15)
        assert np.all(energy == 0.0)
        return
    assert np.ptp(res.potential_energy) > 0.1 * energy[0]
    np.testing.assert_allclose(energy, energy[0], rtol=1e-10)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_torsion_damper_between_two_turning_bars_dissipates_c_times_its_rate_squared(dim):
    """The two bars above, spun, with damping across the pin: the energy falls at c phi'^2,
    phi' the bars' relative rate about the pin written here from both angular velocities
    (both bars turn, so each body's part of the rate counts)."""
    b = mb.ModelBuilder(dim=dim, gravity=None)
    z = np.array([0.0, 0.0, 1.0])

    def placed(angle, position, rate):
        if dim == 2:
            return {"angle": angle, "position": position, "angular_velocity": rate}
        return {"orientation": mb.rotations.axis_angle(z, angle),
                "position": tuple(position) + (0.0,), "angular_velocity": rate * z}

    inertia = (lambda j: j if dim == 2 else (j, j, j))
    a = b.add_body("a", mass=1.0, inertia=inertia(0.05), **placed(0.3, (0.0, 0.0), 2.0))
    c = b.add_body("c", mass=0.5, inertia=inertia(0.02), **placed(1.1, (0.6, 0.3), -3.0))
    pin = b.add(Revolute("pin", a, c, at=(0.3, 0.15) + (() if dim == 2 else (0.0,)),
                         **({} if dim == 2 else {"axis": tuple(z)})))
    b.add(mb.RotationalSpringDamper("torsion", stiffness=4.0, damping=0.05,
                                    **({"body_i": a, "body_j": c} if dim == 2 else
                                       {"joint": pin})))
    t = np.linspace(0.0, 2.0, 4001)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mb.InitialStateWarning)  # the spins are projected
        res = mb.forward_dynamics(b.build(), t, method="DOP853", rtol=1e-12, atol=1e-13)
    omega = [res.body(name).angular_velocity for name in ("a", "c")]
    rate = omega[1] - omega[0] if dim == 2 else (omega[1] - omega[0]) @ z
    energy = res.kinetic_energy + res.potential_energy
    dissipated = dissipated_energy(0.05 * rate ** 2, t)
    assert dissipated[-1] > 0.1 * energy[0] and np.ptp(omega[0]) > 1.0  # both bars turn
    np.testing.assert_allclose(energy[0] - energy[::2], dissipated, rtol=0,
                               atol=1e-9 * dissipated[-1])


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("moving", [False, True])
def test_the_spring_tangent_generalized_alpha_iterates_with_is_the_forces_derivative(
        dim, moving):
    """``K + w D`` of springs (what generalized-alpha's iteration matrix adds) against central
    differences of the generalized forces, ``K = -dQ/dq``, ``D = -dQ/dqd``. The tangent
    leaves out the turning of the point Jacobians, so the springs here join centres of mass
    (constant Jacobians), and the damper rate's change with the line's direction,
    ``c e d'^T (I - e e^T) / l`` on the centres' coordinates, written out here and taken off
    the differences; the rest is the exact derivative."""
    from mbd3d.analyses.alpha_step import force_tangent
    from mbd3d.model import constraints

    rng = np.random.default_rng(dim + 2 * moving)
    b = mb.ModelBuilder(dim=dim, gravity=None)
    bodies = [b.add_body(f"b{k}", mass=1.0, inertia=0.1 if dim == 2 else (0.1, 0.2, 0.3),
                         position=rng.normal(size=dim)) for k in range(3)]
    damping = 0.7
    b.add(mb.SpringDamper("s01", bodies[0], bodies[1], stiffness=30.0, damping=damping,
                          free_length=0.4))
    b.add(mb.SpringDamper("s12", bodies[1], bodies[2], stiffness=20.0, damping=damping,
                          free_length=2.5, actuator=1.5))
    b.add(mb.SpringDamper("s2g", b.ground, bodies[2], stiffness=10.0, damping=damping,
                          at_i=tuple(rng.normal(size=dim)), free_length=0.3))
    model = b.build()
    q = model.q0 + 0.2 * rng.normal(size=model.n_coordinates)
    qd = rng.normal(size=model.n_coordinates) if moving else np.zeros(model.n_coordinates)
    charts = model.charts0
    w = 37.0  # generalized-alpha's gamma' (1/s), any value

    def Q(x, v):  # the springs' generalized forces alone (no gravity, no gyroscopic terms)
        fr = constraints.frames(model, x, v, charts)
        out = np.zeros((model.n_bodies + 1, model.n_coords_per_body))
        for group in model.force_groups:
            group.apply(model, 0.3, fr, out)
        return out[:model.n_bodies].ravel()

    h = 1e-6
    K = np.column_stack([-(Q(q + h * e, qd) - Q(q - h * e, qd)) / (2 * h)
                         for e in np.eye(len(q))])
    D = np.column_stack([-(Q(q, qd + h * e) - Q(q, qd - h * e)) / (2 * h)
                         for e in np.eye(len(q))])
    nc, n_bodies = model.n_coords_per_body, model.n_bodies
    fr = constraints.frames(model, q, qd, charts)
    left_out = np.zeros_like(K)
    for element in model.forces:
        ends = [model.padded_index(body) for body in (element.body_i, element.body_j)]
        R = [fr.Q[k, :dim] for k in ends]
        R[0] = R[0] + (np.array(element.at_i) if element.at_i is not None else 0.0)
        d, d_rate = R[1] - R[0], fr.Qd[ends[1], :dim] - fr.Qd[ends[0], :dim]
        length = np.linalg.norm(d)
        e = d / length
        block = damping * np.outer(e, d_rate @ (np.eye(dim) - np.outer(e, e))) / length
        for a, sign_a in zip(ends, (-1.0, 1.0)):
            for c, sign_c in zip(ends, (-1.0, 1.0)):
                if a < n_bodies and c < n_bodies:
                    left_out[a * nc:a * nc + dim, c * nc:c * nc + dim] += sign_a * sign_c * block
    tangent = force_tangent(model, 0.3, q, qd, charts, w)
    np.testing.assert_allclose(tangent, K - left_out + w * D, rtol=0,
                               atol=1e-6 * np.abs(K).max())
    if moving:  # the left-out term is what the test says it is, not zero
        assert np.abs(left_out).max() > 1e-3 * np.abs(K).max()


def test_a_torque_in_body_axes_turns_with_the_body_as_euler_s_equations_say():
    """A free spatial body, turned at random, driven by a constant torque given in its own
    axes: its angular velocity in body axes follows Euler's equations I w' + w x I w = tau,
    integrated here by SciPy (nothing of mbd3d)."""
    from scipy.integrate import solve_ivp
    from scipy.spatial.transform import Rotation
    inertia = np.array([0.02, 0.035, 0.05])
    tau = np.array([0.03, -0.02, 0.05])
    b = mb.ModelBuilder(dim=3, gravity=None)
    body = b.add_body("b", mass=1.0, inertia=tuple(inertia), position=(0.0, 0.0, 0.0),
                      orientation=Rotation.random(random_state=8).as_matrix(),
                      angular_velocity=(0.5, -1.0, 2.0))
    b.add(mb.Torque("drive", body, tuple(tau), frame="body"))
    t = np.linspace(0.0, 2.0, 21)
    res = mb.forward_dynamics(b.build(), t, method="DOP853", rtol=1e-12, atol=1e-13)
    w0 = res.body("b").angular_velocity_body[0]

    def euler(_, w):
        return (tau - np.cross(w, inertia * w)) / inertia
    exact = solve_ivp(euler, (0.0, 2.0), w0, t_eval=t, method="DOP853", rtol=1e-12,
                      atol=1e-13).y.T
    assert np.ptp(exact, axis=0).min() > 0.1  # every component changes
    np.testing.assert_allclose(res.body("b").angular_velocity_body, exact, rtol=0, atol=1e-9)


@pytest.mark.parametrize("dim", [2, 3])
def test_forces_and_torques_tangent_is_their_derivative_in_closed_form(dim):
    """Generalized-alpha's iteration matrix takes the tangent of point forces and torques in
    closed form (:mod:`mbd3d.numerics.compiled.force_tangents`): for a force in global axes at
    the centre of mass and at another point, one in body axes, a torque in global and in body
    axes, on a body turned away from its chart (Rodrigues parameters not zero) and moving, it
    equals the central differences of the generalized forces over every coordinate and rate,
    nothing left out (a spatial torque's generalized force on the Rodrigues parameters
    depends on them, even in global axes). A force given as f(t, state) is differenced."""
    from mbd3d.model import constraints

    def group_of(element):
        b = mb.ModelBuilder(dim=dim, gravity=None)
        turned = (dict(angle=0.4) if dim == 2 else
                  dict(orientation=Rotation.from_rotvec([0.3, -0.2, 0.4]).as_matrix()))
        body = b.add_body("b", mass=1.0, inertia=0.1 if dim == 2 else (0.1, 0.2, 0.3),
                          position=(0.3, -0.2) + (0.1,) * (dim - 2),
                          velocity=(0.5, 0.1) + (0.0,) * (dim - 2), **turned)
        b.add(element(body))
        model = b.build()
        return model, model.force_groups[0]

    vec = (1.0, -2.0) + (0.5,) * (dim - 2)
    spin = 0.7 if dim == 2 else (0.7, -0.3, 0.2)
    point = (0.2, 0.1) + (-0.3,) * (dim - 2)
    known = [lambda body: mb.PointForce("f", body, vec),
             lambda body: mb.PointForce("f", body, vec, point=point),
             lambda body: mb.PointForce("f", body, vec, point=point, frame="body"),
             lambda body: mb.Torque("t", body, spin),
             lambda body: mb.Torque("t", body, spin, frame="body")]
    rng = np.random.default_rng(dim)
    for element in known:
        model, group = group_of(element)
        assert group.analytic_tangent and group.compiled_tangent(model)
        q = model.q0 + 0.3 * rng.normal(size=model.n_coordinates)  # away from the chart
        qd = rng.normal(size=model.n_coordinates)

        def Q(x, xd):
            out = np.zeros((model.n_bodies + 1, model.n_coords_per_body))
            group.apply(model, 0.0, constraints.frames(model, x, xd, model.charts0), out)
            return out[:model.n_bodies].ravel()
        h = 1e-6
        K = np.column_stack([-(Q(q + e, qd) - Q(q - e, qd)) / (2 * h)
                             for e in h * np.eye(len(q))])
        fr = constraints.frames(model, q, qd, model.charts0)
        rows, cols, values = group.tangent(model, 0.0, fr, 37.0)
        n = model.n_coordinates
        keep = (rows < n) & (cols < n)
        T = np.zeros((n, n))
        np.add.at(T, (rows[keep], cols[keep]), values[keep])
        np.testing.assert_allclose(T, K, rtol=0, atol=1e-8 * max(1.0, np.abs(K).max()))
        if element is not known[0] and (dim == 3 or element is known[1]):
            assert np.abs(K).max() > 0.1  # the state-dependent ones do depend on the state
    state = lambda body: mb.PointForce("f", body, lambda t, state: state.velocity)  # noqa: E731
    model, group = group_of(state)
    assert not group.analytic_tangent and not group.compiled_tangent(model)


@pytest.mark.parametrize("dim", [2, 3])
def test_rotational_spring_tangent_is_its_derivative_where_nothing_is_left_out(dim):
    """The rotational spring-damper's tangent in closed form, ``(k + w c) G^T G`` with ``G``
    the hinge axis on the bodies' rotation coordinates, against central differences of its
    generalized forces: planar (two moving bodies, wound up) it is the whole derivative; in
    space, about a skew hinge, its velocity part is exact at any state and its position part
    where the torque is zero (the turning of the axis it leaves out carries the torque)."""
    from mbd3d.model import constraints
    k, c, w = 3.0, 0.4, 37.0
    b = mb.ModelBuilder(dim=dim, gravity=None)
    if dim == 2:
        one = b.add_body("one", mass=1.0, inertia=0.1, position=(0.2, 0.1), angle=0.3)
        two = b.add_body("two", mass=1.0, inertia=0.2, position=(-0.4, 0.5), angle=-0.6)
        b.add(mb.RotationalSpringDamper("torsion", one, two, stiffness=k, damping=c,
                                        free_angle=0.2))
    else:
        axis = np.array([1.0, 2.0, 2.0]) / 3.0
        frame = Rotation.align_vectors([axis], [[0.0, 0.0, 1.0]])[0].as_matrix()
        disc = b.add_body("disc", mass=1.0, inertia=(0.03, 0.04, 0.05), position=(0, 0, 0),
                          orientation=frame)
        hinge = b.add(Revolute("axle", b.ground, disc, at=(0.0, 0.0, 0.0), axis=axis))
        b.add(mb.RotationalSpringDamper("torsion", joint=hinge, stiffness=k, damping=c))
    model = b.build()
    group = model.force_groups[0]
    assert group.compiled_tangent(model)
    rng = np.random.default_rng(dim)
    q, moving = model.q0.copy(), rng.normal(size=model.n_coordinates)
    if dim == 2:
        q += 0.3 * rng.normal(size=len(q))

    def Q(x, xd):
        out = np.zeros((model.n_bodies + 1, model.n_coords_per_body))
        group.apply(model, 0.0, constraints.frames(model, x, xd, model.charts0), out)
        return out[:model.n_bodies].ravel()

    def tangent(x, xd, weight):
        rows, cols, values = group.tangent(model, 0.0, constraints.frames(
            model, x, xd, model.charts0), weight)
        n = model.n_coordinates
        keep = (rows < n) & (cols < n)
        T = np.zeros((n, n))
        np.add.at(T, (rows[keep], cols[keep]), values[keep])
        return T
    h, eye = 1e-6, 1e-6 * np.eye(len(q))
    at_rest = np.zeros(len(q)) if dim == 3 else moving
    K = np.column_stack([-(Q(q + e, at_rest) - Q(q - e, at_rest)) / (2 * h) for e in eye])
    D = np.column_stack([-(Q(q, moving + e) - Q(q, moving - e)) / (2 * h) for e in eye])
    scale = np.abs(K).max()
    assert scale > 0.1 * k
    np.testing.assert_allclose(tangent(q, at_rest, 0.0), K, rtol=0, atol=1e-8 * scale)
    np.testing.assert_allclose(tangent(q, moving, w) - tangent(q, moving, 0.0), w * D, rtol=0,
                               atol=1e-8 * w * scale)


@pytest.mark.parametrize("layout", ["dense", "banded"])
def test_the_compiled_tangent_storage_is_the_sparse_one(layout):
    """The compiled tangent goes straight into the iteration matrix's storage (scaled, and in
    the permuted band): against the same tangent assembled as a sparse matrix and placed by
    the pattern's own SciPy code (``_tangent_storage``), on a chain of springs and forces
    whose springs reach one to four links along it: the band is ordered and sized to hold
    them (it widens with the reach), so every tangent fits in it."""
    from mbd3d.analyses.alpha_step import _tangent_storage, force_tangent
    from mbd3d.joints import Revolute
    from mbd3d.numerics.compiled import force_tangents
    n_links = 12 if layout == "banded" else 4
    rng = np.random.default_rng(3)
    widths = []
    for reach in range(1, 5):
        b = mb.ModelBuilder(dim=2)
        links = [b.ground]
        for k in range(n_links):
            links.append(b.add_body(f"link{k}", mass=1.0 + k, inertia=0.1 * (k + 1),
                                    position=(k + 0.5, 0.0)))
            b.add(Revolute(f"pin{k}", links[-2], links[-1], at=(float(k), 0.0)))
        for k in range(1, n_links + 1 - reach, 3):
            b.add(mb.SpringDamper(f"s{k}", links[k], links[k + reach], stiffness=5.0 * k,
                                  damping=0.3, point_i=(0.2, 0.1), point_j=(-0.3, 0.05)))
        b.add(mb.RotationalSpringDamper("torsion", links[2], links[3], stiffness=7.0,
                                        damping=0.2))
        b.add(mb.PointForce("pull", links[-1], (0.5, -2.0), point=(0.4, 0.1), frame="body"))
        b.add(mb.Torque("turn", links[1], 0.3))
        model = b.build()
        assert model._penalty_pattern.layout == layout
        arrays, work = model._core.penalty_arrays(model), model._core.workspace()
        q = model.q0 + 0.1 * rng.normal(size=model.n_coordinates)
        qd = rng.normal(size=model.n_coordinates)
        expected, python_factor = _tangent_storage(
            model, force_tangent(model, 0.2, q, qd, model.charts0, 40.0))
        assert force_tangents.tangent_fits(arrays, work) and not python_factor
        extra = np.zeros(len(expected))
        force_tangents.force_tangent_into(work, arrays, 0.2, q, qd, None, 40.0, extra)
        np.testing.assert_allclose(extra, expected, rtol=1e-13,
                                   atol=1e-13 * np.abs(expected).max())
        if layout == "banded":
            widths.append(model._penalty_pattern.kl)
    if layout == "banded":  # a pin couples neighbours: 2 bodies' coordinates, then wider
        assert widths[0] == 5 and widths == sorted(widths) and widths[-1] > widths[0]
