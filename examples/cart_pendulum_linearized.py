"""Linearisation: an inverted pendulum on a cart, and a controller designed on its linear model.

A 1.5 kg cart runs on a horizontal rail; a uniform 0.5 kg pole, 0.8 m long, is pinned on it and
stands upright. A horizontal force on the cart is the input. ``mb.linearize`` gives the linear
equations about the upright state, ``dx' = A dx + B du`` with the state (cart position, pole
angle, and their rates), printed with their names; upright is unstable, at the rate the
Lagrangian gives by hand. A linear-quadratic regulator designed on (A, B) moves every eigenvalue
into the left half-plane. Without it, the pole released 0.001 rad from upright falls away from
it at the unstable eigenvalue's rate, measured from the nonlinear simulation that is recorded.

Recorded to cart_pendulum_linearized.rrd (the fall): rerun cart_pendulum_linearized.rrd

Run: python examples/cart_pendulum_linearized.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as la

import mbd3d as mb
from mbd3d.joints import Prismatic, Revolute
from mbd3d.viewer import check_recording_first, record, run_script

CART, POLE, LENGTH, GRAVITY = 1.5, 0.5, 0.8, 9.81


def cart_pendulum() -> mb.Model:
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -GRAVITY), name="cart-pendulum")
    cart = b.add_body("cart", mass=CART, inertia=0.1, position=(0.0, 0.0))
    pole = b.add_body("pole", mass=POLE, inertia=POLE * LENGTH**2 / 12,
                      position=(0.0, LENGTH / 2), angle=math.pi / 2)
    b.add(Prismatic("rail", b.ground, cart, axis=(1.0, 0.0)))
    b.add(Revolute("hinge", cart, pole, at=(0.0, 0.0)))
    b.add(mb.PointForce("push", cart, force=(0.0, 0.0)))  # zero: the input adds to it
    return b.build()


@check_recording_first
def main(rrd: str | None = None, show: bool = False) -> tuple[mb.LinearModel, np.ndarray]:
    model = cart_pendulum()
    lin = mb.linearize(model, model.q0, coordinates=["cart.x", "pole.theta"],
                       inputs=["push.x"])
    np.set_printoptions(precision=4, suppress=True)
    print("states:", ", ".join(lin.states))
    print("A =\n", lin.A)
    print("B =\n", lin.B)

    # by hand (tilt phi from upright, l = L/2, I the pole's centroidal inertia):
    # lambda^2 = (M + m) m g l / ((M + m)(I + m l^2) - (m l)^2)
    l, inertia = LENGTH / 2, POLE * LENGTH**2 / 12
    by_hand = math.sqrt((CART + POLE) * POLE * GRAVITY * l
                        / ((CART + POLE) * (inertia + POLE * l * l) - (POLE * l) ** 2))
    print(f"unstable eigenvalue {lin.eigenvalues[0].real:.10f} 1/s, by hand {by_hand:.10f}")

    # a regulator on the linear model: u = -K x
    P = la.solve_continuous_are(lin.A, lin.B, np.diag([10.0, 100.0, 1.0, 1.0]), np.eye(1))
    gain = lin.B.T @ P
    closed = np.linalg.eigvals(lin.A - lin.B @ gain)
    print("LQR gain K =", gain.ravel())
    print("closed-loop eigenvalues:", np.sort_complex(closed))

    # without the regulator: released 0.001 rad from upright (the hinge's angle is the pole's
    # from the cart's x axis), the tilt grows as e^(lambda t)
    t = np.linspace(0.0, 1.5, 151)
    fall = mb.forward_dynamics(model, t, initial_positions={"hinge": math.pi / 2 + 1e-3},
                               method="DOP853", rtol=1e-11, atol=1e-13)
    tilt = np.abs(fall.joint("hinge").angle - math.pi / 2)
    early = (t >= 0.8) & (t <= 1.2)  # the growing mode dominates, the tilt still small
    rate = np.polyfit(t[early], np.log(tilt[early]), 1)[0]
    print(f"the fall without control: tilt {tilt[-1]:.3f} rad at {t[-1]:.1f} s, growing at "
          f"{rate:.4f} 1/s between 0.8 and 1.2 s (eigenvalue {lin.eigenvalues[0].real:.4f})")
    if rrd is not None:
        record(fall, rrd, overwrite=True, show=show)
    return lin, gain


if __name__ == "__main__":
    run_script(main, __doc__, "cart_pendulum_linearized.rrd")
