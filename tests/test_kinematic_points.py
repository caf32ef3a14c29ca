"""The time points of kinematic analysis and inverse dynamics solved in one compiled call
(:mod:`mbd3d.numerics.compiled.kinematics`) against LAPACK and against the analyses' own path
through SciPy's LAPACK, which factors the Jacobian with ``getrf`` and estimates its
conditioning with ``gecon``."""

from __future__ import annotations

import pathlib
import warnings

import numpy as np
import pytest
from scipy.linalg.lapack import dgbcon, dgbtrf, dgecon, dgetrf

import mbd3d as mb
from mbd3d.analyses import kinematics
from mbd3d.joints import Distance, Prismatic, Revolute, RotationDriver
from mbd3d.mechanisms import driven_chain, four_bar, slider_crank, spatial_slider_crank
from mbd3d.model import constraints
from mbd3d.numerics.compiled.kinematics import _predict_into, jacobian_storage, kinematic_point
from mbd3d.numerics.linalg import Factorization, jacobian_factors, jacobian_scaling
from mbd3d.numerics.compiled.dense import (band_factor, band_reciprocal_condition,
                                           band_solve_into, band_solve_transpose_into,
                                           lu_factor, lu_solve_transpose_into,
                                           reciprocal_condition)
from mbd3d.numerics.patterns import jacobian_layout
from test_gears import gear_train, planetary

DATA = pathlib.Path(__file__).parent / "data"


@pytest.mark.parametrize("n", [1, 2, 3, 7, 36, 80])
def test_the_condition_estimate_is_lapacks(n):
    """Hager's and Higham's estimate as LAPACK's gecon makes it, on matrices whose
    conditioning spans ten orders (a column scaled down), and the transposed solve."""
    rng = np.random.default_rng(n)
    for trial in range(30):
        # heavy-tailed entries (Cauchy) make the estimator's stopping rules matter
        A = rng.standard_normal((n, n)) if trial < 6 else rng.standard_cauchy((n, n))
        A[:, trial % n] *= 10.0 ** (-2 * (trial % 6))
        norm = float(np.abs(A).sum(axis=0).max())
        expected = dgecon(dgetrf(A)[0], norm, norm="1")[0]
        LU = A.copy()
        piv, regular = lu_factor(LU, 0.0)
        assert regular
        assert reciprocal_condition(LU, norm) == pytest.approx(expected, rel=1e-10)
        b = rng.standard_normal(n)
        x = b.copy()
        lu_solve_transpose_into(LU, piv, x)
        # a backward-stable solve: the residual at the rounding of the products it sums
        size = np.abs(A.T) @ np.abs(x) + np.abs(b)
        assert np.all(np.abs(A.T @ x - b) <= 1e-13 * n * size)


def _lapack_band(A: np.ndarray, kl: int, ku: int) -> np.ndarray:
    """``A`` in LAPACK's band storage with room for fill-in, ``ab[kl + ku + i - j, j]``."""
    n = A.shape[0]
    ab = np.zeros((2 * kl + ku + 1, n))
    for i, j in zip(*np.nonzero(A)):
        ab[kl + ku + i - j, j] = A[i, j]
    return ab


@pytest.mark.parametrize("n, kl, ku", [(1, 0, 0), (2, 1, 0), (3, 0, 2), (7, 2, 3),
                                       (36, 5, 11), (80, 11, 5), (80, 3, 3)])
def test_the_band_condition_estimate_is_lapacks(n, kl, ku):
    """LAPACK's gbcon on gbtrf's factors, and the banded solves with and without the
    transpose, on band matrices whose conditioning spans ten orders: the interchanges of a
    band LU interleave with L, so its estimate is not gecon's."""
    rng = np.random.default_rng(100 * n + kl)
    i, j = np.indices((n, n))
    inside = (i - j <= kl) & (j - i <= ku)
    for trial in range(30):
        A = rng.standard_normal((n, n)) if trial < 6 else rng.standard_cauchy((n, n))
        A *= inside
        A[:, trial % n] *= 10.0 ** (-2 * (trial % 6))
        norm = float(np.abs(A).sum(axis=0).max())
        lu, ipiv, info = dgbtrf(_lapack_band(A, kl, ku), kl, ku)
        expected = dgbcon(kl, ku, lu, ipiv, norm)[0]
        ab = _lapack_band(A, kl, ku).ravel(order="F")
        piv, regular = band_factor(ab, n, kl, ku, 0.0)
        assert info == 0 and regular
        assert band_reciprocal_condition(ab, n, kl, ku, piv, norm) == pytest.approx(
            expected, rel=1e-10)
        for solve, matrix in ((band_solve_into, A), (band_solve_transpose_into, A.T)):
            b = rng.standard_normal(n)
            x = b.copy()
            solve(ab, n, kl, ku, piv, x)
            # backward stable in norm (LU with partial pivoting is not componentwise: a
            # column scaled down makes x large, and L^T's sums cancel)
            size = np.abs(matrix).sum(axis=1).max() * np.abs(x).max() + np.abs(b).max()
            assert np.abs(matrix @ x - b).max() <= 1e-14 * n * size


def test_a_chain_s_jacobian_is_factored_in_a_band_as_narrow_at_any_length():
    """A driven chain's rows and columns ordered along it: the same bandwidths at 10 and 40
    links (the cost of a time point linear in the length), the PUMA's narrow too; a slider-
    crank's Jacobian is factored dense."""
    def bands(model):
        return tuple(jacobian_layout(model._jac_rows, model._jac_cols, model.n_coordinates)[3])

    assert bands(driven_chain(10)) == bands(driven_chain(40))
    kl, ku = bands(driven_chain(40))
    # a pin's two rows and its driver's share the six columns of two bodies: in any order
    # the three rows and six columns span kl + ku >= 2 + 5, and the LU's work, kl (kl + ku)
    # a column, is least with the two on the side of kl
    assert (kl, ku) == (2, 5)
    kl, ku = bands(_puma())
    assert 0 <= kl * (kl + ku) <= 36 ** 2 / 12
    assert bands(slider_crank()) == (-1, -1)


def _puma() -> mb.Model:
    """The PUMA 560 with each joint on its own harmonic motion (36 coordinates)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mb.UrdfWarning)
        return mb.load_urdf(DATA / "puma560.urdf", drive={
            f"joint{i + 1}": mb.Harmonic(0.5 + 0.1 * i, 1.3 + 0.4 * i, 0.0, 0.2 * i - 0.5)
            for i in range(6)})


def _linked_slider() -> mb.Model:
    """A crank pushing a slider through a massless link (a Distance row, whose constant is
    the link's length), the slider drawn turned by 0.4 rad (its rail's angle row keeps that
    constant), a spring pulling it back."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81), name="linked slider")
    crank = b.add_body("crank", mass=1.0, inertia=2e-3, position=(0.05, 0.0))
    slider = b.add_body("slider", mass=3.0, inertia=1e-2, position=(0.33, 0.0), angle=0.4)
    pin = b.add(Revolute("O", b.ground, crank, at=(0.0, 0.0)))
    b.add(Distance("link", crank, slider, at_i=(0.1, 0.0), at_j=(0.33, 0.0)))
    b.add(Prismatic("rail", b.ground, slider, axis=(1.0, 0.0)))
    b.add(RotationDriver("motor", pin, motion=mb.Ramp(0.0, 3.0)))
    b.add(mb.SpringDamper("spring", b.ground, slider, at_i=(0.6, 0.0), at_j=(0.33, 0.0),
                          stiffness=400.0, damping=3.0, free_length=0.2))
    return b.build()


MODELS = {
    "massless link and a turned slider": _linked_slider,
    "slider-crank": slider_crank,
    "four-bar": four_bar,
    "gear train (half-turn branches)": lambda: gear_train(load=2.0),
    "planetary": lambda: planetary(carrier_load=1.5),
    "spatial slider-crank": spatial_slider_crank,
    "PUMA 560": _puma,
    "40-link driven chain (sparse, banded)": lambda: driven_chain(40),
}


@pytest.mark.parametrize("name", list(MODELS))
def test_compiled_time_points_are_the_lapack_path_s(name, monkeypatch):
    """Every number of inverse dynamics agrees with the path through LAPACK (to 1e-11 of its
    size: each solves positions to Newton's tolerance from its own guess), and no point
    falls back to Python (which would pass unseen, only slower)."""
    model = MODELS[name]()
    t = np.linspace(0.0, 0.4, 9)
    with monkeypatch.context() as patch:
        patch.setattr(kinematics, "COMPILED_POINTS", False)
        expected = mb.inverse_dynamics(model, t)

    def no_python_point(*args, **kwargs):
        raise AssertionError("a time point was solved in Python")
    monkeypatch.setattr(kinematics, "COMPILED_POINTS", True)
    monkeypatch.setattr(kinematics, "solve_position", no_python_point)
    res = mb.inverse_dynamics(model, t)
    # the motion of every body, in global axes: a spatial body's coordinates are relative
    # to a chart that each path moves to where its own guess put the body
    fields = ("position", "velocity", "acceleration", "rotation", "angular_velocity",
              "angular_acceleration")
    for field in fields:
        got, want = (np.array([getattr(r.body(body.name), field) for body in model.bodies])
                     for r in (res, expected))
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-11 * np.abs(want).max(),
                                   err_msg=field)
    np.testing.assert_allclose(res.lam, expected.lam, rtol=0,
                               atol=1e-11 * np.abs(expected.lam).max())
    # the conditioning the singular positions are judged by: LAPACK's estimate, gecon's of
    # the dense factors or gbcon's of the band ones, the rows and columns in the layout's order
    q = res.q[-1].copy()
    charts = None if model.dim == 2 else np.array(res.charts[-1])
    solver = kinematics._PointSolver(model, 1e-12, False, None, "inverse dynamics")
    status, conditioning = kinematic_point(
        model._core.workspace(), t[-1], q, charts, solver.scales, 1e-12, model.length_scale,
        50, True, *np.empty((3, model.n_coordinates)),
        jacobian_storage(model.n_coordinates, solver.scales[7]))
    fr = constraints.frames(model, q, charts=charts)
    Cq = constraints.jacobian(model, t[-1], q, fr, sparse=False)
    row_at, col_at, _, (kl, ku) = solver.scales[4:]
    if kl < 0:
        lapack = Factorization(Cq, scaling=jacobian_scaling(model)).reciprocal_condition()
    else:
        r, c = jacobian_factors(model)
        ordered = np.zeros_like(Cq)
        ordered[np.ix_(row_at, col_at)] = r[:, None] * Cq * c[None, :]
        lu, ipiv, _ = dgbtrf(_lapack_band(ordered, kl, ku), kl, ku)
        lapack = dgbcon(kl, ku, lu, ipiv, np.abs(ordered).sum(axis=0).max())[0]
    assert status == 0 and conditioning == pytest.approx(lapack, rel=1e-10)


def test_the_next_point_is_predicted_exactly_for_a_quartic_motion():
    """The guess of a time point integrates the polynomial through the last three points'
    accelerations twice from the last point: exact (to rounding) for positions of degree 4,
    whatever the spacing; for degree 3 where only two points share their charts, 2 where the
    last point's chart is its own (the others' accelerations are in other coordinates)."""
    t = np.array([0.0, 0.3, 0.45, 0.5, 0.62])
    c = np.array([0.7, -1.3, 2.1])  # three coordinates, each its own polynomial
    for degree, back in ((4, 3), (3, 2), (2, 1)):
        q = c[None, :] * t[:, None] ** degree + 0.2 * t[:, None] ** 2 - 0.4
        qd = c[None, :] * degree * t[:, None] ** (degree - 1) + 0.4 * t[:, None]
        qdd = c[None, :] * degree * (degree - 1) * t[:, None] ** (degree - 2) + 0.4
        charts = np.zeros((len(t), 1, 3, 3))  # one spatial body's charts, by point
        charts[:4 - back] = 1.0  # the points before the last `back` in another chart,
        qdd[:4 - back] = 1e3  # their coordinates meaningless in this one
        guess = np.empty(3)
        _predict_into(t, 4, q, qd, qdd, charts, guess)
        np.testing.assert_allclose(guess, q[4], rtol=0.0, atol=1e-14)
    # a degree more is missed by the next term of the series: order h^5 (h = 0.12 s)
    q, qd, qdd = t ** 5, 5 * t ** 4, 20 * t ** 3
    guess = np.empty(1)
    _predict_into(t, 4, q[:, None], qd[:, None], qdd[:, None], np.zeros((0, 0, 3, 3)), guess)
    assert 1e-6 < abs(guess[0] - q[4]) < 10 * 0.12 ** 5
