"""Rigid contacts in forward dynamics: every touch an impact, resolved on the whole mechanism.

A contact or joint stop with :class:`~mbd3d.RigidImpact` exerts no force. Its gap ``g(q)`` is
an event of the run (closing), which the driver (:mod:`mbd3d.analyses.driver`) locates on the
integrator's dense output. There, the positions frozen, the velocities jump by Newton's law of
restitution generalized to several contacts with the joints holding::

    qd+ = qd- + S G^T lam,    S = M^-1 - M^-1 Cq^T (Cq M^-1 Cq^T)^-1 Cq M^-1
    w = W lam + (I + E) v-,   0 <= lam  _|_  w >= 0,    W = G S G^T,   v- = G qd-

over the rows ``A`` that touch (gap within :data:`CLOSED` of zero) and close (rate below zero):
``G`` their gap rows (``g' = G qd``), ``E`` their restitutions, ``lam`` the normal impulses
[N s; a hinge's stop: N m s] and ``w`` the rates after the impact, ``-e v-`` where an impulse
acts. ``S G^T`` is what a unit impulse on each row does to the velocities through the joints:
the solution of the augmented system ``[M Cq^T; Cq 0] [x; y] = [G^T; 0]``, so the joints and the
drivers hold through the impact. The complementarity problem is solved exactly by an active
set (:func:`impulses`). An impulse can close a row that was only touching (a row of balls):
the law is applied again to the rows then closing, until none is (the sequential impacts of
Newton's cradle, whose struck ball alone leaves).

Rows with a friction coefficient ``mu`` take a friction impulse too, by Coulomb's law on the
slip after the impact (:func:`~mbd3d.analyses.sticking.impact_with_friction`): the slip stops
where the impulse that stops it stays within ``mu lam``, else the row slides with ``mu lam``
against the slip it leaves with. Each row's energy lost, the work of its impulses
``-(lam (v- + v+) + P_t . (s- + s+)) / 2`` (without friction ``-(1 - e) lam v- / 2`` >= 0),
adds up to the kinetic energy lost where no driver moves; an impact whose rows would give
the motion energy (Newton's law and Coulomb's together can, where a row's friction turns
its normal rate: Kane's paradox) is refused, naming it. The joints' friction takes its
impulses from the impulses the joints carry (:mod:`mbd3d.analyses.joint_impulses`); a
row's ``energy_lost`` is its own impulses' work, not theirs.

A row that is left touching, opening slower than its ``rest_speed`` while the free motion
presses it closed, would bounce ever shorter (infinitely many impacts
in a finite time): it has come to rest. The integrators then hold it closed until it lets go
(:mod:`mbd3d.analyses.resting`), the joints' friction seeing its force.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from mbd3d.analyses.joint_impulses import joint_friction_impulses
from mbd3d.analyses.sticking import impact_with_friction
from mbd3d.errors import ModelError
from mbd3d.io.history import contact_history
from mbd3d.model import constraints
from mbd3d.model.contacts import contact_group
from mbd3d.model.equations import augmented_accelerations, mass_matrix
from mbd3d.numerics.linalg import (SingularMatrix, augmented_scaling, factor_model_augmented,
                                   solve_augmented_lagrangian)

__all__ = ["RigidContacts", "impulses", "CLOSED", "PAST"]

#: a row touches within CLOSED of zero gap; its event fires PAST beyond the touch, or beyond
#: where an impact left it touching: PAST if idle there, so that rows resting against each
#: other never fire by rounding, LEAVING if it leaves, which the depth of later impacts
#: accumulates (all relative to the model's length scale; a turning stop's in rad)
CLOSED, PAST, LEAVING = 1e-9, 1e-10, 1e-13
#: a row closes at a rate below -CLOSING of its rest speed; it is pressed closed when its free
#: acceleration is below -PRESSED of the model's (rounding leaves idle rows near zero)
CLOSING, PRESSED = 1e-9, 1e-9
#: rounds of the sequential impacts at one instant before the run is refused
ROUNDS = 1000


class RigidContacts:
    """The rigid rows of a model's contacts and stops in one run: their gaps (the events'
    functions), the impact at a touch and the rest check. ``chart()`` gives the integrator's
    current charts (spatial), ``redundant()`` whether the joints' rows depend on each other;
    the impacts are recorded in ``stats["impacts"]``."""

    def __init__(self, model, chart: Callable, redundant: Callable[[], bool], stats: dict):
        self.model, self.chart, self.redundant = model, chart, redundant
        #: the rows held at rest (:class:`mbd3d.analyses.resting.HeldRows`), set by the
        #: integrators' driver where the model has rigid rows
        self.holding = None
        self.group = contact_group(model, required=False)
        rigid = self.group.rigid if self.group is not None else np.zeros(0, dtype=bool)
        self.rows = np.flatnonzero(rigid)
        if not len(self.rows):
            return
        group = self.group
        self.names = [group.names[r] for r in self.rows]
        self.units = [group.owners[r].units[0] for r in self.rows]
        self.scale = np.array([model.length_scale if u == "m" else 1.0 for u in self.units])
        self.e, self.rest_speed = group.restitution[self.rows], group.rest_speed[self.rows]
        self.mu, self.slip_velocity = group.friction[self.rows], group.slip_velocity[self.rows]
        self.mu_static = group.static_friction[self.rows]
        self.floor = self.idle = None  # where the rows fire, which were left idle: start()
        self.records = stats.setdefault("impacts", [])
        self._key, self._report, self._points = None, None, None
        self._convective_key = self._convective_terms = None

    def __len__(self) -> int:
        return len(self.rows)

    def gap(self, index: int, t: float, q: np.ndarray, qd: np.ndarray) -> float:
        """The event function of rigid row ``index``: its gap [m or rad] beyond the depth
        at which it fires (1 while it is held at rest)."""
        if self.holding.mask[index]:
            return 1.0
        return float(self.states(q, qd)[0][index] - self.floor[index])

    def gap_rate(self, index: int, t: float, q: np.ndarray, qd: np.ndarray) -> float:
        """The rate [m/s or rad/s] of :meth:`gap` (0 while it is held at rest)."""
        if self.holding.mask[index]:
            return 0.0
        return float(self.states(q, qd)[1][index])

    def states(self, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(gap, rate)`` of the rigid rows at ``(q, qd)`` in the current charts; the last
        state's are kept, since every row's event asks at the same states."""
        chart = self.chart()
        key = (q.tobytes(), qd.tobytes(), None if chart is None else chart.tobytes())
        if key != self._key:
            states = contact_history(self.model, q[None], qd[None],
                                     None if chart is None else chart[None])
            self._key = key
            self._report = (states.gap[0, self.rows], states.gap_rate[0, self.rows])
            self._points = states.point[0, self.rows]
            self._slips = (states.slip_velocity[0, self.rows], states.normal[0, self.rows])
        return self._report

    def slips(self, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(slip velocity (r, 3) [m/s], normal (r, 3))`` of the rigid rows at ``(q, qd)``,
        global axes (:class:`~mbd3d.ContactStates`)."""
        self.states(q, qd)
        return self._slips

    def start(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Refuse rows inside each other at the run's start ``t``; hold the rows that rest
        there (where the integrator holds rows) and set where rows fire; the state to start
        from."""
        gap, rate = self.states(q, qd)
        inside = np.flatnonzero(gap < -CLOSED * self.scale)
        if len(inside):
            k = inside[0]
            raise ModelError(
                f"rigid contact '{self.names[k]}' starts {-gap[k]:.6g} {self.units[k]} inside "
                f"at t = {t:.9g} s: rigid shapes (and stops) must start apart or touching; "
                "move the bodies (or give q0) so that they do not overlap")
        resting = (gap <= CLOSED * self.scale) & (np.abs(rate) < self.rest_speed)
        if np.any(resting):
            q, qd = self.holding.hold(t, q, qd, resting)
        self.watch(q, qd)
        return q, qd

    def act(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The state after the impact at ``(q, qd)`` at ``t`` (positions unchanged, unless
        rows come to rest and are held)."""
        gap, rate = self.states(q, qd)
        # a row left touching that sank to where it fires, closing slower than its rest speed,
        # is resting (its bodies press together) whatever the check after its impact said
        sunk = gap <= self.floor + 0.5 * PAST * self.scale
        back = self.idle & sunk & (rate > -self.rest_speed)
        if np.any(back):
            q, qd = self.holding.hold(t, q, qd, back)
        for _ in range(ROUNDS):
            gap, rate = self.states(q, qd)
            active = (gap <= CLOSED * self.scale) & (rate < -CLOSING * self.rest_speed)
            if not np.any(active):
                break
            # rows at rest take part in the impact at once (at zero rate): their bodies
            # press together, so an impulse passes through them as through a joint
            active |= self.holding.mask
            qd = self._impact(t, q, qd, active, rate[active])
        else:
            closing = ", ".join(f"'{self.names[k]}'" for k in np.flatnonzero(active)[:6])
            raise ModelError(f"forward dynamics of '{self.model.name}': the impacts at t = "
                             f"{t:.9g} s do not end after {ROUNDS} rounds ({closing} still "
                             "closing); give the contacts a restitution below 1 or compliant "
                             "laws")
        q, qd = self._check_rest(t, q, qd)
        self.watch(q, qd)
        return q, qd

    def _impact(self, t, q, qd, active: np.ndarray, before: np.ndarray) -> np.ndarray:
        """One round: Newton's law on the ``active`` rows closing at ``before``, with
        Coulomb's friction where they have it
        (:func:`~mbd3d.analyses.sticking.impact_with_friction`) and in the joints
        (:func:`~mbd3d.analyses.joint_impulses.joint_friction_impulses`: in two phases,
        the rows brought to rest then to ``-e`` times ``before``, since a joint's slide may
        turn back between them, as a pendulum's hinge does, and its friction with it);
        recorded."""
        e, a = self.e[active], int(np.sum(active))
        G, T = self.rate_rows(q, active)
        slip = T @ qd
        phases = 1 if self.model.friction is None else 2
        lam, P_t, lost = np.zeros(a), np.zeros((a, 3)), np.zeros(a)
        for k in range(phases):
            rates, slips = G @ qd, T @ qd
            # the least change of the rates: to -e times those before at once, or to rest
            # and from there to -e times those before
            closing = ((1.0 + e) * before if phases == 1
                       else rates if k == 0 else rates + e * before)
            qd, p, P = self._phase(t, q, qd, active, G, T, closing)
            lam, P_t = lam + p, P_t + P
            # each row's impulses' work: what it takes from the motion, or gives (Kane's)
            lost += -0.5 * (p * (rates + G @ qd) + np.einsum("ki,ki->k", P, slips + T @ qd))
        if np.any(self.mu_static[active] > 0.0):
            self._refuse_gain(t, active, lost, lam * np.abs(before)
                              + np.linalg.norm(P_t, axis=1) * np.linalg.norm(slip, axis=1))
        else:
            lost = np.maximum(lost, 0.0)  # a row at rest enters at zero rate, to rounding
        after = G @ qd
        self.states(q, qd)
        for a, k in enumerate(np.flatnonzero(active)):
            if lam[a] > 0.0:
                self.records.append({
                    "time": t, "contact": self.names[k], "impulse": float(lam[a]),
                    "friction_impulse": P_t[a].tolist(), "rate_before": float(before[a]),
                    "rate_after": float(after[a]), "energy_lost": float(lost[a]),
                    "point": self._points[k].tolist()})
        return qd

    def _contact_impulses(self, t, q, qd, active, G, T, closing, kick=None,
                          XG=None) -> tuple:
        """``(qd+, p, P_t)`` of the ``active`` rows' impact (normal impulses ``p``, friction
        ``P_t``) with the velocities changed by ``kick`` (n,; the joints' friction) besides:
        Newton's law, the rates' change at least ``closing`` (without ``kick``'s), Coulomb's
        where rows have friction (where it fails, the run is refused naming the rows and the
        time). ``XG``: the response to the rows ``G`` where already known."""
        n = self.model.n_coordinates
        kick = np.zeros(n) if kick is None else kick
        if not np.any(self.mu_static[active] > 0.0):
            X = (self.response(t, q, G) if XG is None else XG)[:n]
            lam = impulses(G @ X, closing + G @ kick)
            return qd + kick + X @ lam, lam, np.zeros((len(lam), 3))
        try:
            return impact_with_friction(G, T, self.slips(q, qd)[1][active], self.mu[active],
                                        closing, qd, lambda R: self.response(t, q, R)[:n],
                                        self.model.n_coords_per_body == 3,
                                        self.mu_static[active], kick)
        except ModelError as error:
            raise ModelError(f"{self._what(t, active)}, {error}") from None

    def _phase(self, t, q, qd, active, G, T, closing) -> tuple:
        """:meth:`_contact_impulses`, with the joints' friction impulses where the model has
        joint friction (:func:`~mbd3d.analyses.joint_impulses.joint_friction_impulses`)."""
        if self.model.friction is None:
            return self._contact_impulses(t, q, qd, active, G, T, closing)
        n = self.model.n_coordinates
        # without the rows' friction their impulses act along G alone: its response (one
        # factorization of the augmented matrix) serves every trial of the joints' friction
        XG = None if np.any(self.mu_static[active] > 0.0) else self.response(t, q, G)

        def contact(kick: np.ndarray, lam: np.ndarray) -> tuple:
            after, p, P_t = self._contact_impulses(t, q, qd, active, G, T, closing, kick, XG)
            if XG is not None:
                return after, p, P_t, lam + XG[n:] @ p
            impulse = G.T @ p + np.einsum("kin,ki->n", T, P_t)  # generalized, of the rows
            return after, p, P_t, lam + self.response(t, q, impulse[None])[n:, 0]

        fr = constraints.frames(self.model, q, qd, self.chart())
        return joint_friction_impulses(self.model, fr, qd, contact,
                                       lambda R: self.response(t, q, R),
                                       self._what(t, active))[:3]

    def _what(self, t: float, active: np.ndarray) -> str:
        """The impact at ``t`` on the ``active`` rows, for errors."""
        names = ", ".join(f"'{self.names[k]}'" for k in np.flatnonzero(active)[:6])
        return (f"forward dynamics of '{self.model.name}': at the impact at t = {t:.9g} s on "
                f"{names}")

    def _refuse_gain(self, t: float, active: np.ndarray, lost: np.ndarray,
                     size: np.ndarray) -> None:
        """Refuse an impact whose rows' impulses would give the motion energy: Newton's law
        with Coulomb's friction can, where a row's friction turns another's normal rate
        (Kane and Levinson's double pendulum)."""
        if float(np.sum(lost)) >= -1e-9 * float(np.sum(size)):
            return
        names = ", ".join(f"'{self.names[k]}'" for k in np.flatnonzero(active)[:6])
        raise ModelError(
            f"forward dynamics of '{self.model.name}': the impact at t = {t:.9g} s on {names} "
            f"would give the motion {-float(np.sum(lost)):.6g} J: Newton's restitution with "
            "Coulomb's friction is not dissipative at this impact (Kane's paradox); lower the "
            "restitution or the friction coefficient, or give the contacts compliant laws")

    def gap_rows(self, q: np.ndarray, active: np.ndarray) -> np.ndarray:
        """``G`` (a, n) of the ``active`` rows: ``g' = G qd`` (:meth:`rate_rows`)."""
        return self.rate_rows(q, active)[0]

    def rate_rows(self, q: np.ndarray, active: np.ndarray, qd: np.ndarray | None = None
                  ) -> tuple[np.ndarray, np.ndarray]:
        """``(G (a, n), T (a, 3, n))`` of the ``active`` rows: their gap rates ``G qd`` and
        slip velocities ``T qd`` are linear in the velocities, so column ``c`` is those at
        the unit velocity of coordinate ``c`` (only the coordinates of the rows' bodies, the
        others' columns are zero). With ``qd``, the convective terms at ``(q, qd)`` come from
        the same evaluation of the contacts (:meth:`convective`; its cost is mostly per call)."""
        model, rows = self.model, self.rows[active]
        nb, nc = model.n_bodies, model.n_coords_per_body
        bodies = self.group._bodies(model)[rows].ravel()
        moving = np.unique(bodies[bodies < nb])
        columns = (moving[:, None] * nc + np.arange(nc)).ravel()
        k = len(columns)
        ends = self._ends(q, qd) if qd is not None else None
        positions, velocities = np.empty((k, len(q))), np.zeros((k, len(q)))
        positions[:] = q
        velocities[np.arange(k), columns] = 1.0
        if ends is not None:
            positions, velocities = np.vstack([positions, ends[0]]), np.vstack([velocities,
                                                                                ends[1]])
        chart = self.chart()
        charts = None if chart is None else np.broadcast_to(chart, (len(positions),)
                                                            + chart.shape)
        states = contact_history(model, positions, velocities, charts)
        if ends is not None:
            self._keep_convective(q, qd, ends[2], states.gap_rate[k:, self.rows],
                                  states.slip_velocity[k:, self.rows])
        G = np.zeros((len(rows), model.n_coordinates))
        G[:, columns] = states.gap_rate[:k, rows].T
        T = np.zeros((len(rows), 3, model.n_coordinates))
        T[:, :, columns] = states.slip_velocity[:k, rows].transpose(1, 2, 0)
        return G, T

    def response(self, t: float, q: np.ndarray, G: np.ndarray) -> np.ndarray:
        """``[S G^T; Y]`` (n + m, a): the velocities a unit impulse on each row gives, the
        joints holding (module doc), over the joints' multipliers it adds (``Y``, per unit
        force on each row when the rows act as forces)."""
        model = self.model
        m = model.n_constraints
        if not len(G):
            return np.zeros((model.n_coordinates + m, 0))
        fr = constraints.frames(model, q, charts=self.chart())
        blocks = model.body_type.mass_blocks(fr, model.mass, model.inertia)
        jac_data = constraints.evaluate(model, t, fr, value=False)[1]
        if not self.redundant():
            try:
                factors = factor_model_augmented(model, blocks, jac_data)
                return np.column_stack([factors.solve(np.concatenate([g, np.zeros(m)]))
                                        for g in G])
            except SingularMatrix:
                pass  # dependent rows found here: the augmented Lagrangian copes with them
        M, Cq = mass_matrix(model, fr), constraints.jacobian_matrix(model, jac_data)
        scaling = augmented_scaling(model)
        columns = [solve_augmented_lagrangian(M, Cq, g, np.zeros(m), scaling=scaling)[:2]
                   for g in G]
        return np.column_stack([np.concatenate(c) for c in columns])

    def _check_rest(self, t: float, q: np.ndarray, qd: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
        """The rows left touching, opening slower than their rest speed while the free motion
        presses them closed, are held (:mod:`mbd3d.analyses.resting`)."""
        gap, rate = self.states(q, qd)
        slow = (gap <= CLOSED * self.scale) & (rate < self.rest_speed)
        # a held row that the impact leaves opening faster than its rest speed flies off
        self.holding.let_go(t, (rate >= self.rest_speed) & self.holding.mask)
        # the rows held with friction that the impact left slipping slide on along it
        self.holding.follow(t, q, qd)
        return self.holding.hold(t, q, qd, slow) if np.any(slow) else (q, qd)

    def convective(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """``(dG/dq qd) qd`` of every row [m/s^2 or rad/s^2]: the part of the gaps'
        accelerations that the accelerations do not make, by a central difference of the
        gap rates along ``qd`` over a step that moves nothing by more than 1e-6 of the
        model's size (about 1e-10 relative)."""
        return self._convective(q, qd)[0]

    def slip_convective(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """``(dT/dq qd) qd`` (r, 3) of every row's slip velocity [m/s^2], as
        :meth:`convective` the gaps'."""
        return self._convective(q, qd)[1]

    def _convective(self, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # the gaps' and the slips' together, the last state's kept: a held row's friction asks
        # for both at the state whose gaps asked (two contact evaluations, not four)
        if self._convective_key == self._state_key(q, qd):
            return self._convective_terms
        ends = self._ends(q, qd)
        if ends is None:
            self._convective_key = None
            return np.zeros(len(self)), np.zeros((len(self), 3))
        chart = self.chart()
        states = contact_history(self.model, *ends[:2],
                                 None if chart is None else np.stack([chart, chart]))
        self._keep_convective(q, qd, ends[2], states.gap_rate[:, self.rows],
                              states.slip_velocity[:, self.rows])
        return self._convective_terms

    def _state_key(self, q: np.ndarray, qd: np.ndarray) -> tuple:
        chart = self.chart()
        return q.tobytes(), qd.tobytes(), None if chart is None else chart.tobytes()

    def _ends(self, q: np.ndarray, qd: np.ndarray) -> tuple | None:
        """The two states of the central difference of the convective terms (positions,
        velocities) and its step, or None where nothing moves (the terms are zero) or they
        are kept already."""
        if self._convective_key == self._state_key(q, qd):
            return None
        speed = np.max(np.abs(qd) / self.model.coordinate_scale, initial=0.0)
        if speed == 0.0:
            return None
        s = 1e-6 / speed  # nothing moves by more than 1e-6 of the model's size
        return np.stack([q + s * qd, q - s * qd]), np.stack([qd, qd]), s

    def _keep_convective(self, q, qd, s: float, rate: np.ndarray, slip: np.ndarray) -> None:
        """Keep the convective terms at ``(q, qd)`` from the gap ``rate`` (2, r) and ``slip``
        velocities (2, r, 3) at the ends of their central difference of step ``s``."""
        self._convective_key = self._state_key(q, qd)
        self._convective_terms = (rate[0] - rate[1]) / (2 * s), (slip[0] - slip[1]) / (2 * s)

    def acceleration_scale(self, t: float, q: np.ndarray, qd: np.ndarray,
                           qdd: np.ndarray | None = None) -> float:
        """The size of the model's accelerations at ``(q, qd)`` [1/s^2, of its length scale]:
        gravity's, the free motion's (``qdd``, default the joints' accelerations), the
        turning's (a bead flung along a turning rod moves in a straight line: the rod's turn
        presses it)."""
        model = self.model
        if qdd is None:
            qdd = augmented_accelerations(model, t, q, qd, self.chart())[:model.n_coordinates]
        speed = np.max(np.abs(qd) / model.coordinate_scale, initial=0.0)
        gravity = float(np.linalg.norm(model.gravity)) / model.length_scale
        return max(gravity, np.max(np.abs(qdd) / model.coordinate_scale, initial=0.0),
                   speed * speed)

    def watch(self, q: np.ndarray, qd: np.ndarray) -> None:
        """Where each row fires from now on, below its gap now: an event's function is then
        positive where an impact leaves it, and the driver watches it from there on
        (:data:`CLOSED`, :data:`PAST`, :data:`LEAVING`)."""
        gap, rate = self.states(q, qd)
        touching = gap <= CLOSED * self.scale
        #: rows left touching without opening (an idle row that fires again closes slowly)
        self.idle = touching & (rate <= CLOSING * self.rest_speed)
        below = np.where(self.idle, PAST, LEAVING) * self.scale
        self.floor = np.where(touching, np.minimum(gap, 0.0) - below, -PAST * self.scale)


def impulses(W: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``lam >= 0`` with ``w = W lam + b >= 0`` and ``lam . w = 0``, for ``W`` symmetric
    positive semi-definite: the minimum of ``lam^T W lam / 2 + b^T lam`` over ``lam >= 0``,
    by Lawson and Hanson's active set (the rows that push are freed one at a time, the
    most violated first; a step that would make one pull stops where it reaches zero).

    Rows that depend on each other (a face's corners) make ``W`` singular and the impulses
    not unique: where the rows pushing are so, ``W`` gains ``1e-12`` of its mean diagonal
    there, a compliance far below any physical one, which shares the impulse evenly; the
    rates ``w`` are checked with ``W`` itself."""
    a = len(b)
    if a == 1 and W[0, 0] > 0.0:  # one row (the common case): the active set's answer at once
        return np.array([-b[0] / W[0, 0] if b[0] < 0.0 else 0.0])
    shift = 1e-12 * max(float(np.trace(W)) / max(a, 1), np.finfo(float).tiny)
    lam, free = np.zeros(a), np.zeros(a, dtype=bool)
    tol = 1e-12 * max(float(np.max(np.abs(b), initial=0.0)), np.finfo(float).tiny)
    for _ in range(4 * a + 10):
        w = W @ lam + b
        violated = ~free & (w < -tol)
        if not np.any(violated):
            break
        free[np.flatnonzero(violated)[np.argmin(w[violated])]] = True
        for _ in range(a + 1):
            z = np.zeros(a)
            Wf = W[np.ix_(free, free)]
            # (a single row's condition is 1 unless it is zero: no SVD for it)
            if (Wf[0, 0] == 0.0 if len(Wf) == 1 else np.linalg.cond(Wf) > 1e10):
                # dependent rows: the least compliance that helps
                Wf = Wf + shift * np.eye(len(Wf))
            z[free] = np.linalg.solve(Wf, -b[free])
            if np.all(z[free] > 0.0):
                lam = z
                break
            down = np.flatnonzero(free & (z <= 0.0))
            ratios = lam[down] / (lam[down] - z[down])
            lam = lam + float(np.min(ratios)) * (z - lam)
            free[down[np.argmin(ratios)]] = False  # the first to reach zero, exactly
            free &= lam > 0.0
            lam[~free] = 0.0
    w = W @ lam + b
    if np.all(w >= -1e-9 * max(float(np.max(np.abs(b), initial=0.0)), float(np.max(
            np.abs(W @ lam), initial=0.0)))):
        return lam
    raise ModelError("the impact's impulses were not found (its contacts' rows depend on "
                     "each other with different restitutions); give the contacts compliant "
                     "laws, or one restitution")
