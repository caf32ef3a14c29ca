"""Contact groups against what is computed apart from them: the broad phase's pairs against a
brute-force search over all pairs, the group's accelerations, tangent and contact states
against the same shapes given pair by pair as Contacts, energy conserved by undamped contacts
in a box of spheres, and the messages for bad groups."""

from __future__ import annotations

import itertools
import math
import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import mbd3d as mb
from mbd3d.errors import ContactWarning, ModelError
from mbd3d.mechanisms import spheres_in_box
from mbd3d.model import constraints
from mbd3d.model.contacts import contact_group
from mbd3d.numerics.compiled import contact_grid as grid


def _brute_force_pairs(A, Q, bodies, points, values, dim) -> set:
    """All pairs whose bounding spheres overlap, or a bounded shape within its bounding
    radius of a plane's half-space, by a loop over every pair."""
    def world(s, row):
        return A[bodies[s]] @ points[s, row] + Q[bodies[s], :dim]

    centre, radius = np.zeros((len(bodies), dim)), np.zeros(len(bodies))
    for s, (kind, r, _) in enumerate(values):
        if kind == grid.SPHERE:
            centre[s], radius[s] = world(s, 0), r
        elif kind == grid.BOX:  # its half diagonal, whichever way it is turned
            centre[s], radius[s] = world(s, 0), np.linalg.norm(points[s, 1]) + r
        elif kind == grid.CAPSULE:
            a, b = world(s, 0), world(s, 1)
            centre[s], radius[s] = (a + b) / 2, np.linalg.norm(b - a) / 2 + r
    found = set()
    for a, b in itertools.combinations(range(len(bodies)), 2):
        planes = [s for s in (a, b) if values[s, 0] == grid.PLANE]
        if bodies[a] == bodies[b] or len(planes) == 2:
            continue
        if not planes:
            near = np.linalg.norm(centre[a] - centre[b]) <= radius[a] + radius[b]
        else:
            p, s = (a, b) if planes[0] == a else (b, a)
            normal = A[bodies[p]] @ points[p, 1]
            near = normal @ (centre[s] - world(p, 0)) <= radius[s]
        if near:
            found.add((a, b))
    return found


@pytest.mark.parametrize("dim", [2, 3])
def test_the_grid_finds_the_pairs_a_search_over_all_pairs_finds(dim):
    rng = np.random.default_rng(dim)
    for trial in range(60):
        count, n_bodies = int(rng.integers(2, 90)), int(rng.integers(1, 40))
        bodies = rng.integers(0, n_bodies + 1, count)  # the last row is the ground's
        A = np.tile(np.eye(dim), (n_bodies + 1, 1, 1))
        Q = np.zeros((n_bodies + 1, 3 * dim - 3))
        for b in range(n_bodies):
            turn = Rotation.random(random_state=100 * trial + b).as_matrix()
            A[b] = turn if dim == 3 else turn[:2, :2] / np.linalg.norm(turn[0, :2])
            # now and then a body far away, beyond the grid's hash range of cells
            Q[b, :dim] = rng.uniform(-1, 1, dim) * (1e14 if rng.uniform() < 0.05 else 1.0)
        if dim == 2:
            A[:-1] = [[[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]]
                      for a in rng.uniform(0, 2 * math.pi, n_bodies)]
        values = np.zeros((count, 3))
        values[:, 0] = rng.choice([grid.SPHERE, grid.SPHERE, grid.CAPSULE, grid.BOX,
                                   grid.PLANE], count)
        values[:, 1] = rng.uniform(0.005, 0.3, count) * rng.uniform(0.1, 1.0)
        points = rng.uniform(-0.3, 0.3, (count, 2, dim))
        planes = values[:, 0] == grid.PLANE
        points[planes, 1] /= np.linalg.norm(points[planes, 1], axis=1)[:, None]
        boxes = values[:, 0] == grid.BOX
        points[boxes, 1] = np.abs(points[boxes, 1])  # half sizes
        pairs = grid.near_pairs(A, Q, bodies, points, values, 0, count)
        found = {tuple(int(s) for s in p) for p in pairs}
        assert len(found) == len(pairs), "a pair found twice"
        assert found == _brute_force_pairs(A, Q, bodies, points, values, dim), trial


def _pile(dim: int, group: bool, law) -> mb.Model:
    """Balls, two capsules, two boxes (rounded, turned), a ball and a box fixed to the ground,
    overlapping here and there, in a corner of two planes; as one group, or as a Contact for
    every pair of shapes."""
    up = np.eye(dim)[dim - 1]
    b = mb.ModelBuilder(dim=dim, gravity=-9.81 * up)
    rng = np.random.default_rng(7)
    shapes = []
    for k in range(9):
        at = np.append(rng.uniform(0.0, 0.5, dim - 1), rng.uniform(0.05, 0.4))
        inertia = 0.003 if dim == 2 else (0.003, 0.004, 0.005)
        body = b.add_body(f"ball{k}", mass=1.0 + 0.5 * (k % 3), inertia=inertia, position=at,
                          angle=0.3 * k if dim == 2 else None)
        shapes.append(mb.Sphere(body, radius=0.06 + 0.02 * (k % 2)))
    for k in range(2):
        body = b.add_body(f"rod{k}", mass=2.0, inertia=0.02 if dim == 2 else (0.02,) * 3,
                          position=np.append(np.full(dim - 1, 0.2 + 0.1 * k), 0.1 + 0.15 * k))
        end = 0.2 * np.eye(dim)[k % (dim - 1)]
        shapes.append(mb.Capsule(body, radius=0.04, ends=(-end, end)))
        shapes.append(mb.Sphere(body, radius=0.03, point=end))  # a knob: same body, no pair
    for k in range(2):
        size = np.array([0.12, 0.08, 0.1][:dim]) * (1.0 + 0.5 * k)
        turn = ({"angle": 0.4 + k} if dim == 2 else
                {"orientation": Rotation.from_rotvec([0.3, 0.2 + k, 0.1]).as_matrix()})
        body = b.add_body(f"crate{k}", mass=1.5 + k, inertia=0.004 if dim == 2 else
                          (0.004, 0.005, 0.006), **turn,
                          position=np.append(np.full(dim - 1, 0.15 + 0.2 * k), 0.08 + 0.1 * k))
        shapes.append(mb.Box(body, size, radius=0.01 * (k + 1)))
    shapes.append(mb.Sphere(b.ground, radius=0.1, at=np.append(np.full(dim - 1, 0.3), 0.0)))
    shapes.append(mb.Box(b.ground, np.full(dim, 0.1), at=np.append(np.full(dim - 1, 0.05), 0.02),
                         radius=0.005))
    shapes.append(mb.Plane(b.ground, normal=up))
    shapes.append(mb.Plane(b.ground, normal=np.eye(dim)[0], at=np.zeros(dim)))
    if group:
        b.add(mb.ContactGroup("pile", shapes, law=law, friction=0.4, slip_velocity=0.01))
    else:
        for (a, first), (c, second) in itertools.combinations(enumerate(shapes), 2):
            if first.body is not second.body:
                b.add(mb.Contact(f"pair{a}_{c}", first, second, law=law, friction=0.4,
                                 slip_velocity=0.01))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ContactWarning)  # they overlap on purpose
        return b.build()


LAWS = {"Hertz from the material": mb.HertzContact(young_modulus=2e7, poisson_ratio=0.3,
                                                    restitution=0.6),
        "linear by frequency": mb.LinearContact(frequency=40.0, restitution=0.5)}


@pytest.mark.parametrize("law", LAWS.values(), ids=LAWS.keys())
@pytest.mark.parametrize("dim", [2, 3])
def test_a_group_pushes_as_its_pairs_given_one_by_one(dim, law):
    """Accelerations, the implicit method's tangent and the energy and deepest gap reported,
    at states where several pairs overlap, equal those of a Contact per pair, whose laws are
    calibrated to each pair's masses and radii on their own."""
    grouped, pairwise = _pile(dim, True, law), _pile(dim, False, law)
    rng = np.random.default_rng(dim)
    touching = 0
    for trial in range(5):
        q = grouped.q0 + rng.normal(0.0, 0.02, grouped.n_coordinates)
        qd = rng.normal(0.0, 1.0, grouped.n_coordinates)
        qdd_group = mb.forward_accelerations(grouped, 0.0, q, qd)[0]
        qdd_pairs = mb.forward_accelerations(pairwise, 0.0, q, qd)[0]
        np.testing.assert_allclose(qdd_group, qdd_pairs, rtol=1e-11,
                                   atol=1e-11 * np.max(np.abs(qdd_pairs)))
        states = [mb.contact_states(m, q, qd) for m in (grouped, pairwise)]
        touching += int(np.sum(states[1].gap < 0.0))
        assert states[0].gap[0] == pytest.approx(np.min(states[1].gap), rel=1e-12)
        assert states[0].potential_energy[0] == pytest.approx(
            np.sum(states[1].potential_energy), rel=1e-12)
        matrices = []
        for m in (grouped, pairwise):
            fr = constraints.frames(m, q, qd)
            rows, cols, values = contact_group(m).tangent(m, 0.0, fr, 0.37)
            size = (len(m.bodies) + 1) * m.n_coords_per_body
            matrices.append(np.zeros((size, size)))
            np.add.at(matrices[-1], (rows, cols), values)
        np.testing.assert_allclose(matrices[0], matrices[1], rtol=1e-11,
                                   atol=1e-11 * np.max(np.abs(matrices[1])))
    assert touching >= 10  # the states pressed many pairs together


@pytest.mark.compiled_only  # 20,000 steps of 27 spheres
def test_undamped_spheres_in_a_box_keep_their_energy():
    """Hertz's law without damping (restitution 1) and no friction: what the spheres and the
    contacts' springs hold stays the energy they started with over many impacts, to the
    integrator's error, which falls with its tolerance (the group's touches are not located:
    its steps see the kink of each)."""
    model = spheres_in_box(27, restitution=1.0, friction=0.0, speed=1.0)
    drift = []
    for rtol in (1e-9, 1e-11):
        res = mb.forward_dynamics(model, np.linspace(0.0, 0.3, 31), rtol=rtol,
                                  atol=1e-3 * rtol)
        balance = res.energy_balance()
        total = balance["kinetic"] + balance["potential"]
        assert np.max(np.abs(balance["dissipated"])) < 1e-12 * total[0]
        drift.append(np.max(np.abs(total - total[0])) / total[0])
        # the spheres did meet, each other or the box: a pair was pressed in at some output
        assert np.min(res.contacts().gap) < 0.0
    assert drift[1] < 1e-7 and drift[1] < drift[0] / 20


@pytest.mark.compiled_only  # thousands of steps of 12 discs
def test_a_dropped_pile_loses_what_its_contacts_dissipate():
    """Damped contacts with friction: the energy the pairs' dampers and friction dissipate,
    summed over the pairs found at each evaluation, closes the balance."""
    model = spheres_in_box(12, dim=2, restitution=0.3, friction=0.5, speed=0.3)
    res = mb.forward_dynamics(model, np.linspace(0.0, 0.25, 6), rtol=1e-7, atol=1e-10)
    balance = res.energy_balance()
    assert np.max(np.abs(balance["total"] - balance["total"][0])) < 1e-5 * balance["total"][0]
    assert balance["dissipated"][-1] > 0.5 * balance["kinetic"][0]


@pytest.mark.compiled_only  # a pile of 8 discs for 0.2 s
def test_a_group_is_one_row_of_the_results_and_the_model_file(tmp_path):
    model = spheres_in_box(8, dim=2, speed=0.0)
    path = tmp_path / "pile.yaml"
    mb.save(model, path)
    again = mb.load(path)
    q, qd = model.q0, np.linspace(-1.0, 1.0, model.n_coordinates)
    np.testing.assert_array_equal(mb.forward_accelerations(again, 0.0, q, qd)[0],
                                  mb.forward_accelerations(model, 0.0, q, qd)[0])
    res = mb.forward_dynamics(model, np.linspace(0.0, 0.2, 5), rtol=1e-6, atol=1e-9)
    states = res.contacts()
    assert states.names == ["pile"]
    assert np.isinf(states.gap[0, 0])  # apart at the start: no pair near
    assert states.gap[-1, 0] < 0.0 and states.normal_force[-1, 0] > 0.0


def test_bad_groups_are_named():
    b = mb.ModelBuilder(dim=3)
    one = b.add_body("one", mass=1.0, inertia=(1.0, 1.0, 1.0), position=(0.0, 0.0, 0.0))
    two = b.add_body("two", mass=1.0, inertia=(1.0, 1.0, 1.0), position=(1.0, 0.0, 0.0))
    law = mb.HertzContact(stiffness=1e6, restitution=0.5)
    with pytest.raises(ModelError, match=r"contact group 'g': shape 1 is a Hole.*add a Contact"):
        mb.ContactGroup("g", [mb.Sphere(one, 0.1), mb.Hole(two, 0.1, axis=(0, 0, 1))], law=law)
    with pytest.raises(ModelError, match="contact group 'g': give shapes on at least two"):
        mb.ContactGroup("g", [mb.Sphere(one, 0.1), mb.Sphere(one, 0.2)], law=law)
    with pytest.raises(ModelError, match="contact group 'g': law must be a compliant law"):
        mb.ContactGroup("g", [mb.Sphere(one, 0.1), mb.Sphere(two, 0.2)],
                        law=mb.RigidImpact(restitution=1.0))
    b.add(mb.ContactGroup("g", [mb.Sphere(one, 0.1), mb.Sphere(two, 0.2)], law=law,
                          friction=-1.0))
    with pytest.raises(ModelError, match="contact group 'g': friction must be >= 0"):
        b.build()
    b = mb.ModelBuilder(dim=2)
    one = b.add_body("one", mass=1.0, inertia=1.0, position=(0.0, 0.0))
    two = b.add_body("two", mass=1.0, inertia=1.0, position=(0.25, 0.0))
    b.add(mb.ContactGroup("g", [mb.Sphere(one, 0.1), mb.Sphere(two, 0.2)], law=law))
    with pytest.warns(ContactWarning, match=r"contact group 'g': two of its shapes overlap by "
                                            r"\(the deepest pair\) 0.05 m"):
        b.build()
