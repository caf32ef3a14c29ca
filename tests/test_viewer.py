"""Recordings read back with Rerun's own reader equal the results they were made from.

Everything here is headless: files are written and read back, the live stream goes to a Rerun
server on loopback that saves what it receives; no window is opened.
"""

from __future__ import annotations

import math
import os
import pathlib
import socket
import sys
import subprocess
import time

import numpy as np
import pytest
import quaternion as npq
import rerun as rr
import trimesh
from rerun.chunk import RrdReader

import mbd3d as mb
from conftest import stop_process, with_default_sigint
from mbd3d.mechanisms import pendulum_chain, slider_crank
from mbd3d.joints import Spherical
from mbd3d.viewer import (Recorder, RecordingError, entity_paths, read_component, record,
                          rerun_executable, show)


@pytest.fixture(autouse=True)
def strict_rerun():
    """Invalid data raises instead of being dropped with a warning."""
    rr.set_strict_mode(True)
    yield
    rr.set_strict_mode(False)


def lifted(a: np.ndarray) -> np.ndarray:
    out = np.zeros((len(a), 3))
    out[:, :a.shape[1]] = a
    return out


def has_footer(path) -> bool:
    try:
        RrdReader(str(path)).store()
        return True
    except RuntimeError:
        return False


def test_slider_crank_recording_holds_its_poses_and_both_screens(tmp_path):
    model = slider_crank(crank_angle=math.radians(65.0), crank_speed=2 * math.pi)
    res = mb.inverse_dynamics(model, np.linspace(0.0, 1.0, 41))
    path = tmp_path / "slider_crank.rrd"
    record(res, path, points={"coupler": ("rod", (0.0, 0.05))}, announce=False)

    paths = entity_paths(path)
    bodies = ("crank", "rod", "slider")
    expected = {f"/world/bodies/{b}{part}" for b in bodies for part in ("", "/shape", "/joints")}
    expected |= {f"/plots/{q}/{b}" for q in ("position", "velocity", "acceleration", "angle")
                 for b in bodies}
    expected |= {"/world/efforts/motor", "/plots/efforts/motor", "/world/trails/coupler",
                 "/plots/energy", "/plots/residuals/position", "/world/ground/rails", "/info"}
    expected |= {f"/world/reactions/{j}" for j in ("O", "A", "B", "rail")}
    assert expected <= paths, expected - paths
    assert len(RrdReader(str(path)).blueprints()) == 1 and has_footer(path)

    k = len(res)
    for name in bodies:
        body = res.body(name)
        steps, translation = read_component(path, f"/world/bodies/{name}",
                                            "Transform3D:translation")
        np.testing.assert_array_equal(steps, np.arange(k))
        np.testing.assert_allclose(translation[:, 0], lifted(body.position), rtol=1e-6, atol=1e-7)
        times, quat = read_component(path, f"/world/bodies/{name}", "Transform3D:quaternion",
                                     "sim_time")
        np.testing.assert_array_equal(times, np.round(res.t * 1e9).astype("timedelta64[ns]"))
        # a turn by the body angle about z, read from the file: (x, y, z, w)
        half = 0.5 * body.angle
        np.testing.assert_allclose(quat[:, 0], np.column_stack(
            [0 * half, 0 * half, np.sin(half), np.cos(half)]), rtol=0, atol=2e-7)
        # the plots are float64: exactly the results
        _, x = read_component(path, f"/plots/position/{name}", "Scalars:scalars")
        np.testing.assert_array_equal(x, body.position)
        _, a = read_component(path, f"/plots/acceleration/{name}", "Scalars:scalars")
        np.testing.assert_array_equal(a, body.acceleration)
    _, effort = read_component(path, "/plots/efforts/motor", "Scalars:scalars")
    np.testing.assert_array_equal(effort[:, 0], res.driver("motor").effort)
    pin = res.joint("O").reaction(on="crank")
    _, force = read_component(path, "/plots/reactions/O/force", "Scalars:scalars")
    np.testing.assert_array_equal(force, pin.force)
    _, energy = read_component(path, "/plots/energy", "Scalars:scalars")
    np.testing.assert_array_equal(energy[:, 0], res.kinetic_energy)
    np.testing.assert_array_equal(energy[:, 2], res.kinetic_energy + res.potential_energy)
    # the reaction arrow starts at the ground pin and points along the force
    _, origins = read_component(path, "/world/reactions/O", "Arrows3D:origins")
    _, vectors = read_component(path, "/world/reactions/O", "Arrows3D:vectors")
    np.testing.assert_allclose(origins[:, 0], 0.0, rtol=0, atol=1e-7)
    ratio = np.linalg.norm(vectors[:, 0], axis=1) / np.linalg.norm(pin.force, axis=1)
    np.testing.assert_allclose(ratio, ratio[0], rtol=1e-5)
    np.testing.assert_allclose(vectors[:, 0, :2] / ratio[:, None], pin.force, rtol=1e-5,
                               atol=1e-5 * np.abs(pin.force).max())
    # the motor torque arrow lies along the crank axis, with the torque's sign
    _, torque = read_component(path, "/world/efforts/motor", "Arrows3D:vectors")
    np.testing.assert_allclose(torque[:, 0, :2], 0.0, rtol=0, atol=1e-12)
    assert np.all(np.sign(torque[:, 0, 2]) == np.sign(res.driver("motor").effort))
    # the trail is the coupler point's path
    _, trail = read_component(path, "/world/trails/coupler", "Points3D:positions")
    np.testing.assert_allclose(trail[:, 0], lifted(res.point("rod", (0.0, 0.05)).position),
                               rtol=1e-6, atol=1e-7)
    # the default crank is a bar from pin to pin (0.12 m long)
    _, vertices = read_component(path, "/world/bodies/crank/shape", "Mesh3D:vertex_positions",
                                 None)
    span = np.ptp(vertices[0][:, 0])
    assert 0.12 < span < 0.12 * 1.2


def test_modes_along_a_motion_and_an_animated_mode_are_recorded(tmp_path):
    """The frequencies read back exactly, the frequency plot's curve passes through them (in
    its square scaling), its view is in the layout; an animated mode moves the crank."""
    from mbd3d.mechanisms import four_bar
    from mbd3d.viewer import record_modes
    along = mb.vibration_modes_along(four_bar(shaft_stiffness=50.0, gravity=0.0),
                                     np.linspace(0.0, 1.0, 7))
    path = tmp_path / "modes.rrd"
    record_modes(along, path, against="crank.theta", announce=False)
    assert {"/plots/modes/frequency", "/modes/curves", "/modes/axes", "/world/bodies/crank",
            "/plots/efforts/motor"} <= entity_paths(path)
    assert has_footer(path) and len(RrdReader(str(path)).blueprints()) == 1
    times, frequency = read_component(path, "/plots/modes/frequency", "Scalars:scalars",
                                      "sim_time")
    np.testing.assert_array_equal(frequency, along.frequencies)
    np.testing.assert_array_equal(times, np.round(along.t * 1e9).astype("timedelta64[ns]"))
    _, curve = read_component(path, "/modes/curves", "LineStrips2D:strips", None)
    points = np.asarray(curve[0][0], dtype=float)
    crank = np.degrees(along.equilibrium.body("crank").angle)
    top = along.frequencies.max()
    np.testing.assert_allclose(points[:, 0], (crank - crank.min()) / np.ptp(crank) * 100,
                               rtol=1e-6)
    np.testing.assert_allclose(-points[:, 1], along.frequencies[:, 0] / top * 100, rtol=1e-6)

    swing = along.at(0).animation(frames=8, cycles=1)
    record(swing, tmp_path / "mode.rrd", announce=False)
    _, turn = read_component(tmp_path / "mode.rrd", "/world/bodies/crank",
                             "Transform3D:quaternion", "step")
    angles = 2 * np.arctan2(turn[:, 0, 2], turn[:, 0, 3])
    np.testing.assert_allclose(angles, swing.body("crank").angle, rtol=0, atol=1e-6)
    assert "/plots/efforts/motor" not in entity_paths(tmp_path / "mode.rrd")
    with pytest.raises(mb.ModelError, match="vibration_modes_along"):
        record_modes(along.at(0), tmp_path / "one.rrd")


def test_spatial_top_recording_turns_like_the_results(tmp_path):
    tilt = mb.rotations.axis_angle((0.0, 1.0, 0.0), math.radians(30))
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -9.81))
    cone = trimesh.creation.cone(radius=0.05, height=0.1, sections=48)
    top = b.add_body("top", shape=cone, density=2700.0, position=0.075 * tilt[:, 2],
                     orientation=tilt, angular_velocity=150.0 * tilt[:, 2])
    b.add(Spherical("tip", b.ground, top, at=(0.0, 0.0, 0.0)))
    res = mb.forward_dynamics(b.build(), np.linspace(0.0, 0.3, 61), method="DOP853")
    assert res.stats["chart_resets"] > 5  # the recording spans many half turns of the charts
    path = tmp_path / "top.rrd"
    record(res, path, announce=False)
    steps, quat = read_component(path, "/world/bodies/top", "Transform3D:quaternion")
    assert len(steps) == len(res)
    xyzw = quat[:, 0].astype(float)
    recorded = npq.as_rotation_matrix(npq.from_float_array(xyzw[:, [3, 0, 1, 2]]))
    np.testing.assert_allclose(recorded, res.body("top").rotation, rtol=0, atol=2e-6)
    # the body is drawn with its own mesh, centred on the centre of mass
    _, vertices = read_component(path, "/world/bodies/top/shape", "Mesh3D:vertex_positions", None)
    np.testing.assert_allclose(vertices[0], top.shape.vertices, rtol=1e-6, atol=1e-7)
    assert {"/plots/angular_velocity/top", "/world/reactions/tip"} <= entity_paths(path)


def raising_force(after: float, error: type[BaseException]):
    def force(t, state):
        if t > after:
            raise error("the force model broke")
        return np.array([0.0, 0.0])
    return force


def test_live_recording_equals_the_recording_of_the_results(tmp_path):
    model = slider_crank(crank_angle=math.radians(65.0), crank_speed=None, crank_torque=2.0)
    live = tmp_path / "live.rrd"
    t = np.linspace(0.0, 0.5, 51)
    res = mb.forward_dynamics(model, t, observers=[Recorder(live, interval=0.0, announce=False)])
    after = tmp_path / "after.rrd"
    record(res, after, announce=False)
    for entity, component in (("/world/bodies/rod", "Transform3D:translation"),
                              ("/plots/reactions/A/force", "Scalars:scalars"),
                              ("/plots/energy", "Scalars:scalars")):
        s1, v1 = read_component(live, entity, component)
        s2, v2 = read_component(after, entity, component)
        np.testing.assert_array_equal(s1, np.arange(len(res)))
        np.testing.assert_array_equal(s1, s2)
        np.testing.assert_array_equal(v1, v2)
    assert has_footer(live)
    # the live recording went out in several blocks, not at the end
    blocks = [c for c in RrdReader(str(live)).stream().to_chunks()
              if c.entity_path == "/world/bodies/rod" and not c.is_static]
    assert len(blocks) > 1


def test_joint_coordinates_are_plotted_one_line_each_continuous_across_live_blocks(tmp_path):
    """A spatial crank turned three times and a slider on it, recorded live point by point:
    each block's own hinge angle starts within half a turn of zero (a spatial angle is read
    from the bodies' attitudes), yet the plot is the results' continuous angle; the slide's
    plot is its displacement."""
    from mbd3d.joints import Prismatic, Revolute, RotationDriver, TranslationDriver
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -9.81))
    crank = b.add_body("crank", mass=1.0, inertia=np.eye(3) * 0.01, position=(0.1, 0, 0))
    slider = b.add_body("slider", mass=0.5, inertia=np.eye(3) * 0.001,
                        position=(0.2, 0.0, 0.0))
    hinge = b.add(Revolute("O", b.ground, crank, at=(0.0, 0.0, 0.0), axis=(0.0, 0.0, 1.0)))
    slide = b.add(Prismatic("rail", crank, slider, at=(0.2, 0.0, 0.0), axis=(1.0, 0.0, 0.0)))
    b.add(RotationDriver("motor", hinge, motion=mb.Ramp(0.0, 2 * math.pi)))
    b.add(TranslationDriver("push", slide, motion=mb.Harmonic(0.05, 1.0)))
    live = tmp_path / "live.rrd"
    t = np.linspace(0.0, 3.0, 151)
    res = mb.inverse_dynamics(b.build(), t,
                              observers=[Recorder(live, interval=0.0, announce=False)])
    assert np.ptp(res.joint("O").angle) > 5 * math.pi
    assert abs(res.subset(100).joint("O").angle[0]) <= math.pi  # what a block sees alone
    for name, quantity in (("O", "angle"), ("rail", "displacement")):
        steps, plotted = read_component(live, f"/plots/joints/{name}/{quantity}",
                                        "Scalars:scalars")
        np.testing.assert_array_equal(steps, np.arange(len(res)))
        np.testing.assert_allclose(plotted[:, 0], getattr(res.joint(name), quantity),
                                   rtol=0, atol=1e-12)


@pytest.mark.parametrize("error", [RuntimeError, KeyboardInterrupt])
def test_a_run_that_fails_or_is_interrupted_leaves_a_valid_recording(tmp_path, error):
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    bar = b.add_body("bar", mass=1.0, inertia=1.0 / 12, position=(0.5, 0.0))
    from mbd3d.joints import Revolute
    b.add(Revolute("pin", b.ground, bar, at=(0.0, 0.0)))
    b.add(mb.PointForce("push", bar, raising_force(0.3, error)))
    path = tmp_path / "broken.rrd"
    recorder = Recorder(path, interval=0.0, announce=False)
    t = np.linspace(0.0, 1.0, 101)
    if error is KeyboardInterrupt:
        res = mb.forward_dynamics(b.build(), t, observers=[recorder])
        assert res.status == "interrupted"
    else:
        with pytest.raises(RuntimeError, match="force model broke") as info:
            mb.forward_dynamics(b.build(), t, observers=[recorder])
        res = info.value.results
    assert 25 <= len(res) <= 31  # everything up to t = 0.3 s
    assert has_footer(path)
    steps, translation = read_component(path, "/world/bodies/bar", "Transform3D:translation")
    np.testing.assert_array_equal(steps, np.arange(len(res)))
    np.testing.assert_allclose(translation[:, 0, :2], res.body("bar").position, rtol=1e-6,
                               atol=1e-7)
    _, text = read_component(path, "/info", "TextDocument:text", None)
    assert res.status in str(text[0])


def test_bad_destinations_are_refused_clearly(tmp_path):
    existing = tmp_path / "old.rrd"
    existing.write_bytes(b"keep me")
    with pytest.raises(RecordingError, match="already exists.*overwrite=True"):
        Recorder(existing)
    assert existing.read_bytes() == b"keep me"
    with pytest.raises(RecordingError, match="does not exist"):
        Recorder(tmp_path / "missing" / "x.rrd")
    with pytest.raises(RecordingError, match="is a folder"):
        Recorder(tmp_path)
    with pytest.raises(RecordingError, match="needs somewhere"):
        Recorder()
    if os.geteuid() != 0:  # root may write anywhere
        locked = tmp_path / "locked"
        locked.mkdir()
        locked.chmod(0o500)
        with pytest.raises(RecordingError, match="no permission"):
            Recorder(locked / "x.rrd")
    model = slider_crank(crank_angle=1.0, crank_speed=1.0)
    res = mb.kinematic_analysis(model, [0.0, 0.1])
    record(res, existing, overwrite=True, announce=False)
    assert has_footer(existing)
    with pytest.raises(mb.ModelError, match="no body 'piston'"):
        record(res, tmp_path / "a.rrd", plots=["piston"])
    with pytest.raises(mb.ModelError, match="shapes= names no body.*wheel"):
        record(res, tmp_path / "b.rrd", shapes={"wheel": trimesh.creation.box()})
    with pytest.raises(mb.ModelError, match="point label 'rod' is the name of a body"):
        record(res, tmp_path / "d.rrd", points={"rod": ("rod", (0.0, 0.0))})
    with pytest.raises(mb.ModelError, match="point 'tip' of body 'rod' must be 2 finite"):
        record(res, tmp_path / "e.rrd", points={"tip": ("rod", (0.0, 0.0, 1.0))})
    recorder = record(res, tmp_path / "c.rrd", announce=False)
    with pytest.raises(RecordingError, match="already recorded"):
        recorder.start(model, res.t, res.analysis)


def test_large_models_record_poses_without_plots_by_default(tmp_path):
    model = pendulum_chain(30)
    res = mb.forward_dynamics(model, np.linspace(0.0, 0.05, 3))
    path = tmp_path / "chain.rrd"
    record(res, path, plots=["link1"], announce=False)
    paths = entity_paths(path)
    assert sum(p.startswith("/world/bodies/") and p.count("/") == 3 for p in paths) == 30
    assert {p for p in paths if p.startswith("/plots/position/")} == {"/plots/position/link1"}
    assert not any(p.startswith("/world/reactions/") for p in paths)
    # the joints' angles instead, a line each, the first 24
    assert sum(p.startswith("/plots/joints/") for p in paths) == 24
    # a robot-sized chain: its 7 angles, not its bodies' 21 positions; its reactions
    res = mb.forward_dynamics(pendulum_chain(7), np.linspace(0.0, 0.05, 3))
    record(res, path, announce=False, overwrite=True)
    paths = entity_paths(path)
    assert not any(p.startswith("/plots/position/") for p in paths)
    assert sum(p.startswith("/plots/joints/") for p in paths) == 7
    assert sum(p.startswith("/world/reactions/") for p in paths) == 7


def test_the_main_job_says_where_the_recording_went(tmp_path, capsys):
    res = mb.kinematic_analysis(slider_crank(crank_angle=1.0, crank_speed=1.0), [0.0, 0.1])
    path = tmp_path / "my run.rrd"
    record(res, path)
    out = capsys.readouterr().out
    assert str(path) in out and f'rerun "{path}"' in out


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_live_stream_reaches_a_rerun_server_on_loopback(tmp_path):
    port = free_port()
    saved = tmp_path / "received.rrd"
    server = subprocess.Popen(with_default_sigint([
        rerun_executable(), "--bind", "127.0.0.1", "--port", str(port), "--save", str(saved)]),
                              stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, env={**os.environ, "CI": "true"})
    try:
        deadline = time.monotonic() + 30
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=0.5).close()
                break
            except OSError:
                if time.monotonic() > deadline or server.poll() is not None:
                    pytest.fail("the rerun server did not start")
                time.sleep(0.1)
        model = slider_crank(crank_angle=math.radians(65.0), crank_speed=2 * math.pi)
        res = mb.inverse_dynamics(model, np.linspace(0.0, 0.5, 26), observers=[
            Recorder(connect=f"rerun+http://127.0.0.1:{port}/proxy", interval=0.0)])
        expected = np.round(lifted(res.body("slider").position), 6)
        deadline = time.monotonic() + 30
        while True:  # the server writes what it receives; wait for all of it
            try:
                steps, translation = read_component(saved, "/world/bodies/slider",
                                                    "Transform3D:translation")
                if len(steps) == len(res):
                    break
            except (KeyError, OSError, RuntimeError, ValueError):
                pass
            if time.monotonic() > deadline:
                pytest.fail("the server did not receive the whole recording")
            time.sleep(0.2)
        np.testing.assert_allclose(translation[:, 0], expected, rtol=0, atol=2e-6)
    finally:
        stop_process(server)


def wait_for_rows(path, entity: str, rows: int, timeout: float = 30.0):
    """The translations of ``entity`` once a server saving to ``path`` has written ``rows``
    time points of it (or what it has after ``timeout`` seconds)."""
    deadline = time.monotonic() + timeout
    while True:
        try:
            steps, values = read_component(path, entity, "Transform3D:translation")
        except (KeyError, OSError, RuntimeError, ValueError):
            steps, values = np.zeros(0), np.zeros((0, 1, 3))
        if len(steps) >= rows or time.monotonic() > deadline:
            return steps, values
        time.sleep(0.2)


def test_spawned_viewer_receives_every_time_point(tmp_path, monkeypatch):
    """Recorder(spawn=True) starts a viewer for the recording being written and streams to it.
    The stand-in is Rerun's own binary listening where the spawned viewer would, saving what
    it receives instead of drawing it (no window here)."""
    from mbd3d.viewer import recorder

    port, saved = free_port(), tmp_path / "spawned.rrd"
    monkeypatch.setattr(recorder, "_viewer_command", lambda p, bind: with_default_sigint([
        rerun_executable(), "--bind", "127.0.0.1", "--port", str(p), "--save", str(saved)]))
    monkeypatch.setenv("DISPLAY", ":99")  # what a desktop session has
    monkeypatch.setenv("CI", "true")  # no analytics from the stand-in
    live = Recorder(spawn=True, viewer_port=port, interval=0.0, announce=False)
    try:
        model = slider_crank(crank_speed=None, crank_torque=2.0)
        res = mb.forward_dynamics(model, np.linspace(0.0, 0.5, 26), observers=[live])
        assert live.viewer_process is not None and live.viewer_process.poll() is None
        # delivered to the viewer when the run ends; the stand-in writes it out in its time
        steps, translation = wait_for_rows(saved, "/world/bodies/slider", 26)
    finally:
        stop_process(live.viewer_process)
    assert len(steps) == len(res) == 26
    np.testing.assert_allclose(translation[:, 0], lifted(res.body("slider").position),
                               rtol=0, atol=2e-6)


def test_spawn_without_a_display_fails_at_once_and_says_how_to_view_a_file(monkeypatch,
                                                                          tmp_path):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    if not sys.platform.startswith("linux"):
        pytest.skip("displays are named by X11 and Wayland variables on Linux only")
    start = time.monotonic()
    with pytest.raises(RecordingError, match="no display.*run: rerun FILE"):
        Recorder(tmp_path / "run.rrd", spawn=True, viewer_port=free_port())
    assert time.monotonic() - start < 2.0


def test_run_script_hands_main_its_options_by_name_after_checking_the_recording(tmp_path):
    from mbd3d.viewer import check_recording_first, run_script

    seen = {}

    @check_recording_first
    def main(duration=1.0, csv_folder=None, rrd=None, show=False):
        seen.update(duration=duration, csv_folder=csv_folder, rrd=rrd, show=show)
        return "done"

    options = {"--duration": {"type": float, "default": 2.0, "help": "simulated time [s]"},
               "--csv": {"dest": "csv_folder", "metavar": "FOLDER"}}
    path = str(tmp_path / "run.rrd")
    assert run_script(main, "A mechanism.\n\nMore.", "x.rrd", options,
                      argv=["--duration", "3", "--rrd", path]) == "done"
    assert seen == {"duration": 3.0, "csv_folder": None, "rrd": path, "show": False}
    # a recording that cannot be written stops the script before main runs, with the message
    seen.clear()
    with pytest.raises(SystemExit, match=r"^error: .*missing"):
        run_script(main, "A mechanism.", "x.rrd",
                   argv=["--rrd", str(tmp_path / "missing" / "a.rrd")])
    assert not seen


def test_a_recording_example_says_its_options_and_refuses_a_bad_path_at_once(tmp_path):
    import subprocess
    example = pathlib.Path(__file__).resolve().parent.parent / "examples" / "bricard.py"
    done = subprocess.run([sys.executable, str(example), "--help"], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0
    assert all(flag in done.stdout for flag in ("--duration", "--rrd", "--show"))
    start = time.monotonic()
    done = subprocess.run([sys.executable, str(example), "--rrd",
                           str(tmp_path / "missing" / "b.rrd")], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 1 and done.stderr.startswith("error: ")
    assert "Traceback" not in done.stderr and time.monotonic() - start < 60


def test_the_viewers_mbd3d_starts_listen_on_this_machine_only(tmp_path, monkeypatch):
    """Rerun's viewer listens on every interface by default (0.0.0.0): a spawned viewer, one
    opened on a file and ``mbd3d view`` are given loopback unless told otherwise."""
    from mbd3d import cli
    from mbd3d.viewer import recorder

    assert recorder._viewer_command(9876)[1:] == ["--bind", "127.0.0.1", "--port", "9876"]
    assert recorder._viewer_command(9876, "0.0.0.0")[1:3] == ["--bind", "0.0.0.0"]
    started = []
    monkeypatch.setattr(recorder.subprocess, "Popen", lambda command, **_: started.append(command))
    monkeypatch.setenv("DISPLAY", ":99")
    path = tmp_path / "run.rrd"
    record(mb.kinematic_analysis(slider_crank(crank_speed=1.0), [0.0, 0.1]), path)
    show(path)
    assert cli.main(["view", str(path)]) == 0
    assert cli.main(["view", str(path), "--bind", "0.0.0.0"]) == 0
    assert [command[1:] for command in started] == [
        ["--bind", "127.0.0.1", str(path)], ["--bind", "127.0.0.1", str(path)],
        ["--bind", "0.0.0.0", str(path)]]
