"""The benchmark models built in Exudyn and MuJoCo, for side-by-side timing at equal accuracy.

Optional: ``pip install -e ".[peers]"`` installs both from the package index. Each function
builds the same model as the mbd3d benchmark (same masses, inertias, lengths, gravity and
initial state), integrates it over ``duration`` with the peer's own integrator at a fixed
step, and returns the reported quantity and the wall time of the integration alone (model
building excluded, as for mbd3d).

- Exudyn (absolute coordinates, like mbd3d): its default implicit generalized-alpha solver
  (index 3, second order, fixed step), with Eigen's sparse LU above 20 bodies.
- MuJoCo (minimal coordinates, a tree of hinge or ball joints): its RK4 integrator, contacts
  off. It has no exact loop closure (equality constraints are soft), so it joins the chain
  benchmarks only.

Newton's cradle (``mbd3d.mechanisms.newtons_cradle``) is the contact scenario: Exudyn's
``ObjectContactSphereSphere`` with the same Hertz law (``K delta^1.5``, undamped) between
neighbours, and its generalized-alpha (its explicit solvers refuse the strings' joints).
MuJoCo has no Hertz law: its soft contact is given the linear law of the same duration of
impact (its "direct" stiffness ``(pi / T)^2`` per unit of the pair's effective mass, no
damping, impedance 0.9999), so its answer is its own, compared with its own converged one.
"""

from __future__ import annotations

import math
import time

import numpy as np

__all__ = ["available", "exudyn_chain", "exudyn_slider_crank", "mujoco_chain",
           "exudyn_cradle", "mujoco_cradle"]


def available(name: str) -> bool:
    """Whether the peer package ``name`` ("exudyn" or "mujoco") can be imported."""
    try:
        __import__(name)
    except ImportError:
        return False
    return True


def _exudyn_settings(exu, n_bodies: int, step: float, duration: float):
    settings = exu.SimulationSettings()
    settings.timeIntegration.numberOfSteps = int(round(duration / step))
    settings.timeIntegration.endTime = duration
    settings.timeIntegration.verboseMode = 0
    settings.solution.file.write = False
    settings.show.computationTime = False
    settings.show.statistics = False
    settings.linearSolver.solverType = (exu.LinearSolverType.EigenSparse if n_bodies > 20
                                        else exu.LinearSolverType.EXUdense)
    return settings


def _exudyn_solve(exu, mbs, settings) -> float:
    mbs.Assemble()
    start = time.perf_counter()
    if not mbs.SolveDynamic(settings):
        raise RuntimeError("Exudyn's dynamic solver failed")
    return time.perf_counter() - start


def exudyn_chain(n_links: int, step: float, duration: float = 1.0, spatial: bool = False,
                 spin: float = 0.0) -> tuple[np.ndarray, float]:
    """Tip of the last link after ``duration`` [s] and the wall time [s].

    Planar: bars of 1 m and 1 kg (inertia 1/12 kg m^2) pinned end to end, horizontal along x
    at rest, gravity -y (``mbd3d.mechanisms.pendulum_chain``). Spatial: the same bars joined
    by ball joints (inertia diag(0.01, 1/12, 1/12)), gravity -z, turning as one rigid body at
    ``spin`` [rad/s] about z at t = 0 (``mbd3d.mechanisms.spatial_chain``).
    """
    import exudyn as exu
    from exudyn.utilities import MarkerBodyPosition, ObjectGround, RevoluteJoint2D, RigidBodyInertia

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    inertia = RigidBodyInertia(mass=1.0, inertiaTensor=np.diag([1e-2, 1 / 12, 1 / 12]))
    omega = np.array([0.0, 0.0, spin])
    previous_end = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[0, 0, 0]))
    previous = ground
    for k in range(n_links):
        centre = np.array([k + 0.5, 0.0, 0.0])
        if spatial:
            body = mbs.CreateRigidBody(inertia=inertia, referencePosition=centre,
                                       gravity=[0, 0, -9.81],
                                       initialVelocity=np.cross(omega, centre),
                                       initialAngularVelocity=omega)
            mbs.CreateSphericalJoint(itemNumbers=[previous, body], position=[k, 0, 0])
        else:
            body = mbs.CreateRigidBody(inertia=inertia, referencePosition=centre,
                                       gravity=[0, -9.81, 0], create2D=True)
            start = mbs.AddMarker(MarkerBodyPosition(bodyNumber=body, localPosition=[-0.5, 0, 0]))
            mbs.AddObject(RevoluteJoint2D(markerNumbers=[previous_end, start]))
            previous_end = mbs.AddMarker(MarkerBodyPosition(bodyNumber=body,
                                                            localPosition=[0.5, 0, 0]))
        previous = body
    wall = _exudyn_solve(exu, mbs, _exudyn_settings(exu, n_links, step, duration))
    tip = mbs.GetObjectOutputBody(previous, exu.OutputVariableType.Position,
                                  localPosition=[0.5, 0, 0],
                                  configuration=exu.ConfigurationType.Current)
    return np.asarray(tip)[:3 if spatial else 2], wall


def exudyn_slider_crank(step: float, qd0: np.ndarray, duration: float = 2.0,
                        crank_angle: float = math.radians(65.0)) -> tuple[float, float]:
    """Crank angle [rad] after ``duration`` [s] of the free slider-crank of
    ``mbd3d.mechanisms.slider_crank(crank_speed=None)`` (Nikravesh's data, under gravity),
    started at ``crank_angle`` with the velocities ``qd0`` (mbd3d's coordinate rates: x, y,
    theta of crank, rod, slider), and the wall time [s]."""
    import exudyn as exu
    from exudyn.utilities import (MarkerBodyPosition, MarkerBodyRigid, ObjectGround,
                                  PrismaticJoint2D, RevoluteJoint2D, RigidBodyInertia,
                                  RotationMatrixZ)

    from mbd3d.mechanisms import slider_crank_positions

    L1, L2 = 0.12, 0.26
    a, rod_angle, b_point = slider_crank_positions(crank_angle, L1, L2)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())

    rates = np.reshape(qd0, (3, 3))

    def body(mass, inertia, centre, angle, rate):
        return mbs.CreateRigidBody(
            inertia=RigidBodyInertia(mass=mass, inertiaTensor=np.diag([inertia] * 3)),
            referencePosition=[*centre, 0.0], referenceRotationMatrix=RotationMatrixZ(angle),
            initialVelocity=[rate[0], rate[1], 0.0], initialAngularVelocity=[0, 0, rate[2]],
            gravity=[0, -9.81, 0], create2D=True)

    def marker(item, local):
        return mbs.AddMarker(MarkerBodyPosition(bodyNumber=item, localPosition=[*local, 0.0]))

    crank = body(1.0, 0.001, a / 2, crank_angle, rates[0])
    rod = body(2.0, 0.01, (a + b_point) / 2, rod_angle, rates[1])
    slider = body(4.0, 0.02, b_point, 0.0, rates[2])
    for (i, at_i), (j, at_j) in (((ground, (0, 0)), (crank, (-L1 / 2, 0))),
                                 ((crank, (L1 / 2, 0)), (rod, (-L2 / 2, 0))),
                                 ((rod, (L2 / 2, 0)), (slider, (0, 0)))):
        mbs.AddObject(RevoluteJoint2D(markerNumbers=[marker(i, at_i), marker(j, at_j)]))
    rail = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0]))
    on_rail = mbs.AddMarker(MarkerBodyRigid(bodyNumber=slider, localPosition=[0, 0, 0]))
    mbs.AddObject(PrismaticJoint2D(markerNumbers=[rail, on_rail], axisMarker0=[1, 0, 0],
                                   normalMarker1=[0, 1, 0], constrainRotation=True))
    wall = _exudyn_solve(exu, mbs, _exudyn_settings(exu, 3, step, duration))
    angle = mbs.GetObjectOutputBody(crank, exu.OutputVariableType.Rotation,
                                    configuration=exu.ConfigurationType.Current)
    # the rotation reported is the one since the reference configuration
    return crank_angle + float(np.ravel(angle)[-1]), wall


def _mujoco_chain_xml(n_links: int, spatial: bool) -> str:
    joint = '<joint type="ball"/>' if spatial else '<joint type="hinge" axis="0 0 1"/>'
    gravity = "0 0 -9.81" if spatial else "0 -9.81 0"
    inertial = f'<inertial pos="0.5 0 0" mass="1" diaginertia="0.01 {1 / 12!r} {1 / 12!r}"/>'
    # built inside out: each body nests the rest of the chain
    body = '<site name="tip" pos="1 0 0"/>'
    for k in reversed(range(n_links)):
        body = f'<body pos="{0 if k == 0 else 1} 0 0">{joint}{inertial}{body}</body>'
    return (f'<mujoco><option gravity="{gravity}" integrator="RK4"><flag contact="disable"/>'
            f'</option><worldbody>{body}</worldbody></mujoco>')


def mujoco_chain(n_links: int, step: float, duration: float = 1.0, spatial: bool = False,
                 spin: float = 0.0) -> tuple[np.ndarray, float]:
    """:func:`exudyn_chain`'s model in MuJoCo (relative joint coordinates), RK4 at ``step``."""
    import mujoco

    model = mujoco.MjModel.from_xml_string(_mujoco_chain_xml(n_links, spatial))
    model.opt.timestep = step
    data = mujoco.MjData(model)
    if spatial:
        data.qvel[2] = spin  # the first ball joint's rate about z; the rest turn with it
    steps = int(round(duration / step))
    start = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(model, data)
    # mj_step leaves the site positions of the start of its last step (they are computed
    # before the integration): the tip of the final state needs its kinematics done once
    mujoco.mj_kinematics(model, data)
    wall = time.perf_counter() - start
    return data.site_xpos[0][:3 if spatial else 2].copy(), wall


def exudyn_cradle(cradle: dict, step: float, duration: float) -> tuple[np.ndarray, float]:
    """The balls' centres (n, 2) [m] at ``duration`` [s] of ``cradle``'s Newton's cradle in
    Exudyn at ``step`` [s], and the wall time [s]. ``cradle``: ``n_balls``, ``radius``,
    ``string_length``, ``gap``, ``release`` as for ``mbd3d.mechanisms.newtons_cradle``, and
    its derived ``mass`` [kg] and Hertz ``stiffness`` [N/m^1.5]."""
    import exudyn as exu
    from exudyn.utilities import (MarkerBodyPosition, MarkerBodyRigid, NodeGenericData,
                                  ObjectContactSphereSphere, ObjectGround, RevoluteJoint2D,
                                  RigidBodyInertia, RotationMatrixZ)

    n, r, L, m = cradle["n_balls"], cradle["radius"], cradle["string_length"], cradle["mass"]
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    inertia = RigidBodyInertia(mass=m, inertiaTensor=np.eye(3) * 0.4 * m * r * r)
    balls, centres = [], []
    for k in range(n):
        pivot = np.array([k * (2 * r + cradle["gap"]), L, 0.0])
        angle = -cradle["release"] if k == 0 else 0.0
        centre = pivot + L * np.array([math.sin(angle), -math.cos(angle), 0.0])
        ball = mbs.CreateRigidBody(inertia=inertia, referencePosition=centre,
                                   referenceRotationMatrix=RotationMatrixZ(angle),
                                   gravity=[0, -9.81, 0], create2D=True)
        on_ground = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=pivot))
        # the pin, string_length above the centre along the ball's own (turned) y axis
        on_ball = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ball, localPosition=[0, L, 0]))
        mbs.AddObject(RevoluteJoint2D(markerNumbers=[on_ground, on_ball]))
        balls.append(ball)
        centres.append(mbs.AddMarker(MarkerBodyRigid(bodyNumber=ball)))
    for k in range(n - 1):
        data = mbs.AddNode(NodeGenericData(numberOfDataCoordinates=4, initialCoordinates=[0] * 4))
        mbs.AddObject(ObjectContactSphereSphere(
            markerNumbers=[centres[k], centres[k + 1]], nodeNumber=data, spheresRadii=[r, r],
            contactStiffness=cradle["stiffness"], contactStiffnessExponent=1.5,
            contactDamping=0.0, impactModel=0))
    settings = _exudyn_settings(exu, n, step, duration)
    settings.timeIntegration.minimumStepSize = 1e-12
    wall = _exudyn_solve(exu, mbs, settings)
    return np.array([mbs.GetObjectOutputBody(b, exu.OutputVariableType.Position,
                                             configuration=exu.ConfigurationType.Current)[:2]
                     for b in balls]), wall


def _mujoco_cradle_xml(cradle: dict, stiffness: float, integrator: str) -> str:
    n, r, L, m = cradle["n_balls"], cradle["radius"], cradle["string_length"], cradle["mass"]
    inertia = 0.4 * m * r * r
    bodies = "".join(
        f'<body pos="{k * (2 * r + cradle["gap"])!r} {L!r} 0">'
        f'<joint type="hinge" axis="0 0 1"/>'
        f'<inertial pos="0 {-L!r} 0" mass="{m!r}" diaginertia="{inertia!r} {inertia!r} '
        f'{inertia!r}"/>'
        f'<geom type="sphere" size="{r!r}" pos="0 {-L!r} 0" condim="1" '
        f'solref="{-stiffness!r} 0" solimp="0.9999 0.9999 0.001"/>'
        f'<site pos="0 {-L!r} 0"/></body>' for k in range(n))
    return (f'<mujoco><option gravity="0 -9.81 0" integrator="{integrator}"/>'
            f'<worldbody>{bodies}</worldbody></mujoco>')


def mujoco_cradle(cradle: dict, step: float, duration: float, impact_duration: float,
                  integrator: str = "RK4") -> tuple[np.ndarray, float]:
    """:func:`exudyn_cradle`'s cradle in MuJoCo, its contacts linear springs that part two
    balls after ``impact_duration`` [s] (see the module docstring), by ``integrator`` at
    ``step``: the balls' centres (n, 2) [m] and the wall time [s]."""
    import mujoco

    stiffness = (math.pi / impact_duration) ** 2
    model = mujoco.MjModel.from_xml_string(_mujoco_cradle_xml(cradle, stiffness, integrator))
    model.opt.timestep = step
    data = mujoco.MjData(model)
    data.qpos[0] = -cradle["release"]
    steps = int(round(duration / step))
    start = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(model, data)
    mujoco.mj_kinematics(model, data)  # the sites of the final state (see mujoco_chain)
    wall = time.perf_counter() - start
    return data.site_xpos[:, :2].copy(), wall
