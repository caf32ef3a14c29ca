"""Every example runs (with small sizes) and its printed results are right."""

from __future__ import annotations

import importlib.util
import math
import pathlib
import re
import sys

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.viewer import entity_paths, read_component
from slider_crank_oracle import SliderCrankOracle

EXAMPLES = pathlib.Path(__file__).resolve().parent.parent / "examples"


def load(name: str):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def recorded_steps(path, body: str) -> int:
    """Number of time points of ``body``'s pose in a recording."""
    return len(read_component(path, f"/world/bodies/{body}", "Transform3D:translation")[0])


def test_slider_crank_example(capsys, tmp_path):
    rrd = tmp_path / "sc.rrd"
    results = load("slider_crank").main(n_points=5, duration=0.5, csv_folder=str(tmp_path),
                                        rrd=str(rrd))
    out = capsys.readouterr().out
    assert "Kinematic analysis" in out and "Force analysis" in out and "Forward dynamics" in out
    assert (tmp_path / "slider_crank_forward.csv").exists()
    assert f"rerun {rrd}" in out and recorded_steps(rrd, "slider") == 5
    assert recorded_steps(tmp_path / "sc_forward.rrd", "crank") == 5
    dyn = results["forward"]
    energy = dyn.kinetic_energy + dyn.potential_energy
    work = 2.0 * (dyn.body("crank").angle - dyn.body("crank").angle[0])
    np.testing.assert_allclose(work, energy - energy[0], rtol=0, atol=1e-8)


def test_four_bar_example(capsys, tmp_path):
    res = load("four_bar").main(n_points=7, rrd=str(tmp_path / "fb.rrd"))
    assert "rocker swing" in capsys.readouterr().out
    assert "/world/trails/coupler middle" in {p.replace("\\", "") for p in
                                              entity_paths(tmp_path / "fb.rrd")}
    assert np.all(np.isfinite(res.driver("motor").effort))
    np.testing.assert_allclose(res.body("crank").angle, math.radians(60) + 2 * math.pi * res.t)


def test_pendulum_spring_equilibrium_example(capsys, tmp_path):
    *rests, held = load("pendulum_spring_equilibrium").main(n_points=3,
                                                             rrd=str(tmp_path / "ps.rrd"))
    out = capsys.readouterr().out
    assert recorded_steps(tmp_path / "ps.rrd", "bar") == 3
    assert out.count("(stable)") == 3 and "motor torque" in out
    # the spring holds the bar higher the stiffer it is, and the pin carries the weight
    angles = [res.body("bar").angle[0] for res in rests]
    assert -math.pi / 2 < angles[0] < angles[1] < angles[2] < 0.0
    # held by the motor: gravity's moment -m g L/2 cos(theta) and the spring's -k theta
    theta = held.body("bar").angle
    np.testing.assert_allclose(held.driver("motor").effort,
                               2.0 * 9.81 * 0.4 * np.cos(theta) + 10.0 * theta, rtol=0, atol=1e-9)


def test_cart_pendulum_linearized_example(capsys, tmp_path):
    lin, gain = load("cart_pendulum_linearized").main(rrd=str(tmp_path / "cp.rrd"))
    out = capsys.readouterr().out
    assert recorded_steps(tmp_path / "cp.rrd", "pole") == 151
    assert "states: cart.x, pole.theta, cart.x_dot, pole.theta_dot" in out
    # the upright pole falls at the rate of its Lagrangian (cart 1.5 kg, pole 0.5 kg, 0.8 m)
    M, m, l, inertia = 1.5, 0.5, 0.4, 0.5 * 0.8**2 / 12
    rate = math.sqrt((M + m) * m * 9.81 * l / ((M + m) * (inertia + m * l * l) - (m * l) ** 2))
    assert lin.eigenvalues[0].real == pytest.approx(rate, rel=1e-9)
    # the regulator stabilises the linear model
    assert np.all(np.linalg.eigvals(lin.A - lin.B @ gain).real < 0)
    # the nonlinear fall from 0.001 rad grows at that rate while the tilt is small (the
    # decaying mode and the tilt's cube make the fit 1e-3 off)
    grown = float(re.search(r"growing at (\S+) 1/s", out).group(1))
    assert grown == pytest.approx(rate, rel=3e-3)


def test_four_bar_modes_example(capsys, tmp_path):
    along = load("four_bar_modes").main(n_points=5, rrd=str(tmp_path / "fbm.rrd"))
    out = capsys.readouterr().out
    assert "speed to avoid [rpm]" in out and "lowest:" in out
    assert (tmp_path / "fbm_mode.rrd").exists() and "/modes/curves" in entity_paths(
        tmp_path / "fbm.rrd")
    # the printed check: the largest difference is tiny against ~10 Hz
    difference = float(re.search(r"largest difference from the check (\S+) Hz", out).group(1))
    assert difference < 1e-6
    assert along.frequencies.shape == (5, 1)


def test_gear_train_example(capsys, tmp_path):
    rrd = tmp_path / "gears.rrd"
    res = load("gear_train").main(n_points=5, rrd=str(rrd))
    out = capsys.readouterr().out
    # the printed checks: Willis's ratio and the power balance
    low, high, willis = (float(x) for x in re.search(
        r"carrier/sun: (\S+) \.\. (\S+); Willis .* = (\S+)", out).groups())
    assert abs(low - 0.04 / 0.13) < 1e-14 and abs(high - willis) < 1e-14
    assert float(re.search(r"largest mismatch (\S+) of", out).group(1)) < 1e-12
    # drawn: the sun's pitch circle on the sun, the fixed ring on the ground, the tooth force
    # of the ring mesh at the pitch point, 90 mm from the centre
    _, vertices = read_component(rrd, "/world/bodies/sun/shape", "Mesh3D:vertex_positions",
                                 timeline=None)
    assert np.max(np.linalg.norm(vertices[0][:, :2], axis=1)) == pytest.approx(0.04, rel=1e-6)
    _, ring = read_component(rrd, "/world/ground/gears", "LineStrips3D:strips", timeline=None)
    assert np.linalg.norm(np.asarray(ring[0][0], dtype=float)[:, :2], axis=1) == pytest.approx(0.09, rel=1e-6)
    _, origins = read_component(rrd, "/world/reactions/planet-ring", "Arrows3D:origins")
    assert np.linalg.norm(origins[:, 0, :2], axis=1) == pytest.approx(0.09, rel=1e-6)
    _, forces = read_component(rrd, "/plots/meshes/sun-planet", "Scalars:scalars")
    mesh = res.joint("sun-planet").mesh_force
    np.testing.assert_allclose(forces, np.column_stack([mesh.tangential, mesh.tooth]))


def test_differential_example(capsys, tmp_path):
    rrd = tmp_path / "differential.rrd"
    res = load("differential").main(n_points=3, rrd=str(rrd))
    out = capsys.readouterr().out
    low, high, expected = (float(x) for x in re.search(
        r"right wheel (\S+) \.\. (\S+) rad/s; 2 x cage - left = (\S+)", out).groups())
    assert low == pytest.approx(expected, abs=1e-11) and high == pytest.approx(expected, abs=1e-11)
    assert float(re.search(r"differ by (\S+) N m", out).group(1)) < 1e-12
    assert float(re.search(r"mismatch (\S+) W", out).group(1)) < 1e-11
    thrust, shigley = (float(x) for x in re.search(r"thrust (\S+) N .* = (\S+) N", out).groups())
    assert thrust == pytest.approx(shigley, rel=1e-9)
    # drawn: each side gear's pitch circle about the axle (x), the spider's about its pin
    for body, radius, axis in (("left", 0.032, 0), ("spider", 0.020, 0)):
        _, vertices = read_component(rrd, f"/world/bodies/{body}/shape",
                                     "Mesh3D:vertex_positions", timeline=None)
        across = np.delete(vertices[0], axis, axis=1)  # body frames: both axes are body x
        assert np.max(np.linalg.norm(across, axis=1)) == pytest.approx(radius, rel=1e-6)
    _, origins = read_component(rrd, "/world/reactions/left\\ mesh", "Arrows3D:origins")
    np.testing.assert_allclose(origins[:, 0], res.joint("left mesh").mesh_force.point, rtol=1e-6)


def test_bouncing_ball_example(capsys, tmp_path):
    rrd = tmp_path / "ball.rrd"
    res = load("bouncing_ball").main(n_points=201, rrd=str(rrd))
    out = capsys.readouterr().out
    rows = re.findall(r"^\s+(\d)\s+\S+\s+(\S+)\s+(\S+)$", out, re.MULTILINE)
    assert len(rows) >= 3
    for bounce, apex, rigid in rows:  # the rigid ball's e^(2n) h0, to the dent's loss
        assert float(rigid) == pytest.approx(0.8 ** (2 * int(bounce)), rel=1e-7)
        assert float(apex) == pytest.approx(float(rigid), rel=1e-3)
        assert float(apex) < float(rigid)
    dent = float(re.search(r"dent (\S+) um", out).group(1))
    # (5 m v^2 / (4 K))^(2/5), K = (4/3) E* sqrt(r), m of the 20 mm steel ball, v from 1 m
    m = 7850.0 * 4 / 3 * math.pi * 0.02 ** 3
    K = 4 / 3 * 210e9 / (2 * (1 - 0.3 ** 2)) * math.sqrt(0.02)
    assert dent == pytest.approx((5 * m * 2 * 9.81 / (4 * K)) ** 0.4 * 1e6, abs=0.01)
    speed = float(re.search(r"first bounce: (\S+) m/s", out).group(1))
    assert speed == pytest.approx(2.5 / 7, rel=2e-3) and speed < 2.5 / 7
    assert recorded_steps(rrd, "ball") == len(res.t) == 201


def test_rigid_impacts_example(capsys, tmp_path):
    rrd = tmp_path / "rod.rrd"
    res = load("rigid_impacts").main(n_points=101, rrd=str(rrd))
    out = capsys.readouterr().out
    impulse, closed_form = (float(x) for x in re.search(
        r"first impulse (\S+) N s, closed form (\S+) N s", out).groups())
    assert impulse == pytest.approx(closed_form, rel=1e-8)
    rows = re.findall(r"^\s+\S+\s+(left|right) end\s+(\S+)\s+(\S+)", out, re.MULTILINE)
    assert len(rows) == len(res.stats["impacts"]) > 4
    for _, closing, opening in rows:  # Newton's law at every touch, e = 0.5
        assert float(opening) == pytest.approx(0.5 * float(closing), rel=1e-5)
    left, right, half = (float(x) for x in re.search(
        r"the ends carry (\S+) N and (\S+) N, half the weight (\S+) N", out).groups())
    assert left == pytest.approx(half, rel=1e-9) and right == pytest.approx(half, rel=1e-9)
    assert res.status == "complete" and "left end comes to rest" in out and "right end comes to rest" in out
    assert recorded_steps(rrd, "rod") == len(res.t)


def test_backspin_example(capsys, tmp_path):
    """Each throw sticks and rolls where the closed form says; the last comes back."""
    rrd = tmp_path / "backspin.rrd"
    runs = load("backspin").main(n_points=41, rrd=str(rrd))
    out = capsys.readouterr().out
    rows = re.findall(r"^\s+(-?[\d.]+)\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)$", out, re.MULTILINE)
    assert len(rows) == 3
    for _, sticks, by_hand, rolls, rolls_by_hand in rows:
        assert float(sticks) == pytest.approx(float(by_hand), rel=1e-8)
        assert float(rolls) == pytest.approx(float(rolls_by_hand), rel=1e-8)
    assert float(rows[-1][3]) < 0.0  # the strong backspin brings it back
    assert all(res.status == "complete" for res in runs)
    assert recorded_steps(rrd, "ball") == 41


def test_stick_slip_example(capsys, tmp_path):
    """Every slip and stick at its closed-form time; friction takes mu_k m g of the way."""
    rrd = tmp_path / "stick_slip.rrd"
    res = load("stick_slip").main(n_points=61, rrd=str(rrd))
    out = capsys.readouterr().out
    rows = re.findall(r"^\s+(slip|stick)\s+(\S+)\s+(\S+)$", out, re.MULTILINE)
    assert [event for event, _, _ in rows] == ["slip", "stick", "slip", "stick", "slip"]
    for _, found, by_hand in rows:
        assert float(found) == pytest.approx(float(by_hand), rel=1e-8)
    took, by_hand = (float(x) for x in re.search(r"friction took (\S+) J \(mu_k m g times the "
                                                   r"way: (\S+) J\)", out).groups())
    assert took == pytest.approx(by_hand, rel=1e-6)
    assert res.status == "complete"
    assert recorded_steps(rrd, "block") == 61


def test_cam_jump_example(capsys, tmp_path):
    rrd = tmp_path / "jump.rrd"
    res = load("cam_jump").main(n_points=81, rrd=str(rrd))
    out = capsys.readouterr().out
    leaves, by_hand, lands, flight = (float(x) for x in re.search(
        r"leaves the cam at (\S+) deg \(by hand (\S+)\) and lands at (\S+) deg \(its free "
        r"flight by hand: (\S+)\)", out).groups())
    # the contact's damper holds the last of the force for c/K = 30 us (0.08 deg) more
    assert 0.0 < leaves - by_hand < 0.15
    assert lands == pytest.approx(flight, abs=0.01)
    assert int(re.search(r"lands (\d+) times", out).group(1)) >= 2
    assert res.status == "complete" and recorded_steps(rrd, "follower") == 81


def test_rolling_disc_example(capsys, tmp_path):
    rrd = tmp_path / "disc.rrd"
    res = load("rolling_disc").main(n_points=5, rrd=str(rrd))
    out = capsys.readouterr().out
    assert float(re.search(r"turning rate by the closed form: (\S+) rad/s", out).group(1)) \
        == pytest.approx(1.541134, abs=5e-7)  # the formula sheet's number
    assert float(re.search(r"lean stays within (\S+) deg", out).group(1)) < 1e-8
    assert float(re.search(r"radius within (\S+) m", out).group(1)) < 1e-10
    assert float(re.search(r"after one turn: (\S+) m", out).group(1)) < 1e-9
    normal, weight, friction, needed = (float(x) for x in re.search(
        r"normal force (\S+) N = m g = (\S+) N; friction (\S+) N = m Omega\^2 R_G = (\S+) N",
        out).groups())
    assert normal == pytest.approx(weight, rel=1e-9) and friction == pytest.approx(needed, rel=1e-9)
    assert float(re.search(r"lean drifts by (\S+) deg", out).group(1)) > 1.0
    # drawn: the table under the disc, the path of a rim point
    _, outline = read_component(rrd, "/world/ground/rails", "LineStrips3D:strips", timeline=None)
    assert np.allclose(np.asarray(outline[0][0], dtype=float)[:, 2], 0.0)
    assert recorded_steps(rrd, "disc") == 5
    assert res.status == "complete"


def test_slider_crank_friction_example(capsys, tmp_path):
    rrd = tmp_path / "scf.rrd"
    res = load("slider_crank_friction").main(n_points=7, rrd=str(rrd))
    out = capsys.readouterr().out
    largest, scale = (float(x) for x in re.search(r"largest (\S+) W of (\S+) W", out).groups())
    assert largest < 1e-10 * scale
    assert float(re.search(r"per revolution: (\S+) J", out).group(1)) > 0
    # the rail's friction is 0.15 times the normal force the rail carries, against the sliding
    normal = res.joint("rail").reaction(on="slider").force[:, 1]
    speed = res.joint("rail").displacement_rate
    np.testing.assert_allclose(res.friction("rail friction"),
                               -0.15 * np.abs(normal) * np.tanh(speed / 1e-3), rtol=1e-12,
                               atol=1e-12)
    assert recorded_steps(rrd, "slider") == 7


def test_slider_crank_clearance_example(capsys, tmp_path):
    """The pin leaves its bearing and strikes it; the slider stays in the band the clearance
    (plus the dent) leaves about the ideal slider-crank's closed-form position, and the band
    shrinks with the clearance."""
    rrd = tmp_path / "clearance.rrd"
    example = load("slider_crank_clearance")
    res, ideal = example.main(n_points=76, turns=1.5, rrd=str(rrd))
    out = capsys.readouterr().out
    assert "within the band" in out
    force = res.contacts().normal_force[:, 0]
    assert np.any(force == 0.0) and np.max(force) > 10 * np.max(np.linalg.norm(
        ideal.joint("B").reaction(on="slider").force, axis=1))
    # the ideal slider by the closed form of the slider-crank
    theta = res.body("crank").angle
    closed = (example.CRANK * np.cos(theta)
              + np.sqrt(example.ROD ** 2 - (example.CRANK * np.sin(theta)) ** 2))
    np.testing.assert_allclose(ideal.body("slider").position[:, 0], closed, rtol=0, atol=1e-12)
    off = np.abs(res.body("slider").position[:, 0] - closed)
    assert np.all(off <= example.band(res)) and np.max(off) > 0.5 * example.CLEARANCE
    tight = mb.forward_dynamics(example.build(1e-5), res.t, method="DOP853", rtol=1e-8,
                                atol=1e-10)
    off = np.abs(tight.body("slider").position[:, 0] - closed)
    assert np.all(off <= example.band(tight, 1e-5))
    assert example.band(tight, 1e-5) < 0.1 * example.band(res)
    assert recorded_steps(rrd, "slider") == 76


def test_cam_follower_example(capsys, tmp_path):
    rrd = tmp_path / "cam.rrd"
    res = load("cam_follower").main(n_points=9, rrd=str(rrd))
    out = capsys.readouterr().out
    lift, speed, accel = (float(x) for x in re.search(
        r"lift (\S+) m, velocity (\S+) m/s, acceleration (\S+) m/s2", out).groups())
    assert lift < 1e-11 and speed < 1e-8 and accel < 1e-4
    assert "0.97 times that speed the follower stays on the cam" in out
    assert "1.03 times that speed the follower lifts off at" in out
    # by hand: the critical speed makes m w^2 s'' + m g + k (0.05 + y) vanish somewhere
    critical = float(re.search(r"lift-off speed by hand: (\S+) rad/s", out).group(1))
    assert 55.0 < critical < 65.0
    # drawn: the cam's surface (the base circle, 40 mm, at its smallest), the contact force on
    # the base circle at the start
    _, vertices = read_component(rrd, "/world/bodies/cam/shape", "Mesh3D:vertex_positions",
                                 timeline=None)
    radii = np.linalg.norm(vertices[0][:, :2], axis=1)
    assert np.any(np.abs(radii - 0.04) < 1e-8) and radii.max() == pytest.approx(0.06, rel=1e-6)
    _, origins = read_component(rrd, "/world/reactions/contact", "Arrows3D:origins")
    assert origins[0, 0, 1] == pytest.approx(0.04, rel=1e-6)
    assert np.all(res.joint("contact").contact_force > 0)


def test_spatial_slider_crank_example(capsys, tmp_path):
    res = load("spatial_slider_crank").main(n_points=5, rrd=str(tmp_path / "ssc.rrd"))
    assert "closed form" in capsys.readouterr().out
    assert recorded_steps(tmp_path / "ssc.rrd", "rod") == 5
    phi = 2 * math.pi * res.t
    x = 0.1 * np.cos(phi) + np.sqrt(0.09 - 0.06**2 - (0.04 - 0.1 * np.sin(phi)) ** 2)
    np.testing.assert_allclose(res.body("slider").position[:, 0], x, rtol=0, atol=1e-12)


def test_spinning_top_example(capsys, tmp_path):
    res = load("spinning_top").main(duration=0.2, n_points=3, rrd=str(tmp_path / "top.rrd"))
    out = capsys.readouterr().out
    assert "chart resets" in out
    # the printed check against steady precession (nutation, azimuth, tip force = m g)
    nutation, azimuth, force = (float(x) for x in re.search(
        r"nutation (\S+) deg, azimuth (\S+) rad, tip force (\S+) N", out).groups())
    assert nutation < 1e-6 and azimuth < 1e-8 and force < 1e-7
    # drawn as the cone with its apex at the tip: 0.075 m below the centre of mass
    _, vertices = read_component(tmp_path / "top.rrd", "/world/bodies/top/shape",
                                 "Mesh3D:vertex_positions", None)
    assert vertices[0][:, 2].min() == pytest.approx(-0.075, abs=1e-7)
    axis = res.body("top").rotation[:, :, 2]
    np.testing.assert_allclose(np.arccos(axis[:, 2]), math.radians(60.0), rtol=0, atol=1e-8)


def test_spatial_four_bar_example(capsys, tmp_path):
    res = load("spatial_four_bar").main(n_points=5, rrd=str(tmp_path / "sfb.rrd"))
    assert recorded_steps(tmp_path / "sfb.rrd", "coupler") == 5
    out = capsys.readouterr().out
    assert "2 redundant constraint equation(s)" in out and "fully driven" in out
    assert np.all(np.isfinite(res.driver("motor").effort))
    # the rocker follows the loop closure solved by hand
    difference = float(re.search(r"solved by hand: largest difference (\S+) rad", out).group(1))
    assert difference < 1e-9


def test_mesh_bodies_example(capsys, tmp_path):
    res = load("mesh_bodies").main(periods=2.2, n_points=221, rrd=str(tmp_path / "mesh.rrd"))
    out = capsys.readouterr().out
    simulated, formula = (float(x) for x in re.search(
        r"period: simulated ([\d.]+) s, formula ([\d.]+) s", out).groups())
    # the compound-pendulum period, with its amplitude correction, from the mesh properties
    assert simulated == pytest.approx(formula, rel=2e-6)
    arm = res.model.body("arm")
    m = 7850.0 * 0.04 * 0.40 * 0.02
    assert arm.mass == pytest.approx(m, rel=1e-12)
    assert arm.inertia[2, 2] == pytest.approx(m * (0.04**2 + 0.40**2) / 12, rel=1e-12)
    assert recorded_steps(tmp_path / "mesh.rrd", "disc") == 221


def test_sweep_slider_crank_example(capsys, tmp_path):
    rrd = tmp_path / "sweep.rrd"
    table = load("sweep_slider_crank").main(speeds=np.array([5.0, 10.0]),
                                            rods=np.array([0.1, 0.3]), n_points=31,
                                            folder=str(tmp_path / "runs"), rrd=str(rrd),
                                            backend="serial")
    out = capsys.readouterr().out
    assert "fastest slider" in out and f"rerun {rrd}" in out
    # the 0.1 m rod is shorter than the 0.12 m crank: it locks before a full turn
    assert [row["status"] for row in table] == ["failed", "ok", "failed", "ok"]
    assert {"/maps/peak_slider_speed", "/maps/peak_torque", "/maps/figure"} <= entity_paths(rrd)
    assert (tmp_path / "sweep.png").stat().st_size > 10_000  # two maps with colour bars
    # crank at 10 rad/s, 0.3 m rod: the slider speed's closed form over the same samples
    dx_dphi, _ = SliderCrankOracle(r=0.12, l=0.3).slider_x_derivatives(
        10.0 * np.linspace(0.0, 2 * math.pi / 5.0, 31))
    assert table.rows[3]["peak slider speed [m/s]"] == pytest.approx(
        np.max(np.abs(10.0 * dx_dphi)), rel=1e-9)


def test_identify_slider_crank_example(capsys, tmp_path):
    example = load("identify_slider_crank")
    out = example.main(n_points=51, rrd=str(tmp_path / "id.rrd"))
    assert "identified" in capsys.readouterr().out and recorded_steps(tmp_path / "id.rrd",
                                                                       "slider") == 51
    fit, errors = out["fit"], out["errors"]
    assert fit.success and fit.nfev <= 10
    # within a few standard errors of the truth, each of them a few percent at most
    assert np.all(np.abs(fit.x - example.TRUE) <= 4 * errors)
    assert np.all(errors <= 0.05 * np.asarray(example.TRUE))
    # the Jacobian's damping column: the torque is linear in the damping, so a central
    # difference of two inverse dynamics runs is exact up to rounding
    t = np.linspace(0.0, 0.5, 51)
    model = out["model"]
    res = mb.inverse_dynamics(model, t)
    name = "forces.dashpot.damping"
    column = mb.sensitivities(res, [name]).effort("motor", name)
    c = mb.parameters(model)[name]
    efforts = [mb.inverse_dynamics(mb.with_parameters(model, {name: c + d}), t)
               .joint("motor").effort for d in (-1.0, 1.0)]
    np.testing.assert_allclose(column, (efforts[1] - efforts[0]) / 2.0, rtol=0, atol=1e-9)
    assert np.max(np.abs(column)) > 0.01


def test_four_bar_synthesis_example(capsys, tmp_path):
    example = load("four_bar_synthesis")
    out = example.main(rrd=str(tmp_path / "fbs.rrd"))
    assert "synthesised" in capsys.readouterr().out and recorded_steps(tmp_path / "fbs.rrd",
                                                                        "coupler") == 101
    fit = out["fit"]
    # a linkage through all eight points exists (it traced them): found to rounding, in a
    # few iterations of the exact Jacobian
    assert fit.success and fit.nfev <= 10
    assert np.max(out["misses"]) < 1e-12
    np.testing.assert_allclose(fit.x, example.TRACED, rtol=0, atol=1e-10)
    # the Jacobian at the start against central differences of the coupler point's path
    start = example.build()
    values = mb.parameters(start)
    sens = mb.sensitivities(mb.kinematic_analysis(start, example.TIMES), example.PARAMETERS)
    got = sens.derivative(lambda r: r.point("coupler", example.COUPLER_POINT).position)
    for j, name in enumerate(example.PARAMETERS):
        h = 1e-4
        moved = [example.path(mb.with_parameters(start, {name: values[name] + d}))[1]
                 for d in (-2 * h, -h, h, 2 * h)]
        difference = (8 * (moved[2] - moved[1]) - (moved[3] - moved[0])) / (12 * h)
        np.testing.assert_allclose(got[..., j], difference, rtol=0, atol=1e-9)


def test_examples_refuse_a_bad_output_path_before_computing(tmp_path, capsys, monkeypatch):
    example = load("slider_crank")
    with pytest.raises(mb.MBDError, match="folder does not exist"):
        example.main(n_points=5, csv_folder=str(tmp_path / "missing"), rrd=str(tmp_path / "a.rrd"))
    assert capsys.readouterr().out == ""  # nothing was computed
    assert list(tmp_path.iterdir()) == []
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    if sys.platform.startswith("linux"):
        with pytest.raises(mb.MBDError, match="no display"):
            load("four_bar").main(n_points=5, rrd=str(tmp_path / "fb.rrd"), show=True)
        assert capsys.readouterr().out == ""


def test_newtons_cradle_example(capsys, tmp_path):
    rrd = tmp_path / "nc.rrd"
    module = load("newtons_cradle")
    res = module.main(n_points=141, rrd=str(rrd))
    assert "swung out to" in capsys.readouterr().out and recorded_steps(rrd, "ball5") == 141
    model = res.model
    energy = np.array([mb.kinetic_energy(model, q, qd) + mb.potential_energy(model, q)
                       for q, qd in zip(res.q, res.qd)])
    np.testing.assert_allclose(energy, energy[0], rtol=0, atol=1e-8 * abs(energy[0]))
    # the last ball swings out to the striker's release, less what the gaps leave with the
    # others: each stops about GAP / STRING rad short of the bottom of its swing, and their
    # small swings hold a share of the energy of that order squared (2e-5 rad of the last
    # ball's swing); the outputs catch its top within 3e-5 rad
    swings = [np.max(np.abs(module.swing(res, k))) for k in range(1, 6)]
    short = module.GAP / module.STRING
    assert 0.0 < module.RELEASE - swings[-1] < 0.05 * short
    assert all(0.5 * short < s < 2 * short for s in swings[1:-1])


@pytest.mark.compiled_only  # 27 spheres, thousands of steps
def test_spheres_in_box_example(capsys, tmp_path):
    rrd = tmp_path / "sib.rrd"
    module = load("spheres_in_box")
    res = module.main(n_points=13, rrd=str(rrd))
    assert "deepest pair" in capsys.readouterr().out and recorded_steps(rrd, "sphere26") == 13
    balance = res.energy_balance()
    # what the balls lose the contacts dissipate, to the integrator's tolerance
    np.testing.assert_allclose(balance["total"], balance["total"][0], rtol=1e-4)
    assert balance["dissipated"][-1] > 0.2 * balance["total"][0]
    # the lowest balls rest on the floor, pressed in by the pile above
    lowest = res.q[-1].reshape(module.BALLS, -1)[:, 2].min()
    assert 0.99 * module.RADIUS < lowest < module.RADIUS
