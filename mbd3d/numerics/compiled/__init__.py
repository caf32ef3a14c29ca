"""The compiled numerical core: body kinematics, constraint rows, dynamics terms and dense
solves, written once as loops over bodies and constraint instances and compiled by Numba.

On models of a few bodies the cost of an evaluation is the interpreter's, not the arithmetic's:
dozens of NumPy calls on arrays of a few rows. Here each formula is a loop over its instances,
compiled to machine code on first use and cached on disk (``__pycache__`` beside these files,
or ``NUMBA_CACHE_DIR``), so later runs start without compiling. The cache is keyed on the
content of this whole folder (:mod:`.cache`): an edit of any file here recompiles every kernel
once, so a kernel never runs with a stale copy of a function it calls from another file. The
rest of mbd3d calls these kernels and keeps no NumPy twin of their formulas.

``NUMBA_DISABLE_JIT=1`` (set before mbd3d is imported) runs the same functions interpreted, for
debugging and coverage; they are then slow but give the same numbers.

Modules: :mod:`.rotations` (Rodrigues parameters), :mod:`.bodies` (frames, body vectors, mass
blocks, quadratic velocity forces, the integrated velocities, chart resets), :mod:`.rows` (the
constraint primitives), :mod:`.motions` (prescribed motions), :mod:`.forces` (force elements),
:mod:`.dense` (dense and banded LU with the pivot test of :mod:`mbd3d.numerics.linalg`),
:mod:`.structures` (the records passed around), :mod:`.accelerations` (the augmented
equations in one call), :mod:`.runge_kutta` and :mod:`.integration` (the explicit integrators
and their loop), :mod:`.callbacks` (what the loop asks of Python), and :mod:`.cache` (the
on-disk cache keyed on this folder's content).
"""

from __future__ import annotations

import os

import numba

from mbd3d.numerics.compiled.cache import key_cache_on_folder

__all__ = ["jit", "jit_calling_python", "DISABLED"]

#: whether Numba runs the kernels interpreted (``NUMBA_DISABLE_JIT=1``)
DISABLED = bool(numba.config.DISABLE_JIT)

# before any kernel is decorated: the cache locator is chosen when cache=True is applied
key_cache_on_folder(os.path.dirname(__file__))

#: compiled once per machine and cached; "numpy" error model: 1/0 gives inf as in NumPy, with
#: no exception checks in the loops; no fastmath: results must not depend on reassociation
jit = numba.njit(cache=True, nogil=True, error_model="numpy")

#: for the small functions that call back into Python (Numba's object mode holds the GIL)
jit_calling_python = numba.njit(cache=True)
