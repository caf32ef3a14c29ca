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
from mbd3d.mechanisms import four_bar, pendulum_chain, slider_crank, spatial_chain
from test_examples import load


def free_slider_crank():
    """Nikravesh's slider-crank turning freely at 30 rad/s under gravity: at a step of 1e-3
    some steps fail and are taken again shorter."""
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
    free_slider_crank, spatial_pendulum, long_chain, four_bars,
    pytest.param(spatial_chain_falling, marks=pytest.mark.compiled_only)])  # 95 s interpreted
def test_the_compiled_loop_takes_the_steps_python_takes(case, monkeypatch):
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
    if case in (spatial_pendulum, spatial_chain_falling):
        assert python.stats["chart_resets"] > 0
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
    """A spring's tangent is built in Python at every step: such a model stays there."""
    def sprung():
        return four_bar(shaft_stiffness=50.0), {}, np.linspace(0.0, 0.1, 3), 1e-3
    res, calls = run(sprung, True, monkeypatch)
    assert calls == 0 and res.stats["steps"] == 100


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
