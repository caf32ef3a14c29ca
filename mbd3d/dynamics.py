"""Forward dynamics: the augmented equations integrated in time with constraint stabilisation.

At every right-hand side evaluation the accelerations and multipliers come from

    [M  Cq^T] [qdd]   [Qe + Qv]
    [Cq 0   ] [lam] = [Qd     ]

(the one place this solve is written: :func:`forward_accelerations`). The state ``(q, qd)`` is
integrated by one of SciPy's ``OdeSolver`` classes, stepped one step at a time. Because the
index-1 equations only hold the constraints at acceleration level, position and velocity drift;
after every accepted step whose residual exceeds ``constraint_tol`` the state is projected back
onto ``C = 0`` and ``Cq qd = -Ct`` (mass-weighted least change: Newton-Raphson for positions, one
linear solve for velocities) and the integrator restarts from the projected state with its last
step size. Output times are interpolated with the integrator's dense output and projected the
same way, so every reported state satisfies the constraints.
"""

from __future__ import annotations

import warnings
from collections import deque
from typing import Sequence

import numpy as np
import scipy.integrate as si

from mbd3d import constraints
from mbd3d.errors import IntegrationError, ModelError, StiffnessWarning
from mbd3d.implicit import consistent_accelerations, integrate_generalized_alpha, rows_dependent
from mbd3d.kinematics import check_times, initial_guess, solve_velocity
from mbd3d.linalg import SingularMatrix, factor_model_augmented, jacobian_scaling
from mbd3d.position import singular_error, solve_position
from mbd3d.observers import Observer, Watch
from mbd3d.results import Results, ResultsBuffer, run_keeping_results

__all__ = ["forward_accelerations", "forward_dynamics", "project_state", "METHODS",
           "GENERALIZED_ALPHA"]

#: integrators selectable by name; "RK45" is the Dormand-Prince 5(4) pair of MATLAB's ode45
METHODS = {"RK45": si.RK45, "DOP853": si.DOP853, "RK23": si.RK23, "Radau": si.Radau}
#: SciPy integrators refused, and why: a projection onto the constraints restarts them
_REFUSED = {name: (f"{name} is a multistep method: every projection onto the constraints "
                   "restarts it at order one with a tiny step, so that it projects again after "
                   "the next step (0.1 s of the free slider-crank took 98 s and 12,000 "
                   "projections). Use 'generalized-alpha' for stiff models, 'Radau' for an "
                   "implicit one-step method, or RK45/DOP853 otherwise.")
            for name in ("BDF", "LSODA")}
#: the implicit index-3 integrator of :mod:`mbd3d.implicit`
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
    qdd, lam, _ = consistent_accelerations(model, t, q, qd, charts, fallback=False)
    return qdd, lam


def project_state(model, t: float, q: np.ndarray, qd: np.ndarray, tol: float,
                  charts: np.ndarray | None = None, redundant: bool = False
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Nearest (mass-weighted) state that satisfies the position and velocity constraints
    (``redundant``: see :func:`mbd3d.solve_position`)."""
    q = solve_position(model, q, t, tol=tol, charts=charts, redundant=redundant)
    return q, solve_velocity(model, q, t, qd_guess=qd, charts=charts, redundant=redundant)


def _project_with_one_factorization(model, t: float, q: np.ndarray, qd: np.ndarray, tol: float,
                                    charts: np.ndarray, evaluated: tuple | None = None
                                    ) -> tuple[np.ndarray, np.ndarray] | None:
    """The mass-weighted projection of :func:`project_state` for a state that has drifted
    only slightly (a step of the explicit integrators), from one factorization.

    ``[M Cq^T; Cq 0]`` is factored once at ``q``; the position and then the velocity
    corrections are simplified Newton iterations with those factors. The drift is far below
    the size of anything in the matrix, so each iteration cuts the residual by orders of
    magnitude, where :func:`project_state` would refactor at every Newton iterate and again
    for the velocities. ``None`` when the iterations do not settle (the caller then falls
    back to :func:`project_state`, which reports singular positions by name).
    ``evaluated``: ``(fr, C, jac_data)`` at ``q`` when the caller has them (the drift check).
    """
    n = model.n_coordinates
    zeros = np.zeros(n)
    fr, C, jac_data = evaluated or _constraints_at(model, t, q, charts)
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


def _difference_jacobian(rhs, n_y: int):
    """Forward-difference Jacobian of ``rhs`` for the implicit integrators.

    SciPy's own estimate adapts its step per column and lets it grow without bound on columns
    that are identically zero (coordinates nothing depends on, such as a free body's position
    under constant gravity), which overflows; a fixed relative step is robust here.
    """
    def jac(t: float, y: np.ndarray) -> np.ndarray:
        f0 = rhs(t, y)
        J = np.empty((n_y, n_y))
        for j in range(n_y):
            h = 1.5e-8 * max(1.0, abs(y[j]))
            y_step = y.copy()
            y_step[j] += h
            J[:, j] = (rhs(t, y_step) - f0) / h
        return J
    return jac


#: smallest singular value of ``Cq``, relative to its largest, below which a collapsed step
#: of an explicit integrator is put down to a singular position: the index-1 accelerations
#: grow without bound there, and the steps shrink until they underflow
NEARLY_SINGULAR = 1e-4
#: largest Jacobian (rows x columns) whose singular values are computed to explain a failure
_LARGEST_SVD = 4_000_000


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
    from mbd3d.forces import RotationalSpringDamper, SpringDamper  # noqa: PLC0415

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
               f"{3.0 / elements[0][0]:.1e} s are unstable"
               + (", and Radau, restarted after every projection onto the constraints, does "
                  "not get far past that either" if method == "Radau" else ""))
    return (f"forward dynamics of '{model.name}' ({method}) is crawling at t = {t:.6g} s: its "
            f"steps average {average_step:.1e} s, {spacing / average_step:.0e} times shorter "
            f"than the output spacing of {spacing:.3g} s. The {culprit}. Use "
            "method='generalized-alpha' with step= a fraction of the motion's time scale, "
            "which is not limited by stiffness.")


def _singular_here(model, t: float, q: np.ndarray, charts, what: str) -> Exception | None:
    """A :class:`SingularJacobianError` naming the joints when the constraint Jacobian at
    ``q`` is (nearly) singular, else None (also when the model is too large to tell)."""
    if not (np.all(np.isfinite(q)) and model.n_constraints
            and model.n_constraints * model.n_coordinates <= _LARGEST_SVD):
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


def _drift(model, t, q, qd, charts) -> tuple[float, tuple]:
    """Largest position or velocity constraint residual, relative to the rows' scales (lengths
    in units of the model's length, per second for velocities), and what was evaluated for it
    (``(frames, C, Jacobian values)``, which a projection from ``q`` starts from)."""
    evaluated = fr, C, jac_data = _constraints_at(model, t, q, charts)
    v = constraints.jacobian_times(model, jac_data, qd) - constraints.velocity_rhs(model, t, fr)
    return max(constraints.largest_relative(model, C),
               constraints.largest_relative(model, v)), evaluated


def _is_number(value) -> bool:
    """A real number (not a flag, a string or an array)."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
        value, (bool, np.bool_))


def forward_dynamics(model, times: Sequence[float], q0: Sequence[float] | None = None,
                     qd0: Sequence[float] | None = None, *, method: str = "RK45",
                     rtol: float = 1e-8, atol: float = 1e-10, constraint_tol: float = 1e-8,
                     max_step: float = np.inf, step: float | None = None,
                     rho_inf: float = 0.9, hold: Sequence[str | int] | None = None,
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
    method : {"RK45", "DOP853", "RK23", "Radau", "generalized-alpha"}
        "RK45" (Dormand-Prince, as MATLAB's ode45) for general use, "DOP853" for tight
        tolerances: SciPy's explicit pairs on the index-1 equations with projection.
        "generalized-alpha": the implicit index-3 method of :mod:`mbd3d.implicit`, for stiff
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
    observers : sequence of Observer, optional
        Watch the run as it goes (e.g. ``viewer.Recorder`` to stream to Rerun); see
        :mod:`mbd3d.observers`.
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
        return integrate_generalized_alpha(
            model, t, q0, qd0, step=step, rho_inf=rho_inf,
            constraint_tol=constraint_tol, max_step=max_step, hold=hold, observers=observers,
            progress=progress)
    if step is not None:
        raise ModelError(f"step applies to method='{GENERALIZED_ALPHA}'; the {method} "
                         "integrator chooses its own steps (limit them with max_step)")
    solver_cls = METHODS[method]
    n = model.n_coordinates
    projection_tol = constraint_tol * 1e-3
    stats = {"method": method, "steps": 0, "rhs_evaluations": 0, "projections": 0,
             "chart_resets": 0, "max_drift": 0.0, "singular_outputs": [], "wall_time": 0.0}
    k_max = len(t)
    out = ResultsBuffer(model, "forward dynamics", t, stats)
    chart = model.charts0  # reference rotations of the current integration segment

    redundant = False  # set at the start: the constraint rows depend on each other

    def accelerations(tt, q, qd):
        if not redundant:
            return forward_accelerations(model, tt, q, qd, chart)
        qdd, lam, _ = consistent_accelerations(model, tt, q, qd, chart, redundant=True)
        return qdd, lam

    # the integrated state is (q, v): positions and the velocities of BodyType.velocities
    # (angular velocities in body axes for spatial bodies), not (q, qd)
    bt = model.body_type

    def rhs(tt: float, y: np.ndarray) -> np.ndarray:
        stats["rhs_evaluations"] += 1
        q = y[:n]
        qd = bt.rates(q, y[n:])
        return np.concatenate([qd, bt.velocity_derivative(q, qd, accelerations(tt, q, qd)[0])])

    def state(q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        return np.concatenate([q, bt.velocities(q, qd)])

    def split(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return y[:n], bt.rates(y[:n], y[n:])

    def record(q: np.ndarray, qd: np.ndarray) -> None:
        tk = t[out.done]
        qdd, lam = accelerations(tk, q, qd)
        if redundant:
            stats["singular_outputs"].append(float(tk))
        out.store(q, qd, qdd, lam, chart)

    def loop() -> None:
        nonlocal chart, redundant
        guess = initial_guess(model, t[0], q0, chart, f"forward dynamics of '{model.name}'",
                              "q0")
        q = solve_position(model, guess, t[0], tol=projection_tol, hold=hold)
        redundant = rows_dependent(model, t[0], q, chart)
        qd = solve_velocity(model, q, t[0], qd_guess=qd0, hold=hold, redundant=redundant)
        # Redundant constraints (dependent rows from the start, as in Bricard's mechanism)
        # are solved throughout by the augmented Lagrangian, which gives the accelerations
        # and minimum-norm multipliers continuously. Rows that become dependent later (a
        # singular position) stop the run with a SingularJacobianError instead: there the
        # index-1 accelerations jump, and generalized-alpha is the method to use.
        record(q, qd)
        watch.tick(t[0], 0)
        # atol in the model's units: positions in units of its length, angles in radians,
        # rates per second, so that a micrometre mechanism is integrated as accurately
        options = {"rtol": rtol, "atol": atol * np.tile(model.coordinate_scale, 2),
                   "max_step": max_step}
        if method == "Radau":
            options["jac"] = _difference_jacobian(rhs, 2 * n)
        solver = solver_cls(rhs, t[0], state(q, qd), t[-1], **options)
        recent: deque = deque(maxlen=_RECENT_STEPS)  # lengths of the last accepted steps [s]
        while out.done < k_max:
            message = solver.step()
            if solver.status == "failed":
                raise _step_failure(model, method, float(solver.t), solver.y[:n], chart, message)
            stats["steps"] += 1
            if not np.all(np.isfinite(solver.y)):
                raise IntegrationError(f"forward dynamics of '{model.name}': the state became "
                                       f"non-finite at t = {solver.t:.6g} s", time=float(solver.t))
            if stats["steps"] == _STIFFNESS_CHECK_STEPS and len(t) > 1:
                spacing = float(np.min(np.diff(t)))
                average = (float(solver.t) - float(t[0])) / stats["steps"]
                message = (_stiffness_message(model, method, float(solver.t), average, spacing)
                           if average < _CRAWL * spacing else None)
                if message is not None:
                    warnings.warn(StiffnessWarning(message), stacklevel=4)
            if not redundant and solver.step_size is not None:
                # The index-1 accelerations grow without bound at a singular position: the
                # steps collapse there, and with luck in the rounding a pair steps over it onto
                # another branch and goes on, a wrong motion that would end "complete". So a
                # collapse is checked, and a singular Jacobian stops the run.
                recent.append(solver.step_size)
                if solver.step_size < STEP_COLLAPSE * max(recent):
                    singular = _singular_here(
                        model, float(solver.t), solver.y[:n], chart,
                        f"forward dynamics of '{model.name}' ({method}: the steps collapsed "
                        f"to {solver.step_size:.1e} s)")
                    if singular is not None:
                        raise singular
                    recent.clear()  # a regular collapse (a sharp force): the new normal
            if t[out.done] <= solver.t:
                dense = solver.dense_output()
                while out.done < k_max and t[out.done] <= solver.t:
                    tk = t[out.done]
                    record(*project_state(model, tk, *split(dense(tk)), projection_tol, chart,
                                          redundant))
            watch.tick(solver.t, stats["steps"])
            if solver.status == "finished" or out.done >= k_max:
                break
            q, qd = split(solver.y)
            drift, evaluated = _drift(model, solver.t, q, qd, chart)
            stats["max_drift"] = max(stats["max_drift"], drift)
            restart = drift > constraint_tol
            if restart:
                projected = None if redundant else _project_with_one_factorization(
                    model, solver.t, q, qd, projection_tol, chart, evaluated)
                q, qd = projected or project_state(model, solver.t, q, qd, projection_tol,
                                                   chart, redundant)
                stats["projections"] += 1
            # between steps only: every stage of a step is evaluated in one chart
            q, qd, chart, moved = model.body_type.reset_charts(q, qd, chart)
            if moved:
                stats["chart_resets"] += 1
            if restart or moved:
                h = min(solver.step_size or np.inf, t[-1] - solver.t)
                solver = solver_cls(rhs, solver.t, state(q, qd), t[-1], first_step=h,
                                    **options)

    watch = Watch(observers, progress, model, t, "forward dynamics", out.partial)
    return run_keeping_results(loop, out.partial, watch)
