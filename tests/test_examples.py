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


def test_spatial_slider_crank_example(capsys):
    res = load("spatial_slider_crank").main(n_points=5)
    assert "closed form" in capsys.readouterr().out
    phi = 2 * math.pi * res.t
    x = 0.1 * np.cos(phi) + np.sqrt(0.09 - 0.06**2 - (0.04 - 0.1 * np.sin(phi)) ** 2)
    np.testing.assert_allclose(res.body("slider").position[:, 0], x, atol=1e-12)


def test_spinning_top_example(capsys):
    res = load("spinning_top").main(duration=0.2, n_points=3)
    assert "chart resets" in capsys.readouterr().out
    axis = res.body("top").rotation[:, :, 2]
    np.testing.assert_allclose(np.arccos(axis[:, 2]), math.radians(60.0), atol=1e-8)


def test_spatial_four_bar_example(capsys):
    res = load("spatial_four_bar").main(n_points=5)
    out = capsys.readouterr().out
    assert "2 redundant constraint equation(s)" in out and "fully driven" in out
    assert np.all(np.isfinite(res.driver("motor").effort))
