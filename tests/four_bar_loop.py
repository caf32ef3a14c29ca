"""The crank-rocker of mbd3d.mechanisms.four_bar solved by hand, for tests: positions by
intersecting circles (the open branch), rates and accelerations from the loop equation
a e(t2) + b e(t3) = d x + c e(t4) differentiated and solved as 2 x 2 systems."""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as la

GROUND, CRANK, COUPLER, ROCKER = 0.30, 0.10, 0.35, 0.30


def perp(t: float) -> np.ndarray:
    return np.array([-math.sin(t), math.cos(t)])


def radial(t: float) -> np.ndarray:
    return np.array([math.cos(t), math.sin(t)])


def four_bar_by_hand(theta2: float, w2: float = 1.0, a2: float = 0.0):
    """``((theta3, theta4), (w3, w4), (a3, a4))``: coupler and rocker angles [rad], rates and
    accelerations for the crank at ``theta2`` turning at ``w2`` with acceleration ``a2``."""
    A = CRANK * radial(theta2)
    O4 = np.array([GROUND, 0.0])
    d = np.linalg.norm(O4 - A)
    e = (O4 - A) / d
    along = (COUPLER ** 2 - ROCKER ** 2 + d * d) / (2 * d)
    B = A + along * e + math.sqrt(COUPLER ** 2 - along ** 2) * np.array([-e[1], e[0]])
    t3, t4 = math.atan2(*(B - A)[::-1]), math.atan2(*(B - O4)[::-1])
    M = np.column_stack([COUPLER * perp(t3), -ROCKER * perp(t4)])
    w3, w4 = la.solve(M, -CRANK * w2 * perp(theta2))
    rhs = (-CRANK * a2 * perp(theta2) + CRANK * w2 ** 2 * radial(theta2)
           + COUPLER * w3 ** 2 * radial(t3) - ROCKER * w4 ** 2 * radial(t4))
    a3, a4 = la.solve(M, rhs)
    return (t3, t4), (w3, w4), (a3, a4)
