"""Haug's slider-crank DAE (SUNDIALS IDAS example idasSlCrank_dns): spring-damper and a force.

E. J. Haug, Intermediate Dynamics (Prentice Hall 1992), Example 6.1.8, as coded in the
SUNDIALS example: a crank (a = 0.5 m, J1 = 1 kg m^2 about its pivot) drives a connecting rod
whose centre runs in a horizontal slot 1 m from the crank pin (mass m2 = 1 kg, J2 = 2 kg m^2);
a spring-damper (k = 1 N/m, c = 1 N s/m, free length 1 m) joins the crank's mid-point to the rod
point 0.5 m from the crank pin, and a constant horizontal force F = 1 N pulls the rod at 2 m from
the crank pin. The mechanism starts at rest with the crank vertical and swings for 10 s.

SUNDIALS writes it in three coordinates (crank angle q, slider position x, rod angle p); here
it is two rigid bodies, two revolutes and a pin in a slot, and (q, x, p) are read off the
bodies. The published output (every 0.4 s, 5 digits, IDAS at rtol 1e-6) is the file
``idasSlCrank_dns.out`` of SUNDIALS (``examples/idas/serial``); the script prints every row of it
beside mbd3d's values and the difference.

Recorded to haug_slider_crank.rrd: rerun haug_slider_crank.rrd

Run: python examples/haug_slider_crank.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import pathlib

import numpy as np
from scipy.integrate import simpson

import mbd3d as mb
from mbd3d.joints import PointOnLine, Revolute
from mbd3d.viewer import check_recording_first, record, run_script

A = 0.5  # crank length, pivot to crank pin [m]
#: SUNDIALS' printed rows (t, q, x, p), with their source in data/README.md
REFERENCE = pathlib.Path(__file__).resolve().parent / "data" / "sundials_idasSlCrank_dns.txt"
#: the quadrature G SUNDIALS prints [J s] (IDAS at rtol 1e-6)
G_IDAS = 3.3366160662934146


def build() -> mb.Model:
    """The mechanism at t = 0: crank vertical (q = pi/2), rod angle p = asin(-a), at rest."""
    b = mb.ModelBuilder(dim=2, name="Haug slider-crank")  # no gravity
    p0 = np.arcsin(-A)
    pin = np.array([0.0, A])                        # crank pin at q = pi/2
    along = np.array([np.cos(p0), np.sin(p0)])      # rod direction
    # the crank's centre of mass is its pivot, so only J1 enters (its mass is carried by the pin)
    crank = b.add_body("crank", mass=1.0, inertia=1.0, position=(0.0, 0.0), angle=np.pi / 2)
    rod = b.add_body("rod", mass=1.0, inertia=2.0, position=pin + along, angle=p0)
    b.add(Revolute("pivot", b.ground, crank, at=(0.0, 0.0)))
    b.add(Revolute("crank pin", crank, rod, at=pin))
    b.add(PointOnLine("slot", b.ground, rod, axis=(1.0, 0.0), at=pin + along))
    b.add(mb.SpringDamper("spring", crank, rod, at_i=pin / 2, at_j=pin + along / 2,
                          stiffness=1.0, damping=1.0, free_length=1.0))
    b.add(mb.PointForce("pull", rod, (1.0, 0.0), point=(1.0, 0.0)))  # 2 m from the crank pin
    return b.build()


def coordinates(res: mb.Results) -> np.ndarray:
    """SUNDIALS' (q, x, p) [rad, m, rad] at every output time, shape (k, 3)."""
    return np.column_stack([res.body("crank").angle, res.body("rod").position[:, 0],
                            res.body("rod").angle])


@check_recording_first
def main(duration: float = 10.0, rtol: float = 1e-11, rrd: str | None = None,
         show: bool = False) -> mb.Results:
    model = build()
    print(mb.mobility(model), "\n")
    # every 0.01 s: the SUNDIALS rows are every 40th point, and Simpson's rule on this grid
    # gives G to 1e-10
    t = np.linspace(0.0, duration, round(duration / 0.01) + 1)
    res = mb.forward_dynamics(model, t, method="DOP853", rtol=rtol, atol=1e-13)
    reference = np.loadtxt(REFERENCE)
    reference = reference[reference[:, 0] <= duration + 1e-9]
    qxp = coordinates(res)[::40]
    error = np.abs(qxp - reference[:, 1:])
    print("SUNDIALS' printed rows (IDAS, rtol 1e-6, 5 digits) beside mbd3d's (DOP853)")
    print(mb.format_table({"t [s]": res.t[::40], "q [rad]": qxp[:, 0], "q IDAS": reference[:, 1],
                           "x [m]": qxp[:, 1], "x IDAS": reference[:, 2],
                           "p [rad]": qxp[:, 2], "p IDAS": reference[:, 3],
                           "max |error|": error.max(axis=1)}, precision=6, rows=len(qxp)))
    print(f"largest difference over the {len(qxp)} rows: {error.max():.1e} rad or m (the rows are "
          "printed to 5 digits)")
    # G of the SUNDIALS example: the time integral of the kinetic energy [J s]
    G = simpson(res.kinetic_energy, x=res.t)
    print(f"\nG = integral of T dt = {G:.10f} J s (IDAS: {G_IDAS:.10f} at rtol 1e-6, "
          f"{abs(G - G_IDAS):.1e} J s apart)")
    print(f"{res.stats['steps']} steps, {res.stats['wall_time']:.2f} s of wall time")
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res


if __name__ == "__main__":
    run_script(main, __doc__, "haug_slider_crank.rrd")
