"""Prescribed motions ``f(t)`` with their first and second derivatives, compiled.

A motion is a sum of *terms*; each term is one of the kinds below with its parameters (the
classes of :mod:`mbd3d.model.motion` describe them to users and hand their terms here). A table of
motions, ``first`` (k + 1,) term offsets, ``kinds`` and ``starts`` (the offset of each term's
parameters in ``params``, with ``starts[-1]`` closing the last), is evaluated in one call.
"""

from __future__ import annotations

import math

import numpy as np

from mbd3d.numerics.compiled import jit

#: term kinds and their parameters
CONSTANT = 0      # value
RAMP = 1          # initial, rate
HARMONIC = 2      # amplitude, frequency [rad/s], phase, offset
POLYNOMIAL = 3    # c0, c1, ... (ascending powers)
SMOOTH_STEP = 4   # t0, t1, start, end (quintic 10 s^3 - 15 s^4 + 6 s^5)


@jit
def term_values(kind: int, p: np.ndarray, t: float):
    """``(f, f', f'')`` of one term with parameters ``p`` at ``t``."""
    if kind == CONSTANT:
        return p[0], 0.0, 0.0
    if kind == RAMP:
        return p[0] + p[1] * t, p[1], 0.0
    if kind == HARMONIC:
        a, w = p[0], p[1]
        s, c = math.sin(w * t + p[2]), math.cos(w * t + p[2])
        return p[3] + a * s, a * w * c, -a * w * w * s
    if kind == POLYNOMIAL:
        # Horner's rule for the value and both derivatives at once
        f = f1 = f2 = 0.0
        for k in range(p.shape[0] - 1, -1, -1):
            f2 = f2 * t + 2.0 * f1
            f1 = f1 * t + f
            f = f * t + p[k]
        return f, f1, f2
    # SMOOTH_STEP
    t0, t1, start, end = p[0], p[1], p[2], p[3]
    if t <= t0:
        return start, 0.0, 0.0
    if t >= t1:
        return end, 0.0, 0.0
    span = t1 - t0
    s = (t - t0) / span
    height = end - start
    # the lowest-order step with zero slope and curvature at both ends
    shape = s ** 3 * (10.0 - 15.0 * s + 6.0 * s * s)
    d_shape = 30.0 * s * s * (1.0 - s) ** 2
    dd_shape = 60.0 * s * (1.0 - s) * (1.0 - 2.0 * s)
    return start + height * shape, height * d_shape / span, height * dd_shape / span ** 2


@jit
def motion_values_into(first: np.ndarray, kinds: np.ndarray, starts: np.ndarray,
                       params: np.ndarray, t: float, out: np.ndarray) -> None:
    """Write ``(f, f', f'')`` of every motion of the table at ``t`` into ``out`` (k, 3)."""
    for m in range(first.shape[0] - 1):
        f = f1 = f2 = 0.0
        for term in range(first[m], first[m + 1]):
            a, b, c = term_values(kinds[term], params[starts[term]:starts[term + 1]], t)
            f += a
            f1 += b
            f2 += c
        out[m, 0] = f
        out[m, 1] = f1
        out[m, 2] = f2


def table(terms_of_motions: list) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(first, kinds, starts, params)`` of motions given as lists of ``(kind, parameters)``."""
    first, kinds, starts, params = [0], [], [0], []
    for terms in terms_of_motions:
        for kind, values in terms:
            kinds.append(kind)
            params.extend(float(v) for v in values)
            starts.append(len(params))
        first.append(len(kinds))
    return (np.array(first, dtype=np.int64), np.array(kinds, dtype=np.int64),
            np.array(starts, dtype=np.int64), np.array(params, dtype=float))
