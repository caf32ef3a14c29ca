"""Published benchmark problems, built with the public API as the examples do, against the
published reference numbers (sources in each test and in the examples' docstrings)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mbd3d as mb
from mbd3d.model import constraints
from mbd3d.model.equations import generalized_forces, mass_matrix
from mbd3d.numerics.linalg import augmented_scaling
from mbd3d.mechanisms import pendulum_chain
from test_examples import load


def test_andrews_squeezing_mechanism_matches_the_test_set_at_30_ms(capsys, tmp_path):
    """Andrews' squeezer as 7 bodies and 10 revolutes: Hairer & Wanner, Solving ODEs II,
    sect. VII.7; reference: Test Set for IVP Solvers (Univ. of Bari), andrews.f, PSIDE at
    tolerance 1e-14."""
    example = load("andrews_squeezer")
    res = example.main(n_points=7, rrd=str(tmp_path / "andrews.rrd"))
    angles = example.test_set_angles(res)[-1]
    assert res.t[-1] == 0.03
    # the benchmark asks for 1e-7 relative; the model reproduces the reference far better
    np.testing.assert_allclose(angles, example.REFERENCE, rtol=1e-8, atol=0)
    # the motor's work went into kinetic and spring energy (no gravity, no losses)
    energy = res.kinetic_energy + res.potential_energy
    work = 0.033 * (res.body("body1").angle - res.body("body1").angle[0])
    np.testing.assert_allclose(energy - energy[0], work, rtol=0, atol=1e-9)
    assert "relative error" in capsys.readouterr().out


def test_haug_slider_crank_reproduces_every_published_sundials_row(capsys, tmp_path,
                                                                   validation_data):
    """Haug, Intermediate Dynamics (1992), Ex. 6.1.8, as the SUNDIALS IDAS example
    idasSlCrank_dns (github.com/LLNL/sundials, examples/idas/serial): all 26 printed rows of
    (q, x, p), and the integral G of the kinetic energy."""
    published = np.loadtxt(validation_data / "sundials_idasSlCrank_dns.txt")
    assert published.shape == (26, 4)
    example = load("haug_slider_crank")
    res = example.main(rrd=str(tmp_path / "haug.rrd"))
    qxp = example.coordinates(res)[::40]
    np.testing.assert_allclose(res.t[::40], published[:, 0], rtol=0, atol=1e-12)
    # the rows hold 5 digits of a solution computed at rtol 1e-6, atol 1e-7: half a unit of the
    # last digit, plus 1e-5 for IDAS' own global error (its G is off by 9e-6, below)
    unit = 1e-4 * 10.0 ** np.floor(np.log10(np.abs(published[:, 1:])))
    assert np.all(np.abs(qxp - published[:, 1:]) <= 0.5 * unit + 1e-5)
    # rows recomputed independently in SUNDIALS' three minimal coordinates (DOP853, rtol
    # 1e-12): the agreement is far tighter than the print
    for t, *expected in [(2.0, 0.5790388121, 1.3803352720, -0.2771440957),
                         (4.0, -1.2064316477, 1.0623426557, 0.4860931634),
                         (6.0, -1.1079974931, 1.1175594839, 0.4638596339),
                         (8.0, 0.6442255395, 1.3536306145, -0.3049963499),
                         (10.0, 1.2756758487, 1.0235785590, -0.4988130492)]:
        np.testing.assert_allclose(qxp[round(t / 0.4)], expected, rtol=0, atol=2e-10)
    # G: 3.3366067995 recomputed in the minimal coordinates at rtol 1e-12; SUNDIALS prints
    # 3.3366160662934146 at its tolerance. The example prints the value it computes.
    out = capsys.readouterr().out
    G = float(out.split("G = integral of T dt = ")[1].split()[0])
    assert abs(G - 3.3366067995) < 2e-10 and abs(G - example.G_IDAS) < 1e-5
    assert np.max(res.position_residual) < 1e-8
    assert "q IDAS" in out and "largest difference over the 26 rows" in out


def test_iftomm_a01_pendulum_follows_the_reference_series(capsys, validation_data):
    """IFToMM / MBS benchmark A01 (M. Gonzalez et al., Univ. of A Coruna): the reference
    series of the point mass, every 0.5 s; here its first 20 s (the example runs all 2000 s)."""
    reference = np.loadtxt(validation_data / "iftomm_A01_simple_pendulum_P1.txt",
                           skiprows=1)[:41]
    res = load("iftomm_pendulum").main(duration=20.0)
    # the file holds 6 significant digits: agreement to its last digit, 1e-3 m is the criterion
    np.testing.assert_allclose(res.body("P1").position, reference[:, 1:], rtol=0, atol=6e-7)
    energy = res.kinetic_energy + res.potential_energy
    assert abs(energy[0]) < 1e-12 and np.max(np.abs(energy)) < 1e-6
    assert "largest error against the reference" in capsys.readouterr().out


def four_bar_oscillator(bars: int, t: np.ndarray) -> np.ndarray:
    """B0 = (cos phi, sin phi) on the parallelogram branch, where all cranks share the angle
    phi and the couplers translate: ((N+1)/3 + N) phi'' = -((N+1)/2 + N) g cos(phi),
    phi(0) = pi/2, phi'(0) = -1 rad/s (the parallelogram branch: every crank at one angle)."""
    inertia, moment = (bars + 1) / 3 + bars, (bars + 1) / 2 + bars
    sol = solve_ivp(lambda _, y: [y[1], -moment * 9.81 * np.cos(y[0]) / inertia],
                    (t[0], t[-1]), [np.pi / 2, -1.0], t_eval=t, method="DOP853", rtol=1e-12,
                    atol=1e-12)
    return np.column_stack([np.cos(sol.y[0]), np.sin(sol.y[0])])


@pytest.mark.compiled_only  # 40 four-bars, 20,000 generalized-alpha steps
def test_iftomm_a02_forty_four_bars_follow_the_adams_series_through_singular_positions(
        capsys, validation_data, tmp_path):
    """IFToMM / MBS benchmark A02 (M. Gonzalez et al., Univ. of A Coruna), N = 40: the
    reference series of B0 from ADAMS/Solver, every 0.05 s for 20 s, within the library's
    high-precision criterion of 1e-3 m; the chain lies flat (Cq loses 40 ranks) 16 times."""
    reference = np.loadtxt(validation_data / "iftomm_A02_n_four_bar_B0.txt", comments="#")
    res = load("iftomm_four_bar").main(bars=40, duration=20.0, rrd=str(tmp_path / "a02.rrd"))
    assert (tmp_path / "a02.rrd").stat().st_size > 0
    b0 = res.point("crank0", (0.5, 0.0)).position
    np.testing.assert_allclose(res.t, reference[:, 0], rtol=0, atol=1e-12)
    assert np.max(np.abs(b0 - reference[:, 1:])) < 1e-3
    # and the separately derived one-degree-of-freedom equation, to the method's h^2 error
    assert np.max(np.abs(b0 - four_bar_oscillator(40, res.t))) < 1e-3
    # it stayed on the parallelogram branch: every crank at the first one's angle
    angles = np.array([res.body(f"crank{k}").angle for k in range(41)])
    assert np.max(np.abs(angles - angles[0])) < 1e-8
    assert res.position_residual.max() < 1e-8 and res.velocity_residual.max() < 1e-8
    energy = res.kinetic_energy + res.potential_energy
    assert np.max(np.abs(energy - energy[0])) < 0.05  # of 620 J (h^2 energy error)
    assert "largest error against the ADAMS reference" in capsys.readouterr().out


def test_iftomm_a02_two_four_bars_converge_to_the_reduced_equation():
    """N = 2 (the variant MBS-BOS and Exudyn simulate): x_B0(10 s) against the reduced
    equation; Exudyn's generalized-alpha at h = 1e-3 is 4.7e-5 m off (its test model
    fourBarMechanismIftomm.py)."""
    example = load("iftomm_four_bar")
    t = np.linspace(0.0, 10.0, 201)
    exact = four_bar_oscillator(2, t)
    errors = []
    for step in (2e-3, 1e-3):
        res = mb.forward_dynamics(example.build(2), t, method="generalized-alpha", step=step)
        b0 = res.point("crank0", (0.5, 0.0)).position
        errors.append(np.max(np.abs(b0 - exact)))
    assert abs(b0[-1, 0] - exact[-1, 0]) < 4.7e-5  # x_B0(10 s), as good as Exudyn's
    assert errors[1] < 3e-4  # over the whole series: 14 passages through the flat position
    assert 3.5 < errors[0] / errors[1] < 6.0  # second order through the singular positions


def test_explicit_methods_stop_at_the_singular_position_naming_joints_and_time():
    example = load("iftomm_four_bar")
    with pytest.raises(mb.SingularJacobianError) as error:
        mb.forward_dynamics(example.build(2), np.linspace(0.0, 3.0, 61), method="RK45")
    # the index-1 accelerations jump where the chain lies flat: an explicit method may step
    # over such a point, onto either branch (which one is decided by rounding), but it is
    # stopped at a singular position (the first or a later one), with the joints named
    t_fine = np.linspace(0.0, 3.0, 30001)
    sin_phi = four_bar_oscillator(2, t_fine)[:, 1]
    first_flat = t_fine[np.argmax(sin_phi <= 0.0)]
    time = error.value.time
    assert time >= first_flat - 0.05, (time, first_flat)
    assert "generalized-alpha" in str(error.value)
    assert error.value.joints
    results = error.value.results
    assert 0 < len(results) and results.t[-1] <= time
    # what was computed before the first singular position is right
    before = results.t < first_flat
    assert np.count_nonzero(before) >= 5
    np.testing.assert_allclose(results.point("crank0", (0.5, 0.0)).position[before],
                               four_bar_oscillator(2, results.t[before]), rtol=0, atol=1e-6)


def test_iftomm_a04_bricard_redundant_constraint_found_and_motion_computed(capsys, tmp_path):
    """IFToMM / MBS benchmark A04: Bricard's mechanism. No reference series exists; checked by
    the mobility report, energy conservation, and two formulations agreeing (the index-3
    implicit one and the explicit index-1 one with minimum-norm multipliers)."""
    example = load("bricard")
    report = mb.mobility(example.build())
    assert (report.gruebler, report.rank, report.dof) == (0, 29, 1)
    res = example.main(duration=2.0, n_points=41, step=5e-4, rrd=str(tmp_path / "bricard.rrd"))
    assert (tmp_path / "bricard.rrd").stat().st_size > 0
    assert "reactions unique: False" in capsys.readouterr().out
    assert not res.reactions_unique
    energy = res.kinetic_energy + res.potential_energy
    assert np.max(np.abs(energy - energy[0])) < 1e-5  # T + V, from rest, of 29 J
    assert np.ptp(res.point("rod2", (0.5, 0.0, 0.0)).position[:, 2]) > 0.3  # it moved
    assert res.position_residual.max() < 1e-10
    explicit = mb.forward_dynamics(example.build(), res.t, method="DOP853", rtol=1e-10,
                                   atol=1e-12)
    assert not explicit.reactions_unique
    for k in range(1, 6):  # poses (raw q would depend on when each run re-referenced charts)
        implicit_body, explicit_body = res.body(f"rod{k}"), explicit.body(f"rod{k}")
        np.testing.assert_allclose(implicit_body.position, explicit_body.position,
                                   rtol=0, atol=5e-6)
        np.testing.assert_allclose(implicit_body.rotation, explicit_body.rotation,
                                   rtol=0, atol=5e-6)
    # minimum-norm multipliers, in the model's dimensionless units (rows over their scale,
    # coordinates times theirs, see mbd3d.numerics.linalg): no component along the dependency of the
    # rows, and the equations of motion hold with them
    model = explicit.model
    weights = augmented_scaling(model)[model.n_coordinates:]
    for k in (10, 40):
        fr = constraints.frames(model, explicit.q[k], explicit.qd[k], explicit.charts[k])
        Cq = constraints.jacobian(model, explicit.t[k], explicit.q[k], fr, sparse=False)
        left_null = np.linalg.svd(weights[:, None] * Cq * model.coordinate_scale)[0][:, -1]
        lam_scaled = explicit.lam[k] / weights
        assert abs(left_null @ lam_scaled) < 1e-6 * np.abs(lam_scaled).max()
        M = mass_matrix(explicit.model, fr)
        balance = M @ explicit.qdd[k] + Cq.T @ explicit.lam[k] - generalized_forces(
            explicit.model, explicit.t[k], fr)
        assert np.abs(balance).max() < 1e-8
    np.testing.assert_allclose(res.lam, explicit.lam,
                               rtol=0, atol=1e-3 * np.abs(explicit.lam).max())


def test_iftomm_a05_flyball_governor_conserves_momentum_and_moves_as_its_rigid_twin(
        capsys, tmp_path):
    """IFToMM / MBS benchmark A05 (MBS-BOS, free shaft spun at 2 pi rad/s): no published
    series, so the physics: angular momentum about the shaft conserved, energy kept but for
    the dampers' share, mirror symmetry, and the stiff springs (k = 8e5 N/m) behaving as the
    rigid couplers of a separately built model integrated by DOP853, to their compliance."""
    example = load("flyball_governor")
    res = example.main(duration=0.6, rrd=str(tmp_path / "flyball.rrd"))
    momentum = example.angular_momentum_z(res)
    assert np.max(np.abs(momentum - momentum[0])) < 1e-5 * momentum[0]
    energy = res.kinetic_energy + res.potential_energy
    # the dampers take a few millijoules as the couplers first stretch (h = 1e-3 puts the
    # integrator's own energy error at the same level)
    assert np.max(np.abs(energy - energy[0])) < 2e-5 * energy[0] and energy[-1] < energy[0]
    right, left = res.body("arm right").position, res.body("arm left").position
    # mirror images, to generalized-alpha's error: it integrates each arm's Rodrigues
    # parameters, and the arms' charts differ by the half turn between them, so the two see
    # different O(h^2) errors (6.8e-9 m at h = 1 ms, a quarter at h/2; DOP853 keeps the
    # symmetry to 4e-14 m)
    np.testing.assert_allclose(right * [1, 1, 1], left * [-1, -1, 1], rtol=0, atol=1e-8)
    sleeve = res.body("sleeve").position[:, 2]
    assert np.ptp(sleeve) > 0.2  # the arms fly out and pull the sleeve up
    rigid = mb.forward_dynamics(example.build(rigid_couplers=True), res.t, method="DOP853",
                                rtol=1e-10, atol=1e-12)
    # couplers carrying ~100 N stretch by ~1e-4 m at 8e5 N/m
    assert np.max(np.abs(sleeve - rigid.body("sleeve").position[:, 2])) < 5e-4
    assert np.max(res.position_residual) < 1e-9
    assert "angular momentum about the shaft" in capsys.readouterr().out


def test_a_collapsed_explicit_step_is_put_down_to_a_singular_position_only_where_there_is_one():
    """Two 1 m links pinned to the ground at x = 0 and x = 2 lie straight: the x rows of the
    three pins depend on each other (a locked chain), so an explicit step that cannot be
    taken there is reported as a singular position with its joints; for a simple pendulum,
    whose Jacobian is regular, the failure stays an IntegrationError."""
    from mbd3d.joints import Revolute
    from mbd3d.analyses.explicit import _step_failure

    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    first = b.add_body("first", mass=1.0, inertia=1.0 / 12, position=(0.5, 0.0))
    second = b.add_body("second", mass=1.0, inertia=1.0 / 12, position=(1.5, 0.0))
    b.add(Revolute("O", b.ground, first, at=(0.0, 0.0)))
    b.add(Revolute("A", first, second, at=(1.0, 0.0)))
    b.add(Revolute("B", second, b.ground, at=(2.0, 0.0)))
    locked = b.build()
    error = _step_failure(locked, "RK45", 0.25, locked.q0, locked.charts0, "step too small")
    assert isinstance(error, mb.SingularJacobianError)
    assert set(error.joints) == {"O", "A", "B"} and error.time == 0.25
    assert "generalized-alpha" in str(error)

    pendulum = pendulum_chain(1)
    error = _step_failure(pendulum, "RK45", 0.25, pendulum.q0, pendulum.charts0, "step too small")
    assert isinstance(error, mb.IntegrationError)
    assert not isinstance(error, mb.SingularJacobianError)
    assert "step too small" in str(error) and error.time == 0.25
