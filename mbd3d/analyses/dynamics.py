"""Forward dynamics: the equations of motion integrated in time with constraint stabilisation.

:func:`forward_dynamics` checks the request once (:class:`~mbd3d.analyses.driver.DynamicsRequest`),
picks the integrator from :data:`INTEGRATORS` (the compiled explicit pairs of
:mod:`mbd3d.analyses.explicit`, generalized-alpha of :mod:`mbd3d.analyses.implicit`) and hands
both to the one driver of :mod:`mbd3d.analyses.driver`, which assembles the consistent initial
state, runs the step loop with its events and observers, and returns the Results.
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.io.observers import Observer
from mbd3d.io.results import Results
from mbd3d.numerics.compiled.runge_kutta import TABLEAUS
from mbd3d.analyses.accelerations import forward_accelerations
from mbd3d.analyses.driver import DynamicsRequest, Event, drive
from mbd3d.analyses.explicit import ExplicitRungeKutta
from mbd3d.analyses.implicit import GeneralizedAlphaIntegrator
from mbd3d.analyses.kinematics import project_state

__all__ = ["forward_accelerations", "forward_dynamics", "project_state", "METHODS",
           "GENERALIZED_ALPHA", "INTEGRATORS"]

#: the explicit integrators selectable by name (the compiled pairs of
#: :mod:`mbd3d.numerics.compiled.runge_kutta`); "RK45" is the Dormand-Prince 5(4) pair of MATLAB's ode45
METHODS = tuple(TABLEAUS)
#: the implicit index-3 integrator of :mod:`mbd3d.analyses.implicit`
GENERALIZED_ALPHA = "generalized-alpha"
#: every method by name: the integrator the driver runs
INTEGRATORS = {**{name: ExplicitRungeKutta for name in METHODS},
               GENERALIZED_ALPHA: GeneralizedAlphaIntegrator}
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


def forward_dynamics(model, times: Sequence[float], q0: Sequence[float] | None = None,
                     qd0: Sequence[float] | None = None, *, method: str = "RK45",
                     rtol: float = 1e-8, atol: float = 1e-10, constraint_tol: float = 1e-8,
                     max_step: float = np.inf, step: float | None = None,
                     rho_inf: float = 0.9, hold: Sequence[str | int] | None = None,
                     initial_rates: Mapping[str, float] | None = None,
                     initial_positions: Mapping[str, float] | None = None, strict: bool = False,
                     observers: Sequence[Observer] | None = None,
                     progress: bool | None = None,
                     events: Sequence[Event] | None = None) -> Results:
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
        "generalized-alpha" only, and required there: the fixed step [s] (kept between output
        times, whose states are interpolated; shortened to land on the last one, and at
        contacts and stops to end at each touch and resolve each impact with a hundred steps
        per period of the contact's oscillation while it lasts; see
        :mod:`mbd3d.analyses.contact_steps`). Its error is second order: halving the step
        quarters it.
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
        prismatic's displacement [m] as ``results.joint(name).angle`` and ``.displacement``
        read them (a spatial hinge's angle is measured between its bodies' reference
        directions, see :mod:`mbd3d.io.joint_coordinates`; a URDF or MJCF robot's hinges and
        slides read the file's joint coordinates), or ``"body.coordinate"``; the rest of the
        mechanism is assembled around them, nearest the guess (see
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
    events : sequence of Event, optional
        Zero crossings of functions of the state to locate (on the integrator's dense
        output, to the precision of the time) and act on: record, stop the run, or go on
        from a new state (an impact); see :class:`mbd3d.Event`. Their times are in
        ``results.stats["events"]``.

    Returns
    -------
    Results
        With ``lam`` (reactions, driver efforts) at every output time; ``stats`` holds
        ``steps`` (accepted), ``rejected_steps`` (tried and shortened: by the error control,
        at a contact's switch, or because a stage could not be evaluated),
        ``rhs_evaluations``, ``projections``, ``chart_resets`` (spatial bodies
        re-referenced), ``max_drift`` (largest residual found at a step end before projection)
        and ``wall_time`` [s]; the explicit methods' also ``initial_step`` [s] (the first
        step tried, by the rule of Hairer, Norsett and Wanner that SciPy's solve_ivp uses);
        generalized-alpha's also its Newton iterations and factorizations and
        ``smallest_step`` [s] (the shortest step taken: shortened at contacts, after failed
        Newton iterations, or to land on the run's end, which it reaches by two even steps
        rather than by a sliver of less than a twentieth of a step). With rigid contacts
        (:class:`mbd3d.RigidImpact`, resolved by :mod:`mbd3d.analyses.impacts`),
        ``impacts``: one dict per contact row and impact, its ``time`` [s], ``contact``,
        ``impulse`` [N s; a turning stop's N m s], ``friction_impulse`` (the friction's on
        the second shape, global axes [N s]), ``rate_before`` and ``rate_after`` (the
        gap's, [m/s or rad/s]), ``energy_lost`` [J] and ``point`` (global [m]: midway
        between the shapes; a stop's, its joint's point on body j); and, for the rigid
        contacts held at rest (:mod:`mbd3d.analyses.resting`), ``rests``: one dict per rest
        or release, its ``time`` [s], ``event`` ("rest" or "release"), ``contacts`` (names)
        and ``energy_lost`` [J] (the bounces no longer made). ``status`` is "stopped" when
        an event stopped the run (the message names it).

    Raises
    ------
    IntegrationError, SingularJacobianError, AssemblyError
        With ``.results`` holding the output times computed before the failure. An interrupt
        (Ctrl-C) returns the results so far with ``status == "interrupted"``.
    """
    if method in _REFUSED:
        raise ModelError(_REFUSED[method])
    if method not in INTEGRATORS:
        raise ModelError(f"method must be one of {', '.join(INTEGRATORS)}; got {method!r}")
    request = DynamicsRequest(model, times, q0, qd0, method, rtol, atol, constraint_tol,
                              max_step, step, rho_inf, hold, initial_rates, initial_positions,
                              strict, observers, progress, events)
    return drive(request, INTEGRATORS[method](request))
