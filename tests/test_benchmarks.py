"""Smoke test: the benchmark scripts run at their smallest size (no timing is asserted)."""

from __future__ import annotations

import importlib.util
import pathlib

BENCHMARKS = pathlib.Path(__file__).resolve().parent.parent / "benchmarks"


import pytest


@pytest.mark.parametrize("name", ["planar_chain", "spatial_chain"])
def test_chain_benchmark_runs(name, capsys, monkeypatch):
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    spec = importlib.util.spec_from_file_location(name, BENCHMARKS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    rows = module.main(sizes=(2,), simulate=True)
    assert rows[0]["N"] == 2 and rows[0]["steps"] > 0
    assert "augmented solve" in capsys.readouterr().out


def test_viewer_logging_benchmark_runs(capsys, monkeypatch):
    spec = importlib.util.spec_from_file_location("viewer_logging",
                                                  BENCHMARKS / "viewer_logging.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    rows = module.main(points=50, links=2, repeat=1)
    assert [r["model"] for r in rows] == ["planar", "spatial"]
    assert all(r["slowdown"] > 0 and r["file_mb"] > 0 for r in rows)
    assert "slow-down" in capsys.readouterr().out
