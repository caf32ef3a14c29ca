"""The inputs and outputs of a linearisation (see :mod:`.linearization`): which forces or
drivers ``u`` is, what ``y`` reads, and ``B`` and ``D``."""

from __future__ import annotations

from typing import Any, Callable, Mapping

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.io.results import Results
from mbd3d.model import constraints
from mbd3d.model.forces import PointForce, Torque
from mbd3d.numerics.compiled import forces as force_kernel

__all__ = ["STEP", "Output", "released_drivers", "outputs_of", "input_matrices"]

#: relative step of the central differences: eps^(1/3) balances truncation and rounding
STEP = float(np.finfo(float).eps) ** (1.0 / 3.0)

Output = str | Callable[[Results], Any]


def released_drivers(model, inputs) -> list[str]:
    """The drivers named as inputs: their effort is the input, their motion is released."""
    drivers = {element.name for element in model.joints if element.is_driver}
    return [spec for spec in inputs if spec in drivers]


def outputs_of(model, outputs, states, what):
    """Output names and specs: ``(index in q, is_rate)`` or a callable (None: the states)."""
    if outputs is None:
        return list(states), None
    items = list(outputs.items()) if isinstance(outputs, Mapping) else [(o, o) for o in outputs]
    names, specs = [], []
    for name, spec in items:
        if isinstance(spec, str):
            label, rate = (spec[:-4], True) if spec.endswith("_dot") else (spec, False)
            try:
                specs.append((model.coordinate_index(label), rate))
            except ModelError as exc:
                raise ModelError(f"{what}: output {spec!r}: {exc} (or a callable of the "
                                 "results)") from None
        elif callable(spec):
            specs.append(spec)
        else:
            raise ModelError(f"{what}: output {name!r} must be a coordinate's name or a "
                             f"callable of the results, got {spec!r}")
        names.append(name if isinstance(name, str) else getattr(name, "__name__", "output"))
    return names, specs


def input_matrices(system, sampler, q, qd, Cq, inputs, k, rates_of, n_outputs, what):
    """``B`` (k + k_v, p) and ``D`` (r, p): each input's generalized force through the
    augmented equations (linear in it: exact) on the rates of the velocity measures
    ``rates_of`` (k_v, the states after the ``k`` displacements), and the outputs' response
    by central differences."""
    model = system.model
    B = np.zeros((k + len(rates_of), len(inputs)))
    D = np.zeros((n_outputs, len(inputs)))
    M, Ca, Q, Qd, _ = system.augmented(q, qd)
    qdd0, lam0_active = system.solve(M, Ca, Q, Qd)
    lam0 = np.empty(model.n_constraints)
    lam0[system.active] = lam0_active
    lam0[system.released_rows] = -system.efforts
    frames = constraints.frames(model, q, qd, system.charts)
    for column, spec in enumerate(inputs):
        if spec in model._joint_by_name:  # a released driver: its effort, along its row
            row = int(model.rows_of(spec)[0])
            Q_u = Cq[row]
        else:
            row, Q_u = None, _unit_force(model, frames, spec, what)
        qdd_u, lam_u_active = system.solve(M, Ca, Q_u, np.zeros(len(system.active)))
        lam_u = np.zeros(model.n_constraints)
        lam_u[system.active] = lam_u_active
        if row is not None:
            lam_u[row] = -1.0  # the released driver's multiplier is minus its effort
        # the velocities' rates are linear in qdd at a fixed state
        B[k:, column] = (sampler.w_rate(q, qd, qdd0 + qdd_u)
                         - sampler.w_rate(q, qd, qdd0))[rates_of]
        if sampler.output_specs is not None and n_outputs:
            h = STEP * max(1.0, float(np.max(np.abs(qdd0), initial=0.0))
                            / max(float(np.max(np.abs(qdd_u))), 1e-300))
            plus = sampler.evaluate(q, qd, qdd0 + h * qdd_u, lam0 + h * lam_u)
            minus = sampler.evaluate(q, qd, qdd0 - h * qdd_u, lam0 - h * lam_u)
            D[:, column] = (plus - minus) / (2 * h)
    return B, D


def _unit_force(model, frames, spec: str, what: str) -> np.ndarray:
    """Generalized force (n,) of a unit value of the input ``spec``."""
    name, _, component = spec.rpartition(".")
    if not name or name not in model._force_by_name:
        name, component = spec, ""
    element = model._force_by_name.get(name)
    if not isinstance(element, (PointForce, Torque)):
        known = [f.name for f in model.forces if isinstance(f, (PointForce, Torque))]
        raise ModelError(f"{what}: input {spec!r} must name a PointForce or Torque of the "
                         f"model and a component ('push.x'); known: {', '.join(known) or 'none'}"
                         " (add one with a zero value to have an input there)")
    planar_torque = isinstance(element, Torque) and model.dim == 2
    axes = "xyz"[:3 if isinstance(element, Torque) else model.dim]
    if planar_torque:
        if component:
            raise ModelError(f"{what}: input {spec!r}: a planar torque has one component; name "
                             f"it '{name}'")
        unit = np.array([0.0, 0.0, 1.0])
    elif component not in tuple(axes):
        raise ModelError(f"{what}: input {spec!r}: name a component of '{name}', one of "
                         f"{', '.join(f'{name}.{a}' for a in axes)}")
    else:
        unit = np.eye(len(axes))[axes.index(component)]
    Q = np.zeros((model.n_bodies + 1, model.n_coords_per_body))
    body = np.array([model.padded_index(element.body)], dtype=np.int64)
    body_frame = np.array([element.frame == "body"], dtype=np.int64)
    if isinstance(element, PointForce):
        point = next(u for group in model.force_groups for e, u, *_ in getattr(group, "items", ())
                     if e is element)
        force_kernel.point_forces_into(frames.A, frames.axes, body, point[None], unit[None],
                                       body_frame, Q)
    else:
        body_frame[0] = body_frame[0] and model.dim == 3
        force_kernel.torques_into(frames.A, frames.axes, body, unit[None], body_frame, Q)
    return Q[:model.n_bodies].ravel()
