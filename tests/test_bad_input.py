"""Bad input and failing analyses: the library's own errors, naming the culprit; partial results
are kept."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.mechanisms import pendulum_chain, slider_crank, slider_crank_positions
from mbd3d.joints import (CoordinateDriver, Distance, Prismatic, Revolute, RotationDriver,
                          Spherical, TranslationDriver)


def builder_with_bar():
    b = mb.ModelBuilder(dim=2)
    bar = b.add_body("bar", mass=1.0, inertia=0.1, position=(0.5, 0.0))
    return b, bar


@pytest.mark.parametrize("kwargs, words", [
    (dict(mass=0.0, inertia=1.0), ["'bar'", "mass", "positive"]),
    (dict(mass=-1.0, inertia=1.0), ["'bar'", "mass"]),
    (dict(mass=float("nan"), inertia=1.0), ["'bar'", "mass"]),
    (dict(mass=1.0, inertia=0.0), ["'bar'", "inertia", "positive"]),
    (dict(mass=1.0, inertia=float("inf")), ["'bar'", "inertia", "finite"]),
    (dict(mass=1.0, inertia=1.0, position=(0.0, float("nan"))), ["'bar'", "position"]),
    (dict(mass=1.0, inertia=1.0, angle=float("nan")), ["'bar'", "angle"]),
    (dict(mass=1.0, inertia=1.0, position=(1.0, 2.0, 3.0)), ["'bar'", "position", "2"]),
    (dict(mass="heavy", inertia=1.0), ["'bar'", "mass"]),
    (dict(mass=True, inertia=1.0), ["'bar'", "mass", "number"]),  # not 1 kg
    (dict(mass=1.0, inertia=1.0, position=(True, False)), ["'bar'", "position"]),
])
def test_body_parameters_are_checked(kwargs, words):
    b = mb.ModelBuilder(dim=2)
    kwargs.setdefault("position", (0.0, 0.0))
    with pytest.raises(mb.ModelError) as info:
        b.add_body("bar", **kwargs)
    for word in words:
        assert word in str(info.value)


def test_duplicate_and_unknown_names():
    b, bar = builder_with_bar()
    with pytest.raises(mb.ModelError, match="duplicate name 'bar'"):
        b.add_body("bar", mass=1.0, inertia=1.0, position=(0, 0))
    b.add(Revolute("pin", b.ground, bar, at=(0, 0)))
    with pytest.raises(mb.ModelError, match="duplicate name 'pin'.*joint 'pin'"):
        b.add(Revolute("pin", b.ground, bar, at=(1, 0)))
    with pytest.raises(mb.ModelError, match="duplicate name 'ground'"):
        b.add_body("ground", mass=1.0, inertia=1.0, position=(0, 0))
    model = b.build()
    with pytest.raises(mb.ModelError, match="no body 'crank'.*bar"):
        model.body("crank")
    res = mb.forward_dynamics(model, [0.0, 0.01])
    with pytest.raises(mb.ModelError, match="no joint or driver 'motor'.*pin"):
        res.joint("motor")


def test_joint_connecting_a_body_to_itself():
    b, bar = builder_with_bar()
    b.add(Revolute("self", bar, bar, at=(0, 0)))
    with pytest.raises(mb.ModelError, match="joint 'self' connects body 'bar' to itself"):
        b.build()


def test_joint_parameters_are_checked():
    b, bar = builder_with_bar()
    b.add(Revolute("pin", b.ground, bar, at=(0, float("nan"))))
    with pytest.raises(mb.ModelError, match="joint 'pin': at must be finite"):
        b.build()
    b, bar = builder_with_bar()
    b.add(Prismatic("rail", b.ground, bar, axis=(0.0, 0.0)))
    with pytest.raises(mb.ModelError, match="joint 'rail': axis must be a non-zero direction"):
        b.build()
    b, bar = builder_with_bar()
    b.add(Distance("rope", b.ground, bar, length=-1.0))
    with pytest.raises(mb.ModelError, match="joint 'rope'.*length must be positive"):
        b.build()
    b, bar = builder_with_bar()
    with pytest.raises(mb.ModelError, match="driver 'm'.*Function"):
        RotationDriver("m", b.ground, bar, motion=lambda t: t)
    other = mb.ModelBuilder(dim=2)
    foreign = other.add_body("foreign", mass=1.0, inertia=1.0, position=(0, 0))
    b.add(Revolute("pin", b.ground, foreign, at=(0, 0)))
    with pytest.raises(mb.ModelError, match="'pin'.*'foreign' belongs to another model builder"):
        b.build()
    with pytest.raises(mb.ModelError, match="add\\(\\) takes a joint"):
        b.add("not a joint")


def test_adding_after_build_is_refused():
    b, bar = builder_with_bar()
    b.add(Revolute("pin", b.ground, bar, at=(0, 0)))
    b.build()
    with pytest.raises(mb.ModelError, match="already built"):
        b.add_body("late", mass=1.0, inertia=1.0, position=(0, 0))


def test_guess_with_nan_is_refused():
    model = pendulum_chain(2)
    guess = model.q0.copy()
    guess[4] = np.nan
    with pytest.raises(mb.ModelError, match="q_guess is not finite at link2.y"):
        mb.solve_position(model, guess)


def test_driver_returning_nan_is_named_and_results_kept():
    b, bar = builder_with_bar()
    pin = b.add(Revolute("pin", b.ground, bar, at=(0, 0)))
    bad = mb.Function(lambda t: 0.0 if t < 0.5 else math.nan, lambda t: 0.0, lambda t: 0.0)
    b.add(RotationDriver("motor", pin, motion=bad))
    with pytest.raises(mb.ModelError, match="driver 'motor'.*non-finite.*t = 0.5") as info:
        mb.kinematic_analysis(b.build(), np.linspace(0.0, 1.0, 11))
    partial = info.value.results
    assert partial.status == "failed" and len(partial) == 5
    np.testing.assert_allclose(partial.t, np.linspace(0.0, 0.4, 5))


def test_kinematic_analysis_of_a_mechanism_that_is_not_fully_driven():
    model = slider_crank(crank_speed=None)
    with pytest.raises(mb.NotFullyDrivenError,
                       match=r"1 degree\(s\) of freedom are not driven\. Add 1 driver\(s\)"):
        mb.kinematic_analysis(model, [0.0])


def test_surplus_rows_that_leave_a_freedom_undriven_are_named():
    """A bar on two pins at one point: four rows for three coordinates, but the twins repeat
    each other, so only two count and the bar's turn is not driven."""
    b = mb.ModelBuilder(dim=2)
    bar = b.add_body("bar", mass=1.0, inertia=0.1, position=(0.5, 0.0))
    b.add(Revolute("pin", b.ground, bar, at=(0.0, 0.0)))
    b.add(Revolute("twin", b.ground, bar, at=(0.0, 0.0)))
    with pytest.raises(mb.NotFullyDrivenError) as info:
        mb.kinematic_analysis(b.build(), [0.0])
    message = str(info.value)
    assert ("4 constraint equations for 3 coordinates, but only 2 are independent" in message
            and "so 1 degree(s) of freedom are not driven" in message)
    sets = [set(group.split(", ")) for group in re.findall(r"\{([^{}]+)\}", message)]
    assert sorted(sets, key=sorted) == [{"pin.x", "twin.x"}, {"pin.y", "twin.y"}]


def test_newton_raphson_failure_names_the_worst_constraints():
    model = pendulum_chain(3)
    guess = model.q0 + 0.4
    with pytest.raises(mb.AssemblyError) as info:
        mb.solve_position(model, guess, t=0.25, max_iterations=1)
    message = str(info.value)
    assert "t = 0.25 s" in message and "after 1 Newton-Raphson iterations" in message
    assert "pin" in message and info.value.time == 0.25
    # the three worst rows (all lengths here), the largest first
    listed = re.search(r"Largest residuals: (.*?)\. Check", message)[1].split("; ")
    sizes = [abs(float(entry.split(" = ")[1].split()[0])) for entry in listed]
    assert len(sizes) == 3 and sizes == sorted(sizes, reverse=True) and sizes[0] > sizes[-1]


def test_joints_that_cannot_be_assembled_are_named():
    # two ropes of 1 m from points 3 m apart cannot both hold the bar's centre: Newton ends at
    # the ropes' common line, where their rows are dependent
    b = mb.ModelBuilder(dim=2)
    bar = b.add_body("bar", mass=1.0, inertia=0.1, position=(0.0, -0.5))
    b.add(Distance("left", b.ground, bar, at_i=(-1.5, 0.0), length=1.0))
    b.add(Distance("right", b.ground, bar, at_i=(1.5, 0.0), length=1.0))
    b.add(CoordinateDriver("hold", bar, "theta", 0.0))
    with pytest.raises(mb.SingularJacobianError) as info:
        mb.solve_position(b.build(), t=0.25)
    message = str(info.value)
    assert "t = 0.25 s" in message and "left.length" in message and "right.length" in message
    assert set(info.value.joints) == {"left", "right"}
    assert info.value.time == 0.25


def test_lock_up_is_reported_with_time_and_joints_and_partial_results():
    # slider driven outwards to the dead centre x = r + l, where crank and rod align
    r, l = 0.12, 0.26
    b = mb.ModelBuilder(dim=2)
    x0 = r * math.cos(1.0) + math.sqrt(l * l - (r * math.sin(1.0)) ** 2)
    crank = b.add_body("crank", mass=1, inertia=0.001, position=(0.06 * math.cos(1.0), 0.06 * math.sin(1.0)), angle=1.0)
    a = r * np.array([math.cos(1.0), math.sin(1.0)])
    psi = math.asin(-a[1] / l)
    rod = b.add_body("rod", mass=2, inertia=0.01, position=(a + (x0, 0)) / 2, angle=psi)
    slider = b.add_body("slider", mass=4, inertia=0.02, position=(x0, 0.0))
    b.add(Revolute("O", b.ground, crank, at=(0, 0)))
    b.add(Revolute("A", crank, rod, at=a))
    b.add(Revolute("B", rod, slider, at=(x0, 0)))
    rail = b.add(Prismatic("rail", b.ground, slider, axis=(1, 0)))
    b.add(TranslationDriver("piston", rail, motion=mb.Ramp(0.0, (r + l - x0) / 1.0)))
    model = b.build()
    # the dead centre is reached at t = 1 s; past it the driver asks for the impossible
    with pytest.raises(mb.SingularJacobianError) as info:
        mb.kinematic_analysis(model, [0.0, 0.3, 0.6, 0.9, 1.2])
    err = info.value
    assert err.time == pytest.approx(1.2)
    assert "t = 1.2 s" in str(err) and "lock-up or toggle" in str(err)
    assert {"O", "A", "B"} <= set(err.joints)
    assert len(err.results) == 4 and err.results.status == "failed"


def test_a_nearly_singular_jacobian_is_reported_with_its_conditioning_in_model_units():
    """Two 1 m links pinned to the ground 1.9999 m apart nearly lie straight: the rows are
    independent, but one combination hardly counts. The message gives the smallest singular
    value over the largest of the Jacobian in the model's units (rows over their scales,
    coordinates times theirs), as NumPy's SVD finds it. A Jacobian too large for an SVD is
    reported without one."""
    from mbd3d.analyses.position import singular_error
    from mbd3d.mechanisms import spatial_chain
    from mbd3d.model import constraints

    run, rise = 0.99995, math.sqrt(1.0 - 0.99995 ** 2)
    b = mb.ModelBuilder(dim=2)
    first = b.add_body("first", mass=1.0, inertia=1 / 12, position=(run / 2, rise / 2),
                       angle=math.atan2(rise, run))
    second = b.add_body("second", mass=1.0, inertia=1 / 12, position=(1.5 * run, rise / 2),
                        angle=-math.atan2(rise, run))
    b.add(Revolute("O", b.ground, first, at=(0.0, 0.0)))
    b.add(Revolute("A", first, second, at=(run, rise)))
    b.add(Revolute("B", second, b.ground, at=(2 * run, 0.0)))
    model = b.build()
    Cq = constraints.jacobian(model, 0.0, model.q0, sparse=False)
    message = str(singular_error(model, Cq, 0.5, "a test"))
    assert "nearly singular at t = 0.5 s" in message
    printed = float(re.search(r"smallest singular value is (\S+) of its largest", message)[1])
    s = np.linalg.svd(Cq / model.row_scale[:, None] * model.coordinate_scale[None, :],
                      compute_uv=False)
    assert s[-1] / s[0] < 1e-2
    assert printed == pytest.approx(s[-1] / s[0], rel=0.06)  # printed to two digits

    chain = spatial_chain(1000)
    Cq = constraints.jacobian(chain, 0.0, chain.q0)
    error = singular_error(chain, Cq, 0.0, "a test")
    assert "too large (3000 x 6000)" in str(error) and error.joints == []


@pytest.mark.parametrize("options", [{"method": "DOP853"},
                                     {"method": "generalized-alpha", "step": 1e-2}])
def test_a_body_far_lighter_than_its_neighbour_is_named_not_called_a_lock_up(options):
    """A double pendulum whose second link weighs 1e-12 of the first: its rows are far from
    dependent (smallest singular value 0.37 of the largest), but the mass-weighted equations
    are singular to rounding. The error names the light body and its mass ratio, not a lock-up
    of joints."""
    b = mb.ModelBuilder(dim=2)
    heavy = b.add_body("heavy", mass=1.0, inertia=0.1, position=(0.5, 0.0))
    light = b.add_body("light", mass=1e-12, inertia=1e-12, position=(1.5, 0.0))
    b.add(Revolute("O", b.ground, heavy, at=(0.0, 0.0)))
    b.add(Revolute("A", heavy, light, at=(1.0, 0.0)))
    with pytest.raises(mb.SingularJacobianError,
                       match=r"although the constraint Jacobian is not .* body 'light' has a "
                             r"mass of 1e-12 kg against 1 kg of 'heavy', a ratio of 1\.0e\+12"
                       ) as caught:
        mb.forward_dynamics(b.build(), [0.0, 0.5], **options)
    assert "lock-up" not in str(caught.value) and caught.value.joints == []


def _bar_on_a_ball(moment: float) -> mb.Model:
    """A 1 m, 1 kg bar on a ball joint whose moment of inertia about its own axis is
    ``moment`` [kg m^2] (a real bar's: 1e-4 or so)."""
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -9.81))
    bar = b.add_body("bar", mass=1.0, inertia=np.diag([moment, 1 / 12, 1 / 12]),
                     position=(0.5, 0.0, 0.0))
    b.add(Spherical("ball", b.ground, bar, at=(0.0, 0.0, 0.0)))
    return b.build()


def test_a_turn_without_inertia_is_named_not_called_a_lock_up():
    """A bar with 1e-16 kg m^2 about its own axis (its spin has no inertia and no joint
    holds it): the velocity analysis names the moment; with 1e-12 the analysis passes and
    generalized-alpha's iteration matrix is singular at every step, however short, which its
    refusal says (not a swing gone unstable)."""
    with pytest.raises(mb.SingularJacobianError,
                       match=r"body 'bar' has a principal moment of inertia of 1e-16 kg m\^2 "
                             r"against 0\.0833 kg m\^2 of 'bar'"):
        mb.forward_dynamics(_bar_on_a_ball(1e-16), [0.0, 0.5], method="DOP853")
    with pytest.raises(mb.IntegrationError, match=r"not even with the step shortened .* The "
                                                  r"iteration matrix was numerically singular"):
        mb.forward_dynamics(_bar_on_a_ball(1e-12), [0.0, 0.5], method="generalized-alpha",
                            step=1e-2)


def test_bad_times_and_options():
    model = pendulum_chain(1)
    with pytest.raises(mb.ModelError, match="strictly increasing"):
        mb.forward_dynamics(model, [0.0, 1.0, 0.5])
    with pytest.raises(mb.ModelError, match="method must be one of"):
        mb.forward_dynamics(model, [0.0, 1.0], method="Euler")
    with pytest.raises(mb.ModelError, match="rtol must be positive"):
        mb.forward_dynamics(model, [0.0, 1.0], rtol=-1.0)
    with pytest.raises(mb.ModelError, match="hold.*'link1.z'"):
        mb.forward_dynamics(model, [0.0, 1.0], hold=["link1.z"])
    # a coordinate by its index: the three of the one link are 0 to 2
    with pytest.raises(mb.ModelError, match=r"hold: coordinate index 3 out of range 0\.\.2$"):
        mb.forward_dynamics(model, [0.0, 1.0], hold=[3])
    # a coordinate held where the rows already fix all
    with pytest.raises(mb.AssemblyError, match="9 constraint equations and 1 held "
                                               "coordinates for 9 coordinates"):
        mb.solve_position(slider_crank(), hold=["crank.x"])


@pytest.mark.parametrize("options, words", [
    (dict(max_step=0.0), "max_step must be a positive"),
    (dict(max_step=-1.0), "max_step must be a positive"),
    (dict(max_step=float("nan")), "max_step must be a positive"),
    (dict(max_step=True), "max_step must be a positive"),
    (dict(method="generalized-alpha", step=0.0), r"step \(the fixed time step.*positive"),
    (dict(method="generalized-alpha", step=float("inf")), r"step \(the fixed time step.*finite"),
    (dict(method="generalized-alpha", step=True), r"step \(the fixed time step.*number"),
    (dict(atol="1e-8"), "atol must be positive"),
])
def test_integrator_options_are_checked_at_the_call(options, words):
    with pytest.raises(mb.ModelError, match=words):
        mb.forward_dynamics(pendulum_chain(1), [0.0, 1.0], **options)


def test_times_beyond_what_doubles_resolve_are_refused_by_name():
    for analysis in (mb.kinematic_analysis, mb.inverse_dynamics, mb.forward_dynamics):
        model = slider_crank(crank_speed=None if analysis is mb.forward_dynamics else 1.0)
        with pytest.raises(mb.ModelError, match=r"times reach 1e\+300 s"):
            analysis(model, [0.0, 1e300])


def test_a_driver_of_a_joint_never_added_is_refused_naming_both():
    b, bar = builder_with_bar()
    pin = Revolute("pin", b.ground, bar, at=(0.0, 0.0))  # made, but never added
    b.add(RotationDriver("motor", pin, motion=mb.Ramp(0.0, 1.0)))
    with pytest.raises(mb.ModelError, match="driver 'motor' drives joint 'pin', which was never "
                                            "added"):
        b.build()
    b, bar = builder_with_bar()
    slide = Prismatic("slide", b.ground, bar, axis=(1.0, 0.0), at=(0.5, 0.0))
    b.add(TranslationDriver("push", slide, motion=0.0))
    with pytest.raises(mb.ModelError, match="'push' drives joint 'slide'"):
        b.build()


def test_an_asymmetric_inertia_is_refused_at_any_scale():
    tensor = np.array([[2.0, 1.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0]])
    for size in (1e-24, 1e-6, 1.0, 1e6):
        b = mb.ModelBuilder(dim=3)
        with pytest.raises(mb.ModelError, match="'grain': inertia must be symmetric"):
            b.add_body("grain", mass=1e-12, inertia=size * tensor, position=(0.0, 0.0, 0.0))
    # symmetric to rounding is symmetric, whatever the size
    b = mb.ModelBuilder(dim=3)
    tiny = 1e-24 * np.diag([2.0, 2.0, 3.0])
    tiny[0, 1], tiny[1, 0] = 1e-25, 1e-25 * (1 + 1e-15)
    b.add_body("grain", mass=1e-12, inertia=tiny, position=(0.0, 0.0, 0.0))


def test_a_piston_driven_slider_crank_stops_at_its_dead_centre():
    """The issue's case: driven at its piston to the dead centre at t = 1 s, the crank speed
    there is unbounded. It used to come back as -1e5 rad/s with every later point accepted (the
    slider beyond its reach, residuals of millimetres) and status complete."""
    L1, L2, phi = 0.12, 0.26, math.radians(65.0)
    a, rod_angle, b_point = slider_crank_positions(phi, L1, L2)
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    crank = b.add_body("crank", mass=1.0, inertia=1e-3, position=a / 2, angle=phi)
    rod = b.add_body("rod", mass=2.0, inertia=1e-2, position=(a + b_point) / 2, angle=rod_angle)
    slider = b.add_body("slider", mass=4.0, inertia=2e-2, position=b_point)
    b.add(Revolute("O", b.ground, crank, point_i=(0.0, 0.0), point_j=(-L1 / 2, 0.0)))
    b.add(Revolute("A", crank, rod, point_i=(L1 / 2, 0.0), point_j=(-L2 / 2, 0.0)))
    b.add(Revolute("B", rod, slider, point_i=(L2 / 2, 0.0), point_j=(0.0, 0.0)))
    rail = b.add(Prismatic("rail", b.ground, slider, axis=(1.0, 0.0), point_i=(0.0, 0.0),
                           point_j=(0.0, 0.0)))  # the driven coordinate: x of the slider
    b.add(TranslationDriver("piston", rail, motion=mb.Ramp(b_point[0], L1 + L2 - b_point[0])))
    model = b.build()
    for analysis in (mb.kinematic_analysis, mb.inverse_dynamics):
        with pytest.raises(mb.SingularJacobianError) as info:
            analysis(model, np.linspace(0.0, 1.05, 106))
        assert info.value.time == pytest.approx(1.0)
        assert {"piston", "O", "A", "B"} <= set(info.value.joints)
        kept = info.value.results
        assert kept.t[-1] == pytest.approx(0.99) and kept.status == "failed"
        # what was kept is right: the closed form of the crank angle for each piston position
        x = kept.body("slider").position[:, 0]
        cos_phi = (x * x + L1 * L1 - L2 * L2) / (2 * x * L1)
        np.testing.assert_allclose(np.cos(kept.body("crank").angle), cos_phi, rtol=0, atol=1e-10)
        assert np.all(x <= L1 + L2)


def test_force_returning_nan_is_named():
    b, bar = builder_with_bar()
    b.add(Revolute("pin", b.ground, bar, at=(0, 0)))
    b.add(mb.PointForce("push", bar, lambda t: (math.nan, 0.0)))
    with pytest.raises(mb.ModelError, match="force 'push' returned a non-finite value") as info:
        mb.forward_dynamics(b.build(), [0.0, 1.0])
    assert info.value.results is not None


def test_errors_are_library_errors():
    assert issubclass(mb.ModelError, mb.MBDError) and issubclass(mb.ModelError, ValueError)
    assert issubclass(mb.SingularJacobianError, mb.AnalysisError)
    assert issubclass(mb.AssemblyError, mb.MBDError)


@pytest.mark.parametrize("where, value", [("q", np.nan), ("qd", np.inf), ("qd", -np.inf)])
def test_a_non_finite_state_is_reported_with_the_time(where, value):
    """forward_accelerations refuses a diverged state by name, whichever entry is bad."""
    model = pendulum_chain(2)
    state = {"q": mb.solve_position(model), "qd": np.zeros(model.n_coordinates)}
    state[where][4] = value
    with pytest.raises(mb.IntegrationError, match="not finite at t = 0.25 s"):
        mb.forward_accelerations(model, 0.25, state["q"], state["qd"])


def test_a_huge_but_finite_state_is_not_called_diverged():
    """A free body far out falls at g: the finiteness test must not mistake entries whose
    squares overflow for infinite ones."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    b.add_body("stone", mass=2.0, inertia=0.5, position=(0.0, 0.0))
    model = b.build()
    q = np.array([1e200, -1e200, 3.0])
    qd = np.array([1e180, 0.0, 1e170])
    qdd, lam = mb.forward_accelerations(model, 0.0, q, qd)
    np.testing.assert_array_equal(qdd, [0.0, -9.81, 0.0])
    assert lam.size == 0


def parallelogram_with_two_motors(free_slider: bool = False) -> mb.Model:
    """A four-bar (unit parallelogram) driven at both ground pivots: one motor too many
    (``free_slider``: and a slider on a rail that no driver moves)."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81), name="four-bar with two motors")
    rod = {"mass": 1.0, "inertia": 1.0 / 12}
    crank = b.add_body("crank", position=(0.0, 0.5), angle=math.pi / 2, **rod)
    coupler = b.add_body("coupler", position=(0.5, 1.0), **rod)
    rocker = b.add_body("rocker", position=(1.0, 0.5), angle=math.pi / 2, **rod)
    o2 = b.add(Revolute("O2", b.ground, crank, at=(0.0, 0.0)))
    b.add(Revolute("A", crank, coupler, at=(0.0, 1.0)))
    b.add(Revolute("B", coupler, rocker, at=(1.0, 1.0)))
    o4 = b.add(Revolute("O4", b.ground, rocker, at=(1.0, 0.0)))
    b.add(RotationDriver("motor", o2, motion=mb.Ramp(0.0, 1.0)))
    b.add(RotationDriver("rocker motor", o4, motion=mb.Ramp(0.0, 1.0)))
    if free_slider:  # a freedom no driver moves
        slider = b.add_body("slider", position=(3.0, 0.0), **rod)
        b.add(Prismatic("rail", b.ground, slider, at=(3.0, 0.0), axis=(1.0, 0.0)))
    return b.build()


def test_an_over_driven_mechanism_is_called_so_naming_its_drivers():
    """Two motors on one hinge, and a four-bar driven at its crank and its rocker: they used
    to be reported as stuck at a singular configuration, a lock-up or toggle position."""
    b, bar = builder_with_bar()
    pin = b.add(Revolute("pin", b.ground, bar, at=(0.0, 0.0)))
    b.add(RotationDriver("motor1", pin, motion=mb.Ramp(0.0, 1.0)))
    b.add(RotationDriver("motor2", pin, motion=mb.Ramp(0.0, 2.0)))
    # what they fight: each other, or the joints (which leave the four-bar one freedom)
    fights = ["motions that the other drivers already fix",
              "motions that the joints already fix (the joints alone leave 1 degree(s) of "
              "freedom for 2 driven motion(s)) (joints involved: "]
    for model, drivers, fight in ((b.build(), {"motor1", "motor2"}, fights[0]),
                                  (parallelogram_with_two_motors(), {"motor", "rocker motor"},
                                   fights[1])):
        report = mb.mobility(model)
        assert set(report.over_driven) == drivers and "over-driven" in report.message
        for analysis in (mb.kinematic_analysis, mb.inverse_dynamics, mb.forward_dynamics):
            with pytest.raises(mb.OverDrivenError, match="is over-driven") as info:
                analysis(model, [0.0, 0.1])
            assert set(info.value.drivers) == drivers, analysis
            message = str(info.value)
            assert "singular" not in message and fight in message
            # the rows that depend on each other, in braces, the drivers' among them
            rows = [row for group in re.findall(r"\{([^{}]+)\}", message)
                    for row in group.split(", ")]
            assert drivers <= {row.split(".")[0] for row in rows}


def test_an_over_driven_mechanism_with_as_many_rows_as_coordinates_is_named():
    """The parallelogram's two motors beside a free slider that no driver moves: the rows are
    as many as the coordinates, but two of them depend on each other (the check that the
    rows are independent must still find the drivers, not report a singular position)."""
    model = parallelogram_with_two_motors(free_slider=True)
    assert model.n_constraints == model.n_coordinates
    with pytest.raises(mb.OverDrivenError, match="is over-driven") as info:
        mb.inverse_dynamics(model, [0.0, 0.1])
    assert set(info.value.drivers) == {"motor", "rocker motor"}


@pytest.mark.parametrize("start", [0.0, 100.0])
def test_a_stiff_model_under_an_explicit_method_is_named_early(start):
    """A spring of 1e12 N/m under RK45 took 17,000 steps and a minute for 5 ms, silently; it
    now warns after 200 steps, naming the spring and suggesting generalized-alpha, which does
    the same run in a few steps. The steps' average length counts from the run's start, late
    or not."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))  # gravity sets the spring ringing
    bar = b.add_body("bar", mass=1.0, inertia=0.1, position=(0.5, 0.0))
    b.add(Revolute("pin", b.ground, bar, at=(0.0, 0.0)))
    b.add(mb.SpringDamper("stiff", b.ground, bar, at_i=(1.0, 1.0), at_j=(1.0, 0.0),
                          stiffness=1e12))
    model = b.build()
    times = start + np.linspace(0.0, 2e-4, 3)
    with pytest.warns(mb.StiffnessWarning, match="spring-damper 'stiff'.*generalized-alpha"
                      ) as caught:
        explicit = mb.forward_dynamics(model, times, method="RK45")
    # the figures it gives hold together: the steps' average times the "times shorter" is
    # the spacing (to the one digit printed)
    found = re.search(r"steps average (\S+) s, (\S+) times shorter than the output spacing of "
                      r"(\S+) s", next(str(w.message) for w in caught
                                        if issubclass(w.category, mb.StiffnessWarning)))
    average, shorter, spacing = (float(x) for x in found.groups())
    assert spacing == pytest.approx(1e-4) and 0.6 < average * shorter / spacing < 1.6
    implicit = mb.forward_dynamics(model, times, method="generalized-alpha", step=1e-5)
    assert implicit.stats["steps"] < explicit.stats["steps"] / 10


def test_the_stiffest_elements_are_rated_on_the_reduced_mass_of_their_bodies():
    """sqrt(k / m) of a spring and c / m of a damper, m the reduced mass m_i m_j / (m_i + m_j)
    of the two bodies (the body's own where the other is the ground), fastest first: what
    the stiffness warning names."""
    from mbd3d.analyses.explicit import stiffest_elements
    b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0))
    light = b.add_body("light", mass=2.0, inertia=0.1, position=(0.0, 0.0))
    heavy = b.add_body("heavy", mass=3.0, inertia=0.1, position=(1.0, 0.0))
    bar = b.add_body("bar", mass=1.0, inertia=0.02, position=(0.0, 1.0))
    for body in (light, heavy):
        b.add(Prismatic(f"rail {body.name}", b.ground, body, axis=(1.0, 0.0)))
    b.add(Revolute("pin", b.ground, bar, at=(0.0, 1.0)))
    b.add(mb.SpringDamper("coupling", light, heavy, stiffness=1.2e5))
    b.add(mb.SpringDamper("brake", b.ground, heavy, point_i=(2.0, 0.0), point_j=(0.0, 0.0),
                          damping=600.0))
    b.add(mb.RotationalSpringDamper("torsion", b.ground, bar, stiffness=50.0))
    rated = stiffest_elements(b.build())
    np.testing.assert_allclose([rate for rate, _ in rated], [math.sqrt(1.2e5 / 1.2),
                                                             600.0 / 3.0, math.sqrt(50 / 0.02)],
                               rtol=1e-12)
    assert "on 1.2 kg" in rated[0][1] and "on 0.02 kg m^2" in rated[2][1]


def test_a_fast_oscillation_sampled_finely_is_not_called_stiff():
    """A 1 kg block on a 1e6 N/m spring (period 6.3 ms, stable explicit steps up to 3 ms)
    sampled every 5 ms: RK45's steps (0.1 ms) are short because the motion is fast, 50 per
    output, not the crawl of a hundred and more; no warning."""
    import warnings
    b = mb.ModelBuilder(dim=2, gravity=(0.0, 0.0))
    block = b.add_body("block", mass=1.0, inertia=0.1, position=(0.1, 0.0))
    b.add(Prismatic("rail", b.ground, block, axis=(1.0, 0.0)))
    b.add(mb.SpringDamper("spring", b.ground, block, point_i=(-0.9, 0.0), point_j=(0.0, 0.0),
                          stiffness=1e6, free_length=0.999))
    model = b.build()
    with warnings.catch_warnings():
        warnings.simplefilter("error", mb.StiffnessWarning)
        res = mb.forward_dynamics(model, np.linspace(0.0, 0.2, 41), method="RK45")
    assert res.stats["steps"] > 2 * 200  # the check ran, twice
    assert 1e-2 * 5e-3 < 0.2 / res.stats["steps"] < 5e-3 / 20


def test_forward_accelerations_names_a_state_of_the_wrong_size():
    from mbd3d.mechanisms import slider_crank

    model = slider_crank(crank_speed=None)
    with pytest.raises(mb.ModelError, match=r"q must have shape \(9,\) for 'slider-crank'"):
        mb.forward_accelerations(model, 0.0, [0.0, 0.0, 0.0], np.zeros(9))
    with pytest.raises(mb.ModelError, match="qd must be an array of 9 numbers"):
        mb.forward_accelerations(model, 0.0, model.q0, "fast")
    qdd, lam = mb.forward_accelerations(model, 0, list(model.q0), [0] * 9)  # lists and ints
    assert qdd.shape == (9,) and lam.shape == (8,)
