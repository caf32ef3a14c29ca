"""The normal force laws of compliant contacts and joint stops, compiled (see
:mod:`mbd3d.model.contact_laws` for the laws and their constants). Contact ``k``'s law is the
row ``values[k] = (kind, r_i, r_j, K, n_K, D, n_D, mu, v_slip, d)`` of
:mod:`~.compiled.contacts`::

    F_n = max(0, K delta^n_K + c(delta) delta')          while delta > 0, else 0
    c(delta) = D delta^n_D                  (d = 0)
             = D S(min(delta / d, 1))       (d > 0; S(b) = b^2 (3 - 2 b))

[N] at the penetration ``delta`` [m] and its rate ``delta'`` [m/s]: the linear
spring-damper (``n_K = 1, n_D = 0``), Hertz with the Tsuji damping (``n_K = 3/2, n_D =
1/4``), the Hunt-Crossley family (``n_D = n_K``) and Adams' IMPACT function (``d > 0``: the
damping ramped in over the penetration ``d``). The potential of the law's spring part is
``K delta^(n_K + 1) / (n_K + 1)`` [J]; what the force does beyond it is dissipated.
"""

from __future__ import annotations

from mbd3d.numerics.compiled import jit


@jit
def normal_force(values, k, delta: float, delta_rate: float) -> float:
    """The normal force [N] of contact ``k``'s law at penetration ``delta`` [m] and rate
    ``delta_rate`` [m/s] (zero when apart, never pulling)."""
    if not delta > 0.0:
        return 0.0
    force = law_force(values, k, delta, delta_rate)
    return force if force > 0.0 else 0.0


@jit
def law_force(values, k, delta: float, delta_rate: float) -> float:
    """``K delta^n_K + c delta'`` of contact ``k`` (``delta > 0``), unclipped."""
    return values[k, 3] * delta ** values[k, 4] + damping(values, k, delta)[0] * delta_rate


@jit
def damping(values, k, delta: float) -> tuple:
    """The damping coefficient ``c`` of contact ``k``'s law at penetration ``delta > 0`` and
    its slope in ``delta``: ``D delta^n_D``, or ``D S(delta / d)`` with the cubic step ``S(b)
    = b^2 (3 - 2 b)`` (1 beyond ``b = 1``) where the law ramps its damping in over ``d =
    values[k, 9] > 0``."""
    D, n_D, d = values[k, 5], values[k, 6], values[k, 9]
    if d > 0.0:
        b = delta / d
        if b >= 1.0:
            return D, 0.0
        return D * b * b * (3.0 - 2.0 * b), D * 6.0 * b * (1.0 - b) / d
    if n_D == 0.0:
        return D, 0.0
    return D * delta ** n_D, D * n_D * delta ** (n_D - 1.0)


@jit
def dissipated_power(values, k, delta: float, delta_rate: float, force: float) -> float:
    """The power [W] the normal force ``force`` of contact ``k`` dissipates at penetration
    ``delta`` and rate ``delta'``: what it does beyond its spring, ``(F_n - K delta^n_K)
    delta'`` (the damper's; where the force is clipped at zero, the spring's work the shapes
    do not get back), zero apart."""
    if not delta > 0.0:
        return 0.0
    return (force - values[k, 3] * delta ** values[k, 4]) * delta_rate


@jit
def law_slopes(values, k, delta: float, delta_rate: float) -> tuple:
    """``(dF_n/d delta, dF_n/d delta')`` of contact ``k``'s law, zero where it does not push."""
    if normal_force(values, k, delta, delta_rate) == 0.0:
        return 0.0, 0.0
    K, n_K = values[k, 3], values[k, 4]
    c, c_slope = damping(values, k, delta)
    return K * n_K * delta ** (n_K - 1.0) + c_slope * delta_rate, c
