"""Results written to an NPZ file and read back: every array and statistic the same, so that
what is derived from them (positions, reactions, contact forces) is too; a file read against
another model, a file that is not one, and hostile files refused by name, within bounds."""

from __future__ import annotations

import io
import math
import zipfile

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.mechanisms import slider_crank

G = 9.81


def _ball_to_rest() -> mb.Model:
    """A spatial ball bouncing to rest on a rigid floor: charts, rests and held forces."""
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G), name="ball")
    ball = b.add_body("ball", mass=0.5, inertia=np.eye(3) * 2e-3, position=(0.0, 0.0, 0.6),
                      angular_velocity=(0.0, 3.0, 1.0))
    b.add(mb.Contact("floor", mb.Sphere(ball, 0.1), mb.Plane(b.ground, normal=(0, 0, 1)),
                     law=mb.RigidImpact(restitution=0.5, rest_speed=0.05)))
    return b.build()


def test_a_run_reads_back_as_it_was_written(tmp_path):
    model = _ball_to_rest()
    res = mb.forward_dynamics(model, np.linspace(0.0, 2.0, 41), method="DOP853")
    assert res.stats["rests"] and res.contact_forces is not None and res.charts is not None
    path = res.to_npz(tmp_path / "ball.npz")
    again = mb.read_results(path, model)
    for name in ("t", "q", "qd", "qdd", "lam", "charts", "turns", "contact_forces",
                 "contact_dissipation"):
        np.testing.assert_array_equal(getattr(again, name), getattr(res, name), err_msg=name)
    assert (again.analysis, again.status, again.message) == (res.analysis, res.status,
                                                            res.message)
    assert again.stats["rests"] == res.stats["rests"]
    assert again.stats["impacts"] == res.stats["impacts"]
    np.testing.assert_array_equal(again.body("ball").position, res.body("ball").position)
    np.testing.assert_array_equal(again.contacts().normal_force, res.contacts().normal_force)
    # a planar inverse dynamics, its reactions from the multipliers, against a new build
    inverse = mb.inverse_dynamics(slider_crank(crank_speed=2 * math.pi),
                                  np.linspace(0.0, 0.5, 6))
    buffer = io.BytesIO()
    inverse.to_npz(buffer)
    (tmp_path / "inverse.npz").write_bytes(buffer.getvalue())
    again = mb.read_results(tmp_path / "inverse.npz", slider_crank(crank_speed=2 * math.pi))
    np.testing.assert_array_equal(again.joint("O").reaction(on="crank").force,
                                  inverse.joint("O").reaction(on="crank").force)
    for name, effort in inverse.efforts.items():
        np.testing.assert_array_equal(again.efforts[name], effort)


def test_a_run_cut_short_reads_back_with_its_status(tmp_path):
    model = _ball_to_rest()
    res = mb.forward_dynamics(model, np.linspace(0.0, 1.0, 11), method="DOP853",
                              events=[mb.Event("low", lambda t, q, qd: q[2] - 0.3,
                                               action="stop")])
    assert res.status == "stopped"
    again = mb.read_results(res.to_npz(tmp_path / "cut.npz"), model)
    assert again.status == "stopped" and len(again) == len(res)


def test_a_file_is_read_only_against_the_model_it_is_of(tmp_path):
    model = _ball_to_rest()
    path = mb.forward_dynamics(model, [0.0, 0.1]).to_npz(tmp_path / "ball.npz")
    other = slider_crank(crank_speed=1.0)
    with pytest.raises(mb.MBDError, match=r"ball\.npz'.*coordinates are not those of model "
                       r"'.*': number 0 is 'ball\.x' in the file, 'crank\.x' in the model"):
        mb.read_results(path, other)


def _npz(**arrays) -> bytes:
    buffer = io.BytesIO()
    np.savez_compressed(buffer, **arrays)
    return buffer.getvalue()


def test_files_that_are_not_results_are_refused_by_name(tmp_path):
    model = _ball_to_rest()
    good = dict(np.load(mb.forward_dynamics(model, [0.0, 0.1]).to_npz(tmp_path / "ok.npz")))
    cases = {
        "text": (b"not a zip", "cannot be read as results"),
        "missing": (_npz(**{k: v for k, v in good.items() if k != "qd"}), "no 'qd' array"),
        "unknown": (_npz(**good, extra=np.zeros(2)), r"unknown arrays \['extra'\]"),
        "pickled": (_npz(**{**good, "lam": np.array([{"a": 1}], dtype=object)}),
                    "cannot be read as results"),
        "shape": (_npz(**{**good, "qd": good["qd"][:, :3]}), r"'qd' has the shape \(2, 3\)"),
        "times": (_npz(**{**good, "t": np.array([0.0, np.nan])}), "not a finite series"),
        # a bomb: 80 MB of zeros compressed to some 80 kB, for two time points
        "bomb": (_npz(**{**good, "q": np.zeros((10 ** 7,))}), "would expand to 80000128 bytes"),
    }
    # a header that declares 8 TB for q in a member of a few hundred bytes
    member = io.BytesIO()
    np.lib.format.write_array_header_1_0(member, {"descr": "<f8", "fortran_order": False,
                                                  "shape": (10 ** 6, 10 ** 6)})
    liar = io.BytesIO()
    with zipfile.ZipFile(liar, "w") as archive:
        for key, value in good.items():
            if key != "q":
                with archive.open(f"{key}.npy", "w") as f:
                    np.lib.format.write_array(f, value)
        archive.writestr("q.npy", member.getvalue() + bytes(64))
    cases["header"] = (liar.getvalue(), r"'q' declares 8000000000000 bytes in")
    for name, (content, words) in cases.items():
        path = tmp_path / f"{name}.npz"
        path.write_bytes(content)
        with pytest.raises(mb.MBDError, match=words) as info:
            mb.read_results(path, model)
        assert f"{name}.npz" in str(info.value), name
    with pytest.raises(mb.MBDError, match="cannot be read as results"):
        mb.read_results(tmp_path / "absent.npz", model)
    assert zipfile.is_zipfile(tmp_path / "bomb.npz")
