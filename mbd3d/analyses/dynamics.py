"""Forward dynamics: the augmented equations integrated in time with constraint stabilisation.

At every right-hand side evaluation the accelerations and multipliers come from

    [M  Cq^T] [qdd]   [Qe + Qv]
    [Cq 0   ] [lam] = [Qd     ]

(assembled and solved in one place, :mod:`mbd3d.numerics.compiled.accelerations`). The state is
integrated by the compiled explicit pairs of :mod:`mbd3d.numerics.compiled.runge_kutta` in the loop of
:mod:`mbd3d.numerics.compiled.integration`, which returns here at output times and when the
constraints have drifted. Because the index-1 equations only hold the constraints at
acceleration level, position and velocity drift; after an accepted step whose residual
exceeds ``constraint_tol`` the state is projected back onto ``C = 0`` and ``Cq qd = -Ct``
(mass-weighted least change: Newton-Raphson for positions, one linear solve for velocities)
and the method goes on from the projected state with its step size (only its first stage is
evaluated again). Output times are interpolated with the method's dense output and projected
the same way, so every reported state satisfies the constraints.
"""

from __future__ import annotations

import warnings
from typing import Mapping, Sequence

import numpy as np

from mbd3d.model import constraints
from mbd3d.numerics.compiled import callbacks, integration as stepping
from mbd3d.numerics.compiled.runge_kutta import TABLEAUS, interpolate, rms
from mbd3d.numerics.compiled.structures import workspace
from mbd3d.model.equations import augmented_accelerations, generalized_forces, python_parts
from mbd3d.errors import IntegrationError, ModelError, SingularJacobianError, StiffnessWarning
from mbd3d.analyses.implicit import (consistent_accelerations, integrate_generalized_alpha,
                                     rows_dependent)
from mbd3d.analyses.initial import consistent_initial_state
from mbd3d.analyses.kinematics import check_times, solve_velocity
from mbd3d.numerics.linalg import SingularMatrix, factor_model_augmented, jacobian_scaling
from mbd3d.numerics.rotations import to_quaternion
from mbd3d.analyses.position import LARGEST_DENSE_ANALYSIS, singular_error, solve_position
from mbd3d.io.observers import Observer, Watch
from mbd3d.io.results import Results
from mbd3d.io.store import ResultsBuffer, run_keeping_results

__all__ = ["forward_accelerations", "forward_dynamics", "project_state", "METHODS",
           "GENERALIZED_ALPHA"]

#: the explicit integrators selectable by name (the compiled pairs of
#: :mod:`mbd3d.numerics.compiled.runge_kutta`); "RK45" is the Dormand-Prince 5(4) pair of MATLAB's ode45
METHODS = tuple(TABLEAUS)
#: integrators refused, and why
_REFUSED = {name: (f"{name} is a multistep method: every projection onto the constraints "
                   "would restart it at order one with a tiny step, so that it projects again "
                   "after the next step (0.1 s of the free slider-crank took 98 s and 12,000 "
                   "projections with SciPy's). Use 'generalized-alpha' for stiff models, or "
                   "RK45/DOP853 otherwise.")
            for name in ("BDF", "LSODA")}
_REFUSED["Radau"] = ("Radau is no longer offered: the explicit integrators now run in mbd3d's "
                     "own compiled loop, and SciPy's Radau, driven from outside it, had to be "
                     "restarted with a new finite-difference Jacobian at every projection and "
                     "chart reset. Use 'generalized-alpha' (implicit, for stiff models and "
                     "singular positions), or RK45/DOP853.")
#: the implicit index-3 integrator of :mod:`mbd3d.analyses.implicit`
GENERALIZED_ALPHA = "generalized-alpha"


def forward_accelerations(model, t: float, q: np.ndarray, qd: np.ndarray,
                          charts: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Accelerations ``qdd`` and multipliers ``lam`` from the augmented equations at ``(t, q, qd)``.

    ``charts``: spatial models, the reference rotations ``q`` is relative to (default the
    model's initial charts).

    Raises
    ------
    SingularJacobianError
        When the augmented matrix is singular (names the dependent joints and the time).
    """
    try:
        x = augmented_accelerations(model, t, q, qd, charts)
    except SingularMatrix:
        return consistent_accelerations(model, t, q, qd, charts, fallback=False)[:2]
    if x is None:
        raise IntegrationError(f"forward dynamics of '{model.name}': the state is not finite "
                               f"at t = {t:.6g} s (the integration diverged)", time=t)
    n = model.n_coordinates
    return x[:n], x[n:]


def project_state(model, t: float, q: np.ndarray, qd: np.ndarray, tol: float,
                  charts: np.ndarray | None = None, redundant: bool = False
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Nearest (mass-weighted) state that satisfies the position and velocity constraints
    (``redundant``: see :func:`mbd3d.solve_position`)."""
    q = solve_position(model, q, t, tol=tol, charts=charts, redundant=redundant)
    return q, solve_velocity(model, q, t, qd_guess=qd, charts=charts, redundant=redundant)


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
#: element's stability limit explains it (steps within ten times that limit)
_CRAWL = 1e-2


def stiffest_elements(model) -> list[tuple[float, str]]:
    """The force elements by how fast they make the model respond, fastest first:
    ``(rate [1/s], description)``, the rate being ``sqrt(k / m)`` of a spring and ``c / m`` of a
    damper on the reduced mass (or inertia) of the bodies they join. An explicit method is
    stable for steps up to about 3 / rate."""
    from mbd3d.model.forces import RotationalSpringDamper, SpringDamper  # noqa: PLC0415

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
    if not elements or average_step > 10 * 3.0 / elements[0][0]:
        return None
    culprit = (f"{elements[0][1]} makes the model stiff: explicit steps above about "
               f"{3.0 / elements[0][0]:.1e} s are unstable")
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


def _is_number(value) -> bool:
    """A real number (not a flag, a string or an array)."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
        value, (bool, np.bool_))


def forward_dynamics(model, times: Sequence[float], q0: Sequence[float] | None = None,
                     qd0: Sequence[float] | None = None, *, method: str = "RK45",
                     rtol: float = 1e-8, atol: float = 1e-10, constraint_tol: float = 1e-8,
                     max_step: float = np.inf, step: float | None = None,
                     rho_inf: float = 0.9, hold: Sequence[str | int] | None = None,
                     initial_rates: Mapping[str, float] | None = None,
                     initial_positions: Mapping[str, float] | None = None, strict: bool = False,
                     observers: Sequence[Observer] | None = None,
                     progress: bool | None = None) -> Results:
    """Integrate the equations of motion from ``times[0]`` to ``times[-1]``.

    Parameters
    ----------
    model : Model
    times : (k,) array_like
        Output times [s], strictly increasing; the integration spans the first to the last.
    q0, qd0 : (n,) array_like, optional
        Initial guesses of coordinates and rates (default the bodies' guesses). They are first
        made consistent: positions by Newton-Raphson, velocities by mass-weighted projection.
    method : {"RK45", "DOP853", "RK23", "generalized-alpha"}
        "RK45" (Dormand-Prince, as MATLAB's ode45) for general use, "DOP853" for tight
        tolerances, "RK23" (Bogacki-Shampine) for loose ones: compiled explicit pairs on the
        index-1 equations with projection.
        "generalized-alpha": the implicit index-3 method of :mod:`mbd3d.analyses.implicit`, for stiff
        models (stiff springs), long runs, redundant constraints and mechanisms that pass
        singular configurations; second order, so it needs small steps for many digits.
    rtol, atol : float
        Integrator tolerances: relative, and absolute in the model's units (positions in units
        of ``model.length_scale``, angles in radians, rates per second), so that the same
        tolerances give the same accuracy to a mechanism of any size. Not used by
        "generalized-alpha", whose accuracy is set by ``step``.
    constraint_tol : float
        Largest position and velocity constraint residual allowed at the end of a step before
        the state is projected back, relative like ``atol`` (length rows in units of the
        model's length, per second for velocities; angle rows in rad, rad/s). Reported states
        are projected too.
    max_step : float
        Largest step [s].
    step : float, optional
        "generalized-alpha" only, and required there: the fixed step [s] (shortened to land on
        output times). Its error is second order: halving the step quarters it.
    rho_inf : float
        "generalized-alpha" only: spectral radius at infinite frequency, in [0, 1]; 1 adds
        no numerical damping, lower values damp the highest frequencies (stiff springs).
    hold : sequence of str or int, optional
        Coordinates kept at their given values (and rates) while assembling the initial state,
        e.g. ``["crank.theta"]``.
    initial_rates : mapping, optional
        Rates the initial state keeps exactly, in the user's terms: a joint's name for its
        angle rate [rad/s] or displacement rate [m/s] (``"name.angle"``,
        ``"name.displacement"`` for a cylindrical joint), or ``"body.coordinate"``; the other
        velocities are the mass-weighted nearest consistent ones to ``qd0`` (see
        :mod:`mbd3d.analyses.initial`).
    initial_positions : mapping, optional
        Positions the initial state takes, named the same way: a revolute's angle [rad] or a
        prismatic's displacement [m] from the drawing, as ``results.joint(name).angle`` and
        ``.displacement`` read them, or ``"body.coordinate"``; the rest of the mechanism is
        assembled around them, nearest the guess (see
        :func:`mbd3d.analyses.initial.place_joints`).
    strict : bool
        Refuse (ModelError) instead of warning (InitialStateWarning) when the given velocities
        (``qd0``, the bodies' ``velocity`` and ``angular_velocity``) or positions (``q0``)
        violate the constraints by more than ``constraint_tol`` and are changed; the changes
        are in ``results.stats["initial_state"]`` either way.
    observers : sequence of Observer, optional
        Watch the run as it goes (e.g. ``viewer.Recorder`` to stream to Rerun); see
        :mod:`mbd3d.io.observers`.
    progress : bool, optional
        Show a progress bar on stderr; default only when stderr is a terminal.

    Returns
    -------
    Results
        With ``lam`` (reactions, driver efforts) at every output time; ``stats`` holds
        ``steps``, ``rhs_evaluations``, ``projections``, ``chart_resets`` (spatial bodies
        re-referenced), ``max_drift`` (largest residual found at a step end before projection)
        and ``wall_time`` [s].

    Raises
    ------
    IntegrationError, SingularJacobianError, AssemblyError
        With ``.results`` holding the output times computed before the failure. An interrupt
        (Ctrl-C) returns the results so far with ``status == "interrupted"``.
    """
    t = check_times(times)
    if len(t) < 2:
        raise ModelError("forward_dynamics needs at least two output times (start and end)")
    if method in _REFUSED:
        raise ModelError(_REFUSED[method])
    if method not in METHODS and method != GENERALIZED_ALPHA:
        raise ModelError(f"method must be one of {', '.join(METHODS)}, {GENERALIZED_ALPHA}; "
                         f"got {method!r}")
    for label, value in (("rtol", rtol), ("atol", atol), ("constraint_tol", constraint_tol)):
        if not (_is_number(value) and np.isfinite(value) and value > 0):
            raise ModelError(f"{label} must be positive and finite, got {value!r}")
    if not (_is_number(max_step) and max_step > 0):  # inf (no limit) is allowed, NaN is not
        raise ModelError(f"max_step must be a positive time [s] (or inf: no limit), got "
                         f"{max_step!r}")
    if method == GENERALIZED_ALPHA:
        constraints.require_holonomic(model, "forward dynamics with generalized-alpha "
                                             "(an index-3 method, on positions)")
        return integrate_generalized_alpha(
            model, t, q0, qd0, step=step, rho_inf=rho_inf,
            constraint_tol=constraint_tol, max_step=max_step, hold=hold,
            initial_rates=initial_rates, initial_positions=initial_positions, strict=strict,
            observers=observers, progress=progress)
    if step is not None:
        raise ModelError(f"step applies to method='{GENERALIZED_ALPHA}'; the {method} "
                         "integrator chooses its own steps (limit them with max_step)")
    tableau = TABLEAUS[method]
    n = model.n_coordinates
    projection_tol = constraint_tol * 1e-3
    stats = {"method": method, "steps": 0, "rhs_evaluations": 0, "projections": 0,
             "chart_resets": 0, "max_drift": 0.0, "singular_outputs": [], "wall_time": 0.0}
    k_max = len(t)
    out = ResultsBuffer(model, "forward dynamics", t, stats)
    bt = model.body_type
    spatial = model.dim == 3
    # the reference rotations of the integration, moved in place by the compiled loop
    charts = np.array(model.charts0) if spatial else None
    # the charts as quaternions, their signs carried along every step (continuous output)
    turns = to_quaternion(charts) if spatial else np.zeros((0, 4))
    redundant = False  # set at the start: the constraint rows depend on each other

    def chart() -> np.ndarray | None:
        return charts.copy() if spatial else None

    def record(q: np.ndarray, qd: np.ndarray) -> None:
        tk = t[out.done]
        qdd, lam, _ = consistent_accelerations(model, tk, q, qd, chart(),
                                               fallback=redundant, redundant=redundant)
        if redundant:
            stats["singular_outputs"].append(float(tk))
        out.store(q, qd, qdd, lam, chart(), turns.copy() if spatial else None)

    # the integrated state is y = (q, v): positions and the velocities of BodyType.velocities
    # (angular velocities in body axes for spatial bodies), not (q, qd)
    def split(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return y[:n].copy(), bt.rates(y[:n], y[n:])

    def python_accelerations(tt, q, qd, charts_now):
        # redundant constraints (the augmented Lagrangian) or joint friction (consistent
        # with its reactions): solved in Python
        charts_now = charts_now if spatial else None
        qdd, lam, _ = consistent_accelerations(model, tt, q, qd, charts_now,
                                               redundant=redundant, fallback=False)
        return qdd, lam

    def failure(flags: int, t_fail: float, y_fail: np.ndarray) -> Exception:
        q, qd = split(y_fail)
        if flags == stepping.STEP_TOO_SMALL:
            return _step_failure(model, method, t_fail, q, chart(),
                                 "the step size fell below the spacing of floating-point "
                                 "numbers at this time")
        if flags == stepping.SINGULAR:
            try:  # raises the error that names the dependent joints
                consistent_accelerations(model, t_fail, q, qd, chart(), fallback=False)
            except (SingularJacobianError, IntegrationError) as error:
                return error
        try:  # a motion or force that cannot be evaluated there is named
            constraints.driver_values(model, t_fail), constraints.motion_phases(model, t_fail)
            generalized_forces(model, t_fail, constraints.frames(model, q, qd, chart()))
        except ModelError as error:
            return error
        return IntegrationError(f"forward dynamics of '{model.name}': the state became "
                                f"non-finite at t = {t_fail:.6g} s (the integration diverged)",
                                time=t_fail)

    def loop() -> None:
        nonlocal redundant
        q, qd, redundant = consistent_initial_state(
            model, t[0], q0, qd0, hold=hold, initial_rates=initial_rates,
            initial_positions=initial_positions, strict=strict,
            tol=constraint_tol, chart=chart(), stats=stats,
            what=f"forward dynamics of '{model.name}'",
            redundant_rows=lambda qq: rows_dependent(model, t[0], qq, chart()))
        # Redundant constraints (dependent rows from the start, as in Bricard's mechanism)
        # are solved throughout by the augmented Lagrangian, which gives the accelerations
        # and minimum-norm multipliers continuously. Rows that become dependent later (a
        # singular position) stop the run with a SingularJacobianError instead: there the
        # index-1 accelerations jump, and generalized-alpha is the method to use.
        record(q, qd)
        watch.tick(t[0], 0)
        arrays = model._core.arrays(
            python_accelerations=redundant or model.friction is not None)
        work = workspace(spatial, arrays)
        # atol in the model's units: positions in units of its length, angles in radians,
        # rates per second, so that a micrometre mechanism is integrated as accurately
        atol_y = atol * np.tile(model.coordinate_scale, 2)
        y = np.concatenate([q, bt.velocities(q, qd)])
        f = np.empty(2 * n)
        K = np.empty((tableau.n_stored, 2 * n))
        y_old = np.empty(2 * n)
        dense = np.empty((tableau.dense_rows, 2 * n))
        recent = np.zeros(_RECENT_STEPS)  # lengths of the last accepted steps [s]
        counters = np.zeros(4, dtype=np.int64)
        drift = np.zeros(2)
        with callbacks.Run(lambda tt, q, qd, charts: python_parts(model, tt, q, qd, charts),
                           solve=lambda values, rhs: model._augmented_pattern.solve(values, rhs),
                           accelerations=python_accelerations) as key:
            def first_stage(tt: float) -> None:
                status = stepping.derivative(arrays, key, tt, y, charts, f, work)
                counters[stepping.RHS_EVALUATIONS] += 1
                if status != 0:
                    raise failure(stepping.SINGULAR if status == 1 else stepping.DIVERGED,
                                  tt, y)

            first_stage(t[0])
            h = _initial_step(arrays, key, tableau, t[0], y, f, charts, rtol, atol_y,
                              min(max_step, t[-1] - t[0]), counters, work)
            t_now = t[0]
            check_at = _STIFFNESS_CHECK_STEPS if len(t) > 1 else -1
            while out.done < k_max:
                flags, t_now, t_old, step, h = stepping.advance(
                    arrays, key, tableau.arrays(), t_now, y, f, h, t[out.done], t[-1], rtol,
                    atol_y, max_step, charts, turns, constraint_tol, _STEP_CHART_LIMIT, recent,
                    counters,
                    drift, K, y_old, dense, 0.0 if redundant else STEP_COLLAPSE, check_at,
                    _STEPS_PER_CALL, work)
                stats.update(steps=int(counters[stepping.STEPS]),
                             rhs_evaluations=int(counters[stepping.RHS_EVALUATIONS]),
                             chart_resets=int(counters[stepping.CHART_RESETS]),
                             max_drift=float(drift[0]))
                if flags in _FAILURES:
                    raise failure(flags, t_now, y_old)
                if flags & stepping.CHECK_STIFFNESS:
                    spacing = float(np.min(np.diff(t)))
                    average = (t_now - float(t[0])) / stats["steps"]
                    message = (_stiffness_message(model, method, t_now, average, spacing)
                               if average < _CRAWL * spacing else None)
                    if message is not None:
                        warnings.warn(StiffnessWarning(message), stacklevel=4)
                if flags & stepping.COLLAPSED:
                    # a regular collapse (a sharp force) becomes the new normal
                    singular = _singular_here(
                        model, t_now, y[:n], chart(),
                        f"forward dynamics of '{model.name}' ({method}: the steps collapsed "
                        f"to {step:.1e} s)")
                    if singular is not None:
                        raise singular
                    recent[:] = 0.0
                if flags & stepping.OUTPUT:
                    while out.done < k_max and t[out.done] <= t_now:
                        tk = t[out.done]
                        yk = interpolate(tableau.dense_kind, dense, y_old, t_old, step, tk)
                        record(*project_state(model, tk, *split(yk), projection_tol, chart(),
                                              redundant))
                watch.tick(t_now, stats["steps"])
                if out.done >= k_max:
                    break
                if flags & stepping.DRIFTED:
                    q, qd = split(y)
                    projected = None if redundant else _project_with_one_factorization(
                        model, t_now, q, qd, projection_tol, chart())
                    q, qd = projected or project_state(model, t_now, q, qd, projection_tol,
                                                       chart(), redundant)
                    stats["projections"] += 1
                    # the method goes on from the projected state: only its first stage
                    # is evaluated again
                    y[:] = np.concatenate([q, bt.velocities(q, qd)])
                    first_stage(t_now)

    watch = Watch(observers, progress, model, t, "forward dynamics", out.partial)
    return run_keeping_results(loop, out.partial, watch)


#: accepted steps the compiled loop takes before it returns to Python anyway, so that an
#: interrupt (Ctrl-C) and the progress bar are seen during a long stretch without outputs
_STEPS_PER_CALL = 2000
#: |g| above which the explicit integrators move a body's chart between steps: zero, so that
#: every step starts from g = 0, where the Rodrigues parameters are nearly linear in the
#: rotation. With the usual limit (a quarter turn) a tumbling body's g grew through each chart
#: in three steps whose error estimates grew faster than the step control predicts, and one
#: step in three was rejected; a reset costs one 3x3 product per body, not a restart.
_STEP_CHART_LIMIT = 0.0
#: what the compiled loop returns when it failed
_FAILURES = (stepping.STEP_TOO_SMALL, stepping.SINGULAR, stepping.DIVERGED)


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
        return min(h0, interval)
    d2 = rms(f1 - f, scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (tableau.error_order + 1))
    return min(100 * h0, h1, interval)
