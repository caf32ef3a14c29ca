"""The initial state of forward dynamics: in the user's terms, and never changed silently.

Forward dynamics starts from positions and velocities that satisfy the constraints. The
positions are the nearest assembled ones to the guess (Newton-Raphson, least change); the
velocities the mass-weighted nearest to the given ones, ``min (qd - v)^T M (qd - v)`` with
``Cq qd = -Ct``, and with the rates the user asks for kept exactly: ``initial_rates`` names
joints (a revolute's angle rate [rad/s], a prismatic's displacement rate [m/s], as
``results.joint(name).angle_rate`` reads them; ``"name.angle"`` or ``"name.displacement"`` for
a cylindrical joint) or coordinates (``"crank.theta"``), each a row ``H qd = value`` beside the
constraints.

Given velocities that violate the constraints are changed by that projection: which
coordinates, from what to what, is reported in ``results.stats["initial_state"]`` and by an
:class:`InitialStateWarning` (an error with ``strict=True``), so that a crank given 6 rad/s
with the other bodies at rest does not start at 0.36 rad/s without a word.
"""

from __future__ import annotations

import warnings
from typing import Mapping

import numpy as np

from mbd3d.errors import ModelError, user_stacklevel
from mbd3d.model import constraints
from mbd3d.model.equations import mass_matrix
from mbd3d.numerics.linalg import SingularMatrix, augmented_scaling, solve_augmented

__all__ = ["InitialStateWarning", "consistent_initial_state", "rate_rows", "keep_rates",
           "report_changes"]


class InitialStateWarning(UserWarning):
    """The initial state given to forward dynamics violated the constraints and was changed."""


def consistent_initial_state(model, t0: float, q0, qd0, *, hold, initial_rates, strict: bool,
                             tol: float, chart, stats: dict, what: str, redundant_rows,
                             initial_positions=None) -> tuple[np.ndarray, np.ndarray, bool]:
    """``(q, qd, redundant)`` to start forward dynamics from (see the module doc):
    ``redundant_rows(q)`` says whether the constraint rows depend on each other there."""
    from mbd3d.analyses.kinematics import initial_guess, solve_velocity  # noqa: PLC0415
    from mbd3d.analyses.position import solve_position  # noqa: PLC0415

    guess = initial_guess(model, t0, q0, chart, what, "q0")
    q = solve_position(model, guess, t0, tol=tol * 1e-3, hold=hold, charts=chart)
    if initial_positions:
        q = place_joints(model, t0, q, chart, initial_positions, tol * 1e-3, what)
    redundant = redundant_rows(q)
    given = given_rates(model, qd0)
    if qd0 is None:
        qd_given = model.qd0.copy()
    else:
        qd_given = np.asarray(qd0, dtype=float).reshape(-1)
        if qd_given.size != model.n_coordinates or not np.all(np.isfinite(qd_given)):
            raise ModelError(f"{what}: qd0 must be {model.n_coordinates} finite numbers")
    if initial_rates:
        qd = keep_rates(model, t0, q, qd_given, chart, initial_rates, what)
    else:
        qd = solve_velocity(model, q, t0, qd_guess=qd_given, hold=hold, charts=chart,
                            redundant=redundant)
    report_changes(model, stats, guess, q, qd_given, qd, tol, strict, what,
                   positions_given=q0 is not None, rates_given=given, chart=chart)
    return q, qd, redundant


def place_joints(model, t: float, q: np.ndarray, chart, positions: Mapping[str, float],
                 tol: float, what: str) -> np.ndarray:
    """The assembled configuration nearest ``q`` (least change) in which the joints and
    coordinates named in ``positions`` have those values: a revolute's angle [rad] and a
    prismatic's displacement [m] as ``results.joint(name)`` reads them,
    ``"name.angle"``/``"name.displacement"`` of a cylindrical joint, ``"body.coordinate"``.

    Newton's method on the constraints and ``p(q) = value``, whose rows are the joint
    coordinates' rates (:func:`rate_rows`: ``dp/dq`` is the row that gives ``p'`` from
    ``q'``). A planar angle is a coordinate, reached with its turns; a spatial one is read
    within half a turn, so a target of several turns gives the same configuration. Spatial
    bodies' charts move as they turn past the chart limit during the iteration, as the
    integrators move them (a pose near a half turn from the drawing, such as a robot's wrist
    turned by two parallel joints, left Newton converging linearly towards the Rodrigues
    parameters' singularity), and the result is given in the caller's ``chart``.
    """
    from mbd3d.errors import AssemblyError  # noqa: PLC0415
    from mbd3d.io.results import Results  # noqa: PLC0415

    names = list(positions)
    targets = np.array([float(positions[name]) for name in names])
    if not np.all(np.isfinite(targets)):
        raise ModelError(f"{what}: initial_positions must be finite numbers, got {positions}")
    angular = np.zeros(len(names), dtype=bool)
    q = np.array(q, dtype=float)
    work = None if chart is None else np.array(chart, dtype=float)  # the iteration's charts
    for _ in range(50):
        H, _, _ = rate_rows(model, t, q, work, {name: 1.0 for name in names}, what,
                            "initial_positions")
        sample = Results(model, "positions", np.array([t]), q[None], np.zeros((1, len(q))),
                         np.zeros((1, len(q))), charts=None if work is None else work[None])
        values = np.empty(len(names))
        for k, name in enumerate(names):
            values[k], angular[k] = _coordinate_value(model, sample, q, name)
        error = values - targets
        if model.dim == 3:
            # a spatial angle is read within half a turn: no turn count to reach
            error[angular] = np.angle(np.exp(1j * error[angular]))
        fr = constraints.frames(model, q, charts=work)
        C, jac_data, _ = constraints.evaluate(model, t, fr)
        Cq = constraints.jacobian_matrix(model, jac_data, sparse=False)
        largest = max(constraints.largest_relative(model, C),
                      float(np.max(np.abs(error) / np.where(angular, 1.0, model.length_scale),
                                   initial=0.0)))
        if largest <= tol:
            return q if work is None else _in_charts(model, q, work, chart, what)
        step = np.linalg.lstsq(np.vstack([Cq, H]), -np.concatenate([C, error]), rcond=None)[0]
        q = q + step
        if work is not None:
            q, _, work, _ = model.body_type.reset_charts(q, None, work)
    raise AssemblyError(f"{what}: the mechanism cannot be assembled with "
                        f"{', '.join(f'{n} = {v:g}' for n, v in zip(names, targets))} (the "
                        "joints cannot reach them together, or they over-determine the "
                        "positions)", time=t)


def _in_charts(model, q: np.ndarray, charts: np.ndarray, target: np.ndarray, what: str
               ) -> np.ndarray:
    """Spatial ``q`` in ``charts`` given in the charts ``target`` instead: each body's
    rotation ``A = A0 A(g)`` kept; refused for a body a half turn from its target chart,
    where no Rodrigues parameters give it."""
    from mbd3d.errors import AssemblyError  # noqa: PLC0415
    from mbd3d.numerics.rotations import from_rodrigues, to_rodrigues  # noqa: PLC0415

    nb = model.n_bodies
    out = np.array(q, dtype=float)
    g = out.reshape(nb, 6)[:, 3:]  # a view into out
    rotation = charts[:nb] @ from_rodrigues(g)
    g[:] = to_rodrigues(np.swapaxes(target[:nb], 1, 2) @ rotation)
    far = ~np.all(np.abs(g) < 1e8, axis=1)
    if np.any(far):
        raise AssemblyError(f"{what}: initial_positions turn "
                            f"{', '.join(model.bodies[k].name for k in np.flatnonzero(far))} "
                            "a half turn from the model's drawing, which its coordinates "
                            "cannot start from: draw the model nearer that pose (or give "
                            "positions a little apart from it)")
    return out


def _coordinate_value(model, sample, q: np.ndarray, name: str) -> tuple[float, bool]:
    """The value of a joint coordinate or ``"body.coordinate"`` at the one-sample results,
    and whether it is an angle."""
    body, _, coordinate = name.rpartition(".")
    if body in {b.name for b in model.bodies} and coordinate in model.body_type.coordinate_names:
        index = model.coordinate_index(name)
        return float(q[index]), model.dim == 2 and coordinate == "theta"
    joint, kind = (body, coordinate) if coordinate in ("angle", "displacement") else (name, None)
    history = sample.joint(joint)
    if kind == "angle" or (kind is None and _has_angle(history)):
        return float(history.angle[0]), True
    return float(history.displacement[0]), False


def _has_angle(history) -> bool:
    try:
        history.angle
    except ModelError:
        return False
    return True


def given_rates(model, qd0) -> np.ndarray:
    """Which coordinates' rates the user gave: all with ``qd0``, else those of the bodies
    given a ``velocity`` or an ``angular_velocity``."""
    n = model.n_coordinates
    if qd0 is not None:
        return np.ones(n, dtype=bool)
    given = np.zeros(n, dtype=bool)
    dim = model.dim
    for body in model.bodies:
        where = model.coordinates_of(body)
        if "velocity" in body.arguments:
            given[where.start:where.start + dim] = True
        if "angular_velocity" in body.arguments:
            given[where.start + dim:where.stop] = True
    return given


def rate_rows(model, t: float, q: np.ndarray, chart, rates: Mapping[str, float], what: str,
              argument: str = "initial_rates") -> tuple[np.ndarray, np.ndarray, list[str]]:
    """``(H (r, n), values (r,), labels)``: each asked rate as a row linear in ``qd``
    (``argument``: the user's argument that named them, for the messages)."""
    from mbd3d.io.results import Results  # noqa: PLC0415

    n = model.n_coordinates
    rows, values, labels = [], [], []
    # every joint rate is linear in qd at fixed q: one sample per unit rate gives its row
    unit = None
    for name, value in rates.items():
        if not np.isfinite(value):
            raise ModelError(f"{what}: {argument}['{name}'] must be a finite number")
        body, _, coordinate = name.rpartition(".")
        if body in {b.name for b in model.bodies} and coordinate in \
                model.body_type.coordinate_names:
            row = np.zeros(n)
            row[model.coordinate_index(name)] = 1.0
        else:
            joint, kind = (body, coordinate) if coordinate in ("angle", "displacement") \
                else (name, None)
            if joint not in {e.name for e in model.joints}:
                raise ModelError(f"{what}: {argument} names '{name}', neither a joint nor a "
                                 "coordinate ('body.coordinate'); joints: "
                                 f"{', '.join(e.name for e in model.joints)}")
            if unit is None:
                charts = None if chart is None else np.broadcast_to(chart, (n,) + chart.shape)
                unit = Results(model, "rates", np.full(n, t), np.broadcast_to(q, (n, n)),
                               np.eye(n), np.zeros((n, n)), charts=charts)
            history = unit.joint(joint)
            try:
                row = (history.displacement_rate if kind == "displacement" else
                       history.angle_rate if kind == "angle" else _single_rate(history))
            except ModelError as exc:
                raise ModelError(f"{what}: {argument}['{name}']: {exc}") from None
        rows.append(np.array(row, dtype=float))
        values.append(float(value))
        labels.append(name)
    return np.array(rows).reshape(len(rows), n), np.array(values), labels


def _single_rate(history) -> np.ndarray:
    """A revolute's angle rate or a prismatic's displacement rate (a cylindrical has both)."""
    from mbd3d.joints import Cylindrical  # noqa: PLC0415

    source = getattr(history.element, "joint", None) or history.element
    if isinstance(source, Cylindrical):
        raise ModelError(f"'{history.name}' is cylindrical: name '{history.name}.angle' or "
                         f"'{history.name}.displacement'")
    try:
        return history.angle_rate
    except ModelError:
        return history.displacement_rate


def keep_rates(model, t: float, q: np.ndarray, qd_guess: np.ndarray, chart,
               rates: Mapping[str, float], what: str) -> np.ndarray:
    """The mass-weighted nearest consistent velocities to ``qd_guess`` that have the asked
    rates exactly."""
    H, values, labels = rate_rows(model, t, q, chart, rates, what)
    fr = constraints.frames(model, q, charts=chart)
    jac_data = constraints.evaluate(model, t, fr, value=False)[1]
    Cq = constraints.jacobian_matrix(model, jac_data, sparse=False)
    nu = constraints.velocity_rhs(model, t, fr)
    M = mass_matrix(model, fr, sparse=False)
    rows = np.vstack([Cq, H])
    # the rate rows in the units of the coordinates they act on
    scale = augmented_scaling(model)
    size = np.sqrt(model.mass_scale) * model.length_scale
    row_scale = np.abs(H) @ model.coordinate_scale / np.maximum(np.abs(H).sum(axis=1), 1e-300)
    scaling = np.concatenate([scale, size / np.maximum(row_scale, 1e-300)])
    try:
        qd, _ = solve_augmented(M, rows, M @ qd_guess, np.concatenate([nu, values]), scaling)
    except SingularMatrix:
        raise ModelError(f"{what}: the initial rates {', '.join(labels)} cannot all be given: "
                         "with the joints and drivers they over-determine the velocities (a "
                         "driven joint's rate is its motion's; a mechanism with k degrees of "
                         "freedom takes at most k rates)") from None
    if not np.allclose(rows @ qd, np.concatenate([nu, values]), rtol=1e-9,
                       atol=1e-9 * max(1.0, float(np.max(np.abs(values), initial=0.0)))):
        raise ModelError(f"{what}: the initial rates {', '.join(labels)} contradict the "
                         "constraints (the velocities cannot have them together)")
    return qd


def report_changes(model, stats: dict, q_given, q: np.ndarray, qd_given: np.ndarray,
                   qd: np.ndarray, tol: float, strict: bool, what: str,
                   positions_given: bool, rates_given: np.ndarray, chart=None) -> None:
    """Record in ``stats["initial_state"]`` the coordinates the consistent initial state
    changed by more than ``tol`` of their scales (rates: of the largest rate's scale), and
    warn of (or refuse, with ``strict``) those the user gave: positions passed as ``q0``,
    rates as ``qd0`` or the bodies' velocities (a driver's rate, or a guess, is no change)."""
    labels = model.coordinate_labels
    scale = model.coordinate_scale
    report = {"positions": {}, "velocities": {}}
    dq = (q - q_given) / scale
    for k in np.flatnonzero(np.abs(dq) > tol):
        report["positions"][labels[k]] = (float(q_given[k]), float(q[k]))
    # rates as the user gives them: centre velocities and angular velocities (global axes)
    rate_labels, given_rates, used_rates = _physical_rates(model, q_given, qd_given, q, qd,
                                                           chart)
    rate_scale = max(float(np.max(np.abs(given_rates) / scale, initial=0.0)),
                     float(np.max(np.abs(used_rates) / scale, initial=0.0)), 1e-300)
    drate = (used_rates - given_rates) / scale / rate_scale
    for k in np.flatnonzero(np.abs(drate) > tol):
        report["velocities"][rate_labels[k]] = (float(given_rates[k]), float(used_rates[k]))
    stats["initial_state"] = report
    changed = {k: v for k, v in report["velocities"].items()
               if rates_given[rate_labels.index(k)]}
    if positions_given:
        changed.update({f"{k} (position)": v for k, v in report["positions"].items()})
    if not changed:
        return
    order = sorted(changed, key=lambda k: -abs(changed[k][1] - changed[k][0]))
    listed = ", ".join(f"{k} {changed[k][0]:.6g} -> {changed[k][1]:.6g}" for k in order[:5])
    more = f" and {len(order) - 5} more" if len(order) > 5 else ""
    message = (f"{what}: the initial state violates the constraints; the consistent one used "
               f"changes {listed}{more} (results.stats['initial_state'] has them all). To keep "
               "chosen rates, give them with initial_rates={'joint': rate} (or "
               "'body.coordinate'); strict=True makes this an error.")
    if strict:
        raise ModelError(message)
    warnings.warn(message, InitialStateWarning, stacklevel=user_stacklevel())


def _physical_rates(model, q_given, qd_given, q, qd, chart):
    """``(labels, given, used)`` (n,): per body its centre's velocity [m/s] and its angular
    velocity [rad/s] (planar: about the normal; spatial: global axes, as ``add_body`` takes
    them), of the given state and of the one used."""
    dim = model.dim
    names = ("vx", "vy", "vz")[:dim] + (("omega",) if dim == 2 else
                                         ("omega_x", "omega_y", "omega_z"))
    labels = [f"{body.name}.{name}" for body in model.bodies for name in names]
    if dim == 2:
        return labels, qd_given, qd
    out = []
    for qq, rates in ((q_given, qd_given), (q, qd)):
        fr = constraints.frames(model, qq, rates, chart)
        R_dot = np.reshape(rates, (model.n_bodies, 6))[:, :3]
        out.append(np.column_stack([R_dot, fr.omega[:model.n_bodies]]).ravel())
    return labels, out[0], out[1]
