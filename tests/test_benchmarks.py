"""Smoke test: the benchmark scripts run at their smallest size (no timing is asserted)."""

from __future__ import annotations

import importlib.metadata
import importlib.util
import pathlib
import sys

BENCHMARKS = pathlib.Path(__file__).resolve().parent.parent / "benchmarks"


import pytest


def _load(name):
    spec = importlib.util.spec_from_file_location(name, BENCHMARKS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("name", ["planar_chain", "spatial_chain"])
def test_chain_benchmark_runs(name, capsys, monkeypatch):
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    spec = importlib.util.spec_from_file_location(name, BENCHMARKS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    rows = module.main(sizes=(1, 2), simulate=True)
    assert [r["N"] for r in rows] == [1, 2] and rows[0]["steps"] > 0
    assert "augmented solve" in capsys.readouterr().out


@pytest.mark.parametrize("name", ["planar_chain", "spatial_chain"])
def test_chain_comparison_runs_without_peers(name, capsys, monkeypatch):
    """The comparison at its smallest: the two mbd3d integrators, peers hidden."""
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    module = _load(name)
    monkeypatch.setattr(sys.modules["peers"], "available", lambda name: False)
    rows = module.main(sizes=(1,), simulate=False, compare=True, peer_links=1)
    out = capsys.readouterr().out
    assert "no peers installed" in out and "mbd3d DOP853" in out
    assert rows[0]["N"] == 1


def test_slider_crank_study_runs(capsys, monkeypatch):
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    module = _load("slider_crank")
    monkeypatch.setattr(module, "DURATION", 0.05)
    rows = module.main(quick=True, repeat=1)
    assert {r["method"] for r in rows} == set(module.STUDY)
    assert all(r["error"] < 1e-2 for r in rows)  # every integrator near the reference
    assert "angle error" in capsys.readouterr().out


def test_viewer_logging_benchmark_runs(capsys, monkeypatch):
    spec = importlib.util.spec_from_file_location("viewer_logging",
                                                  BENCHMARKS / "viewer_logging.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    rows = module.main(points=50, links=2, repeat=1)
    assert [r["model"] for r in rows] == ["planar", "spatial"]
    assert all(r["slowdown"] > 0 and r["file_mb"] > 0 for r in rows)
    assert "slow-down" in capsys.readouterr().out


def test_sweep_speedup_benchmark_runs(capsys, monkeypatch):
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    medians = _load("sweep_speedup").main(points=2, repeat=1, n_points=11)
    assert set(medians) == {"serial", "1 worker", "2 workers"}
    assert "speed-up 2 workers / 1 worker" in capsys.readouterr().out


def test_free_body_benchmark_runs_without_peers(capsys, monkeypatch):
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    module = _load("free_body")
    monkeypatch.setattr(module, "available", lambda name: False)
    rows = module.main(tolerance=1e-6, duration=1.0)
    assert [r["engine"] for r in rows] == ["mbd3d DOP853"] and rows[0]["error"] <= 1e-6
    assert "right-hand sides" in capsys.readouterr().out


def test_friction_benchmark_runs(capsys, monkeypatch):
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    rows = _load("friction").main(repeat=1, duration=0.02)
    assert len(rows) == 4 and all(r["count"] > 0 for r in rows)
    assert "friction costs" in capsys.readouterr().out


def test_contacts_benchmark_runs(capsys, monkeypatch):
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    rows = _load("contacts").main(repeat=1, duration=0.002)
    assert len(rows) == 4 and all(r["count"] > 0 for r in rows)
    assert "the contact costs" in capsys.readouterr().out



def test_kinematics_benchmark_runs(capsys, monkeypatch):
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    rows = _load("kinematics").main(repeat=1, links=(2,), points=5)
    assert [r["n"] for r in rows] == [36, 6]
    assert all(r["dense"] > 0 and r["compiled"] > 0 for r in rows)
    out = capsys.readouterr().out
    assert "factors densely up to" in out and "forward_accelerations" in out


def _robots(monkeypatch):
    """benchmarks/robots.py, or a skip where Pinocchio or the robots are not installed."""
    pytest.importorskip("pinocchio")
    try:
        importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("example-robot-data is not installed")
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    return _load("robots")


def test_robots_benchmark_runs(capsys, monkeypatch):
    """Inverse dynamics of the UR5, the Panda and Solo12 against Pinocchio's RNEA at their smallest
    (the script itself checks that the efforts agree)."""
    rows = _robots(monkeypatch).main(repeat=1, points=5)
    assert [r["robot"] for r in rows] == ["UR5", "Panda", "Solo12"]
    assert all(r["error"] < 1e-10 and r["mbd3d"] > 0 for r in rows)
    assert "Pinocchio's RNEA loop" in capsys.readouterr().out


def test_robot_fall_benchmark_runs(capsys, monkeypatch):
    """The UR5 falling for a tenth of a second against Pinocchio's ABA under SciPy's DOP853
    (the script checks that the final joint angles agree with a tight run of the latter)."""
    row = _robots(monkeypatch).fall(repeat=1, duration=0.1)
    assert row["mbd3d error [rad]"] < 1e-6 and row["their error [rad]"] < 1e-6
    assert row["mbd3d [s]"] > 0 and "Pinocchio ABA + SciPy" in capsys.readouterr().out


def test_cradle_benchmark_runs_without_peers(capsys, monkeypatch):
    """The contact scenario at its smallest (three balls, peers hidden); the impact duration
    it gives MuJoCo against Hertz's closed form ``2.94 delta_max / v``."""
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    module = _load("cradle")
    monkeypatch.setattr(sys.modules["peers"], "available", lambda name: False)
    monkeypatch.setattr(module, "CRADLE", dict(module.CRADLE, n_balls=3))
    monkeypatch.setattr(module, "DURATION", 0.2)
    rows = module.compare(210e9, repeat=1)
    assert [r["engine"] for r in rows] == ["mbd3d DOP853", "mbd3d RK45",
                                           "mbd3d generalized-alpha"]
    assert all(r["error"] <= module.TOLERANCE for r in rows)
    assert "no peers installed" in capsys.readouterr().out
    m, K, v = 0.05, 1e10, 0.7
    delta_max = (5 * m * v * v / (4 * K)) ** 0.4
    assert module.hertz_impact_duration(m, K, v) == pytest.approx(2.9432 * delta_max / v,
                                                                  rel=1e-3)


@pytest.mark.compiled_only  # two piles, hundreds of steps
def test_spheres_in_box_benchmark_runs(capsys, monkeypatch):
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    module = _load("spheres_in_box")
    monkeypatch.setattr(module, "DURATION", 2e-4)
    rows = module.measure([9, 16], repeat=1, dim=2)
    assert [r["n"] for r in rows] == [9, 16] and all(r["near"] > r["n"] for r in rows)
    assert "cost per step ~ N^" in capsys.readouterr().out



def test_sensitivities_benchmark_runs(capsys, monkeypatch):
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    module = _load("sensitivities")
    rows = module.main(points=5, links=2, counts=(1,), repeat=1)
    assert [r["p"] for r in rows] == [1, 1] and all(r["sensitivities [s]"] > 0 for r in rows)
    rows = module.forward(counts=(1,), repeat=1, links=2, duration=0.02)
    assert [r["p"] for r in rows] == [1, 1] and all(r["ratio"] > 0 for r in rows)
    assert "per parameter" in capsys.readouterr().out
