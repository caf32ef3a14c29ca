"""Applied forces: point forces and torques, and what every force element shares (the
spring-damper-actuators are in :mod:`mbd3d.model.springs`).

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
from mbd3d.numerics.checks import finite_scalar, finite_vector
from mbd3d.errors import ModelError
from mbd3d.numerics.compiled import force_tangents, forces as kernel
from mbd3d.model.motion import Motion
from mbd3d.model.arguments import RecordsArguments

if TYPE_CHECKING:
    from mbd3d.model.builder import BuildContext, Model

__all__ = ["ForceElement", "ForceState", "PointForce", "Torque", "resolve_point"]


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

    def compiled_tangent(self, model: "Model") -> bool:
        """Whether the compiled core evaluates the group's forces and its :meth:`tangent`
        (:func:`mbd3d.numerics.compiled.force_tangents.force_tangent_into`), so that an
        implicit integrator needs nothing from Python for it."""
        return False


def block_triplets(model: "Model", bodies: np.ndarray, blocks: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """COO triplets of ``blocks`` (k, p nc, p nc) over the padded coordinates of the bodies
    ``bodies`` (k, p) of each."""
    nc = model.n_coords_per_body
    index = (bodies[:, :, None] * nc + np.arange(nc)).reshape(len(bodies), -1)
    rows = np.broadcast_to(index[:, :, None], blocks.shape)
    cols = np.broadcast_to(index[:, None, :], blocks.shape)
    return rows.ravel(), cols.ravel(), blocks.ravel()


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
        # a force given as a function of the state is differenced by implicit integrators;
        # the others' tangent is known (see mbd3d.numerics.compiled.force_tangents)
        self.analytic_tangent = not any(fn.needs_state for _, _, fn in self.items)

    def _values(self, model, t, fr) -> tuple[np.ndarray, np.ndarray]:
        """The elements' padded body indices and their forces at ``t``, (k, dim)."""
        bodies = np.array([model.padded_index(e.body) for e, _, _ in self.items], dtype=np.int64)
        forces = np.empty((len(self.items), model.dim))
        for k, (e, u, fn) in enumerate(self.items):
            state = _state(model, fr, bodies[k:k + 1], u) if fn.needs_state else None
            forces[k] = _checked(fn(t, state), (model.dim,), f"force '{e.name}'", t)
        return bodies, forces

    def apply(self, model, t, fr, Q):
        bodies, forces = self._values(model, t, fr)
        kernel.point_forces_into(fr.A, fr.axes, bodies, self._points, forces,
                                 self._body_frame, Q)

    def tangent(self, model, t, fr, velocity_weight):
        """The tangent of :func:`mbd3d.numerics.compiled.force_tangents.point_tangent_blocks`
        as COO triplets."""
        bodies, forces = self._values(model, t, fr)
        return block_triplets(model, bodies[:, None], force_tangents.point_tangent_blocks(
            fr.A, fr.axes, fr.Q, getattr(fr, "charts", None), bodies, self._points, forces,
            self._body_frame))

    def compiled_tangent(self, model):
        return self.analytic_tangent and self.table(model) is not None

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

    Parameters
    ----------
    name : str
    body : Body
        The body it acts on.
    torque : float, array_like, Motion or callable
        [N m]: a number (2D) or a vector (3D), a motion ``f(t)``, or a function ``f(t, state)``
        of a :class:`~mbd3d.ForceState`.
    frame : {"global", "body"}
        The axes a spatial torque is given in.
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

    def __init__(self, elements: list[Torque], ctx: "BuildContext"):
        self.elements = elements
        size = None if ctx.dim == 2 else 3
        self.items = [(e, _Value(e.torque, f"torque '{e.name}'", size)) for e in elements]
        self.shape = () if ctx.dim == 2 else (3,)
        # body axes turn a spatial torque; a planar one is about the normal either way
        self._body_frame = np.array([e.frame == "body" and ctx.dim == 3 for e in elements],
                                    dtype=np.int64)
        # see _PointForces
        self.analytic_tangent = not any(fn.needs_state for _, fn in self.items)

    def _values(self, model, t, fr) -> tuple[np.ndarray, np.ndarray]:
        """The elements' padded body indices and their torques at ``t``, (k, 3)."""
        bodies = np.array([model.padded_index(e.body) for e, _ in self.items], dtype=np.int64)
        torques = np.zeros((len(self.items), 3))
        for k, (e, fn) in enumerate(self.items):
            state = (_state(model, fr, bodies[k:k + 1], np.zeros(model.dim)) if fn.needs_state
                     else None)
            n = _checked(fn(t, state), self.shape, f"torque '{e.name}'", t)
            torques[k, 3 - n.size:] = n  # planar: about the normal, (0, 0, n)
        return bodies, torques

    def apply(self, model, t, fr, Q):
        bodies, torques = self._values(model, t, fr)
        kernel.torques_into(fr.A, fr.axes, bodies, torques, self._body_frame, Q)

    def tangent(self, model, t, fr, velocity_weight):
        """The tangent of :func:`mbd3d.numerics.compiled.force_tangents.torque_tangent_blocks`
        as COO triplets."""
        bodies, torques = self._values(model, t, fr)
        return block_triplets(model, bodies[:, None], force_tangents.torque_tangent_blocks(
            fr.A, fr.axes, fr.Q, getattr(fr, "charts", None), bodies, torques,
            self._body_frame))

    def compiled_tangent(self, model):
        return self.analytic_tangent and self.table(model) is not None

    def table(self, model):
        if any(fn.constant is None for _, fn in self.items):
            return None
        torques = np.zeros((len(self.items), 3))
        for k, (_, fn) in enumerate(self.items):
            torques[k, 3 - np.size(fn.constant):] = fn.constant
        return {"torque_bodies": np.array([model.padded_index(e.body) for e, _ in self.items],
                                          dtype=np.int64),
                "torque_values": torques, "torque_body_frame": self._body_frame}


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


def compile_forces(elements: tuple, ctx: "BuildContext") -> list[_CompiledForces]:
    """Group force elements by class (or by their shared ``group_key``) and compile each
    group."""
    groups: dict[Any, list] = {}
    for e in elements:
        groups.setdefault(type(e).group_key or type(e), []).append(e)
    return [type(items[0]).compile(items, ctx) for items in groups.values()]
