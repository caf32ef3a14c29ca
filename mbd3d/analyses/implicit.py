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

    r(q) = M qdd + Cq^T (lam + p C(q)) - Qe = 0,   lam <- lam + p C after each iteration,

with the iteration matrix ``beta' M + gamma' D + K + p Cq^T Cq`` (``D``, ``K`` the tangent of the
applied forces, by finite differences when the model has force elements). That matrix stays
positive definite where ``Cq`` loses rank, so the method passes singular configurations (the
IFToMM N-four-bar) and handles redundant constraints (Bricard's mechanism) without special
cases, and its sparsity is that of the mechanism (banded for a chain). The reported
velocities are projected onto ``Cq qd = -Ct`` with the same factors (mass-orthogonal), so
position and velocity drift stay at the Newton tolerance however long the run.

The iteration matrix is factored at every Newton iterate (two per step are typical): its
penalty part outweighs the mass matrix by the penalty ratio and must follow the configuration,
or the large constraint forces leak into the free directions. The spectral radius at infinity
``rho_inf`` (1: no numerical damping; 0: asymptotic annihilation) sets the coefficients; the
method is second order.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from mbd3d.model import constraints
from mbd3d.numerics.checks import finite_scalar
from mbd3d.model.equations import augmented_accelerations, generalized_forces, python_parts
from mbd3d.errors import AccuracyWarning, IntegrationError, ModelError, user_stacklevel
from mbd3d.numerics.compiled import callbacks, generalized_alpha as kernel
from mbd3d.numerics.rotations import to_quaternion
from mbd3d.analyses.accelerations import consistent_accelerations, rows_dependent
from mbd3d.analyses.contact_steps import ContactSteps
from mbd3d.analyses.kinematics import project_state
from mbd3d.analyses.dissipation import TrapezoidalDissipation
from mbd3d.analyses.driver import DynamicsRequest, Integrator, Segment
from mbd3d.analyses.passages import PassageWatch

__all__ = ["GeneralizedAlpha", "GeneralizedAlphaIntegrator", "LARGEST_TURN"]

#: the largest turn of a body in one step [rad] before generalized-alpha warns that its step is
#: too long for the motion (its phase error per step is about (h omega)^2 / 12: 8 % here)
LARGEST_TURN = 1.0
#: the turn per step is checked on the first steps and then on one step in this many: a step
#: too long for the motion is too long for most of its steps, and the check costs 9 us, a
#: sixth of a slider-crank's step
_TURN_SAMPLE = 16
#: steps one call of :meth:`GeneralizedAlphaIntegrator.advance` takes at most before it returns
#: to the driver without reaching an output (so that the progress bar moves)
_STEPS_PER_CALL = 200


@dataclass(frozen=True)
class GeneralizedAlpha:
    """Coefficients of the generalized-alpha method for a spectral radius ``rho_inf`` in [0, 1]
    (Chung and Hulbert 1993: second order, unconditionally stable, least low-frequency
    damping for the high-frequency damping asked)."""

    rho_inf: float

    def __post_init__(self):
        if not (np.isfinite(self.rho_inf) and 0.0 <= self.rho_inf <= 1.0):
            raise ModelError(f"rho_inf must be between 0 and 1, got {self.rho_inf!r}")

    @property
    def alpha_m(self) -> float:
        return (2.0 * self.rho_inf - 1.0) / (self.rho_inf + 1.0)

    @property
    def alpha_f(self) -> float:
        return self.rho_inf / (self.rho_inf + 1.0)

    @property
    def gamma(self) -> float:
        return 0.5 + self.alpha_f - self.alpha_m

    @property
    def beta(self) -> float:
        return 0.25 * (self.gamma + 0.5) ** 2


def _force_tangent(model, t: float, q: np.ndarray, qd: np.ndarray, charts, gamma_prime: float):
    """``K + gamma' D`` with ``K = -dQe/dq``, ``D = -dQe/dqd`` of the force elements (and the
    joints' friction's ``D``), or None when there are none (gravity does not depend on the state; the spatial bodies' quadratic
    velocity terms are left out of the iteration matrix, which only slows convergence). Groups with an analytic tangent
    (spring-dampers, contacts and joint stops) give it directly; the others are differenced forward, only over the
    coordinates of the bodies they act on."""
    if not model.force_groups and model.friction is None:
        return None
    n, nc, nb = model.n_coordinates, model.n_coords_per_body, model.n_bodies
    fr = constraints.frames(model, q, qd, charts)
    rows, cols, values = [], [], []
    if model.friction is not None:
        # the regularised friction's slope in the sliding speed, at the loads of this state:
        # steep near sticking, where Newton's iteration would not converge without it
        x = augmented_accelerations(model, t, q, qd, charts)
        if x is not None:
            damping = gamma_prime * model.friction.damping(model, fr, x[n:])
            r, c = np.nonzero(damping)
            rows.append(r), cols.append(c), values.append(damping[r, c])
    for group in model.force_groups:
        if group.analytic_tangent:
            r, c, v = group.tangent(model, t, fr, gamma_prime)
            keep = (r < n) & (c < n)  # the ground block (last) is not a coordinate
            rows.append(r[keep]), cols.append(c[keep]), values.append(v[keep])
    differenced = [g for g in model.force_groups if not g.analytic_tangent]
    if differenced:
        def forces(*state):
            Q = np.zeros((nb + 1, nc))
            for group in differenced:
                group.apply(model, t, constraints.frames(model, *state, charts), Q)
            return Q[:nb].ravel()
        bodies = sorted({int(model.padded_index(body)) for group in differenced
                         for element in group.elements for _, body in element.bodies()
                         if not body.is_ground})
        f0 = forces(q, qd)
        for j in (b * nc + k for b in bodies for k in range(nc)):
            for vector, weight in ((q, 1.0), (qd, gamma_prime)):
                h = 1.5e-8 * max(1.0, abs(vector[j]))
                shifted = vector.copy()
                shifted[j] += h
                column = -(forces(*((shifted, qd) if vector is q else (q, shifted))) - f0) / h
                nonzero = np.flatnonzero(column)
                rows.append(nonzero), cols.append(np.full(len(nonzero), j))
                values.append(weight * column[nonzero])
    if not values:
        return None  # elements acting on the ground only
    T = sp.coo_matrix((np.concatenate(values), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(n, n))
    return T.tocsr() if model.sparse else T.toarray()


class _IterationFactors:
    """The factors of the last iteration matrix of a step (``beta' M + gamma' D + K + p Cq^T
    Cq``), to project velocities with (:meth:`solve`), and the indicator of singular
    positions (the conditioning of ``Cq`` in the metric of ``M``, free of the step; see
    :mod:`mbd3d.analyses.passages`). They live in the run's buffers: valid until the next
    step."""

    def __init__(self, arrays, buffers, python_factors, penalty, beta_prime, blocks):
        self.arrays, self.buffers, self.python_factors = arrays, buffers, python_factors
        self.penalty = penalty
        matrix, band, _ = buffers
        log_det = (python_factors.log_abs_determinant if python_factors is not None
                   else kernel.log_abs_determinant(arrays, matrix, band))
        self.indicator = (log_det - len(blocks) * blocks.shape[1] * np.log(beta_prime)
                          - float(np.sum(np.linalg.slogdet(blocks)[1])))

    def solve(self, b: np.ndarray) -> np.ndarray:
        if self.python_factors is not None:
            return self.python_factors.solve(b)
        x = np.empty(len(b))
        kernel.solve_factored(self.arrays, *self.buffers, np.ascontiguousarray(b, dtype=float),
                              x)
        return x


def _tangent_storage(model, tangent) -> tuple[np.ndarray, bool]:
    """The applied forces' tangent in the scaled storage of the iteration matrix's layout
    (dense: (n, n) flattened; banded: the band), and whether Python must factor the matrix
    instead (SuperLU: the sparse layout, or a tangent reaching outside the band)."""
    pattern = model._penalty_pattern
    if pattern.layout == "sparse":
        return np.zeros(0), True
    if tangent is None:
        return np.zeros(0), False
    d = pattern.scale
    if pattern.layout == "dense":
        T = tangent.toarray() if sp.issparse(tangent) else np.asarray(tangent)
        return np.ascontiguousarray((d[:, None] * T * d[None, :]).ravel()), False
    # the band storage the compiled LU takes is LAPACK's, flattened in column order
    band = np.zeros((pattern.band_rows, pattern.size), order="F")
    if not pattern._add_to_band(band, sp.diags(d) @ sp.csr_matrix(tangent) @ sp.diags(d)):
        return np.zeros(0), True
    return band.ravel(order="F"), False


class GeneralizedAlphaIntegrator(Integrator):
    """Generalized-alpha with the fixed step ``request.step`` as the driver runs it (see
    :func:`mbd3d.forward_dynamics`, ``method="generalized-alpha"``).

    The step is kept between output times, whose states are interpolated (cubic Hermite on
    the step, then projected onto the constraints), and shortened only to land on the run's
    end, for one step to a quarter when Newton does not converge (near a singular
    configuration), and at compliant contacts and stops: to end just past each touch and
    release, and to resolve each impact while it lasts (see :mod:`.contact_steps`). Changing
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
                      "chart_resets": 0, "max_drift": 0.0, "singular_outputs": [],
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
        self.newton = _NewtonStep(model, self.coefficients, self.stats, self.newton_tol,
                                  self.relative_penalty, self.max_newton_iterations,
                                  request.projection_tol)
        self.contacts = ContactSteps(model)
        if self.contacts.group is not None:
            self.stats["contact_retries"] = 0
        self.dissipation = TrapezoidalDissipation(model)

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
        # from lam = 0 where the rows depend on each other: the minimum-norm multipliers
        qdd, lam, regular = consistent_accelerations(self.model, tt, q, qd, self.charts,
                                                     None if self.redundant else lam_guess,
                                                     self.redundant)
        if not regular:
            self.stats["singular_outputs"].append(float(tt))
        return qdd, lam

    def start(self, t0: float, q: np.ndarray, qd: np.ndarray, redundant: bool) -> tuple:
        self.redundant = redundant
        self.qdd, self.lam = self._accelerations(t0, q, qd, None)
        self.q, self.qd, self.a = q, qd, self.qdd.copy()
        self.tt, self.h = t0, min(self.step, self.request.max_step)
        self.contacts.start(t0, q, qd, self.charts)
        self.dissipation.restart(t0, q, qd, self.charts)
        return self.qdd, self.lam

    def _trial_step(self) -> float:
        """The next step: the nominal one, shortened to land on the run's end (an output
        time it ends within rounding of is snapped to in :meth:`_step`)."""
        tt, h = self.tt, min(self.h, self.contacts.limit(self.tt))
        end = float(self.request.t[-1])
        h_try = h
        if end - (tt + h_try) < 1e-9 * max(h, 1e-300):
            h_try = end - tt  # past the end, or within rounding of it
        elif end - (tt + h_try) < 0.05 * h:
            h_try = 0.5 * (end - tt)  # two even steps instead of a sliver
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
        steps = 1 if every_step else _STEPS_PER_CALL
        for k in range(steps):
            t_old, q_old, qd_old, _ = self._step(t_target)
            if self.tt >= t_target or k == steps - 1:
                break  # the driver's after_step resets the charts after this one
            self._reset_charts()
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
                self.stats["contact_retries"] += 1  # across a touch or a release: end there
                self.h = shorter
                continue
            self.stats["rejected_steps"] += 1
            self.h = 0.25 * h_try
            if self.h < 1e-14 * max(1.0, abs(self.tt)):
                raise IntegrationError(self._no_convergence(h_try), time=self.tt)
        (q, qd, qdd, a, lam), S = result
        t_old, q_old, qd_old = self.tt, self.q, self.qd
        self.tt += h_try
        if self.contacts.accept(self.tt, q, qd, self.charts):
            # a touch or a release in the step: the recursion starts again (see contact_steps)
            qdd, lam, _ = consistent_accelerations(self.model, self.tt, q, qd, self.charts,
                                                   None if self.redundant else lam,
                                                   self.redundant)
            a = qdd.copy()
        self.stats["steps"] += 1
        self.stats["smallest_step"] = min(self.stats["smallest_step"], h_try)
        self.dissipation.step(self.tt, q, qd, self.charts)
        self.q, self.qd, self.qdd, self.a, self.lam, self.S = q, qd, qdd, a, lam, S
        t_step = self.tt  # where passages are noted: the step's end before it is snapped
        self.passages.step(t_step, S.indicator, q, self.charts)
        if not np.all(np.isfinite(q)) or not np.all(np.isfinite(qd)):
            raise IntegrationError(f"forward dynamics of '{self.model.name}': the state "
                                   f"became non-finite at t = {t_step:.6g} s", time=t_step)
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
            return (q, qd) + self._accelerations(t, q, qd, self.lam)
        q, S = self.q, self.S
        qd = self.newton.project_velocity(t, q, self.qd, self.charts, S, S.penalty)
        return (q, qd) + self._accelerations(t, q, qd, self.lam)

    def after_step(self, segment: Segment) -> None:
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
        self.contacts.restart(t, q, qd, self.charts)
        self.dissipation.restart(t, q, qd, self.charts)
        self.qdd, self.lam, _ = consistent_accelerations(self.model, t, q, qd, self.charts,
                                                         self.lam, self.redundant)
        self.a = self.qdd.copy()


class _NewtonStep:
    """One generalized-alpha step: the Newton iteration on the new positions (compiled:
    :func:`mbd3d.numerics.compiled.generalized_alpha.newton_step`), with the iteration
    matrix's records and buffers made once per run."""

    def __init__(self, model, coefficients: GeneralizedAlpha, stats: dict, newton_tol: float,
                 relative_penalty: float, max_iterations: int, projection_tol: float):
        self.model, self.stats, self.projection_tol = model, stats, projection_tol
        self.am, self.af = coefficients.alpha_m, coefficients.alpha_f
        self.beta, self.gamma = coefficients.beta, coefficients.gamma
        self.newton_tol, self.relative_penalty = newton_tol, relative_penalty
        self.max_iterations = max_iterations
        #: whether the last step tried failed on a singular iteration matrix
        self.singular = False
        n, m = model.n_coordinates, model.n_constraints
        self.spatial = model.dim == 3
        self.work = model._core.workspace()
        self.arrays = model._core.penalty_arrays(model)
        self.penalty, self.lam_effective = np.empty(m), np.empty(m)
        layout = model._penalty_pattern.layout
        self.buffers = (np.empty((n, n) if layout == "dense" else (0, 0)),
                        np.empty(model._penalty_pattern.band_rows * n if layout == "banded"
                                 else 0),
                        np.empty(n, dtype=np.int64))
        self.counters = np.zeros(2, dtype=np.int64)
        # joint friction: every Newton iterate takes the friction of its own state's
        # multipliers (consistent with the reactions there, see mbd3d.model.friction), neither
        # a previous step's nor the iteration's penalty estimates, which are noisy at 1e-4
        self.run = callbacks.Run(
            lambda tt, q, qd, charts: python_parts(model, tt, q, qd, charts, friction=True),
            factor=lambda values, tangent: model._penalty_pattern.factor(values, tangent))

    def project_velocity(self, tt, q, qd, chart, lu, penalty):
        """Mass-orthogonal projection onto ``Cq qd = -Ct`` with the iteration matrix's
        factors: each pass cuts the violation by the penalty ratio."""
        model, stats = self.model, self.stats
        fr = constraints.frames(model, q, charts=chart)
        C, jac_data, _ = constraints.evaluate(model, tt, fr)
        nu = constraints.velocity_rhs(model, tt, fr)
        violation = constraints.jacobian_times(model, jac_data, qd) - nu
        stats["max_drift"] = max(stats["max_drift"],
                                 constraints.largest_relative(model, C),
                                 constraints.largest_relative(model, violation))
        for _ in range(8):
            if constraints.largest_relative(model, violation) <= self.projection_tol:
                break
            qd = qd - lu.solve(constraints.jacobian_transpose_times(model, jac_data,
                                                                     penalty * violation))
            violation = constraints.jacobian_times(model, jac_data, qd) - nu
        return qd

    def __call__(self, tt, h, q_n, qd_n, qdd_n, a_n, lam_n, chart):
        """One step: the new state and the iteration matrix's factors, or None when Newton
        does not converge."""
        model, am, af, beta, gamma = self.model, self.am, self.af, self.beta, self.gamma
        shift = (af * qdd_n - am * a_n) / (1.0 - am)
        q_hat = q_n + h * qd_n + h * h * (0.5 - beta) * a_n + h * h * beta * shift
        qd_hat = qd_n + h * (1.0 - gamma) * a_n + h * gamma * shift
        beta_prime = (1.0 - am) / (h * h * beta * (1.0 - af))
        gamma_prime = gamma / (h * beta)
        q = q_hat + qdd_n / beta_prime  # predictor: unchanged accelerations
        lam = lam_n.copy()
        # the applied forces' tangent varies slowly: once per step, at the predictor
        tangent = _force_tangent(model, tt, q, qd_hat + gamma_prime * (q - q_hat), chart,
                                 gamma_prime)
        extra, python_factor = _tangent_storage(model, tangent)
        self.run.tangent = tangent
        # The iteration matrix is factored at every iterate (full Newton): the constraint
        # force p C Cq^T is normal to the free directions only at the configuration where Cq
        # is evaluated, and it is large (p is the penalty ratio times the mass term); with
        # factors kept from the predictor, its part along the free directions of the old
        # factors passed the convergence test as a tangential force error (a velocity
        # oscillation of 1e-2 rad/s on a slider-crank at h = 1e-3, 200 times the method's
        # own error). The geometric stiffness d(Cq^T lam)/dq is left out (Gauss-Newton on
        # the penalty term, as in ALI3-P): tried, with lam or lam + p C, it made the free
        # slider-crank at h = 5e-4 reject thousands of steps where it rejects none without
        # it (p C is far larger than lam between iterates, so neither is the curvature the
        # next iterate sees).
        outcome = kernel.newton_step(
            self.work, self.arrays, self.run.key, tt, q, q_hat, qd_hat, beta_prime,
            gamma_prime, lam, chart if self.spatial else None, extra, python_factor,
            self.relative_penalty, self.newton_tol, self.projection_tol, self.max_iterations,
            self.penalty, self.lam_effective, *self.buffers, self.counters)
        self.stats["newton_iterations"], self.stats["factorizations"] = (
            int(self.counters[0]), int(self.counters[1]))
        # a singular iteration matrix is a failed step like any other: an iterate thrown
        # far off by a step too long for the motion (a body's Rodrigues parameters at 1e5,
        # nearly half a turn) is singular at the iterate, not in the model; a shorter step
        # is tried, and the refusal says which it was if none converges
        self.singular = outcome == kernel.SINGULAR_MATRIX
        if outcome == kernel.NOT_FINITE and np.all(np.isfinite(q)):
            # a force element or motion that cannot be evaluated there is named
            constraints.driver_values(model, tt)
            generalized_forces(model, tt, constraints.frames(
                model, q, qd_hat + gamma_prime * (q - q_hat), chart))
        if outcome != kernel.CONVERGED:
            return None
        qdd = beta_prime * (q - q_hat)
        qd = qd_hat + gamma_prime * (q - q_hat)
        a = shift + (1.0 - af) / (1.0 - am) * qdd
        S = _IterationFactors(self.arrays, self.buffers,
                              self.run.factors if python_factor else None,
                              self.penalty.copy(), beta_prime,
                              kernel.last_mass_blocks(self.work))
        return (q, qd, qdd, a, self.lam_effective.copy()), S
