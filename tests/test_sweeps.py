"""Parameter sweeps (mbd3d.sweeps): a LocalCluster of two worker processes on loopback gives
the serial run's table; a killed worker, an interrupted sweep and failing runs lose nothing;
the metrics agree with the slider-crank's closed form."""

from __future__ import annotations

import csv
import math
import os
import signal

import numpy as np
import pytest

from mbd3d.errors import MBDError
from mbd3d.mechanisms import slider_crank, slider_crank_positions
from mbd3d.sweeps import Analysis, grid, monte_carlo, sweep
from slider_crank_oracle import SliderCrankOracle

distributed = pytest.importorskip("distributed")

CRANK = 0.12
T = np.linspace(0.0, 0.5, 51)
ANALYSIS = Analysis("inverse dynamics", T)
#: rods of 0.1 m cannot reach the slider line from the crank pin at 65 degrees: those fail
POINTS = grid(speed=[5.0, 20.0], rod=[0.1, 0.26, 0.4])


def factory(speed: float, rod: float, kill_marker: str = ""):
    if kill_marker and not os.path.exists(kill_marker):
        # the first attempt dies with its worker process, as an out-of-memory kill would
        open(kill_marker, "w").close()
        os.kill(os.getpid(), signal.SIGKILL)
    return slider_crank(crank_length=CRANK, rod_length=rod, crank_speed=speed)


def peak_slider_speed(results) -> float:
    return float(np.max(np.abs(results.body("slider").velocity[:, 0])))


def peak_torque(results) -> float:
    return float(np.max(np.abs(results.driver("motor").effort)))


METRICS = {"peak_speed": peak_slider_speed, "peak_torque": peak_torque}


def closed_form_peak_speed(speed: float, rod: float) -> float:
    """The largest slider speed over T from the closed-form geometry (dx/dphi * phi')."""
    dx_dphi, _ = SliderCrankOracle(r=CRANK, l=rod).slider_x_derivatives(
        math.radians(65.0) + speed * T)
    return float(np.max(np.abs(speed * dx_dphi)))


@pytest.fixture(scope="module")
def serial_table(tmp_path_factory):
    return sweep(factory, POINTS, ANALYSIS, METRICS, tmp_path_factory.mktemp("serial"),
                 backend="serial", progress=False)


def test_serial_metrics_match_the_closed_form_and_failures_name_their_point(serial_table):
    rows = {(row["speed"], row["rod"]): row for row in serial_table}
    for (speed, rod), row in rows.items():
        if rod < 0.11:
            assert row["status"] == "failed"
            assert "rod of 0.1 m cannot reach" in row["error"]
            assert row["error"].startswith("building the model")
        else:
            assert row["status"] == "ok", row["error"]
            assert row["peak_speed"] == pytest.approx(closed_form_peak_speed(speed, rod),
                                                      rel=1e-9)
    assert serial_table.summary["failed"] == 2 and serial_table.summary["ok"] == 4
    assert np.isnan(serial_table.column("peak_torque")[0])
    with pytest.raises(MBDError, match="rod=0.1.*failed"):
        serial_table.results(serial_table.failed[0])


def test_local_cluster_of_two_workers_gives_the_serial_table(serial_table, tmp_path):
    table = sweep(factory, POINTS, ANALYSIS, METRICS, tmp_path, workers=2, progress=False)
    assert table.summary["workers"] == 2
    for parallel, serial in zip(table, serial_table):
        assert {k: v for k, v in parallel.items() if k != "wall_time"} == \
               {k: v for k, v in serial.items() if k != "wall_time"}
    # the table on disk holds the same rows
    with open(tmp_path / "table.csv") as f:
        stored = list(csv.DictReader(f))
    assert [row["key"] for row in stored] == [row["key"] for row in table]
    assert float(stored[1]["peak_speed"]) == table.rows[1]["peak_speed"]


def test_a_killed_worker_loses_no_result(serial_table, tmp_path):
    marker = str(tmp_path / "killed-once")
    points = [{**p, "kill_marker": marker if i == 1 else ""} for i, p in enumerate(POINTS)]
    table = sweep(factory, points, ANALYSIS, METRICS, tmp_path / "sweep", workers=2,
                  progress=False)
    assert os.path.exists(marker)  # a worker did die
    assert [row["status"] for row in table] == [row["status"] for row in serial_table]
    assert table.column("peak_torque") == pytest.approx(serial_table.column("peak_torque"),
                                                        nan_ok=True)


def test_interrupted_sweep_resumes_with_only_the_missing_points(tmp_path):
    calls = []
    # a switch the factory reads, not a value it captures: a factory that captures another
    # value is another factory, and its points run again (see the next test)
    interrupt = {"on": True}

    def counting_factory(speed, rod):
        calls.append((speed, rod))
        if len(calls) == 4 and interrupt["on"]:
            raise KeyboardInterrupt  # Ctrl-C while the fourth model is built
        return factory(speed, rod)

    first = sweep(counting_factory, POINTS, ANALYSIS, METRICS, tmp_path, backend="serial",
                  progress=False)
    assert first.summary["interrupted"] and len(first) == 3
    with open(tmp_path / "table.csv") as f:
        assert len(list(csv.DictReader(f))) == 3  # a valid table of what was done
    interrupt["on"], calls[:] = False, []
    second = sweep(counting_factory, POINTS, ANALYSIS, METRICS, tmp_path, backend="serial",
                   progress=False)
    assert calls == [(p["speed"], p["rod"]) for p in POINTS[3:]]
    assert second.summary["skipped"] == 3 and len(second) == len(POINTS)
    assert not second.summary["interrupted"]
    # failed points are finished too; retry_failed runs them again
    calls[:] = []
    sweep(counting_factory, POINTS, ANALYSIS, METRICS, tmp_path, backend="serial",
          retry_failed=True, progress=False)
    assert sorted(calls) == sorted((p["speed"], p["rod"]) for p in POINTS if p["rod"] < 0.11)


def test_a_run_is_the_same_run_in_another_session_and_another_after_an_edit(tmp_path):
    """A factory's identity holds across processes (a comprehension in it once made it differ:
    its code object's repr holds a memory address), and changes with a value it captures."""
    import subprocess
    import sys

    code = ("import sys; sys.path.insert(0, sys.argv[1]); from mbd3d.sweeps import _identity\n"
            "def factory(rods):\n    return [r * 2 for r in rods]\n"
            "print(_identity(factory))")
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    seen = {subprocess.run([sys.executable, "-c", code, root], capture_output=True, text=True,
                           check=True).stdout for _ in range(2)}
    assert len(seen) == 1

    def made_with(rod_length):
        return lambda speed: factory(speed, rod_length)
    points = grid(speed=[5.0])
    sweep(made_with(0.3), points, ANALYSIS, METRICS, tmp_path, backend="serial", progress=False)
    again = sweep(made_with(0.3), points, ANALYSIS, METRICS, tmp_path, backend="serial",
                  progress=False)
    edited = sweep(made_with(0.4), points, ANALYSIS, METRICS, tmp_path, backend="serial",
                   progress=False)
    assert again.summary["skipped"] == 1 and edited.summary["skipped"] == 0
    assert edited.rows[0]["peak_speed"] == pytest.approx(closed_form_peak_speed(5.0, 0.4),
                                                        rel=1e-9)


def test_full_results_are_kept_on_request(tmp_path):
    table = sweep(factory, POINTS[1:2], ANALYSIS, METRICS, tmp_path, keep_results=True,
                  backend="serial", progress=False)
    arrays = table.results(table.rows[0])
    assert arrays["q"].shape == (len(T), 9)
    assert np.array_equal(arrays["t"], T)


def test_without_dask_it_runs_serially_and_says_how_to_get_more(monkeypatch, tmp_path, capsys):
    import mbd3d.sweeps as sweeps
    monkeypatch.setattr(sweeps, "_dask_available", lambda: False)
    table = sweep(factory, POINTS[1:2], ANALYSIS, METRICS, tmp_path)
    assert table.rows[0]["status"] == "ok"
    assert 'pip install "mbd3d[distributed]"' in capsys.readouterr().err
    with pytest.raises(MBDError, match="Dask is not installed"):
        sweep(factory, POINTS[1:2], ANALYSIS, METRICS, tmp_path, backend="dask")


def test_bad_sweep_input_is_named(tmp_path):
    with pytest.raises(MBDError, match="parameter 'rod' = nan"):
        sweep(factory, [{"speed": 1.0, "rod": float("nan")}], ANALYSIS, METRICS, tmp_path)
    with pytest.raises(MBDError, match="metric 'peak' must be a function"):
        sweep(factory, POINTS, ANALYSIS, {"peak": 3.0}, tmp_path)
    with pytest.raises(MBDError, match="unknown kind 'dynamics'"):
        Analysis("dynamics", T)
    with pytest.raises(MBDError, match="parameter 'rod' must be"):
        monte_carlo(3, seed=0, rod=(0.3, 0.2))


def test_monte_carlo_samples_are_reproducible_from_the_seed():
    from scipy.stats import norm
    a = monte_carlo(50, seed=7, rod=(0.25, 0.27), speed=norm(10.0, 0.5))
    b = monte_carlo(50, seed=7, rod=(0.25, 0.27), speed=norm(10.0, 0.5))
    assert a == b and a != monte_carlo(50, seed=8, rod=(0.25, 0.27), speed=norm(10.0, 0.5))
    speeds = np.array([s["speed"] for s in a])
    assert abs(speeds.mean() - 10.0) < 4 * 0.5 / math.sqrt(50)


def test_monte_carlo_draws_from_the_whole_distribution_given():
    """2000 samples of each kind against their distribution (Kolmogorov-Smirnov, seed
    fixed): a (low, high) pair is uniform over all of it, a frozen distribution and a
    function of the generator are drawn from as given."""
    from scipy.stats import kstest, norm, uniform
    samples = monte_carlo(2000, seed=3, rod=(0.25, 0.27), speed=norm(10.0, 0.5),
                          offset=lambda rng: rng.exponential(2.0))
    rods = np.array([s["rod"] for s in samples])
    assert 0.25 <= rods.min() < 0.2501 and 0.2699 < rods.max() <= 0.27
    assert kstest(rods, uniform(0.25, 0.02).cdf).pvalue > 0.01
    assert kstest([s["speed"] for s in samples], norm(10.0, 0.5).cdf).pvalue > 0.01
    assert kstest([s["offset"] for s in samples], "expon", args=(0.0, 2.0)).pvalue > 0.01


def test_table_reads_into_pandas_and_writes_parameters_as_given(serial_table, tmp_path):
    df = serial_table.to_pandas()
    assert list(df.columns) == serial_table.columns and len(df) == len(serial_table)
    np.testing.assert_array_equal(df["peak_speed"].to_numpy(dtype=float),
                                  serial_table.column("peak_speed"))
    # linspace's 0.15000000000000002 is written as the 0.15 the user meant
    rods = grid(rod=np.linspace(0.1, 0.2, 3))
    path = tmp_path / "table.csv"
    table = sweep(factory, [dict(p, speed=5.0) for p in rods], ANALYSIS, METRICS, tmp_path,
                  backend="serial", progress=False)
    table.to_csv(path)
    with open(path, newline="") as f:
        written = [row["rod"] for row in csv.DictReader(f)]
    assert written == ["0.1", "0.15", "0.2"]


def test_a_changed_analysis_or_an_added_metric_never_returns_old_values(tmp_path):
    """The run's key covers the analysis (kind, times, options) and the factory: resuming on
    the same folder after changing the analysis runs again instead of returning the old
    values marked ok; a metric added on resume is computed, not left NaN."""
    points = grid(speed=[5.0], rod=[0.3])
    short = Analysis("inverse dynamics", np.linspace(0.0, 0.2, 21))
    long = Analysis("inverse dynamics", np.linspace(0.0, 2.0, 201))
    final = {"final slider x": lambda r: float(r.body("slider").position[-1, 0])}
    sweep(factory, points, short, final, tmp_path, backend="serial", progress=False)
    second = sweep(factory, points, long, final, tmp_path, backend="serial", progress=False)
    assert second.summary["skipped"] == 0
    slider_at_2s = slider_crank_positions(math.radians(65.0) + 5.0 * 2.0, CRANK, 0.3)[2]
    assert second.rows[0]["final slider x"] == pytest.approx(slider_at_2s[0], rel=1e-12)
    more = {**final, "final crank angle": lambda r: float(r.body("crank").angle[-1])}
    third = sweep(factory, points, long, more, tmp_path, backend="serial", progress=False)
    assert third.rows[0]["final crank angle"] == pytest.approx(math.radians(65.0) + 5.0 * 2.0)
    assert third.rows[0]["status"] == "ok"


def test_an_unreadable_run_file_is_named_and_its_point_runs_again(tmp_path):
    points = grid(speed=[5.0], rod=[0.3])
    sweep(factory, points, ANALYSIS, METRICS, tmp_path, backend="serial", progress=False)
    (run_file,) = (tmp_path / "runs").glob("*.json")
    run_file.write_text('{"status": "ok", "metrics": [], "error": null, "wall_time": 0.1}')
    with pytest.warns(UserWarning, match=f"run file '{run_file}' does not hold a run"):
        table = sweep(factory, points, ANALYSIS, METRICS, tmp_path, backend="serial",
                      progress=False)
    assert table.summary["skipped"] == 0 and table.rows[0]["status"] == "ok"


def test_one_folder_holds_one_sweep_at_a_time(tmp_path):
    from mbd3d.sweeps import _FolderLock

    with _FolderLock(str(tmp_path)):  # another sweep at work in the folder
        with pytest.raises(MBDError, match="is in use by another sweep"):
            sweep(factory, grid(speed=[5.0], rod=[0.3]), ANALYSIS, METRICS, tmp_path,
                  backend="serial", progress=False)
    sweep(factory, grid(speed=[5.0], rod=[0.3]), ANALYSIS, METRICS, tmp_path,
          backend="serial", progress=False)  # free again


def test_values_and_options_are_taken_as_meant(tmp_path):
    # 1 and 1.0 are one point
    with pytest.raises(MBDError, match="more than once"):
        sweep(factory, [{"speed": 5, "rod": 0.3}, {"speed": 5.0, "rod": 0.3}], ANALYSIS,
              METRICS, tmp_path, backend="serial", progress=False)
    sweep(factory, [{"speed": 5, "rod": 0.3}], ANALYSIS, METRICS, tmp_path, backend="serial",
          progress=False)
    again = sweep(factory, [{"speed": 5.0, "rod": 0.3}], ANALYSIS, METRICS, tmp_path,
                  backend="serial", progress=False)
    assert again.summary["skipped"] == 1
    # a 0-d NumPy array is a number
    table = sweep(factory, grid(speed=[5.0], rod=[0.3]), ANALYSIS,
                  {"peak": lambda r: np.max(np.abs(r.body("slider").velocity[:, 0]),
                                            keepdims=False).reshape(())},
                  tmp_path / "arrays", backend="serial", progress=False)
    assert table.rows[0]["status"] == "ok" and isinstance(table.rows[0]["peak"], float)
    # bad options are refused once, when the analysis is described
    with pytest.raises(MBDError, match="takes no option 'rtl'"):
        Analysis("forward dynamics", T, {"rtl": 1e-9})
    with pytest.raises(MBDError, match="method must be one of"):
        Analysis("forward dynamics", T, {"method": "Euler"})


def test_an_interrupted_sweep_reports_the_workers_it_had(tmp_path, monkeypatch):
    import distributed

    real = distributed.as_completed

    def interrupted_after_one(futures):
        for k, future in enumerate(real(futures)):
            if k == 1:
                raise KeyboardInterrupt
            yield future
    monkeypatch.setattr(distributed, "as_completed", interrupted_after_one)
    table = sweep(factory, POINTS, ANALYSIS, METRICS, tmp_path, workers=2, backend="dask",
                  progress=False)
    assert table.summary["interrupted"] and table.summary["workers"] == 2
