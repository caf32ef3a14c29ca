"""Applied forces: point forces, torques, translational and rotational spring-damper-actuators.

Gravity is given to the :class:`mbd3d.ModelBuilder`. Each element contributes generalized forces
``Q = J^T F`` (``J`` the Jacobian of its point of application) through the body type, so the
same elements serve planar and spatial bodies. Elements of one type are compiled into one group;
spring-dampers are evaluated for all instances at once.

Values given as callables are evaluated once per right-hand side evaluation:

- ``f(t)``, or
- ``f(t, state)`` with ``state`` a :class:`ForceState` of the body point (position, velocity,
  angle, angular velocity), for feedback forces.
"""

from __future__ import annotations

import inspect
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from mbd3d.model.body import Body
from mbd3d.model.element import ConstraintElement
from mbd3d.numerics.checks import finite_scalar, finite_vector
from mbd3d.errors import ModelError
from mbd3d.numerics.compiled import forces as kernel
from mbd3d.numerics.compiled.motions import CONSTANT
from mbd3d.model.motion import Motion
from mbd3d.model.arguments import RecordsArguments

if TYPE_CHECKING:
    from mbd3d.model.builder import BuildContext, Model

__all__ = ["ForceElement", "ForceState", "PointForce", "Torque", "SpringDamper",
           "RotationalSpringDamper"]


@dataclass(frozen=True)
class ForceState:
    """State seen by a feedback force ``f(t, state)``: the application point and its body.

    Attributes
    ----------
    position, velocity : ndarray (dim,)
        Global position [m] and velocity [m/s] of the point of application.
    angle : float
        Body angle [rad] (planar bodies).
    angular_velocity : float or ndarray
        Body angular velocity [rad/s].
    """

    position: np.ndarray
    velocity: np.ndarray
    angle: float
    angular_velocity: Any


class ForceElement(RecordsArguments, ABC):
    """Base class of applied force elements."""

    name: str
    #: classes with the same key are compiled into one group (by the first one's compile)
    group_key: str | None = None

    @abstractmethod
    def bodies(self) -> list[tuple[str, Body]]:
        """``(role, body)`` pairs the element acts on (checked when the model is built)."""

    @classmethod
    @abstractmethod
    def compile(cls, elements: list, ctx: "BuildContext") -> "_CompiledForces":
        """Turn all elements of this class into one evaluable group."""


class _CompiledForces(ABC):
    @abstractmethod
    def apply(self, model: "Model", t: float, fr: Any, Q: np.ndarray) -> None:
        """Add the generalized forces into ``Q`` (n_bodies + 1, n_coords), ground row last."""

    def potential(self, model: "Model", fr: Any) -> float:
        """Potential energy stored in the elements [J] (zero for non-conservative ones)."""
        return 0.0

    def table(self, model: "Model") -> dict | None:
        """The group's data for the compiled core (fields of
        :class:`mbd3d.numerics.compiled.structures.ModelArrays`, and ``"actuators"``: the compiled terms
        of its actuators' motions), or None when a value is a Python function."""
        return None

    #: whether :meth:`tangent` is implemented (else implicit integrators difference
    #: :meth:`apply` over the elements' bodies)
    analytic_tangent = False

    def tangent(self, model: "Model", t: float, fr: Any, velocity_weight: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``-dQ/dq - velocity_weight dQ/dqd`` as COO triplets ``(rows, cols, values)`` over
        the padded coordinates ``(n_bodies + 1) * n_coords`` (ground block last)."""
        raise NotImplementedError

    def _no_tangent(self, model: "Model", t: float, fr: Any, velocity_weight: float
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`tangent` of forces that do not depend on the state: none."""
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, np.zeros(0)


class _Value:
    """A force value given as a constant, ``f(t)`` or ``f(t, state)``, evaluated uniformly.

    ``constant`` holds the value when it is one, ``terms`` the motion's compiled terms when it
    is a built-in :class:`Motion` (both None otherwise): what the compiled core can evaluate
    without calling Python."""

    def __init__(self, value: Any, what: str, size: int | None):
        self.needs_state = False
        self.constant = None
        self.terms = value.terms() if isinstance(value, Motion) else None
        if isinstance(value, Motion):
            self._fn = lambda t, state: value.evaluate(t)[0]
        elif callable(value):
            try:
                n_args = len(inspect.signature(value).parameters)
            except (TypeError, ValueError):
                n_args = 1
            if n_args not in (1, 2):
                raise ModelError(f"{what}: a callable must take (t) or (t, state), it takes "
                                 f"{n_args} arguments")
            self.needs_state = n_args == 2
            self._fn = value if self.needs_state else (lambda t, state: value(t))
        else:
            const = (finite_vector(value, size, what) if size is not None
                     else finite_scalar(value, what))
            self.constant = const
            self._fn = lambda t, state: const

    def __call__(self, t: float, state: "ForceState | None") -> Any:
        return self._fn(t, state)


def _checked(value: Any, shape: tuple, what: str, t: float) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float).reshape(shape)
    except (TypeError, ValueError):
        raise ModelError(f"{what} returned {value!r} at t = {t:g} s; expected shape {shape}") from None
    if not np.all(np.isfinite(arr)):
        raise ModelError(f"{what} returned a non-finite value {value!r} at t = {t:g} s")
    return arr


class PointForce(ForceElement):
    """A force applied at a point of a body.

    Parameters
    ----------
    name : str
    body : Body
    force : array_like (dim,) or callable
        Force [N]: constant, ``f(t)`` or ``f(t, state)`` (see :class:`ForceState`).
    point : array_like (dim,), optional
        Point of application in the body frame [m]; default the centre of mass.
    frame : {"global", "body"}
        Axes in which ``force`` is given; ``"body"`` forces turn with the body (a thruster).
    """

    def __init__(self, name: str, body: Body, force: Any, point: Any = None, frame: str = "global"):
        self.name, self.body, self.force, self.point, self.frame = name, body, force, point, frame
        if frame not in ("global", "body"):
            raise ModelError(f"force '{name}': frame must be 'global' or 'body', got {frame!r}")

    def bodies(self) -> list[tuple[str, Body]]:
        return [("body", self.body)]

    @classmethod
    def compile(cls, elements: list, ctx: "BuildContext") -> "_CompiledForces":
        return _PointForces(elements, ctx)


class _PointForces(_CompiledForces):
    tangent = _CompiledForces._no_tangent  # used where analytic_tangent (state-free forces)

    def __init__(self, elements: list[PointForce], ctx: "BuildContext"):
        self.elements = elements
        dim = ctx.dim
        self.items = []
        for e in elements:
            u = np.zeros(dim) if e.point is None else ctx.vector(e.point, f"force '{e.name}': point")
            fn = _Value(e.force, f"force '{e.name}': force", dim)
            self.items.append((e, u, fn))
        self._points = np.array([u for _, u, _ in self.items]).reshape(-1, dim)
        self._body_frame = np.array([e.frame == "body" for e in elements], dtype=np.int64)
        # fixed forces in global axes at the centres of mass do not depend on the state:
        # implicit integrators need not difference them
        self.analytic_tangent = not any(fn.needs_state or e.frame == "body" or np.any(u)
                                        for e, u, fn in self.items)

    def apply(self, model, t, fr, Q):
        bodies = np.array([model.padded_index(e.body) for e, _, _ in self.items], dtype=np.int64)
        forces = np.empty((len(self.items), model.dim))
        for k, (e, u, fn) in enumerate(self.items):
            state = _state(model, fr, bodies[k:k + 1], u) if fn.needs_state else None
            forces[k] = _checked(fn(t, state), (model.dim,), f"force '{e.name}'", t)
        kernel.point_forces_into(fr.A, fr.axes, bodies, self._points, forces,
                                 self._body_frame, Q)

    def table(self, model):
        if any(fn.constant is None for _, _, fn in self.items):
            return None
        return {"point_bodies": np.array([model.padded_index(e.body) for e, _, _ in self.items],
                                         dtype=np.int64),
                "point_points": self._points,
                "point_forces": np.array([fn.constant for _, _, fn in self.items]),
                "point_body_frame": self._body_frame}


def _state(model, fr, idx, u) -> ForceState:
    bt = model.body_type
    position = bt.point(fr, idx, u[None])[0]
    velocity = bt.point_velocity(fr, idx, u[None])[0]
    angle = float(fr.Q[idx[0], 2]) if model.dim == 2 else np.nan
    omega = bt.angular_velocity(fr, idx)[0]
    return ForceState(position, velocity, angle, omega)


class Torque(ForceElement):
    """A pure torque [N m] on a body: constant, ``f(t)`` or ``f(t, state)``.

    In 2D the torque is a scalar about the normal to the plane (counter-clockwise positive). In
    3D it is a vector in global axes, or in body axes with ``frame="body"`` (it turns with the
    body, like a motor's torque on its rotor).
    """

    def __init__(self, name: str, body: Body, torque: Any, frame: str = "global"):
        self.name, self.body, self.torque, self.frame = name, body, torque, frame
        if frame not in ("global", "body"):
            raise ModelError(f"torque '{name}': frame must be 'global' or 'body', got {frame!r}")

    def bodies(self) -> list[tuple[str, Body]]:
        return [("body", self.body)]

    @classmethod
    def compile(cls, elements: list, ctx: "BuildContext") -> "_CompiledForces":
        return _Torques(elements, ctx)


class _Torques(_CompiledForces):
    tangent = _CompiledForces._no_tangent  # used where analytic_tangent (planar, state-free)

    def __init__(self, elements: list[Torque], ctx: "BuildContext"):
        self.elements = elements
        size = None if ctx.dim == 2 else 3
        self.items = [(e, _Value(e.torque, f"torque '{e.name}'", size)) for e in elements]
        self.shape = () if ctx.dim == 2 else (3,)
        # body axes turn a spatial torque; a planar one is about the normal either way
        self._body_frame = np.array([e.frame == "body" and ctx.dim == 3 for e in elements],
                                    dtype=np.int64)
        # a fixed planar torque does not depend on the state (see _PointForces); a spatial
        # one's generalized force on the Rodrigues parameters does, even in global axes
        self.analytic_tangent = ctx.dim == 2 and not any(fn.needs_state for _, fn in self.items)

    def apply(self, model, t, fr, Q):
        bodies = np.array([model.padded_index(e.body) for e, _ in self.items], dtype=np.int64)
        torques = np.zeros((len(self.items), 3))
        for k, (e, fn) in enumerate(self.items):
            state = (_state(model, fr, bodies[k:k + 1], np.zeros(model.dim)) if fn.needs_state
                     else None)
            n = _checked(fn(t, state), self.shape, f"torque '{e.name}'", t)
            torques[k, 3 - n.size:] = n  # planar: about the normal, (0, 0, n)
        kernel.torques_into(fr.A, fr.axes, bodies, torques, self._body_frame, Q)

    def table(self, model):
        if any(fn.constant is None for _, fn in self.items):
            return None
        torques = np.zeros((len(self.items), 3))
        for k, (_, fn) in enumerate(self.items):
            torques[k, 3 - np.size(fn.constant):] = fn.constant
        return {"torque_bodies": np.array([model.padded_index(e.body) for e, _ in self.items],
                                          dtype=np.int64),
                "torque_values": torques, "torque_body_frame": self._body_frame}


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
        Attachment points in the body frames [m]. Alternatively ``at_i``, ``at_j``: the points
        in global coordinates of the drawing (the bodies' initial guesses).
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


def resolve_point(ctx: "BuildContext", body: Body, local: Any, drawing: Any, what: str
                  ) -> np.ndarray:
    """Body-frame point from either a body-frame ``local`` or a global ``drawing`` point."""
    if local is not None and drawing is not None:
        raise ModelError(f"{what}: give the point either in the body frame or in the drawing, "
                         "not both")
    if local is not None:
        return ctx.vector(local, what)
    if drawing is not None:
        return ctx.to_local_point(body, ctx.vector(drawing, what))
    return np.zeros(ctx.dim)


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

    analytic_tangent = True

    def tangent(self, model, t, fr, velocity_weight):
        """With ``d = p_j - p_i = l e`` and ``G = [-J_i, J_j]`` (``J`` the point Jacobians):
        ``G^T H G``, ``H = (k + w c) e e^T + (T / l)(I - e e^T)``: the spring and damper along
        the line and the turning of the line under tension ``T``. Left out: the change of the
        point Jacobians with the rotations (``dJ^T/dq f``) and of the damper rate with the
        positions, both modest terms a modified Newton iteration absorbs."""
        bt = model.body_type
        bi, bj = self._indices(model)
        d, length = self._length(model, fr)
        e = d / length[:, None]
        d_dot = bt.point_velocity(fr, bj, self.u_j) - bt.point_velocity(fr, bi, self.u_i)
        tension = (self.k * (length - self.l0) + self.c * np.einsum("kd,kd->k", e, d_dot)
                   + self._actuation(t)[:, 0])
        along = np.einsum("kd,ke->kde", e, e)
        H = ((self.k + velocity_weight * self.c)[:, None, None] * along
             + (tension / length)[:, None, None] * (np.eye(e.shape[1]) - along))
        G = np.concatenate([-bt.point_jacobian(fr, bi, self.u_i),
                            bt.point_jacobian(fr, bj, self.u_j)], axis=2)
        blocks = np.einsum("kdm,kde,ken->kmn", G, H, G)
        nc = model.n_coords_per_body
        index = np.concatenate([bi[:, None] * nc + np.arange(nc), bj[:, None] * nc + np.arange(nc)],
                               axis=1)
        rows = np.broadcast_to(index[:, :, None], blocks.shape)
        cols = np.broadcast_to(index[:, None, :], blocks.shape)
        return rows.ravel(), cols.ravel(), blocks.ravel()


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


def compile_forces(elements: tuple, ctx: "BuildContext") -> list[_CompiledForces]:
    """Group force elements by class (or by their shared ``group_key``) and compile each
    group."""
    groups: dict[Any, list] = {}
    for e in elements:
        groups.setdefault(type(e).group_key or type(e), []).append(e)
    return [type(items[0]).compile(items, ctx) for items in groups.values()]
