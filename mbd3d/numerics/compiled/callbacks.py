"""What the compiled integrator loops ask of Python: the parts of a model that are Python
objects (force elements, prescribed motions), the sparse solve of a large model, the
augmented-Lagrangian accelerations of a model with redundant constraints, and
generalized-alpha's iteration matrix where it is factored by SuperLU.

The loop calls these from Numba's object mode (about a microsecond per call) with the key of
its run: :class:`Run` registers the run's objects under a key for the length of the run.
Exceptions raised here (a force returning NaN, a motion failing) propagate out of the
compiled loop unchanged.
"""

from __future__ import annotations

import itertools

import numpy as np

_runs: dict[int, "Run"] = {}
_keys = itertools.count(1)


class Run:
    """The Python side of one integration: ``with Run(model) as key: ...``."""

    def __init__(self, model, accelerations=None):
        self.model = model
        #: ``(t, q, qd, charts) -> (qdd, lam)`` for models the compiled solve cannot take
        self.accelerations = accelerations
        #: generalized-alpha: the applied forces' tangent of the step (added to the iteration
        #: matrix by :func:`factor_penalty_and_solve`), and the last factors made there
        self.tangent = None
        self.factors = None
        #: whether :func:`parts` adds the joints' friction, from the multipliers of the state
        #: it is asked at (generalized-alpha; the explicit integrators take friction with the
        #: accelerations)
        self.friction_forces = False
        self.key = next(_keys)

    def __enter__(self) -> int:
        _runs[self.key] = self
        return self.key

    def __exit__(self, *exc) -> None:
        _runs.pop(self.key, None)


def parts(key: int, t: float, q: np.ndarray, qd: np.ndarray, charts: np.ndarray):
    """Generalized forces of the force elements (n,), ``(f, f', f'')`` of the drivers
    (n_drivers, 3) and of the rotation drivers' motions (k, 3) at ``(t, q, qd)``; with the
    run's ``friction_forces``, the joints' friction added to the forces."""
    from mbd3d.model.constraints import _motion_values, frames, motion_phases

    run = _runs[key]
    model = run.model
    extra = np.zeros(model.n_coordinates)
    friction = model.friction is not None and run.friction_forces
    if model.force_groups or friction:
        fr = frames(model, q, qd, charts if model.dim == 3 else None)
        Q = np.zeros((model.n_bodies + 1, model.n_coords_per_body))
        for group in model.force_groups:
            group.apply(model, t, fr, Q)
        if friction:
            from mbd3d.model.equations import augmented_accelerations

            x = augmented_accelerations(model, t, q, qd, charts if model.dim == 3 else None)
            if x is not None:
                model.friction.apply(model, fr, x[model.n_coordinates:], Q)
        extra = np.ascontiguousarray(Q[:model.n_bodies].ravel())
    drivers = _motion_values(model.driver_motions, model.driver_names, t)
    return extra, drivers, np.ascontiguousarray(motion_phases(model, t))


def solve(key: int, values: np.ndarray, rhs: np.ndarray):
    """``(x, status)`` of the augmented system of a sparse model from its entries."""
    from mbd3d.numerics.compiled.accelerations import SINGULAR, SOLVED
    from mbd3d.numerics.linalg import SingularMatrix

    try:
        return np.ascontiguousarray(_runs[key].model._augmented_pattern.solve(values, rhs)), SOLVED
    except SingularMatrix:
        return np.zeros(len(rhs)), SINGULAR


def factor_penalty_and_solve(key: int, values: np.ndarray, r: np.ndarray):
    """``(x, status)``: factor generalized-alpha's iteration matrix from its entries (and the
    run's tangent) in Python (SuperLU, or a tangent outside the band), keep the factors in
    the run, and solve ``A x = r``."""
    from mbd3d.numerics.linalg import SingularMatrix

    run = _runs[key]
    try:
        run.factors = run.model._penalty_pattern.factor(values, run.tangent)
    except SingularMatrix:
        return np.zeros(len(r)), 1
    return np.ascontiguousarray(run.factors.solve(r)), 0


def accelerations(key: int, t: float, q: np.ndarray, qd: np.ndarray, charts: np.ndarray):
    """``(x, status)``: ``(qdd, lam)`` from the run's own solve (redundant constraints)."""
    from mbd3d.numerics.compiled.accelerations import SOLVED

    run = _runs[key]
    qdd, lam = run.accelerations(t, q, qd, charts if run.model.dim == 3 else None)
    return np.ascontiguousarray(np.concatenate([qdd, lam])), SOLVED
