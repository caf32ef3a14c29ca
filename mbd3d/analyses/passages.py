"""Singular positions passed during an implicit integration, found at the cost of a sum of logs.

The generalized-alpha iteration matrix ``S = beta' M + p Cq^T Cq (+ force tangent)`` is factored
every step. In the metric of ``M`` its eigenvalues are ``beta'`` along the free directions and
about ``beta' (1 + r s_i^2)`` along the constrained ones, where ``s_i`` are the singular values of
``Cq`` (scaled by the masses) and ``r = p / beta'`` the relative penalty. So

    D = log|det S| - n log beta' - log det M  ~  sum_i log(1 + r s_i^2)

does not depend on the step and changes smoothly along a regular motion, but dips by
``log(r s^2)`` (tens of units for ``r = 1e8``) where one ``s_i`` passes through zero: a singular
position. The pivots of the LU factors give ``log|det S|`` for free.

A passage is a dip of ``D`` more than ``log(1e4)`` below its highest value over the preceding
steps (one singular value down by a factor 100); it ends when ``D`` is back within ``log(1e2)``.
Its time is that of the lowest ``D``, and the rows of ``Cq`` there with the smallest singular
value name the joints.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from mbd3d.model import constraints
from mbd3d.numerics.linalg import dependent_rows, jacobian_scaling, ranked_rows, summarize

__all__ = ["SingularPassage", "PassageWatch"]

#: entering / leaving a passage: the dip of D below its recent maximum
DIP_ENTER = math.log(1e4)
DIP_LEAVE = math.log(1e2)
#: steps over which the recent maximum of D is taken
WINDOW = 1000


@dataclass(frozen=True)
class SingularPassage:
    """A singular position the motion passed.

    Attributes
    ----------
    time : float
        [s], the step closest to the singular position.
    joints : tuple of str
        Joints and drivers whose constraint rows (nearly) depend on each other there, the
        most involved first (printing a passage shows the first few and how many more).
    rows : tuple of str
        Those rows ("joint.component").
    depth : float
        How far the conditioning indicator dipped, ``log`` of the factor by which the smallest
        singular value's square fell (e.g. 20: by about 5e8).
    """

    time: float
    joints: tuple
    rows: tuple
    depth: float

    def __str__(self) -> str:
        return f"t = {self.time:.6g} s: {summarize(self.joints)}"


class PassageWatch:
    """Follows the indicator ``D`` step by step and collects the passages (see module doc)."""

    def __init__(self, model):
        self.model = model
        self.passages: list[SingularPassage] = []
        self._recent: deque = deque()  # (step, D), decreasing D: a sliding-window maximum
        self._step = 0
        self._episode: dict | None = None

    def step(self, t: float, indicator: float, q: np.ndarray, charts) -> None:
        """Record the accepted step ending at ``t`` with indicator ``D``."""
        self._step += 1
        if not math.isfinite(indicator):
            return
        while self._recent and self._recent[0][0] <= self._step - WINDOW:
            self._recent.popleft()
        reference = self._recent[0][1] if self._recent else None
        episode = self._episode
        if episode is None:
            if reference is not None and indicator < reference - DIP_ENTER:
                self._episode = {"reference": reference, "low": indicator, "t": t,
                                 "q": q.copy(), "charts": None if charts is None else charts.copy()}
                return
        else:
            if indicator < episode["low"]:
                episode.update(low=indicator, t=t, q=q.copy(),
                               charts=None if charts is None else charts.copy())
            if indicator < episode["reference"] - DIP_LEAVE:
                return
            self.close()
        while self._recent and self._recent[-1][1] <= indicator:
            self._recent.pop()
        self._recent.append((self._step, indicator))

    def close(self) -> None:
        """End the open passage, if any (also at the end of the run)."""
        episode, self._episode = self._episode, None
        model = self.model
        if episode is None or not model.n_constraints:
            # without constraint rows nothing can be singular: the dip was the applied forces'
            # tangent in the iteration matrix (a stiff contact opening)
            return
        fr = constraints.frames(model, episode["q"], charts=episode["charts"])
        Cq = constraints.jacobian(model, episode["t"], episode["q"], fr, sparse=False)
        _, groups = dependent_rows(Cq, scaling=jacobian_scaling(model))
        rows = ranked_rows(groups, model.n_constraints)
        self.passages.append(SingularPassage(
            float(episode["t"]), tuple(model.joints_of_rows(rows)),
            tuple(model.row_labels[r] for r in rows), float(episode["reference"] - episode["low"])))
