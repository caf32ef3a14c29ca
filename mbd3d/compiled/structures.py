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
           "WORKSPACE_FIELDS", "DENSE", "BANDED", "SPARSE"]

#: layouts of the augmented matrix (see mbd3d.linalg): solved in compiled code, or by the
#: caller (SuperLU)
DENSE, BANDED, SPARSE = 0, 1, 2


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
#: (mbd3d.linalg), the rows' constants and scales, and empty arrays for the parts of a model
#: that are not Python objects
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
    "c0", "row_scale", "jac_rows", "jac_cols",
    "no_forces", "no_drivers", "no_motions",
)

#: the scratch arrays of one evaluation of the augmented equations
WORKSPACE_FIELDS = (
    "Q", "Qd", "A", "axes", "omega", "kappa", "Gb", "omega_bar",
    "s", "J", "v", "a",
    "C", "data", "gamma", "nu", "row_work", "row_jacobian",
    "blocks", "rhs", "values", "matrix", "band", "permuted", "x",
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
    dense = model.layout == DENSE
    banded = model.layout == BANDED
    return Workspace(
        np.empty((b, nc)), np.empty((b, nc)), np.empty((b, dim, dim)), np.empty((b, 3, n_rot)),
        np.empty((b, 3)), np.empty(b), np.empty((b if spatial else 0, 3, 3)), np.empty((b, 3)),
        np.empty((n_vectors, dim)), np.empty((n_vectors, dim, n_rot)),
        np.empty((n_vectors, dim)), np.empty((n_vectors, dim)),
        np.empty(n_rows), np.empty(nnz), np.empty(n_rows), np.empty(n_rows),
        np.empty(row_work_size(dim, n_rot)), np.empty((dim, n_rot)),
        np.empty((n_bodies, nc, nc)), np.empty(size), np.empty(n_bodies * nc * nc + 2 * nnz),
        np.empty((size, size) if dense else (0, 0)),
        np.empty((2 * model.kl + model.ku + 1) * size if banded else 0), np.empty(size),
        np.empty(size), np.empty((model.driver_rows.shape[0], 3)),
        np.empty((model.rotation_first.shape[0] - 1, 3)))
