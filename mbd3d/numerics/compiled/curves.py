"""Periodic curves of the cam rows, compiled: cubic splines over one turn.

A curve is stored in a flat table at an offset: its ``count + 1`` knots (angles [rad], the last
one turn after the first), then ``count`` rows of 4 coefficients, ascending powers of the
distance from each interval's first knot (see :class:`mbd3d.joints.CamProfile`).
"""

from __future__ import annotations

import math

from mbd3d.numerics.compiled import jit


@jit
def periodic_curve(curves, offset: int, count: int, x: float):
    """``(f, f', f'')`` at the angle ``x`` [rad] (any real: the curve repeats every turn) of the
    curve stored at ``offset`` of ``curves`` with ``count`` intervals."""
    first = curves[offset]
    period = curves[offset + count] - first
    u = x - first
    u -= period * math.floor(u / period)
    u += first
    lo, hi = 0, count - 1
    while lo < hi:  # the interval holding u
        mid = (lo + hi + 1) // 2
        if curves[offset + mid] <= u:
            lo = mid
        else:
            hi = mid - 1
    h = u - curves[offset + lo]
    c = offset + count + 1 + 4 * lo
    a0, a1, a2, a3 = curves[c], curves[c + 1], curves[c + 2], curves[c + 3]
    return (a0 + h * (a1 + h * (a2 + h * a3)), a1 + h * (2.0 * a2 + 3.0 * a3 * h),
            2.0 * a2 + 6.0 * a3 * h)
