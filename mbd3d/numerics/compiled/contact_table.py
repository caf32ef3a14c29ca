"""The layout of the compiled contact table (:mod:`~.compiled.contacts`): the kinds of its rows
and the columns of a row's report."""

from __future__ import annotations

from mbd3d.numerics.compiled import jit

#: the kinds of shape pairs, then of joint stops (from ``HINGE_STOP`` on)
SPHERE_PLANE, SPHERE_SPHERE, SEGMENT_SPHERE, SEGMENT_SEGMENT, BOX_SPHERE = 0, 1, 2, 3, 4
PIN_IN_HOLE, CAM_SPHERE, CAM_PLANE = 5, 6, 7
HINGE_STOP, SLIDE_STOP, CONE_STOP = 8, 9, 10
#: a contact group's row: its shapes' pairs found near each other at each evaluation
GROUP = 11
#: a box against a capsule (after the group's row, so that the kinds' numbers stay)
BOX_SEGMENT = 12
#: body points per contact (``points[k]``)
POINTS = 4
#: the columns of a contact's report: gap [m], gap rate [m/s], normal force [N], friction
#: force on j (3) [N], contact point (3) [m], normal from i to j (3), potential energy [J],
#: dissipated power [W], the slip velocity of j's material point at the contact point
#: relative to i's, its part along the tangent plane (3) [m/s] (what friction opposes)
GAP, GAP_RATE, NORMAL_FORCE, FRICTION, POINT, NORMAL, POTENTIAL = 0, 1, 2, 3, 6, 9, 12
DISSIPATION, SLIP, REPORT_COLUMNS = 13, 14, 17


@jit
def is_stop(kind: float) -> bool:
    """Whether a row of kind ``kind`` (``values[k, 0]``) is a joint stop."""
    return HINGE_STOP <= kind <= CONE_STOP
