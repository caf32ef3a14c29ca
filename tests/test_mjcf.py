"""MJCF import against MuJoCo itself (the `test` extra's `mujoco`): an arm drawn with MuJoCo's
conventions (angles in degrees, Euler angles, a quaternion, a joint's reference angle, a skew
and unnormalised axis, inertias from geoms and an inertial frame, a body welded on) has
MuJoCo's inverse dynamics at random states; a free-floating mechanism with a ball joint,
started from a keyframe's velocities, tumbles as MuJoCo integrates it; a limited hinge stops
at MuJoCo's range. What the model leaves out is said; what it cannot read is refused by name."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import mbd3d as mb

mujoco = pytest.importorskip("mujoco")

ARM = """<mujoco model="arm">
  <compiler angle="degree"/>
  <option gravity="0.3 -0.2 -9.81"><flag contact="disable"/></option>
  <worldbody>
    <geom type="plane" size="1 1 0.1"/>
    <body name="base" pos="0 0 0.1" euler="0 0 30">
      <joint name="yaw" type="hinge" axis="0 0 1"/>
      <geom type="cylinder" size="0.05 0.05" density="2000"/>
      <body name="upper" pos="0 0 0.1" quat="0.9 0.1 0.3 0.2">
        <joint name="shoulder" type="hinge" axis="0 2 0" ref="20"/>
        <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.03"/>
        <body name="sensor" pos="0.2 0.05 0" euler="10 20 30">
          <geom type="box" size="0.02 0.03 0.04" mass="0.3"/>
        </body>
        <body name="fore" pos="0.4 0 0">
          <joint name="elbow" type="hinge" axis="0 1 1" range="-90 90"/>
          <inertial pos="0.15 0.01 0" mass="1.2" diaginertia="0.01 0.02 0.025" euler="5 10 15"/>
          <body name="tool" pos="0.3 0 0">
            <joint name="extend" type="slide" axis="1 0.2 0"/>
            <geom type="sphere" size="0.04" mass="0.5"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>"""
JOINTS = ("yaw", "shoulder", "elbow", "extend")

FLOATING = """<mujoco model="floating">
  <option gravity="0 0 0" integrator="RK4" timestep="1e-4"/>
  <worldbody>
    <body name="hub" pos="0.1 0.2 1" quat="0.8 0.2 -0.3 0.4">
      <freejoint name="float"/>
      <geom type="box" size="0.2 0.1 0.05" density="1000"/>
      <body name="arm" pos="0.25 0 0">
        <joint name="ball" type="ball"/>
        <geom type="capsule" fromto="0 0 0 0.3 0.05 0" size="0.03" density="800"/>
        <body name="flap" pos="0.3 0.05 0" euler="0.3 0.2 0.1">
          <joint name="hinge" type="hinge" axis="1 1 0"/>
          <geom type="ellipsoid" size="0.05 0.08 0.02" density="1200"/>
        </body>
      </body>
    </body>
  </worldbody>
  <keyframe>
    <key name="spin" qpos="0.1 0.2 1 0.8 0.2 -0.3 0.4 0.9 0.1 0.3 -0.2 0.5"
         qvel="0.3 -0.2 0.1 1.0 -2.0 0.5 3.0 -1.0 2.0 4.0"/>
  </keyframe>
</mujoco>"""


GIMBALS = """<mujoco model="gimbals">
  <option integrator="RK4" timestep="1e-4"/>
  <worldbody>
    <body name="torso" pos="0 0 1" euler="0.2 0.1 0.3">
      <joint name="bend_z" type="hinge" axis="0 0 1" pos="0 0 0.1"/>
      <joint name="bend_y" type="hinge" axis="0 1 0" pos="0 0 0.1"/>
      <geom type="box" size="0.15 0.1 0.08" density="1000"/>
      <body name="thigh" pos="0.1 0 -0.1">
        <joint name="hip_x" type="hinge" axis="1 0 0"/>
        <joint name="hip_z" type="hinge" axis="0.2 0 1"/>
        <joint name="hip_y" type="hinge" axis="0 1 0.3" range="-170 170"/>
        <geom type="capsule" fromto="0 0 0 0.05 0.02 -0.3" size="0.04" density="900"/>
        <body name="shin" pos="0.05 0.02 -0.3">
          <joint name="knee" type="hinge" axis="0 -1 0"/>
          <geom type="capsule" fromto="0 0 0 0 0.03 -0.25" size="0.03" density="1100"/>
        </body>
      </body>
    </body>
  </worldbody>
  <keyframe>
    <key name="kick" qpos="0.3 -0.2 0.4 0.1 -0.5 0.6" qvel="1.0 -0.5 2.0 -1.0 0.7 3.0"/>
  </keyframe>
</mujoco>"""


def _moves_as_in_mujoco(path, model, seconds: float, bodies: list[str]) -> None:
    """The centres of mass of ``bodies`` after ``seconds`` of forward dynamics (DOP853 at
    rtol 1e-11, the initial state taken as given: consistent) against MuJoCo's RK4 at 1e-4 s
    from the file's first keyframe (whose own error is about 1e-12 m), to 1e-9 m."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", mb.InitialStateWarning)
        res = mb.forward_dynamics(model, [0.0, seconds], method="DOP853", rtol=1e-11,
                                  atol=1e-12)
    m = mujoco.MjModel.from_xml_path(str(path))
    m.opt.integrator, m.opt.timestep = mujoco.mjtIntegrator.mjINT_RK4, 1e-4
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    for _ in range(round(seconds / 1e-4)):
        mujoco.mj_step(m, d)
    for name in bodies:
        k = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name)
        np.testing.assert_allclose(res.body(name).position[-1], d.xipos[k], rtol=0, atol=1e-9)


def _file(tmp_path, text: str, name: str = "model.xml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_an_arm_has_mujocos_inverse_dynamics(tmp_path):
    """Each joint's generalised force for random positions, rates and accelerations of all
    four joints (MuJoCo's qpos: the shoulder's reference angle of 20 degrees included) against
    MuJoCo's mj_inverse, to 1e-12 of the largest; under those forces, the accelerations
    (mb.forward_dynamics_at) against MuJoCo's mj_forward and the ones asked for."""
    path = _file(tmp_path, ARM)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing left out: contacts are disabled
        model = mb.load_mjcf(path, drive={joint: 0.0 for joint in JOINTS})
    assert [body.name for body in model.bodies] == ["base", "upper", "fore", "tool"]
    assert model.name == "arm"
    # the tool's sphere geom is drawn about its centre of mass, the geom's centre
    np.testing.assert_allclose(np.linalg.norm(model.bodies[3].shape.vertices, axis=1), 0.04,
                               rtol=1e-12)
    rng = np.random.default_rng(1)
    q, qd, qdd = rng.uniform(-1, 1, (6, 4)), rng.uniform(-2, 2, (6, 4)), rng.uniform(-3, 3, (6, 4))
    res = mb.inverse_dynamics_at(model, q, qd, qdd)
    ours = np.column_stack([res.joint(f"{joint}_drive").effort for joint in JOINTS])
    # drawn elsewhere, the joints read MuJoCo's qpos all the same: the same efforts
    drawn = dict(zip(JOINTS, (0.3, -0.4, 0.5, 0.07)))
    posed = mb.load_mjcf(path, drive={joint: 0.0 for joint in JOINTS}, joint_positions=drawn)
    start = mb.forward_dynamics(mb.load_mjcf(path, joint_positions=drawn), [0.0, 1e-3])
    for joint, value in drawn.items():
        view = start.joint(joint)
        assert (view.displacement if joint == "extend" else view.angle)[0] == pytest.approx(
            value, abs=1e-12)
    again = mb.inverse_dynamics_at(posed, q, qd, qdd)
    np.testing.assert_allclose([again.joint(f"{joint}_drive").effort for joint in JOINTS],
                               ours.T, rtol=0, atol=1e-12 * np.abs(ours).max())
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    theirs = np.zeros_like(ours)
    for k in range(len(q)):
        d.qpos[:], d.qvel[:], d.qacc[:] = q[k], qd[k], qdd[k]
        mujoco.mj_inverse(m, d)
        theirs[k] = d.qfrc_inverse
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-12 * np.abs(theirs).max())
    # and forward: the accelerations under the same efforts are MuJoCo's (mj_forward)
    qdd_ours = mb.forward_dynamics_at(model, q, qd, theirs)
    for k in range(len(q)):
        d.qpos[:], d.qvel[:], d.qfrc_applied[:] = q[k], qd[k], theirs[k]
        mujoco.mj_forward(m, d)
        np.testing.assert_allclose(qdd_ours[k], d.qacc, rtol=0, atol=1e-9 * np.abs(d.qacc).max())
        np.testing.assert_allclose(qdd_ours[k], qdd[k], rtol=0, atol=1e-9 * np.abs(qdd[k]).max())


def test_a_free_floating_mechanism_tumbles_as_mujoco_integrates_it(tmp_path):
    """A box on a free joint carrying a capsule on a ball joint and a flap on a hinge, in zero
    gravity, from a keyframe's pose and velocities (every rate nonzero): the centres of mass
    after 0.5 s against MuJoCo's RK4 at 1e-4 s (whose own error is about 1e-12 m: 4e-9 m at
    1e-3 s), and the initial state taken as given (consistent, so not changed)."""
    path = _file(tmp_path, FLOATING)
    with pytest.warns(mb.MjcfWarning, match="not modelled: contacts between geoms"):
        model = mb.load_mjcf(path, keyframe="spin")
    _moves_as_in_mujoco(path, model, 0.5, ["hub", "arm", "flap"])


def test_a_bodys_two_and_three_hinges_through_one_point_move_as_in_mujoco(tmp_path):
    """A torso on two perpendicular hinges through one point (read as a universal joint), a
    thigh on three skew hinges through one point (a ball joint) and a shin on a knee, swinging
    under gravity from a keyframe's pose and rates: the centres of mass after 0.5 s (0.5 m of
    travel) against MuJoCo's RK4 at 1e-4 s; a range on one of three hinges (wide: MuJoCo would
    enforce it) is said to be left out, and such a hinge cannot be driven."""
    path = _file(tmp_path, GIMBALS)
    with pytest.warns(mb.MjcfWarning, match=r"the ranges of joints hip_y \(the ball joint "
                                            r"'hip_x\+hip_z\+hip_y'\)"):
        model = mb.load_mjcf(path, keyframe="kick")
    assert [type(joint).__name__ for joint in model.joints] == ["Universal", "Spherical",
                                                                 "Revolute"]
    _moves_as_in_mujoco(path, model, 0.5, ["torso", "thigh", "shin"])
    # refused before anything is added to a builder given
    builder = mb.ModelBuilder(dim=3)
    with pytest.raises(mb.ModelError, match=r"joint 'bend_y' is one of the joints mbd3d models "
                                            r"as the universal joint 'bend_z\+bend_y'"):
        mb.mjcf_builder(path, drive={"bend_y": 0.0}, builder=builder)
    builder.add_body("torso", mass=1.0, inertia=(0.1, 0.1, 0.1), position=(0, 0, 0))  # free


WALKER = """<mujoco model="walker">
  <option integrator="RK4" timestep="1e-4"/>
  <worldbody>
    <body name="torso" pos="0.1 0 1.2" euler="0 0.3 0">
      <joint name="rootx" type="slide" axis="1 0 0" pos="0 0 0.2"/>
      <joint name="rootz" type="slide" axis="0.6 0 0.8" pos="0 0 0.2"/>
      <joint name="rooty" type="hinge" axis="0 1 0" pos="0.05 0 0.1"/>
      <geom type="capsule" fromto="0 0 0.2 0 0 -0.2" size="0.05"/>
      <body name="leg" pos="0 0 -0.2">
        <joint name="hip" type="hinge" axis="0 -1 0"/>
        <geom type="capsule" fromto="0 0 0 0.1 0 -0.4" size="0.04"/>
      </body>
    </body>
  </worldbody>
  <keyframe><key name="push" qpos="0.2 -0.1 0.4 -0.6" qvel="1.0 2.0 -3.0 4.0"/></keyframe>
</mujoco>"""


def test_a_planar_robots_root_moves_as_in_mujoco(tmp_path):
    """A walker's torso on MuJoCo's usual planar root (two slides, not perpendicular, and a
    hinge normal to them, read as a planar joint) with a leg, thrown from a keyframe under
    gravity: the centres of mass after 0.5 s against MuJoCo's RK4 at 1e-4 s."""
    path = _file(tmp_path, WALKER)
    with pytest.warns(mb.MjcfWarning, match="contacts between geoms"):
        model = mb.load_mjcf(path, keyframe="push")
    assert [type(joint).__name__ for joint in model.joints] == ["Planar", "Revolute"]
    _moves_as_in_mujoco(path, model, 0.5, ["torso", "leg"])


def test_hinge_springs_and_dampers_act_as_in_mujoco(tmp_path):
    """A double pendulum whose hinges carry MuJoCo's joint stiffness (about a ``springref``
    other than the drawing's, a reference angle between them) and damping, swinging from a
    keyframe: the centres of mass after 1 s against MuJoCo's RK4 at 1e-4 s."""
    text = """<mujoco model="sprung"><option integrator="RK4" timestep="1e-4"/>
  <worldbody><body name="upper" pos="0 0 1" euler="0.2 0 0.1">
    <joint name="shoulder" axis="0 1 0.2" stiffness="12" damping="0.4" springref="0.3"
      ref="0.1"/>
    <geom type="capsule" fromto="0 0 0 0.3 0 -0.1" size="0.03"/>
    <body name="lower" pos="0.3 0 -0.1"><joint name="elbow" axis="0 1 0" damping="0.05"/>
      <geom type="capsule" fromto="0 0 0 0.25 0.05 0" size="0.025"/></body>
  </body></worldbody>
  <keyframe><key name="swing" qpos="-0.4 0.8" qvel="2.0 -1.0"/></keyframe>
</mujoco>"""
    path = _file(tmp_path, text)
    with pytest.warns(mb.MjcfWarning, match="contacts between geoms"):
        model = mb.load_mjcf(path, keyframe="swing")
    assert [force.name for force in model.forces] == ["shoulder_spring", "elbow_spring"]
    _moves_as_in_mujoco(path, model, 1.0, ["upper", "lower"])


def _four_bar(crank: float, coupler: float, rocker: float, ground: float) -> str:
    """A four-bar in the x-z plane drawn at crank angle 0 (hinges about y), its loop closed
    at B by a ``connect`` of the coupler to the rocker."""
    d = ground - crank
    along = (coupler**2 - rocker**2 + d**2) / (2 * d)
    up = np.sqrt(coupler**2 - along**2)
    return f"""<mujoco model="four-bar"><compiler angle="radian"/><worldbody>
  <body name="crank"><joint name="O2" axis="0 -1 0"/>
    <geom type="capsule" fromto="0 0 0 {crank} 0 0" size="0.01"/>
    <body name="coupler" pos="{crank} 0 0"><joint name="A" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 {along} 0 {up}" size="0.01"/></body></body>
  <body name="rocker" pos="{ground} 0 0"><joint name="O4" axis="0 1 0"/>
    <geom type="capsule" fromto="0 0 0 {crank + along - ground} 0 {up}" size="0.01"/></body>
</worldbody>
<equality><connect name="B" body1="coupler" body2="rocker" anchor="{along} 0 {up}"/></equality>
</mujoco>"""


def test_a_connect_closes_a_four_bar_that_moves_as_its_closed_form(tmp_path):
    """A crank-rocker four-bar whose loop MuJoCo closes by a ``connect``, its crank driven a
    full turn: the rocker's centre (the middle of the rocker, a uniform capsule) where the
    circles about the crank pin and the rocker pivot meet, to 1e-10 m."""
    crank, coupler, rocker, ground = 0.1, 0.3, 0.25, 0.3
    path = _file(tmp_path, _four_bar(crank, coupler, rocker, ground))
    with pytest.warns(mb.MjcfWarning, match="contacts between geoms"):
        model = mb.load_mjcf(path, drive={"O2": mb.Ramp(0.0, 2 * np.pi)})
    assert [(type(joint).__name__, joint.name) for joint in model.joints] == [
        ("Revolute", "O2"), ("RotationDriver", "O2_drive"), ("Revolute", "A"),
        ("Revolute", "O4"), ("Spherical", "B")]
    times = np.linspace(0.0, 1.0, 37)
    res = mb.kinematic_analysis(model, times)
    theta = 2 * np.pi * times
    A = crank * np.column_stack([np.cos(theta), np.zeros_like(theta), np.sin(theta)])
    e = np.array([ground, 0.0, 0.0]) - A
    d = np.linalg.norm(e, axis=1)[:, None]
    along = (coupler**2 - rocker**2 + d**2) / (2 * d)
    normal = np.column_stack([-e[:, 2], np.zeros_like(theta), e[:, 0]]) / d
    B = A + along * e / d + np.sqrt(coupler**2 - along**2) * normal
    np.testing.assert_allclose(res.body("rocker").position, (B + [ground, 0.0, 0.0]) / 2,
                               rtol=0, atol=1e-10)
    # MuJoCo keeps equality names apart from joint names: a connect named as a joint is kept
    same = _file(tmp_path, _four_bar(crank, coupler, rocker, ground).replace(
        'connect name="B"', 'connect name="A"'), "same.xml")
    with pytest.warns(mb.MjcfWarning):
        named = [joint.name for joint in mb.load_mjcf(same).joints]
    assert named == ["O2", "A", "O4", "A_connect"]


def _welded(block_pose: str | None = None, key: str = "") -> str:
    """A pendulum on a skew hinge carrying a tilted block: nested in the pendulum's body
    without a joint (one rigid body to MuJoCo and mbd3d), or free at ``block_pose`` (``pos``
    and ``quat``) and held by a ``weld``."""
    block = """<geom type="box" size="0.05 0.1 0.02" mass="0.7"/>"""
    nested = f'<body name="block" pos="0.1 0.2 -0.5" euler="30 0 60">{block}</body>'
    free = f'<body name="block" {block_pose}><freejoint/>{block}</body>'
    return f"""<mujoco model="welded"><compiler angle="degree"/>
  <worldbody><body name="bar" pos="0 0 1" euler="10 -20 5">
    <joint name="swing" type="hinge" axis="1 0.2 0.1"/>
    <geom type="capsule" fromto="0 0 0 0 0.1 -0.5" size="0.02" mass="1.5"/>
    {nested if block_pose is None else ""}</body>
  {"" if block_pose is None else free}</worldbody>
  {"" if block_pose is None else '<equality><weld name="glue" body1="bar" body2="block"/>'
   '</equality>'}{key}</mujoco>"""


def test_a_weld_holds_a_free_body_as_if_it_were_part_of_its_body(tmp_path):
    """A free block held to a pendulum by a ``weld`` swings as the same block nested in the
    pendulum's body (which both MuJoCo and mbd3d read as one rigid body): the hinge's angle to
    1e-9 rad over a second, and the weld is a ``Fixed`` joint named as the equality. A
    keyframe that moves the block off the weld's pose is refused, naming the weld."""
    import mbd3d.joints as joints

    # where the nested block is, at rest and released: the free block's pose and keyframe
    m = mujoco.MjModel.from_xml_string(_welded())
    d = mujoco.MjData(m)
    poses = []
    for angle in (0.0, np.radians(70.0)):
        d.qpos[0] = angle
        mujoco.mj_forward(m, d)
        poses.append(np.concatenate([d.xpos[2], d.xquat[2]]))
    at_rest = 'pos="{} {} {}" quat="{} {} {} {}"'.format(*poses[0])
    qpos = " ".join(map(str, [np.radians(70.0), *poses[1]]))
    released = f'<keyframe><key name="swung" qpos="{qpos}"/></keyframe>'
    runs = []
    for text, options in ((_welded(), {"joint_positions": {"swing": np.radians(70.0)}}),
                          (_welded(at_rest, released), {"keyframe": "swung"})):
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            model = mb.load_mjcf(_file(tmp_path, text, f"w{len(runs)}.xml"), **options)
        assert not [w for w in said if "equality" in str(w.message)]  # the weld is modelled
        runs.append(mb.forward_dynamics(model, np.linspace(0.0, 1.0, 11), method="DOP853",
                                        rtol=1e-11, atol=1e-12))
    glue = runs[1].model.joint("glue")
    assert isinstance(glue, joints.Fixed) and glue.body_j.name == "block"
    np.testing.assert_allclose(runs[1].joint("swing").angle, runs[0].joint("swing").angle,
                               rtol=0, atol=1e-9)
    assert np.ptp(runs[0].joint("swing").angle) > 1.0  # it swings
    moved = released.replace(f'qpos="{np.radians(70.0)} ', 'qpos="0.2 ')
    with pytest.raises(mb.ModelError, match="weld 'glue' holds body2 at .* the drawing"):
        mb.load_mjcf(_file(tmp_path, _welded(at_rest, moved), "moved.xml"), keyframe="swung")


def test_a_limited_hinge_stops_at_mujocos_range(tmp_path):
    """A pendulum on a skew hinge with a reference angle, released at rest beside its range
    [-30, 40] degrees: it swings into the upper end and rebounds; at the deepest point of the
    stop (rate zero) its centre of mass is where MuJoCo places it at qpos = 40 degrees, to
    the stop's dent (a stiff law: about 1e-4 rad), and its angle reads qpos."""
    text = """<mujoco model="limited"><compiler angle="degree"/>
  <worldbody><body name="bob" pos="0 0 1" euler="10 -20 5">
    <joint name="swing" type="hinge" axis="1 0.2 0.1" ref="15" range="-30 40"/>
    <inertial pos="0 0 -0.5" mass="2" diaginertia="0.02 0.03 0.04"/>
  </body></worldbody></mujoco>"""
    path = _file(tmp_path, text)
    law = mb.LinearContact(frequency=2000.0, restitution=0.5)
    model = mb.load_mjcf(path, joint_positions={"swing": np.radians(-25.0)}, joint_limits=law)
    assert "swing_limit" in [force.name for force in model.forces]
    times = np.linspace(0.0, 1.0, 4001)
    res = mb.forward_dynamics(model, times, method="DOP853", rtol=1e-10, atol=1e-12)
    rate, angle = res.joint("swing").angle_rate, res.joint("swing").angle
    deepest = np.argmax(angle)
    assert rate[deepest - 1] > 0 > rate[deepest + 1]  # the turn, not the end of the run
    # the hinge reads MuJoCo's qpos: drawn at -25 degrees, stopped just past 40
    assert angle[0] == pytest.approx(np.radians(-25.0), abs=1e-12)
    assert 0 < angle[deepest] - np.radians(40.0) < 5e-4
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    d.qpos[0] = np.radians(40.0)
    mujoco.mj_kinematics(m, d)
    np.testing.assert_allclose(res.body("bob").position[deepest], d.xipos[1], rtol=0,
                               atol=5e-4 * 0.5)


def test_what_mjcf_import_leaves_out_is_said(tmp_path):
    """Actuators, tendons, equality constraints, a ball joint's spring and damping, armature
    and dry friction, a ball joint's range, fluid forces, gravity compensation and contacts
    between geoms: one warning names them (a hinge's spring and damping are modelled: not
    named)."""
    text = """<mujoco model="extras"><option viscosity="0.1"/>
  <worldbody><geom name="floor" type="plane" size="1 1 0.1"/>
    <body name="a" pos="0 0 1" gravcomp="1"><joint name="j1" axis="0 1 0" damping="0.1"
      stiffness="2" armature="0.01" frictionloss="0.2"/><geom type="sphere" size="0.1"/>
      <site name="s1"/>
      <body name="b" pos="0 0 -0.3"><joint name="j2" type="ball" range="0 30" damping="0.3"
        stiffness="1"/>
        <geom type="sphere" size="0.1"/><site name="s2"/></body></body></worldbody>
  <tendon><spatial name="t"><site site="s1"/><site site="s2"/></spatial></tendon>
  <equality><joint joint1="j1"/></equality>
  <actuator><motor joint="j1"/></actuator>
</mujoco>"""
    with pytest.warns(mb.MjcfWarning) as caught:
        model = mb.load_mjcf(_file(tmp_path, text))
    message = str(caught[0].message)
    for part in ("1 actuators", "1 tendons",
                 "1 equality constraints (other than connect and weld)",
                 "joint stiffness (j2)",
                 "joint damping (j2)", "joint armature (j1)", "joint frictionloss (j1)",
                 "the range of ball joint 'j2'", "contacts between geoms",
                 "fluid forces (density 0, viscosity 0.1)", "gravity compensation"):
        assert part in message
    assert [body.name for body in model.bodies] == ["a", "b"]
    assert [force.name for force in model.forces] == ["j1_spring"]


@pytest.mark.parametrize("text, options, message", [
    ("<mujoco><worldbody><body name='a'><joint name='j1' axis='0 0 1'/><joint name='j2' "
     "axis='0 1 1'/><geom size='0.1'/></body></worldbody></mujoco>", {},
     r"body 'a' has 2 joints \(j1 \(hinge\), j2 \(hinge\)\); mbd3d joins two bodies by one "
     r"joint, and reads several only as two hinges about perpendicular axes"),
    ("<mujoco><worldbody><body name='a'><joint name='j1' axis='0 0 1'/><joint name='j2' "
     "type='slide' axis='0 1 0'/><geom size='0.1'/></body></worldbody></mujoco>", {},
     r"body 'a' has 2 joints \(j1 \(hinge\), j2 \(slide\)\)"),
    ("<mujoco><worldbody><body name='a'><joint name='j1' type='slide' axis='1 0 0'/><joint "
     "name='j2' type='slide' axis='0 1 0.1'/><joint name='j3' axis='0 0 1'/><geom size='0.1'/>"
     "</body></worldbody></mujoco>", {}, r"or a hinge and two slides normal to it"),
    ("<mujoco><worldbody><body name='a'><joint name='j1' axis='0 0 1'/><joint name='j2' "
     "axis='0 1 0' pos='0 0 0.1'/><geom size='0.1'/></body></worldbody></mujoco>", {},
     r"all through one point"),
    ("<mujoco><worldbody><body name='a'>\n<joint name='j1' axis='0 0 1'/>\n<geom size='0.1' "
     "type='nonsense'/></body></worldbody></mujoco>", {}, r"MuJoCo refuses it: .*line 3"),
    ("<mujoco><worldbody><body name='a'><joint name='j1' axis='0 0 1'/><geom size='0.1'/>"
     "</body></worldbody></mujoco>", {"drive": {"j2": 0.0}}, r"no joint 'j2' \(joints: j1\)"),
    ("<mujoco><worldbody><body name='a'><joint name='j1' type='ball'/><geom size='0.1'/>"
     "</body></worldbody></mujoco>", {"drive": {"j1": 0.0}},
     r"joint 'j1' is a ball joint; only hinge and slide joints take a coordinate"),
    ("<mujoco><worldbody><body name='a'><joint name='j1' axis='0 0 1'/><geom size='0.1'/>"
     "</body></worldbody><keyframe><key name='home'/></keyframe></mujoco>",
     {"keyframe": "start"}, r"no keyframe 'start' \(named keyframes: home\)"),
])
def test_mjcf_mistakes_are_named_with_the_file(tmp_path, text, options, message):
    path = _file(tmp_path, text, "broken.xml")
    with pytest.raises(mb.ModelError, match=r"MJCF '.*broken\.xml'.*" + message):
        mb.load_mjcf(path, **options)


def test_a_missing_file_is_named(tmp_path):
    with pytest.raises(mb.ModelError, match=r"MJCF '.*gone\.xml' cannot be read"):
        mb.load_mjcf(tmp_path / "gone.xml")


def test_a_model_file_starts_from_an_mjcf_file(tmp_path):
    """``mjcf: {file, drive}`` in a model file gives the model load_mjcf gives (the same
    efforts to the last bit); a mistyped field is named with its line."""
    _file(tmp_path, ARM, "arm.xml")
    drives = ", ".join(f"{joint}: 0.0" for joint in JOINTS)
    text = (f"mbd3d: 1\ndim: 3\ngravity: [0.3, -0.2, -9.81]\n"
            f"mjcf: {{file: arm.xml, drive: {{{drives}}}}}\n")
    (tmp_path / "arm.yaml").write_text(text)
    from_file = mb.load(tmp_path / "arm.yaml")
    direct = mb.load_mjcf(tmp_path / "arm.xml", drive={joint: 0.0 for joint in JOINTS})

    def efforts(model) -> list[float]:
        res = mb.inverse_dynamics_at(model, [0.1, 0.2, 0.3, 0.05], [1.0, -1.0, 0.5, 0.2],
                                     [0.5, 0.1, -2.0, 1.0])
        return [res.joint(f"{joint}_drive").effort[0] for joint in JOINTS]

    assert efforts(from_file) == efforts(direct)
    (tmp_path / "typo.yaml").write_text(text.replace("drive:", "drives:"))
    with pytest.raises(mb.ModelError, match=r"typo\.yaml:4: mjcf\.drives: unknown mjcf field "
                                            r"\(did you mean 'drive'\?\)"):
        mb.load(tmp_path / "typo.yaml")
    (tmp_path / "still.yaml").write_text(text.replace("gravity: [0.3, -0.2, -9.81]\n", ""))
    with pytest.warns(mb.MjcfWarning, match=r"the model's gravity .* is kept, not the file's"):
        mb.load(tmp_path / "still.yaml")


def test_the_files_read_are_the_file_its_includes_and_its_meshes(tmp_path):
    """A body in an included file drawn by a mesh in the compiler's ``meshdir``: the mesh is
    the body's shape (its volume, a 0.2 x 0.1 x 0.4 m box) and every file read is listed."""
    trimesh = pytest.importorskip("trimesh")
    (tmp_path / "meshes").mkdir()
    trimesh.creation.box(extents=(0.2, 0.1, 0.4)).export(tmp_path / "meshes" / "block.stl")
    _file(tmp_path, "<mujoco><worldbody><body name='block' pos='0 0 1'><joint name='j' "
                    "axis='0 1 0'/><geom type='mesh' mesh='block'/></body></worldbody>"
                    "</mujoco>", "part.xml")
    main = _file(tmp_path, "<mujoco><compiler meshdir='meshes'/><asset><mesh name='block' "
                           "file='block.stl'/></asset><include file='part.xml'/></mujoco>")
    read: list = []
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # one body's geoms: no contacts left out
        model = mb.load_mjcf(main, files_read=read)
    assert read == [str(main.resolve()), str((tmp_path / "part.xml").resolve()),
                    str((tmp_path / "meshes" / "block.stl").resolve())]
    # STL holds single precision: the box's corners to about 1e-8 m
    assert model.bodies[0].shape.volume == pytest.approx(0.2 * 0.1 * 0.4, rel=1e-6)
