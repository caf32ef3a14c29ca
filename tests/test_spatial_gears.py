"""Spatial gear pairs, spur and bevel, against what gears must do: a spur train in a tilted
plane reproduces the planar model (kinematics, reactions, tooth forces), a planetary train in
space follows Willis's formula, a bevel differential splits speeds as ``omega_R = 2 omega_c -
omega_L`` with its pitch points rolling without slip, and a bevel pair driven by a torque
accelerates as its one-degree-of-freedom equation says, with the tooth force's thrust of the
textbooks (Shigley, *Mechanical Engineering Design*, ch. 13: ``F_a = F_t tan(phi)
sin(delta)``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import mbd3d as mb
from mbd3d.joints import GearPair, Revolute, RotationDriver

G = 9.81
R1, R2, R3 = 0.05, 0.03, 0.08
INERTIA = (1.2e-3, 4e-4, 6e-3)
CRANK = mb.Polynomial([0.3, 10.0, 3.0])
#: the plane of the spatial twins: the planar x, y, z axes turned by this rotation
TILT = Rotation.from_rotvec([0.4, -0.7, 0.2]).as_matrix()
NORMAL = TILT[:, 2]


def in_space(v) -> np.ndarray:
    """A planar point or vector of the drawing in the tilted plane."""
    return TILT @ np.append(v, 0.0)


def gear_train(dim: int, load: float = -3.0) -> mb.Model:
    """Three gears on fixed axles, 1 -> idler 2 -> 3, the centre line bent at 2; gravity in the
    plane and a load torque on gear 3. In space: the same in the tilted plane."""
    spatial = dim == 3
    b = mb.ModelBuilder(dim=dim, gravity=in_space([0.0, -G]) if spatial else (0.0, -G),
                        name="gear train")
    c2 = np.array([R1 + R2, 0.0])
    c3 = c2 + (R2 + R3) * np.array([math.cos(0.7), math.sin(0.7)])
    gears = []
    for k, (mass, inertia, centre, angle) in enumerate(zip(
            (1.0, 0.4, 2.5), INERTIA, ((0.0, 0.0), c2, c3), (0.3, -0.2, 1.0))):
        if spatial:
            # the axial moment of inertia is the planar one; the others do not matter
            turned = TILT @ Rotation.from_rotvec([0.0, 0.0, angle]).as_matrix()
            gears.append(b.add_body(f"g{k + 1}", mass=mass,
                                    inertia=np.diag([0.6, 0.7, 1.0]) * inertia,
                                    position=in_space(centre), orientation=turned))
        else:
            gears.append(b.add_body(f"g{k + 1}", mass=mass, inertia=inertia, position=centre,
                                    angle=angle))
    axis = {"axis": NORMAL} if spatial else {}
    axles = [b.add(Revolute(n, b.ground, g, at=g.q0[:dim], **axis))
             for n, g in zip("ABC", gears)]
    axis = {"axis_i": NORMAL} if spatial else {}
    b.add(GearPair("m12", gears[0], gears[1], radius_i=R1, radius_j=R2, **axis))
    b.add(GearPair("m23", gears[1], gears[2], radius_i=R2, radius_j=R3, **axis))
    b.add(RotationDriver("motor", axles[0], motion=CRANK))
    b.add(mb.Torque("load", gears[2], load * NORMAL if spatial else load))
    return b.build()


def test_spur_train_in_a_tilted_plane_reproduces_the_planar_one():
    t = np.linspace(0.0, 1.5, 31)
    planar = mb.inverse_dynamics(gear_train(2), t)
    spatial = mb.inverse_dynamics(gear_train(3), t)
    for name, axle in zip(("g1", "g2", "g3"), "ABC"):
        p, s = planar.body(name), spatial.body(name)
        np.testing.assert_allclose(s.angular_velocity, p.angular_velocity[:, None] * NORMAL,
                                   rtol=0, atol=1e-12)
        np.testing.assert_allclose(s.angular_acceleration,
                                   p.angular_acceleration[:, None] * NORMAL, rtol=0, atol=1e-10)
        # both solve positions to 1e-12 of the length scale: 1e-11 rad on the small gears
        turned = spatial.joint(axle).angle
        np.testing.assert_allclose(turned - turned[0], p.angle - p.angle[0], rtol=0, atol=1e-11)
    np.testing.assert_allclose(spatial.driver("motor").effort, planar.driver("motor").effort,
                               rtol=1e-12)
    for mesh in ("m12", "m23"):
        p, s = planar.joint(mesh).mesh_force, spatial.joint(mesh).mesh_force
        np.testing.assert_allclose(s.tangential, p.tangential, rtol=1e-12)
        np.testing.assert_allclose(s.separating, p.separating, rtol=1e-12)
        np.testing.assert_allclose(s.point, np.column_stack([p.point, np.zeros(len(t))])
                                   @ TILT.T, rtol=0, atol=1e-14)
        np.testing.assert_allclose(s.force, np.column_stack([p.force, np.zeros(len(t))])
                                   @ TILT.T, rtol=0, atol=1e-12)
        np.testing.assert_allclose(spatial.joint(mesh).lam, planar.joint(mesh).lam, rtol=1e-12)
    assert np.max(spatial.position_residual) < 1e-12


def test_spatial_planetary_train_follows_willis_over_turns():
    """Sun driven, ring fixed (the ground, an internal mesh), the planet on a carrier that
    turns more than once: in the tilted plane, relative speeds by Willis's formula."""
    rs, rp = 0.04, 0.025
    rr = rs + 2 * rp
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, 0.0), name="planetary")
    disc = lambda m, r: np.diag([0.25, 0.25, 0.5]) * m * r * r  # noqa: E731
    sun = b.add_body("sun", mass=0.5, inertia=disc(0.5, rs), position=(0.0, 0.0, 0.0),
                     orientation=TILT)
    arm = b.add_body("carrier", mass=0.8, inertia=disc(0.8, rr), position=(0.0, 0.0, 0.0),
                     orientation=TILT)
    centre = in_space((rs + rp) * np.array([math.cos(2.0), math.sin(2.0)]))
    planet = b.add_body("planet", mass=0.3, inertia=disc(0.3, rp), position=centre,
                        orientation=TILT)
    shaft = b.add(Revolute("sun shaft", b.ground, sun, at=(0.0, 0.0, 0.0), axis=NORMAL))
    b.add(Revolute("carrier shaft", b.ground, arm, at=(0.0, 0.0, 0.0), axis=NORMAL))
    b.add(Revolute("planet pin", arm, planet, at=centre, axis=NORMAL))
    b.add(GearPair("sun-planet", sun, planet, radius_i=rs, radius_j=rp, axis_i=NORMAL))
    b.add(GearPair("planet-ring", planet, b.ground, radius_i=rp, radius_j=rr, internal=True,
                   center_j=(0.0, 0.0, 0.0), axis_i=NORMAL))
    b.add(RotationDriver("motor", shaft, motion=CRANK))
    res = mb.kinematic_analysis(b.build(), np.linspace(0.0, 2.0, 41))
    spin = {n: res.body(n).angular_velocity @ NORMAL for n in ("sun", "carrier", "planet")}
    np.testing.assert_allclose(spin["carrier"], spin["sun"] * rs / (rs + rr), rtol=1e-12)
    np.testing.assert_allclose(spin["planet"] - spin["carrier"],
                               -(spin["sun"] - spin["carrier"]) * rs / rp, rtol=1e-12)
    carrier = res.joint("carrier shaft").angle
    sun_turn = res.joint("sun shaft").angle - res.joint("sun shaft").angle[0]
    assert carrier[-1] - carrier[0] > 2 * math.pi
    np.testing.assert_allclose(carrier - carrier[0], sun_turn * rs / (rs + rr), rtol=0, atol=1e-12)
    # the planet relative to the carrier, by the pin's angle: against the sun by rs / rp
    pin = res.joint("planet pin").angle
    np.testing.assert_allclose(pin - pin[0], -(sun_turn - (carrier - carrier[0])) * rs / rp,
                               rtol=0, atol=1e-11)


R_SIDE, R_SPIDER = 0.06, 0.03
X, Y = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])


def differential(orientations: np.ndarray, cage=(10.0, 2.0), left=(12.0, -1.5)) -> mb.Model:
    """A bevel differential: the cage turns on the axle x, carrying the spider on a pin along
    y; the side gears turn on the axle and mesh with the spider (apex at the origin, pitch
    radii 60 and 30 mm at the same cone distance, so the side gears' pitch circles are centred
    30 mm from it). The cage and the left gear are driven from the drawing's angles (the
    drivers measure the bodies' x axes, or y where x is the axle, projected on the plane
    normal to it); the bodies' frames are ``orientations`` (4, 3, 3) of the drawing."""
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G), name="differential")
    centres = {"cage": (0.0, 0.0, 0.0), "left": -R_SPIDER * X, "right": R_SPIDER * X,
               "spider": R_SIDE * Y}
    bodies = {name: b.add_body(name, mass=1.0, inertia=np.diag([1e-3, 2e-3, 3e-3]),
                               position=centre, orientation=orientations[k])
              for k, (name, centre) in enumerate(centres.items())}

    def drawing_angle(k):
        x = orientations[k][:, 0]
        x = x if abs(x @ X) < 0.99 else orientations[k][:, 1]
        return math.atan2(x[2], x[1])  # from the ground's y axis, about the axle

    cage_axle = b.add(Revolute("cage axle", b.ground, bodies["cage"], at=centres["cage"],
                               axis=X))
    left_axle = b.add(Revolute("left axle", b.ground, bodies["left"], at=centres["left"],
                               axis=X))
    b.add(Revolute("right axle", b.ground, bodies["right"], at=centres["right"], axis=X))
    b.add(Revolute("spider pin", bodies["cage"], bodies["spider"], at=centres["spider"],
                   axis=Y))
    for side in ("left", "right"):
        b.add(GearPair(f"{side} mesh", bodies[side], bodies["spider"], radius_i=R_SIDE,
                       radius_j=R_SPIDER, axis_i=X, axis_j=Y))
    b.add(RotationDriver("cage drive", cage_axle,
                         motion=mb.Polynomial([drawing_angle(0), cage[0], cage[1] / 2])))
    b.add(RotationDriver("left drive", left_axle,
                         motion=mb.Polynomial([drawing_angle(1), left[0], left[1] / 2])))
    return b.build()


def test_bevel_differential_splits_speeds_and_rolls_without_slip():
    orientations = Rotation.random(4, random_state=7).as_matrix()
    t = np.linspace(0.0, 3.0, 61)
    res = mb.kinematic_analysis(differential(orientations), t)
    w_cage, w_left = 10.0 + 2.0 * t, 12.0 - 1.5 * t
    omega = {n: res.body(n).angular_velocity for n in ("cage", "left", "right", "spider")}
    np.testing.assert_allclose(omega["right"], (2 * w_cage - w_left)[:, None] * X, rtol=0,
                               atol=1e-12)
    np.testing.assert_allclose(res.body("right").angular_acceleration,
                               np.outer(np.full(len(t), 2 * 2.0 + 1.5), X), rtol=0, atol=1e-11)
    # the right gear has turned by 2 cage - left over about 3 turns: no tooth lost
    turned = {n: res.joint(f"{n} axle").angle - res.joint(f"{n} axle").angle[0]
              for n in ("cage", "left", "right")}
    assert turned["right"][-1] > 3 * 2 * math.pi
    np.testing.assert_allclose(turned["right"], 2 * turned["cage"] - turned["left"],
                               rtol=0, atol=1e-11)
    # the spider spins on its pin at (omega_L - omega_c) R_SIDE / R_SPIDER
    spin = res.joint("spider pin").angle_rate
    np.testing.assert_allclose(spin, (w_left - w_cage) * R_SIDE / R_SPIDER, rtol=0, atol=1e-11)
    # pitch points: a spider radius from its centre towards each side gear; the material
    # points of the spider and of the side gear there move alike
    centre = res.body("spider").position
    for side, toward in (("left", -X), ("right", X)):
        point = centre + R_SPIDER * toward
        gear = res.body(side)
        v_gear = gear.velocity + np.cross(omega[side], point - gear.position)
        v_spider = res.body("spider").velocity + np.cross(omega["spider"], point - centre)
        np.testing.assert_allclose(v_gear, v_spider, rtol=0, atol=1e-12)
        assert np.min(np.linalg.norm(v_gear, axis=1)) > 0.1  # they do move
    assert np.max(res.position_residual) < 1e-12


def test_position_analysis_keeps_the_mesh_off_the_half_phase():
    """The mesh row ``sin(Phi)`` also vanishes at ``Phi = pi``. The idler of the tilted train
    (3 reduced teeth in both its meshes) guessed 0.8 pi / 3 off, its meshes' phases 0.8 pi
    off, nearer pi than 0, still assembles as drawn."""
    model = gear_train(3)
    idler = model.body("g2").index
    charts = model.charts0.copy()  # orientations are charts[k] A(g)
    charts[idler] = Rotation.from_rotvec(0.8 * math.pi / 3 * NORMAL).as_matrix() @ charts[idler]
    solved = mb.solve_position(model, model.q0, 0.0, charts=charts)
    assembled = mb.solve_position(model, model.q0, 0.0)
    for k in range(model.n_bodies):
        turned = charts[k] @ mb.rotations.from_rodrigues(solved.reshape(-1, 6)[k, 3:])
        drawn = model.charts0[k] @ mb.rotations.from_rodrigues(assembled.reshape(-1, 6)[k, 3:])
        np.testing.assert_allclose(turned, drawn, rtol=0, atol=1e-12)


def bevel_pair(shaft_angle: float, torque: float) -> tuple[mb.Model, dict]:
    """A pinion (radius 40 mm) driving a wheel (60 mm) across a shaft angle, both on fixed
    axles through the apex at the origin, a torque on the pinion."""
    ri, rj = 0.04, 0.06
    h_i = X
    h_j = np.array([math.cos(shaft_angle), math.sin(shaft_angle), 0.0])
    delta_i = math.atan2(math.sin(shaft_angle), rj / ri + math.cos(shaft_angle))
    delta_j = shaft_angle - delta_i
    cone = ri / math.sin(delta_i)  # the cone distance of the pitch circles
    c_i, c_j = cone * math.cos(delta_i) * h_i, cone * math.cos(delta_j) * h_j
    J_i, J_j = 2e-4, 6e-4
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G), name="bevel pair")
    frame = lambda h: mb.rotations.frame_along(h, hint=(0.0, 0.0, 1.0))  # noqa: E731
    pinion = b.add_body("pinion", mass=0.3, inertia=np.diag([J_i, J_i / 2, J_i / 2]),
                        position=c_i, orientation=frame(h_i))
    wheel = b.add_body("wheel", mass=0.5, inertia=np.diag([J_j, J_j / 2, J_j / 2]),
                       position=c_j, orientation=frame(h_j))
    b.add(Revolute("A", b.ground, pinion, at=c_i, axis=h_i))
    b.add(Revolute("B", b.ground, wheel, at=c_j, axis=h_j))
    b.add(GearPair("mesh", pinion, wheel, radius_i=ri, radius_j=rj, axis_i=h_i, axis_j=h_j))
    b.add(mb.Torque("motor", pinion, torque * h_i))
    return b.build(), dict(ri=ri, rj=rj, J_i=J_i, J_j=J_j, h_i=h_i, h_j=h_j,
                           delta_i=delta_i, delta_j=delta_j, cone=cone)


@pytest.mark.parametrize("shaft_angle", [math.radians(90.0), math.radians(75.0)])
def test_bevel_pair_under_torque_matches_its_equation_and_tooth_force(shaft_angle):
    torque = 0.01
    model, g = bevel_pair(shaft_angle, torque)
    t = np.linspace(0.0, 2.0, 21)
    res = mb.forward_dynamics(model, t, method="DOP853", rtol=1e-11, atol=1e-12)
    ratio = g["ri"] / g["rj"]
    # one degree of freedom: (J_i + J_j ratio^2) alpha_i = torque, the wheel at -ratio
    alpha = torque / (g["J_i"] + g["J_j"] * ratio ** 2)
    pinion, wheel = res.joint("A").angle, res.joint("B").angle
    np.testing.assert_allclose(pinion - pinion[0], alpha * t ** 2 / 2, rtol=0, atol=1e-9)
    assert pinion[-1] - pinion[0] > 6 * 2 * math.pi
    np.testing.assert_allclose(wheel - wheel[0], -ratio * (pinion - pinion[0]), rtol=0, atol=1e-10)
    # the power balance: the torque's work is the kinetic energy
    np.testing.assert_allclose(res.kinetic_energy, torque * (pinion - pinion[0]), rtol=0,
                               atol=1e-11)

    mesh = res.joint("mesh").mesh_force
    # the wheel's axis points away from the apex; the mesh turns it at -ratio alpha
    np.testing.assert_allclose(mesh.tangential, g["J_j"] * -ratio * alpha / g["rj"], rtol=1e-9)
    # the pitch point lies on both pitch circles, at the cone distance from the apex
    point = mesh.point
    for h, radius in ((g["h_i"], g["ri"]), (g["h_j"], g["rj"])):
        np.testing.assert_allclose(np.linalg.norm(np.cross(point, h), axis=1), radius,
                                   rtol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(point, axis=1), g["cone"], rtol=1e-12)
    # the tooth force: its size, normal to the cone's element through the pitch point, its
    # moment about the wheel's axis, and on the pinion the thrust away from the apex and the
    # radial force of straight bevel gears, tan(phi) F_t sin(delta) and cos(delta)
    force = mesh.force
    np.testing.assert_allclose(np.linalg.norm(force, axis=1), mesh.tooth, rtol=1e-12)
    assert np.max(np.abs(np.einsum("ki,ki->k", force, point))) < 1e-14 * g["cone"]
    np.testing.assert_allclose(np.cross(point, force) @ g["h_j"], mesh.tangential * g["rj"],
                               rtol=1e-12)
    tan_phi = math.tan(math.radians(20.0))
    on_pinion = -force
    np.testing.assert_allclose(on_pinion @ g["h_i"],
                               np.abs(mesh.tangential) * tan_phi * math.sin(g["delta_i"]),
                               rtol=1e-12)
    across = point - np.outer(point @ g["h_i"], g["h_i"])
    radial = -np.einsum("ki,ki->k", on_pinion, across) / g["ri"]  # towards the axis
    np.testing.assert_allclose(radial, np.abs(mesh.tangential) * tan_phi
                               * math.cos(g["delta_i"]), rtol=1e-12)


def test_bevel_pair_with_generalized_alpha_converges_at_second_order():
    torque = 0.01
    model, g = bevel_pair(math.radians(75.0), torque)
    t = np.linspace(0.0, 1.0, 11)
    alpha = torque / (g["J_i"] + g["J_j"] * (g["ri"] / g["rj"]) ** 2)
    errors = []
    for step in (2e-3, 1e-3):
        res = mb.forward_dynamics(model, t, method="generalized-alpha", step=step)
        pinion, wheel = res.joint("A").angle, res.joint("B").angle
        errors.append(np.max(np.abs(pinion - pinion[0] - alpha * t ** 2 / 2)))
        # the mesh holds to the Newton tolerance at every step whatever the step's error
        np.testing.assert_allclose(wheel - wheel[0], -g["ri"] / g["rj"] * (pinion - pinion[0]),
                                   rtol=0, atol=1e-9)
    assert 3.5 < errors[0] / errors[1] < 4.5, errors


def spatial_pair(**change) -> mb.ModelBuilder:
    b = mb.ModelBuilder(dim=3, name="bad gears")
    g1 = b.add_body("g1", mass=1.0, inertia=np.eye(3) * 1e-3, position=(0.0, 0.0, 0.0))
    g2 = b.add_body("g2", mass=1.0, inertia=np.eye(3) * 1e-3, position=(0.08, 0.0, 0.0))
    b.add(GearPair("m12", g1, g2, **{"radius_i": 0.05, "radius_j": 0.03, "axis_i": (0, 0, 1),
                                     **change}))
    return b


@pytest.mark.parametrize("change, words", [
    (dict(axis_i=None), ["'m12'", "axis_i="]),
    (dict(radius_j=0.031), ["'m12'", "0.08 m apart in the drawing across the axes",
                                  "need 0.081"]),
    (dict(radius_j=0.03 * math.sqrt(2.0), center_j=(0.05 + 0.03 * math.sqrt(2.0), 0, 0)),
     ["'m12'", "ratio of tooth counts", "module * teeth / 2"]),
    (dict(axis_j=(1, 0, 0), center_j=(0.08, 0.1, 0.0)), ["'m12'", "0.1 m apart",
                                                          "must intersect"]),
    (dict(axis_j=(1, 0, 0), center_i=(0.08, 0.0, 0.0)), ["'m12'", "center_i is the apex"]),
    (dict(axis_j=(1, 0, 0), internal=True, radius_j=0.08), ["'m12'", "internal=True",
                                                            "parallel axes"]),
])
def test_bad_spatial_gear_pairs_are_named(change, words):
    with pytest.raises(mb.ModelError) as info:
        spatial_pair(**change).build()
    for word in words:
        assert word in str(info.value), str(info.value)


def test_planar_gears_take_no_axes():
    b = mb.ModelBuilder(dim=2, name="planar gears")
    g1 = b.add_body("g1", mass=1.0, inertia=1e-3, position=(0.0, 0.0))
    g2 = b.add_body("g2", mass=1.0, inertia=1e-3, position=(0.08, 0.0))
    b.add(GearPair("m12", g1, g2, radius_i=0.05, radius_j=0.03, axis_i=(0, 0, 1)))
    with pytest.raises(mb.ModelError, match="'m12'.*leave out axis_i"):
        b.build()


def test_generalized_alpha_keeps_steps_within_a_quarter_tooth():
    """Gears of 97 and 100 reduced teeth speeding up under a torque: at the step asked for
    (20 ms) the phase's terms would change by up to 500 rad per step, and Newton stops
    converging at 0.4 s; the steps are cut to a quarter of a reduced tooth's turn and the
    pair follows its one-degree-of-freedom equation."""
    ri, rj, inertia = 0.097, 0.1, 2e-3
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, 0.0), name="fine pair")
    Z = np.array([0.0, 0.0, 1.0])
    gears = [b.add_body(n, mass=1.0, inertia=np.diag([0.5, 0.5, 1.0]) * inertia, position=c)
             for n, c in (("i", (0.0, 0.0, 0.0)), ("j", (ri + rj, 0.0, 0.0)))]
    b.add(Revolute("A", b.ground, gears[0], at=(0.0, 0.0, 0.0), axis=Z))
    b.add(Revolute("B", b.ground, gears[1], at=(ri + rj, 0.0, 0.0), axis=Z))
    b.add(GearPair("mesh", gears[0], gears[1], radius_i=ri, radius_j=rj, axis_i=Z))
    b.add(mb.Torque("motor", gears[0], Z))
    t = np.linspace(0.0, 0.5, 6)
    res = mb.forward_dynamics(b.build(), t, method="generalized-alpha", step=2e-2)
    alpha = 1.0 / (inertia * (1.0 + (ri / rj) ** 2))
    pinion, wheel = res.joint("A").angle, res.joint("B").angle
    np.testing.assert_allclose(wheel - wheel[0], -ri / rj * (pinion - pinion[0]),
                               rtol=0, atol=1e-9)
    # the method's own error at these steps (second order), 2e-4 of the 32 rad turned
    np.testing.assert_allclose(pinion - pinion[0], alpha * t ** 2 / 2, rtol=1e-3)
