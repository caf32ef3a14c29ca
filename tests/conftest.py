"""Shared test helpers."""

from __future__ import annotations

import os
import pathlib
import signal
import subprocess
import sys

import pytest

REPO = pathlib.Path(__file__).resolve().parent.parent
VALIDATION_DATA = REPO / "examples" / "data"


@pytest.fixture
def validation_data() -> pathlib.Path:
    """Folder of the published reference series (examples/data/, sources in its README)."""
    return VALIDATION_DATA


@pytest.fixture
def default_sigint():
    """Python's own SIGINT handler (KeyboardInterrupt) for the test, whatever pytest was started
    with: a background job or nohup ignores SIGINT, and a test of Ctrl-C must not depend on
    that. The previous handling is restored afterwards."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def with_default_sigint(command: list[str]) -> list[str]:
    """``command`` started with SIGINT at its default disposition. An ignored SIGINT is
    inherited by child processes: without this, a server started by a test run under nohup
    would ignore the SIGINT meant to stop it."""
    reset = ("import os, signal, sys; signal.signal(signal.SIGINT, signal.SIG_DFL); "
             "os.execvp(sys.argv[1], sys.argv[1:])")
    return [sys.executable, "-c", reset, *command]


def stop_process(process: subprocess.Popen | None, timeout: float = 20.0) -> None:
    """End a process a test started: SIGINT (a Rerun server then writes out what it
    received), and SIGKILL if it is still running ``timeout`` seconds later, so that no
    process or port outlives the test."""
    if process is None or process.poll() is not None:
        return
    process.send_signal(signal.SIGINT)
    try:
        process.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()


try:
    from hypothesis import HealthCheck, settings
    # property-based tests: a short default run, thousands of examples on demand with
    # HYPOTHESIS_PROFILE=thorough
    settings.register_profile("default", max_examples=40, deadline=None, derandomize=True,
                              database=None,
                              suppress_health_check=[HealthCheck.too_slow])
    settings.register_profile("thorough", max_examples=2000, deadline=None,
                              suppress_health_check=[HealthCheck.too_slow])
    settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "default"))
except ImportError:  # the test extra installs it; without it the fuzz tests are skipped
    pass


def pytest_configure(config):
    # tests never open a window
    os.environ.setdefault("MPLBACKEND", "Agg")
    config.addinivalue_line(
        "markers", "compiled_only: too long to run with the compiled core interpreted "
        "(NUMBA_DISABLE_JIT=1); skipped there, run by the compiled suite")


def pytest_collection_modifyitems(config, items):
    """The interpreted suite (NUMBA_DISABLE_JIT=1, which CI runs too) leaves out the tests
    marked compiled_only: the same code, but minutes of pure-Python loops each."""
    import numba

    if not numba.config.DISABLE_JIT:
        return
    skip = pytest.mark.skip(reason="compiled_only: too long interpreted (NUMBA_DISABLE_JIT=1)")
    for item in items:
        if "compiled_only" in item.keywords:
            item.add_marker(skip)
