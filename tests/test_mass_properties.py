"""Mass properties from trimesh meshes against closed forms, and their use as bodies."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

import mbd3d as mb
from mbd3d.joints import Revolute
from mbd3d.model.mass_properties import mesh_properties


def box_inertia(m, a, b, c):
    """Centroidal inertia of a solid box with edges a, b, c along x, y, z."""
    return m / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])


def test_box_mass_center_and_inertia_in_any_placement():
    a, b, c, rho = 0.3, 0.1, 0.04, 7800.0
    rotation = mb.rotations.axis_angle((1.0, 2.0, -0.5), 0.7)
    offset = np.array([0.2, -0.15, 1.3])
    mesh = trimesh.creation.box(extents=(a, b, c))
    placement = np.eye(4)
    placement[:3, :3], placement[:3, 3] = rotation, offset
    mesh.apply_transform(placement)
    props = mesh_properties(mesh, rho)
    m = rho * a * b * c
    assert props.mass == pytest.approx(m, rel=1e-13)
    np.testing.assert_allclose(props.center_of_mass, offset, rtol=0, atol=1e-14)
    # the tensor of the turned box is R I R^T of the box in its own axes
    np.testing.assert_allclose(props.inertia, rotation @ box_inertia(m, a, b, c) @ rotation.T,
                               rtol=0, atol=1e-13 * m * a * a)
    np.testing.assert_allclose(props.mesh.center_mass, 0.0, rtol=0, atol=1e-14)


@pytest.mark.parametrize("sections", [6, 32, 256])
def test_cylinder_equals_the_regular_prism_and_converges_to_the_circle(sections):
    radius, height, rho = 0.05, 0.2, 2700.0
    props = mesh_properties(trimesh.creation.cylinder(radius=radius, height=height,
                                                      sections=sections), rho)
    # trimesh's cylinder is a regular n-gon prism with its corners on the circle: exactly,
    # area n R^2 sin(2 pi/n) / 2 and polar moment per area R^2 (2 + cos(2 pi/n)) / 6
    alpha = 2 * math.pi / sections
    area = 0.5 * sections * radius**2 * math.sin(alpha)
    m = rho * area * height
    polar = radius**2 * (2 + math.cos(alpha)) / 6
    assert props.mass == pytest.approx(m, rel=1e-12)
    np.testing.assert_allclose(np.diag(props.inertia),
                               [m * (polar / 2 + height**2 / 12)] * 2 + [m * polar], rtol=1e-12)
    np.testing.assert_allclose(props.inertia - np.diag(np.diag(props.inertia)), 0.0,
                               rtol=0, atol=1e-14 * m * radius**2)
    # and the circular cylinder's closed forms within the polygon's O(1/n^2) error
    m_circle = rho * math.pi * radius**2 * height
    error = 2 * math.pi**2 / sections**2
    assert abs(props.mass / m_circle - 1) < error
    assert abs(props.inertia[2, 2] / (m_circle * radius**2 / 2) - 1) < 2 * error


def test_body_from_a_mesh_matches_the_body_from_closed_forms():
    a, b, c, rho = 0.4, 0.05, 0.02, 1000.0
    m = rho * a * b * c
    mesh = trimesh.creation.box(extents=(a, b, c))
    mesh.apply_translation((0.5 * a, 0.0, 0.0))  # drawn with its end, not its centre, at 0
    for dim, gravity in ((2, (0.0, -9.81)), (3, (0.0, -9.81, 0.0))):
        models = []
        for from_mesh in (True, False):
            builder = mb.ModelBuilder(dim=dim, gravity=gravity)
            props = (dict(shape=mesh, density=rho) if from_mesh else
                     dict(mass=m, inertia=box_inertia(m, a, b, c)[2, 2] if dim == 2
                          else np.diag(box_inertia(m, a, b, c))))
            bar = builder.add_body("bar", position=(0.5 * a, 0.0, 0.0)[:dim], **props)
            builder.add(Revolute("pin", builder.ground, bar, at=(0.0, 0.0, 0.0)[:dim],
                                 axis=None if dim == 2 else (0.0, 0.0, 1.0)))
            models.append(builder.build())
        np.testing.assert_allclose(models[0].mass, models[1].mass, rtol=1e-13)
        np.testing.assert_allclose(models[0].inertia, models[1].inertia, rtol=1e-12)
        # the body frame sits at the centre of mass: the mesh now spans -a/2..a/2
        shape = models[0].bodies[0].shape
        np.testing.assert_allclose(shape.bounds[:, 0], [-0.5 * a, 0.5 * a], rtol=0, atol=1e-15)
        t = np.linspace(0.0, 0.3, 4)
        swing = [mb.forward_dynamics(model, t, rtol=1e-10, atol=1e-12).body("bar").rotation
                 for model in models]
        np.testing.assert_allclose(swing[0], swing[1], rtol=0, atol=1e-9)


def test_bad_meshes_and_densities_are_named(tmp_path):
    open_box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    open_box.update_faces(np.arange(len(open_box.faces)) != 0)
    b = mb.ModelBuilder(dim=3)
    with pytest.raises(mb.ModelError, match="body 'lid'.*not watertight"):
        b.add_body("lid", shape=open_box, density=1000.0, position=(0, 0, 0))
    box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    for density in (0.0, -5.0, float("nan")):
        with pytest.raises(mb.ModelError, match="body 'block'.*density"):
            b.add_body("block", shape=box, density=density, position=(0, 0, 0))
    inside_out = box.copy()
    inside_out.invert()
    with pytest.raises(mb.ModelError, match="body 'inverted'.*faces point inwards"):
        b.add_body("inverted", shape=inside_out, density=1.0, position=(0, 0, 0))
    with pytest.raises(mb.ModelError, match="body 'both'.*not both"):
        b.add_body("both", shape=box, density=1.0, mass=1.0, position=(0, 0, 0))
    with pytest.raises(mb.ModelError, match="body 'bare'.*mass="):
        b.add_body("bare", position=(0, 0, 0))
    with pytest.raises(mb.ModelError, match="body 'filed'.*does not exist"):
        b.add_body("filed", shape=str(tmp_path / "missing.stl"), density=1.0, position=(0, 0, 0))
    path = tmp_path / "part.stl"
    box.export(path)
    body = b.add_body("from_file", shape=str(path), density=2.0, position=(0, 0, 0))
    assert body.mass == pytest.approx(2.0, rel=1e-12)


def test_primitive_spheres_and_cylinders_have_the_solids_mass_not_their_facets():
    """``{sphere: r}`` and ``{cylinder: [r, h]}`` are drawn by meshes whose facets hold less
    than the solid (0.9 % for the sphere): their mass and inertia are the closed forms."""
    rho, r, h = 7850.0, 0.02, 0.05
    b = mb.ModelBuilder(dim=3)
    ball = b.add_body("ball", shape={"sphere": r}, density=rho, position=(0, 0, 0))
    can = b.add_body("can", shape={"cylinder": [r, h]}, density=rho, position=(1, 0, 0))
    m_ball = rho * 4 / 3 * np.pi * r ** 3
    assert ball.mass == pytest.approx(m_ball, rel=1e-14)
    np.testing.assert_allclose(ball.inertia, 0.4 * m_ball * r * r * np.eye(3), rtol=1e-14,
                               atol=0)
    m_can = rho * np.pi * r * r * h
    assert can.mass == pytest.approx(m_can, rel=1e-14)
    np.testing.assert_allclose(np.diag(can.inertia), [m_can * (3 * r * r + h * h) / 12] * 2
                               + [m_can * r * r / 2], rtol=1e-14, atol=0)
