"""The initial state of forward dynamics in the user's terms: a crank's rate kept exactly, and
the velocities the constraints had to change reported (or refused), never changed silently."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.joints import Prismatic, Revolute
from mbd3d.mechanisms import slider_crank_positions

R, L, PHI = 0.12, 0.26, math.radians(65.0)


def free_slider_crank(crank_rate: float | None = None):
    """The slider-crank without a motor, the crank given ``crank_rate`` [rad/s] as its body's
    angular velocity and the rod and slider at rest (inconsistent)."""
    a, psi, b_point = slider_crank_positions(PHI, R, L)
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81), name="free slider-crank")
    spin = {} if crank_rate is None else {"angular_velocity": crank_rate}
    crank = b.add_body("crank", mass=1.0, inertia=0.001, position=a / 2, angle=PHI, **spin)
    rod = b.add_body("rod", mass=2.0, inertia=0.01, position=(a + b_point) / 2, angle=psi)
    slider = b.add_body("slider", mass=4.0, inertia=0.02, position=b_point)
    b.add(Revolute("O", b.ground, crank, at=(0.0, 0.0)))
    b.add(Revolute("A", crank, rod, at=a))
    b.add(Revolute("B", rod, slider, at=b_point))
    b.add(Prismatic("rail", b.ground, slider, axis=(1.0, 0.0)))
    return b.build()


def closed_form_rates(w):
    """Slider speed and rod rate for crank rate ``w`` (x = r cos phi + sqrt(l^2 - r^2 sin^2))."""
    root = math.sqrt(L * L - (R * math.sin(PHI)) ** 2)
    x_rate = w * (-R * math.sin(PHI) - R * R * math.sin(PHI) * math.cos(PHI) / root)
    # sin(psi) = -r sin(phi) / l
    psi_rate = -w * R * math.cos(PHI) / (L * math.sqrt(1 - (R * math.sin(PHI) / L) ** 2))
    return x_rate, psi_rate


T = np.linspace(0.0, 0.02, 3)


def test_a_given_crank_rate_is_kept_when_asked_for():
    model = free_slider_crank()
    for method in ("DOP853", "generalized-alpha"):
        with warnings.catch_warnings():
            warnings.simplefilter("error", mb.InitialStateWarning)
            res = mb.forward_dynamics(model, T, method=method, initial_rates={"O": 6.0},
                                      **({"step": 1e-3} if method != "DOP853" else {}))
        assert res.joint("O").angle_rate[0] == pytest.approx(6.0, rel=1e-12)
        x_rate, psi_rate = closed_form_rates(6.0)
        assert res.body("slider").velocity[0, 0] == pytest.approx(x_rate, rel=1e-10)
        assert res.body("rod").angular_velocity[0] == pytest.approx(psi_rate, rel=1e-10)
    # a coordinate's rate, likewise
    res = mb.forward_dynamics(model, T, initial_rates={"slider.x": -0.5})
    assert res.body("slider").velocity[0, 0] == pytest.approx(-0.5, rel=1e-12)


def test_velocities_the_constraints_change_are_reported_and_can_be_refused():
    model = free_slider_crank(crank_rate=6.0)
    with pytest.warns(mb.InitialStateWarning, match=r"changes crank\.omega 6 -> ") as caught:
        res = mb.forward_dynamics(model, T)
    assert "initial_rates" in str(caught[0].message)
    before, after = res.stats["initial_state"]["velocities"]["crank.omega"]
    assert before == 6.0 and after == pytest.approx(res.body("crank").angular_velocity[0])
    assert 0.0 < after < 6.0  # the mass-weighted projection shares the motion out
    with pytest.raises(mb.ModelError, match="strict=True makes this an error|violates"):
        mb.forward_dynamics(model, T, strict=True)
    # consistent velocities, from a run's results, pass without a word
    with warnings.catch_warnings():
        warnings.simplefilter("error", mb.InitialStateWarning)
        again = mb.forward_dynamics(model, T, res.q[-1], res.qd[-1], strict=True)
    assert again.stats["initial_state"] == {"positions": {}, "velocities": {}}


def test_impossible_rates_are_refused_by_name():
    model = free_slider_crank()
    with pytest.raises(mb.ModelError, match="cannot all be given"):
        mb.forward_dynamics(model, T, initial_rates={"O": 6.0, "rail": 1.0})
    with pytest.raises(mb.ModelError, match="names 'crank.spin'"):
        mb.forward_dynamics(model, T, initial_rates={"crank.spin": 1.0})
