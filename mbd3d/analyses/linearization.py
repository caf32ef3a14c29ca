"""Linearisation: the linear equations of a mechanism about a state, for control design.

The constrained equations of motion are reduced onto independent measures by partitioning:
``k = n - rank`` displacements free of the position rows are chosen (by the user, or by a
column-pivoted QR of the scaled Jacobian that keeps the best-conditioned dependent set), and
``k_v`` velocities free of every row (``k_v = k`` unless rolling rows constrain velocities
only); the others follow from the constraints, by Newton-Raphson for positions and from
``Cq qd = -Ct`` for rates. The state is ``x = (p, v)``: the independent displacements ``p``
from the reference and the independent velocities ``v``, and about the reference motion
``(x = 0, u0)``

    dx' = A dx + B du,        dy = C dx + D du.

Displacements are taken relative to the reference motion itself: a position by its
difference, a spatial orientation by a small rotation ``theta`` [rad], with an angular
velocity as its velocity (:mod:`.moving_frames` says in which axes). By default both are in
the body's own axes, which turn with the reference (``A = A_ref exp(theta~)``, ``theta = 2 g``
in the reference's chart to first order, ``theta' = d omega_bar - omega_bar_ref x theta``):
about a motion steady in the bodies' axes (a body turning steadily about a fixed axis, a top
precessing without spin of its own) the matrices are constant and their eigenvalues are the
frequencies of the small motions, as about an equilibrium. A motion steady only in a frame
that turns at a constant rate, ``frame_rate`` (a symmetric top spinning about its axis while
it precesses: its body axes turn with the spin; a disc rolling straight on, a frame that does
not turn), has constant matrices with every vector measured in that frame's axes, and their
eigenvalues are then its frequencies. Along any other motion ``A(t)`` describes the
disturbances as a linear time-varying system: integrate ``dx' = A(t) dx`` along it (its
eigenvalues at one instant are not frequencies of the motion; those of a periodic one are
the Floquet multipliers of ``dx' = A(t) dx`` over a period, not computed here).

``B`` is exact: an input is a force whose generalized force ``Q_u`` enters the augmented
equations linearly, one solve per input. The rest of ``A`` and ``C`` comes from central
differences through the position and velocity solves and the augmented equations, with steps
of ``eps^(1/3)`` of each coordinate's scale (accelerations are quadratic in the rates, so the
rate columns carry only rounding).

The reduced form ``Mr dv' + Dr dv + Kr dp = Br du``, ``Mr = N_v^T M N_v`` with ``N_v =
dqd/dv`` (the partitioning's null-space basis), has ``Kr = -Mr A_vp`` and ``Dr = -Mr
A_vv``: at an equilibrium (and without rolling rows, ``v = p'``) the second-order form, with
the stiffness of the applied and the constraint forces (gravity's included) and the dampers';
at a moving state also the centripetal and gyroscopic terms (neither is then symmetric, and
for spatial bodies ``A`` holds the rotation terms the second-order form leaves out).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np
import scipy.linalg as la

from mbd3d.analyses.dynamics import forward_accelerations
from mbd3d.analyses.linear_io import (STEP, Output, input_matrices, outputs_of,
                                      released_drivers)
from mbd3d.analyses.moving_frames import measure
from mbd3d.errors import AnalysisError, ModelError
from mbd3d.io.results import Results
from mbd3d.model import constraints
from mbd3d.model.equations import generalized_forces, mass_matrix

__all__ = ["LinearModel", "linearize", "linearize_at"]

#: relative pivot of the scaled Jacobian below which a column counts as dependent
_RANK_TOLERANCE = 1e-10
#: state names of a spatial body's orientation coordinates g1, g2, g3: rotations about its axes
_ROTATIONS = {"g1": ("rx", "wx"), "g2": ("ry", "wy"), "g3": ("rz", "wz")}


@dataclass(frozen=True)
class LinearModel:
    """The linear equations of a mechanism about a state (see :mod:`.linearization`).

    ``dx' = A dx + B du``, ``dy = C dx + D du`` with ``x = (p, v)``: the independent
    coordinates' displacements from the reference motion and their velocities, in the
    units of the coordinates (lengths [m], planar angles [rad] and their rates) except for
    spatial orientations, whose displacement is a small rotation [rad] and whose velocity is
    an angular velocity [rad/s], about the body's own axes (or, with ``frame_rate``, about the
    axes of the turning frame: :mod:`.moving_frames`). A model with rolling (velocity-level)
    rows has fewer independent velocities ``v`` (k_v) than displacements ``p`` (k): its rows
    fix the rates, not the positions.

    Attributes
    ----------
    A : ndarray (k + k_v, k + k_v)
    B : ndarray (k + k_v, p)
        Per unit of each input [N or N m].
    C : ndarray (r, k + k_v)
    D : ndarray (r, p)
    states : list of str
        ``"body.coordinate"`` for ``p`` (``"body.rx"``, ``.ry``, ``.rz`` for a spatial
        body's rotations), then ``"body.coordinate_dot"`` (``"body.wx"``, ...) for ``v``.
    inputs, outputs : list of str
    mass, damping, stiffness : ndarray (k_v, k_v), (k_v, k_v), (k_v, k)
        ``Mr``, ``Dr``, ``Kr`` of ``Mr dv' + Dr dv + Kr dp = Br du`` (kg, kg m^2, N/m, N
        m/rad, ... by coordinate); without rolling rows (``v = p'`` about an equilibrium)
        the second-order form ``Mr dp'' + Dr dp' + Kr dp = Br du``.
    input_matrix : ndarray (k_v, p)
        ``Br``.
    basis : ndarray (n, k)
        ``N = dq/dp``: how every coordinate follows the independent displacements (for
        spatial bodies ``q`` is relative to ``charts``).
    t : float
        Time [s] of the reference.
    q, qd : ndarray (n,)
        The reference state, relative to ``charts``.
    charts : ndarray or None
        Spatial models: the reference rotations ``q`` is relative to, each body's attitude at
        the reference (so its Rodrigues parameters are zero there).
    rate_basis : ndarray (n, k_v)
        ``dqd/dv``: how every coordinate's rate follows the independent velocities.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: list[str]
    inputs: list[str]
    outputs: list[str]
    mass: np.ndarray
    damping: np.ndarray
    stiffness: np.ndarray
    input_matrix: np.ndarray
    basis: np.ndarray
    t: float
    q: np.ndarray
    qd: np.ndarray
    charts: np.ndarray | None = field(default=None, repr=False)
    rate_basis: np.ndarray | None = field(default=None, repr=False)

    @property
    def eigenvalues(self) -> np.ndarray:
        """Eigenvalues of ``A`` [1/s], largest real part first (a positive one: the state is
        unstable), then by imaginary part."""
        values = np.linalg.eigvals(self.A)
        return values[np.lexsort((-values.imag, -values.real))]


def linearize(model, q: Sequence[float], qd: Sequence[float] | None = None, t: float = 0.0, *,
              inputs: Sequence[str] = (), outputs: Sequence[str] | Mapping[str, Output] | None
              = None, coordinates: Sequence[str] | None = None,
              charts: np.ndarray | None = None, frame_rate: Sequence[float] | None = None,
              tol: float = 1e-8) -> LinearModel:
    """Linear state-space equations of ``model`` about the state ``(q, qd)`` at time ``t``.

    Parameters
    ----------
    model : Model
    q, qd : array_like (n,)
        A state that satisfies the constraints (from an analysis's results, or
        :func:`mbd3d.static_equilibrium`); ``qd`` default zero. Drivers not named in
        ``inputs`` are held at their motion (their coordinates are not states).
    t : float
        Time [s].
    inputs : sequence of str
        What the input ``u`` adds to [N, N m], one component each:

        - a force element of the model, ``"name.x"`` (``.y``, ``.z``) for a
          :class:`~mbd3d.PointForce` (in the axes it was given in) or a spatial
          :class:`~mbd3d.Torque`, ``"name"`` for a planar torque; the element's own value
          is the reference;
        - a driver's name: the driver is released and its effort (along its coordinate, as
          ``results.driver(name).effort``) is the input, about the effort that keeps the
          reference motion; its coordinate becomes a state.
    outputs : sequence of str, or mapping of name to str or callable, optional
        Default the states (``C = I``, ``D = 0``). A string names a coordinate
        (``"cart.x"``) or its rate (``"cart.x_dot"``); a callable takes the one-sample
        :class:`~mbd3d.Results` of a state (positions, velocities, accelerations,
        multipliers) and returns a number or a vector, e.g. a joint's reaction
        ``lambda r: r.joint("pin").reaction().force[0]``.
    coordinates : sequence of str, optional
        The independent coordinates ``"body.coordinate"`` (a spatial body's rotations as
        ``"body.rx"`` or ``"body.g1"``, alike), as many as the mechanism has degrees of
        freedom; default chosen from ``Cq``, the best-conditioned partition.
    charts : ndarray, optional
        Spatial models: the reference rotations ``q`` is relative to (default the model's).
    frame_rate : array_like (3,), optional
        Spatial models: the angular velocity [rad/s, global axes] of a frame whose axes
        the disturbances (displacements, rotations, velocities, angular velocities) are
        measured in (:class:`.moving_frames.TurningFrame`): for a motion steady in a turning
        frame but not in the bodies' axes (a spinning top's steady precession: the
        precession rate about the vertical; a disc rolling straight on: zero), which then has
        constant matrices whose eigenvalues are its frequencies. Default: each body's own
        axes (co-moving).
    tol : float
        How far ``(q, qd)`` may violate the constraints: positions relative to the model's
        length, rates to their largest term.

    Returns
    -------
    LinearModel

    Raises
    ------
    ModelError
        For a state that violates the constraints (names the rows), unknown inputs, outputs
        or coordinates, or coordinates that are not independent at the state.
    """
    what = f"linearisation of '{model.name}'"
    n = model.n_coordinates
    q = _vector(q, n, what, "q")
    qd = np.zeros(n) if qd is None else _vector(qd, n, what, "qd")
    t = float(t)
    if model.dim == 3:
        charts = model.charts0 if charts is None else np.asarray(charts, dtype=float)
        # the reference attitude as every body's chart: orientations start at g = 0
        q, qd, charts, _ = model.body_type.reset_charts(q, qd, charts, limit=0.0)
    else:
        charts = None
    released = released_drivers(model, inputs)
    system = _System(model, t, charts, released)
    Cq = system.jacobian(q)
    _check_state(model, t, system, q, qd, Cq, tol, what)
    # the reference effort of a released driver keeps the reference motion
    _, lam_full = forward_accelerations(model, t, q, qd, charts, what=what)
    system.efforts = np.array([-lam_full[model.rows_of(name)[0]] for name in released])

    measures = measure(model, q, qd, charts, frame_rate, what)
    # displacements free of the position rows; velocities free of every row (a rolling
    # disc's rows constrain velocities only: fewer of them), each in the measures' terms
    E0 = measures.velocity_map(q)
    independent, N = _partition(model, Cq[system.holonomic] @ measures.P,
                                system.holonomic, coordinates, what)
    rolling = len(system.holonomic) < len(system.active)
    rates_of, N_v = (_partition(model, Cq[system.active] @ np.linalg.inv(E0), system.active,
                                None, what) if rolling else (independent, N))
    k, kv = len(independent), len(rates_of)

    states = ([_state_name(model.coordinate_labels[j], 0) for j in independent]
              + [_state_name(model.coordinate_labels[j], 1) for j in rates_of])
    output_names, output_specs = outputs_of(model, outputs, states, what)
    sampler = _Sampler(system, measures, q, qd, independent, N, rates_of, output_specs, what)

    A = np.zeros((k + kv, k + kv))
    C_out = np.zeros((len(output_names), k + kv))
    scale = model.coordinate_scale
    position_steps = STEP * np.maximum(scale[independent], np.abs(q[independent]))
    gravity = float(np.linalg.norm(model.gravity))
    rate_unit = np.sqrt(gravity / model.length_scale) if gravity > 0 else 1.0
    rate_steps = STEP * np.maximum(scale[rates_of] * rate_unit,
                                   np.abs(measures.w0[rates_of]))
    for column in range(k + kv):
        j = column if column < k else column - k
        h = position_steps[j] if column < k else rate_steps[j]
        plus, minus = (sampler.at(column < k, j, sign * h) for sign in (1.0, -1.0))
        A[:k, column] = (plus.x_rate[independent] - minus.x_rate[independent]) / (2 * h)
        A[k:, column] = (plus.w_rate[rates_of] - minus.w_rate[rates_of]) / (2 * h)
        if output_specs is not None:
            C_out[:, column] = (plus.y - minus.y) / (2 * h)
    turning = measures.turning(N)
    if turning is not None:  # a frame that turns: each vector's rate less Omega x itself
        A[:k, :k] += turning[independent]
        A[k:, k:] += measures.turning(N_v)[rates_of]

    B, D_out = input_matrices(system, sampler, q, qd, Cq, inputs, k, rates_of,
                              len(output_names), what)
    if output_specs is None:
        C_out, D_out = np.eye(k + kv), np.zeros((k + kv, B.shape[1]))

    frames = constraints.frames(model, q, qd, charts)
    basis, rate_basis = measures.P @ N, np.linalg.solve(E0, N_v)
    Mr = rate_basis.T @ mass_matrix(model, frames, sparse=False) @ rate_basis
    return LinearModel(
        A=A, B=B, C=C_out, D=D_out, states=states, inputs=list(inputs), outputs=output_names,
        mass=Mr, damping=-Mr @ A[k:, k:], stiffness=-Mr @ A[k:, :k],
        input_matrix=Mr @ B[k:], basis=basis, t=t, q=q, qd=qd, charts=charts,
        rate_basis=rate_basis)


def _state_name(label: str, order: int) -> str:
    body, _, coordinate = label.rpartition(".")
    if coordinate in _ROTATIONS:
        return f"{body}.{_ROTATIONS[coordinate][order]}"
    return label if order == 0 else f"{label}_dot"


def _vector(value, n: int, what: str, name: str) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ModelError(f"{what}: {name} must be {n} numbers") from None
    if array.size != n or not np.all(np.isfinite(array)):
        raise ModelError(f"{what}: {name} must be {n} finite numbers (the model's coordinates), "
                         f"got {array.size}")
    return array.copy()


def _check_state(model, t, system, q, qd, Cq, tol, what) -> None:
    """A linearisation about a state off the constraints would describe another mechanism:
    refuse it, naming the rows (never project it silently). Released drivers' rows are not
    constraints of the linear model."""
    rows = system.active
    frames = constraints.frames(model, q, qd, system.charts)
    C, _, _, nu = constraints.evaluate(model, t, frames, jacobian=False, rate=True)
    position = np.abs(C[rows]) / model.row_scale[rows]
    # rates against the largest term of any row, in units of the model's length
    terms = (np.abs(Cq[rows]) @ np.abs(qd) + np.abs(nu[rows])) / model.row_scale[rows]
    velocity = (np.abs(Cq[rows] @ qd - nu[rows]) / model.row_scale[rows]
                / max(float(np.max(terms, initial=0.0)), 1e-300))
    for kind, violation in (("position", position), ("velocity", velocity)):
        worst = np.argsort(violation)[::-1][:3]
        if violation.size and violation[worst[0]] > tol:
            named = ", ".join(f"{model.row_labels[rows[r]]} ({violation[r]:.1e})" for r in worst
                              if violation[r] > tol)
            raise ModelError(
                f"{what}: the state violates the {kind} constraints at t = {t:.6g} s ({named}, "
                "relative); linearise about a state from an analysis's results, or make it "
                "consistent with mb.solve_position and mb.solve_velocity")


class _System:
    """The equations the linear model describes: the model's, less the rows of the released
    drivers, whose reference efforts act as forces. Dense (a linearisation is of a model
    small enough for its ``A`` to be read)."""

    def __init__(self, model, t, charts, released):
        self.model, self.t, self.charts = model, t, charts
        self.released_rows = np.array([int(model.rows_of(name)[0]) for name in released],
                                      dtype=int)
        for name in released:
            if len(model.rows_of(name)) != 1:
                raise ModelError(f"linearisation of '{model.name}': driver '{name}' has "
                                 f"{len(model.rows_of(name))} rows; an input is one effort")
        self.active = np.setdiff1d(np.arange(model.n_constraints), self.released_rows)
        #: the active rows that constrain positions (not a rolling disc's velocity rows)
        self.holonomic = np.setdiff1d(self.active, model.velocity_rows)
        self.efforts = np.zeros(len(released))

    def jacobian(self, q) -> np.ndarray:
        frames = constraints.frames(self.model, q, charts=self.charts)
        data = constraints.evaluate(self.model, self.t, frames, value=False)[1]
        return constraints.jacobian_matrix(self.model, data, sparse=False)

    def position(self, q, held: np.ndarray, target: np.ndarray, what) -> np.ndarray:
        """Newton-Raphson on the active position rows with the measures ``held @ q`` (rows of
        linear combinations of the coordinates) at ``target``, from a guess first-order close
        (a tangent step)."""
        model = self.model
        rows = self.holonomic
        scale = np.concatenate([model.row_scale[rows],
                                np.abs(held) @ model.coordinate_scale])
        for _ in range(20):
            frames = constraints.frames(model, q, charts=self.charts)
            C, data, _ = constraints.evaluate(model, self.t, frames)
            Cq = constraints.jacobian_matrix(model, data, sparse=False)
            residual = np.concatenate([C[rows], held @ q - target])
            if np.max(np.abs(residual) / scale, initial=0.0) <= 1e-14:
                return q
            q = q - la.lstsq(np.vstack([Cq[rows], held]), residual)[0]
        raise AnalysisError(f"{what}: the constraints do not close about a displaced state at "
                            f"t = {self.t:.6g} s (residual {np.max(np.abs(residual) / scale):.1e});"
                            " the state is at or near a singular position")

    def rates(self, q, E, w) -> np.ndarray:
        """``qd`` with ``Cq qd = -Ct`` (active rows) and the velocity measures ``E qd = w``
        (``E``: rows of the velocity map at ``q``)."""
        model = self.model
        frames = constraints.frames(model, q, charts=self.charts)
        _, data, _, nu = constraints.evaluate(model, self.t, frames, value=False, rate=True)
        Cq = constraints.jacobian_matrix(model, data, sparse=False)[self.active]
        return la.lstsq(np.vstack([Cq, E]), np.concatenate([nu[self.active], w]))[0]

    def augmented(self, q, qd):
        """``(M, Cq of the active rows, Q with the released efforts, Qd of the active rows,
        Cq of every row)`` at a state."""
        model = self.model
        frames = constraints.frames(model, q, qd, self.charts)
        _, data, Qd = constraints.evaluate(model, self.t, frames, value=False, gamma=True)
        Cq = constraints.jacobian_matrix(model, data, sparse=False)
        Q = generalized_forces(model, self.t, frames) + Cq[self.released_rows].T @ self.efforts
        return mass_matrix(model, frames, sparse=False), Cq[self.active], Q, Qd[self.active], Cq

    def solve(self, M, Ca, Q, Qd) -> tuple[np.ndarray, np.ndarray]:
        """``qdd`` and the active rows' ``lam`` of ``[M Ca^T; Ca 0] [qdd; lam] = [Q; Qd]``
        (least squares where rows are redundant: the accelerations are still unique)."""
        n, m = M.shape[0], Ca.shape[0]
        K = np.block([[M, Ca.T], [Ca, np.zeros((m, m))]])
        rhs = np.concatenate([Q, Qd])
        try:
            x = la.solve(K, rhs)
        except la.LinAlgError:
            x = la.lstsq(K, rhs)[0]
        return x[:n], x[n:]

    def accelerations(self, q, qd) -> tuple[np.ndarray, np.ndarray]:
        """``qdd`` and every row's ``lam`` (a released driver's: minus its effort)."""
        M, Ca, Q, Qd, _ = self.augmented(q, qd)
        qdd, lam_active = self.solve(M, Ca, Q, Qd)
        lam = np.empty(self.model.n_constraints)
        lam[self.active] = lam_active
        lam[self.released_rows] = -self.efforts
        return qdd, lam


def _coordinate_index(model, label: str) -> int:
    body, _, name = label.rpartition(".")
    for coordinate, (rotation, _) in _ROTATIONS.items():
        if model.dim == 3 and name == rotation:
            label = f"{body}.{coordinate}"
    return model.coordinate_index(label)


def _partition(model, J: np.ndarray, rows: np.ndarray, coordinates, what: str
               ) -> tuple[np.ndarray, np.ndarray]:
    """The independent measures (in the user's order) of the constraint rows ``rows`` whose
    Jacobian in the measures is ``J``, and the basis ``N`` (n, k) of how every measure
    follows them."""
    independent, dependent = _independent(model, J, rows, coordinates, what)
    N = np.zeros((model.n_coordinates, len(independent)))
    N[independent] = np.eye(len(independent))
    if len(independent) and len(dependent):
        N[dependent] = -la.lstsq(J[:, dependent], J[:, independent])[0]
    return independent, N


def _independent(model, Cq: np.ndarray, rows: np.ndarray, coordinates, what: str
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Indices of the independent (in the user's order) and dependent coordinates, from the
    Jacobian ``Cq`` of the constraint rows ``rows``."""
    n = model.n_coordinates
    scaled = Cq * model.coordinate_scale[None, :] / model.row_scale[rows][:, None]
    if scaled.shape[0]:
        _, R, pivots = la.qr(scaled, pivoting=True, mode="economic")
        diagonal = np.abs(np.diag(R))
        rank = int(np.sum(diagonal > _RANK_TOLERANCE * max(diagonal.max(initial=0.0), 1e-300)))
    else:
        pivots, rank = np.arange(n), 0
    if coordinates is None:
        dependent = np.sort(pivots[:rank])
        return np.setdiff1d(np.arange(n), dependent), dependent
    try:
        independent = np.array([_coordinate_index(model, label) for label in coordinates],
                               dtype=int)
    except ModelError as exc:
        raise ModelError(f"{what}: coordinates: {exc}") from None
    if len(set(independent.tolist())) != n - rank or len(independent) != n - rank:
        hint = " (name a driver in inputs to release it)" if rank == n else ""
        raise ModelError(f"{what}: the mechanism has {n - rank} degrees of freedom here"
                         f"{hint}; coordinates names {len(set(independent.tolist()))} distinct "
                         "ones")
    dependent = np.setdiff1d(np.arange(n), independent)
    block = scaled[:, dependent]
    singular = la.svdvals(block) if block.size else np.zeros(0)
    if rank and singular[rank - 1] <= _RANK_TOLERANCE * max(singular[0], 1e-300):
        suggestion = ", ".join(model.coordinate_labels[j] for j in np.sort(pivots[rank:]))
        raise ModelError(f"{what}: {', '.join(coordinates)} are not independent at this state "
                         "(the joints do not fix the other coordinates from them); choose "
                         f"others, e.g. {suggestion}")
    return independent, dependent


class _Sample:
    __slots__ = ("x_rate", "w_rate", "y")

    def __init__(self, x_rate, w_rate, y):
        self.x_rate, self.w_rate, self.y = x_rate, w_rate, y


class _Sampler:
    """States displaced along one independent measure of displacement or of velocity,
    completed by the constraints, with the rates of every measure and the outputs."""

    def __init__(self, system, measures, q, qd, independent, basis, rates_of, output_specs,
                 what):
        self.system, self.measures, self.q, self.qd = system, measures, q, qd
        self.independent, self.basis, self.rates_of = independent, basis, rates_of
        self.output_specs = output_specs
        self.what = what

    def at(self, position: bool, j: int, h: float) -> _Sample:
        system, measures = self.system, self.measures
        q, w = self.q, measures.w0[self.rates_of].copy()
        if position:
            held = measures.P_inv[self.independent]
            target = held @ q + h * np.eye(len(self.independent))[j]
            q = system.position(q + h * measures.P @ self.basis[:, j], held, target, self.what)
        else:
            w[j] += h
        qd = system.rates(q, measures.velocity_map(q)[self.rates_of], w)
        qdd, lam = system.accelerations(q, qd)
        v, v_rate = measures.rates(q, qd, qdd)
        x_rate = measures.position_rate(v, measures.P_inv @ (q - self.q))
        return _Sample(x_rate, v_rate, self.evaluate(q, qd, qdd, lam))

    def w_rate(self, q, qd, qdd) -> np.ndarray:
        """The velocity measures' rates at a state."""
        return self.measures.rates(q, qd, qdd)[1]

    def evaluate(self, q, qd, qdd, lam) -> np.ndarray | None:
        if self.output_specs is None:
            return None
        system = self.system
        results = None
        values = []
        for spec in self.output_specs:
            if isinstance(spec, tuple):
                index, rate = spec
                values.append([(qd if rate else q)[index]])
                continue
            if results is None:
                charts = system.charts
                results = Results(system.model, "linearisation", np.array([system.t]), q[None],
                                  qd[None], qdd[None], lam[None],
                                  charts=None if charts is None else charts[None])
            values.append(np.ravel(np.asarray(spec(results), dtype=float)))
        return np.concatenate(values) if values else np.zeros(0)


def linearize_at(model, times: Sequence[float], *, about: str = "drawing",
                 inputs: Sequence[str] = (), outputs: Sequence[str] | None = None,
                 coordinates: Sequence[str] | None = None,
                 frame_rate: Sequence[float] | None = None,
                 release: Sequence[str] = ()) -> LinearModel:
    """The linearisation a model file asks for (``{kind: linearize, t: [t0], ...}``): at the
    one time of ``times`` [s], about the drawing's state (``about: drawing``: the model's
    initial coordinates and rates, which must satisfy the constraints: a moving reference
    such as a spinning top's) or about the static equilibrium found from it (``about:
    equilibrium``, with the drivers named in ``release`` released); the other options as for
    :func:`linearize` (outputs named by coordinate)."""
    what = f"linearisation of '{model.name}'"
    t = np.atleast_1d(np.asarray(times, dtype=float))
    if t.size != 1:
        raise ModelError(f"{what}: a linearisation is about one time; give t: [t0], got "
                         f"{t.size} times")
    if about == "drawing":
        q, qd, charts = model.q0, model.qd0, None
    elif about == "equilibrium":
        from mbd3d.analyses.statics import static_equilibrium  # noqa: PLC0415
        rest = static_equilibrium(model, [float(t[0])], release=release)
        q, qd = rest.q[0], np.zeros(model.n_coordinates)
        charts = None if rest.charts is None else rest.charts[0]
    else:
        raise ModelError(f"{what}: about must be 'drawing' or 'equilibrium', got {about!r}")
    if release and about != "equilibrium":
        raise ModelError(f"{what}: release is for about: equilibrium (name the drivers to "
                         "release in inputs to linearise with their efforts as inputs)")
    return linearize(model, q, qd, float(t[0]), inputs=inputs, outputs=outputs,
                     coordinates=coordinates, charts=charts, frame_rate=frame_rate)
