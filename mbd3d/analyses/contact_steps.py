"""Generalized-alpha's steps at compliant contacts and joint stops.

A fixed step longer than a contact lasts steps over most of an impact and returns a wrong
rebound (a ball on a stiff floor, dropped 0.4 m, left at 2.8 m with steps of 10 ms, marked
complete). Each row of the model's contacts and stops has the period of the law's
oscillation in the impact it has or is heading for, ``T`` (at its stiffest, from the closing
speed: :meth:`~mbd3d.model.contacts._Contacts.impact_periods`), and three rules resolve an
impact while leaving the step alone elsewhere:

- a row heading for a touch limits the step to end just past it, by :data:`BAND` of an
  impact's step ``T /`` :data:`PER_PERIOD` (when its gap closes at its rate and the rate's
  own rate over the last step): a stiff contact entered deeper than that within one implicit
  step would store energy no step took out;
- a step that touches neither that little past its end nor with a step of ``T /``
  :data:`PER_PERIOD` or less is retried at half the length (an implicit step's end holds the
  contact force already, so it cannot say where the touch was; at most :data:`TRIES`
  times);
- while an impact lasts, no step is longer than ``T /`` :data:`PER_PERIOD`; a contact that
  stays closed longer than :data:`IMPACT_PERIODS` periods is resting, and the nominal step
  comes back (the method's damping of high frequencies keeps it stable).

After a step in which a row touched or released, the recursion starts again from consistent
accelerations (as after an event): the force jumped inside that step, and the method's
algorithmic accelerations would carry the jump into the next, long step.
"""

from __future__ import annotations

import numpy as np

from mbd3d.model import constraints
from mbd3d.model.contacts import contact_group
from mbd3d.numerics.compiled import contacts as kernel
from mbd3d.numerics.compiled.integration import first_switch

__all__ = ["ContactSteps", "PER_PERIOD", "IMPACT_PERIODS", "BAND", "TRIES"]

#: steps per period of an impact's oscillation; how many periods an impact lasts at most
PER_PERIOD, IMPACT_PERIODS = 100, 3
#: a touch lies within BAND of an impact step before its step's end, or its step is an
#: impact step (at most TRIES retries)
BAND, TRIES = 1e-3, 12


class ContactSteps:
    """The contact rules of one integration, with each row's state at the last accepted
    step's end: its switching function (``before``, positive while the law pushes), gap and
    gap rate, the time of its touch and its impact period ``T``."""

    def __init__(self, model):
        self.model = model
        self.group = contact_group(model, required=False)
        self.tries, self.t = 0, None
        #: the frames of the last state asked about (a step's end is asked about by the
        #: retry, the acceptance and the dissipation), and the report of the last measured
        self._key, self._fr, self.report = None, None, None

    def start(self, t: float, q: np.ndarray, qd: np.ndarray, charts) -> None:
        """Begin at the state ``(q, qd)`` at ``t``, no impact under way."""
        if self.group is None:
            return
        rows = len(self.group.names)
        self.touch, self.period = np.full(rows, -np.inf), np.full(rows, np.inf)
        self.restart(t, q, qd, charts)

    def restart(self, t: float, q: np.ndarray, qd: np.ndarray, charts) -> None:
        """Go on from ``(q, qd)`` at ``t`` (an event's new state, or new charts); the impacts
        of the rows still closed go on."""
        if self.group is None:
            return
        self.before, self.t = self._switches(q, qd, charts), None
        self._measure(t, q, qd, charts, ~(self.before > 0.0))

    def limit(self, t: float) -> float:
        """The longest step [s] the rows allow at ``t`` (inf: none)."""
        if self.group is None:
            return np.inf
        closed = self.before > 0.0
        lasting = closed & (t - self.touch < IMPACT_PERIODS * self.period)
        # just past the touch, by a little of an impact's step
        reach = self._touch_in() + 0.5 * BAND * self.period / PER_PERIOD
        return float(min(np.min(self.period[lasting], initial=np.inf) / PER_PERIOD,
                         np.min(reach[~closed], initial=np.inf)))

    def _touch_in(self) -> np.ndarray:
        """Per row, when its gap closes [s] at its rate and the rate's own rate (from the
        last two steps), ``gap + rate s + acc s^2 / 2 = 0`` (inf: it does not close)."""
        gap, rate, acc = np.maximum(self.gap, 0.0), self.rate, self.acc
        with np.errstate(divide="ignore", invalid="ignore"):  # a group's gap is inf
            root = rate * rate - 2.0 * acc * gap
            s = 2.0 * gap / (-rate + np.sqrt(np.maximum(root, 0.0)))
        return np.where((root >= 0.0) & (s >= 0.0) & np.isfinite(s), s, np.inf)

    def retry(self, h: float, q: np.ndarray, qd: np.ndarray, charts) -> float | None:
        """Half the step ``h`` that reached ``(q, qd)`` when it touched neither within
        :data:`BAND` of an impact step ``T /`` :data:`PER_PERIOD` before its end nor with a
        step that short, or None: accept it."""
        if self.group is None:
            return None
        self.after = self._switches(q, qd, charts)
        touched = ~(self.before > 0.0) & (self.after > 0.0)
        if not np.any(touched) or self.tries >= TRIES:
            return None
        impact_step = np.min(self.period[touched]) / PER_PERIOD
        past = (1.0 - first_switch(self.before, self.after, 0.0)) * h  # how long it overlapped
        if past <= BAND * impact_step or h <= impact_step:
            return None
        self.tries += 1
        return 0.5 * h

    def accept(self, t: float, q: np.ndarray, qd: np.ndarray, charts) -> bool:
        """The step :meth:`retry` accepted ended at ``t``: the rows that closed begin an
        impact (its period from the closing speed before the touch), those open are
        measured again. Whether a row touched or released in the step: the force jumped in
        it, and the method's recursion (its accelerations) should start again there."""
        if self.group is None:
            return False
        was_apart = ~(self.before > 0.0)
        closed = (self.after > 0.0) & was_apart
        switched = bool(np.any((self.after > 0.0) == was_apart))
        self.touch[closed] = t
        self.before, self.tries = self.after, 0
        self._measure(t, q, qd, charts, ~(self.after > 0.0), was_apart)
        return switched

    def _measure(self, t, q, qd, charts, apart: np.ndarray, was_apart=None) -> None:
        """Gaps and rates at ``(q, qd)`` at ``t``, and the rates' rates over the last step
        where the rows were ``was_apart`` at its start too (else 0); the rows ``apart`` get
        the period of the impact their closing speed heads for, and no touch."""
        report = self.report = self.group.states(self.model, self._frames(q, qd, charts))
        gap, rate = report[:, kernel.GAP], report[:, kernel.GAP_RATE]
        self.acc = np.zeros_like(rate)
        if was_apart is not None and self.t is not None and t > self.t:
            both = was_apart & apart
            self.acc[both] = (rate[both] - self.rate[both]) / (t - self.t)
        self.t, self.gap, self.rate = t, gap, rate
        heading = self.group.impact_periods(np.zeros_like(self.gap), self.rate)
        self.period[apart], self.touch[apart] = heading[apart], -np.inf

    def _switches(self, q, qd, charts) -> np.ndarray:
        return self.group.switches(self.model, self._frames(q, qd, charts))

    def _frames(self, q, qd, charts):
        key = (q.tobytes(), qd.tobytes(), None if charts is None else charts.tobytes())
        if key != self._key:
            self._key, self._fr = key, constraints.frames(self.model, q, qd, charts)
        return self._fr

    def power(self) -> np.ndarray:
        """Each row's dissipated power [W] at the state :meth:`accept` or :meth:`restart`
        last measured."""
        return self.report[:, kernel.DISSIPATION]
