"""Static equilibrium: where a mechanism rests under its applied forces, what holds it there,
and whether it stays.

At rest (``qd = qdd = 0``) the equations of motion reduce to

    Cq(q)^T lam = Qe(q, t),    C(q, t) = 0

(gravity, springs, constant forces and torques in ``Qe``; the quadratic velocity forces
vanish). They are solved for ``(q, lam)`` together by Newton's method on the matrix

    [K + H   Cq^T]          K = -dQe/dq   (the applied forces' stiffness)
    [Cq      0   ]          H = d(Cq^T lam)/dq   (the constraint forces' geometric stiffness)

with a backtracking line search on the residual; ``K + H`` is the force balance's derivative by
forward differences (a model's size in residual evaluations per iteration).
Drivers are held at their values at each time, or released (their rows dropped, their efforts
zero), so that a mechanism settles with that freedom.

Stability is the sign of the reduced stiffness ``N^T (K + H) N`` on the tangent space of the
constraints (``N`` a basis of the null space of ``Cq``): the second variation of the potential
energy on the motions the joints allow. Its inertia (how many eigenvalues are positive,
negative, zero) does not depend on the basis or on the units, so "stable" (all positive),
"unstable" (one negative) and "neutral" (none negative, one zero: a free motion without
stiffness) mean the same in any coordinates.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import scipy.linalg as la

from mbd3d.analyses.kinematics import check_times, initial_guess
from mbd3d.errors import AnalysisError, ModelError
from mbd3d.io.observers import Observer, Watch
from mbd3d.io.results import Results
from mbd3d.io.store import ResultsBuffer, run_keeping_results
from mbd3d.model import constraints
from mbd3d.model.equations import generalized_forces

__all__ = ["static_equilibrium"]

#: relative size of a reduced stiffness eigenvalue below which it counts as zero (a free
#: motion without stiffness); the stiffness is differenced, to about 1e-7 of its size
NEUTRAL_TOLERANCE = 1e-6


def static_equilibrium(model, times: float | Sequence[float] = 0.0,
                       q_guess: Sequence[float] | None = None, *,
                       release: Sequence[str] | bool = (), tol: float = 1e-10,
                       max_iterations: int = 50, observers: Sequence[Observer] | None = None,
                       progress: bool | None = None) -> Results:
    """The configuration where the applied forces balance the constraint reactions.

    Parameters
    ----------
    model : Model
    times : float or sequence of float
        Time(s) [s] at which the drivers' values (held) and time-dependent forces are taken.
        Over a grid of times a driven mechanism gives the efforts that hold it still at each
        position of its motion: the static force analysis of textbooks (kinetostatics).
    q_guess : array_like (n,), optional
        Initial guess of the coordinates (default the model's); each later time starts from
        the previous equilibrium. Newton's method converges to the equilibrium nearest the
        guess, stable or not (an inverted pendulum's upright position); its stability is
        reported. To find where a mechanism comes to rest, start it near there, or let a
        damped forward-dynamics run settle first.
    release : sequence of str, or True
        Drivers whose rows are dropped, so that the mechanism settles with their freedom
        (``True``: every driver); their efforts are zero.
    tol : float
        Convergence: every constraint row within ``tol`` of its scale (lengths in units of
        the model's length) and the force balance within ``tol`` of the largest force.
    max_iterations : int
        Newton iterations allowed per time.
    observers, progress
        As for the other analyses.

    Returns
    -------
    Results
        Positions (velocities and accelerations zero), multipliers (joint reactions, driver
        efforts) at each time; ``stats["stability"]`` lists "stable", "unstable", "neutral"
        or "fully constrained" per time, and ``stats["stiffness_eigenvalues"]`` the reduced
        stiffness's eigenvalues (in the basis of an orthonormal null space of ``Cq``: their
        signs are what they mean).

    Raises
    ------
    AnalysisError
        When Newton does not converge (no equilibrium near the guess, or one at a singular
        position), with the time and the residual.
    ModelError
        For an unknown driver in ``release`` or a bad guess.
    """
    constraints.require_holonomic(model, "static equilibrium")
    t = check_times(times)
    what = f"static equilibrium of '{model.name}'"
    active = _active_rows(model, release)
    stats = {"wall_time": 0.0, "newton_iterations": 0, "stability": [],
             "stiffness_eigenvalues": []}
    out = ResultsBuffer(model, "static equilibrium", t, stats)
    n, m = model.n_coordinates, model.n_constraints
    zeros = np.zeros(n)

    def loop() -> None:
        chart = model.charts0
        q = initial_guess(model, t[0], q_guess, chart, what, "q_guess")
        lam = None
        for tk in t:
            q, lam_active, stiffness, Cq = _solve(model, float(tk), q, lam, active, chart, tol,
                                                  max_iterations, stats, what)
            lam = lam_active
            full = np.zeros(m)
            full[active] = lam_active
            stability, eigenvalues = _stability(stiffness, Cq)
            stats["stability"].append(stability)
            stats["stiffness_eigenvalues"].append(eigenvalues)
            out.store(q, zeros, zeros, full, chart)
            watch.tick(tk, out.done)

    watch = Watch(observers, progress, model, t, "static equilibrium", out.partial)
    return run_keeping_results(loop, out.partial, watch)


def _active_rows(model, release) -> np.ndarray:
    """The constraint rows kept: all but the released drivers'."""
    drivers = [element.name for element in model.joints if element.is_driver]
    if release is True:
        names = drivers
    elif isinstance(release, str):
        names = [release]
    else:
        names = list(release)
    dropped = set()
    for name in names:
        if name not in drivers:
            raise ModelError(f"static equilibrium of '{model.name}': release names drivers; "
                             f"'{name}' is none (drivers: {', '.join(drivers) or 'none'})")
        dropped.update(int(r) for r in model.rows_of(name))
    return np.array([r for r in range(model.n_constraints) if r not in dropped], dtype=int)


def _residual(model, t, q, lam, active, chart):
    """``(force balance Cq^T lam - Qe (n,), C (active rows), Cq (active rows, dense), Qe)``."""
    zeros = np.zeros(model.n_coordinates)
    fr = constraints.frames(model, q, zeros, chart)
    C, data, _ = constraints.evaluate(model, t, fr)
    Cq = constraints.jacobian_matrix(model, data, sparse=False)[active]
    Qe = generalized_forces(model, t, fr)
    return Cq.T @ lam - Qe, C[active], Cq, Qe


def _solve(model, t, q, lam, active, chart, tol, max_iterations, stats, what):
    """Newton's method for ``(q, lam)`` at ``t``, with a backtracking line search and steps
    no longer than the coordinates' scales (see :func:`_newton_step`)."""
    n = model.n_coordinates
    row_scale = model.row_scale[active]
    if lam is None:  # the least-squares multipliers at the guess
        _, _, Cq, Qe = _residual(model, t, q, np.zeros(len(active)), active, chart)
        lam = la.lstsq(Cq.T, Qe)[0] if len(active) else np.zeros(0)
    zeros = np.zeros(n)
    mass = np.einsum("kii->ki", model.body_type.mass_blocks(
        constraints.frames(model, q, zeros, chart), model.mass, model.inertia)).ravel()

    def merit(force, C, Qe):
        scale = max(float(np.max(np.abs(Qe), initial=0.0)), model.mass_scale * 1e-12)
        return max(float(np.max(np.abs(force), initial=0.0)) / scale,
                   float(np.max(np.abs(C) / row_scale, initial=0.0)))

    force, C, Cq, Qe = _residual(model, t, q, lam, active, chart)
    size = merit(force, C, Qe)
    for _ in range(max_iterations):
        stiffness = _stiffness(model, t, q, lam, active, chart, Cq)
        if size <= tol:
            return q, lam, stiffness, Cq
        stats["newton_iterations"] += 1
        step = _newton_step(model, stiffness, Cq, force, C, mass)
        fraction = 1.0
        while True:  # backtracking: the first step that lowers the residual
            q_try, lam_try = q + fraction * step[:n], lam + fraction * step[n:]
            trial = _residual(model, t, q_try, lam_try, active, chart)
            trial_size = merit(trial[0], trial[1], trial[3])
            if trial_size < size or fraction < 1.0 / 64:
                break
            fraction *= 0.5
        q, lam = q_try, lam_try
        (force, C, Cq, Qe), size = trial, trial_size
    raise AnalysisError(f"{what}: Newton's method did not converge at t = {t:.6g} s (residual "
                        f"{size:.2e} of the forces' and rows' scale after {max_iterations} "
                        "iterations); there may be no equilibrium near the guess: give "
                        "q_guess closer to one, or hold a driver instead of releasing it")


def _newton_step(model, stiffness, Cq, force, C, mass) -> np.ndarray:
    """The Newton step of ``[stiffness Cq^T; Cq 0] d(q, lam) = -(force, C)``, shortened so
    that no coordinate moves by more than its scale (a length, a radian) at once. Where the
    matrix is singular (the potential flat along a free motion: a pendulum at the horizontal
    without a spring) the stiffness is damped by a small multiple of the masses, which turns
    the step into one along the applied forces."""
    n, k = stiffness.shape[0], Cq.shape[0]
    rhs = -np.concatenate([force, C])
    damping = 0.0
    # the damping's unit: a stiffness of the order of gravity's on the model's length
    unit = 1e-3 * max(float(np.linalg.norm(model.gravity)), 1.0) / model.length_scale
    for _ in range(8):
        J = np.block([[stiffness + damping * np.diag(mass), Cq.T], [Cq, np.zeros((k, k))]])
        lu, piv = la.lu_factor(J, check_finite=False)
        pivots = np.abs(np.diag(lu))
        if pivots.size == 0 or pivots.min() > 1e-12 * pivots.max():
            step = la.lu_solve((lu, piv), rhs, check_finite=False)
            break
        damping = unit if damping == 0.0 else 100.0 * damping
    else:
        step = la.lstsq(J, rhs)[0]
    largest = float(np.max(np.abs(step[:n]) / model.coordinate_scale, initial=0.0))
    return step / largest if largest > 1.0 else step


def _stiffness(model, t, q, lam, active, chart, Cq) -> np.ndarray:
    """``K + H`` (n, n): the derivative of the force balance ``Cq^T lam - Qe`` with respect
    to ``q`` at fixed ``lam``, by forward differences of the residual itself, so that the
    Newton matrix is that of the equations solved (in Rodrigues parameters too, where the
    applied forces' generalized components turn with ``G``)."""
    n = model.n_coordinates
    base = _residual(model, t, q, lam, active, chart)[0]
    stiffness = np.empty((n, n))
    scale = model.coordinate_scale
    for j in range(n):
        h = 1.5e-8 * max(scale[j], abs(q[j]))
        shifted = q.copy()
        shifted[j] += h
        stiffness[:, j] = (_residual(model, t, shifted, lam, active, chart)[0] - base) / h
    return stiffness


def _stability(stiffness: np.ndarray, Cq: np.ndarray) -> tuple[str, np.ndarray]:
    """The class of the equilibrium and the reduced stiffness's eigenvalues (see the module
    doc)."""
    N = la.null_space(Cq) if Cq.shape[0] else np.eye(Cq.shape[1])
    if N.shape[1] == 0:
        return "fully constrained", np.zeros(0)
    reduced = N.T @ stiffness @ N
    eigenvalues = np.linalg.eigvalsh(0.5 * (reduced + reduced.T))
    zero = NEUTRAL_TOLERANCE * max(float(np.max(np.abs(eigenvalues))), 1e-300)
    if np.any(eigenvalues < -zero):
        return "unstable", eigenvalues
    if np.any(np.abs(eigenvalues) <= zero):
        return "neutral", eigenvalues
    return "stable", eigenvalues
