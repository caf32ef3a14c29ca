"""What the compiled integrator loops ask of Python: the parts of a model that are Python
objects (force elements, prescribed motions), the sparse solve of a large model, the
augmented-Lagrangian accelerations of a model with redundant constraints, and
generalized-alpha's iteration matrix where it is factored by SuperLU.

The loop calls these from Numba's object mode (about a microsecond per call) with the key of
its run: :class:`Run` holds, for the length of the run, the functions the caller handed it
(the model's side is :func:`mbd3d.model.equations.python_parts` and the model's patterns), so
that nothing here reaches up into the model. Exceptions raised by them (a force returning
NaN, a motion failing) propagate out of the compiled loop unchanged.
"""

from __future__ import annotations

import itertools
from typing import Callable

import numpy as np

from mbd3d.numerics.linalg import SingularMatrix

_runs: dict[int, "Run"] = {}
_keys = itertools.count(1)


class Run:
    """The Python side of one integration: ``with Run(parts, ...) as key: ...``.

    Parameters
    ----------
    parts : callable
        ``(t, q, qd, charts) -> (extra (n,), drivers (n_drivers, 3), phi (k, 3))``: the
        generalized forces of the Python force elements and the values of the drivers' and
        the rotation drivers' motions.
    solve : callable, optional
        ``(values, rhs) -> x``: the augmented system of a sparse model from its entries;
        raises :class:`SingularMatrix`.
    factor : callable, optional
        ``(values, tangent) -> factors`` (with ``factors.solve(r)``): generalized-alpha's
        iteration matrix, with the applied forces' tangent; raises :class:`SingularMatrix`.
    accelerations : callable, optional
        ``(t, q, qd, charts) -> (qdd, lam)`` for models the compiled solve cannot take.
    """

    def __init__(self, parts: Callable, *, solve: Callable | None = None,
                 factor: Callable | None = None, accelerations: Callable | None = None):
        self.parts = parts
        self.solve = solve
        self.factor = factor
        self.accelerations = accelerations
        #: generalized-alpha: the applied forces' tangent of the step (added to the iteration
        #: matrix by :func:`factor_penalty_and_solve`), and the last factors made there
        self.tangent = None
        self.factors = None
        self.key = next(_keys)

    def __enter__(self) -> int:
        _runs[self.key] = self
        return self.key

    def __exit__(self, *exc) -> None:
        _runs.pop(self.key, None)


def parts(key: int, t: float, q: np.ndarray, qd: np.ndarray, charts: np.ndarray):
    """Generalized forces of the force elements (n,), ``(f, f', f'')`` of the drivers
    (n_drivers, 3) and of the rotation drivers' motions (k, 3) at ``(t, q, qd)``."""
    return _runs[key].parts(t, q, qd, charts)


def solve(key: int, values: np.ndarray, rhs: np.ndarray):
    """``(x, status)`` of the augmented system of a sparse model from its entries."""
    from mbd3d.numerics.compiled.accelerations import SINGULAR, SOLVED

    try:
        return np.ascontiguousarray(_runs[key].solve(values, rhs)), SOLVED
    except SingularMatrix:
        return np.zeros(len(rhs)), SINGULAR


def factor_penalty_and_solve(key: int, values: np.ndarray, r: np.ndarray):
    """``(x, status)``: factor generalized-alpha's iteration matrix from its entries (and the
    run's tangent) in Python (SuperLU, or a tangent outside the band), keep the factors in
    the run, and solve ``A x = r``."""
    run = _runs[key]
    try:
        run.factors = run.factor(values, run.tangent)
    except SingularMatrix:
        return np.zeros(len(r)), 1
    return np.ascontiguousarray(run.factors.solve(r)), 0


def accelerations(key: int, t: float, q: np.ndarray, qd: np.ndarray, charts: np.ndarray):
    """``(x, status)``: ``(qdd, lam)`` from the run's own solve (redundant constraints, joint
    friction, rigid contacts at rest); status singular where the run's solve returns None
    (a stage it cannot evaluate: the loop retries the step shorter)."""
    from mbd3d.numerics.compiled.accelerations import SINGULAR, SOLVED

    solved = _runs[key].accelerations(t, q, qd, charts)
    if solved is None:
        return np.zeros(len(q)), SINGULAR
    return np.ascontiguousarray(np.concatenate(solved)), SOLVED
