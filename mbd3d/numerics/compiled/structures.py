"""The records the compiled core passes around: a model's fixed arrays (:class:`ModelArrays`,
with its force elements and range-space structure as records of their own), the scratch
arrays of one evaluation (:class:`Workspace`), and generalized-alpha's iteration matrix
pattern (:class:`PenaltyArrays`).

They are Numba structure references: one pointer per record in every call, with named fields,
instead of tuples of dozens of arrays whose every member is copied and reference-counted at
each call (which cost both run time and minutes of compilation).

A model's records have one of four types: planar or spatial (their charts), with contacts or
without. A model without force elements has a force record of empty tables, one not solved in
the range space an empty range-space record: a field that is None for some models and a record
for others makes each combination a type of its own, and every kernel that takes the model was
compiled once per combination (up to 11 times over the test suite, several minutes of a first
run). The one exception is the contacts (``ForceArrays.contacts``: a :class:`ContactArrays`,
or None for a model without contacts, joint stops or contact groups): their code is half of
the whole core's, and a model that has none compiles none of it (``contacts is None`` is
decided as the kernel is compiled), so each kernel is compiled at most four times.
"""

from __future__ import annotations

import numpy as np
from numba.core import types
from numba.experimental import structref

from mbd3d.numerics.compiled import DISABLED, jit
from mbd3d.numerics.compiled.rows import row_work_size

__all__ = ["ModelArrays", "Workspace", "ForceArrays", "ContactArrays", "RangeSpaceArrays",
           "PenaltyArrays", "model_arrays", "force_arrays", "contact_arrays", "range_space_arrays",
           "penalty_arrays", "workspace", "contact_count", "MODEL_FIELDS", "WORKSPACE_FIELDS",
           "FORCE_FIELDS", "CONTACT_FIELDS", "RANGE_FIELDS", "PENALTY_FIELDS", "DENSE", "BANDED",
           "SPARSE", "RANGE"]

#: layouts of the augmented matrix (see mbd3d.numerics.linalg): solved in compiled code (RANGE:
#: through Cq M^-1 Cq^T, mbd3d.numerics.compiled.range_space), or by the caller (SuperLU)
DENSE, BANDED, SPARSE, RANGE = 0, 1, 2, 3


class _Record(types.StructRef):
    def preprocess_fields(self, fields):
        # literal types would make every model a new type and compile everything again
        return tuple((name, types.unliteral(typ)) for name, typ in fields)


@structref.register
class ModelArraysType(_Record):
    pass


@structref.register
class WorkspaceType(_Record):
    pass


@structref.register
class ForceArraysType(_Record):
    pass


@structref.register
class ContactArraysType(_Record):
    pass


@structref.register
class RangeSpaceArraysType(_Record):
    pass


@structref.register
class PenaltyArraysType(_Record):
    pass


#: the fixed arrays of a model (see mbd3d.model.equations._Core, which fills them):
#: kinematics and mass, the row table of the primitives (mbd3d.model.primitives.RowTable), the
#: drivers' rows, where the Jacobian values go, the drivers' and rotation drivers' motions
#: (tables of mbd3d.numerics.compiled.motions, used unless python_parts), the compiled force
#: elements (a ForceArrays: see FORCE_FIELDS), the augmented matrix's pattern
#: (mbd3d.numerics.linalg) and the structure of Cq M^-1 Cq^T (a RangeSpaceArrays: see
#: RANGE_FIELDS), the rows' constants and scales, and empty arrays for the parts of a model that
#: are not Python objects
MODEL_FIELDS = (
    "n", "python_accelerations", "python_parts", "solved_here",
    "mass", "inertia", "weight",
    "code", "bi", "bj", "first_row", "slots", "coordinate", "motion", "real", "curves",
    "vector_bodies",
    "vector_local", "n_rows",
    "driver_rows", "destination", "nnz",
    "driver_first", "driver_kinds", "driver_starts", "driver_params",
    "rotation_first", "rotation_kinds", "rotation_starts", "rotation_params",
    "forces",
    "layout", "rows", "cols", "flat", "kl", "ku", "perm", "entry_scale", "scale",
    "pivot_tolerance",
    "range_space",
    "c0", "row_scale", "jac_rows", "jac_cols",
    "no_forces", "no_drivers", "no_motions",
)

#: the structure of Cq M^-1 Cq^T of a model of the RANGE layout
#: (mbd3d.numerics.patterns.RangeSpacePattern; see mbd3d.numerics.compiled.range_space); empty
#: for the other layouts
RANGE_FIELDS = ("slot", "body_start", "positions", "row_position", "bandwidth")

#: generalized-alpha's iteration matrix (mbd3d.numerics.patterns.PenaltyPattern: where the mass
#: blocks and the products of Jacobian entries go, its layout and scale; see
#: mbd3d.numerics.compiled.generalized_alpha), and the model's coordinate and mass scales
PENALTY_FIELDS = ("target", "first", "second", "layout", "rows", "cols", "flat", "kl", "ku",
                  "perm", "inverse", "entry_scale", "scale", "pivot_tolerance", "coordinate_scale",
                  "mass_unit")

#: the force elements of a model as the compiled core evaluates them
#: (mbd3d.numerics.compiled.forces; filled by mbd3d.model.equations._Core from the force groups' tables): spring-damper-actuators,
#: rotational ones, point forces and torques, and their actuators' motions, and the compliant
#: contacts (a ContactArrays, or None). A model without force elements, or with a value given
#: as a Python function (evaluated in Python), has empty tables
FORCE_FIELDS = (
    "spring_bodies", "spring_points", "spring_values", "rotary_bodies", "rotary_values",
    "rotary_vectors", "point_bodies", "point_points", "point_forces", "point_body_frame",
    "torque_bodies", "torque_values", "torque_body_frame",
    "spring_first", "spring_kinds", "spring_starts", "spring_params",
    "rotary_first", "rotary_kinds", "rotary_starts", "rotary_params",
    "contacts",
)

#: the contacts and joint stops of a model (the contact table of
#: mbd3d.numerics.compiled.contacts: bodies, points, values, curves) with the contact groups'
#: shapes and laws (mbd3d.numerics.compiled.contact_groups)
CONTACT_FIELDS = ("bodies", "points", "values", "curves", "shape_bodies", "shape_points",
                  "shape_values", "pair_laws")

#: the model the scratch arrays are sized for (so that a call from Python passes one record,
#: not two: each costs about half a microsecond to hand over), and the scratch arrays of one
#: evaluation of the augmented equations
WORKSPACE_FIELDS = (
    "model", "Q", "Qd", "A", "axes", "omega", "kappa", "Gb", "omega_bar",
    "s", "J", "v", "a",
    "C", "data", "gamma", "nu", "row_work", "row_jacobian",
    "blocks", "rhs", "values", "matrix", "band", "permuted", "x",
    "range_jacobian", "range_band", "range_diagonal", "range_vector", "range_forces",
    "drivers", "phi", "forces", "spring_actuation", "rotary_actuation",
    "contact_power", "stage_power", "dissipated", "dense_power",
)
#: stages of the explicit methods whose contacts' dissipated power a workspace keeps (DOP853's
#: 12, the next step's first and its interpolant's 3 extra, with room)
POWER_STAGES = 20


if not DISABLED:
    class ModelArrays(structref.StructRefProxy):
        """A model's fixed arrays, as the compiled functions take them (fields
        :data:`MODEL_FIELDS`)."""

    class Workspace(structref.StructRefProxy):
        """Scratch arrays of one evaluation (fields :data:`WORKSPACE_FIELDS`)."""

    class ForceArrays(structref.StructRefProxy):
        """A model's compiled force elements (fields :data:`FORCE_FIELDS`)."""

    class ContactArrays(structref.StructRefProxy):
        """A model's compiled contacts (fields :data:`CONTACT_FIELDS`)."""

    class RangeSpaceArrays(structref.StructRefProxy):
        """The structure of a model's range-space solve (fields :data:`RANGE_FIELDS`)."""

    class PenaltyArrays(structref.StructRefProxy):
        """Generalized-alpha's iteration matrix pattern (fields :data:`PENALTY_FIELDS`)."""

    structref.define_proxy(ModelArrays, ModelArraysType, list(MODEL_FIELDS))
    structref.define_proxy(Workspace, WorkspaceType, list(WORKSPACE_FIELDS))
    structref.define_proxy(ForceArrays, ForceArraysType, list(FORCE_FIELDS))
    structref.define_proxy(ContactArrays, ContactArraysType, list(CONTACT_FIELDS))
    structref.define_proxy(RangeSpaceArrays, RangeSpaceArraysType, list(RANGE_FIELDS))
    structref.define_proxy(PenaltyArrays, PenaltyArraysType, list(PENALTY_FIELDS))
else:
    # interpreted (NUMBA_DISABLE_JIT=1): plain records with the same fields
    class _Plain:
        fields: tuple = ()

        def __init__(self, *values):
            for name, value in zip(self.fields, values, strict=True):
                setattr(self, name, value)

    class ModelArrays(_Plain):
        """A model's fixed arrays (fields :data:`MODEL_FIELDS`)."""

        fields = MODEL_FIELDS

    class Workspace(_Plain):
        """Scratch arrays of one evaluation (fields :data:`WORKSPACE_FIELDS`)."""

        fields = WORKSPACE_FIELDS

    class ForceArrays(_Plain):
        """A model's compiled force elements (fields :data:`FORCE_FIELDS`)."""

        fields = FORCE_FIELDS

    class ContactArrays(_Plain):
        """A model's compiled contacts (fields :data:`CONTACT_FIELDS`)."""

        fields = CONTACT_FIELDS

    class RangeSpaceArrays(_Plain):
        """The structure of a model's range-space solve (fields :data:`RANGE_FIELDS`)."""

        fields = RANGE_FIELDS

    class PenaltyArrays(_Plain):
        """Generalized-alpha's iteration matrix pattern (fields :data:`PENALTY_FIELDS`)."""

        fields = PENALTY_FIELDS


@jit
def model_arrays(n, python_accelerations, python_parts, solved_here, mass, inertia, weight,
                 code, bi, bj, first_row, slots, coordinate, motion, real, curves,
                 vector_bodies, vector_local, n_rows, driver_rows, destination, nnz,
                 driver_first, driver_kinds, driver_starts, driver_params, rotation_first,
                 rotation_kinds, rotation_starts, rotation_params, forces, layout, rows, cols,
                 flat, kl, ku, perm, entry_scale, scale, pivot_tolerance, range_space, c0,
                 row_scale, jac_rows, jac_cols, no_forces, no_drivers, no_motions):
    """A :class:`ModelArrays` of the fields :data:`MODEL_FIELDS` (built by a compiled, cached
    function: the proxy's own constructor is compiled in every process). Its arguments are
    named, not ``*fields``: Numba types star arguments as one tuple, and a tuple holding
    records (``forces``, ``range_space``) is typed in Python, 0.3-0.8 ms a call."""
    return ModelArrays(n, python_accelerations, python_parts, solved_here, mass, inertia,
                       weight, code, bi, bj, first_row, slots, coordinate, motion, real, curves,
                       vector_bodies, vector_local, n_rows, driver_rows, destination, nnz,
                       driver_first, driver_kinds, driver_starts, driver_params, rotation_first,
                       rotation_kinds, rotation_starts, rotation_params, forces, layout, rows,
                       cols, flat, kl, ku, perm, entry_scale, scale, pivot_tolerance,
                       range_space, c0, row_scale, jac_rows, jac_cols, no_forces, no_drivers,
                       no_motions)


@jit
def force_arrays(spring_bodies, spring_points, spring_values, rotary_bodies, rotary_values,
                 rotary_vectors, point_bodies, point_points, point_forces, point_body_frame,
                 torque_bodies, torque_values, torque_body_frame, spring_first, spring_kinds,
                 spring_starts, spring_params, rotary_first, rotary_kinds, rotary_starts,
                 rotary_params, contacts):
    """A :class:`ForceArrays` of the fields :data:`FORCE_FIELDS` (named arguments, as
    :func:`model_arrays`: ``contacts`` may be a record)."""
    return ForceArrays(spring_bodies, spring_points, spring_values, rotary_bodies,
                       rotary_values, rotary_vectors, point_bodies, point_points, point_forces,
                       point_body_frame, torque_bodies, torque_values, torque_body_frame,
                       spring_first, spring_kinds, spring_starts, spring_params, rotary_first,
                       rotary_kinds, rotary_starts, rotary_params, contacts)


@jit
def contact_arrays(*fields):
    """A :class:`ContactArrays` of ``fields`` in the order of :data:`CONTACT_FIELDS`."""
    return ContactArrays(*fields)


@jit
def contact_count(contacts) -> int:
    """The rows of a model's contact table ``contacts`` (:class:`ContactArrays`; None:
    none)."""
    if contacts is None:
        return 0
    return contacts.bodies.shape[0]


@jit
def range_space_arrays(*fields):
    """A :class:`RangeSpaceArrays` of ``fields`` in the order of :data:`RANGE_FIELDS`."""
    return RangeSpaceArrays(*fields)


@jit
def penalty_arrays(*fields):
    """A :class:`PenaltyArrays` of ``fields`` in the order of :data:`PENALTY_FIELDS`."""
    return PenaltyArrays(*fields)


@jit
def _range_sizes(model, n_rows: int, n_bodies: int, nc: int):
    """Sizes of the range-space solve's scratch: the bodies' copies of the Jacobian rows,
    the band of S, its rows and the coordinates; none for the other layouts."""
    if model.layout != RANGE:
        return 0, 0, 0, 0
    range_space = model.range_space
    return (range_space.body_start[-1] * nc, (range_space.bandwidth + 1) * n_rows, n_rows,
            n_bodies * nc)


@jit
def _force_sizes(forces, bodies: int):
    """Rows of the force elements' scratch: bodies (with the ground), springs and rotational
    springs."""
    return bodies, forces.spring_first.shape[0] - 1, forces.rotary_first.shape[0] - 1


@jit
def workspace(spatial: bool, model):
    """A :class:`Workspace` for ``model`` (:class:`ModelArrays`)."""
    nc, dim = (6, 3) if spatial else (3, 2)
    n_rot = nc - dim
    n_bodies = model.mass.shape[0]
    b = n_bodies + 1
    n_vectors = model.vector_bodies.shape[0]
    n_rows = model.n_rows
    nnz = model.nnz
    size = n_bodies * nc + n_rows
    # sizes that depend on the layout and body type, computed before the call: a call of
    # more than 30 arguments with conditionals inside is more than Numba's bytecode reader takes
    dense_size = size if model.layout == DENSE else 0
    band_size = (2 * model.kl + model.ku + 1) * size if model.layout == BANDED else 0
    chart_bodies = b if spatial else 0
    range_jacobian, range_band, range_rows, range_forces = _range_sizes(
        model, n_rows, n_bodies, nc)
    force_bodies, springs, rotary_springs = _force_sizes(model.forces, b)
    contacts = contact_count(model.forces.contacts)
    return Workspace(
        model, np.empty((b, nc)), np.empty((b, nc)), np.empty((b, dim, dim)),
        np.empty((b, 3, n_rot)),
        np.empty((b, 3)), np.empty(b), np.empty((chart_bodies, 3, 3)), np.empty((b, 3)),
        np.empty((n_vectors, dim)), np.empty((n_vectors, dim, n_rot)),
        np.empty((n_vectors, dim)), np.empty((n_vectors, dim)),
        np.empty(n_rows), np.empty(nnz), np.empty(n_rows), np.empty(n_rows),
        np.empty(row_work_size(dim, n_rot)), np.empty((dim, n_rot)),
        np.empty((n_bodies, nc, nc)), np.empty(size), np.empty(n_bodies * nc * nc + 2 * nnz),
        np.empty((dense_size, dense_size)), np.empty(band_size), np.empty(size),
        np.empty(size), np.empty(range_jacobian), np.empty(range_band), np.empty(range_rows),
        np.empty(range_rows), np.empty(range_forces), np.empty((model.driver_rows.shape[0], 3)),
        np.empty((model.rotation_first.shape[0] - 1, 3)), np.empty((force_bodies, nc)),
        np.empty((springs, 3)), np.empty((rotary_springs, 3)), np.zeros(contacts),
        np.zeros((POWER_STAGES, contacts)), np.zeros((6, contacts)),
        np.zeros((8, contacts)))
