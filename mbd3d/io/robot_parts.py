"""What the robot importers (:mod:`mbd3d.io.urdf`, :mod:`mbd3d.io.mjcf`) share: links welded
into one body, inertias mended from rounding, joint names apart from body names, and a joint's
driver and stops in the file's joint coordinate."""

from __future__ import annotations

import warnings
from typing import Any, Iterable

import numpy as np

from mbd3d.errors import ModelError, user_stacklevel
from mbd3d.model.motion import Motion

#: the largest relative excess of J3 over J1 + J2 repaired as rounding of published values
INERTIA_ROUNDING = 0.01


def composite(parts: Iterable[tuple[float, np.ndarray, np.ndarray]]
              ) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass [kg], centre [m] and centroidal inertia [kg m^2] of rigidly joined parts, each
    ``(mass, centre, inertia about its centre)`` in one frame (the parallel-axis theorem);
    zeros when nothing has mass."""
    parts = [(m, np.asarray(c, float), np.asarray(I, float)) for m, c, I in parts if m > 0]
    mass = float(sum(m for m, _, _ in parts))
    if not mass > 0:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    centre = sum(m * c for m, c, _ in parts) / mass
    inertia = np.zeros((3, 3))
    for m, c, I in parts:
        d = c - centre
        inertia += I + m * ((d @ d) * np.eye(3) - np.outer(d, d))
    return mass, centre, 0.5 * (inertia + inertia.T)


def physical(inertia: np.ndarray, who: str, welded: str, fix: str, what: str,
             warning: type) -> np.ndarray:
    """A body's inertia (body axes) whose principal moments break ``J1 + J2 >= J3`` by at
    most :data:`INERTIA_ROUNDING` of ``J3``, repaired to ``J3 = J1 + J2`` (a ``warning`` says
    so); refused beyond it. ``who`` names the body in the file, ``welded`` what is welded to
    it (for the refusal), ``fix`` the element to correct."""
    moments, axes = np.linalg.eigh(inertia)
    excess = moments[2] - moments[0] - moments[1]
    if not excess > 1e-9 * moments[2]:
        return inertia
    if excess > INERTIA_ROUNDING * moments[2]:
        raise ModelError(f"{what}: {who}{welded} has principal moments of inertia {moments} "
                         f"[kg m^2], whose largest exceeds the sum of the others by "
                         f"{excess / moments[2]:.1%}; no real body has them (more than "
                         f"rounding): correct its {fix}")
    warnings.warn(f"{what}: {who}: principal moments of inertia {moments} break J1 + J2 >= J3 "
                  f"by {excess / moments[2]:.2%} (rounding of the published values); J3 "
                  "lowered to J1 + J2", warning, stacklevel=user_stacklevel())
    moments[2] = moments[0] + moments[1]
    return axes @ np.diag(moments) @ axes.T


def joint_names(names: Iterable[str], taken: set, what: str, warning: type) -> dict:
    """The model's name of each moving joint: its own, or ``"<name>_joint"`` where a body has
    it (robot files keep the names of links and joints apart, a model does not)."""
    renamed, out = [], {}
    for joint in names:
        name = joint
        if name in taken:
            name = f"{joint}_joint"
            while name in taken:
                name += "_"
            renamed.append(f"'{joint}' -> '{name}'")
        out[joint] = name
        taken.add(name)
    if renamed:
        warnings.warn(f"{what}: joints named as links are renamed in the model: "
                      f"{', '.join(renamed)}", warning, stacklevel=user_stacklevel())
    return out


def add_driver(b, slides: bool, name: str, element, motion: Motion) -> None:
    """Drive a hinge's (``slides``: a slide's) coordinate of the file by ``motion``: a driver
    named ``"<name>_drive"`` (the joint reads the file's coordinate, drawn at its position
    there: ``drawn_angle``, ``drawn_displacement``; see :func:`mbd3d.inverse_dynamics_at`)."""
    from mbd3d.joints import RotationDriver, TranslationDriver  # noqa: PLC0415

    driver = TranslationDriver if slides else RotationDriver
    b.add(driver(f"{name}_drive", element, motion=motion))


def add_limit(b, slides: bool, name: str, element, ends: tuple[float | None, float | None],
              law) -> bool:
    """Add a hinge's (``slides``: a slide's) range ``ends`` in the file's coordinate, which
    the joint reads, as a JointLimit ``"<name>_limit"`` on ``element``; False when it is not
    added (no law, equal ends, or a hinge's ends beyond half a turn, where a spatial hinge's
    angle is measured)."""
    from mbd3d.model.contacts import JointLimit  # noqa: PLC0415

    ends = [None if end is None else float(end) for end in ends]
    if law is None or (not slides and any(end is not None and not -np.pi < end < np.pi
                                          for end in ends)):
        return False
    if None not in ends and not ends[0] < ends[1]:
        return False  # lower = upper = 0: what some files write for "no limits"
    b.add(JointLimit(f"{name}_limit", element, lower=ends[0], upper=ends[1], law=law))
    return True


def limit_law(joint_limits: Any, what: str):
    """The contact law of a robot file's joint limits, or None (``"ignore"``)."""
    from mbd3d.model.contact_laws import ContactLaw, LinearContact  # noqa: PLC0415

    if isinstance(joint_limits, ContactLaw):
        return joint_limits
    if joint_limits == "stop":
        return LinearContact(frequency=100.0, restitution=0.5)
    if joint_limits == "ignore":
        return None
    raise ModelError(f"{what}: joint_limits must be 'stop', 'ignore' or a contact law "
                     f"(mbd3d.LinearContact, ...), got {joint_limits!r}")
