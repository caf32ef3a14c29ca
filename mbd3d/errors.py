"""Error types raised by mbd3d.

Every error the library raises on purpose derives from :class:`MBDError`, so that user code can
catch the library's own failures without catching programming errors. Each message names the body,
joint, force or parameter at fault and says what to do about it.
"""

from __future__ import annotations

import difflib
import sys
from typing import Any


class MBDError(Exception):
    """Base class of every error mbd3d raises on purpose."""


class ModelError(MBDError, ValueError):
    """The model description is invalid (bad parameter, unknown or duplicate name, ...)."""


class NotFullyDrivenError(MBDError, ValueError):
    """A kinematic analysis was asked of a mechanism that still has degrees of freedom."""


class OverDrivenError(MBDError, ValueError):
    """Drivers prescribe motions that the joints, or other drivers, already fix: two motors on
    one hinge, a motor on a rigid loop.

    Attributes
    ----------
    drivers, joints : list of str
        The drivers, and the joints, whose constraint rows depend on each other.
    """

    def __init__(self, message: str, *, drivers: list[str], joints: list[str]):
        super().__init__(message)
        self.drivers, self.joints = list(drivers), list(joints)


class AnalysisError(MBDError, RuntimeError):
    """An analysis failed part way.

    Attributes
    ----------
    time : float or None
        Simulation time [s] at which the failure happened, when known.
    results : mbd3d.Results or None
        Everything computed before the failure (time points already solved). ``None`` when the
        failure happened before the first time point.
    """

    def __init__(self, message: str, *, time: float | None = None, results: Any = None):
        super().__init__(message)
        self.time = time
        self.results = results


class AssemblyError(AnalysisError):
    """Newton-Raphson did not bring the constraint residual below the tolerance."""


class SingularJacobianError(AnalysisError):
    """The constraint Jacobian lost rank (lock-up, toggle or redundant constraints).

    Attributes
    ----------
    joints : list of str
        Names of the joints whose constraint rows are involved in the dependency.
    """

    def __init__(self, message: str, *, joints: list[str] | None = None, **kwargs: Any):
        super().__init__(message, **kwargs)
        self.joints = list(joints or [])


class IntegrationError(AnalysisError):
    """The time integrator failed (step size underflow, non-finite state, ...)."""


class StiffnessWarning(UserWarning):
    """An explicit integrator is crawling: its steps are limited by a stiff element (a stiff
    spring or damper), not by the accuracy asked for; the message names the element."""


class AccuracyWarning(UserWarning):
    """An integration whose settings cannot give the accuracy its results seem to have (a
    fixed step far too long for the motion); the message says what to change."""


class LiftOffWarning(UserWarning):
    """A cam's contact force had to pull: a real follower would leave the cam there, and the
    motion reported after that time (the follower held on the cam) is not physical."""


class ContactWarning(UserWarning):
    """Shapes of a contact overlap in the drawing: the contact starts with the force of that
    penetration (right for a body placed at rest in its static penetration, a mistake for
    one placed inside another); the message names the contact and the depth."""


def user_stacklevel() -> int:
    """The ``stacklevel`` for :func:`warnings.warn`, called where the warning is raised, that
    points the warning at the first caller outside mbd3d: the user's line, not mbd3d's."""
    frame, level = sys._getframe(1), 1
    while frame is not None and frame.f_globals.get("__name__", "").split(".")[0] == "mbd3d":
        frame, level = frame.f_back, level + 1
    return level


def did_you_mean(word: Any, choices) -> str:
    """`` (did you mean 'x'?)`` with the choice nearest ``word``, or nothing when none is
    near: the end of a message about a misspelt name."""
    close = difflib.get_close_matches(str(word), [str(c) for c in choices], n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""
