"""The joints' friction at a rigid impact: Coulomb's law on the impulses the joints carry.

A joint's friction (:mod:`mbd3d.model.friction`) is proportional to its load, a function of
its reactions. At a rigid impact the reactions are impulses ``Lam`` (the multipliers'
impulses), and the friction, integrated over the impact, an impulse ``E_n`` along the
joint's friction direction ``G_n`` (:meth:`~mbd3d.model.friction.FrictionGroup.directions`)
by Coulomb's law on the impulsive load ``L_n(Lam)`` (the regularised law's limit, the slide
being fast against its stiction velocity throughout): the joint either *slides* on in the
sense ``d_n`` it slid before, ``E_n = -mu_n L_n d_n``, or *sticks*, the impact stopping its
slide (``G_n qd+ = 0``) with ``|E_n| <= mu_n L_n``. A joint that did not slide before starts
sticking; where the contacts' rates move it whatever its impulse (the restitution phase of a
hinged pendulum's bounce starts at rest and must swing it back), it slides that way. The
contact rows' impulses are solved with the velocities ``E`` gives (Newton's law still on
their rates before the impact), so ``Lam`` depends on ``E`` and ``E`` on
``Lam``: Newton's method on the modes' equations, with a difference Jacobian (exact within
a piece: the impulses are piecewise affine in ``E``, by the contacts' active set), then a
joint whose slide the impact turned back sticks, one whose sticking impulse leaves its cone
slides (away from that impulse), until the modes hold.

The impact is taken in two phases (:meth:`mbd3d.analyses.impacts.RigidContacts._impact`):
the contact rows brought to rest, then to ``-e`` times their rates before, so that a joint
whose slide the impact turns back (a pendulum's hinge as its tip bounces) rubs against each
sense in turn, as through a stiff contact's compression and restitution.

A carriage sliding on a rail with friction, struck from above by a ball, slows by
``mu P / M`` at the strike (``P`` the ball's impulse): what a stiff compliant contact's
force would take through the rail's friction over its short duration.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from mbd3d.errors import ModelError

__all__ = ["joint_friction_impulses"]

#: Newton iterations for one set of modes; relative step of the difference Jacobian
_NEWTON, _STEP = 30, 1e-7


def joint_friction_impulses(model, fr, qd: np.ndarray, contact: Callable,
                            response: Callable, what: str) -> tuple:
    """What ``contact`` returns at the joints' friction impulses of an impact (module doc).

    Parameters
    ----------
    model : Model
        With joint friction (``model.friction``).
    fr : Frames
        The bodies' frames at the impact.
    qd : ndarray (n,)
        The velocities before the impact.
    contact : callable
        ``contact(kick, lam)``: the contact rows' impact with the velocities changed by
        ``kick`` (n,) and the multipliers' impulses by ``lam`` (m,) through the joints'
        friction, returning a tuple whose first item is the velocities after the impact
        (n,) and whose last is all the multipliers' impulses (m,).
    response : callable
        ``response(R)``: the velocities over the multipliers' impulses (n + m, k) a unit
        impulse along each row of ``R`` gives, the joints holding.
    what : str
        The impact, for the error where the modes do not settle.
    """
    group, n = model.friction, model.n_coordinates
    G = group.directions(model, fr)[0]
    XY = response(G)
    mode = np.sign(G @ qd)  # +-1: sliding that way; 0: sticking

    def solve(E: np.ndarray) -> tuple:
        return contact(XY[:n] @ E, XY[n:] @ E)

    def residual(E: np.ndarray) -> np.ndarray:
        out = solve(E)
        after, lam = out[0], out[-1]
        return np.where(mode != 0.0, E + group.mu * group.loads(model, fr, lam) * mode,
                        G @ after)

    free = solve(np.zeros(len(G)))
    capacity = group.mu * group.loads(model, fr, free[-1])
    size = float(np.max(capacity, initial=0.0))
    if size == 0.0:  # the impact loads no joint with friction
        return free
    E = -capacity * mode
    # the joints' slides before the impact and without friction through it: a joint at rest
    # before (the restitution phase starts so) may be made to slide by the contacts
    speed = max(float(np.max(np.abs(G @ qd), initial=0.0)),
                float(np.max(np.abs(G @ free[0]), initial=0.0)), np.finfo(float).tiny)
    for _ in range(2 * len(G) + 2):
        E = _newton(residual, E, size, what)
        out = solve(E)
        after, capacity = out[0], group.mu * group.loads(model, fr, out[-1])
        slide = G @ after
        back = np.flatnonzero((mode != 0.0) & (mode * slide < -1e-12 * speed))
        # a joint cannot stick where the contacts' rates move it whatever its impulse (no
        # friction impulse zeroes its slide): it slides that way
        moved = np.flatnonzero((mode == 0.0) & (np.abs(slide) > 1e-9 * speed))
        over = np.flatnonzero((mode == 0.0) & (np.abs(E) > (1.0 + 1e-9) * capacity
                                               + 1e-12 * size))
        if not len(back) and not len(moved) and not len(over):
            return out
        if len(back):
            mode[back[0]] = 0.0
        elif len(moved):
            mode[moved[0]] = np.sign(slide[moved[0]])
        else:
            mode[over[0]] = -np.sign(E[over[0]])
    raise ModelError(f"{what}: the joints' friction impulses were not found, their joints "
                     "could neither stick nor slide consistently; lower the joints' friction "
                     "coefficients or give the contacts compliant laws")


def _newton(residual: Callable, E: np.ndarray, size: float, what: str) -> np.ndarray:
    """The root of ``residual`` from ``E`` (piecewise affine: a difference Jacobian is exact
    within a piece, so few steps are needed)."""
    r = residual(E)
    for _ in range(_NEWTON):
        step = _STEP * max(float(np.max(np.abs(E), initial=0.0)), size)
        J = np.column_stack([(residual(E + step * u) - r) / step for u in np.eye(len(E))])
        change = np.linalg.lstsq(J, -r, rcond=1e-12)[0]
        E = E + change
        r = residual(E)
        if float(np.max(np.abs(change), initial=0.0)) <= 1e-13 * max(
                float(np.max(np.abs(E), initial=0.0)), size):
            return E
    raise ModelError(f"{what}: the joints' friction impulses did not converge (a joint at "
                     "or near self-locking); lower the joints' friction coefficients or give "
                     "the contacts compliant laws")
