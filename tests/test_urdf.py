"""URDF import: the PUMA 560 (tests/data/puma560.urdf, with the source of its numbers) against
a recursive Newton-Euler algorithm written here from the Denavit-Hartenberg table (not from the
URDF, not from mbd3d): gravity-holding torques at several poses and inverse-dynamics torques
along a joint trajectory. A closed-loop robot, a URDF chain closed by a link in a model file,
conserves energy. What URDF import does not model is reported."""

from __future__ import annotations

import math
import pathlib
import warnings

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.errors import ContactWarning
from mbd3d.io.urdf import UrdfWarning, load_urdf, urdf_builder

DATA = pathlib.Path(__file__).resolve().parent / "data"
PUMA = DATA / "puma560.urdf"
G = 9.81
pi = math.pi

#: standard DH rows of the PUMA 560 as in the URDF's comment: d, a, alpha, m, centre (DH frame
#: i), inertia about the centre (xx, yy, zz)
DH = [
    (0.0, 0.0, pi / 2, 1.0, (0.0, 0.0, 0.0), (0.2, 0.35, 0.2)),
    (0.0, 0.4318, 0.0, 17.4, (-0.3638, 0.006, 0.2275), (0.13, 0.524, 0.539)),
    (0.15005, 0.0203, -pi / 2, 4.8, (-0.0203, -0.0141, 0.070), (0.066, 0.078, 0.0125)),
    (0.4318, 0.0, pi / 2, 0.82, (0.0, 0.019, 0.0), (1.8e-3, 1.3e-3, 1.8e-3)),
    (0.0, 0.0, -pi / 2, 0.34, (0.0, 0.0, 0.0), (0.3e-3, 0.4e-3, 0.3e-3)),
    (0.0, 0.0, 0.0, 0.09, (0.0, 0.0, 0.032), (0.15e-3, 0.15e-3, 0.04e-3)),
]


def rnea(q, qd, qdd, gravity=G):
    """Joint torques of the standard-DH arm by recursive Newton-Euler (Luh, Walker and Paul),
    every vector in the frame of its own link."""
    z = np.array([0.0, 0.0, 1.0])
    omega, alpha = np.zeros(3), np.zeros(3)
    acceleration = np.array([0.0, 0.0, gravity])  # the base accelerates up: gravity
    rotations, offsets, forces, moments = [], [], [], []
    for (d, a, twist, m, r, inertia), qi, qdi, qddi in zip(DH, q, qd, qdd):
        c, s, ca, sa = math.cos(qi), math.sin(qi), math.cos(twist), math.sin(twist)
        R = np.array([[c, -s * ca, s * sa], [s, c * ca, -c * sa], [0.0, sa, ca]])  # i-1 <- i
        p = np.array([a, d * sa, d * ca])  # origin i from origin i-1, in frame i
        alpha = R.T @ (alpha + z * qddi + np.cross(omega, z * qdi))
        omega = R.T @ (omega + z * qdi)
        acceleration = (np.cross(alpha, p) + np.cross(omega, np.cross(omega, p))
                        + R.T @ acceleration)
        r = np.array(r)
        centre = np.cross(alpha, r) + np.cross(omega, np.cross(omega, r)) + acceleration
        J = np.diag(inertia)
        forces.append(m * centre)
        moments.append(J @ alpha + np.cross(omega, J @ omega))
        rotations.append(R)
        offsets.append(p)
    tau = np.zeros(6)
    f, n = np.zeros(3), np.zeros(3)
    for i in range(5, -1, -1):
        R_next = rotations[i + 1] if i < 5 else np.eye(3)
        p, r = offsets[i], np.array(DH[i][4])
        n = (R_next @ (n + np.cross(R_next.T @ p, f)) if i < 5 else np.zeros(3)) \
            + np.cross(p + r, forces[i]) + moments[i]
        f = (R_next @ f if i < 5 else np.zeros(3)) + forces[i]
        tau[i] = n @ (rotations[i].T @ z)
    return tau


def puma(drive):
    """The PUMA driven by ``drive``, without its stops: Newton-Euler has none (and the pose
    qn puts joint 3 at pi, past the file's limit of 3.14 rad, where its stop pushes)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UrdfWarning)
        return load_urdf(PUMA, drive=drive, joint_limits="ignore")


@pytest.mark.parametrize("turn", [pi, -pi])
def test_a_hinge_drawn_at_half_a_turn_keeps_its_stop_whichever_way_it_reads(turn):
    # joint 3 at +-pi, past the file's limits of +-3.14 rad by 0.0016 rad either way: its
    # stop is added and pushes, whether the drawing's half turn is read as pi or as -pi
    with pytest.warns(ContactWarning, match=r"joint3_limit'.* past its limit by 0.00159265"):
        model = load_urdf(PUMA, drive={"joint3": turn})
    assert "joint3_limit" in [f.name for f in model.forces]


POSES = {"qz": [0, 0, 0, 0, 0, 0], "qr": [0, pi / 2, -pi / 2, 0, 0, 0],
         "qn": [0, pi / 4, pi, 0, pi / 4, 0], "odd": [0.3, -0.7, 1.1, 0.4, -0.9, 0.6]}


@pytest.mark.parametrize("pose", sorted(POSES))
def test_puma_gravity_torques_match_newton_euler(pose):
    q = np.array(POSES[pose], dtype=float)
    model = puma({f"joint{i + 1}": q[i] for i in range(6)})
    rest = mb.static_equilibrium(model)
    efforts = np.array([rest.driver(f"joint{i + 1}_drive").effort[0] for i in range(6)])
    expected = rnea(q, np.zeros(6), np.zeros(6))
    np.testing.assert_allclose(efforts, expected, rtol=0, atol=1e-9 * np.abs(expected).max())
    if pose == "qz":  # the toolbox's documented gravload(qz): 0 37.4837 0.2489 0 0 0
        np.testing.assert_allclose(efforts, [0, 37.4837, 0.2489, 0, 0, 0], rtol=0, atol=5e-5)


def test_puma_inverse_dynamics_along_a_trajectory_matches_newton_euler():
    amplitude = np.array([0.8, 0.6, -0.7, 1.2, 0.9, -1.5])
    rate = np.array([1.3, 2.1, 1.7, 3.0, 2.6, 3.4])
    start = np.array(POSES["odd"])
    model = puma({f"joint{i + 1}": mb.Harmonic(amplitude[i], rate[i], 0.0, start[i])
                  for i in range(6)})
    t = np.linspace(0.0, 2.0, 21)
    res = mb.inverse_dynamics(model, t)
    for k, tk in enumerate(t):
        q = start + amplitude * np.sin(rate * tk)
        qd = amplitude * rate * np.cos(rate * tk)
        qdd = -amplitude * rate ** 2 * np.sin(rate * tk)
        expected = rnea(q, qd, qdd)
        efforts = [res.driver(f"joint{i + 1}_drive").effort[k] for i in range(6)]
        np.testing.assert_allclose(efforts, expected, rtol=0, atol=1e-8 * np.abs(expected).max())


def test_what_urdf_import_does_not_model_is_reported(tmp_path):
    with pytest.warns(UrdfWarning, match=r"joint limits are not enforced \(joint_limits='ignore'"
                                         r"\): joint1"):
        urdf_builder(PUMA, joint_limits="ignore")
    text = PUMA.read_text()
    (tmp_path / "floating.urdf").write_text(text.replace('name="joint4" type="revolute"',
                                                         'name="joint4" type="floating"'))
    with pytest.raises(mb.ModelError, match="joint 'joint4' is floating; it cannot be driven"):
        load_urdf(tmp_path / "floating.urdf", drive={"joint4": 0.1})
    with pytest.raises(mb.ModelError, match="joint 'joint4' is floating; its child is drawn "
                                            "where the URDF puts it"):
        load_urdf(tmp_path / "floating.urdf", joint_positions={"joint4": 0.1})
    (tmp_path / "mimic.urdf").write_text(text.replace(
        '<joint name="joint6" type="revolute">',
        '<joint name="joint6" type="revolute"><mimic joint="joint5" multiplier="2"/>'))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        urdf_builder(tmp_path / "mimic.urdf")
    assert any("mimic joints are not coupled (each moves freely): joint6 = 2.0 x joint5"
               in str(w.message) for w in caught)
    with pytest.raises(mb.ModelError, match="no joint 'joint9'"):
        urdf_builder(PUMA, drive={"joint9": 0.0})
    (tmp_path / "broken.urdf").write_text(text[:500])
    with pytest.raises(mb.ModelError, match=r"broken\.urdf' is not well-formed XML \(.*line 7"):
        urdf_builder(tmp_path / "broken.urdf")


def test_a_urdf_chain_closed_in_a_model_file_conserves_energy(tmp_path):
    """A crank and coupler from a URDF, the loop closed by a Distance link to a ground pivot
    (a four-bar whose rocker is massless), released under gravity; saved as a model file it
    rebuilds the same model."""
    loaded = mb.io.model_file.read(DATA / "closed_loop.yaml")
    model = loaded.model
    assert mb.mobility(model).dof == 1
    res = mb.forward_dynamics(model, np.linspace(0.0, 1.0, 51), method="DOP853", rtol=1e-10,
                              atol=1e-12)
    energy = res.kinetic_energy + res.potential_energy
    swing = np.ptp(res.kinetic_energy)
    assert swing > 0.1  # it moves
    assert np.max(np.abs(energy - energy[0])) < 1e-7 * swing
    again = mb.load(mb.save(model, tmp_path / "closed.yaml"))
    np.testing.assert_array_equal(again.q0, model.q0)


def test_a_link_inertia_given_in_a_turned_inertial_frame_is_turned_into_the_link(tmp_path):
    """A link of point masses, its inertia written in an inertial frame turned by roll, pitch
    and yaw and off the joint, swung about a tilted hinge without gravity: the driver's effort
    is I_axis theta'', I_axis summed over the point masses themselves (turned by SciPy's
    extrinsic xyz angles, URDF's convention), so the tensor's turn into the link's axes is
    checked, whichever way round it is written."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(7)
    masses = rng.uniform(0.5, 2.0, size=5)
    points = rng.normal(scale=0.2, size=(5, 3))
    points -= masses @ points / masses.sum()  # about their centre of mass
    inertia = sum(m * (p @ p * np.eye(3) - np.outer(p, p)) for m, p in zip(masses, points))
    centre, rpy = np.array([0.3, -0.1, 0.2]), np.array([0.7, -0.4, 1.9])
    axis = np.array([0.2, 0.5, 0.84])
    axis /= np.linalg.norm(axis)
    (ixx, ixy, ixz), (_, iyy, iyz), (_, _, izz) = inertia.tolist()
    axis, mass = axis.tolist(), float(masses.sum())
    urdf = tmp_path / "turned.urdf"
    urdf.write_text(f"""<robot name="turned">
  <link name="base"/>
  <joint name="hinge" type="revolute">
    <parent link="base"/><child link="arm"/>
    <origin xyz="0.1 0.2 0.3" rpy="0.3 0.2 -0.5"/>
    <axis xyz="{axis[0]!r} {axis[1]!r} {axis[2]!r}"/>
  </joint>
  <link name="arm">
    <inertial>
      <origin xyz="{centre[0]} {centre[1]} {centre[2]}" rpy="{rpy[0]} {rpy[1]} {rpy[2]}"/>
      <mass value="{mass!r}"/>
      <inertia ixx="{ixx!r}" ixy="{ixy!r}" ixz="{ixz!r}"
               iyy="{iyy!r}" iyz="{iyz!r}" izz="{izz!r}"/>
    </inertial>
  </link>
</robot>""")
    in_link = centre + Rotation.from_euler("xyz", rpy).apply(points)  # joint frame at 0
    moment = sum(m * np.sum(np.cross(axis, p) ** 2) for m, p in zip(masses, in_link))
    amplitude, rate = 0.8, 3.0
    model = load_urdf(urdf, gravity=(0.0, 0.0, 0.0),
                      drive={"hinge": mb.Harmonic(amplitude, rate)})
    t = np.linspace(0.0, 1.0, 11)
    effort = mb.inverse_dynamics(model, t).driver("hinge_drive").effort
    np.testing.assert_allclose(effort, moment * -amplitude * rate ** 2 * np.sin(rate * t),
                               rtol=0, atol=1e-10 * moment * amplitude * rate ** 2)


def test_a_broken_urdf_is_refused_not_loaded_as_part_of_a_robot(tmp_path):
    """A joint naming a link the file does not have (a typo, or a file cut short that the
    parser still recovers) would drop every link below it: refused, naming the file, the
    joint and the link; so is a link with two parents."""
    text = PUMA.read_text()
    typo = tmp_path / "typo.urdf"
    typo.write_text(text.replace('<parent link="link3"/>', '<parent link="lnk3"/>'))
    with pytest.raises(mb.ModelError, match=r"typo\.urdf.*joint 'joint4' names parent link "
                                            r"'lnk3'.*did you mean 'link3'"):
        load_urdf(typo)
    cut = tmp_path / "cut.urdf"
    cut.write_text(text[:text.index('<link name="link3">')])
    with pytest.raises(mb.ModelError, match=r"cut\.urdf.*(joint 'joint3' names child link "
                                            r"'link3'|is not well-formed XML)"):
        load_urdf(cut)
    twice = tmp_path / "twice.urdf"
    twice.write_text(text.replace('<child link="link6"/>', '<child link="link5"/>'))
    with pytest.raises(mb.ModelError, match=r"twice\.urdf.*link 'link5' is the child of joints "
                                            r"'joint5' and 'joint6'"):
        load_urdf(twice)


ONE_JOINT = """<robot name="r">
  <link name="base"/>
  <link name="arm"><inertial><mass value="MASS"/>
    <inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="AXIS"/>
  </joint>
</robot>
"""


@pytest.mark.parametrize("text, message", [
    ("hello, robot\n", r"bad\.urdf' is not well-formed XML \(Start tag expected"),
    ("<foo/>\n", r"bad\.urdf': the root element is <foo>; a URDF's is <robot"),
    ("<robot/>\n", r"bad\.urdf': <robot> has no name attribute"),
    (ONE_JOINT.replace("MASS", "nan").replace("AXIS", "0 0 1"),
     r"bad\.urdf': link 'arm': <mass value> must be a finite number >= 0 \[kg\], got nan"),
    (ONE_JOINT.replace("MASS", "-2").replace("AXIS", "0 0 1"),
     r"bad\.urdf': link 'arm': <mass value> must be a finite number >= 0 \[kg\], got -2"),
    (ONE_JOINT.replace("MASS", "2").replace("AXIS", "0 0 0"),
     r"bad\.urdf': joint 'j1': <axis xyz> \[0.0, 0.0, 0.0\] is not a direction"),
])
def test_urdf_mistakes_are_named_with_the_file_and_the_element(tmp_path, text, message):
    path = tmp_path / "bad.urdf"
    path.write_text(text)
    with pytest.raises(mb.ModelError, match=message):
        urdf_builder(path)
    # the control: the same robot with a mass and an axis loads
    path.write_text(ONE_JOINT.replace("MASS", "2").replace("AXIS", "0 0 1"))
    assert urdf_builder(path).build().n_coordinates == 6


def test_urdf_warnings_are_mbd3d_s_and_point_at_the_callers_line():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        load_urdf(PUMA, joint_limits="ignore")
    urdf_warnings = [w for w in caught if issubclass(w.category, mb.UrdfWarning)]
    assert urdf_warnings and mb.UrdfWarning is UrdfWarning
    assert {w.filename for w in urdf_warnings} == {__file__}


def test_driven_revolute_and_prismatic_joints_with_unnormalised_axes_move_as_drawn(tmp_path):
    """A yaw hinge about a non-unit axis, its origin turned, carrying a slide along a
    non-unit axis, both driven by motions that do not start at zero: the slider's centre
    follows the URDF's chain of transforms, composed here with SciPy. Both the ground's and
    the arm's x axes lean on the hinge's, so the driver must read the drawn angle in the
    plane normal to it."""
    from scipy.spatial.transform import Rotation

    urdf = tmp_path / "slide.urdf"
    urdf.write_text("""<robot name="slide">
  <link name="base"/>
  <joint name="yaw" type="revolute">
    <parent link="base"/><child link="arm"/>
    <origin xyz="0.1 -0.2 0.3" rpy="0.4 -0.3 0.2"/>
    <axis xyz="0.5 0.6 1.8"/>
  </joint>
  <link name="arm">
    <inertial><origin xyz="0.2 0 0"/><mass value="2.0"/>
      <inertia ixx="0.01" iyy="0.02" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="slide" type="prismatic">
    <parent link="arm"/><child link="slider"/>
    <origin xyz="0.5 0.1 0" rpy="0 0.5 0"/>
    <axis xyz="3 0 4"/>
  </joint>
  <link name="slider">
    <inertial><origin xyz="0 0.05 0.02"/><mass value="1.0"/>
      <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
</robot>""")
    yaw, slide = mb.Harmonic(0.6, 2.0, phase=0.5, offset=0.3), mb.Harmonic(0.1, 3.0, 1.0, 0.2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UrdfWarning)
        model = load_urdf(urdf, gravity=(0.0, 0.0, 0.0), drive={"yaw": yaw, "slide": slide})
    t = np.linspace(0.0, 1.0, 6)
    res = mb.kinematic_analysis(model, t)

    def turned(rpy):
        return Rotation.from_euler("xyz", rpy)

    expected = []
    for tk in t:
        theta, s = yaw.evaluate(tk)[0], slide.evaluate(tk)[0]
        axis = np.array([0.5, 0.6, 1.8])
        hinge = Rotation.from_rotvec(theta * axis / np.linalg.norm(axis))
        # the slide's axis is in its joint frame, turned from the arm's by the joint's origin
        in_arm = np.array([0.5, 0.1, 0.0]) + turned([0.0, 0.5, 0.0]).apply(
            s * np.array([0.6, 0.0, 0.8]) + np.array([0.0, 0.05, 0.02]))
        expected.append(np.array([0.1, -0.2, 0.3])
                        + (turned([0.4, -0.3, 0.2]) * hinge).apply(in_arm))
    np.testing.assert_allclose(res.body("slider").position, expected, rtol=0, atol=1e-12)
    with pytest.raises(mb.ModelError, match="no joint 'pitch'"):
        urdf_builder(urdf, joint_positions={"pitch": 0.1})


@pytest.mark.parametrize("reference", ["meshes/part.stl", "package://robot/meshes/part.stl",
                                       "file://{root}/robot/meshes/part.stl"])
def test_visual_meshes_are_found_where_urdf_says(tmp_path, reference):
    """A link's mesh relative to the URDF, in a ROS package found from the URDF's folder
    upwards, or as a file URL: drawn as that mesh, about the link's centre of mass."""
    import trimesh
    (tmp_path / "robot" / "meshes").mkdir(parents=True)
    (tmp_path / "robot" / "urdf").mkdir()
    box = trimesh.creation.box((0.1, 0.2, 0.3))
    box.export(tmp_path / "robot" / "meshes" / "part.stl")
    folder = tmp_path / "robot" / ("" if reference.startswith("meshes") else "urdf")
    urdf = folder / "r.urdf"
    urdf.write_text(f"""<robot name="r">
  <link name="base"/>
  <joint name="hinge" type="continuous">
    <parent link="base"/><child link="part"/><axis xyz="0 0 1"/>
  </joint>
  <link name="part">
    <inertial><origin xyz="0.01 0.02 0.03"/><mass value="1.0"/>
      <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><geometry><mesh filename="{reference.format(root=tmp_path)}"/></geometry></visual>
  </link>
</robot>""")
    shape = load_urdf(urdf).body("part").shape
    np.testing.assert_allclose(shape.bounds, box.bounds - [0.01, 0.02, 0.03], rtol=0,
                               atol=1e-6)


def test_a_urdf_limit_stops_the_joint_at_its_ends_in_urdf_terms(tmp_path):
    """A hinge whose origin is turned and whose axis is skew (so the angle mbd3d measures
    differs from the URDF's coordinate by an offset), spinning freely at 2 rad/s from
    q = 0.1 towards its upper limit 0.5: it bounces at t = 0.2 s with the default stop's
    restitution 0.5 (its inertia about the hinge, a fixed axis), then travels 0.8 rad at 1 rad/s
    to the lower limit -0.3 and bounces again at t = 1.0 s. The stop's contact lasts half its
    100 Hz period, 5 ms."""
    urdf = tmp_path / "limited.urdf"
    urdf.write_text("""<robot name="limited">
  <link name="base"/>
  <joint name="hinge" type="revolute">
    <parent link="base"/><child link="arm"/>
    <origin xyz="0.1 0.2 0.3" rpy="0.3 0.2 -0.5"/>
    <axis xyz="0.2 0.5 0.84"/>
    <limit lower="-0.3" upper="0.5" effort="10" velocity="5"/>
  </joint>
  <link name="arm">
    <inertial>
      <origin xyz="0.3 -0.1 0.2" rpy="0.7 -0.4 1.9"/>
      <mass value="1.3"/>
      <inertia ixx="0.02" ixy="0.001" ixz="-0.002" iyy="0.03" iyz="0.003" izz="0.025"/>
    </inertial>
  </link>
</robot>""")
    model = load_urdf(urdf, gravity=(0.0, 0.0, 0.0), joint_positions={"hinge": 0.1})
    t = [0.0, 0.19, 0.21, 0.99, 1.01]
    res = mb.forward_dynamics(model, t, initial_rates={"hinge": 2.0}, method="DOP853",
                              rtol=1e-11, atol=1e-13)
    rate = res.joint("hinge").angle_rate
    np.testing.assert_allclose(rate, [2.0, 2.0, -1.0, -1.0, 0.5], rtol=1e-7, atol=0)
    with pytest.raises(mb.ModelError, match="joint_limits must be 'stop', 'ignore' or a"):
        load_urdf(urdf, joint_limits="yes")
    # refused before anything is added to a builder given: its bodies' names are still free
    builder = mb.ModelBuilder(dim=3)
    with pytest.raises(mb.ModelError, match="joint_limits must be"):
        urdf_builder(urdf, joint_limits="yes", builder=builder)
    urdf_builder(urdf, builder=builder)


FLOATY = """<robot name="floaty">
  <link name="world"/>
  <link name="puck"><inertial><origin xyz="0.01 0 0"/><mass value="2"/>
    <inertia ixx="0.02" iyy="0.03" izz="0.04" ixy="0.001" ixz="0" iyz="0"/></inertial></link>
  <link name="arm"><inertial><origin xyz="0.2 0 0.1"/><mass value="0.5"/>
    <inertia ixx="0.001" iyy="0.004" izz="0.004" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="base" type="KIND"><parent link="world"/><child link="puck"/>
    <origin xyz="0.1 0.2 0.3" rpy="0.3 0.2 0.1"/><axis xyz="0 0 1"/></joint>
  <joint name="swing" type="revolute"><parent link="puck"/><child link="arm"/>
    <origin xyz="0.05 0 0"/><axis xyz="1 0.3 0"/></joint>
</robot>
"""


@pytest.mark.parametrize("kind", ["planar", "floating"])
def test_a_planar_or_floating_base_recoils_from_a_swinging_arm(tmp_path, kind):
    """A puck on a planar joint (or a floating one) carrying an arm whose hinge, skew to the
    plane, is driven to swing, in zero gravity from rest. Planar: the puck keeps its plane
    (its normal and its height along it, to 1e-9) and the centre of mass of the two stays
    put along the plane (no force along it), while the puck recoils. Floating: the centre of
    mass stays put in all three directions and the puck tilts out of its plane."""
    path = tmp_path / "floaty.urdf"
    path.write_text(FLOATY.replace("KIND", kind))
    model = load_urdf(path, gravity=(0.0, 0.0, 0.0), drive={"swing": mb.Harmonic(0.8, 5.0)})
    assert [type(joint).__name__ for joint in model.joints] == (
        ["Planar"] if kind == "planar" else []) + ["Revolute", "RotationDriver"]
    res = mb.forward_dynamics(model, np.linspace(0.0, 1.0, 11), method="DOP853", rtol=1e-11,
                              atol=1e-12)
    c, s = np.cos, np.sin
    rx, ry, rz = 0.3, 0.2, 0.1  # URDF's rpy: R = Rz Ry Rx
    R = (np.array([[c(rz), -s(rz), 0], [s(rz), c(rz), 0], [0, 0, 1]])
         @ np.array([[c(ry), 0, s(ry)], [0, 1, 0], [-s(ry), 0, c(ry)]])
         @ np.array([[1, 0, 0], [0, c(rx), -s(rx)], [0, s(rx), c(rx)]]))
    normal = R[:, 2]
    puck, arm = res.body("puck").position, res.body("arm").position
    centre = (2.0 * puck + 0.5 * arm) / 2.5
    drift = centre - centre[0]
    tilt = np.linalg.norm(res.body("puck").rotation[:, :, 2] - normal, axis=1)
    if kind == "planar":
        along = drift @ normal
        np.testing.assert_allclose(drift - along[:, None] * normal, 0.0, rtol=0, atol=1e-9)
        np.testing.assert_allclose((puck - puck[0]) @ normal, 0.0, rtol=0, atol=1e-9)
        np.testing.assert_allclose(tilt, 0.0, rtol=0, atol=1e-9)
    else:
        np.testing.assert_allclose(drift, 0.0, rtol=0, atol=1e-9)
        assert tilt.max() > 1e-2
    assert np.max(np.linalg.norm(puck - puck[0], axis=1)) > 1e-3  # it recoils


WELDED = """<robot name="welded">
  <link name="base"/>
  <link name="arm"><inertial><origin xyz="0.2 0 0" rpy="0 0 0.3"/><mass value="2"/>
    <inertia ixx="0.01" iyy="0.03" izz="0.035" ixy="0.002" ixz="0" iyz="0"/></inertial></link>
  <link name="tool"><inertial><origin xyz="0 0.05 0.1"/><mass value="0.5"/>
    <inertia ixx="0" iyy="0" izz="0" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="flange"/>
  <link name="camera"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="arm"/>
    <origin xyz="0 0 0.4"/><axis xyz="0 0 1"/><limit lower="0" upper="0"/></joint>
  <joint name="tool" type="fixed"><parent link="arm"/><child link="tool"/>
    <origin xyz="0.5 0 0" rpy="0 0.4 0"/><axis xyz="0 0 0"/></joint>
  <joint name="mount" type="fixed"><parent link="tool"/><child link="flange"/></joint>
  <joint name="pan" type="continuous"><parent link="flange"/><child link="camera"/>
    <axis xyz="1 0 0"/></joint>
</robot>
"""


def test_links_welded_by_fixed_joints_are_one_body_with_their_summed_inertia(tmp_path):
    """An arm carrying a point-mass tool on a fixed joint (its axis left zero), a massless
    flange and a massless camera on a hinge: one body named after the arm, whose mass, centre
    and inertia are those of the two summed by the parallel-axis theorem, computed here from
    the URDF's numbers; the camera's hinge moves no mass and is left out; the joint and link
    both named 'tool' keep apart; limits with equal ends are no stop."""
    path = tmp_path / "welded.urdf"
    path.write_text(WELDED)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = load_urdf(path)
    said = " ".join(str(w.message) for w in caught if issubclass(w.category, UrdfWarning))
    assert "left out with their links: pan" in said
    assert "joint limits are not enforced" in said and "shoulder [0.0, 0.0]" in said
    assert [body.name for body in model.bodies] == ["arm"]
    assert [e.name for e in model.joints] == ["shoulder"] and not model.forces
    # by hand: both centres and inertias in the drawing (the arm's frame is at z = 0.4)
    c, s = math.cos(0.3), math.sin(0.3)
    R_arm = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    I_arm = R_arm @ np.array([[0.01, 0.002, 0], [0.002, 0.03, 0], [0, 0, 0.035]]) @ R_arm.T
    c, s = math.cos(0.4), math.sin(0.4)
    R_tool = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    centres = np.array([[0.2, 0.0, 0.4], np.array([0.5, 0.0, 0.4]) + R_tool @ [0, 0.05, 0.1]])
    masses = np.array([2.0, 0.5])
    centre = masses @ centres / 2.5
    inertia = I_arm.copy()
    for m, r in zip(masses, centres - centre):
        inertia += m * ((r @ r) * np.eye(3) - np.outer(r, r))
    arm = model.bodies[0]
    assert arm.mass == pytest.approx(2.5, rel=1e-15)
    np.testing.assert_allclose(model.q0[:3], centre, rtol=0, atol=1e-15)
    np.testing.assert_allclose(arm.inertia, inertia, rtol=0, atol=1e-15)  # arm axes = drawing


def test_what_a_broken_robot_gets_is_said(tmp_path):
    """Inertias off the triangle inequality by rounding are repaired, beyond it refused with
    the link; a missing mesh is a warning (or refused, or not read); a driven joint that
    moves no mass is refused; a joint named as a link is renamed; a link named as the
    model's ground becomes '<name>_link'."""
    rounding = ONE_JOINT.replace("MASS", "2").replace("AXIS", "0 0 1").replace(
        'ixx="1" iyy="1" izz="1"', 'ixx="1" iyy="1" izz="2.005"')
    path = tmp_path / "r.urdf"
    path.write_text(rounding)
    with pytest.warns(UrdfWarning, match=r"link 'arm': principal moments .* by 0\.25% .* J3 "
                                          "lowered to J1 \\+ J2"):
        arm = load_urdf(path).bodies[0]
    np.testing.assert_allclose(np.linalg.eigvalsh(arm.inertia), [1, 1, 2], rtol=1e-15)
    path.write_text(rounding.replace('izz="2.005"', 'izz="2.5"'))
    with pytest.raises(mb.ModelError, match=r"r\.urdf': link 'arm' .* exceeds the sum of the "
                                            r"others by 20\.0%; no real body has them"):
        load_urdf(path)
    mesh = rounding.replace('izz="2.005"', 'izz="2"').replace(
        "</inertial></link>", "</inertial><visual><geometry><mesh filename=\"gone.stl\"/>"
        "</geometry></visual></link>", 1)
    path.write_text(mesh)
    with pytest.warns(UrdfWarning, match=r"mesh 'gone\.stl' not found.*link 'arm' is drawn "
                                          "without it"):
        assert load_urdf(path).bodies[0].shape is None
    with pytest.raises(mb.ModelError, match=r"mesh 'gone\.stl' not found"):
        load_urdf(path, meshes="require")
    read: list = []
    load_urdf(path, meshes="skip", files_read=read)
    assert read == [str(path.resolve())]
    with pytest.raises(mb.ModelError, match=r"meshes must be 'load', 'require' or 'skip'"):
        load_urdf(path, meshes="maybe")
    welded = tmp_path / "welded.urdf"
    welded.write_text(WELDED)
    with pytest.raises(mb.ModelError, match=r"joint\(s\) pan move no mass .* cannot be driven"):
        load_urdf(welded, drive={"pan": 0.1})
    with pytest.raises(mb.ModelError, match=r"joint 'tool' is fixed; it cannot be driven"):
        load_urdf(welded, drive={"tool": 0.1})
    same = tmp_path / "same.urdf"
    same.write_text(ONE_JOINT.replace("MASS", "2").replace("AXIS", "0 0 1").replace(
        'joint name="j1"', 'joint name="arm"'))
    with pytest.warns(UrdfWarning, match=r"joints named as links are renamed in the model: "
                                          r"'arm' -> 'arm_joint'"):
        model = load_urdf(same, drive={"arm": mb.Ramp(0.0, 1.0)})
    assert [e.name for e in model.joints] == ["arm_joint", "arm_joint_drive"]
    grounded = tmp_path / "g.urdf"
    grounded.write_text(ONE_JOINT.replace("MASS", "2").replace("AXIS", "0 0 1").replace(
        '"arm"', '"ground"'))
    with pytest.warns(UrdfWarning, match=r"link 'ground' is the body 'ground_link'"):
        assert load_urdf(grounded).bodies[0].name == "ground_link"


def test_joints_read_the_files_joint_coordinates_and_start_from_them(tmp_path):
    """Two hinges on skew axes, their origins turned (so that the links' x axes lean on the
    axes and on each other), and a slide along a skew axis, drawn at joint_positions: each
    reads the file's coordinate, in the drawing and where initial_positions puts it, and the
    last link is where the URDF's chain of transforms (composed here with SciPy) puts it at
    those coordinates."""
    from scipy.spatial.transform import Rotation

    urdf = tmp_path / "arm.urdf"
    urdf.write_text("""<robot name="arm">
  <link name="base"/>
  <joint name="yaw" type="revolute">
    <parent link="base"/><child link="upper"/>
    <origin xyz="0.1 -0.2 0.3" rpy="0.4 -0.3 0.2"/><axis xyz="0.5 0.6 1.8"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/>
  </joint>
  <link name="upper">
    <inertial><origin xyz="0.2 0 0"/><mass value="2.0"/>
      <inertia ixx="0.01" iyy="0.02" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="pitch" type="continuous">
    <parent link="upper"/><child link="lower"/>
    <origin xyz="0.4 0.1 0" rpy="1.2 0.5 -0.7"/><axis xyz="0 1 0.3"/>
  </joint>
  <link name="lower">
    <inertial><origin xyz="0.1 0.05 0.02"/><mass value="1.0"/>
      <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="slide" type="prismatic">
    <parent link="lower"/><child link="slider"/>
    <origin xyz="0.2 0 0.1" rpy="0 0.3 0.6"/><axis xyz="1 2 2"/>
    <limit lower="-0.5" upper="0.5" effort="1" velocity="1"/>
  </joint>
  <link name="slider">
    <inertial><origin xyz="0.03 0 -0.02"/><mass value="0.5"/>
      <inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
</robot>""")

    def pose(yaw, pitch, slide):
        """The slider's centre of mass and rotation at the file's coordinates."""
        def joint(xyz, rpy, axis, angle=0.0, travel=0.0):
            axis = np.asarray(axis, float) / np.linalg.norm(axis)
            turned = Rotation.from_euler("xyz", rpy)
            return np.array(xyz) + turned.apply(travel * axis), turned * Rotation.from_rotvec(
                angle * axis)
        p1, R1 = joint([0.1, -0.2, 0.3], [0.4, -0.3, 0.2], [0.5, 0.6, 1.8], yaw)
        p2, R2 = joint([0.4, 0.1, 0.0], [1.2, 0.5, -0.7], [0.0, 1.0, 0.3], pitch)
        p3, R3 = joint([0.2, 0.0, 0.1], [0.0, 0.3, 0.6], [1.0, 2.0, 2.0], travel=slide)
        return (p1 + R1.apply(p2 + R2.apply(p3 + R3.apply([0.03, 0.0, -0.02]))),
                (R1 * R2 * R3).as_matrix())

    drawn = {"yaw": 0.7, "pitch": -2.9, "slide": 0.15}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UrdfWarning)
        model = load_urdf(urdf, gravity=(0.0, 0.0, 0.0), joint_positions=drawn)
    # the stops are at the file's limits too: each gap to the nearer end, [-3, 3] rad from
    # 0.7 rad and [-0.5, 0.5] m from 0.15 m
    states = mb.contact_states(model, model.q0)
    assert states.names == ["yaw_limit", "slide_limit"]
    np.testing.assert_allclose(states.gap, [2.3, 0.35], rtol=0, atol=1e-12)
    for start in (None, {"yaw": -1.3, "pitch": 2.4, "slide": -0.35}):
        res = mb.forward_dynamics(model, [0.0, 0.01], initial_positions=start)
        at = start or drawn
        for name, value in at.items():
            read = res.joint(name).displacement if name == "slide" else res.joint(name).angle
            assert read[0] == pytest.approx(value, abs=1e-12)
        centre, rotation = pose(at["yaw"], at["pitch"], at["slide"])
        np.testing.assert_allclose(res.body("slider").position[0], centre, rtol=0, atol=1e-12)
        np.testing.assert_allclose(res.body("slider").rotation[0], rotation, rtol=0, atol=1e-12)
