"""Generalized-alpha's steps at compliant contacts and joint stops: the rules of
:mod:`mbd3d.numerics.compiled.contact_steps` (a step limited to end just past a touch,
retried at half its length when it overlapped one too long, and kept to an impact's step
while an impact lasts), with their memory, for the steps taken from Python; the compiled
loop (:mod:`mbd3d.numerics.compiled.alpha_loop`) runs the same kernels on the same arrays.
"""

from __future__ import annotations

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.model.contacts import contact_group
from mbd3d.numerics.compiled import contact_steps as rules

__all__ = ["ContactSteps"]


class ContactSteps:
    """The contact rules of one integration: ``state`` and ``clock`` (see
    :mod:`mbd3d.numerics.compiled.contact_steps`), and each row's dissipated power [W] at
    the last state measured (``power``); ``work``: the compiled workspace the kernels
    evaluate the frames in."""

    def __init__(self, model, work):
        self.model = model
        self.group = contact_group(model, required=False)
        rows = 0 if self.group is None else len(self.group.names)
        self.work = work
        self.state = np.zeros((rules.STATE_ROWS, rows))
        if rows:
            self.state[rules.MASS] = self.group.masses
            self.state[rules.RIGID] = self.group.rigid
        self.clock = np.zeros(3)
        self.power = np.zeros(rows)

    @property
    def retries(self) -> int:
        """The steps retried shorter so far."""
        return int(self.clock[rules.RETRIES])

    def _checked(self, failed: int, t: float) -> None:
        if failed >= 0:
            raise ModelError(f"{self.group.owners[failed].what}: the shapes' cores meet at "
                             f"t = {t:g} s; the contact normal is undefined")

    def start(self, t: float, q: np.ndarray, qd: np.ndarray, charts) -> None:
        """Begin at the state ``(q, qd)`` at ``t``, no impact under way."""
        if self.group is not None:
            self._checked(rules.start(self.work, self.state, self.clock, t, q, qd, charts,
                                      self.power), t)

    def restart(self, t: float, q: np.ndarray, qd: np.ndarray, charts) -> None:
        """Go on from ``(q, qd)`` at ``t`` (an event's new state, or new charts); the impacts
        of the rows still closed go on."""
        if self.group is not None:
            self._checked(rules.restart(self.work, self.state, self.clock, t, q, qd, charts,
                                        self.power), t)

    def limit(self, t: float) -> float:
        """The longest step [s] the rows allow at ``t`` (inf: none)."""
        return rules.step_limit(self.state, t) if self.group is not None else np.inf

    def retry(self, h: float, q: np.ndarray, qd: np.ndarray, charts) -> float | None:
        """Half the step ``h`` that reached ``(q, qd)`` when it overlapped a touch too long,
        or None: accept it."""
        if self.group is None:
            return None
        shorter = rules.retry(self.work, self.state, self.clock, h, q, qd, charts)
        return shorter if shorter > 0.0 else None

    def accept(self, t: float, q: np.ndarray, qd: np.ndarray, charts) -> bool:
        """The step :meth:`retry` accepted ended at ``t``; whether a row touched or released
        in it (the method's recursion should start again there)."""
        if self.group is None:
            return False
        return rules.accept(self.work, self.state, self.clock, t, q, qd, charts, self.power)
