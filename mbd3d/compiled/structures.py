"""The two records the compiled core passes around: a model's fixed arrays
(:class:`ModelArrays`) and the scratch arrays of one evaluation (:class:`Workspace`).

They are Numba structure references: one pointer per record in every call, with named fields,
instead of tuples of dozens of arrays whose every member is copied and reference-counted at
each call (which cost both run time and minutes of compilation).
"""

from __future__ import annotations

import numpy as np
from numba.core import types
from numba.experimental import structref

from mbd3d.compiled import DISABLED, jit
from mbd3d.compiled.rows import row_work_size

__all__ = ["ModelArrays", "Workspace", "model_arrays", "workspace", "MODEL_FIELDS",
           "WORKSPACE_FIELDS", "DENSE", "BANDED", "SPARSE", "RANGE"]

#: layouts of the augmented matrix (see mbd3d.linalg): solved in compiled code (RANGE:
#: through Cq M^-1 Cq^T, mbd3d.compiled.range_space), or by the caller (SuperLU)
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


#: the fixed arrays of a model (see mbd3d.equations._Core, which fills them):
#: kinematics and mass, the row table of the primitives (mbd3d.primitives.RowTable), the
#: drivers' rows, where the Jacobian values go, the drivers' and rotation drivers' motions
#: (tables of mbd3d.compiled.motions, used unless python_parts), the augmented matrix's pattern
#: (mbd3d.linalg) and the structure of Cq M^-1 Cq^T (mbd3d.linalg.RangeSpacePattern), the
#: rows' constants and scales, and empty arrays for the parts of a model that are not Python
#: objects
MODEL_FIELDS = (
    "n", "python_accelerations", "python_parts", "solved_here",
    "mass", "inertia", "weight",
    "code", "bi", "bj", "first_row", "slots", "coordinate", "motion", "vector_bodies",
    "vector_local", "n_rows",
    "driver_rows", "destination", "nnz",
    "driver_first", "driver_kinds", "driver_starts", "driver_params",
    "rotation_first", "rotation_kinds", "rotation_starts", "rotation_params",
    "layout", "rows", "cols", "flat", "kl", "ku", "perm", "entry_scale", "scale",
    "pivot_tolerance",
    "range_slot", "range_body_start", "range_positions", "range_row_position",
    "range_bandwidth",
    "c0", "row_scale", "jac_rows", "jac_cols",
    "no_forces", "no_drivers", "no_motions",
)

#: the model the scratch arrays are sized for (so that a call from Python passes one record,
#: not two: each costs about half a microsecond to hand over), and the scratch arrays of one
#: evaluation of the augmented equations
WORKSPACE_FIELDS = (
    "model", "Q", "Qd", "A", "axes", "omega", "kappa", "Gb", "omega_bar",
    "s", "J", "v", "a",
    "C", "data", "gamma", "nu", "row_work", "row_jacobian",
    "blocks", "rhs", "values", "matrix", "band", "permuted", "x",
    "range_jacobian", "range_band", "range_diagonal", "range_vector", "range_forces",
    "drivers", "phi",
)


if not DISABLED:
    class ModelArrays(structref.StructRefProxy):
        """A model's fixed arrays, as the compiled functions take them (fields
        :data:`MODEL_FIELDS`)."""

    class Workspace(structref.StructRefProxy):
        """Scratch arrays of one evaluation (fields :data:`WORKSPACE_FIELDS`)."""

    structref.define_proxy(ModelArrays, ModelArraysType, list(MODEL_FIELDS))
    structref.define_proxy(Workspace, WorkspaceType, list(WORKSPACE_FIELDS))
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


@jit
def model_arrays(*fields):
    """A :class:`ModelArrays` of ``fields`` in the order of :data:`MODEL_FIELDS` (built by a
    compiled, cached function: the proxy's own constructor is compiled in every process)."""
    return ModelArrays(*fields)


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
    range_rows = n_rows if model.layout == RANGE else 0
    range_jacobian = model.range_body_start[-1] * nc if range_rows else 0
    range_band = (model.range_bandwidth + 1) * range_rows
    range_forces = n_bodies * nc if range_rows else 0
    return Workspace(
        model, np.empty((b, nc)), np.empty((b, nc)), np.empty((b, dim, dim)), np.empty((b, 3, n_rot)),
        np.empty((b, 3)), np.empty(b), np.empty((chart_bodies, 3, 3)), np.empty((b, 3)),
        np.empty((n_vectors, dim)), np.empty((n_vectors, dim, n_rot)),
        np.empty((n_vectors, dim)), np.empty((n_vectors, dim)),
        np.empty(n_rows), np.empty(nnz), np.empty(n_rows), np.empty(n_rows),
        np.empty(row_work_size(dim, n_rot)), np.empty((dim, n_rot)),
        np.empty((n_bodies, nc, nc)), np.empty(size), np.empty(n_bodies * nc * nc + 2 * nnz),
        np.empty((dense_size, dense_size)), np.empty(band_size), np.empty(size),
        np.empty(size), np.empty(range_jacobian), np.empty(range_band), np.empty(range_rows),
        np.empty(range_rows), np.empty(range_forces), np.empty((model.driver_rows.shape[0], 3)),
        np.empty((model.rotation_first.shape[0] - 1, 3)))
