"""Newton's cradle of steel balls with compliant, undamped Hertz contacts: each impact lasts
about 70 us while the balls stand 2 mm apart, so the impulse passes by binary collisions of
equal masses, which conservation of momentum and energy alone settle (e = 1: the striker
stops and the struck ball leaves at its speed). At the end the last ball carries all the
momentum and energy, the others are at rest."""

from __future__ import annotations

import numpy as np
import pytest

import mbd3d as mb

N, GAP, SPEED, RADIUS, MASS = 5, 2e-3, 0.5, 0.05, 0.2


def cradle(dim: int) -> mb.Model:
    """``N`` balls in a row along x, ``GAP`` apart, the first moving at ``SPEED`` into the
    others; steel (Hertz's stiffness of E = 210 GPa, nu = 0.3), no damping, no gravity."""
    b = mb.ModelBuilder(dim=dim, gravity=(0.0,) * dim)
    law = mb.HertzContact(young_modulus=2.1e11, poisson_ratio=0.3, restitution=1.0)
    inertia = 0.4 * MASS * RADIUS ** 2
    balls = [b.add_body(f"ball{k}", mass=MASS,
                        inertia=inertia if dim == 2 else np.eye(3) * inertia,
                        position=(k * (2 * RADIUS + GAP),) + (0.0,) * (dim - 1),
                        velocity=(SPEED if k == 0 else 0.0,) + (0.0,) * (dim - 1))
             for k in range(N)]
    for k in range(N - 1):
        b.add(mb.Contact(f"touch{k}", mb.Sphere(balls[k], RADIUS),
                         mb.Sphere(balls[k + 1], RADIUS), law=law))
    return b.build()


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("method, options, tolerance, balance", [
    # the explicit stages keep a linear invariant to rounding
    ("DOP853", dict(rtol=1e-10, atol=1e-12), 1e-8, 1e-12),
    # a step of 1 ms, shortened into each impact (about 70 us) and back after it; the
    # momentum to the Newton iteration's tolerance
    ("generalized-alpha", dict(step=1e-3), 1e-5, 1e-8)])
def test_the_last_ball_leaves_with_the_strikers_momentum_and_energy(dim, method, options,
                                                                    tolerance, balance):
    model = cradle(dim)
    res = mb.forward_dynamics(model, [0.0, 0.03], method=method, **options)
    nc = model.n_coords_per_body
    v = res.qd[-1, 0::nc]  # the balls' speeds along the row
    expected = np.zeros(N)
    expected[-1] = SPEED
    np.testing.assert_allclose(v, expected, rtol=0, atol=tolerance * SPEED)
    np.testing.assert_allclose(res.qd[-1].reshape(N, nc)[:, 1:], 0.0, rtol=0, atol=1e-12)
    # the contact forces are equal and opposite
    np.testing.assert_allclose(MASS * v.sum(), MASS * SPEED, rtol=balance, atol=0)
    energy = mb.kinetic_energy(model, res.q[-1], res.qd[-1], None if res.charts is None
                               else res.charts[-1])
    np.testing.assert_allclose(energy, 0.5 * MASS * SPEED ** 2, rtol=2 * tolerance, atol=0)
    # the balls passed the impulse one after the other: each was struck after the one before
    moved = [np.argmax(np.abs(res.qd[:, k * nc]) > 0.5 * SPEED) for k in range(N)]
    assert moved[0] == 0 and np.all(np.diff(moved[1:]) >= 0)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_looser_tolerance_takes_fewer_steps_through_the_impacts(dim):
    """Undamped Hertz contacts open as ``delta^(3/2)``, with no slope. A switching function
    that followed the force placed each step's end by a secant that fell short of the release,
    again and again, in steps shrinking towards it: the run then cost the same at any
    tolerance (about 11,000 right-hand sides from rtol 1e-6 to 1e-10). The steps must follow
    the tolerance instead."""
    model = cradle(dim)
    counts = [mb.forward_dynamics(model, [0.0, 0.03], method="DOP853", rtol=rtol,
                                  atol=rtol * 1e-2).stats["rhs_evaluations"]
              for rtol in (1e-6, 1e-10)]
    assert counts[0] < 0.75 * counts[1]
