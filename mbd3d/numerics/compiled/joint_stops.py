"""Joint stops, compiled: the law of a row of the contact table (:mod:`~.compiled.contacts`)
pushing a joint coordinate back into ``[lower, upper]`` (see :mod:`~.compiled.contacts` for the
kinds)."""

from __future__ import annotations

import math

import numpy as np

from mbd3d.numerics.compiled import jit
from mbd3d.numerics.compiled.contact_laws import dissipated_power, normal_force
from mbd3d.numerics.compiled.contact_table import (CONE_STOP, DISSIPATION, GAP, GAP_RATE,
                                                   NORMAL, NORMAL_FORCE, POINT, POTENTIAL,
                                                   SLIDE_STOP)
from mbd3d.numerics.compiled.forces import _add_pair, _add_torque, _point, _turn, _velocity


@jit
def _stop_side(x: float, rate: float, lower: float, upper: float) -> tuple:
    """``(gap, gap rate, sign)`` of a stop's end nearer to being passed, and the direction
    (+1: up the coordinate) it pushes body j."""
    if x - lower < upper - x:
        return x - lower, rate, 1.0
    return upper - x, -rate, -1.0


@jit
def _hinge(A, omega, Q, Qd, k, i, j, points, h) -> tuple:
    """``(theta, theta')`` of hinge stop ``k`` and its axis ``h`` (global, 3D)."""
    if points.shape[2] == 2:
        h[0], h[1], h[2] = 0.0, 0.0, 1.0
        return Q[j, 2] - Q[i, 2], Qd[j, 2] - Qd[i, 2]
    f_i, g_i, f_j = np.zeros(3), np.zeros(3), np.zeros(3)
    _turn(A, i, points[k, 0], f_i)
    _turn(A, i, points[k, 1], g_i)
    _turn(A, j, points[k, 2], f_j)
    along, across, rate = 0.0, 0.0, 0.0
    for x in range(3):
        y, z = (x + 1) % 3, (x + 2) % 3
        h[x] = f_i[y] * g_i[z] - f_i[z] * g_i[y]
        along += f_j[x] * f_i[x]
        across += f_j[x] * g_i[x]
    for x in range(3):
        rate += h[x] * (omega[j, x] - omega[i, x])
    return math.atan2(across, along), rate


@jit
def _slide(A, omega, Q, Qd, k, i, j, points, h, s_i, s_j) -> tuple:
    """``(s, s')`` of slide stop ``k``, its axis ``h`` (global, 3D) and the offsets ``s_i``,
    ``s_j`` of ``P_j`` from the bodies' reference points."""
    dim = points.shape[2]
    p_i, v_i, v_j = np.zeros(3), np.zeros(3), np.zeros(3)
    _point(A, Q, i, points[k, 0], p_i)
    _point(A, Q, j, points[k, 1], s_j)
    _turn(A, i, points[k, 2], h)
    slide, rate = 0.0, 0.0
    for x in range(3):
        d = s_j[x] - p_i[x]
        slide += h[x] * d
        s_i[x] = s_j[x] - (Q[i, x] if x < dim else 0.0)
        s_j[x] -= Q[j, x] if x < dim else 0.0
    _velocity(Qd, omega, dim, i, s_i, v_i)
    _velocity(Qd, omega, dim, j, s_j, v_j)
    for x in range(3):
        # s' = h . (v_Pj - v_Pi) + (omega_i x h) . d: the velocity of P_j relative to the
        # material point of body i it passes
        rate += h[x] * (v_j[x] - v_i[x])
    return slide, rate


@jit
def _cone(A, omega, k, i, j, points, h) -> tuple:
    """``(angle, angle')`` of cone stop ``k`` and the axis ``h`` (global, 3D) it turns about
    (zero where the two axes are aligned)."""
    a_i, a_j = np.zeros(3), np.zeros(3)
    _turn(A, i, points[k, 0], a_i)
    _turn(A, j, points[k, 1], a_j)
    sine, cosine, rate = 0.0, 0.0, 0.0
    for x in range(3):
        y, z = (x + 1) % 3, (x + 2) % 3
        h[x] = a_i[y] * a_j[z] - a_i[z] * a_j[y]
        sine += h[x] * h[x]
        cosine += a_i[x] * a_j[x]
    sine = math.sqrt(sine)
    for x in range(3):
        h[x] = h[x] / sine if sine > 0.0 else 0.0
        rate += h[x] * (omega[j, x] - omega[i, x])
    return math.atan2(sine, cosine), rate


@jit
def _stop_coordinate(A, omega, Q, Qd, k, i, j, points, values, h, s_i, s_j) -> tuple:
    """``(x, x')`` of stop ``k`` with its axis ``h`` (and, for a slide, the offsets ``s_i``,
    ``s_j`` of the point pushed)."""
    if values[k, 0] == SLIDE_STOP:
        return _slide(A, omega, Q, Qd, k, i, j, points, h, s_i, s_j)
    if values[k, 0] == CONE_STOP:
        return _cone(A, omega, k, i, j, points, h)
    return _hinge(A, omega, Q, Qd, k, i, j, points, h)


@jit
def _stop_into(A, axes, omega, Q, Qd, k, i, j, points, values, out, report, power) -> None:
    """Stop ``k``: the law's force back into ``[lower, upper]`` along its joint coordinate (a
    torque about a hinge's or a cone's axis, a force along a slide), and its report and
    dissipated power as :func:`contact_forces_into`'s."""
    h, s_i, s_j, F = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)
    x, rate = _stop_coordinate(A, omega, Q, Qd, k, i, j, points, values, h, s_i, s_j)
    gap, gap_rate, sign = _stop_side(x, rate, values[k, 1], values[k, 2])
    force = normal_force(values, k, -gap, -gap_rate)
    if values[k, 0] != SLIDE_STOP:
        _add_torque(axes, j, h, sign * force, out)
        _add_torque(axes, i, h, -sign * force, out)
    else:
        for x_ in range(3):
            F[x_] = sign * force * h[x_]
        _add_pair(axes, i, j, s_i, s_j, F, out)
    if power.shape[0] > 0:
        power[k] = dissipated_power(values, k, -gap, -gap_rate, force)
    if report.shape[0] > 0:
        delta = -gap if gap < 0.0 else 0.0
        report[k, :] = 0.0
        report[k, DISSIPATION] = dissipated_power(values, k, -gap, -gap_rate, force)
        report[k, GAP], report[k, GAP_RATE], report[k, NORMAL_FORCE] = gap, gap_rate, force
        for x_ in range(3):
            report[k, NORMAL + x_] = sign * h[x_]
            report[k, POINT + x_] = s_j[x_] + (Q[j, x_] if x_ < points.shape[2] else 0.0)
        exponent = values[k, 4] + 1.0
        report[k, POTENTIAL] = values[k, 3] * delta ** exponent / exponent
