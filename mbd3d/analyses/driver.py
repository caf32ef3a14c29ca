"""The one path of a time integration, from the request to the Results::

    forward_dynamics(model, times, ...)                    analyses/dynamics.py
      request = DynamicsRequest(...)                       the arguments, checked once
      integrator = INTEGRATORS[request.method](request)    analyses/explicit.py, implicit.py
      drive(request, integrator)                           this module
        1. the consistent initial state                    analyses/initial.py
        2. the step loop, until the last output time:
             segment = integrator.advance(next output)     compiled steps
             integrator.check(segment)                     collapses, stiffness
             events: zero crossings on the segment's dense output, located and acted on
               (the rigid contacts' touches among them: impacts, analyses/impacts.py)
             outputs inside the segment -> ResultsBuffer -> observers
             integrator.after_step(segment)                projections, chart resets
        3. the buffer -> Results                           io/store.py

An integrator (:class:`Integrator`) owns its method's state between steps; the driver owns the
order of the stages, the outputs, the events and the observers, so that a new integrator or a
new kind of event is written once and every method has it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence

import numpy as np
from scipy.optimize import brentq

from mbd3d.errors import ModelError
from mbd3d.io.observers import Observer, Watch
from mbd3d.io.results import Results
from mbd3d.io.store import ResultsBuffer, run_keeping_results
from mbd3d.analyses.impacts import RigidContacts
from mbd3d.analyses.initial import consistent_initial_state
from mbd3d.analyses.kinematics import check_times, project_state
from mbd3d.analyses.lift_off import warn_lift_off
from mbd3d.analyses.resting import HeldRows

__all__ = ["DynamicsRequest", "Event", "Integrator", "Segment", "drive"]


def _is_number(value) -> bool:
    """A real number (not a flag, a string or an array)."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
        value, (bool, np.bool_))


@dataclass(frozen=True)
class Event:
    """A zero crossing of a function of the state that forward dynamics locates and acts on.

    Parameters
    ----------
    name : str
        How the event is reported (``results.stats["events"]``).
    function : callable
        ``function(t, q, qd) -> float`` with ``t`` [s] and the model's coordinates and rates;
        continuous in the state. The event is where it changes sign, located on the
        integrator's dense output to the precision of the time. The function is sampled at
        a few points of every step, so a crossing and its return within a fraction of a step
        can go unseen. Spatial models: the positions in ``q`` are absolute, the Rodrigues
        parameters relative to the integrator's current charts (which move); write events on
        positions and rates.
    direction : {0, 1, -1}
        1: only crossings from negative to positive; -1: from positive to negative; 0: both.
    action : "record", "stop" or callable
        "record": note the time and go on; "stop": end the run at the event (the outputs
        before it are kept, ``status == "stopped"``); a callable ``action(t, q, qd) -> (q, qd)``
        gives the state to go on from (an impact map: new velocities), which is projected onto
        the constraints before the integrator restarts there.
    rate : callable, optional
        ``rate(t, q, qd) -> float``: the function's rate of change along the motion [its unit
        per s]. Given, a crossing and return between two samples is still found: where the
        rate changes sign between them, the function is evaluated at that turn too (a ball
        dropped through a ball within one long step: the gap between their surfaces goes
        below zero and back).
    tolerance : float
        [the function's unit] >= 0: after a crossing, the next counts only once the function
        has been further than ``tolerance`` from zero, so that a function that leaves zero
        slowly (a follower lifting off a cam, its gap growing with the cube of the time) and
        dithers about it by its rounding for a while counts one crossing, not a dozen. 0:
        every sign change counts.
    """

    name: str
    function: Callable[[float, np.ndarray, np.ndarray], float]
    direction: int = 0
    action: Any = "record"
    rate: Callable[[float, np.ndarray, np.ndarray], float] | None = None
    tolerance: float = 0.0

    def __post_init__(self):
        if not callable(self.function):
            raise ModelError(f"event '{self.name}': function must be callable as "
                             f"function(t, q, qd) -> float, got {self.function!r}")
        if self.direction not in (0, 1, -1):
            raise ModelError(f"event '{self.name}': direction must be 0, 1 or -1, got "
                             f"{self.direction!r}")
        if not (self.action in ("record", "stop") or callable(self.action)):
            raise ModelError(f"event '{self.name}': action must be 'record', 'stop' or a "
                             f"callable (t, q, qd) -> (q, qd), got {self.action!r}")
        if self.rate is not None and not callable(self.rate):
            raise ModelError(f"event '{self.name}': rate must be callable as "
                             f"rate(t, q, qd) -> float, got {self.rate!r}")
        if not (_is_number(self.tolerance) and 0.0 <= self.tolerance < np.inf):
            raise ModelError(f"event '{self.name}': tolerance must be a number >= 0, got "
                             f"{self.tolerance!r}")

    def value(self, t: float, q: np.ndarray, qd: np.ndarray, part: str = "function") -> float:
        """The event's function (``part="rate"``: its rate) at ``(t, q, qd)``, checked.

        Parameters
        ----------
        t : float
            Time [s].
        q, qd : (n,) ndarray
            The state.
        part : {"function", "rate"}
            Which of the event's functions.
        """
        g = (self.function if part == "function" else self.rate)(t, q, qd)
        if not (_is_number(g) and np.isfinite(g)):
            raise ModelError(f"event '{self.name}': {part}(t, q, qd) must return a finite "
                             f"number, returned {g!r} at t = {t:.6g} s")
        return float(g)

    def crosses(self, g_old: float, g_new: float, either: bool = False) -> bool:
        """A crossing in the event's direction (``either``: in either) between two values
        (from exactly zero, where the run restarted at this event, is none).

        Parameters
        ----------
        g_old, g_new : float
            The function's values at the start and the end of a step.
        either : bool
            Count a crossing in either direction.
        """
        up, down = g_old < 0.0 <= g_new, g_old > 0.0 >= g_new
        return (up and (either or self.direction >= 0)) or (down and (either or
                                                                     self.direction <= 0))


@dataclass(frozen=True)
class DynamicsRequest:
    """The arguments of :func:`mbd3d.forward_dynamics`, checked and normalised once (see there
    for their meaning and units)."""

    model: Any
    t: np.ndarray
    q0: Sequence[float] | None
    qd0: Sequence[float] | None
    method: str
    rtol: float
    atol: float
    constraint_tol: float
    max_step: float
    step: float | None
    rho_inf: float
    hold: Sequence[str | int] | None
    initial_rates: Mapping[str, float] | None
    initial_positions: Mapping[str, float] | None
    strict: bool
    observers: Sequence[Observer] | None
    progress: bool | None
    events: tuple[Event, ...] = ()

    def __post_init__(self):
        object.__setattr__(self, "t", check_times(self.t))
        if len(self.t) < 2:
            raise ModelError("forward_dynamics needs at least two output times (start and end)")
        for label in ("rtol", "atol", "constraint_tol"):
            value = getattr(self, label)
            if not (_is_number(value) and np.isfinite(value) and value > 0):
                raise ModelError(f"{label} must be positive and finite, got {value!r}")
        if not (_is_number(self.max_step) and self.max_step > 0):  # inf (no limit) is allowed
            raise ModelError(f"max_step must be a positive time [s] (or inf: no limit), got "
                             f"{self.max_step!r}")
        events = tuple(self.events or ())
        for event in events:
            if not isinstance(event, Event):
                raise ModelError(f"events must be mbd3d.Event objects, got {event!r}")
        object.__setattr__(self, "events", events)

    @property
    def projection_tol(self) -> float:
        """Tolerance of the projections of reported states, below ``constraint_tol``."""
        return self.constraint_tol * 1e-3

    @property
    def what(self) -> str:
        return f"forward dynamics of '{self.model.name}'"


@dataclass
class Segment:
    """What one call of :meth:`Integrator.advance` covered: the accepted steps from ``t_old``
    to ``t_new`` [s], the last of which has a dense output ``state_at(t) -> (q, qd)`` on
    ``[t_start, t_new]`` (the coordinates in the integrator's current charts)."""

    t_start: float
    t_new: float
    state_at: Callable[[float], tuple[np.ndarray, np.ndarray]]
    flags: int = 0
    info: dict = field(default_factory=dict)


class Integrator:
    """One integration method as the driver runs it; see the module doc for the order of the
    calls. ``stats`` is the run's statistics, which the integrator keeps up to date;
    ``redundant`` says whether the constraint rows depend on each other (set by
    :meth:`start`)."""

    stats: dict
    redundant: bool = False
    #: the rigid contacts held at rest (:class:`mbd3d.analyses.resting.HeldRows`), or None
    #: without rigid contacts: the method's accelerations take their forces, its steps
    #: project the held rows
    held: Any = None

    @property
    def holding(self) -> bool:
        """Whether any rigid contact row is held at rest now."""
        return self.held is not None and bool(self.held.any())

    def rows_dependent(self, q: np.ndarray) -> bool:
        """Whether the constraint rows depend on each other at the initial positions ``q``."""
        raise NotImplementedError

    def chart(self) -> np.ndarray | None:
        """A copy of the current reference rotations (spatial models), else None."""
        raise NotImplementedError

    def turns(self) -> np.ndarray | None:
        """A copy of the charts' sign-continuous quaternions (where tracked), else None."""
        raise NotImplementedError

    def session(self):
        """A context manager the whole run happens in (the compiled loop's callbacks)."""
        raise NotImplementedError

    def start(self, t0: float, q: np.ndarray, qd: np.ndarray, redundant: bool) -> tuple:
        """Set up at the consistent initial state; return its ``(qdd, lam)``."""
        raise NotImplementedError

    def advance(self, t_target: float, every_step: bool) -> Segment:
        """Take accepted steps towards ``t_target`` (one when ``every_step``)."""
        raise NotImplementedError

    def check(self, segment: Segment) -> None:
        """The method's own watch over a segment: raise on failure, warn (what it checks at
        every step, such as generalized-alpha's passages, it checks inside :meth:`advance`)."""

    def output(self, t: float, segment: Segment) -> tuple:
        """``(q, qd, qdd, lam)`` reported at output time ``t`` inside ``segment``."""
        raise NotImplementedError

    def after_step(self, segment: Segment) -> None:
        """Between segments: projections, chart resets."""

    def dissipated(self, t: float, segment: Segment | None) -> np.ndarray | None:
        """The energy [J] each contact row has dissipated from the start to ``t`` in
        ``segment`` (None: to the current time; :mod:`mbd3d.analyses.dissipation`), or None
        where the model has no contacts."""
        return None

    def restart(self, t: float, q: np.ndarray, qd: np.ndarray) -> None:
        """Go on from a new consistent state at ``t`` (after an event's action)."""
        raise NotImplementedError

    def close(self) -> None:
        """At the end of the run, however it ends."""


def initial_state(request: DynamicsRequest, integrator: Integrator, redundant_rows
                  ) -> tuple[np.ndarray, np.ndarray, bool]:
    """``(q, qd, redundant)`` at ``t[0]``: consistent with the constraints, the holds and the
    given joint positions and rates (:mod:`mbd3d.analyses.initial`)."""
    r = request
    return consistent_initial_state(
        r.model, r.t[0], r.q0, r.qd0, hold=r.hold, initial_rates=r.initial_rates,
        initial_positions=r.initial_positions, strict=r.strict, tol=r.constraint_tol,
        chart=integrator.chart(), stats=integrator.stats, what=r.what,
        redundant_rows=redundant_rows)


#: points of each segment's dense output at which the events' functions are sampled, so that
#: a function that crosses zero and back within one step (a ball's whole flight in one step of
#: an integrator that is exact on parabolas) is still seen
_SAMPLES = 8


class _Events:
    """The events of one run and their functions' values at the last segment's end (None
    right after a restart at that event: no crossing counts until the state has left it;
    except for the events from ``armed`` on, whose action leaves their function off zero:
    the impacts, :meth:`mbd3d.analyses.impacts.RigidContacts.act`)."""

    def __init__(self, events: tuple[Event, ...], stats: dict, armed: int | None = None):
        self.events, self.armed = events, len(events) if armed is None else armed
        self.found = stats.setdefault("events", []) if events else []
        self.g: list[float | None] = []
        #: per event, whether its function has been further than its tolerance from zero
        #: since its last crossing (see Event.tolerance)
        self.away = [True] * len(events)

    def start(self, t: float, q: np.ndarray, qd: np.ndarray) -> None:
        self.g = [event.value(t, q, qd) for event in self.events]

    def _counts(self, k: int, g_prev: float, g: float) -> bool:
        """Whether event ``k``'s sign change from ``g_prev`` to ``g`` counts (see
        Event.tolerance), and its function's distance from zero noted."""
        event = self.events[k]
        counts = event.crosses(g_prev, g) and (self.away[k] or event.tolerance == 0.0)
        if event.crosses(g_prev, g, either=True):
            self.away[k] = False
        self.away[k] = self.away[k] or abs(g) > event.tolerance
        return counts

    def locate(self, segment: Segment) -> tuple[float, Event] | None:
        """The first crossing that acts (stops or restarts the run) in the segment, as
        ``(time, event)``; the crossings of recording events before it are noted."""
        if not self.events:
            return None
        a, b = segment.t_start, segment.t_new
        times = [a + (b - a) * j / _SAMPLES for j in range(1, _SAMPLES)] + [b]
        states = [segment.state_at(t) for t in times]
        crossings, g_end = [], []
        start = segment.state_at(a)
        # every function at one state before the next: the rigid contacts' functions share
        # one solve per state (resting.py, impacts.py keep the last)
        table = [[event.value(t, *state) for event in self.events]
                 for t, state in zip(times, states)]
        rated = [[None if event.rate is None else event.value(t, *state, "rate")
                  for event in self.events] for t, state in zip([a] + times, [start] + states)]
        for k, event in enumerate(self.events):
            values = [row[k] for row in table]
            rates = None if event.rate is None else [row[k] for row in rated]
            t_prev, g_prev = a, self.g[k]
            for j, (t, g) in enumerate(zip(times, values)):
                t_cross = t
                if g_prev is not None and rates is not None and not event.crosses(g_prev, g):
                    t_cross = self._turn(event, segment, t_prev, t, rates[j], rates[j + 1])
                    g = g if t_cross is None else event.value(t_cross, *segment.state_at(
                        t_cross))
                if g_prev is not None and self._counts(k, g_prev, g):
                    crossings.append((self._root(event, segment, t_prev, t_cross), k))
                    if event.action != "record":
                        break  # it acts at its first crossing: nothing after it happens
                t_prev, g_prev = t, values[j]
            g_end.append(values[-1])
        self.g = g_end
        for te, k in sorted(crossings):
            event = self.events[k]
            if event.action != "record":
                return te, event
            self.found.append({"name": event.name, "time": te})
        return None

    @staticmethod
    def _turn(event: Event, segment: Segment, a: float, b: float, rate_a: float,
              rate_b: float) -> float | None:
        """Where the event's function turns between ``a`` and ``b`` [s] (its rate changes sign
        there), or None."""
        if not rate_a * rate_b < 0.0:
            return None
        return float(brentq(lambda t: event.value(t, *segment.state_at(t), "rate"), a, b,
                            xtol=4 * np.finfo(float).eps * max(abs(a), abs(b))))

    @staticmethod
    def _root(event: Event, segment: Segment, a: float, b: float) -> float:
        """Where the event's function changes sign between ``a`` and ``b`` [s] on the
        segment's dense output."""
        def g(t: float) -> float:
            return event.value(t, *segment.state_at(t))
        ga, gb = g(a), g(b)
        if ga == 0.0:
            return a
        if not ga * gb < 0.0:
            # the dense output ends at the crossing itself, or starts past it (the ends'
            # values changed sign across a projection between segments): at the end
            return b
        eps = np.finfo(float).eps
        return float(brentq(g, a, b, xtol=4 * eps * max(abs(a), abs(b)), rtol=4 * eps))

    def restarted(self, event: Event, t: float, q: np.ndarray, qd: np.ndarray) -> None:
        self.found.append({"name": event.name, "time": t})
        self.start(t, q, qd)
        index = self.events.index(event)
        if index < self.armed:
            self.g[index] = None  # no crossing counts from where it acted


def _new_state(event: Event, t: float, given: Any, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``(q, qd)`` an event's action returned, checked."""
    try:
        q, qd = (np.asarray(x, dtype=float).reshape(-1) for x in given)
    except (TypeError, ValueError):
        q = qd = np.empty(0)
    if not (q.shape == qd.shape == (n,) and np.all(np.isfinite(q)) and np.all(np.isfinite(qd))):
        raise ModelError(f"event '{event.name}' at t = {t:.9g} s: its action must return "
                         f"(q, qd), two arrays of {n} finite numbers, got {given!r}")
    return q, qd


def _impact_events(rigid: RigidContacts) -> tuple[Event, ...]:
    """An event per rigid contact row: its gap closing, acted on by the impact; and where the
    rows are held at rest, its force letting go, acted on by the release."""
    def gap(index: int) -> Callable:
        return lambda t, q, qd: rigid.gap(index, t, q, qd)

    def rate(index: int) -> Callable:
        return lambda t, q, qd: rigid.gap_rate(index, t, q, qd)

    def pressing(index: int) -> Callable:
        return lambda t, q, qd: rigid.holding.release_value(index, t, q, qd)

    def rubbing(index: int) -> Callable:
        return lambda t, q, qd: rigid.holding.friction_value(index, t, q, qd)
    if not len(rigid):
        return ()
    events = tuple(Event(name, gap(k), direction=-1, action=rigid.act, rate=rate(k))
                   for k, name in enumerate(rigid.names))
    if rigid.holding is not None:
        events += tuple(Event(f"{name} lets go", pressing(k), direction=-1,
                              action=rigid.holding.release)
                        for k, name in enumerate(rigid.names))
        events += tuple(Event(f"{name} slips or sticks", rubbing(k), direction=-1,
                              action=rigid.holding.switch_friction)
                        for k, name in enumerate(rigid.names) if rigid.mu[k] > 0.0)
    return events


def drive(request: DynamicsRequest, integrator: Integrator) -> Results:
    """Run ``integrator`` over ``request.t`` (see the module doc); the Results of the outputs,
    kept however the run ends (:func:`mbd3d.io.store.run_keeping_results`)."""
    t, model = request.t, request.model
    stats = integrator.stats
    out = ResultsBuffer(model, "forward dynamics", t, stats)
    rigid = RigidContacts(model, integrator.chart, lambda: integrator.redundant, stats)
    if len(rigid):
        rigid.holding = integrator.held = HeldRows(rigid, request.constraint_tol, stats)
    events = _Events(request.events + _impact_events(rigid), stats, len(request.events))

    def store(q, qd, qdd, lam, segment: Segment | None = None) -> None:
        tk = float(t[out.done])
        forces = friction = None  # of the rigid rows held at rest, every contact row's
        if rigid.holding is not None:
            r = len(rigid.group.names)
            forces, friction = np.zeros(r), np.zeros((r, 3))
            forces[rigid.rows], friction[rigid.rows] = rigid.holding.forces(tk, q, qd)
        out.store(q, qd, qdd, lam, integrator.chart(), integrator.turns(), forces,
                  integrator.dissipated(tk, segment), friction)

    def loop() -> tuple[str, str] | None:
        q, qd, redundant = initial_state(request, integrator, integrator.rows_dependent)
        if len(rigid):
            integrator.redundant = redundant  # the impacts' response needs it from the start
            q, qd = rigid.start(float(t[0]), q, qd)
        store(q, qd, *integrator.start(float(t[0]), q, qd, redundant))
        events.start(float(t[0]), q, qd)
        watch.tick(t[0], 0)
        while out.done < len(t):
            segment = integrator.advance(float(t[out.done]), bool(events.events))
            integrator.check(segment)
            hit = events.locate(segment)
            t_end = segment.t_new if hit is None else hit[0]
            while out.done < len(t) and t[out.done] <= t_end:
                store(*integrator.output(float(t[out.done]), segment), segment)
            watch.tick(t_end, stats["steps"])
            if hit is not None:
                ending = _act(hit, segment)
                if ending is not None:
                    return ending
                continue
            if out.done >= len(t):
                break
            integrator.after_step(segment)
        return None

    def _act(hit: tuple[float, Event], segment: Segment) -> tuple[str, str] | None:
        te, event = hit
        q, qd = segment.state_at(te)
        if event.action == "stop":
            events.found.append({"name": event.name, "time": te})
            return "stopped", f"stopped by event '{event.name}' at t = {te:.9g} s"
        # the action sees the state on the constraints, as the outputs do (generalized-alpha's
        # cubic interpolant leaves a driven joint's rate off by O(h^3) inside a step)
        q, qd = project_state(model, te, q, qd, request.projection_tol, integrator.chart(),
                              integrator.redundant)
        given = event.action(te, q.copy(), qd.copy())
        q, qd = _new_state(event, te, given, len(q))
        q, qd = project_state(model, te, q, qd, request.projection_tol, integrator.chart(),
                              integrator.redundant)
        integrator.restart(te, q, qd)
        events.restarted(event, te, q, qd)
        return None

    def run() -> tuple[str, str] | None:
        try:
            with integrator.session():
                return loop()
        finally:
            integrator.close()

    watch = Watch(request.observers, request.progress, model, t, "forward dynamics",
                  out.partial)
    results = run_keeping_results(run, out.partial, watch)
    warn_lift_off(results, "forward dynamics")
    return results
