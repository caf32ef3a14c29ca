"""Parameters by name (``mb.parameters``, ``mb.with_parameters``): every number a model was
built with, named by its field in the model's file, and a model built again with some
changed. Checked against the models built in Python with those values, against the model
files of the examples (the same names and numbers), and against ``read(file, changes)``."""

from __future__ import annotations

import importlib.util
import math
import pathlib
import warnings

import numpy as np
import pytest

import mbd3d as mb
from mbd3d.errors import ModelError
from mbd3d.io.model_file import read
from mbd3d.joints import PointOnLine, Revolute, RotationDriver

ROOT = pathlib.Path(__file__).resolve().parent.parent


def slider_crank(stiffness: float = 1.0, damping: float = 1.0, rod_mass: float = 1.0,
                 pin: float = 0.5, rate: float = 2.0) -> mb.Model:
    """Haug's slider-crank with its spring-damper, driven at ``rate`` [rad/s]."""
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81), name="slider-crank")
    p0 = math.asin(-pin)
    along = np.array([math.cos(p0), math.sin(p0)])
    crank = b.add_body("crank", mass=1.0, inertia=1.0, position=(0.0, 0.0), angle=math.pi / 2)
    rod = b.add_body("rod", mass=rod_mass, inertia=2.0, position=(0.0, pin) + along, angle=p0)
    b.add(Revolute("pivot", b.ground, crank, at=(0.0, 0.0)))
    b.add(Revolute("pin", crank, rod, at=(0.0, pin)))
    b.add(PointOnLine("slot", b.ground, rod, axis=(1.0, 0.0), at=(0.0, pin) + 2 * along))
    b.add(mb.SpringDamper("spring", crank, rod, at_i=(0.0, pin / 2),
                          at_j=(0.0, pin) + along, stiffness=stiffness, damping=damping,
                          free_length=1.0))
    b.add(RotationDriver("motor", b.ground, crank, motion=mb.Ramp(math.pi / 2, rate)))
    return b.build()


def example(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "examples" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def same_model(a: mb.Model, b: mb.Model) -> None:
    """The same model to the last bit: coordinates, masses, and an inverse dynamics run."""
    np.testing.assert_array_equal(a.q0, b.q0)
    np.testing.assert_array_equal(a.mass, b.mass)
    t = np.linspace(0.0, 0.5, 6)
    ra, rb = mb.inverse_dynamics(a, t), mb.inverse_dynamics(b, t)
    np.testing.assert_array_equal(ra.q, rb.q)
    np.testing.assert_array_equal(ra.lam, rb.lam)


def test_the_names_are_the_model_files_fields():
    values = mb.parameters(slider_crank(stiffness=3.0, damping=0.25, rate=7.0))
    assert values["forces.spring.stiffness"] == 3.0
    assert values["forces.spring.damping"] == 0.25
    assert values["joints.motor.motion.rate"] == 7.0
    assert values["joints.pin.at[1]"] == 0.5
    assert values["gravity[1]"] == -9.81
    assert values["bodies.rod.mass"] == 1.0
    assert list(values)[:2] == ["gravity[0]", "gravity[1]"]


@pytest.mark.parametrize("name", ["haug_slider_crank", "spinning_top", "cam_jump",
                                  "gear_train"])
def test_a_model_from_its_file_has_the_same_parameters(name):
    with warnings.catch_warnings():  # cam_jump starts pressed into its cam
        warnings.simplefilter("ignore", mb.ContactWarning)
        built = example(name).build()
        loaded = mb.load(ROOT / "examples" / "models" / f"{name}.yaml")
    assert mb.parameters(built) == mb.parameters(loaded)


def test_changed_parameters_build_the_model_built_with_them():
    model = slider_crank()
    changed = mb.with_parameters(model, {"forces.spring.stiffness": 40.0,
                                         "forces.spring.damping": 0.5,
                                         "bodies.rod.mass": 2.5,
                                         "joints.motor.motion.rate": 3.0})
    same_model(changed, slider_crank(stiffness=40.0, damping=0.5, rod_mass=2.5, rate=3.0))
    assert mb.parameters(model)["bodies.rod.mass"] == 1.0  # the model is left as it was
    same_model(mb.with_parameters(model, {}), model)
    forward = [mb.forward_dynamics(m, [0.0, 0.1], method="DOP853", rtol=1e-10)
               for m in (changed, slider_crank(40.0, 0.5, 2.5, rate=3.0))]
    np.testing.assert_array_equal(forward[0].q, forward[1].q)


def test_a_model_file_takes_the_same_names_as_changes(tmp_path):
    model = slider_crank()
    path = mb.save(model, tmp_path / "sc.yaml")
    changes = {"joints.slot.at[0]": 1.2, "forces.spring.at_i[1]": 0.3, "gravity[1]": -1.0}
    same_model(read(path, changes).model, mb.with_parameters(model, changes))
    assert mb.parameters(read(path, changes).model)["forces.spring.at_i[1]"] == 0.3


def test_bad_parameters_are_named():
    model = slider_crank()
    with pytest.raises(ModelError, match=r"no parameter 'forces.spring.stifness'.*"
                                         r"forces.spring.stiffness"):
        mb.with_parameters(model, {"forces.spring.stifness": 2.0})
    for value in (math.nan, "2", True, None):
        with pytest.raises(ModelError, match="parameter 'bodies.rod.mass': give a finite"):
            mb.with_parameters(model, {"bodies.rod.mass": value})
    with pytest.raises(ModelError, match=r"<model 'slider-crank'>: bodies\[1\].*mass"):
        mb.with_parameters(model, {"bodies.rod.mass": -1.0})
    b = mb.ModelBuilder(dim=2)
    b.add_body("bob", mass=1.0, inertia=0.1, position=(1.0, 0.0))
    with pytest.raises(ModelError, match="no parameter 'bodies.bob.angle'"):
        mb.with_parameters(b.build(), {"bodies.bob.angle": 0.5})  # not given: no parameter
    b = mb.ModelBuilder(dim=2)
    bob = b.add_body("bob", mass=1.0, inertia=0.1, position=(1.0, 0.0))
    b.add(mb.Torque("push", bob, lambda t: math.sin(t)))
    with pytest.raises(ModelError, match="model 'model': parameters are named by the fields "
                                         "of the model's file.*Python function"):
        mb.parameters(b.build())


def peak_torque(results) -> float:
    return float(np.max(np.abs(results.driver("motor").effort)))


def test_a_sweep_over_named_parameters_runs_the_models_built_with_them(tmp_path):
    """``ModelVariants(model)`` as a sweep's factory: each row's metric is that of the model
    built in Python with the point's values; it travels by pickle (as to Dask's workers); the
    same sweep again runs nothing; a changed model is a new sweep."""
    import pickle

    from mbd3d.sweeps import Analysis, grid, sweep

    variants = pickle.loads(pickle.dumps(mb.ModelVariants(slider_crank())))
    points = grid(**{"forces.spring.stiffness": [10.0, 40.0], "bodies.rod.mass": [1.0, 3.0]})
    analysis = Analysis("inverse dynamics", np.linspace(0.0, 0.5, 11))
    table = sweep(variants, points, analysis, {"peak torque": peak_torque}, tmp_path / "a",
                  backend="serial", progress=False)
    for row in table:
        built = slider_crank(stiffness=row["forces.spring.stiffness"],
                             rod_mass=row["bodies.rod.mass"])
        assert row["peak torque"] == peak_torque(mb.inverse_dynamics(built, analysis.t))
    assert len(set(table.column("peak torque"))) == 4
    again = sweep(mb.ModelVariants(slider_crank()), points, analysis,
                  {"peak torque": peak_torque}, tmp_path / "a", backend="serial",
                  progress=False)
    assert again.summary["skipped"] == len(points)  # stored: none run again
    assert (mb.ModelVariants(slider_crank(pin=0.4)).sweep_identity()
            != variants.sweep_identity())
