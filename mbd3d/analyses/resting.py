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

A held row with a friction coefficient sticks or slides with Coulomb's friction
(:mod:`mbd3d.analyses.sticking`: its force then joins the complementarity problem); its
switches are events: a sticking row's force reaching its cone (``mu_s f - |s|`` [N] crossing
zero), a sliding row's slip along its direction reaching zero (``v . u`` [m/s]), each
watched once its function has left zero after the last switch. Held rows take part in
impacts with their friction (:mod:`mbd3d.analyses.impacts`); a sticking row that an impact
leaves slipping slides on along its slip. Where a sliding row comes to rest, the settling
that takes its last bounce away carries its friction too (``mu`` times that impulse, even
pulling): its friction then adds up to ``mu`` times its normal impulse, as the bounces
would have, so a ball bouncing to rest while it slides loses its slip exactly as one that
slides all along.

Like the joints, the held rows drift under integration: a step that leaves one open or closing
by more than ``constraint_tol`` (of the model's length scale) is projected back (mass-weighted,
the joints holding; a sticking row's slip with it), and so is the state a release starts the
flight from. Held rows are evaluated in Python at each right-hand side (the explicit methods'
callback) and at each Newton iterate of generalized-alpha, which adds their forces
(:meth:`HeldRows.applied`) to the applied forces of the iterate's own state; its
recursion goes on through the projections (each of the tolerance's size).

In a model with joint friction (:mod:`mbd3d.model.friction`), a held row's force loads the
joints, and their friction changes the force: the frictions ``e`` solve
``e = -mu load(lam(e)) tanh(v / v_s)`` with ``lam(e)`` the multipliers with the held rows'
forces at those frictions (the complementarity problem above, its right-hand side moved by
the joints' response to ``e``), by Newton's method
(:func:`~mbd3d.model.friction.solve_frictions`). A row coming to rest takes its last
bounce away with the joints' friction impulses that bounce would have given
(:mod:`mbd3d.analyses.joint_impulses`).
"""

from __future__ import annotations

import numpy as np

from mbd3d.analyses.accelerations import consistent_accelerations
from mbd3d.analyses.impacts import CLOSING, PRESSED, RigidContacts, impulses
from mbd3d.analyses.joint_impulses import joint_friction_impulses
from mbd3d.analyses.kinematics import project_state
from mbd3d.analyses.sticking import (direction, mixed_complementarity, share_by_capacity,
                                     tangents)
from mbd3d.io.history import energies
from mbd3d.model import constraints
from mbd3d.model.friction import solve_frictions

__all__ = ["HeldRows"]

#: rounds of the position projection of the held rows (each one Newton step on their gaps)
_ROUNDS = 4
#: a sliding row whose slip along its direction is below _STOPPED of its rest speed has
#: stopped sliding (the friction event fires there)
_STOPPED = 1e-6
#: the step of the frictions' difference quotient, relative to the largest friction
_FRICTION_STEP = 1e-6


class HeldRows:
    """The rigid rows of one run held closed (``mask``), their forces and their releases.

    ``rigid``: the run's :class:`~mbd3d.analyses.impacts.RigidContacts`, whose gaps, gap rows
    and impact response these use; ``tol``: the projection's tolerance (of the model's length
    scale, as the joints'). The rests and releases are recorded in ``stats["rests"]``."""

    def __init__(self, rigid: RigidContacts, tol: float, stats: dict):
        self.rigid, self.model, self.tol = rigid, rigid.model, tol
        self.mask = np.zeros(len(rigid), dtype=bool)
        self.mu, self.planar = rigid.mu, rigid.model.n_coords_per_body == 3
        #: the static coefficients: a sticking row holds within mu_static f, slides with mu f
        self.mu_static = rigid.mu_static
        #: per row with friction, held: whether it sticks (its slip held at zero), else the
        #: direction it slides along (unit, global; :mod:`mbd3d.analyses.sticking`)
        self.stuck = np.zeros(len(rigid), dtype=bool)
        self.along = np.zeros((len(rigid), 3))
        #: per row, whether its friction event is watched: only once its function has left
        #: zero after a switch (a slide from a push just at the cone starts with no
        #: acceleration, its slip dithering about zero by rounding for a while)
        self.armed = np.zeros(len(rigid), dtype=bool)
        self.records = stats.setdefault("rests", [])
        self._key, self._solution, self._applied = None, None, None

    def any(self) -> bool:
        return bool(np.any(self.mask))

    def accelerations(self, t: float, q: np.ndarray, qd: np.ndarray, qdd0: np.ndarray,
                      lam0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(qdd, lam)`` at ``(t, q, qd)`` with the held rows' forces (module doc), from the
        joints' ``qdd0`` and ``lam0`` there."""
        return self._solve(t, q, qd, self.mask, qdd0, lam0)[:2]

    def applied(self, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """The generalized forces (n,) of the held rows' normal forces and friction at ``(t,
        q, qd)``: what generalized-alpha adds to the applied forces of each Newton iterate
        (the rows' constraint on their gaps' accelerations, held at the iterate's own state
        as the joints' friction is), and the joints' friction of the reactions with them."""
        self._solve(t, q, qd, self.mask)
        return self._applied

    def forces(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(normal (r,) [N], friction (r, 3) [N])``: every rigid row's normal force and the
        friction on its second shape (global axes) at ``(t, q, qd)``; zero where not held."""
        solution = self._solve(t, q, qd, self.mask)
        return solution[2], solution[5]

    def power(self, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """The power [W] every rigid row's friction dissipates at ``(t, q, qd)`` (>= 0)."""
        if not np.any(self.mask & (self.mu_static > 0.0)):
            return np.zeros(len(self.mask))
        slip = self.rigid.slips(q, qd)[0]
        return -np.einsum("ki,ki->k", self._solve(t, q, qd, self.mask)[5], slip)

    def friction_value(self, index: int, t: float, q: np.ndarray, qd: np.ndarray) -> float:
        """The friction event's function of rigid row ``index``: sticking, how far its force
        is inside its cone, ``mu_s f - |s|`` [N]; sliding, its slip along the direction it
        slides, ``v . u`` [m/s]; 1 where it is not held, has no friction or is not armed."""
        if not (self.mask[index] and self.mu_static[index] > 0.0 and self.armed[index]):
            return 1.0
        return float(self._solve(t, q, qd, self.mask)[6][index])

    def switch_friction(self, t: float, q: np.ndarray, qd: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray]:
        """The friction events' action: the sticking rows whose force reached their cone
        slide, away from that force; the sliding rows whose slip reached zero stick, where
        their force then stays within the cone, else slide on the other way."""
        _, _, f, _, _, friction, margin = self._solve(t, q, qd, self.mask)
        rubbing = self.mask & (self.mu_static > 0.0)
        slipping = rubbing & self.stuck & (margin <= 1e-9 * self.mu_static * f)
        stopping = rubbing & ~self.stuck & (margin <= _STOPPED * self.rigid.rest_speed)
        self._slide_away(slipping, friction)
        self._record(t, "slip", slipping)
        return self._stick(t, q, qd, stopping)

    def follow(self, t: float, q: np.ndarray, qd: np.ndarray) -> None:
        """After a step or a jump: the sliding rows slide along their slip where it is
        beyond their slip velocity (below, the rounding of a slip that has just started
        would turn them: :func:`mbd3d.analyses.sticking.direction`), and the sticking rows
        that a jump (an impact elsewhere) left slipping beyond their rest speed slide along
        it; the events of the rows whose function has left zero (1e-6 of the cone,
        :data:`_STOPPED` of the rest speed) armed."""
        rubbing = self.mask & (self.mu_static > 0.0)
        if not np.any(rubbing):
            return
        rigid = self.rigid
        slip = rigid.slips(q, qd)[0]
        speed = np.linalg.norm(slip, axis=1)
        jumped = rubbing & self.stuck & (speed > rigid.rest_speed)
        turned = jumped | rubbing & ~self.stuck & (speed > rigid.slip_velocity)
        self.along[turned] = slip[turned] / speed[turned, None]
        self.stuck[jumped] = self.armed[jumped] = False
        _, _, f, _, _, _, margin = self._solve(t, q, qd, self.mask)
        away = np.where(self.stuck, margin > 1e-6 * self.mu_static * f,
                        margin > _STOPPED * self.rigid.rest_speed)
        self.armed |= rubbing & away

    def _slide_away(self, rows: np.ndarray, friction: np.ndarray) -> None:
        """The ``rows`` slide away from their (sticking) friction ``friction`` (r, 3)."""
        for k in np.flatnonzero(rows):
            size = float(np.linalg.norm(friction[k]))
            self.stuck[k] = self.armed[k] = False
            if size > 0.0:
                self.along[k] = -friction[k] / size

    def _stick(self, t: float, q: np.ndarray, qd: np.ndarray, rows: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
        """Stick the ``rows`` whose friction then stays within its cone (the others slide
        away from it), their slips set to zero (the energy this takes recorded)."""
        if not np.any(rows):
            return q, qd
        self.stuck |= rows
        self.armed[rows] = False
        for _ in range(int(np.sum(rows)) + 1):
            _, _, f, _, _, friction, _ = self._solve(t, q, qd, self.mask)
            over = rows & self.stuck & (np.linalg.norm(friction, axis=1)
                                        > (1.0 + 1e-9) * self.mu_static * f)
            if not np.any(over):
                break
            self._slide_away(over, friction)
        stuck = rows & self.stuck
        if np.any(stuck):
            before = self._kinetic(q, qd)
            q, qd = self.settle(t, q, qd, force=True)
            self._record(t, "stick", stuck, max(before - self._kinetic(q, qd), 0.0))
        return q, qd

    def release_value(self, index: int, t: float, q: np.ndarray, qd: np.ndarray) -> float:
        """The release event's function of rigid row ``index``: ``f - w / W_kk`` [N] while
        held (positive while it presses), 1 otherwise."""
        if not self.mask[index]:
            return 1.0
        _, _, f, w, diag, _, _ = self._solve(t, q, qd, self.mask)
        return float(f[index] - w[index] / diag[index])

    def release(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The release events' action: the held rows that no longer press let go, from
        their gaps and rates at zero (their drift, which generalized-alpha's steps leave up
        to the tolerance, would otherwise start the flight)."""
        q, qd = self.settle(t, q, qd, force=True)
        _, _, f, _, diag, _, _ = self._solve(t, q, qd, self.mask)
        self.let_go(t, self.mask & ~self._pressing(t, q, qd, f, diag))
        self.rigid.watch(q, qd)
        return q, qd

    def let_go(self, t: float, rows: np.ndarray) -> None:
        """Release the held ``rows`` at ``t`` (recorded)."""
        self._record(t, "release", rows & self.mask)
        self.mask = self.mask & ~rows
        self.stuck[rows], self.armed[rows], self.along[rows] = False, False, 0.0

    def hold(self, t: float, q: np.ndarray, qd: np.ndarray, candidates: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
        """Hold the ``candidates`` (touching, slow) that the free motion presses closed, with
        the rows held already: their rates and gaps are set to zero (the kinetic energy this
        takes, about what a bounce below the rest speed carries, is recorded)."""
        rows = candidates | self.mask
        rigid = self.rigid
        _, rate = rigid.states(q, qd)
        # pressed at the state as it is: the slow rates' part of the gaps' accelerations is
        # below what the threshold tells apart
        _, _, f, _, diag, _, _ = self._solve(t, q, qd, rows)
        held = self._pressing(t, q, qd, f, diag) & rows
        if not np.any(held):
            self.let_go(t, self.mask)
            return q, qd
        before, new = self._kinetic(q, qd), held & ~self.mask
        # the new rows with friction slide along their slip (their settling rubs), or stick
        # where it is slow
        slip = rigid.slips(q, qd)[0]
        speed = np.linalg.norm(slip, axis=1)
        slow = new & (self.mu_static > 0.0) & (speed <= rigid.rest_speed)
        moving = new & (speed > 0.0)
        self.along[moving] = slip[moving] / speed[moving, None]
        q, qd = self.settle(t, q, qd, held, force=True, rubbing=True)
        # what the settling takes (>= 0 but for rounding): the bounces' energy, less what a
        # sliding row's friction gives back where its bounce is pulled down (its bounces
        # would have rubbed less than the force that replaces them will)
        lost = before - self._kinetic(q, qd)
        if not np.any(held & (self.mu > 0.0) & ~self.stuck):
            lost = max(lost, 0.0)
        # rows held already that an impact left opening slowly: their bounce is taken too
        bounced = held & self.mask & (np.abs(rate) > CLOSING * rigid.rest_speed)
        if np.any(new) or np.any(bounced):
            self._record(t, "rest", new | bounced, lost)
        self.let_go(t, self.mask & ~held)
        self.mask = held
        self.follow(t, q, qd)
        q, qd = self._stick(t, q, qd, slow)
        self.follow(t, q, qd)
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
               force: bool = False, tol: float | None = None, rubbing: bool = False
               ) -> tuple[np.ndarray, np.ndarray] | None:
        """The state with the held ``rows`` (default all held) closed and idle, the joints
        holding (mass-weighted least change); None when they have not drifted beyond ``tol``
        (default the run's; relative to the model's length scale) unless ``force``. With
        ``rubbing`` (rows coming to rest: the impulses take their bounces), the joints' friction
        takes its impulses too; a drift's correction is not a motion, and takes none."""
        rows = self.mask if rows is None else rows
        tol = self.tol if tol is None else tol
        rigid, model = self.rigid, self.model
        scale = rigid.scale[rows]
        gap, rate = rigid.states(q, qd)
        slip = np.linalg.norm(rigid.slips(q, qd)[0][rows & self.stuck], axis=1)
        drift = max(np.max(np.abs(gap[rows]) / scale, initial=0.0),
                    np.max(np.abs(rate[rows]) / scale, initial=0.0),
                    np.max(slip / model.length_scale, initial=0.0))
        if not np.any(rows) or (drift <= tol and not force):
            return None if not force else (q, qd)
        chart, redundant = rigid.chart(), rigid.redundant()
        for _ in range(_ROUNDS):
            g = rigid.states(q, qd)[0][rows]
            if np.max(np.abs(g) / scale) <= 1e-3 * tol:
                break
            G = rigid.gap_rows(q, rows)
            q = q + self._correction(t, q, G, -g)
            q, qd = project_state(model, t, q, qd, 1e-3 * tol, chart, redundant)
        # the rates: the rows' gaps' and the sticking rows' slips (in their tangents) zero, by
        # impulses along the rows, with Coulomb's friction where rows slide: the bounces a row
        # coming to rest no longer makes (or its drift) rub as the force that replaces them
        G, T = rigid.rate_rows(q, rows)
        held = np.flatnonzero(rows)
        sliding = (self.mu_static[held] > 0.0) & ~self.stuck[held]
        rates = [G]
        columns = [G - (self.mu[held] * sliding)[:, None] * np.einsum(
            "ki,kin->kn", self.along[held], T)]
        normals = rigid.slips(q, qd)[1]
        for a, k in enumerate(held):
            if self.stuck[k]:
                rates.append(tangents(normals[k], self.planar) @ T[a])
                columns.append(rates[-1])
        return q, self._stopped(t, q, qd, np.vstack(rates), np.vstack(columns), rubbing)

    def _stopped(self, t: float, q: np.ndarray, qd: np.ndarray, R: np.ndarray,
                 columns: np.ndarray, rubbing: bool) -> np.ndarray:
        """The velocities with ``R qd`` zero by impulses along ``columns``, the joints holding
        (:meth:`_correction`); with ``rubbing``, with their friction's impulses where they have
        friction, as at an impact (:mod:`mbd3d.analyses.joint_impulses`): the bounces a row
        coming to rest no longer makes would have rubbed in the joints too."""
        model, n = self.model, self.model.n_coordinates
        XY = self.rigid.response(t, q, columns)

        def stop(kick: np.ndarray, lam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            impulse = np.linalg.lstsq(R @ XY[:n], -(R @ (qd + kick)), rcond=1e-12)[0]
            return qd + kick + XY[:n] @ impulse, lam + XY[n:] @ impulse

        if model.friction is None or not rubbing:
            return stop(np.zeros(n), np.zeros(model.n_constraints))[0]
        fr = constraints.frames(model, q, qd, self.rigid.chart())
        return joint_friction_impulses(
            model, fr, qd, stop, lambda G: self.rigid.response(t, q, G),
            f"forward dynamics of '{model.name}': rigid contacts coming to rest at "
            f"t = {t:.9g} s")[0]

    def _correction(self, t: float, q: np.ndarray, R: np.ndarray, change: np.ndarray,
                    columns: np.ndarray | None = None) -> np.ndarray:
        """The change ``X mu`` of the coordinates that changes ``R q`` (``R``: rows of the
        gaps) by ``change``, the joints holding to first order, ``X`` the response to
        generalized impulses along ``columns`` (default ``R``: the mass-weighted least
        change). The rates are corrected by :meth:`_stopped`."""
        X = self.rigid.response(t, q, R if columns is None else columns)
        X = X[:self.model.n_coordinates]
        return X @ np.linalg.lstsq(R @ X, change, rcond=1e-12)[0]

    def _pressing(self, t: float, q: np.ndarray, qd: np.ndarray, f: np.ndarray,
                  diag: np.ndarray) -> np.ndarray:
        """The rows whose force gives their gap an acceleration beyond rounding (:data:`PRESSED`
        of the model's accelerations)."""
        return f * diag > PRESSED * self.rigid.acceleration_scale(t, q, qd) * self.rigid.scale

    def _solve(self, t: float, q: np.ndarray, qd: np.ndarray, rows: np.ndarray,
               qdd0: np.ndarray | None = None, lam0: np.ndarray | None = None) -> tuple:
        """``(qdd, lam, f, w, W_kk, friction, margin)`` with the ``rows`` held (module doc),
        from the joints' ``qdd0`` and ``lam0`` (default solved here); ``f``, ``w`` and
        ``W_kk`` over every rigid row (zero, and one, where not held). The last is kept: the
        right-hand side, the outputs and every release event ask at the same states."""
        rigid, model = self.rigid, self.model
        chart = rigid.chart()
        key = (t, q.tobytes(), qd.tobytes(), rows.tobytes(), self.stuck.tobytes(),
               self.along.tobytes(), None if chart is None else chart.tobytes())
        if key == self._key:
            return self._solution
        if qdd0 is None:
            qdd0, lam0, _ = consistent_accelerations(model, t, q, qd, chart,
                                                     redundant=rigid.redundant())
        if model.friction is None:
            solution, applied = self._held(t, q, qd, rows, qdd0, lam0)
        else:
            solution, applied = self._with_joint_friction(t, q, qd, rows, qdd0, lam0)
        self._key, self._solution, self._applied = key, solution, applied
        return solution

    def _with_joint_friction(self, t: float, q: np.ndarray, qd: np.ndarray, rows: np.ndarray,
                             qdd0: np.ndarray, lam0: np.ndarray) -> tuple[tuple, np.ndarray]:
        """:meth:`_held` where the joints have friction: the frictions ``e`` that the joints'
        reactions with the held rows' forces give (:func:`~mbd3d.model.friction.solve_frictions`;
        ``qdd0`` and ``lam0`` carry the frictions of the reactions without those forces, taken
        out by the joints' response to them). The reactions are piecewise affine in ``e``
        (the held rows' active set), so their slope is a difference quotient, exact within a
        piece; the generalized forces returned include the frictions (generalized-alpha
        adds them to each iterate's applied forces in place of those without the rows)."""
        rigid, model, n = self.rigid, self.model, self.model.n_coordinates
        group = model.friction
        fr = constraints.frames(model, q, qd, rigid.chart())
        G, speed = group.directions(model, fr)
        factor = group.mu * np.tanh(speed / group.v_s)
        efforts = -factor * group.loads(model, fr, lam0)
        response = rigid.response(t, q, G)  # (n + m, k): the joints' to a unit of each
        free = np.concatenate([qdd0, lam0]) - response @ efforts
        parts = self._parts(t, q, qd, rows) if np.any(rows) else None
        solved = {}

        def held(e: np.ndarray) -> tuple[tuple, np.ndarray]:
            if e.tobytes() not in solved:
                x = free + response @ e
                solved[e.tobytes()] = self._held(t, q, qd, rows, x[:n], x[n:], parts)
            return solved[e.tobytes()]

        def slope(e: np.ndarray) -> np.ndarray:
            size = np.max(np.abs(factor * group.loads(model, fr, held(e)[0][1])))
            step = _FRICTION_STEP * max(float(np.max(np.abs(e))), float(size), 1e-300)
            return np.column_stack([(held(e + step * u)[0][1] - held(e)[0][1]) / step
                                    for u in np.eye(len(e))])

        if np.any(rows):
            efforts = solve_frictions(model, t, fr, factor, lambda e: held(e)[0][1], slope,
                                      efforts)
        solution, applied = held(efforts)
        return solution, applied + G.T @ efforts

    def _held(self, t: float, q: np.ndarray, qd: np.ndarray, rows: np.ndarray,
              qdd0: np.ndarray, lam0: np.ndarray, parts: tuple | None = None
              ) -> tuple[tuple, np.ndarray]:
        """The solution :meth:`_solve` returns, from the joints' ``qdd0`` and ``lam0`` with
        the applied forces fixed, and the held rows' generalized forces (n,); ``parts``:
        :meth:`_parts` of the same state and rows (default evaluated here)."""
        rigid, n = self.rigid, self.model.n_coordinates
        r = len(rigid)
        f, w, diag = np.zeros(r), np.zeros(r), np.ones(r)
        friction, margin = np.zeros((r, 3)), np.ones(r)
        if not np.any(rows):
            return (qdd0, lam0, f, w, diag, friction, margin), np.zeros(n)
        a = int(np.sum(rows))
        G, T, convective, XY = self._parts(t, q, qd, rows) if parts is None else parts
        b = G @ qdd0 + convective
        if XY is None:
            z, XY, W, columns = self._with_friction(t, q, qd, rows, G, T, qdd0, b,
                                                    friction, margin)
        else:
            columns = G
            W = G @ XY[:n]
            z = _spread(W, b, impulses(W, b))
        f[rows] = z[:a]
        w[rows] = W[:a] @ z + b
        diag[rows] = np.diag(W)[:a]
        return ((qdd0 + XY[:n] @ z, lam0 + XY[n:] @ z, f, w, diag, friction, margin),
                columns.T @ z)

    def _parts(self, t: float, q: np.ndarray, qd: np.ndarray, rows: np.ndarray) -> tuple:
        """What :meth:`_held` takes of the state alone, whatever the joints' accelerations:
        the held ``rows``' gap and slip rows ``G``, ``T``, their gaps' convective terms and,
        where none has friction, the joints' response ``[X; Y]`` to a unit force on each
        (None with friction: it depends on how they stick or slide)."""
        rigid = self.rigid
        G, T = rigid.rate_rows(q, rows, qd)  # the convective terms in the same call
        convective = rigid.convective(q, qd)[rows]
        rubbing = np.any(self.mu_static[rows] > 0.0)
        return G, T, convective, None if rubbing else rigid.response(t, q, G)

    def _with_friction(self, t, q, qd, rows, G, T, qdd0, b, friction, margin) -> tuple:
        """``(z, [X; Y], A, columns)`` of the held ``rows`` with friction (:mod:`.sticking`):
        ``z`` their normal forces then the sticking rows' tangential ones, ``columns`` the
        generalized directions they act along, ``A`` the response of the normal rows then
        the sticking rows' slips to them; ``friction`` (on the second shapes) and the events'
        ``margin`` filled for the rows."""
        rigid, n = self.rigid, self.model.n_coordinates
        held = np.flatnonzero(rows)
        slip, normal = (x[held] for x in rigid.slips(q, qd))
        mu, mu_s = self.mu[held], self.mu_static[held]
        stuck = self.stuck[held] & (mu_s > 0.0)
        sliding = (mu_s > 0.0) & ~stuck
        blend = rigid.slip_velocity[held]
        e = np.array([direction(v, u, b) if s else np.zeros(3)
                      for v, u, b, s in zip(slip, self.along[held], blend, sliding)])
        columns = G - mu[:, None] * np.einsum("ki,kin->kn", e, T)
        bases = [tangents(normal[a], self.planar) for a in np.flatnonzero(stuck)]
        Ts = np.vstack([B @ T[a] for B, a in zip(bases, np.flatnonzero(stuck))] or
                       [np.zeros((0, n))])
        columns = np.vstack([columns, Ts])
        XY = rigid.response(t, q, columns)
        A = np.vstack([G, Ts]) @ XY[:n]
        conv = rigid.slip_convective(q, qd)[held]
        c = np.concatenate([b] + [B @ (T[a] @ qdd0 + conv[a])
                                  for B, a in zip(bases, np.flatnonzero(stuck))])
        names = ", ".join(f"'{rigid.names[k]}'" for k in held[:6])
        z = mixed_complementarity(A, c, len(held), f"forces of the rigid contacts held at rest "
                                  f"({names}) at t = {t:.9g} s")
        f = z[:len(held)]
        d = 1 if self.planar else 2
        capacity = np.repeat(mu_s[stuck] * f[stuck], d)
        z[len(held):] = share_by_capacity(A[len(held):, len(held):], z[len(held):], capacity)
        for i, a in enumerate(np.flatnonzero(stuck)):
            friction[held[a]] = bases[i].T @ z[len(held) + d * i:len(held) + d * (i + 1)]
        friction[held[sliding]] = -(mu * f)[sliding, None] * e[sliding]
        margin[held[stuck]] = mu_s[stuck] * f[stuck] - np.linalg.norm(friction[held[stuck]],
                                                                    axis=1)
        margin[held[sliding]] = np.einsum("ki,ki->k", slip[sliding], self.along[held[sliding]])
        return z, XY, A, columns

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
