"""Optimisation and identification on exact gradients (``mbd3d.optimization``, ``mbd3d
optimize``): measured motions fitted back to the parameters that made them, each statistic's
gradient against differences of the statistic, several starts through the sweep machinery, and
bad input named."""

from __future__ import annotations

import pathlib
import sys

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.optimization import Fit, Objective, best, optimize, read_measurements
from mbd3d.io.model_file import read
from mbd3d.sweeps import Analysis

EXAMPLES = pathlib.Path(__file__).parent.parent / "examples"
sys.path.insert(0, str(EXAMPLES))
import identify_slider_crank as identify  # noqa: E402
from test_cli import mbd3d  # noqa: E402

T = np.linspace(0.0, 0.5, 26)
MASSES = identify.PARAMETERS[:2]


def measured_torque(model) -> np.ndarray:
    return mb.inverse_dynamics(model, T).joint("motor").effort


def test_fit_finds_the_masses_that_made_the_torque(tmp_path):
    # the torque of the slider-crank with its true masses, fitted from wrong ones: the
    # residual vanishes, so every start that converges ends at the truth
    start = identify.build()
    truth = mb.with_parameters(start, dict(zip(MASSES, identify.TRUE)))
    fit = Fit(T, {"motor.effort": measured_torque(truth)})
    table = optimize(start, Analysis("inverse dynamics", T), {name: (0.1, 20.0)
                                                             for name in MASSES},
                     fit, starts=3, folder=tmp_path / "fit", backend="serial", progress=False)
    assert len(table) == 3 and not table.failed
    row = best(table)
    assert row["objective"] < 1e-20 and row["start objective"] > 1.0
    for name, true in zip(MASSES, identify.TRUE):
        assert row[f"{name} optimised"] == pytest.approx(true, abs=1e-9)
    # run again on the same folder: the starts are kept, nothing is computed again
    again = optimize(start, Analysis("inverse dynamics", T), {name: (0.1, 20.0)
                                                             for name in MASSES},
                     fit, starts=3, folder=tmp_path / "fit", backend="serial", progress=False)
    assert again.summary["skipped"] == 3


@pytest.mark.parametrize("statistic", ["rms", "peak", "mean", "final"])
def test_each_statistic_s_gradient_against_differences(statistic):
    model = identify.build(1.5, 2.5, 10.0)
    objective = Objective("motor.effort", statistic)
    res = mb.inverse_dynamics(model, T)
    value, gradient = objective.value(res, mb.sensitivities(res, identify.PARAMETERS))
    for j, name in enumerate(identify.PARAMETERS):
        h = 1e-3
        x = mb.parameters(model)[name]
        values = [objective.value(*_analysed(mb.with_parameters(model, {name: x + d})))[0]
                  for d in (-2 * h, -h, h, 2 * h)]
        difference = (8 * (values[2] - values[1]) - (values[3] - values[0])) / (12 * h)
        assert gradient[j] == pytest.approx(difference, rel=1e-7, abs=1e-9), name
    assert value == pytest.approx({"rms": np.sqrt(np.mean(res.joint("motor").effort ** 2)),
                                   "peak": np.max(np.abs(res.joint("motor").effort)),
                                   "mean": np.mean(res.joint("motor").effort),
                                   "final": res.joint("motor").effort[-1]}[statistic])


def _analysed(model):
    res = mb.inverse_dynamics(model, T)
    return res, mb.sensitivities(res, identify.PARAMETERS)


def test_minimize_stops_at_the_bound_the_gradient_points_to(tmp_path):
    # the motor's rms torque grows with the slider's mass: the least is at its lower bound
    table = optimize(identify.build(), Analysis("inverse dynamics", T),
                     {"bodies.slider.mass": (0.5, 5.0)}, Objective("motor.effort", "rms"),
                     starts=2, folder=tmp_path / "rms", backend="serial", progress=False)
    row = best(table)
    assert row["bodies.slider.mass optimised"] == pytest.approx(0.5, abs=1e-12)
    assert row["objective"] < row["start objective"]


@pytest.mark.compiled_only
def test_forward_dynamics_gradients_come_from_its_sensitivities(tmp_path):
    # the Haug slider-crank's crank angle after 2 s against its spring's stiffness: the
    # objective's gradient from mb.forward_sensitivities against differences of runs
    import haug_slider_crank  # noqa: PLC0415

    model = haug_slider_crank.build()
    t = np.linspace(0.0, 2.0, 5)
    options = {"method": "DOP853", "rtol": 1e-11, "atol": 1e-13}
    objective = Objective("crank.angle", "final")
    name = "forces.spring.stiffness"
    sens = mb.forward_sensitivities(model, t, [name], **options)
    gradient = objective.value(sens.results, sens)[1][0]
    values = [objective.value(*(lambda s: (s.results, s))(mb.forward_sensitivities(
        mb.with_parameters(model, {name: 1.0 + d}), t, [name], **options)))[0]
        for d in (-2e-3, -1e-3, 1e-3, 2e-3)]
    difference = (8 * (values[2] - values[1]) - (values[3] - values[0])) / 12e-3
    assert gradient == pytest.approx(difference, rel=1e-7)
    table = optimize(model, Analysis("forward dynamics", t, options), {name: (0.5, 2.0)},
                     objective, folder=tmp_path / "forward", backend="serial", progress=False)
    row = best(table)
    assert row is not None and row["objective"] <= row["start objective"]
    with pytest.raises(mb.ModelError, match="generalized-alpha"):
        optimize(model, Analysis("forward dynamics", t, {"method": "generalized-alpha",
                                                          "step": 1e-3}), {name: (0.5, 2.0)},
                 objective, folder=tmp_path / "ga", backend="serial", progress=False)


def test_the_command_fits_a_file_and_writes_the_best_model(tmp_path):
    model_file = EXAMPLES / "models" / "identify_slider_crank.yaml"
    start = mb.load(model_file)
    truth = mb.with_parameters(start, dict(zip(MASSES, identify.TRUE)))
    data = tmp_path / "torque.csv"
    data.write_text("t [s],motor.effort\n" + "".join(
        f"{float(t)!r},{float(value)!r}\n" for t, value in zip(T, measured_torque(truth))))
    out = tmp_path / "best.yaml"
    done = mbd3d("optimize", model_file, "--vary", f"{MASSES[0]}=0.1:20", "--vary",
                 f"{MASSES[1]}=0.1:20", "--fit", data, "--starts", "2", "--serial",
                 "--folder", tmp_path / "runs", "--out", out, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "best: fit of motor.effort" in done.stdout
    fitted = mb.parameters(mb.load(out))
    for name, true in zip(MASSES, identify.TRUE):
        assert fitted[name] == pytest.approx(true, abs=1e-8)
    again = mbd3d("optimize", model_file, "--vary", f"{MASSES[0]}=0.1:20", "--minimize",
                  "rms:motor.effort", "--serial", "--folder", tmp_path / "runs2", "--out", out,
                  cwd=tmp_path)
    assert again.returncode == 2 and "--overwrite" in again.stderr  # nothing replaced


def test_the_file_states_what_to_vary_and_fit(tmp_path):
    # the model file's optimize: section, read as the command line's terms
    start = mb.load(EXAMPLES / "models" / "identify_slider_crank.yaml")
    truth = mb.with_parameters(start, dict(zip(MASSES, identify.TRUE)))
    (tmp_path / "torque.csv").write_text("t [s],motor.effort\n" + "".join(
        f"{float(t)!r},{float(value)!r}\n" for t, value in zip(T, measured_torque(truth))))
    text = (EXAMPLES / "models" / "identify_slider_crank.yaml").read_text()
    model_file = tmp_path / "model.yaml"
    model_file.write_text(text + "optimize:\n  vary:\n" + "".join(
        f"    {name}: [0.1, 20.0]\n" for name in MASSES) + "  fit: torque.csv\n  starts: 2\n")
    (tmp_path / "best").mkdir()
    done = mbd3d("optimize", model_file, "--serial", "--out", tmp_path / "best" / "best.yaml",
                 cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "SweepTable(2 runs, 0 failed)" in done.stdout
    assert (tmp_path / "model_optimize" / "table.csv").exists()
    # the best model's file keeps the section, its measurements found from where it is
    kept = read(tmp_path / "best" / "best.yaml")
    assert kept.optimization == read(model_file).optimization
    assert mb.parameters(kept.model)[MASSES[0]] == pytest.approx(identify.TRUE[0], abs=1e-8)
    model_file.write_text(text + "optimize:\n  vary:\n    bodies.rod.mass: [2.0, 1.0]\n"
                          "  minimize: rms:motor.effort\n")
    bad = mbd3d("optimize", model_file, "--serial", cwd=tmp_path)
    line = len(text.splitlines()) + 3
    assert bad.returncode == 2 and f"model.yaml:{line}: optimize.vary.bodies.rod.mass: bounds" \
        in bad.stderr, bad.stderr
    nothing = mbd3d("optimize", EXAMPLES / "models" / "identify_slider_crank.yaml",
                    "--serial", cwd=tmp_path)
    assert nothing.returncode == 2 and "or an optimize: section" in nothing.stderr


@pytest.mark.parametrize("args, message", [
    (["--vary", "bodies.rod.mass=1", "--minimize", "rms:motor.effort"], "FIELD=LOW:HIGH"),
    (["--vary", "bodies.rod.mass=2:1", "--minimize", "rms:motor.effort"], "lower < upper"),
    (["--vary", "bodies.rod.mas=1:2", "--minimize", "rms:motor.effort"],
     "did you mean 'bodies.rod.mass'"),
    (["--vary", "bodies.rod.mass=1:2", "--minimize", "rms"], "STATISTIC:COLUMN"),
    (["--vary", "bodies.rod.mass=1:2", "--minimize", "max:motor.effort"], "statistic must"),
])
def test_the_command_names_bad_input(tmp_path, args, message):
    done = mbd3d("optimize", EXAMPLES / "models" / "identify_slider_crank.yaml", *args,
                 "--serial", "--folder", tmp_path / "runs", cwd=tmp_path)
    assert done.returncode == 2 and message in done.stderr, done.stderr


def test_measurements_are_read_with_their_line_named(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("t [s],motor.effort\n0.0,1.0\n0.1,oops\n0.2,3.0\n")
    with pytest.raises(mb.ModelError, match="bad.csv, line 3"):
        read_measurements(bad)
    backwards = tmp_path / "backwards.csv"
    backwards.write_text("t [s],motor.effort\n0.1,1.0\n0.0,2.0\n")
    with pytest.raises(mb.ModelError, match="times increasing"):
        read_measurements(backwards)
    with pytest.raises(mb.ModelError, match="no column 'motor.efort'.*did you mean"):
        optimize(identify.build(), Analysis("inverse dynamics", T),
                 {"bodies.rod.mass": (0.5, 5.0)}, Fit(T, {"motor.efort": T}),
                 folder=tmp_path / "f", backend="serial", progress=False)
