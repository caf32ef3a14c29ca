"""The sample store an analysis fills as it runs: :class:`ResultsBuffer` (every time point's
state, preallocated) and :func:`run_keeping_results`, which runs an analysis loop so that no
computed time point is lost, whatever ends it."""

from __future__ import annotations

import time
from typing import Any, Callable

import numpy as np

from mbd3d.io.results import Results

__all__ = ["ResultsBuffer", "run_keeping_results"]


class ResultsBuffer:
    """Histories an analysis fills time point by time point, preallocated for all ``t``.

    :meth:`partial` builds the :class:`Results` of the points stored so far, as the analysis
    hands them to observers while it runs and keeps them when it fails.
    """

    def __init__(self, model, analysis: str, t: np.ndarray, stats: dict,
                 with_lam: bool = True):
        self._clock = time.perf_counter
        self._start = self._clock()
        self.model, self.analysis, self.t, self.stats = model, analysis, t, stats
        k, n = len(t), model.n_coordinates
        self.q, self.qd, self.qdd = (np.empty((k, n)) for _ in range(3))
        self.lam = np.empty((k, model.n_constraints)) if with_lam else None
        self.charts = None if model.charts0 is None else np.empty((k,) + model.charts0.shape)
        self.turns = self.contact_forces = self.contact_dissipation = None
        self.contact_friction = None
        self.done = 0

    def store(self, q, qd, qdd, lam=None, chart=None, turns=None, contact_forces=None,
              contact_dissipation=None, contact_friction=None) -> None:
        """The next time point's state (``chart``: its reference rotations, spatial models;
        ``turns``: the charts' quaternions whose signs follow the motion, where tracked;
        ``contact_forces``, ``contact_friction``: the normal forces (r,) and friction (r, 3)
        of the contact rows held as constraints; ``contact_dissipation``: the energy each
        contact row has dissipated)."""
        k = self.done
        self.q[k], self.qd[k], self.qdd[k] = q, qd, qdd
        if self.lam is not None:
            self.lam[k] = lam
        if self.charts is not None:
            self.charts[k] = chart
        if turns is not None:
            if self.turns is None:
                self.turns = np.empty((len(self.t),) + np.shape(turns))
            self.turns[k] = turns
        if contact_forces is not None:
            if self.contact_forces is None:
                self.contact_forces = np.zeros((len(self.t),) + np.shape(contact_forces))
            self.contact_forces[k] = contact_forces
        if contact_friction is not None:
            if self.contact_friction is None:
                self.contact_friction = np.zeros((len(self.t),) + np.shape(contact_friction))
            self.contact_friction[k] = contact_friction
        if contact_dissipation is not None:
            if self.contact_dissipation is None:
                self.contact_dissipation = np.zeros((len(self.t), len(contact_dissipation)))
            self.contact_dissipation[k] = contact_dissipation
        self.done = k + 1

    def partial(self, status: str, message: str) -> Results:
        """The :class:`~mbd3d.Results` of the points stored so far, marked ``status`` with
        ``message`` (why the analysis stopped)."""
        self.stats["wall_time"] = self._clock() - self._start
        k = self.done
        return Results(self.model, self.analysis, self.t[:k], self.q[:k], self.qd[:k],
                       self.qdd[:k], None if self.lam is None else self.lam[:k], status=status,
                       message=message, stats=self.stats,
                       charts=None if self.charts is None else self.charts[:k],
                       turns=None if self.turns is None else self.turns[:k],
                       contact_forces=None if self.contact_forces is None
                       else self.contact_forces[:k],
                       contact_friction=None if self.contact_friction is None
                       else self.contact_friction[:k],
                       contact_dissipation=None if self.contact_dissipation is None
                       else self.contact_dissipation[:k])


def run_keeping_results(loop: Callable[[], tuple[str, str] | None],
                        partial: Callable[[str, str], "Results"],
                        watch: Any = None) -> "Results":
    """Run an analysis ``loop`` so that no computed time point is lost.

    ``loop()`` returns None when it ran to the end, or ``(status, message)`` when it ended
    early by design (an event that stops the run).
    ``partial(status, message)`` builds the results of the time points done so far. On an error
    they are attached to it (``error.results``) before it propagates; on Ctrl-C they are
    returned with status "interrupted". ``watch`` (:class:`mbd3d.io.observers.Watch`) is started
    before the loop and handed the final results however the loop ends, so a recording of a
    failing run keeps everything up to the failure.
    """
    if watch is not None:
        watch.start()
    try:
        ending = loop()
    except KeyboardInterrupt:
        results = partial("interrupted", "interrupted by the user; the results end at the last "
                                         "completed time point")
    except Exception as exc:
        results = partial("failed", str(exc))
        try:
            exc.results = results  # type: ignore[attr-defined]
        except AttributeError:  # exception types with __slots__
            pass
        if watch is not None:
            watch.finish(results, failing=True)
        raise
    else:
        results = partial(*(ending or ("complete", "")))
    if watch is not None:
        watch.finish(results, failing=False)
    return results
