"""Quantities of many states at once: constraint residuals and energies over a time history.

The solvers evaluate one state at a time; post-processing a run (results, plots, recordings)
needs the same quantities at thousands of time points. Here the states are stacked as if they
were the bodies of one large model (``k`` copies of the bodies plus the ground), so the
constraint rows are evaluated by one compiled call per chunk of time points.
"""

from __future__ import annotations

import numpy as np

from mbd3d.model.body import Frames
from mbd3d.model.constraints import driver_values, motion_phases
from mbd3d.model.primitives import evaluate_rows
from mbd3d.numerics.compiled.contacts import REPORT_COLUMNS

__all__ = ["residuals", "energies", "contact_history"]

#: body rows evaluated per chunk: bounds the memory of a 1000-body model over a long run
CHUNK_ROWS = 20_000


def _chunks(model, k: int):
    size = max(1, CHUNK_ROWS // (model.n_bodies + 1))
    for start in range(0, k, size):
        yield slice(start, min(k, start + size))


def _stacked_frames(model, q: np.ndarray, qd: np.ndarray, charts: np.ndarray | None,
                    ground: bool) -> Frames:
    """Frames of ``k`` states stacked time-major: rows ``t * rows + b``, with the ground as the
    last body of every state when ``ground``."""
    k = len(q)
    nb, nc = model.n_bodies, model.n_coords_per_body
    rows = nb + 1 if ground else nb
    Q = np.zeros((k, rows, nc))
    Qd = np.zeros((k, rows, nc))
    Q[:, :nb] = q.reshape(k, nb, nc)
    Qd[:, :nb] = qd.reshape(k, nb, nc)
    C = None
    if model.charts0 is not None:
        C = np.broadcast_to(model.charts0, (k,) + model.charts0.shape) if charts is None else charts
        C = np.ascontiguousarray(C[:, :rows]).reshape(k * rows, 3, 3)
    return model.body_type.frames(Q.reshape(k * rows, nc), Qd.reshape(k * rows, nc), C)


def residuals(model, t: np.ndarray, q: np.ndarray, qd: np.ndarray,
              charts: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``max |C|`` and ``max |Cq qd + Ct|`` at each of ``k`` states.

    Parameters
    ----------
    model : Model
    t : (k,) ndarray
        Times [s].
    q, qd : (k, n) ndarray
        Coordinates and rates.
    charts : (k, n_bodies + 1, 3, 3) ndarray, optional
        Spatial models: the reference rotations of each state (default the model's initial ones).

    Returns
    -------
    position, velocity : (k,) ndarray
        Largest position [m or rad] and velocity [m/s or rad/s] residual of each state.
    """
    k = len(t)
    position, velocity = np.zeros(k), np.zeros(k)
    for part in _chunks(model, k):
        cp = None if charts is None else charts[part]
        position[part], velocity[part] = _residual_chunk(model, t[part], q[part], qd[part], cp)
    return position, velocity


def _residual_chunk(model, t, q, qd, charts):
    k, m = len(t), model.n_constraints
    if m == 0:
        return np.zeros(k), np.zeros(k)
    fr = _stacked_frames(model, q, qd, charts, ground=True)
    n_motions = len(model.rotation_motions)
    table = model.row_table.repeated(k, model.n_bodies + 1, n_motions)
    phi = (np.concatenate([motion_phases(model, tk) for tk in t]) if n_motions
           else np.zeros((0, 3)))
    c, J, _, nu = evaluate_rows(table, fr, phi, True, True, False, rate=True)
    bi, bj = table.row_bodies()
    v = (np.einsum("rn,rn->r", J[:, 0], fr.Qd[bi]) + np.einsum("rn,rn->r", J[:, 1], fr.Qd[bj])
         - nu)
    C = c.reshape(k, m)
    V = v.reshape(k, m)
    if len(model.driver_rows):
        f = np.stack([driver_values(model, tk) for tk in t])  # (k, 3, n_drivers)
        C[:, model.driver_rows] -= f[:, 0]
        V[:, model.driver_rows] -= f[:, 1]
    C -= model.c0
    return np.max(np.abs(C), axis=1), np.max(np.abs(V), axis=1)


def energies(model, q: np.ndarray, qd: np.ndarray, charts: np.ndarray | None = None
             ) -> tuple[np.ndarray, np.ndarray]:
    """Kinetic and potential energy [J] at each of ``k`` states ``(q, qd)`` (k, n).

    The potential energy is that of gravity (zero at the global origin) and of springs.
    """
    from mbd3d.model.equations import potential_energy
    from mbd3d.model.forces import _CompiledForces

    k, nb, nc = len(q), model.n_bodies, model.n_coords_per_body
    kinetic = np.empty(k)
    for part in _chunks(model, k):
        cp = None if charts is None else charts[part]
        kp = part.stop - part.start
        fr = _stacked_frames(model, q[part], qd[part], cp, ground=False)
        inertia = np.tile(model.inertia, (kp,) + (1,) * (model.inertia.ndim - 1))
        blocks = model.body_type.mass_blocks(fr, np.tile(model.mass, kp), inertia)
        v = qd[part].reshape(kp * nb, nc)
        kinetic[part] = 0.5 * np.einsum("ri,rij,rj->r", v, blocks, v).reshape(kp, nb).sum(axis=1)
    if any(type(g).potential is not _CompiledForces.potential for g in model.force_groups):
        # springs store energy: one state at a time (force groups are not stacked over time)
        potential = np.array([potential_energy(model, q[j], None if charts is None else charts[j])
                              for j in range(k)])
    else:
        R = q.reshape(k, nb, nc)[:, :, :model.dim]
        potential = -np.einsum("b,kbd,d->k", model.mass, R, model.gravity)
    return kinetic, potential


def contact_history(model, q: np.ndarray, qd: np.ndarray, charts: np.ndarray | None = None):
    """:class:`~mbd3d.model.contacts.ContactStates` of every contact and joint stop at each
    of ``k`` states ``(q, qd)`` (k, n), each array with a leading axis ``k``; one compiled
    call per chunk of states."""
    from mbd3d.model.contacts import contact_group, states_of

    group = contact_group(model)
    k = len(q)
    r = len(group.names)
    report = np.empty((k * r, REPORT_COLUMNS))
    for part in _chunks(model, k):
        cp = None if charts is None else charts[part]
        fr = _stacked_frames(model, q[part], qd[part], cp, ground=True)
        report[part.start * r:part.stop * r] = group.states(model, fr, part.stop - part.start)
    return states_of(group, report, k)
