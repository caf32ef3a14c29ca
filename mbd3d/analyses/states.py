"""Analyses at given states of a model's driven coordinates, in any order, not along a
motion: inverse dynamics (the efforts and reactions that hold a mechanism in a state of
positions, rates and accelerations of its drivers), the joint-space mass matrix and bias
forces of the driven coordinates, and forward dynamics (their accelerations under given
efforts).

The drivers' coordinates are the joint terms: a :class:`~mbd3d.joints.RotationDriver`'s angle,
a :class:`~mbd3d.joints.TranslationDriver`'s slide (a URDF's joint angles when it was loaded
with ``drive=``). At each state every driver's motion is replaced by the values given, and the
point is solved as inverse dynamics solves a time point (positions by Newton-Raphson from the
previous state's, then velocities, accelerations and multipliers from the factors of the
Jacobian), so the answers are those of :func:`mbd3d.inverse_dynamics` at the same state.
"""

from __future__ import annotations

import copy
from typing import Any, Mapping

import numpy as np

from mbd3d.analyses.kinematics import (_PointSolver, _require_fully_driven, initial_guess)
from mbd3d.errors import AnalysisError, ModelError, did_you_mean
from mbd3d.io.observers import Watch
from mbd3d.io.results import Results
from mbd3d.io.store import ResultsBuffer, run_keeping_results
from mbd3d.joints import RotationDriver, TranslationDriver
from mbd3d.model import constraints
from mbd3d.model.motion import Motion
from mbd3d.numerics.rotations import to_quaternion

__all__ = ["driven_coordinates", "inverse_dynamics_at", "joint_space_dynamics_at",
           "forward_dynamics_at"]

_ANALYSIS = "inverse dynamics at given states"


def driven_coordinates(model) -> tuple[str, ...]:
    """The names of ``model``'s drivers, in the order the state-wise analyses take and return
    their values (the order they were added).

    Parameters
    ----------
    model : Model
    """
    return tuple(e.name for e in model.joints if e.is_driver)


#: the largest change of a driver's angle [rad] (of a slide: in the model's length) between
#: two positions solved one from the other; a longer way is taken in pieces
_PIECE = 0.25


class _Given(Motion):
    """A driver's motion that is, wherever it is evaluated, ``current[column]``: the ``(f,
    f', f'')`` being solved for (plus the driver's ``offset``)."""

    def __init__(self, current: np.ndarray, column: int, offset: float):
        self.current, self.column, self.offset = current, column, offset

    def evaluate(self, t: float) -> tuple[float, float, float]:
        f, df, d2f = self.current[self.column]
        return float(f) + self.offset, float(df), float(d2f)


def _column(model, names: tuple, given: Any, label: str, analysis: str = _ANALYSIS
            ) -> np.ndarray:
    """``given`` (a mapping by driver name, or an array whose last axis follows ``names``) as
    an array (k, d)."""
    if isinstance(given, Mapping):
        unknown = [key for key in given if key not in names]
        if unknown:
            raise ModelError(f"{analysis} of '{model.name}': {label} names '{unknown[0]}', "
                             f"which is not a driver{did_you_mean(unknown[0], names)}; its "
                             f"drivers: {list(names)}")
        missing = [name for name in names if name not in given]
        if missing:
            raise ModelError(f"{analysis} of '{model.name}': {label} has no value for "
                             f"driver '{missing[0]}' (give every driver's: {list(names)})")
        columns = [np.asarray(given[name], dtype=float).reshape(-1) for name in names]
        sizes = {len(c) for c in columns}
        if len(sizes) > 1 and 1 not in sizes or len(sizes) > 2:
            raise ModelError(f"{analysis} of '{model.name}': the drivers' {label} have "
                             f"different numbers of states: {sorted(sizes)}")
        k = max(sizes)
        return np.column_stack([np.broadcast_to(c, (k,)) for c in columns])
    array = np.asarray(given, dtype=float)
    if array.ndim == 0:  # one value for every driver (zero rates, say)
        array = np.full(len(names), float(array))
    if array.ndim == 1:
        array = array[None, :]
    if array.ndim != 2 or array.shape[1] != len(names):
        raise ModelError(f"{analysis} of '{model.name}': {label} must have one column per "
                         f"driver ({len(names)}: {list(names)}), got shape {np.shape(given)}")
    return array


def _states(model, q: Any, qd: Any, qdd: Any, analysis: str = _ANALYSIS) -> np.ndarray:
    """The states as ``(k, d, 3)``: each driver's ``(f, f', f'')``, checked (errors name
    ``analysis``)."""
    names = driven_coordinates(model)
    if not names:
        raise ModelError(f"{analysis} of '{model.name}': the model has no drivers; the "
                         "states are given in the drivers' coordinates (drive the joints, "
                         "e.g. load_urdf(..., drive={joint: 0.0, ...}))")
    parts = [_column(model, names, value, label, analysis)
             for value, label in ((q, "q"), (qd, "qd"), (qdd, "qdd"))]
    k = max(len(p) for p in parts)
    if any(len(p) not in (1, k) for p in parts):
        raise ModelError(f"{analysis} of '{model.name}': q, qd and qdd give "
                         f"{[len(p) for p in parts]} states")
    states = np.stack([np.broadcast_to(p, (k, len(names))) for p in parts], axis=2)
    bad = np.argwhere(~np.isfinite(states))
    if len(bad):
        s, d, part = bad[0]
        raise ModelError(f"{analysis} of '{model.name}': {('q', 'qd', 'qdd')[part]} of "
                         f"driver '{names[d]}' is not finite in state {s}")
    return states


def _with_given_motions(model, current: np.ndarray):
    """A copy of ``model`` whose drivers' motions are the values in ``current`` (d, 3)."""
    order = {name: column for column, name in enumerate(driven_coordinates(model))}
    offsets = {e.name: getattr(e, "offset", 0.0) for e in model.joints if e.is_driver}
    given = copy.copy(model)
    given.driver_motions = tuple(_Given(current, order[name], offsets[name])
                                 for name in model.driver_names)
    given.rotation_motions = tuple(_Given(current, order[name], offsets[name])
                                   for name in model.rotation_motion_names)
    return given


def _drawn(model, t: float) -> tuple[np.ndarray, np.ndarray] | None:
    """The drivers' coordinates in the drawing and each one's unit of a piece of the way
    (:data:`_PIECE` rad, or of the model's length); None where a driver reads neither an
    angle nor a slide."""
    rest = np.zeros((1, len(model.q0)))
    drawing = Results(model, "drawing", np.array([t]), model.q0[None], rest, rest,
                      charts=None if model.charts0 is None else model.charts0[None])
    values, units = [], []
    for name in driven_coordinates(model):
        element = drawing.joint(name).element
        if isinstance(element, RotationDriver):
            values.append(drawing.joint(name).angle[0] - element.offset)
            units.append(_PIECE)
        elif isinstance(element, TranslationDriver):
            values.append(drawing.joint(name).displacement[0] - element.offset)
            units.append(_PIECE * model.length_scale)
        else:
            return None
    return np.array(values), np.array(units)


def inverse_dynamics_at(model, q: Any, qd: Any, qdd: Any, t: float = 0.0, *,
                        q_guess: Any = None, tol: float = 1e-12) -> Results:
    """The efforts and reactions at given states of the drivers' coordinates.

    Parameters
    ----------
    model : Model
        Fully driven (its drivers fix every coordinate).
    q, qd, qdd : mapping or array_like
        Each driver's coordinate [rad or m], rate [/s] and acceleration [/s^2]: a mapping by
        driver name of scalars or arrays (k,), or arrays (k, d) (or (d,)) in the order of
        :func:`driven_coordinates`, or one number for all; one state broadcasts to all. The
        coordinate is what the driver's motion gives (a RotationDriver's angle, over any
        number of turns, less its ``offset``; a TranslationDriver's slide, less its: a
        URDF's joint coordinates for a robot loaded with ``drive=``).
    t : float
        The time [s] the applied forces are evaluated at (time-dependent ones).
    q_guess : (n,) array_like, optional
        Guess of the absolute coordinates at the first state (default the drawing's); each
        later state starts from the one before (give nearby states one after the other for a
        mechanism with several assembly branches).
    tol : float
        Newton-Raphson tolerance, as for :func:`mbd3d.inverse_dynamics`.

    Returns
    -------
    Results
        One point per state (all at ``t``): ``res.joint(driver).effort`` [N m or N] and the
        reactions, positions, velocities and accelerations, as inverse dynamics gives them.

    Raises
    ------
    ModelError
        A driver missing, unknown (with the nearest name), non-finite values or mismatched
        numbers of states; NotFullyDrivenError, AssemblyError and SingularJacobianError as
        for :func:`mbd3d.inverse_dynamics` (with ``.results`` holding the states done).
    """
    states = _states(model, q, qd, qdd)
    constraints.require_holonomic(model, _ANALYSIS)
    _require_fully_driven(model, _ANALYSIS)
    current = np.zeros(states.shape[1:])
    given = _with_given_motions(model, current)
    times = np.full(len(states), float(t))
    out = ResultsBuffer(given, _ANALYSIS, times, {"wall_time": 0.0})
    turns = None if model.charts0 is None else to_quaternion(model.charts0)
    solve_point = _PointSolver(given, tol, model.n_constraints > model.n_coordinates, turns,
                               _ANALYSIS)
    drawn = _drawn(model, float(t))

    def solve(values: np.ndarray, guess: np.ndarray, chart, first: bool, forces: bool):
        current[:] = values
        return solve_point(float(t), guess, chart, first, forces)

    def loop() -> None:
        chart = model.charts0
        guess = initial_guess(given, float(t), q_guess, chart, f"{_ANALYSIS} of "
                              f"'{model.name}'", "q_guess")
        # the first state from the drawing's, unless a guess was given for it
        start = None if drawn is None or q_guess is not None else drawn[0]
        first = True
        for k, target in enumerate(states):
            if start is not None:
                # far from the last state: there in pieces, each position predicted from the
                # last one's rate along the way, so that Newton-Raphson stays on its branch
                way = target[:, 0] - start
                pieces = int(np.ceil(np.max(np.abs(way) / drawn[1], initial=0.0)))
                for piece in range(1, pieces):
                    values = np.column_stack([start + way * piece / pieces, way,
                                              np.zeros_like(way)])
                    guess, rate, _, _, chart = solve(values, guess, chart, first, False)
                    guess, first = guess + rate / pieces, False
            guess, qd_k, qdd_k, lam, chart = solve(target, guess, chart, first, True)
            out.store(guess, qd_k, qdd_k, lam, chart, None if turns is None else turns.copy())
            start, first = None if drawn is None else target[:, 0], False

    watch = Watch(None, False, given, times, _ANALYSIS, out.partial)
    return run_keeping_results(loop, out.partial, watch)


def joint_space_dynamics_at(model, q: Any, qd: Any, t: float = 0.0, *, q_guess: Any = None,
                            tol: float = 1e-12) -> tuple[np.ndarray, np.ndarray]:
    """The mass matrix and bias forces of the drivers' coordinates at given states: the
    efforts are ``M(q) qdd + b(q, qd)``, with ``b`` the efforts at rest in acceleration
    (gravity, the velocity terms, applied forces).

    Parameters as for :func:`inverse_dynamics_at` (without ``qdd``).

    Parameters
    ----------
    model : Model
    q, qd : mapping or array_like
    t : float
    q_guess : (n,) array_like, optional
    tol : float
        As for :func:`mbd3d.inverse_dynamics_at`.

    Returns
    -------
    M : ndarray (k, d, d)
        ``M[s, i, j]``: the effort of driver ``i`` per unit acceleration of driver ``j``
        [kg m^2, kg m or kg], from the efforts of unit accelerations (exact: the efforts are
        linear in them).
    b : ndarray (k, d)
        [N m or N].
    """
    names = driven_coordinates(model)
    q_given = _states(model, q, qd, 0.0)
    k, d = q_given.shape[:2]
    # per state: (q, qd, 0), (q, 0, 0), then (q, 0, e_j) for each driver
    rows = np.zeros((k, d + 2, d, 3))
    rows[:, :, :, 0] = q_given[:, None, :, 0]
    rows[:, 0, :, 1] = q_given[:, :, 1]
    rows[:, 2:, :, 2] = np.eye(d)
    rows = rows.reshape(-1, d, 3)
    res = inverse_dynamics_at(model, rows[:, :, 0], rows[:, :, 1], rows[:, :, 2], t,
                              q_guess=q_guess, tol=tol)
    efforts = np.column_stack([res.joint(name).effort for name in names]).reshape(k, d + 2, d)
    M = np.swapaxes(efforts[:, 2:, :] - efforts[:, 1:2, :], 1, 2)
    return M, efforts[:, 0, :]


def forward_dynamics_at(model, q: Any, qd: Any, efforts: Any, t: float = 0.0, *,
                        q_guess: Any = None, tol: float = 1e-12) -> np.ndarray:
    """The accelerations of the drivers' coordinates at given states when the drivers exert
    the given efforts instead of imposing their motions: ``M(q) qdd = efforts - b(q, qd)``
    (see :func:`joint_space_dynamics_at`).

    Parameters
    ----------
    model : Model
        Fully driven: the drivers' coordinates are the mechanism's independent ones.
    q, qd : mapping or array_like
        As for :func:`mbd3d.inverse_dynamics_at`.
    efforts : mapping or array_like
        Each driver's effort [N m or N] (what :func:`inverse_dynamics_at` returns as
        ``res.joint(driver).effort``), as ``q`` is given; one state broadcasts to all.
    t, q_guess, tol
        As for :func:`mbd3d.inverse_dynamics_at`.

    Returns
    -------
    ndarray (k, d)
        ``qdd[s, i]``: driver ``i``'s acceleration [rad/s^2 or m/s^2] in state ``s``, in the
        order of :func:`driven_coordinates`.

    Raises
    ------
    ModelError
        As for :func:`mbd3d.inverse_dynamics_at`. and for efforts given for another number of states.
    AnalysisError
        A state where a driver's coordinate moves no mass (the mass matrix is singular).
    """
    what = "forward dynamics at given states"
    k = len(_states(model, q, qd, 0.0, what))
    tau = _column(model, driven_coordinates(model), efforts, "efforts", what)
    if len(tau) not in (1, k):
        raise ModelError(f"{what} of '{model.name}': efforts give {len(tau)} states, q and qd "
                         f"{k}")
    if not np.all(np.isfinite(tau)):
        raise ModelError(f"{what} of '{model.name}': the efforts are not all finite")
    M, b = joint_space_dynamics_at(model, q, qd, t, q_guess=q_guess, tol=tol)
    # a coordinate that moves no mass (or one whose inertia is lost to rounding) leaves its
    # acceleration undetermined: said, not returned as noise
    condition = np.linalg.cond(M)
    bad = np.flatnonzero(~(condition <= 1e12))
    if len(bad):
        raise AnalysisError(f"{what} of '{model.name}': in state {bad[0]} the drivers' mass "
                            f"matrix is singular (condition {condition[bad[0]]:.3g}): a "
                            "driven coordinate moves no mass")
    return np.linalg.solve(M, (np.broadcast_to(tau, b.shape) - b)[..., None])[..., 0]
