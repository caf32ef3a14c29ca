"""Stick-slip: a block dragged through a spring sticks and slips for ever.

A block (3 kg) rests on a rigid floor; a spring (k = 200 N/m) pulls it from a slider driven
away at v = 0.15 m/s. The floor holds it with static friction mu_s = 0.5 and lets it slide
with kinetic friction mu_k = 0.15 (mb.RigidImpact(static_friction=...) and friction=...).
It holds until the spring pulls with mu_s m g, then lurches forward, overshoots, stops and
holds again: the squeal of a door hinge, the chatter of a machine tool's slide.

While it slides, y = (spring's stretch) - mu_k m g / k swings at w = sqrt(k / m) from
y = D = (mu_s - mu_k) m g / k as D cos(w tau) + (v / w) sin(w tau), until the block stops at
w tau = pi + 2 atan(v / (w D)), where y = -D; it then holds (the spring pushes it back with
less than mu_s m g) until y has risen back to D, 2 D / v later. Each switch of the run, an
event on its dense output, is set beside that closed form. Recorded to stick_slip.rrd:
rerun stick_slip.rrd

Run: python examples/stick_slip.py [--rrd FILE] [--show]
"""

from __future__ import annotations

import math

import numpy as np

import mbd3d as mb
from mbd3d.joints import Prismatic, TranslationDriver
from mbd3d.viewer import check_recording_first, record, run_script

G, MASS, K, V, MU_S, MU_K = 9.81, 3.0, 200.0, 0.15, 0.5, 0.15
LENGTH, HEIGHT = 0.4, 0.2


def build() -> mb.Model:
    """The block on the floor y = 0 and the spring to the slider, slack at the start."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -G), name="stick_slip")
    block = b.add_body("block", mass=MASS, inertia=MASS * (LENGTH ** 2 + HEIGHT ** 2) / 12,
                       position=(0.0, HEIGHT / 2))
    b.add(mb.Contact("floor", mb.Box(block, (LENGTH, HEIGHT)),
                     mb.Plane(b.ground, normal=(0.0, 1.0)),
                     law=mb.RigidImpact(restitution=0.0, static_friction=MU_S), friction=MU_K))
    slider = b.add_body("slider", mass=1.0, inertia=0.01, position=(0.5, HEIGHT / 2))
    rail = b.add(Prismatic("rail", b.ground, slider, axis=(1.0, 0.0), at=(0.5, HEIGHT / 2)))
    b.add(TranslationDriver("drag", rail, motion=mb.Ramp(0.0, V)))
    b.add(mb.SpringDamper("spring", block, slider, stiffness=K))
    return b.build()


def switches_by_hand(count: int) -> list[tuple[float, str]]:
    """The first ``count`` slips and sticks [s] of the closed form."""
    D, w = (MU_S - MU_K) * MASS * G / K, math.sqrt(K / MASS)
    first, slide = MU_S * MASS * G / (K * V), (math.pi + 2 * math.atan2(V / w, D)) / w
    period = slide + 2 * D / V
    return [(first + n * period + shift, event) for n in range(count)
            for shift, event in ((0.0, "slip"), (slide, "stick"))][:count]


@check_recording_first
def main(n_points: int = 301, rrd: str | None = None, show: bool = False) -> mb.Results:
    t = np.linspace(0.0, 3.0, n_points)
    res = mb.forward_dynamics(build(), t, method="DOP853", rtol=1e-10, atol=1e-12)
    found = [(r["time"], r["event"]) for r in res.stats["rests"]
             if r["event"] in ("slip", "stick") and r["time"] > 0.0]
    by_hand = switches_by_hand(len(found))
    print(mb.format_table({
        "event": [event for _, event in found],
        "at [s]": [time for time, _ in found],
        "by hand [s]": [time for time, _ in by_hand],
    }, precision=9))
    x = res.body("block").position[:, 0]
    print(f"\nafter {t[-1]:g} s the block has moved {x[-1]:.6f} m (the slider {V * t[-1]:.6f} m); "
          f"friction took {res.energy_balance()['dissipated'][-1]:.6f} J "
          f"(mu_k m g times the way: {MU_K * MASS * G * x[-1]:.6f} J)")
    if rrd is not None:
        record(res, rrd, overwrite=True, show=show)
    return res


if __name__ == "__main__":
    run_script(main, __doc__, "stick_slip.rrd")
