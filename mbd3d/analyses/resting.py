"""Rigid contacts at rest: rows held closed between a rest and a release.

A rigid row comes to rest (:mod:`mbd3d.analyses.impacts`) where it touches, opening slower than
its rest speed, while the free motion presses it closed: bouncing on, it would make infinitely
many ever shorter impacts in a finite time. From there it is *held*: a one-sided constraint on
its gap's acceleration. With ``G`` the held rows' gap rows (``g' = G qd``), ``qdd0`` and
``lam0`` the joints' accelerations and multipliers without them and ``[X; Y]`` the augmented
system's response to a unit force on each row (as for the impacts)::

    qdd = qdd0 + X f,   lam = lam0 + Y f,   0 <= f  _|_  w = W f + b >= 0,
    W = G X,   b = G qdd0 + (dG/dq qd) qd

``f`` are the rows' normal forces [N; a stop of a turning coordinate: N m] and ``w`` their gaps'
accelerations. The complementarity problem is solved exactly by the impacts' active set
(:func:`mbd3d.analyses.impacts.impulses`), so a row whose force would pull lets go within the
right-hand side; its release event, ``f - w / W_kk`` [N] crossing zero downwards (continuous
through the switch), locates where: there the row is released, and its gap watched again for
the next touch. ``(dG/dq qd) qd`` is
:meth:`RigidContacts.convective <mbd3d.analyses.impacts.RigidContacts.convective>`.

Like the joints, the held rows drift under integration: a step that leaves one open or closing
by more than ``constraint_tol`` (of the model's length scale) is projected back (mass-weighted,
the joints holding). Held rows are evaluated in Python at each right-hand side (the explicit
methods' callback); generalized-alpha does not hold rows yet, and stops where one comes to rest.
"""

from __future__ import annotations

import numpy as np

from mbd3d.analyses.accelerations import consistent_accelerations
from mbd3d.analyses.impacts import CLOSING, PRESSED, RigidContacts, impulses
from mbd3d.analyses.kinematics import project_state
from mbd3d.io.history import energies

__all__ = ["HeldRows"]

#: rounds of the position projection of the held rows (each one Newton step on their gaps)
_ROUNDS = 4


class HeldRows:
    """The rigid rows of one run held closed (``mask``), their forces and their releases.

    ``rigid``: the run's :class:`~mbd3d.analyses.impacts.RigidContacts`, whose gaps, gap rows
    and impact response these use; ``tol``: the projection's tolerance (of the model's length
    scale, as the joints'). The rests and releases are recorded in ``stats["rests"]``."""

    def __init__(self, rigid: RigidContacts, tol: float, stats: dict):
        self.rigid, self.model, self.tol = rigid, rigid.model, tol
        self.mask = np.zeros(len(rigid), dtype=bool)
        self.records = stats.setdefault("rests", [])
        self._key, self._solution = None, None

    def any(self) -> bool:
        return bool(np.any(self.mask))

    def accelerations(self, t: float, q: np.ndarray, qd: np.ndarray, qdd0: np.ndarray,
                      lam0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(qdd, lam)`` at ``(t, q, qd)`` with the held rows' forces (module doc), from the
        joints' ``qdd0`` and ``lam0`` there."""
        return self._solve(t, q, qd, self.mask, qdd0, lam0)[:2]

    def forces(self, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """The normal force of every rigid row at ``(t, q, qd)``: zero where not held."""
        return self._solve(t, q, qd, self.mask)[2]

    def release_value(self, index: int, t: float, q: np.ndarray, qd: np.ndarray) -> float:
        """The release event's function of rigid row ``index``: ``f - w / W_kk`` [N] while
        held (positive while it presses), 1 otherwise."""
        if not self.mask[index]:
            return 1.0
        _, _, f, w, diag = self._solve(t, q, qd, self.mask)
        return float(f[index] - w[index] / diag[index])

    def release(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The release events' action: the held rows that no longer press let go."""
        _, _, f, w, diag = self._solve(t, q, qd, self.mask)
        self.let_go(t, self.mask & ~self._pressing(t, q, qd, f, diag))
        self.rigid.watch(q, qd)
        return q, qd

    def let_go(self, t: float, rows: np.ndarray) -> None:
        """Release the held ``rows`` at ``t`` (recorded)."""
        self._record(t, "release", rows & self.mask)
        self.mask = self.mask & ~rows

    def hold(self, t: float, q: np.ndarray, qd: np.ndarray, candidates: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
        """Hold the ``candidates`` (touching, slow) that the free motion presses closed, with
        the rows held already: their rates and gaps are set to zero (the kinetic energy this
        takes, at most what a bounce below the rest speed carries, is recorded)."""
        rows = candidates | self.mask
        rigid = self.rigid
        _, rate = rigid.states(q, qd)
        # pressed at the state as it is: the slow rates' part of the gaps' accelerations is
        # below what the threshold tells apart
        _, _, f, _, diag = self._solve(t, q, qd, rows)
        held = self._pressing(t, q, qd, f, diag) & rows
        if not np.any(held):
            self.let_go(t, self.mask)
            return q, qd
        before = self._kinetic(q, qd)
        q, qd = self.settle(t, q, qd, held, force=True)
        # what the settling takes (>= 0 but for rounding, where nothing moved)
        lost, new = max(before - self._kinetic(q, qd), 0.0), held & ~self.mask
        # rows held already that an impact left opening slowly: their bounce is taken too
        bounced = held & self.mask & (np.abs(rate) > CLOSING * rigid.rest_speed)
        if np.any(new) or np.any(bounced):
            self._record(t, "rest", new | bounced, lost)
        self.let_go(t, self.mask & ~held)
        self.mask = held
        return q, qd

    def _record(self, t: float, event: str, rows: np.ndarray, energy_lost: float = 0.0
                ) -> None:
        """Note the ``rows`` coming to rest or let go at ``t``, with the kinetic energy [J]
        their settling took."""
        if np.any(rows):
            self.records.append({"time": t, "event": event,
                                 "contacts": [self.rigid.names[k] for k in np.flatnonzero(rows)],
                                 "energy_lost": float(energy_lost)})

    def settle(self, t: float, q: np.ndarray, qd: np.ndarray, rows: np.ndarray | None = None,
               force: bool = False, tol: float | None = None
               ) -> tuple[np.ndarray, np.ndarray] | None:
        """The state with the held ``rows`` (default all held) closed and idle, the joints
        holding (mass-weighted least change); None when they have not drifted beyond ``tol``
        (default the run's; relative to the model's length scale) unless ``force``."""
        rows = self.mask if rows is None else rows
        tol = self.tol if tol is None else tol
        rigid, model = self.rigid, self.model
        scale = rigid.scale[rows]
        gap, rate = rigid.states(q, qd)
        drift = max(np.max(np.abs(gap[rows]) / scale, initial=0.0),
                    np.max(np.abs(rate[rows]) / scale, initial=0.0))
        if not np.any(rows) or (drift <= tol and not force):
            return None if not force else (q, qd)
        chart, redundant = rigid.chart(), rigid.redundant()
        for _ in range(_ROUNDS):
            g = rigid.states(q, qd)[0][rows]
            if np.max(np.abs(g) / scale) <= 1e-3 * tol:
                break
            q = q + self._correction(t, q, rows, -g)
            q, qd = project_state(model, t, q, qd, 1e-3 * tol, chart, redundant)
        qd = qd + self._correction(t, q, rows, -rigid.states(q, qd)[1][rows])
        return q, qd

    def _correction(self, t: float, q: np.ndarray, rows: np.ndarray, change: np.ndarray
                    ) -> np.ndarray:
        """The mass-weighted least change ``X mu`` of the coordinates (or rates) that changes
        the ``rows``' gaps (or rates) by ``change``, the joints holding to first order."""
        rigid = self.rigid
        G = rigid.gap_rows(q, rows)
        X = rigid.response(t, q, G)[:self.model.n_coordinates]
        return X @ np.linalg.lstsq(G @ X, change, rcond=1e-12)[0]

    def _pressing(self, t: float, q: np.ndarray, qd: np.ndarray, f: np.ndarray,
                  diag: np.ndarray) -> np.ndarray:
        """The rows whose force gives their gap an acceleration beyond rounding (:data:`PRESSED`
        of the model's accelerations)."""
        return f * diag > PRESSED * self.rigid.acceleration_scale(t, q, qd) * self.rigid.scale

    def _solve(self, t: float, q: np.ndarray, qd: np.ndarray, rows: np.ndarray,
               qdd0: np.ndarray | None = None, lam0: np.ndarray | None = None) -> tuple:
        """``(qdd, lam, f, w, W_kk)`` with the ``rows`` held (module doc); ``f``, ``w`` and
        ``W_kk`` over every rigid row (zero, and one, where not held). The last is kept: the
        right-hand side, the outputs and every release event ask at the same states."""
        rigid, model = self.rigid, self.model
        chart = rigid.chart()
        key = (t, q.tobytes(), qd.tobytes(), rows.tobytes(),
               None if chart is None else chart.tobytes())
        if key == self._key:
            return self._solution
        if qdd0 is None:
            qdd0, lam0, _ = consistent_accelerations(model, t, q, qd, chart,
                                                     redundant=rigid.redundant())
        r, n = len(rigid), model.n_coordinates
        f, w, diag = np.zeros(r), np.zeros(r), np.ones(r)
        qdd, lam = qdd0, lam0
        if np.any(rows):
            G = rigid.gap_rows(q, rows)
            XY = rigid.response(t, q, G)
            W = G @ XY[:n]
            b = G @ qdd0 + rigid.convective(q, qd)[rows]
            f[rows] = _spread(W, b, impulses(W, b))
            w[rows] = W @ f[rows] + b
            diag[rows] = np.diag(W)
            qdd, lam = qdd0 + XY[:n] @ f[rows], lam0 + XY[n:] @ f[rows]
        self._key, self._solution = key, (qdd, lam, f, w, diag)
        return qdd, lam, f, w, diag

    def _kinetic(self, q: np.ndarray, qd: np.ndarray) -> float:
        """The kinetic energy [J] at ``(q, qd)``."""
        chart = self.rigid.chart()
        return float(energies(self.model, q[None], qd[None],
                              None if chart is None else chart[None])[0][0])


def _spread(W: np.ndarray, b: np.ndarray, f: np.ndarray) -> np.ndarray:
    """The forces ``f`` of the complementarity problem ``0 <= f _|_ W f + b >= 0`` spread
    over every row that touches without opening (``W f + b`` zero to rounding), where rows
    depend on each other (a face's corners on a floor): the least-norm forces holding those
    rows, if none of them pulls, else ``f``. The active set gives a basic solution (two
    diagonal corners of four carrying a box), which a rigid body leaves as valid as any;
    the least-norm one is the even share, and keeps every corner of the face held."""
    w = W @ f + b
    size = max(float(np.max(np.abs(b), initial=0.0)), np.finfo(float).tiny)
    touching = (f > 0.0) | (np.abs(w) <= 1e-9 * size)
    if np.all(touching == (f > 0.0)):
        return f
    rows = np.flatnonzero(touching)
    spread = np.linalg.lstsq(W[np.ix_(rows, rows)], -b[rows], rcond=1e-10)[0]
    if np.any(spread < 0.0) or np.max(np.abs(W[np.ix_(rows, rows)] @ spread + b[rows]),
                                        initial=0.0) > 1e-9 * size:
        return f
    out = np.zeros_like(f)
    out[rows] = spread
    return out
