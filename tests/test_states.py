"""Inverse dynamics, joint-space mass matrices and bias forces at given states, in any order:
a closed loop (the slider-crank) against its closed-form one-degree-of-freedom model, and
robots against Pinocchio's RNEA, CRBA and nonlinear effects (written apart from ours, in
joint coordinates)."""

from __future__ import annotations

import importlib.metadata
import math
import pathlib

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.io.model_file import read
from mbd3d.joints import Revolute, RotationDriver
from mbd3d.mechanisms import slider_crank
from four_bar_loop import four_bar_by_hand
from slider_crank_oracle import SliderCrankOracle

MODELS = pathlib.Path(__file__).resolve().parents[1] / "examples" / "models"


def test_slider_crank_efforts_at_states_over_many_turns_in_any_order():
    model = slider_crank(crank_speed=2 * math.pi)
    oracle = SliderCrankOracle()
    rng = np.random.default_rng(4)
    # angles over five turns either way, shuffled: each state far from the one before
    phi, rate, acceleration = (rng.uniform(-30.0, 30.0, 12), rng.normal(size=12) * 8.0,
                               rng.normal(size=12) * 40.0)
    res = mb.inverse_dynamics_at(model, {"motor": phi}, {"motor": rate},
                                 {"motor": acceleration})
    expected = [oracle.driving_torque(*x) for x in zip(phi, rate, acceleration)]
    np.testing.assert_allclose(res.joint("motor").effort, expected, rtol=1e-10,
                               atol=1e-12 * np.max(np.abs(expected)))
    # and on the branch of the drawing (slider right of the crank) at every state
    np.testing.assert_allclose(res.body("slider").position[:, 0], oracle.slider_x(phi),
                               rtol=0, atol=1e-12)
    # a guess for the first state (its solution): the later ones are still reached in pieces
    guessed = mb.inverse_dynamics_at(model, {"motor": phi}, {"motor": rate},
                                     {"motor": acceleration}, q_guess=res.q[0])
    np.testing.assert_allclose(guessed.body("slider").position[:, 0], oracle.slider_x(phi),
                               rtol=0, atol=1e-12)
    M, b = mb.joint_space_dynamics_at(model, phi[:, None], rate[:, None])
    np.testing.assert_allclose(M[:, 0, 0], [oracle.generalized_mass(p) for p in phi],
                               rtol=1e-10, atol=0)
    np.testing.assert_allclose(b[:, 0], [oracle.driving_torque(p, r) for p, r in
                                         zip(phi, rate)], rtol=1e-10, atol=1e-12)


def test_a_driver_s_offset_is_taken_off_the_coordinate_it_starts_from():
    """States near the drawing are reached from the drawing's coordinate, the driven angle or
    slide less the driver's offset: counted with the offset, the way there is the offset long
    and leads a closed loop onto its other branch or out of reach."""
    # answers to the model files' printed digits and Newton-Raphson's tolerance: the other
    # branch is radians away
    # the four-bar's crank angle with an offset of 4 rad: its rocker on the open branch
    four_bar = read(MODELS / "four_bar.yaml", {"joints.motor.offset": 4.0}).model
    drawn = math.pi / 3 - 4.0
    phi = np.array([drawn + 0.05, drawn - 0.05])
    res = mb.inverse_dynamics_at(four_bar, {"motor": phi}, 1.0, 0.0)
    np.testing.assert_allclose(res.body("rocker").angle,
                               [four_bar_by_hand(p + 4.0)[0][1] for p in phi], rtol=0,
                               atol=1e-10)
    # the slider-crank (crank drawn at 65 degrees) driven at its slider with 0.2 m of offset:
    # the crank above the rail
    r, l, drawn = 0.12, 0.26, math.radians(65.0)
    x0 = r * math.cos(drawn) + math.sqrt(l * l - (r * math.sin(drawn)) ** 2)
    by_slide = read(MODELS / "slider_crank.yaml", {
        "joints.motor.type": "TranslationDriver", "joints.motor.joint": "rail",
        "joints.motor.motion": {"type": "Ramp", "initial": x0 - 0.2, "rate": 0.0},
        "joints.motor.offset": 0.2}).model
    # and from 0.37 m to 0.16 m, walked in pieces of a quarter of the model's length (in one,
    # Newton-Raphson turns the crank below the rail)
    x = np.array([x0 + 0.02, x0 - 0.02, 0.37, 0.16])
    res = mb.inverse_dynamics_at(by_slide, {"motor": x - 0.2}, 0.0, 0.0)
    crank_up = np.arccos((r * r + x * x - l * l) / (2 * r * x))
    np.testing.assert_allclose(res.body("crank").angle, crank_up, rtol=0, atol=1e-10)


def _robot(name: str) -> pathlib.Path:
    try:
        share = importlib.metadata.distribution("example-robot-data").locate_file(
            "cmeel.prefix/share/example-robot-data/robots")
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("example-robot-data is not installed")
    return pathlib.Path(str(share)) / name


@pytest.mark.filterwarnings("ignore::mbd3d.io.urdf.UrdfWarning")
@pytest.mark.parametrize("name", ["ur_description/urdf/ur5_robot.urdf",
                                  "panda_description/urdf/panda.urdf"])
def test_robot_dynamics_at_states_match_pinocchio(name):
    pin = pytest.importorskip("pinocchio")
    path = _robot(name)
    reference = pin.buildModelFromUrdf(str(path))
    joints = list(reference.names[1:])
    model = mb.load_urdf(path, meshes="skip", joint_limits="ignore",
                         drive={j: 0.0 for j in joints})
    drivers = [f"{j}_drive" for j in joints]
    assert mb.driven_coordinates(model) == tuple(drivers)
    rng = np.random.default_rng(len(joints))
    k, d = 6, len(joints)
    q, v, a = rng.uniform(-2.5, 2.5, (k, d)), rng.normal(size=(k, d)), rng.normal(size=(k, d))
    for j, joint in enumerate(reference.joints[1:]):
        if joint.shortname() == "JointModelPZ" or "Prismatic" in joint.shortname():
            q[:, j] = rng.uniform(0.0, 0.04, k)  # a finger's slide [m]
    res = mb.inverse_dynamics_at(model, q, v, a)
    M, b = mb.joint_space_dynamics_at(model, q, v)
    data = reference.createData()
    for s in range(k):
        x = np.concatenate([(np.cos(q[s, j]), np.sin(q[s, j])) if joint.nq == 2 else
                            (q[s, j],) for j, joint in enumerate(reference.joints[1:])])
        tau = pin.rnea(reference, data, x, v[s], a[s])
        scale = max(1.0, float(np.max(np.abs(tau))))
        ours = [res.joint(name).effort[s] for name in drivers]
        np.testing.assert_allclose(ours, tau, rtol=0, atol=1e-10 * scale)
        crba = pin.crba(reference, data, x)
        crba = np.triu(crba) + np.triu(crba, 1).T
        np.testing.assert_allclose(M[s], crba, rtol=0, atol=1e-10 * np.max(np.abs(crba)))
        np.testing.assert_allclose(b[s], pin.nonLinearEffects(reference, data, x, v[s]),
                                   rtol=0, atol=1e-10 * scale)
    # forward: the accelerations under random efforts against Pinocchio's articulated-body
    # algorithm
    efforts = rng.normal(size=(k, d)) * np.max(np.abs(b), axis=1, keepdims=True)
    qdd = mb.forward_dynamics_at(model, q, v, efforts)
    for s in range(k):
        x = np.concatenate([(np.cos(q[s, j]), np.sin(q[s, j])) if joint.nq == 2 else
                            (q[s, j],) for j, joint in enumerate(reference.joints[1:])])
        aba = pin.aba(reference, data, x, v[s], efforts[s])
        np.testing.assert_allclose(qdd[s], aba, rtol=0, atol=1e-8 * np.max(np.abs(aba)))


def test_a_slider_crank_under_a_torque_accelerates_as_its_augmented_equations_say():
    """The closed loop's crank acceleration from its joint-space mass and bias (inverse
    dynamics at states) against the same mechanism without its motor and with a torque on
    the crank, its augmented equations of all coordinates solved at each state (forward
    dynamics' own path), over a turn with rates and torques both ways."""
    driven = slider_crank(crank_speed=2 * math.pi)
    theta = np.linspace(0.0, 2 * math.pi, 7)[:-1] + 0.3
    omega, torque = np.linspace(-8.0, 8.0, 6), np.linspace(-3.0, 2.0, 6)
    qdd = mb.forward_dynamics_at(driven, {"motor": theta}, {"motor": omega},
                                 {"motor": torque})
    states = mb.inverse_dynamics_at(driven, {"motor": theta}, {"motor": omega}, 0.0)
    for s in range(len(theta)):
        free = slider_crank(crank_speed=None, crank_torque=float(torque[s]))
        expected, _ = mb.forward_accelerations(free, 0.0, states.q[s], states.qd[s])
        crank = expected[free.coordinate_index("crank.theta")]
        assert qdd[s, 0] == pytest.approx(crank, rel=1e-9, abs=1e-9)


def test_bad_states_are_named():
    model = slider_crank(crank_speed=2 * math.pi)
    for given, message in (({"motr": 1.0}, r"'motr', which is not a driver \(did you mean "
                                           "'motor'"),
                           ({}, "no value for driver 'motor'"),
                           ({"motor": [1.0, np.nan]}, "q of driver 'motor' is not finite in "
                                                      "state 1"),
                           ([[1.0, 2.0]], r"one column per driver \(1: \['motor'\]\)")):
        with pytest.raises(mb.ModelError, match=message):
            mb.inverse_dynamics_at(model, given, 0.0, 0.0)
    with pytest.raises(mb.ModelError, match="q, qd and qdd give"):
        mb.inverse_dynamics_at(model, [[1.0], [2.0]], [[0.0]] * 3, 0.0)
    free = mb.ModelBuilder(dim=2)
    free.add_body("puck", mass=1.0, inertia=0.1, position=(0.0, 0.0))
    with pytest.raises(mb.ModelError, match="has no drivers"):
        mb.inverse_dynamics_at(free.build(), 0.0, 0.0, 0.0)
    with pytest.raises(mb.ModelError, match="forward dynamics at given states of 'slider-crank': "
                                            "efforts give 2 states, q and qd 3"):
        mb.forward_dynamics_at(model, {"motor": [1.0, 2.0, 3.0]}, 0.0, [[1.0], [2.0]])
    # a driven coordinate that moves (almost) nothing: its acceleration is not an answer
    chain = mb.ModelBuilder(dim=2)
    arm = chain.add_body("arm", mass=1.0, inertia=0.1, position=(0.5, 0.0))
    tip = chain.add_body("tip", mass=1e-20, inertia=1e-20, position=(1.5, 0.0))
    for name, i, j, at in (("O", chain.ground, arm, 0.0), ("A", arm, tip, 1.0)):
        joint = chain.add(Revolute(name, i, j, at=(at, 0.0)))
        chain.add(RotationDriver(f"{name}_drive", joint, motion=mb.Ramp(0.0, 0.0)))
    with pytest.raises(mb.AnalysisError, match=r"in state 0 the drivers' mass matrix is "
                                               r"singular \(condition .*moves no mass"):
        mb.forward_dynamics_at(chain.build(), [0.1, 0.2], 0.0, [1.0, 0.0])
