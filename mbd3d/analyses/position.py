"""Position analysis: Newton-Raphson on ``C(q, t) = 0``, the one place it is implemented.

Each iteration solves ``Cq dq = -C``. When the constraints do not fix every coordinate (assembly
of a mechanism for forward dynamics) the step is the mass-weighted least-change one,
``min dq^T M dq`` subject to ``Cq dq = -C``, so the guess moves as little as the constraints
allow and coordinates the user asks to ``hold`` stay where they are. A backtracking line search on
``|C|`` makes it converge from guesses tens of degrees off; the guess picks the assembly branch
(elbow up or down).
"""

from __future__ import annotations

from typing import Iterable, Sequence

import numpy as np
import scipy.sparse as sp

from mbd3d.model import constraints
from mbd3d.model.equations import mass_matrix
from mbd3d.errors import AssemblyError, ModelError, SingularJacobianError
from mbd3d.numerics.linalg import (PIVOT_TOLERANCE, Factorization, SingularMatrix,
                                   augmented_scaling, dependent_rows, jacobian_scaling, ranked_rows,
                                   solve_augmented, solve_augmented_lagrangian, summarize)

#: iterations of the augmented-Lagrangian solve with dependent rows: more means the rows are
#: inconsistent (a lock-up), not redundant
MAX_AUGMENTED_LAGRANGIAN = 50
#: Newton-Raphson iterations of a position analysis before it gives up
MAX_NEWTON_ITERATIONS = 50

__all__ = ["solve_position", "hold_indices", "singular_error"]


def hold_indices(model, hold: Iterable[str | int] | None) -> np.ndarray:
    """Indices in ``q`` of coordinates given as ``"body.coordinate"`` names or integers."""
    out = []
    for item in hold or ():
        if isinstance(item, (int, np.integer)):
            if not 0 <= item < model.n_coordinates:
                raise ModelError(f"hold: coordinate index {item} out of range 0..{model.n_coordinates - 1}")
            out.append(int(item))
        else:
            try:
                out.append(model.coordinate_index(str(item)))
            except ModelError as exc:
                raise ModelError(f"hold: {exc}") from None
    return np.array(sorted(set(out)), dtype=np.intp)


#: largest Jacobian (rows x columns) whose dependent rows are found by a dense SVD
LARGEST_DENSE_ANALYSIS = 4_000_000


def singular_error(model, Cq, t: float, what: str, results=None) -> SingularJacobianError:
    """A :class:`SingularJacobianError` naming the joints whose rows depend on each other,
    the most involved first (a long list is cut to its head and a count)."""
    if Cq.shape[0] * Cq.shape[1] > LARGEST_DENSE_ANALYSIS:
        # the dependent rows come from a dense SVD, out of reach here (a 10,000-link chain's
        # Jacobian would take 14 GB)
        test = (f"a pivot of Cq M^-1 Cq^T fell below {PIVOT_TOLERANCE:g} of its diagonal "
                "entry" if model._augmented_pattern.layout == "range" else
                f"a pivot of the augmented matrix fell below {PIVOT_TOLERANCE:g} of the "
                "largest, in the model's units")
        return SingularJacobianError(
            f"{what}: the constraint Jacobian is singular or nearly so at t = {t:.6g} s "
            f"({test}). The model is too large ({Cq.shape[0]} x {Cq.shape[1]}) to "
            "find the dependent rows by singular value decomposition; run its kinematic "
            "analysis or mb.mobility on a smaller version of it. Forward dynamics passes "
            "singular positions with method='generalized-alpha'.", joints=[], time=t,
            results=results)
    if Cq.shape[0] == 0:  # no rows: what is singular is the mass matrix of the coordinates
        return SingularJacobianError(
            f"{what}: the equations are singular at t = {t:.6g} s, and the model has no "
            "constraints: its mass matrix is (a body's orientation coordinates far from their "
            "chart, where the state diverged, or a body without mass or inertia)", joints=[],
            time=t, results=results)
    scaling = jacobian_scaling(model) if Cq.shape[0] == model.n_constraints else None
    rank, groups = dependent_rows(Cq, scaling=scaling)
    rows = ranked_rows(groups, model.n_constraints)
    joints = model.joints_of_rows(rows)
    if rank < Cq.shape[0]:
        state = (f"singular at t = {t:.6g} s (numerical rank {rank} of {Cq.shape[0]} rows)")
    else:  # nearly singular: every row counts, but one combination of them hardly does
        A = Cq.toarray() if sp.issparse(Cq) else np.asarray(Cq)
        if scaling is not None:
            A = scaling[0][:, None] * A * scaling[1][None, :]
        s = np.linalg.svd(A, compute_uv=False)
        light = _light_body(model)
        if s[-1] > _REGULAR * s[0] and light:
            # the rows are well apart and the masses are not: what the solvers found
            # singular is the mass-weighted system, not the mechanism (a body 1e12 times
            # lighter than its neighbour made a regular pendulum read as a "lock-up")
            return SingularJacobianError(
                f"{what}: the equations are singular at t = {t:.6g} s although the "
                f"constraint Jacobian is not (its smallest singular value is "
                f"{s[-1] / s[0]:.1e} of its largest, in the model's units): {light}",
                joints=[], time=t, results=results)
        state = (f"nearly singular at t = {t:.6g} s (its smallest singular value is "
                 f"{s[-1] / s[0]:.1e} of its largest, in the model's units)")
    return SingularJacobianError(
        f"{what}: the constraint Jacobian is {state}. Dependent rows: "
        f"{summarize([model.row_labels[r] for r in rows], 8)}; joints involved, most first: "
        f"{summarize(joints)}. This is a lock-up or toggle position of the mechanism, or "
        "redundant constraints. Forward dynamics passes singular positions with "
        "method='generalized-alpha'.", joints=joints, time=t, results=results)


#: a scaled constraint Jacobian whose smallest singular value is above this fraction of its
#: largest is regular for every solver here (their pivot tests are at 1e-12)
_REGULAR = 1e-6
#: bodies whose masses differ by more than this are more than the augmented equations
#: resolve in double precision beside the constraints' rows
_MASS_SPREAD = 1e8


def _light_body(model) -> str:
    """What to say of a body too light beside the others for the mass-weighted equations
    (its mass, or a principal moment of inertia), or "" when the masses and the moments are
    each within :data:`_MASS_SPREAD` of each other."""
    if not len(model.mass):
        return ""
    inertia = np.asarray(model.inertia, dtype=float)
    moments = (inertia.reshape(len(model.mass), 1) if inertia.ndim == 1
               else np.linalg.eigvalsh(inertia))
    for values, what, unit in ((model.mass, "a mass", "kg"),
                               (moments, "a principal moment of inertia", "kg m^2")):
        light = int(np.argmin(values.min(axis=1) if values.ndim == 2 else values))
        heavy = int(np.argmax(values.max(axis=1) if values.ndim == 2 else values))
        low, high = np.min(values[light]), np.max(values[heavy])
        if high > _MASS_SPREAD * low:
            return (f"body '{model.bodies[light].name}' has {what} of {low:.3g} {unit} against "
                    f"{high:.3g} {unit} of '{model.bodies[heavy].name}', a ratio of "
                    f"{high / low:.1e}, more than double precision resolves beside the "
                    "constraints. Give it a mass and inertia nearer the others', or weld it to "
                    "a neighbour.")
    return ""


def _check_finite(model, q: np.ndarray, what: str) -> np.ndarray:
    try:
        q = np.array(q, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ModelError(f"{what} must be {model.n_coordinates} numbers (one per coordinate), "
                         f"got {q!r}") from None
    if q.size != model.n_coordinates:
        raise ModelError(f"{what} must have {model.n_coordinates} entries (one per coordinate), "
                         f"got {q.size}")
    bad = np.flatnonzero(~np.isfinite(q))
    if bad.size:
        raise ModelError(f"{what} is not finite at {', '.join(model.coordinate_labels[k] for k in bad[:5])}")
    return q


def _least_change_step(model, q, charts, J, C, m, held):
    """Mass-weighted least-change ``dq`` with ``J dq = -C`` when ``J`` has dependent rows
    (None if even the penalty matrix is singular). Where the linearised rows are slightly
    inconsistent (a drifted state of a redundant mechanism: second-order small) the best
    iterate is still a descent step; at a lock-up it is not, and the line search then stops
    the iteration with the joints named."""
    M = mass_matrix(model, constraints.frames(model, q, charts=charts))
    try:
        dq, _, _ = solve_augmented_lagrangian(M, J, np.zeros(len(q)), -C,
                                              max_iterations=MAX_AUGMENTED_LAGRANGIAN,
                                              scaling=augmented_scaling(model, held))
    except SingularMatrix:
        return None
    return dq if np.all(np.isfinite(dq)) else None


class _PositionEquations:
    """``C(q, t)`` of the Newton-Raphson iteration, with the held coordinates' rows appended,
    its Jacobian, and how far a residual is from converged."""

    def __init__(self, model, t: float, charts, held: np.ndarray, q_held: np.ndarray,
                 tol: float):
        self.model, self.t, self.charts, self.tol = model, t, charts, tol
        self.held, self.q_held, self.n = held, q_held, model.n_coordinates
        # A spatial rotation driver's row sin(e), e = theta - f, also vanishes at e = pi, and
        # so does a gear pair's L sin(e) (e: the centre line's angle from where rolling puts
        # it). Where cos(e) < 0 the row is replaced by sign(e) L (2 - |sin e|), which keeps
        # rising to e = pi: the row is then monotone in e on (-pi, pi] with its only root at
        # e = 0, and its Jacobian is the sin row's with the sign of cos(e) (the derivative
        # |cos e|). Newton reaches the right branch from any guess, never the half turn.
        self.rotating = constraints.has_branches(model)
        self.far_at: dict = {}  # the rows beyond a quarter turn at the last residual's q
        # Residuals are judged relative to the model's scale: length rows (and held
        # positions) in units of its length, angle rows in radians, so that a micrometre
        # mechanism converges as tightly as a metre one. The rounding floor of each kind
        # comes from the coordinates that kind sums: positions and angles for lengths (a
        # point a body's length from its origin moves by that length times the rounding of
        # the body's angle, which keeps counting turns), angles for angles; so a wild
        # position cannot loosen the test of the angles.
        self.scale = np.concatenate([model.row_scale, model.coordinate_scale[held]])
        self.is_length = np.concatenate([model.length_rows, model.position_coordinates[held]])

    def residual(self, qq: np.ndarray) -> np.ndarray:
        model, t, held = self.model, self.t, self.held
        fr = constraints.frames(model, qq, charts=self.charts)
        C = constraints.residual(model, t, qq, fr)
        if self.rotating:
            rows, cosine, amplitude = constraints.branch_cosines(model, t, fr)
            far, amplitude = rows[cosine < 0], amplitude[cosine < 0]
            self.far_at.clear()
            self.far_at[qq.tobytes()] = far
            C[far] = np.sign(C[far]) * (2.0 * amplitude - np.abs(C[far]))
        return np.concatenate([C, qq[held] - self.q_held]) if len(held) else C

    def jacobian(self, qq: np.ndarray):
        model, t, held, n = self.model, self.t, self.held, self.n
        fr = constraints.frames(model, qq, charts=self.charts)
        Cq = constraints.jacobian(model, t, qq, fr, sparse=constraints.kinematic_sparse(model))
        if self.rotating:
            far = self.far_at.get(qq.tobytes())
            if far is None:
                rows, cosine, _ = constraints.branch_cosines(model, t, fr)
                far = rows[cosine < 0]
            if len(far):
                sign = np.ones(Cq.shape[0])
                sign[far] = -1.0
                Cq = sp.diags(sign) @ Cq if sp.issparse(Cq) else sign[:, None] * Cq
        if not len(held):
            return Cq
        H = sp.csr_matrix((np.ones(len(held)), (np.arange(len(held)), held)), shape=(len(held), n))
        return sp.vstack([Cq, H], format="csr") if sp.issparse(Cq) else np.vstack([Cq, H.toarray()])

    def relative(self, C: np.ndarray) -> np.ndarray:
        return C / self.scale

    def worst_and_limit(self, C: np.ndarray, qq: np.ndarray) -> tuple[float, float]:
        """The largest residual over its limit (converged at most 1), and the largest
        relative residual."""
        model, positions = self.model, self.model.position_coordinates
        eps100 = 100 * np.finfo(float).eps
        size = np.abs(self.relative(C))
        angles = float(np.max(np.abs(qq[~positions]), initial=0.0))
        floor_length = eps100 * (1.0 + float(np.max(np.abs(qq[positions]), initial=0.0))
                                 / model.length_scale + angles)
        floor_angle = eps100 * (1.0 + angles)
        limit = np.where(self.is_length, max(self.tol, floor_length), max(self.tol, floor_angle))
        return float(np.max(size / limit, initial=0.0)), float(np.max(size, initial=0.0))


def _no_convergence(model, equations: _PositionEquations, q: np.ndarray, C: np.ndarray,
                    t: float, history: list, stuck: bool, max_iterations: int) -> Exception:
    """The error of a Newton-Raphson iteration that did not converge: stuck at a singular
    configuration (no descent direction) or out of iterations; names the worst rows."""
    m = model.n_constraints
    order = np.argsort(-np.abs(equations.relative(C)[:m]))[:3]
    worst_rows = "; ".join(f"{model.row_labels[r]} = {C[r]:.3e} "
                           f"{'m' if model.length_rows[r] else 'rad'}" for r in order)
    # the largest residual per iteration, relative: lengths in units of the model's length
    trace = ", ".join(f"{h:.1e}" for h in history[-6:])
    trace += f" (relative to {model.length_scale:.3g} m for lengths)"
    if stuck:
        # No descent direction: |C| has a local minimum with C != 0, where the gradient
        # Cq^T C vanishes, so Cq is singular there. The drivers ask for a position beyond a
        # lock-up or toggle, or the joints cannot all be assembled.
        J = equations.jacobian(q)
        J = J.tocsr()[:m] if sp.issparse(J) else J[:m]
        error = singular_error(model, J, t, f"position analysis of '{model.name}'")
        return SingularJacobianError(
            f"position analysis of '{model.name}' is stuck at t = {t:.6g} s at a singular "
            f"configuration (max |C| per iteration: {trace}; largest residuals: {worst_rows}). "
            f"The mechanism cannot reach the position its drivers and joints ask for: it is at a "
            f"lock-up or toggle position, or cannot be assembled. Joints involved, most first: "
            f"{summarize(error.joints)}.", joints=error.joints, time=t)
    return AssemblyError(
        f"position analysis of '{model.name}' did not converge at t = {t:.6g} s after "
        f"{max_iterations} Newton-Raphson iterations (max |C| per iteration: {trace}). "
        f"Largest residuals: {worst_rows}. Check that these joints can be assembled (lengths, "
        "points in body frames) and give initial guesses closer to an assembled configuration.",
        time=t)


def solve_position(model, q_guess: Sequence[float] | None = None, t: float = 0.0, *,
                   tol: float = 1e-12, max_iterations: int = MAX_NEWTON_ITERATIONS,
                   hold: Iterable[str | int] | None = None,
                   charts: np.ndarray | None = None, redundant: bool = False) -> np.ndarray:
    """Solve ``C(q, t) = 0`` by Newton-Raphson from ``q_guess``.

    Parameters
    ----------
    model : Model
    q_guess : (n,) array_like, optional
        Starting point; default ``model.q0`` (the bodies' initial guesses).
    t : float
        Time [s] (drivers are evaluated at ``t``).
    tol : float
        Convergence when every row satisfies ``|C| <= tol``, relative to the model's scale:
        length rows in units of ``model.length_scale``, angle rows in radians. Each kind is
        raised to the rounding level of the coordinates it sums, ``100 eps (1 + max |R| / L
        + max |angle|)`` for lengths and ``100 eps (1 + max |angle|)`` for angles, when that
        is larger (a crank of 1e5 turns puts its points to 1e-10 of their distance).
    max_iterations : int
    hold : iterable of str or int, optional
        Coordinates kept at their guessed values, e.g. ``["crank.theta"]``.
    charts : ndarray, optional
        Spatial models: the reference rotations ``q_guess`` is relative to (default the model's
        initial charts). The result is relative to the same charts.
    redundant : bool
        The rows are known to depend on each other (see :func:`mbd3d.analyses.mobility`): every step
        is the mass-weighted least-change one by the augmented Lagrangian, never an LU of the
        dependent rows (which rounding can let through with an arbitrary null-space part).
        Without it, an iteration that fails is tried again so before the error is raised.

    Returns
    -------
    q : ndarray (n,)

    Raises
    ------
    AssemblyError
        No convergence: the message names the constraint rows with the largest residual.
    SingularJacobianError
        The Jacobian is singular at the iterate (names the joints involved).
    """
    q = _check_finite(model, model.q0 if q_guess is None else q_guess, "q_guess")
    held = hold_indices(model, hold)
    q_held = q[held].copy()
    m, n = model.n_constraints, model.n_coordinates
    if m > n and not len(held):
        # more equations than coordinates: only redundant rows can be satisfied together,
        # so every step is the least-change one (a lock-up shows as a stalled iteration)
        redundant = True
    elif m + len(held) > n:
        raise AssemblyError(
            f"position analysis of '{model.name}': {m} constraint equations"
            f"{f' and {len(held)} held coordinates' if len(held) else ''} for {n} coordinates; "
            "there are redundant constraints (see mbd3d.analyses.mobility) or too many held coordinates",
            time=t)

    equations = _PositionEquations(model, t, charts, held, q_held, tol)
    try:
        return _newton_raphson(model, equations, q, t, charts, redundant, max_iterations)
    except (AssemblyError, SingularJacobianError) as error:
        if redundant:
            raise
        # rounding can let the LU of rows that depend on each other pass its pivot test (a
        # redundant mechanism not declared so): its steps then carry an arbitrary part along
        # the dependent directions and stall, where least-change steps converge; at a lock-up
        # these fail too, and the first error says more
        try:
            return _newton_raphson(model, equations, q, t, charts, True, max_iterations)
        except (AssemblyError, SingularJacobianError):
            raise error from None


def _newton_raphson(model, equations: _PositionEquations, q: np.ndarray, t: float, charts,
                    redundant: bool, max_iterations: int) -> np.ndarray:
    """The iteration of :func:`solve_position` from ``q``: Newton steps (least-change ones
    where the rows depend on each other, or all of them with ``redundant``) shortened by
    backtracking until ``|C|`` decreases."""
    held, n, m = equations.held, model.n_coordinates, model.n_constraints
    m_total = m + len(held)
    C = equations.residual(q)
    norm = float(np.linalg.norm(equations.relative(C)))
    history = []
    M = None
    for iteration in range(max_iterations + 1):
        ratio, worst = equations.worst_and_limit(C, q)
        history.append(worst)
        if ratio <= 1.0:
            return q
        if iteration == max_iterations:
            break
        J = equations.jacobian(q)
        try:
            if redundant:
                raise SingularMatrix("dependent rows")
            if m_total == n:
                dq = Factorization(J, scaling=jacobian_scaling(model, held)).solve(-C)
            else:
                if M is None:
                    M = mass_matrix(model, constraints.frames(model, q, charts=charts))
                dq, _ = solve_augmented(M, J, np.zeros(n), -C, augmented_scaling(model, held))
        except SingularMatrix:
            # dependent rows: redundant constraints (solvable, least change) or a lock-up
            # (no solution); the augmented Lagrangian tells them apart by converging or not
            dq = _least_change_step(model, q, charts, J, C, m, held)
            if dq is None:
                raise singular_error(model, J[:m] if not sp.issparse(J) else J.tocsr()[:m], t,
                                     f"position analysis of '{model.name}'") from None
        # backtracking: accept the first step that reduces |C| (full steps near the solution)
        step = 1.0
        while True:
            q_try = q + step * dq
            C_try = equations.residual(q_try)
            norm_try = float(np.linalg.norm(equations.relative(C_try)))
            if np.isfinite(norm_try) and norm_try < (1.0 - 1e-4 * step) * norm:
                break
            step *= 0.5
            if step < 1e-6:
                break
        if step < 1e-6:
            break
        q, C, norm = q_try, C_try, norm_try

    raise _no_convergence(model, equations, q, C, t, history, iteration < max_iterations,
                          max_iterations)
