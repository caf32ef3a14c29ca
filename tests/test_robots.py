"""Every robot of the example-robot-data collection that Pinocchio loads, loaded by mbd3d and
driven along random joint motions: its joint torques against Pinocchio's recursive
Newton-Euler algorithm (RNEA), an implementation written apart from ours in joint
coordinates. Two robots whose published inertias no real body has are refused, naming the
link."""

from __future__ import annotations

import importlib.metadata
import pathlib

import numpy as np
import pytest

import mbd3d as mb

pin = pytest.importorskip("pinocchio")


def _robots() -> list[pathlib.Path]:
    try:
        share = importlib.metadata.distribution("example-robot-data").locate_file(
            "cmeel.prefix/share/example-robot-data/robots")
    except importlib.metadata.PackageNotFoundError:
        return []
    return sorted(pathlib.Path(str(share)).glob("*/urdf/*.urdf"))


ROBOTS = _robots()
#: published inertias no real body has (beyond rounding): refused, naming the link
REFUSED = {"romeo_small": "RShoulderYawLink", "romeo_laas_small": "RHipPitch_link"}


@pytest.mark.skipif(not ROBOTS, reason="example-robot-data is not installed")
def test_the_collection_is_there():
    assert len(ROBOTS) >= 40


@pytest.mark.filterwarnings("ignore::mbd3d.io.urdf.UrdfWarning")
@pytest.mark.parametrize("path", ROBOTS, ids=[p.stem for p in ROBOTS])
def test_joint_torques_match_pinocchios_rnea(path):
    try:
        reference = pin.buildModelFromUrdf(str(path))
    except Exception:  # noqa: BLE001
        pytest.skip("Pinocchio does not load it either")
    if path.stem in REFUSED:
        with pytest.raises(mb.ModelError, match=f"{path.name}.*link '{REFUSED[path.stem]}'"
                                                ".*no real body has them"):
            mb.load_urdf(path, meshes="skip")
        return
    probe = mb.load_urdf(path, meshes="skip", joint_limits="ignore")
    names = {e.name for e in probe.joints}
    # every joint that moves mass (Pinocchio keeps those that move none: zero torque)
    driven = {j: j if j in names else f"{j}_joint" for j in reference.names[1:]
              if j in names or f"{j}_joint" in names}
    assert len(driven) >= 2
    rng = np.random.default_rng(len(driven))
    motions = {j: mb.Harmonic(rng.uniform(0.1, 0.4), rng.uniform(0.2, 0.6),
                              phase=rng.uniform(0.0, 6.0), offset=rng.uniform(-0.3, 0.3))
               for j in driven}
    model = mb.load_urdf(path, meshes="skip", joint_limits="ignore", drive=motions)
    times = np.array([0.3, 1.1])
    res = mb.inverse_dynamics(model, times)
    data = reference.createData()
    for k, t in enumerate(times):
        q, v, a = pin.neutral(reference), np.zeros(reference.nv), np.zeros(reference.nv)
        for j, motion in motions.items():
            joint = reference.joints[reference.getJointId(j)]
            x, xd, xdd = motion.evaluate(t)[:3]
            # a continuous joint's configuration is (cos, sin) of its angle
            q[joint.idx_q:joint.idx_q + joint.nq] = (np.cos(x), np.sin(x))[:joint.nq] \
                if joint.nq == 2 else x
            v[joint.idx_v], a[joint.idx_v] = xd, xdd
        tau = pin.rnea(reference, data, q, v, a)
        ours = np.array([res.driver(f"{driven[j]}_drive").effort[k] for j in driven])
        theirs = np.array([tau[reference.joints[reference.getJointId(j)].idx_v]
                           for j in driven])
        np.testing.assert_allclose(ours, theirs, rtol=0,
                                   atol=1e-10 * max(1.0, float(np.max(np.abs(theirs)))))
