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


def test_many_changed_rates_are_listed_largest_change_first():
    """A chain of four links given rates that the pins do not allow: the warning names the
    five largest changes, largest first, and counts the others; the stats have them all."""
    from mbd3d.mechanisms import pendulum_chain

    model = pendulum_chain(4)
    qd0 = np.random.default_rng(5).normal(size=model.n_coordinates)
    with pytest.warns(mb.InitialStateWarning) as caught:
        res = mb.forward_dynamics(model, [0.0, 0.01], qd0=qd0)
    changed = res.stats["initial_state"]["velocities"]
    assert len(changed) > 6
    message = str(caught[0].message)
    listed = message.split("changes ")[1].split(f" and {len(changed) - 5} more")[0]
    sizes = []
    for entry in listed.split(", "):
        label, change = entry.rsplit(" ", 3)[0], entry.rsplit(" ", 3)[1:]
        before, after = changed[label]
        assert change == [f"{before:.6g}", "->", f"{after:.6g}"]
        sizes.append(abs(after - before))
    largest = sorted((abs(b - a) for a, b in changed.values()), reverse=True)[:5]
    np.testing.assert_allclose(sizes, largest, rtol=0, atol=0)


def test_impossible_rates_are_refused_by_name():
    model = free_slider_crank()
    with pytest.raises(mb.ModelError, match="cannot all be given"):
        mb.forward_dynamics(model, T, initial_rates={"O": 6.0, "rail": 1.0})
    with pytest.raises(mb.ModelError, match="names 'crank.spin'"):
        mb.forward_dynamics(model, T, initial_rates={"crank.spin": 1.0})


def test_initial_positions_in_joint_terms_place_the_mechanism():
    """The crank put at 2 rad turning at 5 rad/s: the slider where the closed form puts it."""
    from mbd3d.mechanisms import slider_crank
    model = slider_crank(crank_speed=None)
    res = mb.forward_dynamics(model, [0.0, 0.01], initial_positions={"O": 2.0},
                              initial_rates={"O": 5.0}, method="DOP853", rtol=1e-10)
    r, rod = 0.12, 0.26
    x = r * math.cos(2.0) + math.sqrt(rod ** 2 - (r * math.sin(2.0)) ** 2)
    rate = -r * math.sin(2.0) * 5.0 * (1 + r * math.cos(2.0) / math.sqrt(
        rod ** 2 - (r * math.sin(2.0)) ** 2))
    assert res.joint("O").angle[0] == pytest.approx(2.0, abs=1e-12)
    assert res.body("slider").position[0, 0] == pytest.approx(x, abs=1e-12)
    assert res.body("slider").velocity[0, 0] == pytest.approx(rate, rel=1e-10)
    # or by the slider's displacement along its rail, the crank following
    res = mb.forward_dynamics(model, [0.0, 0.01], initial_positions={"rail": 0.3})
    assert res.joint("rail").displacement[0] == pytest.approx(0.3, abs=1e-12)
    # planar angles keep their turns
    res = mb.forward_dynamics(model, [0.0, 0.01], initial_positions={"crank.theta": 2.0 + 4 * math.pi})
    assert res.body("crank").angle[0] == pytest.approx(2.0 + 4 * math.pi, abs=1e-12)


def test_initial_position_of_a_spatial_hinge():
    """A bar on a tilted hinge put at 1 rad from the drawing: its tip where the rotation about
    the axis takes it."""
    axis = np.array([0.0, 1.0, 1.0]) / math.sqrt(2.0)
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -9.81), name="tilted hinge")
    bar = b.add_body("bar", mass=1.0, inertia=np.diag([1e-3, 0.05, 0.05]),
                     position=(0.5, 0.0, 0.0))
    b.add(Revolute("hinge", b.ground, bar, at=(0.0, 0.0, 0.0), axis=axis))
    res = mb.forward_dynamics(b.build(), [0.0, 0.01], initial_positions={"hinge": 1.0},
                              method="DOP853", rtol=1e-10)
    turned = mb.rotations.axis_angle(axis, 1.0) @ np.array([0.5, 0.0, 0.0])
    np.testing.assert_allclose(res.body("bar").position[0], turned, rtol=0, atol=1e-12)
    assert res.joint("hinge").angle[0] == pytest.approx(1.0, abs=1e-12)


def test_initial_positions_past_a_half_turn_from_the_drawing():
    """Three links on parallel hinges (about y), drawn along x, each put at 1.2 rad: the last
    turns 3.6 rad from the drawing, past the half turn where its Rodrigues parameters in the
    model's charts are infinite. Every link where the rotations about y take it."""
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -9.81), name="folded chain")
    length, angle, previous, links = 0.4, 1.2, b.ground, []
    for k in range(3):
        links.append(b.add_body(f"link{k}", mass=1.0, inertia=(1e-4, 0.013, 0.013),
                                position=((k + 0.5) * length, 0.0, 0.0)))
        b.add(Revolute(f"hinge{k}", previous, links[-1], at=(k * length, 0.0, 0.0),
                       axis=(0.0, 1.0, 0.0)))
        previous = links[-1]
    res = mb.forward_dynamics(b.build(), [0.0, 1e-3], method="DOP853", rtol=1e-10,
                              initial_positions={f"hinge{k}": angle for k in range(3)})
    hinge = np.zeros(3)
    for k in range(3):
        turn = mb.rotations.axis_angle((0.0, 1.0, 0.0), (k + 1) * angle)
        centre = hinge + turn @ (0.5 * length, 0.0, 0.0)
        hinge = hinge + turn @ (length, 0.0, 0.0)
        np.testing.assert_allclose(res.body(f"link{k}").position[0], centre, rtol=0,
                                   atol=1e-12)
        np.testing.assert_allclose(res.body(f"link{k}").rotation[0], turn, rtol=0, atol=1e-12)
        assert res.joint(f"hinge{k}").angle[0] == pytest.approx(angle, abs=1e-12)
    # the last link exactly a half turn from its drawing: no coordinates start there
    with pytest.raises(mb.AssemblyError, match="turn link2 a half turn"):
        mb.forward_dynamics(res.model, [0.0, 1e-3],
                            initial_positions={f"hinge{k}": math.pi / 3 for k in range(3)})


def test_initial_positions_that_cannot_hold_together_are_named():
    from mbd3d.mechanisms import slider_crank
    with pytest.raises(mb.AssemblyError, match="O = 2, rail = 0.5"):
        mb.forward_dynamics(slider_crank(crank_speed=None), [0.0, 0.01],
                            initial_positions={"O": 2.0, "rail": 0.5})
    # a name that is neither a joint nor a coordinate is reported as the argument it came in
    with pytest.raises(mb.ModelError, match="initial_positions names 'nope'"):
        mb.forward_dynamics(slider_crank(crank_speed=None), [0.0, 0.01],
                            initial_positions={"nope": 1.0})
    with pytest.raises(mb.ModelError, match="initial_rates names 'nope'"):
        mb.forward_dynamics(slider_crank(crank_speed=None), [0.0, 0.01],
                            initial_rates={"nope": 1.0})
