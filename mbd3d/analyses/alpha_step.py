"""One step of generalized-alpha (:mod:`mbd3d.analyses.implicit`): the method's coefficients,
the Newton iteration on the step's new positions (compiled:
:func:`mbd3d.numerics.compiled.generalized_alpha.newton_step`) and its iteration matrix
``beta' M + gamma' D + K + p Cq^T Cq``: the applied forces' tangent ``K + gamma' D``, its
storage in the matrix's layout, and the factors the step leaves for projections and for
the singular-position indicator.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from mbd3d.errors import ModelError
from mbd3d.model import constraints
from mbd3d.model.equations import augmented_accelerations, generalized_forces, python_parts
from mbd3d.numerics.compiled import (alpha_loop as loop, callbacks, force_tangents,
                                    generalized_alpha as kernel, structures)

__all__ = ["GeneralizedAlpha", "NewtonStep", "IterationFactors", "force_tangent"]


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


def force_tangent(model, t: float, q: np.ndarray, qd: np.ndarray, charts, gamma_prime: float):
    """``K + gamma' D`` with ``K = -dQe/dq``, ``D = -dQe/dqd`` of the force elements (and the
    joints' friction's ``D``), or None when there are none (gravity does not depend on the
    state; the spatial bodies' quadratic velocity terms are left out of the iteration
    matrix, which only slows convergence): a sparse matrix for a sparse model, else an array.
    Groups with an analytic tangent (spring-dampers, point forces and torques not given as
    functions of the state, contacts and joint stops) give it directly; the others are
    differenced forward, only over the coordinates of the bodies they act on. Where the
    compiled core has every group's tangent, :class:`NewtonStep` takes it from
    :func:`~mbd3d.numerics.compiled.force_tangents.force_tangent_into` instead, straight
    into the iteration matrix's storage."""
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
    values, index = np.concatenate(values), (np.concatenate(rows), np.concatenate(cols))
    if model.sparse:
        return sp.coo_matrix((values, index), shape=(n, n)).tocsr()
    T = np.zeros((n, n))  # summed in place: a sparse matrix's checks cost more than the sum
    np.add.at(T, index, values)
    return T


def _compiled_tangent(model, arrays, work) -> bool:
    """Whether every force element's forces and tangent are compiled (no friction, no force
    given as a Python function, no element whose tangent is differenced) and the tangent
    lies inside the iteration matrix's band (a dense or banded layout)."""
    return (model.friction is None and model._penalty_pattern.layout != "sparse"
            and all(group.compiled_tangent(model) for group in model.force_groups)
            and force_tangents.tangent_fits(arrays, work))


class IterationFactors:
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


class NewtonStep:
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
        #: Newton iterations, factorizations and rejected steps of the run
        self.counters = np.zeros(3, dtype=np.int64)
        #: whether the compiled core gives the applied forces' tangent (and their forces), in
        #: the storage of the iteration matrix (``extra``); else :func:`force_tangent` does
        self.compiled_tangent = _compiled_tangent(model, self.arrays, self.work)
        self.extra = np.zeros(0)
        if self.compiled_tangent and force_tangents.has_tangent(self.work):
            self.extra = np.zeros(self.buffers[0].size + self.buffers[1].size)
        #: the rigid contacts held at rest (:class:`mbd3d.analyses.resting.HeldRows`), or None,
        #: and the workspace of the compiled arrays that take the forces from Python then
        self.held, self._held_work = None, None
        self.run = callbacks.Run(
            self._parts,
            factor=lambda values, tangent: model._penalty_pattern.factor(values, tangent))

    def hold(self, held) -> None:
        """Take the forces of the rigid contacts ``held`` at rest (None: none) with each
        iterate's: then everything the iterates' forces need comes from Python."""
        self.held = held
        core = self.model._core
        if held is None:
            self.work = core.workspace()
        else:
            if self._held_work is None:
                self._held_work = structures.workspace(self.spatial,
                                                       core.arrays(python_parts=True))
            self.work = self._held_work

    def _parts(self, tt, q, qd, charts) -> tuple:
        """What an iterate takes from Python: joint friction at the multipliers of its own
        state (consistent with the reactions there, see mbd3d.model.friction), neither a
        previous step's nor the iteration's penalty estimates, which are noisy at 1e-4; and so
        the held rows' forces, which hold their gaps' accelerations at zero there (with the
        joints' friction of the reactions they change: :meth:`HeldRows.applied`)."""
        held = self.held is not None
        extra, drivers, phi = python_parts(self.model, tt, q, qd, charts, friction=not held)
        if held:
            extra = extra + self.held.applied(tt, q.copy(), qd.copy())
        return extra, drivers, phi

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
        model, coefficients = self.model, (self.am, self.af, self.beta, self.gamma)
        shift, q_hat, qd_hat, q = (np.empty(len(q_n)) for _ in range(4))
        beta_prime, gamma_prime = loop.predict_into(coefficients, h, q_n, qd_n, qdd_n, a_n,
                                                    shift, q_hat, qd_hat, q)
        lam = lam_n.copy()
        # the applied forces' tangent varies slowly: once per step, at the predictor
        qd = np.empty(len(q))
        loop.rate_into(gamma_prime, q, q_hat, qd_hat, qd)
        # held rows' forces come from Python, the compiled elements' stay compiled (the held
        # workspace keeps their tables): the same tangent either way
        if self.compiled_tangent:
            force_tangents.force_tangent_into(self.work, self.arrays, tt, q, qd,
                                              chart if self.spatial else None, gamma_prime,
                                              self.extra)
            extra, python_factor = self.extra, False
        else:
            tangent = force_tangent(model, tt, q, qd, chart, gamma_prime)
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
            loop.rate_into(gamma_prime, q, q_hat, qd_hat, qd)
            constraints.driver_values(model, tt)
            generalized_forces(model, tt, constraints.frames(model, q, qd, chart))
        if outcome != kernel.CONVERGED:
            return None
        qd, qdd, a = (np.empty(len(q)) for _ in range(3))
        loop.rates_into(coefficients, beta_prime, gamma_prime, q, q_hat, qd_hat, shift, qd, qdd,
                        a)
        S = IterationFactors(self.arrays, self.buffers,
                              self.run.factors if python_factor else None,
                              self.penalty.copy(), beta_prime,
                              kernel.last_mass_blocks(self.work))
        return (q, qd, qdd, a, self.lam_effective.copy()), S
