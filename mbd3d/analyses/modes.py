"""Vibration modes of a mechanism about a static equilibrium.

Small motions about an equilibrium ``(q0, lam0)`` stay on the tangent space of the constraints,
``dq = N z`` with ``N`` an orthonormal basis of the null space of ``Cq(q0)``. There

    Mr z'' + Dr z' + Kr z = 0,   Mr = N^T M N,  Dr = N^T D N,  Kr = N^T (K + H) N

with ``K = -dQe/dq`` and ``H = d(Cq^T lam)/dq`` at ``lam0`` (the stiffness of
:mod:`mbd3d.analyses.statics`, which includes gravity's through the constraint forces) and
``D = -dQe/dqd`` (the dampers; the quadratic velocity forces have no first-order part at
rest). The eigenvalues ``s`` of the first-order form give each mode's natural frequency
``|s| / 2 pi`` [Hz] and damping ratio ``-Re(s) / |s|`` (negative: the equilibrium is unstable
along that mode); its shape is ``N v`` in the coordinates ``q``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import scipy.linalg as la

from mbd3d.analyses.statics import _active_rows, _stiffness, static_equilibrium
from mbd3d.io.results import Results
from mbd3d.model import constraints
from mbd3d.model.equations import generalized_forces, mass_matrix

__all__ = ["Modes", "vibration_modes"]


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


def vibration_modes(model, q_guess: Sequence[float] | None = None, t: float = 0.0, *,
                    release: Sequence[str] | bool = ()) -> Modes:
    """Natural frequencies, damping ratios and mode shapes of ``model`` about its static
    equilibrium at time ``t`` (found from ``q_guess`` by :func:`static_equilibrium`, with the
    drivers named in ``release`` released and the others held).

    Returns
    -------
    Modes
        One entry per eigenvalue ``s`` with ``Im s >= 0``: a degree of freedom that
        oscillates (undamped or underdamped) once, one that does not (overdamped, unstable,
        free) twice, with its two real roots.
    """
    rest = static_equilibrium(model, [t], q_guess, release=release)
    q, chart = rest.q[0], None if rest.charts is None else rest.charts[0]
    active = _active_rows(model, release)
    lam = rest.lam[0][active]
    n = model.n_coordinates
    zeros = np.zeros(n)
    fr = constraints.frames(model, q, zeros, chart)
    _, data, _ = constraints.evaluate(model, t, fr)
    Cq = constraints.jacobian_matrix(model, data, sparse=False)[active]
    N = la.null_space(Cq) if len(active) else np.eye(n)
    M = mass_matrix(model, fr, sparse=False)
    stiffness = _stiffness(model, t, q, lam, active, chart, Cq)
    damping = _damping(model, t, q, chart)
    Mr, Dr, Kr = (N.T @ X @ N for X in (M, damping, stiffness))
    k = N.shape[1]
    if k == 0:
        return Modes(np.zeros(0), np.zeros(0), np.zeros((0, n), dtype=complex), rest)
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
    ratios = np.where(size > 0, -values.real / np.where(size > 0, size, 1.0), 0.0)
    order = np.argsort(frequencies, kind="stable")
    return Modes(frequencies[order], ratios[order], shapes[order], rest)


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
