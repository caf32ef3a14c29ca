"""The check, after an analysis that gives reactions, that no cam had to pull its follower:
where the contact force is negative a real follower leaves the cam, and what the analysis
reports after that time is the motion of a follower held on, which is not physical."""

from __future__ import annotations

import warnings

import numpy as np

from mbd3d.errors import LiftOffWarning, user_stacklevel

__all__ = ["warn_lift_off"]


def warn_lift_off(results, analysis: str) -> None:
    """Warn (:class:`mbd3d.LiftOffWarning`) for each cam whose contact force is negative at an
    output time of ``results``, naming the cam, the first such time and the force there."""
    from mbd3d.joints.cams import CamFollower, FlatFaceFollower  # noqa: PLC0415

    if results.lam is None or not len(results.t):
        return
    for element in results.model.joints:
        if not isinstance(element, (CamFollower, FlatFaceFollower)):
            continue
        force = results.joint(element.name).contact_force
        pulling = np.flatnonzero(force < 0.0)
        if not len(pulling):
            continue
        k = int(pulling[0])
        warnings.warn(LiftOffWarning(
            f"{analysis} of '{results.model.name}': cam '{element.name}' would have to pull "
            f"its follower at t = {results.t[k]:.6g} s (contact force {force[k]:.3g} N, the "
            f"first of {len(pulling)} output times where it is negative; "
            f"results.joint('{element.name}').lift_off lists them). A real follower leaves the "
            "cam there, so the motion reported after it is not physical: a stronger return "
            "spring or a lower speed keeps it on."), stacklevel=user_stacklevel())
