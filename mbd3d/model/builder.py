"""Building a model: bodies, joints, drivers and forces, then an immutable :class:`Model`.

The builder collects the user's description; :meth:`ModelBuilder.build` checks it, converts joint
data to body frames, groups the constraint primitives by type (so that each type is evaluated for
all its instances at once), fixes the sparsity pattern of the Jacobian and returns a
:class:`Model`. Solvers take the model and plain arrays ``(t, q, qd)`` and never modify it.

Coordinates: body ``k`` owns ``q[k * n_coords:(k + 1) * n_coords]``; constraint rows are numbered
primitive type by primitive type, and ``Model.row_labels`` and :meth:`Model.rows_of` map rows
back to joints.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from mbd3d.model.body import Body, BodyType
from mbd3d.numerics.checks import finite_scalar, finite_vector
from mbd3d.model.element import ConstraintElement, PrimitiveSpec
from mbd3d.errors import ModelError
from mbd3d.model.built import Model

__all__ = ["ModelBuilder", "Model", "BuildContext"]

def _body_type(dim: int) -> BodyType:
    if dim == 2:
        from mbd3d.planar.body import PlanarBody
        return PlanarBody()
    if dim == 3:
        from mbd3d.model.spatial import SpatialBody
        return SpatialBody()
    raise ModelError(f"dim must be 2 (planar) or 3 (spatial), got {dim!r}")


def _check_name(name: Any, what: str) -> str:
    if not isinstance(name, str) or not name.strip():
        raise ModelError(f"{what} name must be a non-empty string, got {name!r}")
    return name


def _charts(bodies: Sequence[Body]) -> np.ndarray:
    """Reference rotations of the bodies, and the identity for the ground (last row)."""
    charts = np.tile(np.eye(3), (len(bodies) + 1, 1, 1))
    for b in bodies:
        charts[b.index] = b.chart
    return charts


class BuildContext:
    """Geometry helpers handed to joints and forces while a model is built.

    Global points and directions of the drawing are converted to body frames with the bodies'
    initial guesses, so global joint data are only meaningful when the guess is the drawing.
    """

    def __init__(self, body_type: BodyType, bodies: Sequence[Body], ground: Body):
        self.body_type = body_type
        self.dim = body_type.dim
        self._bodies = {id(b) for b in bodies} | {id(ground)}
        self.ground = ground
        n = len(bodies)
        Q = np.zeros((n + 1, body_type.n_coords))
        for b in bodies:
            Q[b.index] = b.q0
        self.charts = _charts(bodies) if body_type.dim == 3 else None
        #: frames of the drawing (the bodies' initial guesses), ground last
        self.frames = body_type.frames(Q, charts=self.charts)
        self._n = n

    def row(self, body: Body) -> int:
        """Row of ``body`` in :attr:`frames` (the ground is the last row)."""
        return self._n if body.is_ground else body.index

    def _row(self, body: Body) -> np.ndarray:
        return np.array([self.row(body)])

    def check_body(self, body: Any, element: str, role: str) -> Body:
        """Return ``body`` if it is a body of this model, else raise naming ``element``."""
        if not isinstance(body, Body):
            raise ModelError(f"'{element}': {role} must be a body returned by add_body "
                             f"(or builder.ground), got {body!r}")
        if id(body) not in self._bodies:
            raise ModelError(f"'{element}': {role} '{body.name}' belongs to another model builder")
        return body

    def vector(self, value: Any, what: str) -> np.ndarray:
        """A finite vector of ``dim`` components."""
        return finite_vector(value, self.dim, what)

    def direction(self, value: Any, what: str) -> np.ndarray:
        """A unit vector; a zero vector is refused."""
        arr = self.vector(value, what)
        norm = float(np.linalg.norm(arr))
        if norm < 1e-12:
            raise ModelError(f"{what} must be a non-zero direction, got {value!r}")
        return arr / norm

    def scalar(self, value: Any, what: str, positive: bool = False) -> float:
        return finite_scalar(value, what, positive)

    def rotation(self, body: Body) -> np.ndarray:
        """Rotation matrix of ``body`` at its initial guess (global frame for the ground)."""
        return self.frames.A[self._row(body)][0]

    def to_local_point(self, body: Body, point: np.ndarray) -> np.ndarray:
        """Body-frame coordinates of the global point ``point`` at the initial guess."""
        R = self.frames.Q[self._row(body)][0, :self.dim]
        return self.rotation(body).T @ (point - R)

    def to_local_vector(self, body: Body, vector: np.ndarray) -> np.ndarray:
        return self.rotation(body).T @ vector

    def to_global_point(self, body: Body, u: np.ndarray) -> np.ndarray:
        return self.body_type.point(self.frames, self._row(body), u[None])[0]

    def initial_coordinate(self, body: Body, coordinate: int) -> float:
        return float(self.frames.Q[self._row(body)][0, coordinate])


class ModelBuilder:
    """Collects bodies, joints, drivers and forces; :meth:`build` returns a :class:`Model`.

    Parameters
    ----------
    dim : int
        2 for planar mechanisms.
    gravity : sequence of float, optional
        Gravitational acceleration [m/s^2], global axes, e.g. ``(0, -9.81)``. Default: none.
    name : str
        Name of the model, used in results and messages.

    Examples
    --------
    >>> import mbd3d as mb
    >>> from mbd3d.joints import Revolute
    >>> b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    >>> bar = b.add_body("bar", mass=1.0, inertia=1.0 / 12, position=(0.5, 0.0))
    >>> _ = b.add(Revolute("pin", b.ground, bar, at=(0.0, 0.0)))
    >>> model = b.build()
    >>> model.n_coordinates, model.n_constraints
    (3, 2)
    """

    def __init__(self, dim: int = 2, gravity: Sequence[float] | None = None, name: str = "model"):
        self.body_type = _body_type(dim)
        self.dim = dim
        self.name = _check_name(name, "model")
        self.gravity = (np.zeros(dim) if gravity is None
                        else finite_vector(gravity, dim, "gravity [m/s^2]"))
        nc = self.body_type.n_coords
        self.ground = Body("ground", -1, 0.0, None, np.zeros(nc), np.zeros(nc), is_ground=True)
        self._bodies: list[Body] = []
        self._elements: list[Any] = []
        self._names: dict[str, str] = {"ground": "the ground"}
        self._built = False

    def _claim(self, name: str, what: str) -> None:
        if self._built:
            raise ModelError(f"cannot add {what} '{name}': the model was already built; "
                             "make a new ModelBuilder")
        if name in self._names:
            raise ModelError(f"duplicate name '{name}' for a {what}: already used by "
                             f"{self._names[name]}; names must be unique in a model")
        self._names[name] = f"{what} '{name}'"

    def add_body(self, name: str, *, mass: float | None = None, inertia: Any = None,
                 position: Sequence[float], angle: float | None = None,
                 orientation: Any = None, velocity: Sequence[float] | None = None,
                 angular_velocity: Any = None, shape: Any = None,
                 density: float | None = None) -> Body:
        """Add a rigid body and return its handle.

        Give either ``mass`` and ``inertia``, or a closed ``shape`` and its ``density``.

        Parameters
        ----------
        name : str
            Unique name of the body.
        mass : float
            Mass [kg], positive.
        inertia : float or array_like
            Centroidal inertia [kg m^2]: planar, the moment about the normal to the plane;
            spatial, the 3x3 tensor in body axes (or its 3 principal values), positive definite.
        shape : trimesh.Trimesh, path or dict, optional
            The body's geometry (a mesh, an STL/OBJ/PLY file, or a primitive ``{"box": [x, y,
            z]}``, ``{"cylinder": [radius, height]}`` along z, ``{"sphere": radius}`` centred on
            the body frame), lengths in metres; what the viewer draws. With ``density`` it also gives the mass properties and the body frame
            is put at the mesh's centre of mass (mesh axes; for a planar body the mesh's x-y
            plane is the plane of motion). Without, the mesh is drawn as given, in the body
            frame.
        density : float, optional
            [kg/m^3] of the solid ``shape`` (uniform); replaces ``mass`` and ``inertia``.
        position : (dim,) sequence
            Initial guess of the centre of mass [m], global frame.
        angle : float, optional
            Planar: initial guess of the body angle [rad] (body x axis from the global x axis).
        orientation : array_like, optional
            Spatial: initial orientation, a 3x3 rotation matrix (body axes as columns, global
            components) or a unit quaternion (w, x, y, z); see :mod:`mbd3d.numerics.rotations` for
            axis-angle and Rodrigues parameters. Default: aligned with the global axes.
        velocity : (dim,) sequence, optional
            Initial velocity of the centre of mass [m/s] for forward dynamics (default zero).
        angular_velocity : float or (3,) sequence, optional
            Initial angular velocity [rad/s] for forward dynamics (spatial: global axes).

        Returns
        -------
        Body
            The handle joints and forces refer to.

        Raises
        ------
        ModelError
            Duplicate name, non-positive or non-finite mass, inertia or density, non-finite
            guess, a shape that is not a closed mesh when its mass properties are asked.
        """
        # what a model file writes back (mbd3d.io.model_file)
        arguments = {key: value for key, value in (
            ("mass", mass), ("inertia", inertia), ("position", position), ("angle", angle),
            ("orientation", orientation), ("velocity", velocity),
            ("angular_velocity", angular_velocity), ("shape", shape), ("density", density))
            if value is not None}
        _check_name(name, "body")
        if self._built or name in self._names:
            self._claim(name, "body")  # raises the duplicate / already-built error
        mesh = None
        if density is not None:
            if shape is None:
                raise ModelError(f"body '{name}': density= needs the body's shape= (a closed "
                                 "mesh) to compute its mass properties")
            if mass is not None or inertia is not None:
                raise ModelError(f"body '{name}': give mass= and inertia=, or shape= with "
                                 "density=, not both")
            from mbd3d.model.mass_properties import mesh_properties
            props = mesh_properties(shape, density, name)
            mass, mesh = props.mass, props.mesh
            inertia = props.inertia if self.dim == 3 else props.inertia[2, 2]
        else:
            if mass is None or inertia is None:
                raise ModelError(f"body '{name}': give its mass= [kg] and inertia= [kg m^2], or "
                                 "a closed shape= mesh with its density= [kg/m^3]")
            if shape is not None:
                from mbd3d.model.mass_properties import load_mesh
                mesh = load_mesh(shape, f"body '{name}'")
        mass_value = finite_scalar(mass, f"body '{name}': mass [kg]", positive=True)
        bt = self.body_type
        if self.dim == 3 and angle is not None:
            raise ModelError(f"body '{name}': a spatial body takes orientation=, not angle=")
        if self.dim == 2 and orientation is not None:
            raise ModelError(f"body '{name}': a planar body takes angle= [rad], not orientation=")
        inertia_value = bt.check_inertia(inertia, name)
        q0, chart = bt.initial_state(name, position, angle if self.dim == 2 else orientation)
        qd0 = bt.initial_rates(name, velocity, angular_velocity, q0, chart)
        body = Body(name, len(self._bodies), mass_value, inertia_value, q0, qd0, chart=chart,
                    shape=mesh)
        body.arguments = arguments
        self._claim(name, "body")  # only once valid: a refused body leaves its name free
        self._bodies.append(body)
        return body

    def add(self, element: Any) -> Any:
        """Add a joint, driver or force element; returns it for convenience.

        Parameters
        ----------
        element : ConstraintElement or ForceElement
            A joint, driver, higher pair, contact or force element of this builder's bodies.
        """
        from mbd3d.model.forces import ForceElement

        if not isinstance(element, (ConstraintElement, ForceElement)):
            raise ModelError(f"add() takes a joint, driver or force (from joints/ or mbd3d), "
                             f"got {element!r}")
        _check_name(element.name, type(element).__name__)
        kind = "driver" if getattr(element, "is_driver", False) else (
            "force" if isinstance(element, ForceElement) else "joint")
        self._claim(element.name, kind)
        self._elements.append(element)
        return element

    def build(self, sparse: bool | None = None) -> "Model":
        """Check the description and return the immutable :class:`Model`.

        Parameters
        ----------
        sparse : bool, optional
            Force sparse (True) or dense (False) linear algebra; by default sparse when the number
            of coordinates plus constraints exceeds ``mbd3d.model.built.SPARSE_THRESHOLD``.
        """
        from mbd3d.model.forces import ForceElement

        if not self._bodies:
            raise ModelError(f"model '{self.name}' has no bodies; add some with add_body()")
        ctx = BuildContext(self.body_type, self._bodies, self.ground)
        specs: list[tuple[int, PrimitiveSpec]] = []
        constraint_elements = [e for e in self._elements if isinstance(e, ConstraintElement)]
        for e_index, element in enumerate(constraint_elements):
            if element.body_i is None:  # drivers of absolute coordinates act against the ground
                element.body_i = self.ground
            ctx.check_body(element.body_i, element.name, "body_i")
            ctx.check_body(element.body_j, element.name, "body_j")
            if element.body_i is element.body_j:
                raise ModelError(f"joint '{element.name}' connects body '{element.body_i.name}' "
                                 "to itself; a joint needs two different bodies")
            driven = getattr(element, "joint", None)
            if driven is not None and not any(driven is e for e in constraint_elements):
                # without the joint the driver alone would hold one coordinate, and the
                # "driven" body would fall off its hinge or slider
                raise ModelError(
                    f"driver '{element.name}' drives joint '{driven.name}', which was never "
                    f"added to this model; add that {type(driven).__name__} with builder.add() "
                    "before build(), or drive a joint of this model")
            for spec in element.primitives(ctx):
                specs.append((e_index, spec))
        force_elements = [e for e in self._elements if isinstance(e, ForceElement)]
        for force in force_elements:
            for role, body in force.bodies():
                ctx.check_body(body, force.name, role)
        model = Model(self, ctx, constraint_elements, specs, force_elements, sparse)
        self._built = True
        return model
