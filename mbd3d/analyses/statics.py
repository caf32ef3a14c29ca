"""Static equilibrium: where a mechanism rests under its applied forces, what holds it there,
and whether it stays.

At rest (``qd = qdd = 0``) the equations of motion reduce to

    Cq(q)^T lam = Qe(q, t),    C(q, t) = 0

(gravity, springs, constant forces and torques in ``Qe``; the quadratic velocity forces
vanish). They are solved for ``(q, lam)`` together by Newton's method on the matrix

    [K + H   Cq^T]          K = -dQe/dq   (the applied forces' stiffness)
    [Cq      0   ]          H = d(Cq^T lam)/dq   (the constraint forces' geometric stiffness)

with a backtracking line search on the residual; ``K + H`` is the force balance's derivative by
forward differences (a model's size in residual evaluations per iteration). The step is taken
in the joints' free motions (the null-space method), so that a neutral motion, along which the
differenced stiffness is noise, does not carry it away (:func:`_newton_step`).
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
from mbd3d.model.tangents import OFFSETS, slope

__all__ = ["static_equilibrium", "active_rows", "equilibrium_residual", "accurate_stiffness"]

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
    release : sequence of str, or bool
        Drivers whose rows are dropped, so that the mechanism settles with their freedom
        (``True``: every driver, ``False``: none); their efforts are zero.
    tol : float
        Convergence: every constraint row within ``tol`` of its scale (lengths in units of
        the model's length) and either the force balance within ``tol`` of the largest
        applied force or the last Newton step within ``tol`` of the coordinates' scales (the
        test that applies where the applied forces vanish at the equilibrium, as at a relaxed
        spring without gravity).
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
        signs are what they mean); ``stats["released"]`` names the drivers released.

    Raises
    ------
    AnalysisError
        When Newton does not converge (no equilibrium near the guess, or one at a singular
        position), with the time and the residual.
    ModelError
        For an unknown driver in ``release`` or a bad guess.
    """
    t = check_times(times)
    what = f"static equilibrium of '{model.name}'"
    active = active_rows(model, release)
    stats = {"wall_time": 0.0, "newton_iterations": 0, "stability": [],
             "stiffness_eigenvalues": [],
             "released": list(dict.fromkeys(
                 model.joints[model.row_element[r]].name
                 for r in sorted(set(range(model.n_constraints)) - set(active))))}
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


def active_rows(model, release) -> np.ndarray:
    """The constraint rows kept: all but the released drivers'."""
    drivers = [element.name for element in model.joints if element.is_driver]
    if release is True:
        names = drivers
    elif release is False or release is None:
        names = []
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


def equilibrium_residual(model, t, q, lam, active, chart):
    """``(force balance Cq^T lam - Qe (n,), C (active rows), Cq (active rows, dense), Qe)``."""
    zeros = np.zeros(model.n_coordinates)
    fr = constraints.frames(model, q, zeros, chart)
    C, data, _ = constraints.evaluate(model, t, fr)
    Cq = constraints.jacobian_matrix(model, data, sparse=False)[active]
    Qe = generalized_forces(model, t, fr)
    return Cq.T @ lam - Qe, C[active], Cq, Qe


def _solve(model, t, q, lam, active, chart, tol, max_iterations, stats, what):
    """Newton's method for ``(q, lam)`` at ``t``, with a backtracking line search and steps
    no longer than the coordinates' scales (see :func:`_newton_step`).

    Converged when the constraint rows are within ``tol`` of their scales and either the force
    balance is within ``tol`` of the largest applied force, or the Newton step moves no
    coordinate by more than ``tol`` of its scale. The second test is what ends the solve where
    the applied forces vanish at the equilibrium (a relaxed spring without gravity): there the
    force balance relative to the applied forces stays of order one all the way in."""
    n = model.n_coordinates
    row_scale = model.row_scale[active]
    if lam is None:  # the least-squares multipliers at the guess
        _, _, Cq, Qe = equilibrium_residual(model, t, q, np.zeros(len(active)), active, chart)
        lam = la.lstsq(Cq.T, Qe)[0] if len(active) else np.zeros(0)

    def rows(C):
        return float(np.max(np.abs(C) / row_scale, initial=0.0))

    def merit(force, C, unit):
        return max(float(np.max(np.abs(force), initial=0.0)) / unit, rows(C))

    force, C, Cq, Qe = equilibrium_residual(model, t, q, lam, active, chart)
    tiny = model.mass_scale * 1e-12
    size = merit(force, C, max(_largest(Qe), tiny))
    unit = None
    for _ in range(max_iterations):
        stiffness = _stiffness(model, t, q, lam, active, chart, Cq)
        if size <= tol:
            return q, lam, stiffness, Cq
        if unit is None:
            # the line search's force unit, fixed for the solve so that it judges the point
            # and the trial alike however small the forces become near the equilibrium: the
            # forces at the guess, or those its stiffness makes over the coordinates' scales
            # (where the guess is unloaded but off its rows: a driver moved, a spring not yet
            # stretched)
            unit = max(_largest(Qe), _largest(force),
                       _largest(stiffness * model.coordinate_scale), tiny)
        stats["newton_iterations"] += 1
        step = _newton_step(model, stiffness, Cq, force, C)
        if (rows(C) <= tol
                and np.max(np.abs(step[:n]) / model.coordinate_scale, initial=0.0) <= tol):
            return q + step[:n], lam + step[n:], stiffness, Cq
        fraction = 1.0
        while True:  # backtracking: the first step that lowers the residual
            q_try, lam_try = q + fraction * step[:n], lam + fraction * step[n:]
            trial = equilibrium_residual(model, t, q_try, lam_try, active, chart)
            common = max(unit, _largest(Qe), _largest(trial[3]))
            if (merit(trial[0], trial[1], common) < merit(force, C, common)
                    or fraction < 1.0 / 64):
                break
            fraction *= 0.5
        q, lam = q_try, lam_try
        force, C, Cq, Qe = trial
        size = merit(force, C, max(_largest(Qe), tiny))
    raise AnalysisError(f"{what}: Newton's method did not converge at t = {t:.6g} s (residual "
                        f"{size:.2e} of the forces' and rows' scale after {max_iterations} "
                        "iterations); there may be no equilibrium near the guess: give "
                        "q_guess closer to one, or hold a driver instead of releasing it")


def _largest(values: np.ndarray) -> float:
    return float(np.max(np.abs(values), initial=0.0))


def _newton_step(model, stiffness, Cq, force, C) -> np.ndarray:
    """The Newton step ``d(q, lam)`` of ``stiffness dq + Cq^T dlam = -force``,
    ``Cq dq = -C``, by the null-space method, shortened so that no coordinate moves by more
    than its scale (a length, a radian) at once.

    In coordinates divided by their scales, ``dq`` is the least-norm correction of the rows
    plus a motion ``N z`` in the joints' free motions (``N`` an orthonormal null space of
    ``Cq``), where ``N^T K N z = -N^T (force + K dq_rows)``. That reduced stiffness is solved
    through its singular values, each raised to at least :data:`NEUTRAL_TOLERANCE` of the
    largest and to a stiffness of the order of gravity's on the model's length: along a
    neutral motion (the spin of a bar about its own axis) the differenced stiffness is noise,
    and a plain solve would send the step along it; along a motion where the potential is
    flat but pushed (a pendulum at the horizontal without a spring) the step follows the
    force, downhill."""
    scale = model.coordinate_scale
    C_rows = Cq * scale
    K = scale[:, None] * stiffness * scale
    dx = -la.lstsq(C_rows, C)[0] if C_rows.shape[0] else np.zeros(len(scale))
    N = la.null_space(C_rows) if C_rows.shape[0] else np.eye(len(scale))
    if N.shape[1]:
        U, sigma, Vt = la.svd(N.T @ K @ N)
        # gravity's stiffness on the model's length, per coordinate scale squared [J]
        pull = 1e-3 * max(float(np.linalg.norm(model.gravity)), 1.0) / model.length_scale
        floor = max(NEUTRAL_TOLERANCE * sigma[0], pull * model.mass_scale
                    * model.length_scale ** 2)
        g = N.T @ (scale * force + K @ dx)
        # a flat direction is given the floor's stiffness with a positive sign (its differenced
        # sign is noise), so that the step goes with the force there, downhill
        flat = sigma < floor
        U[:, flat] = Vt[flat].T
        dx -= N @ (Vt.T @ ((U.T @ g) / np.maximum(sigma, floor)))
    dq = scale * dx
    dlam = (la.lstsq(Cq.T, -(force + stiffness @ dq))[0] if Cq.shape[0] else np.zeros(0))
    step = np.concatenate([dq, dlam])
    largest = float(np.max(np.abs(dx), initial=0.0))
    return step / largest if largest > 1.0 else step


def _stiffness(model, t, q, lam, active, chart, Cq) -> np.ndarray:
    """``K + H`` (n, n): the derivative of the force balance ``Cq^T lam - Qe`` with respect
    to ``q`` at fixed ``lam``, by forward differences of the residual itself, so that the
    Newton matrix is that of the equations solved (in Rodrigues parameters too, where the
    applied forces' generalized components turn with ``G``)."""
    n = model.n_coordinates
    base = equilibrium_residual(model, t, q, lam, active, chart)[0]
    stiffness = np.empty((n, n))
    scale = model.coordinate_scale
    for j in range(n):
        h = 1.5e-8 * max(scale[j], abs(q[j]))
        shifted = q.copy()
        shifted[j] += h
        stiffness[:, j] = (equilibrium_residual(model, t, shifted, lam, active, chart)[0] - base) / h
    return stiffness


def accurate_stiffness(model, t, q, lam, active, chart) -> np.ndarray:
    """``K + H`` (n, n) as :func:`_stiffness` gives it, by fourth-order central differences
    of a thousandth of each coordinate's scale (about 1e-12 of its size where the forces are
    smooth, against :func:`_stiffness`'s 1e-8, at four times the evaluations): for what is
    read from it, modes and their sensitivities."""
    columns = []
    for j in range(len(q)):
        h = 1e-3 * model.coordinate_scale[j]
        shifted = [q.copy() for _ in OFFSETS]
        for o, x in zip(OFFSETS, shifted):
            x[j] += o * h
        columns.append(slope([equilibrium_residual(model, t, x, lam, active, chart)[0]
                              for x in shifted], h))
    return np.column_stack(columns)


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
