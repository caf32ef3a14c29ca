"""Watching an analysis while it runs: a progress bar in a terminal, live viewers.

Every analysis takes ``observers=[...]``. An observer is told when the analysis starts, sees the
results grow (at most every ``interval`` seconds of wall time, so watching costs little), and
gets the final results however the analysis ends: complete, failed or interrupted. The live
Rerun recorder of the ``viewer`` package is one; :class:`ProgressBar` is another, shown by
default when the analysis runs in a terminal.
"""

from __future__ import annotations

import os
import sys
import time as _time
import warnings
from typing import TYPE_CHECKING, Callable, Sequence, TextIO

import numpy as np

from mbd3d.errors import ModelError

if TYPE_CHECKING:
    from mbd3d.io.results import Results

__all__ = ["Observer", "ProgressBar"]


class Observer:
    """Base class of what watches an analysis; override the methods you need.

    Attributes
    ----------
    interval : float
        Smallest wall-clock time [s] between two calls of :meth:`update`.
    """

    interval: float = 0.25

    def start(self, model, times: np.ndarray, analysis: str) -> None:
        """The analysis ``analysis`` of ``model`` over output ``times`` [s] begins.

        Parameters
        ----------
        model : Model
        times : (k,) ndarray
            The output times [s].
        analysis : str
            The analysis' name (``"forward dynamics"``, ...).
        """

    def update(self, results: "Results", time: float, steps: int) -> None:
        """Progress: ``results`` holds the output times done so far (status "running"),
        ``time`` [s] is how far the solver has got, ``steps`` how many steps it took.

        Parameters
        ----------
        results : Results
            The output times done so far.
        time : float
            How far the solver has got [s].
        steps : int
            Steps taken so far.
        """

    def finish(self, results: "Results") -> None:
        """The analysis ended; ``results.status`` says how ("complete", "failed",
        "interrupted").

        Parameters
        ----------
        results : Results
            All of the run's results.
        """


class ProgressBar(Observer):
    """A one-line progress bar: simulated time, steps per second and time left.

    Parameters
    ----------
    stream : text stream, optional
        Where to draw (default ``sys.stderr``).
    delay : float
        Wall time [s] before the bar first appears, so that short analyses stay quiet.
    """

    interval = 0.1

    def __init__(self, stream: TextIO | None = None, delay: float = 0.5):
        self.stream = stream
        self.delay = delay
        self._shown = False

    def start(self, model, times: np.ndarray, analysis: str) -> None:
        self._label = f"{analysis} of '{model.name}'"
        self._t0, self._t1 = float(times[0]), float(times[-1])
        self._wall0 = _time.perf_counter()
        self._shown = False

    def _draw(self, time: float, steps: int, end: str = "") -> None:
        elapsed = _time.perf_counter() - self._wall0
        span = self._t1 - self._t0
        fraction = 1.0 if span <= 0 else min(max((time - self._t0) / span, 0.0), 1.0)
        filled = int(round(24 * fraction))
        rate = steps / elapsed if elapsed > 0 else 0.0
        left = elapsed * (1.0 - fraction) / fraction if fraction > 0 else float("nan")
        eta = "--:--" if not np.isfinite(left) else f"{int(left) // 60}:{int(left) % 60:02d}"
        line = (f"\r{self._label} [{'#' * filled}{'-' * (24 - filled)}] {100 * fraction:3.0f}% "
                f"t = {time:.4g}/{self._t1:.4g} s, {rate:,.0f} steps/s, {eta} left")
        stream = self.stream or sys.stderr
        stream.write(line + end)
        stream.flush()
        self._shown = True

    def update(self, results: "Results", time: float, steps: int) -> None:
        if _time.perf_counter() - self._wall0 >= self.delay:
            self._draw(time, steps)

    def finish(self, results: "Results") -> None:
        if self._shown:
            done = float(results.t[-1]) if len(results) else self._t0
            self._draw(done, int(results.stats.get("steps", len(results))),
                       end=f"  {results.status}\n")


def _progress_wanted(progress: bool | None) -> bool:
    if progress is not None:
        return bool(progress)
    if os.environ.get("MBD3D_PROGRESS", "").lower() in ("0", "false", "no", "off"):
        return False
    try:
        return sys.stderr is not None and sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


class Watch:
    """What an analysis loop calls: throttles and fans out the observer calls."""

    def __init__(self, observers: Sequence[Observer] | None, progress: bool | None, model,
                 times: np.ndarray, analysis: str, partial: Callable[[str, str], "Results"]):
        items = list(observers or ())
        for obs in items:
            if not all(callable(getattr(obs, m, None)) for m in ("start", "update", "finish")):
                raise ModelError(f"observers must have start(), update() and finish() methods "
                                 f"(see mbd3d.Observer), got {obs!r}")
        if _progress_wanted(progress):
            items.append(ProgressBar())
        self.observers = items
        self.model, self.times, self.analysis, self.partial = model, times, analysis, partial
        self._due = [0.0] * len(items)
        self._next = float("inf") if not items else 0.0

    def start(self) -> None:
        now = _time.perf_counter()
        for i, obs in enumerate(self.observers):
            obs.start(self.model, self.times, self.analysis)
            self._due[i] = now + getattr(obs, "interval", Observer.interval)
        self._next = min(self._due, default=float("inf"))

    def tick(self, time: float, steps: int) -> None:
        """Called by the loop after every step; costs one clock reading when nothing is due."""
        now = _time.perf_counter()
        if now < self._next:
            return
        results = self.partial("running", "")
        for i, obs in enumerate(self.observers):
            if now >= self._due[i]:
                obs.update(results, float(time), int(steps))
                self._due[i] = _time.perf_counter() + getattr(obs, "interval", Observer.interval)
        self._next = min(self._due)

    def finish(self, results: "Results", failing: bool) -> None:
        """Hand the final results to every observer. While an error propagates, an observer's
        own failure is reported as a warning so that it does not hide the original error."""
        for obs in self.observers:
            if not failing:
                obs.finish(results)
                continue
            try:
                obs.finish(results)
            except Exception as exc:  # noqa: BLE001 - the analysis error matters more
                warnings.warn(f"observer {obs!r} failed while the analysis stopped: {exc}",
                              RuntimeWarning, stacklevel=2)
