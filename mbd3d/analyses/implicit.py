"""Implicit index-3 generalized-alpha integration with augmented-Lagrangian Newton iterations.

The generalized-alpha method of Chung and Hulbert (1993), applied to the index-3 equations of
motion as Arnold and Bruls (2007) do::

    M(q) qdd + Cq^T lam = Qe(t, q, qd)        C(q, t) = 0

at every step ``t_n -> t_n + h``. With ``a`` the method's acceleration-like variable,

    (1 - alpha_m) a_{n+1} + alpha_m a_n = (1 - alpha_f) qdd_{n+1} + alpha_f qdd_n
    q_{n+1}  = q_n + h qd_n + h^2 (1/2 - beta) a_n + h^2 beta a_{n+1}
    qd_{n+1} = qd_n + h (1 - gamma) a_n + h gamma a_{n+1}

so that ``qdd_{n+1} = beta' (q_{n+1} - q_hat)`` and ``qd_{n+1} = qd_hat + gamma' (q_{n+1} -
q_hat)`` are affine in the new positions. The one unknown is ``q_{n+1}``; the constraints are
enforced at position level by the method of multipliers (the index-3 augmented Lagrangian of
Bayo, Garcia de Jalon and Serna; Cuadrado et al.'s ALI3-P): Newton iterations on

    r(q) = M qdd + Cq^T (lam + p C(q)) - Qe = 0,   lam <- lam + p (C + Cq dq) after each
                                                  Newton step dq,

with the iteration matrix ``beta' M + gamma' D + K + p Cq^T Cq`` (``D``, ``K`` the tangent of the
applied forces: in closed form for spring-dampers, compiled, by finite differences for the
elements whose forces are Python functions). That matrix stays
positive definite where ``Cq`` loses rank, so the method passes singular configurations (the
IFToMM N-four-bar) and handles redundant constraints (Bricard's mechanism) without special
cases, and its sparsity is that of the mechanism (banded for a chain). The reported
velocities are projected onto ``Cq qd = -Ct`` with the same factors (mass-orthogonal), so
position and velocity drift stay at the Newton tolerance however long the run.

(the constraints linearised at the iterate: the multipliers' own Newton step, so that the
next step closes the constraints' quadratic remainder instead of flipping its sign). A step
has converged when Newton's last step was below the tolerance and the constraints hold at
the iterate it reached, tested before another factorization. The iteration matrix is
factored at every Newton iterate (two per step are typical): its
penalty part outweighs the mass matrix by the penalty ratio and must follow the configuration,
or the large constraint forces leak into the free directions. The spectral radius at infinity
``rho_inf`` (1: no numerical damping; 0: asymptotic annihilation) sets the coefficients; the
method is second order.

Between output times the steps of a model without rigid contacts, spatial gear meshes, joint
friction or force elements whose forces or tangent are not compiled (see
:mod:`mbd3d.numerics.compiled.force_tangents`) run in a compiled loop
(:mod:`mbd3d.numerics.compiled.alpha_loop`), compliant contacts' step rules included, the
same steps as this module's :meth:`GeneralizedAlphaIntegrator._step` takes; it hands back
what needs Python.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from mbd3d.model import constraints
from mbd3d.numerics.checks import finite_scalar
from mbd3d.errors import AccuracyWarning, IntegrationError, ModelError, user_stacklevel
from mbd3d.numerics.rotations import to_quaternion
from mbd3d.analyses.accelerations import consistent_accelerations, rows_dependent
from mbd3d.analyses.alpha_step import GeneralizedAlpha, IterationFactors, NewtonStep
from mbd3d.analyses.contact_steps import ContactSteps
from mbd3d.analyses.kinematics import project_state
from mbd3d.analyses.dissipation import TrapezoidalDissipation
from mbd3d.analyses.driver import DynamicsRequest, Integrator, Segment
from mbd3d.analyses.passages import PassageWatch
from mbd3d.model.spatial import CHART_LIMIT
from mbd3d.numerics.compiled import alpha_loop, generalized_alpha as kernel

__all__ = ["GeneralizedAlpha", "GeneralizedAlphaIntegrator", "LARGEST_TURN"]

#: the largest turn of a body in one step [rad] before generalized-alpha warns that its step is
#: too long for the motion (its phase error per step is about (h omega)^2 / 12: 8 % here)
LARGEST_TURN = 1.0
#: the turn per step is checked on the first steps and then on one step in this many: a step
#: too long for the motion is too long for most of its steps, and the check costs 9 us, a
#: sixth of a slider-crank's step
_TURN_SAMPLE = 16
#: whether the compiled loop takes the steps of the models it can (tests compare it with the
#: steps taken here; interpreted, ``NUMBA_DISABLE_JIT=1``, it runs as Python too)
COMPILED_STEPS = True
#: steps one call of :meth:`GeneralizedAlphaIntegrator.advance` takes at most before it returns
#: to the driver without reaching an output (so that the progress bar moves)
_STEPS_PER_CALL = 200


class GeneralizedAlphaIntegrator(Integrator):
    """Generalized-alpha with the fixed step ``request.step`` as the driver runs it (see
    :func:`mbd3d.forward_dynamics`, ``method="generalized-alpha"``).

    The step is kept between output times, whose states are interpolated (cubic Hermite on
    the step, then projected onto the constraints), and shortened only to land on the run's
    end, for one step to a quarter when Newton does not converge (near a singular
    configuration), and at compliant contacts and stops: to end just past each touch and
    release, and to resolve each impact while it lasts (see :mod:`~.compiled.contact_steps`). Rigid
    contacts at rest are held as in the explicit methods (:mod:`.resting`): their forces join
    each Newton iterate's applied forces, their drift is projected after each step. Changing
    the step disturbs the recursion (its ``a_n`` lags ``qdd`` by (alpha_m - alpha_f) h): a
    bar pendulum at 500 steps a swing failed when steps were cut to land on outputs every
    1.1 or 1.3 steps.
    """

    #: Newton's tolerance on the residual, the penalty ratio and the iterations per step
    newton_tol, relative_penalty, max_newton_iterations = 1e-10, 1e8, 30

    def __init__(self, request: DynamicsRequest):
        model = self.model = request.model
        constraints.require_holonomic(model, "forward dynamics with generalized-alpha "
                                             "(an index-3 method, on positions)")
        if request.step is None:
            raise ModelError("method='generalized-alpha' needs a fixed step [s], e.g. "
                             "step=1e-3 (the error of this second-order method scales with "
                             "step^2)")
        self.step = finite_scalar(request.step, "step (the fixed time step of "
                                  "generalized-alpha) [s]", positive=True)
        self.request, self.coefficients = request, GeneralizedAlpha(request.rho_inf)
        self.stats = {"method": "generalized-alpha", "rho_inf": request.rho_inf, "steps": 0,
                      "rejected_steps": 0, "newton_iterations": 0, "factorizations": 0,
                      "chart_resets": 0, "projections": 0, "max_drift": 0.0,
                      "singular_outputs": [],
                      "smallest_step": math.inf, "wall_time": 0.0}
        self.redundant = False  # set at the start: the constraint rows depend on each other
        self.passages = PassageWatch(model)
        self.stats["singular_passages"] = self.passages.passages
        # spatial models: the charts as quaternions whose signs follow the motion
        self._turns = None if model.charts0 is None else to_quaternion(model.charts0)
        # a writable copy: the kernels are compiled for writable arrays (model.charts0 is not)
        self.charts = None if model.charts0 is None else np.array(model.charts0)
        self.meshes = constraints.has_spatial_meshes(model)
        self._turn_warned = False
        self.newton = NewtonStep(model, self.coefficients, self.stats, self.newton_tol,
                                  self.relative_penalty, self.max_newton_iterations,
                                  request.projection_tol)
        self.contacts = ContactSteps(model, model._core.workspace())
        group = self.contacts.group
        if group is not None:
            self.stats["contact_retries"] = 0
        self.dissipation = TrapezoidalDissipation(model)
        #: whether the compiled loop takes the steps while nothing is held at rest (a rigid
        #: contact's impacts are events, whose steps the driver takes one by one)
        self.compiled_steps = (COMPILED_STEPS and self.newton.compiled_tangent
                               and not self.meshes
                               and (group is None or not np.any(group.rigid)))
        self._records = None

    def chart(self) -> np.ndarray | None:
        return self.charts

    def turns(self) -> np.ndarray | None:
        return None if self._turns is None else self._turns.copy()

    def rows_dependent(self, q: np.ndarray) -> bool:
        return rows_dependent(self.model, self.request.t[0], q, self.charts)

    def session(self):
        return self.newton.run

    def close(self) -> None:
        self.passages.close()  # a passage still open at the end (or at a failure)

    def _accelerations(self, tt: float, q: np.ndarray, qd: np.ndarray, lam_guess) -> tuple:
        qdd, lam, regular = self._consistent(tt, q, qd, lam_guess)
        if not regular:
            self.stats["singular_outputs"].append(float(tt))
        return qdd, lam

    def _take_holds(self) -> None:
        """The Newton step and the dissipation take the rigid rows held now (or none)."""
        held = self.held if self.holding else None
        self.newton.hold(held)
        self.dissipation.held = held

    def _consistent(self, tt: float, q: np.ndarray, qd: np.ndarray, lam_guess) -> tuple:
        """``(qdd, lam, regular)`` at ``(tt, q, qd)`` with the forces of the rigid contacts
        held at rest (from lam = 0 where the rows depend on each other: the minimum-norm
        multipliers)."""
        qdd, lam, regular = consistent_accelerations(self.model, tt, q, qd, self.charts,
                                                     None if self.redundant else lam_guess,
                                                     self.redundant)
        if self.holding:
            qdd, lam = self.held.accelerations(tt, q, qd, qdd, lam)
        return qdd, lam, regular

    def start(self, t0: float, q: np.ndarray, qd: np.ndarray, redundant: bool) -> tuple:
        self.redundant = redundant
        self._take_holds()
        self.qdd, self.lam = self._accelerations(t0, q, qd, None)
        self.q, self.qd, self.a = q, qd, self.qdd.copy()
        self.tt, self.h = t0, min(self.step, self.request.max_step)
        self.contacts.start(t0, q, qd, self.charts)
        self.dissipation.restart(t0, q, qd, self.charts)
        return self.qdd, self.lam

    def _trial_step(self) -> float:
        """The next step: the nominal one, shortened to land on the run's end (an output
        time it ends within rounding of is snapped to in :meth:`_step`)."""
        h_try = alpha_loop.trial_step(self.tt, min(self.h, self.contacts.limit(self.tt)),
                                      float(self.request.t[-1]))
        if self.meshes:
            # spatial gears know their angles modulo a tooth of the reduced ratio: no step may
            # turn a mesh's gears by a quarter of one (half what lets Newton's guess be a tooth
            # off, a factor of two left for gears speeding up)
            speed = constraints.mesh_turn_speed(self.model, self.q, self.qd, self.charts)
            if speed * h_try > 0.5 * math.pi:
                h_try = 0.5 * math.pi / speed
        return h_try

    def advance(self, t_target: float, every_step: bool) -> Segment:
        """Steps until the output time ``t_target`` (one step when ``every_step``, at most
        :data:`_STEPS_PER_CALL` otherwise, so that interrupts and progress are seen)."""
        if self.compiled_steps and not every_step and not self.holding:
            return self._advance_compiled(t_target)
        steps = 1 if every_step else _STEPS_PER_CALL
        for k in range(steps):
            t_old, q_old, qd_old, _ = self._step(t_target)
            if self.tt >= t_target or k == steps - 1:
                break  # the driver's after_step resets the charts after this one
            self._reset_charts()
        return self._segment(t_old, q_old, qd_old)

    def _segment(self, t_old: float, q_old: np.ndarray, qd_old: np.ndarray) -> Segment:
        """The last step, from ``(t_old, q_old, qd_old)`` to the state reached."""
        t_new, q, qd = self.tt, self.q, self.qd

        def state_at(t: float) -> tuple[np.ndarray, np.ndarray]:
            """The last step's end, or between its ends the cubic Hermite interpolant of the
            positions (and its derivative), for locating events."""
            if t >= t_new:
                return q, qd
            h = t_new - t_old
            s = (t - t_old) / h
            h00, h10, h01, h11 = (2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s,
                                  -2 * s**3 + 3 * s**2, s**3 - s**2)
            d00, d10, d01, d11 = ((6 * s**2 - 6 * s) / h, 3 * s**2 - 4 * s + 1,
                                  (-6 * s**2 + 6 * s) / h, 3 * s**2 - 2 * s)
            return (h00 * q_old + h10 * h * qd_old + h01 * q + h11 * h * qd,
                    d00 * q_old + d10 * qd_old + d01 * q + d11 * qd)
        return Segment(t_old, t_new, state_at)

    def _advance_compiled(self, t_target: float) -> Segment:
        """:meth:`advance` with the steps taken by the compiled loop
        (:mod:`mbd3d.numerics.compiled.alpha_loop`); what it hands back is done here: a step
        whose Newton iteration failed is taken by :meth:`_step` (shortened as there), a turn
        too long is warned of, a chart reset or a contact's touch or release restarts the
        recursion."""
        newton, stats, c = self.newton, self.stats, self.coefficients
        if self._records is None:
            n = self.model.n_coordinates
            self._records = (np.empty(2), np.empty(n), np.empty(n), np.empty(_STEPS_PER_CALL),
                             np.empty(_STEPS_PER_CALL), np.empty((_STEPS_PER_CALL, n)))
        times, q_old, qd_old, out_t, out_indicator, out_q = self._records
        budget, last = _STEPS_PER_CALL, None
        while True:
            settings = (float(self.step), float(self.request.max_step), newton.relative_penalty,
                        newton.newton_tol, newton.projection_tol, int(newton.max_iterations),
                        CHART_LIMIT, LARGEST_TURN, not self._turn_warned, int(stats["steps"]),
                        _TURN_SAMPLE)
            times[:] = self.tt, float(self.request.t[-1])
            # new arrays: the states handed out before (outputs, segments) stay as they were
            q, qd, qdd, a, lam = (np.array(x, dtype=float)
                                  for x in (self.q, self.qd, self.qdd, self.a, self.lam))
            contacts, dissipation = self.contacts, self.dissipation
            (status, tt, t_old, h, h_last, smallest, taken, t_step, _,
             switched) = alpha_loop.alpha_steps(
                newton.work, newton.arrays, newton.run.key, (c.alpha_m, c.alpha_f, c.beta,
                                                             c.gamma),
                settings, times, float(t_target), float(self.h), q, qd, qdd, a, lam,
                self.charts, newton.penalty, newton.lam_effective, *newton.buffers,
                newton.counters, q_old, qd_old, out_t[:budget], out_indicator[:budget],
                out_q[:budget], (contacts.state, contacts.clock, dissipation.z,
                                 dissipation.times, contacts.power))
            budget -= taken
            self.h = h  # shortened by retries and rejections even where no step was taken
            stats["rejected_steps"] = int(newton.counters[2])
            if contacts.group is not None:
                stats["contact_retries"] = contacts.retries
            if taken:
                self._accept_compiled(tt, h, (q, qd, qdd, a, lam), h_last, smallest, taken)
                last = (t_old, q_old.copy(), qd_old.copy())
                for k in range(taken):
                    self.passages.step(float(out_t[k]), float(out_indicator[k]), out_q[k],
                                       self.charts)
            if switched:  # a touch or a release in the step: see _step
                self.qdd, self.lam, _ = self._consistent(t_step, self.q, self.qd, self.lam)
                self.a = self.qdd.copy()
            if status == alpha_loop.TURNED:
                self._check_turn(self.q, q_old, h_last, t_step)
            elif status == alpha_loop.NOT_CONVERGED:
                last = self._step(t_target)[:3]
                budget -= 1
            if self.tt >= t_target or budget <= 0:
                return self._segment(*last)
            self._reset_charts()

    def _accept_compiled(self, tt: float, h: float, state: tuple, h_last: float,
                         smallest: float, taken: int) -> None:
        """Take the state, the counts and the last step's factors the compiled loop left."""
        newton, stats, c = self.newton, self.stats, self.coefficients
        self.tt, self.h = tt, h
        self.q, self.qd, self.qdd, self.a, self.lam = state
        # every iterate was finite (else its Newton iteration failed): a state that is not
        # can only be an overflow in the last update
        if not np.all(np.isfinite(self.q)) or not np.all(np.isfinite(self.qd)):
            raise IntegrationError(self._not_finite(tt), time=tt)
        stats["steps"] += taken
        stats["smallest_step"] = min(stats["smallest_step"], smallest)
        stats["newton_iterations"], stats["factorizations"] = (int(newton.counters[0]),
                                                               int(newton.counters[1]))
        beta_prime = (1.0 - c.alpha_m) / (h_last * h_last * c.beta * (1.0 - c.alpha_f))
        self.S = IterationFactors(newton.arrays, newton.buffers, None, newton.penalty.copy(),
                                  beta_prime, kernel.last_mass_blocks(newton.work))

    def _not_finite(self, t: float) -> str:
        return (f"forward dynamics of '{self.model.name}': the state became non-finite at "
                f"t = {t:.6g} s")

    def _step(self, t_target: float) -> tuple:
        """One accepted step towards ``t_target`` (shorter ones after a rejection), with the
        passages, the state's finiteness and the turn per step checked; returns the step's
        start ``(t_old, q_old, qd_old)`` and its end before it was snapped to the target."""
        while True:
            h_try = self._trial_step()
            result = self.newton(self.tt + h_try, h_try, self.q, self.qd, self.qdd, self.a,
                                 self.lam, self.charts)
            if result is not None:
                shorter = self.contacts.retry(h_try, result[0][0], result[0][1], self.charts)
                if shorter is None:
                    break
                # across a touch or a release: end there
                self.stats["contact_retries"] = self.contacts.retries
                self.h = shorter
                continue
            self.newton.counters[2] += 1
            self.stats["rejected_steps"] = int(self.newton.counters[2])
            self.h = 0.25 * h_try
            if self.h < 1e-14 * max(1.0, abs(self.tt)):
                raise IntegrationError(self._no_convergence(h_try), time=self.tt)
        (q, qd, qdd, a, lam), S = result
        t_old, q_old, qd_old = self.tt, self.q, self.qd
        self.tt += h_try
        if self.contacts.accept(self.tt, q, qd, self.charts):
            # a touch or a release in the step: the recursion starts again (see contact_steps)
            qdd, lam, _ = self._consistent(self.tt, q, qd, lam)
            a = qdd.copy()
        self.stats["steps"] += 1
        self.stats["smallest_step"] = min(self.stats["smallest_step"], h_try)
        self.dissipation.step(self.tt, q, qd, self.charts,
                              None if self.contacts.group is None else self.contacts.power)
        self.q, self.qd, self.qdd, self.a, self.lam, self.S = q, qd, qdd, a, lam, S
        t_step = self.tt  # where passages are noted: the step's end before it is snapped
        self.passages.step(t_step, S.indicator, q, self.charts)
        if not np.all(np.isfinite(q)) or not np.all(np.isfinite(qd)):
            raise IntegrationError(self._not_finite(t_step), time=t_step)
        steps = self.stats["steps"]
        if not self._turn_warned and (steps <= _TURN_SAMPLE or steps % _TURN_SAMPLE == 0):
            self._check_turn(q, q_old, h_try, t_step)
        # back to the nominal step after a recovery, doubling: jumping straight back from a
        # quarter step, the free slider-crank at h = 1e-3 (crank at 80 rad/s) cycled between
        # rejection and return with the predictor's error growing every cycle, to 1e18 m at
        # t = 0.113 s, where no step converged any more
        self.h = min(self.step, self.request.max_step, 2.0 * self.h)
        if abs(self.tt - t_target) <= 1e-12 * max(1.0, abs(t_target)):
            self.tt = t_target
        return t_old, q_old, qd_old, t_step

    def _no_convergence(self, h_try: float) -> str:
        """What to say when no step, however short, converges from the state reached. With
        steps long for the motion (20 a swing or fewer), index-3 generalized-alpha's
        velocities can start to alternate from step to step and grow until the state is off
        its path: an independent implementation with a full Newton iteration does the same
        on a bar pendulum released level, at rho_inf = 0.9 and 20 steps a swing."""
        model, step = self.model, min(self.step, self.request.max_step)
        text = (f"forward dynamics of '{model.name}': generalized-alpha Newton iterations do "
                f"not converge at t = {self.tt:.6g} s, not even with the step shortened from "
                f"{step:.3g} s to {h_try:.3g} s. ")
        shape = (model.n_bodies, model.n_coords_per_body)
        v = model.body_type.velocities(self.q, self.qd).reshape(shape)
        speed = np.linalg.norm(v[:, model.dim:], axis=1)
        k = int(np.argmax(speed)) if len(speed) else 0
        if len(speed) and speed[k] * step > LARGEST_TURN:
            text += (f"Body '{model.bodies[k].name}' turns at {speed[k]:.3g} rad/s there, "
                     f"{speed[k] * step:.3g} rad per step: the run may have gone unstable "
                     "before (velocities alternating from step to step and growing). ")
        elif self.newton.singular:  # not a run gone unstable: the model
            text += ("The iteration matrix was numerically singular there (a pivot at the "
                     "rounding level of its column): a direction with neither inertia nor "
                     "constraint stiffness, such as a body many orders of magnitude lighter "
                     "than the others. ")
        rho = self.request.rho_inf
        damping = (f", or more numerical damping (rho_inf below {rho:g}, e.g. {rho / 2:g})"
                   if rho > 0 else "")
        return text + f"Try a smaller step{damping}, or check the model's stiffness and masses."

    def _check_turn(self, q: np.ndarray, q_old: np.ndarray, h: float, t: float) -> None:
        """Warn once when a body turned by more than :data:`LARGEST_TURN` in the step ``h``:
        a second-order method's error per step grows as (h omega)^2, and such a step gives a
        wrong motion however well Newton converges. The turn is read from the rotation
        coordinates' change (a spatial body's Rodrigues parameters change by about half the
        angle); see :data:`_TURN_SAMPLE` for the steps checked."""
        model = self.model
        shape = (model.n_bodies, model.n_coords_per_body)
        change = np.abs(q.reshape(shape)[:, model.dim:] - q_old.reshape(shape)[:, model.dim:])
        turn = change.max(axis=1) * (2.0 if model.dim == 3 else 1.0)
        k = int(np.argmax(turn)) if len(turn) else 0
        if len(turn) and turn[k] > LARGEST_TURN:
            self._turn_warned = True
            warnings.warn(AccuracyWarning(
                f"forward dynamics of '{model.name}' (generalized-alpha): body "
                f"'{model.bodies[k].name}' turned by {turn[k]:.3g} rad in the step of {h:.3g} s "
                f"ending at t = {t:.6g} s; a step this long for the motion gives a wrong swing "
                f"(the error grows as step^2). Use step <= {h * 0.1 / turn[k]:.2g} s (a tenth "
                "of a radian per step) or less."), stacklevel=user_stacklevel())

    def output(self, t: float, segment: Segment) -> tuple:
        # the reported velocities are projected onto Cq qd = -Ct, while the recursion keeps
        # its own, because projecting them inside it costs the method its order
        if t < segment.t_new:  # between step ends: the interpolant, projected
            q, qd = project_state(self.model, t, *segment.state_at(t),
                                  self.request.projection_tol, self.charts, self.redundant)
        else:
            q, S = self.q, self.S
            qd = self.newton.project_velocity(t, q, self.qd, self.charts, S, S.penalty)
        if self.holding:  # the rows held at rest too
            q, qd = self.held.settle(t, q, qd, tol=self.request.projection_tol) or (q, qd)
        return (q, qd) + self._accelerations(t, q, qd, self.lam)

    def after_step(self, segment: Segment) -> None:
        if self.holding:
            # the held rows' gaps drift as the joints' velocities do at acceleration level:
            # brought back where beyond the tolerance, the recursion going on (its
            # accelerations are the motion's; the change is of the tolerance's size)
            self.held.follow(self.tt, self.q, self.qd)  # sliding rows follow their slip
            settled = self.held.settle(self.tt, self.q, self.qd)
            if settled is not None:
                self.q, self.qd = settled
                self.stats["projections"] += 1
        self._reset_charts()

    def _reset_charts(self) -> None:
        q, qd, chart, moved = self.model.body_type.reset_charts(self.q, self.qd, self.charts,
                                                                turns=self._turns)
        if moved:
            # new orientation coordinates: restart the recursion from consistent
            # accelerations in the new charts (as at the initial time)
            self.stats["chart_resets"] += 1
            self.charts = chart
            self.restart(self.tt, q, qd)

    def dissipated(self, t: float, segment: Segment | None) -> np.ndarray | None:
        return self.dissipation.at(t)

    def restart(self, t: float, q: np.ndarray, qd: np.ndarray) -> None:
        self.tt, self.q, self.qd = t, q, qd
        self._take_holds()  # rows held or let go
        self.contacts.restart(t, q, qd, self.charts)
        self.dissipation.restart(t, q, qd, self.charts)
        self.qdd, self.lam, _ = self._consistent(t, q, qd, self.lam)
        self.a = self.qdd.copy()
