"""The mbd3d command line, end to end in subprocesses: exit statuses, files written, messages
on stderr that name the file, line and field of a mistake."""

from __future__ import annotations

import csv
import io
import os
import pathlib
import shutil
import subprocess
import sys

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.viewer import read_component
from test_model_files import GOOD

ROOT = pathlib.Path(__file__).resolve().parent.parent
MODELS = ROOT / "examples" / "models"


def mbd3d(*args: str, cwd=None) -> subprocess.CompletedProcess:
    env = {**os.environ, "MBD3D_PROGRESS": "0"}
    return subprocess.run([sys.executable, "-m", "mbd3d.cli", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, env=env, timeout=600)


def test_the_console_script_is_installed_beside_python():
    script = shutil.which("mbd3d", path=os.path.dirname(sys.executable))
    assert script is not None, "pip install should have put the mbd3d command beside python"


def test_help_everywhere():
    for command in ((), ("check",), ("run",), ("view",), ("sweep",)):
        done = mbd3d(*command, "--help")
        assert done.returncode == 0 and "usage: mbd3d" in done.stdout


def test_check_reports_mobility_and_the_analyses():
    done = mbd3d("check", MODELS / "four_bar.yaml")
    assert done.returncode == 0, done.stderr
    assert "degrees of freedom     0" in done.stdout
    assert "analysis: inverse over 0 to 1 s, 241 points" in done.stdout


def test_check_finds_a_kinematic_analysis_of_a_free_mechanism(tmp_path):
    motor = GOOD[GOOD.index("  - type: RotationDriver"):GOOD.index("analyses:")]
    (tmp_path / "free.yaml").write_text(GOOD.replace(motor, ""))
    done = mbd3d("check", tmp_path / "free.yaml")
    assert done.returncode == 1 and "problem: needs 1 more driver(s)" in done.stdout


def test_run_writes_the_recording_and_the_csv(tmp_path):
    done = mbd3d("run", MODELS / "slider_crank.yaml", "--t", "0:0.5:0.05", "--rrd",
                 tmp_path / "sc.rrd", "--csv", tmp_path, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "inverse dynamics, 11 time points, complete" in done.stdout
    steps, _ = read_component(tmp_path / "sc.rrd", "/world/bodies/slider",
                              "Transform3D:translation")
    assert len(steps) == 11
    table = np.genfromtxt(tmp_path / "slider_crank_inverse.csv", delimiter=",", names=True)
    np.testing.assert_allclose(table["t_s"], np.linspace(0.0, 0.5, 11))


def test_run_writes_where_the_file_says(tmp_path):
    (tmp_path / "m.yaml").write_text(GOOD.replace(
        "points: 11}}", "points: 11}, rrd: out/run.rrd, csv: out}"))
    (tmp_path / "out").mkdir()
    done = mbd3d("run", tmp_path / "m.yaml", cwd=ROOT)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "out" / "run.rrd").exists() and (tmp_path / "out" / "m_inverse.csv").exists()


def test_run_with_a_changed_value_and_another_analysis(tmp_path):
    done = mbd3d("run", MODELS / "four_bar_modes.yaml", "--analysis", "forward", "--t",
                 "0:0.1:0.05", "--method", "DOP853", "--set", "bodies.crank.mass=0.4")
    assert done.returncode == 0, done.stderr
    assert "forward dynamics, 3 time points, complete" in done.stdout


def _printed_table(stdout: str, title: str) -> dict[str, np.ndarray]:
    """The columns of a table ``mbd3d run`` printed under ``title:`` (names with units)."""
    lines = stdout.split(f"{title}:\n", 1)[1].split("\n\n", 1)[0].splitlines()
    names = [n + "]" for n in lines[0].strip().split("]") if n.strip()]
    rows = np.array([[float(x) for x in line.split()] for line in lines[1:]])
    return {name.strip(): rows[:, k] for k, name in enumerate(names)}


def test_run_tables_show_joint_coordinates_and_driver_efforts():
    done = mbd3d("run", MODELS / "slider_crank.yaml", "--t", "0:0.5:0.05", "--rows", "6")
    assert done.returncode == 0, done.stderr
    res = mb.inverse_dynamics(mb.load(MODELS / "slider_crank.yaml"), np.linspace(0.0, 0.5, 11))
    shown = _printed_table(done.stdout, "joint coordinates and driver efforts")
    k = np.searchsorted(res.t, shown["t [s]"])
    assert len(k) == 6 and np.all(np.isclose(res.t[k], shown["t [s]"], rtol=0, atol=1e-12))
    # printed to 5 significant digits
    for name, expected in (("O.angle [rad]", res.joint("O").angle),
                           ("rail.displacement [m]", res.joint("rail").displacement),
                           ("motor.effort [N m]", res.driver("motor").effort)):
        np.testing.assert_allclose(shown[name], expected[k], rtol=5e-5, atol=1e-12)
    bodies = _printed_table(done.stdout, "centres of mass")
    np.testing.assert_allclose(bodies["slider.x [m]"], res.body("slider").position[k, 0],
                               rtol=5e-5)


def test_a_model_file_can_ask_for_the_modes_along_a_motion(tmp_path):
    """The four-bar driven through a spring: its one frequency at each crank position, in the
    table, the CSV and a recording, as vibration_modes_along gives them."""
    text = (MODELS / "four_bar_modes.yaml").read_text().replace("kind: equilibrium",
                                                                "kind: modes")
    assert "kind: modes" in text
    (tmp_path / "fbm.yaml").write_text(text)
    done = mbd3d("run", tmp_path / "fbm.yaml", "--csv", tmp_path, "--rrd", tmp_path / "m.rrd")
    assert done.returncode == 0, done.stderr
    assert "vibration modes at 37 positions, complete" in done.stdout
    model = mb.load(tmp_path / "fbm.yaml")
    modes = mb.vibration_modes_along(model, np.linspace(0.0, 1.0, 37))
    table = np.genfromtxt(tmp_path / "fbm_modes.csv", delimiter=",", names=True)
    np.testing.assert_array_equal(table["mode_1_f_Hz"], modes.frequencies[:, 0])
    assert np.all(modes.frequencies[:, 0] > 1.0)
    _, plotted = read_component(tmp_path / "m.rrd", "/plots/modes/frequency", "Scalars:scalars",
                                "sim_time")
    np.testing.assert_allclose(plotted[:, 0], modes.frequencies[:, 0], rtol=0, atol=1e-12)
    again = mbd3d("run", tmp_path / "fbm.yaml", "--csv", tmp_path)
    assert again.returncode == 2 and "already exists" in again.stderr
    assert "--overwrite on the command line" in again.stderr  # the option this tool takes
    refused = mbd3d("sweep", tmp_path / "fbm.yaml", "--grid", "bodies.crank.mass=0.2,0.3")
    assert refused.returncode == 2 and "sweep runs kinematic, inverse or forward" in refused.stderr


def test_a_model_file_can_ask_for_a_linearisation(tmp_path):
    """The cart-pole linearised about its upright drawing and about the equilibrium found
    from it: the matrices in the CSV are those mb.linearize gives, the unstable root is
    printed; one time only, no recording."""
    text = (MODELS / "cart_pendulum_linearized.yaml").read_text()
    start = text.index("analyses:")
    analysis = ("analyses:\n- kind: linearize\n  t: [0.0]\n  about: ABOUT\n"
                "  inputs: [push.x]\n  coordinates: [cart.x, pole.theta]\n"
                "  outputs: [pole.theta]\n")
    model = mb.load(MODELS / "cart_pendulum_linearized.yaml")
    lin = mb.linearize(model, model.q0, inputs=["push.x"], outputs=["pole.theta"],
                       coordinates=["cart.x", "pole.theta"])
    for about in ("drawing", "equilibrium"):
        path = tmp_path / f"{about}.yaml"
        path.write_text(text[:start] + analysis.replace("ABOUT", about))
        done = mbd3d("run", path, "--csv", tmp_path)
        assert done.returncode == 0, done.stderr
        assert "4 states: cart.x, pole.theta, cart.x_dot, pole.theta_dot" in done.stdout
        rows = list(csv.reader(io.StringIO((tmp_path / f"{about}_linearize.csv").read_text())))
        assert rows[0] == ["matrix", "row", "column", "value"]
        for name in "ABCD":
            got = np.array([float(r[3]) for r in rows[1:] if r[0] == name])
            np.testing.assert_allclose(got, getattr(lin, name).ravel(), rtol=1e-6,
                                       atol=1e-9 * np.max(np.abs(getattr(lin, name))))
        unstable = np.max(lin.eigenvalues.real)
        assert f"{unstable:.5g}" in done.stdout
    for old, new, message in (("t: [0.0]", "t: [0.0, 1.0]", "about one time"),
                              ("about: drawing", "about: up", "about must be 'drawing' or")):
        path = tmp_path / "bad.yaml"
        path.write_text(text[:start] + analysis.replace("ABOUT", "drawing").replace(old, new))
        done = mbd3d("run", path)
        assert done.returncode == 2 and message in done.stderr, done.stderr
    path = tmp_path / "drawing.yaml"
    done = mbd3d("run", path, "--rrd", tmp_path / "x.rrd")
    assert done.returncode == 2 and "no motion to record" in done.stderr


@pytest.mark.parametrize("args, message", [
    (("run", "{bad}"), r"bad.yaml:8: joints\[0\].body_j: no body or joint 'bra'"),
    (("run", "{good}", "--t", "0:1"), "give START:STOP:STEP"),
    (("run", "{good}", "--set", "bodies.bar.mass=-2"), r"good.yaml:6: bodies\[0\]\.mass: body 'bar'"
                                                       ": mass"),
    (("run", "{good}", "--analysis", "inverse", "--method", "RK45"), "--method is for forward"),
    (("run", "{good}", "--sensitivity", "bodies.bar.mas"), "did you mean 'bodies.bar.mass'"),
    (("run", "{good}", "--analysis", "modes", "--sensitivity", "bodies.bar.mass"),
     "--sensitivity is for kinematic, inverse, equilibrium and forward analyses, not modes"),
    (("run", "{good}", "--analysis", "forward", "--method", "generalized-alpha",
      "--sensitivity", "bodies.bar.mass"), "not method 'generalized-alpha'"),
    (("check", "{missing}"), "cannot be read"),
    (("view", "{missing}"), "no recording"),
])
def test_mistakes_exit_2_with_the_reason_on_stderr(tmp_path, args, message):
    good = (tmp_path / "good.yaml")
    good.write_text(GOOD)
    (tmp_path / "bad.yaml").write_text(GOOD.replace("body_j: bar", "body_j: bra"))
    paths = {"bad": tmp_path / "bad.yaml", "good": good, "missing": tmp_path / "missing.yaml"}
    done = mbd3d(*(a.format(**paths) for a in args))
    assert done.returncode == 2, (done.stdout, done.stderr)
    assert done.stdout == ""
    import re
    assert re.search(message, done.stderr), done.stderr


def test_run_prints_and_writes_the_sensitivities_asked_for(tmp_path):
    names = ("bodies.slider.mass", "joints.B.point_i[0]")
    done = mbd3d("run", MODELS / "slider_crank.yaml", "--t", "0:0.2:0.05", "--csv", tmp_path,
                 *[a for name in names for a in ("--sensitivity", name)], cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "sensitivities to bodies.slider.mass:" in done.stdout
    with open(tmp_path / "slider_crank_inverse_sensitivities.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    # what the library gives for the same analysis
    res = mb.inverse_dynamics(mb.load(MODELS / "slider_crank.yaml"), np.arange(5) * 0.05)
    sens = mb.sensitivities(res, names)
    for name in names:
        written = [float(row[f"d(motor.effort)/d({name})"]) for row in rows]
        np.testing.assert_allclose(written, sens.effort("motor", name), rtol=1e-12, atol=0)
        written = [float(row[f"d(slider.x)/d({name})"]) for row in rows]
        np.testing.assert_allclose(written, sens.sensitivity("slider.x", name), rtol=1e-12,
                                   atol=1e-300)
    # a second run replaces the file only with --overwrite, refused before computing
    (tmp_path / "slider_crank_inverse.csv").unlink()
    command = ("run", MODELS / "slider_crank.yaml", "--t", "0:0.2:0.05", "--csv", tmp_path,
               "--sensitivity", names[0])
    refused = mbd3d(*command, cwd=tmp_path)
    assert refused.returncode == 2 and "_sensitivities.csv' already exists" in refused.stderr
    assert refused.stdout == "" and not (tmp_path / "slider_crank_inverse.csv").exists()
    assert mbd3d(*command, "--overwrite", cwd=tmp_path).returncode == 0


@pytest.mark.compiled_only
def test_run_integrates_forward_sensitivities_with_the_motion(tmp_path):
    # the Haug slider-crank's file (DOP853, rtol 1e-11): the CSV holds what
    # mb.forward_sensitivities gives for the same run
    name = "forces.spring.stiffness"
    done = mbd3d("run", MODELS / "haug_slider_crank.yaml", "--t", "0:1:0.5", "--csv",
                 tmp_path, "--sensitivity", name, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    with open(tmp_path / "haug_slider_crank_forward_sensitivities.csv", newline="") as f:
        written = [float(row[f"d(crank.theta)/d({name})"]) for row in csv.DictReader(f)]
    sens = mb.forward_sensitivities(mb.load(MODELS / "haug_slider_crank.yaml"),
                                    [0.0, 0.5, 1.0], [name], method="DOP853", rtol=1e-11,
                                    atol=1e-13)
    np.testing.assert_allclose(written, sens.sensitivity("crank.theta", name), rtol=1e-12,
                               atol=1e-300)
    assert abs(written[-1]) > 1e-4


def test_an_unknown_command_is_a_usage_error():
    done = mbd3d("simulate", "x.yaml")
    assert done.returncode == 2 and "invalid choice" in done.stderr


def test_a_file_without_analyses_needs_times(tmp_path):
    text = GOOD[:GOOD.index("analyses:")]
    (tmp_path / "m.yaml").write_text(text)
    done = mbd3d("run", tmp_path / "m.yaml")
    assert done.returncode == 2 and "asks for no analysis" in done.stderr


def test_a_failing_analysis_exits_1_and_writes_what_it_computed(tmp_path):
    """A slider driven out to its dead centre at t = 1 s: past it the analysis stops with the
    joints named; the points before are in the CSV."""
    from mbd3d.joints import Prismatic, Revolute, TranslationDriver
    import math
    import mbd3d as mb
    r, l = 0.12, 0.26
    b = mb.ModelBuilder(dim=2, name="dead centre")
    x0 = r * math.cos(1.0) + math.sqrt(l * l - (r * math.sin(1.0)) ** 2)
    a = r * np.array([math.cos(1.0), math.sin(1.0)])
    crank = b.add_body("crank", mass=1, inertia=0.001, position=a / 2, angle=1.0)
    rod = b.add_body("rod", mass=2, inertia=0.01, position=(a + (x0, 0)) / 2,
                     angle=math.asin(-a[1] / l))
    slider = b.add_body("slider", mass=4, inertia=0.02, position=(x0, 0.0))
    b.add(Revolute("O", b.ground, crank, at=(0, 0)))
    b.add(Revolute("A", crank, rod, at=a))
    b.add(Revolute("B", rod, slider, at=(x0, 0)))
    rail = b.add(Prismatic("rail", b.ground, slider, axis=(1, 0)))
    b.add(TranslationDriver("piston", rail, motion=mb.Ramp(0.0, r + l - x0)))
    path = mb.save(b.build(), tmp_path / "dead.yaml")
    done = mbd3d("run", path, "--analysis", "kinematic", "--t", "0:1.2:0.3", "--csv", tmp_path)
    assert done.returncode == 1
    assert "lock-up or toggle" in done.stderr and "t = 1.2 s" in done.stderr
    table = np.genfromtxt(tmp_path / "dead_kinematic.csv", delimiter=",", names=True)
    assert len(table) == 4


def test_sweep_runs_the_grid_and_keeps_the_table(tmp_path):
    done = mbd3d("sweep", MODELS / "slider_crank.yaml", "--grid",
                 "joints.motor.motion.rate=3,6", "--t", "0:0.5:0.05", "--serial", "--folder",
                 tmp_path / "sweep")
    assert done.returncode == 0, done.stderr
    assert "SweepTable(2 runs, 0 failed)" in done.stdout
    table = (tmp_path / "sweep" / "table.csv").read_text()
    assert "p_joints_motor_motion_rate" in table and "peak |motor effort|" in table
    # the default metrics are what they are called: the motor's effort, largest in magnitude
    # where it is negative here, and the slider's last position, from runs made apart
    from mbd3d.io.model_file import read
    rows = list(csv.DictReader(io.StringIO(table)))
    assert [float(row["p_joints_motor_motion_rate"]) for row in rows] == [3.0, 6.0]
    for row in rows:
        model = read(MODELS / "slider_crank.yaml", {
            "joints.motor.motion.rate": float(row["p_joints_motor_motion_rate"])}).model
        res = mb.inverse_dynamics(model, np.linspace(0.0, 0.5, 11))
        effort = res.driver("motor").effort
        assert -effort.min() > effort.max()
        assert float(row["peak |motor effort|"]) == pytest.approx(np.abs(effort).max(),
                                                                  rel=1e-12)
        assert float(row["final slider.x"]) == pytest.approx(
            res.body("slider").position[-1, 0], rel=1e-12)
    done = mbd3d("sweep", MODELS / "slider_crank.yaml", "--grid", "joints.motr.rate=1",
                 "--serial", "--folder", tmp_path / "bad")
    assert done.returncode == 2 and "no entry 'motr'" in done.stderr


def test_a_model_file_writes_only_inside_its_folder_and_replaces_nothing_unasked(tmp_path):
    """Output paths in a model file stay inside its folder (a file someone else wrote cannot
    make mbd3d run replace notes.txt elsewhere); check lists every destination; an existing
    output is replaced only with --overwrite, on the command line's paths too."""
    folder = tmp_path / "models"
    folder.mkdir()
    notes = tmp_path / "notes.txt"
    notes.write_text("mine")
    for bad in ("../notes.txt", str(notes), "sub/../../notes.txt"):
        for key in ("rrd", "csv"):
            path = folder / "evil.yaml"
            path.write_text(GOOD.replace("points: 11}}", f"points: 11}}, {key}: '{bad}'}}"))
            done = mbd3d("run", path)
            assert done.returncode == 2, (bad, key, done.stdout, done.stderr)
            assert "evil.yaml:14: analyses[0]." + key in done.stderr
            assert "leaves the model file's folder" in done.stderr
            assert notes.read_text() == "mine"
    path = folder / "good.yaml"
    path.write_text(GOOD.replace("points: 11}}", "points: 11}, rrd: out/run.rrd, csv: out}"))
    (folder / "out").mkdir()
    done = mbd3d("check", path)
    assert f"writes the recording to {folder / 'out' / 'run.rrd'}" in done.stdout
    assert f"writes the CSV to {folder / 'out' / 'good_inverse.csv'}" in done.stdout
    assert mbd3d("run", path).returncode == 0
    written = {p: p.read_bytes() for p in (folder / "out").iterdir()}
    assert len(written) == 2
    done = mbd3d("run", path, "--set", "joints.motor.motion.rate=3.0")
    assert done.returncode == 2 and "already exists" in done.stderr
    assert {p: p.read_bytes() for p in (folder / "out").iterdir()} == written
    assert "(exists: mbd3d run replaces it only with --overwrite)" in mbd3d("check", path).stdout
    other = tmp_path / "mine.rrd"
    other.write_text("mine")
    done = mbd3d("run", path, "--rrd", other, "--overwrite")
    assert done.returncode == 0 and other.read_bytes() != b"mine"
    done = mbd3d("run", path, "--overwrite", "--set", "joints.motor.motion.rate=3.0")
    assert done.returncode == 0
    assert (folder / "out" / "good_inverse.csv").read_bytes() != written[
        folder / "out" / "good_inverse.csv"]


@pytest.mark.filterwarnings("ignore::mbd3d.io.urdf.UrdfWarning")  # the PUMA's joint limits
def test_a_sweep_of_a_model_file_is_keyed_on_every_file_it_reads(tmp_path):
    """Rows of a sweep are reused while its key is the same: the key covers the model file,
    the URDF it starts from and that URDF's meshes, so an edit of any makes a new sweep."""
    import trimesh

    from mbd3d.cli import _FileFactory
    shutil.copy(ROOT / "tests" / "data" / "puma560.urdf", tmp_path / "arm.urdf")
    urdf = (tmp_path / "arm.urdf").read_text()
    trimesh.creation.box((0.1, 0.1, 0.1)).export(tmp_path / "hand.stl")
    (tmp_path / "arm.urdf").write_text(urdf.replace(
        '<geometry><cylinder radius="0.04" length="0.1"/></geometry>',
        '<geometry><mesh filename="hand.stl"/></geometry>', 1))
    path = tmp_path / "arm.yaml"
    path.write_text("mbd3d: 1\ndim: 3\nurdf: {file: arm.urdf}\n")
    key = _FileFactory(str(path), {}).sweep_identity()
    assert key == _FileFactory(str(path), {}).sweep_identity()
    edits = [(tmp_path / "arm.urdf", ('<mass value="4.8"/>', '<mass value="4.9"/>')),
             (tmp_path / "hand.stl", None)]
    for edited, change in edits:
        if change is None:
            trimesh.creation.box((0.1, 0.1, 0.2)).export(edited)
        else:
            assert change[0] in edited.read_text()
            edited.write_text(edited.read_text().replace(*change))
        new = _FileFactory(str(path), {}).sweep_identity()
        assert new != key, edited
        key = new


#: the model file of test_model_files without its motor and analysis: a free pendulum
FREE_PENDULUM = GOOD.split("  - type: RotationDriver")[0]


def test_run_writes_as_it_computes_so_that_a_killed_run_leaves_what_it_did(tmp_path):
    """mbd3d run writes the CSV and the recording as the time points are computed: killed
    (SIGKILL, nothing to clean up) part way, it leaves complete rows in a CSV that reads
    back and a recording of them; run to the end, its CSV is the one to_csv writes."""
    import signal
    import time

    path = tmp_path / "free.yaml"
    path.write_text(FREE_PENDULUM)
    process = subprocess.Popen(
        [sys.executable, "-m", "mbd3d.cli", "run", str(path), "--analysis", "forward", "--t",
         "0:20000:1", "--method", "DOP853", "--rtol", "1e-13", "--rrd", "run.rrd", "--csv", "."],
        cwd=tmp_path, env={**os.environ, "MBD3D_PROGRESS": "0"}, stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL)
    csv_path = tmp_path / "free_forward.csv"
    try:
        deadline = time.monotonic() + 300
        while time.monotonic() < deadline and process.poll() is None:
            if csv_path.exists() and csv_path.read_text().count("\n") >= 4:
                break
            time.sleep(0.2)
    finally:
        process.send_signal(signal.SIGKILL)
        process.wait()
    table = np.genfromtxt(csv_path, delimiter=",", names=True)
    assert 3 <= len(table) < 20001
    np.testing.assert_array_equal(table["t_s"], np.arange(len(table)))
    assert np.all(np.isfinite(table.view((float, len(table.dtype.names)))))
    steps, _ = read_component(tmp_path / "run.rrd", "/world/bodies/bar",
                              "Transform3D:translation")
    assert len(steps) >= 1
    # to the end: the rows written as they came are those of the finished results
    (tmp_path / "out").mkdir()
    done = mbd3d("run", path, "--analysis", "forward", "--t", "0:0.5:0.01", "--csv", "out",
                 cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    res = mb.forward_dynamics(mb.load(path), np.linspace(0.0, 0.5, 51))
    res.to_csv(tmp_path / "api.csv")
    assert (tmp_path / "out" / "free_forward.csv").read_text() == (
        tmp_path / "api.csv").read_text()


def test_view_names_a_file_that_is_no_recording_and_sweep_writes_where_it_is_run(tmp_path):
    (tmp_path / "x.csv").write_text("t [s]\n0.0\n")
    done = mbd3d("view", tmp_path / "x.csv")
    assert done.returncode == 2 and "is not a Rerun recording" in done.stderr
    # the default sweep folder is made in the working directory, not beside the model file
    done = mbd3d("sweep", MODELS / "slider_crank.yaml", "--grid", "joints.motor.motion.rate=3",
                 "--t", "0:0.1:0.05", "--serial", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "slider_crank_sweep" / "table.csv").is_file()
    assert not (MODELS / "slider_crank_sweep").exists()


@pytest.mark.parametrize("times, message", [("0:inf:0.1", "need finite numbers"),
                                            ("0:1e9:1e-9", "output times, more than")])
def test_impossible_time_grids_on_the_command_line_are_refused(times, message):
    done = mbd3d("run", MODELS / "slider_crank.yaml", "--t", times)
    assert done.returncode == 2 and message in done.stderr and "Traceback" not in done.stderr


def test_an_interrupted_sweep_exits_130_and_help_states_the_exit_codes(tmp_path, monkeypatch,
                                                                      capsys):
    import mbd3d.cli as cli
    built = cli._FileFactory.__call__
    calls = []

    def interrupted_at_the_second(self, **params):  # Ctrl-C while the second point is built
        calls.append(params)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return built(self, **params)

    monkeypatch.setattr(cli._FileFactory, "__call__", interrupted_at_the_second)
    status = cli.main(["sweep", str(MODELS / "slider_crank.yaml"), "--grid",
                       "joints.motor.motion.rate=3,6,9", "--t", "0:0.2:0.05", "--serial",
                       "--folder", str(tmp_path / "sweep")])
    assert status == 130
    assert "interrupted; the runs done are kept" in capsys.readouterr().err
    assert len(list((tmp_path / "sweep" / "runs").glob("*.json"))) == 1  # the first run kept
    done = mbd3d("--help")
    assert "exit status: 0 done, 1 the analysis failed" in done.stdout
    assert "130 interrupted" in done.stdout
