"""The README's quick start and the user guide's snippets run as printed and mean what they
say."""

from __future__ import annotations

import pathlib
import re
import time

import numpy as np
import pytest

from conftest import stop_process, with_default_sigint

ROOT = pathlib.Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
DOCS = ROOT / "docs"


def test_quick_start_runs(tmp_path, monkeypatch, capsys):
    text = README.read_text()
    block = re.search(r"## Quick start.*?```python\n(.*?)```", text, re.S).group(1)
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    exec(compile(block, "README quick start", "exec"), namespace)
    res = namespace["res"]
    assert "degrees of freedom     0" in capsys.readouterr().out
    assert (tmp_path / "slider_crank.csv").exists()
    assert (tmp_path / "slider_crank.rrd").exists()
    # the guesses in the README are off; the assembled slider sits at the closed-form position
    phi = np.radians(65)
    x = 0.12 * np.cos(phi) + np.sqrt(0.26**2 - (0.12 * np.sin(phi)) ** 2)
    assert abs(res.body("slider").position[0, 0] - x) < 1e-12


def test_spatial_snippet_runs(capsys):
    text = (DOCS / "getting_started.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    spatial = [b for b in blocks if "dim=3" in b]
    assert spatial
    namespace: dict = {}
    exec(compile(spatial[0], "README spatial snippet", "exec"), namespace)
    res = namespace["res"]
    assert res.status == "complete" and res.stats["chart_resets"] > 0
    energy = res.kinetic_energy + res.potential_energy
    assert np.max(np.abs(energy - energy[0])) < 1e-6 * np.max(res.kinetic_energy)


def test_first_two_commands_are_install_and_test():
    text = README.read_text()
    commands = re.search(r"```bash\n(.*?)```", text, re.S).group(1).strip().splitlines()
    assert commands[0] == "python -m pip install . && python examples/slider_crank.py"
    assert commands[1] == 'python -m pip install ".[test]" && python -m pytest'


def test_sweep_snippet_runs_on_a_local_cluster(tmp_path, monkeypatch, capsys):
    section = (DOCS / "guide" / "sweeps.md").read_text()
    block = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "__main__"}
    exec(compile(block, "README sweep snippet", "exec"), namespace)
    table = namespace["table"]
    assert [row["status"] for row in table] == ["failed", "ok", "failed", "ok"]
    assert (tmp_path / "sweep_results" / "table.csv").exists()
    assert "SweepTable(4 runs, 2 failed)" in capsys.readouterr().out


def viewer_blocks() -> list[str]:
    section = (DOCS / "guide" / "viewer.md").read_text().split("\n## ", 1)[0]
    return re.findall(r"```python\n(.*?)```", section, re.S)


def store_rows(path: pathlib.Path) -> list[int]:
    """Time points of the slider's pose in each recording of a file saved by a rerun server."""
    from rerun.chunk import RrdReader

    if not path.exists():
        return []
    try:
        reader = RrdReader(str(path))
        return [sum(len(chunk.to_record_batch()) for chunk in reader.stream(store=store).to_chunks()
                    if chunk.entity_path == "/world/bodies/slider" and not chunk.is_static)
                for store in reader.recordings()]
    except (OSError, RuntimeError, ValueError):  # the server is still writing its first bytes
        return []


@pytest.mark.filterwarnings("ignore:RRD file has no footer")  # a live stream saved by rerun
def test_viewer_snippets_run_as_written(tmp_path, monkeypatch):
    """The file snippet runs as printed; the display snippet runs as printed with Rerun's own
    binary, saving instead of drawing, as the viewer it spawns and connects to, and the file
    viewer replaced by a program that only checks its argument (no window here)."""
    import socket
    import subprocess

    from mbd3d.viewer import read_component, recorder, rerun_executable

    first, second = viewer_blocks()
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    exec(compile(first, "README viewer snippet", "exec"), namespace)
    for name in ("live.rrd", "run.rrd"):
        steps, _ = read_component(tmp_path / name, "/world/bodies/slider", "Transform3D:translation")
        assert len(steps) == 201

    with socket.socket() as sock:
        if sock.connect_ex(("127.0.0.1", recorder.VIEWER_PORT)) == 0:
            pytest.skip(f"port {recorder.VIEWER_PORT} is taken: a viewer is running here")
    received = tmp_path / "viewer received.rrd"
    binary = rerun_executable()
    monkeypatch.setattr(recorder, "_viewer_command", lambda port, bind: with_default_sigint([
        binary, "--bind", "127.0.0.1", "--port", str(port), "--save", str(received)]))
    spawned = []
    spawn = recorder.spawn_viewer
    monkeypatch.setattr(recorder, "spawn_viewer",
                        lambda *a: spawned.append(spawn(*a)) or spawned[-1])
    monkeypatch.setattr(recorder, "rerun_executable", lambda: "test")  # `test FILE`: no window
    monkeypatch.setenv("DISPLAY", ":99")
    monkeypatch.setenv("CI", "true")
    try:
        exec(compile(second, "README display snippet", "exec"), namespace)
        # both runs were delivered to the viewer when they ended; the stand-in writes them
        # out in its own time
        deadline = time.monotonic() + 30
        while store_rows(received) != [201, 201] and time.monotonic() < deadline:
            time.sleep(0.2)
    finally:
        for _, process in spawned:
            stop_process(process)
    assert len(spawned) == 1 and spawned[0][1] is not None  # started once, then reused
    # both runs reached it, each a recording of its own with every time point
    assert store_rows(received) == [201, 201]
    assert isinstance(namespace["show"]("run.rrd"), subprocess.Popen)


def test_model_file_snippet_loads_runs_and_reports_mistakes_as_shown(tmp_path):
    import mbd3d as mb
    from mbd3d.io.model_file import read
    section = (DOCS / "guide" / "model_files.md").read_text()
    block = re.search(r"```yaml\n(.*?)```", section, re.S).group(1)
    path = tmp_path / "pendulum.yaml"
    path.write_text(block)
    loaded = read(path)
    res = loaded.analyses[0].run(loaded.model)
    np.testing.assert_allclose(res.body("bar").angle, 6.0 * res.t, rtol=0, atol=1e-12)
    shown = re.search(r"`pendulum.yaml:8: (.*?)`", section, re.S).group(1).replace("\n", " ")
    path.write_text(block.replace("body_j: bar", "body_j: bra"))
    with pytest.raises(mb.ModelError) as info:
        mb.load(path)
    assert str(info.value).endswith("pendulum.yaml:8: " + shown)
