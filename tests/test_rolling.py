"""A disc rolling without slipping down an incline against the closed forms: acceleration
g sin(b) / (1 + I / (m r^2)), the normal force m g cos(b), the traction that rolling needs,
the turn of -s / r, and energy conserved (rolling does no work)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.joints import RollingDisc

G = 9.81
INTEGRATORS = [dict(method="DOP853", rtol=1e-11, atol=1e-12),
               dict(method="generalized-alpha", step=1e-3)]


@pytest.mark.parametrize("options", INTEGRATORS, ids=["DOP853", "generalized-alpha"])
@pytest.mark.parametrize("shape", [0.5, 1.0], ids=["disc", "hoop"])
def test_disc_rolls_down_an_incline_as_the_closed_forms_say(options, shape):
    m, r, slope = 2.0, 0.15, 0.35
    inertia = shape * m * r * r
    down = np.array([math.cos(slope), -math.sin(slope)])
    up = np.array([math.sin(slope), math.cos(slope)])
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G), name="rolling disc")
    disc = b.add_body("disc", mass=m, inertia=inertia, position=r * up, angle=0.3)
    b.add(RollingDisc("roll", b.ground, disc, radius=r, axis=down))
    t = np.linspace(0.0, 1.0, 11)
    res = mb.forward_dynamics(b.build(), t, **options)
    accel = G * math.sin(slope) / (1 + inertia / (m * r * r))
    travel = (res.body("disc").position - r * up) @ down
    # generalized-alpha integrates constant accelerations exactly
    np.testing.assert_allclose(travel, 0.5 * accel * t * t, rtol=0, atol=1e-10)
    np.testing.assert_allclose(res.body("disc").angle - 0.3, -travel / r, rtol=0, atol=1e-10)
    joint = res.joint("roll")
    np.testing.assert_allclose(joint.contact_force, m * G * math.cos(slope), rtol=1e-9)
    # the track holds the disc back by what turning it takes: I alpha / r
    np.testing.assert_allclose(joint.traction, -inertia * accel / (r * r), rtol=1e-9)
    point, normal = joint.contact()
    np.testing.assert_allclose(point @ up, 0.0, rtol=0, atol=1e-12)  # on the track
    energy = res.kinetic_energy + res.potential_energy
    np.testing.assert_allclose(energy, energy[0], rtol=0, atol=1e-9 * m * G * r)


def test_rolling_disc_is_planar_only_and_its_forces_are_its_own():
    b = mb.ModelBuilder(dim=3, name="spatial disc")
    disc = b.add_body("disc", mass=1.0, inertia=np.eye(3) * 1e-2, position=(0.0, 0.1, 0.0))
    b.add(RollingDisc("roll", b.ground, disc, radius=0.1, axis=(1.0, 0.0, 0.0)))
    with pytest.raises(mb.ModelError, match="'roll'.*planar models only"):
        b.build()
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G), name="disc")
    disc = b.add_body("disc", mass=1.0, inertia=5e-3, position=(0.0, 0.1))
    b.add(RollingDisc("roll", b.ground, disc, radius=0.1, axis=(1.0, 0.0)))
    res = mb.forward_dynamics(b.build(), [0.0, 0.1])
    with pytest.raises(mb.ModelError, match="contact_force .* traction"):
        res.joint("roll").mesh_force
