"""Forward sensitivities of forward dynamics: how a motion changes with the model's parameters,
integrated with the motion by the same compiled Runge-Kutta steps.

``mb.forward_sensitivities(model, t, parameters, integrals=...)`` runs forward dynamics through
the one driver (:mod:`mbd3d.analyses.driver`) with :class:`SensitiveRungeKutta`, which after
every accepted step of the state takes the same step of the sensitivities (the formula sheet's
1.1 and 1.2; SUNDIALS calls this the *staggered direct* method):

- the sensitivities ``S = dy/dp`` of the integrated state ``y = (q, v)`` go through the step's
  own stages with the method's own weights, each stage's derivative being the change of the
  right-hand side ``f(t, y)`` along the parameter with the stage state moving by its
  sensitivity, ``d/dh f_{p+h}(t, Y + h S)``: the change of the compiled right-hand side
  and of the equations' residual of the model's variants with the stage's accelerations and
  multipliers held (:class:`mbd3d.model.tangents.ModelTangent`, a fourth-order difference,
  about 1e-12 of its size), then the accelerations' change from one solve with the stage's
  augmented matrix, factored once for all parameters (sheet 1.1). All stages of all
  parameters are one compiled call per step
  (:func:`~mbd3d.numerics.compiled.sensitivity_steps.sensitivity_stages_into`), which asks
  for the variants at a shorter step where a sensitivity is large and they are not made yet.
  With the step sizes the state's error control chose (not differentiated, so the
  sensitivities stay out of the error norm), the result is the derivative of the computed
  solution itself, to that precision;
- the integrals ``G = int g(t, q, qd) dt`` the user names are carried along as states of
  their own, with their sensitivities ``int (g_q s + g_qd s' + g_p) dt``: ``g`` is a Python
  function, evaluated here at the stages the compiled call kept (the integrals do not feed
  back into the motion, so they follow it);
- the dense output of the sensitivities is the method's own interpolant of their stages, so
  output times need no extra steps (DOP853's three extra stages are computed only in steps
  with an output time); at an output, the accelerations' and multipliers' sensitivities are
  the stages' tangent at that state;
- where the state is projected onto the constraints (after a drifting step, at every output)
  its sensitivities are projected as the projection's derivative (sheet 1.4), to first order
  in the projection's correction: the neglected change of the projection's direction is of
  the size of the drift a step leaves (below about ``rtol`` of the state), so the
  sensitivities are those of the computed solution to about that, not to rounding (a run of
  fixed 25 ms steps drifting 1e-4 is followed to 8e-6, see the tests); where a spatial
  body's chart is reset, its Rodrigues parameters' sensitivities are mapped by the reset's
  Jacobian ``(I - g*~) / (1 + g*.g*)`` (sheet 1.5);
- the start is consistent: ``Cq s0 = -C_p`` and its velocity rows, with the least mass-weighted
  change and the held coordinates held (sheet 1.3), as the initial state is assembled.

Not covered (refused by name): generalized-alpha, events and rigid contacts (sensitivities jump
at an impact), joint friction, redundant constraints, force elements and motions given as
Python functions, rolling rows.
"""

from __future__ import annotations

from typing import Callable, Mapping, Sequence

import numpy as np
import scipy.linalg
from numba.typed import List

from mbd3d.errors import IntegrationError, ModelError
from mbd3d.io.observers import Observer
from mbd3d.io.parameters import parameter_tangent
from mbd3d.io.sensitivity_results import Sensitivities
from mbd3d.model import constraints
from mbd3d.model.contacts import contact_group
from mbd3d.model.equations import mass_matrix
from mbd3d.model.tangents import OFFSETS, ModelTangent, reach, slope, state_scale
from mbd3d.numerics.compiled.runge_kutta import (DOP853_INTERPOLANT, TABLEAUS,
                                                 dop853_coefficients, interpolate,
                                                 polynomial_coefficients, stage_state)
from mbd3d.numerics.compiled.sensitivity_steps import (LEVELS, REFINE,
                                                       accelerations_tangent_into,
                                                       rows_tangent_into,
                                                       sensitivity_stages_into)
from mbd3d.numerics.compiled.structures import workspace
from mbd3d.numerics.linalg import factor_model_augmented
from mbd3d.analyses.driver import DynamicsRequest, Segment, drive
from mbd3d.analyses.explicit import FAILURES, ExplicitRungeKutta
from mbd3d.analyses.position import hold_indices

__all__ = ["forward_sensitivities", "SensitiveRungeKutta"]

#: ``g(model, t, q, qd) -> float``: an integrand, evaluated with the model's variants too
Integrand = Callable[[object, float, np.ndarray, np.ndarray], float]


def forward_sensitivities(model, times: Sequence[float], parameters: Sequence[str] | str,
                          q0: Sequence[float] | None = None, qd0: Sequence[float] | None = None,
                          *, integrals: Mapping[str, Integrand] | None = None,
                          method: str = "DOP853", rtol: float = 1e-8, atol: float = 1e-10,
                          constraint_tol: float = 1e-8, max_step: float = np.inf,
                          hold: Sequence[str | int] | None = None, strict: bool = False,
                          observers: Sequence[Observer] | None = None,
                          progress: bool | None = None) -> Sensitivities:
    """Forward dynamics and the derivatives of its motion with respect to ``parameters``.

    Parameters
    ----------
    model : Model
    times : (k,) array_like
        Output times [s], strictly increasing.
    parameters : str or sequence of str
        Parameter names, as :func:`mbd3d.parameters` lists them.
    q0, qd0, method, rtol, atol, constraint_tol, max_step, hold, strict, observers, progress
        As :func:`mbd3d.forward_dynamics` takes them; ``method`` one of its explicit pairs
        ("DOP853", "RK45", "RK23"). The steps are those the state's error control chooses;
        the sensitivities follow them, so tighten ``rtol`` for more digits of both.
    integrals : mapping of str to callable, optional
        Integrals to carry along, each ``g(model, t, q, qd) -> float`` (e.g. ``lambda m, t,
        q, qd: mb.kinetic_energy(m, q, qd)``): ``G(t) = int_{t0}^{t} g dt`` and its
        sensitivities (``sens.integral(name)``, ``sens.integral(name, parameter)``). ``g`` is
        called with the model's variants too, so that what it reads from the model (a mass)
        is differentiated. Spatial models: ``q``'s Rodrigues parameters are relative to the
        integrator's current charts (as an Event's are): integrate what does not depend on
        them (energies, positions, rates).

    Returns
    -------
    Sensitivities
        ``sens.results`` the forward dynamics' Results; ``sens.sensitivity("slider.x",
        name)`` (``of="qd"``, ``"qdd"``), ``sens.effort``, ``sens.derivative(f)`` as for the
        other analyses (:func:`mbd3d.sensitivities`); ``sens.integral(name, parameter)``.
        ``sens.results.stats["sensitivity_evaluations"]`` counts the stages' right-hand
        sides and the model variants' residuals the sensitivities evaluated.

    Raises
    ------
    ModelError
        A parameter that is not one (with the nearest names) or that alone makes the model
        invalid; what is not covered (see the module doc).
    IntegrationError, SingularJacobianError
        As forward dynamics raises them; ``.results`` holds the outputs computed.
    """
    if isinstance(parameters, str):
        parameters = [parameters]
    if method not in TABLEAUS:
        raise ModelError(f"forward sensitivities integrate with the explicit pairs "
                         f"{', '.join(TABLEAUS)}; got method={method!r} (generalized-alpha's "
                         "are not available yet)")
    request = DynamicsRequest(model, times, q0, qd0, method, rtol, atol, constraint_tol,
                              max_step, None, 0.9, hold, None, None, strict, observers,
                              progress)
    what = f"forward sensitivities of '{model.name}'"
    tangents = [parameter_tangent(model, name, what) for name in parameters]
    integrator = SensitiveRungeKutta(request, tangents, dict(integrals or {}))
    results = drive(request, integrator)
    return integrator.sensitivities(results, parameters)


class SensitiveRungeKutta(ExplicitRungeKutta):
    """A compiled explicit pair with the forward sensitivities of its steps (see the module
    doc): the state is stepped by :class:`ExplicitRungeKutta`, one step per call, and the
    sensitivities and integrals, ``z``, follow each accepted step.

    ``z`` holds the integrals ``G`` (m), then per parameter ``S`` (2 n, the sensitivities of
    ``y = (q, v)``) and ``dG/dp`` (m).
    """

    def __init__(self, request: DynamicsRequest, tangents: Sequence[ModelTangent],
                 integrals: Mapping[str, Integrand]):
        super().__init__(request)
        model = self.model
        _refuse(model, request)
        self.tangents, self.integrands = tuple(tangents), dict(integrals)
        for name, g in self.integrands.items():
            if not callable(g):
                raise ModelError(f"forward sensitivities of '{model.name}': integral "
                                 f"'{name}' must be callable as g(model, t, q, qd) -> float")
        self.m, self.n2 = len(self.integrands), 2 * self.n
        self.width = self.n2 + self.m
        self.sets = _VariantSets(model, self.tangents, self.spatial)
        self.z = self.z_old = self.z_dense = self._k0 = self._pending = None
        self.outputs: list[tuple] = []  # per output: (dq, dqd, dqdd, dlam, G, dG)
        self.stats["sensitivity_evaluations"] = 0

    # -- the run ------------------------------------------------------------------------------
    def start(self, t0: float, q: np.ndarray, qd: np.ndarray, redundant: bool) -> tuple:
        if redundant:
            raise ModelError(f"forward sensitivities of '{self.model.name}': its constraint "
                             "rows depend on each other (redundant constraints), whose "
                             "multipliers are not the model's own: not covered")
        first = super().start(t0, q, qd, redundant)
        held = hold_indices(self.model, self.request.hold)
        z = np.zeros(self.m + len(self.tangents) * self.width)
        zero = np.zeros(self.n)
        pairs = self._projected(t0, q, qd, [(zero, zero)] * len(self.tangents), held)
        for j, (s, sd) in enumerate(pairs):
            z[self._s(j)] = self._state_tangent(q, qd, s, sd)
        self.z = z
        self._record(t0, q, qd, *first, pairs, z)
        return first

    def advance(self, t_target: float, every_step: bool) -> Segment:
        y_start = self.y.copy()
        charts = self.chart()
        segment = super().advance(t_target, True)  # one step: the sensitivities follow it
        if segment.flags in FAILURES:
            return segment
        if self.spatial:
            moved = np.any(self.charts != charts, axis=(1, 2))
            if moved.any():
                self._reset_charts(y_start, moved)
        self._step(segment)
        return segment

    def after_step(self, segment: Segment) -> None:
        projections = self.stats["projections"]
        y = self.y.copy()
        super().after_step(segment)
        if self.stats["projections"] != projections:  # the state was projected
            q, qd = self._split(self.y)
            q_from, qd_from = self._split(y)
            pairs = self._projected(self.t_now, q, qd, [
                self._rate_tangent(q_from, qd_from, self.z[self._s(j)])
                for j in range(len(self.tangents))])
            for j, (s, sd) in enumerate(pairs):
                self.z[self._s(j)] = self._state_tangent(q, qd, s, sd)
            self._k0 = None

    def output(self, t: float, segment: Segment) -> tuple:
        q, qd, qdd, lam = super().output(t, segment)
        t_old, step = segment.t_start, segment.info["step"]
        kind = self.tableau.dense_kind
        z = interpolate(kind, self._dense(), self.z_old, t_old, step, t)
        q_from, qd_from = segment.state_at(t)  # before the output's projection
        pairs = self._projected(t, q, qd, [self._rate_tangent(q_from, qd_from, z[self._s(j)])
                                           for j in range(len(self.tangents))])
        self._record(t, q, qd, qdd, lam, pairs, z)
        return q, qd, qdd, lam

    def restart(self, t: float, q: np.ndarray, qd: np.ndarray) -> None:
        super().restart(t, q, qd)
        self._k0 = None  # the first stage is evaluated again

    # -- the sensitivities' step ------------------------------------------------------------
    def _s(self, j: int) -> slice:
        """Where parameter ``j``'s sensitivities of ``y`` are in ``z``."""
        start = self.m + j * self.width
        return slice(start, start + self.n2)

    def _g(self, j: int) -> slice:
        """Where parameter ``j``'s sensitivities of the integrals are in ``z``."""
        start = self.m + j * self.width + self.n2
        return slice(start, start + self.m)

    def _step(self, segment: Segment) -> None:
        """``z`` through the step just accepted, with its stages: the sensitivities' stages in
        one compiled call (:func:`sensitivity_stages_into`), then the integrals' stages here.
        The dense output's extra stages (DOP853's three of sixteen) are left to the first
        output time in the step (:meth:`_dense`): most steps have none."""
        tab, step, t_old = self.tableau, segment.info["step"], segment.t_start
        W, C = self.sets.weights(tab)
        stages, first = len(tab.B), self._k0 is None
        L = np.zeros((tab.n_stored, self.z.size))
        if not first:
            L[0] = self._k0
        stage_y, stage_z = np.empty((len(W) + 1, self.n2)), np.empty((len(W) + 1, self.z.size))
        pending = (t_old, step, L, stage_y, stage_z)
        self._stages(pending, W[:stages], C[:stages], 0 if first else 1, first)
        if self.m:
            z_new = stage_state(self.z, L, W[stages - 1], stages, step, np.empty(self.z.size))
        else:
            z_new = stage_z[stages].copy()
        # the dense output is made of the step's own z_new, before any projection of z
        self._pending, self.z_dense = pending + (z_new.copy(),), None
        self.z_old, self.z, self._k0 = self.z, z_new, L[stages].copy()

    def _stages(self, pending: tuple, W: np.ndarray, C: np.ndarray, start: int,
                first: bool) -> None:
        """The stages ``start`` on (0: the first too) of the pending step into its ``L``
        (asking for finer variants as the compiled call needs them), then the integrals'."""
        t_old, step, L, stage_y, stage_z = pending[:5]
        counts = np.zeros(1, dtype=np.int64)
        status = -1
        while status < 0:  # until the finer variants the stages need are all made
            status = sensitivity_stages_into(
                *self.sets.own, self.key, self.sets.variants, self.sets.works, self.sets.steps,
                self.sets.have, self.sets.refine, self.model.coordinate_scale, self.m,
                self.width, W, C, t_old, step, self.y_old, self.K,
                self.z if start <= 1 else self.z_old, L, self.charts, first, max(start, 1),
                stage_y, stage_z, counts)
            if status < 0:
                self.sets.make(-status - 1)
        self.stats["sensitivity_evaluations"] += int(counts[0])
        if status != 0:
            raise IntegrationError(
                f"forward sensitivities of '{self.model.name}': the model or one of its "
                f"variants (a parameter moved) could not be evaluated in the step from t = "
                f"{t_old:.6g} s beside the motion (a singular or non-finite state)", time=t_old)
        for i in range(start, len(W) + 1) if self.m else ():
            t = t_old + (C[i - 1] if i else 0.0) * step
            self._integral_rates(t, stage_y[i], stage_z[i], L[i])

    def _dense(self) -> np.ndarray:
        """The dense output's coefficients of ``z`` in the step just taken, its extra stages
        computed when first needed."""
        if self.z_dense is None:
            tab = self.tableau
            t_old, step, L, _, _, z_new = self._pending
            stages = len(tab.B)
            if tab.dense_kind == DOP853_INTERPOLANT:
                W, C = self.sets.weights(tab)
                self._stages(self._pending, W, C, stages + 1, False)
                self.z_dense = dop853_coefficients(L, tab.D, self.z_old, z_new, L[0],
                                                   L[stages], step)
            else:
                self.z_dense = polynomial_coefficients(L, tab.P, stages + 1)
        return self.z_dense

    def _integral_rates(self, t: float, y: np.ndarray, z: np.ndarray, out: np.ndarray) -> None:
        """The integrals' part of ``dz/dt`` at the stage ``(t, y)``, ``z`` the stage's
        sensitivities: the integrands, and per parameter their change along it."""
        out[:self.m] = self._integrals(self.model, t, *self._split(y))
        scale = state_scale(self.model, y[self.n:])
        for j, tangent in enumerate(self.tangents):
            S = z[self._s(j)]
            out[self._g(j)] = tangent.along(
                lambda model, h: self._integrals(model, t, *self._split(y + h * S)),
                reach(scale, S), make_finer=False)

    def _integrals(self, model, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        out = np.empty(self.m)
        for k, (name, g) in enumerate(self.integrands.items()):
            value = g(model, t, q, qd)
            try:
                out[k] = value if np.ndim(value) == 0 else np.nan
            except (TypeError, ValueError):
                out[k] = np.nan
            if not np.isfinite(out[k]):
                raise ModelError(f"integral '{name}': g(model, t, q, qd) must return a finite "
                                 f"number, returned {value!r} at t = {t:.6g} s")
        return out

    def _reset_charts(self, y_start: np.ndarray, moved: np.ndarray) -> None:
        """Map the Rodrigues parameters' sensitivities through the chart reset at the start
        of the step just taken (sheet 1.5; the body-axis velocities are unchanged)."""
        bodies = np.flatnonzero(moved)
        g = y_start[:self.n].reshape(-1, 6)[bodies, 3:]
        # J s = (s - g x s) / (1 + g.g), every moved body at once
        for j in range(len(self.tangents)):
            S = self.z[self._s(j)][:self.n].reshape(-1, 6)  # a view into z
            s = S[bodies, 3:]
            S[bodies, 3:] = (s - np.cross(g, s)) / (1.0 + np.sum(g * g, axis=1))[:, None]
        self._k0 = None

    # -- coordinates: the sensitivities of y = (q, v) and of (q, qd) ------------------------
    def _rate_tangent(self, q: np.ndarray, qd: np.ndarray, S: np.ndarray) -> tuple:
        """``(s, s')``, the sensitivities of ``(q, qd)``, from ``S`` of ``y = (q, v)``:
        ``qd = rates(q, v)`` is a polynomial of degree three along any line, which the
        fourth-order difference (exact to degree four) differentiates exactly."""
        body = self.model.body_type
        v = body.velocities(q, qd)
        s, sv = S[:self.n], S[self.n:]
        h = 1.0 / max(1.0, float(np.max(np.abs(S), initial=0.0)))
        return s, slope([body.rates(q + o * h * s, v + o * h * sv) for o in OFFSETS], h)

    def _state_tangent(self, q: np.ndarray, qd: np.ndarray, s: np.ndarray, sd: np.ndarray
                       ) -> np.ndarray:
        """``S`` of ``y = (q, v)`` from ``(s, s')``: ``v = velocities(q, qd)`` is linear in
        ``qd``, so ``S_v = velocities(q, s' - d(rates)/dq s)`` at ``v`` held."""
        body = self.model.body_type
        v = body.velocities(q, qd)
        h = 1.0 / max(1.0, float(np.max(np.abs(s), initial=0.0)))
        along = slope([body.rates(q + o * h * s, v) for o in OFFSETS], h)
        return np.concatenate([s, body.velocities(q, sd - along)])

    # -- results --------------------------------------------------------------------------------
    def _record(self, t: float, q, qd, qdd, lam, pairs: list, z: np.ndarray) -> None:
        """The sensitivities at an output time: of ``(q, qd)`` each parameter's ``(s, s')``
        of ``pairs``, of ``(qdd, lam)`` their change along it at that state (as the stages
        take it, one compiled call for all parameters), of the integrals from ``z``."""
        p = len(self.tangents)
        out = [np.zeros((self.n, p)), np.zeros((self.n, p)), np.zeros((self.n, p)),
               np.zeros((len(lam), p)), z[:self.m].copy(), np.zeros((self.m, p))]
        if p:
            y = np.concatenate([q, self.model.body_type.velocities(q, qd)])
            Z = np.array([self._state_tangent(q, qd, s, sd) for s, sd in pairs])
            change = self._along(accelerations_tangent_into, t, y, Z, self.n + len(lam))
            out[2][:], out[3][:] = change[:, :self.n].T, change[:, self.n:].T
        for j, (s, sd) in enumerate(pairs):
            out[0][:, j], out[1][:, j] = s, sd
            out[5][:, j] = z[self._g(j)]
        self.outputs.append(tuple(out))

    def _along(self, kernel, t: float, y: np.ndarray, Z: np.ndarray, size: int) -> np.ndarray:
        """``(p, size)``: what the compiled ``kernel`` (:func:`accelerations_tangent_into`,
        :func:`rows_tangent_into`) gives at ``(t, y)`` along each parameter with the state
        moving by its row of ``Z``, the finer variants it asks for made."""
        sets, counts = self.sets, np.zeros(1, dtype=np.int64)
        out = np.empty((len(Z), size))
        status = -1
        while status < 0:  # until the finer variants it needs are all made
            status = kernel(*sets.own, self.key, sets.variants, sets.works, sets.steps,
                            sets.have, sets.refine, self.model.coordinate_scale, t, y,
                            np.asarray(Z, dtype=float), self.charts, counts, out)
            if status < 0:
                sets.make(-status - 1)
        self.stats["sensitivity_evaluations"] += int(counts[0])
        if status != 0:
            raise IntegrationError(
                f"forward sensitivities of '{self.model.name}': the model or one of its "
                f"variants (a parameter moved) could not be evaluated at t = {t:.6g} s (a "
                "singular or non-finite state)", time=t)
        return out

    def _projected(self, t: float, q: np.ndarray, qd: np.ndarray, pairs: Sequence[tuple],
                   held: np.ndarray | None = None) -> list[tuple]:
        """Each parameter's ``(s, s')`` of ``pairs`` projected as the mass-weighted
        projection of ``(q, qd)`` onto the constraints moves them (sheet 1.4): ``[M Cq^T; Cq
        0] [ds; mu] = [0; -dC]``, ``dC`` the change of the position rows along the parameter
        with ``q`` moving by ``s``, then the same for ``s'`` with the change of the velocity
        rows ``Cq qd + C_t`` (``s`` corrected); both changes compiled
        (:func:`rows_tangent_into`), one factorization for all parameters. ``held``
        coordinates (indices) are kept (their rows ``ds_i = 0`` beside the constraints', as
        the initial state holds them)."""
        model = self.model
        if not pairs or not model.n_constraints:
            return list(pairs)
        fr = constraints.frames(model, q, qd, self.chart())
        correction = _least_change(model, fr, constraints.evaluate(model, t, fr, False,
                                                                   True)[1], held)
        m, y = model.n_constraints, np.concatenate([q, model.body_type.velocities(q, qd)])
        change = self._along(rows_tangent_into, t, y,
                             [self._state_tangent(q, qd, s, sd) for s, sd in pairs], 2 * m)
        moved = [s + correction(c[:m]) for (s, _), c in zip(pairs, change)]
        change = self._along(rows_tangent_into, t, y,
                             [self._state_tangent(q, qd, s, sd)
                              for s, (_, sd) in zip(moved, pairs)], 2 * m)
        return [(s, sd + correction(c[m:])) for s, (_, sd), c in zip(moved, pairs, change)]

    def sensitivities(self, results, parameters: Sequence[str]) -> Sensitivities:
        """The :class:`Sensitivities` of ``results`` (the outputs this run computed)."""
        k = len(results.t)
        dq, dqd, dqdd, dlam, G, dG = (np.array([o[i] for o in self.outputs[:k]])
                                      for i in range(6))
        integrals = {name: (G[:, i], dG[:, i, :]) for i, name in enumerate(self.integrands)}
        return Sensitivities(results, parameters, self.tangents, dq, dqd, dqdd, dlam,
                             integrals=integrals)


class _VariantSets:
    """The compiled right-hand sides the sensitivities' stages evaluate: the model's own (with
    two workspaces of its own, one keeping each stage's matrix while the other evaluates; the
    run's holds its contacts' power) and, per parameter, its
    variants, four per level (level ``l`` at a step ``2**-(REFINE l)`` of the first), in the
    typed lists :func:`sensitivity_stages_into` takes; level 0 made with the tangent, finer
    ones as the stages ask for them (:meth:`make`)."""

    def __init__(self, model, tangents: Sequence[ModelTangent], spatial: bool):
        self.spatial, self.tangents = spatial, tuple(tangents)
        self.own = self._compiled(model)
        p = len(self.tangents)
        self.steps = np.ones((p, LEVELS))
        self.have = np.zeros((p, LEVELS), dtype=bool)
        self.refine = np.array([tangent.can_refine for tangent in self.tangents], dtype=bool)
        self.variants, self.works = List(), List()
        for _ in range(p * LEVELS * 4):  # placeholders: levels not made are never read
            self.variants.append(self.own[0])
            self.works.append(self.own[1])
        for j, tangent in enumerate(self.tangents):
            self._install(j, 0, [v._core.arrays() for v in tangent.variants], tangent.step)
        self._weights = None

    def _compiled(self, model) -> tuple:
        arrays = model._core.arrays()
        return arrays, workspace(self.spatial, arrays), workspace(self.spatial, arrays)

    def _install(self, j: int, level: int, arrays: Sequence, step: float) -> None:
        for o, record in enumerate(arrays):
            self.variants[(j * LEVELS + level) * 4 + o] = record
            self.works[(j * LEVELS + level) * 4 + o] = workspace(self.spatial, record)
        self.steps[j, level], self.have[j, level] = step, True

    def make(self, code: int) -> None:
        """Make the variants the stages asked for, ``code = j LEVELS + level``: interpolated
        where the parameter enters the compiled arrays affinely, else built
        (:meth:`~mbd3d.model.tangents.ModelTangent.finer_arrays`)."""
        j, level = divmod(code, LEVELS)
        self._install(j, level, *self.tangents[j].finer_arrays(REFINE * level))

    def weights(self, tab) -> tuple[np.ndarray, np.ndarray]:
        """``(W, C)``: each stage's weights after the first (padded to the stored stages) and
        its time in steps, in the compiled step's order: the method's stages, the solution's
        (``B``, at the step's end) and the dense output's extra stages."""
        if self._weights is None:
            rows = ([(tab.A[i], tab.C[i]) for i in range(1, len(tab.B))] + [(tab.B, 1.0)]
                    + list(zip(tab.A_extra, tab.C_extra)))
            W = np.zeros((len(rows), tab.n_stored))
            for r, (a, _) in enumerate(rows):
                W[r, :len(a)] = a
            self._weights = W, np.array([c for _, c in rows], dtype=float)
        return self._weights


def _refuse(model, request: DynamicsRequest) -> None:
    """What forward sensitivities do not cover, named (see the module doc)."""
    what = f"forward sensitivities of '{model.name}'"
    reasons = []
    if model._core.python_parts:
        reasons.append("force elements or motions given as Python functions, or joint "
                       "friction (evaluated in Python, not through the model's variants)")
    if len(model.velocity_rows):
        reasons.append("rolling rows (velocity-only constraints)")
    group = contact_group(model, required=False)
    if group is not None and np.any(group.rigid):
        reasons.append("rigid contacts (the sensitivities jump at an impact)")
    if reasons:
        raise ModelError(f"{what}: not covered for {'; '.join(reasons)}")


def _least_change(model, fr, data: np.ndarray, held: np.ndarray | None):
    """``dx(r)``: the least mass-weighted change with ``Cq dx = -r`` (``held`` coordinates
    kept), from the model's own factorization of ``[M Cq^T; Cq 0]`` (dense with ``held``)."""
    n = model.n_coordinates
    blocks = model.body_type.mass_blocks(fr, model.mass, model.inertia)
    if held is None or not len(held):
        factors = factor_model_augmented(model, blocks, data)
        return lambda r: factors.solve(np.concatenate([np.zeros(n), -r]))[:n]
    rows = np.vstack([constraints.jacobian_matrix(model, data, sparse=False), np.eye(n)[held]])
    K = np.block([[mass_matrix(model, fr, sparse=False), rows.T],
                  [rows, np.zeros((len(rows), len(rows)))]])
    lu = scipy.linalg.lu_factor(K, check_finite=False)
    return lambda r: scipy.linalg.lu_solve(lu, np.concatenate(
        [np.zeros(n), -r, np.zeros(len(held))]), check_finite=False)[:n]
