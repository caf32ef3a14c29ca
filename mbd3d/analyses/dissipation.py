"""The energy the compliant contacts and joint stops of a model dissipate over a forward
dynamics run, per contact row [J]: the integral of the power each dissipates (its damper's,
its force clipped at zero, its friction's;
:func:`~mbd3d.numerics.compiled.contact_laws.dissipated_power`).

The explicit methods integrate it in their compiled loop as they would the energy as a
state of its own: by their weights on the stages' powers
(:func:`mbd3d.numerics.compiled.integration.dissipate`), with their error control on it and
their dense output between step ends; each row's penetration is a switching function, so
that a step ends where a law clipped at zero stops unloading its spring (the power's kink).
Generalized-alpha takes the trapezoidal rule on its steps' ends, of its own order, and the
cubic Hermite interpolant between them. With the kinetic and potential energy (the
contacts' springs included) and the impacts' losses, the balance
:meth:`mbd3d.Results.energy_balance` closes to the integrator's tolerance.
"""

from __future__ import annotations

import numpy as np

from mbd3d.model import constraints
from mbd3d.model.contacts import contact_group
from mbd3d.numerics.compiled.contact_steps import trapezoid_step
from mbd3d.numerics.compiled.contacts import DISSIPATION

__all__ = ["contact_power", "dissipation_controls", "hermite", "TrapezoidalDissipation"]


def contact_power(model, q: np.ndarray, qd: np.ndarray, charts=None) -> np.ndarray:
    """The power [W] each contact row of ``model`` dissipates at ``(q, qd)`` (empty without
    contacts)."""
    group = contact_group(model, required=False)
    if group is None:
        return np.zeros(0)
    return group.states(model, constraints.frames(model, q, qd, charts))[:, DISSIPATION]


def dissipation_controls(model, atol: float) -> np.ndarray:
    """Per contact row, how the explicit methods control the error of its dissipated energy
    (:func:`mbd3d.numerics.compiled.integration.dissipation_error`): the absolute tolerance
    [J], ``atol`` of the model's energy scale (its mass at the speed of a length per second
    and raised by its length against gravity); and 1 where the row's power jumps at a touch
    (a damping ``D delta^0``, neither ramped nor growing from zero), else 0."""
    group = contact_group(model)
    L = model.length_scale
    energy = float(np.sum(model.mass)) * (float(np.linalg.norm(model.gravity)) * L + L * L)
    values = group.table(model)["contact_values"]
    jumps = (values[:, 5] > 0.0) & (values[:, 6] == 0.0) & (values[:, 9] == 0.0)
    return np.stack([np.full(len(values), atol * energy), jumps.astype(float)])


def hermite(t: float, t_old: float, step: float, z: np.ndarray) -> np.ndarray:
    """The energies at ``t`` in the step ``[t_old, t_old + step]`` from ``z`` (rows: the
    energies at its end and start, the powers at its end and start): the cubic Hermite
    interpolant, exact at both ends."""
    if step <= 0.0:
        return z[0].copy()
    s = min(max((t - t_old) / step, 0.0), 1.0)
    h00, h10 = (1 + 2 * s) * (1 - s) ** 2, s * (1 - s) ** 2
    h01, h11 = s * s * (3 - 2 * s), s * s * (s - 1)
    return h00 * z[1] + h10 * step * z[3] + h01 * z[0] + h11 * step * z[2]


class TrapezoidalDissipation:
    """The contacts' dissipated energies over generalized-alpha's steps: the trapezoidal rule
    on the powers at the steps' ends (second order, as the method), the cubic Hermite
    interpolant between them; None of it for a model without contacts (:meth:`at`)."""

    def __init__(self, model):
        self.model = model
        group = contact_group(model, required=False)
        self.z = np.zeros((4, 0 if group is None else len(group.names)))
        #: the last step's start and end [s] (the compiled loop steps them on too)
        self.times = np.zeros(2)
        #: the rigid contacts held at rest, whose friction dissipates too (None: none held)
        self.held = None

    def _power(self, t: float, q: np.ndarray, qd: np.ndarray, charts,
               power: np.ndarray | None = None) -> np.ndarray:
        """Every contact row's dissipated power [W] at ``(q, qd)`` (``power``: the compliant
        rows', evaluated there already), a held rigid row's friction's included."""
        power = contact_power(self.model, q, qd, charts) if power is None else power.copy()
        if self.held is not None:
            power[self.held.rigid.rows] += self.held.power(t, q, qd)
        return power

    def restart(self, t: float, q: np.ndarray, qd: np.ndarray, charts) -> None:
        """Go on from the state ``(q, qd)`` at ``t`` (the start, or inside the last step)."""
        z = self.z
        if not z.shape[1]:
            return
        z[0] = self.at(t)
        z[1], z[2] = z[0], self._power(t, q, qd, charts)
        z[3] = z[2]
        self.times[:] = t

    def step(self, t: float, q: np.ndarray, qd: np.ndarray, charts,
             power: np.ndarray | None = None) -> None:
        """The step from the last end to ``t``, ending at ``(q, qd)`` (``power``: the
        contacts' there, if evaluated already)."""
        if self.z.shape[1]:
            trapezoid_step(self.z, self.times, t, self._power(t, q, qd, charts, power))

    def at(self, t: float) -> np.ndarray | None:
        """The energies at ``t`` in the last step, or None without contacts."""
        if not self.z.shape[1]:
            return None
        t_old, t_new = self.times
        return hermite(t, t_old, t_new - t_old, self.z)
