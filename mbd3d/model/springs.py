"""Spring-damper-actuators: translational, between two body points, and rotational, across a
hinge. Their forces and their tangent (what implicit integrators add to the iteration matrix)
are compiled (:mod:`mbd3d.numerics.compiled.forces`,
:mod:`mbd3d.numerics.compiled.force_tangents`); an actuator is a constant, a built-in
:class:`~mbd3d.Motion` (compiled too) or a Python function of time.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.model.body import Body
from mbd3d.model.element import ConstraintElement
from mbd3d.model.forces import (ForceElement, block_triplets, _checked, _CompiledForces,
                                _Value, resolve_point)
from mbd3d.numerics.compiled import force_tangents, forces as kernel
from mbd3d.numerics.compiled.motions import CONSTANT

if TYPE_CHECKING:
    from mbd3d.model.builder import BuildContext

__all__ = ["SpringDamper", "RotationalSpringDamper", "coincident_points"]


class _SpringGroup(_CompiledForces):
    """What translational and rotational spring-damper groups share: checked stiffness and
    damping, actuators, and the body indices of each element."""

    def __init__(self, elements: list, ctx: "BuildContext"):
        self.elements = elements
        self.k = np.array([ctx.scalar(e.stiffness, f"spring '{e.name}': stiffness")
                           for e in elements])
        self.c = np.array([ctx.scalar(e.damping, f"spring '{e.name}': damping")
                           for e in elements])
        bad = np.flatnonzero((self.k < 0) | (self.c < 0))
        if bad.size:
            e = elements[bad[0]]
            raise ModelError(f"spring '{e.name}': stiffness and damping must be >= 0, got "
                             f"{e.stiffness}, {e.damping}")
        self.actuators = [(n, _Value(e.actuator, f"spring '{e.name}': actuator", None))
                          for n, e in enumerate(elements) if e.actuator is not None]
        self._rows = None

    def _indices(self, model):
        if self._rows is None:
            self._rows = (np.array([model.padded_index(e.body_i) for e in self.elements]),
                          np.array([model.padded_index(e.body_j) for e in self.elements]))
        return self._rows

    def _bodies(self, model) -> np.ndarray:
        """The padded indices of each element's two bodies, (k, 2)."""
        return np.stack(self._indices(model), axis=1).astype(np.int64)

    def _actuator_terms(self) -> list | None:
        """The compiled terms of every element's actuator (none: an empty sum), or None when
        one is a Python function."""
        terms: list = [[] for _ in self.elements]
        for n, fn in self.actuators:
            if fn.terms is not None:
                terms[n] = fn.terms
            elif fn.constant is not None:
                terms[n] = [(CONSTANT, np.array([fn.constant]))]
            else:
                return None
        return terms

    analytic_tangent = True

    def compiled_tangent(self, model):
        return self._actuator_terms() is not None

    def _actuation(self, t: float) -> np.ndarray:
        """The actuators' tensions or torques at ``t`` in the first column of (k, 3), the
        layout of motion values the compiled forces take."""
        out = np.zeros((len(self.elements), 3))
        for n, fn in self.actuators:
            out[n, 0] = float(_checked(fn(t, None), (), f"spring '{self.elements[n].name}' "
                                       "actuator", t))
        return out


class SpringDamper(ForceElement):
    """Translational spring-damper-actuator between a point of body i and a point of body j.

    The tension ``T = stiffness (l - free_length) + damping dl/dt + actuator(t)`` [N] pulls the
    two points together when positive.

    Parameters
    ----------
    name : str
    body_i, body_j : Body
    point_i, point_j : array_like (dim,), optional
        Attachment points in the body frames [m].
    at_i, at_j : array_like (dim,), optional
        The points in global coordinates of the drawing (the bodies' initial guesses),
        instead of ``point_i``, ``point_j``.
    stiffness : float
        [N/m], >= 0.
    damping : float
        [N s/m], >= 0.
    free_length : float, optional
        [m]; default the distance of the points in the drawing.
    actuator : Motion or callable f(t), optional
        Additional tension [N].
    """

    def __init__(self, name: str, body_i: Body, body_j: Body, *, point_i: Any = None,
                 point_j: Any = None, at_i: Any = None, at_j: Any = None, stiffness: float = 0.0,
                 damping: float = 0.0, free_length: float | None = None, actuator: Any = None):
        self.name, self.body_i, self.body_j = name, body_i, body_j
        self.point_i, self.point_j, self.at_i, self.at_j = point_i, point_j, at_i, at_j
        self.stiffness, self.damping = stiffness, damping
        self.free_length, self.actuator = free_length, actuator

    def bodies(self) -> list[tuple[str, Body]]:
        return [("body_i", self.body_i), ("body_j", self.body_j)]

    @classmethod
    def compile(cls, elements: list, ctx: "BuildContext") -> "_CompiledForces":
        return _SpringDampers(elements, ctx)


def coincident_points(name: str, t: float) -> ModelError:
    """The error of a spring whose two points coincide: its force has no direction."""
    return ModelError(f"spring '{name}': its two points coincide at t = {t:g} s; the force "
                      "direction is undefined (give the spring a non-zero length)")


class _SpringDampers(_SpringGroup):
    def __init__(self, elements: list[SpringDamper], ctx: "BuildContext"):
        super().__init__(elements, ctx)
        ui, uj, l0 = [], [], []
        for e in elements:
            pi = resolve_point(ctx, e.body_i, e.point_i, e.at_i, f"spring '{e.name}': point_i")
            pj = resolve_point(ctx, e.body_j, e.point_j, e.at_j, f"spring '{e.name}': point_j")
            if e.free_length is None:
                length = float(np.linalg.norm(ctx.to_global_point(e.body_j, pj)
                                              - ctx.to_global_point(e.body_i, pi)))
            else:
                length = ctx.scalar(e.free_length, f"spring '{e.name}': free_length")
                if length < 0:
                    raise ModelError(f"spring '{e.name}': free_length must be >= 0, got {length}")
            ui.append(pi), uj.append(pj), l0.append(length)
        self.u_i, self.u_j, self.l0 = np.array(ui), np.array(uj), np.array(l0)
        self._points = np.ascontiguousarray(np.stack([self.u_i, self.u_j], axis=1))
        self._values = np.ascontiguousarray(np.stack([self.k, self.c, self.l0], axis=1))

    def _length(self, model, fr):
        bt = model.body_type
        bi, bj = self._indices(model)
        d = bt.point(fr, bj, self.u_j) - bt.point(fr, bi, self.u_i)
        return d, np.sqrt(np.einsum("kd,kd->k", d, d))

    def apply(self, model, t, fr, Q):
        failed = kernel.spring_forces_into(fr.A, fr.axes, fr.omega3, fr.Q, fr.Qd,
                                           self._bodies(model), self._points,
                                           self._values, self._actuation(t), Q)
        if failed >= 0:
            raise coincident_points(self.elements[failed].name, t)

    def table(self, model):
        terms = self._actuator_terms()
        if terms is None:
            return None
        return {"spring_bodies": self._bodies(model), "spring_points": self._points,
                "spring_values": self._values, "actuators": terms}

    def potential(self, model, fr) -> float:
        _, length = self._length(model, fr)
        return float(0.5 * np.sum(self.k * (length - self.l0) ** 2))

    def tangent(self, model, t, fr, velocity_weight):
        """The tangent of the springs of
        :func:`mbd3d.numerics.compiled.force_tangents.spring_tangent_blocks` as COO triplets."""
        bodies = self._bodies(model)
        return block_triplets(model, bodies, force_tangents.spring_tangent_blocks(
            fr.A, fr.axes, fr.omega3, fr.Q, fr.Qd, bodies, self._points, self._values,
            self._actuation(t), float(velocity_weight)))


class RotationalSpringDamper(ForceElement):
    """Rotational spring-damper-actuator across a revolute: a torque on body j about the hinge
    (opposite on body i) [N m], ``-stiffness (phi - free_angle) - damping dphi/dt + actuator(t)``.

    ``phi`` is the rotation of body j relative to body i: planar, ``theta_j - theta_i``
    (unwrapped, so the spring can be wound by many turns); spatial, the angle about the
    revolute's axis between the bodies' x axes projected on the plane normal to it (as for
    :class:`joints.RotationDriver`), within half a turn of ``free_angle``.

    Parameters
    ----------
    name : str
    body_i, body_j : Body
        Planar models: the two bodies. Spatial models: give ``joint`` instead.
    joint : Revolute, optional
        The revolute across which the spring acts (required in 3D: its axis).
    stiffness : float
        [N m/rad], >= 0.
    damping : float
        [N m s/rad], >= 0.
    free_angle : float, optional
        [rad]; default the relative angle in the drawing.
    actuator : Motion or callable f(t), optional
        Torque on body j [N m].
    """

    def __init__(self, name: str, body_i: Body | None = None, body_j: Body | None = None, *,
                 joint: Any = None, stiffness: float = 0.0, damping: float = 0.0,
                 free_angle: float | None = None, actuator: Any = None):
        if joint is not None:
            body_i, body_j = joint.body_i, joint.body_j
        if body_i is None or body_j is None:
            raise ModelError(f"spring '{name}': give body_i and body_j, or the joint")
        self.name, self.body_i, self.body_j, self.joint = name, body_i, body_j, joint
        self.stiffness, self.damping = stiffness, damping
        self.free_angle, self.actuator = free_angle, actuator

    def bodies(self) -> list[tuple[str, Body]]:
        return [("body_i", self.body_i), ("body_j", self.body_j)]

    @classmethod
    def compile(cls, elements: list, ctx: "BuildContext") -> "_CompiledForces":
        return _RotationalSprings(elements, ctx)


class _RotationalSprings(_SpringGroup):
    def __init__(self, elements: list[RotationalSpringDamper], ctx: "BuildContext"):
        super().__init__(elements, ctx)
        self.planar = ctx.dim == 2
        if not self.planar:
            vectors = []
            for e in elements:
                if e.joint is None:
                    raise ModelError(f"spring '{e.name}': in space, give the Revolute it acts "
                                     "across (joint=): its axis is the spring's axis")
                if not isinstance(e.joint, ConstraintElement):
                    raise ModelError(f"spring '{e.name}': needs a Revolute, got {e.joint!r}")
                vectors.append(e.joint.hinge_directions(ctx, f"spring '{e.name}'"))
            self.f_i, self.g_i, self.f_j = (np.array(v) for v in zip(*vectors))
        free = [e.free_angle for e in elements]
        self.phi0 = np.zeros(len(elements))
        if any(a is None for a in free):
            bi = np.array([ctx.row(e.body_i) for e in self.elements])
            bj = np.array([ctx.row(e.body_j) for e in self.elements])
            drawing = self._angle(ctx.body_type, ctx.frames, bi, bj)
        for n, a in enumerate(free):
            self.phi0[n] = (drawing[n] if a is None
                            else ctx.scalar(a, f"spring '{elements[n].name}': free_angle"))
        self._values = np.ascontiguousarray(np.stack([self.k, self.c, self.phi0], axis=1))
        self._vectors = (np.zeros((0, 3, 3)) if self.planar else
                         np.ascontiguousarray(np.stack([self.f_i, self.g_i, self.f_j], axis=1)))

    def _angle(self, bt, fr, bi, bj) -> np.ndarray:
        if self.planar:
            return fr.Q[bj, 2] - fr.Q[bi, 2]
        f_j = bt.rotate(fr, bj, self.f_j)
        return np.arctan2(np.einsum("kd,kd->k", f_j, bt.rotate(fr, bi, self.g_i)),
                          np.einsum("kd,kd->k", f_j, bt.rotate(fr, bi, self.f_i)))

    def _stretch(self, bt, fr, bi, bj) -> np.ndarray:
        stretch = self._angle(bt, fr, bi, bj) - self.phi0
        # spatial angles are known modulo a turn: take the branch nearest the free angle
        return stretch if self.planar else np.angle(np.exp(1j * stretch))

    def apply(self, model, t, fr, Q):
        kernel.rotary_forces_into(fr.A, fr.axes, fr.omega3, fr.Q, fr.Qd, self._bodies(model),
                                  self._values, self._vectors, self._actuation(t), Q)

    def table(self, model):
        terms = self._actuator_terms()
        if terms is None:
            return None
        return {"rotary_bodies": self._bodies(model), "rotary_values": self._values,
                "rotary_vectors": self._vectors, "actuators": terms}

    def potential(self, model, fr) -> float:
        bi, bj = self._indices(model)
        return float(0.5 * np.sum(self.k * self._stretch(model.body_type, fr, bi, bj) ** 2))

    def tangent(self, model, t, fr, velocity_weight):
        """The tangent of the springs of
        :func:`mbd3d.numerics.compiled.force_tangents.rotary_tangent_blocks` as COO
        triplets."""
        bodies = self._bodies(model)
        return block_triplets(model, bodies, force_tangents.rotary_tangent_blocks(
            fr.A, fr.axes, bodies, self._values, self._vectors, float(velocity_weight)))
