"""Generalized-alpha's compiled step loop (mbd3d.numerics.compiled.alpha_loop) against the steps
taken one by one in Python (mbd3d.analyses.implicit), which the rest of the suite checks
against closed forms and other integrators: the same steps must give the same numbers, bit
for bit, through rejected steps, chart resets, singular passages and turn warnings, in dense
and banded layouts, planar and spatial."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.analyses import implicit
from mbd3d.mechanisms import pendulum_chain, slider_crank, spatial_chain
from test_examples import load


#: Newton iterations a step at most in :func:`free_slider_crank` (30 by default, which it
#: never needs: its steps are not rejected then)
NEWTON_HELD = 4


def free_slider_crank():
    """Nikravesh's slider-crank turning freely at 30 rad/s under gravity: at a step of 1e-3,
    with Newton held to 4 iterations (:data:`NEWTON_HELD`), some steps fail and are taken
    again shorter."""
    model = slider_crank(crank_speed=None)
    guess = np.zeros(model.n_coordinates)
    guess[model.coordinate_index("crank.theta")] = 30.0
    qd0 = mb.solve_velocity(model, model.q0, qd_guess=guess, hold=["crank.theta"])
    return model, {"qd0": qd0}, np.linspace(0.0, 2.0, 41), 1e-3


def spatial_pendulum():
    """A spatial double pendulum swinging out of its plane: its charts are re-referenced;
    outputs fall between step ends."""
    model = spatial_chain(2)
    qd0 = np.zeros(model.n_coordinates)
    qd0[1] = 1.0
    return model, {"qd0": qd0}, np.r_[0.0, np.linspace(0.1, 1.4, 14) + 3.7e-4, 1.5], 5e-4


def long_chain():
    """40 planar links falling from the horizontal: a banded iteration matrix."""
    return pendulum_chain(40, angle=0.0), {}, np.linspace(0.0, 0.5, 6), 1e-3


def spatial_chain_falling():
    """12 links on ball joints, the first pushed sideways: spatial and banded."""
    model = spatial_chain(12)
    qd0 = np.zeros(model.n_coordinates)
    qd0[1] = 2.0
    return model, {"qd0": qd0}, np.linspace(0.0, 3.0, 7), 1e-3


def four_bars():
    """IFToMM A02 with two four-bars: singular positions passed and reported."""
    return load("iftomm_four_bar").build(2), {}, np.linspace(0.0, 3.0, 31), 1e-3


def haug_slider_crank():
    """Haug's slider-crank (SUNDIALS' idasSlCrank): a spring-damper and a force at a point of
    the rod, whose tangents the loop builds in compiled code."""
    return load("haug_slider_crank").build(), {}, np.linspace(0.0, 1.0, 11), 1e-3


def sprung_chain():
    """30 planar links with a torsion spring-damper at every pin, the last pulled at its end
    by a force fixed in its own axes: a banded matrix with the springs' tangent in the band."""
    from mbd3d.joints import Revolute
    b = mb.ModelBuilder(dim=2)
    previous = b.ground
    for k in range(30):
        body = b.add_body(f"link{k}", mass=1.0, inertia=1 / 12, position=(k + 0.5, 0.0))
        b.add(Revolute(f"pin{k}", previous, body, at=(float(k), 0.0)))
        b.add(mb.RotationalSpringDamper(f"torsion{k}", previous, body, stiffness=200.0,
                                        damping=0.5))
        previous = body
    b.add(mb.PointForce("pull", previous, (0.0, -3.0), point=(0.5, 0.0), frame="body"))
    return b.build(), {}, np.linspace(0.0, 0.5, 6), 1e-3


def sprung_spatial_pair():
    """Two spatial bodies on skew hinges with a torsion spring-damper, a spring-damper with an
    actuator (its tension in the tangent at the step's end time) to the ground from an offset
    point, a torque in body axes and a force in global axes at a point: every compiled force
    element's tangent, turning through chart resets."""
    from mbd3d.joints import Revolute
    b = mb.ModelBuilder(dim=3)
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    one = b.add_body("one", mass=1.0, inertia=(0.03, 0.04, 0.05), position=(0.3, 0.0, 0.0),
                     angular_velocity=5.0 * axis, velocity=np.cross(5.0 * axis, (0.3, 0.0, 0.0)))
    two = b.add_body("two", mass=0.5, inertia=(0.02, 0.01, 0.02), position=(0.6, 0.2, 0.0),
                     angular_velocity=5.0 * axis, velocity=np.cross(5.0 * axis, (0.6, 0.2, 0.0)))
    hinge = b.add(Revolute("first", b.ground, one, at=(0.0, 0.0, 0.0), axis=axis))
    b.add(Revolute("second", one, two, at=(0.6, 0.0, 0.0), axis=(0.0, 0.0, 1.0)))
    b.add(mb.RotationalSpringDamper("torsion", joint=hinge, stiffness=0.05, damping=0.01))
    b.add(mb.SpringDamper("spring", b.ground, two, at_i=(0.5, 0.5, 0.5), point_j=(0.1, 0.0, 0.0),
                          stiffness=40.0, damping=0.2, free_length=0.3,
                          actuator=mb.Harmonic(2.0, 30.0)))
    b.add(mb.Torque("motor", one, (0.0, 0.0, 0.3), frame="body"))
    b.add(mb.PointForce("push", two, (0.5, 0.0, -1.0), point=(0.1, 0.05, 0.0)))
    return b.build(), {}, np.linspace(0.0, 2.0, 11), 1e-3


def clearance_slider_crank():
    """Flores' slider-crank with a clearance at the rod-slider pin (Hertz's law): the pin
    flies and strikes, so steps are limited before touches, retried across them and kept to
    an impact's step while one lasts; every touch and release hands the loop back."""
    return load("slider_crank_clearance").build(), {}, np.linspace(0.0, 6e-3, 7), 1e-4


def cone_stop():
    """A bar swinging on a ball joint into a cone limit (Hunt and Crossley's law) and out:
    a spatial stop, with chart resets between the strikes."""
    from mbd3d.joints import Spherical
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -9.81))
    bar = b.add_body("bar", mass=1.0, inertia=(1e-3, 0.08, 0.08), position=(0.0, 0.0, -0.5),
                     orientation=[[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]],
                     velocity=(-1.5, -0.3, 0.0), angular_velocity=(-0.6, 3.0, 0.0))
    ball = b.add(Spherical("ball", b.ground, bar, at=(0.0, 0.0, 0.0)))
    b.add(mb.JointLimit("cone", ball, upper=0.5, axis=(0.0, 0.0, -1.0),
                        law=mb.HuntCrossley(stiffness=2e4, restitution=0.6, impact_speed=2.0)))
    return b.build(), {}, np.linspace(0.0, 2.0, 11), 1e-3


def balls_in_a_box():
    """Three balls thrown into a box, one contact group (its pairs found as they come near)
    with friction: the group's forces and tangent in the loop, a dense matrix."""
    from mbd3d.mechanisms import spheres_in_box
    model = spheres_in_box(3, radius=0.01, density=1000.0, young_modulus=1e7,
                           restitution=0.5, friction=0.3, speed=0.3, seed=1)
    return model, {}, np.linspace(0.0, 0.1, 6), 1e-4


def run(case, compiled: bool, monkeypatch, **options):
    """The case's generalized-alpha run with the steps in the compiled loop or in Python, and
    how many calls the compiled loop had."""
    model, start, t, step = case()
    calls = []
    steps = implicit.alpha_loop.alpha_steps

    def counted(*args):
        calls.append(1)
        return steps(*args)
    with monkeypatch.context() as patch:
        patch.setattr(implicit, "COMPILED_STEPS", compiled)
        patch.setattr(implicit.alpha_loop, "alpha_steps", counted)
        with warnings.catch_warnings():  # the rates given are made consistent, in both runs
            warnings.simplefilter("ignore", mb.InitialStateWarning)
            res = mb.forward_dynamics(model, t, method="generalized-alpha", step=step,
                                      **start, **options)
    return res, len(calls)


@pytest.mark.parametrize("case", [
    free_slider_crank, spatial_pendulum, long_chain, four_bars, haug_slider_crank,
    sprung_chain, sprung_spatial_pair, clearance_slider_crank, cone_stop, balls_in_a_box,
    pytest.param(spatial_chain_falling, marks=pytest.mark.compiled_only)])  # 95 s interpreted
def test_the_compiled_loop_takes_the_steps_python_takes(case, monkeypatch):
    if case is free_slider_crank:
        monkeypatch.setattr(implicit.GeneralizedAlphaIntegrator, "max_newton_iterations",
                            NEWTON_HELD)
    compiled, calls = run(case, True, monkeypatch)
    python, none = run(case, False, monkeypatch)
    assert calls > 0 and none == 0
    for field in ("t", "q", "qd", "qdd", "lam"):
        np.testing.assert_array_equal(getattr(compiled, field), getattr(python, field),
                                      err_msg=field)
    for key, value in python.stats.items():
        if key != "wall_time":
            assert compiled.stats[key] == value, key
    assert [(p.time, p.joints) for p in compiled.singular_passages] == \
        [(p.time, p.joints) for p in python.singular_passages]
    np.testing.assert_allclose([p.depth for p in compiled.singular_passages],
                               [p.depth for p in python.singular_passages], rtol=1e-9)
    # what each case is there for happened
    if case is free_slider_crank:
        assert python.stats["rejected_steps"] > 0
    if case in (spatial_pendulum, spatial_chain_falling, sprung_spatial_pair, cone_stop):
        assert python.stats["chart_resets"] > 0
    if case in (clearance_slider_crank, cone_stop, balls_in_a_box):
        assert python.contact_dissipation[-1].sum() > 0.0  # the contacts touched
        np.testing.assert_array_equal(compiled.contact_dissipation, python.contact_dissipation)
    if case is clearance_slider_crank:
        assert python.stats["contact_retries"] > 0
    if case is four_bars:
        assert len(python.singular_passages) >= 2


def test_a_turn_too_long_is_warned_once_from_either_loop(monkeypatch):
    def pendulum():
        # a bar on a ball joint released level swings through the bottom at 5.4 rad/s: about
        # a radian a step (its Rodrigues parameters change by half of it)
        return spatial_chain(1), {}, np.linspace(0.0, 1.0, 3), 0.2

    messages = []
    for compiled in (True, False):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res, calls = run(pendulum, compiled, monkeypatch)
        messages.append([str(w.message) for w in caught
                         if issubclass(w.category, mb.AccuracyWarning)])
        assert (calls > 0) == compiled
    assert len(messages[0]) == 1 and messages[0] == messages[1]
    assert "turned by" in messages[0][0]
    assert np.all(np.isfinite(res.q))


def test_models_whose_steps_need_python_are_not_given_to_the_loop(monkeypatch):
    """A force given as a Python function of the state (differenced in Python at every step)
    keeps its steps in Python; a spring does not, near or far along the chain: the band of
    the iteration matrix is ordered and sized to hold the springs' tangent too (a spring
    from link 1 to link 12 closes a loop, and the ordering folds the chain about it)."""
    from mbd3d.joints import Revolute

    def chain(extra):
        def case():
            b = mb.ModelBuilder(dim=2)
            links = [b.ground]
            for k in range(12):
                links.append(b.add_body(f"link{k}", mass=1.0, inertia=1 / 12,
                                        position=(k + 0.5, 0.0)))
                b.add(Revolute(f"pin{k}", links[-2], links[-1], at=(float(k), 0.0)))
            b.add(extra(links))
            return b.build(), {}, np.linspace(0.0, 0.05, 3), 1e-3
        return case
    near = chain(lambda links: mb.SpringDamper("near", links[3], links[4], stiffness=10.0))
    far = chain(lambda links: mb.SpringDamper("far", links[1], links[12], stiffness=10.0))
    felt = chain(lambda links: mb.PointForce("drag", links[5],
                                             lambda t, state: -0.1 * state.velocity))
    for case, in_loop in ((near, True), (far, True), (felt, False)):
        model = case()[0]
        assert model._penalty_pattern.layout == "banded"
        res, calls = run(case, True, monkeypatch)
        assert (calls > 0) == in_loop and res.stats["steps"] == 50
        if case is far:  # the same steps from Python
            python, _ = run(case, False, monkeypatch)
            np.testing.assert_array_equal(res.q, python.q)


def test_the_loop_s_mass_determinants_are_numpy_s():
    """The singular-position indicator takes ``log |det|`` of each mass block (a spatial
    block changes with the orientation); the loop's own LU against NumPy's ``slogdet``."""
    rng = np.random.default_rng(7)
    blocks = rng.normal(size=(5, 6, 6)) * np.logspace(-3, 3, 5)[:, None, None]
    blocks[2] = blocks[2] @ blocks[2].T  # symmetric, as mass blocks are
    expected = float(np.sum(np.linalg.slogdet(blocks)[1]))
    assert implicit.alpha_loop._log_abs_det_blocks(blocks) == pytest.approx(expected,
                                                                            rel=1e-13)
    blocks[3, :, 0] = 0.0  # a singular block: -inf, as slogdet
    assert implicit.alpha_loop._log_abs_det_blocks(blocks) == -np.inf
