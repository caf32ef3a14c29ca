"""Inverse dynamics along a 1000-point joint trajectory of real robots (the UR5, the Panda and
Solo12 of the example-robot-data collection): mbd3d's inverse dynamics against a loop of
Pinocchio's recursive Newton-Euler algorithm (RNEA) over the same joint positions, rates and
accelerations, timed in turn in one process; the efforts agree to 1e-10 of their size
(checked here).

Needs the test extra (``pip install -e ".[test]"``: ``pin``, ``example-robot-data``).

Run: python benchmarks/robots.py [--repeat N] [--points N]
"""

from __future__ import annotations

import argparse
import importlib.metadata
import pathlib
import warnings

import numpy as np

import mbd3d as mb
from measure import machine, median_time

#: the robots of issue #34, as Pinocchio builds them from the URDF (a fixed base: Solo12's
#: trunk welded to the ground, its four legs moving)
ROBOTS = {"UR5": "ur_description/urdf/ur5_robot.urdf",
          "Panda": "panda_description/urdf/panda.urdf",
          "Solo12": "solo_description/robots/solo12.urdf"}


def _path(relative: str) -> pathlib.Path:
    share = importlib.metadata.distribution("example-robot-data").locate_file(
        "cmeel.prefix/share/example-robot-data/robots")
    return pathlib.Path(str(share)) / relative


def _setup(relative: str, points: int):
    """mbd3d's model driven along harmonic joint motions, Pinocchio's model, the times and
    the joint states (q, v, a) (k, nv) in Pinocchio's order, and the driven joints."""
    import pinocchio as pin  # noqa: PLC0415 - a test extra
    path = _path(relative)
    reference = pin.buildModelFromUrdf(str(path))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mb.UrdfWarning)
        probe = mb.load_urdf(path, meshes="skip", joint_limits="ignore")
        names = {e.name for e in probe.joints}
        driven = [j for j in reference.names[1:] if j in names]
        rng = np.random.default_rng(len(driven))
        motions = {j: mb.Harmonic(rng.uniform(0.2, 0.6), rng.uniform(0.5, 1.5),
                                  phase=rng.uniform(0.0, 6.0), offset=rng.uniform(-0.5, 0.5))
                   for j in driven}
        model = mb.load_urdf(path, meshes="skip", joint_limits="ignore", drive=motions)
    times = np.linspace(0.0, 2.0, points)
    q = np.tile(pin.neutral(reference), (points, 1))
    v, a = np.zeros((points, reference.nv)), np.zeros((points, reference.nv))
    for j, motion in motions.items():
        joint = reference.joints[reference.getJointId(j)]
        assert joint.nq == 1, "revolute and prismatic joints only"
        for k, t in enumerate(times):
            q[k, joint.idx_q], v[k, joint.idx_v], a[k, joint.idx_v] = motion.evaluate(t)[:3]
    return model, reference, times, (q, v, a), driven


def main(repeat: int = 5, points: int = 1000) -> list[dict]:
    import pinocchio as pin  # noqa: PLC0415
    print(machine(), f"Pinocchio {pin.__version__}")
    rows = []
    for label, relative in ROBOTS.items():
        model, reference, times, (q, v, a), driven = _setup(relative, points)
        data = reference.createData()

        def rnea():
            return [pin.rnea(reference, data, q[k], v[k], a[k]) for k in range(points)]

        def ours():
            return mb.inverse_dynamics(model, times)
        res = ours()  # compiles
        tau = np.array(rnea())
        efforts = np.array([res.driver(f"{j}_drive").effort for j in driven]).T
        columns = [reference.joints[reference.getJointId(j)].idx_v for j in driven]
        error = np.max(np.abs(efforts - tau[:, columns])) / max(1.0, np.max(np.abs(tau)))
        assert error < 1e-10, f"{label}: the efforts differ from Pinocchio's by {error:.1e}"
        # timed in turn, so that both see the same machine
        mine, theirs = [], []
        for _ in range(repeat):
            mine.append(median_time(ours, 1))
            theirs.append(median_time(rnea, 1))
        rows.append({"robot": label, "coordinates": model.n_coordinates, "points": points,
                     "mbd3d": float(np.median(mine)) / points,
                     "pinocchio": float(np.median(theirs)) / points, "error": error})
    print(mb.format_table({
        "robot": [r["robot"] for r in rows],
        "coordinates": [r["coordinates"] for r in rows],
        "mbd3d [us/point]": [r["mbd3d"] * 1e6 for r in rows],
        "Pinocchio RNEA [us/point]": [r["pinocchio"] * 1e6 for r in rows],
        "ratio": [r["mbd3d"] / r["pinocchio"] for r in rows],
        "largest difference": [r["error"] for r in rows],
    }, precision=4))
    print("issue #34's target: at most 20 times Pinocchio's RNEA loop")
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--points", type=int, default=1000)
    arguments = parser.parse_args()
    main(repeat=arguments.repeat, points=arguments.points)
