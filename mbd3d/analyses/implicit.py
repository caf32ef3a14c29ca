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
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from mbd3d.model import constraints
from mbd3d.numerics.checks import finite_scalar
from mbd3d.model.equations import (augmented_accelerations, generalized_forces, mass_matrix,
                                   python_parts)
from mbd3d.errors import IntegrationError, ModelError
from mbd3d.model.friction import raise_friction_with_redundancy
from mbd3d.numerics.compiled import callbacks, generalized_alpha as kernel
from mbd3d.numerics.rotations import to_quaternion
from mbd3d.numerics.linalg import (SingularMatrix, augmented_scaling, solve_augmented_lagrangian,
                                   solve_model_augmented)
from mbd3d.io.observers import Watch
from mbd3d.analyses.passages import PassageWatch
from mbd3d.analyses.initial import consistent_initial_state
from mbd3d.analyses.position import singular_error
from mbd3d.io.results import Results
from mbd3d.io.store import ResultsBuffer, run_keeping_results

__all__ = ["GeneralizedAlpha", "consistent_accelerations", "rows_dependent",
           "integrate_generalized_alpha"]


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


def consistent_accelerations(model, t: float, q: np.ndarray, qd: np.ndarray, charts=None,
                             lam: np.ndarray | None = None, redundant: bool = False,
                             fallback: bool = True) -> tuple[np.ndarray, np.ndarray, bool]:
    """``qdd`` and ``lam`` of the augmented equations, also where ``Cq`` loses rank.

    The augmented matrix is factored by LU as in :func:`mbd3d.forward_accelerations`; where it
    is singular (a singular configuration, redundant constraints) the augmented-Lagrangian
    iteration gives the accelerations of the consistent equations and the multipliers without
    a component in the null space of ``Cq^T`` (minimum-norm from ``lam = 0``). With
    ``redundant`` (rows known to be dependent) the LU is skipped: rounding can lift its
    smallest pivot above the singularity threshold, and the solution would be noise. Without
    ``fallback`` a singular matrix raises instead (the explicit integrators' rule).

    Returns
    -------
    qdd, lam : ndarray
    regular : bool
        False when the augmented matrix was singular (multipliers not unique).
    """
    n = model.n_coordinates
    if not redundant:
        try:
            x = augmented_accelerations(model, t, q, qd, charts)
        except SingularMatrix:
            if not fallback:
                raise singular_error(model, constraints.jacobian(model, t, q, constraints.frames(
                    model, q, charts=charts)), t, f"forward dynamics of '{model.name}'") from None
        else:
            if x is None:
                raise IntegrationError(f"forward dynamics of '{model.name}': the state is not "
                                       f"finite at t = {t:.6g} s (the integration diverged)",
                                       time=t)
            return x[:n], x[n:], True
    if model.friction is not None:
        raise_friction_with_redundancy(model, t)
    fr = constraints.frames(model, q, qd, charts)
    _, jac_data, gamma = constraints.evaluate(model, t, fr, value=False, jacobian=True, gamma=True)
    Qe = generalized_forces(model, t, fr)
    M = mass_matrix(model, fr)
    Cq = constraints.jacobian_matrix(model, jac_data)
    try:
        qdd, lam, _ = solve_augmented_lagrangian(M, Cq, Qe, gamma, lam=lam,
                                                 scaling=augmented_scaling(model))
    except SingularMatrix:
        raise singular_error(model, Cq, t, f"forward dynamics of '{model.name}'") from None
    return qdd, lam, False


def rows_dependent(model, t: float, q: np.ndarray, charts=None) -> bool:
    """Whether the augmented matrix ``[M Cq^T; Cq 0]`` is singular at ``q``: constraint rows
    that depend on each other (redundant constraints, or a singular configuration)."""
    fr = constraints.frames(model, q, charts=charts)
    _, jac_data, _ = constraints.evaluate(model, t, fr, value=False)
    blocks = model.body_type.mass_blocks(fr, model.mass, model.inertia)
    try:
        solve_model_augmented(model, blocks, jac_data,
                              np.zeros(model.n_coordinates + model.n_constraints))
    except SingularMatrix:
        return True
    return False


def _force_tangent(model, t: float, q: np.ndarray, qd: np.ndarray, charts, gamma_prime: float):
    """``K + gamma' D`` with ``K = -dQe/dq``, ``D = -dQe/dqd`` of the force elements (and the
    joints' friction's ``D``), or None when there are none (gravity does not depend on the state; the spatial bodies' quadratic
    velocity terms are left out of the iteration matrix, which only slows convergence). Groups with an analytic tangent
    (spring-dampers) give it directly; the others are differenced forward, only over the
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


def integrate_generalized_alpha(model, t: np.ndarray, q0, qd0, *, step: float | None,
                                rho_inf: float,
                                constraint_tol: float, max_step: float, hold, observers,
                                progress, initial_rates=None, initial_positions=None,
                                strict: bool = False,
                                newton_tol: float = 1e-10,
                                relative_penalty: float = 1e8,
                                max_newton_iterations: int = 30) -> Results:
    """Generalized-alpha integration over the output times ``t``; see
    :func:`mbd3d.forward_dynamics` (``method="generalized-alpha"``) for the parameters.

    The step is fixed: shortened only to land on output times, or for one step to a
    quarter when Newton does not converge (near a singular configuration).
    """
    coefficients = GeneralizedAlpha(rho_inf)
    am, af = coefficients.alpha_m, coefficients.alpha_f
    beta, gamma = coefficients.beta, coefficients.gamma
    if step is None:
        raise ModelError("method='generalized-alpha' needs a fixed step [s], e.g. step=1e-3 "
                         "(the error of this second-order method scales with step^2)")
    step = finite_scalar(step, "step (the fixed time step of generalized-alpha) [s]",
                         positive=True)
    n = model.n_coordinates
    projection_tol = constraint_tol * 1e-3
    stats = {"method": "generalized-alpha", "rho_inf": rho_inf, "steps": 0,
             "rejected_steps": 0, "newton_iterations": 0, "factorizations": 0,
             "chart_resets": 0, "max_drift": 0.0, "singular_outputs": [], "wall_time": 0.0}
    k_max = len(t)
    out = ResultsBuffer(model, "forward dynamics", t, stats)

    redundant = False  # set at the start: the constraint rows depend on each other
    passages = PassageWatch(model)
    # spatial models: the charts as quaternions whose signs follow the motion
    turns = None if model.charts0 is None else to_quaternion(model.charts0)
    stats["singular_passages"] = passages.passages

    def record(q, qd, chart, lam_guess):
        tk = t[out.done]
        # from lam = 0 where the rows depend on each other: the minimum-norm multipliers
        qdd, lam, regular = consistent_accelerations(model, tk, q, qd, chart,
                                                     None if redundant else lam_guess,
                                                     redundant)
        if not regular:
            stats["singular_outputs"].append(float(tk))
        out.store(q, qd, qdd, lam, chart, None if turns is None else turns.copy())
        return qdd, lam

    def project_velocity(tt, q, qd, chart, lu, penalty):
        """Mass-orthogonal projection onto ``Cq qd = -Ct`` with the iteration matrix's
        factors: each pass cuts the violation by the penalty ratio."""
        fr = constraints.frames(model, q, charts=chart)
        C, jac_data, _ = constraints.evaluate(model, tt, fr)
        nu = constraints.velocity_rhs(model, tt, fr)
        violation = constraints.jacobian_times(model, jac_data, qd) - nu
        stats["max_drift"] = max(stats["max_drift"],
                                 constraints.largest_relative(model, C),
                                 constraints.largest_relative(model, violation))
        for _ in range(8):
            if constraints.largest_relative(model, violation) <= projection_tol:
                break
            qd = qd - lu.solve(constraints.jacobian_transpose_times(model, jac_data,
                                                                     penalty * violation))
            violation = constraints.jacobian_times(model, jac_data, qd) - nu
        return qd

    def newton(tt, h, q_n, qd_n, qdd_n, a_n, lam_n, chart):
        """One step: the new state and the iteration matrix's factors, or None when Newton
        does not converge (the iteration itself is compiled:
        :func:`mbd3d.numerics.compiled.generalized_alpha.newton_step`)."""
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
        run.tangent = tangent
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
            work, arrays, run.key, tt, q, q_hat, qd_hat, beta_prime, gamma_prime, lam,
            chart if spatial else None, extra, python_factor, relative_penalty, newton_tol,
            projection_tol, max_newton_iterations, penalty, lam_effective, *buffers, counters)
        stats["newton_iterations"], stats["factorizations"] = (int(counters[0]),
                                                               int(counters[1]))
        if outcome == kernel.SINGULAR_MATRIX:
            raise IntegrationError(
                f"forward dynamics of '{model.name}': the generalized-alpha iteration "
                f"matrix is numerically singular at t = {tt:.6g} s. Its pivots span the "
                "penalty ratio times the spread of the bodies' masses and inertias: check "
                "for bodies many orders of magnitude lighter than the others (or give "
                "them mass).", time=tt)
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
        S = _IterationFactors(arrays, buffers, run.factors if python_factor else None,
                              penalty.copy(), beta_prime, kernel.last_mass_blocks(work))
        return (q, qd, qdd, a, lam_effective.copy()), S

    meshes = constraints.has_spatial_meshes(model)

    def loop() -> None:
        nonlocal redundant
        chart = model.charts0
        q, qd, redundant = consistent_initial_state(
            model, t[0], q0, qd0, hold=hold, initial_rates=initial_rates,
            initial_positions=initial_positions, strict=strict,
            tol=constraint_tol, chart=chart, stats=stats,
            what=f"forward dynamics of '{model.name}'",
            redundant_rows=lambda qq: rows_dependent(model, t[0], qq, chart))
        qdd, lam = record(q, qd, chart, None)
        a = qdd.copy()
        watch.tick(t[0], 0)
        tt = float(t[0])
        h = min(step, max_step)
        while out.done < k_max:
            target = float(t[out.done])
            h_try = min(h, target - tt)
            if target - (tt + h_try) < 1e-9 * max(h, 1e-300):
                h_try = target - tt
            elif target - (tt + h_try) < 0.05 * h:
                h_try = 0.5 * (target - tt)  # two even steps instead of a sliver
            if meshes:
                # spatial gears know their angles modulo a tooth of the reduced ratio: no
                # step may turn a mesh's gears by a quarter of one (half what lets Newton's
                # guess be a tooth off, a factor of two left for gears speeding up)
                speed = constraints.mesh_turn_speed(model, q, qd, chart)
                if speed * h_try > 0.5 * math.pi:
                    h_try = 0.5 * math.pi / speed
            result = newton(tt + h_try, h_try, q, qd, qdd, a, lam, chart)
            if result is None:
                stats["rejected_steps"] += 1
                h = 0.25 * h_try
                if h < 1e-14 * max(1.0, abs(tt)):
                    raise IntegrationError(
                        f"forward dynamics of '{model.name}': generalized-alpha Newton "
                        f"iterations do not converge at t = {tt:.6g} s even with a step of "
                        f"{h_try:.3g} s. Check the model's stiffness and masses, or try a "
                        "smaller step.", time=tt)
                continue
            (q_new, qd_new, qdd_new, a_new, lam_new), S = result
            tt += h_try
            stats["steps"] += 1
            q, qd, qdd, a, lam = q_new, qd_new, qdd_new, a_new, lam_new
            passages.step(tt, S.indicator, q, chart)
            if not np.all(np.isfinite(q)) or not np.all(np.isfinite(qd)):
                raise IntegrationError(f"forward dynamics of '{model.name}': the state became "
                                       f"non-finite at t = {tt:.6g} s", time=tt)
            # back to the nominal step after a recovery, doubling: jumping straight back
            # from a quarter step, the free slider-crank at h = 1e-3 (crank at 80 rad/s)
            # cycled between rejection and return with the predictor's error growing every
            # cycle, to 1e18 m at t = 0.113 s, where no step converged any more
            h = min(step, max_step, 2.0 * h)
            if tt >= target - 1e-12 * max(1.0, abs(target)):
                tt = target
                # the reported velocities are projected onto Cq qd = -Ct; the recursion keeps
                # its own, because projecting them inside it costs the method its order
                record(q, project_velocity(tt, q, qd, chart, S, S.penalty), chart, lam)
            watch.tick(tt, stats["steps"])
            q_moved, qd_moved, chart_new, moved = model.body_type.reset_charts(q, qd, chart,
                                                                               turns=turns)
            if moved:
                # new orientation coordinates: restart the recursion from consistent
                # accelerations in the new charts (as at the initial time)
                stats["chart_resets"] += 1
                q, qd, chart = q_moved, qd_moved, chart_new
                qdd, lam, _ = consistent_accelerations(model, tt, q, qd, chart, lam, redundant)
                a = qdd.copy()

    # the compiled iteration's records and buffers, made once per run
    spatial = model.dim == 3
    work = model._core.workspace()
    arrays = model._core.penalty_arrays(model)
    m = model.n_constraints
    penalty, lam_effective = np.empty(m), np.empty(m)
    layout = model._penalty_pattern.layout
    buffers = (np.empty((n, n) if layout == "dense" else (0, 0)),
               np.empty(model._penalty_pattern.band_rows * n if layout == "banded" else 0),
               np.empty(n, dtype=np.int64))
    counters = np.zeros(2, dtype=np.int64)
    # joint friction: every Newton iterate takes the friction of its own state's multipliers
    # (consistent with the reactions there, see mbd3d.model.friction), neither a previous
    # step's nor the iteration's penalty estimates, which are noisy at 1e-4
    run = callbacks.Run(lambda tt, q, qd, charts: python_parts(model, tt, q, qd, charts,
                                                               friction=True),
                        factor=lambda values, tangent: model._penalty_pattern.factor(values,
                                                                                     tangent))

    def run_steps() -> None:
        try:
            with run:
                loop()
        finally:
            passages.close()  # a passage still open at the end (or at a failure)

    watch = Watch(observers, progress, model, t, "forward dynamics", out.partial)
    return run_keeping_results(run_steps, out.partial, watch)
