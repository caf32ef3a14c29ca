"""A box against a box: each corner of either box against the other box. Checked against the
same box on a plane (the table's top face is a plane where the box lands on it: the two
models must move alike), against the weight each corner carries at rest, and against the
static penetration of a linear law."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import mbd3d as mb

G = 9.81


def _tilted_box(dim: int, table: str, reverse: bool = False, law=None):
    """A box dropped tilted onto a floor at height 0: a plane, or the top face of a box fixed
    to the ground (2 m wide, 1 m deep), the pair given either way round."""
    size = np.array([0.4, 0.2, 0.3])[:dim]
    m = 3.0
    if dim == 2:
        inertia = m / 12 * (size[0] ** 2 + size[1] ** 2)
        pose = {"position": (0.0, 0.35), "angle": 0.3}
    else:
        inertia = m / 12 * np.diag([size[1] ** 2 + size[2] ** 2, size[0] ** 2 + size[2] ** 2,
                                    size[0] ** 2 + size[1] ** 2])
        pose = {"position": (0.0, 0.35, 0.0),
                "orientation": Rotation.from_euler("xz", [0.15, 0.25]).as_matrix()}
    b = mb.ModelBuilder(dim=dim, gravity=(0.0, -G) + (0.0,) * (dim - 2))
    box = b.add_body("box", mass=m, inertia=inertia, **pose)
    if table == "plane":
        floor = mb.Plane(b.ground, normal=(0.0, 1.0) + (0.0,) * (dim - 2))
    else:
        floor = mb.Box(b.ground, (2.0, 1.0, 2.0)[:dim], at=(0.0, -0.5, 0.0)[:dim])
    law = law or mb.RigidImpact(restitution=0.3, rest_speed=0.05)
    pair = (floor, mb.Box(box, size)) if reverse else (mb.Box(box, size), floor)
    b.add(mb.Contact("floor", *pair, law=law))
    return b.build(), size, m


@pytest.mark.parametrize("dim", [2, 3])
def test_a_box_tumbling_onto_a_table_moves_as_onto_its_top_plane_and_rests_on_its_corners(dim):
    """Rigid impacts, then the corners held at rest: the table's top face is the plane's, so
    every impact, rest and release is the same, to the rounding of the two gaps' formulas; at
    rest the box's lower corners share its weight (half each planar, a quarter spatial), the
    pair given either way round. The tumble amplifies rounding: the plane's own states at
    0.35 s move by 1.5e-7 when only the output times change, hence 1e-6 on the states."""
    t = np.linspace(0.0, 1.5, 151)
    runs = {}
    for table, reverse in (("plane", False), ("box", False), ("box", True)):
        model, size, m = _tilted_box(dim, table, reverse)
        runs[table, reverse] = mb.forward_dynamics(model, t, method="DOP853", rtol=1e-10,
                                                   atol=1e-12)
    plane = runs["plane", False]
    assert plane.status == "complete" and plane.stats["rests"]
    for key in (("box", False), ("box", True)):
        res = runs[key]
        assert res.status == "complete"
        for kind in ("impacts", "rests"):
            assert [r["time"] for r in res.stats[kind]] == pytest.approx(
                [r["time"] for r in plane.stats[kind]], abs=1e-9)
        np.testing.assert_allclose(res.q, plane.q, rtol=0, atol=1e-6)
        contacts = res.contacts()
        # "floor[first corner -+-]": the box's corners by the signs of their coordinates,
        # y = -size / 2 below; the table's corners ("second" or "first", reversed) far off
        mine = "second" if key[1] else "first"
        lower = [k for k, name in enumerate(contacts.names)
                 if name.startswith(f"floor[{mine} corner")
                 and name[-2 if dim == 2 else -3] == "-"]
        assert len(lower) == 2 ** (dim - 1)
        np.testing.assert_allclose(contacts.normal_force[-1, lower], m * G / len(lower),
                                   rtol=1e-9)
        assert np.all(np.delete(contacts.normal_force[-1], lower) == 0.0)
        np.testing.assert_allclose(res.body("box").position[-1, 1], size[1] / 2, rtol=0,
                                   atol=1e-9)


@pytest.mark.parametrize("reverse", [False, True])
def test_a_slab_on_a_post_sinks_to_the_linear_laws_static_penetration(reverse):
    """A slab wider than the post it lies on: the post's four top corners press into the
    slab's bottom face (the rows of the second box's corners), each carrying a quarter of its
    weight, m g / 4 = k delta, at the penetration delta the slab sinks to."""
    m, k = 2.0, 2e5
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -G))
    slab_size = np.array([0.6, 0.4, 0.05])
    inertia = m / 12 * np.diag([slab_size[1] ** 2 + slab_size[2] ** 2,
                                slab_size[0] ** 2 + slab_size[2] ** 2,
                                slab_size[0] ** 2 + slab_size[1] ** 2])
    slab = b.add_body("slab", mass=m, inertia=inertia, position=(0.3, 0.0, 0.0251))
    post = mb.Box(b.ground, (0.1, 0.1, 1.0), at=(0.3, 0.0, -0.5))  # its top at z = 0
    shapes = (post, mb.Box(slab, slab_size)) if reverse else (mb.Box(slab, slab_size), post)
    b.add(mb.Contact("post", *shapes, law=mb.LinearContact(stiffness=k, restitution=0.2)))
    res = mb.forward_dynamics(b.build(), [0.0, 1.0, 1.5], method="DOP853", rtol=1e-10,
                              atol=1e-13)
    assert res.status == "complete"
    delta = m * G / (4 * k)
    np.testing.assert_allclose(res.body("slab").position[1:, 2], slab_size[2] / 2 - delta,
                               rtol=1e-9)
    np.testing.assert_allclose(res.body("slab").velocity[-1], 0.0, atol=1e-10)
    contacts = res.contacts()
    post_side = "first" if reverse else "second"
    top = [k for k, name in enumerate(contacts.names)
           if name.startswith(f"post[{post_side} corner") and name[-2] == "+"]
    assert len(top) == 4
    np.testing.assert_allclose(contacts.normal_force[-1, top], m * G / 4, rtol=1e-9)
    assert np.all(np.delete(contacts.normal_force[-1], top) == 0.0)
    # each row's normal points from the pair's first shape to its second
    np.testing.assert_allclose(contacts.normal[-1, top], [[0.0, 0.0, 1.0 if reverse else -1.0]] * 4,
                               atol=1e-12)
