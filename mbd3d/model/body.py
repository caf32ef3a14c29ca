"""Bodies and the body-kinematics interface that joints and forces are written against.

A :class:`Body` is the user's description of one rigid body (name, mass properties, initial guess).
A :class:`BodyType` holds the kinematics of one kind of body (planar or spatial) and evaluates them
*batched*: every method takes an array of body indices and returns one row per index (the
formulas themselves are compiled loops, :mod:`mbd3d.numerics.compiled.bodies`). Joints never look at the
coordinates themselves; they ask the body type for

- the global position of a body point ``r = R + A u`` and its Jacobian ``dr/dq``,
- a body-fixed vector ``a = A v`` and its Jacobian,
- their velocities and the velocity-dependent parts of their accelerations
  (the terms that do not multiply ``qdd``),

which is what lets one joint library serve planar and spatial bodies.

The ground is not a body with coordinates: in the batched arrays it is one extra row (index
``n_bodies``) whose coordinates are all zero, so its frame is the global frame and its points are
given in global coordinates. Its columns are dropped when the Jacobian is assembled.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

import numpy as np

from mbd3d.numerics.compiled.bodies import body_vectors

__all__ = ["Body", "BodyType", "Frames", "Vectors", "rotate_rows"]


class Body:
    """A rigid body of a model under construction (returned by ``ModelBuilder.add_body``).

    Attributes
    ----------
    name : str
        Unique name, used in results and error messages.
    index : int
        Position of the body in the model; the body owns ``q[index * n_coords:(index + 1) * n_coords]``.
        ``-1`` for the ground.
    mass : float
        Mass [kg].
    inertia : float or ndarray
        Centroidal moment of inertia [kg m^2]: a scalar about the normal axis for planar bodies.
    q0, qd0 : ndarray
        Initial guess of the body's coordinates and their rates (body frame at the centre of mass).
    chart : ndarray (3, 3) or None
        Spatial bodies: the reference rotation ``q0`` is relative to.
    shape : trimesh.Trimesh or None
        The body's geometry in the body frame [m], drawn by the viewer.
    arguments : dict
        The arguments of ``add_body`` that made it (what a model file writes back).
    is_ground : bool
        Whether it is the ground (fixed, no coordinates).
    """

    def __init__(self, name: str, index: int, mass: float, inertia: Any,
                 q0: np.ndarray, qd0: np.ndarray, is_ground: bool = False,
                 chart: np.ndarray | None = None, shape: Any = None):
        self.name = name
        self.shape = shape
        self.chart = chart
        self.index = index
        self.mass = mass
        self.inertia = inertia
        self.q0 = q0
        self.qd0 = qd0
        self.is_ground = is_ground
        self.arguments: dict[str, Any] = {}

    def __repr__(self) -> str:
        if self.is_ground:
            return "Body(ground)"
        return f"Body({self.name!r}, mass={self.mass}, inertia={self.inertia!r})"


class Frames:
    """Per-body kinematic quantities for one state, computed once per evaluation.

    All arrays have one row per body plus a last row for the ground. Every body type gives
    ``Q``, ``R``, ``A`` and the arrays of the compiled core (``axes``, ``omega3``, ``kappa``:
    see :mod:`mbd3d.numerics.compiled.bodies`); ``Qd``, ``Rd`` and ``omega`` exist when velocities were
    given (``Qd`` is None otherwise), and each body type adds its own.
    """

    Qd = None

    def __init__(self, **arrays: np.ndarray):
        self.__dict__.update(arrays)

    def vectors(self, bodies: np.ndarray, local: np.ndarray, velocities: bool = False):
        """``(s, J, v, a)`` of body-frame vectors ``local`` (k, dim) of ``bodies`` (k,): see
        :class:`Vectors` (``v``, ``a`` empty without ``velocities``)."""
        if velocities and self.Qd is None:
            raise ValueError("body vector velocities need frames with velocities")
        return body_vectors(self.A, self.axes, self.omega3, self.kappa,
                            np.asarray(bodies, dtype=np.int64),
                            np.ascontiguousarray(local, dtype=float), velocities)


#: rows above which :func:`rotate_rows` uses einsum: np.matvec's cost per row (tens of ns for
#: 2x2 and 3x3 matrices) outgrows einsum's larger fixed cost beyond a few dozen rows
_EINSUM_ROWS = 32


def rotate_rows(A: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``A[k] @ v[k]`` for every row k: (k, d, d) with (k, d) -> (k, d)."""
    if len(v) > _EINSUM_ROWS:
        return np.einsum("kij,kj->ki", A, v)
    return np.matvec(A, v)


class Vectors:
    """Body-fixed vectors of many bodies in one state: ``s = A v`` in global components and what
    the constraint primitives need of them, one row per vector.

    Attributes
    ----------
    s : ndarray (k, dim)
        Global components of the vectors [m for points' offsets].
    J : ndarray (k, dim, n_rot)
        ``ds/dq`` with respect to the rotation coordinates of each vector's body (the last
        ``n_rot = n_coords - dim`` coordinates): ``d(R + s)/dq = [I, J]`` for a point.
    v : ndarray (k, dim) or None
        ``ds/dt`` [per s]; None when no velocities were given.
    a : ndarray (k, dim) or None
        Velocity-dependent part of ``d2s/dt2`` (the part not multiplying ``qdd``) [per s^2].
    """

    __slots__ = ("s", "J", "v", "a")

    def __init__(self, s: np.ndarray, J: np.ndarray, v: np.ndarray | None = None,
                 a: np.ndarray | None = None):
        self.s, self.J, self.v, self.a = s, J, v, a


class BodyType(ABC):
    """Kinematics of one kind of rigid body, evaluated for many bodies at once.

    Index arrays ``idx`` have shape ``(k,)``; body-frame points ``u`` and vectors ``v`` have shape
    ``(k, dim)``; results are ``(k, dim)`` for positions and ``(k, dim, n_coords)`` for Jacobians.
    """

    #: dimension of the space the bodies move in (2 or 3)
    dim: int
    #: number of coordinates per body
    n_coords: int
    #: names of the coordinates, in order
    coordinate_names: tuple[str, ...]
    #: short name used in messages ("planar", "spatial")
    name: str
    #: whether the mass matrix is constant, so that the quadratic velocity vector vanishes
    constant_mass: bool = False

    # -- model data ------------------------------------------------------------------------------
    @abstractmethod
    def check_inertia(self, inertia: Any, body: str) -> Any:
        """Validate a centroidal inertia given by the user and return it in canonical form."""

    @abstractmethod
    def initial_state(self, body: str, position: Any, orientation: Any
                      ) -> tuple[np.ndarray, np.ndarray | None]:
        """Coordinates of a body at ``position`` with ``orientation``, and its chart (the
        reference rotation the coordinates are relative to; ``None`` for planar bodies)."""

    @abstractmethod
    def initial_rates(self, body: str, velocity: Any, angular_velocity: Any, q0: np.ndarray,
                      chart: np.ndarray | None) -> np.ndarray:
        """Coordinate rates of a body with the given centre-of-mass velocity and angular velocity."""

    def reset_charts(self, q: np.ndarray, qd: np.ndarray | None, charts: np.ndarray | None,
                     limit: float = 1.0, turns: np.ndarray | None = None):
        """Re-reference bodies whose orientation coordinates approach a singularity.

        Returns ``(q, qd, charts, changed)``. Bodies whose coordinates have no singularity
        (planar) return their inputs unchanged.
        """
        return q, qd, charts, False

    # -- the velocities the explicit integrators carry ----------------------------------------
    # An integrator's error control and a chart reset act on the velocities it carries. For
    # spatial bodies those are the angular velocities in body axes, not the rates of the
    # Rodrigues parameters: omega_bar is physical, bounded and unchanged by a chart reset,
    # and for a free body it obeys Euler's equations alone, so a tolerance buys the accuracy
    # it buys elsewhere (the rates of g, carried instead, cost up to 1000 x in accuracy on a
    # tumbling body). Planar bodies carry their coordinates' rates.
    def velocities(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """The integrated velocities ``v`` (n,) of coordinates ``q`` with rates ``qd``."""
        return qd

    def rates(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """The coordinates' rates ``qd`` (n,) of integrated velocities ``v``."""
        return v

    def velocity_derivative(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """``dv/dt`` (n,) from the coordinates' second derivatives ``qdd``."""
        return qdd

    # -- kinematics ------------------------------------------------------------------------------
    # The primitives work with ``s = A v``, the global components of a body-fixed vector, and
    # what follows from it and per-body data (:meth:`vectors`): a body type differs only in
    # its frames, from which one compiled loop serves planar and spatial vectors.
    @abstractmethod
    def frames(self, Q: np.ndarray, Qd: np.ndarray | None = None,
               charts: np.ndarray | None = None) -> Frames:
        """Per-body quantities for coordinates ``Q`` (n_bodies + 1, n_coords), ground row last,
        relative to the bodies' ``charts`` (reference rotations; ignored by planar bodies)."""

    def vectors(self, fr: Frames, idx: np.ndarray, v: np.ndarray, velocities: bool = False
                ) -> Vectors:
        """Everything the constraint primitives need of body-frame vectors ``v`` (k, dim) of
        bodies ``idx``, in one compiled evaluation (see :class:`Vectors`); ``velocities`` asks
        for ``ds/dt`` and the acceleration term too (needs velocities in ``fr``)."""
        s, J, v_dot, a = fr.vectors(idx, v, velocities)
        return Vectors(s, J, v_dot, a) if velocities else Vectors(s, J)

    def rotate(self, fr: Frames, idx: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``s = A v``: global components of body-frame vectors ``v`` (k, dim)."""
        # take(axis=0) gathers rows of stacked arrays for a quarter of what fancy indexing
        # costs, from a few rows (0.25 against 1 us) to 20,000 (63 against 277 us)
        return rotate_rows(fr.A.take(idx, axis=0), v)

    # conveniences for forces and results, built on the methods above
    def point(self, fr: Frames, idx: np.ndarray, u: np.ndarray) -> np.ndarray:
        """Global position ``R + A u`` [m] of body points ``u`` (body frame)."""
        return fr.R.take(idx, axis=0) + self.rotate(fr, idx, u)

    def point_jacobian(self, fr: Frames, idx: np.ndarray, u: np.ndarray) -> np.ndarray:
        """``d(R + A u)/dq``, shape (k, dim, n_coords)."""
        J = np.zeros((len(u), self.dim, self.n_coords))
        J[:, :, :self.dim] = np.eye(self.dim)
        J[:, :, self.dim:] = self.vectors(fr, idx, u).J
        return J

    def point_velocity(self, fr: Frames, idx: np.ndarray, u: np.ndarray) -> np.ndarray:
        """Global velocity of body points [m/s] (needs velocities in ``fr``)."""
        return fr.Rd.take(idx, axis=0) + self.vectors(fr, idx, u, velocities=True).v

    def point_acceleration_term(self, fr: Frames, idx: np.ndarray, u: np.ndarray) -> np.ndarray:
        """Velocity-dependent part of the acceleration of body points [m/s^2]."""
        return self.vectors(fr, idx, u, velocities=True).a

    def vector(self, fr: Frames, idx: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Global components ``A v`` of body-fixed vectors ``v``."""
        return self.rotate(fr, idx, v)

    @abstractmethod
    def cross(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Cross product of rows: a scalar per row in 2D, a vector per row in 3D."""

    # -- dynamics --------------------------------------------------------------------------------
    @abstractmethod
    def mass_blocks(self, fr: Frames, mass: np.ndarray, inertia: np.ndarray) -> np.ndarray:
        """Per-body mass matrices, shape (n_bodies, n_coords, n_coords)."""

    @abstractmethod
    def quadratic_velocity(self, fr: Frames, mass: np.ndarray, inertia: np.ndarray) -> np.ndarray:
        """Per-body quadratic velocity vectors ``Qv``, shape (n_bodies, n_coords) (zero, and
        not asked for, when ``constant_mass``)."""

    @abstractmethod
    def torque_generalized(self, fr: Frames, idx: np.ndarray, torque: np.ndarray) -> np.ndarray:
        """Generalized forces (k, n_coords) of torques given in global components."""

    @abstractmethod
    def wrench(self, fr: Frames, idx: np.ndarray, generalized: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
        """Force [N] and moment about the centre of mass [N m], global components, that produce
        the generalized forces ``generalized`` (k, n_coords) on bodies ``idx``."""

    @abstractmethod
    def angular_velocity(self, fr: Frames, idx: np.ndarray) -> np.ndarray:
        """Angular velocity [rad/s]: (k,) about the normal in 2D, (k, 3) global in 3D."""

    @abstractmethod
    def angular_acceleration(self, fr: Frames, idx: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """Angular acceleration [rad/s^2] of bodies ``idx`` whose coordinate accelerations are
        ``qdd`` (k, n_coords): (k,) in 2D, (k, 3) global in 3D."""

    def relative_angle(self, fr: Frames, idx_i: np.ndarray, idx_j: np.ndarray,
                       jacobian: bool = False) -> np.ndarray:
        """Rotation of body j relative to body i about the plane normal [rad], unwrapped.

        With ``jacobian=True`` return the derivative with respect to the coordinates of
        (i, j) instead, shape (k, 2, n_coords).
        """
