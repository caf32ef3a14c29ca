"""A free body tumbling through the intermediate-axis flip, at equal accuracy in every engine.

Principal inertias (1, 2, 3) kg m^2, angular velocity (0.01, 3, 0) rad/s in body axes at
t = 0, no gravity: the body spins about its intermediate axis and flips over and back several
times in 20 s (mbd3d re-references its Rodrigues parameters about 40 times). The quantity is
the orientation at t = 20 s, to 1e-8 rad of a reference that shares no code with any engine:
Euler's equations with a unit quaternion, integrated by SciPy's DOP853 at rtol 1e-13.

For each engine the cheapest setting tried that reaches the tolerance (mbd3d's rtol, the
peers' step, halved from a coarse one), then the medians of 3 rounds that run the engines in
turn (see measure.interleaved_medians):

- mbd3d: DOP853 on the absolute coordinates (position, Rodrigues parameters);
- Exudyn: its explicit RK4 with Lie-group integration of a rotation-vector node (its best
  setting for a free rigid body);
- MuJoCo: RK4 on a free joint.

Run: python benchmarks/free_body.py [--tolerance 1e-8] [--duration 20]
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from measure import cheapest, interleaved_medians, machine  # noqa: E402
from peers import available  # noqa: E402

import mbd3d as mb  # noqa: E402

INERTIA = np.array([1.0, 2.0, 3.0])  # principal moments [kg m^2]
OMEGA0 = np.array([0.01, 3.0, 0.0])  # body axes [rad/s]


def reference(duration: float) -> np.ndarray:
    """Orientation (3 x 3) at ``duration`` from Euler's equations and a unit quaternion."""
    def rhs(_, y):
        w, (qw, *qv) = y[4:], y[:4]
        qv = np.array(qv)
        q_dot = 0.5 * np.concatenate([[-qv @ w], qw * w + np.cross(qv, w)])
        return np.concatenate([q_dot, -np.cross(w, INERTIA * w) / INERTIA])
    sol = solve_ivp(rhs, (0.0, duration), np.concatenate([[1.0, 0.0, 0.0, 0.0], OMEGA0]),
                    method="DOP853", rtol=1e-13, atol=1e-14)
    q = sol.y[:4, -1]
    return Rotation.from_quat(np.concatenate([q[1:], q[:1]]) / np.linalg.norm(q)).as_matrix()


def mbd3d_run(rtol: float, duration: float):
    b = mb.ModelBuilder(dim=3, name="free body")
    b.add_body("body", mass=1.0, inertia=INERTIA, position=(0.0, 0.0, 0.0),
               angular_velocity=OMEGA0)
    model = b.build()

    def run():
        start = time.perf_counter()
        res = mb.forward_dynamics(model, [0.0, duration], method="DOP853", rtol=rtol,
                                  progress=False)
        wall = time.perf_counter() - start
        return res.body("body").rotation[-1], wall, res.stats
    return run


def exudyn_run(step: float, duration: float):
    import exudyn as exu
    from exudyn.utilities import RigidBodyInertia

    def run():
        system = exu.SystemContainer()
        mbs = system.AddSystem()
        body = mbs.CreateRigidBody(inertia=RigidBodyInertia(mass=1.0,
                                                            inertiaTensor=np.diag(INERTIA)),
                                   referencePosition=[0, 0, 0], initialAngularVelocity=OMEGA0,
                                   nodeType=exu.NodeType.RotationRotationVector,
                                   gravity=[0, 0, 0])
        mbs.Assemble()
        settings = exu.SimulationSettings()
        settings.timeIntegration.numberOfSteps = int(round(duration / step))
        settings.timeIntegration.endTime = duration
        settings.timeIntegration.verboseMode = 0
        settings.timeIntegration.explicit.useLieGroupIntegration = True
        settings.solution.file.write = False
        settings.show.computationTime = settings.show.statistics = False
        start = time.perf_counter()
        mbs.SolveDynamic(settings, solverType=exu.DynamicSolverType.RK44)
        wall = time.perf_counter() - start
        A = mbs.GetObjectOutputBody(body, exu.OutputVariableType.RotationMatrix,
                                    configuration=exu.ConfigurationType.Current)
        return np.reshape(A, (3, 3)), wall, {}
    return run


def mujoco_run(step: float, duration: float):
    import mujoco

    xml = ('<mujoco><option gravity="0 0 0" integrator="RK4"><flag contact="disable"/></option>'
           '<worldbody><body><freejoint/><inertial pos="0 0 0" mass="1" diaginertia="'
           + " ".join(f"{float(v)!r}" for v in INERTIA) + '"/></body></worldbody></mujoco>')
    model = mujoco.MjModel.from_xml_string(xml)
    model.opt.timestep = step

    def run():
        data = mujoco.MjData(model)
        data.qvel[3:6] = OMEGA0  # a free joint's angular velocity is in body axes
        start = time.perf_counter()
        for _ in range(int(round(duration / step))):
            mujoco.mj_step(model, data)
        mujoco.mj_kinematics(model, data)  # the orientation of the final state
        wall = time.perf_counter() - start
        w, x, y, z = data.xquat[1]
        return Rotation.from_quat([x, y, z, w]).as_matrix(), wall, {}
    return run


def main(tolerance: float = 1e-8, duration: float = 20.0) -> list[dict]:
    A_ref = reference(duration)

    def error(answer) -> float:
        return float(Rotation.from_matrix(A_ref.T @ answer).magnitude())

    engines = [("mbd3d DOP853", mbd3d_run, [1e-6 / 2**k for k in range(30)], "rtol")]
    if available("exudyn"):
        engines.append(("Exudyn RK4 Lie group", exudyn_run, [1e-2 / 2**k for k in range(14)], "h"))
    if available("mujoco"):
        engines.append(("MuJoCo RK4", mujoco_run, [1e-2 / 2**k for k in range(14)], "h"))
    found = []
    for name, make, values, label in engines:
        runs = [(f"{label} {v:.3g}", make(v, duration)) for v in values]
        hit = cheapest([(lab, lambda run=run: run()[:2]) for lab, run in runs], error,
                       tolerance)
        if hit is None:
            print(f"{name}: no setting tried reaches {tolerance:g} rad")
            continue
        setting, err, run = hit
        found.append({"engine": name, "setting": setting, "error": err, "run": run})
    walls = interleaved_medians([row["run"] for row in found])
    for row, wall in zip(found, walls):
        row["wall"] = wall
    best = found[0]["wall"]
    print(f"free body through the intermediate-axis flip, {duration:g} s, orientation to "
          f"{tolerance:g} rad; {machine()}")
    print(mb.format_table({
        "engine": [r["engine"] for r in found], "cheapest setting": [r["setting"] for r in found],
        "rotation error [rad]": [r["error"] for r in found],
        "wall [s]": [r["wall"] for r in found],
        "mbd3d / this": [best / r["wall"] for r in found]}, precision=3))
    stats = mbd3d_run(float(found[0]["setting"].split()[-1]), duration)()[2]
    print(f"mbd3d: {stats['steps']} steps, {stats['rhs_evaluations']} right-hand sides, "
          f"{stats['chart_resets']} chart resets, "
          f"{1e6 * best / stats['rhs_evaluations']:.0f} us per right-hand side in all")
    targets = {"Exudyn RK4 Lie group": 1.0, "MuJoCo RK4": 0.5}
    for row in found[1:]:
        ratio, target = best / row["wall"], targets[row["engine"]]
        print(f"mbd3d / {row['engine']}: {ratio:.3g} (target <= {target}: "
              f"{'met' if ratio <= target else 'missed'})")
    return found


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tolerance", type=float, default=1e-8, help="rotation error [rad]")
    parser.add_argument("--duration", type=float, default=20.0, help="simulated time [s]")
    args = parser.parse_args()
    main(args.tolerance, args.duration)
