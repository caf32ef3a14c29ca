"""Terms of the equations of motion ``M qdd + Cq^T lam = Qe + Qv``: mass matrix, applied and
quadratic velocity forces, energies."""

from __future__ import annotations

import threading
from typing import Any, Sequence

import numpy as np
import scipy.sparse as sp

from mbd3d.model.body import Frames, rotate_rows
from mbd3d.numerics.compiled import accelerations as kernel, structures
from mbd3d.numerics.compiled.motions import table as motion_table
from mbd3d.model.constraints import _motion_values, driver_values, frames, motion_phases
from mbd3d.errors import ModelError
from mbd3d.numerics.linalg import SingularMatrix

__all__ = ["mass_matrix", "mass_times", "generalized_forces", "kinetic_energy",
           "potential_energy", "augmented_accelerations"]


def mass_matrix(model, fr: Frames, sparse: bool | None = None):
    """Mass matrix ``M`` (n, n): block diagonal, one block per body. CSR when sparse."""
    blocks = model.body_type.mass_blocks(fr, model.mass, model.inertia)
    nb, nc = blocks.shape[0], blocks.shape[1]
    if model.sparse if sparse is None else sparse:
        return sp.bsr_matrix((blocks, np.arange(nb), np.arange(nb + 1)),
                             shape=(nb * nc, nb * nc)).tocsr()
    M = np.zeros((nb * nc, nb * nc))
    idx = np.arange(nb)[:, None] * nc + np.arange(nc)[None, :]
    M[idx[:, :, None], idx[:, None, :]] = blocks
    return M


def mass_times(blocks: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``M x`` (n,) from the per-body mass blocks (n_bodies, n_coords, n_coords), without
    assembling ``M``."""
    return rotate_rows(blocks, x.reshape(blocks.shape[:2])).ravel()


def generalized_forces(model, t: float, fr: Frames) -> np.ndarray:
    """``Qe + Qv``: gravity, force elements and the quadratic velocity vector, shape (n,)."""
    nb = model.n_bodies
    Q = model._weight.copy()
    if not model.body_type.constant_mass:
        Q[:nb] += model.body_type.quadratic_velocity(fr, model.mass, model.inertia)
    for group in model.force_groups:
        group.apply(model, t, fr, Q)
    return Q[:nb].ravel()


def kinetic_energy(model, q: np.ndarray, qd: np.ndarray, charts: np.ndarray | None = None
                   ) -> float:
    """``T = 1/2 qd^T M qd`` [J] (``charts``: see :func:`mbd3d.model.constraints.frames`).

    Parameters
    ----------
    model : Model
    q, qd : (n,) array_like
        The state (positions in ``charts`` for a spatial model).
    charts : ndarray, optional
        Spatial models: the bodies' reference rotations (default the model's).
    """
    fr = frames(model, q, qd, charts)
    blocks = model.body_type.mass_blocks(fr, model.mass, model.inertia)
    v = np.reshape(qd, blocks.shape[:2])
    return float(0.5 * np.einsum("ki,kij,kj->", v, blocks, v))


def potential_energy(model, q: np.ndarray, charts: np.ndarray | None = None) -> float:
    """Potential energy of gravity (zero at the global origin) and of springs [J].

    Parameters
    ----------
    model : Model
    q : (n,) array_like
        Positions (in ``charts`` for a spatial model).
    charts : ndarray, optional
        Spatial models: the bodies' reference rotations (default the model's).
    """
    nb = model.n_bodies
    R = np.reshape(q, (nb, model.n_coords_per_body))[:, :model.dim]
    V = -float(np.sum(model.mass * (R @ model.gravity)))
    fr = None
    for group in model.force_groups:
        if fr is None:
            fr = frames(model, q, np.zeros_like(q), charts)
        V += group.potential(model, fr)
    return V


class _Core:
    """A model's arrays in the form the compiled core takes them (built once; the
    :class:`~mbd3d.numerics.compiled.structures.ModelArrays` records are made when first asked for, so
    that a model stays picklable)."""

    def __init__(self, model):
        table, pattern = model.row_table, model._augmented_pattern
        nb = model.n_bodies
        self.spatial = model.dim == 3
        self.layout = {"dense": structures.DENSE, "banded": structures.BANDED,
                       "sparse": structures.SPARSE, "range": structures.RANGE}[pattern.layout]
        banded = pattern.layout == "banded"
        range_space = pattern.range_space if pattern.layout == "range" else None
        inertia = np.array(model.inertia)
        if not self.spatial:
            from mbd3d.planar.body import inertia_tensors
            inertia = inertia_tensors(inertia)
        self.driver_rows = np.array(model.driver_rows, dtype=np.int64)
        terms = [m.terms() for m in model.driver_motions + model.rotation_motions]
        #: the motions the tables below were made of (a copy of the model with other motions
        #: shares this core, and evaluates its own in Python: see constraints.driver_values)
        self.motions = (model.driver_motions, model.rotation_motions)
        force_tables = [group.table(model) for group in model.force_groups]
        #: the force groups only Python can evaluate (elements given as functions); the others
        #: are evaluated in the compiled core whatever else a model has in Python
        self.python_forces = tuple(group for group, table in zip(model.force_groups,
                                                                 force_tables) if table is None)
        #: parts only Python can evaluate: those force groups, motions given as functions, and
        #: joint friction (it needs the multipliers)
        self.python_parts = (any(t is None for t in terms) or bool(self.python_forces)
                             or model.friction is not None)
        driver_table = motion_table([] if self.python_parts else terms[:len(model.driver_rows)])
        rotation_table = motion_table([] if self.python_parts
                                      else terms[len(model.driver_rows):])
        #: the fields of the records of the force elements and of the range-space solve (empty
        #: tables: none); made into records with the model's (see arrays), so that it stays
        #: picklable
        self._forces = _force_fields(model, [t for t in force_tables if t is not None])
        self._range_space = _range_space_fields(range_space)
        # writable contiguous copies: the compiled functions are typed (and cached) for those
        self._fields = dict(
            n=model.n_coordinates, solved_here=self.layout != structures.SPARSE,
            python_parts=self.python_parts,
            mass=np.array(model.mass), inertia=inertia, weight=np.array(model._weight[:nb].ravel()),
            code=table.code, bi=table.bi, bj=table.bj, first_row=table.first_row,
            slots=table.slots, coordinate=table.coordinate, motion=table.motion,
            real=np.ascontiguousarray(table.real), curves=np.array(table.curves),
            vector_bodies=table.vector_bodies,
            vector_local=np.ascontiguousarray(table.vector_local),
            n_rows=table.n_rows, driver_rows=self.driver_rows,
            **dict(zip(("driver_first", "driver_kinds", "driver_starts", "driver_params"),
                       driver_table)),
            **dict(zip(("rotation_first", "rotation_kinds", "rotation_starts",
                        "rotation_params"), rotation_table)),
            destination=model._jac_destination, nnz=len(model._jac_take), layout=self.layout,
            rows=np.array(pattern.rows, dtype=np.int64),
            cols=np.array(pattern.cols, dtype=np.int64),
            flat=np.array(pattern.flat if banded else [], dtype=np.int64),
            kl=pattern.kl if banded else 0, ku=pattern.ku if banded else 0,
            perm=np.array(pattern.perm if banded else [], dtype=np.int64),
            entry_scale=np.array(pattern.entry_scale), scale=np.array(pattern.scale),
            pivot_tolerance=float(pattern.pivot_tolerance),
            c0=np.array(model.c0), row_scale=np.array(model.row_scale, dtype=float),
            jac_rows=np.array(model._jac_rows, dtype=np.int64),
            jac_cols=np.array(model._jac_cols, dtype=np.int64),
            no_forces=np.zeros(model.n_coordinates), no_drivers=np.zeros((0, 3)),
            no_motions=np.zeros((0, 3)))
        self._records: dict[tuple[bool, bool], structures.ModelArrays] = {}
        self._penalty = None
        self._scratch = threading.local()
        self.no_forces = self._fields["no_forces"]
        self.no_motions = self._fields["no_motions"]

    def arrays(self, python_accelerations: bool = False,
               python_parts: bool = False) -> "structures.ModelArrays":
        """The model as the compiled functions take it; ``python_accelerations``: the
        accelerations come from Python (redundant rows, joint friction, rigid contacts held at
        rest: :meth:`mbd3d.analyses.explicit.ExplicitRungeKutta._python_accelerations`);
        ``python_parts``: the forces and motions too, whatever the model has in Python
        (generalized-alpha adds the forces of rigid contacts held at rest to them)."""
        key = (bool(python_accelerations), bool(python_parts) or self.python_parts)
        if key not in self._records:
            self._records[key] = _record((self._fields, self._forces, self._range_space),
                                         *key)
        return self._records[key]

    def slopes(self, others: Sequence["_Core"], offsets: Sequence[float]) -> tuple | None:
        """How this model's compiled arrays change per unit of offset, where ``others`` are
        its variants at ``offsets`` (one of them 1) and every floating-point field is affine
        in the offset to rounding (a mass, a spring's stiffness, a joint's point): the
        tables ``(fields, forces, range space)`` of slopes (integer fields must agree, and
        are taken as they are); None where any is not (a normalised axis, a count, contacts),
        or the model has parts in Python."""
        mine = (self._fields, self._forces, self._range_space)
        theirs = [(o._fields, o._forces, o._range_space) for o in others]
        if self.python_parts or any(o.python_parts for o in others):
            return None
        unit = list(offsets).index(1.0)
        slopes = []
        for part, table in enumerate(mine):
            slope = {}
            for name, value in table.items():
                values = [t[part][name] for t in theirs]
                slope[name] = _affine_slope(value, values, offsets, values[unit] if
                                            isinstance(value, (np.ndarray, float)) else None)
                if slope[name] is _NOT_AFFINE:
                    return None
            slopes.append(slope)
        return tuple(slopes)

    def moved_arrays(self, slopes: tuple, offset: float) -> "structures.ModelArrays":
        """The compiled arrays of this model moved by ``offset`` along ``slopes``
        (:meth:`slopes`): the variant at that offset, without building it."""
        tables = tuple({name: value if slope[name] is None else value + offset * slope[name]
                        for name, value in table.items()}
                       for table, slope in zip((self._fields, self._forces,
                                                self._range_space), slopes))
        return _record(tables, False, self.python_parts)

    def penalty_arrays(self, model) -> "structures.PenaltyArrays":
        """Generalized-alpha's iteration matrix pattern as the compiled Newton iteration takes
        it (:mod:`mbd3d.numerics.compiled.generalized_alpha`), made when first asked for."""
        if self._penalty is None:
            pattern = model._penalty_pattern
            banded = pattern.layout == "banded"
            layout = {"dense": structures.DENSE, "banded": structures.BANDED,
                      "sparse": structures.SPARSE}[pattern.layout]
            self._penalty = structures.penalty_arrays(
                np.array(pattern.target, dtype=np.int64),
                np.array(pattern.first, dtype=np.int64),
                np.array(pattern.second, dtype=np.int64), layout,
                np.array(pattern.rows, dtype=np.int64), np.array(pattern.cols, dtype=np.int64),
                np.array(pattern.flat if pattern.layout != "sparse" else [], dtype=np.int64),
                pattern.kl if banded else 0, pattern.ku if banded else 0,
                np.array(pattern.perm if banded else [], dtype=np.int64),
                np.array(pattern.inverse if banded else [], dtype=np.int64),
                np.array(pattern.entry_scale), np.array(pattern.scale),
                float(pattern.pivot_tolerance), np.array(model.coordinate_scale, dtype=float),
                float(model.mass_scale * model.length_scale ** 2))
        return self._penalty

    def workspace(self) -> "structures.Workspace":
        """Scratch arrays for the compiled evaluations of this thread (each thread has its
        own: nothing in them outlives a call, so results never depend on them)."""
        work = getattr(self._scratch, "work", None)
        if work is None:
            work = self._scratch.work = structures.workspace(self.spatial, self.record)
        return work

    @property
    def record(self) -> "structures.ModelArrays":
        """:meth:`arrays` of the accelerations solved in compiled code."""
        return self.arrays()

    def __getstate__(self) -> dict:
        return {key: value for key, value in self.__dict__.items()
                if key not in ("_records", "_scratch", "_penalty")}

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state, _records={}, _penalty=None, _scratch=threading.local())


#: a field that is not affine in a parameter (see _Core.slopes)
_NOT_AFFINE = object()


def _affine_slope(value: Any, values: Sequence[Any], offsets: Sequence[float], unit: Any):
    """The slope per unit of offset of a field whose variants at ``offsets`` are ``values``
    (``unit`` the one at offset 1): None for a field that must not change (integers, flags,
    records: equal in every variant), :data:`_NOT_AFFINE` where it changes otherwise."""
    if isinstance(value, float) or (isinstance(value, np.ndarray) and value.dtype.kind == "f"):
        if any(np.shape(v) != np.shape(value) for v in values):
            return _NOT_AFFINE
        slope = np.asarray(unit, dtype=float) - value
        # rounding: the variants' own and the slope's, a few units of the largest
        tolerance = 32.0 * np.finfo(float).eps * (np.abs(value) + np.abs(unit))
        for o, v in zip(offsets, values):
            if np.any(np.abs(v - value - o * slope) > abs(o) * tolerance + 1e-300):
                return _NOT_AFFINE
        return slope
    if isinstance(value, np.ndarray):
        same = all(isinstance(v, np.ndarray) and np.array_equal(v, value) for v in values)
    elif value is None or isinstance(value, (bool, int, str, np.integer)):
        same = all(type(v) is type(value) and v == value for v in values)
    else:  # a record (the contacts): not compared, not interpolated
        same = all(v is value for v in values)
    return None if same else _NOT_AFFINE


def _record(tables: tuple, python_accelerations: bool, python_parts: bool
            ) -> "structures.ModelArrays":
    """The :class:`~mbd3d.numerics.compiled.structures.ModelArrays` of the tables ``(fields,
    forces, range space)`` of :class:`_Core`."""
    fields, forces, range_space = tables
    fields = dict(fields, python_accelerations=python_accelerations, python_parts=python_parts,
                  forces=structures.force_arrays(*(forces[name] for name in
                                                   structures.FORCE_FIELDS)),
                  range_space=structures.range_space_arrays(
                      *(range_space[name] for name in structures.RANGE_FIELDS)))
    return structures.model_arrays(*(fields[name] for name in structures.MODEL_FIELDS))


def _range_space_fields(pattern) -> dict:
    """The fields of the model's :class:`~mbd3d.numerics.compiled.structures.RangeSpaceArrays`,
    empty for a model solved otherwise (every model's record has the same type: see
    :mod:`~mbd3d.numerics.compiled.structures`)."""
    if pattern is None:
        nothing = np.zeros(0, dtype=np.int64)
        return dict(slot=nothing, body_start=np.zeros(1, dtype=np.int64), positions=nothing,
                    row_position=nothing, bandwidth=0)
    return dict(slot=pattern.slot, body_start=pattern.body_start, positions=pattern.positions,
                row_position=pattern.row_position, bandwidth=pattern.bandwidth)


def _force_fields(model, tables: list[dict]) -> dict:
    """The fields of the model's :class:`~mbd3d.numerics.compiled.structures.ForceArrays` from its
    force groups' tables (each kind at most one group, empty for the kinds the model has not,
    all empty without any; the contacts a record of their own, None without any)."""
    dim = model.dim
    fields = {
        "spring_bodies": np.zeros((0, 2), dtype=np.int64),
        "spring_points": np.zeros((0, 2, dim)), "spring_values": np.zeros((0, 3)),
        "rotary_bodies": np.zeros((0, 2), dtype=np.int64), "rotary_values": np.zeros((0, 3)),
        "rotary_vectors": np.zeros((0, 3, 3)),
        "point_bodies": np.zeros(0, dtype=np.int64), "point_points": np.zeros((0, dim)),
        "point_forces": np.zeros((0, dim)), "point_body_frame": np.zeros(0, dtype=np.int64),
        "torque_bodies": np.zeros(0, dtype=np.int64), "torque_values": np.zeros((0, 3)),
        "torque_body_frame": np.zeros(0, dtype=np.int64), "contacts": None}
    actuators = {"spring": [], "rotary": []}
    for table in tables:
        table = dict(table)
        terms = table.pop("actuators", None)
        if terms is not None:
            actuators["spring" if "spring_bodies" in table else "rotary"] = terms
        if "contact_bodies" in table:
            # a record of their own, None without contacts: see structures.ContactArrays
            fields["contacts"] = structures.contact_arrays(*(
                np.ascontiguousarray(table[f"contact_{name}"])
                for name in structures.CONTACT_FIELDS))
        else:
            fields.update({key: np.ascontiguousarray(value) for key, value in table.items()})
    for kind, terms in actuators.items():
        fields.update(zip((f"{kind}_first", f"{kind}_kinds", f"{kind}_starts",
                           f"{kind}_params"), motion_table(terms)))
    return fields


def python_parts(model, t: float, q: np.ndarray, qd: np.ndarray, charts: np.ndarray,
                 friction: bool = False):
    """What the compiled loops take from Python (see
    :class:`mbd3d.numerics.compiled.callbacks.Run`): the generalized forces (n,) of the force
    elements given as Python functions (the others are compiled), ``(f, f', f'')`` of the
    drivers (n_drivers, 3) and of the rotation drivers' motions (k, 3) at ``(t, q, qd)``,
    ``charts`` the spatial bodies' (ignored for planar ones). With ``friction``, the joints'
    friction of the multipliers of this very state is added to the forces
    (generalized-alpha; the explicit integrators take friction with the accelerations)."""
    charts = charts if model.dim == 3 else None
    extra = np.zeros(model.n_coordinates)
    friction = model.friction is not None and friction
    groups = model._core.python_forces
    if groups or friction:
        fr = frames(model, q, qd, charts)
        Q = np.zeros((model.n_bodies + 1, model.n_coords_per_body))
        for group in groups:
            group.apply(model, t, fr, Q)
        if friction:
            x = augmented_accelerations(model, t, q, qd, charts)
            if x is not None:
                model.friction.apply(model, fr, x[model.n_coordinates:], Q)
        extra = np.ascontiguousarray(Q[:model.n_bodies].ravel())
    drivers = _motion_values(model.driver_motions, model.driver_names, t)
    return extra, drivers, np.ascontiguousarray(motion_phases(model, t))


def augmented_accelerations(model, t: float, q: np.ndarray, qd: np.ndarray,
                            charts: np.ndarray | None = None) -> np.ndarray | None:
    """``(qdd, lam)`` stacked (n + m,) from the augmented equations at ``(t, q, qd)``, or None
    when the state is not finite.

    Everything but the force elements and motions given as Python functions, and the SuperLU
    solve of a large model with a wide band, is one compiled call
    (:mod:`mbd3d.numerics.compiled.accelerations`): the one place this system is assembled and solved.

    Raises
    ------
    SingularMatrix
        When the matrix is singular (dependent constraint rows).
    """
    q, qd = _coordinates(model, q, "q"), _coordinates(model, qd, "qd")
    core = model._core
    # a planar model has no charts (and its compiled functions no spatial code); the kernels
    # are compiled for writable arrays (the model's own charts are read-only), and a
    # read-only argument would compile them all again
    charts = (model.charts0 if charts is None else charts) if core.spatial else None
    if charts is not None and not charts.flags.writeable:
        charts = np.array(charts)
    if not core.python_parts:
        return _solved(model, t, q, qd, charts,
                       *kernel.accelerations_with_parts(core.workspace(), float(t), q, qd,
                                                        charts, core.no_forces, core.no_motions,
                                                        core.no_motions))
    fr = frames(model, q, qd, charts)
    extra = core.no_forces
    if core.python_forces:  # the others are compiled
        Q = np.zeros((model.n_bodies + 1, model.n_coords_per_body))
        for group in core.python_forces:
            group.apply(model, t, fr, Q)
        extra = Q[:model.n_bodies].ravel()
    phi = motion_phases(model, t)
    drivers = _motion_values(model.driver_motions, model.driver_names, t)

    def solve(friction: np.ndarray | None) -> tuple[np.ndarray | None, np.ndarray | None]:
        x = _solved(model, t, q, qd, charts, *kernel.accelerations_with_parts(
            core.workspace(), float(t), q, qd, charts,
            extra if friction is None else extra + friction, phi, drivers))
        return (None, None) if x is None else (x[model.n_coordinates:], x)

    if model.friction is None:
        return solve(None)[1]
    from mbd3d.model.friction import consistent_multipliers  # noqa: PLC0415
    lam, x = solve(None)
    if x is None:
        return None
    return consistent_multipliers(model, t, fr, solve, lam, x)[1]


def _solved(model, t: float, q: np.ndarray, qd: np.ndarray, charts, x: np.ndarray,
            status: int) -> np.ndarray | None:
    """``x = (qdd, lam)`` of a compiled solve of the augmented equations, with its status
    turned into an error or None (see :func:`augmented_accelerations`)."""
    core = model._core
    if status == kernel.NOT_FINITE:
        # a motion or force that cannot be evaluated is named (ModelError); else the state
        # diverged
        driver_values(model, t), motion_phases(model, t)
        if np.all(np.isfinite(q)) and np.all(np.isfinite(qd)):
            generalized_forces(model, t, frames(model, q, qd, charts))
        return None
    if status == kernel.SINGULAR:
        raise SingularMatrix("smallest pivot below tolerance")
    if core.layout == structures.SPARSE:
        n_values = len(x) - model.n_coordinates - model.n_constraints
        return model._augmented_pattern.solve(x[:n_values], x[n_values:])
    return x



def _coordinates(model, x, name: str) -> np.ndarray:
    """``x`` as the contiguous, writable float array (n,) the compiled core takes (a read-only
    one, such as the model's ``q0``, would be a type of its own, compiled again)."""
    if (type(x) is np.ndarray and x.dtype == np.float64 and x.shape == (model.n_coordinates,)
            and x.flags.c_contiguous and x.flags.writeable):
        return x
    try:
        array = np.array(x, dtype=float, order="C")
    except (TypeError, ValueError):
        raise ModelError(f"{name} must be an array of {model.n_coordinates} numbers "
                         f"(the coordinates of '{model.name}'), got {x!r}") from None
    if array.shape != (model.n_coordinates,):
        raise ModelError(f"{name} must have shape ({model.n_coordinates},) for "
                         f"'{model.name}' ({', '.join(model.coordinate_labels[:3])}, ...), "
                         f"got shape {array.shape}")
    return array
