"""Accelerations and multipliers at a given state, from the augmented equations

    [M  Cq^T] [qdd]   [Qe + Qv]
    [Cq 0   ] [lam] = [Qd     ]

(assembled and solved in one place, :mod:`mbd3d.numerics.compiled.accelerations`), and where
``Cq`` loses rank, from the augmented-Lagrangian iteration. Every integrator reports its outputs
through these.
"""

from __future__ import annotations

import numpy as np

from mbd3d.model import constraints
from mbd3d.model.equations import augmented_accelerations, generalized_forces, mass_matrix
from mbd3d.errors import IntegrationError
from mbd3d.model.friction import raise_friction_with_redundancy
from mbd3d.numerics.linalg import (SingularMatrix, augmented_scaling, solve_augmented_lagrangian,
                                   solve_model_augmented)
from mbd3d.analyses.position import singular_error

__all__ = ["forward_accelerations", "consistent_accelerations", "rows_dependent"]


def forward_accelerations(model, t: float, q: np.ndarray, qd: np.ndarray,
                          charts: np.ndarray | None = None, *, what: str | None = None
                          ) -> tuple[np.ndarray, np.ndarray]:
    """Accelerations ``qdd`` and multipliers ``lam`` from the augmented equations at ``(t, q, qd)``.

    ``charts``: spatial models, the reference rotations ``q`` is relative to (default the
    model's initial charts). ``what``: the analysis its errors name (default forward
    dynamics of the model).

    Parameters
    ----------
    model : Model
    t : float
        Time [s].
    q, qd : (n,) array_like
        The state, positions in ``charts`` for a spatial model.
    charts : ndarray, optional
        See above.
    what : str, optional
        See above.

    Raises
    ------
    SingularJacobianError
        When the augmented matrix is singular (names the dependent joints and the time).
    """
    try:
        x = augmented_accelerations(model, t, q, qd, charts)
    except SingularMatrix:
        return consistent_accelerations(model, t, q, qd, charts, fallback=False, what=what)[:2]
    if x is None:
        raise IntegrationError(f"{what or _what(model)}: the state is not finite at "
                               f"t = {t:.6g} s (the integration diverged)", time=t)
    n = model.n_coordinates
    return x[:n], x[n:]


def _what(model) -> str:
    return f"forward dynamics of '{model.name}'"


def consistent_accelerations(model, t: float, q: np.ndarray, qd: np.ndarray, charts=None,
                             lam: np.ndarray | None = None, redundant: bool = False,
                             fallback: bool = True, what: str | None = None
                             ) -> tuple[np.ndarray, np.ndarray, bool]:
    """``qdd`` and ``lam`` of the augmented equations, also where ``Cq`` loses rank.

    The augmented matrix is factored by LU as in :func:`mbd3d.forward_accelerations`; where it
    is singular (a singular configuration, redundant constraints) the augmented-Lagrangian
    iteration gives the accelerations of the consistent equations and the multipliers without
    a component in the null space of ``Cq^T`` (minimum-norm from ``lam = 0``). With
    ``redundant`` (rows known to be dependent) the LU is skipped: rounding can lift its
    smallest pivot above the singularity threshold, and the solution would be noise. Without
    ``fallback`` a singular matrix raises instead (the explicit integrators' rule). ``what``:
    the analysis its errors name (default forward dynamics of the model).

    Returns
    -------
    qdd, lam : ndarray
    regular : bool
        False when the augmented matrix was singular (multipliers not unique).
    """
    n = model.n_coordinates
    what = what or _what(model)
    if not redundant:
        try:
            x = augmented_accelerations(model, t, q, qd, charts)
        except SingularMatrix:
            if not fallback:
                raise singular_error(model, constraints.jacobian(model, t, q, constraints.frames(
                    model, q, charts=charts)), t, what) from None
        else:
            if x is None:
                raise IntegrationError(f"{what}: the state is not finite at t = {t:.6g} s "
                                       "(the integration diverged)", time=t)
            return x[:n], x[n:], True
    if model.friction is not None:
        raise_friction_with_redundancy(model, t)
    fr = constraints.frames(model, q, qd, charts)
    _, jac_data, gamma = constraints.evaluate(model, t, fr, value=False, jacobian=True, gamma=True)
    Qe = generalized_forces(model, t, fr)
    M = mass_matrix(model, fr)
    Cq = constraints.jacobian_matrix(model, jac_data)
    try:
        qdd, lam, _ = solve_augmented_lagrangian(M, Cq, Qe, gamma, lam=lam,
                                                 scaling=augmented_scaling(model))
    except SingularMatrix:
        raise singular_error(model, Cq, t, what) from None
    return qdd, lam, False


def rows_dependent(model, t: float, q: np.ndarray, charts=None) -> bool:
    """Whether the augmented matrix ``[M Cq^T; Cq 0]`` is singular at ``q``: constraint rows
    that depend on each other (redundant constraints, or a singular configuration)."""
    fr = constraints.frames(model, q, charts=charts)
    _, jac_data, _ = constraints.evaluate(model, t, fr, value=False)
    blocks = model.body_type.mass_blocks(fr, model.mass, model.inertia)
    try:
        solve_model_augmented(model, blocks, jac_data,
                              np.zeros(model.n_coordinates + model.n_constraints))
    except SingularMatrix:
        return True
    return False
