"""Forward sensitivities of forward dynamics (``mb.forward_sensitivities``): SUNDIALS' published
slider-crank (idasSlCrank_FSA), then planar and spatial motions against central differences of
runs of the models rebuilt with each parameter changed (``mb.with_parameters``), closed loops,
projections and chart resets included."""

from __future__ import annotations

import contextlib
import math
import pathlib
import sys

import numpy as np
import pytest
from scipy.integrate import simpson

import mbd3d as mb
from mbd3d import mechanisms
from mbd3d.io.parameters import parameter_tangent, parameter_value
from mbd3d.numerics.compiled.accelerations import accelerations_with_parts
from mbd3d.numerics import patterns
from mbd3d.numerics.compiled.structures import workspace

EXAMPLES = pathlib.Path(__file__).parent.parent / "examples"
sys.path.insert(0, str(EXAMPLES))
import haug_slider_crank  # noqa: E402
import spinning_top  # noqa: E402

#: a fourth-order central difference: offsets in steps and weights
OFFSETS, WEIGHTS = (-2.0, -1.0, 1.0, 2.0), np.array([1.0, -8.0, 8.0, -1.0]) / 12.0
SPRING = ("forces.spring.stiffness", "forces.spring.damping")


def kinetic_energy(model, t, q, qd) -> float:
    return mb.kinetic_energy(model, q, qd)


def central_difference(model, name: str, h: float, measure) -> np.ndarray:
    """``d measure(model)/d name`` by a fourth-order central difference of step ``h``."""
    value = mb.parameters(model)[name]
    values = [measure(mb.with_parameters(model, {name: value + o * h})) for o in OFFSETS]
    return np.tensordot(WEIGHTS, np.array(values), axes=1) / h


def test_sundials_published_figures():
    # idasSlCrank_FSA at rtol 1e-6: G = int_0^10 kinetic energy dt = 3.3366157997761721,
    # dG/dk = 3.3346e-01, dG/dc = -3.6375e-01. Their run is good to its tolerance: its G is
    # 2.7e-6 (relative) from the tight figure, and its own central differences give dG/dk =
    # 0.33345, 3e-5 from its sensitivity; a run at the same tolerance agrees within those.
    sens = mb.forward_sensitivities(haug_slider_crank.build(), [0.0, 10.0], SPRING,
                                    integrals={"G": kinetic_energy}, rtol=1e-6, atol=1e-8)
    assert sens.integral("G")[-1] == pytest.approx(3.3366157997761721, rel=1e-5)
    assert sens.integral("G", SPRING[0])[-1] == pytest.approx(0.33346, rel=5e-5)
    assert sens.integral("G", SPRING[1])[-1] == pytest.approx(-0.36375, rel=5e-5)
    assert sens.integral("G")[0] == 0.0 and not np.any(sens.integral("G", SPRING[0])[0])


@pytest.mark.compiled_only
def test_sundials_tight_against_differences():
    # tight: G = 3.33660680 (the figure the Haug example prints, Simpson on its outputs), and
    # dG/dp against central differences of G from plain runs, each G by Simpson's rule on
    # outputs every 0.01 s (1e-10 of G, the example's check)
    model = haug_slider_crank.build()
    sens = mb.forward_sensitivities(model, [0.0, 10.0], SPRING, integrals={"G": kinetic_energy},
                                    rtol=1e-11, atol=1e-13)
    assert sens.integral("G")[-1] == pytest.approx(3.33660680, abs=5e-9)
    t = np.linspace(0.0, 10.0, 1001)

    def G(variant) -> float:
        res = mb.forward_dynamics(variant, t, method="DOP853", rtol=1e-12, atol=1e-14)
        return simpson(res.kinetic_energy, x=t)
    for name in SPRING:
        reference = central_difference(model, name, 1e-3, G)
        assert sens.integral("G", name)[-1] == pytest.approx(reference, rel=1e-8), name


def _closed_loop():
    """The slider-crank turned by a constant torque from rest: three turns in a second, the
    crank passing its dead centres ever faster."""
    return mechanisms.slider_crank(crank_angle=math.radians(65.0), crank_speed=None,
                                   crank_torque=2.0)


def state(res) -> np.ndarray:
    """``(q, qd, qdd, lam)`` side by side at every output."""
    return np.concatenate([res.q, res.qd, res.qdd, res.lam], axis=1)


def sensitivity_and_difference(model, sens, j: int, name: str, options: dict) -> tuple:
    """Parameter ``j``'s ``(dq, dqd, dqdd, dlam)`` side by side from ``sens``, and the same
    from central differences of runs with ``options``, in steps of 1e-5 of the parameter's
    size: the angle moves by 16 rad per N m of the torque, and a difference's error grows
    with the fourth power of its step's move (steps of 1e-4 were 4e-8 off at 0.8 s), its
    noise as the runs' error over the step."""
    h = 1e-5 * max(abs(mb.parameters(model)[name]), 0.1)
    runs = central_difference(model, name, h, lambda m: state(mb.forward_dynamics(
        m, sens.results.t, **options)))
    got = np.concatenate([sens.dq[:, :, j], sens.dqd[:, :, j], sens.dqdd[:, :, j],
                          sens.dlam[:, :, j]], axis=1)
    return got, runs


@pytest.mark.compiled_only
@pytest.mark.parametrize("constraint_tol", [1e-8, 1e-14], ids=["few projections", "projected"])
def test_closed_loop_against_differences(constraint_tol):
    # lengths, a mass and the torque; positions, rates, accelerations and multipliers at every
    # output. With constraint_tol=1e-12 hundreds of steps end projected, and so do their
    # sensitivities (the sheet's 1.4).
    model = _closed_loop()
    t = np.linspace(0.0, 1.0, 11)
    names = ["joints.B.point_i[0]", "bodies.slider.mass", "forces.torque.torque",
             "joints.rail.point_i[1]"]
    options = dict(method="DOP853", rtol=1e-12, atol=1e-14, constraint_tol=constraint_tol)
    sens = mb.forward_sensitivities(model, t, names, **options)
    if constraint_tol < 1e-8:
        assert sens.results.stats["projections"] > 100
    tight = dict(options, rtol=1e-13, atol=1e-15)
    for j, name in enumerate(names):
        got, runs = sensitivity_and_difference(model, sens, j, name, tight)
        n, m = model.n_coordinates, model.n_constraints
        for part, columns in (("q", slice(0, n)), ("qd", slice(n, 2 * n)),
                              ("qdd", slice(2 * n, 3 * n)), ("lam", slice(3 * n, 3 * n + m))):
            reference = runs[:, columns]
            error = np.max(np.abs(got[:, columns] - reference))
            assert error <= 1e-8 * np.max(np.abs(reference)), (name, part, error)


@pytest.mark.compiled_only
def test_without_finer_variants_against_differences(monkeypatch):
    # parameters whose tangents cannot make variants at a shorter step: where a sensitivity is
    # large the stages take the state's change from the model itself (a shorter step) and the
    # parameter's from the variants with the state held, eight right-hand sides for four
    from mbd3d.analyses import forward_sensitivities as module
    from mbd3d.io.parameters import parameter_variants
    from mbd3d.model.tangents import ModelTangent
    model = _closed_loop()
    t = np.linspace(0.0, 1.0, 6)
    names = ["bodies.slider.mass", "forces.torque.torque"]
    options = dict(method="DOP853", rtol=1e-12, atol=1e-14)
    finer = mb.forward_sensitivities(model, t, names, **options)
    monkeypatch.setattr(module, "parameter_tangent", lambda m, name, what: ModelTangent(
        m, *parameter_variants(m, name, OFFSETS), what))
    sens = mb.forward_sensitivities(model, t, names, **options)
    assert (sens.results.stats["sensitivity_evaluations"]
            > finer.results.stats["sensitivity_evaluations"])  # the other rule was taken
    tight = dict(options, rtol=1e-13, atol=1e-15)
    for j, name in enumerate(names):
        got, reference = sensitivity_and_difference(model, sens, j, name, tight)
        assert np.max(np.abs(got - reference)) <= 1e-8 * np.max(np.abs(reference)), name


@pytest.mark.compiled_only
def test_a_held_start_against_differences():
    # the crank's angle held while the start is assembled: a parameter that moves the loop's
    # closure moves the slider and rod, never the crank (the sheet's 1.3 with held rows), as
    # the runs of the moved models start
    model = _closed_loop()
    t = np.linspace(0.0, 0.2, 5)
    options = dict(method="DOP853", rtol=1e-12, atol=1e-14, hold=["crank.theta"])
    names = ["joints.A.point_i[0]", "joints.B.point_i[0]", "joints.rail.point_i[1]"]
    sens = mb.forward_sensitivities(model, t, names, **options)
    tight = dict(options, rtol=1e-13, atol=1e-15)
    for j, name in enumerate(names):
        got, reference = sensitivity_and_difference(model, sens, j, name, tight)
        assert sens.dq[0, model.coordinate_index("crank.theta"), j] == 0.0
        assert np.max(np.abs(got - reference)) <= 1e-8 * np.max(np.abs(reference)), name


@pytest.mark.compiled_only
@pytest.mark.parametrize("layout", ["dense", "banded", "sparse", "range"])
def test_every_layout_against_differences(layout, monkeypatch):
    # each stage's augmented matrix, solved once for the state, then solves every parameter's
    # change of the accelerations (the sheet's 1.1): factored again (dense, banded), through
    # SuperLU (the caller's solve) or from the range-space factors the stage's solve kept
    with monkeypatch.context() as patch:
        if layout == "sparse":
            patch.setattr(patterns, "BANDED_WORK_LIMIT", -1)
        if layout == "banded":
            patch.setattr(patterns, "RANGE_SPACE_WORK_LIMIT", -1)
        model = mechanisms.pendulum_chain(6, sparse=layout != "dense", link_mass=2.7,
                                          link_length=0.8)
        assert model._augmented_pattern.layout == layout
        t = np.linspace(0.0, 0.4, 5)
        names = ["bodies.link3.mass", "gravity[1]"]
        options = dict(method="DOP853", rtol=1e-12, atol=1e-14)
        sens = mb.forward_sensitivities(model, t, names, **options)
        tight = dict(options, rtol=1e-13, atol=1e-15)
        for j, name in enumerate(names):
            got, reference = sensitivity_and_difference(model, sens, j, name, tight)
            error = np.max(np.abs(got - reference))
            assert error <= 1e-8 * np.max(np.abs(reference)), (name, error)


@pytest.mark.compiled_only
def test_coarse_projected_steps_against_differences():
    # fixed steps of 25 ms (tolerances that never shorten them), so that the runs of the moved
    # models take the very same steps and their differences are the computed motion's
    # derivative; each step drifts off the constraints by up to 1e-4 and is projected back.
    # The sensitivities follow the projections to first order in their corrections (the
    # sheet's 1.4): within 2e-5 here (7.8e-6 measured); not following them is 1.7e-4 off.
    model = _closed_loop()
    t = np.linspace(0.0, 0.5, 11)
    options = dict(method="DOP853", rtol=1.0, atol=1.0, max_step=0.025, constraint_tol=1e-12)
    names = ["joints.B.point_i[0]", "bodies.slider.mass", "forces.torque.torque"]
    sens = mb.forward_sensitivities(model, t, names, **options)
    stats = sens.results.stats
    assert stats["steps"] == 20 and stats["projections"] >= 10 and stats["max_drift"] > 1e-5
    for j, name in enumerate(names):
        got, reference = sensitivity_and_difference(model, sens, j, name, options)
        assert np.max(np.abs(got - reference)) <= 2e-5 * np.max(np.abs(reference)), name


@pytest.mark.compiled_only
def test_spatial_top_against_differences():
    # the heavy top precessing on its tip: its chart is reset at every step (the sheet's
    # 1.5), the tip's point moves the constraint (a consistent start, 1.3); a point on the
    # rim (read from the results through the sensitivities) and the centre against
    # differences
    model = spinning_top.build()
    t = np.linspace(0.0, 0.3, 7)
    names = ["bodies.top.mass", "joints.tip.at[0]", "bodies.top.inertia[2]"]
    options = dict(method="DOP853", rtol=1e-12, atol=1e-14)
    sens = mb.forward_sensitivities(model, t, names, **options)
    assert sens.results.stats["chart_resets"] > 100

    def rim(res) -> np.ndarray:
        return res.point("top", (0.05, 0.0, -0.05)).position

    def rim_and_centre(variant) -> np.ndarray:
        res = mb.forward_dynamics(variant, t, **options)
        return np.concatenate([rim(res), res.body("top").position], axis=1)
    got = sens.derivative(rim)
    for j, name in enumerate(names):
        value, size = parameter_value(model, name)
        h = 1e-4 * (max(abs(value), size) or model.length_scale)
        # the tip moved, the top's given velocities no longer fit it: they are projected, as
        # its sensitivities are at the start
        moved = name.startswith("joints")
        with pytest.warns(mb.InitialStateWarning) if moved else contextlib.nullcontext():
            reference = central_difference(model, name, h, rim_and_centre)
        assert np.max(np.abs(got[..., j] - reference[:, :3])) <= 1e-8 * np.max(
            np.abs(reference[:, :3])), name
        centre = sens.dq[:, :3, j]
        assert np.max(np.abs(centre - reference[:, 3:])) <= 1e-8 * np.max(
            np.abs(reference[:, 3:])), name


@pytest.mark.parametrize("maker, name, affine", [
    (lambda: mechanisms.slider_crank(crank_angle=1.134, crank_speed=None, crank_torque=2.0),
     "bodies.slider.mass", True),
    (lambda: mechanisms.slider_crank(crank_angle=1.134, crank_speed=None, crank_torque=2.0),
     "joints.A.point_i[0]", True),
    (lambda: mechanisms.slider_crank(crank_angle=1.134, crank_speed=None, crank_torque=2.0),
     "forces.torque.torque", True),
    # a hinge's axis is normalised: not affine in its component, so its variants are built
    (lambda: mechanisms.spatial_four_bar(crank_speed=None), "joints.O2.axis[0]", False)])
def test_variants_at_a_shorter_step_without_building_them(maker, name, affine):
    # where a sensitivity is large the forward sensitivities' stages ask for the variants at a
    # step 2**-8 of the first; a parameter the compiled arrays are affine in gets them
    # interpolated from the first variants, and their accelerations and multipliers must be
    # those of the models built at those values
    model = maker()
    tangent = parameter_tangent(model, name, "")
    made, step = tangent.finer_arrays(8)
    assert (8 not in tangent._refined) == affine  # built only where not affine
    built, built_step = tangent.finer(8)
    assert step == built_step == tangent.step / 256
    rng = np.random.default_rng(3)
    q, qd = model.q0, rng.normal(size=model.n_coordinates)
    charts = np.array(model.charts0) if model.dim == 3 else None
    core = model._core

    def solved(arrays):
        x, status = accelerations_with_parts(workspace(model.dim == 3, arrays), 0.3, q, qd,
                                             charts, core.no_forces, core.no_motions,
                                             core.no_motions)
        assert status == 0
        return x
    for arrays, variant in zip(made, built):
        expected = solved(variant._core.arrays())
        assert np.allclose(solved(arrays), expected, rtol=1e-13,
                           atol=1e-13 * np.max(np.abs(expected)))
    # and the interpolated variants do move: their difference is the parameter's effect
    if affine:
        x = [solved(arrays) for arrays in made]
        assert np.max(np.abs(x[3] - x[0])) > 1e-9 * np.max(np.abs(x[0]))


def test_integrals_read_like_results(tmp_path):
    sens = mb.forward_sensitivities(haug_slider_crank.build(), np.linspace(0.0, 0.5, 6),
                                    [SPRING[0]], integrals={"energy": kinetic_energy},
                                    rtol=1e-8)
    columns = sens.columns()
    assert np.array_equal(columns["energy"], sens.integral("energy"))
    assert np.array_equal(columns[f"d(energy)/d({SPRING[0]})"],
                          sens.integral("energy", SPRING[0]))
    assert "d(crank.theta)/d(forces.spring.stiffness)" in columns
    # the kinetic energy grows from rest: its integral increases
    assert np.all(np.diff(sens.integral("energy")) > 0)
    with pytest.raises(mb.ModelError, match="did you mean 'energy'"):
        sens.integral("enrgy")
    frame = sens.to_pandas()
    assert frame.shape[0] == 6
    path = sens.to_csv(tmp_path / "sensitivities.csv")
    assert pathlib.Path(path).read_text().startswith("t [s]")


def test_refused_by_name():
    model = haug_slider_crank.build()
    with pytest.raises(mb.ModelError, match="generalized-alpha's are not available"):
        mb.forward_sensitivities(model, [0.0, 0.1], SPRING, method="generalized-alpha")
    with pytest.raises(mb.ModelError, match="did you mean 'forces.spring.stiffness'"):
        mb.forward_sensitivities(model, [0.0, 0.1], ["forces.spring.stifness"])
    with pytest.raises(mb.ModelError, match="integral 'G' must be callable"):
        mb.forward_sensitivities(model, [0.0, 0.1], SPRING, integrals={"G": 1.0})
    with pytest.raises(mb.ModelError, match="integral 'G'.*finite number"):
        mb.forward_sensitivities(model, [0.0, 0.1], SPRING,
                                 integrals={"G": lambda m, t, q, qd: math.nan})
    with pytest.raises(mb.ModelError, match="integral 'G'.*finite number"):
        mb.forward_sensitivities(model, [0.0, 0.1], SPRING,
                                 integrals={"G": lambda m, t, q, qd: "energy"})
    ball = mb.load(EXAMPLES / "models" / "rigid_impacts.yaml")
    with pytest.raises(mb.ModelError, match="rigid contacts"):
        mb.forward_sensitivities(ball, [0.0, 0.1], [next(iter(mb.parameters(ball)))])
    friction = mb.load(EXAMPLES / "models" / "slider_crank_friction.yaml")
    with pytest.raises(mb.ModelError, match="joint friction"):
        mb.forward_sensitivities(friction, [0.0, 0.1], [next(iter(mb.parameters(friction)))])
