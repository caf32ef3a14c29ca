"""Sensitivities: how an analysis' results change with the model's parameters, named as
:func:`mbd3d.parameters` names them (``joints.B.point_i[0]``, ``bodies.rod.mass``,
``joints.motor.motion.rate``), at every output time.

``mb.sensitivities(res, parameters)`` differentiates the results ``res`` of a kinematic
analysis or of inverse dynamics (the formula sheet's 3.1, 3.2 and 4.1), with the Jacobian of
each time point:

- positions: ``Cq s = -C_p`` (``s = dq/dp``), ``C_p`` from the compiled rows
  (:class:`mbd3d.model.tangents.ModelTangent`);
- velocities and accelerations: ``Cq s' = -d(Cq qd + C_t)`` and ``Cq s'' = -d(Cq qdd -
  gamma)``, the change of the rows along the parameter with the state moving by its
  sensitivity;
- inverse dynamics: ``Cq^T mu = -d(M qdd + Cq^T lam - Q)`` with ``lam`` held (``mu =
  dlam/dp``; a driver's effort changes by ``-mu``); with joint friction ``Q`` includes the
  frictions of the reactions held, which follow the reactions: ``Cq^T`` gains their
  derivative in ``lam``;

and those of a static equilibrium (2.2) with its Newton matrix, ``[K Cq^T; Cq 0] [s; mu] =
-[d(Cq^T lam - Qe); C_p]``; vibration modes' frequencies and damping ratios (5.1, 5.2) are
those of the modes about the equilibrium moved along the parameter. Each ``d(...)`` is the
change along the parameter (:meth:`mbd3d.model.tangents.ModelTangent.along`).

A parameter the results do not depend on (a mass in kinematics) has zero sensitivities; any
quantity read from the results (a point's path, a reaction) has its own through
:meth:`Sensitivities.derivative`.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import scipy.linalg

from mbd3d.analyses.modes import Modes, ModesAlong, modes_about
from mbd3d.analyses.position import singular_error
from mbd3d.analyses.statics import accurate_stiffness, active_rows, equilibrium_residual
from mbd3d.errors import ModelError
from mbd3d.io.parameters import parameter_tangent
from mbd3d.io.results import Results
from mbd3d.io.sensitivity_results import ModeSensitivities, Sensitivities
from mbd3d.model import constraints
from mbd3d.model.equations import generalized_forces, mass_matrix
from mbd3d.model.tangents import reach, state_scale

__all__ = ["sensitivities"]

_ANALYSES = ("kinematic analysis", "inverse dynamics", "static equilibrium")


def sensitivities(results: Results | Modes | ModesAlong, parameters: Sequence[str]
                  ) -> Sensitivities | ModeSensitivities:
    """The derivatives of ``results`` with respect to each of ``parameters``.

    Parameters
    ----------
    results : Results, Modes or ModesAlong
        Of :func:`mbd3d.kinematic_analysis`, :func:`mbd3d.inverse_dynamics` or
        :func:`mbd3d.static_equilibrium`, complete; or vibration modes
        (:func:`mbd3d.vibration_modes`, :func:`mbd3d.vibration_modes_along`).
    parameters : str or sequence of str
        Parameter names, as :func:`mbd3d.parameters` lists them.

    Returns
    -------
    Sensitivities or ModeSensitivities
        ``sens.sensitivity("slider.x", "joints.B.point_i[0]")`` over time [coordinate units
        per unit of the parameter], ``of="qd"`` or ``"qdd"`` for rates, ``sens.effort(...)``
        after inverse dynamics, ``sens.derivative(f)`` of any quantity ``f(results)``; of
        modes, ``sens.frequency(mode, name)`` [Hz per unit of the parameter] and the damping
        ratios'.

    Raises
    ------
    ModelError
        Results of another analysis, or not complete; a name that is not a parameter (with
        the nearest ones); a parameter the model is not valid without changing others too (a
        universal joint's axis component) or whose change changes the model's rows; a model
        with rolling (velocity-only) rows.
    SingularJacobianError
        At a singular position, naming the joints and the time, as the analysis does.
    """
    if isinstance(parameters, str):  # one name, not its characters
        parameters = [parameters]
    if isinstance(results, (Modes, ModesAlong)):
        return _modes(results, parameters)
    model = results.model
    what = f"sensitivities of the {results.analysis} of '{model.name}'"
    _check(model, results, what)
    tangents = [parameter_tangent(model, name, what) for name in parameters]
    if results.analysis == "static equilibrium":
        dq, dlam = _static(results, tangents)
        return Sensitivities(results, parameters, tangents, dq, np.zeros_like(dq),
                             np.zeros_like(dq), dlam)
    return _kinematic(results, parameters, tangents)


def _kinematic(results: Results, parameters: Sequence[str], tangents: list) -> Sensitivities:
    """The sensitivities of a kinematic analysis or inverse dynamics (see the module doc)."""
    model = results.model
    forces = results.analysis == "inverse dynamics"
    shape = (len(results.t), model.n_coordinates, len(tangents))
    dq, dqd, dqdd = np.zeros(shape), np.zeros(shape), np.zeros(shape)
    dlam = np.zeros((len(results.t), model.n_constraints, len(tangents))) if forces else None
    for k, t in enumerate(results.model_t):
        state = _State(results, k)
        scale, n = state_scale(model, state.qd, state.qdd), model.n_coordinates
        fr = constraints.frames(model, state.q, charts=state.charts)
        Cq = constraints.jacobian(model, t, state.q, fr, sparse=False)
        solve = _solver(model, Cq, t)
        solve_lam = _multiplier_solver(model, t, state, Cq, solve) if forces else None
        for j, tangent in enumerate(tangents):
            s = solve(-tangent.constraint_rows(t, fr))
            s_dot = solve(-tangent.along(lambda v, h: _velocity_rows(v, t, state, s, h),
                                         reach(scale[:n], s)))
            s_ddot = solve(-tangent.along(
                lambda v, h: _acceleration_rows(v, t, state, s, s_dot, h),
                reach(scale[:2 * n], s, s_dot)))
            dq[k, :, j], dqd[k, :, j], dqdd[k, :, j] = s, s_dot, s_ddot
            if forces:
                dlam[k, :, j] = solve_lam(-tangent.along(lambda v, h: _dynamic_residual(
                    v, t, state, (s, s_dot, s_ddot), h), reach(scale, s, s_dot, s_ddot)))
    return Sensitivities(results, parameters, tangents, dq, dqd, dqdd, dlam)


def _multiplier_solver(model, t: float, state: _State, Cq: np.ndarray, solve):
    """``mu = solve_lam(b)`` of ``d(residual)/d(lam) mu = b`` (the dynamic residual's, see
    :func:`_dynamic_residual`): ``Cq^T`` alone, or with joint friction, whose forces
    ``G^T e`` follow the reactions, ``e = -mu_f load(lam) tanh(v / v_s)``: ``Cq^T + G^T
    diag(mu_f tanh(v / v_s)) dload/dlam``."""
    if model.friction is None:
        return lambda b: solve(b, transpose=True)
    group = model.friction
    fr = constraints.frames(model, state.q, state.qd, state.charts)
    G, speed = group.directions(model, fr)
    _, grad = group.loads(model, fr, state.lam, jacobian=True)
    A = Cq.T + G.T @ ((group.mu * np.tanh(speed / group.v_s))[:, None] * grad)
    solve_A = _solver(model, A.T, t)
    return lambda b: solve_A(b, transpose=True)


def _static(results: Results, tangents: list) -> tuple[np.ndarray, np.ndarray]:
    """``dq/dp`` and ``dlam/dp`` of a static equilibrium (the formula sheet's 2.2): ``[K
    Cq^T; Cq 0] [s; mu] = -[d(Cq^T lam - Qe); C_p]`` along the parameter at the state
    held, ``K`` the force balance's derivative in ``q`` (fourth-order central differences),
    over the rows the analysis kept (its released drivers' dropped). A neutral motion (a free
    spin without stiffness) leaves the matrix singular; the least-squares solution takes no
    part of it."""
    model = results.model
    active = active_rows(model, results.stats.get("released", []))
    n = model.n_coordinates
    dq = np.zeros((len(results.t), n, len(tangents)))
    dlam = np.zeros((len(results.t), model.n_constraints, len(tangents)))
    for k, t in enumerate(results.model_t):
        state = _State(results, k)
        lam = state.lam[active]
        balance = lambda v, q: equilibrium_residual(  # noqa: E731
            v, t, q, lam, active, state.charts)
        Cq = balance(model, state.q)[2]
        if np.linalg.matrix_rank(Cq) < len(active):
            raise ModelError(f"sensitivities of the static equilibrium of '{model.name}': its "
                             f"rows are dependent at t = {t:g} s, so its multipliers are one "
                             "of many that balance it, whose derivatives are not the model's")
        matrix = np.block([[accurate_stiffness(model, t, state.q, lam, active, state.charts),
                            Cq.T], [Cq, np.zeros((len(active), len(active)))]])
        fr = constraints.frames(model, state.q, charts=state.charts)
        for j, tangent in enumerate(tangents):
            rhs = np.concatenate([tangent.along(lambda v, h: balance(v, state.q)[0]),
                                  tangent.constraint_rows(t, fr)[active]])
            x = scipy.linalg.lstsq(matrix, -rhs)[0]
            dq[k, :, j], dlam[k, active, j] = x[:n], x[n:]
    return dq, dlam


def _modes(modes: Modes | ModesAlong, parameters: Sequence[str]) -> ModeSensitivities:
    """The modes' frequencies and damping ratios along each parameter: the modes about the
    equilibrium moved by its sensitivities, of the model's variants (the formula sheet's
    5.1 and 5.2 without the eigenvectors' algebra, whatever the damping)."""
    eq = modes.equilibrium
    static = sensitivities(eq, parameters)
    model = eq.model
    active = active_rows(model, eq.stats.get("released", []))
    along = isinstance(modes, ModesAlong)
    shape = (len(eq.t), modes.frequencies.shape[-1], len(parameters))
    frequencies, ratios = np.full(shape, np.nan), np.full(shape, np.nan)
    for k, t in enumerate(eq.model_t):
        state = _State(eq, k)
        count = int(np.sum(np.isfinite(np.atleast_2d(modes.frequencies)[k])))
        for j, tangent in enumerate(static.tangents):
            def about(variant, h: float) -> np.ndarray:
                f, zeta, _ = modes_about(variant, t, state.q + h * static.dq[k, :, j],
                                         (state.lam + h * static.dlam[k, :, j])[active],
                                         state.charts, active)
                if len(f) != count:
                    raise ModelError(f"sensitivities of the modes of '{model.name}' to "
                                     f"parameter '{parameters[j]}': the number of modes "
                                     "changes with it")
                return np.concatenate([f, zeta])
            change = tangent.along(about, reach(state_scale(model), static.dq[k, :, j]))
            frequencies[k, :count, j], ratios[k, :count, j] = change[:count], change[count:]
    if not along:
        frequencies, ratios = frequencies[0], ratios[0]
    return ModeSensitivities(parameters, frequencies, ratios, static)


def _check(model, results: Results, what: str) -> None:
    if results.analysis == "forward dynamics":
        raise ModelError(f"{what}: a motion's sensitivities are integrated with it; run "
                         "mb.forward_sensitivities(model, t, parameters, ...) with the "
                         "arguments of the forward dynamics")
    if results.analysis not in _ANALYSES:
        raise ModelError(f"{what}: sensitivities are available for "
                         f"{', '.join(_ANALYSES[:-1])} and {_ANALYSES[-1]} so far")
    if results.status != "complete":
        raise ModelError(f"{what}: the results are {results.status} ({results.message})")
    if len(model.velocity_rows):
        raise ModelError(f"{what}: its rolling rows constrain velocities only, so its "
                         "positions depend on the path taken and have no sensitivities")
    if results.analysis == "inverse dynamics" and not results.reactions_unique:
        raise ModelError(f"{what}: its multipliers are the minimum-norm ones of dependent "
                         f"rows (at t = {results.stats['singular_outputs'][0]:g} s), one of "
                         "many that balance it: their derivatives are not the model's")


class _State:
    """Time point ``k`` of the results: ``q``, ``qd``, ``qdd``, ``lam`` and the charts."""

    def __init__(self, results: Results, k: int):
        self.q, self.qd, self.qdd = results.q[k], results.qd[k], results.qdd[k]
        self.lam = None if results.lam is None else results.lam[k]
        self.charts = None if results.charts is None else results.charts[k]


def _velocity_rows(variant, t: float, state: _State, s: np.ndarray, h: float) -> np.ndarray:
    """``Cq qd + C_t`` of ``variant`` at positions moved by ``h s``, ``qd`` held."""
    fr = constraints.frames(variant, state.q + h * s, charts=state.charts)
    _, data, _, nu = constraints.evaluate(variant, t, fr, False, True, False, True)
    return constraints.jacobian_times(variant, data, state.qd) - nu


def _acceleration_rows(variant, t: float, state: _State, s: np.ndarray, s_dot: np.ndarray,
                       h: float) -> np.ndarray:
    """``Cq qdd - gamma`` of ``variant`` at the state moved by ``h (s, s')``, ``qdd``
    held."""
    fr = constraints.frames(variant, state.q + h * s, state.qd + h * s_dot, state.charts)
    _, data, gamma = constraints.evaluate(variant, t, fr, False, True, True)
    return constraints.jacobian_times(variant, data, state.qdd) - gamma


def _dynamic_residual(variant, t: float, state: _State, rates: tuple, h: float) -> np.ndarray:
    """``M qdd + Cq^T lam - Q`` of ``variant`` at the state moved by ``h (s, s', s'')``,
    ``lam`` held (``Q`` with the joints' friction of those reactions)."""
    s, s_dot, s_ddot = rates
    fr = constraints.frames(variant, state.q + h * s, state.qd + h * s_dot, state.charts)
    data = constraints.evaluate(variant, t, fr, False, True)[1]
    residual = (mass_matrix(variant, fr, sparse=False) @ (state.qdd + h * s_ddot)
                + constraints.jacobian_transpose_times(variant, data, state.lam)
                - generalized_forces(variant, t, fr))
    if variant.friction is not None:
        # the frictions of the reactions held
        G, speed = variant.friction.directions(variant, fr)
        residual -= variant.friction.efforts(variant, fr, state.lam, speed) @ G
    return residual


def _solver(model, Cq: np.ndarray, t: float):
    """``x = solve(b, transpose=False)`` of ``Cq x = b`` (``Cq^T x = b``): by LU when square,
    else (redundant rows) by least squares, the minimum norm of ``Cq^T x = b`` as inverse
    dynamics reports it; a singular ``Cq`` is named as the analysis names it."""
    if Cq.shape[0] != Cq.shape[1]:
        return lambda b, transpose=False: _least_squares(model, Cq.T if transpose else Cq, b,
                                                         t)
    lu = scipy.linalg.lu_factor(Cq, check_finite=False)
    if not np.min(np.abs(np.diag(lu[0]))) > 1e-13 * np.max(np.abs(lu[0])):
        raise singular_error(model, Cq, t, "sensitivities")
    return lambda b, transpose=False: scipy.linalg.lu_solve(lu, b, trans=int(transpose),
                                                            check_finite=False)


def _least_squares(model, A: np.ndarray, b: np.ndarray, t: float) -> np.ndarray:
    """The solution of ``A x = b`` for dependent rows (redundant constraints), which must
    agree: a parameter that moves them apart (a redundant joint's point out of the plane
    its loop closes in) has no derivative, the mechanism would no longer assemble."""
    x = np.linalg.lstsq(A, b, rcond=None)[0]
    if np.max(np.abs(A @ x - b), initial=0.0) > 1e-8 * max(np.max(np.abs(b)), 1e-300):
        raise ModelError(f"sensitivities of '{model.name}' at t = {t:g} s: the parameter "
                         "moves its redundant constraints apart (the mechanism would lock "
                         "up): it has no derivative of its own")
    return x
