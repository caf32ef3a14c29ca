"""Velocity and acceleration analysis, kinematic analysis over a time grid, inverse dynamics.

For a fully driven mechanism (as many independent constraints as coordinates) the motion follows
from the constraints alone: positions by Newton-Raphson, then ``Cq qd = -Ct`` and
``Cq qdd = Qd`` with the same LU factors of ``Cq``. Inverse dynamics then reads the multipliers
from ``Cq^T lam = Qe + Qv - M qdd`` (the first block row of the augmented equations), again with
those factors.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp

from mbd3d.model import constraints
from mbd3d.model.equations import generalized_forces, mass_matrix, mass_times
from mbd3d.numerics.checks import is_finite_vector
from mbd3d.model.friction import consistent_multipliers, raise_friction_with_redundancy
from mbd3d.numerics.rotations import to_quaternion
from mbd3d.errors import AnalysisError, ModelError, NotFullyDrivenError, OverDrivenError
from mbd3d.numerics import compiled
from mbd3d.model.spatial import CHART_LIMIT
from mbd3d.numerics.compiled.kinematics import VELOCITY_TOLERANCE, kinematic_points
from mbd3d.numerics.linalg import (RANK_TOLERANCE, Factorization, SingularMatrix,
                                   augmented_scaling, dependent_rows, jacobian_factors,
                                   jacobian_scaling, ranked_rows, solve_augmented,
                                   solve_augmented_lagrangian, solve_model_augmented, summarize)
from mbd3d.numerics.patterns import jacobian_layout
from mbd3d.analyses.position import (MAX_AUGMENTED_LAGRANGIAN, MAX_NEWTON_ITERATIONS,
                                     hold_indices, singular_error, solve_position)
from mbd3d.io.observers import Observer, Watch
from mbd3d.io.results import Results
from mbd3d.io.store import ResultsBuffer, run_keeping_results
from mbd3d.analyses.lift_off import warn_lift_off

__all__ = ["project_state", "solve_velocity", "solve_acceleration", "kinematic_analysis",
           "inverse_dynamics",
           "check_times"]


def check_times(times: Sequence[float]) -> np.ndarray:
    """A 1-D, finite, strictly increasing array of times [s]."""
    try:
        t = np.atleast_1d(np.asarray(times, dtype=float))
    except (TypeError, ValueError):
        raise ModelError(f"times must be a 1-D sequence of numbers [s], got {times!r}") from None
    if t.ndim != 1 or t.size == 0:
        raise ModelError(f"times must be a non-empty 1-D sequence of times [s], got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise ModelError("times must be finite")
    if t.size > 1 and not np.all(np.diff(t) > 0):
        raise ModelError("times must be strictly increasing")
    if np.max(np.abs(t)) > LATEST_TIME:
        raise ModelError(f"times reach {np.max(np.abs(t)):.3g} s, beyond {LATEST_TIME:.0e} s: "
                         "there doubles keep no digits for the steps of an analysis or for the "
                         "angles of anything that turns; give times in seconds of the motion")
    return t


#: largest time an analysis accepts [s] (about 30,000 years): beyond it, double precision
#: leaves less than 1e-4 s of resolution for the steps and angles lose their turns
LATEST_TIME = 1e12


def _require_fully_driven(model, what: str) -> None:
    n, m = model.n_coordinates, model.n_constraints
    if m < n:
        raise NotFullyDrivenError(
            f"{what} needs a fully driven mechanism, but '{model.name}' has {n} coordinates and "
            f"{m} constraint equations: {n - m} degree(s) of freedom are not driven. Add "
            f"{n - m} driver(s) (RotationDriver, TranslationDriver, CoordinateDriver) or use "
            "mbd3d.forward_dynamics.")


def solve_velocity(model, q: np.ndarray, t: float = 0.0, *, qd_guess: Sequence[float] | None = None,
                   hold: Sequence[str | int] | None = None,
                   charts: np.ndarray | None = None, redundant: bool = False) -> np.ndarray:
    """Velocities consistent with the constraints: ``Cq qd = -Ct``.

    For a fully driven mechanism the solution is unique. Otherwise it is the mass-weighted
    projection of ``qd_guess`` (default ``model.qd0``), keeping held coordinates' rates.

    Parameters
    ----------
    model : Model
    q : (n,) array_like
        Assembled positions (in ``charts`` for a spatial model).
    t : float
        Time [s] (of the drivers' motions).
    qd_guess : (n,) array_like, optional
        Velocities to project (default ``model.qd0``).
    hold : sequence of str or int, optional
        Coordinates whose rates are kept (``"crank.theta"`` or indices).
    charts : ndarray, optional
        Spatial models: the bodies' reference rotations ``q`` is given in (default the model's).
    redundant : bool
        The rows are known to depend on each other (see :func:`mbd3d.mobility`): the
        projection goes straight to the augmented Lagrangian, since an LU of dependent rows
        can pass its pivot test by rounding and return an arbitrary null-space component.

    Returns
    -------
    qd : ndarray (n,)
    """
    q = np.asarray(q, dtype=float)
    fr = constraints.frames(model, q, charts=charts)
    jac_data = constraints.evaluate(model, t, fr, value=False)[1]
    nu = constraints.velocity_rhs(model, t, fr)
    n, m = model.n_coordinates, model.n_constraints
    held = hold_indices(model, hold)
    guess = np.asarray(model.qd0 if qd_guess is None else qd_guess, dtype=float).reshape(-1)
    if guess.size != n or not np.all(np.isfinite(guess)):
        raise ModelError(f"qd_guess must be {n} finite numbers")
    regular = not redundant
    if regular and not len(held) and m < n:
        # the common case (a projection during a simulation): the model's augmented matrix,
        # whose pattern and band ordering are fixed at build
        blocks = model.body_type.mass_blocks(fr, model.mass, model.inertia)
        try:
            return solve_model_augmented(model, blocks, jac_data,
                                         np.concatenate([mass_times(blocks, guess), nu]))[:n]
        except SingularMatrix:
            regular = False
    Cq = constraints.jacobian_matrix(model, jac_data)
    try:
        if not regular:
            raise SingularMatrix("dependent rows")
        if m == n and not len(held):
            return Factorization(Cq, scaling=jacobian_scaling(model)).solve(nu)
        if len(held):
            H = np.zeros((len(held), n))
            H[np.arange(len(held)), held] = 1.0
            Cq = sp.vstack([Cq, sp.csr_matrix(H)], format="csr") if sp.issparse(Cq) else np.vstack([Cq, H])
            nu = np.concatenate([nu, guess[held]])
        M = mass_matrix(model, fr)
        qd, _ = solve_augmented(M, Cq, M @ guess, nu, augmented_scaling(model, held))
        return qd
    except SingularMatrix:
        pass
    # dependent rows: with redundant constraints the mass-weighted projection still exists
    # (the augmented Lagrangian finds it); with inconsistent ones (a lock-up) it does not
    try:
        M = mass_matrix(model, fr)
        qd, _, iterations = solve_augmented_lagrangian(M, Cq, M @ guess, nu,
                                                       max_iterations=MAX_AUGMENTED_LAGRANGIAN,
                                                       scaling=augmented_scaling(model, held))
        if iterations < MAX_AUGMENTED_LAGRANGIAN:
            return qd
    except SingularMatrix:
        pass
    raise singular_error(model, Cq[:m], t, f"velocity analysis of '{model.name}'")


def project_state(model, t: float, q: np.ndarray, qd: np.ndarray, tol: float,
                  charts: np.ndarray | None = None, redundant: bool = False
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Nearest (mass-weighted) state that satisfies the position and velocity constraints
    (``redundant``: see :func:`mbd3d.solve_position`).

    Parameters
    ----------
    model : Model
    t : float
        Time [s].
    q, qd : (n,) array_like
        The state to project.
    tol : float
        Newton-Raphson tolerance of the positions (see :func:`mbd3d.solve_position`).
    charts, redundant
        As for :func:`solve_velocity`.
    """
    q = solve_position(model, q, t, tol=tol, charts=charts, redundant=redundant)
    return q, solve_velocity(model, q, t, qd_guess=qd, charts=charts, redundant=redundant)


def solve_acceleration(model, q: np.ndarray, qd: np.ndarray, t: float = 0.0, *,
                       charts: np.ndarray | None = None) -> np.ndarray:
    """Accelerations of a fully driven mechanism: ``Cq qdd = Qd``.

    Parameters
    ----------
    model : Model
        Fully driven.
    q, qd : (n,) array_like
        A consistent state (in ``charts`` for a spatial model).
    t, charts
        As for :func:`solve_velocity`.
    """
    _require_fully_driven(model, "solve_acceleration")
    fr = constraints.frames(model, q, qd, charts)
    if model.n_constraints > model.n_coordinates:
        # redundant rows (see kinematic_analysis): the consistent solution, by the augmented
        # Lagrangian
        return _solve_redundant(model, t, mass_matrix(model, fr),
                                constraints.jacobian(model, t, q, fr),
                                np.zeros(model.n_coordinates),
                                constraints.acceleration_rhs(model, t, q, qd, fr),
                                f"acceleration analysis of '{model.name}'")[0]
    try:
        return Factorization(constraints.jacobian(model, t, q, fr),
                             scaling=jacobian_scaling(model)).solve(
            constraints.acceleration_rhs(model, t, q, qd, fr))
    except SingularMatrix:
        raise singular_error(model, constraints.jacobian(model, t, q, fr), t,
                             f"acceleration analysis of '{model.name}'") from None


def initial_guess(model, t0: float, guess, chart, what: str, name: str) -> np.ndarray:
    """The guess ``guess`` of an analysis's first positions (default the model's), refused by
    ``name`` when it is no vector of ``n`` finite numbers, and the model refused when it is
    over-driven there (:func:`require_not_over_driven`)."""
    n = model.n_coordinates
    if guess is not None and not is_finite_vector(guess, n):
        raise ModelError(f"{what}: {name} must be {n} finite numbers (one per coordinate: "
                         f"{', '.join(model.coordinate_labels[:3])}, ...), got {guess!r}")
    q = np.array(model.q0 if guess is None else guess, dtype=float)
    require_not_over_driven(model, t0, q, chart, what)
    return q


#: largest Jacobian (rows x columns) checked for over-driving before an analysis (a dense SVD
#: where its rows are independent, three more where not: about 0.1 s each at this size)
_LARGEST_RANK_CHECK = 250_000


def require_not_over_driven(model, t: float, q: np.ndarray, chart, what: str) -> None:
    """Refuse a model whose drivers depend on each other or on the joints at ``q`` (two motors
    on one hinge, a motor on a rigid loop) with an :class:`OverDrivenError` naming them: such
    a mechanism cannot follow its drivers, and would otherwise be reported as stuck at a
    singular position."""
    driver_rows = np.zeros(model.n_constraints, dtype=bool)
    for element in model.joints:
        if element.is_driver:
            driver_rows[model.rows_of(element.name)] = True
    if not np.any(driver_rows) or model.n_constraints * model.n_coordinates > _LARGEST_RANK_CHECK:
        # three dense SVDs: for large models the analysis itself names the joints if it fails
        return
    Cq = constraints.jacobian(model, t, q, constraints.frames(model, q, charts=chart),
                              sparse=False)
    rows, columns = jacobian_scaling(model)
    # Rows independent together are independent in any subset (a subset's singular values
    # lie within the whole's), so the common case needs one SVD without its vectors
    scaled = rows[:, None] * Cq * columns[None, :]
    if model.n_constraints <= model.n_coordinates and np.all(np.isfinite(scaled)):
        singular = la.svdvals(scaled)
        if singular[-1] > RANK_TOLERANCE * singular[0]:
            return

    def rank_and_groups(selected):
        if not np.any(selected):
            return 0, []
        rank, groups = dependent_rows(Cq[selected], scaling=(rows[selected], columns))
        index = np.flatnonzero(selected)
        return rank, [index[g] for g in groups]
    driver_rank, driver_groups = rank_and_groups(driver_rows)
    joint_rank, _ = rank_and_groups(~driver_rows)
    rank, groups = rank_and_groups(np.ones(model.n_constraints, dtype=bool))
    if driver_rank < np.count_nonzero(driver_rows):
        involved, fix = driver_groups, "the other drivers already fix"
    elif joint_rank + driver_rank > rank:
        involved = [g for g in groups if np.any(driver_rows[g])]
        fix = (f"the joints already fix (the joints alone leave "
               f"{model.n_coordinates - joint_rank} degree(s) of freedom for {driver_rank} "
               "driven motion(s))")
    else:
        return
    labels = ranked_rows(involved, model.n_constraints)
    names = model.joints_of_rows(labels)
    drivers = [name for name in names if model.joint(name).is_driver]
    joints = [name for name in names if not model.joint(name).is_driver]
    sets = "; ".join("{" + summarize([model.row_labels[r] for r in g], 8) + "}" for g in involved)
    raise OverDrivenError(
        f"{what}: '{model.name}' is over-driven: the driver(s) {summarize(drivers)} prescribe "
        f"motions that {fix}"
        + (f" (joints involved: {summarize(joints)})" if joints else "")
        + f". Rows that depend on each other: {sets}. Remove a driver, or free the joint it "
        "fights; mbd3d.analyses.mobility(model) lists the redundant equations.",
        drivers=drivers, joints=joints)


def _require_redundant_but_driven(model, t: float, q: np.ndarray, chart, analysis: str) -> None:
    """A mechanism with more constraint equations than coordinates must still be fully driven
    (its rows span every coordinate, the surplus redundant); else a
    :class:`NotFullyDrivenError` that says so (over-driving is refused before, by
    :func:`require_not_over_driven`)."""
    Cq = constraints.jacobian(model, t, q, constraints.frames(model, q, charts=chart),
                              sparse=False)
    rank, groups = dependent_rows(Cq, scaling=jacobian_scaling(model))
    n = model.n_coordinates
    if rank < n:
        rows = "; ".join("{" + summarize([model.row_labels[r] for r in g], 8) + "}"
                         for g in groups)
        raise NotFullyDrivenError(
            f"{analysis} needs a fully driven mechanism: '{model.name}' has "
            f"{model.n_constraints} constraint equations for {n} coordinates, but only {rank} "
            f"are independent (rows that depend on each other: {rows}), so {n - rank} "
            "degree(s) of freedom are not driven. Add drivers, or use mbd3d.forward_dynamics (see mbd3d.analyses.mobility).")


def _solve_redundant(model, t: float, M, Cq, b: np.ndarray, c: np.ndarray, what: str):
    """``[M Cq^T; Cq 0] [x; lam] = [b; c]`` with dependent rows of ``Cq`` that span every
    coordinate, by the augmented Lagrangian: the unique ``x`` and the minimum-norm ``lam``;
    a :class:`SingularJacobianError` when the rows are inconsistent (a lock-up)."""
    x, lam, used = solve_augmented_lagrangian(M, Cq, b, c, max_iterations=MAX_AUGMENTED_LAGRANGIAN,
                                              scaling=augmented_scaling(model))
    if used == MAX_AUGMENTED_LAGRANGIAN:
        raise singular_error(model, Cq, float(t), what)
    return x, lam


def _redundant_rates(model, t: float, q: np.ndarray, chart, with_forces: bool, analysis: str):
    """``qd``, ``qdd`` and the minimum-norm ``lam`` where the rows of ``Cq`` depend on each
    other but span every coordinate."""
    fr = constraints.frames(model, q, charts=chart)
    Cq = constraints.jacobian(model, t, q, fr)
    M = mass_matrix(model, fr)
    n = model.n_coordinates
    what = f"{analysis} of '{model.name}'"
    qd, _ = _solve_redundant(model, t, M, Cq, np.zeros(n), constraints.velocity_rhs(model, t, fr),
                             what)
    fr = constraints.frames(model, q, qd, chart)
    if with_forces and model.friction is not None:
        raise_friction_with_redundancy(model, t)
    forces = generalized_forces(model, t, fr) if with_forces else np.zeros(n)
    qdd, lam = _solve_redundant(model, t, M, Cq, forces,
                                constraints.acceleration_rhs(model, t, q, qd, fr), what)
    return qd, qdd, lam if with_forces else None


#: a time point where the dimensionless Jacobian's reciprocal condition number falls below
#: this fraction of its value at the first point is a singular position: its velocities would
#: be 10^4 times more sensitive to the positions than at the start (relative to the start, so
#: that a long chain, whose conditioning is modest everywhere, is not taken for singular)
SINGULAR_CONDITIONING = 1e-4


def _check_velocities(model, Cq, qd: np.ndarray, nu: np.ndarray, t: float, what: str) -> None:
    """Every accepted time point satisfies ``Cq qd = -Ct`` (rows over their scale, relative to
    the size of the terms), else an AnalysisError: the last guard against reporting a state
    that is not the mechanism's."""
    # rows over their scale, against the largest term of any row (a row whose terms cancel
    # has a residual at the rounding level of the others, not of its own)
    terms = (abs(Cq) @ np.abs(qd) + np.abs(nu)) / model.row_scale
    violation = np.abs(Cq @ qd - nu) / model.row_scale
    size = float(np.max(terms, initial=0.0))
    if not (np.all(np.isfinite(qd)) and np.all(violation <= VELOCITY_TOLERANCE * size)):
        bad = int(np.argmax(violation))
        raise AnalysisError(f"{what}: the velocities at t = {t:.6g} s do not satisfy the "
                            f"constraints (row {model.row_labels[bad]}: relative residual "
                            f"{violation[bad] / size:.1e}); the Jacobian is too "
                            "ill-conditioned here to trust them", time=t)


def _mesh_pieces(model, q: np.ndarray, qd: np.ndarray, chart, h: float) -> int:
    """Into how many steps to cut the step ``h`` after the state ``(q, qd)`` so that no spatial
    gear mesh's phase terms change by more than a quarter turn in one (half the change that
    lets a guess be a tooth off, leaving a factor of two for gears speeding up)."""
    speed = constraints.mesh_turn_speed(model, q, qd, chart)
    return max(1, int(math.ceil(speed * h / (0.5 * math.pi))))


#: time points solved in one compiled call at most (a few milliseconds)
POINTS_PER_CALL = 100
#: solve the time points of a kinematic sweep in one compiled call where the model allows
#: (:func:`_compiled_layout`); interpreted (``NUMBA_DISABLE_JIT=1``) the LAPACK path is
#: faster, and the tests set this to compare the two
COMPILED_POINTS = not compiled.DISABLED


def _compiled_layout(model, surplus: bool) -> tuple | None:
    """How :func:`mbd3d.numerics.compiled.kinematics.kinematic_points` factors the Jacobian
    of ``model`` (:func:`mbd3d.numerics.patterns.jacobian_layout`), or None where its time
    points are solved in Python: its motions or forces not in the compiled core (joint
    friction, Python functions), its rows not as many as its coordinates, or a large model
    whose Jacobian has no narrow band."""
    if not (COMPILED_POINTS and not surplus and constraints.motions_compiled(model)
            and model.n_constraints == model.n_coordinates):
        return None
    layout = jacobian_layout(model._jac_rows, model._jac_cols, model.n_coordinates)
    dense = layout[3][0] < 0
    return None if dense and constraints.kinematic_sparse(model) else layout


class _PointSolver:
    """One time point of a kinematic sweep: positions from a guess, then velocities,
    accelerations and (``forces``) multipliers, all from the factors of ``Cq``; in one
    compiled call where the model allows, else (and to name what failed) in Python."""

    def __init__(self, model, tol: float, surplus: bool, turns, analysis: str):
        self.model, self.tol, self.surplus, self.turns = model, tol, surplus, turns
        self.analysis, self.what = analysis, f"{analysis} of '{model.name}'"
        self.reference = 1.0  # the Jacobian's conditioning at the first time point
        self.scales = None
        layout = _compiled_layout(model, surplus)
        if layout is not None:
            self.scales = (*jacobian_factors(model), np.asarray(model.length_rows, dtype=bool),
                           np.asarray(model.position_coordinates, dtype=bool), *layout)

    def batch(self, t: np.ndarray, start: int, stop: int, q: np.ndarray, chart, turns,
              out: ResultsBuffer, forces: bool):
        """Solve the points ``t[start:stop]`` in one compiled call
        (:func:`~mbd3d.numerics.compiled.kinematics.kinematic_points`) into ``out``, from the
        guess ``q`` of the first; returns ``(the first point not solved, its chart)``: that
        point (failed, or singular) is for the solver's call to solve, which names the
        cause."""
        model, spatial = self.model, chart is not None
        chart = np.array(chart, dtype=float) if spatial else None  # updated in place
        if spatial and out.turns is None:
            out.turns = np.empty((len(t),) + turns.shape)
        empty = np.empty((0, 0))
        settings = (self.scales, self.tol, model.length_scale, MAX_NEWTON_ITERATIONS,
                    CHART_LIMIT, SINGULAR_CONDITIONING)
        reached, self.reference = kinematic_points(
            model._core.workspace(), t, start, stop, np.array(q, dtype=float), chart,
            turns if spatial else np.empty((0, 4)), settings, forces, self.reference,
            out.q, out.qd, out.qdd, out.lam if forces else empty,
            out.charts if spatial else np.empty((0, 0, 0, 0)),
            out.turns if spatial else empty)
        out.done = reached
        return reached, chart

    def __call__(self, tk: float, q: np.ndarray, chart, first: bool, forces: bool):
        """Positions from the guess ``q``, velocities, accelerations and (``forces``) the
        multipliers at ``tk``: ``(q, qd, qdd, lam, chart)``."""
        model = self.model
        # keep orientation coordinates away from their singularity (spatial bodies)
        q, _, chart, _ = model.body_type.reset_charts(q, None, chart, turns=self.turns)
        q = solve_position(model, q, tk, tol=self.tol, charts=chart, redundant=self.surplus)
        if self.surplus:
            if first:
                _require_redundant_but_driven(model, tk, q, chart, self.analysis)
            qd, qdd, lam = _redundant_rates(model, tk, q, chart, forces, self.analysis)
            return q, qd, qdd, lam, chart
        fr = constraints.frames(model, q, charts=chart)
        Cq = constraints.jacobian(model, tk, q, fr, sparse=constraints.kinematic_sparse(model))
        try:
            lu = Factorization(Cq, scaling=jacobian_scaling(model))
        except SingularMatrix:
            raise singular_error(model, Cq, float(tk), self.what) from None
        # A singular position (a dead centre of a driven slider, a toggle) has a finite
        # position but unbounded velocities: stop there rather than report them
        conditioning = lu.reciprocal_condition()
        if first:
            self.reference = conditioning
        if conditioning < SINGULAR_CONDITIONING * self.reference:
            raise singular_error(model, Cq, float(tk), f"{self.what} (the velocities are "
                                 f"unbounded here: the Jacobian's conditioning fell from "
                                 f"{self.reference:.1e} at the start to {conditioning:.1e})")
        nu = constraints.velocity_rhs(model, tk, fr)
        qd = lu.solve(nu)
        _check_velocities(model, Cq, qd, nu, float(tk), self.what)
        fr = constraints.frames(model, q, qd, chart)
        qdd = lu.solve(constraints.acceleration_rhs(model, tk, q, qd, fr))
        lam = None
        if forces:
            # first block row of the augmented equations: Cq^T lam = Qe + Qv - M qdd
            rhs = generalized_forces(model, tk, fr) - mass_matrix(model, fr) @ qdd
            lam = lu.solve(rhs, transpose=True)
            if model.friction is not None:
                # the friction forces depend on the reactions they change
                lam = consistent_multipliers(
                    model, float(tk), fr,
                    lambda extra: (lu.solve(rhs + extra, transpose=True), None), lam)[0]
        return q, qd, qdd, lam, chart


def _sweep(model, times, q_guess, tol, with_forces: bool, analysis: str, observers,
           progress) -> Results:
    t = check_times(times)
    # positions on a time grid come from the constraints alone: not those of velocity rows
    constraints.require_holonomic(model, analysis)
    _require_fully_driven(model, analysis)
    # more equations than coordinates: redundant rows if they still fix every coordinate
    # (checked on the assembled first point), solved then by the augmented Lagrangian
    surplus = model.n_constraints > model.n_coordinates
    stats = {"wall_time": 0.0}
    if surplus:
        stats["singular_outputs"] = []
    out = ResultsBuffer(model, analysis, t, stats, with_lam=with_forces)

    # spatial models: the charts as quaternions whose signs follow the motion
    turns = None if model.charts0 is None else to_quaternion(model.charts0)

    what = f"{analysis} of '{model.name}'"
    solve_point = _PointSolver(model, tol, surplus, turns, analysis)

    def predicted(q, qd, qdd, h):
        # second-order Taylor predictor: Newton-Raphson then needs one or two iterations and
        # stays on the branch of the previous time point
        guess = q + h * qd + 0.5 * h * h * qdd
        return guess if np.all(np.isfinite(guess)) else q  # a step it cannot extrapolate

    # stretches of points in one compiled call: short enough that observers and Ctrl-C are
    # heard between them; one point at a time where a spatial mesh needs steps between points
    stretch = 1 if constraints.has_spatial_meshes(model) else POINTS_PER_CALL

    def loop() -> None:
        chart = model.charts0
        q = initial_guess(model, t[0], q_guess, chart, what, "q_guess")
        k = 0
        while k < len(t):
            tk = t[k]
            if k > 0:
                last = (t[k - 1], out.q[k - 1], out.qd[k - 1], out.qdd[k - 1])
                # spatial gears know their angles modulo a tooth of the reduced ratio: steps
                # between solved states short enough that no guess can be a tooth off
                pieces = _mesh_pieces(model, last[1], last[2], chart, tk - last[0])
                for s in range(1, pieces):
                    ts = last[0] + (tk - last[0]) * s / pieces
                    q, qd, qdd, _, chart = solve_point(
                        ts, predicted(*last[1:], ts - last[0]), chart, False, False)
                    last = (ts, q, qd, qdd)
                q = predicted(*last[1:], tk - last[0])
            if solve_point.scales is not None:
                reached, chart = solve_point.batch(t, k, min(k + stretch, len(t)), q, chart,
                                                   turns, out, with_forces)
                if reached > k:
                    # a point the call handed back is tried once more from this loop's own
                    # guess, then solved here in Python, which names what fails
                    k = reached
                    watch.tick(t[k - 1], out.done)
                    continue
            q, qd, qdd, lam, chart = solve_point(tk, q, chart, k == 0, with_forces)
            if surplus:
                stats["singular_outputs"].append(float(tk))
            out.store(q, qd, qdd, lam, chart, None if turns is None else turns.copy())
            watch.tick(tk, out.done)
            k += 1

    watch = Watch(observers, progress, model, t, analysis, out.partial)
    results = run_keeping_results(loop, out.partial, watch)
    if with_forces:
        warn_lift_off(results, analysis)
    return results


def kinematic_analysis(model, times: Sequence[float], q_guess: Sequence[float] | None = None, *,
                       tol: float = 1e-12, observers: Sequence[Observer] | None = None,
                       progress: bool | None = None) -> Results:
    """Positions, velocities and accelerations of a fully driven mechanism over ``times``.

    Parameters
    ----------
    model : Model
        Must be fully driven: its constraint rows fix every coordinate. More equations than
        coordinates are accepted when the surplus is redundant (a planar four-bar built of
        four spatial revolutes); they are then solved by the augmented Lagrangian, and inverse
        dynamics reports the minimum-norm multipliers (``Results.reactions_unique`` is False).
    times : (k,) array_like
        Strictly increasing times [s].
    q_guess : (n,) array_like, optional
        Guess for the first time point (default: the bodies' initial guesses); it selects the
        assembly branch, which is then followed.
    tol : float
        Newton-Raphson tolerance, relative to the model's scale (see
        :func:`mbd3d.solve_position`).
    observers : sequence of Observer, optional
        Watch the analysis as it goes (e.g. ``viewer.Recorder``); see :mod:`mbd3d.io.observers`.
    progress : bool, optional
        Show a progress bar on stderr; default only when stderr is a terminal.

    Returns
    -------
    Results
        ``q``, ``qd``, ``qdd`` at every time (no multipliers).

    Raises
    ------
    NotFullyDrivenError
        The mechanism has undriven degrees of freedom (also when redundant rows leave some).
    OverDrivenError
        Drivers prescribe motions the joints or other drivers already fix.
    AssemblyError, SingularJacobianError
        At a time point that cannot be solved (e.g. a lock-up), or at a singular position,
        where the Jacobian's reciprocal condition number (in the model's units) has fallen
        below 1e-4 of its value at the first point and the velocities are unbounded;
        ``.results`` holds what was computed before it.
    """
    return _sweep(model, times, q_guess, tol, False, "kinematic analysis", observers, progress)


def inverse_dynamics(model, times: Sequence[float], q_guess: Sequence[float] | None = None, *,
                     tol: float = 1e-12, observers: Sequence[Observer] | None = None,
                     progress: bool | None = None) -> Results:
    """Kinematic analysis plus the multipliers: joint reactions and driver efforts.

    The results also carry ``lam``, so ``results.joint(name).reaction(on=...)`` and
    ``results.driver(name).effort`` are available.

    Parameters
    ----------
    model, times, q_guess, tol, observers, progress
        As for :func:`mbd3d.kinematic_analysis`.
    """
    return _sweep(model, times, q_guess, tol, True, "inverse dynamics", observers, progress)
