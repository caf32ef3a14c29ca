"""Contacts over a run: the histories of ``Results.contacts()``, their table columns and
their recording, checked against Newton's second law and the shapes' geometry, not against
the report that computes them."""

from __future__ import annotations

import numpy as np
import pytest
import rerun as rr
from scipy.spatial.transform import Rotation

import mbd3d as mb
from mbd3d.viewer import entity_paths, read_component, record

G = 9.81
M_BOX, M_BALL, R_BALL = 2.0, 0.5, 0.05


def _crate_and_ball(dim: int):
    """A box sliding and turning on the floor with friction, and a ball dropped onto it: a
    ball-box, a box-floor (a row per corner) and a ball-floor contact."""
    up = np.eye(dim)[-1]
    b = mb.ModelBuilder(dim=dim, gravity=-G * up)
    if dim == 2:
        box = b.add_body("box", mass=M_BOX, inertia=0.03, position=(0.0, 0.1051),
                         velocity=(1.0, 0.0), angular_velocity=0.5)
        ball = b.add_body("ball", mass=M_BALL, inertia=5e-4, position=(0.05, 0.3))
        size = (0.4, 0.2)
    else:
        box = b.add_body("box", mass=M_BOX, inertia=np.diag([0.02, 0.03, 0.04]),
                         position=(0.0, 0.0, 0.112), velocity=(1.0, 0.3, 0.0),
                         orientation=Rotation.from_rotvec([0.02, -0.01, 0.3]).as_matrix(),
                         angular_velocity=(0.0, 0.0, 2.0))
        ball = b.add_body("ball", mass=M_BALL, inertia=np.eye(3) * 5e-4,
                          position=(0.05, 0.02, 0.3))
        size = (0.4, 0.3, 0.2)
    floor = mb.Plane(b.ground, normal=up)
    b.add(mb.Contact("crate", mb.Box(box, size, radius=0.005), floor,
                     law=mb.HertzContact(stiffness=1e8, restitution=0.5), friction=0.3,
                     slip_velocity=1e-3))
    b.add(mb.Contact("drop", mb.Sphere(ball, R_BALL), mb.Box(box, size),
                     law=mb.HertzContact(stiffness=1e7, restitution=0.8), friction=0.2))
    b.add(mb.Contact("ball floor", mb.Sphere(ball, R_BALL), floor,
                     law=mb.LinearContact(stiffness=1e5, restitution=0.5)))
    return b.build()


@pytest.fixture(scope="module", params=[2, 3])
def run(request):
    model = _crate_and_ball(request.param)
    return mb.forward_dynamics(model, np.linspace(0.0, 0.4, 161), method="DOP853", rtol=1e-10,
                               atol=1e-12)


def _push(states, names):
    """(k, r, 3): each row's force on its second shape, normal and friction."""
    rows = [n for n, name in enumerate(states.names) if name.split("[")[0] in names]
    return (states.normal_force[:, rows, None] * states.normal[:, rows]
            + states.friction_force[:, rows])


def test_contact_forces_over_a_run_are_what_accelerates_each_body(run):
    """At every output, each body's mass times its acceleration (from the integrator's own
    force evaluation) equals its weight plus the contact forces the history reports on it:
    the box is the first shape against the floor and the second against the ball, the ball
    the first of both its pairs."""
    dim = run.model.dim
    states = run.contacts()
    assert states.gap.shape == (len(run.t), 2 ** dim + 2)
    weight = np.zeros(3)
    weight[dim - 1] = -G
    on_box = _push(states, {"drop"}).sum(axis=1) - _push(states, {"crate"}).sum(axis=1)
    on_ball = -_push(states, {"drop", "ball floor"}).sum(axis=1)
    for name, mass, force in (("box", M_BOX, on_box), ("ball", M_BALL, on_ball)):
        accel = np.zeros((len(run.t), 3))
        accel[:, :dim] = run.body(name).acceleration
        scale = np.max(np.abs(force)) + mass * G
        np.testing.assert_allclose(mass * accel, mass * weight + force, rtol=0,
                                   atol=1e-9 * scale)
    # the run struck everything it was meant to: the ball hit the box, the box slid on the
    # floor while the ball never reached it
    assert np.max(states.normal_force[:, states.names.index("drop")]) > 10 * M_BALL * G
    sliding = np.linalg.norm(_push(states, {"crate"}).sum(axis=1)[:, :dim - 1], axis=1)
    assert np.max(sliding) > 0.25 * M_BOX * G
    assert np.all(states.normal_force[:, -1] == 0.0)


def test_gaps_and_points_over_a_run_follow_the_bodies(run):
    """The ball's gap to the floor is its height less its radius; its contact point lies
    below it, midway across the gap; the normal points from the ball (the first shape) down
    to the floor."""
    dim = run.model.dim
    states = run.contacts()
    r = states.names.index("ball floor")
    centre = run.body("ball").position
    np.testing.assert_allclose(states.gap[:, r], centre[:, -1] - R_BALL, rtol=0, atol=1e-15)
    np.testing.assert_allclose(states.gap_rate[:, r], run.body("ball").velocity[:, -1],
                               rtol=0, atol=1e-15)
    expected = np.zeros((len(run.t), 3))
    expected[:, :dim] = centre
    expected[:, dim - 1] = 0.5 * (centre[:, -1] - R_BALL)
    np.testing.assert_allclose(states.point[:, r], expected, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(states.normal[:, r], np.tile(-np.eye(3)[dim - 1],
                                                              (len(run.t), 1)))


def test_every_contact_row_has_its_columns_in_the_tables(run):
    states = run.contacts()
    cols = run.columns()
    for r, name in enumerate(states.names):
        np.testing.assert_array_equal(cols[f"{name}.gap [m]"], states.gap[:, r])
        np.testing.assert_array_equal(cols[f"{name}.Fn [N]"], states.normal_force[:, r])
        np.testing.assert_array_equal(cols[f"{name}.Ft [N]"],
                                      np.linalg.norm(states.friction_force[:, r], axis=1))


def test_a_model_without_contacts_says_so():
    b = mb.ModelBuilder(dim=2)
    b.add_body("free", mass=1.0, inertia=0.1, position=(0.0, 0.0))
    res = mb.forward_dynamics(b.build(), [0.0, 0.1])
    with pytest.raises(mb.ModelError, match="has no contacts or joint limits"):
        res.contacts()
    assert not any(".gap" in c for c in res.columns())


def test_a_recording_draws_the_contact_shapes_and_forces(run, tmp_path):
    rr.set_strict_mode(True)
    try:
        path = tmp_path / "contacts.rrd"
        record(run, path, announce=False)
    finally:
        rr.set_strict_mode(False)
    dim = run.model.dim
    states = run.contacts()
    paths = entity_paths(path)
    assert {"/world/ground/contacts", "/plots/contacts/drop",
            "/world/contacts/drop"} <= paths, paths
    # the ball is drawn as a sphere of its radius about its centre, not as an inertia box
    _, vertices = read_component(path, "/world/bodies/ball/shape", "Mesh3D:vertex_positions",
                                 None)
    np.testing.assert_allclose(np.linalg.norm(vertices[0], axis=1), R_BALL, rtol=1e-6)
    # the floor's top face lies on the plane
    _, floor = read_component(path, "/world/ground/contacts", "Mesh3D:vertex_positions", None)
    assert np.max(floor[0][:, dim - 1]) == pytest.approx(0.0, abs=1e-7)
    # the energy plot is the balance: with what the contacts dissipated, its total is level
    _, energy = read_component(path, "/plots/energy", "Scalars:scalars")
    balance = run.energy_balance()
    np.testing.assert_array_equal(energy, np.column_stack([balance[part] for part in (
        "kinetic", "potential", "dissipated", "lost_in_impacts", "total")]))
    assert energy[-1, 2] > 0.1 * np.ptp(energy[:, 0] + energy[:, 1])  # a loss plotted
    np.testing.assert_allclose(energy[:, 4], energy[0, 4], rtol=0,
                               atol=1e-8 * np.ptp(energy[:, 0] + energy[:, 1]))
    r = states.names.index("drop")
    _, plotted = read_component(path, "/plots/contacts/drop", "Scalars:scalars")
    np.testing.assert_array_equal(plotted[:, 0], states.normal_force[:, r])
    # the arrow starts at the contact point and points along the force on the ball
    _, origins = read_component(path, "/world/contacts/drop", "Arrows3D:origins")
    _, vectors = read_component(path, "/world/contacts/drop", "Arrows3D:vectors")
    np.testing.assert_allclose(origins[:, 0], states.point[:, r], rtol=0, atol=1e-6)
    force = _push(states, {"drop"})[:, 0]
    hit = np.argmax(states.normal_force[:, r])
    scale = np.linalg.norm(vectors[hit, 0]) / np.linalg.norm(force[hit])
    np.testing.assert_allclose(vectors[:, 0], scale * force, rtol=1e-5,
                               atol=1e-6 * np.linalg.norm(vectors[hit, 0]))
