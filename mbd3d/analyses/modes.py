"""Vibration modes of a mechanism about a static equilibrium.

Small motions about an equilibrium ``(q0, lam0)`` stay on the tangent space of the constraints,
``dq = N z`` with ``N`` an orthonormal basis of the null space of ``Cq(q0)``. There

    Mr z'' + Dr z' + Kr z = 0,   Mr = N^T M N,  Dr = N^T D N,  Kr = N^T (K + H) N

with ``K = -dQe/dq`` and ``H = d(Cq^T lam)/dq`` at ``lam0`` (the stiffness of
:mod:`mbd3d.analyses.statics`, which includes gravity's through the constraint forces,
differenced to fourth order: :func:`mbd3d.analyses.statics.accurate_stiffness`) and
``D = -dQe/dqd`` (the dampers; the quadratic velocity forces have no first-order part at
rest). The eigenvalues ``s`` of the first-order form give each mode's natural frequency
``|s| / 2 pi`` [Hz] and damping ratio ``-Re(s) / |s|`` (negative: the equilibrium is unstable
along that mode); its shape is ``N v`` in the coordinates ``q``.

Along a driven motion (:func:`vibration_modes_along`) the same is done at each position of a
grid of times, with the drivers held there: the frozen-position frequencies a designer
compares with the speeds of the machine. They leave out the motion's own velocity terms
(centripetal, gyroscopic), small where the machine runs well below its frequencies; about a
moving state use :func:`mbd3d.linearize`.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Sequence

import numpy as np
import scipy.linalg as la

from mbd3d.analyses.position import solve_position
from mbd3d.analyses.statics import accurate_stiffness, active_rows, static_equilibrium
from mbd3d.errors import ModelError
from mbd3d.io.exports import write_columns
from mbd3d.io.results import Results
from mbd3d.model import constraints
from mbd3d.model.equations import generalized_forces, mass_matrix

__all__ = ["Modes", "ModesAlong", "vibration_modes", "vibration_modes_along", "modes_about"]


@dataclass(frozen=True)
class Modes:
    """Vibration modes about an equilibrium, lowest natural frequency first.

    Attributes
    ----------
    frequencies : ndarray (k,)
        Natural (undamped) frequencies ``|s| / 2 pi`` [Hz]; 0 for a free motion without
        stiffness.
    damping_ratios : ndarray (k,)
        Damping ratios [-] (0 undamped, 1 critically damped; negative where the equilibrium
        is unstable along the mode, and then the "frequency" is its growth rate over 2 pi).
    shapes : ndarray (k, n), complex
        Mode shapes in the coordinates ``q`` (in phase for an undamped mode: real up to a
        common factor), each scaled to a largest entry of 1.
    equilibrium : Results
        The static equilibrium the modes are about (positions, reactions, stability).
    """

    frequencies: np.ndarray
    damping_ratios: np.ndarray
    shapes: np.ndarray
    equilibrium: Results

    def animation(self, mode: int = 0, amplitude: float | None = None, frames: int = 48,
                  cycles: int = 2) -> Results:
        """The mechanism vibrating in one mode, as the results of an analysis (for
        :func:`mbd3d.viewer.record` or plots): ``q = q0 + amplitude Re(shape e^(i w t))``
        over ``cycles`` periods, each position put back on the constraints by Newton's method
        (the shape is tangent to them, so the correction is second order in the amplitude).

        Parameters
        ----------
        mode : int
            Index into ``frequencies`` (0: the lowest).
        amplitude : float, optional
            Multiplies the shape (largest entry 1); default a tenth of the model's length
            for a shape led by a position [m], a tenth of a radian for one led by an angle.
        frames : int
            Time points per period.
        cycles : int
            Periods recorded. A mode without an oscillation (a free or overdamped motion) is
            drawn as a swing of period 1 s along its shape.
        """
        eq = self.equilibrium
        model = eq.model
        if not -len(self.frequencies) <= mode < len(self.frequencies):
            raise ModelError(f"mode {mode}: the model has {len(self.frequencies)} modes here "
                             f"(0 to {len(self.frequencies) - 1})")
        shape = self.shapes[mode]
        if amplitude is None:
            lead = int(np.argmax(np.abs(shape)))
            amplitude = 0.1 * (model.length_scale if model.position_coordinates[lead] else 1.0)
        frequency = float(self.frequencies[mode])
        oscillates = frequency > 0 and abs(self.damping_ratios[mode]) < 1
        period = 1.0 / frequency if oscillates else 1.0
        omega = 2 * np.pi / period
        t = np.linspace(0.0, cycles * period, cycles * frames + 1)
        phase = np.exp(1j * omega * t)[:, None]
        q0, chart = eq.q[0], None if eq.charts is None else eq.charts[0]
        q = q0 + amplitude * (shape[None, :] * phase).real
        for k in range(len(t)):
            q[k] = solve_position(model, q[k], eq.t[0], charts=chart)
        qd = amplitude * (1j * omega * shape[None, :] * phase).real
        qdd = amplitude * (-omega * omega * shape[None, :] * phase).real
        message = (f"mode {mode % len(self.frequencies) + 1} of {len(self.frequencies)}: "
                   f"{frequency:.6g} Hz, damping ratio {self.damping_ratios[mode]:.4g}, "
                   f"shape times {amplitude:.3g}, about the equilibrium at t = {eq.t[0]:g} s "
                   "(the time axis is the vibration's)")
        return Results(model, "vibration mode", t, q, qd, qdd, message=message,
                       charts=None if chart is None else np.broadcast_to(chart, (len(t),)
                                                                          + chart.shape),
                       model_t=np.full(len(t), eq.t[0]))


@dataclass(frozen=True)
class ModesAlong:
    """Vibration modes at each position of a driven motion (see :func:`vibration_modes_along`).

    Attributes
    ----------
    t : ndarray (k,)
        Times [s] of the positions (the drivers' values there).
    frequencies, damping_ratios : ndarray (k, r)
        Per position, lowest frequency first [Hz], [-]; NaN where a position has fewer modes.
    shapes : ndarray (k, r, n), complex
    equilibrium : Results
        The positions (static equilibria with the drivers held), reactions and efforts.
    """

    t: np.ndarray
    frequencies: np.ndarray
    damping_ratios: np.ndarray
    shapes: np.ndarray
    equilibrium: Results

    def columns(self) -> dict[str, np.ndarray]:
        """The frequencies and damping ratios as named columns, ``t [s]``, ``mode 1 f
        [Hz]``, ``mode 1 zeta [-]``, ... (NaN where a position has fewer modes)."""
        cols = {"t [s]": self.t}
        for r in range(self.frequencies.shape[1]):
            cols[f"mode {r + 1} f [Hz]"] = self.frequencies[:, r]
            cols[f"mode {r + 1} zeta [-]"] = self.damping_ratios[:, r]
        return cols

    def to_csv(self, path: str | os.PathLike, overwrite: bool = True) -> str:
        """Write :meth:`columns` to a CSV file (atomically; an existing file is replaced only
        with ``overwrite``); returns its path.

        Parameters
        ----------
        path : str or path-like
            The CSV file.
        overwrite : bool
            Replace ``path`` where it exists.
        """
        return write_columns(self.columns(), path, overwrite)

    def at(self, index: int) -> Modes:
        """The modes at the ``index``-th position (to animate one).

        Parameters
        ----------
        index : int
            A time point of the motion.
        """
        count = int(np.sum(np.isfinite(self.frequencies[index])))
        return Modes(self.frequencies[index, :count], self.damping_ratios[index, :count],
                     self.shapes[index, :count], self.equilibrium.subset(index, index + 1))


def vibration_modes_along(model, times: Sequence[float], q_guess: Sequence[float] | None = None,
                          *, release: Sequence[str] | bool = ()) -> ModesAlong:
    """Natural frequencies, damping ratios and shapes at each position of a driven motion.

    At each time of ``times`` the mechanism rests where its drivers put it (the static
    equilibrium with the drivers held, and those named in ``release`` released), and its
    modes about that position are computed as by :func:`vibration_modes`: the frequencies
    against crank angle that show the speeds to avoid. A mechanism needs compliance (springs,
    or a released driver) to vibrate at all: a fully driven rigid one has no modes.

    Parameters
    ----------
    model : Model
    times : (k,) array_like
        Times [s] of the drivers' motions, increasing.
    q_guess : (n,) array_like, optional
        Guess of the first position (default the drawing); each later one starts from the last.
    release : sequence of str, or bool
        Drivers released (``True``: every one), as for :func:`mbd3d.static_equilibrium`.

    Returns
    -------
    ModesAlong
    """
    rest = static_equilibrium(model, times, q_guess, release=release)
    active = active_rows(model, release)
    found = []
    for k in range(len(rest)):
        chart = None if rest.charts is None else rest.charts[k]
        found.append(modes_about(model, float(rest.t[k]), rest.q[k], rest.lam[k][active],
                                  chart, active))
    width = max((len(f) for f, _, _ in found), default=0)
    n = model.n_coordinates
    frequencies = np.full((len(found), width), np.nan)
    ratios = np.full((len(found), width), np.nan)
    shapes = np.full((len(found), width, n), np.nan, dtype=complex)
    for k, (f, r, s) in enumerate(found):
        frequencies[k, :len(f)], ratios[k, :len(f)], shapes[k, :len(f)] = f, r, s
    return ModesAlong(rest.t, frequencies, ratios, shapes, rest)


def vibration_modes(model, q_guess: Sequence[float] | None = None, t: float = 0.0, *,
                    release: Sequence[str] | bool = ()) -> Modes:
    """Natural frequencies, damping ratios and mode shapes of ``model`` about its static
    equilibrium at time ``t`` (found from ``q_guess`` by :func:`static_equilibrium`, with the
    drivers named in ``release`` released and the others held).

    Parameters
    ----------
    model : Model
    q_guess : (n,) array_like, optional
        Guess of the equilibrium's positions (default the drawing).
    t : float
        Time [s] of the drivers' positions and of the forces.
    release : sequence of str, or bool
        Drivers released (``True``: every one), as for :func:`mbd3d.static_equilibrium`.

    Returns
    -------
    Modes
        One entry per eigenvalue ``s`` with ``Im s >= 0``: a degree of freedom that
        oscillates (undamped or underdamped) once, one that does not (overdamped, unstable,
        free) twice, with its two real roots.
    """
    rest = static_equilibrium(model, [t], q_guess, release=release)
    active = active_rows(model, release)
    frequencies, ratios, shapes = modes_about(
        model, t, rest.q[0], rest.lam[0][active],
        None if rest.charts is None else rest.charts[0], active)
    return Modes(frequencies, ratios, shapes, rest)


def modes_about(model, t: float, q: np.ndarray, lam: np.ndarray, chart, active: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Frequencies [Hz], damping ratios and shapes about the equilibrium ``(q, lam)`` (the
    multipliers of the ``active`` rows), lowest frequency first."""
    n = model.n_coordinates
    zeros = np.zeros(n)
    fr = constraints.frames(model, q, zeros, chart)
    _, data, _ = constraints.evaluate(model, t, fr)
    Cq = constraints.jacobian_matrix(model, data, sparse=False)[active]
    N = la.null_space(Cq) if len(active) else np.eye(n)
    M = mass_matrix(model, fr, sparse=False)
    stiffness = accurate_stiffness(model, t, q, lam, active, chart)
    damping = _damping(model, t, q, chart)
    Mr, Dr, Kr = (N.T @ X @ N for X in (M, damping, stiffness))
    k = N.shape[1]
    if k == 0:
        return np.zeros(0), np.zeros(0), np.zeros((0, n), dtype=complex)
    # first-order form [z; z'] ' = A [z; z']
    A = np.block([[np.zeros((k, k)), np.eye(k)],
                  [-la.solve(Mr, Kr), -la.solve(Mr, Dr)]])
    eigenvalues, vectors = la.eig(A)
    # one of each conjugate pair; real roots (a degree of freedom that does not oscillate:
    # overdamped, unstable or free) all
    keep = np.flatnonzero(eigenvalues.imag >= -1e-12 * np.abs(eigenvalues))
    values = eigenvalues[keep]
    shapes = (N @ vectors[:k, keep]).T
    for shape in shapes:
        largest = shape[np.argmax(np.abs(shape))]
        if largest != 0:
            shape /= largest
    size = np.abs(values)
    frequencies = size / (2 * np.pi)
    ratios = np.where(size > 0, -values.real / np.where(size > 0, size, 1.0), 0.0) + 0.0
    order = np.argsort(frequencies, kind="stable")
    return frequencies[order], ratios[order], shapes[order]


def _damping(model, t: float, q: np.ndarray, chart) -> np.ndarray:
    """``D = -dQe/dqd`` at rest (n, n), by central differences (the quadratic velocity
    forces' derivative vanishes there)."""
    n = model.n_coordinates
    D = np.empty((n, n))
    scale = model.coordinate_scale
    for j in range(n):
        h = 1e-6 * scale[j]
        rates = np.zeros(n)
        rates[j] = h
        plus = generalized_forces(model, t, constraints.frames(model, q, rates, chart))
        minus = generalized_forces(model, t, constraints.frames(model, q, -rates, chart))
        D[:, j] = -(plus - minus) / (2 * h)
    return D
