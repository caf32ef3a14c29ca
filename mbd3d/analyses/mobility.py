"""Mobility report: Gruebler count against the numerical rank of the constraint Jacobian."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
import scipy.linalg as la

from mbd3d.model import constraints
from mbd3d.numerics.linalg import dependent_rows, jacobian_scaling, summarize

__all__ = ["MobilityReport", "mobility"]


@dataclass(frozen=True)
class MobilityReport:
    """Degrees of freedom of a model at one configuration.

    Attributes
    ----------
    model : str
        The model's name.
    n_bodies, n_coordinates, n_constraints : int
    gruebler : int
        ``n_d = x n_b - n_c`` (x = 3 planar, 6 spatial): the count from the equations alone.
    rank : int
        Numerical rank of ``Cq`` at the configuration.
    dof : int
        ``n_coordinates - rank``: the actual mobility.
    redundant : int
        ``n_constraints - rank``: constraint equations that depend on others.
    dependent : list of list of str
        For each redundant equation, a smallest set of rows ("joint.component") that depend
        on each other, the most involved first.
    free_coordinates : list of str
        ``dof`` coordinates ("body.coordinate") that can be chosen independent: driving these
        (or giving them as ``hold`` to :func:`mbd3d.solve_position`) fixes the mechanism. Found
        by a column-pivoted QR of ``Cq`` (coordinate partitioning); the choice is not unique.
    free_directions : ndarray (n_coordinates, dof)
        Orthonormal basis of the velocities the constraints allow (null space of ``Cq``).
    over_driven : list of str
        Drivers among the dependent rows: they prescribe motions the joints or other drivers
        already fix, and no analysis can follow them.
    velocity_rows : int
        Rows that constrain velocities only (nonholonomic). With them ``dof`` counts the
        independent velocities, and the configurations reachable have the larger dimension
        ``configuration_dof`` (a disc rolling on a plane: 3 and 5).
    configuration_dof : int
        ``n_coordinates`` less the rank of the position-level rows.
    """

    model: str
    n_bodies: int
    n_coordinates: int
    n_constraints: int
    gruebler: int
    rank: int
    dof: int
    redundant: int
    dependent: list = field(default_factory=list)
    free_coordinates: list = field(default_factory=list)
    free_directions: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    over_driven: list = field(default_factory=list)
    velocity_rows: int = 0
    configuration_dof: int = 0

    @property
    def fully_driven(self) -> bool:
        """Whether the drivers fix every degree of freedom, with no row depending on others
        (a kinematic analysis can run)."""
        return self.dof == 0 and self.redundant == 0

    @property
    def message(self) -> str:
        """What the report found, in words: over-driven or redundant (with the sets of rows
        that depend on each other), the degrees of freedom left (nonholonomic ones said so),
        or fully driven."""
        if self.over_driven:
            sets = "; ".join("{" + summarize(group, 8) + "}" for group in self.dependent)
            return (f"over-driven: the driver(s) {summarize(self.over_driven)} prescribe motions "
                    f"the joints or other drivers already fix. Rows that depend on each other, "
                    f"one set per redundant equation: {sets}")
        if self.redundant:
            sets = "; ".join("{" + summarize(group, 8) + "}" for group in self.dependent)
            return (f"{self.redundant} redundant constraint equation(s): the Gruebler count "
                    f"({self.gruebler}) understates the mobility ({self.dof}). Rows that depend "
                    f"on each other, one set per redundant equation: {sets}")
        if self.velocity_rows:
            return (f"{self.dof} degree(s) of freedom of motion in a {self.configuration_dof}-"
                    "dimensional space of configurations (nonholonomic: forward dynamics with "
                    "an explicit method)")
        if self.dof == 0:
            return "fully driven (kinematic analysis possible)"
        return f"{self.dof} degree(s) of freedom (forward dynamics, or add drivers)"

    def __str__(self) -> str:
        return "\n".join([
            f"Mobility of '{self.model}'",
            f"  bodies                 {self.n_bodies}",
            f"  coordinates            {self.n_coordinates}",
            f"  constraint equations   {self.n_constraints}",
            f"  Gruebler n_d = n - m   {self.gruebler}",
            f"  rank of Cq             {self.rank}",
            f"  degrees of freedom     {self.dof}",
            *([f"  velocity-only rows     {self.velocity_rows}",
               f"  configuration freedom  {self.configuration_dof}"] if self.velocity_rows else []),
            *([f"  free coordinates       {', '.join(self.free_coordinates)}"]
              if self.free_coordinates else []),
            f"  => {self.message}",
        ])


def mobility(model, q: Sequence[float] | None = None, t: float = 0.0,
             charts: np.ndarray | None = None) -> MobilityReport:
    """Count coordinates, constraints and degrees of freedom of ``model`` at ``q``.

    Parameters
    ----------
    model : Model
    q : (n,) array_like, optional
        Configuration (default the bodies' initial guesses). The rank is that of the Jacobian
        there, so pass an assembled configuration away from singular positions.
    t : float
        Time [s] (of the drivers' rows).
    charts : ndarray, optional
        Spatial models: the bodies' reference rotations ``q`` is given in (default the
        model's).
    """
    q = np.asarray(model.q0 if q is None else q, dtype=float)
    Cq = constraints.jacobian(model, t, q, constraints.frames(model, q, charts=charts), sparse=False)
    n, m = model.n_coordinates, model.n_constraints
    if m:
        rank, groups = dependent_rows(Cq, scaling=jacobian_scaling(model))
    else:
        rank, groups = 0, []
    redundant = m - rank
    dependent = [[model.row_labels[r] for r in g] for g in groups] if redundant else []
    dof = n - rank
    if m:
        # the columns QR pivots first span the rows' range; the others are free to choose
        # (in the dimensionless Jacobian, so that the choice does not depend on units)
        rows, columns = jacobian_scaling(model)
        _, _, pivots = la.qr(rows[:, None] * Cq * columns[None, :], mode="economic",
                             pivoting=True)
        free = sorted(pivots[rank:])
        _, _, Vt = la.svd(Cq)
        directions = Vt[rank:].T
    else:
        free, directions = range(n), np.eye(n)
    over_driven = [] if not redundant else [
        name for name in model.joints_of_rows(np.concatenate(groups))
        if model.joint(name).is_driver]
    configuration_dof = dof
    if len(model.velocity_rows):
        # nonholonomic rows restrict velocities only: the configurations have the freedom
        # the position-level rows leave
        positions = np.setdiff1d(np.arange(m), model.velocity_rows)
        scale_rows, scale_columns = jacobian_scaling(model)
        configuration_dof = n - (dependent_rows(Cq[positions], scaling=(
            scale_rows[positions], scale_columns))[0] if len(positions) else 0)
    return MobilityReport(model.name, model.n_bodies, n, m, n - m, rank, dof, redundant,
                          dependent, [model.coordinate_labels[k] for k in free], directions,
                          over_driven, len(model.velocity_rows), configuration_dof)
