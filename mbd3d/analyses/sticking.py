"""Coulomb friction at rigid contacts held at rest: the forces of one state, sticking or sliding.

A held row (:mod:`mbd3d.analyses.resting`) with a friction coefficient ``mu`` either *sticks*,
its slip velocity ``v = T qd`` (the tangential part of the second shape's material point's
velocity relative to the first's, :class:`~mbd3d.ContactStates`) held at zero by a tangential
force ``s`` of free sign, which must stay within the cone ``|s| <= mu_s f`` (``mu_s`` the
static coefficient, :class:`~mbd3d.RigidImpact`'s ``static_friction``, at least ``mu``); or
*slides* along a direction ``u``, the friction ``-mu f e`` opposing ``e``, the slip's direction
(``u`` where the slip vanishes: at the start of a slide; :func:`direction`). With ``[X; Y]``
the augmented system's response to a unit generalized force along each column (the joints
holding) and ``f`` the normal forces::

    qdd = qdd0 + X z,   z = (f, s),   columns  G_k^T - mu_k T_k^T e_k  (sliding),
                                               G_k^T, (B_k T_k)^T (sticking, B_k its tangents)
    0 <= f  _|_  G qdd + g >= 0,     B T qdd + t = 0 (the sticking rows)

with ``g`` and ``t`` the gaps' and the slips' convective terms (``(dG/dq qd) qd``): a mixed
complementarity problem (:func:`mixed_complementarity`), not symmetric where rows
slide. Where sticking rows depend on each other (a box's corners flat on a floor: their slips
are one) the split of their tangential forces is not determined by the motion; it is taken in
proportion to each row's ``mu f`` (:func:`share_by_capacity`), so that they reach their cones
together and the face slips as one, as a rigid body's does.
"""

from __future__ import annotations

import numpy as np

from mbd3d.errors import ModelError

__all__ = ["direction", "tangents", "mixed_complementarity", "share_by_capacity",
           "impact_with_friction"]

#: trials of an impact's sticking and sliding rows (each a change of one row's mode) before
#: the impact is refused; Newton iterations on the directions its rows slide in space
_TRIALS, _NEWTON = 200, 50


def direction(slip: np.ndarray, along: np.ndarray, blend: float) -> np.ndarray:
    """The direction (unit, global) in which a sliding row slips: its slip velocity's
    ``v / |v|`` where the slip is beyond the small speed ``blend`` [m/s]; below, turning
    smoothly (with a continuous slope) into ``u``, the direction it slides along, as
    ``(v + w u) / |v + w u|``, ``w = (b - |v|)^2 / b``: ``u`` where the slip vanishes, at the
    start of a slide and at the stop where the row sticks. The slip's direction alone would
    follow the rounding of a vanishing slip, sideways in space, and the steps would
    collapse on its noise (Coulomb's friction turns a slow slip stiffly)."""
    speed = float(np.linalg.norm(slip))
    if speed >= blend:
        return slip / speed
    blended = slip + (blend - speed) ** 2 / blend * along
    size = float(np.linalg.norm(blended))
    return blended / size if size > 0.0 else along


def tangents(normal: np.ndarray, planar: bool) -> np.ndarray:
    """Unit tangents (d, 3) at a contact of unit ``normal``: one in the plane of a planar
    model, two orthogonal ones in space."""
    if planar:
        return np.array([[-normal[1], normal[0], 0.0]])
    axis = np.eye(3)[0] if abs(normal[0]) < 0.9 else np.eye(3)[1]
    t1 = axis - (axis @ normal) * normal
    t1 /= np.linalg.norm(t1)
    return np.array([t1, np.cross(normal, t1)])


def _solve_part(A: np.ndarray, c: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """``z`` zero off ``rows`` with ``(A z + c)[rows] = 0``: where those rows depend on each
    other, the least-norm such ``z`` (the even share; a compliance added instead, as the
    impacts add one, would leave its own size in the rows' accelerations: a held block
    creeping by 1e-12 m in a second)."""
    z = np.zeros(len(c))
    if not len(rows):
        return z
    Ar = A[np.ix_(rows, rows)]
    if np.linalg.cond(Ar) > 1e10:
        z[rows] = np.linalg.lstsq(Ar, -c[rows], rcond=1e-10)[0]
    else:
        z[rows] = np.linalg.solve(Ar, -c[rows])
    return z


def mixed_complementarity(A: np.ndarray, c: np.ndarray, a: int,
                          what: str = "forces of the rigid contacts held at rest") -> np.ndarray:
    """``z`` with ``0 <= z_k _|_ (A z + c)_k >= 0`` for ``k < a`` and ``(A z + c)_k = 0``
    beyond, by Murty's least-index principal pivoting: starting from every ``k < a`` pressing,
    the first row whose force pulls or whose rate sinks is switched, until none is. It ends
    for a P-matrix ``A``; where it does not (sliding friction that presses a contact closed
    the harder it presses: Painleve's paradox), the run is refused, saying so (``what``: the
    forces or impulses sought)."""
    m = len(c)
    size = max(float(np.max(np.abs(c), initial=0.0)), np.finfo(float).tiny)
    pressing = np.ones(a, dtype=bool)
    for _ in range(8 * a + 8):
        z = _solve_part(A, c, np.concatenate([np.flatnonzero(pressing), np.arange(a, m)]))
        y = A @ z + c
        tol = 1e-10 * max(size, float(np.max(np.abs(A @ z), initial=0.0)))
        wrong = np.flatnonzero((pressing & (z[:a] < -tol)) | (~pressing & (y[:a] < -tol)))
        if not len(wrong):
            z[:a][~pressing] = 0.0
            return z
        pressing[wrong[0]] = not pressing[wrong[0]]
    raise ModelError(f"the {what} were not found: sliding friction there would press a "
                     "contact closed harder the harder it presses (Painleve's paradox); "
                     "lower the friction coefficient or give the contacts compliant laws")


def share_by_capacity(A: np.ndarray, s: np.ndarray, capacity: np.ndarray) -> np.ndarray:
    """The sticking rows' tangential forces ``s`` shared in proportion to ``capacity`` (each
    row's ``mu f``, repeated per tangent) where ``A`` (their response to one another) leaves
    the split free: the forces with the same ``A s`` of least ``sum s^2 / capacity``, i.e.
    ``D A (A D A)^+ A s``; ``s`` itself where ``A`` is regular."""
    if len(s) < 2 or np.linalg.cond(A) <= 1e10:
        return s
    D = np.maximum(capacity, np.finfo(float).tiny)
    target = A @ s
    y = np.linalg.lstsq((A * D) @ A, target, rcond=1e-10)[0]
    return D * (A @ y)


def impact_with_friction(G: np.ndarray, T: np.ndarray, normal: np.ndarray, mu: np.ndarray,
                         closing: np.ndarray, qd: np.ndarray, response, planar: bool,
                         mu_static: np.ndarray | None = None, kick: np.ndarray | None = None
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An impact on rigid rows with Coulomb's friction: ``(qd+, P_n (a,) [N s], P_t (a, 3)
    [N s])``, the velocities after it and each row's normal and friction impulses (the
    friction on the second shape, global axes).

    Newton's law holds the normal rates as without friction (``G qd+ - G qd- + closing >= 0``,
    complementary to ``P_n >= 0``; ``closing`` (a,) is ``(1 + e) G qd-`` for a whole impact,
    ``G qd- - target`` for a phase that brings the rates to ``target``) and Coulomb's the
    slips after the impact, as a held row's
    (Moreau's law, the tangential restitution zero): a row *sticks*, ``T qd+ = 0`` with
    ``|P_t| <= mu_s P_n`` (``mu_static``, default ``mu``), or *slides*, ``P_t = -mu P_n u``
    with ``u`` the direction of its slip ``T qd+`` after the impact. ``G`` (a, n) and ``T``
    (a, 3, n) are the rows' gap and slip rows at the impact, ``normal`` (a, 3) their normals,
    ``response(R)`` the velocities (n, k) a unit impulse on each row of ``R`` gives, the joints
    holding. Every row starts
    sticking; a row that cannot stick (its slip tied to its normal rate) or whose impulse
    leaves its cone slides, away from that impulse, and a planar row whose slip turned back
    slides the other way, until the modes hold; in space the sliding rows' directions are
    those their slips come out along (:func:`_settle_directions`). ``kick`` (n,): a change
    of the velocities by other impulses at the same impact (the joints' friction), which
    Newton's law does not restore (``closing`` is of the rates before any impulse)."""
    a = len(G)
    kick = np.zeros_like(qd) if kick is None else kick
    mu_s = mu if mu_static is None else mu_static
    bases = [tangents(normal[k], planar) for k in range(a)]
    stuck, phi = mu_s > 0.0, np.zeros(a)
    before = max(float(np.max(np.abs(G @ qd), initial=0.0)),
                 float(np.max(np.abs(T @ qd), initial=0.0)), np.finfo(float).tiny)
    for _ in range(_TRIALS):
        (after, P_n, P_t), phi = _settle_directions(G, T, bases, mu, mu_s, closing, qd, kick,
                                                    response, stuck, phi, before)
        slip = T @ after
        speed = np.linalg.norm(slip, axis=1)
        # a row that cannot stick with the others (a pendulum's tip bouncing off a floor:
        # its slip and its gap's rate move together) slides along the slip it is left with
        unheld = np.flatnonzero(stuck & (speed > 1e-9 * before))
        size = max(float(np.max(P_n, initial=0.0)), np.finfo(float).tiny)
        over = np.flatnonzero(stuck & (np.linalg.norm(P_t, axis=1)
                                       > (1.0 + 1e-9) * mu_s * P_n + 1e-12 * size))
        if len(unheld) or len(over):
            k = unheld[0] if len(unheld) else over[0]
            stuck[k] = False
            phi[k] = _angle(bases[k], slip[k] if len(unheld) else -P_t[k])
            continue
        sliding = (mu_s > 0.0) & ~stuck
        along = _directions(bases, phi)
        back = np.flatnonzero(sliding & (np.einsum("ki,ki->k", slip, along) < -1e-12 * before))
        if not len(back):
            return after, P_n, P_t
        phi[back[0]] += np.pi
    raise ModelError("the impulses of an impact with friction were not found: its rows "
                     "could neither stick nor slide consistently (sliding friction that "
                     "presses a contact closed, Painleve's paradox at an impact); lower the "
                     "friction coefficients or give the contacts compliant laws")


def _angle(basis: np.ndarray, vector: np.ndarray) -> float:
    """The angle [rad] of ``vector`` from the first tangent of ``basis`` about the normal (0
    or pi in the plane)."""
    return float(np.arctan2(basis[1] @ vector, basis[0] @ vector) if len(basis) > 1
                 else (0.0 if basis[0] @ vector >= 0.0 else np.pi))


def _directions(bases: list, phi: np.ndarray) -> np.ndarray:
    """The unit directions (a, 3) at angles ``phi`` from each row's first tangent."""
    return np.array([np.cos(p) * B[0] + (np.sin(p) * B[1] if len(B) > 1 else 0.0)
                     for B, p in zip(bases, phi)]).reshape(len(phi), 3)


def _settle_directions(G, T, bases, mu, mu_s, closing, qd, kick, response, stuck, phi,
                       before) -> tuple:
    """``((qd+, P_n, P_t), phi)`` with the sliding rows' directions those of their slips
    after the impact: in the plane as given; in space, each row's angle ``phi`` solved by
    Newton's method (a difference Jacobian, the step halved until the mismatch falls), since
    a row's friction turns its own slip and the others' (substitution alone can circle)."""
    sliding = np.flatnonzero((mu_s > 0.0) & ~stuck)

    def mismatch(angles):
        out = _impact_trial(G, T, bases, mu, mu_s, closing, qd, kick, response, stuck,
                            _directions(bases, angles))
        slip = T[sliding] @ out[0]
        moving = np.linalg.norm(slip, axis=1) > 1e-12 * before
        turn = np.array([_angle(bases[k], v) for k, v in zip(sliding, slip)]) - angles[sliding]
        return out, np.where(moving, (turn + np.pi) % (2 * np.pi) - np.pi, 0.0)

    out, r = mismatch(phi)
    if len(bases) == 0 or len(bases[0]) == 1:
        return out, phi
    for _ in range(_NEWTON):
        if np.max(np.abs(r), initial=0.0) <= 1e-12:
            return out, phi
        J = np.empty((len(sliding), len(sliding)))
        for j, k in enumerate(sliding):
            nudged = phi.copy()
            nudged[k] += 1e-7
            J[:, j] = (mismatch(nudged)[1] - r) / 1e-7
        step = np.linalg.lstsq(J, -r, rcond=1e-12)[0]
        for _ in range(30):
            trial = phi.copy()
            trial[sliding] += step
            new, r_new = mismatch(trial)
            if np.linalg.norm(r_new) < np.linalg.norm(r):
                break
            step = 0.5 * step
        out, r, phi = new, r_new, trial
    raise ModelError("the impulses of an impact with friction were not found: the directions "
                     "in which its rows slide did not settle; lower the friction "
                     "coefficients or give the contacts compliant laws")


def _impact_trial(G, T, bases, mu, mu_s, closing, qd, kick, response, stuck, along) -> tuple:
    """``(qd+, P_n, P_t)`` of an impact with the rows ``stuck`` sticking and the others
    with friction sliding ``along`` (:func:`impact_with_friction`; ``kick`` the velocities'
    change by the joints' friction)."""
    a, n = G.shape
    sliding = (mu > 0.0) & ~stuck
    columns = G - (mu * sliding)[:, None] * np.einsum("ki,kin->kn", along, T)
    sticking = np.flatnonzero(stuck)
    Ts = np.vstack([bases[k] @ T[k] for k in sticking] or [np.zeros((0, n))])
    X = response(np.vstack([columns, Ts]))
    A = np.vstack([G, Ts]) @ X
    c = np.concatenate([closing + G @ kick, Ts @ (qd + kick)])
    z = mixed_complementarity(A, c, a, "impulses of an impact with friction")
    d = len(bases[0]) if a else 1
    z[a:] = share_by_capacity(A[a:, a:], z[a:], np.repeat(mu_s[stuck] * z[:a][stuck], d))
    P_t = np.zeros((a, 3))
    for i, k in enumerate(sticking):
        P_t[k] = bases[k].T @ z[a + d * i:a + d * (i + 1)]
    P_t[sliding] = -(mu * z[:a])[sliding, None] * along[sliding]
    return qd + kick + X @ z, z[:a], P_t
