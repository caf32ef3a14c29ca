"""Every example runs (with small sizes) and its printed results are right."""

from __future__ import annotations

import importlib.util
import math
import pathlib

import numpy as np
import pytest

EXAMPLES = pathlib.Path(__file__).resolve().parent.parent / "examples"


def load(name: str):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_slider_crank_example(capsys, tmp_path):
    results = load("slider_crank").main(n_points=5, duration=0.5, csv_folder=str(tmp_path))
    out = capsys.readouterr().out
    assert "Kinematic analysis" in out and "Force analysis" in out and "Forward dynamics" in out
    assert (tmp_path / "slider_crank_forward.csv").exists()
    dyn = results["forward"]
    energy = dyn.kinetic_energy + dyn.potential_energy
    work = 2.0 * (dyn.body("crank").angle - dyn.body("crank").angle[0])
    np.testing.assert_allclose(work, energy - energy[0], atol=1e-8)


def test_four_bar_example(capsys):
    res = load("four_bar").main(n_points=7)
    assert "rocker swing" in capsys.readouterr().out
    assert np.all(np.isfinite(res.driver("motor").effort))
    np.testing.assert_allclose(res.body("crank").angle, math.radians(60) + 2 * math.pi * res.t)
