"""Coulomb friction in joints, from the joints' own reactions.

A friction force is proportional to the normal force a joint carries, and that is a reaction:
it comes from the multipliers, which depend on the accelerations, which depend on the friction.
:func:`consistent_multipliers` solves this loop at every evaluation (Newton's method in the k
frictions, the multipliers being affine in them), so the friction always uses the multipliers
of the same state, never those of an earlier step.

The law is Coulomb's, regularised for stiction: the friction opposes the sliding speed ``v``
of the contact surface with magnitude ``mu N tanh(v / v_s)``. Above a few ``v_s`` (the
``stiction_velocity``, default 1 mm/s) it is ``mu N``; below, it grows linearly with ``v``, so
a joint loaded below its friction limit does not stick exactly but creeps at the speed
``v = v_s artanh(F / (mu N))`` that balances the load ``F``. The law is smooth: every
integrator takes it, and a smaller ``v_s`` makes sticking more exact and the equations
stiffer (an explicit integrator then takes short steps near sticking).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mbd3d.errors import AnalysisError, IntegrationError, ModelError
from mbd3d.model.body import Body
from mbd3d.model.forces import ForceElement
from mbd3d.numerics.compiled import forces as kernel

__all__ = ["JointFriction", "FrictionGroup", "consistent_multipliers", "solve_frictions",
           "raise_friction_with_redundancy"]

#: Newton iterations allowed to make friction and reactions consistent, and the residual of
#: the frictions (relative to the largest) at which they are
MAX_FRICTION_ITERATIONS = 60
FRICTION_TOLERANCE = 1e-12


class JointFriction(ForceElement):
    """Coulomb friction in a revolute or prismatic joint (planar or spatial).

    Revolute: a torque about the hinge opposing the relative rotation, of magnitude
    ``mu (pin_radius |F_radial| + axial_arm |F_axial|)``, ``F`` the pin's reaction force
    (planar: all of it is radial); the sliding speed is the pin surface's,
    ``pin_radius * omega_rel``. Prismatic: a force along the axis opposing the sliding, of
    magnitude ``mu |F_normal|``, ``F_normal`` the reaction force normal to the axis (the
    reaction moment is taken without friction). Both on body j, and opposite on body i. See
    :mod:`mbd3d.model.friction` for the regularised law and how it is made consistent with
    the reactions.

    Parameters
    ----------
    name : str
    joint : Revolute or Prismatic
        The joint (already added to the model).
    coefficient : float
        Coulomb's coefficient ``mu`` (dimensionless, >= 0).
    pin_radius : float, optional
        Revolute: radius of the pin or journal [m] (required for a revolute).
    axial_arm : float
        Spatial revolute: mean radius of the thrust face taking the axial load [m]; 0 leaves
        axial loads without friction.
    stiction_velocity : float
        ``v_s`` of the regularised law [m/s] (a revolute's at the pin's surface), > 0. What it
        costs, from ``F = mu N tanh(v / v_s)``: at ``v = v_s`` the friction is 76 % of
        ``mu N``, at ``3 v_s`` 99.5 %; a joint held by friction at half its limit creeps at
        ``0.55 v_s``, at 90 % at ``1.47 v_s``; a stop-and-reverse is smeared over speeds of a
        few ``v_s``. Choose it well below the sliding speeds that matter (at 100 ``v_s`` the
        friction is Coulomb's to machine precision) and as large as the creep you accept:
        the law's slope ``mu N / v_s`` is a damping that an explicit integrator must resolve
        (steps below about ``m v_s / (mu N)``, ``m`` the moving mass), while
        generalized-alpha takes it in its iteration matrix. The default, 1 mm/s, suits
        machines whose parts slide at centimetres to metres per second.
    """

    def __init__(self, name: str, joint: Any, coefficient: float, *,
                 pin_radius: float | None = None, axial_arm: float = 0.0,
                 stiction_velocity: float = 1e-3):
        self.name = name
        self.joint = joint
        self.coefficient = coefficient
        self.pin_radius = pin_radius
        self.axial_arm = axial_arm
        self.stiction_velocity = stiction_velocity

    def bodies(self) -> list[tuple[str, Body]]:
        return [("body_i", self.joint.body_i), ("body_j", self.joint.body_j)]

    @classmethod
    def compile(cls, elements: list, ctx) -> "FrictionGroup":
        raise ModelError("joint friction is made into a FrictionGroup by the model itself")


def _positive(ctx, value: Any, what: str, allow_zero: bool) -> float:
    x = ctx.scalar(value, what)
    if not (x > 0 or (allow_zero and x == 0)):
        raise ModelError(f"{what} must be {'>= 0' if allow_zero else 'positive'}, got {value!r}")
    return x


class FrictionGroup:
    """Every :class:`JointFriction` of a model, evaluated together.

    Built with the model (:meth:`build`), when the joints' rows and reaction frames are known.
    """

    def __init__(self, model, elements: list[JointFriction], ctx):
        self.elements = elements
        self.dim = model.dim
        k = len(elements)
        self.revolute = np.zeros(k, dtype=bool)
        self.mu, self.v_s = np.zeros(k), np.zeros(k)
        self.radius, self.axial = np.zeros(k), np.zeros(k)
        self.bi = np.zeros(k, dtype=np.int64)
        self.bj = np.zeros(k, dtype=np.int64)
        self.force_rows = np.zeros((k, model.dim), dtype=np.int64)  # revolute: the point rows
        self.normal_rows = np.zeros((k, model.dim - 1), dtype=np.int64)  # prismatic
        self.u_j = np.zeros((k, model.dim))
        self.axis_i = np.zeros((k, model.dim))
        for n, e in enumerate(elements):
            what = f"friction '{e.name}'"
            joint = e.joint
            kind = getattr(joint, "friction_kind", None)
            if kind is None:
                raise ModelError(f"{what}: joint friction is for Revolute and Prismatic joints, "
                                 f"got {joint!r}")
            if model._joint_by_name.get(joint.name, (None, None))[1] is not joint:
                raise ModelError(f"{what}: its joint '{joint.name}' is not part of the model; "
                                 "add the joint to the builder too")
            self.mu[n] = _positive(ctx, e.coefficient, f"{what}: coefficient", True)
            self.v_s[n] = _positive(ctx, e.stiction_velocity, f"{what}: stiction_velocity", False)
            self.bi[n] = model.padded_index(joint.body_i)
            self.bj[n] = model.padded_index(joint.body_j)
            labels = {model.row_labels[r].rpartition(".")[2]: r for r in model.rows_of(joint.name)}
            u_i, u_j, axes = model.reaction_frame(joint.name)
            self.u_j[n] = u_j
            if kind == "revolute":
                self.revolute[n] = True
                if e.pin_radius is None:
                    raise ModelError(f"{what}: a revolute's friction needs pin_radius= (the "
                                     "radius of the pin or journal, [m])")
                self.radius[n] = _positive(ctx, e.pin_radius, f"{what}: pin_radius", False)
                self.axial[n] = _positive(ctx, e.axial_arm, f"{what}: axial_arm", True)
                self.force_rows[n] = [labels[c] for c in "xyz"[:model.dim]]
                self.axis_i[n] = axes[:, 2] if model.dim == 3 else 0.0
            else:
                if e.pin_radius is not None or e.axial_arm:
                    raise ModelError(f"{what}: pin_radius and axial_arm are for revolutes; a "
                                     "prismatic joint's friction is coefficient x normal force")
                self.normal_rows[n] = ([labels["normal"]] if model.dim == 2
                                       else [labels["normal_f"], labels["normal_g"]])
                self.axis_i[n] = axes[:, 0]
        self.names = [e.name for e in elements]
        self._revolutes = np.flatnonzero(self.revolute)
        self._prismatics = np.flatnonzero(~self.revolute)

    # -- the friction forces ---------------------------------------------------------------
    def loads(self, model, fr, lam: np.ndarray, jacobian: bool = False):
        """What each friction is proportional to, from the multipliers ``lam`` (m,):
        ``pin_radius |F_r| + axial_arm |F_a|`` [N m] for a revolute (``F`` its pin force),
        ``|F_normal|`` [N] for a prismatic joint, (k,); with ``jacobian`` also its
        derivative with respect to ``lam``, (k, m)."""
        load = np.zeros(len(self.elements))
        grad = np.zeros((len(self.elements), len(lam))) if jacobian else None
        rev, pri = self._revolutes, self._prismatics
        if len(rev):
            rows = self.force_rows[rev]
            force = lam[rows]  # the pin forces on body j, global axes
            radius = self.radius[rev, None]
            if self.dim == 2:
                size = np.sqrt(np.sum(force * force, axis=1))
                load[rev] = radius[:, 0] * size
                slope = radius * force / np.maximum(size, 1e-300)[:, None]
            else:
                axis = model.body_type.rotate(fr, self.bi[rev], self.axis_i[rev])
                along = np.sum(force * axis, axis=1)
                radial = force - along[:, None] * axis
                size = np.sqrt(np.sum(radial * radial, axis=1))
                load[rev] = radius[:, 0] * size + self.axial[rev] * np.abs(along)
                slope = (radius * radial / np.maximum(size, 1e-300)[:, None]
                         + self.axial[rev, None] * np.sign(along)[:, None] * axis)
            if jacobian:
                grad[rev[:, None], rows] = slope
        if len(pri):
            # the dot-2 rows' vectors are unit normals: their multipliers are the force
            rows = self.normal_rows[pri]
            normal = lam[rows]
            size = np.sqrt(np.sum(normal * normal, axis=1))
            load[pri] = size
            if jacobian:
                grad[pri[:, None], rows] = normal / np.maximum(size, 1e-300)[:, None]
        return (load, grad) if jacobian else load

    def directions(self, model, fr) -> tuple[np.ndarray, np.ndarray]:
        """``(G, speed)``: ``G`` (k, n), the generalized forces of a unit friction of each
        element (1 N m about the axis on body j, -1 N m on body i; 1 N along the axis at
        body j's point, -1 N on body i there), and the sliding speed [m/s] (k,), ``arm``
        times ``G qd`` (by virtual power, ``G qd`` is the relative rate the friction
        opposes)."""
        nb, nc = model.n_bodies, model.n_coords_per_body
        bt = model.body_type
        k = len(self.elements)
        G = np.zeros((k, nb + 1, nc))
        axis = np.zeros((k, 3))
        axis[:, :self.dim] = bt.rotate(fr, self.bi, self.axis_i)
        axis[self.revolute] = [0.0, 0.0, 1.0] if self.dim == 2 else axis[self.revolute]
        point_j = bt.point(fr, self.bj, self.u_j)
        u_i = _to_local(fr, self.bi, point_j)
        plain = np.zeros(1, dtype=np.int64)
        for n in range(k):
            bodies = (self.bj[n:n + 1], self.bi[n:n + 1])
            if self.revolute[n]:
                for body, sign in zip(bodies, (1.0, -1.0)):
                    kernel.torques_into(fr.A, fr.axes, body, sign * axis[n:n + 1], plain, G[n])
            else:
                for body, u, sign in zip(bodies, (self.u_j[n:n + 1], u_i[n:n + 1]), (1.0, -1.0)):
                    kernel.point_forces_into(fr.A, fr.axes, body, u,
                                             sign * axis[n:n + 1, :self.dim], plain, G[n])
        G = G[:, :nb].reshape(k, nb * nc)
        qd = fr.Qd[:nb].ravel()
        return G, np.where(self.revolute, self.radius, 1.0) * (G @ qd)

    def efforts(self, model, fr, lam: np.ndarray, speed: np.ndarray) -> np.ndarray:
        """The frictions (k,): torques [N m] on body j about the axis (revolute), forces [N]
        along it (prismatic), opposing the sliding ``speed`` (see :meth:`directions`)."""
        return -self.mu * self.loads(model, fr, lam) * np.tanh(speed / self.v_s)

    def apply(self, model, fr, lam: np.ndarray, Q: np.ndarray) -> np.ndarray:
        """Add the friction forces of the multipliers ``lam`` into ``Q`` (n_bodies + 1,
        n_coords); returns the frictions (see :meth:`efforts`)."""
        G, speed = self.directions(model, fr)
        effort = self.efforts(model, fr, lam, speed)
        Q[:model.n_bodies] += (effort @ G).reshape(model.n_bodies, -1)
        return effort

    def damping(self, model, fr, lam: np.ndarray) -> np.ndarray:
        """``-dQ/dqd`` (n, n) of the frictions at fixed loads: the regularised law's slope,
        ``mu load sech^2(v / v_s) arm / v_s`` along each ``G G^T`` (what an implicit
        integrator needs near sticking, where the slope is steep)."""
        G, speed = self.directions(model, fr)
        arm = np.where(self.revolute, self.radius, 1.0)
        slope = (self.mu * self.loads(model, fr, lam) * arm / self.v_s
                 / np.cosh(np.minimum(np.abs(speed / self.v_s), 350.0)) ** 2)
        return (G.T * slope) @ G


def _to_local(fr, idx: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Body-frame coordinates (k, dim) of global points (k, dim) in bodies ``idx``."""
    dim = points.shape[1]
    return np.einsum("kba,kb->ka", fr.A[idx], points - fr.Q[idx, :dim])


def consistent_multipliers(model, t: float, fr, solve, lam0: np.ndarray, x0=None):
    """The multipliers and the frictions they imply, solved together.

    ``solve(extra)`` returns ``(lam, x)``: the multipliers (m,) and whatever else the caller
    solves for (or None) with the generalized forces ``extra`` (n,) added to the applied
    ones; it is affine in ``extra``, and ``(lam0, x0)`` is its value without friction. The
    frictions ``e`` (k,) then satisfy ``e = -mu load(lam0 + W e) tanh(v / v_s)``, ``W`` the
    multipliers' response to each unit friction (k more solves), which Newton's method
    solves in k unknowns (:func:`solve_frictions`, which raises where there is none).
    Returns ``(lam, x)`` with the frictions applied."""
    group: FrictionGroup = model.friction
    G, speed = group.directions(model, fr)
    k = len(group.elements)
    W = np.empty((len(lam0), k))
    responses = []
    for n in range(k):
        lam_n, x_n = solve(G[n])
        if lam_n is None:  # a state the solve cannot take (not finite)
            return None, None
        W[:, n] = lam_n - lam0
        responses.append(None if x_n is None else x_n - x0)
    factor = group.mu * np.tanh(speed / group.v_s)
    efforts = solve_frictions(model, t, fr, factor, lambda e: lam0 + W @ e, lambda e: W,
                              -factor * group.loads(model, fr, lam0))
    lam = lam0 + W @ efforts
    x = None if x0 is None else x0 + sum(e * r for e, r in zip(efforts, responses))
    return lam, x


def solve_frictions(model, t: float, fr, factor: np.ndarray, multipliers, slope,
                    efforts: np.ndarray) -> np.ndarray:
    """The frictions ``e`` (k,) consistent with the multipliers they give rise to, by
    Newton's method from ``efforts``: ``e = -factor load(lam(e))``, ``factor`` (k,) being
    ``mu tanh(v / v_s)`` and ``load`` :meth:`FrictionGroup.loads`. ``multipliers(e)`` gives
    ``lam`` (m,), ``slope(e)`` its derivative ``dlam/de`` (m, k) there.

    Raises
    ------
    IntegrationError
        Where no consistent friction is found: the joint is at or near self-locking (its
        friction arm too long for its geometry).
    """
    group: FrictionGroup = model.friction
    scale = float(np.max(np.abs(efforts), initial=0.0))
    for _ in range(MAX_FRICTION_ITERATIONS):
        load, grad = group.loads(model, fr, multipliers(efforts), jacobian=True)
        error = efforts + factor * load
        scale = max(scale, float(np.max(np.abs(efforts))))
        if float(np.max(np.abs(error))) <= FRICTION_TOLERANCE * max(scale, 1e-300):
            return efforts
        jacobian = np.eye(len(efforts)) + factor[:, None] * (grad @ slope(efforts))
        try:
            efforts = efforts - np.linalg.solve(jacobian, error)
        except np.linalg.LinAlgError:
            break
    raise IntegrationError(
        f"'{model.name}': the friction in {', '.join(repr(n) for n in group.names)} and "
        f"the reactions it depends on have no consistent solution at t = {t:.6g} s: the "
        "joint is at or near self-locking, its friction coefficient too high for its "
        "geometry", time=t)


def raise_friction_with_redundancy(model, t: float) -> None:
    """Joint friction needs the reactions, which redundant (or singular) constraints leave
    undetermined."""
    raise AnalysisError(
        f"'{model.name}': joint friction ({', '.join(repr(n) for n in model.friction.names)}) "
        f"needs the joints' reactions, but at t = {t:.6g} s the constraints are redundant or "
        "singular and the reactions are not unique; remove the redundant constraints (see "
        "mb.mobility) to use friction", time=t)
