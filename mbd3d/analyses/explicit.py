"""The explicit integrators of forward dynamics: the compiled Runge-Kutta pairs on the index-1
equations, with projection onto the constraints.

At every right-hand side evaluation the accelerations and multipliers come from the augmented
equations (:mod:`mbd3d.analyses.accelerations`). The state is integrated by the compiled pairs
of :mod:`mbd3d.numerics.compiled.runge_kutta` in the loop of
:mod:`mbd3d.numerics.compiled.integration`, which returns here at output times and when the
constraints have drifted. Because the index-1 equations only hold the constraints at
acceleration level, position and velocity drift; after an accepted step whose residual
exceeds ``constraint_tol`` the state is projected back onto ``C = 0`` and ``Cq qd = -Ct``
(mass-weighted least change: Newton-Raphson for positions, one linear solve for velocities)
and the method goes on from the projected state with its step size (only its first stage is
evaluated again). Output times are interpolated with the method's dense output and projected
the same way, so every reported state satisfies the constraints. The step loop around it is
the driver's (:mod:`mbd3d.analyses.driver`).
"""

from __future__ import annotations

import contextlib
import warnings

import numpy as np

from mbd3d.model import constraints
from mbd3d.numerics.compiled import callbacks, integration as stepping
from mbd3d.numerics.compiled.runge_kutta import TABLEAUS, interpolate, rms
from mbd3d.numerics.compiled.structures import workspace
from mbd3d.model.equations import generalized_forces, python_parts
from mbd3d.errors import (IntegrationError, ModelError, SingularJacobianError, StiffnessWarning,
                          user_stacklevel)
from mbd3d.numerics.linalg import SingularMatrix, factor_model_augmented, jacobian_scaling
from mbd3d.numerics.rotations import to_quaternion
from mbd3d.analyses.accelerations import consistent_accelerations, rows_dependent
from mbd3d.analyses.dissipation import contact_power, dissipation_controls
from mbd3d.analyses.driver import DynamicsRequest, Integrator, Segment
from mbd3d.analyses.kinematics import project_state
from mbd3d.analyses.position import LARGEST_DENSE_ANALYSIS, singular_error

__all__ = ["ExplicitRungeKutta", "FAILURES", "stiffest_elements"]


class ExplicitRungeKutta(Integrator):
    """A compiled explicit pair (``request.method``, one of
    :data:`mbd3d.numerics.compiled.runge_kutta.TABLEAUS`) as the driver runs it."""


    def __init__(self, request: DynamicsRequest):
        model = self.model = request.model
        if request.step is not None:
            raise ModelError(f"step applies to method='generalized-alpha'; the "
                             f"{request.method} integrator chooses its own steps (limit them "
                             "with max_step)")
        self.request, self.tableau = request, TABLEAUS[request.method]
        self.stats = {"method": request.method, "steps": 0, "rejected_steps": 0,
                      "rhs_evaluations": 0,
                      "projections": 0, "chart_resets": 0, "max_drift": 0.0,
                      "singular_outputs": [], "wall_time": 0.0}
        self.n, self.spatial = model.n_coordinates, model.dim == 3
        # the reference rotations of the integration, moved in place by the compiled loop
        self.charts = np.array(model.charts0) if self.spatial else None
        # the charts as quaternions, their signs carried along every step (continuous output)
        self._turns = to_quaternion(self.charts) if self.spatial else np.zeros((0, 4))
        self.redundant = False  # set at the start: the constraint rows depend on each other
        self.key = self.arrays = self._python = None
        # the contacts' dissipated power and energy, in the workspace (dissipation.py)
        self._power = self._stage_power = self._energy = self._dense_power = None
        self.t_last, self.step_last = 0.0, 0.0  # the last step's start and length [s]

    def chart(self) -> np.ndarray | None:
        return self.charts.copy() if self.spatial else None

    def turns(self) -> np.ndarray | None:
        return self._turns.copy() if self.spatial else None

    def rows_dependent(self, q: np.ndarray) -> bool:
        return rows_dependent(self.model, self.request.t[0], q, self.chart())

    @contextlib.contextmanager
    def session(self):
        model = self.model
        with callbacks.Run(lambda tt, q, qd, charts: python_parts(model, tt, q, qd, charts),
                           solve=lambda values, rhs: model._augmented_pattern.solve(values, rhs),
                           accelerations=self._python_accelerations) as key:
            self.key = key
            yield

    def _python_accelerations(self, tt, q, qd, charts_now):
        """``(qdd, lam)`` at ``(tt, q, qd)`` solved in Python, for a stage the compiled
        right-hand side does not cover (see below)."""
        # redundant constraints (the augmented Lagrangian), joint friction (consistent with
        # its reactions) or rigid contacts held at rest: solved in Python. A stage that
        # cannot be solved is reported to the loop as the compiled solve reports it (None:
        # singular), which retries the step shorter and names the failure if it persists.
        charts_now = charts_now if self.spatial else None
        try:
            qdd, lam, _ = consistent_accelerations(self.model, tt, q, qd, charts_now,
                                                   redundant=self.redundant, fallback=False)
            if len(self._power):  # as the compiled forces report it
                self._power[:] = contact_power(self.model, q, qd, charts_now)
            qdd, lam = self._held_accelerations(tt, q, qd, qdd, lam)
            if self.holding and len(self._power):  # the friction of the rows held at rest
                self._power[self.held.rigid.rows] += self.held.power(tt, q, qd)
            return qdd, lam
        except (SingularJacobianError, IntegrationError):
            return None

    def _accelerations(self, tt: float, q: np.ndarray, qd: np.ndarray) -> tuple:
        qdd, lam, _ = consistent_accelerations(self.model, tt, q, qd, self.chart(),
                                               fallback=self.redundant, redundant=self.redundant)
        if self.redundant:
            self.stats["singular_outputs"].append(float(tt))
        return self._held_accelerations(tt, q, qd, qdd, lam)

    def _held_accelerations(self, tt, q, qd, qdd, lam) -> tuple:
        """``(qdd, lam)`` with the forces of the rigid contacts held at rest."""
        if not self.holding:
            return qdd, lam
        return self.held.accelerations(tt, q, qd, qdd, lam)

    def _set_arrays(self) -> None:
        """The model's compiled arrays: the right-hand side in Python where the compiled one
        does not cover the model's state (see :meth:`_python_accelerations`)."""
        python = self.redundant or self.model.friction is not None or self.holding
        if self.arrays is None or python != self._python:
            self._python = python
            self.arrays = self.model._core.arrays(python_accelerations=python)
            self.work = workspace(self.spatial, self.arrays)
            power, stages, dissipated, dense = stepping.dissipation_arrays(self.work)
            if self._power is not None:  # the energy the contacts dissipated so far
                dissipated[:] = self._energy
                stages[0] = self._stage_power[0]
            elif dissipated.shape[1]:
                dissipated[4:] = dissipation_controls(self.model, self.request.atol)
            self._power, self._stage_power, self._energy = power, stages, dissipated
            self._dense_power = dense[:self.tableau.dense_rows]

    # the integrated state is y = (q, v): positions and the velocities of BodyType.velocities
    # (angular velocities in body axes for spatial bodies), not (q, qd)
    def _split(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return y[:self.n].copy(), self.model.body_type.rates(y[:self.n], y[self.n:])

    def _join(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        return np.concatenate([q, self.model.body_type.velocities(q, qd)])

    def start(self, t0: float, q: np.ndarray, qd: np.ndarray, redundant: bool) -> tuple:
        # Redundant constraints (dependent rows from the start, as in Bricard's mechanism)
        # are solved throughout by the augmented Lagrangian, which gives the accelerations
        # and minimum-norm multipliers continuously. Rows that become dependent later (a
        # singular position) stop the run with a SingularJacobianError instead: there the
        # index-1 accelerations jump, and generalized-alpha is the method to use.
        self.redundant = redundant
        first = self._accelerations(t0, q, qd)
        model, n, r = self.model, self.n, self.request
        self._set_arrays()
        # atol in the model's units: positions in units of its length, angles in radians,
        # rates per second, so that a micrometre mechanism is integrated as accurately
        self.atol_y = r.atol * np.tile(model.coordinate_scale, 2)
        self.y = self._join(q, qd)
        self.f = np.empty(2 * n)
        self.K = np.empty((self.tableau.n_stored, 2 * n))
        self.y_old = np.empty(2 * n)
        self.dense = np.empty((self.tableau.dense_rows, 2 * n))
        self.recent = np.zeros(_RECENT_STEPS)  # lengths of the last accepted steps [s]
        self.counters = np.zeros(4, dtype=np.int64)
        self.drift = np.zeros(2)
        self._first_stage(t0)
        self.h = _initial_step(self.arrays, self.key, self.tableau, t0, self.y, self.f,
                               self.charts, r.rtol, self.atol_y,
                               min(r.max_step, r.t[-1] - t0), self.counters, self.work)
        self.stats["initial_step"] = self.h
        self.t_now = self.t_last = t0
        self.check_at = _STIFFNESS_CHECK_STEPS
        return first

    def _first_stage(self, tt: float) -> None:
        status = stepping.derivative(self.arrays, self.key, tt, self.y, self.charts, self.f,
                                     self.work)
        self._stage_power[0] = self._energy[2] = self._power  # the next step's start
        self.counters[stepping.RHS_EVALUATIONS] += 1
        if status != 0:
            raise self._failure(stepping.SINGULAR if status == 1 else stepping.DIVERGED, tt,
                                self.y)

    def advance(self, t_target: float, every_step: bool) -> Segment:
        r = self.request
        # every_step: each step passes the "output" time, so the loop returns after it with
        # its dense output (for the events)
        flags, self.t_now, t_old, step, self.h = stepping.advance(
            self.arrays, self.key, self.tableau.arrays(), self.t_now, self.y, self.f, self.h,
            self.t_now if every_step else t_target, r.t[-1], r.rtol, self.atol_y, r.max_step,
            self.charts, self._turns, r.constraint_tol, _STEP_CHART_LIMIT, self.recent,
            self.counters, self.drift, self.K, self.y_old, self.dense,
            0.0 if self.redundant else STEP_COLLAPSE, self.check_at, _STEPS_PER_CALL,
            self.work)
        self.t_last, self.step_last = t_old, step
        c = self.counters
        self.stats.update(steps=int(c[stepping.STEPS]),
                          rhs_evaluations=int(c[stepping.RHS_EVALUATIONS]),
                          chart_resets=int(c[stepping.CHART_RESETS]),
                          rejected_steps=int(c[stepping.REJECTED]),
                          max_drift=float(self.drift[0]))
        kind, dense, y_old = self.tableau.dense_kind, self.dense, self.y_old

        def state_at(tt: float) -> tuple[np.ndarray, np.ndarray]:
            return self._split(interpolate(kind, dense, y_old, t_old, step, tt))
        return Segment(t_old, self.t_now, state_at, flags, {"step": step})

    def check(self, segment: Segment) -> None:
        flags, model, method = segment.flags, self.model, self.request.method
        if flags in FAILURES:
            raise self._failure(flags, segment.t_new, self.y_old)
        if flags & stepping.CHECK_STIFFNESS:
            t = self.request.t
            spacing = float(np.min(np.diff(t)))
            average = (segment.t_new - float(t[0])) / self.stats["steps"]
            message = (_stiffness_message(model, method, segment.t_new, average, spacing)
                       if average < _CRAWL * spacing else None)
            if message is not None:
                warnings.warn(StiffnessWarning(message), stacklevel=user_stacklevel())
        if flags & stepping.COLLAPSED:
            # a regular collapse (a sharp force) becomes the new normal
            singular = _singular_here(
                model, segment.t_new, self.y[:self.n], self.chart(),
                f"forward dynamics of '{model.name}' ({method}: the steps collapsed "
                f"to {segment.info['step']:.1e} s)")
            if singular is not None:
                raise singular
            self.recent[:] = 0.0

    def output(self, t: float, segment: Segment) -> tuple:
        tol, (q, qd) = self.request.projection_tol, segment.state_at(t)
        # the dense output drifts as little as a step: one factorization projects it
        projected = None if self.redundant else _project_with_one_factorization(
            self.model, t, q, qd, tol, self.chart())
        q, qd = projected or project_state(self.model, t, q, qd, tol, self.chart(),
                                           self.redundant)
        if self.holding:
            q, qd = self.held.settle(t, q, qd, tol=tol) or (q, qd)  # rows held at rest too
        return (q, qd) + self._accelerations(t, q, qd)

    def after_step(self, segment: Segment) -> None:
        held = self.holding
        if not (segment.flags & stepping.DRIFTED or held):
            return
        q, qd = self._split(self.y)
        if held:
            self.held.follow(self.t_now, q, qd)  # sliding rows follow their slip
        tol, t_now = self.request.projection_tol, self.t_now
        changed = bool(segment.flags & stepping.DRIFTED)
        if changed:
            projected = None if self.redundant else _project_with_one_factorization(
                self.model, t_now, q, qd, tol, self.chart())
            q, qd = projected or project_state(self.model, t_now, q, qd, tol, self.chart(),
                                               self.redundant)
        if held and (settled := self.held.settle(t_now, q, qd)) is not None:
            q, qd, changed = *settled, True  # the rows held at rest drifted (resting.py)
        if not changed:
            return
        self.stats["projections"] += 1
        self.restart(t_now, q, qd)

    def dissipated(self, t: float, segment: Segment | None) -> np.ndarray | None:
        if not self._energy.shape[1]:
            return None
        if segment is None:
            return self._energy[0].copy()
        return self._energy_at(t, segment.t_start, segment.info["step"])

    def _energy_at(self, t: float, t_old: float, step: float) -> np.ndarray:
        """The contacts' dissipated energies at ``t`` in the last step ``[t_old, t_old +
        step]``, from its interpolant (computed with its dense output)."""
        if step == 0.0 or t >= t_old + step:
            return self._energy[0].copy()
        return interpolate(self.tableau.dense_kind, self._dense_power, self._energy[1], t_old,
                           step, t)

    def restart(self, t: float, q: np.ndarray, qd: np.ndarray) -> None:
        # the method goes on from the new state: only its first stage is evaluated again,
        # and the contacts have dissipated what they had at t, inside the last step
        if self._energy.shape[1] and t < self.t_now:  # an event's time: dense output
            self._energy[0] = self._energy_at(t, self.t_last, self.step_last)
        self._set_arrays()  # rows held at rest or let go change how it is evaluated
        self.y[:] = self._join(q, qd)
        self.t_now = t
        self._first_stage(t)

    def _failure(self, flags: int, t_fail: float, y_fail: np.ndarray) -> Exception:
        model, method = self.model, self.request.method
        q, qd = self._split(y_fail)
        if flags == stepping.STEP_TOO_SMALL:
            return _step_failure(model, method, t_fail, q, self.chart(),
                                 "the step size fell below the spacing of floating-point "
                                 "numbers at this time")
        if flags == stepping.SINGULAR:
            try:  # raises the error that names the dependent joints
                consistent_accelerations(model, t_fail, q, qd, self.chart(), fallback=False)
            except (SingularJacobianError, IntegrationError) as error:
                return error
        try:  # a motion or force that cannot be evaluated there is named
            constraints.driver_values(model, t_fail), constraints.motion_phases(model, t_fail)
            generalized_forces(model, t_fail, constraints.frames(model, q, qd, self.chart()))
        except ModelError as error:
            return error
        return IntegrationError(f"forward dynamics of '{model.name}': the state became "
                                f"non-finite at t = {t_fail:.6g} s (the integration diverged)",
                                time=t_fail)


def _project_with_one_factorization(model, t: float, q: np.ndarray, qd: np.ndarray, tol: float,
                                    charts: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The mass-weighted projection of :func:`project_state` for a state that has drifted
    only slightly (a step of the explicit integrators), from one factorization.

    ``[M Cq^T; Cq 0]`` is factored once at ``q``; the position and then the velocity
    corrections are simplified Newton iterations with those factors. The drift is far below
    the size of anything in the matrix, so each iteration cuts the residual by orders of
    magnitude, where :func:`project_state` would refactor at every Newton iterate and again
    for the velocities. ``None`` when the iterations do not settle (the caller then falls
    back to :func:`project_state`, which reports singular positions by name).
    """
    n = model.n_coordinates
    zeros = np.zeros(n)
    fr, C, jac_data = _constraints_at(model, t, q, charts)
    try:
        lu = factor_model_augmented(
            model, model.body_type.mass_blocks(fr, model.mass, model.inertia), jac_data)
    except SingularMatrix:
        return None
    for _ in range(_SIMPLIFIED_NEWTON_ITERATIONS):
        if constraints.largest_relative(model, C) <= tol:
            break
        q = q + lu.solve(np.concatenate([zeros, -C]))[:n]
        fr, C, jac_data = _constraints_at(model, t, q, charts)
    else:
        return None
    nu = constraints.velocity_rhs(model, t, fr)
    for _ in range(_SIMPLIFIED_NEWTON_ITERATIONS):
        violation = constraints.jacobian_times(model, jac_data, qd) - nu
        if constraints.largest_relative(model, violation) <= tol:
            return q, qd
        qd = qd - lu.solve(np.concatenate([zeros, violation]))[:n]
    return None


#: iterations allowed to :func:`_project_with_one_factorization` before falling back
_SIMPLIFIED_NEWTON_ITERATIONS = 6


#: smallest singular value of ``Cq``, relative to its largest, below which a collapsed step
#: of an explicit integrator is put down to a singular position: the index-1 accelerations
#: grow without bound there, and the steps shrink until they underflow
NEARLY_SINGULAR = 1e-4


#: an accepted step this many times shorter than the longest of the recent ones is a collapse,
#: and the Jacobian's conditioning is checked there
STEP_COLLAPSE = 1e-3
#: accepted steps over which the longest recent step is taken
_RECENT_STEPS = 50


#: accepted steps after which the explicit integrators look at their average step
_STIFFNESS_CHECK_STEPS = 200
#: an average step this many times shorter than the output spacing is a crawl, when a stiff
#: element explains it (one whose longest stable step is shorter than the output spacing)
_CRAWL = 1e-2


def stiffest_elements(model) -> list[tuple[float, str]]:
    """The force elements by how fast they make the model respond, fastest first:
    ``(rate [1/s], description)``, the rate being ``sqrt(k / m)`` of a spring and ``c / m`` of a
    damper on the reduced mass (or inertia) of the bodies they join. An explicit method is
    stable for steps up to about 3 / rate."""
    from mbd3d.model.springs import RotationalSpringDamper, SpringDamper  # noqa: PLC0415

    def reduced(bodies, inertia: bool) -> float:
        values = []
        for body in bodies:
            if body is None or body.is_ground:
                continue
            if not inertia:
                values.append(body.mass)
            else:
                values.append(float(np.min(np.linalg.eigvalsh(np.atleast_2d(body.inertia)))))
        return 1.0 / sum(1.0 / v for v in values) if values else np.inf

    found = []
    for element in model.forces:
        if isinstance(element, (SpringDamper, RotationalSpringDamper)):
            rotational = isinstance(element, RotationalSpringDamper)
            m = reduced((element.body_i, element.body_j), rotational)
            k, c = float(element.stiffness or 0.0), float(element.damping or 0.0)
            rate = max(np.sqrt(k / m), c / m)
            units = ("N m/rad", "N m s/rad", "kg m^2") if rotational else ("N/m", "N s/m", "kg")
            found.append((rate, f"spring-damper '{element.name}' (k = {k:.3g} {units[0]}, "
                                f"c = {c:.3g} {units[1]} on {m:.3g} {units[2]}: "
                                f"{rate:.3g} 1/s)"))
    return sorted(found, reverse=True)


def _stiffness_message(model, method: str, t: float, average_step: float, spacing: float
                       ) -> str | None:
    """What to tell the user when the explicit steps crawl, or None when no stiff element
    explains the short steps (then the motion itself is fast, and the steps are right)."""
    elements = stiffest_elements(model)
    if not elements:
        return None
    limit = 3.0 / elements[0][0]  # the longest stable explicit step [s]
    if limit >= spacing:
        # an element slower than the outputs does not make the steps crawl between them
        # (a cam's knots, a fast motion's accuracy do: the steps are right)
        return None
    culprit = (f"{elements[0][1]} makes the model stiff: explicit steps above about "
               f"{limit:.1e} s are unstable")
    return (f"forward dynamics of '{model.name}' ({method}) is crawling at t = {t:.6g} s: its "
            f"steps average {average_step:.1e} s, {spacing / average_step:.0e} times shorter "
            f"than the output spacing of {spacing:.3g} s. The {culprit}. Use "
            "method='generalized-alpha' with step= a fraction of the motion's time scale, "
            "which is not limited by stiffness.")


def _singular_here(model, t: float, q: np.ndarray, charts, what: str) -> Exception | None:
    """A :class:`SingularJacobianError` naming the joints when the constraint Jacobian at
    ``q`` is (nearly) singular, else None (also when the model is too large to tell)."""
    if not (np.all(np.isfinite(q)) and model.n_constraints
            and model.n_constraints * model.n_coordinates <= LARGEST_DENSE_ANALYSIS):
        return None
    Cq = constraints.jacobian(model, t, q, constraints.frames(model, q, charts=charts),
                              sparse=False)
    rows, columns = jacobian_scaling(model)  # in the model's units, whatever its size
    s = np.linalg.svd(rows[:, None] * Cq * columns[None, :], compute_uv=False)
    if s[-1] <= NEARLY_SINGULAR * s[0]:
        return singular_error(model, Cq, t, what)
    return None


def _step_failure(model, method: str, t: float, q: np.ndarray, charts, message: str
                  ) -> Exception:
    """The error for an explicit integrator that cannot take a step: a
    :class:`SingularJacobianError` naming the joints when the mechanism is at (or next to) a
    singular position, which is where the steps of an index-1 method collapse, otherwise an
    :class:`IntegrationError`."""
    what = f"forward dynamics of '{model.name}'"
    singular = _singular_here(model, t, q, charts,
                              f"{what} ({method} could not take a step: {message})")
    if singular is not None:
        return singular
    return IntegrationError(
        f"{what}: the {method} integrator failed at t = {t:.6g} s: {message}. Try a smaller "
        "max_step, looser tolerances or method='generalized-alpha' for stiff models.", time=t)


def _constraints_at(model, t, q, charts) -> tuple:
    """``(frames, C, Jacobian values)`` at positions ``q``."""
    fr = constraints.frames(model, q, charts=charts)
    C, jac_data, _ = constraints.evaluate(model, t, fr)
    return fr, C, jac_data



#: accepted steps the compiled loop takes before it returns to Python anyway, so that an
#: interrupt (Ctrl-C) and the progress bar are seen during a long stretch without outputs
_STEPS_PER_CALL = 2000
#: ``|g|`` above which the explicit integrators move a body's chart between steps: zero, so that
#: every step starts from g = 0, where the Rodrigues parameters are nearly linear in the
#: rotation. With the usual limit (a quarter turn) a tumbling body's g grew through each chart
#: in three steps whose error estimates grew faster than the step control predicts, and one
#: step in three was rejected; a reset costs one 3x3 product per body, not a restart.
_STEP_CHART_LIMIT = 0.0
#: what the compiled loop returns when it failed
FAILURES = (stepping.STEP_TOO_SMALL, stepping.SINGULAR, stepping.DIVERGED)


def _initial_step(arrays, key, tableau, t0: float, y: np.ndarray,
                  f: np.ndarray, charts, rtol: float, atol: np.ndarray, interval: float,
                  counters, work) -> float:
    """The first step (Hairer, Norsett and Wanner, *Solving ODEs I*, II.4): from the sizes of
    the state, its derivative and a difference of derivatives, so that the first step's error
    is near the tolerance."""
    scale = atol + np.abs(y) * rtol
    d0, d1 = rms(y, scale), rms(f, scale)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    h0 = min(h0, interval)
    f1 = np.empty_like(f)
    status = stepping.derivative(arrays, key, t0 + h0, y + h0 * f, charts, f1, work)
    counters[stepping.RHS_EVALUATIONS] += 1
    if status != 0:
        return h0
    d2 = rms(f1 - f, scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        # the rule's max(1e-6, 1e-3 h0): h0 is at most 1e-6 here (d1 is below 1e-5)
        h1 = 1e-6
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (tableau.error_order + 1))
    return min(100 * h0, h1, interval)
