"""Inverse dynamics along a 1000-point joint trajectory of real robots (the UR5, the Panda and
Solo12 of the example-robot-data collection): mbd3d's inverse dynamics against a loop of
Pinocchio's recursive Newton-Euler algorithm (RNEA) over the same joint positions, rates and
accelerations, timed in turn in one process; the efforts agree to 1e-10 of their size
(checked here).

With ``--fall``: the UR5 falling freely for a second from a random pose, mbd3d's forward
dynamics (DOP853) against SciPy's DOP853 on Pinocchio's articulated-body algorithm (ABA) in
joint coordinates, both at the same rtol and atol, timed in turn; each one's final joint
angles against a reference run of the latter at rtol 1e-13 (mbd3d's within 1000 rtol of it:
checked here).

Needs the test extra (``pip install -e ".[test]"``: ``pin``, ``example-robot-data``).

Run: python benchmarks/robots.py [--repeat N] [--points N] [--fall]
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


def fall(repeat: int = 5, duration: float = 1.0, rtol: float = 1e-8, atol: float = 1e-10
         ) -> dict:
    """The UR5's free fall (see the module doc): wall times [s], their ratio and the final
    joint angles' largest errors [rad] of both against the tight reference."""
    import pinocchio as pin  # noqa: PLC0415
    from scipy.integrate import solve_ivp  # noqa: PLC0415

    path = _path(ROBOTS["UR5"])
    reference = pin.buildModelFromUrdf(str(path))
    data = reference.createData()
    nq, nv = reference.nq, reference.nv
    assert nq == nv, "revolute joints only"
    names = list(reference.names[1:])
    q0 = np.random.default_rng(5).uniform(-1.0, 1.0, nq)
    with warnings.catch_warnings():  # drawn in the starting pose, in the file's coordinates
        warnings.simplefilter("ignore", mb.UrdfWarning)
        model = mb.load_urdf(path, meshes="skip", joint_limits="ignore",
                             joint_positions=dict(zip(names, q0)))
    y0, no_torque = np.concatenate([q0, np.zeros(nv)]), np.zeros(nv)

    def rates(_t, y):
        return np.concatenate([y[nq:], pin.aba(reference, data, y[:nq], y[nq:], no_torque)])

    def theirs(tol=rtol, tol_abs=atol):
        return solve_ivp(rates, (0.0, duration), y0, method="DOP853", rtol=tol, atol=tol_abs)

    def ours():
        return mb.forward_dynamics(model, [0.0, duration], method="DOP853", rtol=rtol,
                                   atol=atol)
    exact = theirs(1e-13, 1e-13).y[:nq, -1]
    res, sol = ours(), theirs()  # ours compiles
    # the hinges read the file's joint coordinates (their drawn angles are q0)
    final = [res.joint(j).angle[-1] for j in names]
    error_ours = np.max(np.abs(np.array(final) - exact))
    error_theirs = np.max(np.abs(sol.y[:nq, -1] - exact))
    assert error_ours < 1e3 * rtol, f"the UR5's fall differs from Pinocchio's by {error_ours:.1e}"
    mine, others = [], []
    for _ in range(repeat):  # in turn
        mine.append(median_time(ours, 1))
        others.append(median_time(theirs, 1))
    row = {"mbd3d [s]": float(np.median(mine)), "Pinocchio ABA + SciPy [s]":
           float(np.median(others)), "ratio": float(np.median(mine) / np.median(others)),
           "mbd3d error [rad]": error_ours, "their error [rad]": error_theirs,
           "mbd3d steps": res.stats["steps"], "their steps": sol.t.size - 1}
    print(machine(), f"Pinocchio {pin.__version__}")
    print(f"UR5 falling for {duration} s from a random pose, DOP853 at rtol {rtol:g}, atol "
          f"{atol:g} (medians of {repeat}, in turn)\n")
    print(mb.format_table({key: [value] for key, value in row.items()}, precision=4))
    print("issue #34's target: at most 1 x Pinocchio ABA + SciPy")
    return row


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--points", type=int, default=1000)
    parser.add_argument("--fall", action="store_true", help="the UR5's free fall instead")
    arguments = parser.parse_args()
    if arguments.fall:
        fall(repeat=arguments.repeat)
    else:
        main(repeat=arguments.repeat, points=arguments.points)
