"""The README's quick start runs as printed and means what it says."""

from __future__ import annotations

import pathlib
import re

import numpy as np

README = pathlib.Path(__file__).resolve().parent.parent / "README.md"


def test_quick_start_runs(tmp_path, monkeypatch, capsys):
    text = README.read_text()
    block = re.search(r"## Quick start\s+```python\n(.*?)```", text, re.S).group(1)
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
    text = README.read_text()
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
    text = README.read_text()
    section = text.split("## Parameter sweeps", 1)[1]
    block = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "__main__"}
    exec(compile(block, "README sweep snippet", "exec"), namespace)
    table = namespace["table"]
    assert [row["status"] for row in table] == ["failed", "ok", "failed", "ok"]
    assert (tmp_path / "sweep_results" / "table.csv").exists()
    assert "SweepTable(4 runs, 2 failed)" in capsys.readouterr().out
