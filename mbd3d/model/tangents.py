"""How a model's equations change with one of its parameters, from its variants: the model
built with the parameter at four values about its own (``OFFSETS`` steps; made by
:mod:`mbd3d.analyses.sensitivities`, which names parameters).

- The constraint rows' change ``C_p`` is exact in how the rows depend on their data: the
  body-frame vectors' change (a fourth-order central difference of the variants' vectors:
  exact to rounding where they are linear in the parameter, as a joint's point is, about
  1e-12 relative where they are not, as a normalised axis) goes through the compiled rows'
  own chain rule (:func:`mbd3d.model.primitives.rows_along_vectors`); the constants ``c0``
  and the motions ``f(t)`` enter with slope -1, a rotation driver's angle through its row's
  rate. Rows whose own numbers change (a gear's ratio, a cam's curve) are differenced.
- Anything else (velocity and acceleration rows, forces, masses, a reaction) is the same
  central difference along a path that moves the state with its sensitivity and the model
  through its variants (:meth:`ModelTangent.along`): 1e-11 relative or better where the
  quantity is smooth, exact to rounding where it is linear in the parameter (a mass, a
  stiffness).
"""

from __future__ import annotations

import math
from typing import Any, Callable, Sequence

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.model import constraints
from mbd3d.model.primitives import evaluate_rows, rows_along_vectors
from mbd3d.numerics.compiled.sensitivity_steps import LEVELS, OFFSETS, REACH, REFINE

__all__ = ["ModelTangent", "OFFSETS", "REACH", "reach", "slope", "state_scale"]

# OFFSETS: the stencil's offsets, in steps, of the fourth-order central difference
# :func:`slope`; REACH: the largest move of the state, relative to its scale, per step of
# :meth:`ModelTangent.along` (its stencil's error, about this to the fourth power, stays near
# rounding); the variants at a shorter step are made at steps ``2**-k`` shorter, ``k`` a
# multiple of ``REFINE`` up to ``_MOST_REFINED``. One definition, the compiled stages' (the
# forward sensitivities apply the same rule in compiled code).
_MOST_REFINED = REFINE * (LEVELS - 1)


def slope(values: Sequence[Any], step: float) -> np.ndarray:
    """The fourth-order central difference of ``values`` (at
    :data:`~mbd3d.numerics.compiled.sensitivity_steps.OFFSETS` steps): differences first, so
    that what does not change gives exactly zero."""
    return (8.0 * (np.asarray(values[2]) - values[1]) - (np.asarray(values[3]) - values[0])
            ) / (12.0 * step)


def reach(scale: np.ndarray, *moves: np.ndarray) -> float:
    """How far a state moves along ``moves`` (its parts' sensitivities, e.g. ``s`` and
    ``s'``) per unit of the parameter, relative to ``scale`` (one array per part, or one for
    all): the largest ``|move_i| / scale_i``, for :meth:`ModelTangent.along`."""
    move = np.concatenate([np.ravel(m) for m in moves])
    return float(np.max(np.abs(move) / np.broadcast_to(scale, move.shape), initial=0.0))


def state_scale(model, *rates: np.ndarray) -> np.ndarray:
    """What a change of a state ``(q, *rates)`` (e.g. ``(q, qd, qdd)``) is measured against
    (:func:`reach`): positions against the model's scale (lengths in its length, angles in
    radians), each rate against that scale per second (squared) or its own size."""
    scale = model.coordinate_scale
    return np.concatenate([scale] + [scale + np.abs(r) for r in rates])


class ModelTangent:
    """The tangent of ``model`` along a parameter whose variants (the model with the parameter
    at ``OFFSETS`` times ``step`` from its value) are ``variants``; messages name ``what``.

    Raises
    ------
    ModelError
        Variants whose structure differs from the model's (other rows, another number of
        coordinates): the parameter changes what the model is, not its numbers.
    """

    def __init__(self, model, variants: Sequence[Any], step: float, what: str,
                 finer: Callable[[int], tuple[Sequence[Any], float]] | None = None):
        self.model, self.variants, self.step = model, tuple(variants), float(step)
        #: ``finer(k) -> (variants, step / 2**k)``: the variants at a shorter step (see
        #: :meth:`along`), made when first needed and kept
        self._finer, self._refined = finer, {}
        self._slopes = None  # the compiled arrays' slopes (finer_arrays), () where not affine
        table = model.row_table
        for variant in variants:
            other = variant.row_table
            if (variant.n_coordinates != model.n_coordinates or other.n_rows != table.n_rows
                    or any(not np.array_equal(getattr(other, key), getattr(table, key))
                           for key in ("code", "bi", "bj", "first_row", "slots"))):
                raise ModelError(f"{what}: changing it changes the model's coordinates or "
                                 "constraint rows, not only their numbers")
        #: d(body-frame vectors)/dp (V, dim) and dc0/dp (m,)
        self.vectors = slope([v.row_table.vector_local for v in variants], step)
        self.c0 = slope([v.c0 for v in variants], step)
        self._rows_own = not all(
            np.array_equal(v.row_table.real, table.real)
            and np.array_equal(v.row_table.curves, table.curves) for v in variants)

    def along(self, quantity: Callable[[Any, float], Any], reach: float = 0.0,
              make_finer: bool = True) -> np.ndarray:
        """``d quantity/dp``: the central difference of ``quantity(variant, offset)`` over the
        variants, ``offset`` the parameter's change [its unit] at which each is (move the
        state by its sensitivity times ``offset``).

        ``reach``: how far the state moves per unit of ``offset``, relative to its scale (the
        largest ``|s_i| / scale_i``). Where a step of the variants would move it further than
        :data:`~mbd3d.numerics.compiled.sensitivity_steps.REACH`, the stencil's error (the
        fourth power of that move) would show: a crank whose angle changes by 16 rad per N m
        of its torque, differenced with steps of 2e-3 N m, was off by 4e-4. The change is
        then the parameter's alone (the variants with the state held, ``offset`` 0) plus
        the state's alone (``quantity(model, offset)``, the model itself with the state moved
        by a shorter step); or, where the tangent can make variants at a shorter step
        (:meth:`finer`), those, at a step short enough (four
        evaluations instead of eight: the rounding of a shorter step is the same as the
        state's alone, ``eps / REACH`` of the change). Without ``make_finer`` only variants
        already made are used (building them costs more than a few evaluations saved)."""
        if reach * self.step <= REACH:
            return slope([quantity(v, o * self.step) for o, v in zip(OFFSETS, self.variants)],
                         self.step)
        # halvings of the step, by fours (at most four sets of variants made per parameter)
        k = REFINE * math.ceil(math.log2(reach * self.step / REACH) / REFINE)
        if self.can_refine and k <= _MOST_REFINED and (make_finer or k in self._refined):
            variants, step = self.finer(k)
            return slope([quantity(v, o * step) for o, v in zip(OFFSETS, variants)], step)
        h = REACH / reach
        return (slope([quantity(self.model, o * h) for o in OFFSETS], h)
                + slope([quantity(v, 0.0) for v in self.variants], self.step))

    @property
    def can_refine(self) -> bool:
        """Whether the tangent can make its variants at a shorter step (:meth:`finer`)."""
        return self._finer is not None

    def finer(self, k: int) -> tuple[tuple, float]:
        """``(variants, step)``: the variants at a step ``2**-k`` of the first [the
        parameter's unit], made when first asked for and kept."""
        if k not in self._refined:
            variants, step = self._finer(k)
            self._refined[k] = (tuple(variants), float(step))
        return self._refined[k]

    def finer_arrays(self, k: int) -> tuple[list, float]:
        """``(arrays, step)``: the compiled arrays of the variants at a step ``2**-k`` of the
        first, interpolated from the model's and its variants' where every number of them is
        affine in the parameter (checked on the variants, to rounding: a mass, a stiffness, a
        joint's point), else those of the variants built (:meth:`finer`)."""
        if self._slopes is None:
            self._slopes = self.model._core.slopes([v._core for v in self.variants],
                                                   OFFSETS) or ()
        if self._slopes and k not in self._refined:
            fraction = 2.0 ** -k  # the slopes are per step of the first variants
            return ([self.model._core.moved_arrays(self._slopes, o * fraction)
                     for o in OFFSETS], self.step * fraction)
        variants, step = self.finer(k)
        return [v._core.arrays() for v in variants], step

    def constraint_rows(self, t: float, fr) -> np.ndarray:
        """``C_p`` (m,) at time ``t`` [s] and the frames ``fr`` of a state [row units per
        unit of the parameter]."""
        model = self.model
        if self._rows_own:
            return self.along(lambda v, _: constraints.evaluate(v, t, fr, True, False)[0])
        phi = constraints.motion_phases(model, t)
        C_p = -self.c0
        if np.any(self.vectors):
            C_p = C_p + rows_along_vectors(model.row_table, fr, phi, self.vectors)
        if len(model.driver_rows):
            f_p = self.along(lambda v, _: constraints.driver_values(v, t)[0])
            C_p[model.driver_rows] -= f_p
        if len(phi):
            phi_p = self.along(lambda v, _: constraints.motion_phases(v, t)[:, 0])
            for row in np.flatnonzero(phi_p):
                C_p = C_p - phi_p[row] * _rotation_rates(model, fr, phi, row)
        return C_p


def _rotation_rates(model, fr, phi: np.ndarray, row: int) -> np.ndarray:
    """``nu`` (m,) of the rows with ``phi'`` = 1 for rotation motion ``row`` and 0 for the
    others: ``-dC/dphi`` of that motion's rows."""
    unit = phi.copy()
    unit[:, 1:] = 0.0
    unit[row, 1] = 1.0
    return evaluate_rows(model.row_table, fr, unit, False, False, False, True)[3]
