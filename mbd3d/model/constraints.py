"""Evaluation of the constraint equations of a model: ``C``, ``Cq``, ``-Ct`` and ``Qd``.

``C = c(q) - c0 - f(t)`` row by row (see :mod:`mbd3d.model.primitives`). All primitive instances are
evaluated in one compiled loop; the Jacobian values go straight into the pattern fixed when the
model was built (dense array, or CSR with precomputed ordering when
``model.sparse``).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from mbd3d.model.body import Frames
from mbd3d.errors import ModelError
from mbd3d.model.primitives import evaluate_rows
from mbd3d.numerics.compiled import (kinematics as kinematics_kernel, motions as motions_kernel,
                                     rows as rows_kernel)

__all__ = ["frames", "largest_relative", "evaluate", "residual", "jacobian", "jacobian_matrix",
           "jacobian_times", "jacobian_transpose_times", "velocity_rhs", "acceleration_rhs",
           "driver_values", "motion_phases", "motions_compiled"]


def frames(model, q: np.ndarray, qd: np.ndarray | None = None,
           charts: np.ndarray | None = None) -> Frames:
    """Per-body kinematic quantities of state ``(q, qd)``; the ground is the last row.

    ``charts`` (spatial models): the reference rotations ``q`` is relative to, (n_bodies + 1,
    3, 3); default the model's initial charts, which ``model.q0`` is relative to.
    """
    shape, ground = (model.n_bodies + 1, model.n_coords_per_body), model._ground_row
    # one concatenation per array: this runs at every right-hand side of an integration
    Q = np.concatenate((q, ground)).reshape(shape)
    Qd = None if qd is None else np.concatenate((qd, ground)).reshape(shape)
    return model.body_type.frames(Q, Qd, model.charts0 if charts is None else charts)


def largest_relative(model, rows: np.ndarray) -> float:
    """``max |rows|`` over constraint rows (residuals of positions or of velocities), each in
    the model's units: lengths over its length scale, angles as they are."""
    return float(np.max(np.abs(rows) / model.row_scale, initial=0.0))


def driver_values(model, t: float) -> np.ndarray:
    """``(f, f', f'')`` of every row driven by ``c(q) - f(t)``, shape (3, n_drivers).

    Raises
    ------
    ModelError
        If a driver's motion returns a non-finite value (names the driver and the time).
    """
    values = _compiled_motions(model, "driver", len(model.driver_motions), t)
    if values is None:
        values = _motion_values(model.driver_motions, model.driver_names, t)
    return values.T


def _compiled_motions(model, table: str, count: int, t: float) -> np.ndarray | None:
    """``(f, f', f'')`` (count, 3) of the drivers' (``table="driver"``) or rotation drivers'
    (``"rotation"``) motions from the compiled core's tables in one call; None where a
    motion is a Python function, a copy of the model has motions of its own, or a value is
    not finite (the caller's evaluation then names the driver)."""
    if not motions_compiled(model):
        return None
    fields = model._core._fields
    out = np.empty((count, 3))
    motions_kernel.motion_values_into(fields[f"{table}_first"], fields[f"{table}_kinds"],
                                      fields[f"{table}_starts"], fields[f"{table}_params"],
                                      float(t), out)
    return out if np.all(np.isfinite(out)) else None


def motions_compiled(model) -> bool:
    """Whether the compiled core's tables hold the model's motions: none is a Python
    function and the model is not a copy with motions of its own."""
    core = model._core
    return not core.python_parts and (core.motions[0] is model.driver_motions
                                      and core.motions[1] is model.rotation_motions)


def _motion_values(motions, names, t: float) -> np.ndarray:
    """``(f, f', f'')`` of ``motions`` at ``t``, (k, 3), checked to be finite."""
    out = np.empty((len(motions), 3))
    for k, motion in enumerate(motions):
        try:
            out[k] = motion.evaluate(t)
        except (TypeError, ValueError) as exc:
            raise ModelError(f"driver '{names[k]}': its motion failed at t = {t:g} s: {exc}") from exc
        if not np.all(np.isfinite(out[k])):
            raise ModelError(f"driver '{names[k]}': its motion returned a non-finite value "
                             f"(f, f', f'') = {tuple(out[k])} at t = {t:g} s")
    return out


def motion_phases(model, t: float) -> np.ndarray:
    """``(f, f', f'')`` of the motions of rows whose time dependence sits inside the primitive
    (spatial rotation drivers), (k, 3)."""
    if not model.rotation_motions:
        return _NO_MOTIONS
    values = _compiled_motions(model, "rotation", len(model.rotation_motions), t)
    if values is None:
        values = _motion_values(model.rotation_motions, model.rotation_motion_names, t)
    return values


_NO_MOTIONS = np.zeros((0, 3))


def has_branches(model) -> bool:
    """Whether the model has rows of the form ``L sin(e)`` (see :func:`branch_cosines`)."""
    return any(g.cls.kind in ("rotation", "gear", "gear_mesh") for g in model.groups)


def branch_cosines(model, t: float, fr: Frames) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows of the form ``L sin(e)``, with ``cos(e)`` and ``L`` on each: they vanish half a
    turn of ``e`` away too, where the cosine is -1.

    The spatial rotation drivers' rows are ``sin(theta - f)`` (``L = 1``; see
    :class:`mbd3d.model.primitives.Rotation`); the planar gear pairs' are
    ``|d| sin(psi - phi)`` (see :class:`mbd3d.model.primitives.Gear`), the spatial ones'
    ``size sin(Phi)`` (see :class:`mbd3d.model.primitives.GearMesh`); evaluated by
    :func:`mbd3d.numerics.compiled.kinematics.branch_cosines_into`.
    """
    table = model.row_table
    s = fr.vectors(table.vector_bodies, table.vector_local, False)[0]
    cosine, amplitude = np.empty(model.n_constraints), np.empty(model.n_constraints)
    kinematics_kernel.branch_cosines_into(table.code, table.bi, table.bj, table.first_row,
                                          table.slots, table.motion, table.real,
                                          motion_phases(model, t), fr.Q, s, cosine, amplitude)
    rows = np.flatnonzero(amplitude > 0.0)
    return rows, cosine[rows], amplitude[rows]


def require_holonomic(model, what: str) -> None:
    """Refuse models with velocity-level (nonholonomic) rows for analyses that need the
    positions to follow from the constraints, naming the joints."""
    if not len(model.velocity_rows):
        return
    joints = model.joints_of_rows(model.velocity_rows)
    raise ModelError(
        f"{what} needs positions that the constraints fix, but in '{model.name}' "
        f"{', '.join(repr(j) for j in joints)} constrain{'s' if len(joints) == 1 else ''} "
        "velocities only (nonholonomic: a disc rolling on a plane reaches any position by "
        "rolling); forward dynamics with an explicit method (method='DOP853', 'RK45' or "
        "'RK23') integrates its motion; static equilibrium, modes and mb.linearize take it")


def has_spatial_meshes(model) -> bool:
    """Whether the model has spatial gear meshes (see :func:`mesh_turn_speed`)."""
    return any(g.cls.kind == "gear_mesh" for g in model.groups)


def mesh_turn_speed(model, q: np.ndarray, qd: np.ndarray, charts=None) -> float:
    """The largest rate [rad/s] at which a spatial gear mesh's phase terms change (see
    :func:`mbd3d.numerics.compiled.rows.mesh_turn_speeds`) at ``(q, qd)``; zero without
    spatial gears. Position analysis from a guess that errs by less than the change since a
    solved state cannot skip a tooth while ``speed * step < pi``."""
    if not has_spatial_meshes(model):
        return 0.0
    fr = frames(model, q, qd, charts)
    table = model.row_table
    s, _, v, a = fr.vectors(table.vector_bodies, table.vector_local, True)
    return float(np.max(rows_kernel.mesh_turn_speeds(table.code, table.bi, table.bj,
                                                     table.slots, table.real, fr.Q, fr.Qd,
                                                     s, v, a)))


def evaluate(model, t: float, fr: Frames, value: bool = True, jacobian: bool = True,
             gamma: bool = False, rate: bool = False
             ) -> tuple[np.ndarray | None, np.ndarray | None, np.ndarray | None]:
    """``C``, the Jacobian values in the model's pattern, and ``Qd``, in one compiled pass over
    all primitive instances (:func:`mbd3d.model.primitives.evaluate_rows`).

    Returns ``(C (m,), jac_data (nnz,), Qd (m,))`` with ``None`` for the parts not asked for,
    and with ``rate`` a fourth part, ``-Ct`` (m,); turn ``jac_data`` into a matrix with
    :func:`jacobian_matrix`.
    """
    C, data, Qd, nu = evaluate_rows(model.row_table, fr, motion_phases(model, t), value,
                                    jacobian, gamma, rate, model._jac_destination,
                                    len(model._jac_take))
    if (value or gamma or rate) and len(model.driver_rows):
        f = driver_values(model, t)
        if value:
            C[model.driver_rows] -= f[0]
        if gamma:
            Qd[model.driver_rows] += f[2]
        if rate:
            nu[model.driver_rows] = f[1]
    if value:
        C -= model.c0
    return (C, data, Qd, nu) if rate else (C, data, Qd)


def jacobian_matrix(model, data: np.ndarray, sparse: bool | None = None):
    """``Cq`` (m, n) from its values in the model's pattern: ndarray, or CSR when sparse."""
    shape = (model.n_constraints, model.n_coordinates)
    if model.sparse if sparse is None else sparse:
        return sp.csr_matrix((data, model._jac_cols, model._jac_indptr), shape=shape)
    Cq = np.zeros(shape)
    Cq[model._jac_rows, model._jac_cols] = data
    return Cq


def jacobian_times(model, data: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``Cq x`` from the Jacobian values, without assembling the matrix."""
    return np.bincount(model._jac_rows, weights=data * x[model._jac_cols],
                       minlength=model.n_constraints)


def jacobian_transpose_times(model, data: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``Cq^T y`` from the Jacobian values, without assembling the matrix."""
    return np.bincount(model._jac_cols, weights=data * y[model._jac_rows],
                       minlength=model.n_coordinates)


def residual(model, t: float, q: np.ndarray, fr: Frames | None = None) -> np.ndarray:
    """Constraint residual ``C(q, t)``, shape (m,) [m or rad per row]."""
    return evaluate(model, t, frames(model, q) if fr is None else fr, True, False)[0]


#: kinematic analyses factor ``Cq`` (n x n) densely up to this many coordinates: LAPACK's LU
#: of a 36 x 36 Jacobian (a six-joint robot) takes microseconds where SciPy's sparse matrices
#: and SuperLU cost a millisecond in overheads alone (benchmarks/kinematics.py)
KINEMATIC_DENSE_LIMIT = 100


def kinematic_sparse(model) -> bool:
    """Whether the position, velocity and acceleration analyses of ``model`` factor its
    Jacobian as a sparse matrix (:data:`KINEMATIC_DENSE_LIMIT`)."""
    return model.sparse and model.n_coordinates > KINEMATIC_DENSE_LIMIT


def jacobian(model, t: float, q: np.ndarray, fr: Frames | None = None,
             sparse: bool | None = None):
    """Constraint Jacobian ``Cq`` at time ``t`` [s] (rotation drivers' rows depend on it),
    shape (m, n): ndarray, or CSR matrix when sparse."""
    data = evaluate(model, t, frames(model, q) if fr is None else fr, False, True)[1]
    return jacobian_matrix(model, data, sparse)


def velocity_rhs(model, t: float, fr: Frames | None = None) -> np.ndarray:
    """Right-hand side ``-Ct`` of ``Cq qd = -Ct``: ``f'(t)`` on driven rows, zero elsewhere.

    Rows whose time dependence sits inside the primitive (spatial rotation drivers) need the
    configuration ``fr``.
    """
    if not model.rotation_motions:
        nu = np.zeros(model.n_constraints)
        if len(model.driver_rows):
            nu[model.driver_rows] = driver_values(model, t)[1]
        return nu
    if fr is None:
        raise ValueError("velocity_rhs needs the configuration (fr) for this model")
    return evaluate(model, t, fr, value=False, jacobian=False, rate=True)[3]


def acceleration_rhs(model, t: float, q: np.ndarray, qd: np.ndarray,
                     fr: Frames | None = None) -> np.ndarray:
    """Right-hand side ``Qd = -(Cq qd)_q qd - 2 Cqt qd - Ctt`` of ``Cq qdd = Qd``."""
    fr = frames(model, q, qd) if fr is None else fr
    return evaluate(model, t, fr, False, False, True)[2]
