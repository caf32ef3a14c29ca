"""The built model: :class:`Model`, immutable, made by
:meth:`mbd3d.model.builder.ModelBuilder.build`. It numbers the coordinates and constraint rows,
groups the constraint primitives by type (so that each type is evaluated for all its instances
at once), fixes the sparsity pattern of the Jacobian and of the matrices the solvers factor,
and holds the compiled form of its forces.
"""

from __future__ import annotations

from collections import OrderedDict
from functools import cached_property
from typing import TYPE_CHECKING, Any, Iterable

import numpy as np

from mbd3d.model.body import Body
from mbd3d.model.element import ConstraintElement, PrimitiveSpec
from mbd3d.errors import ModelError
from mbd3d.numerics.patterns import AugmentedPattern, PenaltyPattern
from mbd3d.model.motion import Motion
from mbd3d.model.primitives import PRIMITIVES, RowTable

if TYPE_CHECKING:
    from mbd3d.model.builder import BuildContext, ModelBuilder

__all__ = ["Model", "SPARSE_THRESHOLD"]

#: systems with more unknowns than this (coordinates + constraints) use sparse linear algebra
#: (banded LAPACK, or SuperLU when the bandwidth is large; see mbd3d.numerics.linalg): one augmented
#: solve of a planar or spatial chain costs the same dense and banded at 36 to 50 unknowns on
#: the 2-core reference machine (benchmarks/planar_chain.py --crossover)
SPARSE_THRESHOLD = 48


class _Group:
    """All instances of one primitive type, with their stacked data and row range."""

    def __init__(self, cls, dim, n_bodies, items: list[tuple[int, PrimitiveSpec]], offset: int):
        self.cls = cls
        self.count = len(items)
        self.rows_per = cls.rows(dim)
        self.offset = offset
        self.n_rows = self.count * self.rows_per
        self.bi = np.array([n_bodies if s.body_i.is_ground else s.body_i.index for _, s in items],
                           dtype=np.intp)
        self.bj = np.array([n_bodies if s.body_j.is_ground else s.body_j.index for _, s in items],
                           dtype=np.intp)
        self.params = {}
        for key in cls.params:
            values = [np.asarray(s.params[key]) for _, s in items]
            # stacked, unless their lengths differ (cams' curves): then a list
            same = all(v.shape == values[0].shape for v in values)
            self.params[key] = np.array(values) if same else values
        self.elements = np.array([e for e, _ in items], dtype=np.intp)
        # primitives whose rows depend on time themselves (the spatial rotation driver)
        self.motions = tuple(s.motion for _, s in items) if getattr(cls, "time_dependent", False) else ()
        self.motion_names = ()


class Model:
    """A built, immutable multibody model. Created by :meth:`ModelBuilder.build`.

    Parameters
    ----------
    builder : ModelBuilder
        Its bodies, ground, gravity and name.
    ctx : BuildContext
        The drawing the elements were checked and turned into rows in.
    elements : list of ConstraintElement
        Joints and drivers, in the order added.
    specs : list of (int, PrimitiveSpec)
        Their constraint primitives, each with its element's index.
    forces : list of ForceElement
    sparse : bool or None
        Sparse linear algebra; None: by the model's size.

    Attributes
    ----------
    name : str
    dim : int
        2 (planar) or 3 (spatial).
    body_type : BodyType
        Kinematics of the bodies.
    bodies : tuple of Body
        The moving bodies, in coordinate order.
    joints : tuple of ConstraintElement
        Joints and drivers, in the order they were added.
    forces : tuple of ForceElement
    n_coordinates : int
        Length ``n`` of ``q``.
    n_constraints : int
        Number ``m`` of constraint equations.
    q0, qd0 : ndarray, shape (n,)
        The initial guesses of coordinates and rates given with the bodies.
    charts0 : ndarray (n_bodies + 1, 3, 3) or None
        Spatial models: the reference rotations ``q0`` is relative to (ground last).
    mass : ndarray, shape (n_bodies,)
    inertia : ndarray
        Centroidal inertias, (n_bodies,) for planar bodies.
    gravity : ndarray, shape (dim,)
    row_labels : list of str
        ``"joint.component"`` for each constraint row.
    velocity_rows : ndarray of int
        Rows that constrain velocities only (nonholonomic: a disc rolling on a plane), whose
        ``c`` is zero; the configurations they leave are ``n - (m - len(velocity_rows))``
        dimensional, the velocities ``n - m``.
    coordinate_labels : list of str
        ``"body.coordinate"`` for each coordinate.
    sparse : bool
        Whether the solvers use sparse linear algebra for this model.
    """

    def __init__(self, builder: ModelBuilder, ctx: BuildContext, elements: list,
                 specs: list[tuple[int, PrimitiveSpec]], forces: list, sparse: bool | None):
        bt = builder.body_type
        self.name = builder.name
        self.dim = builder.dim
        self.body_type = bt
        self.bodies = tuple(builder._bodies)
        self.joints = tuple(elements)
        self.forces = tuple(forces)
        self.ground = builder.ground
        self.gravity = builder.gravity.copy()
        nb, nc = len(self.bodies), bt.n_coords
        self.n_bodies = nb
        self.n_coords_per_body = nc
        self.n_coordinates = nb * nc
        self.q0 = np.concatenate([b.q0 for b in self.bodies])
        self.qd0 = np.concatenate([b.qd0 for b in self.bodies])
        self.mass = np.array([b.mass for b in self.bodies])
        self.inertia = np.array([b.inertia for b in self.bodies])
        self.charts0 = ctx.charts
        # generalized forces of gravity, constant: (n_bodies + 1, n_coords), ground row zero
        self._weight = np.zeros((nb + 1, nc))
        self._weight[:nb, :self.dim] = self.mass[:, None] * self.gravity[None, :]
        self._ground_row = np.zeros(nc)  # the ground's coordinates, appended to q by frames
        self._body_by_name = {b.name: b for b in self.bodies}
        self._joint_by_name = {e.name: (i, e) for i, e in enumerate(self.joints)}
        self._force_by_name = {f.name: f for f in self.forces}
        self.coordinate_labels = [f"{b.name}.{c}" for b in self.bodies for c in bt.coordinate_names]

        rows = self._number_rows(self._by_kind(specs))
        labels, row_element, row_is_length, velocity_only, c0 = rows[:5]
        driver_rows, driver_motions, driver_names, offset = rows[5:]
        self.n_constraints = offset
        self._lay_out_rows()
        self.row_labels = labels
        self.row_element = np.array(row_element, dtype=np.intp)
        self._set_scales(specs, np.array(row_is_length, dtype=bool))
        self.c0 = np.array(c0)
        #: rows that constrain velocities only (nonholonomic), whose c is zero
        self.velocity_rows = np.flatnonzero(velocity_only)
        self.driver_rows = np.array(driver_rows, dtype=np.intp)
        self.driver_motions = tuple(driver_motions)
        self.driver_names = tuple(driver_names)
        self._rows_of = {e.name: np.flatnonzero(self.row_element == i)
                         for i, e in enumerate(self.joints)}
        # each joint's reaction frame is laid out when first asked for, from the drawing's
        # frames (a tenth of a 100-link chain's build, which variants of a model never read)
        self._drawing, self._reaction_frames = ctx, {}
        self._hinge_directions = {e.name: e.hinge_directions(ctx, f"joint '{e.name}'")
                                  for e in self.joints if self.dim == 3 and "angle" in
                                  getattr(e, "limit_coordinates", ())}
        self._build_jacobian_pattern()
        if sparse is None:
            sparse = self.n_coordinates + self.n_constraints > SPARSE_THRESHOLD
        self.sparse = bool(sparse)
        self._augmented_pattern = AugmentedPattern(self)

        from mbd3d.model.equations import _Core
        from mbd3d.model.forces import compile_forces
        from mbd3d.model.friction import FrictionGroup, JointFriction
        frictions = [f for f in self.forces if isinstance(f, JointFriction)]
        self.force_groups = compile_forces(
            tuple(f for f in self.forces if not isinstance(f, JointFriction)), ctx)
        #: the joints' friction (mbd3d.model.friction), which needs the multipliers: None
        #: without
        self.friction = FrictionGroup(self, frictions, ctx) if frictions else None
        for arr in (self.q0, self.qd0, self.mass, self.inertia, self.gravity, self.c0,
                    self._ground_row, self._weight,
                    *(() if self.charts0 is None else (self.charts0,))):
            arr.setflags(write=False)
        self._core = _Core(self)

    @cached_property
    def _penalty_pattern(self) -> PenaltyPattern:
        """Generalized-alpha's iteration matrix pattern, laid out when first asked for (the
        other analyses never read it: a fourteenth of a 100-link chain's build)."""
        return PenaltyPattern(self)

    def _by_kind(self, specs: list[tuple[int, PrimitiveSpec]]) -> OrderedDict:
        """The primitive instances grouped by type, in a fixed order, each checked against
        the model's dimension and bodies."""
        by_kind: OrderedDict[str, list] = OrderedDict((k, []) for k in PRIMITIVES)
        for e_index, spec in specs:
            if spec.kind not in PRIMITIVES:
                raise ModelError(f"joint '{self.joints[e_index].name}': unknown primitive "
                                 f"{spec.kind!r}")
            if getattr(PRIMITIVES[spec.kind], "planar_only", False) and self.dim != 2:
                raise ModelError(f"joint '{self.joints[e_index].name}': its {spec.kind} "
                                 "constraint is defined for planar bodies only")
            if getattr(PRIMITIVES[spec.kind], "spatial_only", False) and self.dim != 3:
                raise ModelError(f"joint '{self.joints[e_index].name}': its {spec.kind} "
                                 "constraint is defined for spatial bodies only")
            if spec.body_i.is_ground and spec.body_j.is_ground:
                raise ModelError(f"joint '{self.joints[e_index].name}' connects the ground to itself")
            by_kind[spec.kind].append((e_index, spec))
        return by_kind

    def _number_rows(self, by_kind: OrderedDict) -> tuple:
        """Number the constraint rows type by type (making :attr:`groups`): each row's label,
        joint, kind (length or angle), whether it constrains velocities only and its ``c0``,
        and the rows, motions and names of the one-row drivers; then the row count."""
        nb = self.n_bodies
        self.groups: list[_Group] = []
        offset = 0
        labels: list[str] = []
        row_element: list[int] = []
        row_is_length: list[bool] = []
        velocity_only: list[bool] = []
        c0: list[float] = []
        driver_rows, driver_motions, driver_names = [], [], []
        # each joint's primitive instances: their positions in the row table (row order)
        self._instances_of: dict[str, list[int]] = {e.name: [] for e in self.joints}
        instance = 0
        for kind, items in by_kind.items():
            if not items:
                continue
            group = _Group(PRIMITIVES[kind], self.dim, nb, items, offset)
            self.groups.append(group)
            for local, (e_index, spec) in enumerate(items):
                self._instances_of[self.joints[e_index].name].append(instance)
                instance += 1
                r = group.rows_per
                if len(spec.labels) != r:
                    raise ModelError(f"joint '{self.joints[e_index].name}': primitive {kind} "
                                     f"needs {r} row labels, got {spec.labels!r}")
                name = self.joints[e_index].name
                cls = PRIMITIVES[kind]
                is_length = (cls.length_rows if cls.length_rows is not None
                             else cls.row_is_length(spec.params, self.dim))
                for k in range(r):
                    labels.append(f"{name}.{spec.labels[k]}")
                    row_element.append(e_index)
                    row_is_length.append(is_length)
                    velocity_only.append(k in getattr(cls, "velocity_rows", ()))
                    c0.append(float(spec.c0) if k == 0 else 0.0)
                if spec.motion is not None and group.motions:
                    if not isinstance(spec.motion, Motion):
                        raise ModelError(f"driver '{name}': motion must be an mbd3d Motion, "
                                         f"got {spec.motion!r}")
                    group.motion_names += (name,)
                elif spec.motion is not None:
                    if r != 1:
                        raise ModelError(f"joint '{name}': only one-row primitives can be driven")
                    if not isinstance(spec.motion, Motion):
                        raise ModelError(f"driver '{name}': motion must be an mbd3d Motion, "
                                         f"got {spec.motion!r}")
                    driver_rows.append(offset)
                    driver_motions.append(spec.motion)
                    driver_names.append(name)
                offset += r
        return (labels, row_element, row_is_length, velocity_only, c0, driver_rows,
                driver_motions, driver_names, offset)

    # -- the table of all primitive instances --------------------------------------------------
    def _lay_out_rows(self) -> None:
        """Stack every primitive instance, in row order, into the :class:`RowTable` the
        compiled loop evaluates in one call; the motions of rotation drivers are numbered
        in the same order (rows of ``phi``)."""
        instances, motions, names = [], [], []
        for g in self.groups:
            for local in range(g.count):
                params = {key: value[local] for key, value in g.params.items()}
                motion_row = -1
                if g.motions:
                    motion_row = len(motions)
                    motions.append(g.motions[local])
                    names.append(g.motion_names[local])
                instances.append((g.cls, g.bi[local], g.bj[local], params, motion_row))
        self.row_table = RowTable.from_instances(instances, self.dim)
        self.rotation_motions, self.rotation_motion_names = tuple(motions), tuple(names)

    # -- Jacobian sparsity pattern ---------------------------------------------------------------
    def _build_jacobian_pattern(self) -> None:
        nb, nc = self.n_bodies, self.n_coords_per_body
        all_rows, all_cols = [], []
        for g in self.groups:
            r = g.rows_per
            rows = g.offset + np.arange(g.count)[:, None] * r + np.arange(r)[None, :]
            bodies = np.stack([g.bi, g.bj], axis=1)  # (k, 2)
            cols = bodies[:, :, None] * nc + np.arange(nc)[None, None, :]
            cols = np.where(bodies[:, :, None] == nb, -1, cols)  # ground: no columns
            shape = (g.count, r, 2, nc)
            all_rows.append(np.broadcast_to(rows[:, :, None, None], shape).ravel())
            all_cols.append(np.broadcast_to(cols[:, None, :, :], shape).ravel())
        rows = np.concatenate(all_rows) if all_rows else np.zeros(0, dtype=np.intp)
        cols = np.concatenate(all_cols) if all_cols else np.zeros(0, dtype=np.intp)
        take = np.flatnonzero(cols >= 0)
        rows, cols = rows[take], cols[take]
        order = np.lexsort((cols, rows))
        self._jac_take = take[order]
        self._jac_rows = rows[order]
        self._jac_cols = cols[order]
        counts = np.bincount(self._jac_rows, minlength=self.n_constraints)
        self._jac_indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.intp)
        # where the compiled loop puts entry (2 row + side) n_coords + coordinate: its position
        # in the values of the pattern, -1 for the ground's columns
        self._jac_destination = np.full(self.n_constraints * 2 * nc, -1, dtype=np.int64)
        self._jac_destination[self._jac_take] = np.arange(len(take))

    # -- named access ----------------------------------------------------------------------------
    def body(self, name: str) -> Body:
        """The body called ``name``.

        Parameters
        ----------
        name : str
            As given to :meth:`mbd3d.ModelBuilder.add_body`.
        """
        try:
            return self._body_by_name[name]
        except KeyError:
            raise ModelError(f"model '{self.name}' has no body '{name}'; bodies: "
                             f"{', '.join(self._body_by_name) or '(none)'}") from None

    def joint(self, name: str) -> ConstraintElement:
        """The joint or driver called ``name``.

        Parameters
        ----------
        name : str
            As given to the joint or driver.
        """
        return self._joint_by_name[self._check_joint(name)][1]

    def force(self, name: str) -> Any:
        """The force element called ``name``; a :class:`~mbd3d.ModelError` naming the
        model's forces if there is none.

        Parameters
        ----------
        name : str
            As given to the force element.
        """
        try:
            return self._force_by_name[name]
        except KeyError:
            raise ModelError(f"model '{self.name}' has no force '{name}'; forces: "
                             f"{', '.join(self._force_by_name) or '(none)'}") from None

    def _check_joint(self, name: str) -> str:
        if name not in self._joint_by_name:
            raise ModelError(f"model '{self.name}' has no joint or driver '{name}'; known: "
                             f"{', '.join(self._joint_by_name) or '(none)'}")
        return name

    def rows_of(self, name: str) -> np.ndarray:
        """Constraint rows of the joint or driver ``name``.

        Parameters
        ----------
        name : str
            A joint's or driver's name.
        """
        return self._rows_of[self._check_joint(name)]

    def reaction_frame(self, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Where joint or driver ``name`` acts: ``(u_i, u_j, axes)``, its point in the frames of
        body i and body j [m] and its axes as columns in body i's frame (what reactions are
        reported about and in).

        Parameters
        ----------
        name : str
            A joint's or driver's name.
        """
        frames = self._reaction_frames
        if self._check_joint(name) not in frames:
            frames[name] = self._joint_by_name[name][1].reaction_frame(self._drawing)
        return frames[name]

    def hinge_directions(self, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Where spatial hinge ``name`` (revolute, cylindrical, planar) measures its angle
        from: ``(f_i, g_i, f_j)``, unit vectors normal to its axis, ``f_i`` and ``g_i`` in body
        i's frame, ``f_j`` in body j's (the angle is that of ``f_j`` from ``f_i`` towards
        ``g_i``, see :mod:`mbd3d.io.joint_coordinates`).

        Parameters
        ----------
        name : str
            A revolute, cylindrical or planar joint's name.
        """
        if self._check_joint(name) not in self._hinge_directions:
            raise ModelError(f"'{name}' of model '{self.name}' is not a spatial hinge "
                             "(revolute, cylindrical or planar joint of a spatial model)")
        return self._hinge_directions[name]

    def padded_index(self, body: Body) -> int:
        """Row of ``body`` in the per-body arrays of the solvers (the ground is the last row).

        Parameters
        ----------
        body : Body
            One of the model's bodies, or its ground.
        """
        return self.n_bodies if body.is_ground else body.index

    def coordinates_of(self, body: str | Body) -> slice:
        """The slice of ``q`` owned by ``body``.

        Parameters
        ----------
        body : str or Body
            The body or its name.
        """
        b = self.body(body) if isinstance(body, str) else body
        nc = self.n_coords_per_body
        return slice(b.index * nc, (b.index + 1) * nc)

    def coordinate_index(self, spec: str) -> int:
        """Index in ``q`` of a coordinate named ``"body.coordinate"``, e.g. ``"crank.theta"``.

        Parameters
        ----------
        spec : str
            ``"body.coordinate"``, the coordinate one of ``model.body_type.coordinate_names``.
        """
        body, _, coord = spec.rpartition(".")
        names = self.body_type.coordinate_names
        if not body or coord not in names:
            raise ModelError(f"coordinate {spec!r} must be 'body.c' with c one of {names}")
        return self.coordinates_of(body).start + names.index(coord)

    def _set_scales(self, specs, row_is_length: np.ndarray) -> None:
        """The model's characteristic length and mass, and from them the scale of every
        coordinate and constraint row, so that tolerances, pivots and ranks mean the same for a
        mechanism of micrometres and grams as for one of metres and tonnes.

        The length is the largest of: the spread of the bodies' guessed centres of mass about
        their centroid, the distance of every joint point from its body's centre of mass (of a
        ground point, from the body it holds), and every body's radius of gyration. The mass
        is the mean body mass.
        """
        dim, nb = self.dim, self.n_bodies
        R = self.q0.reshape(nb, self.n_coords_per_body)[:, :dim]
        lengths = [float(np.max(np.linalg.norm(R - R.mean(axis=0), axis=1), initial=0.0))]
        for _, spec in specs:
            for key, value in spec.params.items():
                if not key.startswith("u_"):
                    continue
                body, other = ((spec.body_i, spec.body_j) if key.endswith("_i")
                               else (spec.body_j, spec.body_i))
                if not body.is_ground:  # a point in the body's frame: its offset
                    lengths.append(float(np.linalg.norm(value)))
                elif not other.is_ground:  # a point of the ground: its distance to the body
                    lengths.append(float(np.linalg.norm(np.asarray(value) - R[other.index])))
        J = self.inertia if self.inertia.ndim == 1 else np.trace(self.inertia, axis1=1, axis2=2) / 3
        lengths.append(float(np.max(np.sqrt(J / self.mass))))
        length = max(lengths)
        #: characteristic length of the mechanism [m]
        self.length_scale = length if np.isfinite(length) and length > 0 else 1.0
        #: characteristic mass [kg]: the mean body mass
        self.mass_scale = float(np.mean(self.mass))
        #: scale of each constraint row: the length scale for rows that are lengths, 1 for
        #: rows that are angles or cosines
        self.row_scale = np.where(row_is_length, self.length_scale, 1.0)
        #: which constraint rows are lengths [m] (the others are angles or cosines)
        self.length_rows = row_is_length
        per_body = np.ones(self.n_coords_per_body)
        per_body[:dim] = self.length_scale
        #: scale of each coordinate: the length scale for positions, 1 for angles and
        #: Rodrigues parameters
        self.coordinate_scale = np.tile(per_body, nb)
        #: which coordinates are positions [m] (the others are angles or Rodrigues parameters)
        self.position_coordinates = np.tile(np.arange(self.n_coords_per_body) < dim, nb)

    def joints_of_rows(self, rows: Iterable[int]) -> list[str]:
        """Names of the joints owning ``rows``, without repetition, in row order.

        Parameters
        ----------
        rows : iterable of int
            Constraint row indices.
        """
        seen: dict[str, None] = {}
        for r in rows:
            seen[self.joints[self.row_element[r]].name] = None
        return list(seen)

    def __repr__(self) -> str:
        return (f"Model({self.name!r}: {self.n_bodies} {self.body_type.name} bodies, "
                f"{len(self.joints)} joints/drivers, {self.n_coordinates} coordinates, "
                f"{self.n_constraints} constraints)")
