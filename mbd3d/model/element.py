"""What a constraint element (joint or driver) must tell the model builder.

Joints live in :mod:`mbd3d.joints`; they derive from :class:`ConstraintElement` and
describe themselves as a list of :class:`PrimitiveSpec` (see :mod:`mbd3d.model.primitives`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from mbd3d.errors import ModelError
from mbd3d.model.body import Body
from mbd3d.model.motion import Motion
from mbd3d.model.arguments import RecordsArguments

if TYPE_CHECKING:
    from mbd3d.model.builder import BuildContext

__all__ = ["ConstraintElement", "PrimitiveSpec"]


@dataclass
class PrimitiveSpec:
    """One instance of a constraint primitive contributed by an element.

    Attributes
    ----------
    kind : str
        Key of the primitive in :data:`mbd3d.model.primitives.PRIMITIVES`.
    body_i, body_j : Body
        The two bodies (either may be the ground, not both).
    params : dict
        Body-frame data of the primitive (points ``u_i``, ``u_j``, vectors ``v_i``, ``v_j``, ...).
    labels : tuple of str
        Name of each row, e.g. ``("x", "y")``; appears in results and error messages.
    c0 : float
        Constant subtracted from ``c(q)`` (one-row primitives).
    motion : Motion or None
        Prescribed ``f(t)`` subtracted from the row (drivers).
    """

    kind: str
    body_i: Body
    body_j: Body
    params: dict[str, Any] = field(default_factory=dict)
    labels: tuple[str, ...] = ()
    c0: float = 0.0
    motion: Motion | None = None


class ConstraintElement(RecordsArguments, ABC):
    """Base class of joints and drivers.

    Subclasses set ``name``, ``body_i`` and ``body_j`` and implement :meth:`primitives`.
    """

    name: str
    body_i: Body
    body_j: Body
    #: drivers report an ``effort``; joints report reactions only
    is_driver: bool = False
    #: drivers: the unit of the effort ("N m" for a torque, "N" for a force)
    effort_unit: str = ""
    #: the joint friction the element can carry (:class:`mbd3d.JointFriction`): "revolute"
    #: (a pin's), "prismatic" (a slide's) or None
    friction_kind: str | None = None

    @abstractmethod
    def primitives(self, ctx: "BuildContext") -> list[PrimitiveSpec]:
        """The primitive instances this element adds, body data in body frames."""

    def reaction_frame(self, ctx: "BuildContext") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Where reactions are reported: ``(point on i, point on j, axes on i)``.

        Points are body-frame coordinates of the point about which the reaction moment is taken
        on each body; ``axes`` (dim, dim) holds the joint axes as columns in body i's frame.
        The default is the centres of mass and body i's own axes.
        """
        dim = ctx.dim
        return np.zeros(dim), np.zeros(dim), np.eye(dim)

    def hinge_directions(self, ctx: "BuildContext", what: str
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Spatial hinges: ``(f_i, g_i, f_j)`` in body frames, the reference directions from
        which a rotation about the hinge's axis is measured (``g_i = h_i x f_i``), for the
        drivers and springs acting across it. Other elements refuse, naming ``what`` asked."""
        raise ModelError(f"{what}: needs a Revolute, got {self!r}")

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name!r}, {self.body_i.name!r}, {self.body_j.name!r})"
