"""Results export and named access; the mobility report."""

from __future__ import annotations

import csv
import math
import os
import re
import stat

import time

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.joints import Revolute, RotationDriver
from mbd3d.mechanisms import pendulum_chain, slider_crank, spatial_slider_crank


@pytest.fixture(scope="module")
def inverse():
    model = slider_crank(crank_speed=2 * math.pi)
    return mb.inverse_dynamics(model, np.linspace(0.0, 0.5, 6))


def test_csv_export_reads_back_with_units_and_the_printed_reactions(inverse, tmp_path):
    path = tmp_path / "slider.csv"
    inverse.to_csv(path)
    with open(path, newline="") as f:
        header, *rows = list(csv.reader(f))
    assert len(rows) == 6 and all(len(r) == len(header) for r in rows)
    data = {name: np.array([float(r[k]) for r in rows]) for k, name in enumerate(header)}
    np.testing.assert_array_equal(data["t [s]"], inverse.t)
    np.testing.assert_array_equal(data["slider.x [m]"], inverse.body("slider").position[:, 0])
    np.testing.assert_array_equal(data["crank.alpha [rad/s^2]"], inverse.qdd[:, 2])
    np.testing.assert_array_equal(data["motor.effort [N m]"], inverse.driver("motor").effort)
    # reactions as the example's force table prints them: on the named body, global axes
    pin = inverse.joint("O").reaction(on="crank")
    np.testing.assert_array_equal(data["O.Fx on crank [N]"], pin.force[:, 0])
    np.testing.assert_array_equal(data["O.M on crank [N m]"], pin.moment)
    rail = inverse.joint("rail").reaction(on="slider")
    np.testing.assert_array_equal(data["rail.Fy on slider [N]"], rail.force[:, 1])
    # the rail pushes the slider up, against gravity and the rod: the CSV says so with the
    # sign of the printed table, not the multiplier's
    assert np.all(data["rail.Fy on slider [N]"] * inverse.joint("rail").lam[:, 0] < 0)
    assert not any(name.endswith(".lam") for name in header)
    # NumPy reads it too
    table = np.loadtxt(path, delimiter=",", skiprows=1)
    np.testing.assert_array_equal(table[:, header.index("slider.vx [m/s]")],
                                  inverse.body("slider").velocity[:, 0])


def test_csv_names_with_commas_and_line_breaks_read_back(tmp_path):
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    arm = b.add_body("arm, left", mass=1.0, inertia=0.1, position=(0.5, 0.0))
    b.add(Revolute("pin\nA", b.ground, arm, at=(0.0, 0.0)))
    res = mb.forward_dynamics(b.build(), np.linspace(0.0, 0.1, 4))
    path = tmp_path / "odd names.csv"
    res.to_csv(path)
    with open(path, newline="") as f:
        header, *rows = list(csv.reader(f))
    assert "arm, left.x [m]" in header and "pin\nA.Fx on arm, left [N]" in header
    assert len(rows) == 4 and all(len(r) == len(header) for r in rows)
    k = header.index("arm, left.angle [rad]")
    np.testing.assert_array_equal([float(r[k]) for r in rows], res.body("arm, left").angle)


def test_spatial_csv_has_quaternions_not_chart_coordinates(tmp_path):
    model = spatial_slider_crank()
    res = mb.inverse_dynamics(model, np.linspace(0.0, 0.5, 5))
    cols = res.columns()
    assert not any(".g1" in c for c in cols)
    np.testing.assert_array_equal(np.column_stack([cols[f"rod.q{c} [-]"] for c in "wxyz"]),
                                  res.body("rod").quaternion)
    np.testing.assert_array_equal(cols["rod.omega_z [rad/s]"], res.body("rod").angular_velocity[:, 2])


def test_to_pandas_has_named_columns_with_units(inverse):
    df = inverse.to_pandas()
    assert df.index.name == "t [s]" and np.array_equal(df.index, inverse.t)
    np.testing.assert_array_equal(df["motor.effort [N m]"], inverse.driver("motor").effort)
    assert df.attrs["units"]["O.Fy on crank [N]"] == "N"
    assert df.attrs["units"]["slider.ax [m/s^2]"] == "m/s^2"


def test_point_history_indexes_its_positions(inverse):
    tip = inverse.point("crank", (0.06, 0.0))
    np.testing.assert_array_equal(tip[:, 0], tip.position[:, 0])
    np.testing.assert_array_equal(np.asarray(tip), tip.position)
    assert len(tip) == len(inverse.t)


def test_exports_respect_the_umask_and_keep_an_existing_files_mode(inverse, tmp_path):
    new = tmp_path / "new.csv"
    old_umask = os.umask(0o022)
    try:
        inverse.to_csv(new)
    finally:
        os.umask(old_umask)
    assert stat.S_IMODE(new.stat().st_mode) == 0o644
    kept = tmp_path / "kept.npz"
    kept.write_bytes(b"old")
    kept.chmod(0o664)
    inverse.to_npz(kept)
    assert stat.S_IMODE(kept.stat().st_mode) == 0o664


def test_a_write_protected_file_is_not_replaced(inverse, tmp_path):
    protected = tmp_path / "protected.csv"
    protected.write_text("keep me")
    protected.chmod(0o444)
    with pytest.raises(mb.MBDError, match="write-protected"):
        inverse.to_csv(protected)
    assert protected.read_text() == "keep me"


def test_export_to_a_folder_or_into_a_file_names_the_target(inverse, tmp_path):
    with pytest.raises(mb.MBDError, match=f"'{tmp_path}': it is a folder"):
        inverse.to_csv(tmp_path)
    (tmp_path / "plain").write_text("")
    with pytest.raises(mb.MBDError, match="is a file, not a folder"):
        inverse.to_npz(tmp_path / "plain" / "x.npz")


def test_npz_export_reads_back(inverse, tmp_path):
    path = tmp_path / "slider.npz"
    inverse.to_npz(path)
    with np.load(path) as data:
        np.testing.assert_array_equal(data["q"], inverse.q)
        np.testing.assert_array_equal(data["lam"], inverse.lam)
        assert list(data["coordinate_labels"])[:3] == ["crank.x", "crank.y", "crank.theta"]
        assert str(data["analysis"]) == "inverse dynamics"


def test_export_to_a_missing_folder_is_a_clear_error(inverse, tmp_path):
    with pytest.raises(mb.MBDError, match="does not exist"):
        inverse.to_csv(tmp_path / "nowhere" / "x.csv")
    assert list(tmp_path.iterdir()) == []


def test_reactions_need_multipliers():
    model = slider_crank(crank_speed=1.0)
    res = mb.kinematic_analysis(model, [0.0, 0.1])
    with pytest.raises(mb.MBDError, match="inverse_dynamics"):
        res.joint("O").reaction()
    inv = mb.inverse_dynamics(model, [0.0, 0.1])
    with pytest.raises(mb.ModelError, match="'A' connects 'crank' and 'rod'.*'slider'"):
        inv.joint("A").reaction(on="slider")
    with pytest.raises(mb.ModelError, match="joint, not a driver"):
        inv.joint("A").effort
    assert set(inv.efforts) == {"motor"}


def test_interrupt_keeps_the_results_so_far(monkeypatch):
    model = pendulum_chain(2)
    calls = {"n": 0}
    import mbd3d.analyses.explicit as dynamics
    real = dynamics._project_with_one_factorization  # each output's projection

    def interrupted(*args):  # Ctrl-C while an output is being stored
        calls["n"] += 1
        if calls["n"] > 200:
            raise KeyboardInterrupt
        return real(*args)

    monkeypatch.setattr(dynamics, "_project_with_one_factorization", interrupted)
    res = mb.forward_dynamics(model, np.linspace(0.0, 5.0, 501))
    assert res.status == "interrupted" and 1 < len(res) < 501
    assert "interrupted" in res.message
    np.testing.assert_array_equal(res.t, np.linspace(0.0, 5.0, 501)[:len(res)])


def test_ctrl_c_stops_a_long_stretch_of_compiled_steps(default_sigint):
    # outputs far apart: the compiled loop still returns every few thousand steps, so a real
    # SIGINT ends the run with the outputs done so far instead of waiting for the next one
    import os
    import signal
    import threading

    model = pendulum_chain(8)
    timer = threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.perf_counter()
    timer.start()
    try:
        res = mb.forward_dynamics(model, [0.0, 1.0, 1000.0], rtol=1e-10, atol=1e-12)
    finally:
        timer.cancel()
    # interpreted (NUMBA_DISABLE_JIT=1) the first second may not be reached yet
    assert res.status == "interrupted" and len(res) in (1, 2)
    assert time.perf_counter() - start < 30.0


def test_mobility_of_a_fully_driven_and_a_free_mechanism():
    report = mb.mobility(slider_crank())
    assert (report.n_coordinates, report.n_constraints, report.gruebler, report.rank,
            report.dof, report.redundant) == (9, 9, 0, 9, 0, 0)
    assert report.fully_driven
    free = mb.mobility(pendulum_chain(4))
    assert (free.gruebler, free.dof, free.redundant) == (4, 4, 0)
    assert "4 degree(s) of freedom" in str(free)


@pytest.mark.parametrize("build", [lambda: pendulum_chain(4), lambda: slider_crank(crank_speed=None)])
def test_free_coordinates_and_directions_complete_the_jacobian(build):
    """Holding the reported free coordinates leaves a square regular system (they can be
    driven), and the free directions are orthonormal velocities the constraints allow."""
    from mbd3d.model import constraints
    model = build()
    report = mb.mobility(model)
    Cq = constraints.jacobian(model, 0.0, model.q0, sparse=False)
    free = [model.coordinate_index(label) for label in report.free_coordinates]
    assert len(free) == report.dof > 0
    held = np.eye(model.n_coordinates)[free]
    square = np.vstack([Cq, held])
    assert square.shape[0] == square.shape[1]
    assert np.linalg.cond(square) < 1e6
    D = report.free_directions
    assert D.shape == (model.n_coordinates, report.dof)
    np.testing.assert_allclose(D.T @ D, np.eye(report.dof), rtol=0, atol=1e-12)
    assert np.max(np.abs(Cq @ D)) < 1e-12
    assert "free coordinates" in str(report)


def test_free_coordinates_are_chosen_alike_in_any_unit_of_length():
    """The free coordinates are picked in the dimensionless Jacobian: drawn in millimetres,
    metres or kilometres a chain and a slider-crank offer the same ones."""
    for scale in (1e-3, 1.0, 1e3):
        chain = mb.mobility(pendulum_chain(4, link_length=scale))
        crank = mb.mobility(slider_crank(crank_length=0.12 * scale, rod_length=0.26 * scale,
                                         crank_speed=None))
        assert chain.free_coordinates == [f"link{k}.theta" for k in range(1, 5)], scale
        assert crank.free_coordinates == ["crank.theta"], scale


def test_mobility_finds_the_redundancy_of_a_double_parallelogram():
    # three parallel cranks and one coupler: Gruebler says 0, the linkage moves (1 DOF)
    b = mb.ModelBuilder(dim=2)
    cranks = [b.add_body(f"crank{k}", mass=1.0, inertia=0.1, position=(k, 0.5),
                         angle=math.pi / 2) for k in range(3)]
    coupler = b.add_body("coupler", mass=1.0, inertia=0.1, position=(1.0, 1.0))
    for k, crank in enumerate(cranks):
        b.add(Revolute(f"ground{k}", b.ground, crank, at=(k, 0.0)))
        b.add(Revolute(f"top{k}", crank, coupler, at=(k, 1.0)))
    model = b.build()
    report = mb.mobility(model)
    assert (report.gruebler, report.rank, report.dof, report.redundant) == (0, 11, 1, 1)
    # its rows depend on each other everywhere: rounding lets their LU pass, whose steps
    # stalled 2e-5 m off (AssemblyError); the least-change steps of the augmented Lagrangian
    # assemble it from a disturbed guess, onto rows that all hold
    from mbd3d.model import constraints
    guess = model.q0 + 0.02 * np.random.default_rng(3).normal(size=model.n_coordinates)
    q = mb.solve_position(model, guess)
    assert np.max(np.abs(constraints.residual(model, 0.0, q, constraints.frames(model, q)))) \
        < 1e-12
    assert np.max(np.abs(q - guess)) < 0.1
    involved = {label.split(".")[0] for group in report.dependent for label in group}
    assert involved and involved <= {"ground0", "ground1", "ground2", "top0", "top1", "top2"}
    # the message counts them and lists each set of rows that depend on each other in braces
    assert report.message.startswith("1 redundant constraint equation(s): the Gruebler count "
                                     "(0) understates the mobility (1)")
    sets = re.findall(r"\{([^{}]+)\}", report.message)
    assert len(sets) == len(report.dependent) == 1
    assert set(sets[0].split(", ")) == set(report.dependent[0])
    # a second motor on a driven crank's pin: over-driven, both drivers named
    b = mb.ModelBuilder(dim=2)
    crank = b.add_body("crank", mass=1.0, inertia=0.1, position=(0.5, 0.0))
    pin = b.add(Revolute("pin", b.ground, crank, at=(0.0, 0.0)))
    for name in ("motor", "brake"):
        b.add(RotationDriver(name, pin, motion=0.0))
    report = mb.mobility(b.build())
    assert report.over_driven and report.message.startswith("over-driven")
    sets = re.findall(r"\{([^{}]+)\}", report.message)
    assert len(sets) == len(report.dependent) == 1
    assert {"motor", "brake"} <= {label.split(".")[0] for label in sets[0].split(", ")}


def _per_state(res):
    """Residuals and energies one state at a time, through the solvers' own functions."""
    from mbd3d.model import constraints
    model = res.model
    out = []
    for k, t in enumerate(res.t):
        q, charts = res._state(k)
        fr = constraints.frames(model, q, charts=charts)
        C, data, _ = constraints.evaluate(model, t, fr)
        v = constraints.jacobian_matrix(model, data) @ res.qd[k] - constraints.velocity_rhs(model, t, fr)
        out.append((np.max(np.abs(C), initial=0.0), np.max(np.abs(v), initial=0.0),
                    mb.kinetic_energy(model, q, res.qd[k], charts),
                    mb.potential_energy(model, q, charts)))
    return np.array(out).T


@pytest.mark.parametrize("case", ["planar driven", "spatial driven", "spatial free", "springs"])
def test_histories_evaluated_at_once_equal_state_by_state(case):
    from mbd3d.mechanisms import spatial_slider_crank
    times = np.linspace(0.0, 0.6, 7)
    if case == "planar driven":
        res = mb.inverse_dynamics(slider_crank(crank_speed=2 * math.pi), times)
    elif case == "spatial driven":  # rotation driver rows depend on time inside the primitive
        res = mb.inverse_dynamics(spatial_slider_crank(), times)
    elif case == "spatial free":  # several chart resets: states in different charts
        b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -9.81))
        body = b.add_body("tumbler", mass=1.0, inertia=(1.0, 2.0, 3.0), position=(0, 0, 1),
                          angular_velocity=(0.1, 8.0, 0.2))
        b.add(Revolute("hinge", b.ground, body, at=(0, 0, 0), axis=(0.0, 1.0, 0.0)))
        res = mb.forward_dynamics(b.build(), np.linspace(0.0, 2.0, 21))
        assert res.stats["chart_resets"] > 0
    else:
        b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
        mass = b.add_body("mass", mass=2.0, inertia=0.1, position=(0.0, -1.0))
        b.add(mb.SpringDamper("spring", b.ground, mass, at_i=(0, 0), at_j=(0, -1.0),
                              stiffness=50.0, free_length=0.8, damping=0.3))
        res = mb.forward_dynamics(b.build(), times)
    position, velocity, kinetic, potential = _per_state(res)
    np.testing.assert_allclose(res.position_residual, position, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(res.velocity_residual, velocity, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(res.kinetic_energy, kinetic, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res.potential_energy, potential, rtol=1e-12, atol=1e-12)
